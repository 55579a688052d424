//! Exact rigid links through the ply stack (issue 5): a three-ply strip stitched at every
//! node column is rolled up into a full circle by an end moment. The stitch links place each
//! ply node at its thickness offset along the master node's current director, so the ply
//! separations must stay at their offsets through a rotation of 2π (a linearised link would
//! drift by about |r| θ²/2, i.e. ≈ 20 link lengths at θ = 2π).
//!
//! Reference: pure bending of an inextensible elastic strip (Euler's elastica; Timoshenko &
//! Gere, *Theory of Elastic Stability*, 1961, §2.7; Sze, Liu & Lo 2004, §3.2 for the shell
//! version): a constant end moment M bends the neutral axis into a circle of radius
//! R = EI/M, so M = 2π EI/L closes it into a full circle (tip back at the root). The plies
//! bonded at every node column act as one section of thickness 3t (parallel-axis theorem),
//! EI = E b (3t)³/12, with the neutral axis in the middle ply.

use nalgebra::Vector3;
use plyshell::{scene, solver::Solver};

const L: f64 = 0.3;
const B: f64 = 0.05;
const T: f64 = 0.0003;
const E: f64 = 1.0e7;

fn scene_text(moment_per_length: f64) -> String {
    let xs: Vec<String> = (0..=48).map(|i| format!(r#"(name: "q{i}", panel: "strip", points: [({x}, 0.0), ({x}, {B})])"#, x = L * i as f64 / 48.0)).collect();
    format!(
        r#"Scene(
    name: "ply_roll_up",
    materials: {{"felt": StVenantKirchhoff(young: {E:e}, poisson: 0.0)}},
    parts: [],
    garment: Some((
        element_size: 0.00625,
        plies: {{"top": (material: "felt", thickness: {T}), "mid": (material: "felt", thickness: {T}), "bot": (material: "felt", thickness: {T})}},
        panels: [(name: "strip", outline: [(0.0, 0.0), ({L}, 0.0), ({L}, {B}), (0.0, {B})],
                  edges: {{"root": (from: 3, to: 0), "tip": (from: 1, to: 2)}},
                  grain: (1.0, 0.0), plies: ["top", "mid", "bot"])],
        stitch_lines: [{lines}],
    )),
    node_sets: {{
        "root_top": Edge(part: "strip/top", edge: "root"), "root_mid": Edge(part: "strip/mid", edge: "root"),
        "root_bot": Edge(part: "strip/bot", edge: "root"), "tip_top": Edge(part: "strip/top", edge: "tip"),
    }},
    boundary: [Clamp(set: "root_top"), Clamp(set: "root_mid"), Clamp(set: "root_bot")],
    loads: {{"m": EdgeMoment(set: "tip_top", moment_per_length: (0.0, {mpl}, 0.0))}},
    steps: [(name: "roll", increments: 40, scale: {{"m": 1.0}})],
    output: (vtu: false),
)"#,
        lines = xs.join(", "),
        mpl = -moment_per_length,
    )
}

#[test]
fn stitched_three_ply_strip_rolls_into_a_circle_with_exact_ply_offsets() {
    let ei = E * B * (3.0 * T).powi(3) / 12.0;
    let m = 2.0 * std::f64::consts::PI * ei / L;
    let text = scene_text(m / B);
    let sc = scene::parse("ply_roll_up.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let built = scene::build(&sc, "ply_roll_up.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let model = &built.model;
    let part = |name: &str| model.parts.iter().find(|p| p.name == name).unwrap_or_else(|| panic!("part {name}"));
    let (top, mid, bot) = (part("strip/top"), part("strip/mid"), part("strip/bot"));
    assert_eq!(top.n_nodes, mid.n_nodes);
    let mut solver = Solver::new(model, sc.solver.clone()).expect("solver");
    let mut state = model.initial_state();
    let mut iterations = 0;
    solver
        .run(&built.steps, &mut state, &mut |rep, _, _| iterations += rep.iterations, &mut |_| {})
        .unwrap_or_else(|e| panic!("{e}"));
    let x = |n: usize| model.position(&state, n);
    // Ply separations: every middle/bottom node sits at its reference offset from the top node
    // of the same pattern point, along the top node's current director.
    let mut worst_len = 0.0_f64;
    let mut worst_dir = 0.0_f64;
    let mut max_rotation = 0.0_f64;
    for i in 0..top.n_nodes {
        let (nt, nm, nb) = (top.first_node + i, mid.first_node + i, bot.first_node + i);
        let d = state.frames[nt].d;
        max_rotation = max_rotation.max(d.dot(&model.frames0[nt].d).clamp(-1.0, 1.0).acos());
        for (ns, z0) in [(nm, -T), (nb, -2.0 * T)] {
            let r = x(ns) - x(nt);
            worst_len = worst_len.max((r.norm() - z0.abs()).abs() / z0.abs());
            worst_dir = worst_dir.max((r - d * z0).norm() / z0.abs());
        }
    }
    // Neutral axis (middle ply) on a circle of radius EI/M = L/(2π); tip back at the root.
    let r_expect = ei / m;
    let mids: Vec<Vector3<f64>> = (0..mid.n_nodes).map(|i| x(mid.first_node + i)).collect();
    let tip_gap = mids
        .iter()
        .zip(0..mid.n_nodes)
        .filter(|&(_, i)| (model.x0[mid.first_node + i].x - L).abs() < 1e-9)
        .map(|(p, i)| {
            let root = model.x0[mid.first_node + i] - Vector3::new(L, 0.0, 0.0);
            (p - root).norm()
        })
        .fold(0.0, f64::max);
    // Circle through the middle ply: centre in the x–z plane from the interior nodes' mean.
    let interior: Vec<&Vector3<f64>> = mids.iter().zip(0..mid.n_nodes).filter(|&(_, i)| model.x0[mid.first_node + i].x < L - 1e-9).map(|(p, _)| p).collect();
    let c = interior.iter().fold(Vector3::zeros(), |s, p| s + **p) / interior.len() as f64;
    let radii: Vec<f64> = interior.iter().map(|p| (p.x - c.x).hypot(p.z - c.z)).collect();
    let r_mean = radii.iter().sum::<f64>() / radii.len() as f64;
    let r_spread = radii.iter().map(|r| (r - r_mean).abs()).fold(0.0, f64::max);
    println!(
        "max rotation {:.1}°, {iterations} Newton iterations; ply separation error {worst_len:.2e} (length), {worst_dir:.2e} (offset vector) of the link; \
         neutral-axis radius {r_mean:.6} vs EI/M {r_expect:.6} ({:+.3} %), spread {:.2e}; tip-to-root gap {tip_gap:.3e} m ({:.3} % of L)",
        max_rotation.to_degrees(),
        100.0 * (r_mean / r_expect - 1.0),
        r_spread / r_expect,
        100.0 * tip_gap / L
    );
    assert!(max_rotation > 179.0_f64.to_radians(), "the strip did not roll through a half turn");
    assert!(worst_len < 0.01 && worst_dir < 0.01, "ply separations drift: {worst_len:.3e}, {worst_dir:.3e}");
    assert!((r_mean / r_expect - 1.0).abs() < 0.01, "radius {r_mean} vs {r_expect}");
    assert!(tip_gap < 0.01 * L, "tip {tip_gap}");
}
