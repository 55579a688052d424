//! Distances between the primitives of triangulated shell mid-surfaces — point–triangle and
//! edge–edge pairs — with the closest-feature classification that picks the smooth formula
//! valid at a configuration (IPC: Li et al., *Incremental Potential Contact*, ACM Trans.
//! Graph. 39(4), 2020, §4 and supplement A; closest points after Ericson, *Real-Time
//! Collision Detection*, 2005, §5.1.5 and §5.1.9).
//!
//! A pair is four nodes in slots 0–3: (p, t₀, t₁, t₂) for a point and a triangle, (a₀, a₁, b₀,
//! b₁) for two edges. Its squared distance is one of four expressions of the slots its
//! closest features involve — point–point |p−q|², point–edge |(a−p)×(b−p)|²/|b−a|²,
//! point–plane ((p−a)·n)²/|n|² and line–line ((b₀−a₀)·n)²/|n|² — each smooth where it is the
//! distance; its gradient and Hessian in closed form are in `distance.rs` (the forms here in
//! `crate::autodiff`'s `Hd`, with exact derivatives, are the tests' reference).

use nalgebra::Vector3;

use super::distance;
#[cfg(test)]
use crate::autodiff::{cross, dot, point, sub, Hd, Hv};

/// The closest features of a pair: which slots enter the distance.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Feature {
    /// Between the points of slots i and j.
    PointPoint(usize, usize),
    /// Between the point of slot i and the line through slots j, k.
    PointEdge(usize, usize, usize),
    /// Between the point of slot i and the plane through slots j, k, l.
    PointPlane(usize, usize, usize, usize),
    /// Between the line through slots i, j and the line through k, l.
    LineLine(usize, usize, usize, usize),
}

/// Closest features of point x[0] and triangle x[1..4], with the weights w such that
/// Σ w_k x_k is the vector from the triangle's closest point to the point (Ericson §5.1.5).
pub fn point_triangle_feature(x: &[Vector3<f64>; 4]) -> (Feature, [f64; 4]) {
    let (p, a, b, c) = (x[0], x[1], x[2], x[3]);
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (Feature::PointPoint(0, 1), [1.0, -1.0, 0.0, 0.0]);
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (Feature::PointPoint(0, 2), [1.0, 0.0, -1.0, 0.0]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (Feature::PointEdge(0, 1, 2), [1.0, -(1.0 - v), -v, 0.0]);
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (Feature::PointPoint(0, 3), [1.0, 0.0, 0.0, -1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (Feature::PointEdge(0, 1, 3), [1.0, -(1.0 - w), 0.0, -w]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (Feature::PointEdge(0, 2, 3), [1.0, 0.0, -(1.0 - w), -w]);
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    (Feature::PointPlane(0, 1, 2, 3), [1.0, -(1.0 - v - w), -v, -w])
}

/// Closest features of edges x[0]–x[1] and x[2]–x[3], with the weights w such that Σ w_k x_k
/// is the vector between their closest points (Ericson §5.1.9). Nearly parallel edges are
/// measured from the closest endpoint (their line–line distance is undefined).
pub fn edge_edge_feature(x: &[Vector3<f64>; 4]) -> (Feature, [f64; 4]) {
    let (d1, d2, r) = (x[1] - x[0], x[3] - x[2], x[0] - x[2]);
    let (a, e, f) = (d1.dot(&d1), d2.dot(&d2), d2.dot(&r));
    let (b, c) = (d1.dot(&d2), d1.dot(&r));
    let denom = a * e - b * b;
    if denom <= 1e-10 * a * e {
        // Parallel: the closest of the four endpoint-to-edge distances.
        let mut best: Option<(f64, Feature, [f64; 4])> = None;
        for (i, j, k) in [(0, 2, 3), (1, 2, 3), (2, 0, 1), (3, 0, 1)] {
            let (feat, wl) = point_segment_feature(&x[i], &x[j], &x[k]);
            let mut w = [0.0; 4];
            w[i] = 1.0;
            w[j] = -wl[0];
            w[k] = -wl[1];
            let v: Vector3<f64> = (0..4).map(|m| x[m] * w[m]).sum();
            let feat = match feat {
                0 => Feature::PointPoint(i, j),
                1 => Feature::PointPoint(i, k),
                _ => Feature::PointEdge(i, j, k),
            };
            // Weights along the vector from the second primitive to the first.
            let (v, w) = if i < 2 { (v, w) } else { (-v, w.map(|q| -q)) };
            if best.as_ref().is_none_or(|b| v.norm_squared() < b.0) {
                best = Some((v.norm_squared(), feat, w));
            }
        }
        let (_, feat, w) = best.unwrap_or((0.0, Feature::PointPoint(0, 2), [1.0, 0.0, -1.0, 0.0]));
        return (feat, w);
    }
    let mut s = ((b * f - c * e) / denom).clamp(0.0, 1.0);
    let mut t = (b * s + f) / e;
    if t < 0.0 {
        t = 0.0;
        s = (-c / a).clamp(0.0, 1.0);
    } else if t > 1.0 {
        t = 1.0;
        s = ((b - c) / a).clamp(0.0, 1.0);
    }
    let w = [1.0 - s, s, -(1.0 - t), -t];
    let (si, ti) = (s > 0.0 && s < 1.0, t > 0.0 && t < 1.0);
    let ia = if s <= 0.0 { 0 } else { 1 };
    let ib = if t <= 0.0 { 2 } else { 3 };
    let feat = match (si, ti) {
        (true, true) => Feature::LineLine(0, 1, 2, 3),
        (false, true) => Feature::PointEdge(ia, 2, 3),
        (true, false) => Feature::PointEdge(ib, 0, 1),
        (false, false) => Feature::PointPoint(ia, ib),
    };
    (feat, w)
}

/// Closest feature of segment a–b to point p: 0 at a, 1 at b, 2 inside; with the weights
/// (1 − t, t) of the closest point.
fn point_segment_feature(p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> (u8, [f64; 2]) {
    let ab = b - a;
    let l2 = ab.norm_squared();
    let t = if l2 > 0.0 { (p - a).dot(&ab) / l2 } else { 0.0 };
    if t <= 0.0 {
        (0, [1.0, 0.0])
    } else if t >= 1.0 {
        (1, [0.0, 1.0])
    } else {
        (2, [1.0 - t, t])
    }
}

#[cfg(test)]
/// Squared distance of the features `f` of the four points `x`, with its gradient and
/// Hessian with respect to the 12 coordinates (slot k: variables 3k..3k+3).
pub fn squared_distance(f: Feature, x: &[Vector3<f64>; 4]) -> Hd<12> {
    // Differentiated only in the slots the feature involves (6 or 9 variables for point–point
    // and point–edge: a quarter and a half of the work), then expanded to the 12.
    match f {
        Feature::PointPoint(i, j) => expanded::<6>(f, x, &[i, j]),
        Feature::PointEdge(i, j, k) => expanded::<9>(f, x, &[i, j, k]),
        _ => {
            let p: [Hv<12>; 4] = std::array::from_fn(|k| point(&x[k], k));
            squared_distance_of(f, &p)
        }
    }
}

#[cfg(test)]
/// [`squared_distance_of`] with variables only for `slots` (N = 3 × their number), its
/// gradient and Hessian expanded to the 12 coordinates of the four slots.
fn expanded<const N: usize>(f: Feature, x: &[Vector3<f64>; 4], slots: &[usize]) -> Hd<12> {
    let r = squared_distance_in::<N>(f, x, slots);
    let at = |c: usize| 3 * slots[c / 3] + c % 3;
    let mut out = Hd::<12>::c(r.v);
    out.lin = r.lin;
    for ci in 0..N {
        out.g[at(ci)] = r.g[ci];
        for cj in 0..N {
            out.h[at(ci)][at(cj)] = r.h[ci][cj];
        }
    }
    out
}

#[cfg(test)]
/// Squared distance of the features `f` of the four points `x`, differentiated only in the
/// coordinates of `slots` (N = 3 × their number; slot `slots[c]` takes variables 3c..3c+3),
/// the other points held fixed: the derivatives of a feature in its own nodes only.
pub fn squared_distance_in<const N: usize>(f: Feature, x: &[Vector3<f64>; 4], slots: &[usize]) -> Hd<N> {
    let p: [Hv<N>; 4] = std::array::from_fn(|k| match slots.iter().position(|&s| s == k) {
        Some(c) => point(&x[k], c),
        None => [Hd::c(x[k].x), Hd::c(x[k].y), Hd::c(x[k].z)],
    });
    squared_distance_of(f, &p)
}

/// Squared distance of the features `f` (value only; [`distance::value`]).
pub fn squared_distance_value(f: Feature, x: &[Vector3<f64>; 4]) -> f64 {
    distance::value(f, x)
}

/// The ratio forms in [`Hd`]: exact gradients and Hessians by automatic differentiation, the
/// reference of the closed forms of [`distance`] in the tests.
#[cfg(test)]
fn squared_distance_of<const N: usize>(f: Feature, p: &[Hv<N>; 4]) -> Hd<N> {
    match f {
        Feature::PointPoint(i, j) => {
            let d = sub(&p[i], &p[j]);
            dot(&d, &d)
        }
        Feature::PointEdge(i, j, k) => {
            let c = cross(&sub(&p[j], &p[i]), &sub(&p[k], &p[i]));
            let e = sub(&p[k], &p[j]);
            dot(&c, &c) * dot(&e, &e).recip()
        }
        Feature::PointPlane(i, j, k, l) => {
            let n = cross(&sub(&p[k], &p[j]), &sub(&p[l], &p[j]));
            dot(&sub(&p[i], &p[j]), &n).square() * dot(&n, &n).recip()
        }
        Feature::LineLine(i, j, k, l) => {
            let n = cross(&sub(&p[j], &p[i]), &sub(&p[l], &p[k]));
            dot(&sub(&p[k], &p[i]), &n).square() * dot(&n, &n).recip()
        }
    }
}

#[cfg(test)]
/// |e_a × e_b|² of edges x[0]–x[1] and x[2]–x[3] (the argument of the edge–edge mollifier),
/// with gradient and Hessian.
pub fn cross_squared(x: &[Vector3<f64>; 4]) -> Hd<12> {
    let p: [Hv<12>; 4] = std::array::from_fn(|k| point(&x[k], k));
    let c = cross(&sub(&p[1], &p[0]), &sub(&p[3], &p[2]));
    dot(&c, &c)
}

/// The edge–edge mollifier of IPC (eq. 17 of the supplement): m(x) = −x²/ε² + 2x/ε for
/// x < ε, 1 beyond, with m, m′, m″ at x.
pub fn mollifier(x: f64, eps: f64) -> (f64, f64, f64) {
    if x >= eps {
        (1.0, 0.0, 0.0)
    } else {
        let r = x / eps;
        (r * (2.0 - r), (2.0 - 2.0 * r) / eps, -2.0 / (eps * eps))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
        Vector3::new(x, y, z)
    }

    /// Brute-force distance by sampling both primitives densely.
    fn sampled_pt(x: &[Vector3<f64>; 4]) -> f64 {
        let n = 400;
        let mut best = f64::INFINITY;
        for i in 0..=n {
            for j in 0..=(n - i) {
                let (u, w) = (i as f64 / n as f64, j as f64 / n as f64);
                let q = x[1] + (x[2] - x[1]) * u + (x[3] - x[1]) * w;
                best = best.min((x[0] - q).norm());
            }
        }
        best
    }

    #[test]
    fn point_triangle_distance_matches_sampling_in_every_region() {
        let tri = [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.1), v(0.2, 0.9, -0.1)];
        for p in [v(0.3, 0.3, 0.5), v(-0.5, -0.4, 0.2), v(1.6, -0.2, 0.0), v(0.5, -0.6, 0.3), v(0.9, 0.9, -0.4), v(-0.4, 0.5, 0.1), v(0.1, 1.5, 0.0)] {
            let x = [p, tri[0], tri[1], tri[2]];
            let (f, w) = point_triangle_feature(&x);
            let d = squared_distance_value(f, &x).sqrt();
            let r: Vector3<f64> = (0..4).map(|k| x[k] * w[k]).sum();
            let s = sampled_pt(&x);
            assert!((d - s).abs() < 2e-3, "{p:?} {f:?}: {d} vs sampled {s}");
            assert!((r.norm() - d).abs() < 1e-12, "{f:?}: weights give {} not {d}", r.norm());
        }
    }

    #[test]
    fn edge_edge_distance_matches_sampling() {
        for x in [
            [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.5, -0.5, 0.3), v(0.4, 0.5, 0.3)],
            [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(1.5, -0.5, 0.3), v(1.4, 0.5, 0.3)],
            [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(1.5, 0.2, 0.3), v(2.4, 0.5, 0.3)],
            [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.3, 0.2, 0.1), v(1.3, 0.2, 0.1)],
        ] {
            let (f, w) = edge_edge_feature(&x);
            let d = squared_distance_value(f, &x).sqrt();
            let r: Vector3<f64> = (0..4).map(|k| x[k] * w[k]).sum();
            let n = 2000;
            let s = (0..=n)
                .flat_map(|i| (0..=n).step_by(10).map(move |j| (i, j)))
                .map(|(i, j)| {
                    let (s, t) = (i as f64 / n as f64, j as f64 / n as f64);
                    ((x[0] + (x[1] - x[0]) * s) - (x[2] + (x[3] - x[2]) * t)).norm()
                })
                .fold(f64::INFINITY, f64::min);
            assert!((d - s).abs() < 3e-3, "{f:?}: {d} vs sampled {s}");
            assert!((r.norm() - d).abs() < 1e-12, "{f:?}: weights give {} not {d}", r.norm());
        }
    }

    /// The contact term uses ∂dist/∂x_k = w_k n (closest points stationary); it must equal
    /// the exact gradient of the feature's distance in every region.
    #[test]
    fn distance_gradient_is_weights_times_normal() {
        let tri = [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.1), v(0.2, 0.9, -0.1)];
        let mut cases: Vec<(bool, [Vector3<f64>; 4])> = [v(0.3, 0.3, 0.5), v(-0.5, -0.4, 0.2), v(0.5, -0.6, 0.3), v(0.9, 0.9, -0.4)].iter().map(|&p| (true, [p, tri[0], tri[1], tri[2]])).collect();
        cases.push((false, [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.5, -0.5, 0.3), v(0.4, 0.5, 0.3)]));
        cases.push((false, [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(1.5, -0.5, 0.3), v(1.4, 0.5, 0.3)]));
        for (pt, x) in cases {
            let (f, w) = if pt { point_triangle_feature(&x) } else { edge_edge_feature(&x) };
            let d2 = squared_distance(f, &x);
            let d = d2.v.sqrt();
            let n: Vector3<f64> = (0..4).map(|k| x[k] * w[k]).sum::<Vector3<f64>>() / d;
            for i in 0..12 {
                let exact = d2.g[i] / (2.0 * d);
                assert!((exact - w[i / 3] * n[i % 3]).abs() < 1e-12, "{f:?} component {i}: {exact} vs {}", w[i / 3] * n[i % 3]);
            }
        }
    }

    #[test]
    fn squared_distance_derivatives_match_finite_differences() {
        let x = [v(0.3, 0.25, 0.4), v(0.0, 0.0, 0.0), v(1.0, 0.1, 0.1), v(0.2, 0.9, -0.1)];
        for f in [Feature::PointPlane(0, 1, 2, 3), Feature::PointEdge(0, 1, 2), Feature::LineLine(0, 2, 1, 3), Feature::PointPoint(0, 3)] {
            let d = squared_distance(f, &x);
            let h = 1e-6;
            for i in 0..12 {
                let mut xp = x;
                let mut xm = x;
                xp[i / 3][i % 3] += h;
                xm[i / 3][i % 3] -= h;
                let (dp, dm) = (squared_distance(f, &xp), squared_distance(f, &xm));
                let g = (dp.v - dm.v) / (2.0 * h);
                assert!((g - d.g[i]).abs() < 1e-7, "{f:?} grad {i}: {} vs {g}", d.g[i]);
                for j in 0..12 {
                    let hh = (dp.g[j] - dm.g[j]) / (2.0 * h);
                    assert!((hh - d.h[i][j]).abs() < 1e-6 * (1.0 + hh.abs()), "{f:?} hess {i},{j}: {} vs {hh}", d.h[i][j]);
                }
            }
        }
    }
}
