//! Kinematic vectors of the 4-node shell: mid-surface positions, unit directors and the
//! geodesic edge gradients of the director field, the linear forms over them that make up
//! the covariant base vectors, and the chain from kinematic-vector variations to the nodal
//! DOFs (translations and director tilts).
//!
//! Director gradients (geodesic interpolation): along each element edge the director field
//! is taken as the great-circle (SLERP) arc between the two unit nodal directors; its
//! derivative at the edge midpoint is E = θ v/|v| = φ v with v = d_b − d_a, θ the angle
//! between the directors and φ = asin(|v|/2)/(|v|/2) (Crisfield & Jelenić 1999, Proc. R.
//! Soc. A 455, 1125, for the two-node analogue). See the module documentation of `shell4`.

use nalgebra::{Matrix3, Matrix3x2, Vector3};

use super::director::DirectorFrame;
use super::quadrature::bilinear;
use super::shell4::ElementFailure;
use super::ELEMENT_DOFS;

/// Number of kinematic vectors of an element state: 4 mid-surface positions x̄_a, 4 unit
/// directors d_a and 4 edge director gradients E_k.
pub(super) const NV: usize = 12;
/// First director index among the kinematic vectors.
pub(super) const VD: usize = 4;
/// First edge-gradient index among the kinematic vectors.
pub(super) const VE: usize = 8;
/// Element edges (a, b) carrying the geodesic director difference E_k = F(d_b − d_a):
/// E_0, E_1 run along ξ (η = −1, +1), E_2, E_3 along η (ξ = −1, +1).
pub(super) const EDGES: [(usize, usize); 4] = [(0, 1), (3, 2), (0, 3), (1, 2)];

/// Series coefficients of h(y) = asin(√y)/√y = Σ c_n yⁿ (n = 1…15) and of its first two
/// derivatives: (c_n, n c_n, n(n−1) c_n), c_n = β_n/(2n+1), β_n = C(2n,n)/4ⁿ =
/// β_{n−1}(2n−1)/(2n) (Abramowitz & Stegun 4.4.40).
const ARC_SERIES: [[f64; 3]; 15] = {
    let mut out = [[0.0; 3]; 15];
    let mut beta = 1.0;
    let mut n = 1;
    while n < 16 {
        let nf = n as f64;
        beta *= (2.0 * nf - 1.0) / (2.0 * nf);
        let c = beta / (2.0 * nf + 1.0);
        out[n - 1] = [c, nf * c, nf * (nf - 1.0) * c];
        n += 1;
    }
    out
};

/// Arc-to-chord factor of the geodesic between two unit vectors whose difference v has
/// w = |v|²: φ = θ / |v| = asin(s)/s with s = |v|/2 = sin(θ/2), θ the angle between them.
/// Returns (φ, dφ/dw, d²φ/dw²), or None when the vectors are (nearly) antipodal, where the
/// geodesic is undefined. Series of asin(s)/s = Σ C(2n,n)/(4ⁿ(2n+1)) s²ⁿ for small s
/// (Abramowitz & Stegun 4.4.40), closed form otherwise.
pub(crate) fn arc_factor(w: f64) -> Option<[f64; 3]> {
    arc_factors([w])[0]
}

/// [`arc_factor`] of L values at once. The series runs in L independent lanes (the element's
/// four edges: one dependency chain of fifteen steps instead of four after each other), each
/// lane with the operations of the scalar series in the same order, so every lane's result is
/// the scalar one bit for bit; lanes past the series' range take the closed form.
#[inline(always)]
pub(crate) fn arc_factors<const L: usize>(w: [f64; L]) -> [Option<[f64; 3]>; L] {
    let y = w.map(|w| 0.25 * w);
    let (mut h, mut h1, mut h2) = ([1.0; L], [0.0; L], [0.0; L]);
    let mut y_nm1 = [1.0; L]; // y^{n−1}
    let mut y_nm2 = [0.0; L]; // y^{n−2} (no term for n = 1)
    for [c, nc, nnc] in ARC_SERIES {
        for l in 0..L {
            h[l] += c * y_nm1[l] * y[l];
            h1[l] += nc * y_nm1[l];
            h2[l] += nnc * y_nm2[l];
            y_nm2[l] = y_nm1[l];
            y_nm1[l] *= y[l];
        }
    }
    std::array::from_fn(|l| {
        let y = y[l];
        if !(y < 0.999_999) || y < 0.0 {
            return None;
        }
        let (h, hy, hyy) = if y < 0.02 {
            (h[l], h1[l], h2[l])
        } else {
            let s = y.sqrt();
            let r = (1.0 - y).sqrt();
            let a = s.asin();
            (a / s, 0.5 / (y * r) - 0.5 * a / (y * s), -0.75 / (y * y * r) + 0.25 / (y * r * r * r) + 0.75 * a / (y * y * s))
        };
        // d/dw = ¼ d/dy.
        Some([h, 0.25 * hy, 0.0625 * hyy])
    })
}

/// Geodesic edge gradient E = φ(|v|²) v of the director difference v = d_b − d_a: the
/// derivative at the edge midpoint of the great-circle (SLERP) interpolation of the two
/// nodal directors, 2·(θ/2)·(v/|v|), with θ the angle between them. Returns (φ, φ', φ'').
pub(super) fn edge_gradient(v: &Vector3<f64>) -> Result<(f64, f64, f64), ElementFailure> {
    let w = v.norm_squared();
    let [phi, d1, d2] = arc_factor(w).ok_or(ElementFailure::DirectorSpread { chord: w.sqrt() })?;
    Ok((phi, d1, d2))
}

/// Linear form p = Σ_i c_i V_i of the kinematic vectors (at most six non-zero terms).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Lin {
    n: usize,
    idx: [usize; 6],
    c: [f64; 6],
}

impl Lin {
    fn push(&mut self, i: usize, c: f64) {
        if c != 0.0 && self.n < 6 {
            self.idx[self.n] = i;
            self.c[self.n] = c;
            self.n += 1;
        }
    }

    /// Whether the form has no terms.
    pub(super) fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// The (index, coefficient) terms.
    #[inline(always)]
    pub(super) fn terms(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.idx[..self.n].iter().copied().zip(self.c[..self.n].iter().copied())
    }

    /// Σ_i c_i v_i.
    #[inline(always)]
    pub(super) fn eval(&self, v: &[Vector3<f64>; NV]) -> Vector3<f64> {
        let mut out = Vector3::zeros();
        for (i, c) in self.terms() {
            out += v[i] * c;
        }
        out
    }
}

/// Covariant base-vector forms at (ξ, η, ζ): g_ξ, g_η, g_ζ. The in-plane director
/// gradients are d,ξ = ¼(1−η) E_0 + ¼(1+η) E_1 and d,η = ¼(1−ξ) E_2 + ¼(1+ξ) E_3 — the
/// bilinear interpolation's edge differences d_b − d_a replaced by the geodesic ones.
/// g_ξ depends on (η, ζ) only, g_η on (ξ, ζ) and g_ζ on (ξ, η): forms are shared between
/// points of a rule.
pub(super) fn base_forms(xi: f64, eta: f64, zeta: f64, h: f64) -> [Lin; 3] {
    let (n, dxi, deta) = bilinear(xi, eta);
    let hz = 0.5 * zeta * h;
    let mut g = [Lin::default(); 3];
    for a in 0..4 {
        g[0].push(a, dxi[a]);
        g[1].push(a, deta[a]);
    }
    g[0].push(VE, hz * 0.25 * (1.0 - eta));
    g[0].push(VE + 1, hz * 0.25 * (1.0 + eta));
    g[1].push(VE + 2, hz * 0.25 * (1.0 - xi));
    g[1].push(VE + 3, hz * 0.25 * (1.0 + xi));
    for a in 0..4 {
        g[2].push(VD + a, 0.5 * h * n[a]);
    }
    g
}

/// The base-vector forms of (ξ, η) split by their dependence on the thickness coordinate:
/// g(ζ) = a + ζ b with a = `base_forms(ξ, η, 0, h)` (positions in g_ξ, g_η; directors in
/// g_ζ) and b the edge-gradient part of g_ξ, g_η at ζ = 1 (empty for g_ζ). Returns [a, b].
pub(super) fn base_forms_split(xi: f64, eta: f64, h: f64) -> [[Lin; 3]; 2] {
    let a = base_forms(xi, eta, 0.0, h);
    let full = base_forms(xi, eta, 1.0, h);
    let b = full.map(|g| {
        let mut out = Lin::default();
        for (i, c) in g.terms().filter(|&(i, _)| i >= VE) {
            out.push(i, c);
        }
        out
    });
    [a, b]
}

/// The kinematic vectors of one element state: their changes V_i − V⁰_i from the reference,
/// the derivatives of the geodesic edge gradients and the maps from tilt variations to
/// director and edge-gradient variations.
pub(super) struct Kinematics {
    /// Changes from the reference (u_a, d_a − D_a, E_k − E⁰_k).
    pub dv: [Vector3<f64>; NV],
    /// Current edge differences v_k = d_b − d_a.
    pub v: [Vector3<f64>; 4],
    /// ∂E_k/∂v_k = φ I + 2φ' v vᵀ (symmetric).
    pub jac: [Matrix3<f64>; 4],
    /// (φ', φ'') of each edge, derivatives with respect to |v|².
    pub dphi: [[f64; 2]; 4],
    /// Tangent maps T_a = [t1 t2] of the nodes: δd_a = T_a δα_a.
    pub tm: [Matrix3x2<f64>; 4],
    /// ∂E_k/∂α at the edge's start and end nodes: −J_k T_a and +J_k T_b.
    pub jt: [[Matrix3x2<f64>; 2]; 4],
}

impl Kinematics {
    /// Kinematic vectors of the state with displacements `u` and director `frames`, for
    /// reference vectors `r` (X̄_a, D_a, E⁰_k) with reference edge factors `phi0`.
    #[inline(always)]
    pub(super) fn new(r: &[Vector3<f64>; NV], phi0: &[f64; 4], u: &[Vector3<f64>; 4], frames: &[DirectorFrame; 4]) -> Result<Self, ElementFailure> {
        let mut dv = [Vector3::zeros(); NV];
        for a in 0..4 {
            dv[a] = u[a];
            dv[VD + a] = frames[a].d - r[VD + a];
        }
        let v: [Vector3<f64>; 4] = std::array::from_fn(|k| frames[EDGES[k].1].d - frames[EDGES[k].0].d);
        // The four edges' arc factors at once (`arc_factors`; each as `edge_gradient`'s).
        let w = v.map(|v| v.norm_squared());
        let factors = arc_factors(w);
        let mut jac = [Matrix3::identity(); 4];
        let mut dphi = [[0.0; 2]; 4];
        for (k, &(a, b)) in EDGES.iter().enumerate() {
            let v0 = r[VD + b] - r[VD + a];
            let [phi, d1, d2] = factors[k].ok_or(ElementFailure::DirectorSpread { chord: w[k].sqrt() })?;
            // E − E⁰ = φ (v − v⁰) + (φ − φ⁰) v⁰, free of cancellation for small changes.
            dv[VE + k] = (dv[VD + b] - dv[VD + a]) * phi + v0 * (phi - phi0[k]);
            jac[k] = Matrix3::identity() * phi + v[k] * v[k].transpose() * (2.0 * d1);
            dphi[k] = [d1, d2];
        }
        let tm: [Matrix3x2<f64>; 4] = std::array::from_fn(|a| frames[a].tangent_map());
        let jt = std::array::from_fn(|e| {
            let (a, b) = EDGES[e];
            [-(jac[e] * tm[a]), jac[e] * tm[b]]
        });
        Ok(Self { dv, v, jac, dphi, tm, jt })
    }

    /// Maps a gradient over the kinematic vectors to the director side of node a: the
    /// 3-vector g_{d_a} + Σ_k ±J_k g_{E_k} (+ when a is the edge's end node b, − when its
    /// start a).
    #[inline(always)]
    pub(super) fn director_chain(&self, g: &[Vector3<f64>; NV]) -> [Vector3<f64>; 4] {
        let mut eff = [g[VD], g[VD + 1], g[VD + 2], g[VD + 3]];
        for (k, &(a, b)) in EDGES.iter().enumerate() {
            if g[VE + k] != Vector3::zeros() {
                let je = self.jac[k] * g[VE + k];
                eff[b] += je;
                eff[a] -= je;
            }
        }
        eff
    }

    /// Adds to the DOF-space row `out` the variation of y·p for the linear form `p` at fixed
    /// y: Σ_i c_i (∂V_i/∂DOF)ᵀ y, with δx̄_a = δu_a, δd_a = T_a δα_a and
    /// δE_k = J_k (T_b δα_b − T_a δα_a).
    #[inline(always)]
    pub(super) fn chain_form(&self, p: &Lin, y: &Vector3<f64>, out: &mut [f64; ELEMENT_DOFS]) {
        for (i, c) in p.terms() {
            if i < VD {
                let o = 5 * i;
                out[o] += c * y[0];
                out[o + 1] += c * y[1];
                out[o + 2] += c * y[2];
            } else if i < VE {
                let a = i - VD;
                let t = self.tm[a].tr_mul(y);
                out[5 * a + 3] += c * t[0];
                out[5 * a + 4] += c * t[1];
            } else {
                let k = i - VE;
                let (a, b) = EDGES[k];
                let ta = self.jt[k][0].tr_mul(y);
                let tb = self.jt[k][1].tr_mul(y);
                out[5 * a + 3] += c * ta[0];
                out[5 * a + 4] += c * ta[1];
                out[5 * b + 3] += c * tb[0];
                out[5 * b + 4] += c * tb[1];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lane-wise arc factors equal, bit for bit, the one-value series and closed form
    /// (the former scalar `arc_factor`), lane by lane, whatever the other lanes hold: series
    /// and closed-form lanes side by side, and the refused values (nearly antipodal
    /// directors, NaN).
    #[test]
    fn arc_factor_lanes_equal_the_scalar_evaluation() {
        let scalar = |w: f64| -> Option<[f64; 3]> {
            let y = 0.25 * w;
            if !(y < 0.999_999) || y < 0.0 {
                return None;
            }
            let (h, hy, hyy) = if y < 0.02 {
                let (mut h, mut h1, mut h2, mut y_nm1, mut y_nm2) = (1.0, 0.0, 0.0, 1.0, 0.0);
                for [c, nc, nnc] in ARC_SERIES {
                    h += c * y_nm1 * y;
                    h1 += nc * y_nm1;
                    h2 += nnc * y_nm2;
                    y_nm2 = y_nm1;
                    y_nm1 *= y;
                }
                (h, h1, h2)
            } else {
                let (s, r) = (y.sqrt(), (1.0 - y).sqrt());
                let a = s.asin();
                (a / s, 0.5 / (y * r) - 0.5 * a / (y * s), -0.75 / (y * y * r) + 0.25 / (y * r * r * r) + 0.75 * a / (y * y * s))
            };
            Some([h, 0.25 * hy, 0.0625 * hyy])
        };
        let bits = |f: Option<[f64; 3]>| f.map(|v| v.map(f64::to_bits));
        for w in [[1e-9, 0.05, 0.0799, 3.9], [0.0801, 4.0, f64::NAN, 2.0], [0.0, 1e-3, 0.5, 0.079_999]] {
            let lanes = arc_factors(w);
            for (l, &wl) in w.iter().enumerate() {
                assert_eq!(bits(lanes[l]), bits(scalar(wl)), "w = {wl}");
                assert_eq!(bits(arc_factor(wl)), bits(scalar(wl)), "w = {wl}");
            }
        }
    }
}
