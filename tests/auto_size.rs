//! `element_size: Auto((tolerance: ..))` (issue 18): the size field from the fabric's
//! bending length, the Cerda–Mahadevan wrinkle wavelength, the body's curvature and the
//! seams (`garment::sizing`), and the graded pattern meshes that follow it.
//!
//! Formula (module doc of `garment::sizing`): h = √(8 tol) · min(ℓ_b, λ/2π, R_body) with
//! ℓ_b = (B/(ρ_A g))^{1/3} (Peirce 1930) — the linear-interpolation error h² |f''| / 8 of a
//! shape with length scale ℓ equal to tol · |f|.

use plyshell::garment::sizing::{bending_length, G};
use plyshell::{analysis, scene};

/// Plate bending rigidity E t³ / 12(1 − ν²).
fn plate_b(e: f64, t: f64, nu: f64) -> f64 {
    e * t.powi(3) / (12.0 * (1.0 - nu * nu))
}

/// A fabric strip (SVK, E = 2 MPa, t = 0.5 mm, ν = 0, ρ_A = 0.2 kg/m²: ℓ_b = 22.0 mm) of
/// length `l` and width `w`, clamped at x = 0 and hanging under its own weight (a Peirce
/// cantilever), meshed at `size` (RON text of an element size).
fn strip(size: &str, l: f64, w: f64, extra_panel: &str, contact: &str) -> String {
    format!(
        r#"Scene(
    name: "peirce",
    materials: {{"cloth": StVenantKirchhoff(young: 2.0e6, poisson: 0.0)}},
    parts: [],
    garment: Some((
        element_size: {size},
        plies: {{"shell": (material: "cloth", thickness: 0.0005, areal_density: 0.2)}},
        panels: [(name: "strip", outline: [(0.0, 0.0), ({l}, 0.0), ({l}, {w}), (0.0, {w})],
                  edges: {{"root": (from: 3, to: 0), "tip": (from: 1, to: 2)}},
                  grain: (1.0, 0.0), plies: ["shell"]{extra_panel})],
    )),
    node_sets: {{"root": Edge(part: "strip", edge: "root")}},
    boundary: [Clamp(set: "root")],
    loads: {{"weight": Gravity(part: "strip", areal_density: 0.2, g: (0.0, 0.0, -9.81))}},
    steps: [(name: "hang", increments: 8, scale: {{"weight": 1.0}})],
    monitors: [(name: "tip", point: ({l}, 0.0, 0.0), part: Some("strip"), dofs: [Ux, Uz])],
    {contact}
    output: (vtu: false),
)"#
    )
}

/// The target sizes of every garment element (the VTU's `element_size` cell data).
fn sizes(text: &str) -> (Vec<f64>, usize) {
    let sc = scene::parse("auto.ron", text).unwrap_or_else(|e| panic!("{e}"));
    let built = scene::build(&sc, "auto.ron", text).unwrap_or_else(|e| panic!("{e}"));
    let l = built.garment.as_ref().expect("a garment layout");
    (l.part_element_size.iter().flatten().copied().collect(), built.model.elements.len())
}

/// On a single panel without seams, notches or bodies the Auto size is the formula,
/// uniformly: √(8 tol) ℓ_b (the wrinkle wavelength under the panel's own weight, 2√π L^{1/4}
/// ℓ_b^{3/4} / 2π = 42 mm here, is longer than ℓ_b), and the mapped grid has ceil(L/h)
/// elements along each side. Analytic, to rounding.
#[test]
fn auto_size_is_the_bending_length_formula_on_a_plain_panel() {
    let (l, w, tol): (f64, f64, f64) = (0.3, 0.1, 0.02);
    let lb = bending_length(plate_b(2.0e6, 0.0005, 0.0), 0.2);
    assert!((lb - (2.0e6 * 0.0005f64.powi(3) / 12.0 / (0.2 * G)).cbrt()).abs() < 1e-15);
    let want = (8.0 * tol).sqrt() * lb;
    // No span ends inside straight runs: the strip's named edges end at corners, but span
    // ends are refined as notches; turn the seam/notch refinement off for the plain formula.
    let text = strip(&format!("Auto((tolerance: {tol}, seam_factor: 1.0))"), l, w, "", "");
    let (h, n) = sizes(&text);
    println!("ℓ_b = {:.4} mm, h = {:.4} mm, {n} elements", 1e3 * lb, 1e3 * want);
    assert!(h.iter().all(|&x| (x - want).abs() < 1e-12 * want), "sizes {:?} vs {want}", &h[..3]);
    assert_eq!(n, ((l / want).ceil() * (w / want).ceil()) as usize);
}

/// A panel-level size overrides the garment's, and a panel lying on a body more curved than
/// the fabric's bending length gets its size from the body: a 10 mm cylinder under the same
/// strip rolled round it, h = √(8 tol) (R + d) with d = 1 mm the strip's distance from the
/// body (the radius of the offset surface the strip lies on; the normal-turn estimate of
/// `radius_from_normals` is exact for a cylinder), to 2 %.
#[test]
fn auto_size_follows_the_body_curvature() {
    let tol: f64 = 0.02;
    let r_body = 0.01;
    let text = format!(
        r#"Scene(
    name: "wrap",
    materials: {{"cloth": StVenantKirchhoff(young: 2.0e6, poisson: 0.0)}},
    parts: [],
    garment: Some((
        element_size: 0.01,
        plies: {{"shell": (material: "cloth", thickness: 0.0005, areal_density: 0.2)}},
        panels: [(name: "wrap", outline: [(0.0, 0.0), (0.05, 0.0), (0.05, 0.1), (0.0, 0.1)], plies: ["shell"],
                  element_size: Some(Auto((tolerance: {tol}, seam_factor: 1.0))),
                  placement: Cylinder(origin: (0.0, 0.0, 0.0), axis: (0.0, 0.0, 1.0), radius: 0.011))],
    )),
    node_sets: {{"all": Part(part: "wrap")}},
    boundary: [Fix(set: "all", dofs: [Uz])],
    loads: {{"weight": Gravity(part: "wrap", areal_density: 0.2, g: (0.0, 0.0, -9.81))}},
    steps: [(name: "s", increments: 1, scale: {{"weight": 1.0}})],
    contact: Some((bodies: [(name: "rod", shape: Cylinder(radius: {r_body}, height: 0.3))])),
    output: (vtu: false),
)"#
    );
    let (h, _) = sizes(&text);
    let want = (8.0 * tol).sqrt() * 0.011;
    println!("h = {:.4} mm (body radius 10 mm, panel at 11 mm), want {:.4} mm", 1e3 * h[0], 1e3 * want);
    assert!(h.iter().all(|&x| (x / want - 1.0).abs() < 0.02), "{} vs {want}", h[0]);
}

/// Seams and notches refine: a strip with a seam along its tip edge and a notch span gets
/// half the size on the seam, graded back to the panel size over ℓ_b, and more elements.
#[test]
fn seams_refine_the_auto_mesh() {
    let (l, w, tol): (f64, f64, f64) = (0.3, 0.1, 0.02);
    let plain = strip(&format!("Auto((tolerance: {tol}, seam_factor: 1.0))"), l, w, "", "");
    let (h_plain, n_plain) = sizes(&plain);
    let text = format!(
        r#"Scene(
    name: "seamed",
    materials: {{"cloth": StVenantKirchhoff(young: 2.0e6, poisson: 0.0)}},
    parts: [],
    garment: Some((
        element_size: Auto((tolerance: {tol})),
        plies: {{"shell": (material: "cloth", thickness: 0.0005, areal_density: 0.2)}},
        panels: [
            (name: "a", outline: [(0.0, 0.0), ({l}, 0.0), ({l}, {w}), (0.0, {w})], edges: {{"tip": (from: 1, to: 2), "root": (from: 3, to: 0)}}, grain: (1.0, 0.0), plies: ["shell"]),
            (name: "b", outline: [(0.0, 0.0), ({l}, 0.0), ({l}, {w}), (0.0, {w})], edges: {{"root": (from: 3, to: 0)}}, grain: (1.0, 0.0), plies: ["shell"],
             placement: Rigid(translation: ({l}, 0.0, 0.0))),
        ],
        seams: [(name: "join", a: (panel: "a", edge: "tip"), b: (panel: "b", edge: "root"), kind: Plain)],
    )),
    node_sets: {{"root": Edge(part: "a", edge: "root")}},
    boundary: [Clamp(set: "root")],
    loads: {{"weight": Gravity(part: "a", areal_density: 0.2, g: (0.0, 0.0, -9.81))}},
    steps: [(name: "s", increments: 1, scale: {{"weight": 1.0}})],
    output: (vtu: false),
)"#
    );
    let (h, n) = sizes(&text);
    let base = h_plain[0];
    let (lo, hi) = h.iter().fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
    println!("plain: {n_plain} elements at {:.2} mm; seamed two panels: {n} elements, sizes {:.2}–{:.2} mm", 1e3 * base, 1e3 * lo, 1e3 * hi);
    assert!((hi - base).abs() < 1e-12 * base, "largest size {hi} vs {base}");
    // Element centroids lie half an element off the seam: between 0.5 h and 0.5 h + the ramp.
    assert!(lo > 0.5 * base && lo < 0.75 * base, "smallest size {lo}");
    assert!(n > 2 * n_plain, "{n} vs 2 × {n_plain}");
}

/// Bad `Auto` parameters are located errors naming the field.
#[test]
fn bad_auto_parameters_are_located_errors() {
    for (size, field, words) in [
        ("Auto((tolerance: 0.9))", "garment.element_size.tolerance", "between 0 and 0.5"),
        ("Auto((tolerance: -1.0))", "garment.element_size.tolerance", "between 0 and 0.5"),
        ("Auto((tolerance: 0.01, seam_factor: 2.0))", "garment.element_size.seam_factor", "seam factor"),
        ("Auto((tolerance: 0.01, tension: Some(-3.0)))", "garment.element_size.tension", "positive tension"),
    ] {
        let text = strip(size, 0.3, 0.1, "", "");
        let sc = scene::parse("bad.ron", &text).unwrap_or_else(|e| panic!("{e}"));
        let e = scene::build(&sc, "bad.ron", &text).err().unwrap_or_else(|| panic!("{size} accepted"));
        println!("{e}");
        assert_eq!(e.field, field, "{e}");
        assert!(e.message.contains(words), "{e}");
        assert_eq!(e.line, 6, "{e}");
    }
    // A misspelt parameter is a parse error at its line.
    let text = strip("Auto((tolerence: 0.01))", 0.3, 0.1, "", "");
    let e = scene::parse("bad.ron", &text).err().expect("refused");
    println!("{e}");
    assert_eq!(e.line, 6, "{e}");
    assert!(e.to_string().contains("tolerence"), "{e}");
    // A ply without any areal density: located at the element size, naming the ply.
    let text = strip("Auto((tolerance: 0.01))", 0.3, 0.1, "", "").replace(", areal_density: 0.2)}", ")}").replace("Gravity(part: \"strip\"", "Gravity(part: \"other\"");
    let sc = scene::parse("bad.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let e = scene::build(&sc, "bad.ron", &text).err().expect("refused");
    println!("{e}");
    assert!(e.field.starts_with("garment.element_size") && e.message.contains("areal density"), "{e}");
}

/// The Peirce cantilever (strip 4.5 ℓ_b long, hanging under its own weight): the Auto mesh
/// at tolerance 0.01 puts the tip within 1 % of the strip's length (the tolerance it asks for)
/// of the tip on a uniform mesh of ℓ_b / 10, with fewer than a quarter of its DOFs (measured: 0.04 % of L, 700 against 3450 DOFs:
/// the size formula is conservative here).
#[test]
fn auto_mesh_of_a_peirce_cantilever_matches_the_fine_mesh_with_fewer_dofs() {
    let (l, w, tol) = (0.1, 0.03, 0.01);
    let lb = bending_length(plate_b(2.0e6, 0.0005, 0.0), 0.2);
    let run = |size: String| {
        let text = strip(&size, l, w, "", "");
        let sc = scene::parse("peirce.ron", &text).unwrap_or_else(|e| panic!("{e}"));
        let built = scene::build(&sc, "peirce.ron", &text).unwrap_or_else(|e| panic!("{e}"));
        let t = std::time::Instant::now();
        let s = analysis::run(&sc, &built, &Default::default(), &mut |_| {}).unwrap_or_else(|e| panic!("{size}: {e}"));
        let v = s.monitors[0].values.last().expect("a value").clone();
        println!("{size}: {} DOFs, tip (ux, uz) = ({:.5}, {:.5}) m, {:.2} s", s.sizes.dofs, v[0], v[1], t.elapsed().as_secs_f64());
        (s.sizes.dofs, v[0], v[1])
    };
    let (n_fine, ux_fine, uz_fine) = run(format!("{}", lb / 10.0));
    let (n_auto, ux_auto, uz_auto) = run(format!("Auto((tolerance: {tol}))"));
    let err = (ux_auto - ux_fine).hypot(uz_auto - uz_fine) / l;
    println!("tip error {:.3} % of L; DOFs {n_auto} vs {n_fine}", 100.0 * err);
    assert!(uz_fine < -0.5 * l, "the strip hangs: uz = {uz_fine}");
    assert!(err < tol, "tip error {err} of L");
    assert!(4 * n_auto < n_fine, "{n_auto} vs {n_fine} DOFs");
}

/// The shipped Cusick scene (`garments/drape/cusick.ron`) with polyester faille (B = 1.5e-6
/// N·m in its weaker direction, ρ_A = 0.15 kg/m², h = 0.3 mm) and its specimen meshed by
/// `mesh` (RON text of a mesh spec).
fn cusick_with(mesh: &str) -> String {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/garments/drape/cusick.ron")).expect("scene");
    text.replace("preset: Some(\"cotton_broadcloth\")", "preset: Some(\"polyester_faille\")")
        .replace("FocusedAnnulus(ri: 0.02, ro: 0.15, ntheta: 48, focus: 0.09, refine: 8.0, inner_aspect: 4.0)", mesh)
        .replace("output: (every: 50)", "output: (vtu: false)")
}

/// Ring radii and sectors of a built annulus (nodes on rings of equal radius).
fn rings_of(text: &str) -> (Vec<f64>, usize) {
    let sc = scene::parse("cusick.ron", text).unwrap_or_else(|e| panic!("{e}"));
    let built = scene::build(&sc, "cusick.ron", text).unwrap_or_else(|e| panic!("{e}"));
    let mut r: Vec<f64> = built.model.x0.iter().map(|x| x.xy().norm()).collect();
    r.sort_by(f64::total_cmp);
    r.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    (r.clone(), built.model.x0.len() / r.len())
}

/// `SizedAnnulus` with `Auto` on the Cusick specimen (`scene::sizing`), against the formulas
/// by hand: the sectors make the circumferential width at the disc's edge r_e (90 mm; the
/// probe finds the edge where the rounded rim leaves the specimen's thickness, 89–91 mm)
/// √(8T) λ/2π, λ the Cerda–Mahadevan wavelength of the overhang L = ro − r_e under the edge
/// tension ρ_A g L; the finest ring step, at the rim, is √(8T) ℓ_T with ℓ_T = √(B/(ρ_A g L))
/// (4.1 mm, larger than the 1 mm rim radius) to the ring equidistribution's rounding (10 %);
/// the outer overhang's rings are √(8T) ℓ_b apart (10 %); the 25 % grading and the 4:1
/// aspect bound hold everywhere. A fixed size h gives rings ≤ h apart and sectors ≤ h wide at ro.
#[test]
fn sized_annulus_follows_the_fold_wavelength_and_the_rim() {
    let (t, b, rho, ro): (f64, f64, f64, f64) = (0.02, 1.5e-6, 0.15, 0.15);
    let s = (8.0 * t).sqrt();
    let (r, ntheta) = rings_of(&cusick_with(&format!("SizedAnnulus(ri: 0.02, ro: {ro}, element_size: Auto((tolerance: {t})))")));
    let sectors = |re: f64| {
        let l = ro - re;
        let lam = plyshell::sizing::wrinkle_wavelength(b, rho * G * l, l);
        (std::f64::consts::TAU * re / (s * lam / std::f64::consts::TAU)).ceil() as usize
    };
    let lb = bending_length(b, rho);
    let lt = plyshell::sizing::tension_length(b, rho * G * (ro - 0.09));
    let steps: Vec<f64> = r.windows(2).map(|w| w[1] - w[0]).collect();
    let min = steps.iter().copied().fold(f64::INFINITY, f64::min);
    let outer = steps[steps.len() - 1];
    println!(
        "Auto T = {t}: {ntheta} sectors × {} rings ({} nodes); ℓ_b = {:.2} mm, ℓ_T = {:.2} mm; rim step {:.3} mm, outer {:.3} mm",
        r.len(),
        r.len() * ntheta,
        1e3 * lb,
        1e3 * lt,
        1e3 * min,
        1e3 * outer
    );
    assert!((sectors(0.089)..=sectors(0.091)).contains(&ntheta), "{ntheta} sectors, by hand {}..{}", sectors(0.089), sectors(0.091));
    assert!((min / (s * lt) - 1.0).abs() < 0.1, "rim step {min} vs {}", s * lt);
    assert!((outer / (s * lb) - 1.0).abs() < 0.1, "outer step {outer} vs {}", s * lb);
    let w = std::f64::consts::TAU / ntheta as f64;
    for (k, d) in steps.iter().enumerate() {
        assert!(*d <= 4.0 * w * r[k + 1] * 1.01, "ring {k}: {d} over 4 widths");
        if k > 0 {
            let q = d / steps[k - 1];
            assert!(q < 1.3 && q > 1.0 / 1.3, "ring {k}: steps {} → {d}", steps[k - 1]);
        }
    }
    let (r, ntheta) = rings_of(&cusick_with("SizedAnnulus(ri: 0.02, ro: 0.15, element_size: 0.005)"));
    assert_eq!(ntheta, (std::f64::consts::TAU * 0.15 / 0.005).ceil() as usize);
    assert_eq!(r.len(), 27);
    assert!(r.windows(2).all(|w| w[1] - w[0] <= 0.005 * (1.0 + 1e-9)));
}

/// Bad `SizedAnnulus` values are located errors naming the field and the line.
#[test]
fn bad_sized_annulus_values_are_located_errors() {
    for (mesh, field, words) in [
        ("SizedAnnulus(ri: 0.02, ro: 0.01, element_size: Auto((tolerance: 0.02)))", "parts[specimen].mesh.ro", "greater than ri"),
        ("SizedAnnulus(ri: -0.02, ro: 0.15, element_size: Auto((tolerance: 0.02)))", "parts[specimen].mesh.ri", "positive inner radius"),
        ("SizedAnnulus(ri: 0.02, ro: 0.15, element_size: Auto((tolerance: 0.9)))", "parts[specimen].mesh.element_size.tolerance", "between 0 and 0.5"),
        ("SizedAnnulus(ri: 0.02, ro: 0.15, element_size: Auto((tolerance: 0.02, tension: Some(0.0))))", "parts[specimen].mesh.element_size.tension", "positive tension"),
        ("SizedAnnulus(ri: 0.02, ro: 0.15, element_size: -0.005)", "parts[specimen].mesh.element_size", "positive element size"),
    ] {
        let text = cusick_with(mesh);
        let sc = scene::parse("cusick.ron", &text).unwrap_or_else(|e| panic!("{e}"));
        let e = scene::build(&sc, "cusick.ron", &text).err().unwrap_or_else(|| panic!("{mesh} accepted"));
        println!("{e}");
        assert_eq!(e.field, field, "{e}");
        assert!(e.message.contains(words), "{e}");
        assert_eq!(e.line, 18, "{e}");
    }
    // A misspelt parameter is a parse error at its line.
    let text = cusick_with("SizedAnnulus(ri: 0.02, ro: 0.15, element_size: Auto((tolerence: 0.02)))");
    let e = scene::parse("cusick.ron", &text).err().expect("refused");
    assert_eq!(e.line, 18, "{e}");
    assert!(e.to_string().contains("tolerence"), "{e}");
}

/// `SizedRectangle` with `Auto` (`scene::sizing::sized_rectangle`): the shipped cotton sheet
/// over a sphere (`garments/drape/sphere.ron`; B = 0.9e-5 N·m in its weaker direction, ρ_A =
/// 0.12 kg/m²) gets the garment panels' size √(8T) min(ℓ_b, λ/2π, R_body): on the 80 mm
/// sphere the bending length ℓ_b = 19.7 mm governs, (⌈0.3 / h⌉)² elements; on a 10 mm sphere
/// the body's radius does: that of the offset sphere through the probe point nearest the top,
/// between 10.15 mm (the sheet lies 0.15 mm above the sphere) and √(10.15² + d²) mm, d ≤ 5.6 mm
/// the half diagonal of the probe grid (the ℓ_b-sized grid, 7.9 mm).
#[test]
fn sized_rectangle_takes_the_panel_size() {
    let t: f64 = 0.02;
    let s = (8.0 * t).sqrt();
    let lb = bending_length(0.9e-5, 0.12);
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/garments/drape/sphere.ron")).expect("scene");
    let text = text.replace("Rectangle(lx: 0.3, ly: 0.3, nx: 16, ny: 16)", &format!("SizedRectangle(lx: 0.3, ly: 0.3, element_size: Auto((tolerance: {t})))"));
    for (radius, l_lo, l_hi) in [(0.08, lb, lb), (0.01, 0.01015, 0.01015f64.hypot(0.3 / (0.3 / (s * lb)).ceil() / 2f64.sqrt()))] {
        let text = text.replace("Sphere(radius: 0.08), translation: (0.15, 0.15, -0.08015)", &format!("Sphere(radius: {radius}), translation: (0.15, 0.15, {})", -radius - 0.00015));
        let sc = scene::parse("sphere.ron", &text).unwrap_or_else(|e| panic!("{e}"));
        let built = scene::build(&sc, "sphere.ron", &text).unwrap_or_else(|e| panic!("{e}"));
        let (lo, hi) = ((0.3 / (s * l_hi)).ceil() as usize, (0.3 / (s * l_lo)).ceil() as usize);
        println!("sphere {radius} m: {} elements, by hand {lo}² to {hi}²", built.model.elements.len());
        assert!((lo..=hi).any(|n| built.model.elements.len() == n * n), "{} elements", built.model.elements.len());
    }
    let text = text.replace("Auto((tolerance: 0.02))", "Auto((tolerance: 0.02, tension: Some(-1.0)))");
    let sc = scene::parse("sphere.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let e = scene::build(&sc, "sphere.ron", &text).err().expect("refused");
    println!("{e}");
    assert_eq!(e.field, "parts[cloth].mesh.element_size.tension", "{e}");
    assert_eq!(e.line, 9, "{e}");
}
