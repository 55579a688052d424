//! `plyshell compare`: the same movement protocol on several garment variants (e.g. two
//! seam layouts), solved one after the other, and a side-by-side report.
//!
//! Every variant is a scene file with a `protocol` (`scene::protocol`); all must take the
//! garment through the same poses (same names, same order). Each is solved into
//! `OUT/VARIANT/` (its VTU/PVD series, pose pictures and `summary.json`); the report is built
//! from those `summary.json` files alone, so its numbers are theirs:
//!
//! - `compare.json`: per pose and seam the seam measures of each variant (force per length
//!   max/mean, utilisation max/mean, opening max, where), per pose and variant the strain
//!   hot spot, clearance, body pressure, ply separation and solve effort; seams matched by
//!   name, those present in only some variants listed as such;
//! - `compare.md`: the same as Markdown tables, with the pose pictures;
//! - `plots/force_SEAM_POSE.svg`: force per length along each seam in each pose, one line per
//!   variant.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde_json::{json, Value};

use crate::analysis::{self, RunError, RunOptions};
use crate::io::plot;
use crate::scene::{self, BuiltScene, Scene};
use crate::solver::Progress;

/// A loaded variant.
pub struct Variant {
    /// Name in the report (the scene's name, made unique by the file stem or an index).
    pub name: String,
    /// Scene file.
    pub file: PathBuf,
    pub scene: Scene,
    pub built: BuiltScene,
}

/// Loads and builds every file (errors located in the file), and checks that each has a
/// protocol through the same poses as the first.
pub fn load_variants(files: &[PathBuf]) -> Result<Vec<Variant>, String> {
    if files.len() < 2 {
        return Err(format!("compare needs at least two scene files, found {}", files.len()));
    }
    let mut out: Vec<Variant> = Vec::new();
    for f in files {
        let (scene, built) = scene::load(f).map_err(|e| e.to_string())?;
        let Some(p) = &built.protocol else {
            return Err(format!("{}: the scene has no protocol: compare runs each variant through a movement protocol (add `protocol: Some((body: \"…\"))` naming a mannequin body with a motion file)", f.display()));
        };
        if let Some(first) = out.first() {
            let names = |b: &BuiltScene| b.protocol.as_ref().map(|p| p.poses.iter().map(|q| q.name.clone()).collect::<Vec<_>>()).unwrap_or_default();
            let (a, b) = (names(&first.built), names(&built));
            if a != b {
                return Err(format!("{}: protocol poses [{}] differ from {}'s [{}]; every variant must go through the same poses", f.display(), b.join(", "), first.file.display(), a.join(", ")));
            }
        }
        let _ = p;
        let stem = f.file_stem().map_or_else(|| "variant".into(), |s| s.to_string_lossy().into_owned());
        let mut name = scene.name.clone();
        if out.iter().any(|v| v.name == name) {
            name = stem;
        }
        let base = name.clone();
        let mut k = 1;
        while out.iter().any(|v| v.name == name) {
            k += 1;
            name = format!("{base}_{k}");
        }
        out.push(Variant { name, file: f.clone(), scene, built });
    }
    Ok(out)
}

/// Solves every variant into `out/NAME/` and writes the report into `out`. A variant whose
/// solve fails is still reported (its status says why, with the poses it reached); the
/// result is then an error naming it, after the report is written.
pub fn run(variants: &[Variant], out: &Path, progress: &mut dyn FnMut(&str, &Progress)) -> Result<Report, String> {
    if out.exists() && !out.is_dir() {
        return Err(format!("--out {}: exists and is not a directory; name a directory for the report", out.display()));
    }
    std::fs::create_dir_all(out).map_err(|e| format!("--out {}: {e}", out.display()))?;
    let mut results = Vec::new();
    let mut failures = Vec::new();
    for v in variants {
        let dir = out.join(&v.name);
        let options = RunOptions { out_dir: Some(dir.clone()) };
        let r = analysis::run(&v.scene, &v.built, &options, &mut |p| progress(&v.name, p));
        if let Err(e) = &r {
            failures.push(format!("{}: {e}", v.name));
            if matches!(e, RunError::Setup(_)) {
                results.push((v, json!({ "status": format!("failed: {e}") })));
                continue;
            }
        }
        let text = std::fs::read_to_string(dir.join("summary.json")).map_err(|e| format!("{}: {e}", dir.join("summary.json").display()))?;
        let summary: Value = serde_json::from_str(&text).map_err(|e| format!("{}: {e}", dir.join("summary.json").display()))?;
        results.push((v, summary));
    }
    let inputs: Vec<(&str, String, &Value)> = results.iter().map(|(v, s)| (v.name.as_str(), v.file.display().to_string(), s)).collect();
    let report = write_report(out, &inputs)?;
    if failures.is_empty() { Ok(report) } else { Err(format!("the report is in {}, but {}", out.display(), failures.join("; "))) }
}

/// What the report holds (also `compare.json`).
pub struct Report {
    pub json: Value,
    /// Files written, relative to the output directory.
    pub files: Vec<String>,
}

/// The seam measures copied into the table.
const SEAM_KEYS: [&str; 6] = ["force_per_length_max", "force_per_length_mean", "utilisation_max", "utilisation_mean", "opening_max", "max_at"];

/// Writes `compare.json`, `compare.md` and the seam plots for the variants' summaries
/// `(name, file, summary.json)` into `out`.
pub fn write_report(out: &Path, variants: &[(&str, String, &Value)]) -> Result<Report, String> {
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let poses_of = |s: &Value| -> Vec<Value> { s["poses"]["poses"].as_array().cloned().unwrap_or_default() };
    let pose_names: Vec<String> = variants.iter().map(|v| poses_of(v.2)).max_by_key(|p| p.len()).unwrap_or_default().iter().filter_map(|p| p["pose"].as_str().map(String::from)).collect();
    // Seams by name, in first-seen order, with the variants that have them.
    let mut seams: Vec<(String, Vec<String>)> = Vec::new();
    for (name, _, s) in variants {
        for pose in poses_of(s) {
            for seam in pose["measures"]["seams"].as_array().into_iter().flatten() {
                let Some(sn) = seam["name"].as_str() else { continue };
                match seams.iter_mut().find(|(n, _)| n == sn) {
                    Some((_, vs)) if !vs.iter().any(|v| v == name) => vs.push(name.to_string()),
                    Some(_) => {}
                    None => seams.push((sn.to_string(), vec![name.to_string()])),
                }
            }
        }
    }
    let find_pose = |s: &Value, pose: &str| poses_of(s).into_iter().find(|p| p["pose"].as_str() == Some(pose));
    let find_seam = |p: &Value, seam: &str| p["measures"]["seams"].as_array().and_then(|a| a.iter().find(|x| x["name"].as_str() == Some(seam)).cloned());
    let mut rows = Vec::new();
    let mut pose_rows = Vec::new();
    for pose in &pose_names {
        for (seam, _) in &seams {
            let mut values = serde_json::Map::new();
            for (name, _, s) in variants {
                let v = find_pose(s, pose).and_then(|p| find_seam(&p, seam)).map(|x| {
                    let mut m = serde_json::Map::new();
                    for k in SEAM_KEYS {
                        m.insert(k.into(), x[k].clone());
                    }
                    Value::Object(m)
                });
                values.insert(name.to_string(), v.unwrap_or(Value::Null));
            }
            rows.push(json!({ "pose": pose, "seam": seam, "values": values }));
        }
        let mut values = serde_json::Map::new();
        for (name, _, s) in variants {
            let v = find_pose(s, pose).map(|p| {
                let m = &p["measures"];
                let gap_max = m["ply_separation"].as_array().and_then(|a| a.iter().filter_map(|g| g["max"].as_f64()).reduce(f64::max));
                json!({
                    "strain_max_principal": m["strain"]["max_principal"],
                    "strain_p95_principal": m["strain"]["p95_principal"],
                    "strain_at_panel": m["strain"]["panel"],
                    "strain_at": m["strain"]["at"],
                    "clearance_min": m["body"]["clearance_min"],
                    "clearance_mean": m["body"]["clearance_mean"],
                    "pressure_max": m["body"]["pressure_max"],
                    "total_contact_force": m["body"]["total_force"],
                    "ply_gap_max": gap_max,
                    "at_rest": p["at_rest"],
                    "time_steps": p["time_steps"],
                    "wall_s": p["wall_s"],
                    "picture": p["picture"],
                })
            });
            values.insert(name.to_string(), v.unwrap_or(Value::Null));
        }
        pose_rows.push(json!({ "pose": pose, "values": values }));
    }
    let all: Vec<&str> = variants.iter().map(|v| v.0).collect();
    let partial: Vec<Value> = seams.iter().filter(|(_, vs)| vs.len() < all.len()).map(|(n, vs)| json!({ "seam": n, "only_in": vs })).collect();
    let report = json!({
        "variants": variants.iter().map(|(n, f, s)| json!({ "name": n, "file": f, "status": s["status"], "wall_s": s["wall_s"], "sizes": s["sizes"] })).collect::<Vec<_>>(),
        "poses": pose_names,
        "seams": seams.iter().map(|(n, vs)| json!({ "name": n, "variants": vs })).collect::<Vec<_>>(),
        "seams_not_in_every_variant": partial,
        "seam_rows": rows,
        "pose_rows": pose_rows,
    });
    let mut files = Vec::new();
    let write = |name: &str, bytes: &[u8]| crate::io::atomic::write_atomic(&out.join(name), bytes).map_err(|e| format!("{}: {e}", out.join(name).display()));
    write("compare.json", serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?.as_bytes())?;
    files.push("compare.json".to_string());
    // Plots: force per length along each seam, per pose, one line per variant.
    let plots = out.join("plots");
    std::fs::create_dir_all(&plots).map_err(|e| format!("{}: {e}", plots.display()))?;
    let mut plot_files: BTreeMap<(String, String), String> = BTreeMap::new();
    for pose in &pose_names {
        for (seam, _) in &seams {
            let series: Vec<plot::Series> = variants
                .iter()
                .filter_map(|(name, _, s)| {
                    let x = find_pose(s, pose).and_then(|p| find_seam(&p, seam))?;
                    let (sv, fv) = (x["profile"]["s"].as_array()?, x["profile"]["force"].as_array()?);
                    let points = sv.iter().zip(fv).filter_map(|(a, b)| Some((a.as_f64()?, b.as_f64()?))).collect();
                    Some(plot::Series { name: name.to_string(), points, reference: false })
                })
                .collect();
            if series.is_empty() {
                continue;
            }
            let file = format!("plots/force_{}_{}.svg", file_safe(seam), file_safe(pose));
            plot::plot_xy(&out.join(&file), &format!("seam {seam}, pose {pose}"), "arc length along the seam (m)", "force per length (N/m)", &series, false, false).map_err(|e| format!("{file}: {e}"))?;
            plot_files.insert((pose.clone(), seam.clone()), file.clone());
            files.push(file);
        }
    }
    write("compare.md", markdown(&report, variants, &plot_files).as_bytes())?;
    files.push("compare.md".to_string());
    Ok(Report { json: report, files })
}

/// A name usable in a file name: letters, digits, `-` and `_` kept, anything else `_`.
fn file_safe(s: &str) -> String {
    s.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '_' { c } else { '_' }).collect()
}

/// A number for a table (3 significant digits), or "–".
fn num(v: &Value, factor: f64) -> String {
    match v.as_f64() {
        Some(x) if x.is_finite() => {
            let y = x * factor;
            if y != 0.0 && (y.abs() >= 1e4 || y.abs() < 1e-2) { format!("{y:.2e}") } else { format!("{y:.3}") }
        }
        _ => "–".into(),
    }
}

fn markdown(report: &Value, variants: &[(&str, String, &Value)], plots: &BTreeMap<(String, String), String>) -> String {
    let mut md = String::from("# Seam-layout comparison\n\n");
    md += "Written by `plyshell compare` from each variant's `summary.json` (`VARIANT/summary.json`; its VTU/PVD series and pose pictures beside it).\n\n";
    md += "| variant | file | status | nodes | solve (s) |\n|---|---|---|---|---|\n";
    for (n, f, s) in variants {
        md += &format!("| {n} | `{f}` | {} | {} | {} |\n", s["status"].as_str().unwrap_or("–"), s["sizes"]["nodes"], num(&s["wall_s"], 1.0));
    }
    if let Some(p) = report["seams_not_in_every_variant"].as_array().filter(|a| !a.is_empty()) {
        md += "\nSeams not in every variant:\n\n";
        for x in p {
            md += &format!("- `{}`: only in {}\n", x["seam"].as_str().unwrap_or(""), x["only_in"].as_array().map(|a| a.iter().filter_map(|v| v.as_str()).collect::<Vec<_>>().join(", ")).unwrap_or_default());
        }
    }
    let names: Vec<&str> = variants.iter().map(|v| v.0).collect();
    let empty = Vec::new();
    let rows = report["seam_rows"].as_array().unwrap_or(&empty);
    let pose_rows = report["pose_rows"].as_array().unwrap_or(&empty);
    for pose in report["poses"].as_array().unwrap_or(&empty).iter().filter_map(|p| p.as_str()) {
        md += &format!("\n## Pose `{pose}`\n\nSeam force per length q (N/m: max, mean), utilisation (q/strength: max) and opening (mm: max):\n\n| seam |");
        for n in &names {
            md += &format!(" {n}: q max | {n}: q mean | {n}: util. max | {n}: opening max |");
        }
        md += "\n|---|";
        md += &"---|".repeat(4 * names.len());
        md += "\n";
        for r in rows.iter().filter(|r| r["pose"].as_str() == Some(pose)) {
            let seam = r["seam"].as_str().unwrap_or("");
            md += &format!("| {seam} |");
            for n in &names {
                let v = &r["values"][*n];
                if v.is_null() {
                    md += " (no seam) | | | |";
                } else {
                    md += &format!(" {} | {} | {} | {} |", num(&v["force_per_length_max"], 1.0), num(&v["force_per_length_mean"], 1.0), num(&v["utilisation_max"], 1.0), num(&v["opening_max"], 1e3));
                }
            }
            md += "\n";
        }
        md += "\n| variant | max principal strain (panel) | 95th pct. | clearance min / mean (mm) | max pressure (Pa) | contact force (N) | ply gap max (mm) | at rest | time steps | wall (s) |\n|---|---|---|---|---|---|---|---|---|---|\n";
        let mut pictures = Vec::new();
        for r in pose_rows.iter().filter(|r| r["pose"].as_str() == Some(pose)) {
            for n in &names {
                let v = &r["values"][*n];
                if v.is_null() {
                    md += &format!("| {n} | (pose not reached) | | | | | | | | |\n");
                    continue;
                }
                md += &format!(
                    "| {n} | {} ({}) | {} | {} / {} | {} | {} | {} | {} | {} | {} |\n",
                    num(&v["strain_max_principal"], 1.0),
                    v["strain_at_panel"].as_str().unwrap_or("–"),
                    num(&v["strain_p95_principal"], 1.0),
                    num(&v["clearance_min"], 1e3),
                    num(&v["clearance_mean"], 1e3),
                    num(&v["pressure_max"], 1.0),
                    num(&v["total_contact_force"], 1.0),
                    num(&v["ply_gap_max"], 1e3),
                    v["at_rest"],
                    v["time_steps"],
                    num(&v["wall_s"], 1.0),
                );
                if let Some(p) = v["picture"].as_str() {
                    pictures.push(format!("![{n}, {pose}]({n}/{p})"));
                }
            }
        }
        if !pictures.is_empty() {
            md += &format!("\n{}\n", pictures.join(" "));
        }
        let seam_plots: Vec<String> = plots.iter().filter(|((p, _), _)| p == pose).map(|((_, s), f)| format!("[{s}]({f})")).collect();
        if !seam_plots.is_empty() {
            md += &format!("\nForce along the seams: {}\n", seam_plots.join(", "));
        }
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    fn summary(seams: &[(&str, f64)]) -> Value {
        let seams: Vec<Value> = seams.iter().map(|(n, q)| json!({ "name": n, "force_per_length_max": q, "profile": { "s": [0.0, 0.1], "force": [q, q] } })).collect();
        json!({ "status": "completed", "poses": { "poses": [ { "pose": "rest", "measures": { "seams": seams } } ] } })
    }

    /// Seams are matched by name: a seam in one variant only is listed as such and its other
    /// cells are null; shared seams carry each variant's own number.
    #[test]
    fn seams_are_matched_by_name() {
        let dir = std::env::temp_dir().join(format!("plyshell_compare_unit_{}", std::process::id()));
        let (a, b) = (summary(&[("side", 1.5), ("yoke", 2.0)]), summary(&[("side", 3.0), ("raglan", 4.0)]));
        let r = write_report(&dir, &[("A", "a.ron".into(), &a), ("B", "b.ron".into(), &b)]).expect("report");
        let rows = r.json["seam_rows"].as_array().expect("rows");
        let row = |s: &str| rows.iter().find(|x| x["seam"] == s).expect("row");
        assert_eq!(row("side")["values"]["A"]["force_per_length_max"], 1.5);
        assert_eq!(row("side")["values"]["B"]["force_per_length_max"], 3.0);
        assert!(row("yoke")["values"]["B"].is_null() && row("raglan")["values"]["A"].is_null());
        let partial = &r.json["seams_not_in_every_variant"];
        assert_eq!(partial, &json!([{ "seam": "yoke", "only_in": ["A"] }, { "seam": "raglan", "only_in": ["B"] }]));
        let md = std::fs::read_to_string(dir.join("compare.md")).expect("md");
        assert!(md.contains("`yoke`: only in A") && md.contains("`raglan`: only in B"), "{md}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
