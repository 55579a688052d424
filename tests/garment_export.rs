//! Garment export (issue 5): elements carry panel, ply and material ids; seams are line cells
//! with their force per unit length; the flat pattern is exported beside the 3D states. All
//! read back with Python's meshio (PyPI).
//!
//! Reference for the seam force: a strip pulled by a uniform edge traction q carries the
//! same force per unit length q across any section (statics), so the tie force of a seam
//! across the strip is −q per unit length (the master side holds the slave side back).

use std::path::{Path, PathBuf};
use std::process::Command;

use plyshell::{analysis, scene};

/// A Python with meshio: $PLYSHELL_PYTHON, else the virtual environment under target/ that
/// tests/export_meshio.rs creates.
fn python_with_meshio() -> PathBuf {
    if let Ok(p) = std::env::var("PLYSHELL_PYTHON") {
        return PathBuf::from(p);
    }
    let venv = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/py-venv");
    let py = venv.join("bin/python");
    let ok = Command::new(&py).args(["-c", "import meshio"]).status().map(|s| s.success()).unwrap_or(false);
    if !ok {
        let made = Command::new("python3").args(["-m", "venv"]).arg(&venv).status().expect("python3 -m venv");
        assert!(made.success());
        let pip = Command::new(venv.join("bin/pip")).args(["install", "--quiet", "meshio"]).status().expect("pip");
        assert!(pip.success(), "pip install meshio failed");
    }
    py
}

const SCRIPT: &str = r#"
import json, sys, os
import meshio
m = meshio.read(sys.argv[1])
out = {"types": [c.type for c in m.cells], "counts": [len(c.data) for c in m.cells]}
for name in ["panel", "ply", "material", "seam", "seam_force_per_length"]:
    out[name] = [b.tolist() for b in m.cell_data[name]]
out["zmax"] = float(abs(m.points[:, 2]).max())
print(json.dumps(out))
"#;

fn read(file: &Path) -> serde_json::Value {
    let o = Command::new(python_with_meshio()).arg("-c").arg(SCRIPT).arg(file).output().expect("python");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).expect("json")
}

fn run(text: &str, out: &Path) -> plyshell::results::Summary {
    let sc = scene::parse("x.ron", text).unwrap_or_else(|e| panic!("{e}"));
    let built = scene::build(&sc, "x.ron", text).unwrap_or_else(|e| panic!("{e}"));
    let _ = std::fs::remove_dir_all(out);
    analysis::run(&sc, &built, &analysis::RunOptions { out_dir: Some(out.to_path_buf()) }, &mut |_| {}).unwrap_or_else(|e| panic!("{e}"))
}

/// Plain seam across a strip in tension q = 1000 N/m, matching node rows (part b is meshed
/// 12 × 2 against a's 8 × 2): every seam line cell carries (−1000, 0, 0) N/m within 1e-6
/// relative. (Non-matching rows: see tests/seams.rs — only the total is exact there.)
#[test]
fn seam_line_cells_carry_the_transmitted_force() {
    let text = r#"Scene(
    name: "pull",
    materials: {"m": StVenantKirchhoff(young: 1.0e7, poisson: 0.0)},
    parts: [
        (name: "a", mesh: Rectangle(lx: 0.5, ly: 0.1, nx: 8, ny: 2), material: "m", thickness: 0.01),
        (name: "b", mesh: Rectangle(lx: 0.5, ly: 0.1, nx: 12, ny: 2), material: "m", thickness: 0.01, offset: Some((0.5, 0.0, 0.0))),
    ],
    node_sets: {"root": Edge(part: "a", edge: "xmin"), "cut_a": Edge(part: "a", edge: "xmax"), "cut_b": Edge(part: "b", edge: "xmin"), "tip": Edge(part: "b", edge: "xmax")},
    boundary: [Clamp(set: "root"), Fix(set: "tip", dofs: [Uz])],
    loads: {"p": EdgeForce(set: "tip", force_per_length: (1000.0, 0.0, 0.0))},
    seams: [(name: "cut", master: "cut_a", slave: "cut_b", kind: Plain)],
    steps: [(name: "load", increments: 2, scale: {"p": 1.0})],
)"#;
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/test-output/garment_export_pull");
    let summary = run(text, &out);
    assert!(summary.files.iter().any(|f| f == "pull_garment.pvd"), "{:?}", summary.files);
    let v = read(&out.join("pull_garment_0002.vtu"));
    assert_eq!(v["types"], serde_json::json!(["quad", "line"]));
    assert_eq!(v["counts"][1], 2, "two seam segments along the 3-node slave row");
    let forces = v["seam_force_per_length"][1].as_array().expect("line forces").clone();
    for f in &forces {
        let fx = f[0].as_f64().unwrap_or(0.0);
        println!("seam force per length {f}");
        assert!((fx + 1000.0).abs() < 1e-6 * 1000.0 && f[1].as_f64().unwrap_or(1.0).abs() < 1e-6 * 1000.0, "{f}");
    }
}

/// The sewn sleeve's export: quads tagged with panel 0, ply 0, material 0; the underarm seam
/// as 20 line cells; the flat pattern lies in the plane z = 0.
#[test]
fn garment_vtu_has_panel_ply_material_and_seam_lines() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/garments/sleeve.ron");
    let text = std::fs::read_to_string(path).expect("sleeve.ron").replace("increments: 10, scale: {\"sew\"", "increments: 5, scale: {\"sew\"");
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/test-output/garment_export_sleeve");
    let summary = run(&text, &out);
    let last = summary.files.iter().rfind(|f| f.starts_with("sleeve_garment_0")).expect("a garment vtu").clone();
    let v = read(&out.join(&last));
    assert_eq!(v["counts"], serde_json::json!([360, 20]));
    for name in ["panel", "ply", "material"] {
        assert!(v[name][0].as_array().expect("quads").iter().all(|x| x.as_i64() == Some(0)), "{name}");
    }
    assert!(v["seam"][1].as_array().expect("lines").iter().all(|x| x.as_i64() == Some(0)));
    let flat = read(&out.join("sleeve_pattern.vtu"));
    assert!(flat["zmax"].as_f64().unwrap_or(1.0) < 1e-12, "{}", flat["zmax"]);
}

const PVD_SCRIPT: &str = r#"
import json, sys, os, xml.etree.ElementTree as ET
import meshio
out = sys.argv[1]
res = {}
for pvd in sys.argv[2:]:
    files = [d.get("file") for d in ET.parse(os.path.join(out, pvd)).getroot().iter("DataSet")]
    cells = []
    for f in files:
        m = meshio.read(os.path.join(out, f))
        cells.append({c.type: len(c.data) for c in m.cells})
        if "ply" in m.cell_data:
            res["plies"] = sorted(set(int(v) for v in m.cell_data["ply"][0]))
            res["materials"] = sorted(set(int(v) for v in m.cell_data["material"][0]))
            res["ply_names"] = bytes(m.field_data["ply_names"].astype("uint8")).decode().split("\0")[:-1]
            res["ply_thickness"] = m.field_data["ply_thickness"].tolist()
            quads = m.cells[0].data
            r = (m.points[:, 0] ** 2 + m.points[:, 1] ** 2) ** 0.5
            ply = m.cell_data["ply"][0]
            res["radius_by_ply"] = [float(r[quads[ply == k]].mean()) for k in sorted(set(ply.tolist()))]
            res["ply_masks"] = sorted(set(int(v) for v in m.cell_data["ply_mask"][0]))
    res[pvd] = cells
print(json.dumps(res))
"#;

/// The three-ply NBC sleeve solves end to end from garments/nbc_sleeve.ron to VTU/PVD files
/// that meshio reads (both collections, every file), with plies 0, 1, 2 and three materials
/// tagged. Statics: the vertical support forces at the armhole carry the whole applied
/// weight within 1e-6, and that weight is Σ ρ_k g · 2πR·H within 2 % (the plies sit at
/// radii R ± 1 mm and the 19-sided facets lose 0.45 % of the perimeter).
#[test]
fn nbc_sleeve_solves_end_to_end() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/garments/nbc_sleeve.ron");
    let text = std::fs::read_to_string(path).expect("nbc_sleeve.ron");
    let sc = scene::parse("nbc_sleeve.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let built = scene::build(&sc, "nbc_sleeve.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let model = &built.model;
    println!("nodes {} elements {} equations {} ties {}", model.n_nodes(), model.elements.len(), model.dofs.n_free, model.dofs.ties.len());
    // Statics through the solver's internal forces at the reactions.
    let mut solver = plyshell::solver::Solver::new(model, sc.solver.clone()).unwrap_or_else(|e| panic!("{e}"));
    let mut state = model.initial_state();
    solver.run(&built.steps, &mut state, &mut |_, _, _| {}, &mut |_| {}).unwrap_or_else(|e| panic!("{e}"));
    let f = solver.internal_force();
    let mut f_ext = vec![0.0; f.len()];
    let scales = vec![1.0; model.loads.len()];
    model.external_force(&state, &scales, &mut f_ext);
    let untied_z = |g: &usize| g % 5 == 2 && model.dofs.tie_of[*g] == plyshell::model::UNTIED;
    let support: f64 = (0..f.len()).filter(untied_z).filter(|&g| model.dofs.eq[g] == plyshell::model::FIXED).map(|g| f[g] - f_ext[g]).sum();
    let applied: f64 = (0..f.len()).filter(untied_z).map(|g| f_ext[g]).sum();
    let weight = (0.20 + 0.25 + 0.10) * 9.81 * 0.376991118 * 0.40;
    println!("support force {support:.9} N, applied {applied:.9} N, continuum weight {weight:.9} N");
    assert!((support + applied).abs() < 1e-6 * weight, "{support} vs {applied}");
    assert!((-applied / weight - 1.0).abs() < 2e-2, "faceted, ply-offset areas within 2 % of 2πR·H");
    // Files through the analysis driver, read back by meshio.
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/test-output/garment_export_nbc");
    let summary = run(&text, &out);
    assert_eq!(summary.status, "completed");
    let o = Command::new(python_with_meshio()).arg("-c").arg(PVD_SCRIPT).arg(&out).arg("nbc_sleeve.pvd").arg("nbc_sleeve_garment.pvd").output().expect("python");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    // One file per converged increment (automatic increments: as many as the step took).
    let n = summary.increments.len();
    assert!(n >= 1);
    assert_eq!(v["nbc_sleeve.pvd"].as_array().map(|a| a.len()), Some(n));
    assert_eq!(v["nbc_sleeve_garment.pvd"].as_array().map(|a| a.len()), Some(n));
    assert_eq!(v["nbc_sleeve_garment.pvd"][n - 1]["quad"], 1140);
    // The underarm seam: 20 segments in each of the 3 plies (every ply is sewn).
    assert_eq!(v["nbc_sleeve_garment.pvd"][3]["line"], 60);
    assert_eq!(v["plies"], serde_json::json!([0, 1, 2]));
    assert_eq!(v["materials"], serde_json::json!([0, 1, 2]));
    // Ply ids follow the stack, innermost first (issue 19), with names and thicknesses as
    // field data; the mean radius of each ply's nodes grows with its id.
    assert_eq!(v["ply_names"], serde_json::json!(["liner", "carbon", "outer"]));
    assert_eq!(v["ply_thickness"], serde_json::json!([0.0003, 0.0015, 0.0004]));
    let r: Vec<f64> = v["radius_by_ply"].as_array().expect("radii").iter().filter_map(|x| x.as_f64()).collect();
    println!("mean radius by ply id {r:?}");
    assert!(r.len() == 3 && r[0] < r[1] && r[1] < r[2], "{r:?}");
}

/// Stack order of plies from several panels, innermost first.
#[test]
fn plies_are_numbered_in_stack_order() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/garments/nbc_sleeve.ron")).expect("nbc_sleeve.ron");
    let sc = scene::parse("nbc_sleeve.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let mut g = sc.garment.expect("a garment");
    assert_eq!(g.plies_in_stack_order(), ["liner", "carbon", "outer"]);
    // A second panel without the carbon layer, and an unused ply, keep the order.
    let mut p = g.panels[0].clone();
    p.name = "hood".into();
    p.plies = vec!["outer".into(), "liner".into()];
    g.panels.insert(0, p);
    g.plies.insert("a_spare".into(), g.plies["liner"].clone());
    assert_eq!(g.plies_in_stack_order(), ["liner", "carbon", "outer", "a_spare"]);
}

/// Issue 18 (ply fidelity): the NBC sleeve with `ply_model: Laminate` — one shell whose
/// section stacks outer shell, carbon layer and liner — solves end to end, and its export
/// still names the plies it stands for: ply and material −1 on its quads, `ply_mask` 7 (ply
/// ids 0, 1, 2), the three `ply_names`, and the OBJ group `sleeve/outer+carbon+liner`. Its
/// weight (the three Gravity loads on the plies' names, aliases of the laminate) is
/// Σ ρ_k g · 2πR·H within 1 % (the 19-sided facets lose 0.45 % of the perimeter). The
/// cuff's vertical displacement is reported against the discrete model (numbers, not a
/// tight bound: the discrete sleeve hangs from its outer ply only, the laminate from the
/// whole stack, so their upper 10 cm above the first quilting line differ in stiffness).
#[test]
fn nbc_sleeve_as_a_laminate_solves_and_names_its_plies() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/garments/nbc_sleeve.ron");
    let text = std::fs::read_to_string(path).expect("nbc_sleeve.ron");
    let laminate = text.replace("element_size: 0.02,", "element_size: 0.02,\n        ply_model: Laminate,");
    assert_ne!(laminate, text);
    let sc = scene::parse("nbc_sleeve.ron", &laminate).unwrap_or_else(|e| panic!("{e}"));
    let built = scene::build(&sc, "nbc_sleeve.ron", &laminate).unwrap_or_else(|e| panic!("{e}"));
    let model = &built.model;
    let mut f_ext = vec![0.0; model.n_nodes() * 5];
    model.external_force(&model.initial_state(), &vec![1.0; model.loads.len()], &mut f_ext);
    // (Forces on tied DOFs are carried over to their masters: count the untied ones.)
    let applied: f64 = (2..f_ext.len()).step_by(5).filter(|&g| model.dofs.tie_of[g] == plyshell::model::UNTIED).map(|g| f_ext[g]).sum();
    let weight = (0.20 + 0.25 + 0.10) * 9.81 * 0.376991118 * 0.40;
    println!("laminate: applied {applied:.6} N vs continuum weight {weight:.6} N");
    assert!((-applied / weight - 1.0).abs() < 1e-2, "{applied} vs {weight}");
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/test-output/garment_export_nbc_laminate");
    let lam = run(&laminate, &out);
    let dis = run(&text, &Path::new(env!("CARGO_MANIFEST_DIR")).join("target/test-output/garment_export_nbc_discrete"));
    assert_eq!((lam.status.as_str(), dis.status.as_str()), ("completed", "completed"));
    let cuff = |s: &plyshell::results::Summary| s.monitors.iter().find(|m| m.name == "cuff_outer").and_then(|m| m.values.last()).map_or(f64::NAN, |v| v[0]);
    for (name, s) in [("laminate", &lam), ("discrete", &dis)] {
        println!("{name}: {} nodes, {} free DOFs, {} Newton iterations, wall {:.2} s, cuff Uz {:.4e} m", s.sizes.nodes, s.sizes.dofs, s.newton_iterations, s.wall_s, cuff(s));
    }
    println!("cuff Uz laminate / discrete = {:.3}", cuff(&lam) / cuff(&dis));
    assert_eq!(3 * lam.sizes.nodes, dis.sizes.nodes, "one shell instead of three");
    assert!(cuff(&lam) < 0.0 && (cuff(&lam) / cuff(&dis) - 1.0).abs() < 0.25, "cuff {} vs {}", cuff(&lam), cuff(&dis));
    let o = Command::new(python_with_meshio()).arg("-c").arg(PVD_SCRIPT).arg(&out).arg("nbc_sleeve_garment.pvd").output().expect("python");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert_eq!(v["plies"], serde_json::json!([-1]));
    assert_eq!(v["materials"], serde_json::json!([-1]));
    assert_eq!(v["ply_masks"], serde_json::json!([7]));
    assert_eq!(v["ply_names"], serde_json::json!(["liner", "carbon", "outer"]));
    let obj = std::fs::read_to_string(out.join("nbc_sleeve_garment.obj")).expect("garment OBJ");
    assert!(obj.contains("sleeve/outer+carbon+liner"), "OBJ groups: {:?}", obj.lines().filter(|l| l.starts_with('g') || l.starts_with('o')).collect::<Vec<_>>());
}

const CLEARANCE_SCRIPT: &str = r#"
import json, sys
import meshio
res = {}
for f in sys.argv[1:]:
    m = meshio.read(f)
    res[f] = {k: m.point_data[k].tolist() for k in ("body_clearance", "contact_pressure") if k in m.point_data}
print(json.dumps(res))
"#;

/// Clearance to the body and contact pressure on the garment VTU (issue 17, item 7), as on
/// the shell VTU: the two-panel seam strip (thickness 10 mm, in the plane z = 0, pulled in
/// its plane) over a floor plane at z = −0.05 m has the clearance 0.05 − 0.005 = 0.045 m at
/// every node (exact: plane distance minus the half thickness; the in-plane pull keeps z = 0
/// to round-off) and no contact pressure, in both files, read by meshio.
#[test]
fn garment_vtu_carries_body_clearance_and_contact_pressure() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/garments/examples/two_panel_seam.ron");
    let text = std::fs::read_to_string(path).expect("two_panel_seam.ron");
    let text = text.replace("linear: true, ", "").replace(
        "    monitors:",
        "    contact: Some((bodies: [(name: \"floor\", shape: Plane, translation: (0.0, 0.0, -0.05))])),\n    monitors:",
    );
    assert!(text.contains("floor") && !text.contains("linear: true"), "the scene changed: update this test's replacements");
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/test-output/garment_export_clearance");
    let summary = run(&text, &out);
    let shell = summary.files.iter().rfind(|f| f.starts_with("two_panel_seam_0")).expect("a shell vtu").clone();
    let garment = summary.files.iter().rfind(|f| f.starts_with("two_panel_seam_garment_0")).expect("a garment vtu").clone();
    let (a, b) = (out.join(&shell), out.join(&garment));
    let o = Command::new(python_with_meshio()).arg("-c").arg(CLEARANCE_SCRIPT).arg(&a).arg(&b).output().expect("python");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    for f in [&a, &b] {
        let data = &v[f.to_str().expect("utf8")];
        let clearance = data["body_clearance"].as_array().unwrap_or_else(|| panic!("{}: no body_clearance: {data}", f.display()));
        assert_eq!(clearance.len(), 110, "{}", f.display());
        for c in clearance {
            let c = c.as_f64().expect("a number");
            assert!((c - 0.045).abs() < 1e-9, "{}: clearance {c}, expected 0.045", f.display());
        }
        let pressure = data["contact_pressure"].as_array().expect("contact_pressure");
        assert!(pressure.iter().all(|p| p.as_f64() == Some(0.0)), "{}", f.display());
    }
}
