//! Sparse symmetric factorization with faer: symbolic analysis (AMD ordering, elimination
//! tree, supernodes) once per pattern, numeric Cholesky each Newton iteration into
//! preallocated storage. LLᵀ is tried first (its failure is a free positive-definiteness
//! test); an indefinite tangent falls back to LDLᵀ on the same symbolic structure.
//!
//! With two or more threads and a large enough system with a small, balanced separator, the
//! numeric LLᵀ is split in two halves factorized on two cores at once
//! (`split_cholesky.rs`, one level of nested dissection with a dense Schur complement); an
//! LLᵀ failure there falls back to the monolithic LLᵀ/LDLᵀ. The monolithic symbolic analysis
//! is always made (its factor's work decides whether the split pays); its storage is
//! allocated on first use. faer's own parallel numeric factorization is not used: on the 2-core
//! machine it was slower than the sequential one at every size (see `factor_threads`).

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, simplicial, supernodal, CholeskySymbolicParams, LdltRef, LltRef, SymbolicCholesky,
    SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

use super::separator::{dissect, SEP};
use super::split_cholesky::SplitCholesky;
use crate::assembly::Pattern;

/// Smallest system for which the split factorization is used (below it the monolithic
/// factorization takes under about a millisecond and the halves' join does not pay).
pub const SPLIT_MIN_EQUATIONS: usize = 4000;
/// Largest separator, as a fraction of the equations, for which the split is used.
const SPLIT_MAX_SEPARATOR: f64 = 0.05;
/// Smallest half, as a fraction of the equations outside the separator.
const SPLIT_MIN_HALF: f64 = 0.35;
/// Largest |Σ|³ (the order of the split's dense work: the separator's blocks of the two
/// halves, their products S_k and the factorization of S, each about |Σ|³/3 multiply-adds)
/// against the monolithic factor's Σ c_j². Measured: ≈ 0.05 on 5-DOF grids from 32² to
/// 100², where the split's critical path is 1.9–2.1× shorter; ≈ 1.0 on the three-ply
/// `nbc_hood.ron` and `nbc_sleeve_on_arm.ron` tangents, whose plies AMD orders almost
/// independently while a level-set separator cuts through all three (1.0–1.15×).
const SPLIT_MAX_DENSE_WORK: f64 = 0.25;

/// Which factorization the last numeric step produced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FactorKind {
    /// Positive definite: LLᵀ.
    Llt,
    /// Not positive definite: LDLᵀ without pivoting.
    Ldlt,
}

/// Errors of the linear solver.
#[derive(Clone, Debug)]
pub enum LinearError {
    /// The symbolic analysis failed (out of memory or index overflow).
    Symbolic(String),
    /// The tangent is singular (a zero pivot in LDLᵀ).
    Singular,
}

impl std::fmt::Display for LinearError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LinearError::Symbolic(s) => write!(f, "symbolic factorization failed: {s}"),
            LinearError::Singular => write!(f, "tangent matrix is singular"),
        }
    }
}

/// The monolithic factorization: AMD symbolic analysis and the factor's storage.
struct Monolithic {
    symbolic: SymbolicCholesky<usize>,
    l_values: Vec<f64>,
    buffer: MemBuffer,
}

/// AMD ordering and symbolic analysis of the monolithic factorization.
fn monolithic_symbolic(sym: SymbolicSparseColMatRef<'_, usize>) -> Result<SymbolicCholesky<usize>, LinearError> {
    let n = sym.nrows();
    factorize_symbolic_cholesky(sym, Side::Upper, SymmetricOrdering::Amd, CholeskySymbolicParams::default())
        .map_err(|e| LinearError::Symbolic(format!("{e:?} (analysing {n} equations with {} stored entries)", sym.row_idx().len())))
}

/// Σ c_j² over the columns of the factor (c_j the column's entries): proportional to the
/// numeric factorization's floating-point work (George & Liu 1981, §2.2: Σ c_j(c_j + 3)/2
/// multiplications for LLᵀ).
fn factor_work(symbolic: &SymbolicCholesky<usize>) -> f64 {
    let mut work = 0.0;
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(sym) => {
            let cp = sym.col_ptr();
            for j in 0..sym.ncols() {
                work += ((cp[j + 1] - cp[j]) as f64).powi(2);
            }
        }
        SymbolicCholeskyRaw::Supernodal(sym) => {
            for k in 0..sym.n_supernodes() {
                let w = sym.supernode_end()[k] - sym.supernode_begin()[k];
                let below = sym.supernode(k).pattern().len();
                for t in 0..w {
                    work += ((w - t + below) as f64).powi(2);
                }
            }
        }
    }
    work
}

impl Monolithic {
    /// Allocates the factor's storage and workspace for the analysed `symbolic`.
    fn new(symbolic: SymbolicCholesky<usize>) -> Result<Self, LinearError> {
        let n = symbolic.nrows();
        // The factor's size is known now, before its storage is allocated: check it against
        // the memory budget and allocate fallibly (an abort is never the answer).
        let len = symbolic.len_val();
        crate::budget::check_alloc(&format!("the Cholesky factor of {n} equations ({len} entries)"), len as u64, 8).map_err(LinearError::Symbolic)?;
        let mut l_values = Vec::new();
        l_values
            .try_reserve_exact(len)
            .map_err(|_| LinearError::Symbolic(format!("out of memory for the Cholesky factor of {n} equations ({len} entries)")))?;
        l_values.resize(len, 0.0);
        let par = Par::Seq;
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()),
            symbolic.factorize_numeric_ldlt_scratch::<f64>(par, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, par),
        ]);
        let buffer = MemBuffer::try_new(req).map_err(|_| LinearError::Symbolic("out of memory for workspace".into()))?;
        Ok(Self { symbolic, l_values, buffer })
    }
}

/// A reusable sparse Cholesky solver for one pattern.
pub struct SparseCholesky {
    pattern: SymbolicSparseColMat<usize>,
    /// The two-core split factorization, if the pattern has a good separator.
    split: Option<SplitCholesky>,
    /// The monolithic factorization: allocated at once without a split, on first use
    /// otherwise (from `mono_symbolic`).
    mono: Option<Monolithic>,
    mono_symbolic: Option<SymbolicCholesky<usize>>,
    /// The last successful numeric factorization is the split one.
    split_active: bool,
    kind: FactorKind,
    /// Matrix values of the factorization held, if it succeeded.
    factored: Option<Vec<f64>>,
    /// CPU seconds on the numeric factorizations' critical path so far: the calling
    /// thread's for the monolithic one, max(halves) + Schur for the split one.
    cpu_path: f64,
}

impl SparseCholesky {
    /// Symbolic analysis of the upper-triangular pattern; `threads` for the numeric phase
    /// (two or more: the split factorization where it applies).
    pub fn analyse(pattern: &Pattern, threads: usize) -> Result<Self, LinearError> {
        let n = pattern.n;
        let sym = SymbolicSparseColMat::new_checked(n, n, pattern.col_ptr.clone(), None, pattern.row_idx.clone());
        let symbolic = monolithic_symbolic(sym.as_ref())?;
        let split = if threads >= 2 && n >= SPLIT_MIN_EQUATIONS { Self::analyse_split(pattern, factor_work(&symbolic))? } else { None };
        let (mono, mono_symbolic) = if split.is_none() { (Some(Monolithic::new(symbolic)?), None) } else { (None, Some(symbolic)) };
        Ok(Self { pattern: sym, split, mono, mono_symbolic, split_active: false, kind: FactorKind::Llt, factored: None, cpu_path: 0.0 })
    }

    /// The split analysis if the pattern's separator is small (≤ 5 % of the equations),
    /// balanced (each half ≥ 35 % of the rest) and its dense work |Σ|³ small against the
    /// monolithic factorization's `mono_work` ([`factor_work`]); None otherwise.
    fn analyse_split(pattern: &Pattern, mono_work: f64) -> Result<Option<SplitCholesky>, LinearError> {
        let n = pattern.n;
        let part = dissect(n, &pattern.col_ptr, &pattern.row_idx);
        let mut counts = [0usize; 3];
        part.iter().for_each(|&p| counts[p as usize] += 1);
        let rest = (n - counts[SEP as usize]) as f64;
        let small = counts[SEP as usize] as f64 <= SPLIT_MAX_SEPARATOR * n as f64;
        let balanced = counts[0].min(counts[1]) as f64 >= SPLIT_MIN_HALF * rest;
        let dense = (counts[SEP as usize] as f64).powi(3);
        if !(small && balanced && dense <= SPLIT_MAX_DENSE_WORK * mono_work) {
            return Ok(None);
        }
        let split = SplitCholesky::analyse(n, &pattern.col_ptr, &pattern.row_idx, &part).map_err(|e| LinearError::Symbolic(format!("{e} (splitting {n} equations)")))?;
        crate::budget::check_alloc(&format!("the split Cholesky factor of {n} equations"), split.factor_nnz() as u64, 8).map_err(LinearError::Symbolic)?;
        Ok(Some(split))
    }

    /// Size of the split factorization's separator, if the split is in use.
    pub fn separator_len(&self) -> Option<usize> {
        self.split.as_ref().map(|s| s.separator_len())
    }

    /// CPU seconds of the last split factorization: half 1, half 2 (each on its core), and
    /// the dense Schur complement's assembly and LLᵀ; None without the split.
    pub fn split_profile(&self) -> Option<[f64; 3]> {
        self.split.as_ref().map(|s| s.profile)
    }

    /// CPU seconds on the critical path of the numeric factorizations so far (what the
    /// factorizations take on free cores; a shared machine inflates their wall time).
    pub fn cpu_path_seconds(&self) -> f64 {
        self.cpu_path
    }

    /// Takes over the critical-path CPU time of the factorizations of `old` (a solver for
    /// the pattern this one's grew from).
    pub fn carry_cpu_path(&mut self, old: &SparseCholesky) {
        self.cpu_path += old.cpu_path;
    }

    /// The monolithic factorization, analysed on first use.
    fn mono(&mut self) -> Result<&mut Monolithic, LinearError> {
        if self.mono.is_none() {
            let symbolic = match self.mono_symbolic.take() {
                Some(s) => s,
                None => monolithic_symbolic(self.pattern.as_ref())?,
            };
            self.mono = Some(Monolithic::new(symbolic)?);
        }
        self.mono.as_mut().ok_or(LinearError::Singular)
    }

    /// Which factorization the last successful numeric step produced.
    pub fn kind(&self) -> FactorKind {
        self.kind
    }

    /// Number of stored values of the factor (of the split factorization if in use).
    pub fn factor_nnz(&self) -> usize {
        match (&self.split, &self.mono) {
            (Some(s), _) if self.split_active || self.mono.is_none() => s.factor_nnz(),
            (_, Some(m)) => m.l_values.len(),
            _ => 0,
        }
    }

    fn matrix<'a>(&'a self, values: &'a [f64]) -> SparseColMatRef<'a, usize, f64> {
        let s: SymbolicSparseColMatRef<'a, usize> = self.pattern.as_ref();
        SparseColMatRef::new(s, values)
    }

    /// Numeric factorization of the matrix with the analysed pattern and `values`; a matrix
    /// equal to the one factorized last keeps that factorization (e.g. the inertia check of
    /// a converged increment and the first iteration of the next one).
    pub fn factorize(&mut self, values: &[f64]) -> Result<FactorKind, LinearError> {
        if self.factored.as_deref() == Some(values) {
            return Ok(self.kind);
        }
        let mut factored = self.factored.take().unwrap_or_default();
        let kind = self.factorize_numeric(values)?;
        factored.clear();
        factored.extend_from_slice(values);
        self.factored = Some(factored);
        Ok(kind)
    }

    /// LLᵀ factorization only: Ok(true) when the matrix is positive definite (the factor is
    /// then ready for [`Cholesky::solve`]), Ok(false) when the factorization met a
    /// non-positive pivot. No LDLᵀ fallback: for callers that replace an indefinite matrix
    /// anyway (projected Newton), where the inertia of the rejected matrix is not needed.
    pub fn factorize_definite(&mut self, values: &[f64]) -> bool {
        if self.factored.as_deref() == Some(values) {
            return self.kind == FactorKind::Llt;
        }
        let mut factored = self.factored.take().unwrap_or_default();
        let ok = self.factorize_llt(values);
        if !ok {
            // The partial factor is garbage: nothing is cached.
            return false;
        }
        self.kind = FactorKind::Llt;
        factored.clear();
        factored.extend_from_slice(values);
        self.factored = Some(factored);
        true
    }

    /// LLᵀ by the split factorization if there is one, else by the monolithic one; false if
    /// the matrix is not positive definite (a split that meets a non-positive pivot is not
    /// followed by a monolithic LLᵀ: the caller's LDLᵀ, if any, gives the inertia).
    fn factorize_llt(&mut self, values: &[f64]) -> bool {
        let t = crate::cpu_time::thread_seconds();
        if let Some(split) = &mut self.split {
            // A failure of the split's LLᵀ means A is not positive definite (each bordered
            // half is a principal submatrix's congruent, S its Schur complement); the
            // monolithic LDLᵀ below gives the inertia.
            let ok = split.factorize(values);
            let [h1, h2, s] = split.profile;
            self.cpu_path += h1.max(h2) + s + (crate::cpu_time::thread_seconds() - t);
            self.split_active = ok;
            return ok;
        }
        self.split_active = false;
        let pattern = &self.pattern;
        let Some(mono) = self.mono.as_mut() else { return false };
        let a = SparseColMatRef::new(pattern.as_ref(), values);
        let ok = mono
            .symbolic
            .factorize_numeric_llt::<f64>(&mut mono.l_values, a, Side::Upper, LltRegularization::default(), Par::Seq, MemStack::new(&mut mono.buffer), Default::default())
            .is_ok();
        self.cpu_path += crate::cpu_time::thread_seconds() - t;
        ok
    }

    fn factorize_numeric(&mut self, values: &[f64]) -> Result<FactorKind, LinearError> {
        if self.factorize_llt(values) {
            self.kind = FactorKind::Llt;
            return Ok(FactorKind::Llt);
        }
        let t = crate::cpu_time::thread_seconds();
        self.mono()?;
        let pattern = &self.pattern;
        let mono = self.mono.as_mut().ok_or(LinearError::Singular)?;
        let a = SparseColMatRef::new(pattern.as_ref(), values);
        mono.symbolic
            .factorize_numeric_ldlt::<f64>(&mut mono.l_values, a, Side::Upper, LdltRegularization::default(), Par::Seq, MemStack::new(&mut mono.buffer), Default::default())
            .map_err(|_| LinearError::Singular)?;
        self.cpu_path += crate::cpu_time::thread_seconds() - t;
        self.split_active = false;
        self.kind = FactorKind::Ldlt;
        Ok(FactorKind::Ldlt)
    }

    /// Solves A x = rhs in place with the last factorization.
    pub fn solve(&mut self, rhs: &mut [f64]) {
        if self.split_active {
            if let Some(split) = &mut self.split {
                split.solve(rhs);
            }
            return;
        }
        let Some(mono) = self.mono.as_mut() else { return };
        let n = rhs.len();
        let mat = MatMut::from_column_major_slice_mut(rhs, n, 1);
        let stack = MemStack::new(&mut mono.buffer);
        match self.kind {
            FactorKind::Llt => LltRef::new(&mono.symbolic, &mono.l_values).solve_in_place_with_conj(Conj::No, mat, Par::Seq, stack),
            FactorKind::Ldlt => LdltRef::new(&mono.symbolic, &mono.l_values).solve_in_place_with_conj(Conj::No, mat, Par::Seq, stack),
        }
    }

    /// Inertia of the last factorized matrix: the number of negative pivots of D in
    /// P A Pᵀ = L D Lᵀ (0 after a successful LLᵀ). L is unit lower triangular, so A is
    /// congruent to D and by Sylvester's law of inertia A has exactly as many negative
    /// eigenvalues as D has negative entries. The LDLᵀ runs without pivoting and without
    /// regularization (`LdltRegularization::default()` has no sign enforcement), so the
    /// signs are those of the exact factorization whenever it exists and is computed stably.
    pub fn negative_pivots(&self) -> usize {
        if self.kind == FactorKind::Llt {
            return 0;
        }
        self.pivots().iter().filter(|d| **d < 0.0).count()
    }

    /// The pivots of the last factorization: D of L D Lᵀ, or the squared diagonal of L
    /// after LLᵀ (in elimination order).
    pub fn pivots(&self) -> Vec<f64> {
        if self.split_active {
            return self.split.as_ref().map(|s| s.pivots()).unwrap_or_default();
        }
        let square = self.kind == FactorKind::Llt;
        let Some(mono) = self.mono.as_ref() else { return Vec::new() };
        let mut out = Vec::with_capacity(mono.symbolic.nrows());
        match mono.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(sym) => {
                // Each column of the simplicial factor stores its diagonal first.
                let cp = sym.col_ptr();
                let l = simplicial::SimplicialLdltRef::<'_, usize, f64>::new(sym, &mono.l_values);
                let v = l.values();
                for j in 0..sym.ncols() {
                    out.push(v[cp[j]]);
                }
            }
            SymbolicCholeskyRaw::Supernodal(sym) => {
                // The top block of each supernode holds the diagonal block of the factor.
                let l = supernodal::SupernodalLdltRef::<'_, usize, f64>::new(sym, &mono.l_values);
                for s in 0..sym.n_supernodes() {
                    let m = l.supernode(s).val();
                    for j in 0..m.ncols() {
                        out.push(m[(j, j)]);
                    }
                }
            }
        }
        if square {
            out.iter_mut().for_each(|d| *d *= *d);
        }
        out
    }

    /// Smallest over largest pivot magnitude of the last factorization: a cheap
    /// conditioning indicator (round-off level means a mechanism or a critical point).
    pub fn pivot_ratio(&self) -> f64 {
        let p = self.pivots();
        let lo = p.iter().fold(f64::INFINITY, |m, d| m.min(d.abs()));
        let hi = p.iter().fold(0.0f64, |m, d| m.max(d.abs()));
        if hi > 0.0 { lo / hi } else { 0.0 }
    }

    /// y = A x for the symmetric matrix stored as its upper triangle with `values`.
    pub fn multiply(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        let a = self.matrix(values);
        y.iter_mut().for_each(|v| *v = 0.0);
        let (cp, ri) = (a.symbolic().col_ptr(), a.symbolic().row_idx());
        for c in 0..x.len() {
            for p in cp[c]..cp[c + 1] {
                let r = ri[p];
                y[r] += values[p] * x[c];
                if r != c {
                    y[c] += values[p] * x[r];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 5-point Laplacian plus a shift on an m×m grid, upper triangle.
    fn laplacian(m: usize) -> (Pattern, Vec<f64>) {
        let n = m * m;
        let mut col_ptr = vec![0];
        let mut row_idx = Vec::new();
        let mut values = Vec::new();
        for c in 0..n {
            let (i, j) = (c % m, c / m);
            if j > 0 {
                row_idx.push(c - m);
                values.push(-1.0);
            }
            if i > 0 {
                row_idx.push(c - 1);
                values.push(-1.0);
            }
            row_idx.push(c);
            values.push(4.01);
            col_ptr.push(row_idx.len());
        }
        (Pattern { n, col_ptr, row_idx }, values)
    }

    #[test]
    fn solves_small_and_large_systems_to_round_off() {
        for m in [5, 60, 150] {
            let (p, v) = laplacian(m);
            let mut chol = SparseCholesky::analyse(&p, 2).unwrap();
            assert_eq!(chol.factorize(&v).unwrap(), FactorKind::Llt);
            let b: Vec<f64> = (0..p.n).map(|i| ((i * 7919) % 13) as f64 - 6.0).collect();
            let mut x = b.clone();
            chol.solve(&mut x);
            let mut ax = vec![0.0; p.n];
            chol.multiply(&v, &x, &mut ax);
            let err = ax.iter().zip(&b).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            assert!(err < 1e-10, "m={m}: residual {err}");
            // Indefinite: shift the diagonal negative, LDLT takes over.
            let vneg: Vec<f64> = v.iter().map(|&a| if a > 0.0 { a - 6.0 } else { a }).collect();
            assert_eq!(chol.factorize(&vneg).unwrap(), FactorKind::Ldlt);
            let mut x = b.clone();
            chol.solve(&mut x);
            chol.multiply(&vneg, &x, &mut ax);
            let err = ax.iter().zip(&b).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            assert!(err < 1e-8, "m={m} indefinite: residual {err}");
        }
    }

    /// The negative-pivot count equals the number of negative eigenvalues (Sylvester's law
    /// of inertia) for shifted 5-point Laplacians, whose eigenvalues are known in closed form:
    /// λ_ij = d − 2cos(iπ/(m+1)) − 2cos(jπ/(m+1)) for diagonal d. Small m exercises the
    /// simplicial factor, large m the supernodal one.
    #[test]
    fn negative_pivots_count_negative_eigenvalues() {
        for m in [6, 40, 150] {
            let (p, v) = laplacian(m);
            let mut chol = SparseCholesky::analyse(&p, 1).unwrap();
            let supernodal = matches!(chol.mono.as_ref().unwrap().symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_));
            if m != 40 {
                assert_eq!(supernodal, m > 40, "m={m}: expected the other factor storage");
            }
            for shift in [0.0, 1.3, 2.7, 4.6] {
                let d = 4.01 - shift;
                let vs: Vec<f64> = v.iter().map(|&a| if a > 0.0 { d } else { a }).collect();
                chol.factorize(&vs).unwrap();
                let h = std::f64::consts::PI / (m + 1) as f64;
                let mut expected = 0;
                for i in 1..=m {
                    for j in 1..=m {
                        if d - 2.0 * (h * i as f64).cos() - 2.0 * (h * j as f64).cos() < 0.0 {
                            expected += 1;
                        }
                    }
                }
                assert_eq!(chol.negative_pivots(), expected, "m={m} shift={shift}");
            }
        }
    }
}
