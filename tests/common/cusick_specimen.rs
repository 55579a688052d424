//! The seeded Cusick specimen shared by `tests/cusick.rs` and `examples/cusick_mesh.rs`: the
//! shipped scene `garments/drape/cusick.ron` with another preset (its thickness, the discs
//! moved to touch it) and another specimen mesh, optionally carrying the 0.1 mm random-field
//! imperfection of the overhang (correlation length 50 mm, tapered to zero over r = 90…110 mm
//! so that the part clamped between the discs stays flat).

use nalgebra::Vector3;
use plyshell::contact::drape::seed_outside_support;
use plyshell::scene::{self, BuiltScene, Scene};
use plyshell::solver::imperfection::RandomField;

/// The scene's specimen mesh, as written in `garments/drape/cusick.ron`.
pub const SHIPPED_MESH: &str = "FocusedAnnulus(ri: 0.02, ro: 0.15, ntheta: 48, focus: 0.09, refine: 8.0, inner_aspect: 4.0)";

/// The Cusick scene for `preset` with its specimen meshed by `mesh` (RON text of a mesh spec),
/// seeded with `seed` (0: the perfect specimen), built, without VTU output; and the preset's
/// thickness.
pub fn specimen(preset: &str, seed: u64, mesh: &str) -> Result<(Scene, BuiltScene, f64), String> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/garments/drape/cusick.ron");
    let text = std::fs::read_to_string(path).map_err(|e| format!("{path}: {e}"))?;
    let h = plyshell::material::FabricProperties::preset(preset).ok_or_else(|| format!("unknown preset {preset}"))?.thickness;
    let text = text
        .replace("preset: Some(\"cotton_broadcloth\")", &format!("preset: Some(\"{preset}\")"))
        .replace("thickness: 0.3e-3", &format!("thickness: {h:e}"))
        .replace("translation: (0.0, 0.0, -0.010149999)", &format!("translation: (0.0, 0.0, {:e})", -0.5 * h + 1e-9 - 0.01))
        .replace("translation: (0.0, 0.0, 0.010149999)", &format!("translation: (0.0, 0.0, {:e})", 0.5 * h - 1e-9 + 0.01))
        .replace("output: (every: 50)", "output: (vtu: false)")
        .replace(SHIPPED_MESH, mesh);
    let sc = scene::parse(path, &text).map_err(|e| e.to_string())?;
    let mut built = scene::build(&sc, path, &text).map_err(|e| e.to_string())?;
    if seed != 0 {
        let rf = RandomField { amplitude: 0.1e-3, correlation_length: 0.05, seed };
        built.model = seed_outside_support(&built.model, &rf, &Vector3::zeros(), 0.09, 0.11);
    }
    Ok((sc, built, h))
}
