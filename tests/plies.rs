//! Plies and stitch lines (issue 5): each ply of a panel is its own shell mesh offset
//! through the stack; stitch lines (quilting) join the plies rigidly through the thickness.
//!
//! References (Euler–Bernoulli cantilever, tip load P, length L, Timoshenko & Gere): three
//! unbonded plies of thickness t bend independently, w = P L³ / (3 E · 3 I₁) with
//! I₁ = b t³/12; fully bonded they act as one section of thickness 3t,
//! I = b (3t)³/12 = 27 I₁ (3 I₁ own + 2 · b t · t² parallel-axis), w = P L³ / (3 E · 27 I₁) —
//! nine times stiffer. Quilting at intervals lies in between.
//!
//! The strips are solved in one linear step with the garment's surface contact off
//! (`interply: (enabled: false)`; it is on by default, and a linear step refuses it): equal
//! plies under equal loads press on each other with no force, and a linear step is a single
//! update, which the barrier's collision detection would shorten (to 12 % of the unbonded tip
//! deflection here, before the refusal).

use plyshell::{analysis, scene};

const L: f64 = 0.3;
const B: f64 = 0.05;
const T: f64 = 0.001;
const E: f64 = 1.0e7;
const P: f64 = 1.0e-3;

fn strip(stitch_xs: &[f64]) -> String {
    let lines: Vec<String> = stitch_xs
        .iter()
        .enumerate()
        .map(|(i, x)| format!(r#"(name: "q{i}", panel: "strip", points: [({x}, 0.0), ({x}, {B})])"#))
        .collect();
    let ply_sets: Vec<String> = ["top", "mid", "bot"]
        .iter()
        .map(|p| format!(r#""root_{p}": Edge(part: "strip/{p}", edge: "root"), "tip_{p}": Edge(part: "strip/{p}", edge: "tip")"#))
        .collect();
    let q = P / 3.0 / B;
    format!(
        r#"Scene(
    name: "plies",
    materials: {{"felt": StVenantKirchhoff(young: {E:e}, poisson: 0.0)}},
    parts: [],
    garment: Some((
        element_size: 0.0125,
        plies: {{"top": (material: "felt", thickness: {T}), "mid": (material: "felt", thickness: {T}), "bot": (material: "felt", thickness: {T})}},
        panels: [(name: "strip", outline: [(0.0, 0.0), ({L}, 0.0), ({L}, {B}), (0.0, {B})],
                  edges: {{"root": (from: 3, to: 0), "tip": (from: 1, to: 2)}},
                  grain: (1.0, 0.0), plies: ["top", "mid", "bot"])],
        stitch_lines: [{lines}],
        interply: (enabled: false),
    )),
    node_sets: {{{sets}}},
    boundary: [Clamp(set: "root_top"), Clamp(set: "root_mid"), Clamp(set: "root_bot")],
    loads: {{"p": EdgeForce(set: "tip_top", force_per_length: (0.0, 0.0, {q})), "p2": EdgeForce(set: "tip_mid", force_per_length: (0.0, 0.0, {q})), "p3": EdgeForce(set: "tip_bot", force_per_length: (0.0, 0.0, {q}))}},
    steps: [(name: "load", increments: 1, linear: true, scale: {{"p": 1.0, "p2": 1.0, "p3": 1.0}})],
    monitors: [(name: "tip", point: ({L}, 0.0, 0.0), part: Some("strip/mid"), dofs: [Uz])],
    output: (vtu: false),
)"#,
        lines = lines.join(", "),
        sets = ply_sets.join(", "),
    )
}

fn tip(stitch_xs: &[f64]) -> f64 {
    let text = strip(stitch_xs);
    let sc = scene::parse("plies.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let built = scene::build(&sc, "plies.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let s = analysis::run(&sc, &built, &Default::default(), &mut |_| {}).unwrap_or_else(|e| panic!("{e}"));
    s.monitors[0].values.last().map_or(f64::NAN, |v| v[0])
}

#[test]
fn stitch_lines_bond_the_plies() {
    let i1 = B * T.powi(3) / 12.0;
    let unbonded = P * L.powi(3) / (3.0 * E * 3.0 * i1);
    let bonded = P * L.powi(3) / (3.0 * E * 27.0 * i1);
    // No stitch line: three independent plies (1 %).
    let w0 = tip(&[]);
    println!("unbonded: {w0:.6e} vs {unbonded:.6e} ({:+.3} %)", 100.0 * (w0 / unbonded - 1.0));
    assert!((w0 / unbonded - 1.0).abs() < 1e-2);
    // A stitch line through every node column (element size 0.0125): full bond (2 %).
    let all: Vec<f64> = (1..=24).map(|i| i as f64 * 0.0125).collect();
    let w_all = tip(&all);
    println!("fully stitched: {w_all:.6e} vs {bonded:.6e} ({:+.3} %)", 100.0 * (w_all / bonded - 1.0));
    assert!((w_all / bonded - 1.0).abs() < 2e-2);
    // Quilting every 5 cm: measurably stiffer than unbonded, not stiffer than full bond.
    let w_q = tip(&[0.05, 0.1, 0.15, 0.2, 0.25, 0.3]);
    println!("quilted every 5 cm: {w_q:.6e}, stiffening ×{:.2} (full bond ×{:.2})", w0 / w_q, w0 / w_all);
    assert!(w0 / w_q > 1.5 && w_q >= w_all * (1.0 - 1e-9));
}

/// Issue 18: a seam between panels connects the laminated shell. The same cantilever cut at
/// mid-span into a discrete root half (three plies stitched at every node column: bonded)
/// and a laminated tip half (`ply_model: Some(Laminate)`), joined by a welded seam (the
/// laminate tied to the root half's outermost ply, whose stack is linked along the seam),
/// deflects as the fully bonded section, w = P L³ / (3 E · 27 I₁), within 2 % (the bound of
/// the fully stitched discrete strip above; the tie at the outer ply's offset, not the
/// stack's mid-surface, is the modelling error at the joint).
#[test]
fn welded_seam_joins_a_laminated_half_to_a_stitched_half() {
    let h = 0.0125;
    let lines: Vec<String> = (1..=12).map(|i| format!(r#"(name: "q{i}", panel: "root_half", points: [({x}, 0.0), ({x}, {B})])"#, x = i as f64 * h)).collect();
    let half = 0.5 * L;
    let text = format!(
        r#"Scene(
    name: "mixed",
    materials: {{"felt": StVenantKirchhoff(young: {E:e}, poisson: 0.0)}},
    parts: [],
    garment: Some((
        element_size: {h},
        plies: {{"top": (material: "felt", thickness: {T}), "mid": (material: "felt", thickness: {T}), "bot": (material: "felt", thickness: {T})}},
        panels: [
            (name: "root_half", outline: [(0.0, 0.0), ({half}, 0.0), ({half}, {B}), (0.0, {B})],
             edges: {{"root": (from: 3, to: 0), "joint": (from: 1, to: 2)}}, grain: (1.0, 0.0), plies: ["top", "mid", "bot"]),
            (name: "tip_half", outline: [({half}, 0.0), ({L}, 0.0), ({L}, {B}), ({half}, {B})],
             edges: {{"joint": (from: 3, to: 0), "tip": (from: 1, to: 2)}}, grain: (1.0, 0.0), plies: ["top", "mid", "bot"], ply_model: Some(Laminate)),
        ],
        seams: [(name: "joint", a: (panel: "root_half", edge: "joint"), b: (panel: "tip_half", edge: "joint", reversed: true), kind: Welded)],
        stitch_lines: [{lines}],
        interply: (enabled: false),
    )),
    node_sets: {{"root_top": Edge(part: "root_half/top", edge: "root"), "root_mid": Edge(part: "root_half/mid", edge: "root"), "root_bot": Edge(part: "root_half/bot", edge: "root"), "tip": Edge(part: "tip_half", edge: "tip")}},
    boundary: [Clamp(set: "root_top"), Clamp(set: "root_mid"), Clamp(set: "root_bot")],
    loads: {{"p": EdgeForce(set: "tip", force_per_length: (0.0, 0.0, {q}))}},
    steps: [(name: "load", increments: 1, linear: true, scale: {{"p": 1.0}})],
    monitors: [(name: "tip", point: ({L}, 0.0, 0.0), part: Some("tip_half"), dofs: [Uz])],
    output: (vtu: false),
)"#,
        lines = lines.join(", "),
        q = P / B,
    );
    let sc = scene::parse("mixed.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let built = scene::build(&sc, "mixed.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let names: Vec<&str> = built.model.parts.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["root_half/top", "root_half/mid", "root_half/bot", "tip_half"]);
    let s = analysis::run(&sc, &built, &Default::default(), &mut |_| {}).unwrap_or_else(|e| panic!("{e}"));
    let w = s.monitors[0].values.last().map_or(f64::NAN, |v| v[0]);
    let bonded = P * L.powi(3) / (3.0 * E * 27.0 * B * T.powi(3) / 12.0);
    println!("discrete root half + laminated tip half: {w:.6e} vs bonded {bonded:.6e} ({:+.3} %)", 100.0 * (w / bonded - 1.0));
    assert!((w / bonded - 1.0).abs() < 2e-2, "{w} vs {bonded}");
}
