//! What barrier surface contact costs (issue 13's closing table): solves each scene with its
//! inter-ply and self contact on, and again with `garment.interply.enabled = false`, and
//! prints per scene the wall time with contact on and off, the contact share of the solve
//! (the solver's contact timer — pair evaluation and the scatter of its tangent blocks — over
//! the wall time; and with collision detection and commits added), active pairs per contact
//! node, the smallest gap over d̂, the Newton iterations, and the factorization's time and
//! the Cholesky factor's size at the end with contact on and off (the contact blocks couple
//! the plies in the tangent's pattern, and the fill they cause is a cost of contact the
//! contact timer does not see), and how often the pattern grew for blocks outside it.
//!
//! cargo run --release --example contact_cost -- [SCENE.ron ...] [--no-off]
//!
//! Default scene: garments/nbc_sleeve.ron. `--no-off` skips the runs without contact (the
//! NBC sleeve on the arm does not come to rest without it). Nothing is written to disk.
//! Times are wall times on the machine as it is: on a loaded machine compare shares, not
//! seconds.

use std::path::Path;

use plyshell::scene;
use plyshell::solver::Solver;

/// One run: (wall s, Newton iterations, a summary as JSON: `timings` (the solver's), `sizes`
/// (`factor_nnz` at the end, after any growth of the pattern) and the surface contact's
/// section `surface_contact`). The solve is that of `plyshell solve` (body contact, surface
/// contact and compliant seams attached, the steps run), without output.
fn solve(path: &Path, contact: bool) -> Result<(f64, usize, serde_json::Value), String> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| format!("{file}: {e}"))?;
    let mut sc = scene::parse(&file, &text).map_err(|e| e.to_string())?;
    if !contact {
        match sc.garment.as_mut() {
            Some(g) => g.interply.enabled = false,
            None => return Err(format!("{file}: no garment, no surface contact to turn off")),
        }
    }
    let built = scene::build(&sc, &file, &text).map_err(|e| e.to_string())?;
    let model = &built.model;
    let t = std::time::Instant::now();
    let mut solver = Solver::new(model, sc.solver.clone())?;
    if let Some(c) = &built.contact {
        plyshell::contact::attach(&mut solver, model, c)?;
    }
    if let Some(s) = &built.interply {
        plyshell::contact::interply::attach(&mut solver, model, s)?;
    }
    if let Some(c) = plyshell::garment::compliant::CompliantSeams::new(&built.seams) {
        solver.add_nodal_forces(Box::new(c));
    }
    let mut state = model.initial_state();
    let mut iterations = 0usize;
    let run = solver.run(&built.steps, &mut state, &mut |r, _, _| iterations += r.iterations, &mut |_| {});
    run.map_err(|e| format!("{file}: {e} (after {iterations} Newton iterations; {:?})", solver.timings))?;
    let wall = t.elapsed().as_secs_f64();
    let mut json = serde_json::json!({
        "timings": serde_json::to_value(&solver.timings).map_err(|e| e.to_string())?,
        "sizes": {"factor_nnz": solver.sizes().2},
    });
    for (name, value) in solver.nodal_forces().iter().filter_map(|f| f.summary()) {
        json[name] = value;
    }
    Ok((wall, iterations, json))
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let off = !args.iter().any(|a| a == "--no-off");
    let mut scenes: Vec<String> = args.into_iter().filter(|a| !a.starts_with("--")).collect();
    if scenes.is_empty() {
        scenes.push(concat!(env!("CARGO_MANIFEST_DIR"), "/garments/nbc_sleeve.ron").into());
    }
    println!("| scene | wall on (s) | wall off (s) | contact share | incl. CCD + commit | pairs/node (max) | min gap/d̂ | Newton on | Newton off | factorization on / off (s) | factor entries on / off | pattern growths |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    for s in &scenes {
        let path = Path::new(s);
        let (wall, iters, json) = solve(path, true)?;
        let f = |v: &serde_json::Value| v.as_f64().unwrap_or(f64::NAN);
        let contact = f(&json["timings"]["contact"]);
        let sc = &json["surface_contact"];
        let (ccd, commit) = (f(&sc["timings"]["ccd"]), f(&sc["timings"]["commit"]));
        let fact = |j: &serde_json::Value| (f(&j["timings"]["factorization"]), j["sizes"]["factor_nnz"].as_u64().unwrap_or(0));
        let (fact_on, nnz_on) = fact(&json);
        let (wall_off, iters_off, fact_off, nnz_off) = if off {
            let (w, i, j) = solve(path, false)?;
            let (fo, no) = fact(&j);
            (format!("{w:.1}"), i.to_string(), format!("{fo:.1}"), no.to_string())
        } else {
            ("—".into(), "—".into(), "—".into(), "—".into())
        };
        let name = path.file_name().map_or(s.clone(), |n| n.to_string_lossy().into_owned());
        println!(
            "| {name} | {wall:.1} | {wall_off} | {:.1} % | {:.1} % | {:.1} | {:.3} | {iters} | {iters_off} | {fact_on:.1} / {fact_off} | {nnz_on} / {nnz_off} | {} |",
            100.0 * contact / wall,
            100.0 * (contact + ccd + commit) / wall,
            f(&sc["max_pairs_per_node"]),
            f(&sc["min_gap_ratio"]),
            json["timings"]["pattern_growths"],
        );
    }
    Ok(())
}
