//! Path-following steps fail with a diagnosis (step, iteration, residual history, worst
//! element, likely cause) and leave the last converged state; their scene fields are checked
//! with file:line:col errors.

use std::path::Path;

use plyshell::analysis::{self, RunError, RunOptions};
use plyshell::bench::scenes;
use plyshell::scene;

fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).expect("needle in text") + 1
}

fn error_of(text: &str) -> scene::SceneError {
    match scene::parse("bad.ron", text) {
        Err(e) => e,
        Ok(s) => scene::build(&s, "bad.ron", text).expect_err("the scene should be rejected"),
    }
}

/// The hinged roof without its hinges is a mechanism: the arc-length step cuts back to its
/// minimum arc length and stops; the error names step 1, the iteration count, the residual
/// history, a worst element and the likely cause (a nearly singular tangent: a mechanism),
/// and the last converged (initial) state is written as a VTU beside summary.json.
#[test]
fn arc_length_on_a_mechanism_fails_with_a_diagnosis() {
    let text = scenes::HINGED_ROOF.replace("        Pin(set: \"hinged\"),\n", "");
    assert_ne!(text, scenes::HINGED_ROOF);
    let sc = scene::parse("roof", &text).expect("parse");
    let built = scene::build(&sc, "roof", &text).expect("build");
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/test-output/path_mechanism");
    let _ = std::fs::remove_dir_all(&out);
    match analysis::run(&sc, &built, &RunOptions { out_dir: Some(out.clone()) }, &mut |_| {}) {
        Err(RunError::Solve { error, summary }) => {
            assert_eq!(error.step, 0);
            assert!(error.iteration > 0);
            assert!(!error.residuals.is_empty());
            assert!(error.worst_element.is_some());
            assert!(error.cause.contains("nearly singular tangent") && error.cause.contains("mechanism"), "{}", error.cause);
            assert!(summary.status.starts_with("failed: step 1 'path'"), "{}", summary.status);
            assert!(out.join("hinged_roof_last_converged.vtu").exists());
            assert!(out.join("summary.json").exists());
        }
        other => panic!("expected a solve failure, got {other:?}"),
    }
}

/// Displacement control needs a one-node set: a set of several nodes is rejected at its
/// position in the step.
#[test]
fn displacement_control_on_a_multi_node_set_is_rejected() {
    let text = scenes::HINGED_ROOF.replace(
        "kind: ArcLength(length: 0.5, max_length: Some(1.0), max_load_factor: 4.0, max_displacement: Some(30.0)),",
        "kind: DisplacementControl(set: \"hinged\", dof: Uz, value: -1.0),",
    );
    let e = error_of(&text);
    assert!(e.message.contains("exactly one node"), "{e}");
    assert_eq!(e.field, "steps[path].kind.set");
    assert_eq!(e.line, line_of(&text, "DisplacementControl"), "{e}");
}

/// A non-positive arc length is rejected with the field named.
#[test]
fn negative_arc_length_is_rejected() {
    let text = scenes::HINGED_ROOF.replace("ArcLength(length: 0.5", "ArcLength(length: -0.5");
    let e = error_of(&text);
    assert_eq!(e.field, "steps[path].kind.length", "{e}");
    assert!(e.line > 0, "{e}");
}

/// A buckling mode number of 0 in the imperfection is rejected.
#[test]
fn imperfection_mode_zero_is_rejected() {
    let text = scenes::PLATE_POSTBUCKLING.replace("(mode: 1, amplitude", "(mode: 0, amplitude");
    let e = error_of(&text);
    assert_eq!(e.field, "imperfection.modes.mode", "{e}");
}
