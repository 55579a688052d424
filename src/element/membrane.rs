//! MITC4+ assumed membrane strains (Ko, Lee & Bathe, "A new MITC4+ shell element",
//! Computers & Structures 182 (2017) 404–418; geometrically nonlinear form: "The MITC4+
//! shell element in geometric nonlinear analysis", C&S 185 (2017) 1–14).
//!
//! The in-plane covariant Green–Lagrange strains of a level ζ split into a membrane part,
//! the strains of the mid-surface e^m_ij = ½(x̄,i·x̄,j − X̄,i·X̄,j), and the rest (terms with
//! the director gradients). MITC4+ replaces the membrane part by an assumed field ê^m
//! interpolated from five tying points — A (0, 1) and B (0, −1) for e_ξξ, C (1, 0) and
//! D (−1, 0) for e_ηη, E (0, 0) for e_ξη:
//!
//! ê_ξξ = ½(1+η) e^A + ½(1−η) e^B + (η²−1) Q̂,
//! ê_ηη = ½(1+ξ) e^C + ½(1−ξ) e^D + (ξ²−1) Q̂,
//! ê_ξη = e^E + ¼ξ (e^A − e^B) + ¼η (e^C − e^D) + ξη Q̂,
//! Q̂ = a_A e^A + a_B e^B + a_C e^C + a_D e^D + a_E e^E
//!
//! (the assumed membrane strain field of Ko, Lee & Bathe 2017a, written here with the common
//! term Q̂ collected; `tests::assumed_field_is_exact_for_constant_strain_on_distorted_element`
//! checks the identity that fixes the coefficients). e^A = e_ξξ
//! at A and e^B likewise are the stretches of the element edges η = ±1 (x̄,ξ there is half
//! the edge chord), e^C, e^D those of ξ = ±1: they vanish when the element bends without
//! stretching its edges, which is what frees a curved element from membrane locking. Q̂
//! estimates the strain along the distortion vector x_d of the bilinear geometry
//! X̄ = x_c + ξ x_r + η x_s + ξη x_d: with x_d = c_r x_r + c_s x_s + d n (n normal to x_r, x_s),
//! D = c_r² + c_s² − 1 (< 0 for a convex quadrilateral),
//! a_A = c_r(c_r−1)/(2D), a_B = c_r(c_r+1)/(2D), a_C = c_s(c_s−1)/(2D),
//! a_D = c_s(c_s+1)/(2D), a_E = 2 c_r c_s / D,
//! which makes the interpolation exact for every constant strain field of a flat,
//! arbitrarily distorted element (membrane patch test). The coefficients come from the
//! reference geometry (total Lagrangian, as in the nonlinear paper); the tying strains are
//! the Green–Lagrange membrane strains of the current state, so the assumed field is exact
//! under rigid motions of any size.
//!
//! In the element each level's in-plane strains become e(ζ) + (ê^m − e^m): the correction
//! ê^m − e^m is independent of ζ, so its pair strains, their DOF rows and their stress
//! weights are evaluated once per element, not once per level.

use nalgebra::Vector3;

use super::kinematics::{base_forms, Kinematics, Lin};
use super::tangent::Row;
use super::ELEMENT_DOFS;

/// Tying points (ξ, η) A, B, C, D, E and the natural component (0 = ξξ, 1 = ηη, 2 = ξη)
/// sampled at each.
const TYING: [(f64, f64, usize); 5] = [(0.0, 1.0, 0), (0.0, -1.0, 0), (1.0, 0.0, 1), (-1.0, 0.0, 1), (0.0, 0.0, 2)];

/// Largest number of distinct membrane pair strains of a rule: the 5 tying strains and the
/// three membrane strains of each of the 2×2 points and of the centre (15 for 2×2 points).
pub(super) const MAX_MPAIRS: usize = 16;

/// Weights of the five tying strains in the three assumed natural membrane strains
/// [ê_ξξ, ê_ηη, ê_ξη] at one point of one element.
pub(super) type TyingWeights = [[f64; 5]; 3];

/// A point where the assumed membrane strains replace the mid-surface ones.
#[derive(Clone, Copy, Debug)]
pub(super) struct MembranePoint {
    /// Natural coordinate ξ.
    pub xi: f64,
    /// Natural coordinate η.
    pub eta: f64,
    /// Indices of the point's own membrane pairs e^m_ξξ, e^m_ηη, e^m_ξη.
    pub own: [usize; 3],
}

/// The membrane tying of a section rule: the distinct membrane pair strains (the five tying
/// strains first) and the points where the assumed field is used, the in-plane points of a
/// level in order and then the element centre.
#[derive(Clone, Debug)]
pub(super) struct MembraneTying {
    /// Pair strains ½(p·q − P·Q) as form indices of the rule; 0–4 are A, B, C, D, E.
    pub pairs: Vec<(usize, usize)>,
    /// The in-plane points of each level, then the centre (last).
    pub points: Vec<MembranePoint>,
}

impl MembraneTying {
    /// The tying of points `pts` (ξ, η), with `form` giving the rule's index of a form.
    pub(super) fn new(pts: &[(f64, f64)], form: &mut impl FnMut(Lin) -> usize) -> Self {
        let mut pairs: Vec<(usize, usize)> = Vec::new();
        let mut pair = |p: Lin, q: Lin, form: &mut dyn FnMut(Lin) -> usize| {
            let key = (form(p), form(q));
            pairs.iter().position(|f| *f == key).unwrap_or_else(|| {
                pairs.push(key);
                pairs.len() - 1
            })
        };
        // Mid-surface forms: at ζ = 0 the base-vector forms g_ξ, g_η hold positions only.
        for &(xi, eta, c) in &TYING {
            let g = base_forms(xi, eta, 0.0, 0.0);
            let (p, q) = match c {
                0 => (g[0], g[0]),
                1 => (g[1], g[1]),
                _ => (g[0], g[1]),
            };
            pair(p, q, form);
        }
        let points = pts
            .iter()
            .map(|&(xi, eta)| {
                let g = base_forms(xi, eta, 0.0, 0.0);
                let own = [pair(g[0], g[0], form), pair(g[1], g[1], form), pair(g[0], g[1], form)];
                MembranePoint { xi, eta, own }
            })
            .collect();
        Self { pairs, points }
    }

    /// Tying weights of each point for the element with reference mid-surface nodes `x0`
    /// (counter-clockwise from (−1, −1)): the interpolation of the module documentation
    /// with the distortion coefficients a_A … a_E of the element.
    pub(super) fn weights(&self, x0: &[Vector3<f64>; 4]) -> Vec<TyingWeights> {
        let [a_a, a_b, a_c, a_d, a_e] = distortion_coefficients(x0);
        self.points
            .iter()
            .map(|p| {
                let (r, s) = (p.xi, p.eta);
                let (qr, qs, qrs) = (s * s - 1.0, r * r - 1.0, r * s);
                [
                    [0.5 * (1.0 + s) + a_a * qr, 0.5 * (1.0 - s) + a_b * qr, a_c * qr, a_d * qr, a_e * qr],
                    [a_a * qs, a_b * qs, 0.5 * (1.0 + r) + a_c * qs, 0.5 * (1.0 - r) + a_d * qs, a_e * qs],
                    [0.25 * r + a_a * qrs, -0.25 * r + a_b * qrs, 0.25 * s + a_c * qrs, -0.25 * s + a_d * qrs, 1.0 + a_e * qrs],
                ]
            })
            .collect()
    }
}

/// Coefficients a_A, a_B, a_C, a_D, a_E of the assumed membrane field (Ko, Lee & Bathe
/// 2017a): x_d is split as c_r x_r + c_s x_s plus a part normal to x_r and x_s
/// (least squares over the tangent plane), D = c_r² + c_s² − 1. Zero for a parallelogram.
fn distortion_coefficients(x0: &[Vector3<f64>; 4]) -> [f64; 5] {
    let xr = (-x0[0] + x0[1] + x0[2] - x0[3]) * 0.25;
    let xs = (-x0[0] - x0[1] + x0[2] + x0[3]) * 0.25;
    let xd = (x0[0] - x0[1] + x0[2] - x0[3]) * 0.25;
    let (grr, grs, gss) = (xr.dot(&xr), xr.dot(&xs), xs.dot(&xs));
    let det = grr * gss - grs * grs;
    if !(det > 0.0) {
        return [0.0; 5];
    }
    let (br, bs) = (xd.dot(&xr), xd.dot(&xs));
    let cr = (gss * br - grs * bs) / det;
    let cs = (grr * bs - grs * br) / det;
    let d = cr * cr + cs * cs - 1.0;
    if d.abs() < 1e-12 {
        // A degenerate (triangle-like) quadrilateral: no distortion correction.
        return [0.0; 5];
    }
    [cr * (cr - 1.0) / (2.0 * d), cr * (cr + 1.0) / (2.0 * d), cs * (cs - 1.0) / (2.0 * d), cs * (cs + 1.0) / (2.0 * d), 2.0 * cr * cs / d]
}

/// Largest number of membrane points of a rule (2×2 in-plane points and the centre).
const MAX_MPOINTS: usize = 5;

/// The membrane pair strains of one element state, the corrections ê^m − e^m at the rule's
/// membrane points and their DOF rows (with the tangent), and the pairs' accumulated stress
/// weights.
pub(super) struct MembraneState {
    /// Corrections ê^m − e^m of [E_ξξ, E_ηη, E_ξη] per membrane point.
    corr: [[f64; 3]; MAX_MPOINTS],
    /// Their DOF rows (only with the tangent).
    corr_rows: [[Row; 3]; MAX_MPOINTS],
    /// Stress weights σ of the pairs, summed over all points and levels.
    pub sigma: [f64; MAX_MPAIRS],
}

impl MembraneState {
    /// Evaluates the pairs of `tying` from the reference values `forms0` and changes `df` of
    /// the rule's forms (cancellation-free, as the level pairs) and the corrections at its
    /// points with tying weights `w`, with their DOF rows if `with_tangent`. The points are
    /// at most [`MAX_MPOINTS`] (`SectionRule::fits`).
    #[inline(always)]
    pub(super) fn new(tying: &MembraneTying, w: &[TyingWeights], forms: &[Lin], forms0: &[Vector3<f64>], df: &[Vector3<f64>], kin: &Kinematics, with_tangent: bool) -> Self {
        let mut e = [0.0; MAX_MPAIRS];
        let mut rows = [[0.0; ELEMENT_DOFS]; MAX_MPAIRS];
        for (t, &(p, q)) in tying.pairs.iter().enumerate() {
            let (pr, dp, qr, dq) = (forms0[p], df[p], forms0[q], df[q]);
            e[t] = 0.5 * (pr.dot(&dq) + dp.dot(&qr) + dp.dot(&dq));
            if with_tangent {
                if p == q {
                    kin.chain_form(&forms[p], &(pr + dp), &mut rows[t]);
                } else {
                    kin.chain_form(&forms[p], &((qr + dq) * 0.5), &mut rows[t]);
                    kin.chain_form(&forms[q], &((pr + dp) * 0.5), &mut rows[t]);
                }
            }
        }
        let mut corr = [[0.0; 3]; MAX_MPOINTS];
        let mut corr_rows = [[[0.0; ELEMENT_DOFS]; 3]; MAX_MPOINTS];
        for (i, (point, w)) in tying.points.iter().zip(w).enumerate().take(MAX_MPOINTS) {
            for c in 0..3 {
                corr[i][c] = w[c].iter().zip(&e[..5]).map(|(wt, et)| wt * et).sum::<f64>() - e[point.own[c]];
                if with_tangent {
                    let b = &mut corr_rows[i][c];
                    for (t, &wt) in w[c].iter().enumerate() {
                        if wt != 0.0 {
                            b.iter_mut().zip(&rows[t]).for_each(|(x, y)| *x += wt * y);
                        }
                    }
                    b.iter_mut().zip(&rows[point.own[c]]).for_each(|(x, y)| *x -= y);
                }
            }
        }
        Self { corr, corr_rows, sigma: [0.0; MAX_MPAIRS] }
    }

    /// Adds ê^m − e^m at membrane point `i` to the first three natural strains `nat`.
    #[inline(always)]
    pub(super) fn correct(&self, i: usize, nat: &mut [f64]) {
        nat.iter_mut().zip(&self.corr[i]).for_each(|(n, c)| *n += c);
    }

    /// Adds the DOF rows of ê^m − e^m at membrane point `i` to the first three natural rows
    /// `bn`.
    #[inline(always)]
    pub(super) fn add_correction_rows(&self, i: usize, bn: &mut [Row; 5]) {
        for (b, r) in bn.iter_mut().zip(&self.corr_rows[i]) {
            b.iter_mut().zip(r).for_each(|(x, y)| *x += y);
        }
    }

    /// Adds the stresses `sn` conjugate to the natural components at `point` (tying weights
    /// `w`) to the pairs' stress weights.
    #[inline(always)]
    pub(super) fn add_stress(&mut self, point: &MembranePoint, w: &TyingWeights, sn: &[f64]) {
        for c in 0..3 {
            for (t, &wt) in w[c].iter().enumerate() {
                self.sigma[t] += wt * sn[c];
            }
            self.sigma[point.own[c]] -= sn[c];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// For a flat distorted quadrilateral and a constant membrane strain ε, the natural
    /// strains e_ij(ξ, η) = g_i·ε·g_j are quadratic in ξ, η; the assumed field built from
    /// their values at the tying points reproduces them exactly at any point.
    #[test]
    fn assumed_field_is_exact_for_constant_strain_on_distorted_element() {
        let x0 = [Vector3::new(0.0, 0.0, 0.0), Vector3::new(1.3, 0.2, 0.0), Vector3::new(0.9, 1.1, 0.0), Vector3::new(-0.2, 0.7, 0.0)];
        let eps = nalgebra::Matrix3::new(0.3, -0.7, 0.0, -0.7, 1.1, 0.0, 0.0, 0.0, 0.0);
        let nat = |xi: f64, eta: f64| {
            let (_, dxi, deta) = super::super::quadrature::bilinear(xi, eta);
            let gx: Vector3<f64> = (0..4).map(|a| x0[a] * dxi[a]).sum();
            let gy: Vector3<f64> = (0..4).map(|a| x0[a] * deta[a]).sum();
            [gx.dot(&(eps * gx)), gy.dot(&(eps * gy)), gx.dot(&(eps * gy))]
        };
        let tied: Vec<f64> = TYING.iter().map(|&(x, y, c)| nat(x, y)[c]).collect();
        let pts = [(0.3, -0.8), (-0.577, 0.577), (0.9, 0.1), (0.0, 0.0)];
        let mut forms = Vec::new();
        let tying = MembraneTying::new(&pts, &mut |l| {
            forms.push(l);
            forms.len() - 1
        });
        for (w, &(xi, eta)) in tying.weights(&x0).iter().zip(&pts) {
            let exact = nat(xi, eta);
            for c in 0..3 {
                let assumed: f64 = w[c].iter().zip(&tied).map(|(a, b)| a * b).sum();
                assert!((assumed - exact[c]).abs() < 1e-13, "({xi}, {eta}) component {c}: {assumed} vs {}", exact[c]);
            }
        }
    }
}
