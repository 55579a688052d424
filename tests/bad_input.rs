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
