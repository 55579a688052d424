//! Solve-driving benchmarks (`plyshell bench --drive`): the limp-fabric and large-rotation
//! cases of the solver, measured by how a solve gets to its answer — time steps or
//! increments, Newton iterations, line-search cuts, projected (indefinite) iterations and
//! the assembly/factorization split — beside its error.
//!
//! - Sheet onto a sphere: a free 0.8 m square sheet dropped 5 cm onto a sphere of radius
//!   0.2 m resting on a ground plane, friction 0.4, barrier contact, a Dynamic step with
//!   defaults to rest; the value is the vertical contact resultant over the weight ρ_A g A
//!   (reference 1, static equilibrium). Materials: SVK with E h = 500 N/m, D = 5e-6 N·m,
//!   ρ_A = 0.15 kg/m², and the `cotton_broadcloth` and `light_cotton` presets. The
//!   `_sequenced` rows solve the same drop by mesh sequencing (`coarse_levels`, from 16²
//!   up, `analysis_sequence`): their counts and times are summed over the levels, and
//!   `rms_to_direct_m` compares their rest positions with the direct solve's on the same
//!   mesh (the paths differ, and with friction so may the rest states).
//! - Sagging plate: a 0.6 m square plate, t = 0.4 mm, E = 2e8 Pa, ν = 0.3, ρ_A = 0.12
//!   kg/m², clamped on one edge, sagging under its weight in a Static step with the default
//!   (automatic) increments; the value is the tip deflection at the middle of the free edge,
//!   against the 100×100 result (−0.57513 m, measured on this code: the mesh-converged
//!   value to 1e-4 relative, 10² … 100² giving −0.57418, −0.57478, −0.57508, −0.57513).

use std::path::Path;
use std::time::Instant;

use serde::Serialize;

use super::{series_by, solve_variant, write_records};

/// Sheet-onto-sphere scene; `{N}`, `{MATERIAL}`, `{SECTION}`, `{LOAD}` and `{DYNAMIC}` (the
/// Dynamic step's settings, empty for the defaults) are substituted.
const SHEET_ON_SPHERE: &str = r#"Scene(
    name: "sheet_on_sphere",
    materials: {"cloth": {MATERIAL}},
    parts: [(name: "sheet", mesh: Rectangle(lx: 0.8, ly: 0.8, nx: {N}, ny: {N}), material: "cloth", {SECTION})],
    loads: {"weight": {LOAD}},
    steps: [(name: "fall", increments: 1, scale: {"weight": 1.0}, kind: Dynamic(({DYNAMIC})))],
    contact: Some((formulation: Barrier(),
        bodies: [
            (name: "ball", shape: Sphere(radius: 0.2), translation: (0.4, 0.4, -0.2503), friction: 0.4),
            (name: "ground", shape: Plane, translation: (0.0, 0.0, -0.4503), friction: 0.4),
        ],
    )),
)"#;

/// Sagging-plate scene; `{N}` is substituted.
const SAGGING_PLATE: &str = r#"Scene(
    name: "sagging_plate",
    materials: {"m": StVenantKirchhoff(young: 2.0e8, poisson: 0.3)},
    parts: [(name: "plate", mesh: Rectangle(lx: 0.6, ly: 0.6, nx: {N}, ny: {N}), material: "m", thickness: 0.4e-3, areal_density: 0.12)],
    node_sets: {"edge": Plane(point: (0.0, 0.0, 0.0), normal: (1.0, 0.0, 0.0))},
    boundary: [Clamp(set: "edge")],
    loads: {"weight": Gravity(part: "plate", areal_density: 0.12, g: (0.0, 0.0, -9.81))},
    steps: [(name: "sag", increments: 10, scale: {"weight": 1.0})],
    monitors: [(name: "tip", point: (0.6, 0.3, 0.0), dofs: [Uz])],
)"#;

/// Tip deflection of the sagging plate on the 100×100 mesh (m); see the module doc.
pub const SAG_REFERENCE: f64 = -0.57513;

/// (material entry, part fields, load) of the sheet materials.
const SHEETS: [(&str, &str, &str, &str); 3] = [
    (
        "svk",
        "StVenantKirchhoff(young: 1.5128e6, poisson: 0.3)",
        "thickness: 3.3045e-4, areal_density: 0.15",
        r#"Gravity(part: "sheet", areal_density: 0.15, g: (0.0, 0.0, -9.81))"#,
    ),
    (
        "cotton_broadcloth",
        r#"Fabric((preset: Some("cotton_broadcloth")))"#,
        "thickness: 0.3e-3",
        r#"SelfWeight(part: "sheet", g: (0.0, 0.0, -9.81))"#,
    ),
    (
        "light_cotton",
        r#"Fabric((preset: Some("light_cotton")))"#,
        "thickness: 0.25e-3",
        r#"SelfWeight(part: "sheet", g: (0.0, 0.0, -9.81))"#,
    ),
];

/// One solve-driving run.
#[derive(Clone, Debug, Serialize)]
pub struct DriveRecord {
    /// Case name.
    pub case: String,
    /// Mesh (elements per side).
    pub mesh: String,
    /// Free DOFs (0 when the scene did not build).
    pub dofs: usize,
    /// Converged time steps or increments.
    pub steps: usize,
    /// Newton iterations.
    pub newton_iterations: usize,
    /// Step halvings of the energy line search.
    pub line_search_cuts: usize,
    /// Newton iterations on the PSD-projected tangent.
    pub projected_iterations: usize,
    /// Assembly time (s).
    pub assembly_s: f64,
    /// Factorization time (s).
    pub factorization_s: f64,
    /// Wall time of the solve (s).
    pub wall_s: f64,
    /// Computed value (NaN when the solve failed).
    pub value: f64,
    /// Reference value.
    pub reference: f64,
    /// Relative error (NaN when the solve failed).
    pub rel_error: f64,
    /// "completed" or the failure diagnosis.
    pub status: String,
    /// Mesh sequencing (`coarse_levels`): per level "mesh: time steps / Newton iterations",
    /// the scene's mesh last; the counts and times above are then summed over the levels.
    /// Empty for a direct solve.
    pub levels: String,
    /// RMS distance (m) between the rest positions of the nodes and those of the direct
    /// solve on the same mesh (NaN when there is none to compare with).
    pub rms_to_direct_m: f64,
}

/// Solves `template` with `{N}` = n and the other substitutions; the value from the summary.
/// Returns the record and the rest positions of the nodes. A sequenced solve's counts and
/// times are those of all its levels (`summary.sequence`).
fn run_case(
    case: &str,
    n: usize,
    template: &str,
    replace: &[(&str, String)],
    reference: f64,
    value: impl Fn(&crate::results::Summary) -> Option<f64>,
) -> (DriveRecord, Vec<[f64; 3]>) {
    let mut text = template.replace("{N}", &n.to_string());
    for (from, to) in replace {
        text = text.replace(from, to);
    }
    let t = Instant::now();
    let outcome = solve_variant(&text, case, &[]);
    let wall_s = t.elapsed().as_secs_f64();
    let mesh = format!("{n}x{n}");
    match outcome {
        Ok(s) => {
            let v = value(&s).unwrap_or(f64::NAN);
            let mut r = DriveRecord {
                case: case.into(),
                mesh,
                dofs: s.sizes.dofs,
                steps: s.increments.len(),
                newton_iterations: s.newton_iterations,
                line_search_cuts: s.timings.line_search_cuts,
                projected_iterations: s.timings.projected_iterations,
                assembly_s: s.timings.assembly,
                factorization_s: s.timings.factorization,
                wall_s,
                value: v,
                reference,
                rel_error: ((v - reference) / reference).abs(),
                status: s.status.clone(),
                levels: String::new(),
                rms_to_direct_m: f64::NAN,
            };
            if let Some(serde_json::Value::Array(levels)) = s.extra.get("sequence").map(|q| &q["levels"]) {
                let count = |l: &serde_json::Value, k: &str| l[k].as_u64().unwrap_or(0) as usize;
                let secs = |l: &serde_json::Value, k: &str| l[k].as_f64().unwrap_or(0.0);
                let mut names = Vec::new();
                for l in levels {
                    r.steps += count(l, "time_steps");
                    r.newton_iterations += count(l, "newton_iterations");
                    r.line_search_cuts += count(l, "line_search_cuts");
                    r.projected_iterations += count(l, "projected_iterations");
                    r.assembly_s += secs(l, "assembly_s");
                    r.factorization_s += secs(l, "factorization_s");
                    names.push(format!("{}: {}/{}", l["mesh"].as_str().unwrap_or("?"), count(l, "time_steps"), count(l, "newton_iterations")));
                }
                names.push(format!("{n}x{n}: {}/{}", s.increments.len(), s.newton_iterations));
                r.levels = names.join(", ");
            }
            (r, s.final_positions)
        }
        Err(e) => (
            DriveRecord {
                case: case.into(),
                mesh,
                dofs: 0,
                steps: 0,
                newton_iterations: 0,
                line_search_cuts: 0,
                projected_iterations: 0,
                assembly_s: 0.0,
                factorization_s: 0.0,
                wall_s,
                value: f64::NAN,
                reference,
                rel_error: f64::NAN,
                status: e,
                levels: String::new(),
                rms_to_direct_m: f64::NAN,
            },
            Vec::new(),
        ),
    }
}

/// RMS distance between two lists of node positions of the same mesh (NaN otherwise).
pub fn rms_distance(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    if a.len() != b.len() || a.is_empty() {
        return f64::NAN;
    }
    let sum: f64 = a.iter().zip(b).map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>()).sum();
    (sum / a.len() as f64).sqrt()
}

/// Coarser meshes of the sequenced sheet drops: down to 16 elements per side.
fn sequence_levels(n: usize) -> usize {
    (n / 16).max(1).ilog2() as usize
}

/// Vertical contact resultant of the last increment over the weight of the sheet.
fn resultant_over_weight(s: &crate::results::Summary, weight: f64) -> Option<f64> {
    let last = s.increments.last()?;
    let rz = last
        .extra
        .iter()
        .rev()
        .find_map(|v| v.get("contact")?.get("resultant")?.get(2)?.as_f64())?;
    Some(rz / weight)
}

/// Runs the sheet-on-sphere and sagging-plate cases (the smallest meshes with `quick`),
/// prints the table, writes JSON and a wall-time-per-case plot beside it.
pub fn run_drive(json: &Path, quick: bool) -> Result<(), String> {
    let mut recs: Vec<DriveRecord> = Vec::new();
    println!(
        "{:<34} {:>8} {:>7} {:>6} {:>7} {:>6} {:>6} {:>8} {:>8} {:>8} {:>10} {:>9}  status",
        "case",
        "mesh",
        "dofs",
        "steps",
        "newton",
        "cuts",
        "proj",
        "asm_s",
        "fact_s",
        "wall_s",
        "value",
        "rel_err"
    );
    let print = |r: &DriveRecord| {
        let status: String = r.status.chars().take(60).collect();
        println!(
            "{:<34} {:>8} {:>7} {:>6} {:>7} {:>6} {:>6} {:>8.2} {:>8.2} {:>8.2} {:>10.5} {:>9.2e}  {status}",
            r.case,
            r.mesh,
            r.dofs,
            r.steps,
            r.newton_iterations,
            r.line_search_cuts,
            r.projected_iterations,
            r.assembly_s,
            r.factorization_s,
            r.wall_s,
            r.value,
            r.rel_error
        );
        if !r.levels.is_empty() {
            let rms = if r.rms_to_direct_m.is_finite() { format!("; rest positions {:.2e} m RMS from the direct solve", r.rms_to_direct_m) } else { String::new() };
            println!("{:<34} levels (time steps/Newton iterations) {}{rms}", "", r.levels);
        }
    };
    for (name, material, section, load) in SHEETS {
        let meshes: &[usize] = match (name, quick) {
            ("svk", false) => &[16, 32, 64, 128],
            ("svk", true) => &[16],
            (_, false) => &[32, 64],
            (_, true) => &[32],
        };
        // Mesh sequencing (`coarse_levels`, from 16² up) beside the direct drop.
        let sequenced: &[usize] = match (name, quick) {
            ("svk", false) => &[32, 64, 128],
            ("svk", true) => &[32],
            ("cotton_broadcloth", false) => &[64],
            _ => &[],
        };
        let density = if name == "svk" {
            Some(0.15)
        } else {
            crate::material::FabricProperties::preset(name).map(|p| p.areal_density)
        };
        let mut direct: Vec<(usize, Vec<[f64; 3]>)> = Vec::new();
        for (&n, levels) in meshes.iter().map(|n| (n, 0)).chain(sequenced.iter().map(|n| (n, sequence_levels(*n)))) {
            let rep = [
                ("{MATERIAL}", material.to_string()),
                ("{SECTION}", section.to_string()),
                ("{LOAD}", load.to_string()),
                ("{DYNAMIC}", if levels > 0 { format!("coarse_levels: {levels}") } else { String::new() }),
            ];
            let case = if levels > 0 { format!("sheet_on_sphere_{name}_sequenced") } else { format!("sheet_on_sphere_{name}") };
            let (mut r, positions) = run_case(&case, n, SHEET_ON_SPHERE, &rep, 1.0, |s| {
                resultant_over_weight(s, density? * 0.64 * 9.81)
            });
            if levels == 0 {
                direct.push((n, positions));
            } else if let Some((_, d)) = direct.iter().find(|d| d.0 == n) {
                r.rms_to_direct_m = rms_distance(d, &positions);
            }
            print(&r);
            recs.push(r);
        }
    }
    for &n in if quick { &[20][..] } else { &[20, 50, 100][..] } {
        let (r, _) = run_case(
            "sagging_plate_tip_uz",
            n,
            SAGGING_PLATE,
            &[],
            SAG_REFERENCE,
            |s| s.monitors.first()?.values.last()?.first().copied(),
        );
        print(&r);
        recs.push(r);
    }
    let series = series_by(&recs, |r| &r.case, |r| (r.dofs > 0 && r.wall_s > 0.0).then_some((r.dofs as f64, r.wall_s)));
    let svg = write_records(json, &recs, &series, ("plyshell solve driving: wall time against model size", "free DOFs", "wall time (s)"))?;
    println!("records in {}, plot in {}", json.display(), svg.display());
    Ok(())
}
