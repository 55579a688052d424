//! Movement protocol and seam-layout comparison (issue 17, items 4 and 5).
//!
//! Two variants of a small cloth on the default mannequin (`garments/compare/flap_*.ron`:
//! a 0.2 m square of cotton broadcloth draped over the left forearm, arms held forward, with
//! a 0.08 m flap sewn to its right or its left edge by a compliant seam) are run by `plyshell
//! compare` through the two poses of `garments/body/carry.ron` (arms forward; then the trunk
//! turned 35°, the forearm carrying the cloth sideways). The shipped sleeve variants
//! (`garments/compare/`) take minutes per pose and are run for `docs/compare/` instead.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

fn exe() -> &'static str {
    env!("CARGO_BIN_EXE_plyshell")
}

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("garments/compare").join(name)
}

/// A fresh scratch directory under target/.
fn scratch(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("protocol_{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch dir");
    d
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
    let (a, b) = (data("flap_right.ron"), data("flap_left.ron"));
    let out = d.join("report");
    let started = std::time::Instant::now();
    let (code, stdout, err) = run(&["compare", a.to_str().expect("utf8"), b.to_str().expect("utf8"), "--out", out.to_str().expect("utf8"), "--quiet"]);
    println!("{stdout}\n{err}\ncompare took {:.1} s", started.elapsed().as_secs_f64());
    assert_eq!(code, 0, "{err}");
    let report = read_json(&out.join("compare.json"));
    let md = std::fs::read_to_string(out.join("compare.md")).expect("compare.md");
    let poses = ["arms_forward", "arms_forward_twist"];
    assert_eq!(report["poses"], serde_json::json!(poses));
    let names = ["flap_right", "flap_left"];
    let summaries: Vec<Value> = names.iter().map(|n| read_json(&out.join(n).join("summary.json"))).collect();
    // The table's numbers are the summaries' numbers (both variants have the seam
    // "flap_seam", one row per pose).
    let rows = report["seam_rows"].as_array().expect("rows");
    assert_eq!(rows.len(), 2);
    for row in rows {
        let p = row["pose"].as_str().expect("pose");
        for (n, s) in names.iter().zip(&summaries) {
            let seam = pose(s, p)["measures"]["seams"].as_array().expect("seams").iter().find(|x| x["name"] == "flap_seam").expect("seam");
            for key in ["force_per_length_max", "force_per_length_mean", "utilisation_max", "utilisation_mean", "opening_max", "max_at"] {
                assert_eq!(row["values"][*n][key], seam[key], "{n} {p} {key}");
            }
            assert!(md.contains(&format!("{n}: q max")), "compare.md has no column for {n}");
        }
    }
    // The flap's weight: areal density 0.12 kg/m² (the cotton_broadcloth preset) × 0.08 m ×
    // 0.2 m × 9.81 m/s².
    let weight = 0.12 * 0.08 * 0.2 * 9.81;
    for (n, s) in names.iter().zip(&summaries) {
        assert_eq!(s["status"], "completed", "{n}");
        assert_eq!(s["poses"]["poses"].as_array().map(Vec::len), Some(2), "{n}: one entry per pose");
        for p in poses {
            let e = pose(s, p);
            let m = &e["measures"];
            let body = &m["body"];
            let seam = &m["seams"][0];
            let r: Vec<f64> = seam["resultant"].as_array().expect("resultant").iter().map(|v| v.as_f64().expect("number")).collect();
            println!(
                "{n} {p}: seam resultant {r:.5?} N (flap weight {weight:.5} N), q max {:.4} mean {:.4} N/m, util max {:.2e}, opening max {:.2e} m; contact force {:.4} N, p max {:.2} Pa, clearance min {:.2e} m; strain max {:.4}; {} time steps, {:.1} s",
                seam["force_per_length_max"].as_f64().unwrap_or(f64::NAN),
                seam["force_per_length_mean"].as_f64().unwrap_or(f64::NAN),
                seam["utilisation_max"].as_f64().unwrap_or(f64::NAN),
                seam["opening_max"].as_f64().unwrap_or(f64::NAN),
                body["total_force"].as_f64().unwrap_or(f64::NAN),
                body["pressure_max"].as_f64().unwrap_or(f64::NAN),
                body["clearance_min"].as_f64().unwrap_or(f64::NAN),
                m["strain"]["max_principal"].as_f64().unwrap_or(f64::NAN),
                e["time_steps"],
                e["wall_s"].as_f64().unwrap_or(f64::NAN),
            );
            assert_eq!(e["at_rest"], true, "{n} {p}");
            // At rest the flap hangs free below the seam: the seam alone holds it, so the
            // force the cloth exerts on it through the seam is its weight, straight up.
            assert!((r[2] - weight).abs() <= 0.02 * weight, "{n} {p}: seam resultant {r:?} vs flap weight {weight}");
            assert!(r[0].hypot(r[1]) <= 0.05 * weight, "{n} {p}: horizontal seam resultant {r:?}");
            // Barrier contact keeps every face off the body: clearance ≥ 0; the arm carries
            // the cloth by contact.
            let cmin = body["clearance_min"].as_f64().expect("clearance");
            assert!(cmin >= 0.0, "{n} {p}: clearance {cmin}");
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
    assert!(out.join(format!("plots/force_flap_seam_{}.svg", poses[1])).exists(), "no seam plot");
}

/// A bad file among the variants stops `compare` before any solve with a located error.
#[test]
fn compare_refuses_a_bad_variant_with_its_location() {
    let d = scratch("bad");
    let text = std::fs::read_to_string(data("flap_right.ron")).expect("read");
    let good = d.join("good.ron");
    std::fs::write(&good, text.replace("\"../body/", &format!("\"{}/", PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("garments/body").display()))).expect("write");
    let text = std::fs::read_to_string(&good).expect("read");
    let bad = d.join("bad.ron");
    std::fs::write(&bad, text.replace("protocol: Some((body: \"body\"", "protocol: Some((body: \"bdy\"")).expect("write");
    let out = d.join("report");
    let (code, _, err) = run(&["compare", good.to_str().expect("utf8"), bad.to_str().expect("utf8"), "--out", out.to_str().expect("utf8"), "--quiet"]);
    assert_ne!(code, 0);
    let line = text.lines().position(|l| l.contains("protocol: Some((body:")).expect("protocol line") + 1;
    assert!(err.contains(&format!("bad.ron:{line}:")) && err.contains("protocol.body") && err.contains("no contact body named \"bdy\""), "{err}");
    assert!(!out.join("flap_right").exists(), "a variant was solved before the bad file was refused");
    // A scene without a protocol is named too.
    let plain = d.join("plain.ron");
    let without: Vec<&str> = text.lines().filter(|l| !l.trim_start().starts_with("protocol:")).collect();
    std::fs::write(&plain, without.join("\n")).expect("write");
    let (code, _, err) = run(&["compare", good.to_str().expect("utf8"), plain.to_str().expect("utf8"), "--out", out.to_str().expect("utf8"), "--quiet"]);
    assert_ne!(code, 0);
    assert!(err.contains("plain.ron") && err.contains("no protocol"), "{err}");
}
