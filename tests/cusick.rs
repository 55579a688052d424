//! Cusick drape test (BS 5058 / ISO 9073-9; reference/README.md): a 300 mm specimen on a
//! 180 mm disc. Two presets of very different bending rigidity — cotton broadcloth
//! (1.157e-5 N·m, measured DC 82.9 %) and polyester faille (1.86e-6 N·m, measured DC
//! 28.3 %; Matsudaira et al. 2015 as quoted in reference/README.md) — should order correctly
//! (stiffer → higher DC) and land in the physically plausible range of the test (DC between
//! 0 % limp and 100 % stiff; real fabrics about 15–95 %). Only the stiff preset's drape
//! converges so far; see the test's note. Coarse mesh (32 sectors, graded
//! rings) to stay within the test-time budget; the mesh study and fold distribution are
//! produced by `examples/cusick.rs` and reported in the issue notes.

use plyshell::{analysis, scene};

/// Runs the shipped Cusick scene with `preset` on the coarse mesh; returns (DC %, folds,
/// max penetration / thickness).
fn cusick(preset: &str) -> (f64, u64, f64) {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/garments/drape/cusick.ron");
    let text = std::fs::read_to_string(path).expect("scene");
    let h = plyshell::material::FabricProperties::preset(preset).expect("preset").thickness;
    let text = text
        .replace("preset: Some(\"cotton_broadcloth\")", &format!("preset: Some(\"{preset}\")"))
        .replace("thickness: 0.3e-3", &format!("thickness: {h:e}"))
        .replace("translation: (0.0, 0.0, -0.010149999)", &format!("translation: (0.0, 0.0, {:e})", -0.5 * h + 1e-9 - 0.01))
        .replace("translation: (0.0, 0.0, 0.010149999)", &format!("translation: (0.0, 0.0, {:e})", 0.5 * h - 1e-9 + 0.01))
        .replace("nr: 16, ntheta: 48", "nr: 11, ntheta: 32")
        .replace("time_step: 1.0e-3", "time_step: 0.75e-3")
        .replace("increments: 400", "increments: 400")
        .replace("output: (every: 50)", "output: (vtu: false)");
    let sc = scene::parse(path, &text).expect("parse");
    let built = scene::build(&sc, path, &text).expect("build");
    let s = analysis::run(&sc, &built, &Default::default(), &mut |_| {}).expect("solve");
    let d = &s.extra["drape"];
    let dc = d["drape_coefficient_percent"].as_f64().expect("dc");
    let folds = d["folds"].as_u64().expect("folds");
    let pen = d["max_penetration"].as_f64().expect("penetration");
    println!("{preset}: DC {dc:.1} %, folds {folds}, penetration {:.2} % of h, {} increments, {} Newton iterations, {:.1} s", 100.0 * pen / h, s.increments.len(), s.newton_iterations, s.wall_s);
    (dc, folds, pen / h)
}

/// Cotton broadcloth (measured DC 82.9 %) drapes to a coefficient in the plausible range
/// (50–95 %) without penetrating the discs by more than 5 % of its thickness. The comparison
/// with the limp polyester faille (measured 28.3 %) is not asserted here: its drape does not
/// converge past 0.26 s of pseudo-time on this mesh (reported in the issue notes).
#[test]
fn cotton_broadcloth_drape_coefficient_is_plausible() {
    let (dc, _, pen) = cusick("cotton_broadcloth");
    assert!((50.0..=95.0).contains(&dc), "DC {dc} % outside the plausible range for cotton broadcloth");
    assert!(pen < 0.05, "penetration {pen} of h");
}
