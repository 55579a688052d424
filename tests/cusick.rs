//! Cusick drape test (BS 5058 / ISO 9073-9; reference/README.md): a 300 mm specimen on a
//! 180 mm disc. Two presets of very different bending rigidity — cotton broadcloth
//! (1.157e-5 N·m, measured DC 82.9 %) and polyester faille (1.86e-6 N·m, measured DC
//! 28.3 %; Matsudaira et al. 2015 as quoted in reference/README.md) — must order correctly
//! (stiffer → higher DC) and land in the physically plausible range of the test (real
//! fabrics about 15–95 %), on the shipped scene's mesh (48 sectors, rings refined 8× at the
//! disc rim) and its Dynamic step (backward Euler to rest). The drape coefficient must also
//! change by less than 3 percentage points between the two finest meshes of a uniformly
//! refined family (issue 4). The wider mesh study and the fold distribution are produced by
//! `examples/cusick.rs` and reported in the issue notes.

#[path = "common/cusick_specimen.rs"]
mod cusick_specimen;

use cusick_specimen::SHIPPED_MESH;
use plyshell::analysis;

/// Drape outcome of one run.
struct Drape {
    dc: f64,
    penetration_over_h: f64,
    dofs: usize,
}

/// Runs the shipped Cusick scene with `preset` to rest — with `seed` ≠ 0 from a specimen
/// carrying the seeded 0.1 mm random-field imperfection (correlation length 50 mm) of
/// `examples/cusick.rs`, tapered to zero over r = 90…110 mm so the clamped part between the
/// discs stays flat — and returns its drape coefficient (%) and the largest penetration over
/// the thickness.
fn cusick(preset: &str, seed: u64) -> Drape {
    cusick_on(preset, seed, 48)
}

/// [`cusick`] on the scene's mesh family with `ntheta` sectors (the rings scale with it).
fn cusick_on(preset: &str, seed: u64, ntheta: usize) -> Drape {
    cusick_meshed(preset, seed, &SHIPPED_MESH.replace("ntheta: 48", &format!("ntheta: {ntheta}")))
}

/// [`cusick`] with the specimen meshed by `mesh` (RON text of a mesh spec).
fn cusick_meshed(preset: &str, seed: u64, mesh: &str) -> Drape {
    let (sc, built, h) = cusick_specimen::specimen(preset, seed, mesh).expect("the Cusick specimen");
    let s = analysis::run(&sc, &built, &Default::default(), &mut |_| {}).expect("solve");
    let d = &s.extra["drape"];
    let dc = d["drape_coefficient_percent"].as_f64().expect("dc");
    let folds = d["folds"].as_u64().expect("folds");
    let pen = d["max_penetration"].as_f64().expect("penetration");
    let sectors = built.model.x0.iter().filter(|x| (x.xy().norm() - 0.15).abs() < 1e-9).count();
    println!(
        "{preset} (seed {seed}, {mesh}: {sectors} sectors): DC {dc:.3} %, folds {folds}, penetration {:.2} % of h, {} DOFs, {} time steps, {} Newton iterations, {:.1} s wall",
        100.0 * pen / h,
        s.sizes.dofs,
        s.increments.len(),
        s.newton_iterations,
        s.wall_s
    );
    Drape { dc, penetration_over_h: pen / h, dofs: s.sizes.dofs }
}

/// Cotton broadcloth (B = 1.157e-5 N·m, measured 82.9 %) drapes to a higher coefficient than
/// polyester faille (B = 1.86e-6 N·m, measured 28.3 %), by at least 5 points; cotton lies in
/// 50–95 %, faille in the plausible 15–95 % of real fabrics (an elastic model without the
/// bending hysteresis of real yarns drapes a limp fabric less deeply than measured); neither
/// penetrates the discs by more than 5 % of its thickness (the bound), nor does cotton
/// started from a seeded imperfection of its overhang (seed 1), whose coefficient stays
/// within the plausible range too.
#[test]
fn stiffer_fabric_drapes_to_a_higher_coefficient() {
    let (cotton, faille, perturbed) = std::thread::scope(|s| {
        let c = s.spawn(|| cusick("cotton_broadcloth", 0));
        let f = s.spawn(|| cusick("polyester_faille", 0));
        let p = cusick("cotton_broadcloth", 1);
        (c.join().expect("cotton run"), f.join().expect("faille run"), p)
    });
    assert!((50.0..=95.0).contains(&cotton.dc), "DC {} % outside the plausible range for cotton broadcloth", cotton.dc);
    assert!((15.0..=95.0).contains(&faille.dc), "DC {} % outside the plausible range for polyester faille", faille.dc);
    assert!(cotton.dc > faille.dc + 5.0, "stiffer cotton DC {} % should exceed faille DC {} %", cotton.dc, faille.dc);
    assert!(cotton.penetration_over_h < 0.05, "cotton penetration {} of h", cotton.penetration_over_h);
    assert!(faille.penetration_over_h < 0.05, "faille penetration {} of h", faille.penetration_over_h);
    assert!(perturbed.penetration_over_h < 0.05, "perturbed cotton penetration {} of h", perturbed.penetration_over_h);
    assert!((50.0..=95.0).contains(&perturbed.dc), "perturbed cotton DC {} % outside the plausible range", perturbed.dc);
}

/// Mesh convergence of the drape coefficient (issue 4: "DC changes by less than 3 percentage
/// points between the two finest meshes"). The scene's mesh family is refined uniformly —
/// every radial and circumferential step scales with 1/ntheta — from 128 to 160 sectors
/// (20,480 and 29,600 DOFs). Polyester faille is the preset whose coefficient moves most with
/// the mesh (its limp overhang folds tightly and wraps the 1 mm rim round); both meshes must
/// also keep penetration below 5 % of the thickness.
///
/// The specimen is the seeded one of [`cusick`] (seed 1): its imperfection is a continuous
/// random field of position (`RandomField`, 0.1 mm), so both meshes carry the same physical
/// specimen and its folds are chosen by it, not by round-off. Measured (2026-12-05, DC % with
/// folds): the perfect specimen picks its fold pattern by round-off — 96 sectors 29.6 (15) or
/// 30.5 (15), 128 sectors 27.6 (13) or 27.3 (13), 160 sectors 26.2 (13) or 25.5 (12) with two
/// builds differing only in the round-off of the element Hessians' PSD projection — while
/// seed 1 gives 26.616 (12) at 128 and 25.498 (12) at 160 with either build. 96 sectors lie
/// outside the asymptotic range (seeds 1 and 2: 30.2 → 26.6 and 29.7 → 27.5 from 96 to 128
/// sectors), so this test refines from 128.
#[test]
fn drape_coefficient_converges_under_mesh_refinement() {
    // The two meshes solve side by side (two threads), as the runs of the test above do.
    let (coarse, fine) = std::thread::scope(|s| {
        let coarse = s.spawn(|| cusick_on("polyester_faille", 1, 128));
        let fine = faille_160();
        (coarse.join().expect("128-sector run"), fine)
    });
    let change = fine.dc - coarse.dc;
    assert!(change.abs() < 3.0, "faille DC moved {change:.2} points from 128 sectors ({:.2} %) to 160 ({:.2} %)", coarse.dc, fine.dc);
    assert!(coarse.penetration_over_h < 0.05 && fine.penetration_over_h < 0.05, "penetration {} / {} of h", coarse.penetration_over_h, fine.penetration_over_h);
}

/// The seeded faille specimen (seed 1) on 160 sectors, the finest mesh the project runs:
/// solved once, shared by the convergence test and the Auto-mesh test.
fn faille_160() -> &'static Drape {
    static FINE: std::sync::OnceLock<Drape> = std::sync::OnceLock::new();
    FINE.get_or_init(|| cusick_on("polyester_faille", 1, 160))
}

/// Issue 18: a specimen meshed from the physics, `SizedAnnulus(.., element_size:
/// Auto((tolerance: 0.02)))` (`scene::sizing`: sectors from the Cerda–Mahadevan fold
/// wavelength of the overhang, rings from the bending length, graded down to the tensioned
/// fabric's boundary layer √(B/T) at the disc rim, no size of its own between the discs),
/// reaches the drape coefficient of the finest shipped mesh (160 sectors, above) within 1
/// point with fewer DOFs, on the same seeded faille specimen; penetration stays below 5 % of
/// the thickness. T = 0.02 is the tolerance the garments use; it asks for 159 sectors
/// (the 160-sector mesh's circumferential resolution: the drape coefficient moves with the
/// sector count, 26.62 / 25.50 / 24.59 % at 128 / 160 / 192 sectors, and hardly with the
/// rings, 26.78 % with 128 sectors on the 160-sector rings, 25.30 % with 160 on the
/// 128-sector rings) on 33 rings of elements instead of 37.
#[test]
fn auto_mesh_reaches_the_finest_drape_coefficient_with_fewer_dofs() {
    let (auto, fine) = std::thread::scope(|s| {
        let auto = s.spawn(|| cusick_meshed("polyester_faille", 1, "SizedAnnulus(ri: 0.02, ro: 0.15, element_size: Auto((tolerance: 0.02)))"));
        let fine = faille_160();
        (auto.join().expect("Auto run"), fine)
    });
    let off = auto.dc - fine.dc;
    println!("Auto: DC {:.3} % with {} DOFs; 160 sectors: {:.3} % with {} DOFs ({off:+.3} points)", auto.dc, auto.dofs, fine.dc, fine.dofs);
    assert!(off.abs() < 1.0, "Auto mesh DC {:.3} % is {off:+.3} points off the 160-sector {:.3} %", auto.dc, fine.dc);
    assert!(auto.dofs < fine.dofs, "Auto mesh {} DOFs against {} on 160 sectors", auto.dofs, fine.dofs);
    assert!(auto.penetration_over_h < 0.05, "penetration {} of h", auto.penetration_over_h);
}
