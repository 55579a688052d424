//! A `StaticDamped` (Levenberg–Marquardt) step with barrier inter-ply contact: its trial
//! states add contact couplings, so the tangent's pattern grows inside an iteration, and a
//! rejected trial must leave the base state's tangent in the grown pattern (it used to
//! restore the old values and panic in the factorization: "symbolic.row_idx().len() ==
//! val.len()", 26934 against 26925). The trial is limited to the collision-free fraction of
//! the correction like every other update. Reference: the independent intersection check
//! (`contact::intersection`, triangles thickened to prisms, GJK) on every accepted state.

use plyshell::scene;
use plyshell::solver::Solver;

#[test]
fn damped_static_step_with_interply_contact_completes_without_intersections() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("garments/studies/two_ply_flap.ron");
    let shipped = std::fs::read_to_string(&path).expect("the two-ply flap");
    // The flap as shipped (contact off for the study's speed), with its default inter-ply
    // contact on (barrier, μ = 0.3) and the step driven by the damped static Newton.
    let text = shipped.replace("interply: (enabled: false),", "").replace("(name: \"hang\", increments: 8,", "(name: \"hang\", increments: 8, kind: StaticDamped,");
    assert!(text.contains("StaticDamped") && !text.contains("enabled: false"), "scene edits applied");
    let sc = scene::parse("flap.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let built = scene::build(&sc, "flap.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let model = &built.model;
    let parts: Vec<usize> = (0..model.parts.len()).collect();
    let mut state = model.initial_state();
    let (mut overlaps, mut accepted, mut last_residual) = (0usize, 0usize, f64::NAN);
    let mut solver = Solver::new(model, sc.solver.clone()).expect("solver");
    let setup = built.interply.as_ref().expect("inter-ply contact on by default");
    assert!(setup.barrier.is_some(), "the barrier formulation");
    plyshell::contact::interply::attach(&mut solver, model, setup).expect("surface contact attaches");
    solver
        .run(
            &built.steps,
            &mut state,
            &mut |r, s, _| {
                accepted += 1;
                last_residual = r.residuals.last().copied().unwrap_or(f64::NAN);
                overlaps += plyshell::contact::intersection::intersecting_prisms(model, s, &parts, 1.0 - 0.2).len();
            },
            &mut |_| {},
        )
        .unwrap_or_else(|e| panic!("{e}"));
    println!("{accepted} increments, last relative residual {last_residual:.2e}, overlapping prisms {overlaps}");
    assert!(accepted >= 8, "every nominal increment accepted ({accepted})");
    assert!(last_residual <= 1e-7, "last increment converged: relative residual {last_residual:.2e}");
    assert_eq!(overlaps, 0, "no intersecting plies in any accepted state");
}
