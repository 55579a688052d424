//! Garment export: quads tagged with panel, ply and material ids, and seams as line cells
//! carrying their force per unit length; in 3D (a model state) or as the flat pattern; and
//! the garment as a textured surface (groups per panel and ply, UVs from the pattern).

use std::path::Path;

use nalgebra::Vector3;

use super::SeamInfo;
use crate::io::surface::TexturedMesh;
use crate::io::vtu::{write_vtu, DataArray, FieldValues, VtuMesh};
use crate::model::{Model, State};

/// Names and ids of the garment's panels, plies and materials, per model part and node.
#[derive(Clone, Debug, Default)]
pub struct GarmentLayout {
    /// Panel names (id = index).
    pub panels: Vec<String>,
    /// Ply names (id = index), in stack order, innermost first.
    pub plies: Vec<String>,
    /// Thickness of each ply (m), by ply id.
    pub ply_thickness: Vec<f64>,
    /// Material names (id = index).
    pub materials: Vec<String>,
    /// (panel, ply, material) ids of each model part; −1 for parts outside the garment, and
    /// ply and material −1 for a laminated panel (it stands for several).
    pub part_tags: Vec<[i32; 3]>,
    /// Ply ids each model part stands for: one for a ply, the whole stack (innermost last)
    /// for a laminated panel, none outside the garment.
    pub part_plies: Vec<Vec<i32>>,
    /// Flat-pattern position of each model node laid out for export (panels side by side,
    /// plies stacked below), or None for nodes outside the garment.
    pub flat: Vec<Option<[f64; 3]>>,
    /// Pattern coordinates (u, v) of each model node in its panel's flat pattern (m), or None
    /// for nodes outside the garment.
    pub pattern_uv: Vec<Option<[f64; 2]>>,
    /// Target element size (m) of each quad of each model part (the panel's size field at
    /// the quad's pattern centroid, `garment::sizing`); empty outside the garment.
    pub part_element_size: Vec<Vec<f64>>,
}

/// The garment's quads as a textured surface for OBJ and glTF: one group `panel/ply` per
/// ply of each panel (panel by panel, plies innermost first), texture coordinates the flat pattern coordinates in
/// metres (a tiling print texture of 1 m × 1 m maps at true scale, along the pattern's axes),
/// vertex positions from `position(node)`. Returns the surface and the model node of each
/// vertex (garment nodes only, in node order).
pub fn garment_surface(model: &Model, layout: &GarmentLayout, position: impl Fn(usize) -> [f64; 3]) -> (TexturedMesh, Vec<usize>) {
    let nodes: Vec<usize> = (0..model.n_nodes()).filter(|&n| layout.pattern_uv.get(n).copied().flatten().is_some()).collect();
    let mut vertex = vec![usize::MAX; model.n_nodes()];
    for (v, &n) in nodes.iter().enumerate() {
        vertex[n] = v;
    }
    let mut tagged: Vec<((i32, i32), String, Vec<[usize; 4]>)> = Vec::new();
    for (pi, part) in model.parts.iter().enumerate() {
        let Some(&[panel, ply, _]) = layout.part_tags.get(pi) else { continue };
        let Some(panel_name) = layout.panels.get(panel as usize).filter(|_| panel >= 0) else { continue };
        // A laminate's group names its plies, `panel/outer+carbon+liner`.
        let ids = layout.part_plies.get(pi).map_or(&[][..], |v| v.as_slice());
        let names: Vec<&str> = ids.iter().filter_map(|&i| layout.plies.get(i as usize).filter(|_| i >= 0)).map(|s| s.as_str()).collect();
        if names.is_empty() {
            continue;
        }
        let ply_name = names.join("+");
        let quads: Vec<[usize; 4]> = model.elements[part.first_element..part.first_element + part.n_elements]
            .iter()
            .map(|e| e.nodes.map(|n| vertex[n]))
            .filter(|q| q.iter().all(|&v| v != usize::MAX))
            .collect();
        tagged.push(((panel, ply), format!("{panel_name}/{ply_name}"), quads));
    }
    // Panel by panel, plies in stack order (innermost first), as the ply ids.
    tagged.sort_by_key(|t| t.0);
    let groups: Vec<(String, Vec<[usize; 4]>)> = tagged.into_iter().map(|(_, name, quads)| (name, quads)).collect();
    let mesh = TexturedMesh {
        positions: nodes.iter().map(|&n| position(n)).collect(),
        uvs: nodes.iter().map(|&n| layout.pattern_uv[n].unwrap_or([0.0; 2])).collect(),
        groups,
    };
    (mesh, nodes)
}

/// Writes the garment VTU. With `state`, points are the deformed positions and seam lines
/// carry `seam_force_per_length` (the springs' for compliant seams, else from the all-DOF
/// internal and external forces `forces`), `seam_utilisation` (force per length / strength,
/// 0 without a strength) and `seam_opening` (m; `compliant::seam_points`);
/// without, the flat pattern layout is written (seams as lines between the flat spans,
/// forces zero). Cell data: `panel`, `ply`, `material`, `part`, `seam` (−1 where it does
/// not apply; ply and material −1 on a laminated panel), `ply_mask` (bit i: the cell stands
/// for ply id i — one bit per ply, all its plies' bits on a laminate) and the force per unit
/// length (quads: zero), and `element_size` (m, the target size of the panel's size field at
/// the quad, `garment::sizing`; 0 on seam lines and outside the garment). Field data (with a layout): by ply
/// id, `ply_names` (UTF-8, each name ended by a NUL byte) and `ply_thickness` (m); likewise
/// `panel_names` and `material_names`. `extra_point_data` (name, components, values per
/// model node) is appended to the point data: the contact terms' `contact_pressure`,
/// `body_clearance`, … of the shell VTU.
pub fn write_garment_vtu(
    path: &Path,
    model: &Model,
    state: Option<&State>,
    layout: Option<&GarmentLayout>,
    seams: &[SeamInfo],
    forces: Option<(&[f64], &[f64])>,
    extra_point_data: &[(String, usize, Vec<f64>)],
    binary: bool,
) -> std::io::Result<()> {
    let points: Vec<[f64; 3]> = (0..model.n_nodes())
        .map(|n| match state {
            Some(s) => {
                let p = model.position(s, n);
                [p.x, p.y, p.z]
            }
            None => layout.and_then(|l| l.flat.get(n).copied().flatten()).unwrap_or([model.x0[n].x, model.x0[n].y, model.x0[n].z]),
        })
        .collect();
    let quads: Vec<[usize; 4]> = model.elements.iter().map(|e| e.nodes).collect();
    let mut lines = Vec::new();
    let mut seam_id = Vec::new();
    let mut line_force: Vec<Vector3<f64>> = Vec::new();
    let (mut line_util, mut line_open) = (Vec::new(), Vec::new());
    for (si, s) in seams.iter().enumerate() {
        let pts = match state {
            Some(st) => super::compliant::seam_points(s, |n| model.position(st, n), forces),
            None => vec![super::compliant::SeamPoint::default(); s.slave.len()],
        };
        for k in 0..s.slave.len().saturating_sub(1) {
            lines.push([s.slave[k], s.slave[k + 1]]);
            seam_id.push(si as i32);
            line_force.push((pts[k].force + pts[k + 1].force) * 0.5);
            line_util.push(0.5 * (pts[k].utilisation + pts[k + 1].utilisation));
            line_open.push(0.5 * (pts[k].opening + pts[k + 1].opening));
        }
    }
    let tag = |e: usize, k: usize| -> i32 { layout.and_then(|l| l.part_tags.get(model.elements[e].part)).map_or(-1, |t| t[k]) };
    let n_q = quads.len();
    let int = |k: usize| -> Vec<i32> { (0..n_q).map(|e| tag(e, k)).chain(std::iter::repeat_n(-1, lines.len())).collect() };
    let part: Vec<i32> = model.elements.iter().map(|e| e.part as i32).chain(std::iter::repeat_n(-1, lines.len())).collect();
    // Bit i set: the cell stands for ply id i (a laminate sets several).
    let mask_of = |p: usize| -> i32 { layout.and_then(|l| l.part_plies.get(p)).map_or(0, |ids| ids.iter().filter(|&&i| (0..31).contains(&i)).fold(0, |m, &i| m | (1 << i))) };
    let ply_mask: Vec<i32> = model.elements.iter().map(|e| mask_of(e.part)).chain(std::iter::repeat_n(0, lines.len())).collect();
    let seam: Vec<i32> = std::iter::repeat_n(-1, n_q).chain(seam_id).collect();
    let force: Vec<f64> = std::iter::repeat_n(0.0, 3 * n_q).chain(line_force.iter().flat_map(|f| [f.x, f.y, f.z])).collect();
    let element_size: Vec<f64> = model
        .elements
        .iter()
        .enumerate()
        .map(|(e, el)| {
            let sizes = layout.and_then(|l| l.part_element_size.get(el.part));
            let first = model.parts.get(el.part).map_or(0, |p| p.first_element);
            sizes.and_then(|v| v.get(e.wrapping_sub(first))).copied().unwrap_or(0.0)
        })
        .chain(std::iter::repeat_n(0.0, lines.len()))
        .collect();
    let utilisation: Vec<f64> = std::iter::repeat_n(0.0, n_q).chain(line_util).collect();
    let opening: Vec<f64> = std::iter::repeat_n(0.0, n_q).chain(line_open).collect();
    let displacement: Vec<f64> = (0..model.n_nodes())
        .flat_map(|n| {
            let u = state.map_or(Vector3::zeros(), |s| s.u[n]);
            [u.x, u.y, u.z]
        })
        .collect();
    let mesh = VtuMesh {
        points: &points,
        quads: &quads,
        lines: &lines,
        point_data: std::iter::once(DataArray { name: "displacement", components: 3, values: &displacement })
            .chain(extra_point_data.iter().map(|(name, components, values)| DataArray { name, components: *components, values }))
            .collect(),
        cell_data: vec![
            DataArray { name: "seam_force_per_length", components: 3, values: &force },
            DataArray { name: "seam_utilisation", components: 1, values: &utilisation },
            DataArray { name: "seam_opening", components: 1, values: &opening },
            DataArray { name: "element_size", components: 1, values: &element_size },
        ],
        int_cell_data: vec![("panel", int(0)), ("ply", int(1)), ("material", int(2)), ("part", part), ("seam", seam), ("ply_mask", ply_mask)],
        field_data: layout.map_or_else(Vec::new, |l| {
            vec![
                ("ply_names", FieldValues::names(&l.plies)),
                ("ply_thickness", FieldValues::Float(l.ply_thickness.clone())),
                ("panel_names", FieldValues::names(&l.panels)),
                ("material_names", FieldValues::names(&l.materials)),
            ]
        }),
    };
    write_vtu(path, &mesh, binary)
}
