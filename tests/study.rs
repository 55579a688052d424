//! `plyshell study` (issue 18) on the small two-ply flap (`garments/studies/two_ply_flap.ron`):
//! the table's reference row (finest mesh, discrete plies) has zero error against itself,
//! the DOFs grow with the mesh level and the ply model, and the coarser runs' errors are
//! finite; the Markdown, JSON and SVG files are written.

use plyshell::garment::PlyModel;
use plyshell::study::{run_study, StudyOptions};

#[test]
fn study_of_a_two_ply_flap_writes_a_table_with_a_zero_error_reference() {
    let out = std::env::temp_dir().join(format!("plyshell_study_{}", std::process::id()));
    let options = StudyOptions { sizes: vec![2.0, 1.0], tolerances: vec![], ply_models: vec![PlyModel::Laminate, PlyModel::Discrete], out: out.clone(), vtu: false };
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("garments/studies/two_ply_flap.ron");
    let rows = run_study(&path, &options, &mut |m| println!("{m}")).unwrap_or_else(|e| panic!("{e}"));
    println!("{}", plyshell::study::markdown("two_ply_flap", &rows));
    let labels: Vec<&str> = rows.iter().map(|r| r.label.as_str()).collect();
    assert_eq!(labels, ["laminate h×2", "discrete h×2", "laminate h×1", "discrete h×1 (reference)"]);
    assert!(rows.iter().all(|r| r.status == "completed"), "{labels:?}");
    let reference = rows.last().expect("a reference row");
    assert_eq!((reference.shape_rms, reference.shape_max), (0.0, 0.0));
    assert_eq!(reference.seam_force_error, Some(0.0));
    // DOFs grow with fidelity: mesh level within a ply model, and discrete over laminate.
    assert!(rows[0].dofs < rows[2].dofs && rows[1].dofs < rows[3].dofs, "{:?}", rows.iter().map(|r| r.dofs).collect::<Vec<_>>());
    assert!(rows[0].dofs < rows[1].dofs && rows[2].dofs < rows[3].dofs);
    // The coarser runs differ from the reference, by a finite error below the flap's size.
    for r in &rows[..3] {
        assert!(r.shape_rms > 0.0 && r.shape_max >= r.shape_rms && r.shape_max < 0.5, "{}: {} {}", r.label, r.shape_rms, r.shape_max);
        assert!(r.seam_force_error.is_some_and(|e| e.is_finite()), "{}", r.label);
    }
    // The coarsest run costs less CPU than the reference (4× fewer DOFs and no ply pairs).
    assert!(rows[0].cpu_s < reference.cpu_s, "{} vs {} s", rows[0].cpu_s, reference.cpu_s);
    for f in ["study.md", "study.json", "study.svg"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("study.json")).expect("study.json")).expect("JSON");
    assert_eq!(json["runs"].as_array().map(|a| a.len()), Some(4));
    let _ = std::fs::remove_dir_all(&out);
}
