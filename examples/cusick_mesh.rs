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

#[path = "../tests/common/cusick_specimen.rs"]
mod cusick_specimen;

use plyshell::analysis;

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
    let (sc, built, h) = cusick_specimen::specimen(&preset, seed, &mesh)?;
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
