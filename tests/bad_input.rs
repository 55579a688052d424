//! Bad input gets a clear error naming the file, line, column and field, never a panic.

use plyshell::scene;

const GOOD: &str = r#"Scene(
    name: "strip",
    materials: {"steel": StVenantKirchhoff(young: 1.0e6, poisson: 0.3)},
    parts: [(name: "strip", mesh: Rectangle(lx: 1.0, ly: 0.1, nx: 4, ny: 1), material: "steel", thickness: 0.01)],
    node_sets: {"root": Edge(part: "strip", edge: "xmin"), "tip": Edge(part: "strip", edge: "xmax")},
    boundary: [Clamp(set: "root")],
    loads: {"pull": TotalForce(set: "tip", force: (1.0, 0.0, 0.0))},
    steps: [(name: "load", increments: 1, scale: {"pull": 1.0})],
)"#;

fn error_of(text: &str) -> scene::SceneError {
    let parsed = scene::parse("bad.ron", text);
    match parsed {
        Err(e) => e,
        Ok(s) => scene::build(&s, "bad.ron", text).expect_err("the scene should be rejected"),
    }
}

fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).expect("needle in text") + 1
}

#[test]
fn the_good_scene_builds() {
    let s = scene::parse("good.ron", GOOD).expect("parse");
    scene::build(&s, "good.ron", GOOD).expect("build");
}

#[test]
fn malformed_ron_names_line_and_column() {
    let text = GOOD.replace("thickness: 0.01)", "thickness: 0.01");
    let e = error_of(&text);
    assert_eq!(e.file, "bad.ron");
    assert!(e.line > 0 && e.column > 0, "{e}");
    let text = GOOD.replace("young: 1.0e6", "young: \"stiff\"");
    let e = error_of(&text);
    assert_eq!(e.line, line_of(&text, "stiff"), "{e}");
    assert!(e.to_string().starts_with("bad.ron:3:"), "{e}");
}

#[test]
fn unknown_material_is_named_with_its_position() {
    let text = GOOD.replace("material: \"steel\"", "material: \"steal\"");
    let e = error_of(&text);
    assert_eq!(e.field, "parts[strip].material");
    assert!(e.message.contains("unknown material \"steal\"") && e.message.contains("steel"), "{e}");
    assert_eq!(e.line, line_of(&text, "steal"));
    assert!(e.column > 0);
}

#[test]
fn selector_that_selects_nothing_is_rejected() {
    let text = GOOD.replace("\"tip\": Edge(part: \"strip\", edge: \"xmax\")", "\"tip\": Box(min: (5.0, 5.0, 5.0), max: (6.0, 6.0, 6.0))");
    let e = error_of(&text);
    assert_eq!(e.field, "node_sets[tip]");
    assert!(e.message.contains("selects no node"), "{e}");
    assert_eq!(e.line, line_of(&text, "Box(min"));
}

#[test]
fn negative_thickness_is_rejected_at_the_field() {
    let text = GOOD.replace("thickness: 0.01", "thickness: -0.01");
    let e = error_of(&text);
    assert_eq!(e.field, "parts[strip].thickness");
    assert!(e.message.contains("positive thickness"), "{e}");
    let line = line_of(&text, "thickness: -0.01");
    assert_eq!(e.line, line);
    assert_eq!(e.column, text.lines().nth(line - 1).and_then(|l| l.find("thickness")).map(|c| c + 1).expect("column"));
}

#[test]
fn load_on_a_missing_set_names_the_load_and_the_set() {
    let text = GOOD.replace("TotalForce(set: \"tip\"", "TotalForce(set: \"end\"");
    let e = error_of(&text);
    assert_eq!(e.field, "loads[pull].set");
    assert!(e.message.contains("no node set named \"end\"") && e.message.contains("root"), "{e}");
    assert_eq!(e.line, line_of(&text, "set: \"end\""));
}

#[test]
fn unknown_field_and_bad_enum_are_syntax_errors_with_position() {
    let text = GOOD.replace("thickness: 0.01", "thicknes: 0.01");
    let e = error_of(&text);
    assert!(e.message.contains("thicknes"), "{e}");
    assert_eq!(e.line, line_of(&text, "thicknes:"));
    let text = GOOD.replace("Clamp(set", "Glue(set");
    let e = error_of(&text);
    assert!(e.message.contains("Glue"), "{e}");
}

#[test]
fn missing_scene_file_is_an_error_not_a_panic() {
    let e = scene::load(std::path::Path::new("garments/does_not_exist.ron")).expect_err("missing file");
    assert!(e.to_string().contains("does_not_exist.ron"));
}

// ---- Issue 16: no input may crash, hang or exhaust the machine (own triggers). ----

use std::time::{Duration, Instant};

/// The error of `text`, which must come within `limit` (no hang).
fn quick_error_of(text: &str, limit: Duration) -> scene::SceneError {
    let t = Instant::now();
    let e = error_of(text);
    assert!(t.elapsed() < limit, "took {:?}: {e}", t.elapsed());
    e
}

#[test]
fn huge_grid_counts_are_refused_by_the_budget_before_allocating() {
    // 80 000 × 70 000 quads: far beyond any memory, below the old 1e8-node limit only in count.
    let text = GOOD.replace("nx: 4, ny: 1", "nx: 80000, ny: 70000");
    let e = quick_error_of(&text, Duration::from_secs(2));
    assert_eq!(e.field, "parts[strip].mesh", "{e}");
    assert!(e.message.contains("nx × ny") && e.message.contains("memory budget") && e.message.contains("nodes"), "{e}");
    assert_eq!(e.line, line_of(&text, "nx: 80000"));
}

#[test]
fn a_count_of_two_to_the_64_minus_one_is_an_error_not_a_wrap() {
    for repl in ["nx: 18446744073709551615, ny: 1", "nx: 4, ny: 18446744073709551615", "nx: 9223372036854775808, ny: 2"] {
        let text = GOOD.replace("nx: 4, ny: 1", repl);
        let e = quick_error_of(&text, Duration::from_secs(2));
        assert_eq!(e.field, "parts[strip].mesh", "{repl}: {e}");
        assert!(e.line > 0, "{e}");
    }
    // The generator alone (library use) refuses it too.
    let e = plyshell::mesh::rectangle(1.0, 1.0, 3, usize::MAX).expect_err("too large");
    assert!(e.to_string().contains("too large"), "{e}");
}

#[test]
fn cylinder_and_annulus_counts_beyond_the_budget_name_their_fields() {
    let cyl = GOOD.replace(
        "Rectangle(lx: 1.0, ly: 0.1, nx: 4, ny: 1)",
        "CylindricalPanel(radius: 1.0, length: 1.0, theta0: 0.0, theta1: 90.0, n_axial: 5000, n_circ: 60000)",
    );
    let e = quick_error_of(&cyl, Duration::from_secs(2));
    assert!(e.field == "parts[strip].mesh" && e.message.contains("n_axial × n_circ") && e.message.contains("memory budget"), "{e}");
    // A focused annulus of 2^32 + 1 sectors: the ring march stops at the node limit.
    let ann = GOOD.replace(
        "Rectangle(lx: 1.0, ly: 0.1, nx: 4, ny: 1)",
        "FocusedAnnulus(ri: 0.02, ro: 0.15, ntheta: 4294967297, focus: 0.09, refine: 8.0)",
    );
    let e = quick_error_of(&ann, Duration::from_secs(5));
    assert_eq!(e.field, "parts[strip].mesh", "{e}");
    assert!(e.message.contains("ntheta"), "{e}");
}

#[test]
fn type_mismatches_name_the_field_and_what_was_expected() {
    let cases = [
        ("increments: 1", "increments: 2.5", "increments", "expected an integer, found 2.5"),
        ("increments: 1", "increments: 1e400", "increments", "expected an integer, found 1e400"),
        ("increments: 1", "increments: -1", "increments", "found -1"),
        ("nx: 4", "nx: 4.5", "nx", "expected an integer, found 4.5"),
        ("thickness: 0.01", "thickness: \"thin\"", "thickness", "expected a number, found \"thin\""),
    ];
    for (from, to, field, msg) in cases {
        let text = GOOD.replace(from, to);
        let e = error_of(&text);
        assert!(e.field.ends_with(field) && e.message.contains(msg), "{to}: {e}");
        assert_eq!(e.line, line_of(&text, to), "{e}");
    }
}

#[test]
fn non_finite_vectors_are_rejected_at_their_field() {
    let text = GOOD.replace("force: (1.0, 0.0, 0.0)", "force: (1.0, 1e999, 0.0)");
    let e = error_of(&text);
    assert_eq!(e.field, "loads[pull].force", "{e}");
    assert_eq!(e.line, line_of(&text, "1e999"));
}

#[test]
fn a_byte_order_mark_is_accepted_and_bad_utf8_is_located() {
    let text = format!("\u{feff}{GOOD}");
    let s = scene::parse("bom.ron", &text).expect("a BOM is accepted");
    scene::build(&s, "bom.ron", &text).expect("and the scene builds");
    let mut bytes = GOOD.as_bytes().to_vec();
    let at = GOOD.find("steel").expect("steel") + 2;
    bytes[at] = 0xff;
    let e = scene::decode("bad.ron", bytes).expect_err("invalid UTF-8");
    assert_eq!((e.line, e.column), (3, GOOD.lines().nth(2).and_then(|l| l.find("steel")).expect("col") + 3), "{e}");
    assert!(e.message.contains(&format!("byte offset {at}")) && e.message.contains("0xff"), "{e}");
}

#[test]
fn names_with_quotes_or_control_characters_are_printed_escaped_at_their_position() {
    for (written, shown) in [(r#""ti\"p""#, r#""ti\"p""#), (r#""ti\u{0}p""#, r#""ti\0p""#), ("\"ti\u{1b}p\"", r#""ti\u{1b}p""#)] {
        let text = GOOD.replace("\"tip\": Edge", &format!("{written}: Edge")).replace("set: \"tip\"", &format!("set: {written}"));
        let e = error_of(&text);
        assert!(e.message.contains(shown), "{written}: {e}");
        assert_eq!(e.line, line_of(&text, &format!("{written}: Edge")), "{e}");
        assert!(e.column > 0);
        assert!(!e.to_string().contains(|c: char| c.is_control()), "{e:?}");
    }
}

#[test]
fn a_monitor_recording_nothing_is_rejected_by_check() {
    let text = GOOD.replace(
        "steps: [",
        "monitors: [(name: \"tip\", point: (1.0, 0.0, 0.0), dofs: [])],\n    steps: [",
    );
    let e = error_of(&text);
    assert_eq!(e.field, "monitors[tip].dofs", "{e}");
    assert_eq!(e.line, line_of(&text, "dofs: []"));
}

/// A one-panel garment scene with `panel` as its outline and element size `h`.
fn garment_scene(outline: &str, h: &str, extra: &str) -> String {
    format!(
        r#"Scene(
    name: "g",
    materials: {{"cloth": StVenantKirchhoff(young: 1.0e6, poisson: 0.3)}},
    parts: [],
    garment: Some((
        element_size: {h},
        plies: {{"shell": (material: "cloth", thickness: 0.0005)}},
        panels: [(name: "front", outline: {outline}, edges: {{"hem": (from: 0, to: 1)}}, plies: ["shell"]{extra})],
    )),
    node_sets: {{"hem": Edge(part: "front", edge: "hem")}},
    boundary: [Pin(set: "hem")],
    steps: [(name: "none", increments: 1)],
)"#
    )
}

const PANEL: &str = "[(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.5, 1.4), (0.0, 1.0)]";

#[test]
fn a_tiny_garment_element_size_is_refused_quickly() {
    let good = garment_scene(PANEL, "0.1", "");
    let s = scene::parse("g.ron", &good).expect("parse");
    scene::build(&s, "g.ron", &good).expect("the panel meshes at 0.1");
    for h in ["1.0e-6", "2.5e-8"] {
        let text = garment_scene(PANEL, h, "");
        let e = quick_error_of(&text, Duration::from_secs(3));
        assert_eq!(e.field, "garment.element_size", "{h}: {e}");
        assert!(e.message.contains("front") && e.message.contains("nodes"), "{e}");
        assert_eq!(e.line, line_of(&text, "element_size"));
    }
    // A curved edge sampled at a tiny size: refused before sampling.
    let text = garment_scene(PANEL, "2.5e-8", r#", curves: [(edge: "hem", sagitta: 0.1)]"#);
    quick_error_of(&text, Duration::from_secs(3));
}

#[test]
fn absurd_outline_coordinates_are_refused_quickly() {
    for v in ["1.0e308", "-1.0e308", "2.0e4"] {
        let text = garment_scene(&PANEL.replace("(0.5, 1.4)", &format!("(0.5, {v})")), "0.1", "");
        let e = quick_error_of(&text, Duration::from_secs(2));
        assert_eq!(e.field, "garment.panels[front].outline", "{v}: {e}");
        assert!(e.message.contains("vertex 3"), "{e}");
    }
    let e = plyshell::garment::mesh::mesh_polygon(&[[0.0, 0.0], [1.0, 0.0], [0.5, 1e308], [0.0, 1.0]], 0.1, &[], [1.0, 0.0]).expect_err("refused");
    assert!(e.contains("vertex 2"), "{e}");
}

#[test]
fn self_intersection_of_a_long_outline_is_near_linear() {
    use plyshell::garment::graph::self_intersection;
    let n = 200_000;
    let circle: Vec<[f64; 2]> = (0..n).map(|k| {
        let t = std::f64::consts::TAU * k as f64 / n as f64;
        [t.cos(), t.sin()]
    }).collect();
    let t = Instant::now();
    assert_eq!(self_intersection(&circle), Ok(None));
    // A bow tie: the segments 0→1 and 2→3 cross.
    let mut bow = circle.clone();
    bow.swap(50_000, 150_000);
    let hit = self_intersection(&bow).expect("checked").expect("crossing found");
    assert!(hit.0 < hit.1, "{hit:?}");
    assert!(t.elapsed() < Duration::from_secs(5), "{:?}", t.elapsed());
    // Small outlines keep the exact first pair.
    assert_eq!(self_intersection(&[[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]]), Ok(Some((0, 2))));
}

#[test]
fn drape_specimen_must_be_the_mesh_and_the_raster_is_bounded() {
    let text = include_str!("../garments/drape/cusick.ron").replace("specimen_radius: 0.15", "specimen_radius: 4294967297.0");
    let s = scene::parse("cusick.ron", &text).expect("parse");
    let e = scene::build(&s, "garments/drape/cusick.ron", &text).expect_err("the radius is not the mesh's");
    assert_eq!(e.field, "drape.specimen_radius", "{e}");
    assert_eq!(e.line, line_of(&text, "specimen_radius"));
    // The raster coarsens instead of allocating 10^13 cells.
    let r = plyshell::contact::drape::raster_resolution(1.05 * 4294967297.0, 0.0005);
    assert!(2.0 * 1.05 * 4294967297.0 / r <= plyshell::contact::drape::MAX_RASTER_SIDE as f64 + 1e-6);
    assert_eq!(plyshell::contact::drape::raster_resolution(0.1575, 0.0005), 0.0005);
}

#[test]
fn a_stitch_line_off_its_panel_is_an_error() {
    let text = garment_scene(PANEL, "0.1", "").replace(
        "    )),\n    node_sets",
        "        stitch_lines: [(name: \"quilt\", panel: \"front\", points: [(0.2, 0.5), (1.6, 0.5)])],\n    )),\n    node_sets",
    );
    let e = error_of(&text);
    assert_eq!(e.field, "garment.stitch_lines[quilt].points[1]", "{e}");
    assert!(e.message.contains("outside panel \"front\""), "{e}");
    assert_eq!(e.line, line_of(&text, "stitch_lines"));
}

#[test]
fn a_ply_thinner_than_its_fabric_is_an_error() {
    let text = garment_scene(PANEL, "0.1", "")
        .replace("StVenantKirchhoff(young: 1.0e6, poisson: 0.3)", "Fabric((preset: Some(\"ripstop\")))")
        .replace("thickness: 0.0005", "thickness: 0.0009");
    let e = error_of(&text);
    assert_eq!(e.field, "garment.plies[shell].thickness", "{e}");
    assert!(e.message.contains("0.00035") && e.message.contains("0.0009"), "{e}");
    assert_eq!(e.line, line_of(&text, "thickness: 0.0009"));
}

/// Two panels side by side joined along their touching sides; `reversed` picks the direction.
fn two_panels(reversed: bool) -> String {
    format!(
        r#"Scene(
    name: "g",
    materials: {{"cloth": StVenantKirchhoff(young: 1.0e6, poisson: 0.3)}},
    parts: [],
    garment: Some((
        element_size: 0.1,
        plies: {{"shell": (material: "cloth", thickness: 0.0005)}},
        panels: [
            (name: "left", outline: [(0.0, 0.0), (0.5, 0.0), (0.5, 1.0), (0.0, 1.0)],
             edges: {{"side": (from: 1, to: 2), "hem": (from: 0, to: 1)}}, plies: ["shell"]),
            (name: "right", outline: [(0.0, 0.0), (0.5, 0.0), (0.5, 1.0), (0.0, 1.0)],
             edges: {{"side": (from: 3, to: 0)}}, plies: ["shell"],
             placement: Rigid(translation: (0.5, 0.0, 0.0))),
        ],
        seams: [(name: "centre", a: (panel: "left", edge: "side"), b: (panel: "right", edge: "side", reversed: {reversed}), kind: Plain)],
    )),
    node_sets: {{"hem": Edge(part: "left", edge: "hem")}},
    boundary: [Pin(set: "hem")],
    steps: [(name: "none", increments: 1)],
)"#
    )
}

#[test]
fn a_seam_sewn_crossed_draws_a_warning() {
    let good = two_panels(true);
    let b = scene::build(&scene::parse("g.ron", &good).expect("parse"), "g.ron", &good).expect("build");
    assert!(b.warnings.iter().all(|w| !w.contains("crossed")), "{:?}", b.warnings);
    let bad = two_panels(false);
    let b = scene::build(&scene::parse("g.ron", &bad).expect("parse"), "g.ron", &bad).expect("build");
    let w = b.warnings.iter().find(|w| w.contains("sewn crossed")).expect("a crossed-seam warning");
    assert!(w.contains("centre") && w.contains(&format!("g.ron:{}:", line_of(&bad, "name: \"centre\""))), "{w}");
}

#[test]
fn a_garment_resting_on_contact_bodies_is_not_called_unsupported() {
    let text = garment_scene(PANEL, "0.1", "").replace("    boundary: [Pin(set: \"hem\")],\n", "");
    let b = scene::build(&scene::parse("g.ron", &text).expect("parse"), "g.ron", &text).expect("build");
    assert!(b.warnings.iter().any(|w| w.contains("neither supported")), "{:?}", b.warnings);
    let text = text.replace(
        "    steps:",
        "    contact: Some((bodies: [(name: \"table\", shape: Box(half_extents: (1.0, 1.0, 0.1)), translation: (0.5, 0.5, -0.2))])),\n    steps:",
    );
    let b = scene::build(&scene::parse("g.ron", &text).expect("parse"), "g.ron", &text).expect("build");
    assert!(b.warnings.iter().all(|w| !w.contains("neither supported")), "{:?}", b.warnings);
}

/// Found by the fuzzer: a syntax error after a key preceded by a multi-byte character (a
/// comment's "é") made the field lookup slice inside the character.
#[test]
fn field_lookup_after_multibyte_text_does_not_panic() {
    let text = GOOD.replace("    parts: [", "    // métal\n    parts: [").replace("material: \"steel\",", "material: \"steel\" thickness_x,");
    let e = error_of(&text);
    assert!(e.line > 0 && e.column > 0, "{e}");
    let text = GOOD.replace("increments: 1", "increments: ééééééééééééééééééééééééééééééééééééééééééééé");
    let e = error_of(&text);
    assert!(e.line > 0, "{e}");
}

/// `check` rejects what `solve` would reject only on reaching it.
#[test]
fn check_rejects_what_the_solve_would_refuse_later() {
    // A buckling step that changes no load.
    let text = GOOD.replace(
        "steps: [(name: \"load\", increments: 1, scale: {\"pull\": 1.0})]",
        "steps: [(name: \"load\", increments: 1, scale: {\"pull\": 1.0}), (name: \"modes\", increments: 1, kind: Buckling(modes: 2))]",
    );
    let e = error_of(&text);
    assert_eq!(e.field, "steps[modes].scale", "{e}");
    assert!(e.message.contains("changes no load"), "{e}");
    // A plot against a pattern that does not exist, or that no step scales.
    let text = GOOD.replace("    steps:", "    output: (plot_against: Some(\"push\")),\n    steps:");
    let e = error_of(&text);
    assert!(e.field == "output.plot_against" && e.message.contains("no load named \"push\""), "{e}");
    assert_eq!(e.line, line_of(&text, "plot_against"));
    let text = GOOD
        .replace("\"pull\": TotalForce", "\"idle\": TotalForce(set: \"tip\", force: (0.0, 1.0, 0.0)), \"pull\": TotalForce")
        .replace("    steps:", "    output: (plot_against: Some(\"idle\")),\n    steps:");
    let e = error_of(&text);
    assert!(e.field == "output.plot_against" && e.message.contains("no step scales"), "{e}");
    // Nothing free to solve for.
    let text = GOOD.replace("boundary: [Clamp(set: \"root\")]", "node_sets_all: (),\n    boundary: [Clamp(set: \"root\"), Clamp(set: \"all\")]").replace("node_sets_all: (),\n    ", "").replace(
        "\"tip\": Edge(part: \"strip\", edge: \"xmax\")}",
        "\"tip\": Edge(part: \"strip\", edge: \"xmax\"), \"all\": Part(part: \"strip\")}",
    );
    let e = error_of(&text);
    assert!(e.field == "boundary" && e.message.contains("nothing to solve"), "{e}");
}

/// Loop bounds and thread counts from the file are bounded before the solve.
#[test]
fn solver_controls_and_step_counts_are_bounded() {
    for (repl, field) in [
        ("solver: (threads: 4294967297),", "solver.threads"),
        ("solver: (max_cutbacks: 18446744073709551615),", "solver.max_cutbacks"),
        ("solver: (max_iterations: 0),", "solver.max_iterations"),
        ("solver: (residual_tol: NaN),", "solver.residual_tol"),
        ("solver: (energy_tol: -1.0),", "solver.energy_tol"),
    ] {
        let text = GOOD.replace("    steps:", &format!("    {repl}\n    steps:"));
        let e = error_of(&text);
        assert_eq!(e.field, field, "{repl}: {e}");
        assert_eq!(e.line, line_of(&text, "solver:"), "{e}");
    }
    let text = GOOD.replace("increments: 1", "increments: 4294967297");
    let e = error_of(&text);
    assert_eq!(e.field, "steps[load].increments", "{e}");
    let text = GOOD.replace("scale: {\"pull\": 1.0})", "scale: {\"pull\": 1.0}, kind: Buckling(modes: 4294967297))");
    let e = error_of(&text);
    assert_eq!(e.field, "steps[load].kind.modes", "{e}");
}

/// Found by the fuzzer: a reference written with a `\u{..}` escape was not located.
#[test]
fn a_reference_written_with_a_unicode_escape_is_located() {
    let text = GOOD.replace("material: \"steel\"", "material: \"st\\u{1e6}el\"");
    let e = error_of(&text);
    assert_eq!(e.field, "parts[strip].material", "{e}");
    assert_eq!(e.line, line_of(&text, "st\\u{1e6}el"), "{e}");
}

// ---------------------------------------------------------------------------------------
// Pattern files (DXF, AAMA / ASTM D6673 layers): malformed files give an error naming the
// file, the entity's handle and layer, and what was expected; never a panic.

use plyshell::pattern::dxf::{read_dxf, read_dxf_bytes};

/// A DXF (R2000, millimetres) with one block per `(block name, entities)` and an INSERT of
/// each in the ENTITIES section. Entities are group-code text.
fn dxf(blocks: &[(&str, String)]) -> String {
    let mut t = String::from("0\nSECTION\n2\nHEADER\n9\n$ACADVER\n1\nAC1015\n9\n$INSUNITS\n70\n4\n0\nENDSEC\n0\nSECTION\n2\nBLOCKS\n");
    for (name, body) in blocks {
        t += &format!("0\nBLOCK\n5\n1{name}\n8\n0\n2\n{name}\n70\n0\n10\n0.0\n20\n0.0\n30\n0.0\n3\n{name}\n");
        t += body;
        t += "0\nENDBLK\n8\n0\n";
    }
    t += "0\nENDSEC\n0\nSECTION\n2\nENTITIES\n";
    for (k, (name, _)) in blocks.iter().enumerate() {
        t += &format!("0\nINSERT\n5\n{:X}\n8\n0\n2\n{name}\n10\n0.0\n20\n0.0\n30\n0.0\n", 0xF00 + k);
    }
    t + "0\nENDSEC\n0\nEOF\n"
}

/// A closed (or open) LWPOLYLINE with handle `h` on `layer`.
fn lwpolyline(h: &str, layer: &str, pts: &[[f64; 2]], closed: bool) -> String {
    let mut t = format!("0\nLWPOLYLINE\n5\n{h}\n100\nAcDbEntity\n8\n{layer}\n100\nAcDbPolyline\n90\n{}\n70\n{}\n", pts.len(), i32::from(closed));
    for p in pts {
        t += &format!("10\n{}\n20\n{}\n", p[0], p[1]);
    }
    t
}

fn line(h: &str, layer: &str, a: [f64; 2], b: [f64; 2]) -> String {
    format!("0\nLINE\n5\n{h}\n100\nAcDbEntity\n8\n{layer}\n100\nAcDbLine\n10\n{}\n20\n{}\n30\n0.0\n11\n{}\n21\n{}\n31\n0.0\n", a[0], a[1], b[0], b[1])
}

fn text(h: &str, value: &str) -> String {
    format!("0\nTEXT\n5\n{h}\n100\nAcDbEntity\n8\n1\n100\nAcDbText\n10\n10.0\n20\n10.0\n30\n0.0\n40\n5.0\n1\n{value}\n")
}

const SQUARE: [[f64; 2]; 4] = [[0.0, 0.0], [100.0, 0.0], [100.0, 100.0], [0.0, 100.0]];

fn piece(name: &str, h: u32) -> String {
    lwpolyline(&format!("{:X}", h), "1", &SQUARE, true) + &line(&format!("{:X}", h + 1), "7", [50.0, 10.0], [50.0, 90.0]) + &text(&format!("{:X}", h + 2), &format!("Piece Name: {name}"))
}

#[test]
fn a_well_formed_hand_written_dxf_reads() {
    let p = read_dxf_bytes("ok.dxf", dxf(&[("A", piece("front", 0x100))]).as_bytes(), None, None).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(p.len(), 1);
    assert_eq!(p[0].name, "front");
    assert_eq!(p[0].outline, vec![[0.0, 0.0], [0.1, 0.0], [0.1, 0.1], [0.0, 0.1]]);
}

#[test]
fn an_open_boundary_names_its_handle_and_layer() {
    let body = lwpolyline("2A", "1", &SQUARE, false) + &line("2B", "7", [50.0, 10.0], [50.0, 90.0]);
    let e = read_dxf_bytes("open.dxf", dxf(&[("A", body)]).as_bytes(), None, None).expect_err("open boundary");
    assert_eq!((e.handle, e.layer.as_deref()), (Some(0x2A), Some("1")), "{e}");
    let s = e.to_string();
    assert!(s.starts_with("open.dxf: entity 2A (layer \"1\"): block \"A\": the boundary is open: its ends are 100.000 mm apart"), "{s}");
}

#[test]
fn a_missing_grain_line_and_an_unknown_layer_are_named() {
    let body = lwpolyline("2A", "1", &SQUARE, true);
    let e = read_dxf_bytes("nograin.dxf", dxf(&[("A", body)]).as_bytes(), None, None).expect_err("no grain");
    assert!(e.message.contains("no grain line: expected a LINE on layer 7") && e.handle == Some(0xF00), "{e}");
    let body = piece("front", 0x100) + &line("3C", "CUT", [0.0, 0.0], [1.0, 1.0]);
    let e = read_dxf_bytes("layer.dxf", dxf(&[("A", body)]).as_bytes(), None, None).expect_err("unknown layer");
    assert_eq!((e.handle, e.layer.as_deref()), (Some(0x3C), Some("CUT")), "{e}");
    assert!(e.message.contains("unknown layer \"CUT\"") && e.message.contains("AAMA / ASTM D6673"), "{e}");
}

#[test]
fn a_unitless_file_needs_its_units() {
    let text = dxf(&[("A", piece("front", 0x100))]).replace("$INSUNITS\n70\n4", "$INSUNITS\n70\n0");
    let e = read_dxf_bytes("unitless.dxf", text.as_bytes(), None, None).expect_err("unitless");
    assert!(e.message.contains("$INSUNITS is Unitless") && e.message.contains("give the units"), "{e}");
    let p = read_dxf_bytes("unitless.dxf", text.as_bytes(), None, Some(plyshell::garment::LengthUnit::Cm)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(p[0].outline[2], [1.0, 1.0]);
}

#[test]
fn duplicated_piece_names_are_rejected() {
    let e = read_dxf_bytes("dup.dxf", dxf(&[("A", piece("front", 0x100)), ("B", piece("front", 0x200))]).as_bytes(), None, None).expect_err("duplicate");
    assert!(e.message.contains("duplicated piece name \"front\"") && e.message.contains("F00"), "{e}");
    assert_eq!(e.handle, Some(0xF01));
}

#[test]
fn a_notch_off_the_boundary_is_rejected() {
    let body = piece("front", 0x100) + &line("4D", "4", [50.0, 50.0], [51.0, 50.0]);
    let e = read_dxf_bytes("notch.dxf", dxf(&[("A", body)]).as_bytes(), None, None).expect_err("notch inside");
    assert_eq!((e.handle, e.layer.as_deref()), (Some(0x4D), Some("4")), "{e}");
    assert!(e.message.contains("from the boundary"), "{e}");
}

#[test]
fn truncated_empty_and_garbage_files_are_errors_not_panics() {
    let good = dxf(&[("A", piece("front", 0x100))]);
    for cut in [good.len() / 4, good.len() / 2, good.len() * 3 / 4, good.len() - 8] {
        let e = read_dxf_bytes("cut.dxf", &good.as_bytes()[..cut], None, None).expect_err("truncated");
        println!("truncated at {cut}: {e}");
        assert!(e.to_string().starts_with("cut.dxf: "), "{e}");
    }
    let shipped = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/garments/patterns/two_piece.dxf")).expect("shipped dxf");
    for cut in [shipped.len() / 3, shipped.len() * 2 / 3] {
        let e = read_dxf_bytes("two_piece_cut.dxf", &shipped[..cut], None, None).expect_err("truncated");
        println!("shipped truncated at {cut}: {e}");
    }
    let e = read_dxf_bytes("empty.dxf", b"", None, None).expect_err("empty");
    assert!(e.message.contains("empty"), "{e}");
    let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
    let garbage: Vec<u8> = (0..4096)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 24) as u8
        })
        .collect();
    let e = read_dxf_bytes("garbage.dxf", &garbage, None, None).expect_err("garbage");
    println!("garbage: {e}");
    assert!(e.to_string().starts_with("garbage.dxf: "), "{e}");
    let e = read_dxf(std::path::Path::new("/nonexistent/pattern.dxf"), None, None).expect_err("missing file");
    assert!(e.to_string().starts_with("/nonexistent/pattern.dxf: cannot read the pattern file"), "{e}");
}

#[test]
fn a_garment_pattern_error_is_located_at_the_pattern_field() {
    let text = GOOD.replace("    steps:", "    garment: Some((element_size: 0.05, pattern: Some(Dxf(file: \"missing.dxf\")), plies: {\"p\": (material: \"steel\", thickness: 0.01)}, panels: [(name: \"front\", plies: [\"p\"])])),\n    steps:");
    let e = error_of(&text);
    assert_eq!(e.field, "garment.pattern");
    assert_eq!(e.line, line_of(&text, "pattern:"), "{e}");
    assert!(e.message.contains("missing.dxf: cannot read the pattern file"), "{e}");
    // A panel without outline that names no piece of the file.
    let dir = std::env::temp_dir().join(format!("plyshell_bad_pattern_{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    std::fs::write(dir.join("one.dxf"), dxf(&[("A", piece("back", 0x100))])).expect("write");
    let text = text.replace("missing.dxf", "one.dxf");
    let file = dir.join("scene.ron");
    std::fs::write(&file, &text).expect("write");
    let e = scene::load(&file).expect_err("no such piece");
    assert_eq!(e.field, "garment.panels[front].outline");
    assert!(e.message.contains("no piece of that name; its pieces: back"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A linear step cannot run with a garment's barrier surface contact (on by default): the
/// collision detection would shorten its one update. Refused at the step's `linear` key;
/// accepted with the contact turned off.
#[test]
fn a_linear_step_with_garment_barrier_contact_is_refused() {
    let text = garment_scene(PANEL, "0.1", "").replace("(name: \"none\", increments: 1)", "(name: \"none\", increments: 1, linear: true)");
    let e = error_of(&text);
    assert_eq!(e.field, "steps[none].linear", "{e}");
    assert!(e.message.contains("interply: (enabled: false)"), "{e}");
    assert_eq!(e.line, line_of(&text, "linear: true"), "{e}");
    let off = text.replace("plies: {\"shell\"", "interply: (enabled: false),\n        plies: {\"shell\"");
    let s = scene::parse("g.ron", &off).expect("parse");
    scene::build(&s, "g.ron", &off).expect("linear with contact off builds");
}
