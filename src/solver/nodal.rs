//! Configuration-dependent forces on node translations — contact with rigid bodies, penalty
//! springs, tethers — added to the external loads in every assembly of every step kind
//! (static, damped, dynamic, path following), with their stiffness in the tangent.

use nalgebra::Matrix3;

use crate::element::NODE_DOFS;
use crate::model::{Model, State};

/// Forces on node translations that depend on the current configuration.
pub trait NodalForces: Send + Sync {
    /// Adds the forces acting on the nodes in `state` to `f_ext` (all DOFs, [`NODE_DOFS`] per
    /// node, same sign as applied loads) and pushes, for every node n they depend on, the 3×3
    /// block ∂f_n/∂u_n (forces depending only on their own node; the solver adds the
    /// symmetric part of −∂f/∂u to the tangent).
    fn add(&self, model: &Model, state: &State, f_ext: &mut [f64], jacobian: &mut Vec<(usize, Matrix3<f64>)>);
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
