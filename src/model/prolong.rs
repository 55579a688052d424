//! Prolongation of a state from a coarse structured grid onto a finer one of the same part
//! (nested iteration / mesh sequencing: a solve continued on a refined mesh, Briggs, Henson &
//! McCormick, *A Multigrid Tutorial* 2000, ch. 3, the interpolation operator I_{2h}^h).
//!
//! Both meshes are the `Rectangle` grid of the same part: node (i, j) of an nx × ny grid is
//! the part's node i + j (nx + 1), at the pattern point (i/nx, j/ny) of the part. A fine
//! node takes the bilinear interpolation, in the reference (pattern) coordinates, of the
//! coarse element containing it: its displacement from the same combination of the coarse
//! displacements (so the current position is the interpolated position, the reference
//! grid being affine), its director the normalised combination of the coarse directors.
//! Bilinear interpolation reproduces every affine field exactly, so a flat or affinely
//! deformed sheet is mapped without change.

use nalgebra::Vector3;

use super::{Model, State};
use crate::element::DirectorFrame;

/// A part meshed as a structured `nx × ny` grid of quads in a model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GridPart {
    /// Part index in the model.
    pub part: usize,
    /// Elements along the first and second pattern direction.
    pub nx: usize,
    /// See `nx`.
    pub ny: usize,
}

/// For each node of the fine grid (in its numbering) the coarse nodes and bilinear weights
/// (at most four, weights summing to 1) that interpolate it.
pub fn grid_weights(coarse: (usize, usize), fine: (usize, usize)) -> Vec<Vec<(usize, f64)>> {
    let ((cx, cy), (fx, fy)) = (coarse, fine);
    // Coarse cell and local coordinate of fine index k of n along an axis of c cells.
    let locate = |k: usize, n: usize, c: usize| -> (usize, f64) {
        let s = k as f64 * c as f64 / n as f64;
        let i = (s.floor() as usize).min(c.saturating_sub(1));
        (i, (s - i as f64).clamp(0.0, 1.0))
    };
    let mut out = Vec::with_capacity((fx + 1) * (fy + 1));
    for j in 0..=fy {
        let (cj, eta) = locate(j, fy, cy);
        for i in 0..=fx {
            let (ci, xi) = locate(i, fx, cx);
            let node = |a: usize, b: usize| a + b * (cx + 1);
            let w = [
                (node(ci, cj), (1.0 - xi) * (1.0 - eta)),
                (node(ci + 1, cj), xi * (1.0 - eta)),
                (node(ci, cj + 1), (1.0 - xi) * eta),
                (node(ci + 1, cj + 1), xi * eta),
            ];
            out.push(w.into_iter().filter(|&(_, w)| w != 0.0).collect());
        }
    }
    out
}

/// The displacement Σ w_a u_a and the director frame of the normalised Σ w_a d_a (first
/// tangent from Σ w_a t1_a) of `state` at the nodes and weights `w`; None where the directors
/// cancel (a folded state).
pub fn interpolate(state: &State, w: &[(usize, f64)]) -> Option<(Vector3<f64>, DirectorFrame)> {
    let u: Vector3<f64> = w.iter().map(|&(a, x)| state.u[a] * x).sum();
    let d: Vector3<f64> = w.iter().map(|&(a, x)| state.frames[a].d * x).sum();
    let t1: Vector3<f64> = w.iter().map(|&(a, x)| state.frames[a].t1 * x).sum();
    (d.norm() > 1e-8).then(|| (u, DirectorFrame::new(d, Some(t1))))
}

/// The state of `fine` interpolated from `state` of `coarse`, part by part (`parts` pairs the
/// coarse and fine grid of each part; nodes of other parts keep the fine reference state):
/// displacements bilinearly, directors bilinearly and normalised, each frame's first
/// tangent from the interpolated first tangents. Also returns, per fine node, the coarse
/// weights used (empty for nodes not mapped), so that other nodal fields can follow.
pub fn prolong(coarse: &Model, state: &State, fine: &Model, parts: &[(GridPart, GridPart)]) -> Result<(State, Vec<Vec<(usize, f64)>>), String> {
    let mut out = fine.initial_state();
    let mut weights = vec![Vec::new(); fine.n_nodes()];
    for (c, f) in parts {
        let (cp, fp) = (&coarse.parts[c.part], &fine.parts[f.part]);
        if cp.n_nodes != (c.nx + 1) * (c.ny + 1) || fp.n_nodes != (f.nx + 1) * (f.ny + 1) {
            return Err(format!(
                "part {}: {} coarse and {} fine nodes, not the {}×{} and {}×{} grids expected",
                fp.name, cp.n_nodes, fp.n_nodes, c.nx, c.ny, f.nx, f.ny
            ));
        }
        for (k, w) in grid_weights((c.nx, c.ny), (f.nx, f.ny)).into_iter().enumerate() {
            let n = fp.first_node + k;
            let w: Vec<(usize, f64)> = w.into_iter().map(|(a, x)| (cp.first_node + a, x)).collect();
            let (u, frame) = interpolate(state, &w).ok_or_else(|| format!("part {}: the coarse directors round fine node {k} cancel (folded coarse state)", fp.name))?;
            out.u[n] = u;
            out.frames[n] = frame;
            weights[n] = w;
        }
    }
    Ok((out, weights))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_sum_to_one_and_hit_coarse_nodes() {
        let w = grid_weights((2, 3), (4, 6));
        assert_eq!(w.len(), 5 * 7);
        for (k, wk) in w.iter().enumerate() {
            let s: f64 = wk.iter().map(|x| x.1).sum();
            assert!((s - 1.0).abs() < 1e-15, "node {k}: weights sum {s}");
        }
        // Fine node (2, 2) is coarse node (1, 1); fine (1, 0) the midpoint of coarse 0–1.
        assert_eq!(w[2 + 2 * 5], vec![(1 + 3, 1.0)]);
        assert_eq!(w[1], vec![(0, 0.5), (1, 0.5)]);
        // Non-nested ratio (3 → 5 cells): still a partition of unity.
        for wk in grid_weights((3, 3), (5, 5)) {
            assert!((wk.iter().map(|x| x.1).sum::<f64>() - 1.0).abs() < 1e-14);
        }
    }
}
