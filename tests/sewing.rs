//! Virtual sewing (issue 5): a flat panel rolled onto a cylinder with a gap is sewn shut by a
//! seam whose tie offset drives the gap to zero over the first step.
//!
//! Reference: the closed configuration is exact by construction of the tie (gap offset
//! −g₀·λ with λ → 1), so every seam gap must fall to round-off; the acceptance bound
//! is 1e-6 of the panel size. The closed sleeve's circumference is the pattern width W,
//! so its mean radius must approach W/(2π) (isometric closure, small membrane strain).

use plyshell::scene;
use plyshell::solver::Solver;

#[test]
fn sewing_closes_the_sleeve() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/garments/sleeve.ron");
    let text = std::fs::read_to_string(path).expect("garments/sleeve.ron");
    let sc = scene::parse("sleeve.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let built = scene::build(&sc, "sleeve.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    assert!(built.warnings.is_empty(), "{:?}", built.warnings);
    let model = &built.model;
    let seam = &built.seams[0];
    let size = 0.40_f64.max(0.3581415625);
    let gap0 = seam.gaps(|n| model.x0[n]).into_iter().fold(0.0, f64::max);
    println!("nodes {} elements {} equations {} ties {}", model.n_nodes(), model.elements.len(), model.dofs.n_free, model.dofs.ties.len());
    assert!(gap0 > 0.01, "initial gap {gap0}");
    let mut solver = Solver::new(model, sc.solver.clone()).expect("solver");
    let mut state = model.initial_state();
    let sew_only = &built.steps[..1];
    let t = std::time::Instant::now();
    solver.run(sew_only, &mut state, &mut |_, _, _| {}, &mut |_| {}).unwrap_or_else(|e| panic!("{e}"));
    let gaps = seam.gaps(|n| model.position(&state, n));
    let worst = gaps.iter().copied().fold(0.0, f64::max);
    println!("sewing: initial gap {gap0:.4e} m, final worst gap {worst:.3e} m ({:.2e} of the panel size), {:.2} s", worst / size, t.elapsed().as_secs_f64());
    assert!(worst < 1e-6 * size, "{worst}");
    // Mean radius about the axis of the sewn sleeve at its mid-height row ≈ W/(2π) (0.5 %).
    let w = 0.3581415625;
    let ring: Vec<usize> = (0..model.n_nodes()).filter(|&n| (model.x0[n].z - 0.2).abs() < 1e-9).collect();
    let c = ring.iter().map(|&n| model.position(&state, n)).sum::<nalgebra::Vector3<f64>>() / ring.len() as f64;
    let r_mean = ring.iter().map(|&n| { let p = model.position(&state, n) - c; p.x.hypot(p.y) }).sum::<f64>() / ring.len() as f64;
    let r_expect = w / (2.0 * std::f64::consts::PI);
    println!("mean radius {r_mean:.6} vs W/2π {r_expect:.6}");
    assert!((r_mean - r_expect).abs() < 5e-3 * r_expect);
}

#[test]
fn sewn_sleeve_hangs_under_gravity() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/garments/sleeve.ron");
    let text = std::fs::read_to_string(path).expect("garments/sleeve.ron");
    let sc = scene::parse("sleeve.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let built = scene::build(&sc, "sleeve.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let summary = plyshell::analysis::run(&sc, &built, &Default::default(), &mut |_| {}).unwrap_or_else(|e| panic!("{e}"));
    println!("{} increments, {} Newton iterations, {:.2} s", summary.increments.len(), summary.newton_iterations, summary.wall_s);
    assert_eq!(summary.increments.len(), 14);
}
