//! Lagged, smoothed Coulomb friction of surface contact pairs (IPC §5, Li et al. 2020): the
//! committed state of a pair (anchor, closest-point weights, normal and normal force of the
//! last converged state) and its friction potential.

use std::collections::HashMap;

use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;

use super::surface::Kind;

/// Committed friction state of a pair.
#[derive(Clone, Debug)]
pub(super) struct Friction {
    pub(super) nodes: [usize; 4],
    pub(super) weights: [f64; 4],
    pub(super) normal: Vector3<f64>,
    pub(super) force: f64,
    pub(super) anchor: Vector3<f64>,
    pub(super) delta: f64,
    pub(super) sliding: bool,
    pub(super) slip: f64,
}

/// Friction of one committed pair at a configuration: a potential of the pair's weighted
/// point r = Σ_k w_k x_k, whose gradient in x_k is w_k g and Hessian block in (x_i, x_j) is
/// w_i w_j K.
pub(super) struct FrictionTerm {
    pub(super) key: (Kind, usize, usize),
    pub(super) nodes: [usize; 4],
    pub(super) weights: [f64; 4],
    pub(super) energy: f64,
    /// ∂D/∂r.
    pub(super) g: Vector3<f64>,
    /// ∂²D/∂r², positive semi-definite (when asked for).
    pub(super) k: Option<Matrix3<f64>>,
    /// Friction force on slot 0 (the point or the first edge).
    pub(super) force: Vector3<f64>,
}

/// The committed pairs of `map` that carry friction (normal force λ̄ > 0), in the map's
/// order: the list [`terms`] runs over, kept from one commit to the next (collected from the
/// map in every evaluation, serially, it cost 0.4 s of the NBC sleeve on the arm).
pub(super) fn committed<S: std::hash::BuildHasher>(map: &HashMap<(Kind, usize, usize), Friction, S>) -> Vec<((Kind, usize, usize), Friction)> {
    map.iter().filter(|(_, h)| h.force > 0.0).map(|(k, h)| (*k, h.clone())).collect()
}

/// The tangent projector P = I − n̄n̄ᵀ of committed pair `h`, its slip s = P (r − r̂) at `x`
/// and |s|.
#[inline]
fn slip(h: &Friction, x: &(dyn Fn(usize) -> Vector3<f64> + Sync)) -> (Matrix3<f64>, Vector3<f64>, f64) {
    let r: Vector3<f64> = (0..4).map(|k| x(h.nodes[k]) * h.weights[k]).sum();
    let p = Matrix3::identity() - h.normal * h.normal.transpose();
    let s = p * (r - h.anchor);
    (p, s, s.norm())
}

/// D = μλ̄ δ ln cosh(|s|/δ) at |s| = `sn` (written with ln(1 + e^(−2a)) for large a), with
/// `cap` = μλ̄.
#[inline]
fn potential(cap: f64, delta: f64, sn: f64) -> f64 {
    let arg = sn / delta;
    cap * delta * (arg + (-2.0 * arg).exp().ln_1p() - std::f64::consts::LN_2)
}

/// The friction potentials of the `committed` pairs at `x` alone, in their order: the
/// energies of [`terms`], bit for bit, for a trial state judged by its potential.
pub(super) fn energies(committed: &[((Kind, usize, usize), Friction)], mu: f64, x: &(dyn Fn(usize) -> Vector3<f64> + Sync)) -> Vec<f64> {
    if mu == 0.0 {
        return Vec::new();
    }
    let mut out = Vec::new();
    committed
        .par_iter()
        .map(|(_, h)| {
            let (_, _, sn) = slip(h, x);
            potential(mu * h.force, h.delta, sn)
        })
        .collect_into_vec(&mut out);
    out
}

/// Friction potentials D = μλ̄ δ ln cosh(|s|/δ) of the `committed` pairs at `x`, s the
/// slip of the pair's weighted points from their anchor in the lagged tangent plane, with
/// gradient and (when `hessian`) the exact Hessian, positive semi-definite.
pub(super) fn terms(committed: &[((Kind, usize, usize), Friction)], mu: f64, x: &(dyn Fn(usize) -> Vector3<f64> + Sync), hessian: bool) -> Vec<FrictionTerm> {
    if mu == 0.0 {
        return Vec::new();
    }
    committed
        .par_iter()
        .map(|(key, h)| {
            let key = *key;
            let (p, s, sn) = slip(h, x);
            let cap = mu * h.force;
            let arg = sn / h.delta;
            let energy = potential(cap, h.delta, sn);
            let (g3, k3) = if sn > 0.0 {
                let sh = s / sn;
                let th = arg.tanh();
                let along = cap / h.delta * (1.0 - th * th);
                let across = cap * th / sn;
                (sh * (cap * th), sh * sh.transpose() * (along - across) + p * across)
            } else {
                (Vector3::zeros(), p * (cap / h.delta))
            };
            FrictionTerm { key, nodes: h.nodes, weights: h.weights, energy, g: g3, k: hessian.then_some(k3), force: -g3 }
        })
        .collect()
}
