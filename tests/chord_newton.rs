//! Chord (modified) Newton (`solver: (chord: Some(()))`): the same equilibrium as full
//! Newton to within the Newton tolerance, on a plate clamped at one edge sagging to nearly
//! vertical under its own weight (the case of `tests/automatic_increments.rs`) and on a
//! clamped plate under large-deflection pressure.

use plyshell::scene;
use plyshell::solver::Solver;

/// Tip displacement (x, z), strain energy and Newton iterations of the sagging plate.
fn sag(chord: &str) -> ([f64; 2], f64, usize) {
    let text = format!(
        r#"Scene(
        name: "sag",
        materials: {{"m": StVenantKirchhoff(young: 2.0e8, poisson: 0.3)}},
        parts: [(name: "plate", mesh: Rectangle(lx: 0.6, ly: 0.6, nx: 10, ny: 10), material: "m", thickness: 0.4e-3, areal_density: 0.12)],
        node_sets: {{"edge": Plane(point: (0.0, 0.0, 0.0), normal: (1.0, 0.0, 0.0))}},
        boundary: [Clamp(set: "edge")],
        loads: {{"weight": Gravity(part: "plate", areal_density: 0.12, g: (0.0, 0.0, -9.81))}},
        steps: [(name: "sag", increments: 10, scale: {{"weight": 1.0}})],
        solver: (chord: {chord}),
    )"#
    );
    let sc = scene::parse("sag.ron", &text).expect("parse");
    let built = scene::build(&sc, "sag.ron", &text).expect("build");
    let tip = built.model.x0.iter().enumerate().min_by(|a, b| {
        let d = |x: &nalgebra::Vector3<f64>| (x - nalgebra::Vector3::new(0.6, 0.3, 0.0)).norm();
        d(a.1).total_cmp(&d(b.1))
    });
    let tip = tip.expect("nodes").0;
    let mut solver = Solver::new(&built.model, sc.solver.clone()).expect("solver");
    let mut state = built.model.initial_state();
    let (mut iterations, mut energy) = (0, 0.0);
    solver
        .run(&built.steps, &mut state, &mut |r, _, _| {
            iterations += r.iterations;
            energy = r.energy;
        }, &mut |_| {})
        .expect("solve");
    ([state.u[tip].x, state.u[tip].z], energy, iterations)
}

#[test]
fn chord_newton_reaches_full_newtons_equilibrium() {
    let (full, e_full, its_full) = sag("None");
    let (chord, e_chord, its_chord) = sag("Some(())");
    eprintln!("full Newton {its_full} iterations, tip {full:?}; chord {its_chord} iterations, tip {chord:?}");
    assert!(full[1] < -0.5, "tip {full:?}");
    for k in 0..2 {
        assert!((chord[k] - full[k]).abs() < 1e-6 * full[k].abs(), "tip {chord:?} vs {full:?}");
    }
    assert!((e_chord - e_full).abs() < 1e-6 * e_full.abs(), "energy {e_chord} vs {e_full}");
}

#[test]
fn chord_settings_are_checked_at_the_field() {
    let text = r#"Scene(
        name: "bad",
        materials: {"m": StVenantKirchhoff(young: 2.0e8, poisson: 0.3)},
        parts: [(name: "plate", mesh: Rectangle(lx: 0.6, ly: 0.6, nx: 2, ny: 2), material: "m", thickness: 0.4e-3)],
        node_sets: {"edge": Plane(point: (0.0, 0.0, 0.0), normal: (1.0, 0.0, 0.0))},
        boundary: [Clamp(set: "edge")],
        loads: {"weight": Gravity(part: "plate", areal_density: 0.12, g: (0.0, 0.0, -9.81))},
        steps: [(name: "sag", increments: 1, scale: {"weight": 1.0})],
        solver: (chord: Some((contraction: 1.5))),
    )"#;
    let sc = scene::parse("bad.ron", text).expect("parse");
    let err = scene::build(&sc, "bad.ron", text).err().expect("refused").to_string();
    assert!(err.contains("solver.chord.contraction"), "{err}");
}
