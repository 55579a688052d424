//! Which plies of a meshed garment meet: the garment's `interply` settings checked and turned
//! into the contact setup (ply pairs for the penalty formulation, the garment's parts for the
//! barrier surface contact).

use super::{GarmentMesh, GarmentSpec};
use crate::contact::interply::{InterplyFormulation, InterplySettings, InterplySetup};
use crate::contact::ipc::{SurfaceSettings, SurfaceSetup};
use crate::input::{Locator, SceneError};

/// The inter-ply contact of a meshed garment: every pair of adjacent plies (k, k+1) of each
/// multi-ply panel (model parts `first_part + i` for garment part i), with the garment's
/// settings; None when disabled or no panel has two plies. Bad settings are errors located
/// at their key in the scene file.
pub fn interply_setup(
    spec: &GarmentSpec,
    mesh: &GarmentMesh,
    first_part: usize,
    loc: &Locator,
) -> Result<Option<InterplySetup>, SceneError> {
    let s = &spec.interply;
    let bad = |key: &str, msg: &str| loc.at(Some("interply"), Some(key), format!("garment.interply.{key}"), msg.to_string());
    let ok = |x: f64| x.is_finite() && x > 0.0;
    if !ok(s.penalty_factor) {
        return Err(bad("penalty_factor", "expected a positive penalty factor"));
    }
    if s.penalty.is_some_and(|k| !ok(k)) {
        return Err(bad("penalty", "expected a positive nodal penalty (N/m)"));
    }
    if !(s.friction.is_finite() && s.friction >= 0.0) {
        return Err(bad("friction", "expected a non-negative friction coefficient"));
    }
    if !ok(s.tangential_factor) {
        return Err(bad("tangential_factor", "expected a positive tangential factor"));
    }
    let mut ply_pairs = Vec::new();
    for (i, p) in mesh.parts.iter().enumerate() {
        if let Some(j) = mesh.parts.iter().position(|q| q.panel == p.panel && q.ply == p.ply + 1) {
            ply_pairs.push((first_part + i, first_part + j));
            ply_pairs.push((first_part + j, first_part + i));
        }
    }
    let settings = InterplySettings { penalty_factor: s.penalty_factor, penalty: s.penalty, friction: s.friction, tangential_factor: s.tangential_factor };
    if let InterplyFormulation::Barrier { distance_factor, stiffness_factor, friction_slip, self_contact, compression_tolerance } = s.formulation {
        let surface = SurfaceSettings { distance_factor, stiffness_factor, friction: s.friction, friction_slip, self_contact, compression_tolerance };
        if let Some((key, msg)) = surface.problem() {
            return Err(bad(&format!("formulation.{key}"), msg));
        }
        if !s.enabled || (ply_pairs.is_empty() && mesh.parts.len() < 2 && !self_contact) {
            return Ok(None);
        }
        let parts = (first_part..first_part + mesh.parts.len()).collect();
        return Ok(Some(InterplySetup { ply_pairs, settings, barrier: Some(SurfaceSetup { parts, settings: surface }) }));
    }
    if !s.enabled || ply_pairs.is_empty() {
        return Ok(None);
    }
    Ok(Some(InterplySetup { ply_pairs, settings, barrier: None }))
}
