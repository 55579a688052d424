//! The command line under hostile use (issue 16): a closed stdout pipe, `--out` naming a
//! file, a memory budget set by `--max-memory`, a monitor plot that cannot be written (the
//! summary is still written) and a failed solve whose message names only the last state file.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

const STRIP: &str = r#"Scene(
    name: "strip",
    materials: {"steel": StVenantKirchhoff(young: 1.0e6, poisson: 0.3)},
    parts: [(name: "strip", mesh: Rectangle(lx: 1.0, ly: 0.1, nx: 4, ny: 1), material: "steel", thickness: 0.01)],
    node_sets: {"root": Edge(part: "strip", edge: "xmin"), "tip": Edge(part: "strip", edge: "xmax")},
    boundary: [Clamp(set: "root")],
    loads: {"pull": TotalForce(set: "tip", force: (1.0, 0.0, 0.0))},
    steps: [(name: "load", increments: 2, scale: {"pull": 1.0})],
    monitors: [(name: "tip", point: (1.0, 0.0, 0.0), dofs: [Ux])],
)"#;

fn exe() -> &'static str {
    env!("CARGO_BIN_EXE_plyshell")
}

/// A fresh scratch directory under target/.
fn scratch(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("cli_robustness_{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch dir");
    d
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).expect("write scene");
    p
}

fn run(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(exe()).args(args).output().expect("run plyshell");
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stdout).into_owned(), String::from_utf8_lossy(&out.stderr).into_owned())
}

#[test]
fn a_closed_stdout_pipe_is_not_a_panic() {
    let d = scratch("pipe");
    let scene = write(&d, "strip.ron", STRIP);
    let mut child = Command::new(exe()).args(["check", scene.to_str().expect("utf8")]).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().expect("spawn");
    // Close the read end at once, like `| head -0`.
    drop(child.stdout.take());
    let mut err = String::new();
    child.stderr.take().expect("stderr").read_to_string(&mut err).expect("stderr");
    let status = child.wait().expect("wait");
    assert!(!err.contains("panicked") && !err.contains("Broken pipe"), "{err}");
    assert_eq!(status.code(), Some(0), "{err}");
}

#[test]
fn out_naming_a_file_is_refused_before_the_solve() {
    let d = scratch("out_file");
    let scene = write(&d, "strip.ron", STRIP);
    let file = write(&d, "results", "not a directory");
    let (code, _, err) = run(&["solve", scene.to_str().expect("utf8"), "--out", file.to_str().expect("utf8"), "--quiet"]);
    assert_eq!(code, 1);
    assert!(err.contains("--out") && err.contains("not a directory") && !err.contains("os error 17"), "{err}");
}

#[test]
fn max_memory_sets_the_budget_and_names_the_field() {
    let d = scratch("budget");
    let scene = write(&d, "big.ron", &STRIP.replace("nx: 4, ny: 1", "nx: 300, ny: 300"));
    let (code, _, err) = run(&["check", scene.to_str().expect("utf8"), "--max-memory", "200M"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("big.ron:4:") && err.contains("parts[strip].mesh") && err.contains("200.0 MiB") && err.contains("--max-memory"), "{err}");
    let (code, out, err) = run(&["check", scene.to_str().expect("utf8"), "--max-memory", "8G"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("90601 nodes"), "{out}");
    let (code, _, err) = run(&["check", scene.to_str().expect("utf8"), "--max-memory", "lots"]);
    assert_ne!(code, 0);
    assert!(err.contains("lots"), "{err}");
}

#[test]
fn a_failed_monitor_plot_still_writes_summary_json() {
    let d = scratch("plot");
    let scene = write(&d, "strip.ron", STRIP);
    let out = d.join("out");
    // A directory where the plot should go: the SVG cannot be written.
    std::fs::create_dir_all(out.join("strip_monitors.svg")).expect("blocker");
    let (code, _, err) = run(&["solve", scene.to_str().expect("utf8"), "--out", out.to_str().expect("utf8"), "--quiet"]);
    assert_eq!(code, 1);
    assert!(err.contains("monitor plot") && err.contains("summary.json was written"), "{err}");
    let summary = std::fs::read_to_string(out.join("summary.json")).expect("summary.json written");
    assert!(summary.contains("\"status\": \"completed\"") && summary.contains("output_problems"), "{summary}");
}

#[test]
fn a_failed_solve_names_only_the_last_state_file() {
    let d = scratch("fail");
    // Two converged increments of a small tip load, then a step that crushes the strip.
    let text = STRIP
        .replace("force: (1.0, 0.0, 0.0)", "force: (0.0, 0.0, 1.0e-4)")
        .replace("scale: {\"pull\": 1.0})]", "scale: {\"pull\": 1.0}), (name: \"crush\", increments: 1, scale: {\"pull\": 1.0e9})]")
        .replace("    monitors:", "    solver: (max_cutbacks: 0),\n    monitors:");
    let scene = write(&d, "strip.ron", &text);
    let out = d.join("out");
    let (code, _, err) = run(&["solve", scene.to_str().expect("utf8"), "--out", out.to_str().expect("utf8"), "--quiet"]);
    assert_eq!(code, 1);
    assert!(err.contains("strip_last_converged.vtu") && !err.contains("strip_0001.vtu") && !err.contains("strip.pvd"), "{err}");
    assert!(out.join("summary.json").exists() && out.join("strip_0002.vtu").exists());
}

/// PVD times of a `Dynamic` step are its simulated seconds (issue 17, item 7), and stay
/// increasing across a static step before and after it: the strip is pulled statically
/// (2 increments: times 0.5, 1), swings for 0.03 s in fixed steps of 0.01 s (times
/// 1.01, 1.02, 1.03) and is pulled again (2 increments: 1.53, 2.03).
#[test]
fn pvd_times_of_a_dynamic_step_are_seconds() {
    let d = scratch("pvd_seconds");
    let text = STRIP.replace(
        r#"steps: [(name: "load", increments: 2, scale: {"pull": 1.0})],"#,
        r#"steps: [(name: "load", increments: 2, scale: {"pull": 1.0}),
            (name: "swing", increments: 1, scale: {"pull": 2.0}, kind: Dynamic((dt: 0.01, dt_max: 0.01, duration: 0.03))),
            (name: "again", increments: 2, scale: {"pull": 3.0})],"#,
    );
    let text = text.replace("thickness: 0.01)", "thickness: 0.01, areal_density: 78.5)");
    assert!(text.contains("swing") && text.contains("areal_density"), "the strip scene changed: update this test's replacement");
    let scene = write(&d, "strip.ron", &text);
    let out = d.join("out");
    let (code, _, err) = run(&["solve", scene.to_str().expect("utf8"), "--out", out.to_str().expect("utf8"), "--quiet"]);
    assert_eq!(code, 0, "{err}");
    let pvd = std::fs::read_to_string(out.join("strip.pvd")).expect("pvd");
    let times: Vec<f64> = pvd
        .split("timestep=\"")
        .skip(1)
        .map(|s| s.split('"').next().and_then(|v| v.parse().ok()).expect("a timestep number"))
        .collect();
    let expected = [0.5, 1.0, 1.01, 1.02, 1.03, 1.53, 2.03];
    assert_eq!(times.len(), expected.len(), "{pvd}");
    for (t, e) in times.iter().zip(expected) {
        assert!((t - e).abs() < 1e-9, "PVD times {times:?}, expected {expected:?}");
    }
}

/// Without a terminal (stderr captured, as in a log file or CI) `solve` prints progress
/// lines — elapsed time, percentage, step, iteration, residual — at each new step, where
/// the hidden progress bar would have shown them (issue 17, item 7).
#[test]
fn progress_lines_are_printed_when_stderr_is_not_a_terminal() {
    let d = scratch("progress_lines");
    let text = STRIP.replace(
        r#"steps: [(name: "load", increments: 2, scale: {"pull": 1.0})],"#,
        r#"steps: [(name: "load", increments: 2, scale: {"pull": 1.0}), (name: "more", increments: 2, scale: {"pull": 2.0})],"#,
    );
    assert!(text.contains("\"more\""), "the strip scene changed: update this test's replacement");
    let scene = write(&d, "strip.ron", &text);
    let out = d.join("out");
    let (code, _, err) = run(&["solve", scene.to_str().expect("utf8"), "--out", out.to_str().expect("utf8")]);
    assert_eq!(code, 0, "{err}");
    let lines: Vec<&str> = err.lines().filter(|l| l.starts_with('[') && l.contains(" s] ") && l.contains("residual")).collect();
    assert!(lines.iter().any(|l| l.contains("step 1 'load'")) && lines.iter().any(|l| l.contains("step 2 'more'")), "progress lines: {lines:?}\nstderr: {err}");
}

/// `plyshell study` refuses a scene without a garment and bad size multipliers, and on the
/// two-ply flap at one mesh level (discrete only: the reference alone) prints its table and
/// writes study.md / study.json.
#[test]
fn study_refuses_bad_input_and_writes_its_table() {
    let d = scratch("study");
    let scene = write(&d, "strip.ron", STRIP);
    let (code, _, err) = run(&["study", scene.to_str().expect("utf8"), "--out", d.join("s").to_str().expect("utf8")]);
    assert_eq!(code, 1);
    assert!(err.contains("no garment"), "{err}");
    let flap = Path::new(env!("CARGO_MANIFEST_DIR")).join("garments/studies/two_ply_flap.ron");
    let (code, _, err) = run(&["study", flap.to_str().expect("utf8"), "--sizes", "2,-1", "--out", d.join("s").to_str().expect("utf8")]);
    assert_eq!(code, 1);
    assert!(err.contains("positive size multipliers"), "{err}");
    let out = d.join("flap");
    let (code, stdout, err) = run(&["study", flap.to_str().expect("utf8"), "--sizes", "2", "--discrete-only", "--out", out.to_str().expect("utf8")]);
    assert_eq!(code, 0, "{err}");
    assert!(stdout.contains("| discrete h×2 (reference) |"), "{stdout}");
    assert!(out.join("study.md").is_file() && out.join("study.json").is_file());
}
