//! Linearized buckling, (K_T + λ K_Δ) φ = 0 by shift-invert Lanczos, against classical
//! stability theory (Timoshenko & Gere, Theory of Elastic Stability, 2nd ed. 1961).

use plyshell::bench;

/// Simply supported square plate under uniform uniaxial compression (§9.2): the lowest
/// eigenvalue gives k = N_cr b² / (π² D) = 4 within 1 % on a 16×16 mesh (b/t = 100, so
/// transverse shear lowers k by well under 0.1 %). The next modes have m = 2 and 3
/// half-waves along the load, k = (m + 1/m)² = 6.25 and 11.11: checked within 3 % and 5 %
/// (coarser resolution of the shorter waves).
#[test]
fn square_plate_buckling_coefficient_is_four() {
    let (k, s, w) = bench::plate_buckling(16).expect("solve");
    eprintln!("plate 16x16: k = {k:.5} ({:+.3} %), {} dofs, {w:.2} s", 100.0 * (k / 4.0 - 1.0), s.sizes.dofs);
    assert!((k - 4.0).abs() < 0.04, "k = {k}");
    let b = s.increments[0].buckling.as_ref().expect("buckling report");
    let d = 1.0e7 * 1e-6 / (12.0 * 0.91);
    let ks: Vec<f64> = b.eigenvalues.iter().map(|l| l / (std::f64::consts::PI.powi(2) * d)).collect();
    assert!((ks[1] / 6.25 - 1.0).abs() < 0.03, "second k = {}", ks[1]);
    assert!((ks[2] / (100.0 / 9.0) - 1.0).abs() < 0.05, "third k = {}", ks[2]);
    assert!(b.residuals.iter().all(|r| *r < 1e-6), "eigen residuals {:?}", b.residuals);
}

/// Axially compressed cylinder (§11.4): the lowest eigenvalue within 5 % of
/// σ_cr = E t / (R √(3(1−ν²))). R/t = 100, L = R, ν = 0 (membrane prebuckling state, no
/// end bending), ends w = v = 0 with free axial motion (SS3), Batdorf Z = 100 — the regime
/// where the classical value is the finite cylinder's lowest eigenvalue. Quarter of the
/// circumference with symmetry planes, 40 × 60 elements (6.8 elements per axisymmetric
/// half-wave of 0.169 R); about 2 s in release.
#[test]
fn axially_compressed_cylinder_buckles_at_the_classical_stress() {
    let (ratio, s, w) = bench::cylinder_buckling(40, 60).expect("solve");
    eprintln!("cylinder 40x60 quarter: sigma/sigma_cl = {ratio:.5}, {} dofs, {w:.2} s", s.sizes.dofs);
    assert!((ratio - 1.0).abs() < 0.05, "ratio {ratio}");
}

/// Buckling at a given state: after a static step to half the critical load, a `Buckling`
/// step for a further unit compression finds the remaining margin, λ = λ_cr − 0.5 N_cr (the
/// flat prebuckling state is a membrane state, so K_T there is K₀ + ½ N_cr K_σ up to the
/// prebuckling strain): within 0.1 % of the value from the unloaded plate.
#[test]
fn buckling_at_a_preloaded_state_gives_the_remaining_margin() {
    let text = bench::scenes::PLATE_BUCKLING.replace(
        "steps: [(name: \"buckling\", increments: 1, scale: {\"compression\": 1.0}, kind: Buckling(modes: 4))],",
        "steps: [(name: \"preload\", increments: 2, scale: {\"compression\": 18.0764}), (name: \"buckling\", increments: 1, scale: {\"compression\": 19.0764}, kind: Buckling(modes: 1))],",
    );
    assert_ne!(text, bench::scenes::PLATE_BUCKLING);
    let s = bench::solve_variant(&text, "plate_preloaded", &[]).expect("solve");
    let lam = s.increments.iter().find_map(|i| i.buckling.as_ref()).expect("buckling").eigenvalues[0];
    let (k, _, _) = bench::plate_buckling(16).expect("solve");
    let d = 1.0e7 * 1e-6 / (12.0 * 0.91);
    let lam_cr = k * std::f64::consts::PI.powi(2) * d;
    let expected = lam_cr - 18.0764;
    eprintln!("preloaded: remaining {lam:.5}, expected {expected:.5}");
    assert!((lam / expected - 1.0).abs() < 1e-3, "remaining margin {lam} vs {expected}");
    let critical = &s.increments.last().expect("increments").buckling.as_ref().expect("buckling").critical_scales[0];
    assert!((critical[0] / lam_cr - 1.0).abs() < 1e-3, "critical scale {} vs {lam_cr}", critical[0]);
}

/// The `Buckling` step writes its modes as VTU point fields `mode_k` (3 components) and
/// `mode_k_tilt` (2) for every node, scaled to a largest translation of 1, and lists the
/// file in summary.json; the first mode of the square plate is the one-half-wave bulge, so
/// its centre node carries the largest (unit, out-of-plane) translation.
#[test]
fn buckling_modes_are_written_as_vtu_point_fields() {
    use plyshell::analysis::{self, RunOptions};
    use plyshell::scene;
    let text = bench::scenes::PLATE_BUCKLING
        .replace("nx: 16, ny: 16", "nx: 8, ny: 8")
        .replace("    monitors:", "    output: (binary: false),\n    monitors:");
    let sc = scene::parse("plate", &text).expect("parse");
    let built = scene::build(&sc, "plate", &text).expect("build");
    let out = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/test-output/buckling_modes");
    let _ = std::fs::remove_dir_all(&out);
    let s = analysis::run(&sc, &built, &RunOptions { out_dir: Some(out.clone()) }, &mut |_| {}).expect("solve");
    let name = "plate_buckling_buckling_step1.vtu";
    assert!(s.files.iter().any(|f| f == name), "{:?}", s.files);
    let vtu = std::fs::read_to_string(out.join(name)).expect("mode file");
    let n_points = built.model.n_nodes();
    for k in 1..=4 {
        for (field, comps) in [(format!("mode_{k}"), 3), (format!("mode_{k}_tilt"), 2)] {
            let tag = format!("Name=\"{field}\"");
            let at = vtu.find(&tag).unwrap_or_else(|| panic!("no {field}"));
            let body = &vtu[at..];
            let start = body.find('>').expect("tag end") + 1;
            let end = body.find("</DataArray>").expect("array end");
            let values: Vec<f64> = body[start..end].split_whitespace().map(|v| v.parse().expect("number")).collect();
            assert_eq!(values.len(), comps * n_points, "{field}");
            if comps == 3 {
                let largest = values.chunks(3).map(|t| (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt()).fold(0.0, f64::max);
                assert!((largest - 1.0).abs() < 1e-12, "{field}: largest translation {largest}");
                if k == 1 {
                    let centre = built.node_sets["centre"][0];
                    assert!((values[3 * centre + 2].abs() - 1.0).abs() < 1e-9, "mode 1 at the centre: {}", values[3 * centre + 2]);
                }
            }
        }
    }
}
