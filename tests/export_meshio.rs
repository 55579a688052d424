//! Export: the VTU files and the PVD collection of a solve open in Python's meshio (PyPI),
//! with the solver's own point count, cell count and field values.

use std::path::{Path, PathBuf};
use std::process::Command;

use plyshell::analysis::{self, RunOptions};
use plyshell::scene;

/// A Python with meshio: $PLYSHELL_PYTHON, else a virtual environment under target/ that is
/// created (pip install meshio) on first use.
fn python_with_meshio() -> PathBuf {
    if let Ok(p) = std::env::var("PLYSHELL_PYTHON") {
        return PathBuf::from(p);
    }
    let venv = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/py-venv");
    let py = venv.join("bin/python");
    let ok = Command::new(&py).args(["-c", "import meshio"]).status().map(|s| s.success()).unwrap_or(false);
    if !ok {
        let made = Command::new("python3").args(["-m", "venv"]).arg(&venv).status().expect("python3 -m venv");
        assert!(made.success(), "could not create {}", venv.display());
        let pip = Command::new(venv.join("bin/pip")).args(["install", "--quiet", "meshio"]).status().expect("pip");
        assert!(pip.success(), "pip install meshio failed");
    }
    py
}

const SCRIPT: &str = r#"
import json, sys, os, xml.etree.ElementTree as ET
import meshio
out = sys.argv[1]
pvd = [f for f in os.listdir(out) if f.endswith('.pvd')][0]
root = ET.parse(os.path.join(out, pvd)).getroot()
entries = [(float(d.get('timestep')), d.get('file')) for d in root.iter('DataSet')]
result = {'entries': []}
for t, f in entries:
    m = meshio.read(os.path.join(out, f))
    quads = sum(len(b.data) for b in m.cells if b.type == 'quad')
    node = int(sys.argv[2])
    result['entries'].append({
        'time': t, 'file': f, 'points': int(len(m.points)), 'quads': int(quads),
        'displacement': [float(v) for v in m.point_data['displacement'][node]],
        'x': [float(v) for v in m.points[node]],
        'cell_fields': sorted(m.cell_data.keys()),
    })
print(json.dumps(result))
"#;

#[test]
fn vtu_and_pvd_open_in_meshio_with_the_solver_numbers() {
    let text = include_str!("../garments/examples/roll_up.ron").replace("increments: 40", "increments: 8").replace("every: 2", "every: 1");
    let sc = scene::parse("demo", &text).expect("parse");
    let built = scene::build(&sc, "demo", &text).expect("build");
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/test-output/export_meshio");
    let _ = std::fs::remove_dir_all(&out);
    let summary = analysis::run(&sc, &built, &RunOptions { out_dir: Some(out.clone()) }, &mut |_| {}).expect("solve");
    assert!(out.join("summary.json").exists());
    assert!(summary.files.iter().any(|f| f.ends_with(".svg")));
    let node = summary.monitors[0].node;
    let py = python_with_meshio();
    let o = Command::new(py).arg("-c").arg(SCRIPT).arg(&out).arg(node.to_string()).output().expect("run python");
    assert!(o.status.success(), "python failed: {}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json from python");
    let entries = v["entries"].as_array().expect("entries");
    assert!(summary.increments.len() >= 2, "{} increments", summary.increments.len());
    assert_eq!(entries.len(), summary.increments.len(), "one VTU per increment in the PVD");
    for (e, (inc, mon)) in entries.iter().zip(summary.increments.iter().zip(&summary.monitors[0].values)) {
        assert_eq!(e["points"].as_u64(), Some(built.model.n_nodes() as u64));
        assert_eq!(e["quads"].as_u64(), Some(built.model.elements.len() as u64));
        assert!((e["time"].as_f64().expect("time") - inc.time).abs() < 1e-9);
        // Monitored Ux and Uz against the displacement field meshio read.
        let d = e["displacement"].as_array().expect("displacement");
        let (ux, uz) = (d[0].as_f64().expect("ux"), d[2].as_f64().expect("uz"));
        assert!((ux - mon[0]).abs() <= 1e-12 * (1.0 + mon[0].abs()), "{ux} vs {}", mon[0]);
        assert!((uz - mon[1]).abs() <= 1e-12 * (1.0 + mon[1].abs()), "{uz} vs {}", mon[1]);
        let x = e["x"].as_array().expect("x");
        assert!((x[0].as_f64().expect("x0") - (12.0 + ux)).abs() < 1e-9, "deformed points");
        let fields: Vec<&str> = e["cell_fields"].as_array().expect("fields").iter().filter_map(|f| f.as_str()).collect();
        for f in ["energy_density", "membrane_strain", "membrane_stress", "part"] {
            assert!(fields.contains(&f), "cell field {f} missing: {fields:?}");
        }
    }
}
