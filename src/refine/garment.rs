//! A-posteriori refinement of garment panels (issue 18 item 1): the indicator of the rest
//! state becomes a size field per panel in pattern coordinates, and the pattern-space panel
//! mesher (`garment::mesh::mesh_polygon_graded`, which grades by a size field already) meshes
//! the panels again; seams, plies, quilting ties and contact are rebuilt from the garment
//! graph on the new meshes by the scene builder (`scene::build_sized`), and the state is
//! mapped between the two meshes of each ply part in its panel's pattern coordinates
//! (`map::map_state`, any two quad meshes of the same pattern).
//!
//! The field of a panel: every element asks for h_e = min_k h (T/η_k)^{1/2} along the
//! pattern directions (`size_field::target_size`, clamped to [h/4, min(2h, a quarter of the
//! panel's extent)]); the field's base size is the largest of them and each element asking
//! for less is a point refinement at its pattern centroid (`garment::sizing::Refinement`)
//! whose size grows back to the base with slope `size_field::GRADING` (|dh/dx| ≤ 0.2, the
//! grading of the tensor grids). A four-sided convex panel is a mapped grid graded by the
//! field along its sides; other panels are the Delaunay split graded inwards from their
//! outline (the mesher's module doc). The new mesh is not nested in the old one.

use crate::garment::sizing::{Refinement, SizeField};
use crate::model::Model;
use crate::scene::BuiltScene;

use super::indicator::ElementIndicator;
use super::size_field::{target_size, GRADING};

/// Pattern coordinates of every node: its panel's (u, v) for garment nodes (the layout's
/// `pattern_uv`), the reference (x, y) otherwise.
pub fn pattern_of(b: &BuiltScene) -> Vec<[f64; 2]> {
    let flat = super::map::pattern_of(&b.model);
    match &b.garment {
        Some(layout) => flat.iter().enumerate().map(|(n, p)| layout.pattern_uv.get(n).copied().flatten().unwrap_or(*p)).collect(),
        None => flat,
    }
}

/// The panel (index in the garment spec) of each model part, None outside the garment.
pub fn part_panels(b: &BuiltScene) -> Vec<Option<usize>> {
    (0..b.model.parts.len()).map(|p| b.garment.as_ref().and_then(|l| l.part_tags.get(p)).and_then(|t| usize::try_from(t[0]).ok())).collect()
}

/// The size the element asks for in the garment mesher's isotropic field: the smaller of
/// the two pattern directions' targets, `cap` the panel's quarter extent.
fn element_target(i: &ElementIndicator, tolerance: f64, cap: f64) -> f64 {
    target_size(i, 0, tolerance, cap).min(target_size(i, 1, tolerance, cap))
}

/// A quarter of each panel's pattern extent (the `Auto` cap), over the nodes of its parts.
fn caps(model: &Model, pattern: &[[f64; 2]], panel_of: &[Option<usize>], panels: usize) -> Vec<f64> {
    let mut lo = vec![[f64::INFINITY; 2]; panels];
    let mut hi = vec![[f64::NEG_INFINITY; 2]; panels];
    for (p, part) in model.parts.iter().enumerate() {
        let Some(k) = panel_of[p] else { continue };
        for n in part.first_node..part.first_node + part.n_nodes {
            for c in 0..2 {
                lo[k][c] = lo[k][c].min(pattern[n][c]);
                hi[k][c] = hi[k][c].max(pattern[n][c]);
            }
        }
    }
    lo.iter().zip(&hi).map(|(l, h)| 0.25 * (h[0] - l[0]).max(h[1] - l[1])).collect()
}

/// The size each garment element asks for (module doc; NaN outside the garment).
pub fn element_sizes(model: &Model, pattern: &[[f64; 2]], panel_of: &[Option<usize>], panels: usize, ind: &[ElementIndicator], tolerance: f64) -> Vec<f64> {
    let cap = caps(model, pattern, panel_of, panels);
    model.elements.iter().zip(ind).map(|(el, i)| panel_of[el.part].map_or(f64::NAN, |k| element_target(i, tolerance, cap[k]))).collect()
}

/// The size field of each of `panels` panels from the indicators `ind` of `model`'s elements
/// (module doc), the nodes' pattern coordinates `pattern`, the parts' panels `panel_of`.
/// Also the elements over the tolerance and those asking for twice their smaller extent (the
/// report's counts).
pub fn panel_fields(model: &Model, pattern: &[[f64; 2]], panel_of: &[Option<usize>], panels: usize, ind: &[ElementIndicator], tolerance: f64) -> Result<(Vec<SizeField>, usize, usize), String> {
    let sizes = element_sizes(model, pattern, panel_of, panels, ind, tolerance);
    let mut wanted: Vec<Vec<([f64; 2], f64)>> = vec![Vec::new(); panels];
    let (mut marked, mut coarsened) = (0, 0);
    for (e, el) in model.elements.iter().enumerate() {
        let Some(k) = panel_of[el.part] else { continue };
        let (i, h) = (&ind[e], sizes[e]);
        if i.value() > tolerance {
            marked += 1;
        } else if h >= 2.0 * i.h[0].min(i.h[1]) * (1.0 - 1e-9) {
            coarsened += 1;
        }
        let c = el.nodes.iter().fold([0.0; 2], |a, &n| [a[0] + 0.25 * pattern[n][0], a[1] + 0.25 * pattern[n][1]]);
        wanted[k].push((c, h));
    }
    let mut fields = Vec::with_capacity(panels);
    for (k, w) in wanted.into_iter().enumerate() {
        let base = w.iter().map(|x| x.1).fold(0.0, f64::max);
        if !(base.is_finite() && base > 0.0) {
            return Err(format!("panel {k}: no element to size (its parts have no elements)"));
        }
        let refinements = w
            .into_iter()
            .filter(|&(_, h)| h < base * (1.0 - 1e-9))
            .map(|(c, h)| Refinement { points: vec![c], segment: None, h_near: h, band: (base - h) / GRADING })
            .collect();
        fields.push(SizeField { base, refinements, scales: None, across: true });
    }
    Ok((fields, marked, coarsened))
}
