//! Configuration-dependent forces on node translations — contact with rigid bodies, viscous
//! stabilization, penalty springs, tethers — added to the external loads in every assembly of
//! every step kind (static, damped, dynamic, path following), with their stiffness in the
//! tangent. The single hook for such terms: stateful ones (friction anchors, the previous
//! configuration) are told when an increment begins and when it has converged.

use nalgebra::Matrix3;

use crate::element::NODE_DOFS;
use crate::model::{Model, State};

/// Forces on node translations that depend on the current configuration.
pub trait NodalForces: Send {
    /// Adds the forces acting on the nodes in `state` to `f_ext` (all DOFs, [`NODE_DOFS`] per
    /// node, same sign as applied loads) and pushes, for every node n they depend on, the 3×3
    /// block ∂f_n/∂u_n (forces depending only on their own node; the solver adds the
    /// symmetric part of −∂f/∂u to the tangent, through the tie transformation for tied
    /// slaves). A term that finds the trial state inadmissible (e.g. a node through a body)
    /// writes NaN into `f_ext`; the solver's safeguarded step then backtracks.
    fn add(&mut self, model: &Model, state: &State, f_ext: &mut [f64], jacobian: &mut Vec<(usize, Matrix3<f64>)>);
    /// Called before each (sub-)increment or time-step attempt with its size as a fraction of
    /// the nominal one (1 normally, ½, ¼, … after cut-backs).
    fn begin_increment(&mut self, fraction: f64) {
        let _ = fraction;
    }
    /// Called once per converged (sub-)increment or time step with the converged state, so
    /// the term can update its history; returns a report for the increment, if any.
    fn commit(&mut self, model: &Model, state: &State) -> Option<serde_json::Value> {
        let _ = (model, state);
        None
    }
    /// Wall time spent in proximity search so far (s), reported separately from assembly.
    fn search_seconds(&self) -> f64 {
        0.0
    }
    /// Extra point data to export for `state`: (name, components, values per node).
    fn point_data(&self, model: &Model, state: &State) -> Vec<(String, usize, Vec<f64>)> {
        let _ = (model, state);
        Vec::new()
    }
    /// A summary of the whole run: (section name in summary.json, value).
    fn summary(&self) -> Option<(String, serde_json::Value)> {
        None
    }
}

/// Adds −½(J + Jᵀ) of node `n`'s translations to the upper-triangular CSC tangent `values`.
pub(super) fn add_node_block(model: &Model, col_ptr: &[usize], row_idx: &[usize], values: &mut [f64], n: usize, j: &Matrix3<f64>) {
    // Through the tie transformation (Tᵀ J T) when the node is a tied slave.
    let expanded: [Vec<(usize, f64)>; 3] = std::array::from_fn(|a| model.dofs.expand(NODE_DOFS * n + a));
    for b in 0..3 {
        for &(c, wc) in &expanded[b] {
            for a in 0..3 {
                for &(r, wr) in &expanded[a] {
                    if r > c {
                        continue;
                    }
                    let rows = &row_idx[col_ptr[c]..col_ptr[c + 1]];
                    if let Ok(p) = rows.binary_search(&r) {
                        values[col_ptr[c] + p] -= 0.5 * wr * wc * (j[(a, b)] + j[(b, a)]);
                    }
                }
            }
        }
    }
}
