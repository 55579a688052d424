//! The barrier potential of the active surface-contact pairs, differentiated once per closest
//! feature (IPC: Li et al., *Incremental Potential Contact*, ACM Trans. Graph. 39(4), 2020,
//! §4 and supplement A, where point–triangle and edge–edge pairs whose closest features are
//! a vertex pair or a vertex and an edge are collected as vertex–vertex and vertex–edge
//! constraints with a multiplicity).
//!
//! Stacked plies make many pairs share a closest feature: above a stacked vertex pair (a, b)
//! every point–triangle pair of a with a triangle around b and every edge–edge pair of an
//! edge at a with an edge at b measures the same distance |x_a − x_b|. The potential stays
//! the sum over all pairs, Σ_p κ_p b(dist_f − c_p, d̂_p), each pair with its own offset,
//! barrier thickness and stiffness; but a pair's energy is a function of its feature's
//! distance dist_f only, so per feature f
//!
//!   E_f(x) = Σ_{p ∈ f} e_p(dist_f(x)),   ∇E_f = E′ ∇dist_f,   ∇²E_f = E″ ∇dist_f ∇dist_fᵀ + E′ ∇²dist_f
//!
//! with the scalar sums E′ = Σ e_p′ and E″ = Σ e_p″: the distance's derivatives are formed
//! once per feature, in that feature's own nodes (2, 3 or 4), instead of once per pair in
//! all four. The sum is the same smooth potential as before, to round-off. Edge–edge pairs
//! inside the mollifier's range (nearly parallel edges) carry a factor depending on all four
//! nodes and are differentiated on their own.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use nalgebra::{Matrix3, Vector3};

use crate::autodiff::{cross, dot, point, Hd, Hv};
use super::primitives::{mollifier, squared_distance_in, Feature};
use crate::element::NODE_DOFS;

/// Multiply-rotate hash for small integer keys (the Fx hash of the Rust compiler): node
/// numbers need no protection against collisions chosen by an adversary.
#[derive(Default, Clone, Copy)]
pub(super) struct FxHasher(u64);

impl Hasher for FxHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_usize(&mut self, i: usize) {
        self.write_u64(i as u64);
    }
    fn write_u8(&mut self, i: u8) {
        self.write_u64(i as u64);
    }
}

/// A `HashMap` with [`FxHasher`].
pub(super) type FxMap<K, V> = HashMap<K, V, BuildHasherDefault<FxHasher>>;

/// The closest feature of a pair by its global node numbers, in a canonical order (the
/// distance of each kind is symmetric in the orders it forgets).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub(super) enum FeatureKey {
    /// Two vertices (sorted).
    PointPoint([usize; 2]),
    /// A vertex and an edge (its nodes sorted).
    PointEdge(usize, [usize; 2]),
    /// A vertex and a triangle's plane (its nodes sorted).
    PointPlane(usize, [usize; 3]),
    /// Two edges' lines (each sorted, the pair sorted).
    LineLine([usize; 2], [usize; 2]),
}

fn sorted<const M: usize>(mut a: [usize; M]) -> [usize; M] {
    a.sort_unstable();
    a
}

impl FeatureKey {
    /// The key of feature `f` of a pair on global `nodes` (its slots 0–3).
    pub(super) fn of(f: Feature, nodes: &[usize; 4]) -> Self {
        match f {
            Feature::PointPoint(i, j) => Self::PointPoint(sorted([nodes[i], nodes[j]])),
            Feature::PointEdge(i, j, k) => Self::PointEdge(nodes[i], sorted([nodes[j], nodes[k]])),
            Feature::PointPlane(i, j, k, l) => Self::PointPlane(nodes[i], sorted([nodes[j], nodes[k], nodes[l]])),
            Feature::LineLine(i, j, k, l) => {
                let (a, b) = (sorted([nodes[i], nodes[j]]), sorted([nodes[k], nodes[l]]));
                Self::LineLine(a.min(b), a.max(b))
            }
        }
    }

    /// The feature's nodes (slots 0.., the rest unused) and the feature in those slots.
    fn nodes(&self) -> ([usize; 4], usize, Feature) {
        match *self {
            Self::PointPoint([a, b]) => ([a, b, a, a], 2, Feature::PointPoint(0, 1)),
            Self::PointEdge(p, [a, b]) => ([p, a, b, p], 3, Feature::PointEdge(0, 1, 2)),
            Self::PointPlane(p, [a, b, c]) => ([p, a, b, c], 4, Feature::PointPlane(0, 1, 2, 3)),
            Self::LineLine([a, b], [c, d]) => ([a, b, c, d], 4, Feature::LineLine(0, 1, 2, 3)),
        }
    }
}

/// One pair's barrier energy as a function of its feature's distance: e(dist), e′, e″.
#[derive(Clone, Copy, Debug)]
pub(super) struct Scalar {
    pub(super) e: f64,
    pub(super) e1: f64,
    pub(super) e2: f64,
}

/// Gradient and Hessian of a potential in the coordinates of 2, 3 or 4 nodes.
pub(super) enum Derivative {
    Two([usize; 2], Hd<6>),
    Three([usize; 3], Hd<9>),
    Four([usize; 4], Hd<12>),
}

/// Σ_p e_p(dist_f) for the pairs of one feature: per distinct key, the summed scalars.
pub(super) fn group(pairs: impl Iterator<Item = (FeatureKey, Scalar)>) -> Vec<(FeatureKey, Scalar)> {
    let mut all: Vec<(FeatureKey, Scalar)> = pairs.collect();
    all.sort_unstable_by(|a, b| a.0.cmp(&b.0));
    let mut out: Vec<(FeatureKey, Scalar)> = Vec::with_capacity(all.len());
    for (k, s) in all {
        match out.last_mut() {
            Some((last, acc)) if *last == k => {
                acc.e += s.e;
                acc.e1 += s.e1;
                acc.e2 += s.e2;
            }
            _ => out.push((k, s)),
        }
    }
    out
}

/// Gradient and Hessian of E(dist_f(x)) = Σ_p e_p(dist_f) (see the module comment) in the
/// feature's own nodes, at positions `x`.
pub(super) fn derivative(key: &FeatureKey, s: &Scalar, x: &(dyn Fn(usize) -> Vector3<f64> + Sync)) -> Derivative {
    let (nodes, m, f) = key.nodes();
    let xs = nodes.map(x);
    // E as a function of the squared distance q = dist²: dE/dq = E′/(2 dist),
    // d²E/dq² = E″/(4 dist²) − E′/(4 dist³).
    let chain = |q: f64| {
        let dist = q.sqrt();
        let (dd, ddd) = (0.5 / dist, -0.25 / (dist * dist * dist));
        (s.e, s.e1 * dd, s.e2 * dd * dd + s.e1 * ddd)
    };
    match m {
        2 => {
            let q = squared_distance_in::<6>(f, &xs, &[0, 1]);
            let (e, e1, e2) = chain(q.v);
            Derivative::Two([nodes[0], nodes[1]], q.chain(e, e1, e2))
        }
        3 => {
            let q = squared_distance_in::<9>(f, &xs, &[0, 1, 2]);
            let (e, e1, e2) = chain(q.v);
            Derivative::Three([nodes[0], nodes[1], nodes[2]], q.chain(e, e1, e2))
        }
        _ => {
            let q = squared_distance_in::<12>(f, &xs, &[0, 1, 2, 3]);
            let (e, e1, e2) = chain(q.v);
            Derivative::Four(nodes, q.chain(e, e1, e2))
        }
    }
}

/// `d` in the 12 coordinates of the four nodes `nodes` (the feature's nodes are among them).
fn in_pair_nodes(d: &Derivative, nodes: &[usize; 4]) -> Hd<12> {
    fn spread<const N: usize>(e: &Hd<N>, own: &[usize], nodes: &[usize; 4]) -> Hd<12> {
        let slot: Vec<usize> = own.iter().map(|a| nodes.iter().position(|b| b == a).unwrap_or(0)).collect();
        let at = |c: usize| 3 * slot[c / 3] + c % 3;
        let mut out = Hd::<12>::c(e.v);
        out.lin = e.lin;
        for i in 0..N {
            out.g[at(i)] += e.g[i];
            for j in 0..N {
                out.h[at(i)][at(j)] += e.h[i][j];
            }
        }
        out
    }
    match d {
        Derivative::Two(n, e) => spread(e, n, nodes),
        Derivative::Three(n, e) => spread(e, n, nodes),
        Derivative::Four(n, e) => spread(e, n, nodes),
    }
}

/// Gradient and Hessian, in the four nodes (a₀, a₁, b₀, b₁) of a nearly parallel edge–edge
/// pair, of E = F(dist_f) m(|u × v|²) (IPC supplement eq. 17: the mollifier m of threshold
/// `eps`, u = a₁ − a₀, v = b₁ − b₀), `s` holding F, F′, F″ in the distance of the pair's
/// closest feature `key`. The distance is differentiated in the feature's own nodes and
/// |u × v|² in the six coordinates of u and v, then both are spread to the twelve (∂/∂a₀ =
/// −∂/∂u, ∂/∂a₁ = ∂/∂u, likewise for v) and multiplied: the same derivatives as the product
/// formed in all twelve coordinates throughout, at a fraction of the work.
pub(super) fn mollified_derivative(nodes: &[usize; 4], key: &FeatureKey, s: &Scalar, eps: f64, x: &(dyn Fn(usize) -> Vector3<f64> + Sync)) -> Hd<12> {
    let f = in_pair_nodes(&derivative(key, s, x), nodes);
    let xs = nodes.map(x);
    let (u, v) = (xs[1] - xs[0], xs[3] - xs[2]);
    let uv = [Vector3::zeros(), u, Vector3::zeros(), v];
    // |u × v|² in the variables u (0..3) and v (3..6): slots 1 and 3 of `uv`.
    let cs = {
        let p: [Hv<6>; 4] = std::array::from_fn(|k| match k {
            1 => point(&uv[1], 0),
            3 => point(&uv[3], 1),
            _ => [Hd::c(0.0), Hd::c(0.0), Hd::c(0.0)],
        });
        let c = cross(&p[1], &p[3]);
        dot(&c, &c)
    };
    let (mv, m1, m2) = mollifier(cs.v, eps);
    let m6 = cs.chain(mv, m1, m2);
    let var = |i: usize| -> (usize, f64) {
        let (slot, c) = (i / 3, i % 3);
        (3 * (slot / 2) + c, if slot % 2 == 0 { -1.0 } else { 1.0 })
    };
    let mut m = Hd::<12>::c(m6.v);
    m.lin = m6.lin;
    for i in 0..12 {
        let (vi, si) = var(i);
        m.g[i] = si * m6.g[vi];
        for j in 0..12 {
            let (vj, sj) = var(j);
            m.h[i][j] = si * sj * m6.h[vi][vj];
        }
    }
    f * m
}

/// The tangent blocks of the contact terms: −∇²E per node (`diag`) and per node pair a < b
/// (`off`, the block of row a, column b).
#[derive(Default)]
pub(super) struct Blocks {
    pub(super) diag: FxMap<usize, Matrix3<f64>>,
    pub(super) off: FxMap<(usize, usize), Matrix3<f64>>,
}

impl Blocks {
    /// Adds −(the 3×3 block of slots i, j) to the tangent blocks of nodes a = nodes[i],
    /// b = nodes[j], visiting each unordered slot pair once (a ≤ b).
    fn add(&mut self, nodes: &[usize], block: impl Fn(usize, usize) -> Matrix3<f64>) {
        for (i, &a) in nodes.iter().enumerate() {
            for (j, &b) in nodes.iter().enumerate() {
                if a > b || (a == b && i != j) {
                    continue;
                }
                let m = block(i, j);
                if a == b {
                    *self.diag.entry(a).or_insert_with(Matrix3::zeros) -= m;
                } else {
                    *self.off.entry((a, b)).or_insert_with(Matrix3::zeros) -= m;
                }
            }
        }
    }

    /// Forces −∇E into `f_ext` and blocks −∇²E (symmetrised) of a potential differentiated
    /// in the coordinates of `nodes`.
    pub(super) fn add_hd<const N: usize>(&mut self, nodes: &[usize], e: &Hd<N>, f_ext: &mut [f64], hessian: bool) {
        for (k, &a) in nodes.iter().enumerate() {
            for c in 0..3 {
                f_ext[NODE_DOFS * a + c] -= e.g[3 * k + c];
            }
        }
        if hessian {
            self.add(nodes, |i, j| Matrix3::from_fn(|p, q| 0.5 * (e.h[3 * i + p][3 * j + q] + e.h[3 * j + q][3 * i + p])));
        }
    }

    /// [`Blocks::add_hd`] for a [`Derivative`].
    pub(super) fn add_derivative(&mut self, d: &Derivative, f_ext: &mut [f64], hessian: bool) {
        match d {
            Derivative::Two(n, e) => self.add_hd(n, e, f_ext, hessian),
            Derivative::Three(n, e) => self.add_hd(n, e, f_ext, hessian),
            Derivative::Four(n, e) => self.add_hd(n, e, f_ext, hessian),
        }
    }

    /// Forces and blocks of a potential of r = Σ_k w_k x_k (friction): gradient w_k g and
    /// Hessian blocks w_i w_j K; slots with w_k = 0 contribute nothing and are skipped.
    pub(super) fn add_weighted(&mut self, nodes: &[usize; 4], weights: &[f64; 4], g: &Vector3<f64>, k: Option<&Matrix3<f64>>, f_ext: &mut [f64]) {
        let used: Vec<usize> = (0..4).filter(|&s| weights[s] != 0.0).collect();
        for &s in &used {
            for c in 0..3 {
                f_ext[NODE_DOFS * nodes[s] + c] -= weights[s] * g[c];
            }
        }
        let Some(k) = k else { return };
        let sub: Vec<usize> = used.iter().map(|&s| nodes[s]).collect();
        self.add(&sub, |i, j| k * (weights[used[i]] * weights[used[j]]));
    }
}

#[cfg(test)]
mod tests {
    use super::super::primitives::{cross_squared, edge_edge_feature, squared_distance};
    use super::*;

    /// The energy of pairs summed per feature and the mollified edge–edge product formed in
    /// the features' own coordinates have the derivatives of the same energies formed in all
    /// twelve coordinates of each pair (the formulation before the split).
    #[test]
    fn per_feature_derivatives_match_the_twelve_coordinate_forms() {
        let v = Vector3::new;
        let ids = [7usize, 3, 12, 5];
        // Nearly parallel edges (mollified) whose closest features are an endpoint and an
        // edge, and crossing edges (line–line).
        for xs in [
            [v(0.0, 0.0, 0.0), v(1.0, 0.02, 0.0), v(0.3, 0.0, 0.05), v(1.4, 0.0, 0.051)],
            [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.5, -0.5, 0.3), v(0.45, 0.5, 0.31)],
        ] {
            let x = |a: usize| xs[ids.iter().position(|&b| b == a).unwrap_or(0)];
            let (feat, _) = edge_edge_feature(&xs);
            let key = FeatureKey::of(feat, &ids);
            let q = squared_distance(feat, &xs);
            let dist = q.v.sqrt();
            let s = Scalar { e: 0.3 * dist * dist, e1: 0.6 * dist + 0.1, e2: 0.6 - 0.2 * dist };
            let (dd, ddd) = (0.5 / dist, -0.25 / (dist * dist * dist));
            let full = q.chain(s.e, s.e1 * dd, s.e2 * dd * dd + s.e1 * ddd);
            let split = in_pair_nodes(&derivative(&key, &s, &x), &ids);
            let eps = 1e-3 * (xs[1] - xs[0]).norm_squared() * (xs[3] - xs[2]).norm_squared() * 50.0;
            let cs = cross_squared(&xs);
            let (mv, m1, m2) = mollifier(cs.v, eps);
            let full_m = full * cs.chain(mv, m1, m2);
            let split_m = mollified_derivative(&ids, &key, &s, eps, &x);
            for (a, b) in [(&full, &split), (&full_m, &split_m)] {
                let scale = a.h.iter().flatten().fold(a.g.iter().fold(0.0f64, |m, g| m.max(g.abs())), |m, h| m.max(h.abs()));
                assert!((a.v - b.v).abs() <= 1e-12 * a.v.abs().max(1e-300), "{feat:?}: value {} vs {}", a.v, b.v);
                for i in 0..12 {
                    assert!((a.g[i] - b.g[i]).abs() <= 1e-10 * scale, "{feat:?}: gradient {i}: {} vs {}", a.g[i], b.g[i]);
                    for j in 0..12 {
                        assert!((a.h[i][j] - b.h[i][j]).abs() <= 1e-10 * scale, "{feat:?}: Hessian {i},{j}: {} vs {}", a.h[i][j], b.h[i][j]);
                    }
                }
            }
        }
    }
}
