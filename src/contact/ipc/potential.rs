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

use super::distance;
use super::primitives::{mollifier, Feature};

/// Multiply-rotate hash for small integer keys (the Fx hash of the Rust compiler): node
/// numbers need no protection against collisions chosen by an adversary.
#[derive(Default, Clone, Copy)]
pub(crate) struct FxHasher(u64);

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
pub(crate) type FxMap<K, V> = HashMap<K, V, BuildHasherDefault<FxHasher>>;

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

/// Gradient and Hessian of a potential in the coordinates of up to four nodes: `g[k]` the
/// gradient in node `nodes[k]` and `h[i][j]` (i ≤ j) the Hessian's block of nodes i and j,
/// for k, i, j < `m` (the rest unused).
#[derive(Clone, Debug)]
pub(super) struct Derivative {
    pub(super) nodes: [usize; 4],
    pub(super) m: usize,
    pub(super) g: [Vector3<f64>; 4],
    pub(super) h: [[Matrix3<f64>; 4]; 4],
}

impl Derivative {
    /// All zero, on no nodes (m = 0).
    pub(super) fn zero() -> Self {
        Self { nodes: [0; 4], m: 0, g: [Vector3::zeros(); 4], h: [[Matrix3::zeros(); 4]; 4] }
    }

    /// The Hessian projected onto the positive semi-definite cone (eigenvalues clamped at 0,
    /// Teran et al. 2005; IPC projects every pair's Hessian so, Li et al. 2020 §4.1): the
    /// 3m × 3m matrix of the blocks decomposed with nalgebra's symmetric eigensolver. The
    /// gradient is unchanged.
    pub(super) fn project_hessian(&mut self) {
        let m = self.m;
        let dense = nalgebra::DMatrix::from_fn(3 * m, 3 * m, |r, c| self.block(r / 3, c / 3)[(r % 3, c % 3)]);
        if dense.clone().cholesky().is_some() {
            return;
        }
        let eig = nalgebra::SymmetricEigen::new(dense);
        let clamped = eig.eigenvalues.map(|l| l.max(0.0));
        let psd = &eig.eigenvectors * nalgebra::DMatrix::from_diagonal(&clamped) * eig.eigenvectors.transpose();
        for i in 0..m {
            for j in i..m {
                self.h[i][j] = Matrix3::from_fn(|r, c| psd[(3 * i + r, 3 * j + c)]);
            }
        }
    }

    /// The block (i, j) for any order of i, j.
    pub(super) fn block(&self, i: usize, j: usize) -> Matrix3<f64> {
        if i <= j {
            self.h[i][j]
        } else {
            self.h[j][i].transpose()
        }
    }
}

/// Bits per node number in a packed feature key ([`FeatureKey::packed`]).
const PACKED_NODE_BITS: u32 = 23;

impl FeatureKey {
    /// The key as the high 94 bits of a u128 above a free low 32 (its variant in 2 bits, then
    /// its nodes, 23 bits each, the unused ones 0): packed keys compare as the keys do (the
    /// derived order: variant, then the nodes in order). None when a node number needs more
    /// than 23 bits.
    fn packed(&self) -> Option<u128> {
        let (tag, nodes): (u128, [usize; 4]) = match *self {
            Self::PointPoint([a, b]) => (0, [a, b, 0, 0]),
            Self::PointEdge(p, [a, b]) => (1, [p, a, b, 0]),
            Self::PointPlane(p, [a, b, c]) => (2, [p, a, b, c]),
            Self::LineLine([a, b], [c, d]) => (3, [a, b, c, d]),
        };
        let mut k = tag;
        for a in nodes {
            if a >> PACKED_NODE_BITS != 0 {
                return None;
            }
            k = (k << PACKED_NODE_BITS) | a as u128;
        }
        Some(k << 32)
    }
}

/// Σ_p e_p(dist_f) for the pairs of one feature: per distinct key, the summed scalars, in
/// the order of the keys. The pairs are sorted by key with `sort_unstable` and each key's
/// scalars summed in the sorted order; the sort runs on the packed keys, each with its pair's
/// index in the low 32 bits and compared without it ([`FeatureKey::packed`]): the same
/// comparisons of the same keys, so the same permutation and the same sums, bit for bit, as
/// sorting the (key, scalar) pairs themselves (a fifth of the bytes to move; that sort cost
/// 1.15 s of the NBC sleeve on the arm, serial). Without packed keys (a node number beyond
/// 23 bits, or 2³² pairs), the pairs themselves.
pub(super) fn group(pairs: impl Iterator<Item = (FeatureKey, Scalar)>) -> Vec<(FeatureKey, Scalar)> {
    let all: Vec<(FeatureKey, Scalar)> = pairs.collect();
    let packed: Option<Vec<u128>> =
        if all.len() <= u32::MAX as usize { all.iter().enumerate().map(|(i, (k, _))| k.packed().map(|p| p | i as u128)).collect() } else { None };
    let mut out: Vec<(FeatureKey, Scalar)> = Vec::with_capacity(all.len());
    let mut push = |k: FeatureKey, s: Scalar| match out.last_mut() {
        Some((last, acc)) if *last == k => {
            acc.e += s.e;
            acc.e1 += s.e1;
            acc.e2 += s.e2;
        }
        _ => out.push((k, s)),
    };
    match packed {
        Some(mut order) => {
            order.sort_unstable_by_key(|&p| p >> 32);
            for p in order {
                let (k, s) = all[(p as u32) as usize];
                push(k, s);
            }
        }
        None => {
            let mut all = all;
            all.sort_unstable_by(|a, b| a.0.cmp(&b.0));
            for (k, s) in all {
                push(k, s);
            }
        }
    }
    out
}

/// Gradient and Hessian of E(dist_f(x)) = Σ_p e_p(dist_f) (see the module comment) in the
/// feature's own nodes, at positions `x`, by the closed forms of [`distance`].
pub(super) fn derivative(key: &FeatureKey, s: &Scalar, x: &(dyn Fn(usize) -> Vector3<f64> + Sync)) -> Derivative {
    let mut d = Derivative::zero();
    derivative_into(key, s, x, &mut d);
    d
}

/// [`derivative`] written into `out` in place (a reused buffer: its gradient and Hessian
/// entries beyond the feature's m nodes are left as they were, and nothing reads them).
pub(super) fn derivative_into(key: &FeatureKey, s: &Scalar, x: &(dyn Fn(usize) -> Vector3<f64> + Sync), out: &mut Derivative) {
    let (nodes, _, f) = key.nodes();
    let xs = nodes.map(x);
    // E as a function of the squared distance q = dist²: dE/dq = E′/(2 dist),
    // d²E/dq² = E″/(4 dist²) − E′/(4 dist³).
    let chain = |q: f64| {
        let dist = q.sqrt();
        let (dd, ddd) = (0.5 / dist, -0.25 / (dist * dist * dist));
        (s.e1 * dd, s.e2 * dd * dd + s.e1 * ddd)
    };
    out.nodes = nodes;
    out.m = distance::chain_into(f, &xs, chain, &mut out.g, &mut out.h);
}

/// `d` in the four nodes `nodes` (the feature's nodes are among them): gradient per node
/// and all sixteen Hessian blocks.
fn in_pair_nodes(d: &Derivative, nodes: &[usize; 4]) -> ([Vector3<f64>; 4], [[Matrix3<f64>; 4]; 4]) {
    let slot: [usize; 4] = std::array::from_fn(|k| nodes.iter().position(|&b| b == d.nodes[k]).unwrap_or(0));
    let mut g = [Vector3::zeros(); 4];
    let mut h = [[Matrix3::zeros(); 4]; 4];
    for i in 0..d.m {
        g[slot[i]] += d.g[i];
        for j in 0..d.m {
            h[slot[i]][slot[j]] += d.block(i, j);
        }
    }
    (g, h)
}

/// Gradient and Hessian, in the four nodes (a₀, a₁, b₀, b₁) of a nearly parallel edge–edge
/// pair, of E = F(dist_f) m(|u × v|²) (IPC supplement eq. 17: the mollifier m of threshold
/// `eps`, u = a₁ − a₀, v = b₁ − b₀), `s` holding F, F′, F″ in the distance of the pair's
/// closest feature `key`. The distance is differentiated in the feature's own nodes and
/// |u × v|² in u and v ([`distance::cross_squared`]), then both are spread to the four nodes
/// (∂/∂a₀ = −∂/∂u, ∂/∂a₁ = ∂/∂u, likewise for v) and multiplied by the product rule
/// ∇²(F m) = m ∇²F + F ∇²m + ∇F ∇mᵀ + ∇m ∇Fᵀ.
pub(super) fn mollified_derivative(nodes: &[usize; 4], key: &FeatureKey, s: &Scalar, eps: f64, x: &(dyn Fn(usize) -> Vector3<f64> + Sync)) -> Derivative {
    let (gf, hf) = in_pair_nodes(&derivative(key, s, x), nodes);
    let xs = nodes.map(x);
    let (cs, gc, hc) = distance::cross_squared(&(xs[1] - xs[0]), &(xs[3] - xs[2]));
    let (mv, m1, m2) = mollifier(cs, eps);
    // Slot k moves u (k = 0, 1) or v (k = 2, 3) with sign −1 (k even) or +1 (k odd).
    let var = |k: usize| k / 2;
    let sign = |k: usize| if k % 2 == 0 { -1.0 } else { 1.0 };
    let gm: [Vector3<f64>; 4] = std::array::from_fn(|k| gc[var(k)] * (sign(k) * m1));
    let hc_of = |a: usize, b: usize| match (a, b) {
        (0, 0) => hc[0],
        (0, _) => hc[1],
        (_, 0) => hc[1].transpose(),
        _ => hc[2],
    };
    let mut out = Derivative { nodes: *nodes, m: 4, g: [Vector3::zeros(); 4], h: [[Matrix3::zeros(); 4]; 4] };
    for i in 0..4 {
        out.g[i] = gf[i] * mv + gm[i] * s.e;
        for j in i..4 {
            let hm = gc[var(i)] * gc[var(j)].transpose() * (sign(i) * sign(j) * m2) + hc_of(var(i), var(j)) * (sign(i) * sign(j) * m1);
            out.h[i][j] = hf[i][j] * mv + hm * s.e + gf[i] * gm[j].transpose() + gm[i] * gf[j].transpose();
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::primitives::{cross_squared, edge_edge_feature, point_triangle_feature, squared_distance};
    use super::*;

    /// Gradient and Hessian blocks of four nodes as the 12-coordinate arrays of `Hd<12>`.
    fn dense(g: &[Vector3<f64>; 4], h: &[[Matrix3<f64>; 4]; 4]) -> ([f64; 12], [[f64; 12]; 12]) {
        let gd = std::array::from_fn(|i| g[i / 3][i % 3]);
        let hd = std::array::from_fn(|i| std::array::from_fn(|j| h[i / 3][j / 3][(i % 3, j % 3)]));
        (gd, hd)
    }

    /// The energy of pairs summed per feature, differentiated in the features' own nodes by
    /// the closed forms of `distance.rs`, and the mollified edge–edge product have the
    /// derivatives of the same energies formed by automatic differentiation in all twelve
    /// coordinates of each pair (the formulation before them), to 10⁻¹⁰ of the largest entry.
    #[test]
    fn per_feature_derivatives_match_the_twelve_coordinate_forms() {
        let v = Vector3::new;
        let ids = [7usize, 3, 12, 5];
        // Nearly parallel edges (mollified) whose closest features are an endpoint and an
        // edge, crossing edges (line–line), and a point over a triangle's face, beyond an
        // edge and beyond a vertex (point–triangle).
        let tri = [v(0.0, 0.0, 0.0), v(0.02, 0.0, 0.001), v(0.004, 0.018, -0.001)];
        for (edges, xs) in [
            (true, [v(0.0, 0.0, 0.0), v(1.0, 0.02, 0.0), v(0.3, 0.0, 0.05), v(1.4, 0.0, 0.051)]),
            (true, [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.5, -0.5, 0.3), v(0.45, 0.5, 0.31)]),
            (false, [v(0.008, 0.006, 0.0012), tri[0], tri[1], tri[2]]),
            (false, [v(0.01, -0.004, 0.0008), tri[0], tri[1], tri[2]]),
            (false, [v(-0.002, -0.001, 0.0011), tri[0], tri[1], tri[2]]),
        ] {
            let x = |a: usize| xs[ids.iter().position(|&b| b == a).unwrap_or(0)];
            let (feat, _) = if edges { edge_edge_feature(&xs) } else { point_triangle_feature(&xs) };
            let key = FeatureKey::of(feat, &ids);
            let q = squared_distance(feat, &xs);
            let dist = q.v.sqrt();
            let s = Scalar { e: 0.3 * dist * dist, e1: 0.6 * dist + 0.1, e2: 0.6 - 0.2 * dist };
            let (dd, ddd) = (0.5 / dist, -0.25 / (dist * dist * dist));
            let full = q.chain(s.e, s.e1 * dd, s.e2 * dd * dd + s.e1 * ddd);
            let (g, h) = in_pair_nodes(&derivative(&key, &s, &x), &ids);
            let mut cases = vec![(full, dense(&g, &h))];
            if edges {
                let eps = 1e-3 * (xs[1] - xs[0]).norm_squared() * (xs[3] - xs[2]).norm_squared() * 50.0;
                let cs = cross_squared(&xs);
                let (mv, m1, m2) = mollifier(cs.v, eps);
                let full_m = full * cs.chain(mv, m1, m2);
                let d = mollified_derivative(&ids, &key, &s, eps, &x);
                let hm: [[Matrix3<f64>; 4]; 4] = std::array::from_fn(|i| std::array::from_fn(|j| d.block(i, j)));
                cases.push((full_m, dense(&d.g, &hm)));
            }
            for (a, (bg, bh)) in cases {
                let scale = a.h.iter().flatten().fold(a.g.iter().fold(0.0f64, |m, g| m.max(g.abs())), |m, h| m.max(h.abs()));
                for i in 0..12 {
                    assert!((a.g[i] - bg[i]).abs() <= 1e-10 * scale, "{feat:?}: gradient {i}: {} vs {}", a.g[i], bg[i]);
                    for j in 0..12 {
                        assert!((a.h[i][j] - bh[i][j]).abs() <= 1e-10 * scale, "{feat:?}: Hessian {i},{j}: {} vs {}", a.h[i][j], bh[i][j]);
                    }
                }
            }
        }
    }

    /// The projected Hessian of a derivative is positive semi-definite, equals V max(Λ, 0) Vᵀ
    /// of the exact one, keeps an already positive definite Hessian bit for bit, and leaves
    /// the gradient alone.
    #[test]
    fn projected_hessian_is_the_psd_part() {
        let mut d = Derivative::zero();
        d.m = 3;
        d.nodes = [4, 7, 9, 0];
        // A symmetric 9×9 matrix with negative eigenvalues: A = B + Bᵀ − 3 I.
        let b = nalgebra::DMatrix::from_fn(9, 9, |r, c| ((r * 7 + c * 3) % 5) as f64 * 0.3 - 0.4);
        let a = &b + b.transpose() - nalgebra::DMatrix::identity(9, 9) * 3.0;
        for i in 0..3 {
            for j in i..3 {
                d.h[i][j] = Matrix3::from_fn(|r, c| a[(3 * i + r, 3 * j + c)]);
            }
            d.g[i] = Vector3::new(i as f64, 1.0, -2.0);
        }
        let eig = nalgebra::SymmetricEigen::new(a.clone());
        assert!(eig.eigenvalues.min() < -1.0, "the test matrix is indefinite");
        let expected = &eig.eigenvectors * nalgebra::DMatrix::from_diagonal(&eig.eigenvalues.map(|l| l.max(0.0))) * eig.eigenvectors.transpose();
        let g = d.g;
        d.project_hessian();
        let got = nalgebra::DMatrix::from_fn(9, 9, |r, c| d.block(r / 3, c / 3)[(r % 3, c % 3)]);
        assert!((&got - &expected).amax() < 1e-12 * expected.amax(), "{got} vs {expected}");
        assert!(nalgebra::SymmetricEigen::new(got).eigenvalues.min() > -1e-12);
        assert_eq!(d.g, g);
        // Positive definite: unchanged.
        let spd = &a * a.transpose() + nalgebra::DMatrix::identity(9, 9);
        for i in 0..3 {
            for j in i..3 {
                d.h[i][j] = Matrix3::from_fn(|r, c| spd[(3 * i + r, 3 * j + c)]);
            }
        }
        let before = d.h;
        d.project_hessian();
        assert_eq!(d.h, before);
    }

    /// The grouping by packed keys gives the keys and sums, bit for bit, of sorting the
    /// (key, scalar) pairs themselves with `sort_unstable` (the permutation of equal keys
    /// decides the order of each sum): stacked-ply-like lists with many repeats of few keys.
    #[test]
    fn grouping_by_packed_keys_matches_sorting_the_pairs() {
        let reference = |all: &[(FeatureKey, Scalar)]| {
            let mut all = all.to_vec();
            all.sort_unstable_by(|a, b| a.0.cmp(&b.0));
            let mut out: Vec<(FeatureKey, Scalar)> = Vec::new();
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
        };
        let mut seed = 12345u64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        for (len, nodes) in [(0usize, 10usize), (1, 10), (20, 5), (100, 4), (3000, 8), (20000, 12), (20000, 1500), (50000, 9_000_000)] {
            let all: Vec<(FeatureKey, Scalar)> = (0..len)
                .map(|_| {
                    let n: [usize; 4] = std::array::from_fn(|_| (next() % nodes as u64) as usize);
                    let key = match next() % 4 {
                        0 => FeatureKey::PointPoint(sorted([n[0], n[1]])),
                        1 => FeatureKey::PointEdge(n[0], sorted([n[1], n[2]])),
                        2 => FeatureKey::PointPlane(n[0], sorted([n[1], n[2], n[3]])),
                        _ => FeatureKey::LineLine(sorted([n[0], n[1]]), sorted([n[2], n[3]])),
                    };
                    let v = |r: u64| (r % 1_000_000) as f64 * 1.37e-3 - 600.0;
                    (key, Scalar { e: v(next()), e1: v(next()), e2: v(next()) })
                })
                .collect();
            let (a, b) = (group(all.iter().copied()), reference(&all));
            assert_eq!(a.len(), b.len());
            for ((ka, sa), (kb, sb)) in a.iter().zip(&b) {
                assert_eq!(ka, kb);
                assert_eq!([sa.e, sa.e1, sa.e2].map(f64::to_bits), [sb.e, sb.e1, sb.e2].map(f64::to_bits), "{len} pairs: {ka:?}");
            }
        }
    }
}
