//! Compliant seams (`seams[..].stiffness`, `strength`): stitches as springs of stiffness k
//! per length, reported as force per length, utilisation and opening.
//!
//! Reference (statics, small strain): a strip of two panels joined across its width w by a
//! seam of stitch stiffness k (N/m²), clamped at one end and pulled at the other by a
//! uniform edge force q = F/w (ν = 0, so the stress is uniform σ = q/t): every stitch carries
//! q per length, so the seam opens by q/k, its utilisation is q/strength, and the tip moves
//! by q L/(E t) + q/k.

use plyshell::{analysis, scene};

const L: f64 = 1.0;
const W: f64 = 0.1;
const T: f64 = 0.01;
const E: f64 = 1.0e7;
const Q: f64 = 1000.0;
const K: f64 = 2.0e6;
const STRENGTH: f64 = 4000.0;

fn strip() -> String {
    let part = |name: &str, x0: f64| format!(r#"(name: "{name}", mesh: Rectangle(lx: {h}, ly: {W}, nx: 8, ny: 2), material: "m", thickness: {T}, offset: Some(({x0}, 0.0, 0.0)))"#, h = 0.5 * L);
    format!(
        r#"Scene(
    name: "compliant_strip",
    materials: {{"m": StVenantKirchhoff(young: {E:e}, poisson: 0.0)}},
    parts: [{a}, {b}],
    node_sets: {{"root": Edge(part: "a", edge: "xmin"), "cut_a": Edge(part: "a", edge: "xmax"), "cut_b": Edge(part: "b", edge: "xmin"), "tip": Edge(part: "b", edge: "xmax")}},
    boundary: [Clamp(set: "root"), Fix(set: "tip", dofs: [Uz])],
    loads: {{"p": EdgeForce(set: "tip", force_per_length: ({Q}, 0.0, 0.0))}},
    seams: [(name: "cut", master: "cut_a", slave: "cut_b", kind: Plain, stiffness: Some({K:e}), strength: Some({STRENGTH}))],
    steps: [(name: "pull", increments: 1, linear: true, scale: {{"p": 1.0}})],
    monitors: [(name: "tip", point: ({L}, 0.0, 0.0), part: Some("b"), dofs: [Ux])],
    output: (binary: false),
)"#,
        a = part("a", 0.0),
        b = part("b", 0.5 * L)
    )
}

/// The values of an ASCII VTU cell-data array `name`.
fn vtu_array(text: &str, name: &str) -> Vec<f64> {
    let start = text.find(&format!("Name=\"{name}\"")).unwrap_or_else(|| panic!("no array {name}"));
    let body = &text[start..];
    let open = body.find('>').expect("tag") + 1;
    let close = body.find("</DataArray>").expect("end");
    body[open..close].split_whitespace().map(|v| v.parse().expect("number")).collect()
}

/// Opening = q/k and utilisation = q/strength within 1e-6 relative, in summary.json (mean
/// and max) and on the garment VTU's seam line cells; force per length q across the seam,
/// none along it; the tip moves by q L/(E t) + q/k.
#[test]
fn compliant_seam_opens_by_force_over_stiffness() {
    let text = strip();
    let sc = scene::parse("compliant.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let built = scene::build(&sc, "compliant.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let dir = std::env::temp_dir().join(format!("plyshell_compliant_seam_{}", std::process::id()));
    let summary = analysis::run(&sc, &built, &analysis::RunOptions { out_dir: Some(dir.clone()) }, &mut |_| {}).unwrap_or_else(|e| panic!("{e}"));
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).expect("summary.json")).expect("json");
    let vtu = std::fs::read_to_string(dir.join("compliant_strip_garment_0001.vtu")).expect("garment vtu");
    let _ = std::fs::remove_dir_all(&dir);
    let rel = |a: f64, b: f64| ((a - b) / b).abs();
    let (opening, utilisation) = (Q / K, Q / STRENGTH);
    let s = &json["seams"][0];
    println!("{s}");
    let get = |k: &str| s[k].as_f64().unwrap_or_else(|| panic!("seams[0].{k}"));
    for key in ["opening_mean", "opening_max"] {
        assert!(rel(get(key), opening) < 1e-6, "{key} {} vs q/k {opening}", get(key));
    }
    for key in ["utilisation_mean", "utilisation_max"] {
        assert!(rel(get(key), utilisation) < 1e-6, "{key} {} vs q/strength {utilisation}", get(key));
    }
    for key in ["force_per_length_mean", "force_per_length_max", "across_mean", "across_max"] {
        assert!(rel(get(key), Q) < 1e-6, "{key} {} vs q {Q}", get(key));
    }
    assert!(get("along_max") < 1e-6 * Q, "along {}", get("along_max"));
    // Seam line cells come after the 2 × 16 quads.
    let n_q = 32;
    let open_cells = &vtu_array(&vtu, "seam_opening")[n_q..];
    let util_cells = &vtu_array(&vtu, "seam_utilisation")[n_q..];
    assert_eq!(open_cells.len(), 2);
    for (&o, &u) in open_cells.iter().zip(util_cells) {
        assert!(rel(o, opening) < 1e-6 && rel(u, utilisation) < 1e-6, "VTU line cell: opening {o}, utilisation {u}");
    }
    let tip = summary.monitors[0].values.last().expect("tip")[0];
    let exact = Q * L / (E * T) + Q / K;
    println!("opening {} (q/k {opening}), utilisation {} (q/S {utilisation}), tip {tip:.9e} vs {exact:.9e}", get("opening_max"), get("utilisation_max"));
    assert!(rel(tip, exact) < 1e-6, "tip {tip} vs q L/(E t) + q/k = {exact}");
}

/// A non-positive stiffness and a compliant seam with a closing load are refused with the
/// field and a located line.
#[test]
fn bad_compliant_seams_are_refused() {
    let base = strip();
    let cases = [
        (base.replace(&format!("stiffness: Some({K:e})"), "stiffness: Some(-1.0)"), "seams[cut].stiffness"),
        (base.replace("strength: Some(4000)", "strength: Some(0.0)"), "seams[cut].strength"),
        (base.replace("strength: Some(4000)", "strength: Some(4000), closing: Some(\"sew\")").replace("loads: {", "loads: {\"sew\": Closure, "), "seams[cut].stiffness"),
    ];
    for (text, field) in cases {
        assert_ne!(text, base, "{field}: replacement failed");
        let sc = scene::parse("compliant.ron", &text).unwrap_or_else(|e| panic!("{e}"));
        let err = scene::build(&sc, "compliant.ron", &text).err().unwrap_or_else(|| panic!("{field}: accepted"));
        assert!(err.to_string().contains(field) && err.line > 0, "{err}");
    }
}

/// The same strip as a garment (two panels, one ply, the seam in `garment.seams` with
/// `stiffness` and `strength`): opening q/k and utilisation q/strength within 1e-6, and
/// the tip moves by q L/(E t) + q/k. One linear step, so the garment's surface contact
/// (on by default, refused by a linear step) is off: a flat strip pulled in its plane.
#[test]
fn garment_seam_with_stiffness_is_compliant() {
    let half = 0.5 * L;
    let text = format!(
        r#"Scene(
    name: "compliant_garment",
    materials: {{"m": StVenantKirchhoff(young: {E:e}, poisson: 0.0)}},
    parts: [],
    garment: Some((
        element_size: 0.0125,
        plies: {{"felt": (material: "m", thickness: {T})}},
        panels: [
            (name: "root_half", outline: [(0.0, 0.0), ({half}, 0.0), ({half}, {W}), (0.0, {W})],
             edges: {{"root": (from: 3, to: 0), "joint": (from: 1, to: 2)}}, grain: (1.0, 0.0), plies: ["felt"]),
            (name: "tip_half", outline: [({half}, 0.0), ({L}, 0.0), ({L}, {W}), ({half}, {W})],
             edges: {{"joint": (from: 3, to: 0), "tip": (from: 1, to: 2)}}, grain: (1.0, 0.0), plies: ["felt"]),
        ],
        seams: [(name: "joint", a: (panel: "root_half", edge: "joint"), b: (panel: "tip_half", edge: "joint", reversed: true), kind: Plain,
                 stiffness: Some({K:e}), strength: Some({STRENGTH}))],
        interply: (enabled: false),
    )),
    node_sets: {{"root": Edge(part: "root_half", edge: "root"), "tip": Edge(part: "tip_half", edge: "tip")}},
    boundary: [Clamp(set: "root"), Fix(set: "tip", dofs: [Uz])],
    loads: {{"p": EdgeForce(set: "tip", force_per_length: ({Q}, 0.0, 0.0))}},
    steps: [(name: "pull", increments: 1, linear: true, scale: {{"p": 1.0}})],
    monitors: [(name: "tip", point: ({L}, 0.0, 0.0), part: Some("tip_half"), dofs: [Ux])],
    output: (vtu: false),
)"#
    );
    let sc = scene::parse("compliant_garment.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let built = scene::build(&sc, "compliant_garment.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let summary = analysis::run(&sc, &built, &Default::default(), &mut |_| {}).unwrap_or_else(|e| panic!("{e}"));
    let s = &summary.extra["seams"][0];
    let rel = |a: f64, b: f64| ((a - b) / b).abs();
    let (o, u) = (s["opening_mean"].as_f64().expect("opening"), s["utilisation_max"].as_f64().expect("utilisation"));
    let tip = summary.monitors[0].values.last().expect("tip")[0];
    let exact = Q * L / (E * T) + Q / K;
    println!("garment seam: opening {o:.9e} (q/k {:.9e}), utilisation {u:.9} (q/S {}), tip {tip:.9e} vs {exact:.9e}", Q / K, Q / STRENGTH);
    assert!(s["compliant"].as_bool() == Some(true));
    assert!(rel(o, Q / K) < 1e-6 && rel(u, Q / STRENGTH) < 1e-6);
    assert!(rel(tip, exact) < 1e-6, "tip {tip} vs {exact}");
}
