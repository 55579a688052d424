//! Movement protocol and seam-layout comparison (issue 17, items 4 and 5).
//!
//! The two shipped sleeve variants (`garments/compare/sleeve_{underarm,back}.ron`: a knit
//! sleeve sewn round the left elbow of the default mannequin, seam under the arm or on the
//! back of the arm) are run, at a coarser element size (3 cm instead of 2 cm), through a
//! two-pose protocol (`tests/data/protocol/elbow.ron`: the rest pose, then the left elbow
//! bent from 10° to 70°) by `plyshell compare`.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

fn exe() -> &'static str {
    env!("CARGO_BIN_EXE_plyshell")
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A fresh scratch directory under target/.
fn scratch(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("protocol_{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch dir");
    d
}

/// The shipped variant `name` at element size 3 cm on the elbow protocol, written to `dir`
/// (body files by absolute path).
fn variant(dir: &Path, name: &str) -> PathBuf {
    let text = std::fs::read_to_string(root().join(format!("garments/compare/{name}.ron"))).expect("variant");
    let abs = |p: &str| root().join(p).display().to_string();
    let text = text
        .replace("element_size: 0.02", "element_size: 0.03")
        .replace("\"../body/measurements.ron\"", &format!("\"{}\"", abs("garments/body/measurements.ron")))
        .replace("\"../body/motion.ron\"", &format!("\"{}\"", abs("tests/data/protocol/elbow.ron")));
    assert!(text.contains("element_size: 0.03") && text.contains("elbow.ron"), "the variant file changed: update the substitutions");
    let p = dir.join(format!("{name}.ron"));
    std::fs::write(&p, text).expect("write variant");
    p
}

fn run(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(exe()).args(args).output().expect("run plyshell");
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stdout).into_owned(), String::from_utf8_lossy(&out.stderr).into_owned())
}

fn read_json(p: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))).expect("json")
}

/// The pose entry `pose` of a summary.json.
fn pose<'a>(summary: &'a Value, pose: &str) -> &'a Value {
    summary["poses"]["poses"].as_array().expect("poses").iter().find(|p| p["pose"] == pose).unwrap_or_else(|| panic!("no pose {pose}"))
}

/// `compare` solves both variants through the protocol; its table holds exactly each
/// variant's own summary.json numbers, and the per-pose measures are physically sane.
#[test]
fn compare_tables_each_variants_pose_measures() {
    let d = scratch("compare");
    let a = variant(&d, "sleeve_underarm");
    let b = variant(&d, "sleeve_back");
    let out = d.join("report");
    let started = std::time::Instant::now();
    let (code, stdout, err) = run(&["compare", a.to_str().expect("utf8"), b.to_str().expect("utf8"), "--out", out.to_str().expect("utf8"), "--quiet"]);
    println!("{stdout}\n{err}\ncompare took {:.1} s", started.elapsed().as_secs_f64());
    assert_eq!(code, 0, "{err}");
    let report = read_json(&out.join("compare.json"));
    let md = std::fs::read_to_string(out.join("compare.md")).expect("compare.md");
    assert_eq!(report["poses"], serde_json::json!(["rest", "elbow_bent"]));
    let names = ["sleeve_underarm", "sleeve_back"];
    let summaries: Vec<Value> = names.iter().map(|n| read_json(&out.join(n).join("summary.json"))).collect();
    // The table's numbers are the summaries' numbers (both variants have the seam
    // "sleeve_seam", one row per pose).
    let rows = report["seam_rows"].as_array().expect("rows");
    assert_eq!(rows.len(), 2);
    for row in rows {
        let p = row["pose"].as_str().expect("pose");
        for (n, s) in names.iter().zip(&summaries) {
            let seam = pose(s, p)["measures"]["seams"].as_array().expect("seams").iter().find(|x| x["name"] == "sleeve_seam").expect("seam");
            for key in ["force_per_length_max", "force_per_length_mean", "utilisation_max", "utilisation_mean", "opening_max", "max_at"] {
                assert_eq!(row["values"][*n][key], seam[key], "{n} {p} {key}");
            }
            assert!(md.contains(&format!("{n}: q max")), "compare.md has no column for {n}");
        }
    }
    for (n, s) in names.iter().zip(&summaries) {
        assert_eq!(s["status"], "completed", "{n}");
        for p in ["rest", "elbow_bent"] {
            let e = pose(s, p);
            let m = &e["measures"];
            let body = &m["body"];
            println!(
                "{n} {p}: seam q max {:.3} mean {:.3} N/m, util max {:.2e}; contact force {:.3} N, p max {:.1} Pa, clearance min {:.2e} mean {:.2e} m; strain max {:.4}; {} time steps, {:.1} s",
                m["seams"][0]["force_per_length_max"].as_f64().unwrap_or(f64::NAN),
                m["seams"][0]["force_per_length_mean"].as_f64().unwrap_or(f64::NAN),
                m["seams"][0]["utilisation_max"].as_f64().unwrap_or(f64::NAN),
                body["total_force"].as_f64().unwrap_or(f64::NAN),
                body["pressure_max"].as_f64().unwrap_or(f64::NAN),
                body["clearance_min"].as_f64().unwrap_or(f64::NAN),
                body["clearance_mean"].as_f64().unwrap_or(f64::NAN),
                m["strain"]["max_principal"].as_f64().unwrap_or(f64::NAN),
                e["time_steps"],
                e["wall_s"].as_f64().unwrap_or(f64::NAN),
            );
            assert_eq!(e["at_rest"], true, "{n} {p}");
            // Barrier contact keeps every face off the body: clearance ≥ 0.
            let cmin = body["clearance_min"].as_f64().expect("clearance");
            assert!(cmin >= 0.0, "{n} {p}: clearance {cmin}");
            // The sewn sleeve grips the arm: the arm carries it by contact pressure.
            assert!(body["total_force"].as_f64().expect("force") > 0.0, "{n} {p}: no contact force");
            // Each pose's VTU, garment VTU and picture exist.
            for key in ["vtu", "garment_vtu", "picture"] {
                let f = e[key].as_str().unwrap_or_else(|| panic!("{n} {p}: no {key}"));
                let bytes = std::fs::read(out.join(n).join(f)).unwrap_or_else(|e| panic!("{n}/{f}: {e}"));
                if key == "picture" {
                    assert_eq!(&bytes[1..4], b"PNG", "{f}");
                }
            }
        }
    }
    // Bending the elbow stretches the sleeve over the point of the elbow (the outer contour
    // of a flexed joint is longer than the straight one): the seam lying there, on the back
    // of the arm, carries more force per length than at rest.
    let util = |s: &Value, p: &str| pose(s, p)["measures"]["seams"][0]["utilisation_max"].as_f64().expect("utilisation");
    let (rest, bent) = (util(&summaries[1], "rest"), util(&summaries[1], "elbow_bent"));
    assert!(bent > rest, "back seam: utilisation {bent} with the elbow bent vs {rest} at rest");
}

/// A bad file among the variants stops `compare` before any solve with a located error.
#[test]
fn compare_refuses_a_bad_variant_with_its_location() {
    let d = scratch("bad");
    let good = variant(&d, "sleeve_underarm");
    let text = std::fs::read_to_string(&good).expect("read");
    let bad = d.join("bad.ron");
    std::fs::write(&bad, text.replace("protocol: Some((body: \"body\"", "protocol: Some((body: \"bdy\"")).expect("write");
    let out = d.join("report");
    let (code, _, err) = run(&["compare", good.to_str().expect("utf8"), bad.to_str().expect("utf8"), "--out", out.to_str().expect("utf8"), "--quiet"]);
    assert_ne!(code, 0);
    let line = text.lines().position(|l| l.contains("protocol: Some((body:")).expect("protocol line") + 1;
    assert!(err.contains(&format!("bad.ron:{line}:")) && err.contains("protocol.body") && err.contains("no contact body named \"bdy\""), "{err}");
    assert!(!out.join("sleeve_underarm").exists(), "a variant was solved before the bad file was refused");
    // A scene without a protocol is named too.
    let plain = d.join("plain.ron");
    let without: Vec<&str> = text.lines().filter(|l| !l.trim_start().starts_with("protocol:")).collect();
    std::fs::write(&plain, without.join("\n")).expect("write");
    let (code, _, err) = run(&["compare", good.to_str().expect("utf8"), plain.to_str().expect("utf8"), "--out", out.to_str().expect("utf8"), "--quiet"]);
    assert_ne!(code, 0);
    assert!(err.contains("plain.ron") && err.contains("no protocol"), "{err}");
}
