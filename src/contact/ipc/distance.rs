//! Closed-form gradients and Hessians of the squared distances of contact primitives —
//! point–point, point–edge (line), point–plane and line–line — in the nodes of the closest
//! feature (the formulas of IPC's `distance/` module, Li et al., *Incremental Potential
//! Contact*, ACM Trans. Graph. 39(4), 2020, supplement A, written here in one form for all
//! four).
//!
//! Each distance is a minimum over the closest points' parameters θ (none, t on a line,
//! (u, v) on a plane, (s, t) on two lines) of q(x, θ) = |r|², r = Σ_k c_k(θ) x_k, with
//! coefficients c_k affine in θ: c_k = c_k⁰ + Σ_α c_kα θ_α. With D_α = ∂r/∂θ_α = Σ_k c_kα x_k,
//! the Gram matrix G_αβ = D_α·D_β and the optimum θ* (where D_α·r = 0), the envelope theorem
//! and implicit differentiation of θ*(x) give
//!
//!   ∂q/∂x_i = 2 c_i r,
//!   ∂²q/∂x_i∂x_j = 2 c_i c_j I − 2 Σ_αβ ω_iα (G⁻¹)_αβ ω_jβᵀ,   ω_iα = c_iα r + c_i D_α,
//!
//! (the Schur complement ∂²q/∂x² − ∂²q/∂x∂θ (∂²q/∂θ²)⁻¹ ∂²q/∂θ∂x). The 3×3 blocks cost a few
//! dozen flops each, on fixed-size nalgebra matrices; `crate::autodiff` derives the same
//! derivatives from the ratio forms of `primitives.rs` and is the reference of the tests.

use nalgebra::{Matrix3, Vector3};

use super::primitives::Feature;

/// The squared distance q of a feature of M nodes with P closest-point parameters, and what
/// its gradient and Hessian are formed from (see the module comment).
#[derive(Clone, Copy, Debug)]
pub struct SquaredDistance<const M: usize, const P: usize> {
    /// q, from the same ratio form (and the same operations) as [`value`].
    pub value: f64,
    /// r = Σ_k c_k x_k at the optimum: the vector between the closest points.
    r: Vector3<f64>,
    /// c_k at the optimum.
    c: [f64; M],
    /// ω_kα = c_kα r + c_k D_α.
    omega: [[Vector3<f64>; P]; M],
    /// G⁻¹.
    ginv: [[f64; P]; P],
}

fn dot(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    // In the order of `autodiff::dot`, so that values agree to the bit.
    a.x * b.x + a.y * b.y + a.z * b.z
}

fn cross(a: &Vector3<f64>, b: &Vector3<f64>) -> Vector3<f64> {
    Vector3::new(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x)
}

impl<const M: usize, const P: usize> SquaredDistance<M, P> {
    fn new(value: f64, r: Vector3<f64>, c: [f64; M], dc: [[f64; P]; M], dirs: [Vector3<f64>; P], gram_inverse: [[f64; P]; P]) -> Self {
        let omega = std::array::from_fn(|k| std::array::from_fn(|a| r * dc[k][a] + dirs[a] * c[k]));
        Self { value, r, c, omega, ginv: gram_inverse }
    }

    /// ∂q/∂x_i = 2 c_i r.
    pub fn gradient(&self, i: usize) -> Vector3<f64> {
        self.r * (2.0 * self.c[i])
    }

    /// The block ∂²q/∂x_i∂x_j.
    pub fn hessian(&self, i: usize, j: usize) -> Matrix3<f64> {
        let mut h = Matrix3::from_diagonal_element(2.0 * self.c[i] * self.c[j]);
        for a in 0..P {
            let mut w = Vector3::zeros();
            for b in 0..P {
                w += self.omega[i][b] * self.ginv[a][b];
            }
            h -= (w * self.omega[j][a].transpose()) * 2.0;
        }
        h
    }

    /// The block (i, j) of the Hessian of F(q): F″ ∇_i q ∇_j qᵀ + F′ ∂²q/∂x_i∂x_j, for
    /// F′ = `f1`, F″ = `f2`.
    pub fn chain_hessian(&self, i: usize, j: usize, f1: f64, f2: f64) -> Matrix3<f64> {
        self.r * self.r.transpose() * (4.0 * f2 * self.c[i] * self.c[j]) + self.hessian(i, j) * f1
    }
}

/// |p − q|² (slots p, q).
pub fn point_point(p: &Vector3<f64>, q: &Vector3<f64>) -> SquaredDistance<2, 0> {
    let d = p - q;
    SquaredDistance::new(dot(&d, &d), d, [1.0, -1.0], [[], []], [], [])
}

/// Squared distance of point p to the line through a, b (slots p, a, b):
/// |(a − p) × (b − p)|² / |b − a|², r = p − a − t (b − a).
pub fn point_line(p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> SquaredDistance<3, 1> {
    let (ap, bp) = (a - p, b - p);
    let cr = cross(&ap, &bp);
    let e = b - a;
    let ee = dot(&e, &e);
    let value = dot(&cr, &cr) * (1.0 / ee);
    let pa = p - a;
    let t = dot(&pa, &e) / ee;
    let r = pa - e * t;
    // r = p − (1 − t) a − t b; ∂r/∂t = a − b.
    SquaredDistance::new(value, r, [1.0, t - 1.0, -t], [[0.0], [1.0], [-1.0]], [-e], [[1.0 / ee]])
}

/// Inverse of the 2×2 Gram matrix of d0, d1.
fn gram_inverse(d0: &Vector3<f64>, d1: &Vector3<f64>) -> [[f64; 2]; 2] {
    let (g00, g01, g11) = (dot(d0, d0), dot(d0, d1), dot(d1, d1));
    let det = g00 * g11 - g01 * g01;
    [[g11 / det, -g01 / det], [-g01 / det, g00 / det]]
}

/// Squared distance of point p to the plane through a, b, c (slots p, a, b, c):
/// ((p − a)·n)² / |n|², n = (b − a) × (c − a); r = p − a − u (b − a) − v (c − a).
pub fn point_plane(p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>, c: &Vector3<f64>) -> SquaredDistance<4, 2> {
    let (e1, e2) = (b - a, c - a);
    let n = cross(&e1, &e2);
    let pa = p - a;
    let pn = dot(&pa, &n);
    let nn = dot(&n, &n);
    let value = (pn * pn) * (1.0 / nn);
    // r along n, exactly (no cancellation of the in-plane parts).
    let r = n * (pn / nn);
    // u, v with p − r = a + u e1 + v e2: from the Gram system of e1, e2.
    let gi = gram_inverse(&e1, &e2);
    let (b0, b1) = (dot(&pa, &e1), dot(&pa, &e2));
    let (u, v) = (gi[0][0] * b0 + gi[0][1] * b1, gi[1][0] * b0 + gi[1][1] * b1);
    // ∂r/∂u = −e1, ∂r/∂v = −e2: the Gram matrix of (−e1, −e2) is that of (e1, e2).
    SquaredDistance::new(value, r, [1.0, u + v - 1.0, -u, -v], [[0.0, 0.0], [1.0, 1.0], [-1.0, 0.0], [0.0, -1.0]], [-e1, -e2], gi)
}

/// Squared distance of the line through a0, a1 and the line through b0, b1 (slots a0, a1,
/// b0, b1): ((b0 − a0)·n)² / |n|², n = (a1 − a0) × (b1 − b0); r = x_a(s) − x_b(t).
pub fn line_line(a0: &Vector3<f64>, a1: &Vector3<f64>, b0: &Vector3<f64>, b1: &Vector3<f64>) -> SquaredDistance<4, 2> {
    let (u, v) = (a1 - a0, b1 - b0);
    let n = cross(&u, &v);
    let w = b0 - a0;
    let wn = dot(&w, &n);
    let nn = dot(&n, &n);
    let value = (wn * wn) * (1.0 / nn);
    // r = a0 + s u − b0 − t v, along n: r = −n (w·n)/|n|².
    let r = n * (-wn / nn);
    let mv = -v;
    let gi = gram_inverse(&u, &mv);
    // D_s = u, D_t = −v; optimum G θ = −(D·(a0 − b0)) = (D·w).
    let (q0, q1) = (dot(&u, &w), dot(&mv, &w));
    let (s, t) = (gi[0][0] * q0 + gi[0][1] * q1, gi[1][0] * q0 + gi[1][1] * q1);
    SquaredDistance::new(value, r, [1.0 - s, s, t - 1.0, -t], [[-1.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.0, -1.0]], [u, mv], gi)
}

/// Gradient (per node) and Hessian (per node pair) of F(q) for the squared distance q of
/// feature `f` of the nodes at `x` (the feature must use slots 0..m in order, as the
/// canonical features of `potential.rs` do), with (F′, F″) = `dq(q)`. Returns m, the
/// gradient in slots 0..m and the upper blocks (i ≤ j < m) of the Hessian.
pub fn chain(f: Feature, x: &[Vector3<f64>; 4], dq: impl Fn(f64) -> (f64, f64)) -> (usize, [Vector3<f64>; 4], [[Matrix3<f64>; 4]; 4]) {
    let mut g = [Vector3::zeros(); 4];
    let mut h = [[Matrix3::zeros(); 4]; 4];
    let m = chain_into(f, x, dq, &mut g, &mut h);
    (m, g, h)
}

/// [`chain`] written into `g` and `h` in place: returns m and sets `g[i]` and `h[i][j]`
/// for i ≤ j < m only, leaving the other entries as they were (a caller reusing a buffer
/// reads no more than those).
pub fn chain_into(f: Feature, x: &[Vector3<f64>; 4], dq: impl Fn(f64) -> (f64, f64), g: &mut [Vector3<f64>; 4], h: &mut [[Matrix3<f64>; 4]; 4]) -> usize {
    fn fill<const M: usize, const P: usize>(d: &SquaredDistance<M, P>, dq: impl Fn(f64) -> (f64, f64), g: &mut [Vector3<f64>; 4], h: &mut [[Matrix3<f64>; 4]; 4]) -> usize {
        let (f1, f2) = dq(d.value);
        for i in 0..M {
            g[i] = d.gradient(i) * f1;
            for j in i..M {
                h[i][j] = d.chain_hessian(i, j, f1, f2);
            }
        }
        M
    }
    match f {
        Feature::PointPoint(..) => fill(&point_point(&x[0], &x[1]), dq, g, h),
        Feature::PointEdge(..) => fill(&point_line(&x[0], &x[1], &x[2]), dq, g, h),
        Feature::PointPlane(..) => fill(&point_plane(&x[0], &x[1], &x[2], &x[3]), dq, g, h),
        Feature::LineLine(..) => fill(&line_line(&x[0], &x[1], &x[2], &x[3]), dq, g, h),
    }
}

/// The squared distance of feature `f` of the points `x` (any slots), value only: the ratio
/// forms of [`Feature`]'s documentation in plain floating point, in the order of operations
/// of the constructors above (and of the automatic differentiation of the tests), so that
/// all give the same bits.
pub fn value(f: Feature, x: &[Vector3<f64>; 4]) -> f64 {
    match f {
        Feature::PointPoint(i, j) => {
            let d = x[i] - x[j];
            dot(&d, &d)
        }
        Feature::PointEdge(i, j, k) => {
            let cr = cross(&(x[j] - x[i]), &(x[k] - x[i]));
            let e = x[k] - x[j];
            dot(&cr, &cr) * (1.0 / dot(&e, &e))
        }
        Feature::PointPlane(i, j, k, l) => {
            let n = cross(&(x[k] - x[j]), &(x[l] - x[j]));
            let pn = dot(&(x[i] - x[j]), &n);
            (pn * pn) * (1.0 / dot(&n, &n))
        }
        Feature::LineLine(i, j, k, l) => {
            let n = cross(&(x[j] - x[i]), &(x[l] - x[k]));
            let wn = dot(&(x[k] - x[i]), &n);
            (wn * wn) * (1.0 / dot(&n, &n))
        }
    }
}

/// |u × v|² of u = a1 − a0, v = b1 − b0 (the argument of the edge–edge mollifier) with its
/// gradient in (u, v) and Hessian blocks (uu, uv, vv), from |u × v|² = |u|²|v|² − (u·v)²:
/// ∇_u = 2|v|² u − 2(u·v) v, ∇_v = 2|u|² v − 2(u·v) u, H_uu = 2|v|² I − 2 v vᵀ,
/// H_vv = 2|u|² I − 2 u uᵀ, H_uv = 4 u vᵀ − 2 v uᵀ − 2(u·v) I.
pub fn cross_squared(u: &Vector3<f64>, v: &Vector3<f64>) -> (f64, [Vector3<f64>; 2], [Matrix3<f64>; 3]) {
    let c = cross(u, v);
    let (uu, vv, uv) = (dot(u, u), dot(v, v), dot(u, v));
    let g = [u * (2.0 * vv) - v * (2.0 * uv), v * (2.0 * uu) - u * (2.0 * uv)];
    let i = Matrix3::identity();
    let h = [i * (2.0 * vv) - v * v.transpose() * 2.0, u * v.transpose() * 4.0 - v * u.transpose() * 2.0 - i * (2.0 * uv), i * (2.0 * uu) - u * u.transpose() * 2.0];
    (dot(&c, &c), g, h)
}

#[cfg(test)]
mod tests {
    use super::super::primitives::{cross_squared as ad_cross_squared, squared_distance};
    use super::*;
    use crate::autodiff::Hd;

    fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
        Vector3::new(x, y, z)
    }

    /// Largest |entry| of an AD gradient and Hessian: the scale of the relative tolerance.
    fn scale(d: &Hd<12>) -> f64 {
        d.h.iter().flatten().chain(d.g.iter()).fold(0.0f64, |m, x| m.max(x.abs()))
    }

    /// The closed forms equal the second-order automatic differentiation of the ratio forms
    /// (`primitives::squared_distance`, the formulation before them) to 10⁻¹⁰ of the largest
    /// derivative, and the values to the bit, for every feature at generic and at stacked-ply
    /// configurations (a point 1 mm above a 2 cm facet; edges 1 mm apart).
    #[test]
    fn closed_forms_match_automatic_differentiation() {
        let configs = [
            [v(0.3, 0.25, 0.4), v(0.0, 0.0, 0.0), v(1.0, 0.1, 0.1), v(0.2, 0.9, -0.1)],
            [v(0.011, 0.007, 0.001), v(0.0, 0.0, 0.0), v(0.02, 0.0, 0.0002), v(0.0, 0.02, -0.0001)],
            [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.5, -0.5, 0.3), v(0.45, 0.5, 0.31)],
            [v(0.0, 0.0, 0.0), v(0.02, 0.001, 0.0), v(0.005, -0.01, 0.001), v(0.006, 0.012, 0.0012)],
        ];
        for x in configs {
            for f in [Feature::PointPoint(0, 1), Feature::PointEdge(0, 1, 2), Feature::PointPlane(0, 1, 2, 3), Feature::LineLine(0, 1, 2, 3)] {
                let ad = squared_distance(f, &x);
                let (f1, f2) = (0.7, -1.9);
                let full = ad.chain(0.0, f1, f2);
                let (m, g, h) = chain(f, &x, |q| {
                    assert_eq!(q.to_bits(), ad.v.to_bits(), "{f:?}: value {q} vs {}", ad.v);
                    (f1, f2)
                });
                assert_eq!(value(f, &x).to_bits(), ad.v.to_bits(), "{f:?}: value {} vs {}", value(f, &x), ad.v);
                let sf = scale(&full);
                for i in 0..4 {
                    for c in 0..3 {
                        let want = if i < m { full.g[3 * i + c] } else { 0.0 };
                        assert!((g[i][c] - want).abs() <= 1e-10 * sf, "{f:?}: gradient {i}.{c}: {} vs {want}", g[i][c]);
                    }
                    for j in 0..4 {
                        let (blk, hi) = if i <= j { (h[i][j], j) } else { (h[j][i].transpose(), i) };
                        for p in 0..3 {
                            for q in 0..3 {
                                let want = if hi < m { full.h[3 * i + p][3 * j + q] } else { 0.0 };
                                assert!((blk[(p, q)] - want).abs() <= 1e-10 * sf, "{f:?}: Hessian {i}.{p},{j}.{q}: {} vs {want}", blk[(p, q)]);
                            }
                        }
                    }
                }
            }
        }
    }

    /// The closest-point coefficients c_k of each form sum to zero (r is a difference of
    /// points), and r equals Σ c_k x_k.
    #[test]
    fn coefficients_are_differences() {
        let x = [v(0.3, 0.25, 0.4), v(0.0, 0.0, 0.0), v(1.0, 0.1, 0.1), v(0.2, 0.9, -0.1)];
        let pl = point_plane(&x[0], &x[1], &x[2], &x[3]);
        let ll = line_line(&x[0], &x[1], &x[2], &x[3]);
        for d in [pl, ll] {
            assert!(d.c.iter().sum::<f64>().abs() < 1e-14);
            let r: Vector3<f64> = (0..4).map(|k| x[k] * d.c[k]).sum();
            assert!((r - d.r).norm() < 1e-14);
        }
        let pe = point_line(&x[0], &x[1], &x[2]);
        assert!(pe.c.iter().sum::<f64>().abs() < 1e-14);
        let r: Vector3<f64> = (0..3).map(|k| x[k] * pe.c[k]).sum();
        assert!((r - pe.r).norm() < 1e-14);
    }

    /// |u × v|² and its derivatives equal automatic differentiation of the cross product.
    #[test]
    fn cross_squared_matches_automatic_differentiation() {
        let x = [v(0.0, 0.0, 0.0), v(1.0, 0.02, 0.0), v(0.3, 0.0, 0.05), v(1.4, 0.0, 0.051)];
        let ad = ad_cross_squared(&x);
        let (val, g, h) = cross_squared(&(x[1] - x[0]), &(x[3] - x[2]));
        let s = scale(&ad);
        assert!((val - ad.v).abs() <= 1e-14 * ad.v.abs().max(1e-300));
        for c in 0..3 {
            // slot 1 is +u, slot 3 is +v
            assert!((g[0][c] - ad.g[3 + c]).abs() <= 1e-10 * s);
            assert!((g[1][c] - ad.g[9 + c]).abs() <= 1e-10 * s);
            for d in 0..3 {
                assert!((h[0][(c, d)] - ad.h[3 + c][3 + d]).abs() <= 1e-10 * s);
                assert!((h[1][(c, d)] - ad.h[3 + c][9 + d]).abs() <= 1e-10 * s);
                assert!((h[2][(c, d)] - ad.h[9 + c][9 + d]).abs() <= 1e-10 * s);
            }
        }
    }
}
