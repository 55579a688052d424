//! Speed against error of a-posteriori refinement (`refine`) on a drape: the cotton sheet on
//! the sphere (`garments/drape/sphere.ron` with barrier contact, the sphere 1.2 mm below the
//! sheet) on uniform n × n grids and refined from 16 × 16 at a tolerance, each compared with
//! a uniform reference grid: every state is mapped onto the reference mesh in pattern space
//! (`refine::map::map_state`: the same material point) and the RMS and largest distance of
//! the positions is the shape error. Writes one JSON line per run to stdout; user CPU from
//! `getrusage` (run with RAYON_NUM_THREADS=1).
//!
//! `cargo run --release --example refine_speed -- [REF_N] [TOL,...] [MEMBRANE]` (default 48,
//! 0.02, true; MEMBRANE false continues from the interpolated state, without
//! `refine::relax`).

use plyshell::refine::map::{map_state, pattern_of};
use plyshell::{analysis, scene};
use serde_json::json;

fn text(n: usize, refine: &str) -> String {
    let membrane = std::env::args().nth(3).unwrap_or_else(|| "true".into());
    let refine = refine.replace("passes: 1))", &format!("passes: 1, relax_membrane: {membrane}))"));
    let t = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/garments/drape/sphere.ron")).unwrap_or_default();
    t.replace("nx: 16, ny: 16", &format!("nx: {n}, ny: {n}"))
        .replace("max_steps: 2000)))]", &format!("max_steps: 2000)), refine: {refine})]"))
        .replace("contact: Some((", "contact: Some((formulation: Barrier(),")
        .replace("translation: (0.15, 0.15, -0.08015)", "translation: (0.15, 0.15, -0.0812)")
        .replace("output: (every: 20)", "output: (vtu: false)")
}

/// Solves; returns the summary, the model and the CPU seconds.
fn solve(t: &str, tol: Option<f64>) -> Result<(plyshell::results::Summary, plyshell::model::Model, f64), String> {
    let sc = scene::parse("sphere.ron", t).map_err(|e| e.to_string())?;
    let b = scene::build(&sc, "sphere.ron", t).map_err(|e| e.to_string())?;
    let c0 = plyshell::cpu_time::process_seconds();
    let s = analysis::run(&sc, &b, &Default::default(), &mut |_| {}).map_err(|e| e.to_string())?;
    let cpu = plyshell::cpu_time::process_seconds() - c0;
    // The refined model: the pass's scene rebuilt (one pass).
    let model = match tol {
        None => b.model,
        Some(tol) => {
            let membrane = std::env::args().nth(3).unwrap_or_else(|| "true".into());
            let sc0 = scene::parse("sphere.ron", &t.replace(&format!("refine: Some((tolerance: {tol}, passes: 1, relax_membrane: {membrane}))"), "refine: None")).map_err(|e| e.to_string())?;
            let b0 = scene::build(&sc0, "sphere.ron", t).map_err(|e| e.to_string())?;
            let first = analysis::run(&sc0, &b0, &Default::default(), &mut |_| {}).map_err(|e| e.to_string())?;
            let st = first.final_state.ok_or("no state")?;
            let mut fine = plyshell::refine::refined_scene_of(&sc0, &b0.model, &st, tol)?;
            fine.contact = None;
            scene::build(&fine, "refined", "").map_err(|e| e.to_string())?.model
        }
    };
    Ok((s, model, cpu))
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let n_ref: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(48);
    let tols: Vec<f64> = args.get(2).map(|a| a.split(',').filter_map(|x| x.parse().ok()).collect()).unwrap_or_else(|| vec![0.02]);
    let (rs, rm, rcpu) = solve(&text(n_ref, "None"), None)?;
    let rstate = rs.final_state.clone().ok_or("no reference state")?;
    let rp = pattern_of(&rm);
    let error = |m: &plyshell::model::Model, s: &plyshell::results::Summary| -> Result<(f64, f64), String> {
        let st = s.final_state.as_ref().ok_or("no state")?;
        let (mapped, _) = map_state(m, st, &pattern_of(m), &rm, &rp)?;
        let d: Vec<f64> = (0..rm.n_nodes()).map(|n| (rm.position(&mapped, n) - rm.position(&rstate, n)).norm()).collect();
        Ok(((d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt(), d.iter().copied().fold(0.0, f64::max)))
    };
    let line = |case: String, s: &plyshell::results::Summary, cpu: f64, err: (f64, f64)| {
        println!("{}", json!({ "case": case, "status": s.status, "dofs": s.sizes.dofs, "elements": s.sizes.elements, "time_steps": s.increments.len(), "newton_iterations": s.newton_iterations, "user_cpu_s": cpu, "rms_m": err.0, "max_m": err.1, "refinement": s.extra.get("refinement") }));
    };
    line(format!("uniform {n_ref}x{n_ref} (reference)"), &rs, rcpu, (0.0, 0.0));
    for n in [16usize, 24, 32] {
        let (s, m, cpu) = solve(&text(n, "None"), None)?;
        let e = error(&m, &s)?;
        line(format!("uniform {n}x{n}"), &s, cpu, e);
    }
    for tol in tols {
        let (s, m, cpu) = solve(&text(16, &format!("Some((tolerance: {tol}, passes: 1))")), Some(tol))?;
        let e = error(&m, &s)?;
        line(format!("refined from 16x16, T = {tol}, 1 pass"), &s, cpu, e);
    }
    Ok(())
}
