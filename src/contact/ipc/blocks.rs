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
//!
//! The rows are split into as many ranges as there are threads, balanced by the layout's
//! blocks, and each range goes through every contribution in order, keeping the blocks (and
//! the forces) of its own rows: each block and force still sums the same contributions in
//! the same order.

use std::ops::Range;

use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;

use super::potential::{Derivative, FxMap};
use crate::element::NODE_DOFS;

/// The tangent blocks of the contact terms: −∇²E per node (row a = column b) and per node
/// pair a < b (the block of row a, column b), summed over one evaluation
/// ([`Blocks::sum_in_parts`], then [`Blocks::take`]).
#[derive(Default)]
pub(super) struct Blocks {
    /// The layout (the last evaluation's blocks): row a's columns are
    /// `cols[row_ptr[a]..row_ptr[a + 1]]`, ascending, each ≥ a.
    row_ptr: Vec<usize>,
    cols: Vec<usize>,
    /// This evaluation's sum of each layout block, valid where `touched`.
    sums: Vec<Matrix3<f64>>,
    touched: Vec<bool>,
    /// This evaluation's blocks outside the layout, per part of the rows.
    extra: Vec<FxMap<(usize, usize), Matrix3<f64>>>,
}

/// The blocks and forces of the rows (nodes) `rows`, summed by one thread.
pub(super) struct Part<'a> {
    rows: Range<usize>,
    row_ptr: &'a [usize],
    cols: &'a [usize],
    /// Layout index of `sums[0]`.
    first: usize,
    sums: &'a mut [Matrix3<f64>],
    touched: &'a mut [bool],
    extra: &'a mut FxMap<(usize, usize), Matrix3<f64>>,
    /// The forces of `rows` (`f[NODE_DOFS * (a − rows.start) + c]`).
    f: &'a mut [f64],
}

impl Part<'_> {
    /// The sum of block (a, b), a ≤ b, a in this part's rows: zero when first met in this
    /// evaluation.
    #[inline]
    fn sum(&mut self, a: usize, b: usize) -> &mut Matrix3<f64> {
        if a + 1 < self.row_ptr.len() {
            let (start, end) = (self.row_ptr[a], self.row_ptr[a + 1]);
            if let Some(k) = self.cols[start..end].iter().position(|&c| c == b) {
                let i = start + k - self.first;
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
    /// b = nodes[j] of this part's rows, visiting each unordered slot pair once (a ≤ b).
    #[inline]
    fn add(&mut self, nodes: &[usize], block: impl Fn(usize, usize) -> Matrix3<f64>) {
        for (i, &a) in nodes.iter().enumerate() {
            if !self.rows.contains(&a) {
                continue;
            }
            for (j, &b) in nodes.iter().enumerate() {
                if a > b || (a == b && i != j) {
                    continue;
                }
                let m = block(i, j);
                *self.sum(a, b) -= m;
            }
        }
    }

    /// Subtracts `g` from the forces of node `a` when it is one of this part's rows.
    #[inline]
    fn force(&mut self, a: usize, g: impl Fn(usize) -> f64) {
        if self.rows.contains(&a) {
            let r = NODE_DOFS * (a - self.rows.start);
            for c in 0..3 {
                self.f[r + c] -= g(c);
            }
        }
    }

    /// Forces −∇E and blocks −∇²E (the diagonal ones symmetrised) of a [`Derivative`].
    pub(super) fn add_derivative(&mut self, d: &Derivative) {
        let nodes = &d.nodes[..d.m];
        for (k, &a) in nodes.iter().enumerate() {
            self.force(a, |c| d.g[k][c]);
        }
        self.add(nodes, |i, j| if i == j { (d.h[i][i] + d.h[i][i].transpose()) * 0.5 } else { d.block(i, j) });
    }

    /// Forces and blocks of a potential of r = Σ_k w_k x_k (friction): gradient w_k g and
    /// Hessian blocks w_i w_j K; slots with w_k = 0 contribute nothing and are skipped.
    pub(super) fn add_weighted(&mut self, nodes: &[usize; 4], weights: &[f64; 4], g: &Vector3<f64>, k: Option<&Matrix3<f64>>) {
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
            self.force(nodes[s], |c| weights[s] * g[c]);
        }
        let Some(k) = k else { return };
        self.add(&sub[..n], |i, j| k * (weights[used[i]] * weights[used[j]]));
    }
}

impl Blocks {
    /// Sums this evaluation's contributions: `add` is called once per part of the rows
    /// (`parts` of them, in parallel), each call making every contribution in order; each
    /// part keeps the blocks and the forces (into `f_ext`, all nodes' DOFs) of its rows.
    pub(super) fn sum_in_parts(&mut self, f_ext: &mut [f64], parts: usize, add: impl Fn(&mut Part) + Sync) {
        let nodes = f_ext.len() / NODE_DOFS;
        let parts = parts.clamp(1, nodes.max(1));
        // Row boundaries: equal shares of the layout's blocks, else of the nodes.
        let laid = self.row_ptr.len().saturating_sub(1).min(nodes);
        let mut bounds = vec![0usize; parts + 1];
        for p in 1..parts {
            bounds[p] = if self.cols.is_empty() {
                p * nodes / parts
            } else {
                let target = p * self.cols.len() / parts;
                self.row_ptr[..=laid].partition_point(|&r| r < target).min(laid)
            }
            .max(bounds[p - 1]);
        }
        bounds[parts] = nodes;
        self.extra.resize_with(parts, FxMap::default);
        let (row_ptr, cols) = (&self.row_ptr, &self.cols);
        let at = |a: usize| if a < row_ptr.len() { row_ptr[a] } else { cols.len() };
        let mut out: Vec<Part> = Vec::with_capacity(parts);
        let (mut sums, mut touched, mut f) = (&mut self.sums[..], &mut self.touched[..], &mut f_ext[..]);
        for (p, extra) in self.extra.iter_mut().enumerate() {
            let rows = bounds[p]..bounds[p + 1];
            let (first, last) = (at(rows.start), at(rows.end));
            let (s, rest_s) = std::mem::take(&mut sums).split_at_mut(last - first);
            let (t, rest_t) = std::mem::take(&mut touched).split_at_mut(last - first);
            let len_f = if p + 1 == parts { f.len() } else { NODE_DOFS * rows.len() };
            let (fp, rest_f) = std::mem::take(&mut f).split_at_mut(len_f);
            (sums, touched, f) = (rest_s, rest_t, rest_f);
            out.push(Part { rows, row_ptr, cols, first, sums: s, touched: t, extra, f: fp });
        }
        if parts == 1 {
            out.iter_mut().for_each(|p| add(p));
        } else {
            out.par_iter_mut().for_each(|p| add(p));
        }
    }

    /// Hands on this evaluation's blocks in (row, column) order — each node block to
    /// `node(a, −∇²E_aa)`, each node-pair block to `pair(a, b, −∇²E_ab)`, a < b — and makes
    /// them the layout of the next evaluation.
    pub(super) fn take(&mut self, mut node: impl FnMut(usize, Matrix3<f64>), mut pair: impl FnMut(usize, usize, Matrix3<f64>)) {
        let mut extra: Vec<((usize, usize), Matrix3<f64>)> = self.extra.iter_mut().flat_map(|e| e.drain()).collect();
        extra.sort_unstable_by_key(|e| e.0);
        let unchanged = extra.is_empty() && self.touched.iter().all(|&t| t);
        // The next layout, built as the blocks go out (in order) unless it is this one.
        let (mut row_ptr, mut cols) = (Vec::new(), Vec::new());
        let mut emit = |(a, b): (usize, usize), m: Matrix3<f64>| {
            if !unchanged {
                while row_ptr.len() <= a {
                    row_ptr.push(cols.len());
                }
                cols.push(b);
            }
            if a == b {
                node(a, m);
            } else {
                pair(a, b, m);
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
                    emit(e.0, e.1);
                }
                emit(key, self.sums[i]);
            }
        }
        for e in next {
            emit(e.0, e.1);
        }
        if !unchanged {
            row_ptr.push(cols.len());
            self.row_ptr = row_ptr;
            self.cols = cols;
            // Sums are written before they are read (`touched`): no need to clear them.
            self.sums.resize(self.cols.len(), Matrix3::zeros());
            self.touched.clear();
        }
        self.touched.resize(self.cols.len(), false);
        self.touched.iter_mut().for_each(|t| *t = false);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Over evaluations whose blocks come and go, summed in one, two or three parts of the
    /// rows, [`Blocks::take`] gives each evaluation's blocks in (row, column) order with the
    /// sums — bit for bit — of a hash map summing the same contributions in the same order
    /// from zero, and the same forces.
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
        let nodes = 90;
        for round in 0..14 {
            // Contributions on nodes base..base + span: the range moves, shrinks and grows.
            let span = [40usize, 40, 40, 60, 20, 20, 80, 80, 5, 40, 40, 4, 89, 4][round];
            let base = [0usize, 0, 3, 0, 10, 10, 0, 0, 2, 0, 0, 7, 0, 86][round];
            let mut list = Vec::new();
            while list.len() < 300 {
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
                // A feature's nodes are distinct.
                let mut seen = d.nodes[..m].to_vec();
                seen.sort_unstable();
                seen.dedup();
                if seen.len() == m {
                    list.push(d);
                }
            }
            let mut reference: FxMap<(usize, usize), Matrix3<f64>> = FxMap::default();
            let (mut f, mut f_ref) = (vec![0.0; NODE_DOFS * nodes], vec![0.0; NODE_DOFS * nodes]);
            for d in &list {
                let nodes = &d.nodes[..d.m];
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
            let parts = 1 + round % 3;
            blocks.sum_in_parts(&mut f, parts, |part| list.iter().for_each(|d| part.add_derivative(d)));
            let got = std::cell::RefCell::new(Vec::new());
            blocks.take(|a, m| got.borrow_mut().push(((a, a), m)), |a, b, m| got.borrow_mut().push(((a, b), m)));
            let got: Vec<((usize, usize), Matrix3<f64>)> = got.into_inner();
            let mut want: Vec<((usize, usize), Matrix3<f64>)> = reference.into_iter().collect();
            want.sort_unstable_by_key(|e| e.0);
            assert!(got.windows(2).all(|w| w[0].0 < w[1].0), "round {round}: (row, column) order");
            assert_eq!(got.len(), want.len(), "round {round}");
            for (g, w) in got.iter().zip(&want) {
                assert_eq!(g.0, w.0, "round {round}");
                assert!(g.1.iter().zip(w.1.iter()).all(|(p, q)| p.to_bits() == q.to_bits()), "round {round}: block {:?}", g.0);
            }
            assert!(f.iter().zip(&f_ref).all(|(p, q)| p.to_bits() == q.to_bits()), "round {round}: forces");
        }
    }
}
