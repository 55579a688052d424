//! Mixed-integration-point stresses for Newton's geometric stiffness.
//!
//! Magisano, Leonetti & Garcea (2017), *How to improve efficiency and robustness of the
//! Newton method in geometrically nonlinear structural problems discretized via
//! displacement-based finite elements* (CMAME 313, 986–1005): the stresses at the
//! integration points are treated as independent variables of the Newton iteration (the
//! Hellinger–Reissner form condensed point by point). Linearising r_u = Σ Bᵀσ − f and
//! r_σ = E(q) − C⁻¹σ at (q_k, σ_k) and eliminating Δσ leaves the displacement system
//! (K_σ(σ_k) + BᵀCB) Δq = f − Bᵀ S(E(q_k)) — the standard residual with the geometric
//! stiffness K_σ evaluated with σ_k — and the stress update σ_{k+1} = S(E_k) + C_k B_k Δq,
//! the stress *extrapolated* along the linearised strain instead of recomputed from
//! E(q_{k+1}). After a Newton step that turns part of a thin shell rigidly, E(q_{k+1})
//! carries the spurious membrane stretch of the linearised rotation (½|Δθ|² per unit
//! length); the displacement-based tangent feeds that stress into K_σ and the next steps
//! zigzag, while the extrapolated σ_{k+1} does not contain it. Since
//! σ̃_{k+1} − S(E_{k+1}) = O(|Δq|²), quadratic convergence is kept.
//!
//! An element records, at each tangent evaluation, its w·detJ-weighted stress S·w and the
//! rows D·B·w per integration point ([`PointRecord`]); the assembler extrapolates them to the
//! next evaluation's configuration ([`extrapolate`]) with the change of the element's
//! unknowns since the record ([`unknown_change`]).

use nalgebra::Vector3;

use super::director::DirectorFrame;
use super::rule::ElementGeometry;
use super::{ELEMENT_DOFS, NODE_DOFS};
use crate::material::Voigt5;

/// What a tangent evaluation records at one integration point: the w·detJ-weighted stress
/// (lamina Voigt components as the material returns them) and the rows of D·B·w·detJ, so
/// that the stress of a nearby configuration q is predicted as sw + db·(q − q_rec).
#[derive(Clone, Copy, Debug)]
pub struct PointRecord {
    /// Stress × w·detJ.
    pub sw: Voigt5,
    /// D·B × w·detJ, one 20-wide row per stress component.
    pub db: [[f64; ELEMENT_DOFS]; 5],
}

impl Default for PointRecord {
    fn default() -> Self {
        Self { sw: Voigt5::zeros(), db: [[0.0; ELEMENT_DOFS]; 5] }
    }
}

/// Mixed-stress input and output of one element evaluation with its tangent.
pub struct Mixed<'a> {
    /// The extrapolated w·detJ-weighted stress per integration point, used for the geometric
    /// stiffness in place of the stress of the current strains; None: the current stress.
    pub geo: Option<&'a [Voigt5]>,
    /// Receives this evaluation's [`PointRecord`] per integration point.
    pub record: &'a mut [PointRecord],
}

/// Number of integration points of an element's rule: the length of its [`Mixed`] slices.
pub fn point_count(geom: &ElementGeometry) -> usize {
    geom.points.len()
}

/// Change of an element's 20 unknowns from the recorded configuration (`u0`, `f0`) to
/// (`u`, `f`): the translations' difference and, per node, the tilt (α1, α2) in the
/// recorded frame (t1, t2) that carries the recorded director onto the current one along
/// the great circle — the inverse of the exponential map d = cos|θ| d₀ + sin|θ| θ/|θ|
/// of [`DirectorFrame::tilted`].
pub fn unknown_change(u0: &[Vector3<f64>; 4], f0: &[DirectorFrame; 4], u: &[Vector3<f64>; 4], f: &[DirectorFrame; 4]) -> [f64; ELEMENT_DOFS] {
    let mut dq = [0.0; ELEMENT_DOFS];
    for a in 0..4 {
        let du = u[a] - u0[a];
        let d0 = f0[a].d;
        let d = f[a].d;
        let tangential = d - d0 * d0.dot(&d);
        let s = tangential.norm();
        let (a1, a2) = if s > 1e-300 {
            let angle = s.atan2(d0.dot(&d)) / s;
            (angle * tangential.dot(&f0[a].t1), angle * tangential.dot(&f0[a].t2))
        } else {
            (0.0, 0.0)
        };
        let q = &mut dq[NODE_DOFS * a..NODE_DOFS * (a + 1)];
        q.copy_from_slice(&[du.x, du.y, du.z, a1, a2]);
    }
    dq
}

/// The predicted w·detJ-weighted stress sw + db·Δq of each recorded point.
pub fn extrapolate(records: &[PointRecord], dq: &[f64; ELEMENT_DOFS], out: &mut [Voigt5]) {
    for (o, r) in out.iter_mut().zip(records) {
        let mut s = r.sw;
        for (c, row) in r.db.iter().enumerate() {
            s[c] += row.iter().zip(dq).map(|(a, b)| a * b).sum::<f64>();
        }
        *o = s;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_change_inverts_the_tilt_and_the_translation() {
        let f0 = [DirectorFrame::new(Vector3::new(0.1, -0.2, 1.0), Some(Vector3::x())); 4];
        let alpha = [[0.3, -0.4], [0.0, 0.0], [1e-9, 2e-9], [-1.2, 0.7]];
        let f: [DirectorFrame; 4] = std::array::from_fn(|a| f0[a].tilted(alpha[a]));
        let u0 = [Vector3::new(1.0, 2.0, 3.0); 4];
        let u: [Vector3<f64>; 4] = std::array::from_fn(|a| u0[a] + Vector3::new(a as f64, -0.5, 0.25));
        let dq = unknown_change(&u0, &f0, &u, &f);
        for a in 0..4 {
            for i in 0..3 {
                assert!((dq[5 * a + i] - (u[a] - u0[a])[i]).abs() < 1e-14);
            }
            assert!((dq[5 * a + 3] - alpha[a][0]).abs() < 1e-12 && (dq[5 * a + 4] - alpha[a][1]).abs() < 1e-12, "node {a}: {:?}", &dq[5 * a + 3..5 * a + 5]);
        }
    }
}
