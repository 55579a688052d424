//! A picture of a garment on its body at one state: the garment's quads coloured by panel
//! (shaded by ply), the contact bodies in grey and the seams in red, seen from the front
//! (looking along −y, the body facing +y) and from the body's left (along +x), framed on
//! the garment ([`crate::io::raster`]).

use nalgebra::Vector3;

use super::export::GarmentLayout;
use super::SeamInfo;
use crate::contact::{RigidBody, Shape};
use crate::io::raster::{render, Picture, Segment, Triangle};
use crate::model::{Model, State};

/// Panel colours (Tableau 10).
const PALETTE: [[u8; 3]; 10] = [[31, 119, 180], [255, 127, 14], [44, 160, 44], [148, 103, 189], [140, 86, 75], [227, 119, 194], [188, 189, 34], [23, 190, 207], [127, 127, 127], [214, 39, 40]];

/// The picture (two views of `size` pixels) of `state` with the bodies `bodies` placed
/// where they are at that state.
pub fn garment_picture(model: &Model, state: &State, layout: Option<&GarmentLayout>, seams: &[SeamInfo], bodies: &[RigidBody], size: u32) -> Picture {
    let x = |n: usize| model.position(state, n);
    let mut triangles: Vec<Triangle> = Vec::new();
    let (mut lo, mut hi) = (Vector3::repeat(f64::INFINITY), Vector3::repeat(f64::NEG_INFINITY));
    for el in &model.elements {
        let tag = layout.and_then(|l| l.part_tags.get(el.part)).copied().unwrap_or([el.part as i32, 0, 0]);
        let base = PALETTE[tag[0].max(0) as usize % PALETTE.len()];
        // Inner plies darker, so the outermost shows the panel's colour.
        let c = base.map(|v| (f64::from(v) * (1.0 - 0.15 * f64::from(tag[1].max(0)).min(3.0))) as u8);
        let q = el.nodes.map(x);
        for p in &q {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        triangles.push(([q[0], q[1], q[2]], c));
        triangles.push(([q[0], q[2], q[3]], c));
    }
    if triangles.is_empty() {
        (lo, hi) = (Vector3::repeat(-1.0), Vector3::repeat(1.0));
    }
    // Bodies: mesh triangles within reach of the garment (twice its size round it).
    let reach = 0.5 * (hi - lo).norm();
    let (blo, bhi) = (lo - Vector3::repeat(reach), hi + Vector3::repeat(reach));
    for b in bodies {
        let Shape::Mesh(m) = &b.shape else { continue };
        let v: Vec<Vector3<f64>> = m.vertices().iter().map(|p| b.pose * nalgebra::Point3::new(p.x, p.y, p.z)).map(|p| p.coords).collect();
        for t in m.indices() {
            let tri = t.map(|i| v[i as usize]);
            if tri.iter().any(|p| p.iter().zip(blo.iter().zip(bhi.iter())).all(|(x, (a, b))| x >= a && x <= b)) {
                triangles.push((tri, [200, 200, 200]));
            }
        }
    }
    let mut lines: Vec<Segment> = Vec::new();
    for s in seams {
        for w in s.slave.windows(2) {
            lines.push(([x(w[0]), x(w[1])], [220, 0, 0]));
        }
    }
    render(&triangles, &lines, (lo, hi), &[Vector3::new(0.0, -1.0, 0.0), Vector3::new(1.0, 0.0, 0.0)], size, 3e-3)
}
