//! Director orientation barrier: keeps every nodal director on its own side of the tangent
//! plane of each element corner it belongs to.
//!
//! MITC4 ties the transverse shear at the edge midpoints (Dvorkin & Bathe 1984), where it
//! sees only the average of the two nodal directors of an edge. A zigzag of the director
//! tilts along an edge (+θ, −θ, +θ, …) therefore stores no shear energy; only the bending
//! energy B (2θ/L)² A resists it. For fabric, whose bending rigidity B is 10⁻⁴ of its shear
//! stiffness times the element area, that is a near-mechanism: in a drape, impacts and
//! swinging free edges pump it until a director passes through the surface (90° and on to
//! 180° from the corner normal), an element is folded through itself and no time step
//! converges. A continuum Reissner–Mindlin shell would charge such a director the shear
//! energy G h A tan²θ; no physical state of a thin shell has a director within 60° of its
//! surface plane.
//!
//! The barrier charges exactly those states. For each corner I of an element, with corner
//! normal n_I = (x_{I+1} − x_I) × (x_{I−1} − x_I) / |…| and cosine c_I = s_I d_I · n_I (s_I
//! the sign of the reference configuration), the energy is
//!
//!   Π_b = κ Σ_I b(c_I),   b(c) = −(c − ĉ)² ln(c / ĉ) for c < ĉ, 0 otherwise,
//!
//! the log barrier of Incremental Potential Contact (Li et al., ACM TOG 39(4) 2020, eq. 6)
//! in the cosine instead of a distance: C² at the activation cosine ĉ = cos 60°, infinite as
//! the director reaches the tangent plane (c → 0), where the element reports
//! [`ElementFailure::DirectorThroughSurface`] so line searches backtrack. The stiffness
//! κ = `STIFFNESS` · B per corner is chosen to dominate the element-scale bending energy that
//! drives the zigzag (≈ B θ² per element); states with every director within 60° of its
//! corner normals — every regular shell state — are unchanged to the last bit.
//!
//! Gradient and Hessian are exact, from second-order forward differentiation (`autodiff`) in
//! the nine coordinates of the corner and its two neighbours and the corner director's two
//! tilts; the director varies as d + t1 α1 + t2 α2 − ½|α|² d, the second-order expansion of
//! the exponential map used by `director` (ΔΔd = −(δα·Δα) d).

use nalgebra::Vector3;

use super::director::DirectorFrame;
use super::shell4::ElementFailure;
use super::{ElemMat, ElemVec, NODE_DOFS};
use crate::autodiff::{Hd, Hv, cross, dot};

/// Activation cosine ĉ of the barrier: the director 60° off the corner normal.
pub const ACTIVATION: f64 = 0.5;

/// Barrier stiffness per corner in units of the section's bending rigidity B.
pub const STIFFNESS: f64 = 25.0;

/// Reference cosine below which a corner is left out (a reference director already far from
/// the corner normal: strongly warped or folded reference meshes).
const REFERENCE_MIN: f64 = 0.9;

/// Variables of one corner: 3 × 3 coordinates (the corner, its next and previous nodes) and
/// the corner director's two tilts.
const N: usize = 11;

/// Corner signs of an element from its reference configuration: s_I = sign(d_I · n_I), or 0
/// for a corner left out (|d_I · n_I| below `REFERENCE_MIN` or a degenerate corner).
pub fn reference_signs(x0: &[Vector3<f64>; 4], d0: &[Vector3<f64>; 4]) -> [i8; 4] {
    std::array::from_fn(|i| {
        let n = corner_normal(x0, i);
        let c = n.map_or(0.0, |n| d0[i].dot(&n));
        if c >= REFERENCE_MIN {
            1
        } else if c <= -REFERENCE_MIN {
            -1
        } else {
            0
        }
    })
}

/// Unit normal of corner `i`, (x_{i+1} − x_i) × (x_{i−1} − x_i) normalised (None if degenerate).
fn corner_normal(x: &[Vector3<f64>; 4], i: usize) -> Option<Vector3<f64>> {
    let m = (x[(i + 1) % 4] - x[i]).cross(&(x[(i + 3) % 4] - x[i]));
    let len = m.norm();
    (len > 0.0).then(|| m / len)
}

/// b(c) of the module doc and its first two derivatives (zero above ĉ).
fn barrier(c: f64) -> (f64, f64, f64) {
    if c >= ACTIVATION {
        return (0.0, 0.0, 0.0);
    }
    let (dc, l) = (c - ACTIVATION, (c / ACTIVATION).ln());
    (
        -dc * dc * l,
        -2.0 * dc * l - dc * dc / c,
        -2.0 * l - 4.0 * dc / c + dc * dc / (c * c),
    )
}

/// Adds the barrier's energy, force (to `force`) and tangent (to `k`, when given) for an
/// element with current positions `x`, director frames `frames`, reference corner signs
/// `signs` and corner stiffness `kappa`; returns the energy. Fails when a director has
/// reached or passed its corner's tangent plane.
pub fn add(
    x: &[Vector3<f64>; 4],
    frames: &[DirectorFrame; 4],
    signs: &[i8; 4],
    kappa: f64,
    force: &mut ElemVec,
    k: Option<&mut ElemMat>,
) -> Result<f64, ElementFailure> {
    let mut energy = 0.0;
    let mut k = k;
    for i in 0..4 {
        if signs[i] == 0 {
            continue;
        }
        let s = f64::from(signs[i]);
        let Some(n) = corner_normal(x, i) else {
            continue;
        };
        let c = s * frames[i].d.dot(&n);
        if c >= ACTIVATION {
            continue;
        }
        if c <= 0.0 || !c.is_finite() {
            return Err(ElementFailure::DirectorThroughSurface { cosine: c });
        }
        let nodes = [i, (i + 1) % 4, (i + 3) % 4];
        let cosine = corner_cosine(x, &frames[i], nodes).scale(s);
        let (b, b1, b2) = barrier(cosine.v);
        let e = cosine.chain(b, b1, b2).scale(kappa);
        energy += e.v;
        // Variable v ↦ element DOF: coordinates of nodes[v / 3], then the corner's tilts.
        let dof = |v: usize| {
            if v < 9 {
                NODE_DOFS * nodes[v / 3] + v % 3
            } else {
                NODE_DOFS * i + 3 + (v - 9)
            }
        };
        for a in 0..N {
            force[dof(a)] += e.g[a];
        }
        if let Some(k) = k.as_deref_mut() {
            for a in 0..N {
                for b in 0..N {
                    k[(dof(a), dof(b))] += e.h[a][b];
                }
            }
        }
    }
    Ok(energy)
}

/// d_I · n_I as a function of the 11 corner variables (at their current values: zero
/// displacement increments and tilts).
fn corner_cosine(x: &[Vector3<f64>; 4], frame: &DirectorFrame, nodes: [usize; 3]) -> Hd<N> {
    let p: [Hv<N>; 3] =
        std::array::from_fn(|j| std::array::from_fn(|c| Hd::var(x[nodes[j]][c], 3 * j + c)));
    let e1: Hv<N> = std::array::from_fn(|c| p[1][c] - p[0][c]);
    let e2: Hv<N> = std::array::from_fn(|c| p[2][c] - p[0][c]);
    let m = cross(&e1, &e2);
    let (a1, a2) = (Hd::<N>::var(0.0, 9), Hd::<N>::var(0.0, 10));
    let half_square = (a1 * a1 + a2 * a2).scale(0.5);
    let d: Hv<N> = std::array::from_fn(|c| {
        Hd::c(frame.d[c]) + a1.scale(frame.t1[c]) + a2.scale(frame.t2[c])
            - half_square.scale(frame.d[c])
    });
    let len2 = dot(&m, &m);
    let len = len2.v.sqrt();
    let inv_len = len2.chain(
        1.0 / len,
        -0.5 / (len * len2.v),
        0.75 / (len * len2.v * len2.v),
    );
    dot(&d, &m) * inv_len
}

#[cfg(test)]
mod tests {
    use super::*;

    fn element(tilt: f64) -> ([Vector3<f64>; 4], [DirectorFrame; 4]) {
        let x = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(0.1, 0.01, 0.002),
            Vector3::new(0.11, 0.09, -0.003),
            Vector3::new(-0.01, 0.1, 0.001),
        ];
        let frames = std::array::from_fn(|i| {
            let d = Vector3::new(
                if i % 2 == 0 { tilt } else { -tilt }.sin(),
                0.1 * tilt,
                if i % 2 == 0 { tilt } else { -tilt }.cos(),
            )
            .normalize();
            DirectorFrame::new(d, Some(Vector3::x()))
        });
        (x, frames)
    }

    #[test]
    fn barrier_is_c2_at_activation_and_grows_to_the_plane() {
        let (b, b1, b2) = barrier(ACTIVATION - 1e-9);
        assert!(b.abs() < 1e-17 && b1.abs() < 1e-8 && b2.abs() < 1e-7);
        assert!(barrier(1e-6).0 > barrier(0.1).0 && barrier(0.1).0 > barrier(0.3).0);
    }

    /// Inactive below 60°: no energy, force or stiffness, bit for bit.
    #[test]
    fn regular_states_are_untouched() {
        let (x, frames) = element(0.3);
        let signs = reference_signs(&x, &frames.map(|f| f.d));
        assert_eq!(signs, [1; 4]);
        let (mut f, mut k) = (ElemVec::zeros(), ElemMat::zeros());
        let e = add(&x, &frames, &signs, 1.0, &mut f, Some(&mut k)).expect("admissible");
        assert!(e == 0.0 && f.iter().all(|v| *v == 0.0) && k.iter().all(|v| *v == 0.0));
    }

    /// Force and tangent against central differences of the energy and force: translations
    /// moved directly, tilts by the director's exponential map (second-order consistent).
    #[test]
    fn force_and_tangent_match_finite_differences() {
        let (x, frames) = element(1.2);
        let signs = [1; 4];
        let kappa = 2.0;
        let (mut f, mut k) = (ElemVec::zeros(), ElemMat::zeros());
        let e0 = add(&x, &frames, &signs, kappa, &mut f, Some(&mut k)).expect("admissible");
        assert!(e0 > 0.0, "the 1.2 rad zigzag is inside the barrier");
        let perturbed = |j: usize, h: f64| {
            let (mut xp, mut fp) = (x, frames);
            let (node, c) = (j / NODE_DOFS, j % NODE_DOFS);
            if c < 3 {
                xp[node][c] += h;
            } else {
                let mut alpha = [0.0; 2];
                alpha[c - 3] = h;
                fp[node] = frames[node].rotated(&frames[node].tilt_rotation(alpha));
            }
            let mut g = ElemVec::zeros();
            let e = add(&xp, &fp, &signs, kappa, &mut g, None).expect("admissible");
            (e, g)
        };
        let h = 1e-6;
        let scale_f = f.abs().max();
        let scale_k = k.abs().max();
        for j in 0..4 * NODE_DOFS {
            let ((ep, gp), (em, gm)) = (perturbed(j, h), perturbed(j, -h));
            assert!(
                ((ep - em) / (2.0 * h) - f[j]).abs() < 1e-6 * scale_f,
                "force {j}"
            );
            for i in 0..4 * NODE_DOFS {
                // The tilt columns are tested on the tilt-frame components; translation rows
                // of tilt columns and tilt rows of translation columns both follow from them.
                let fd = (gp[i] - gm[i]) / (2.0 * h);
                assert!(
                    (fd - k[(i, j)]).abs() < 1e-5 * scale_k,
                    "tangent ({i}, {j}): {fd} vs {}",
                    k[(i, j)]
                );
            }
        }
    }

    #[test]
    fn a_director_through_the_surface_fails() {
        let (x, frames) = element(1.7);
        let mut f = ElemVec::zeros();
        assert!(matches!(
            add(&x, &frames, &[1; 4], 1.0, &mut f, None),
            Err(ElementFailure::DirectorThroughSurface { .. })
        ));
    }
}
