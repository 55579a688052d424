//! MITC4+ (Ko, Lee & Bathe, "A new MITC4+ shell element", Computers & Structures 182 (2017)
//! 404–418) verified as in that paper: patch tests, zero-energy modes, isotropy, and
//! convergence on regular and distorted meshes (each edge divided 1:2:…:N, nodes on the
//! exact surface) against published and analytic references — for the paper's element
//! (`Mitc4Plus`) and for the variant with the in-plane shear sampled at the element centre
//! (`Mitc4PlusCentre`), which also passes the in-plane bending cases of MITC4.

use nalgebra::{DMatrix, Vector3};
use plyshell::element::{DirectorFrame, Section, ShearTreatment, ShellElement};
use plyshell::material::{ShellMaterial, StVenantKirchhoff};
use plyshell::scene;
use std::sync::Arc;

fn solve_text(text: &str) -> plyshell::results::Summary {
    let sc = scene::parse("patch", text).expect("parse");
    let dir = std::env::current_dir().expect("cwd").join("tests/data/x.ron");
    let built = scene::build(&sc, &dir.display().to_string(), text).expect("build");
    plyshell::analysis::run(&sc, &built, &Default::default(), &mut |_| {}).expect("solve")
}

/// Nodes of the MacNeal & Harder (1985) distorted five-element patch (tests/data/macneal_patch.obj).
const NODES: [(f64, f64); 8] = [(0.0, 0.0), (0.24, 0.0), (0.24, 0.12), (0.0, 0.12), (0.04, 0.02), (0.18, 0.03), (0.16, 0.08), (0.08, 0.08)];

const VARIANTS: [ShearTreatment; 2] = [ShearTreatment::Mitc4Plus, ShearTreatment::Mitc4PlusCentre];

/// Membrane patch test on the distorted patch (constant stress: uniaxial σx, then pure
/// shear τ, applied as boundary tractions): the exact linear displacement field at every
/// node to 1e-8 (MITC4+ passes it, Ko, Lee & Bathe 2017).
#[test]
fn mitc4plus_membrane_patch_test() {
    let (e, nu, t, s) = (1.0e6, 0.25, 0.001, 1.0e3);
    let g = e / (2.0 * (1.0 + nu));
    let monitors: String = NODES.iter().enumerate().map(|(i, (x, y))| format!("(name: \"n{i}\", point: ({x}, {y}, 0.0), dofs: [Ux, Uy, Uz]),\n")).collect();
    type Field = Box<dyn Fn(f64, f64) -> (f64, f64)>;
    let cases: Vec<(String, String, String, Field)> = vec![
        (
            format!("\"right\": EdgeForce(set: \"right\", force_per_length: ({:e}, 0.0, 0.0)), \"left\": EdgeForce(set: \"left\", force_per_length: ({:e}, 0.0, 0.0))", s * t, -s * t),
            "\"right\": 1.0, \"left\": 1.0".into(),
            "Fix(set: \"origin\", dofs: [Ux, Uy]), Fix(set: \"top_left\", dofs: [Ux])".into(),
            Box::new(move |x, y| (s / e * x, -nu * s / e * y)),
        ),
        (
            format!(
                "\"right\": EdgeForce(set: \"right\", force_per_length: (0.0, {a:e}, 0.0)), \"left\": EdgeForce(set: \"left\", force_per_length: (0.0, {b:e}, 0.0)), \"top\": EdgeForce(set: \"top\", force_per_length: ({a:e}, 0.0, 0.0)), \"bottom\": EdgeForce(set: \"bottom\", force_per_length: ({b:e}, 0.0, 0.0))",
                a = s * t,
                b = -s * t
            ),
            "\"right\": 1.0, \"left\": 1.0, \"top\": 1.0, \"bottom\": 1.0".into(),
            "Fix(set: \"origin\", dofs: [Ux, Uy]), Fix(set: \"bottom_right\", dofs: [Uy])".into(),
            Box::new(move |_x, y| (s / g * y, 0.0)),
        ),
    ];
    for ((loads, scale, supports, field), form) in cases.iter().flat_map(|c| VARIANTS.map(|v| (c, v))) {
        let text = format!(
            "Scene(name: \"membrane_patch\", materials: {{\"m\": StVenantKirchhoff(young: {e:e}, poisson: {nu})}},
             parts: [(name: \"p\", mesh: Obj(path: \"macneal_patch.obj\"), material: \"m\", thickness: {t:e}, shear: {form:?})],
             node_sets: {{ \"all\": Box(min: (-1.0, -1.0, -1.0), max: (1.0, 1.0, 1.0)),
                \"origin\": Nearest(point: (0.0, 0.0, 0.0)), \"top_left\": Nearest(point: (0.0, 0.12, 0.0)),
                \"bottom_right\": Nearest(point: (0.24, 0.0, 0.0)),
                \"right\": Plane(point: (0.24, 0.0, 0.0), normal: (1.0, 0.0, 0.0)), \"left\": Plane(point: (0.0, 0.0, 0.0), normal: (1.0, 0.0, 0.0)),
                \"top\": Plane(point: (0.0, 0.12, 0.0), normal: (0.0, 1.0, 0.0)), \"bottom\": Plane(point: (0.0, 0.0, 0.0), normal: (0.0, 1.0, 0.0)) }},
             boundary: [Fix(set: \"all\", dofs: [Uz, TiltX, TiltY]), {supports}],
             loads: {{ {loads} }},
             steps: [(name: \"s\", increments: 1, linear: true, scale: {{ {scale} }})],
             monitors: [{monitors}])"
        );
        let res = solve_text(&text);
        let (umax, vmax) = field(0.24, 0.12);
        let norm = (umax * umax + vmax * vmax).sqrt();
        for (h, &(x, y)) in res.monitors.iter().zip(&NODES) {
            let (u, v) = field(x, y);
            let now = h.values.last().expect("value");
            let err = ((now[0] - u).powi(2) + (now[1] - v).powi(2) + now[2].powi(2)).sqrt() / norm;
            assert!(err < 1e-8, "{form:?}: node {} error {err:e}", h.name);
        }
    }
}

/// Bending patch test on the distorted patch: uniform edge moment m (ν = 0), clamped at
/// x = 0; the exact w = ½ κ x², κ = 12 m / (E t³), at every node to 1e-8 of the tip value.
#[test]
fn mitc4plus_bending_patch_test() {
    let (e, t, m) = (1.0e6, 0.001, 1.0e-6);
    let kappa = 12.0 * m / (e * t * t * t);
    let monitors: String = NODES.iter().enumerate().map(|(i, (x, y))| format!("(name: \"n{i}\", point: ({x}, {y}, 0.0), dofs: [Uz]),\n")).collect();
    for form in VARIANTS {
        let text = format!(
            "Scene(name: \"bending_patch\", materials: {{\"m\": StVenantKirchhoff(young: {e:e}, poisson: 0.0)}},
             parts: [(name: \"p\", mesh: Obj(path: \"macneal_patch.obj\"), material: \"m\", thickness: {t:e}, shear: {form:?})],
             node_sets: {{ \"root\": Box(min: (-0.001, -1.0, -1.0), max: (0.001, 1.0, 1.0)),
                          \"tip\": Box(min: (0.239, -1.0, -1.0), max: (0.241, 1.0, 1.0)) }},
             boundary: [Clamp(set: \"root\")],
             loads: {{ \"moment\": EdgeMoment(set: \"tip\", moment_per_length: (0.0, {:e}, 0.0)) }},
             steps: [(name: \"s\", increments: 1, linear: true, scale: {{\"moment\": 1.0}})],
             monitors: [{monitors}])",
            -m
        );
        let s = solve_text(&text);
        let w_tip = 0.5 * kappa * 0.24 * 0.24;
        for (h, &(x, _)) in s.monitors.iter().zip(&NODES) {
            let w = h.values.last().expect("value")[0];
            let exact = 0.5 * kappa * x * x;
            assert!((w - exact).abs() < 1e-8 * w_tip, "{form:?}: node {} w = {w:e}, exact {exact:e}", h.name);
        }
    }
}

fn stiffness(shear: ShearTreatment, x0: [Vector3<f64>; 4], d0: [Vector3<f64>; 4], grain: Option<Vector3<f64>>, thickness: f64) -> DMatrix<f64> {
    let material: Arc<dyn ShellMaterial> = Arc::new(StVenantKirchhoff::new(1.0e4, 0.3, 5.0 / 6.0));
    let section = Section { thickness, shear, thickness_points: 2, material };
    let el = ShellElement { x0, d0, grain, section: &section };
    let frames = d0.map(|d| DirectorFrame::new(d, Some(Vector3::x())));
    let k = el.response(&[Vector3::zeros(); 4], &frames, true).expect("element").stiffness.expect("tangent");
    DMatrix::from_fn(20, 20, |i, j| k[(i, j)])
}

fn zero_modes(k: &DMatrix<f64>) -> usize {
    let eig = k.clone().symmetric_eigen();
    let max = eig.eigenvalues.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    eig.eigenvalues.iter().filter(|v| v.abs() < 1e-10 * max).count()
}

/// A flat distorted quadrilateral, the same warped (nodes off its plane by ±4 % of its size)
/// with non-parallel directors, and a square.
fn shapes() -> Vec<(&'static str, [Vector3<f64>; 4], [Vector3<f64>; 4])> {
    let flat = [Vector3::new(0.0, 0.0, 0.0), Vector3::new(1.2, 0.1, 0.0), Vector3::new(1.0, 0.9, 0.0), Vector3::new(-0.1, 1.1, 0.0)];
    let warped = [Vector3::new(0.0, 0.0, 0.04), Vector3::new(1.2, 0.1, -0.04), Vector3::new(1.0, 0.9, 0.04), Vector3::new(-0.1, 1.1, -0.04)];
    let tilted = [Vector3::new(0.05, -0.02, 1.0), Vector3::new(-0.03, 0.04, 1.0), Vector3::new(0.02, 0.03, 1.0), Vector3::new(-0.01, -0.05, 1.0)].map(|d| d.normalize());
    let square = [Vector3::new(0.0, 0.0, 0.0), Vector3::new(1.0, 0.0, 0.0), Vector3::new(1.0, 1.0, 0.0), Vector3::new(0.0, 1.0, 0.0)];
    vec![("square", square, [Vector3::z(); 4]), ("flat distorted", flat, [Vector3::z(); 4]), ("warped distorted", warped, tilted)]
}

/// Zero-energy mode test (as in Ko, Lee & Bathe 2017): a free MITC4+ element, square, flat
/// distorted and warped distorted with non-parallel directors, thin and thick, has exactly
/// the six rigid-body modes (eigenvalues below 1e-10 of the largest).
#[test]
fn mitc4plus_free_element_has_exactly_six_zero_energy_modes() {
    for form in VARIANTS {
        for (name, x0, d0) in shapes() {
            for t in [0.1, 0.001] {
                let k = stiffness(form, x0, d0, None, t);
                assert_eq!(zero_modes(&k), 6, "{form:?}: {name}, t = {t}");
            }
        }
    }
}

/// Isotropy test (as in Ko, Lee & Bathe 2017): the element stiffness must not depend on
/// which node is numbered first. With the lamina frame fixed by a grain direction, renumbering
/// the nodes cyclically (a → a+1) gives the same stiffness with rows and columns permuted
/// node-wise, to 1e-10 of its largest entry, on the three shapes.
#[test]
fn mitc4plus_stiffness_is_independent_of_node_numbering() {
    let grain = Some(Vector3::new(1.0, 0.3, 0.0));
    for (form, (name, x0, d0)) in VARIANTS.into_iter().flat_map(|f| shapes().into_iter().map(move |s| (f, s))) {
        let k = stiffness(form, x0, d0, grain, 0.01);
        for shift in 1..4 {
            let p: [usize; 4] = std::array::from_fn(|a| (a + shift) % 4);
            let kp = stiffness(form, p.map(|a| x0[a]), p.map(|a| d0[a]), grain, 0.01);
            // Local node a of the renumbered element is node p[a] of the original one; the
            // director frames are built from the same director and reference axis, so the
            // tilt DOFs correspond one to one.
            let scale = k.abs().max();
            let mut worst: f64 = 0.0;
            for a in 0..4 {
                for b in 0..4 {
                    for i in 0..5 {
                        for j in 0..5 {
                            worst = worst.max((kp[(5 * a + i, 5 * b + j)] - k[(5 * p[a] + i, 5 * p[b] + j)]).abs() / scale);
                        }
                    }
                }
            }
            assert!(worst < 1e-10, "{form:?}: {name}, shift {shift}: {worst:e}");
        }
    }
}

/// Regular meshes of the Scordelis–Lo roof and the pinched cylinder: MITC4+ reproduces the
/// published MITC4 convergence of Ko, Lee, Lee & Bathe (C&S 193, 2017), quoted in
/// reference/README.md (normalized by 0.3024 and 1.8248e-5, Belytschko et al. 1985). On
/// these meshes every element is a flat rectangle, whose assumed membrane strains equal the
/// displacement-based ones in linear analysis, so MITC4+ and the published MITC4 coincide
/// (Ko, Lee & Bathe 2017a give the same values for both). The published values have three
/// digits; tolerance 0.003 on the normalized value (measured within 0.0017).
#[test]
fn mitc4plus_regular_meshes_match_published_convergence() {
    use plyshell::bench::locking::{pinched_cylinder, scordelis_lo};
    use plyshell::mesh::Spacing::Uniform;
    let f = ShearTreatment::Mitc4Plus;
    for (n, published) in [(4, 0.943), (8, 0.973), (16, 0.989), (32, 0.994)] {
        let v = scordelis_lo(n, f, Uniform).expect("solve").0;
        assert!((v - published).abs() < 0.003, "Scordelis–Lo {n}x{n}: {v:.4} vs published {published}");
    }
    for (n, published) in [(8, 0.747), (16, 0.929), (32, 0.987)] {
        let v = pinched_cylinder(n, f, Uniform).expect("solve").0;
        assert!((v - published).abs() < 0.003, "pinched cylinder {n}x{n}: {v:.4} vs published {published}");
    }
}

/// Distorted meshes (each edge divided 1:2:…:N, nodes on the exact surface): normalized
/// deflection against the converged references — Scordelis–Lo 0.3024 and pinched cylinder
/// 1.8248e-5 (Belytschko et al., CMAME 51 (1985) 221–258, via Ko, Lee, Lee & Bathe, C&S 193
/// (2017)); pinched hemisphere with an 18° hole (MacNeal & Harder, FEAD 1 (1985) 3–20)
/// 0.0924 as given for this configuration by the Kratos shell obstacle course, citing
/// Bouclier, Elguedj & Combescure, CMAME 267 (2013) 86–110 (MacNeal & Harder's theoretical
/// 0.094 is for the closed hemisphere; reference/obstacle_course_linear_reference.csv).
/// Measured (MITC4+ / MITC4+ centre shear /
/// MITC4): pinched hemisphere 16×16 0.998 / 1.000 / 0.69, 32×32 1.007 / 1.008 / 0.97;
/// Scordelis–Lo 16×16 1.022 / 1.038 / 1.006, 32×32 1.003 / 1.007 / 0.999; pinched cylinder
/// 32×32 0.973 / 0.974 / 0.988. Tolerances: the hemisphere (bending dominated, t/R = 0.004,
/// where membrane locking shows) within 2 % at N = 16 and 32; Scordelis–Lo within 3 %
/// (MITC4+) or 5 % (centre shear) at 16 and 1 % at 32 — both are more flexible than MITC4 on
/// this coarse distorted roof; the pinched cylinder within 4 % at 32 (neither MITC4+ is
/// better than MITC4 there: this point-load problem does not lock, and they are 1.5 % more
/// flexible).
#[test]
fn mitc4plus_distorted_meshes_converge_to_references() {
    use plyshell::bench::locking::{pinched_cylinder, pinched_hemisphere, scordelis_lo};
    use plyshell::mesh::Spacing::Distorted;
    for (f, roof16) in [(ShearTreatment::Mitc4Plus, 0.03), (ShearTreatment::Mitc4PlusCentre, 0.05)] {
        for n in [16, 32] {
            let v = pinched_hemisphere(n, f, Distorted).expect("solve").0;
            assert!((v - 1.0).abs() < 0.02, "{f:?}: hemisphere distorted {n}x{n}: {v:.4}");
        }
        for (n, tol) in [(16, roof16), (32, 0.01)] {
            let v = scordelis_lo(n, f, Distorted).expect("solve").0;
            assert!((v - 1.0).abs() < tol, "{f:?}: Scordelis–Lo distorted {n}x{n}: {v:.4}");
        }
        let v = pinched_cylinder(32, f, Distorted).expect("solve").0;
        assert!((v - 1.0).abs() < 0.04, "{f:?}: pinched cylinder distorted 32x32: {v:.4}");
    }
}

/// The centre-shear variant keeps what MITC4's centre-sampled in-plane shear gains on the
/// 12×2 strips of tests/linear_obstacle.rs, with the same 3 % tolerances: twisted beam
/// (Ko, Lee, Lee & Bathe 2017 references in reference/obstacle_course_linear_reference.csv;
/// measured −0.4 %, −1.7 %, +0.5 %, −1.2 %) and the straight strip in in-plane bending
/// (Timoshenko beam 5.6304e-4; measured −1.8 %). The paper's MITC4+ gives 0.920 on the thick
/// twisted beam out of plane and 0.738 on the strip (parasitic in-plane shear of the bilinear
/// membrane, which MITC4+ does not address), so it cannot be the default.
#[test]
fn mitc4plus_centre_shear_passes_in_plane_bending_strips() {
    use plyshell::bench::{linear_value, scenes};
    for (t, in_plane, reference) in [(0.32, true, 5.424e-3), (0.32, false, 1.754e-3), (0.0032, true, 5.256e-3), (0.0032, false, 1.294e-3)] {
        let p = if t < 0.01 { 1e-6 } else { 1.0 };
        let (load, q) = if in_plane { ("in_plane", 1) } else { ("out_of_plane", 0) };
        let rep = [("thickness: 0.32", format!("thickness: {t:e}, shear: Mitc4PlusCentre")), ("scale: {\"in_plane\": 1.0}", format!("scale: {{\"{load}\": {p:e}}}"))];
        let (v, _, _) = linear_value(scenes::TWISTED_BEAM, "twisted_beam", &rep, q).expect("solve");
        let err = (v - reference).abs() / reference;
        assert!(err < 0.03, "t = {t}, in_plane = {in_plane}: {v:e} vs {reference:e}, error {err:.4}");
    }
    let (e, nu, t, b, l) = (29.0e6, 0.22, 0.32, 1.1, 12.0);
    let reference = l * l * l / (3.0 * e * t * b * b * b / 12.0) + l / (5.0 / 6.0 * e / (2.0 * (1.0 + nu)) * b * t);
    let rep = [
        ("twist: 90.0", "twist: 0.0".to_string()),
        ("scale: {\"in_plane\": 1.0}", "scale: {\"out_of_plane\": 1.0}".to_string()),
        ("thickness: 0.32", "thickness: 0.32, shear: Mitc4PlusCentre".to_string()),
    ];
    let (v, _, _) = linear_value(scenes::TWISTED_BEAM, "straight_strip", &rep, 0).expect("solve");
    let err = (v - reference).abs() / reference;
    assert!(err < 0.03, "straight strip: {v:e} vs beam theory {reference:e}, error {err:.4}");
}

/// Fabric quarter-circle arch under a radial tip force (`bench::locking::fabric_arch`;
/// analytic curved-beam deflection (π/4) f R³ / B) at the effective t/R of garments,
/// 1e-3, 3e-3 and 7e-3. Regular 16-element mesh: within 1 % (bending discretization error,
/// measured −0.83 % for every formulation and t/R: the flat rectangular elements do not
/// lock). Distorted meshes: 32 elements within 2 % (measured −0.9 … −1.2 %), and the
/// 16-element result independent of t/R to 0.03 (measured 0.931, 0.941, 0.948, both
/// variants within 0.001) — the mark of a locking-free element; MITC4 gives 0.41, 0.63,
/// 0.75 there.
#[test]
fn fabric_arch_bends_without_membrane_locking_at_garment_thickness() {
    use plyshell::bench::locking::fabric_arch;
    use plyshell::mesh::Spacing::{Distorted, Uniform};
    for f in VARIANTS {
        let mut coarse = Vec::new();
        for tr in [1e-3, 3e-3, 7e-3] {
            let v = fabric_arch(tr, 16, f, Uniform).expect("solve").0;
            assert!((v - 1.0).abs() < 0.01, "{f:?}: t/R = {tr}, regular 16: {v:.4}");
            let v = fabric_arch(tr, 32, f, Distorted).expect("solve").0;
            assert!((v - 1.0).abs() < 0.02, "{f:?}: t/R = {tr}, distorted 32: {v:.4}");
            coarse.push(fabric_arch(tr, 16, f, Distorted).expect("solve").0);
        }
        let spread = coarse.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b)) - coarse.iter().fold(f64::INFINITY, |a, &b| a.min(b));
        assert!(spread < 0.03, "{f:?}: distorted 16: {coarse:?}");
    }
}

/// Geometrically nonlinear MITC4+: the cantilever rolled into a full circle by an end moment
/// (analytic, reference/sze2004_cantilever_end_moment.csv), 16×1 elements, St. Venant–
/// Kirchhoff and neo-Hookean: tip within 1 % of the circle at each of the 20 load levels, the
/// tolerance of the MITC4 test in tests/nonlinear_sze.rs.
#[test]
fn mitc4plus_rolls_cantilever_into_a_circle() {
    use plyshell::bench::{end_moment_with, Material};
    for (m, f) in [Material::Svk, Material::NeoHookean].into_iter().flat_map(|m| VARIANTS.map(|f| (m, f))) {
        let c = end_moment_with(16, 0.1, m, f).expect("solve");
        assert_eq!(c.points.len(), 20);
        for p in &c.points {
            assert!(p.rel_error() < 0.01, "{m:?} {f:?} at M/Mmax = {}: tip {:?} vs {:?}", p.level, p.computed, p.reference);
        }
    }
}

/// A garment's plies take their formulation from `garment.shear` (default MITC4): the NBC
/// sleeve without the field, and with `shear: Mitc4PlusCentre` or `shear: Sri`, builds every
/// ply section with the formulation named.
#[test]
fn garment_plies_take_the_garment_formulation() {
    let text = std::fs::read_to_string("garments/nbc_sleeve.ron").expect("scene");
    for (insert, expected) in [("", ShearTreatment::Mitc4), (" shear: Mitc4PlusCentre,", ShearTreatment::Mitc4PlusCentre), (" shear: Sri,", ShearTreatment::Sri)] {
        let t = text.replacen("element_size: 0.02,", &format!("element_size: 0.02,{insert}"), 1);
        let sc = scene::parse("nbc_sleeve", &t).expect("parse");
        let built = scene::build(&sc, "garments/nbc_sleeve.ron", &t).expect("build");
        assert!(!built.model.sections.is_empty());
        assert!(built.model.sections.iter().all(|s| s.shear == expected), "{insert}");
    }
}

/// Half model (y ≥ 0) of the clamped hyperbolic paraboloid z = x² − y², (x, y) ∈ [−L/2, L/2]²
/// (Chapelle & Bathe 1998; Bathe, Iosilevich & Chapelle, "An evaluation of the MITC shell
/// elements", C&S 75 (2000) 1–30): clamped at x = −L/2, the other edges free, under its
/// self-weight (8000 N/m³ × t per area), L = 1, E = 2e11, ν = 0.3; n × n/2 elements,
/// regular or distorted (`Spacing::point`), nodes on the exact surface, written as an OBJ.
/// Returns the downward deflection at the midpoint of the free edge (L/2, 0).
fn clamped_hypar(t: f64, n: usize, f: ShearTreatment, spacing: plyshell::mesh::Spacing) -> f64 {
    use std::fmt::Write;
    let dir = std::env::temp_dir().join(format!("plyshell_hypar_{}_{n}_{spacing:?}_{f:?}_{t:e}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let (nu, nv) = (n, n / 2);
    let mut obj = String::new();
    for j in 0..=nv {
        for i in 0..=nu {
            let (s, r) = spacing.point(i, j, nu, nv);
            let (x, y) = (s - 0.5, 0.5 * r);
            writeln!(obj, "v {x:.17e} {y:.17e} {:.17e}", x * x - y * y).expect("write");
        }
    }
    for j in 0..nv {
        for i in 0..nu {
            let a = j * (nu + 1) + i + 1;
            writeln!(obj, "f {} {} {} {}", a, a + 1, a + nu + 2, a + nu + 1).expect("write");
        }
    }
    std::fs::write(dir.join("hypar.obj"), obj).expect("obj");
    let text = format!(
        "Scene(name: \"clamped_hypar\", materials: {{\"steel\": StVenantKirchhoff(young: 2.0e11, poisson: 0.3)}},
         parts: [(name: \"shell\", mesh: Obj(path: \"hypar.obj\"), material: \"steel\", thickness: {t:e}, shear: {f:?})],
         node_sets: {{\"root\": Plane(point: (-0.5, 0.0, 0.0), normal: (1.0, 0.0, 0.0)), \"sym\": Plane(point: (0.0, 0.0, 0.0), normal: (0.0, 1.0, 0.0))}},
         boundary: [Clamp(set: \"root\"), Symmetry(set: \"sym\", normal: Y)],
         loads: {{\"weight\": Gravity(part: \"shell\", areal_density: {rho:e}, g: (0.0, 0.0, -1.0))}},
         steps: [(name: \"linear\", increments: 1, linear: true, scale: {{\"weight\": 1.0}})],
         monitors: [(name: \"a\", point: (0.5, 0.0, 0.25), dofs: [Uz])])",
        rho = 8000.0 * t
    );
    let path = dir.join("hypar.ron").display().to_string();
    let sc = scene::parse(&path, &text).expect("parse");
    let built = scene::build(&sc, &path, &text).expect("build");
    let s = plyshell::analysis::run(&sc, &built, &Default::default(), &mut |_| {}).expect("solve");
    let _ = std::fs::remove_dir_all(&dir);
    -s.monitors[0].values.last().expect("value")[0]
}

/// Clamped hyperbolic paraboloid (`clamped_hypar`), the pure bending-dominated doubly curved
/// shell of Chapelle & Bathe, distorted and regular meshes, t/L = 1/100 and 1/1000.
/// References: the MITC16 deflections of Bathe, Iosilevich & Chapelle (C&S 75 (2000) 1–30,
/// Table 2: 9.3355e-5 and 6.3941e-3; one fine MITC16 mesh, not an asymptotic value), as
/// quoted with the inputs above in FinEtoolsFlexStructures (clamped_hypar_examples.jl).
/// Measured, normalized (MITC4 / MITC4+ / MITC4+ centre shear), n × n/2 elements:
///
/// | t/L | mesh | 16 | 32 | 64 |
/// |---|---|---|---|---|
/// | 1/100 | regular | 0.968 / 0.954 / 0.968 | 0.987 / 0.981 / 0.987 | 0.995 / 0.993 / 0.995 |
/// | 1/100 | distorted | 0.797 / 0.803 / 0.828 | 0.945 / 0.923 / 0.936 | 0.983 / 0.973 / 0.979 |
/// | 1/1000 | regular | 0.962 / 0.948 / 0.962 | 0.978 / 0.970 / 0.978 | 0.991 / 0.988 / 0.991 |
/// | 1/1000 | distorted | 0.076 / 0.600 / 0.621 | 0.399 / 0.843 / 0.858 | 0.873 / 0.941 / 0.950 |
///
/// (regular elements of z = x² − y² are flat, where MITC4 and the centre-shear variant
/// coincide). Asserted for both MITC4+ variants: regular 64×32 within 2 % at both t/L;
/// distorted 64×32 within 7 % (the finest mesh of the study against a single-mesh
/// reference); distorted 32×16 at t/L = 1/1000 within 20 %, where MITC4 locks (asserted below
/// 0.5, so that the case does test membrane locking). MITC4+ is not free of thickness
/// dependence here: on the distorted 32×16 mesh it loses 8 % from t/L = 1/100 to 1/1000.
#[test]
fn clamped_hyperbolic_paraboloid_against_mitc16() {
    use plyshell::mesh::Spacing::{Distorted, Uniform};
    for (t, reference) in [(0.01, 9.3355e-5), (0.001, 6.3941e-3)] {
        for f in VARIANTS {
            let v = clamped_hypar(t, 64, f, Uniform) / reference;
            assert!((v - 1.0).abs() < 0.02, "{f:?}: t/L = {t}, regular 64x32: {v:.4}");
            let v = clamped_hypar(t, 64, f, Distorted) / reference;
            assert!((v - 1.0).abs() < 0.07, "{f:?}: t/L = {t}, distorted 64x32: {v:.4}");
        }
    }
    let reference = 6.3941e-3;
    for f in VARIANTS {
        let v = clamped_hypar(0.001, 32, f, Distorted) / reference;
        assert!((v - 1.0).abs() < 0.2, "{f:?}: t/L = 1/1000, distorted 32x16: {v:.4}");
    }
    let v = clamped_hypar(0.001, 32, ShearTreatment::Mitc4, Distorted) / reference;
    assert!(v < 0.5, "MITC4, t/L = 1/1000, distorted 32x16: {v:.4} (expected membrane locking)");
}
