//! `ply_model: Auto` (issue 18, ply fidelity): laminate where the plies move as one, discrete
//! plies where they would slide (`garment::ply_auto`, `analysis_auto`).
//!
//! The three-ply cantilever of tests/interply.rs (10 cm × 2 cm, plies 1 mm, E = 20, 100,
//! 200 MPa top to bottom, 0.3 kg/m² each, clamped at the root through all plies, under its
//! own weight; inter-ply friction μ = 0.3) in two clear-cut states:
//!
//! - **quilted at every node column** (stitch lines every 5 mm): every node is tied through
//!   the stack, so no ply can slip relative to another (slip and peel ratios 0): Auto keeps
//!   the laminate, solves once, and its result is the `Laminate` run's (the same model: to
//!   round-off);
//! - **unquilted**: the cantilever's shear flow (Jourawski, τ = V Q / (I b), ~ 1.5 V/(b H) at
//!   the middle interface with V = q (L − x)) is ~100× the friction capacity μ p that the
//!   plies' weight presses into the interfaces (p = ρ g per ply above), and nothing but the
//!   root clamp holds the plies (δ up to L): Auto must choose discrete plies, solve twice,
//!   and give the `Discrete` run's result (the same model; to round-off). The physics says
//!   why: the unbonded stack deflects as Σ E_i I_i (Timoshenko & Gere), 5.45× the bonded
//!   transformed section the laminate would give — so the laminate must not be kept.
//!
//! Bad Auto input: `Auto` on a single-ply panel is a located error (tests/garment_validation.rs).

use plyshell::analysis::RunOptions;
use plyshell::analysis_auto;
use plyshell::scene;

#[path = "common/three_ply.rs"]
mod three_ply;
use three_ply::{B, E, G, H, L, RHO, T};

/// The shared three-ply cantilever (`tests/common/three_ply.rs`) with the panel's `ply_model`.
fn cantilever(stitch_xs: &[f64], ply_model: &str) -> String {
    three_ply::cantilever(stitch_xs, Some(ply_model))
}

/// Solves a scene (two passes for Auto): the run, the tip deflection (the monitor's Uz).
fn solve(text: &str) -> analysis_auto::AutoRun {
    let sc = scene::parse("ply_auto.ron", text).unwrap_or_else(|e| panic!("{e}"));
    analysis_auto::run(&sc, "ply_auto.ron", text, &RunOptions::default(), &mut |_| {}).unwrap_or_else(|e| panic!("{e}"))
}

fn tip(r: &analysis_auto::AutoRun) -> f64 {
    r.summary.monitors[0].values.last().map_or(f64::NAN, |v| v[0])
}

/// Largest distance between the two runs' final node positions (same model required).
fn largest_difference(a: &analysis_auto::AutoRun, b: &analysis_auto::AutoRun) -> f64 {
    assert_eq!(a.summary.final_positions.len(), b.summary.final_positions.len(), "the same model");
    a.summary.final_positions.iter().zip(&b.summary.final_positions).map(|(p, q)| ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()).fold(0.0, f64::max)
}

#[test]
fn densely_quilted_plies_stay_laminated() {
    let every_column: Vec<f64> = (1..=20).map(|i| i as f64 * H).collect();
    let auto = solve(&cantilever(&every_column, "Auto"));
    let lam = solve(&cantilever(&every_column, "Laminate"));
    for line in analysis_auto::describe(&auto) {
        println!("{line}");
    }
    assert_eq!(auto.passes, 1, "the laminate is kept: one solve");
    assert_eq!(auto.choices.len(), 1);
    assert_eq!(auto.choices[0].model, "laminate");
    let d = &auto.demands[0];
    assert_eq!(d.interfaces.len(), 2, "three plies, two interfaces");
    // 0 up to the round-off of the nodes' distances to the stitch lines (~1e-18 m).
    assert!(d.slip_ratio < 1e-9 && d.peel_ratio < 1e-9, "every node tied: nothing can slip ({} / {})", d.slip_ratio, d.peel_ratio);
    let diff = largest_difference(&auto, &lam);
    println!("Auto tip {:.6e} m, Laminate tip {:.6e} m, largest node difference {diff:.2e} m", tip(&auto), tip(&lam));
    assert!(diff <= 1e-12 * L, "Auto = Laminate: {diff}");
    assert!(auto.summary.extra.contains_key("ply_model_auto"));
}

#[test]
fn unquilted_plies_that_would_slide_are_discrete() {
    let auto = solve(&cantilever(&[], "Auto"));
    let discrete = solve(&cantilever(&[], "Discrete"));
    for line in analysis_auto::describe(&auto) {
        println!("{line}");
    }
    for i in &auto.demands[0].interfaces {
        println!("  {} | {}: slip {:.3}, peel {:.3}, slipping area {:.0} %, mean τ {:.2} Pa, mean p {:.2} Pa", i.inner, i.outer, i.slip_ratio, i.peel_ratio, 100.0 * i.slipping_area_fraction, i.mean_shear, i.mean_pressure);
    }
    assert_eq!(auto.choices[0].model, "discrete");
    assert_eq!(auto.passes, 2, "laminate first, then the discrete plies");
    let d = &auto.demands[0];
    assert!(d.slip_ratio > 10.0 * plyshell::garment::ply_auto::SLIP_LIMIT, "slip ratio {} far above the limit", d.slip_ratio);
    // Where the shear exceeds the friction: nearly everywhere (the root clamp and the tip,
    // where V → 0, aside).
    assert!(d.interfaces.iter().all(|i| i.slipping_area_fraction > 0.8), "{:?}", d.interfaces);
    let diff = largest_difference(&auto, &discrete);
    // Unbonded reference: w = q L⁴/(8 Σ E_i I_i) (tests/interply.rs holds the discrete run
    // to it); the laminate would be 5.45× stiffer.
    let i1 = B * T.powi(3) / 12.0;
    let w_unbonded = 3.0 * RHO * G * B * L.powi(4) / (8.0 * E.iter().map(|e| e * i1).sum::<f64>());
    println!("Auto tip {:.6e} m, Discrete tip {:.6e} m (unbonded beam {w_unbonded:.6e}), largest node difference {diff:.2e} m", tip(&auto), tip(&discrete));
    assert!(diff <= 1e-12 * L, "Auto = Discrete: {diff}");
    assert!((-tip(&auto) / w_unbonded - 1.0).abs() < 0.05, "tip {} vs unbonded {w_unbonded}", -tip(&auto));
}

/// `plyshell solve` on an Auto scene prints the choice per panel and writes it into
/// summary.json (`ply_model_auto`: model, reason, slip and peel ratios per interface, the
/// first pass's cost), the first (laminated) pass's files in `auto_first_pass/`.
#[test]
fn solve_reports_the_auto_choice() {
    let dir = std::env::temp_dir().join(format!("plyshell_ply_auto_{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let file = dir.join("cantilever.ron");
    std::fs::write(&file, cantilever(&[], "Auto")).expect("scene");
    let out = dir.join("out");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_plyshell")).args(["solve", "--quiet", "--out"]).arg(&out).arg(&file).output().expect("plyshell runs");
    let stdout = String::from_utf8_lossy(&run.stdout);
    println!("{stdout}{}", String::from_utf8_lossy(&run.stderr));
    assert!(run.status.success());
    assert!(stdout.contains("ply_model Auto: panel \"strip\" → discrete (slip"), "{stdout}");
    let summary: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("summary.json")).expect("summary.json")).expect("JSON");
    let auto = &summary["ply_model_auto"];
    assert_eq!(auto["passes"], 2);
    assert_eq!(auto["panels"][0]["model"], "discrete");
    assert_eq!(auto["panels"][0]["interfaces"].as_array().map(|a| a.len()), Some(2));
    assert!(auto["panels"][0]["slip_ratio"].as_f64().is_some_and(|s| s > plyshell::garment::ply_auto::SLIP_LIMIT));
    assert_eq!(auto["first_pass"]["status"], "completed");
    assert!(out.join("auto_first_pass").join("summary.json").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Peel: the same unquilted cantilever turned over (placed rotated 180° about its length, so
/// the director and the outer plies point down): the outermost ply's weight now pulls it off
/// the others (q = ρ g = 2.9 Pa, no pressure at that interface), nothing but the root clamp
/// holds it (δ up to L), so its peel ratio q δ²/(2 |N_out| h_out) is over the limit of 1
/// (1.31; the estimate takes the tension that holds the ply up from the bonded laminate's
/// bending, so it understates the peel of plies that also slide) — while upright the same
/// weight presses the interfaces (peel ratio 0).
#[test]
fn plies_hanging_under_the_stack_would_peel() {
    let upright = cantilever(&[], "Auto");
    let flipped = upright.replace(r#"ply_model: Some(Auto))]"#, r#"ply_model: Some(Auto), placement: Rigid(rotation_deg: (180.0, 0.0, 0.0)))]"#);
    assert_ne!(upright, flipped);
    let up = solve(&upright);
    let down = solve(&flipped);
    for (name, r) in [("upright", &up), ("turned over", &down)] {
        for i in &r.demands[0].interfaces {
            println!("{name}: {} | {}: slip {:.3}, peel {:.3}, mean p {:.2} Pa", i.inner, i.outer, i.slip_ratio, i.peel_ratio, i.mean_pressure);
        }
    }
    assert!(up.demands[0].peel_ratio < 1e-9, "upright: the weight presses the plies together ({})", up.demands[0].peel_ratio);
    let outermost = &down.demands[0].interfaces[1];
    assert_eq!(outermost.outer, "top");
    assert!(outermost.peel_ratio > plyshell::garment::ply_auto::PEEL_LIMIT, "turned over: {}", outermost.peel_ratio);
    assert!(outermost.mean_pressure < 1e-9 * RHO * G, "no pressure where the outermost ply hangs: {}", outermost.mean_pressure);
    assert_eq!(down.choices[0].model, "discrete");
}

/// A laminated first pass that does not solve is no model of the garment: its Auto panels go
/// discrete (fidelity is only raised). Here a Dynamic step allowed a single time step, so the
/// quilted cantilever (laminated if its first pass came to rest) cannot reach rest in either
/// pass: the run fails, and its summary records the discrete choice and why.
#[test]
fn a_failed_laminate_pass_goes_discrete() {
    let every_column: Vec<f64> = (1..=20).map(|i| i as f64 * H).collect();
    let text = cantilever(&every_column, "Auto").replace(r#"scale: {"g1": 1.0, "g2": 1.0, "g3": 1.0})"#, r#"scale: {"g1": 1.0, "g2": 1.0, "g3": 1.0}, kind: Dynamic((dt: 1.0e-3, max_steps: 1)))"#);
    assert!(text.contains("max_steps: 1"));
    let sc = scene::parse("ply_auto.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let Err(plyshell::analysis::RunError::Solve { error, summary }) = analysis_auto::run(&sc, "ply_auto.ron", &text, &RunOptions::default(), &mut |_| {}) else { panic!("expected the solve to fail") };
    println!("{error}");
    let auto = &summary.extra["ply_model_auto"];
    println!("{auto:#}");
    assert_eq!(auto["panels"][0]["model"], "discrete");
    assert!(auto["panels"][0]["reason"].as_str().is_some_and(|r| r.contains("first pass failed")), "{auto}");
    assert!(auto["first_pass"]["failure"].as_str().is_some_and(|f| f.contains("max_steps")), "{auto}");
}
