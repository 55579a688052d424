//! OBJ and glTF 2.0 (.glb) exports of the solved garment (issue 19), read back by independent
//! readers from PyPI: trimesh (OBJ and GLB), pygltflib (GLB structure), meshio (the garment
//! VTU of the same state, for positions and displacements).
//!
//! Exact expectations: the shipped two-piece pattern hangs in the plane y = 0 with pattern
//! coordinates (u, v) placed at x = u (+ 0.202 m for the right panel), z = v, so every
//! vertex's reference position (deformed position − displacement, from the VTU) must equal
//! its texture coordinate mapped that way, to 1e-9 m; positions must equal the VTU's.

use std::path::{Path, PathBuf};
use std::process::Command;

use plyshell::{analysis, scene};

fn python() -> PathBuf {
    let py = std::env::var("PLYSHELL_PYTHON").map(PathBuf::from).unwrap_or_else(|_| Path::new(env!("CARGO_MANIFEST_DIR")).join("target/py-venv/bin/python"));
    let ok = Command::new(&py).args(["-c", "import trimesh, pygltflib, meshio"]).status().map(|s| s.success()).unwrap_or(false);
    if !ok {
        let pip = Command::new(&py).args(["-m", "pip", "install", "--quiet", "trimesh", "pygltflib", "meshio"]).status().expect("pip");
        assert!(pip.success(), "pip install trimesh pygltflib meshio failed (the test needs them from PyPI)");
    }
    py
}

const SCRIPT: &str = r#"
import json, sys, os, warnings
import numpy as np, trimesh, pygltflib, meshio
warnings.simplefilter("ignore")
out, name, vtu = sys.argv[1], sys.argv[2], sys.argv[3]
m = meshio.read(os.path.join(out, vtu))
shift = {"left/shell": 0.0, "right/shell": 0.202}
panel = {"left/shell": 0, "right/shell": 1}
quads = m.cells[0].data
def check(groups):
    res = {}
    for gname, g in groups:
        uv = np.asarray(g.visual.uv, dtype=float)
        # Each vertex's VTU point of the same panel (sewn seams put two panels' nodes at one
        # position) at the same position, its reference position, and the UV mapped.
        own = np.unique(quads[m.cell_data["panel"][0] == panel[gname]])
        pts, disp = m.points[own], m.point_data["displacement"][own]
        d = np.linalg.norm(pts[None, :, :] - np.asarray(g.vertices)[:, None, :], axis=2)
        k = d.argmin(axis=1)
        ref = pts[k] - disp[k]
        mapped = np.column_stack([uv[:, 0] + shift[gname], np.zeros(len(uv)), uv[:, 1]])
        res[gname] = {"vertices": len(g.vertices), "triangles": len(g.faces), "position_error": float(d.min(axis=1).max()),
                      "uv_error": float(np.abs(ref - mapped).max()), "uv_min": uv.min(axis=0).tolist(), "uv_max": uv.max(axis=0).tolist()}
    return res
s = trimesh.load(os.path.join(out, name + "_garment.obj"), process=False, split_groups=True, group_material=False)
result = {"obj": check(sorted(s.geometry.items()))}
# trimesh turns glTF's TEXCOORD_0 (origin top left) back to v upwards.
s = trimesh.load(os.path.join(out, name + "_garment.glb"), process=False)
result["glb"] = check(sorted(s.geometry.items()))
g = pygltflib.GLTF2().load(os.path.join(out, name + "_garment.glb"))
result["meshes"] = [x.name for x in g.meshes]
result["nodes"] = [x.name for x in g.nodes]
result["targets"] = [len(x.primitives[0].targets) for x in g.meshes]
result["counts"] = [g.accessors[x.primitives[0].attributes.POSITION].count for x in g.meshes]
result["texcoord_range"] = [[g.accessors[x.primitives[0].attributes.TEXCOORD_0].min, g.accessors[x.primitives[0].attributes.TEXCOORD_0].max] for x in g.meshes]
result["animation"] = [a.name for a in g.animations]
result["pose_times"] = g.scenes[0].extras["pose_times"]
print(json.dumps(result))
"#;

#[test]
fn obj_and_glb_read_back_with_groups_vertex_counts_and_pattern_uvs() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("garments/patterns/two_piece.ron");
    let (sc, built) = scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/test-output/garment_surface");
    let _ = std::fs::remove_dir_all(&out);
    let summary = analysis::run(&sc, &built, &analysis::RunOptions { out_dir: Some(out.clone()) }, &mut |_| {}).unwrap_or_else(|e| panic!("{e}"));
    for f in ["two_piece_garment.obj", "two_piece_garment.glb"] {
        assert!(summary.files.iter().any(|x| x == f), "{f} in {:?}", summary.files);
        println!("{f}: {} bytes", std::fs::metadata(out.join(f)).map(|m| m.len()).unwrap_or(0));
    }
    let last = summary.files.iter().rfind(|f| f.starts_with("two_piece_garment_0")).expect("garment vtu").clone();
    let o = Command::new(python()).arg("-c").arg(SCRIPT).arg(&out).arg("two_piece").arg(&last).output().expect("python");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    println!("{v:#}");
    let model = &built.model;
    let groups = ["left/shell", "right/shell"];
    for (k, g) in groups.iter().enumerate() {
        let (nodes, quads) = (model.parts[k].n_nodes as u64, model.parts[k].n_elements as u64);
        for (format, tol_uv) in [("obj", 1e-9), ("glb", 1e-6)] {
            let r = &v[format][g];
            assert_eq!(r["vertices"].as_u64(), Some(nodes), "{format} {g}");
            assert_eq!(r["triangles"].as_u64(), Some(2 * quads), "{format} {g}");
            let f = |key: &str| r[key].as_f64().unwrap_or(f64::INFINITY);
            // OBJ: full decimal precision; glTF: 32-bit floats (metres).
            assert!(f("position_error") < if format == "obj" { 1e-12 } else { 1e-6 }, "{format} {g}: {r}");
            assert!(f("uv_error") < tol_uv, "{format} {g}: {r}");
            assert_eq!(r["uv_min"], serde_json::json!([0.0, 0.0]), "{format} {g}");
            let max: Vec<f64> = r["uv_max"].as_array().expect("uv max").iter().filter_map(|x| x.as_f64()).collect();
            assert!((max[0] - 0.2).abs() < tol_uv && (max[1] - 0.3).abs() < tol_uv, "{format} {g}: {max:?}");
        }
    }
    assert_eq!(v["meshes"], serde_json::json!(groups));
    assert_eq!(v["nodes"], serde_json::json!(groups));
    assert_eq!(v["counts"], serde_json::json!([model.parts[0].n_nodes, model.parts[1].n_nodes]));
    // Raw TEXCOORD_0: v flipped (1 − v) as glTF's texture origin is the top left.
    for r in v["texcoord_range"].as_array().expect("ranges") {
        let x: Vec<f64> = r.as_array().expect("min, max").iter().flat_map(|a| a.as_array().cloned().unwrap_or_default()).filter_map(|x| x.as_f64()).collect();
        let want = [0.0, 0.7, 0.2, 1.0];
        assert!(x.len() == 4 && x.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-6), "{x:?}");
    }
    // One morph target per exported state (every converged increment of sew and hang), times
    // as solved.
    let n = summary.increments.len();
    assert!(n >= 2);
    assert_eq!(v["targets"], serde_json::json!([n, n]));
    assert_eq!(v["animation"], serde_json::json!(["poses"]));
    let times: Vec<f64> = summary.increments.iter().map(|r| r.time).collect();
    assert_eq!(v["pose_times"], serde_json::json!(times));
}

/// Groups of a multi-ply panel come in stack order, innermost first (as the ply ids), each
/// with its ply's own nodes and quads.
#[test]
fn surface_groups_follow_the_stack() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("garments/nbc_sleeve.ron");
    let (_, built) = scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let layout = built.garment.as_ref().expect("garment layout");
    let model = &built.model;
    let (mesh, nodes) = plyshell::garment::export::garment_surface(model, layout, |n| model.x0[n].into());
    let names: Vec<&str> = mesh.groups.iter().map(|g| g.0.as_str()).collect();
    assert_eq!(names, ["sleeve/liner", "sleeve/carbon", "sleeve/outer"]);
    assert_eq!(nodes.len(), model.n_nodes());
    for (_, quads) in &mesh.groups {
        assert_eq!(quads.len(), model.elements.len() / 3);
    }
}
