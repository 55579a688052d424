//! Broad phase of surface contact: candidate point–triangle and edge–edge pairs whose
//! bounding boxes, each inflated by its primitive's pad, overlap — at one configuration or over the straight
//! sweep between two (for collision detection). A parry3d bounding-volume hierarchy of the
//! triangles (edges) is queried with each point's (edge's) box, so the search costs
//! O(n log n), not O(n²).

use std::sync::{Arc, Mutex};

use nalgebra::Vector3;
use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::math::Vector as PVec;
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy};
use rayon::prelude::*;

fn aabb(points: impl Iterator<Item = Vector3<f64>>, inflate: f64) -> Aabb {
    let mut lo = Vector3::repeat(f64::INFINITY);
    let mut hi = Vector3::repeat(f64::NEG_INFINITY);
    for p in points {
        lo = lo.inf(&p);
        hi = hi.sup(&p);
    }
    Aabb::new(PVec::new(lo.x - inflate, lo.y - inflate, lo.z - inflate), PVec::new(hi.x + inflate, hi.y + inflate, hi.z + inflate))
}

/// How far each primitive's box is inflated: per point, per triangle and per edge (for
/// surface contact, each primitive's largest half thickness, so that two boxes overlap
/// whenever the primitives are closer than the sum, their contact distance).
pub struct Pads<'a> {
    /// Per point.
    pub point: &'a [f64],
    /// Per triangle.
    pub tri: &'a [f64],
    /// Per edge.
    pub edge: &'a [f64],
}

/// Whether the boxes of two primitives — each spanning its nodes' positions in every
/// configuration of `configs`, inflated by its pad — overlap (boundaries included): the test
/// [`candidates`] applies, repeated on one pair.
pub fn boxes_overlap(a: &[usize], pad_a: f64, b: &[usize], pad_b: f64, configs: &[&dyn Fn(usize) -> Vector3<f64>]) -> bool {
    let ba = aabb(configs.iter().flat_map(|x| a.iter().map(move |&n| x(n))), pad_a);
    let bb = aabb(configs.iter().flat_map(|x| b.iter().map(move |&n| x(n))), pad_b);
    (0..3).all(|k| ba.mins[k] <= bb.maxs[k] && bb.mins[k] <= ba.maxs[k])
}

/// Whether two boxes overlap (boundaries included): the test of [`boxes_overlap`] on boxes
/// already built.
pub fn overlap(a: &Aabb, b: &Aabb) -> bool {
    (0..3).all(|k| a.mins[k] <= b.maxs[k] && b.mins[k] <= a.maxs[k])
}

/// The boxes of every point, triangle and edge over `configs`, each inflated by its pad:
/// those [`boxes_overlap`] builds for one pair, built once per primitive.
pub fn primitive_boxes(points: &[usize], tris: &[[usize; 3]], edges: &[[usize; 2]], configs: &[&dyn Fn(usize) -> Vector3<f64>], pads: &Pads) -> (Vec<Aabb>, Vec<Aabb>, Vec<Aabb>) {
    let tri_boxes: Vec<Aabb> = tris.iter().zip(pads.tri).map(|(t, &r)| aabb(configs.iter().flat_map(|x| t.iter().map(move |&n| x(n))), r)).collect();
    let edge_boxes: Vec<Aabb> = edges.iter().zip(pads.edge).map(|(e, &r)| aabb(configs.iter().flat_map(|x| e.iter().map(move |&n| x(n))), r)).collect();
    let point_boxes: Vec<Aabb> = points.iter().zip(pads.point).map(|(&n, &r)| aabb(configs.iter().map(|x| x(n)), r)).collect();
    (point_boxes, tri_boxes, edge_boxes)
}

/// A refit after this many calls is replaced by a fresh build: refitting keeps the tree's
/// topology, whose boxes loosen as the surface deforms far from where it was built.
const REBUILD_AFTER: usize = 64;

/// Bounding-volume hierarchies of the triangles and of the edges, kept between searches: a
/// later search refits them to its boxes (a linear pass over the tree, parry3d's
/// `Bvh::refit_without_opt`) instead of building them anew (a binned SAH build, about as
/// costly as the queries themselves on a sewn sleeve).
#[derive(Default)]
pub struct Trees {
    tri: Option<Bvh>,
    edge: Option<Bvh>,
    refits: usize,
}

/// `tree` fitted to the leaf boxes `boxes`: refitted when it has their number of leaves,
/// else built.
fn fit(tree: &mut Option<Bvh>, boxes: &[Aabb], rebuild: bool) {
    match tree.as_mut() {
        Some(t) if !rebuild && t.leaf_count() as usize == boxes.len() => {
            for (i, b) in boxes.iter().enumerate() {
                let _ = t.update_partially_if_present(*b, i as u32, 0.0);
            }
            t.refit_without_opt();
        }
        _ => *tree = Some(Bvh::from_leaves(BvhBuildStrategy::default(), boxes)),
    }
}

/// Candidate pairs (point index, triangle index) and (edge index a, edge index b), a < b,
/// whose boxes, inflated by their `pads`, overlap: every pair of primitives closer than the
/// sum of their pads is among them. Each primitive's box spans its nodes' positions in every
/// configuration of `configs` (one: a configuration; two: a straight sweep between them,
/// which stays inside the box). `point_ok(p, t)` and `edge_ok(a, b)` filter out excluded
/// pairs. The pairs come sorted (by point, then triangle; by edge a, then b), whatever the
/// trees' shape. `trees` holds the hierarchies between calls (refitted here).
#[allow(clippy::too_many_arguments)]
pub fn candidates(
    points: &[usize],
    tris: &[[usize; 3]],
    edges: &[[usize; 2]],
    configs: &[&dyn Fn(usize) -> Vector3<f64>],
    pads: &Pads,
    point_ok: &(dyn Fn(usize, usize) -> bool + Sync),
    edge_ok: &(dyn Fn(usize, usize) -> bool + Sync),
    trees: &Mutex<Trees>,
) -> (Vec<(usize, usize)>, Vec<(usize, usize)>) {
    let (point_boxes, tri_boxes, edge_boxes) = primitive_boxes(points, tris, edges, configs, pads);
    let mut guard = trees.lock().unwrap_or_else(|e| e.into_inner());
    let t = &mut *guard;
    let rebuild = t.refits >= REBUILD_AFTER;
    t.refits = if rebuild { 0 } else { t.refits + 1 };
    fit(&mut t.tri, &tri_boxes, rebuild);
    fit(&mut t.edge, &edge_boxes, rebuild);
    let (Some(tri_bvh), Some(edge_bvh)) = (t.tri.as_ref(), t.edge.as_ref()) else {
        return (Vec::new(), Vec::new());
    };
    let pt: Vec<(usize, usize)> = (0..points.len())
        .into_par_iter()
        .flat_map_iter(|i| {
            let mut hits: Vec<(usize, usize)> = tri_bvh.intersect_aabb(&point_boxes[i]).map(|t| (i, t as usize)).filter(|&(i, t)| point_ok(i, t)).collect();
            hits.sort_unstable();
            hits.into_iter()
        })
        .collect();
    let ee: Vec<(usize, usize)> = (0..edges.len())
        .into_par_iter()
        .flat_map_iter(|a| {
            let mut hits: Vec<(usize, usize)> = edge_bvh.intersect_aabb(&edge_boxes[a]).map(|b| b as usize).filter(|&b| a < b && edge_ok(a, b)).map(|b| (a, b)).collect();
            hits.sort_unstable();
            hits.into_iter()
        })
        .collect();
    (pt, ee)
}

/// The candidates of a collision-detection sweep, kept for the evaluations along it. Found
/// with pads widened by a slack σ, they hold every pair closer than the sum of its pads at
/// any configuration whose every node lies within σ of its box over the sweep (spanned by the
/// node's positions at the segment's two ends): such an evaluation needs no broad phase of
/// its own.
pub struct Sweep<P> {
    lo: Vec<Vector3<f64>>,
    hi: Vec<Vector3<f64>>,
    pairs: Arc<Vec<P>>,
}

impl<P> Sweep<P> {
    /// The sweep's candidates `pairs`, with each point's box `lo`..`hi` over the sweep.
    pub fn new(lo: Vec<Vector3<f64>>, hi: Vec<Vector3<f64>>, pairs: Arc<Vec<P>>) -> Self {
        Self { lo, hi, pairs }
    }

    /// The candidates when every point `points[i]` lies at `x` within `slack` of its box
    /// (then they include every pair near `x`), else None.
    pub fn pairs_at(&self, points: &[usize], x: &(dyn Fn(usize) -> Vector3<f64> + Sync), slack: f64) -> Option<Arc<Vec<P>>> {
        let s = Vector3::repeat(slack);
        let inside = points.iter().enumerate().all(|(i, &a)| {
            let p = x(a);
            (self.lo[i] - s).iter().zip(p.iter()).all(|(l, v)| l <= v) && (self.hi[i] + s).iter().zip(p.iter()).all(|(h, v)| v <= h)
        });
        inside.then(|| self.pairs.clone())
    }
}
