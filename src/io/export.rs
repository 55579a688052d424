//! A model state as a VTU file: deformed quads with nodal and element fields.

use std::path::Path;

use rayon::prelude::*;

use super::vtu::{write_vtu, DataArray, VtuMesh};
use crate::model::{Model, State};

/// Export settings.
#[derive(Clone, Debug, Default)]
pub struct ExportOptions {
    /// Base64 binary (true) or ASCII data arrays.
    pub binary: bool,
    /// Further point data (name, components, values per node), e.g. contact pressure.
    pub extra_point_data: Vec<(String, usize, Vec<f64>)>,
    /// Further cell data (name, components, values per element), e.g. the refinement
    /// indicator.
    pub extra_cell_data: Vec<(String, usize, Vec<f64>)>,
}

/// Writes `state` of `model` as a VTU: points at the deformed mid-surface; point data
/// `displacement`, `director`, `reference_position`; cell data `membrane_strain`
/// (E11, E22, 2E12 at the centre of the mid-surface, lamina frame), `membrane_stress`
/// (S11, S22, S12 there), `energy_density` (strain energy per reference area), `part`, and
/// `failed` (1 where the element could not be evaluated; its values are then written as 0).
pub fn write_state_vtu(path: &Path, model: &Model, state: &State, options: &ExportOptions) -> std::io::Result<()> {
    let points: Vec<[f64; 3]> = (0..model.n_nodes()).map(|n| model.position(state, n)).map(|p| [p.x, p.y, p.z]).collect();
    let quads: Vec<[usize; 4]> = model.elements.iter().map(|e| e.nodes).collect();
    let displacement: Vec<f64> = (0..model.n_nodes()).flat_map(|n| model.displacement(state, n).iter().copied().collect::<Vec<_>>()).collect();
    let director: Vec<f64> = state.frames.iter().flat_map(|f| [f.d.x, f.d.y, f.d.z]).collect();
    let reference: Vec<f64> = model.x0.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
    let per_element: Vec<Option<([f64; 3], [f64; 3], f64)>> = (0..model.elements.len())
        .into_par_iter()
        .map(|e| {
            let el = model.element(e);
            let nodes = model.elements[e].nodes;
            let x = nodes.map(|n| state.u[n]);
            let f = nodes.map(|n| state.frames[n]);
            let (strain, stress) = el.centre_state(&x, &f).ok()?;
            let energy = el.response(&x, &f, false).ok()?.energy / el.reference_area();
            Some(([strain[0], strain[1], strain[2]], [stress[0], stress[1], stress[2]], energy))
        })
        .collect();
    let ok = |p: &Option<([f64; 3], [f64; 3], f64)>| p.unwrap_or(([0.0; 3], [0.0; 3], 0.0));
    let strain: Vec<f64> = per_element.iter().flat_map(|p| ok(p).0).collect();
    let stress: Vec<f64> = per_element.iter().flat_map(|p| ok(p).1).collect();
    let energy: Vec<f64> = per_element.iter().map(|p| ok(p).2).collect();
    let failed: Vec<i32> = per_element.iter().map(|p| i32::from(p.is_none())).collect();
    let part: Vec<i32> = model.elements.iter().map(|e| e.part as i32).collect();
    let mesh = VtuMesh {
        points: &points,
        quads: &quads,
        lines: &[],
        point_data: vec![
            DataArray { name: "displacement", components: 3, values: &displacement },
            DataArray { name: "director", components: 3, values: &director },
            DataArray { name: "reference_position", components: 3, values: &reference },
        ]
        .into_iter()
        .chain(options.extra_point_data.iter().map(|(name, components, values)| DataArray { name, components: *components, values }))
        .collect(),
        cell_data: vec![
            DataArray { name: "membrane_strain", components: 3, values: &strain },
            DataArray { name: "membrane_stress", components: 3, values: &stress },
            DataArray { name: "energy_density", components: 1, values: &energy },
        ]
        .into_iter()
        .chain(options.extra_cell_data.iter().map(|(name, components, values)| DataArray { name, components: *components, values }))
        .collect(),
        int_cell_data: vec![("part", part), ("failed", failed)],
        field_data: vec![],
    };
    write_vtu(path, &mesh, options.binary)
}
