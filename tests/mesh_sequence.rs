//! Mesh sequencing (`Dynamic((coarse_levels: L))`, `analysis_sequence`): the prolongation
//! reproduces affine states exactly, and a sequenced drop of the sheet onto the sphere rests
//! with the vertical contact resultant equal to the weight.

use nalgebra::{Rotation3, Vector3};
use plyshell::element::DirectorFrame;
use plyshell::model::prolong::{prolong, GridPart};
use plyshell::scene;

fn sheet(n: usize, levels: usize) -> String {
    format!(
        r#"Scene(
    name: "sheet_on_sphere",
    output: (vtu: false),
    materials: {{"cloth": StVenantKirchhoff(young: 1.5128e6, poisson: 0.3)}},
    parts: [(name: "sheet", mesh: Rectangle(lx: 0.8, ly: 0.8, nx: {n}, ny: {n}), material: "cloth", thickness: 3.3045e-4, areal_density: 0.15)],
    loads: {{"weight": Gravity(part: "sheet", areal_density: 0.15, g: (0.0, 0.0, -9.81))}},
    steps: [(name: "fall", increments: 1, scale: {{"weight": 1.0}}, kind: Dynamic((coarse_levels: {levels})))],
    contact: Some((formulation: Barrier(),
        bodies: [
            (name: "ball", shape: Sphere(radius: 0.2), translation: (0.4, 0.4, -0.2503), friction: 0.4),
            (name: "ground", shape: Plane, translation: (0.0, 0.0, -0.4503), friction: 0.4),
        ],
    )),
)"#
    )
}

fn built(text: &str) -> (scene::Scene, scene::BuiltScene) {
    let sc = scene::parse("seq.ron", text).unwrap_or_else(|e| panic!("{e}"));
    let b = scene::build(&sc, "seq.ron", text).unwrap_or_else(|e| panic!("{e}"));
    (sc, b)
}

/// An affine deformation x = A X + c with a rotated director field maps without change:
/// every fine node gets A X + c and the rotated director (to round-off).
#[test]
fn prolongation_reproduces_affine_states() {
    let (_, coarse) = built(&sheet(4, 0));
    let (_, fine) = built(&sheet(8, 0));
    let a = nalgebra::Matrix3::new(1.1, 0.2, 0.0, -0.1, 0.9, 0.0, 0.3, 0.05, 1.0);
    let c = Vector3::new(0.01, -0.02, 0.3);
    let rot = Rotation3::from_euler_angles(0.3, -0.2, 0.1);
    let affine = |m: &plyshell::model::Model| {
        let mut s = m.initial_state();
        for n in 0..m.n_nodes() {
            s.u[n] = a * m.x0[n] + c - m.x0[n];
            s.frames[n] = DirectorFrame::new(rot * m.frames0[n].d, Some(rot * m.frames0[n].t1));
        }
        s
    };
    let pairs = [(GridPart { part: 0, nx: 4, ny: 4 }, GridPart { part: 0, nx: 8, ny: 8 })];
    let (mapped, _) = prolong(&coarse.model, &affine(&coarse.model), &fine.model, &pairs).unwrap_or_else(|e| panic!("{e}"));
    let exact = affine(&fine.model);
    for n in 0..fine.model.n_nodes() {
        assert!((mapped.u[n] - exact.u[n]).norm() < 1e-14, "node {n}: {} vs {}", mapped.u[n], exact.u[n]);
        assert!((mapped.frames[n].d - exact.frames[n].d).norm() < 1e-14, "node {n} director");
    }
    // The flat reference state maps onto the fine reference state.
    let (flat, _) = prolong(&coarse.model, &coarse.model.initial_state(), &fine.model, &pairs).unwrap_or_else(|e| panic!("{e}"));
    for n in 0..fine.model.n_nodes() {
        assert!(flat.u[n].norm() < 1e-15 && (flat.frames[n].d - fine.model.frames0[n].d).norm() < 1e-15);
    }
}

/// The 0.8 m SVK sheet dropped onto the sphere (`bench::drive`), 32×32 sequenced from 16×16
/// (`coarse_levels: 1`): the coarse rest state maps onto the fine mesh with no face on or
/// inside a body, and the fine step comes to a stable rest with the vertical contact
/// resultant equal to the weight ρ_A g A within 10⁻³ (static equilibrium).
#[test]
fn sequenced_drop_rests_with_the_weight_on_the_bodies() {
    let text = sheet(32, 1);
    let (sc, b) = built(&text);
    let s = plyshell::analysis::run(&sc, &b, &Default::default(), &mut |_| {}).unwrap_or_else(|e| panic!("{e}"));
    let seq = &s.extra["sequence"];
    assert_eq!(seq["levels"][0]["mesh"], "16x16");
    let min_gap = seq["mapping"]["min_gap_m"].as_f64().expect("min gap");
    assert!(min_gap > 0.0, "a mapped face starts on or inside a body: gap {min_gap:e}");
    let last = s.increments.last().expect("increments");
    assert!(last.dynamics.as_ref().is_some_and(|d| d.at_rest), "not at rest");
    let rz = last.extra.iter().rev().find_map(|v| v.get("contact")?.get("resultant")?.get(2)?.as_f64()).expect("contact resultant");
    let weight = 0.15 * 0.64 * 9.81;
    assert!(((rz - weight) / weight).abs() < 1e-3, "vertical resultant {rz} N vs weight {weight} N");
    println!(
        "16² {} time steps / {} Newton iterations, mapped static residual {:.3e}, then 32² {} / {}",
        seq["levels"][0]["time_steps"], seq["levels"][0]["newton_iterations"], seq["mapping"]["static_residual"].as_f64().unwrap_or(f64::NAN), s.increments.len(), s.newton_iterations
    );
}

/// Values mesh sequencing cannot honour are refused at the step's `coarse_levels`, with the
/// field named and the reason: too many halvings, a later step, a mesh that is not a grid.
#[test]
fn bad_coarse_levels_are_located() {
    let err = |text: &str| {
        let sc = scene::parse("seq.ron", text).unwrap_or_else(|e| panic!("{e}"));
        match scene::build(&sc, "seq.ron", text) {
            Ok(_) => panic!("accepted"),
            Err(e) => e,
        }
    };
    let e = err(&sheet(16, 4));
    assert_eq!(e.field, "steps[fall].kind.coarse_levels");
    assert!(e.line > 0 && e.message.contains("fewer than 2 elements per side"), "{e}");
    let two = sheet(16, 0).replace(
        r#"kind: Dynamic((coarse_levels: 0)))]"#,
        r#"kind: Dynamic(())), (name: "again", increments: 1, scale: {"weight": 1.0}, kind: Dynamic((coarse_levels: 1)))]"#,
    );
    let e = err(&two);
    assert_eq!(e.field, "steps[again].kind.coarse_levels");
    assert!(e.message.contains("only the first step"), "{e}");
    let tube = sheet(16, 1).replace("Rectangle(lx: 0.8, ly: 0.8, nx: 16, ny: 16)", "CylindricalPanel(radius: 0.2, length: 0.8, theta0: 0.0, theta1: 90.0, n_axial: 16, n_circ: 16)");
    let e = err(&tube);
    assert!(e.message.contains("Rectangle grids only"), "{e}");
    let e = err(&sheet(16, 1).replace("kind: Dynamic((coarse_levels: 1))", "kind: Dynamic((coarse_levels: 1, duration: 0.1))"));
    assert!(e.message.contains("steps to rest"), "{e}");
}
