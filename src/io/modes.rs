//! Buckling modes as VTU point fields on the state they were computed at.

use std::path::Path;

use super::vtu::{write_vtu, DataArray, VtuMesh};
use crate::element::NODE_DOFS;
use crate::model::{Model, State};

/// Writes `modes` (5 values per node: translations, tilts) of `model` at `state` as one VTU:
/// points at the state's mid-surface; point data `mode_k` (translation, 3 components) and
/// `mode_k_tilt` (α1, α2 in the node's frame) for k = 1, 2, ….
pub fn write_modes_vtu(path: &Path, model: &Model, state: &State, modes: &[Vec<f64>], binary: bool) -> std::io::Result<()> {
    let points: Vec<[f64; 3]> = (0..model.n_nodes()).map(|n| model.position(state, n)).map(|p| [p.x, p.y, p.z]).collect();
    let quads: Vec<[usize; 4]> = model.elements.iter().map(|e| e.nodes).collect();
    let names: Vec<(String, String)> = (1..=modes.len()).map(|k| (format!("mode_{k}"), format!("mode_{k}_tilt"))).collect();
    let fields: Vec<(Vec<f64>, Vec<f64>)> = modes
        .iter()
        .map(|m| {
            let t = (0..model.n_nodes()).flat_map(|n| m[NODE_DOFS * n..NODE_DOFS * n + 3].to_vec()).collect();
            let a = (0..model.n_nodes()).flat_map(|n| m[NODE_DOFS * n + 3..NODE_DOFS * n + 5].to_vec()).collect();
            (t, a)
        })
        .collect();
    let mut point_data = Vec::new();
    for ((nt, na), (t, a)) in names.iter().zip(&fields) {
        point_data.push(DataArray { name: nt, components: 3, values: t });
        point_data.push(DataArray { name: na, components: 2, values: a });
    }
    let mesh = VtuMesh { points: &points, quads: &quads, lines: &[], point_data, cell_data: vec![], int_cell_data: vec![], field_data: vec![] };
    write_vtu(path, &mesh, binary)
}
