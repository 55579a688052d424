//! Growth of the tangent's sparsity pattern when nodal-force terms (contact) bring node-pair
//! blocks outside it: the new couplings are merged into the pattern, the scatter maps moved
//! to the grown pattern (`Pattern::with_pairs`, `Assembler::regrown`), the symbolic analysis
//! redone, and the tangent assembled so far is carried into the grown pattern instead of
//! being assembled again. The old pattern is a sub-pattern of the grown one, so every
//! assembled entry has its place there; the entries that were outside — the only ones
//! missing — are then added at the new positions alone, in the order a full re-assembly would
//! add them, so the result is the same bit for bit (each entry receives the same operations
//! in the same order).

use std::time::Instant;

use nalgebra::Matrix3;

use super::linear::SparseCholesky;
use super::newton::Solver;
use crate::assembly::Pattern;
use crate::element::NODE_DOFS;
use crate::model::Model;

/// How a growth of the pattern ended.
pub(super) enum Growth {
    /// The analysis of the grown pattern failed; pattern and values unchanged.
    Failed,
    /// Grown, the assembled values carried over; `fresh[s]` marks the entries of the grown
    /// pattern that the old one lacked (still zero).
    Carried { fresh: Vec<bool> },
}

/// Slot of entry (r, c), r ≤ c, in the pattern, if stored and marked in `fresh`.
fn fresh_slot(col_ptr: &[usize], row_idx: &[usize], fresh: &[bool], r: usize, c: usize) -> Option<usize> {
    let p = row_idx[col_ptr[c]..col_ptr[c + 1]].binary_search(&r).ok()? + col_ptr[c];
    fresh[p].then_some(p)
}

/// [`super::nodal::add_node_block`] restricted to the entries marked in `fresh` (same loop
/// order, same operations).
fn add_node_block_fresh(model: &Model, p: &Pattern, fresh: &[bool], values: &mut [f64], n: usize, j: &Matrix3<f64>) {
    super::nodal::for_each_node_entry(model, n, j, |r, c, v| {
        if let Some(s) = fresh_slot(&p.col_ptr, &p.row_idx, fresh, r, c) {
            values[s] -= v;
        }
    });
}

/// [`super::nodal::add_node_pair_block`] restricted to the entries marked in `fresh` (same
/// loop order, same operations; for two free nodes each entry receives one term, the one
/// `BlockSlots::add_pair_blocks` adds).
fn add_node_pair_block_fresh(model: &Model, p: &Pattern, fresh: &[bool], values: &mut [f64], a: usize, b: usize, j: &Matrix3<f64>) {
    super::nodal::for_each_pair_entry(model, a, b, j, |r, c, v| {
        if let Some(s) = fresh_slot(&p.col_ptr, &p.row_idx, fresh, r, c) {
            values[s] += v;
        }
    });
}

/// How the nodal-force terms' tangent blocks went into the assembled tangent.
pub(super) enum NodalTangent {
    /// Added (into the pattern as it was, or as it grew).
    Added,
    /// Outside the pattern, which could not grow: left out.
    Dropped,
    /// The pattern grew but the tangent could not be carried over: assemble again.
    Reassemble,
}

impl<'m> Solver<'m> {
    /// Adds the tangent blocks of the nodal-force terms' `evaluation` to the assembled
    /// tangent. A block outside the pattern (a pair that came into contact outside it) grows
    /// the pattern; the tangent assembled so far is carried over and only the blocks'
    /// entries that were left out are added ([`Solver::add_fresh_blocks`]), unless the
    /// mixed-stress records are in use (they start anew with a new pattern, so the elements
    /// are assembled again, as before).
    pub(super) fn add_nodal_tangent(&mut self, evaluation: &super::reuse::NodalEvaluation) -> NodalTangent {
        let (jacobian, pairs) = (&evaluation.jacobian, &evaluation.pairs);
        let p = &self.assembler.pattern;
        self.block_slots.add_node_blocks(self.model, &p.col_ptr, &p.row_idx, &mut self.values, jacobian);
        let outside = self.block_slots.add_pair_blocks(self.model, &p.col_ptr, &p.row_idx, &mut self.values, pairs);
        if outside.is_empty() {
            return NodalTangent::Added;
        }
        let n_outside = outside.len();
        match self.grow_pattern_carrying(outside.clone()) {
            Growth::Carried { fresh } if !self.assembler.mixed => {
                self.add_fresh_blocks(&fresh, jacobian, pairs, &outside);
                NodalTangent::Added
            }
            Growth::Failed => {
                self.timings.dropped_pair_blocks += n_outside;
                NodalTangent::Dropped
            }
            Growth::Carried { .. } => NodalTangent::Reassemble,
        }
    }

    /// Couples the node pairs `pairs` in the tangent's pattern: rebuilds the pattern and the
    /// scatter maps and redoes the symbolic analysis. Returns false (pattern unchanged) when
    /// the analysis of the grown pattern fails. The values assembled so far are carried
    /// into the grown pattern ([`Solver::grow_pattern_carrying`]).
    pub(super) fn grow_pattern(&mut self, pairs: Vec<(usize, usize)>) -> bool {
        !matches!(self.grow_pattern_carrying(pairs), Growth::Failed)
    }

    /// [`Solver::grow_pattern`], telling how: the assembler's settings and kept element
    /// responses pass to the new one (`Assembler::take_over`), and the assembled values move
    /// to their positions in the grown pattern.
    pub(super) fn grow_pattern_carrying(&mut self, pairs: Vec<(usize, usize)>) -> Growth {
        let t0 = Instant::now();
        let mut couplings = self.couplings.clone();
        couplings.extend(pairs);
        couplings.sort_unstable();
        couplings.dedup();
        // The couplings not yet in the pattern, merged into it (`Pattern::with_pairs`: the
        // pattern `Assembler::with_couplings` builds with all of them).
        let added: Vec<(usize, usize)> = couplings.iter().filter(|p| self.couplings.binary_search(p).is_err()).copied().collect();
        let (pattern, pos) = self.assembler.pattern.with_pairs(self.model, &added);
        let threads = if self.settings.factor_threads == 0 { rayon::current_num_threads() } else { self.settings.factor_threads };
        // A pattern whose two-core split was refused is not dissected again on growth: the
        // grown pattern only adds couplings, which make no separator smaller (measured on the
        // 5 cm NBC hood, 506 growths: symbolic analysis 4.9 → 3.4 s).
        let threads = if self.cholesky.separator_len().is_none() { 1 } else { threads };
        let grown = match SparseCholesky::analyse(&pattern, threads) {
            Ok(mut cholesky) => {
                cholesky.carry_cpu_path(&self.cholesky);
                let mut values = vec![0.0; pattern.row_idx.len()];
                let mut fresh = vec![true; values.len()];
                for (&q, &v) in pos.iter().zip(&self.values) {
                    values[q] = v;
                    fresh[q] = false;
                }
                let growth = Growth::Carried { fresh };
                let assembler = self.assembler.regrown(pattern, &pos);
                self.values = values;
                self.assembler = assembler;
                self.cholesky = cholesky;
                self.couplings = couplings;
                self.block_slots.clear();
                self.timings.pattern_growths += 1;
                growth
            }
            Err(_) => Growth::Failed,
        };
        self.timings.analysis += t0.elapsed().as_secs_f64();
        grown
    }

    /// After a growth that carried the values over: adds the entries of the node blocks
    /// `jacobian` and node-pair blocks `pairs` (those `Solver::assemble` scattered before
    /// the growth) that fall on the `fresh` positions — the ones left out before — in the
    /// order of the blocks, as an assembly into the grown pattern would have added them.
    pub(super) fn add_fresh_blocks(&mut self, fresh: &[bool], jacobian: &[(usize, Matrix3<f64>)], pairs: &[(usize, usize, Matrix3<f64>)], outside: &[(usize, usize)]) {
        let p = &self.assembler.pattern;
        let free = |n: usize| (0..3).all(|k| self.model.dofs.eq[NODE_DOFS * n + k] != crate::model::FIXED);
        // A free node's own block lies in its element couplings, never on a new position.
        for (n, j) in jacobian.iter().filter(|(n, _)| !free(*n)) {
            add_node_block_fresh(self.model, p, fresh, &mut self.values, *n, j);
        }
        // Only a pair with an entry outside the old pattern has one on a new position.
        let mut outside = outside.to_vec();
        outside.sort_unstable();
        for (a, b, j) in pairs.iter().filter(|(a, b, _)| outside.binary_search(&(*a, *b)).is_ok()) {
            add_node_pair_block_fresh(self.model, p, fresh, &mut self.values, *a, *b, j);
        }
    }
}
