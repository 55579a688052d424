//! `plyshell check` reports each seam's initial gap and every part that starts inside (or
//! within the barrier distance of) a contact body (issue 17 item 7), run through the binary.
//!
//! References, from the geometry written in `garments/examples/vest.ron`:
//! - the front and back panels have the same outline and rotation and differ only by their
//!   translations, so every matched pair of a seam joining the same edge of both is apart by
//!   |t_front − t_back| = 0.24 m (max and mean, relative 1e-9), and each side's length is the
//!   outline's length along the edge span;
//! - a capsule's signed distance is |x − closest point of its axis segment| − r, so with the
//!   front panel moved into the torso the nodes on or inside are those with that distance
//!   ≤ h/2 and the deepest penetration is max(h/2 − d) (relative 1e-9).

use std::path::{Path, PathBuf};
use std::process::Command;

use nalgebra::Vector3;
use plyshell::scene;

const VEST: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/garments/examples/vest.ron");

fn scratch(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("check_report_{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch dir");
    d
}

/// Runs `plyshell check SCENE --json JSON`: (exit code, stdout, stderr, parsed JSON).
fn check(dir: &Path, text: &str) -> (i32, String, String, serde_json::Value) {
    let scene = dir.join("scene.ron");
    std::fs::write(&scene, text).expect("write scene");
    let json = dir.join("check.json");
    let out = Command::new(env!("CARGO_BIN_EXE_plyshell")).args(["check", scene.to_str().expect("utf8"), "--json", json.to_str().expect("utf8")]).output().expect("run plyshell");
    let report = serde_json::from_str(&std::fs::read_to_string(&json).expect("check.json")).expect("json");
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stdout).into_owned(), String::from_utf8_lossy(&out.stderr).into_owned(), report)
}

fn close(got: f64, want: f64, what: &str) {
    assert!((got - want).abs() <= 1e-9 * want.abs(), "{what}: {got} vs {want}");
}

#[test]
fn vest_seams_report_their_initial_gaps() {
    let text = std::fs::read_to_string(VEST).expect("vest.ron");
    let sc = scene::parse("vest.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let built = scene::build(&sc, "vest.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let g = sc.garment.as_ref().expect("garment");
    let panel = |n: &str| g.panels.iter().find(|p| p.name == n).expect("panel");
    let placed = |n: &str| match panel(n).placement {
        plyshell::garment::Placement::Rigid { translation, rotation_deg } => (Vector3::from(translation), rotation_deg),
        _ => panic!("rigid placement expected"),
    };
    let ((tf, rf), (tb, rb)) = (placed("front"), placed("back"));
    assert_eq!(rf, rb, "same rotation");
    assert_eq!(panel("front").outline, panel("back").outline, "same outline");
    let gap = (tf - tb).norm();
    close(gap, 0.24, "the sewing test's 24 cm");
    let (code, stdout, stderr, r) = check(&scratch("vest"), &text);
    println!("{stdout}{stderr}");
    assert_eq!(code, 0, "{stderr}");
    let seams = r["seams"].as_array().expect("seams");
    assert_eq!(seams.len(), 4);
    for (s, spec) in seams.iter().zip(&g.seams) {
        assert_eq!(s["name"], spec.name.as_str());
        assert_eq!(spec.a.edge, spec.b.edge, "the seam joins the same edge of both panels");
        let outline = &panel(&spec.a.panel).outline;
        let span = &panel(&spec.a.panel).edges[&spec.a.edge];
        let n = outline.len();
        let mut len = 0.0;
        let mut k = span.from;
        while k != span.to {
            let (p, q) = (outline[k], outline[(k + 1) % n]);
            len += (q[0] - p[0]).hypot(q[1] - p[1]);
            k = (k + 1) % n;
        }
        let info = built.seams.iter().find(|i| i.name == spec.name).expect("built seam");
        println!("{}: {} pairs, length {len} m, gap {gap} m", spec.name, info.slave.len());
        assert_eq!(s["pairs"].as_u64(), Some(info.slave.len() as u64));
        close(s["max_gap"].as_f64().expect("max_gap"), gap, "max gap");
        close(s["mean_gap"].as_f64().expect("mean_gap"), gap, "mean gap");
        close(s["length_a"].as_f64().expect("length_a"), len, "side a length");
        close(s["length_b"].as_f64().expect("length_b"), len, "side b length");
        assert_eq!(s["mismatched"], false);
        assert!(stdout.lines().any(|l| l.trim_start().starts_with(spec.name.as_str()) && l.contains("2.4000e-1")), "table row of {}", spec.name);
    }
    assert_eq!(r["contact"], "barrier");
    assert_eq!(r["near_bodies"].as_array().map(Vec::len), Some(0), "the vest starts clear of the bodies");
}

/// Signed distance of `x` from a capsule of radius `r` round the segment `a`–`b`.
fn capsule_distance(x: Vector3<f64>, a: Vector3<f64>, b: Vector3<f64>, r: f64) -> f64 {
    let t = ((x - a).dot(&(b - a)) / (b - a).norm_squared()).clamp(0.0, 1.0);
    (x - (a + (b - a) * t)).norm() - r
}

#[test]
fn a_panel_moved_into_the_torso_is_named_with_the_body() {
    let text = std::fs::read_to_string(VEST).expect("vest.ron").replace("translation: (-0.2, 0.12, 0.0)", "translation: (-0.2, 0.0, 0.0)");
    let sc = scene::parse("vest_in_torso.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let built = scene::build(&sc, "vest_in_torso.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let m = &built.model;
    let half = 0.5 * 0.0005; // h/2 of the shell ply
    let bodies = &sc.contact.as_ref().expect("contact").bodies;
    let (code, stdout, stderr, r) = check(&scratch("in_torso"), &text);
    println!("{stdout}{stderr}");
    assert_eq!(code, 1, "a part inside a body under barrier contact fails the check");
    // Located at the panel's name in the file (file:line:col: field: message).
    let line = text[..text.find("name: \"front\"").expect("front")].matches('\n').count() + 1;
    let located = stderr.lines().find(|l| l.contains("garment.panels[front]: part 'front' starts inside body 'torso'")).unwrap_or_else(|| panic!("{stderr}"));
    assert!(located.starts_with("error: ") && located.contains(&format!("scene.ron:{line}:")), "{located} (line {line})");
    let near = r["near_bodies"].as_array().expect("near_bodies");
    for b in bodies {
        let plyshell::scene::ShapeSpec::Capsule { radius, height } = b.shape else { panic!("capsule bodies") };
        // Local axis z; a rotation of 90° about y carries it to x.
        let axis = match b.rotation {
            [0.0, 0.0, 0.0] => Vector3::z(),
            [0.0, 90.0, 0.0] => Vector3::x(),
            other => panic!("rotation {other:?}"),
        };
        let c = Vector3::from(b.translation);
        let (a, e) = (c - axis * (0.5 * height), c + axis * (0.5 * height));
        for part in &m.parts {
            let gaps: Vec<f64> = (part.first_node..part.first_node + part.n_nodes).map(|n| capsule_distance(m.x0[n], a, e, radius) - half).collect();
            let inside = gaps.iter().filter(|&&g| g <= 0.0).count();
            let near_count = gaps.iter().filter(|&&g| g > 0.0 && g < 2.0 * half).count();
            let row = near.iter().find(|p| p["body"] == b.name.as_str() && p["part"] == part.name.as_str());
            println!("{} in {}: {inside} inside, {near_count} within d̂ (analytic)", part.name, b.name);
            if inside + near_count == 0 {
                assert!(row.is_none(), "{row:?}");
                continue;
            }
            let row = row.unwrap_or_else(|| panic!("no row for {} in {}", part.name, b.name));
            assert_eq!(row["inside"].as_u64(), Some(inside as u64));
            assert_eq!(row["within_barrier"].as_u64(), Some(near_count as u64));
            if inside > 0 {
                let deepest = -gaps.iter().copied().fold(f64::INFINITY, f64::min);
                close(row["deepest_penetration"].as_f64().expect("deepest"), deepest, "deepest penetration");
                assert_eq!(row["level"], "error");
            }
        }
    }
    let torso = near.iter().find(|p| p["body"] == "torso" && p["part"] == "front").expect("front in torso");
    // The front panel now lies on the torso's axis plane: its deepest node is at most r + h/2 in.
    let deepest = torso["deepest_penetration"].as_f64().expect("deepest");
    assert!(deepest > 0.05 && deepest <= 0.1 + half + 1e-12, "{deepest}");
    assert!(near.iter().all(|p| p["part"] != "back"), "the back panel stays 12 cm from the torso axis");
}

#[test]
fn a_seam_whose_sides_differ_in_length_is_flagged() {
    // The back's right edge shortened from 0.35 m to 0.30 m: 14 % shorter than the front's;
    // the build admits it only with the span tolerance raised (default 2 %) to 20 %.
    let text = std::fs::read_to_string(VEST).expect("vest.ron").replacen("element_size: 0.04,", "element_size: 0.04, span_tolerance: 0.2,", 1);
    let back = text.find("name: \"back\"").expect("back panel");
    let text = format!("{}{}", &text[..back], text[back..].replacen("(0.4, 0.35), (0.32, 0.55)", "(0.4, 0.30), (0.32, 0.55)", 1));
    let (code, stdout, stderr, r) = check(&scratch("mismatch"), &text);
    println!("{stdout}{stderr}");
    assert_eq!(code, 0, "{stderr}");
    let right = r["seams"].as_array().expect("seams").iter().find(|s| s["name"] == "right_side").expect("right_side");
    assert_eq!(right["mismatched"], true);
    close(right["length_mismatch"].as_f64().expect("mismatch"), 0.05 / 0.35, "relative length difference");
    assert!(stderr.lines().any(|l| l.starts_with("warning: ") && l.contains("garment.seams[right_side]: seam 'right_side': its sides differ")), "{stderr}");
    assert!(r["seams"].as_array().expect("seams").iter().filter(|s| s["mismatched"] == true).count() == 1);
}

/// Penalty contact: the Cusick drape specimen is placed resting on its support discs (faces
/// touching by 1e-9 m, mid-surface outside), which the penalty formulation accepts: listed as
/// info, no warning, exit 0.
#[test]
fn a_part_resting_on_a_support_under_penalty_contact_is_info() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/garments/drape/cusick.ron")).expect("cusick.ron");
    let (code, stdout, stderr, r) = check(&scratch("cusick"), &text);
    println!("{stdout}{stderr}");
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(r["contact"], "penalty");
    let near = r["near_bodies"].as_array().expect("near_bodies");
    assert!(!near.is_empty() && near.iter().all(|p| p["level"] == "info" && p["midsurface_inside"] == 0), "{near:?}");
    assert!(!stderr.contains("part 'specimen'"), "{stderr}");
}

/// `plyshell check` validates the mannequin's own files too (measurements, pose, motion),
/// told apart by their top-level RON struct: every shipped one passes, and a pose naming an
/// unknown joint is refused with its file, line and column.
#[test]
fn check_validates_mannequin_files() {
    let run = |p: &Path| Command::new(env!("CARGO_BIN_EXE_plyshell")).arg("check").arg(p).output().expect("run plyshell");
    let body = Path::new(env!("CARGO_MANIFEST_DIR")).join("garments/body");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&body).expect("garments/body").chain(std::fs::read_dir(body.join("poses")).expect("poses")).filter_map(|e| e.ok().map(|e| e.path())).filter(|p| p.extension().is_some_and(|x| x == "ron")).collect();
    files.sort();
    assert!(files.len() >= 10, "{files:?}");
    for f in &files {
        let o = run(f);
        assert!(o.status.success(), "{}: {}", f.display(), String::from_utf8_lossy(&o.stderr));
    }
    let d = scratch("bad_pose");
    let bad = d.join("bad.ron");
    std::fs::write(&bad, "// a pose\nPose(\n    elbow_x: (flexion: 10),\n)\n").expect("write");
    let o = run(&bad);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("bad.ron:3:"), "{err}");
}
