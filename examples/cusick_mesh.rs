//! Cusick drape on a chosen specimen mesh, with the seeded specimen of `tests/cusick.rs`
//! (a 0.1 mm random-field imperfection of the overhang, correlation length 50 mm, tapered to
//! zero over r = 90…110 mm; the discs not shifted), for mesh studies such as issue 18's: which
//! direction of the annulus carries the drape coefficient's error, and the `Auto` mesh.
//!
//! cargo run --release --example cusick_mesh -- PRESET SEED MESH
//!
//! MESH is the RON text of a mesh spec, e.g.
//! `"SizedAnnulus(ri: 0.02, ro: 0.15, element_size: Auto((tolerance: 0.02)))"`, or
//! `rings:A:K:N`: the rings of `FocusedAnnulus` with A sectors and rim refinement K
//! (`mesh::focused_rings`, inner aspect 4) carrying N sectors (an `AnnulusRings`). Prints one
//! JSON line: DOFs, nodes, time steps, Newton iterations, wall time, drape coefficient, folds,
//! penetration over the thickness. `docs/drape/cusick_mesh_study.jsonl` holds the runs of the
//! README's table.

use nalgebra::Vector3;
use plyshell::contact::drape::seed_outside_support;
use plyshell::solver::imperfection::RandomField;
use plyshell::{analysis, scene};

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: cusick_mesh PRESET SEED MESH";
    let preset = args.get(1).ok_or(usage)?.clone();
    let seed: u64 = args.get(2).ok_or(usage)?.parse().map_err(|e| format!("SEED: {e}"))?;
    let mut mesh = args.get(3).ok_or(usage)?.clone();
    if let Some(rest) = mesh.strip_prefix("rings:") {
        let v: Vec<f64> = rest.split(':').map(|x| x.parse::<f64>().map_err(|e| format!("rings:A:K:N: {e}"))).collect::<Result<_, _>>()?;
        let [a, k, n] = v[..] else { return Err("rings:A:K:N needs three numbers".into()) };
        let radii = plyshell::mesh::focused_rings(0.02, 0.15, a as usize, 0.09, k, 4.0).map_err(|e| e.to_string())?;
        mesh = format!("AnnulusRings(radii: {radii:?}, ntheta: {})", n as usize);
    }
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/garments/drape/cusick.ron");
    let text = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
    let h = plyshell::material::FabricProperties::preset(&preset).ok_or("unknown preset")?.thickness;
    let text = text
        .replace("preset: Some(\"cotton_broadcloth\")", &format!("preset: Some(\"{preset}\")"))
        .replace("thickness: 0.3e-3", &format!("thickness: {h:e}"))
        .replace("translation: (0.0, 0.0, -0.010149999)", &format!("translation: (0.0, 0.0, {:e})", -0.5 * h + 1e-9 - 0.01))
        .replace("translation: (0.0, 0.0, 0.010149999)", &format!("translation: (0.0, 0.0, {:e})", 0.5 * h - 1e-9 + 0.01))
        .replace("output: (every: 50)", "output: (vtu: false)")
        .replace("FocusedAnnulus(ri: 0.02, ro: 0.15, ntheta: 48, focus: 0.09, refine: 8.0, inner_aspect: 4.0)", &mesh);
    let sc = scene::parse(path, &text).map_err(|e| e.to_string())?;
    let mut built = scene::build(&sc, path, &text).map_err(|e| e.to_string())?;
    if seed != 0 {
        let rf = RandomField { amplitude: 0.1e-3, correlation_length: 0.05, seed };
        built.model = seed_outside_support(&built.model, &rf, &Vector3::zeros(), 0.09, 0.11);
    }
    let s = analysis::run(&sc, &built, &Default::default(), &mut |_| {}).map_err(|e| e.to_string())?;
    let d = &s.extra["drape"];
    let line = serde_json::json!({
        "mesh": mesh, "preset": preset, "seed": seed, "dofs": s.sizes.dofs, "nodes": s.sizes.nodes,
        "steps": s.increments.len(), "its": s.newton_iterations, "wall": s.wall_s,
        "dc": d["drape_coefficient_percent"], "folds": d["folds"],
        "pen_over_h": d["max_penetration"].as_f64().map(|p| p / h),
    });
    println!("{line}");
    Ok(())
}
