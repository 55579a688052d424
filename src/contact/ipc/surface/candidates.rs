//! Candidate pairs of surface contact (see the parent module doc): the broad phase at one
//! configuration, with the cache of each pair's reference constants, and the candidates of a
//! collision-detection sweep, filtered from the list kept with a margin (a Verlet list,
//! [`Near`]) and kept for the evaluations along the sweep.

use std::sync::Arc;

use nalgebra::Vector3;
use rayon::prelude::*;

use super::super::broad_phase::{candidates, overlap, primitive_boxes, Pads};
use super::super::potential::FxMap;
use super::super::primitives::squared_distance_value;
use super::{Constants, Kind, Near, Pair, SurfaceContact, MOLLIFIER};

/// The representative of node `a` in the union–find forest `rep` (the nodes joined by ties),
/// compressing the path to it.
pub(super) fn find(rep: &mut [usize], a: usize) -> usize {
    let mut r = a;
    while rep[r] != r {
        r = rep[r];
    }
    let mut b = a;
    while rep[b] != r {
        let next = rep[b];
        rep[b] = r;
        b = next;
    }
    r
}

impl SurfaceContact {
    /// Whether point `i` and triangle `t` may form a pair (not excluded: same quad, a shared
    /// or tied node, or the same part without self contact).
    fn point_ok(&self, i: usize, t: usize) -> bool {
        let p = self.points[i];
        let q = self.tri_quad[t];
        (self.settings.self_contact || self.part_of[p] != self.quad_part[q]) && !self.quad_reps[q].contains(&self.rep[p])
    }

    /// Whether edges `a` and `b` may form a pair (the exclusions of `point_ok`).
    fn edge_ok(&self, a: usize, b: usize) -> bool {
        let (ea, eb) = (self.edges[a], self.edges[b]);
        if !self.settings.self_contact && self.part_of[ea[0]] == self.part_of[eb[0]] {
            return false;
        }
        let (ra, rb) = (ea.map(|n| self.rep[n]), eb.map(|n| self.rep[n]));
        if ra.iter().any(|r| rb.contains(r)) {
            return false;
        }
        let (qa, qb) = (self.edge_quads[a], self.edge_quads[b]);
        !qa.iter().any(|&q| q != usize::MAX && qb.contains(&q))
    }

    /// The four nodes of candidate `key` of `kind`: point and triangle, or edge and edge.
    pub(super) fn nodes(&self, kind: Kind, key: (usize, usize)) -> [usize; 4] {
        match kind {
            Kind::PointTriangle => {
                let t = self.tris[key.1];
                [self.points[key.0], t[0], t[1], t[2]]
            }
            Kind::EdgeEdge => {
                let (a, b) = (self.edges[key.0], self.edges[key.1]);
                [a[0], a[1], b[0], b[1]]
            }
        }
    }

    /// Reference constants of the pair on `nodes`; None for a pair coincident in the
    /// reference (excluded).
    fn constants(&self, kind: Kind, nodes: &[usize; 4]) -> Option<Constants> {
        let xr = nodes.map(|a| self.x_ref[a]);
        let (feat, _) = Self::feature(kind, &xr);
        let dref = squared_distance_value(feat, &xr).sqrt();
        let h = nodes.map(|a| self.half[a]);
        let c = match kind {
            Kind::PointTriangle => h[0] + h[1].max(h[2]).max(h[3]),
            Kind::EdgeEdge => h[0].max(h[1]) + h[2].max(h[3]),
        };
        let cm = c.min(dref);
        if !(cm > 1e-6 * c) {
            return None;
        }
        let dhat = self.settings.distance_factor * cm;
        let eps = match kind {
            Kind::PointTriangle => 0.0,
            Kind::EdgeEdge => MOLLIFIER * (xr[1] - xr[0]).norm_squared() * (xr[3] - xr[2]).norm_squared(),
        };
        Some(Constants { offset: cm - dhat, dhat, eps })
    }

    /// Each primitive's own contact pad: every pair that can be active (closer than c, the
    /// sum of its primitives' half thicknesses) or reach zero gap along a sweep is found.
    pub(super) fn pads(&self) -> Pads<'_> {
        Pads { point: &self.point_pad, tri: &self.tri_pad, edge: &self.edge_pad }
    }

    /// The last sweep's candidates when configuration `x` lies within its slack of the sweep
    /// (see [`Sweep`]), else None.
    pub(super) fn swept_pairs(&self, x: &(dyn Fn(usize) -> Vector3<f64> + Sync)) -> Option<Arc<Vec<Pair>>> {
        let sw = self.sweep.lock().ok()?;
        sw.as_ref()?.pairs_at(&self.points, x, self.slack)
    }

    /// Candidate pairs near configuration(s) `configs`, with their nodes and constants (from
    /// the cache of reference constants; those of pairs new to it are computed and kept).
    pub(super) fn pairs(&self, configs: &[&dyn Fn(usize) -> Vector3<f64>], pads: &Pads) -> Vec<(Kind, (usize, usize), [usize; 4], Constants)> {
        let (pt, ee) = candidates(&self.points, &self.tris, &self.edges, configs, pads, &|i, t| self.point_ok(i, t), &|a, b| self.edge_ok(a, b), &self.trees);
        let all: Vec<(Kind, (usize, usize))> = pt.into_iter().map(|k| (Kind::PointTriangle, k)).chain(ee.into_iter().map(|k| (Kind::EdgeEdge, k))).collect();
        let cached: Vec<Option<Option<Constants>>> = {
            let cache = self.constants.read().unwrap_or_else(|e| e.into_inner());
            all.par_iter().map(|&(kind, key)| cache.get(&(kind, key.0, key.1)).copied()).collect()
        };
        let fresh: Vec<((Kind, usize, usize), Option<Constants>)> = all
            .par_iter()
            .zip(&cached)
            .filter(|(_, c)| c.is_none())
            .map(|(&(kind, key), _)| ((kind, key.0, key.1), self.constants(kind, &self.nodes(kind, key))))
            .collect();
        let computed: FxMap<(Kind, usize, usize), Option<Constants>> = fresh.into_iter().collect();
        let out = all
            .par_iter()
            .zip(&cached)
            .filter_map(|(&(kind, key), c)| {
                let c = match c {
                    Some(c) => *c,
                    None => computed.get(&(kind, key.0, key.1)).copied().flatten(),
                };
                c.map(|c| (kind, key, self.nodes(kind, key), c))
            })
            .collect();
        if !computed.is_empty() {
            self.constants.write().unwrap_or_else(|e| e.into_inner()).extend(computed);
        }
        out
    }

    /// The candidates of the sweep from `x0` to `x1` (each point's box `lo`..`hi` over it)
    /// with the sweep pads: the same pairs, in the same order, as a search of the trees, but
    /// filtered from the kept candidates of [`Near`] while every point stays within their
    /// margin, and searched (with the margin) only when one leaves it.
    pub(super) fn sweep_pairs(&self, x0: &dyn Fn(usize) -> Vector3<f64>, x1: &dyn Fn(usize) -> Vector3<f64>, lo: &[Vector3<f64>], hi: &[Vector3<f64>]) -> Vec<Pair> {
        let (pp, tp, ep) = &self.sweep_pads;
        let pads = Pads { point: pp, tri: tp, edge: ep };
        let configs: [&dyn Fn(usize) -> Vector3<f64>; 2] = [x0, x1];
        let mut near = self.near.lock().unwrap_or_else(|e| e.into_inner());
        // Within the margin (less a relative 10⁻⁹, against round-off at touching boxes).
        let m = Vector3::repeat(self.near_margin * (1.0 - 1e-9));
        let covered = near.as_ref().is_some_and(|n| {
            n.lo.len() == lo.len() && (0..lo.len()).all(|i| (n.lo[i] - m).iter().zip(lo[i].iter()).all(|(a, b)| a <= b) && (n.hi[i] + m).iter().zip(hi[i].iter()).all(|(a, b)| b <= a))
        });
        if !covered {
            let (np, nt, ne) = &self.near_pads;
            let pairs = self.pairs(&configs, &Pads { point: np, tri: nt, edge: ne });
            *near = Some(Near { lo: lo.to_vec(), hi: hi.to_vec(), pairs });
            if let Ok(mut tm) = self.timings.lock() {
                tm.ccd_searches += 1;
            }
        }
        let Some(n) = near.as_ref() else { return Vec::new() };
        // Each primitive's box once, then the broad phase's box test per kept pair.
        let (pb, tb, eb) = primitive_boxes(&self.points, &self.tris, &self.edges, &configs, &pads);
        n.pairs
            .par_iter()
            .filter(|&&(kind, (i, j), _, _)| match kind {
                Kind::PointTriangle => overlap(&pb[i], &tb[j]),
                Kind::EdgeEdge => overlap(&eb[i], &eb[j]),
            })
            .copied()
            .collect()
    }
}
