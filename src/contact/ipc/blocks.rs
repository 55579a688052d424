//! The tangent blocks of the surface-contact terms, summed per node pair into a layout kept
//! from one evaluation to the next.
//!
//! An evaluation adds some 190,000 contributions (the per-feature barrier derivatives, the
//! mollified edge–edge pairs and the friction terms; NBC sleeve on the arm) onto about 16,000
//! node-pair blocks, serially, in a fixed order. A hash map of the blocks, built afresh in
//! every evaluation, cost 2.4 s of that solve. Between Newton iterations the set of blocks
//! barely changes, so each block is looked up in the last evaluation's set instead: per row
//! node its columns, ascending (a compressed row layout); only blocks new to it go into a
//! hash map, and the layout becomes this evaluation's set for the next one. Each block sums
//! its contributions in the order they come, from zero, as the hash map did (the same values
//! bit for bit); the blocks are handed on in (row, column) order.

use nalgebra::{Matrix3, Vector3};

use super::potential::{Derivative, FxMap};
use crate::element::NODE_DOFS;

/// The tangent blocks of the contact terms: −∇²E per node (row a = column b) and per node
/// pair a < b (the block of row a, column b), summed over one evaluation ([`Blocks::take`]).
#[derive(Default)]
pub(super) struct Blocks {
    /// The layout (the last evaluation's blocks): row a's columns are
    /// `cols[row_ptr[a]..row_ptr[a + 1]]`, ascending, each ≥ a.
    row_ptr: Vec<usize>,
    cols: Vec<usize>,
    /// This evaluation's sum of each layout block, valid where `touched`.
    sums: Vec<Matrix3<f64>>,
    touched: Vec<bool>,
    /// This evaluation's blocks outside the layout.
    extra: FxMap<(usize, usize), Matrix3<f64>>,
}

impl Blocks {
    /// The sum of block (a, b), a ≤ b: zero when first met in this evaluation.
    #[inline]
    fn sum(&mut self, a: usize, b: usize) -> &mut Matrix3<f64> {
        if a + 1 < self.row_ptr.len() {
            let (start, end) = (self.row_ptr[a], self.row_ptr[a + 1]);
            if let Some(k) = self.cols[start..end].iter().position(|&c| c == b) {
                let i = start + k;
                if !self.touched[i] {
                    self.touched[i] = true;
                    self.sums[i] = Matrix3::zeros();
                }
                return &mut self.sums[i];
            }
        }
        self.extra.entry((a, b)).or_insert_with(Matrix3::zeros)
    }

    /// Adds −(the 3×3 block of slots i, j) to the tangent blocks of nodes a = nodes[i],
    /// b = nodes[j], visiting each unordered slot pair once (a ≤ b).
    fn add(&mut self, nodes: &[usize], block: impl Fn(usize, usize) -> Matrix3<f64>) {
        for (i, &a) in nodes.iter().enumerate() {
            for (j, &b) in nodes.iter().enumerate() {
                if a > b || (a == b && i != j) {
                    continue;
                }
                let m = block(i, j);
                *self.sum(a, b) -= m;
            }
        }
    }

    /// Forces −∇E into `f_ext` and blocks −∇²E (the diagonal ones symmetrised) of a
    /// [`Derivative`].
    pub(super) fn add_derivative(&mut self, d: &Derivative, f_ext: &mut [f64], hessian: bool) {
        let nodes = &d.nodes[..d.m];
        for (k, &a) in nodes.iter().enumerate() {
            for c in 0..3 {
                f_ext[NODE_DOFS * a + c] -= d.g[k][c];
            }
        }
        if hessian {
            self.add(nodes, |i, j| if i == j { (d.h[i][i] + d.h[i][i].transpose()) * 0.5 } else { d.block(i, j) });
        }
    }

    /// Forces and blocks of a potential of r = Σ_k w_k x_k (friction): gradient w_k g and
    /// Hessian blocks w_i w_j K; slots with w_k = 0 contribute nothing and are skipped.
    pub(super) fn add_weighted(&mut self, nodes: &[usize; 4], weights: &[f64; 4], g: &Vector3<f64>, k: Option<&Matrix3<f64>>, f_ext: &mut [f64]) {
        // The used slots and their nodes in fixed arrays (no allocation per pair).
        let (mut slots, mut sub, mut n) = ([0usize; 4], [0usize; 4], 0);
        for s in 0..4 {
            if weights[s] != 0.0 {
                (slots[n], sub[n]) = (s, nodes[s]);
                n += 1;
            }
        }
        let used = &slots[..n];
        for &s in used {
            for c in 0..3 {
                f_ext[NODE_DOFS * nodes[s] + c] -= weights[s] * g[c];
            }
        }
        let Some(k) = k else { return };
        self.add(&sub[..n], |i, j| k * (weights[used[i]] * weights[used[j]]));
    }

    /// This evaluation's blocks in (row, column) order — the node blocks (a, −∇²E_aa) and the
    /// node-pair blocks (a, b, −∇²E_ab), a < b — and a fresh start for the next evaluation,
    /// whose layout they become.
    pub(super) fn take(&mut self) -> (Vec<(usize, Matrix3<f64>)>, Vec<(usize, usize, Matrix3<f64>)>) {
        let mut extra: Vec<((usize, usize), Matrix3<f64>)> = self.extra.drain().collect();
        extra.sort_unstable_by_key(|e| e.0);
        let unchanged = extra.is_empty() && self.touched.iter().all(|&t| t);
        let (mut diag, mut off) = (Vec::new(), Vec::with_capacity(self.cols.len() + extra.len()));
        let mut push = |(a, b): (usize, usize), m: Matrix3<f64>| {
            if a == b {
                diag.push((a, m));
            } else {
                off.push((a, b, m));
            }
        };
        // The layout's touched blocks and the extra ones, merged in (row, column) order.
        let mut next = extra.into_iter().peekable();
        for a in 0..self.row_ptr.len().saturating_sub(1) {
            for i in self.row_ptr[a]..self.row_ptr[a + 1] {
                if !self.touched[i] {
                    continue;
                }
                let key = (a, self.cols[i]);
                while let Some(e) = next.next_if(|e| e.0 < key) {
                    push(e.0, e.1);
                }
                push(key, self.sums[i]);
            }
        }
        for e in next {
            push(e.0, e.1);
        }
        if unchanged {
            self.touched.iter_mut().for_each(|t| *t = false);
        } else {
            let rows = diag.iter().map(|d| d.0 + 1).chain(off.iter().map(|o| o.0 + 1)).max().unwrap_or(0);
            let mut count = vec![0usize; rows + 1];
            for a in diag.iter().map(|d| d.0).chain(off.iter().map(|o| o.0)) {
                count[a + 1] += 1;
            }
            for a in 0..rows {
                count[a + 1] += count[a];
            }
            // Both lists are in (row, column) order; a row's node block comes first.
            let mut cols = vec![0usize; count[rows]];
            let mut fill = count.clone();
            for (a, b) in diag.iter().map(|d| (d.0, d.0)).chain(off.iter().map(|o| (o.0, o.1))) {
                cols[fill[a]] = b;
                fill[a] += 1;
            }
            self.row_ptr = count;
            self.sums = vec![Matrix3::zeros(); cols.len()];
            self.touched = vec![false; cols.len()];
            self.cols = cols;
        }
        (diag, off)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Over evaluations whose blocks come and go, [`Blocks::take`] gives each evaluation's
    /// blocks, in (row, column) order, with the sums — bit for bit — of a hash map summing
    /// the same contributions in the same order from zero, and the same forces.
    #[test]
    fn blocks_match_a_fresh_hash_map_over_changing_sets() {
        let mut seed = 987654321u64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        let mut blocks = Blocks::default();
        for round in 0..12 {
            // Contributions on nodes 0..span: the node range moves and shrinks and grows.
            let span = [40usize, 40, 40, 60, 20, 20, 80, 80, 5, 40, 40, 1][round];
            let base = [0usize, 0, 3, 0, 10, 10, 0, 0, 2, 0, 0, 7][round];
            let mut reference: FxMap<(usize, usize), Matrix3<f64>> = FxMap::default();
            let n_dofs = NODE_DOFS * (base + span + 1);
            let (mut f, mut f_ref) = (vec![0.0; n_dofs], vec![0.0; n_dofs]);
            for _ in 0..300 {
                let m = 2 + (next() % 3) as usize;
                let mut d = Derivative::zero();
                d.m = m;
                for k in 0..m {
                    d.nodes[k] = base + (next() % span as u64) as usize;
                    d.g[k] = Vector3::from_fn(|_, _| (next() % 1000) as f64 * 0.37 - 150.0);
                    for l in 0..4 {
                        d.h[k][l] = Matrix3::from_fn(|_, _| (next() % 1000) as f64 * 1.3e-3 - 0.61);
                    }
                }
                // A feature's nodes are distinct; a friction pair may repeat none either.
                let mut seen = d.nodes[..m].to_vec();
                seen.sort_unstable();
                seen.dedup();
                if seen.len() < m {
                    continue;
                }
                blocks.add_derivative(&d, &mut f, true);
                let nodes = &d.nodes[..m];
                for (k, &a) in nodes.iter().enumerate() {
                    for c in 0..3 {
                        f_ref[NODE_DOFS * a + c] -= d.g[k][c];
                    }
                }
                for (i, &a) in nodes.iter().enumerate() {
                    for (j, &b) in nodes.iter().enumerate() {
                        if a > b {
                            continue;
                        }
                        let blk = if i == j { (d.h[i][i] + d.h[i][i].transpose()) * 0.5 } else { d.block(i, j) };
                        *reference.entry((a, b)).or_insert_with(Matrix3::zeros) -= blk;
                    }
                }
            }
            let (diag, off) = blocks.take();
            let got: Vec<((usize, usize), Matrix3<f64>)> = diag.iter().map(|&(a, m)| ((a, a), m)).chain(off.iter().map(|&(a, b, m)| ((a, b), m))).collect();
            let mut want: Vec<((usize, usize), Matrix3<f64>)> = reference.into_iter().collect();
            want.sort_unstable_by_key(|e| e.0);
            let mut sorted = got.clone();
            sorted.sort_unstable_by_key(|e| e.0);
            assert_eq!(diag.windows(2).all(|w| w[0].0 < w[1].0) && off.windows(2).all(|w| (w[0].0, w[0].1) < (w[1].0, w[1].1)), true, "round {round}: order");
            assert_eq!(got.len(), want.len(), "round {round}");
            for (g, w) in sorted.iter().zip(&want) {
                assert_eq!(g.0, w.0, "round {round}");
                assert!(g.1.iter().zip(w.1.iter()).all(|(p, q)| p.to_bits() == q.to_bits()), "round {round}: block {:?}", g.0);
            }
            assert!(f.iter().zip(&f_ref).all(|(p, q)| p.to_bits() == q.to_bits()), "round {round}: forces");
        }
    }
}
