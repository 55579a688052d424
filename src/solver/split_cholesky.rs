//! Two-core sparse Cholesky by one level of nested dissection with a dense Schur complement
//! (George 1973, "Nested dissection of a regular finite element mesh"; the block elimination
//! of Golub & Van Loan, "Matrix Computations", §4.2). With a vertex separator Σ splitting the
//! other equations into halves R₁, R₂ that do not couple (`separator.rs`),
//!
//!   A = [[A₁, 0, B₁], [0, A₂, B₂], [B₁ᵀ, B₂ᵀ, C]],   S = C − B₁ᵀA₁⁻¹B₁ − B₂ᵀA₂⁻¹B₂.
//!
//! Each bordered half M_k = [[A_k, B_k], [B_kᵀ, C]] is factorized by faer's supernodal LLᵀ
//! (AMD on A_k, Σ last), the two on the two cores at once (`rayon::join`, each sequential).
//! The trailing block L_Σk of the factor of M_k satisfies L_Σk L_Σkᵀ = S_k = C − B_kᵀA_k⁻¹B_k,
//! so S = S₁ + S₂ − C, which is factorized densely. A x = b is solved by
//!   (1) [u_k; v_k] = M_k⁻¹ [b_k; 0],  g_k = −S_k v_k = B_kᵀA_k⁻¹b_k,
//!   (2) x_Σ = S⁻¹ (b_Σ − g₁ − g₂),
//!   (3) x_k = top of M_k⁻¹ [b_k; S_k x_Σ + g_k] = A_k⁻¹ (b_k − B_k x_Σ),
//! since M_k⁻¹ [b; w] = [A_k⁻¹(b − B_k v); v] with v = S_k⁻¹ (w − B_kᵀA_k⁻¹ b). Steps (1)
//! and (3) take one forward and one backward substitution with the half's factor (see
//! `Half::first_pass`), so a solve costs what the monolithic one does, on two cores.

use crate::assembly::Pattern;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::linalg::matmul::triangular::BlockStructure;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, supernodal, CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Accum, Conj, Mat, MatMut, Par, Side};

use super::separator::{HALF1, HALF2, SEP};

/// One bordered half M_k = [[A_k, B_k], [B_kᵀ, C]] in its elimination order (AMD on A_k, Σ last).
struct Half {
    /// Equation of A at each of the first n_k positions of M_k.
    rows: Vec<usize>,
    /// Lower triangle of M_k (CSC), the form faer's supernodal factorization reads.
    lower: SymbolicSparseColMat<usize>,
    /// Index into A's stored values of each stored value of `lower`.
    gather: Vec<usize>,
    values: Vec<f64>,
    symbolic: SymbolicCholesky<usize>,
    l_values: Vec<f64>,
    buffer: MemBuffer,
    /// S_k = L_Σk L_Σkᵀ (lower triangle valid).
    schur: Mat<f64>,
    /// L_Σk, the trailing |Σ|×|Σ| block of the factor (lower triangle).
    l_sep: Mat<f64>,
    work: Vec<f64>,
}

/// The numeric Cholesky of a symmetric positive definite matrix split by one separator.
pub(super) struct SplitCholesky {
    halves: [Half; 2],
    /// Equations of Σ, in Σ order.
    sep: Vec<usize>,
    /// (i, j, p), i ≥ j: A's stored value p is C(i, j).
    c_entries: Vec<(usize, usize, usize)>,
    /// S, then its dense Cholesky factor (lower).
    s: Mat<f64>,
    buffer: MemBuffer,
    work: Vec<f64>,
    /// CPU seconds of the last numeric factorization (`cpu_time::thread_seconds`): half 1, half 2
    /// (each on its core), and the dense Schur complement's assembly and factorization.
    pub(super) profile: [f64; 3],
}

impl Half {
    /// Symbolic analysis of half `k` (HALF1 or HALF2) of the dissection `part` of the
    /// upper-triangular pattern (`loc` = position of each equation within its part).
    fn analyse(n: usize, col_ptr: &[usize], row_idx: &[usize], part: &[u8], loc: &[usize], k: u8, n_sep: usize) -> Result<Half, String> {
        let members: Vec<usize> = (0..n).filter(|&i| part[i] == k).collect();
        let nk = members.len();
        // Elimination order of A_k: AMD on the graph of M_k (so that the minimum-degree
        // choices see the border couplings B_k), then Σ moved last. (Making Σ a clique so
        // that AMD itself keeps it last gave factors up to 17 % larger on 5-DOF grids.)
        let local = |i: usize| if part[i] == SEP { nk + loc[i] } else { loc[i] };
        let mut cp = vec![0usize];
        let mut ri = Vec::new();
        let mut in_domain: Vec<usize> = members.clone();
        in_domain.extend((0..n).filter(|&i| part[i] == SEP));
        for &c in &in_domain {
            for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
                if part[r] == k || part[r] == SEP {
                    ri.push(local(r));
                }
            }
            cp.push(ri.len());
        }
        let md = in_domain.len();
        // Entries (r in Σ, c in R_k) with r < c fall below the diagonal in this numbering:
        // rebuild as the upper triangle of the symmetric pattern.
        let (cp, ri) = upper_of_symmetrized(md, &cp, &ri);
        let nnz = ri.len();
        let graph = SymbolicSparseColMat::new_checked(md, md, cp, None, ri);
        let mut perm = vec![0usize; md];
        let mut perm_inv = vec![0usize; md];
        let mut mem = MemBuffer::try_new(amd::order_scratch::<usize>(md, nnz)).map_err(|_| "out of memory for AMD".to_string())?;
        amd::order(&mut perm, &mut perm_inv, graph.as_ref(), amd::Control::default(), MemStack::new(&mut mem)).map_err(|e| format!("AMD of a half: {e:?}"))?;
        drop(mem);
        let order: Vec<usize> = perm.into_iter().filter(|&i| i < nk).collect();
        let mut perm_inv = vec![0usize; nk];
        for (p, &i) in order.iter().enumerate() {
            perm_inv[i] = p;
        }
        let rows: Vec<usize> = order.iter().map(|&i| members[i]).collect();
        let m = nk + n_sep;
        let pos = |i: usize| if part[i] == SEP { nk + loc[i] } else { perm_inv[loc[i]] };
        // Lower CSC of M_k with the gather map; and its transpose's structure (upper).
        let mut count = vec![0usize; m + 1];
        let mut count_up = vec![0usize; m + 1];
        for c in 0..n {
            if part[c] != k && part[c] != SEP {
                continue;
            }
            for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
                if part[r] != k && part[r] != SEP {
                    continue;
                }
                let (a, b) = (pos(r), pos(c));
                count[a.min(b) + 1] += 1;
                count_up[a.max(b) + 1] += 1;
            }
        }
        for j in 0..m {
            count[j + 1] += count[j];
            count_up[j + 1] += count_up[j];
        }
        let len = count[m];
        let mut entries = vec![(0usize, 0usize); len]; // (row, value index) per lower column
        let mut up_rows = vec![0usize; len];
        let (mut fill, mut fill_up) = (count.clone(), count_up.clone());
        for c in 0..n {
            if part[c] != k && part[c] != SEP {
                continue;
            }
            for p in col_ptr[c]..col_ptr[c + 1] {
                let r = row_idx[p];
                if part[r] != k && part[r] != SEP {
                    continue;
                }
                let (a, b) = (pos(r), pos(c));
                let (lo, hi) = (a.min(b), a.max(b));
                entries[fill[lo]] = (hi, p);
                fill[lo] += 1;
                up_rows[fill_up[hi]] = lo;
                fill_up[hi] += 1;
            }
        }
        for j in 0..m {
            entries[count[j]..count[j + 1]].sort_unstable();
            up_rows[count_up[j]..count_up[j + 1]].sort_unstable();
        }
        let gather: Vec<usize> = entries.iter().map(|e| e.1).collect();
        let lower = SymbolicSparseColMat::new_checked(m, m, count, None, entries.iter().map(|e| e.0).collect());
        let upper = SymbolicSparseColMat::new_checked(m, m, count_up, None, up_rows);
        let params = CholeskySymbolicParams { supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL, ..Default::default() };
        let symbolic = factorize_symbolic_cholesky(upper.as_ref(), Side::Upper, SymmetricOrdering::Identity, params)
            .map_err(|e| format!("symbolic factorization of a half: {e:?}"))?;
        let lv = symbolic.len_val();
        let mut l_values = Vec::new();
        l_values.try_reserve_exact(lv).map_err(|_| format!("out of memory for a half factor ({lv} entries)"))?;
        l_values.resize(lv, 0.0);
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]);
        let buffer = MemBuffer::try_new(req).map_err(|_| "out of memory for workspace".to_string())?;
        Ok(Half {
            rows,
            lower,
            values: vec![0.0; gather.len()],
            gather,
            symbolic,
            l_values,
            buffer,
            schur: Mat::zeros(n_sep, n_sep),
            l_sep: Mat::zeros(n_sep, n_sep),
            work: vec![0.0; m],
        })
    }

    fn nk(&self) -> usize {
        self.rows.len()
    }

    /// LLᵀ of M_k and S_k = L_Σk L_Σkᵀ; false if M_k is not positive definite.
    fn factorize(&mut self, a_values: &[f64]) -> bool {
        for (v, &p) in self.values.iter_mut().zip(&self.gather) {
            *v = a_values[p];
        }
        let m = SparseColMatRef::new(self.lower.as_ref(), &self.values);
        let ok = self
            .symbolic
            .factorize_numeric_llt::<f64>(&mut self.l_values, m, Side::Lower, LltRegularization::default(), Par::Seq, MemStack::new(&mut self.buffer), Default::default())
            .is_ok();
        if !ok {
            return false;
        }
        let SymbolicCholeskyRaw::Supernodal(sym) = self.symbolic.raw() else {
            return false; // forced supernodal at analysis
        };
        let nk = self.nk();
        let l = supernodal::SupernodalLltRef::<'_, usize, f64>::new(sym, &self.l_values);
        for s in 0..sym.n_supernodes() {
            let (begin, end) = (sym.supernode_begin()[s], sym.supernode_end()[s]);
            if end <= nk {
                continue;
            }
            let node = l.supernode(s);
            let (val, pattern) = (node.val(), node.pattern());
            let w = end - begin;
            for j in begin.max(nk)..end {
                let (jl, js) = (j - begin, j - nk);
                for il in jl..w {
                    self.l_sep[(begin + il - nk, js)] = val[(il, jl)];
                }
                for (t, &r) in pattern.iter().enumerate() {
                    self.l_sep[(r - nk, js)] = val[(w + t, jl)];
                }
            }
        }
        faer::linalg::matmul::triangular::matmul(
            self.schur.as_mut(),
            BlockStructure::TriangularLower,
            Accum::Replace,
            self.l_sep.as_ref(),
            BlockStructure::TriangularLower,
            self.l_sep.transpose(),
            BlockStructure::TriangularUpper,
            1.0,
            Par::Seq,
        );
        true
    }

    /// Step (1) by the factor M_k = L Lᵀ, L = [[L_A, 0], [L_BA, L_Σ]]: the forward solve of
    /// [b_k; 0] gives [y_A; y_Σ] with y_A = L_A⁻¹ b_k, y_Σ = −L_Σ⁻¹ L_BA y_A, and since
    /// v_k = L_Σ⁻ᵀ y_Σ, g_k = −S_k v_k = −L_Σ y_Σ. y_A stays in `work` for step (3).
    fn first_pass(&mut self, b: &[f64], g: &mut [f64]) {
        let nk = self.nk();
        for (w, &i) in self.work.iter_mut().zip(&self.rows) {
            *w = b[i];
        }
        self.work[nk..].fill(0.0);
        let SymbolicCholeskyRaw::Supernodal(sym) = self.symbolic.raw() else { return };
        let m = self.work.len();
        let rhs = MatMut::from_column_major_slice_mut(&mut self.work, m, 1);
        supernodal::SupernodalLltRef::<'_, usize, f64>::new(sym, &self.l_values).l_solve_with_conj(Conj::No, rhs, Par::Seq, MemStack::new(&mut self.buffer));
        // g = −L_Σ y_Σ (L_Σ lower triangular).
        let y = &self.work[nk..];
        g.iter_mut().for_each(|v| *v = 0.0);
        for j in 0..y.len() {
            let col = self.l_sep.col(j);
            for i in j..y.len() {
                g[i] -= col[i] * y[j];
            }
        }
    }

    /// Step (3): the backward solve of Lᵀ [x_A; x_Σ] = [y_A; L_Σᵀ x_Σ] gives
    /// x_A = L_A⁻ᵀ (y_A − L_BAᵀ x_Σ) = A_k⁻¹ (b_k − B_k x_Σ), the half's unknowns, left in
    /// the first n_k entries of `work`.
    fn second_pass(&mut self, x_sep: &[f64]) {
        let nk = self.nk();
        for j in 0..x_sep.len() {
            let col = self.l_sep.col(j);
            self.work[nk + j] = (j..x_sep.len()).map(|i| col[i] * x_sep[i]).sum();
        }
        let SymbolicCholeskyRaw::Supernodal(sym) = self.symbolic.raw() else { return };
        let m = self.work.len();
        let rhs = MatMut::from_column_major_slice_mut(&mut self.work, m, 1);
        supernodal::SupernodalLltRef::<'_, usize, f64>::new(sym, &self.l_values).l_transpose_solve_with_conj(Conj::No, rhs, Par::Seq, MemStack::new(&mut self.buffer));
    }
}

/// Upper triangle (sorted, diagonal included) of the symmetric pattern whose entries are
/// given in CSC form in either triangle.
fn upper_of_symmetrized(m: usize, cp: &[usize], ri: &[usize]) -> (Vec<usize>, Vec<usize>) {
    let mut cols: Vec<Vec<usize>> = vec![Vec::new(); m];
    for c in 0..m {
        cols[c].push(c);
        for &r in &ri[cp[c]..cp[c + 1]] {
            cols[r.max(c)].push(r.min(c));
        }
    }
    let mut out_cp = vec![0usize];
    let mut out_ri = Vec::new();
    for col in &mut cols {
        col.sort_unstable();
        col.dedup();
        out_ri.extend_from_slice(col);
        out_cp.push(out_ri.len());
    }
    (out_cp, out_ri)
}

impl SplitCholesky {
    /// Symbolic analysis for the dissection `part` (HALF1/HALF2/SEP per equation) of the
    /// upper-triangular CSC pattern.
    pub(super) fn analyse(n: usize, col_ptr: &[usize], row_idx: &[usize], part: &[u8]) -> Result<Self, String> {
        let mut loc = vec![0usize; n];
        let mut counts = [0usize; 3];
        for i in 0..n {
            let k = part[i] as usize;
            loc[i] = counts[k];
            counts[k] += 1;
        }
        let n_sep = counts[SEP as usize];
        let sep: Vec<usize> = (0..n).filter(|&i| part[i] == SEP).collect();
        let mut c_entries = Vec::new();
        for c in 0..n {
            if part[c] != SEP {
                continue;
            }
            for p in col_ptr[c]..col_ptr[c + 1] {
                let r = row_idx[p];
                if part[r] == SEP {
                    let (a, b) = (loc[r], loc[c]);
                    c_entries.push((a.max(b), a.min(b), p));
                }
            }
        }
        let (h1, h2) = rayon::join(
            || Half::analyse(n, col_ptr, row_idx, part, &loc, HALF1, n_sep),
            || Half::analyse(n, col_ptr, row_idx, part, &loc, HALF2, n_sep),
        );
        let req = StackReq::any_of(&[
            faer::linalg::cholesky::llt::factor::cholesky_in_place_scratch::<f64>(n_sep, Par::Seq, Default::default()),
            faer::linalg::cholesky::llt::solve::solve_in_place_scratch::<f64>(n_sep, 1, Par::Seq),
        ]);
        let buffer = MemBuffer::try_new(req).map_err(|_| "out of memory for workspace".to_string())?;
        Ok(Self { halves: [h1?, h2?], sep, c_entries, s: Mat::zeros(n_sep, n_sep), buffer, work: vec![0.0; n_sep], profile: [0.0; 3] })
    }

    /// Size of the separator Σ.
    pub(super) fn separator_len(&self) -> usize {
        self.sep.len()
    }

    /// Stored values of the two half factors and the dense lower triangle of S's factor.
    pub(super) fn factor_nnz(&self) -> usize {
        let s = self.sep.len();
        self.halves[0].l_values.len() + self.halves[1].l_values.len() + s * (s + 1) / 2
    }

    /// Numeric LLᵀ of the matrix with the analysed pattern and `values` (upper triangle);
    /// false if it is not positive definite.
    pub(super) fn factorize(&mut self, values: &[f64]) -> bool {
        self.factorize_halves(values) && self.factorize_schur(values)
    }

    /// The two bordered halves' LLᵀ, on two cores; false if one is not positive definite.
    fn factorize_halves(&mut self, values: &[f64]) -> bool {
        let [h1, h2] = &mut self.halves;
        let timed = |h: &mut Half| {
            let t = crate::cpu_time::thread_seconds();
            let ok = h.factorize(values);
            (ok, crate::cpu_time::thread_seconds() - t)
        };
        let ((ok1, t1), (ok2, t2)) = rayon::join(|| timed(h1), || timed(h2));
        self.profile = [t1, t2, 0.0];
        ok1 && ok2
    }

    /// S = S₁ + S₂ − C and its dense LLᵀ; false if S is not positive definite.
    fn factorize_schur(&mut self, values: &[f64]) -> bool {
        let [h1, h2] = &self.halves;
        let t = crate::cpu_time::thread_seconds();
        let ns = self.sep.len();
        for j in 0..ns {
            for i in j..ns {
                self.s[(i, j)] = h1.schur[(i, j)] + h2.schur[(i, j)];
            }
        }
        for &(i, j, p) in &self.c_entries {
            self.s[(i, j)] -= values[p];
        }
        let ok = faer::linalg::cholesky::llt::factor::cholesky_in_place(self.s.as_mut(), LltRegularization::default(), Par::Seq, MemStack::new(&mut self.buffer), Default::default()).is_ok();
        self.profile[2] = crate::cpu_time::thread_seconds() - t;
        ok
    }

    /// Solves A x = rhs in place with the last factorization.
    pub(super) fn solve(&mut self, rhs: &mut [f64]) {
        let ns = self.sep.len();
        let (mut g1, mut g2) = (vec![0.0; ns], vec![0.0; ns]);
        let b: &[f64] = rhs;
        let [h1, h2] = &mut self.halves;
        rayon::join(|| h1.first_pass(b, &mut g1), || h2.first_pass(b, &mut g2));
        for (k, &i) in self.sep.iter().enumerate() {
            self.work[k] = b[i] - g1[k] - g2[k];
        }
        let xs = MatMut::from_column_major_slice_mut(&mut self.work, ns, 1);
        faer::linalg::cholesky::llt::solve::solve_in_place_with_conj(self.s.as_ref(), Conj::No, xs, Par::Seq, MemStack::new(&mut self.buffer));
        let xs = &self.work;
        rayon::join(|| h1.second_pass(xs), || h2.second_pass(xs));
        for h in [&*h1, &*h2] {
            for (&i, &v) in h.rows.iter().zip(&h.work[..h.nk()]) {
                rhs[i] = v;
            }
        }
        for (k, &i) in self.sep.iter().enumerate() {
            rhs[i] = xs[k];
        }
    }

    /// Pivots of the factorization P A Pᵀ = L Lᵀ in the order [R₁, R₂, Σ]: the squared
    /// diagonal of L.
    pub(super) fn pivots(&self) -> Vec<f64> {
        let mut out = Vec::new();
        for h in &self.halves {
            if let SymbolicCholeskyRaw::Supernodal(sym) = h.symbolic.raw() {
                let l = supernodal::SupernodalLltRef::<'_, usize, f64>::new(sym, &h.l_values);
                for s in 0..sym.n_supernodes() {
                    let (begin, end) = (sym.supernode_begin()[s], sym.supernode_end()[s]);
                    let m = l.supernode(s).val();
                    for j in begin..end.min(h.nk()) {
                        out.push(m[(j - begin, j - begin)].powi(2));
                    }
                }
            }
        }
        for k in 0..self.sep.len() {
            out.push(self.s[(k, k)].powi(2));
        }
        out
    }
}

/// A test and benchmark system (`examples/factor_speed.rs`): the upper-triangular pattern
/// and values of `copies` m×m-element quad grids of 5-DOF nodes (the column of nodes i = 0
/// clamped), the graph Laplacian ⊗ K₅ plus `shift`·I, K₅ coupling three stiff (1e3) and two
/// soft (1) DOFs like a shell's translations and rotations (positive definite for shift > 0);
/// the copies stacked as plies and tied node to node at every `tie_every`-th node (0: none,
/// disjoint copies), like quilted plies.
pub fn grid_plies(m: usize, copies: usize, tie_every: usize, shift: f64) -> (Pattern, Vec<f64>) {
    let per = m * (m + 1);
    let nn = per * copies;
    let mut adj: Vec<Vec<usize>> = vec![Vec::new(); nn];
    for a in (0..per).filter(|a| tie_every > 0 && a % tie_every == 0) {
        for c in 1..copies {
            adj[a + (c - 1) * per].push(a + c * per);
            adj[a + c * per].push(a + (c - 1) * per);
        }
    }
    for cpy in 0..copies {
        let eqn = |i: usize, j: usize| if i == 0 { usize::MAX } else { cpy * per + j * m + (i - 1) };
        for j in 0..m {
            for i in 0..m {
                let q = [eqn(i, j), eqn(i + 1, j), eqn(i + 1, j + 1), eqn(i, j + 1)];
                for &a in &q {
                    for &b in &q {
                        if a != usize::MAX && b != usize::MAX {
                            adj[a].push(b);
                        }
                    }
                }
            }
        }
    }
    adj.iter_mut().for_each(|a| {
        a.sort_unstable();
        a.dedup();
    });
    let k5 = |k: usize, l: usize| {
        let s = [1e3, 1e3, 1e3, 1.0, 1.0];
        if k == l { 2.0 * s[k] } else { 0.3 * f64::sqrt(s[k] * s[l]) }
    };
    let (mut col_ptr, mut row_idx, mut values) = (vec![0], Vec::new(), Vec::new());
    for a in 0..nn {
        for k in 0..5 {
            let col = a * 5 + k;
            for &b in &adj[a] {
                for l in 0..5 {
                    let row = b * 5 + l;
                    if row <= col {
                        row_idx.push(row);
                        let w = if a == b { (adj[a].len() - 1) as f64 + 0.5 } else { -1.0 };
                        values.push(w * k5(l, k) + if row == col { shift } else { 0.0 });
                    }
                }
            }
            col_ptr.push(row_idx.len());
        }
    }
    (Pattern { n: nn * 5, col_ptr, row_idx }, values)
}

#[cfg(test)]
mod tests {
    use super::super::linear::{FactorKind, SparseCholesky};
    use crate::assembly::Pattern;

    /// Upper-triangular pattern and values of a 5-DOF-per-node quad grid of m×m elements
    /// (column of nodes i = 0 clamped, `copies` disjoint copies): the graph Laplacian ⊗ K₅
    /// plus `shift`·I, K₅ coupling three stiff (1e3) and two soft (1) DOFs like a shell's
    /// translations and rotations; positive definite for shift > 0.
    fn grid5(m: usize, copies: usize, shift: f64) -> (Pattern, Vec<f64>) {
        super::grid_plies(m, copies, 0, shift)
    }

    fn rhs(n: usize) -> Vec<f64> {
        (0..n).map(|i| ((i * 7919) % 13) as f64 - 6.0).collect()
    }

    /// ‖A x − b‖ / ‖b‖.
    fn relative_residual(chol: &SparseCholesky, values: &[f64], x: &[f64], b: &[f64]) -> f64 {
        let mut ax = vec![0.0; b.len()];
        chol.multiply(values, x, &mut ax);
        let r = ax.iter().zip(b).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
        r / b.iter().map(|v| v * v).sum::<f64>().sqrt()
    }

    /// Solves with the split (two threads) and the monolithic (one thread) factorization.
    fn split_and_monolithic(p: &Pattern, v: &[f64]) -> (SparseCholesky, Vec<f64>, Vec<f64>) {
        let b = rhs(p.n);
        let mut split = SparseCholesky::analyse(p, 2).unwrap();
        assert_eq!(split.factorize(v).unwrap(), FactorKind::Llt);
        let mut xs = b.clone();
        split.solve(&mut xs);
        let mut mono = SparseCholesky::analyse(p, 1).unwrap();
        assert!(mono.separator_len().is_none());
        mono.factorize(v).unwrap();
        let mut xm = b.clone();
        mono.solve(&mut xm);
        (split, xs, xm)
    }

    /// The split solution of grid systems (condition number about 1e8 with the shift 1e-4)
    /// has a relative residual at round-off (< 1e-13, as the monolithic one) and agrees
    /// with the monolithic solution to 1e-9 relative.
    #[test]
    fn split_solution_matches_monolithic_on_grids() {
        for (m, shift) in [(30, 1e-4), (50, 1e-4), (50, 10.0)] {
            let (p, v) = grid5(m, 1, shift);
            let (split, xs, xm) = split_and_monolithic(&p, &v);
            let sep = split.separator_len().unwrap();
            // A straight grid line across the m × (m + 1) free nodes: m nodes of 5 DOFs.
            assert_eq!(sep, 5 * m, "m={m}: separator");
            let b = rhs(p.n);
            let (rs, rm) = (relative_residual(&split, &v, &xs, &b), relative_residual(&split, &v, &xm, &b));
            assert!(rs < 1e-13 && rm < 1e-13, "m={m}: residuals split {rs:e}, monolithic {rm:e}");
            let scale = xm.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            let dx = xs.iter().zip(&xm).fold(0.0f64, |a, (s, m)| a.max((s - m).abs())) / scale;
            assert!(dx < 1e-9, "m={m}: split and monolithic solutions differ by {dx:e}");
        }
    }

    /// Two disconnected grids are distributed whole: an empty separator, exact agreement in
    /// the residual with the monolithic solve.
    #[test]
    fn disconnected_pattern_splits_without_separator() {
        let (p, v) = grid5(30, 2, 1e-4);
        let (split, xs, _) = split_and_monolithic(&p, &v);
        assert_eq!(split.separator_len(), Some(0));
        let b = rhs(p.n);
        let r = relative_residual(&split, &v, &xs, &b);
        assert!(r < 1e-13, "residual {r:e}");
    }

    /// An indefinite matrix makes the split LLᵀ fail; the monolithic LDLᵀ takes over and
    /// counts the negative eigenvalues (Sylvester): shifting the grid matrix by −σ·I moves
    /// the eigenvalues of the Laplacian ⊗ K₅ below σ negative. Reference count: the
    /// eigenvalues of the shifted matrix from the monolithic count on one thread, checked
    /// there against closed forms (`linear.rs`); here, the split path must report the same
    /// count, then return to the split LLᵀ for a definite matrix.
    #[test]
    fn indefinite_matrix_falls_back_with_inertia() {
        let (p, v) = grid5(30, 1, 1e-4);
        let mut split = SparseCholesky::analyse(&p, 2).unwrap();
        assert!(split.separator_len().is_some());
        let mut mono = SparseCholesky::analyse(&p, 1).unwrap();
        let mut diag = vec![false; v.len()];
        for c in 0..p.n {
            for s in p.col_ptr[c]..p.col_ptr[c + 1] {
                diag[s] = p.row_idx[s] == c;
            }
        }
        for sigma in [2.0, 5.0, 40.0] {
            let vs: Vec<f64> = v.iter().zip(&diag).map(|(&a, &d)| if d { a - sigma } else { a }).collect();
            assert!(!split.factorize_definite(&vs), "sigma={sigma}: LLT must fail");
            assert_eq!(split.factorize(&vs).unwrap(), FactorKind::Ldlt);
            mono.factorize(&vs).unwrap();
            let expected = mono.negative_pivots();
            assert!(expected > 0);
            assert_eq!(split.negative_pivots(), expected, "sigma={sigma}");
            let b = rhs(p.n);
            let mut x = b.clone();
            split.solve(&mut x);
            let r = relative_residual(&split, &vs, &x, &b);
            assert!(r < 1e-8, "sigma={sigma}: indefinite residual {r:e}");
        }
        assert!(split.factorize_definite(&v));
        assert_eq!(split.negative_pivots(), 0);
        let b = rhs(p.n);
        let mut x = b.clone();
        split.solve(&mut x);
        assert!(relative_residual(&split, &v, &x, &b) < 1e-13);
    }

    /// Three 30² plies quilted together at every 37th node: the level-set separator cuts
    /// through all three plies (|Σ| = 450, 3 % of the equations, balanced) while AMD orders
    /// the plies almost independently, so the split's dense work |Σ|³ is large against the
    /// monolithic factor's and the monolithic factorization is kept.
    #[test]
    fn quilted_plies_stay_monolithic() {
        let (p, v) = super::grid_plies(30, 3, 37, 1e-4);
        let mut chol = SparseCholesky::analyse(&p, 2).unwrap();
        assert!(chol.separator_len().is_none());
        assert_eq!(chol.factorize(&v).unwrap(), FactorKind::Llt);
        let b = rhs(p.n);
        let mut x = b.clone();
        chol.solve(&mut x);
        assert!(relative_residual(&chol, &v, &x, &b) < 1e-13);
    }

    /// Small systems, and patterns without a small balanced separator (an arrow matrix: one
    /// equation coupled to all others), use the monolithic factorization even on two threads.
    #[test]
    fn small_or_unseparable_patterns_stay_monolithic() {
        let (p, v) = grid5(10, 1, 1e-4);
        assert!(p.n < super::super::linear::SPLIT_MIN_EQUATIONS);
        let mut chol = SparseCholesky::analyse(&p, 2).unwrap();
        assert!(chol.separator_len().is_none());
        assert_eq!(chol.factorize(&v).unwrap(), FactorKind::Llt);
        let n = 6000;
        let (mut col_ptr, mut row_idx, mut values) = (vec![0], Vec::new(), Vec::new());
        for c in 0..n {
            if c > 0 {
                row_idx.push(0);
                values.push(1.0);
            }
            row_idx.push(c);
            values.push(if c == 0 { n as f64 } else { 2.0 });
            col_ptr.push(row_idx.len());
        }
        let arrow = Pattern { n, col_ptr, row_idx };
        let mut chol = SparseCholesky::analyse(&arrow, 2).unwrap();
        assert!(chol.separator_len().is_none());
        assert_eq!(chol.factorize(&values).unwrap(), FactorKind::Llt);
        let b = rhs(n);
        let mut x = b.clone();
        chol.solve(&mut x);
        assert!(relative_residual(&chol, &values, &x, &b) < 1e-13);
    }
}
