//! An independent check for intersecting shells, written apart from the contact code that
//! prevents them: every triangle of the participating parts' deformed mid-surfaces (each quad
//! split along its 1–3 diagonal) is thickened into a prism ± s h/2 along its normal, and every
//! pair of prisms that share no node (nor nodes joined by a tie: seams, stitch lines, ply
//! links) and lie in different quads is tested for overlap with parry3d's GJK intersection
//! test on their convex hulls. A parry3d BVH of the prisms' boxes keeps it near linear.

use nalgebra::Vector3;
use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::math::{Pose, Vector as PVec};
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy};
use parry3d_f64::shape::ConvexPolyhedron;
use rayon::prelude::*;

use crate::element::NODE_DOFS;
use crate::model::{Model, State};

/// An overlap found by [`intersecting_prisms`]: the two triangles' nodes and their parts.
#[derive(Clone, Debug)]
pub struct Overlap {
    pub first: [usize; 3],
    pub second: [usize; 3],
    pub parts: (String, String),
}

/// Overlapping pairs of thickened triangles of `parts` (model part indices) at `state`; the
/// prisms are ± `scale` × h/2 thick (h the element's section thickness).
pub fn intersecting_prisms(model: &Model, state: &State, parts: &[usize], scale: f64) -> Vec<Overlap> {
    let n = model.n_nodes();
    // Nodes joined by ties count as one.
    let mut root: Vec<usize> = (0..n).collect();
    fn up(root: &mut [usize], mut a: usize) -> usize {
        while root[a] != a {
            root[a] = root[root[a]];
            a = root[a];
        }
        a
    }
    for t in &model.dofs.ties {
        let s = t.slave / NODE_DOFS;
        for m in t.masters.iter().map(|&(m, _)| m / NODE_DOFS).chain(t.links.iter().map(|&(m, _)| m)) {
            let (a, b) = (up(&mut root, s), up(&mut root, m));
            root[a] = b;
        }
    }
    let group: Vec<usize> = (0..n).map(|a| up(&mut root, a)).collect();
    let x = |a: usize| model.x0[a] + state.u[a];
    // (nodes, quad id, part, prism corners)
    let mut prisms: Vec<([usize; 3], usize, usize, [Vector3<f64>; 6])> = Vec::new();
    for &p in parts {
        let info = &model.parts[p];
        for e in info.first_element..info.first_element + info.n_elements {
            let def = &model.elements[e];
            let half = 0.5 * scale * model.sections[def.section].thickness;
            let nd = def.nodes;
            for t in [[nd[0], nd[1], nd[2]], [nd[0], nd[2], nd[3]]] {
                let v = t.map(x);
                let nrm = (v[1] - v[0]).cross(&(v[2] - v[0]));
                let nn = nrm.norm();
                if nn == 0.0 {
                    continue;
                }
                let off = nrm * (half / nn);
                prisms.push((t, e, p, [v[0] + off, v[1] + off, v[2] + off, v[0] - off, v[1] - off, v[2] - off]));
            }
        }
    }
    let boxes: Vec<Aabb> = prisms
        .iter()
        .map(|(_, _, _, c)| {
            let lo = c.iter().fold(Vector3::repeat(f64::INFINITY), |m, p| m.inf(p));
            let hi = c.iter().fold(Vector3::repeat(f64::NEG_INFINITY), |m, p| m.sup(p));
            Aabb::new(PVec::new(lo.x, lo.y, lo.z), PVec::new(hi.x, hi.y, hi.z))
        })
        .collect();
    let bvh = Bvh::from_leaves(BvhBuildStrategy::default(), &boxes);
    let hull = |c: &[Vector3<f64>; 6]| ConvexPolyhedron::from_convex_hull(&c.map(|p| PVec::new(p.x, p.y, p.z)));
    (0..prisms.len())
        .into_par_iter()
        .flat_map_iter(|i| {
            let (ti, qi, pi, ci) = &prisms[i];
            let gi = ti.map(|a| group[a]);
            let mut found = Vec::new();
            let Some(hi) = hull(ci) else { return found.into_iter() };
            for j in bvh.intersect_aabb(&boxes[i]).map(|j| j as usize).filter(|&j| j > i) {
                let (tj, qj, pj, cj) = &prisms[j];
                if qi == qj || tj.iter().any(|a| gi.contains(&group[*a])) {
                    continue;
                }
                let Some(hj) = hull(cj) else { continue };
                if parry3d_f64::query::intersection_test(&Pose::identity(), &hi, &Pose::identity(), &hj).is_ok_and(|r| r.intersecting) {
                    found.push(Overlap { first: *ti, second: *tj, parts: (model.parts[*pi].name.clone(), model.parts[*pj].name.clone()) });
                }
            }
            found.into_iter()
        })
        .collect()
}
