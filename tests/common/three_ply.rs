//! The three-ply cantilever shared by `tests/interply.rs` and `tests/ply_auto.rs`: a 0.1 m ×
//! 0.02 m strip of three 1 mm SVK plies (E 2e7, 1e8, 2e8 Pa, ν = 0), each clamped at its root
//! and hanging under its own weight, quilted by stitch lines across the strip.
//! (`#[path = "common/three_ply.rs"] mod three_ply;` in each.)

pub const L: f64 = 0.1;
pub const B: f64 = 0.02;
pub const T: f64 = 0.001;
pub const E: [f64; 3] = [2.0e7, 1.0e8, 2.0e8];
pub const RHO: f64 = 0.3;
pub const G: f64 = 9.81;
pub const H: f64 = 0.005;

/// The cantilever's scene, quilted by a stitch line across the strip at each of `stitch_xs`,
/// with the panel's `ply_model` when given (else the garment default, discrete plies).
pub fn cantilever(stitch_xs: &[f64], ply_model: Option<&str>) -> String {
    let lines: Vec<String> = stitch_xs
        .iter()
        .enumerate()
        .map(|(i, x)| format!(r#"(name: "q{i}", panel: "strip", points: [({x}, 0.0), ({x}, {B})])"#))
        .collect();
    format!(
        r#"Scene(
    name: "three_ply_cantilever",
    materials: {{"soft": StVenantKirchhoff(young: {e0:e}, poisson: 0.0), "mid": StVenantKirchhoff(young: {e1:e}, poisson: 0.0), "stiff": StVenantKirchhoff(young: {e2:e}, poisson: 0.0)}},
    parts: [],
    garment: Some((
        element_size: {H},
        plies: {{"top": (material: "soft", thickness: {T}, areal_density: {RHO}), "mid": (material: "mid", thickness: {T}, areal_density: {RHO}), "bot": (material: "stiff", thickness: {T}, areal_density: {RHO})}},
        panels: [(name: "strip", outline: [(0.0, 0.0), ({L}, 0.0), ({L}, {B}), (0.0, {B})],
                  edges: {{"root": (from: 3, to: 0), "tip": (from: 1, to: 2)}},
                  grain: (1.0, 0.0), plies: ["top", "mid", "bot"]{model})],
        stitch_lines: [{lines}],
        interply: (enabled: true, friction: 0.3),
    )),
    node_sets: {{"root_top": Edge(part: "strip/top", edge: "root"), "root_mid": Edge(part: "strip/mid", edge: "root"), "root_bot": Edge(part: "strip/bot", edge: "root")}},
    boundary: [Clamp(set: "root_top"), Clamp(set: "root_mid"), Clamp(set: "root_bot")],
    loads: {{"g1": Gravity(part: "strip/top", areal_density: {RHO}, g: (0.0, 0.0, -{G})), "g2": Gravity(part: "strip/mid", areal_density: {RHO}, g: (0.0, 0.0, -{G})), "g3": Gravity(part: "strip/bot", areal_density: {RHO}, g: (0.0, 0.0, -{G}))}},
    steps: [(name: "load", increments: 2, scale: {{"g1": 1.0, "g2": 1.0, "g3": 1.0}})],
    monitors: [(name: "tip", point: ({L}, 0.0, 0.0), part: Some("strip/mid"), dofs: [Uz])],
    output: (vtu: false),
)"#,
        e0 = E[0],
        e1 = E[1],
        e2 = E[2],
        lines = lines.join(", "),
        model = ply_model.map(|m| format!(", ply_model: Some({m})")).unwrap_or_default(),
    )
}
