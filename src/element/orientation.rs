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
//! Corner collapse. The corner normal n_I is undefined where the corner's edges become
//! collinear, and it flips there: an element sheared or crushed in its own plane until a
//! corner angle reaches 0° or 180° takes c_I from about +1 to −1 in one step, with no
//! warning from b(c) (measured on the NBC suit's arms-forward pose: an underarm gusset corner
//! at a corner-Jacobian ratio 0.000, every trial past it rejected with c = −0.86, the time
//! step collapsing to 10⁻¹⁰ s). A second barrier therefore charges the corner's area
//! measured along its director, J_I = s_I (x_{I+1} − x_I) × (x_{I−1} − x_I) · d_I = |…| c_I,
//! against its reference value: r_I = J_I / J⁰_I, energy κ_A b_A(r_I) with the same log
//! barrier activated at r̂ = [`AREA_ACTIVATION`] (2 %) and κ_A = [`AREA_STIFFNESS`] · (E h) J⁰_I,
//! the section's membrane stiffness times the corner's reference area. J_I is a polynomial
//! in the coordinates and director, smooth through the collapse, and vanishes before c_I
//! can flip. A corner at 2 % of its area is far past any physical state of a woven
//! fabric (a sheared weave jams at 40–50°, an area ratio cos γ ≈ 0.65–0.75; Prodromou &
//! Chen, Composites A 28, 1997): it is the yarn jamming that a fold inside one coarse
//! element would have to pass through.
//!
//! Folds inside one element. The element interpolates its directors along each edge by the
//! great circle between the two nodal ones, undefined when they are opposite
//! ([`ElementFailure::DirectorSpread`] at |d_b − d_a|² = 4 (1 − 10⁻⁶)): an element folded
//! flat through 180° across one edge, a fold inside one element (measured on the NBC suit's
//! arms-forward pose with the collapse barrier on: the time step collapsed at 100 % of the
//! motion, every trial rejected with |d_b − d_a| = 1.999999 on a front quarter's element). A
//! third barrier charges x = (1 + d_a · d_b)/2 − 10⁻⁶ on each edge, activated at
//! x̂ = [`SPREAD_ACTIVATION`] (the directors 160° apart) with the cosine barrier's stiffness
//! κ, infinite where the interpolation fails: a coarse element refuses to fold further and the
//! fold spreads to its neighbours, as a finer mesh would let it.
//!
//! Gradient and Hessian are exact, from second-order forward differentiation (`autodiff`) in
//! the nine coordinates of the corner and its two neighbours and the corner director's two
//! tilts; the director varies as d + t1 α1 + t2 α2 − ½|α|² d, the second-order expansion of
//! the exponential map used by `director` (ΔΔd = −(δα·Δα) d).

use nalgebra::Vector3;

use super::director::DirectorFrame;
use super::kinematics::EDGES;
use super::shell4::ElementFailure;
use super::{ElemMat, ElemVec, NODE_DOFS};
use crate::autodiff::{Hd, Hv, cross, dot};

/// Activation cosine ĉ of the barrier: the director 60° off the corner normal.
pub const ACTIVATION: f64 = 0.5;

/// Barrier stiffness per corner in units of the section's bending rigidity B.
pub const STIFFNESS: f64 = 25.0;

/// Activation r̂ of the corner-collapse barrier: 2 % of the corner's reference area along its
/// director (at 0.1 the barrier also charged the folds of the coarse levels of the sheet
/// dropped on a sphere, 16² 284 → 688 Newton iterations; at 0.02 it leaves them near their
/// cost: 16² 273, 32² 356, 64² 434 against 284, 334, 449).
pub const AREA_ACTIVATION: f64 = 0.02;

/// Activation x̂ of the edge-fold barrier: the two directors of an element edge 160° apart,
/// (1 + cos 160°)/2 (at 120° it charged the coarse sheet's folds like the collapse barrier
/// at 0.1; see [`AREA_ACTIVATION`]).
pub const SPREAD_ACTIVATION: f64 = 0.0302;

/// (1 + d_a · d_b)/2 at which the great-circle interpolation of an edge's directors fails
/// (`kinematics::arc_factor`: |d_b − d_a|²/4 < 1 − 10⁻⁶).
const SPREAD_LIMIT: f64 = 1e-6;

/// Corner-collapse barrier stiffness in units of the section's membrane stiffness E h times
/// the corner's reference area J⁰_I.
pub const AREA_STIFFNESS: f64 = 1.0;

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

/// The corner barriers of one element: reference signs, the cosine barrier's stiffness κ,
/// the corners' reference areas along their directors s_I J⁰_I (0 for a corner left out)
/// and the membrane stiffness E h that scales the collapse barrier.
#[derive(Clone, Debug)]
pub struct CornerBarriers {
    /// Corner signs s_I ([`reference_signs`]).
    pub signs: [i8; 4],
    /// Cosine barrier stiffness κ (J).
    pub kappa: f64,
    /// Reference corner areas along the directors, J⁰_I > 0 (m²).
    pub areas: [f64; 4],
    /// Membrane stiffness E h of the section (N/m).
    pub membrane: f64,
}

impl CornerBarriers {
    /// The barriers of an element with reference positions `x0` and directors `d0`, cosine
    /// stiffness `kappa` and membrane stiffness `membrane`.
    pub fn new(x0: &[Vector3<f64>; 4], d0: &[Vector3<f64>; 4], kappa: f64, membrane: f64) -> Self {
        let signs = reference_signs(x0, d0);
        let areas = std::array::from_fn(|i| f64::from(signs[i]) * corner_cross(x0, i).dot(&d0[i]));
        Self { signs, kappa, areas, membrane }
    }
}

/// (x_{i+1} − x_i) × (x_{i−1} − x_i).
fn corner_cross(x: &[Vector3<f64>; 4], i: usize) -> Vector3<f64> {
    (x[(i + 1) % 4] - x[i]).cross(&(x[(i + 3) % 4] - x[i]))
}

/// Unit normal of corner `i`, (x_{i+1} − x_i) × (x_{i−1} − x_i) normalised (None if degenerate).
fn corner_normal(x: &[Vector3<f64>; 4], i: usize) -> Option<Vector3<f64>> {
    let m = corner_cross(x, i);
    let len = m.norm();
    (len > 0.0).then(|| m / len)
}

/// b(c) of the module doc and its first two derivatives (zero above ĉ = `activation`).
fn barrier(c: f64, activation: f64) -> (f64, f64, f64) {
    if c >= activation {
        return (0.0, 0.0, 0.0);
    }
    let (dc, l) = (c - activation, (c / activation).ln());
    (
        -dc * dc * l,
        -2.0 * dc * l - dc * dc / c,
        -2.0 * l - 4.0 * dc / c + dc * dc / (c * c),
    )
}

/// Adds the barriers' energy, force (to `force`) and tangent (to `k`, when given) for an
/// element with current positions `x`, director frames `frames` and barrier data `corners`;
/// returns the energy. Fails when a director has reached or passed its corner's tangent
/// plane (which a collapsed corner's flipped normal also reports).
pub fn add(
    x: &[Vector3<f64>; 4],
    frames: &[DirectorFrame; 4],
    corners: &CornerBarriers,
    force: &mut ElemVec,
    k: Option<&mut ElemMat>,
) -> Result<f64, ElementFailure> {
    let mut energy = 0.0;
    let mut k = k;
    for i in 0..4 {
        if corners.signs[i] == 0 {
            continue;
        }
        let s = f64::from(corners.signs[i]);
        let Some(n) = corner_normal(x, i) else {
            continue;
        };
        let c = s * frames[i].d.dot(&n);
        let area = s * corner_cross(x, i).dot(&frames[i].d) / corners.areas[i];
        if c >= ACTIVATION && area >= AREA_ACTIVATION {
            continue;
        }
        if c <= 0.0 || !c.is_finite() {
            return Err(ElementFailure::DirectorThroughSurface { cosine: c });
        }
        let nodes = [i, (i + 1) % 4, (i + 3) % 4];
        if c < ACTIVATION {
            let cosine = corner_cosine(x, &frames[i], nodes).scale(s);
            let (b, b1, b2) = barrier(cosine.v, ACTIVATION);
            let e = cosine.chain(b, b1, b2).scale(corners.kappa);
            energy += e.v;
            scatter(&e, nodes, i, force, k.as_deref_mut());
        }
        if area < AREA_ACTIVATION {
            let ratio = corner_jacobian(x, &frames[i], nodes).scale(s / corners.areas[i]);
            let (b, b1, b2) = barrier(ratio.v, AREA_ACTIVATION);
            let e = ratio.chain(b, b1, b2).scale(AREA_STIFFNESS * corners.membrane * corners.areas[i]);
            energy += e.v;
            scatter(&e, nodes, i, force, k.as_deref_mut());
        }
    }
    for (a, b) in EDGES {
        let x = 0.5 * (1.0 + frames[a].d.dot(&frames[b].d)) - SPREAD_LIMIT;
        if x >= SPREAD_ACTIVATION - SPREAD_LIMIT {
            continue;
        }
        if x <= 0.0 || !x.is_finite() {
            return Err(ElementFailure::DirectorSpread { chord: (frames[b].d - frames[a].d).norm() });
        }
        let xd = (edge_cosine(&frames[a], &frames[b]) + Hd::c(1.0)).scale(0.5) - Hd::c(SPREAD_LIMIT);
        let (bx, b1, b2) = barrier(xd.v, SPREAD_ACTIVATION - SPREAD_LIMIT);
        let e = xd.chain(bx, b1, b2).scale(corners.kappa);
        energy += e.v;
        // Variable v ↦ element DOF: the tilts of a, then those of b.
        let dof = |v: usize| if v < 2 { NODE_DOFS * a + 3 + v } else { NODE_DOFS * b + 3 + (v - 2) };
        for p in 0..4 {
            force[dof(p)] += e.g[p];
        }
        if let Some(k) = k.as_deref_mut() {
            for p in 0..4 {
                for q in 0..4 {
                    k[(dof(p), dof(q))] += e.h[p][q];
                }
            }
        }
    }
    Ok(energy)
}

/// d_a · d_b as a function of the two directors' tilts (variables 0–1 of a, 2–3 of b).
fn edge_cosine(fa: &DirectorFrame, fb: &DirectorFrame) -> Hd<4> {
    let director = |f: &DirectorFrame, first: usize| -> Hv<4> {
        let (a1, a2) = (Hd::<4>::var(0.0, first), Hd::<4>::var(0.0, first + 1));
        let half_square = (a1 * a1 + a2 * a2).scale(0.5);
        std::array::from_fn(|c| Hd::c(f.d[c]) + a1.scale(f.t1[c]) + a2.scale(f.t2[c]) - half_square.scale(f.d[c]))
    };
    dot(&director(fa, 0), &director(fb, 2))
}

/// Adds the gradient and Hessian of a corner term `e` in the 11 variables of corner `i`
/// (coordinates of `nodes`, then the corner's tilts) to the element force and tangent.
fn scatter(e: &Hd<N>, nodes: [usize; 3], i: usize, force: &mut ElemVec, k: Option<&mut ElemMat>) {
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
    if let Some(k) = k {
        for a in 0..N {
            for b in 0..N {
                k[(dof(a), dof(b))] += e.h[a][b];
            }
        }
    }
}

/// The corner cross product m = (x_{I+1} − x_I) × (x_{I−1} − x_I) and director d_I as
/// functions of the 11 corner variables (at their current values).
fn corner_vectors(x: &[Vector3<f64>; 4], frame: &DirectorFrame, nodes: [usize; 3]) -> (Hv<N>, Hv<N>) {
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
    (m, d)
}

/// m · d_I (the corner's area along its director) as a function of the 11 corner variables.
fn corner_jacobian(x: &[Vector3<f64>; 4], frame: &DirectorFrame, nodes: [usize; 3]) -> Hd<N> {
    let (m, d) = corner_vectors(x, frame, nodes);
    dot(&d, &m)
}

/// d_I · n_I as a function of the 11 corner variables (at their current values: zero
/// displacement increments and tilts).
fn corner_cosine(x: &[Vector3<f64>; 4], frame: &DirectorFrame, nodes: [usize; 3]) -> Hd<N> {
    let (m, d) = corner_vectors(x, frame, nodes);
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

    /// Barrier data with the current corner areas along the directors scaled by
    /// `area_scale` as the reference ones (a scale above 1/`AREA_ACTIVATION` activates the
    /// collapse barrier).
    fn corners(x: &[Vector3<f64>; 4], frames: &[DirectorFrame; 4], signs: [i8; 4], kappa: f64, area_scale: f64) -> CornerBarriers {
        let areas = std::array::from_fn(|i| area_scale * f64::from(signs[i]) * corner_cross(x, i).dot(&frames[i].d));
        CornerBarriers { signs, kappa, areas, membrane: 3.0 }
    }

    #[test]
    fn barrier_is_c2_at_activation_and_grows_to_the_plane() {
        let (b, b1, b2) = barrier(ACTIVATION - 1e-9, ACTIVATION);
        assert!(b.abs() < 1e-17 && b1.abs() < 1e-8 && b2.abs() < 1e-7);
        assert!(barrier(1e-6, ACTIVATION).0 > barrier(0.1, ACTIVATION).0 && barrier(0.1, ACTIVATION).0 > barrier(0.3, ACTIVATION).0);
    }

    /// Inactive below 60°: no energy, force or stiffness, bit for bit.
    #[test]
    fn regular_states_are_untouched() {
        let (x, frames) = element(0.3);
        let c = CornerBarriers::new(&x, &frames.map(|f| f.d), 1.0, 3.0);
        assert_eq!(c.signs, [1; 4]);
        let (mut f, mut k) = (ElemVec::zeros(), ElemMat::zeros());
        let e = add(&x, &frames, &c, &mut f, Some(&mut k)).expect("admissible");
        assert!(e == 0.0 && f.iter().all(|v| *v == 0.0) && k.iter().all(|v| *v == 0.0));
    }

    /// Force and tangent against central differences of the energy and force: translations
    /// moved directly, tilts by the director's exponential map (second-order consistent);
    /// the cosine barrier alone (tilted directors), the collapse barrier alone (corners at
    /// 1/60 of their reference area), both, and the edge-fold barrier (directors 166° apart).
    #[test]
    fn force_and_tangent_match_finite_differences() {
        for (tilt, area_scale) in [(1.2, 1.0), (0.3, 60.0), (1.2, 60.0), (1.45, 1.0)] {
            finite_difference_check(tilt, area_scale);
        }
    }

    fn finite_difference_check(tilt: f64, area_scale: f64) {
        let (x, frames) = element(tilt);
        let corners = corners(&x, &frames, [1; 4], 2.0, area_scale);
        let (mut f, mut k) = (ElemVec::zeros(), ElemMat::zeros());
        let e0 = add(&x, &frames, &corners, &mut f, Some(&mut k)).expect("admissible");
        assert!(e0 > 0.0, "tilt {tilt}, area scale {area_scale}: inside a barrier");
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
            let e = add(&xp, &fp, &corners, &mut g, None).expect("admissible");
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
            add(&x, &frames, &corners(&x, &frames, [1; 4], 1.0, 1.0), &mut f, None),
            Err(ElementFailure::DirectorThroughSurface { .. })
        ));
    }

    /// Directors of an edge folding towards opposite: the edge barrier's energy grows without
    /// bound before the great-circle interpolation fails, and fails at that limit.
    #[test]
    fn an_edge_folding_flat_is_charged_before_its_directors_oppose() {
        let (x, frames0) = element(0.0);
        let corners = corners(&x, &frames0, [0; 4], 1.0, 1.0);
        // Node 1's director turned by θ about the y axis, away from node 0's (z).
        let energy = |theta: f64| {
            let mut frames = frames0;
            frames[1] = DirectorFrame::new(Vector3::new(theta.sin(), 0.0, theta.cos()), Some(Vector3::y()));
            let mut f = ElemVec::zeros();
            add(&x, &frames, &corners, &mut f, None).map(|e| (e, f.norm()))
        };
        let deg = std::f64::consts::PI / 180.0;
        let e: Vec<(f64, f64)> = [150.0, 165.0, 170.0, 175.0, 179.8].iter().map(|&t| energy(t * deg).expect("admissible")).collect();
        assert_eq!(e[0], (0.0, 0.0));
        assert!(e.windows(2).skip(1).all(|w| w[1].0 > w[0].0 && w[1].1 > w[0].1), "{e:?}");
        assert!(matches!(energy(179.99 * deg), Err(ElementFailure::DirectorSpread { .. })));
    }

    /// A corner sheared in its own plane towards 180°: the cosine barrier stays silent (its
    /// normal keeps c ≈ 1 until it flips), the collapse barrier's energy grows without bound
    /// as the corner's area vanishes, and the flipped corner fails.
    #[test]
    fn a_collapsing_corner_is_charged_before_it_flips() {
        let (x0, frames) = element(0.0);
        let reference = CornerBarriers::new(&x0, &frames.map(|f| f.d), 1.0, 3.0);
        // Move node 0 towards the segment between its neighbours 1 and 3 (corner 0's angle
        // opens to 180° when it reaches it) and past it.
        let target = 0.5 * (x0[1] + x0[3]);
        let energy = |t: f64| {
            let mut x = x0;
            x[0] = x0[0] + t * (target - x0[0]);
            let mut f = ElemVec::zeros();
            add(&x, &frames, &reference, &mut f, None).map(|e| (e, f.norm()))
        };
        let e: Vec<(f64, f64)> = [0.5, 0.99, 0.999, 0.99999].iter().map(|&t| energy(t).expect("admissible")).collect();
        assert_eq!(e[0], (0.0, 0.0));
        assert!(e[1].0 > 0.0 && e[2].0 > e[1].0 && e[3].0 > e[2].0, "{e:?}");
        // The force grows like 1/r as the area ratio r falls (0.001 → 0.00001).
        assert!(e[3].1 > 30.0 * e[2].1, "{e:?}");
        assert!(matches!(energy(1.01), Err(ElementFailure::DirectorThroughSurface { .. })));
    }
}
