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

use super::autodiff::Hd;
use super::primitives::{squared_distance_in, Feature};
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
