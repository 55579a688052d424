//! Pair measurement of surface contact (see the parent module doc): each candidate pair's
//! closest feature and gap, its barrier energy κ m b(d, d̂) and, for an evaluation, the
//! active terms with their normals and weights; the lower gap bounds that let a sweep skip
//! pairs which cannot be active, and the gaps a collision-detection sweep starts from.

use std::sync::Arc;

use nalgebra::Vector3;
use rayon::prelude::*;

use super::super::potential::{mollified_derivative, FeatureKey, Scalar};
use super::super::primitives::{edge_edge_feature, mollifier, point_triangle_feature, squared_distance_value, Feature};
use super::{Kind, Pair, SurfaceContact, Term};
use crate::contact::barrier::barrier;
use crate::model::{Model, State};

impl SurfaceContact {
    pub(super) fn feature(kind: Kind, x: &[Vector3<f64>; 4]) -> (Feature, [f64; 4]) {
        match kind {
            Kind::PointTriangle => point_triangle_feature(x),
            Kind::EdgeEdge => edge_edge_feature(x),
        }
    }

    /// The candidate pairs at configuration `x`: the last sweep's when `x` lies within it,
    /// else those of a search of the trees.
    pub(super) fn candidates_at(&self, x: &(dyn Fn(usize) -> Vector3<f64> + Sync)) -> Arc<Vec<Pair>> {
        let swept = self.swept_pairs(x);
        if let Ok(mut tm) = self.timings.lock() {
            if swept.is_some() {
                tm.evaluations_on_sweep += 1;
            } else {
                tm.evaluations_searched += 1;
            }
        }
        swept.unwrap_or_else(|| Arc::new(self.pairs(&[x], &self.pads())))
    }

    /// For candidates `pairs` at `x`: per pair certainly inactive by the bound of
    /// [`StartGaps`], that lower bound of its gap; NaN for the others (None when `pairs` are
    /// not those of the last sweep).
    pub(super) fn inactive_by_bound(&self, pairs: &Arc<Vec<Pair>>, x: &(dyn Fn(usize) -> Vector3<f64> + Sync)) -> Option<Vec<f64>> {
        let guard = self.start.lock().ok()?;
        let st = guard.as_ref()?;
        if !Arc::ptr_eq(&st.pairs, pairs) || st.gaps.len() != pairs.len() || st.from.len() != self.points.len() {
            return None;
        }
        let moves: Vec<f64> = self.points.iter().zip(&st.from).map(|(&a, p)| (x(a) - p).norm()).collect();
        let mv = |a: usize| moves[self.point_index[a]];
        let mut out = Vec::new();
        pairs
            .par_iter()
            .zip(&st.gaps)
            .map(|(&(kind, _, nodes, c), &g0)| {
                let m = nodes.map(mv);
                let delta = match kind {
                    Kind::PointTriangle => m[0] + m[1].max(m[2]).max(m[3]),
                    Kind::EdgeEdge => m[0].max(m[1]) + m[2].max(m[3]),
                };
                let bound = g0 - delta * (1.0 + 1e-12) - self.bound_margin;
                if bound > c.dhat * 1.05 {
                    bound
                } else {
                    f64::NAN
                }
            })
            .collect_into_vec(&mut out);
        if let Ok(mut tm) = self.timings.lock() {
            tm.pairs_measured += pairs.len();
            tm.pairs_bounded += out.iter().filter(|b| !b.is_nan()).count();
        }
        Some(out)
    }

    /// The active pairs at `state` (gap below d̂): gap, energy κ_p m_p b(d, d̂_p), normal force
    /// and closest-point weights, with the energy's first two derivatives in the distance of
    /// the pair's closest feature (summed per feature and differentiated in the nodes by
    /// [`potential::derivative`](super::potential::derivative)); a pair inside the edge–edge
    /// mollifier's range is differentiated on its own in all four nodes when `derivatives`.
    /// A pair at or through zero gap has infinite energy.
    pub(super) fn evaluate(&self, model: &Model, state: &State, derivatives: bool) -> Vec<Term> {
        let x = |a: usize| model.x0[a] + state.u[a];
        let pairs = self.candidates_at(&x);
        let skip = self.inactive_by_bound(&pairs, &x);
        self.evaluate_pairs(&pairs, &x, derivatives, skip.as_deref(), None)
    }

    /// [`SurfaceContact::evaluate`] over the candidates `pairs` at positions `x`; with
    /// `gaps`, also every candidate's gap d = dist − c_p (active or not), in the order of
    /// `pairs`.
    pub(super) fn evaluate_pairs<X: Fn(usize) -> Vector3<f64> + Sync>(&self, pairs: &[Pair], x: &X, derivatives: bool, skip: Option<&[f64]>, gaps: Option<&mut Vec<(f64, bool)>>) -> Vec<Term> {
        let term = |i: usize, gap_out: Option<&mut (f64, bool)>| {
            // Certainly inactive (`StartGaps`): not measured; its lower bound is kept.
            if let Some(bound) = skip.map(|s| s[i]).filter(|b| !b.is_nan()) {
                if let Some(g) = gap_out {
                    *g = (bound, false);
                }
                return None;
            }
            let (kind, key, nodes, c) = pairs[i];
            let xs = nodes.map(x);
            let (feat, weights) = Self::feature(kind, &xs);
            let dist = squared_distance_value(feat, &xs).sqrt();
            let gap = dist - c.offset;
            if let Some(g) = gap_out {
                *g = (gap, true);
            }
            if gap >= c.dhat {
                return None;
            }
            let kap = nodes.iter().map(|&a| self.kappa[a]).sum::<f64>() / 4.0;
            let r: Vector3<f64> = (0..4).map(|k| xs[k] * weights[k]).sum();
            let normal = if dist > 0.0 { r / dist } else { Vector3::zeros() };
            let thin = 2.0 * nodes.iter().map(|&a| self.half[a]).fold(f64::INFINITY, f64::min);
            let feature = FeatureKey::of(feat, &nodes);
            let inf = Scalar { e: f64::INFINITY, e1: 0.0, e2: 0.0 };
            let mut term = Term { kind, key, nodes, feature, scalar: inf, mollified: None, parallel: false, gap, dhat: c.dhat, eps: c.eps, thin, energy: f64::INFINITY, force: f64::INFINITY, normal, weights };
            if gap <= 0.0 {
                return Some(term);
            }
            let (b, b1, b2) = barrier(gap, c.dhat);
            // κ b(√q − c_p) (× m(|e_a × e_b|²) for nearly parallel edges): its exact
            // gradient and Hessian follow by second-order automatic differentiation of the
            // squared distance q. The Hessian is not projected: a pair pressed onto a
            // vertex or an edge of the other surface has a negative tangential stiffness
            // κ b′ ∇²dist (the force turns as the point slides), and Newton without it
            // stalls where plies slide on each other (the NBC sleeve in a static step
            // stopped at a residual of 10⁻⁶ with a projected or Gauss–Newton tangent; it
            // converges with the exact one).
            let mollified = parallel_mollifier(kind, &xs, c.eps);
            term.parallel = mollified.is_some();
            if mollified.is_some() && derivatives {
                let f = Scalar { e: kap * b, e1: kap * b1, e2: kap * b2 };
                term.mollified = Some(Box::new(mollified_derivative(&nodes, &feature, &f, c.eps, x)));
            }
            let m = mollified.unwrap_or(1.0);
            term.scalar = Scalar { e: kap * b * m, e1: kap * b1, e2: kap * b2 };
            term.energy = kap * b * m;
            term.force = -kap * m * b1;
            Some(term)
        };
        match gaps {
            Some(g) => {
                g.clear();
                g.resize(pairs.len(), (f64::NAN, false));
                g.par_iter_mut().enumerate().filter_map(|(i, g)| term(i, Some(g))).collect()
            }
            None => (0..pairs.len()).into_par_iter().filter_map(|i| term(i, None)).collect(),
        }
    }

    /// The gap of every pair of `pairs` at `from` where the last Newton evaluation
    /// (`add_coupled`) found it — at that very state, bit for bit, among its candidates —
    /// with whether it was measured (else a lower bound, `StartGaps`); (NaN, false) where
    /// not found. Both candidate lists are in the broad phase's order (point–triangle pairs
    /// by point and triangle, then edge–edge pairs by edges), so one merge finds them.
    pub(super) fn gaps_at_start(&self, pairs: &[Pair], from: &State) -> Vec<(f64, bool)> {
        let mut out = vec![(f64::NAN, false); pairs.len()];
        let Some((known, gaps)) = self.start_gaps.as_ref() else { return out };
        let same = |a: &Vector3<f64>, b: &Vector3<f64>| a.iter().zip(b.iter()).all(|(p, q)| p.to_bits() == q.to_bits());
        if self.last_u.len() != self.points.len() || !self.points.iter().zip(&self.last_u).all(|(&a, u)| same(&from.u[a], u)) {
            return out;
        }
        let order = |p: &Pair| (p.0 == Kind::EdgeEdge, p.1);
        let mut j = 0;
        for (p, g) in pairs.iter().zip(out.iter_mut()) {
            let k = order(p);
            while j < known.len() && order(&known[j]) < k {
                j += 1;
            }
            if j < known.len() && order(&known[j]) == k {
                *g = gaps[j];
            }
        }
        out
    }
}

/// The edge–edge mollifier m(|e_a × e_b|²) of a nearly parallel edge pair (IPC, Li et al.
/// 2020 §4.4): Some(m) when `kind` is edge–edge and |e_a × e_b|² < `eps`, else None (m = 1).
#[inline]
pub(super) fn parallel_mollifier(kind: Kind, xs: &[Vector3<f64>; 4], eps: f64) -> Option<f64> {
    if kind != Kind::EdgeEdge {
        return None;
    }
    let (u, v) = (xs[1] - xs[0], xs[3] - xs[2]);
    let cs2 = u.cross(&v).norm_squared();
    (cs2 < eps).then(|| mollifier(cs2, eps).0)
}
