//! Collision detection of surface contact (see the parent module doc): the largest fraction
//! of a Newton step along which no candidate pair's gap falls below (1 − `CCD_CLOSE`) of its
//! value, by additive CCD (Li, Kaufman & Jiang 2021) over the sweep's candidates.

use std::sync::Arc;
use std::time::Instant;

use nalgebra::Vector3;
use rayon::prelude::*;

use super::super::broad_phase::Sweep;
use super::super::primitives::squared_distance_value;
use super::{positions, Kind, StartGaps, SurfaceContact, CCD_CLOSE};
use crate::contact::ccd::conservative_advancement;
use crate::model::{Model, State};

impl SurfaceContact {
    /// Additive CCD (`NodalForces::max_step`): along the straight move from `from` to `to`, a
    /// pair's distance falls at most by the sum of its two primitives' largest nodal moves
    /// relative to the pair's mean move per unit of the step, so from a gap g it may advance
    /// by (g − g_min)/ℓ, g_min = (1 − CCD_CLOSE) g₀, repeatedly; the smallest fraction over all
    /// candidate pairs of the sweep is the bound. Keeps the sweep's candidates and its gaps
    /// at `from` for the evaluations along it.
    pub(super) fn collision_free_fraction(&self, model: &Model, from: &State, to: &State) -> f64 {
        let t = Instant::now();
        let (p0, p1) = (positions(model, from), positions(model, to));
        let x0 = |a: usize| p0[a];
        let x1 = |a: usize| p1[a];
        let lo: Vec<Vector3<f64>> = self.points.iter().map(|&a| x0(a).inf(&x1(a))).collect();
        let hi: Vec<Vector3<f64>> = self.points.iter().map(|&a| x0(a).sup(&x1(a))).collect();
        let pairs = Arc::new(self.sweep_pairs(&x0, &x1, &lo, &hi));
        // The gaps at `from` the last Newton evaluation found (the same values gap_at(0)
        // computes: the same operations on the same positions).
        let start = self.gaps_at_start(&pairs, from);
        let mut outcome: Vec<(f64, f64)> = Vec::new();
        pairs
            .par_iter()
            .zip(&start)
            .map(|(&(kind, _, nodes, c), &(g0, measured))| {
                let a = nodes.map(x0);
                let d: [Vector3<f64>; 4] = std::array::from_fn(|k| x1(nodes[k]) - a[k]);
                // The distance does not change when all four nodes move alike: bound the rate
                // by the moves relative to their mean (additive CCD, Li, Kaufman & Jiang 2021,
                // §4), so that plies moving together advance in one step.
                let mean = (d[0] + d[1] + d[2] + d[3]) * 0.25;
                let r: [f64; 4] = std::array::from_fn(|k| (d[k] - mean).norm());
                let (m1, m2) = match kind {
                    Kind::PointTriangle => (r[0], r[1].max(r[2]).max(r[3])),
                    Kind::EdgeEdge => (r[0].max(r[1]), r[2].max(r[3])),
                };
                let gap_at = |s: f64| {
                    let xs: [Vector3<f64>; 4] = std::array::from_fn(|k| a[k] + d[k] * s);
                    let (feat, _) = Self::feature(kind, &xs);
                    squared_distance_value(feat, &xs).sqrt() - c.offset
                };
                if m1 + m2 == 0.0 {
                    return (1.0, g0);
                }
                let rate = m1 + m2;
                if !measured && CCD_CLOSE * g0 >= rate * (1.0 + 1e-9) {
                    // The gap is at least g0 (`StartGaps`): advancement takes the whole step
                    // at once, as it would from the gap itself.
                    return (1.0, g0);
                }
                let g0 = if !measured || !d.iter().all(|v| v.iter().all(|c| c.is_finite())) { gap_at(0.0) } else { g0 };
                (conservative_advancement(g0, rate, CCD_CLOSE, 100, |s| Some(gap_at(s))), g0)
            })
            .collect_into_vec(&mut outcome);
        let s = outcome.iter().map(|o| o.0).fold(1.0, f64::min);
        if let Ok(mut st) = self.start.lock() {
            let gaps = outcome.iter().map(|o| o.1).collect();
            *st = Some(StartGaps { pairs: pairs.clone(), gaps, from: self.points.iter().map(|&a| x0(a)).collect() });
        }
        if let Ok(mut sw) = self.sweep.lock() {
            *sw = Some(Sweep::new(lo, hi, pairs));
        }
        if let Ok(mut tm) = self.timings.lock() {
            tm.ccd += t.elapsed().as_secs_f64();
            tm.ccd_calls += 1;
            if s < 1.0 {
                tm.ccd_limited += 1;
            }
        }
        s
    }
}
