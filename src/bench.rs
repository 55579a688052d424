//! Verification benchmarks: each runs a bundled scene at a chosen mesh and compares with
//! its published or analytic reference. Used by `plyshell bench` and by the tests.

use std::path::Path;
use std::time::Instant;

use serde::Serialize;

use crate::analysis::{self, RunOptions};
use crate::io::plot::{plot_xy, Series};
use crate::results::Summary;
use crate::scene;

pub mod drive;
pub mod locking;

/// Bundled benchmark scenes.
pub mod scenes {
    /// Sze et al. (2004) §3.2 end-moment cantilever.
    pub const END_MOMENT: &str = include_str!("../garments/benchmarks/cantilever_end_moment.ron");
    /// Sze et al. (2004) §3.1 end-shear cantilever.
    pub const END_SHEAR: &str = include_str!("../garments/benchmarks/cantilever_end_shear.ron");
    /// Sze et al. (2004) §3.3 slit annular plate.
    pub const SLIT_ANNULUS: &str = include_str!("../garments/benchmarks/slit_annular_plate.ron");
    /// Scordelis–Lo roof.
    pub const SCORDELIS_LO: &str = include_str!("../garments/benchmarks/scordelis_lo_roof.ron");
    /// Pinched cylinder.
    pub const PINCHED_CYLINDER: &str = include_str!("../garments/benchmarks/pinched_cylinder.ron");
    /// Twisted beam.
    pub const TWISTED_BEAM: &str = include_str!("../garments/benchmarks/twisted_beam.ron");
    /// Clamped plate, thin limit.
    pub const CLAMPED_PLATE: &str = include_str!("../garments/benchmarks/clamped_plate.ron");
    /// Simply supported square plate in uniaxial compression, linearized buckling.
    pub const PLATE_BUCKLING: &str = include_str!("../garments/benchmarks/plate_buckling.ron");
    /// Axially compressed cylinder (quarter), linearized buckling.
    pub const CYLINDER_BUCKLING: &str = include_str!("../garments/benchmarks/cylinder_buckling.ron");
    /// The square plate loaded past buckling, seeded with its first mode.
    pub const PLATE_POSTBUCKLING: &str = include_str!("../garments/benchmarks/plate_postbuckling.ron");
    /// Sze et al. (2004) §3.8a hinged cylindrical roof, arc length.
    pub const HINGED_ROOF: &str = include_str!("../garments/benchmarks/hinged_roof.ron");
}

/// Bundled reference tables (copies of `shared/reference`, headers name the sources).
pub mod references {
    /// Elastica computed for the end-shear cantilever.
    pub const END_SHEAR_ELASTICA: &str = include_str!("../reference/cantilever_end_shear_elastica_computed.csv");
    /// Sze et al. (2004) slit annular plate, S4R 10×80.
    pub const SLIT_ANNULUS: &str = include_str!("../reference/sze2004_slit_annular_plate.csv");
    /// Sze et al. (2004) hinged roof case a, ordered along the path.
    pub const HINGED_ROOF_A: &str = include_str!("../reference/sze2004_hinged_roof_case_a.csv");
}

/// One benchmark run.
#[derive(Clone, Debug, Serialize)]
pub struct Record {
    /// Benchmark name.
    pub benchmark: String,
    /// Mesh label.
    pub mesh: String,
    /// Free DOFs.
    pub dofs: usize,
    /// Newton iterations.
    pub newton_iterations: usize,
    /// Wall time of the solve (s).
    pub wall_s: f64,
    /// Computed value (for curves: at the last load level).
    pub value: f64,
    /// Reference value it compares with.
    pub reference: f64,
    /// Relative error (for curves: the largest over all reference levels).
    pub rel_error: f64,
}

/// Parses a numeric CSV with `#` comments and one header line.
pub fn parse_csv(text: &str) -> Vec<Vec<f64>> {
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .skip(1)
        .map(|l| l.split(',').filter_map(|v| v.trim().parse::<f64>().ok()).collect())
        .collect()
}

/// Applies text substitutions to a scene template and solves it without writing files.
pub fn solve_variant(template: &str, name: &str, replace: &[(&str, String)]) -> Result<Summary, String> {
    let mut text = template.to_string();
    for (from, to) in replace {
        if !text.contains(from) {
            return Err(format!("benchmark {name}: template has no '{from}'"));
        }
        text = text.replacen(from, to, 1);
    }
    let sc = scene::parse(name, &text).map_err(|e| e.to_string())?;
    let built = scene::build(&sc, name, &text).map_err(|e| e.to_string())?;
    analysis::run(&sc, &built, &RunOptions::default(), &mut |_| {}).map_err(|e| e.to_string())
}

/// Material variants the curves are run with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Material {
    /// St. Venant–Kirchhoff.
    Svk,
    /// Ciarlet neo-Hookean with K, μ from the same E, ν.
    NeoHookean,
}

/// Substitution turning a scene's St. Venant–Kirchhoff material into the neo-Hookean one
/// with the same E, ν.
fn material_swap(m: Material) -> Vec<(&'static str, String)> {
    match m {
        Material::Svk => vec![],
        Material::NeoHookean => vec![("StVenantKirchhoff(", "NeoHookean(".to_string())],
    }
}

/// `thickness: h` with the shear treatment: SRI when asked for, else MITC4 (these
/// benchmarks compare the two transverse shear treatments, so MITC4 is named explicitly
/// rather than taken from the default formulation).
fn thickness_field(h: f64, shear_sri: bool) -> String {
    use crate::element::ShearTreatment::{Mitc4, Sri};
    thickness_with(h, if shear_sri { Sri } else { Mitc4 })
}

/// `thickness: h, shear: f`.
fn thickness_with(h: f64, f: crate::element::ShearTreatment) -> String {
    format!("thickness: {h:e}, shear: {}", locking::formulation_name(f))
}

/// A tip-curve comparison: load level, computed (a, b), reference (a, b).
#[derive(Clone, Debug)]
pub struct CurvePoint {
    /// Load fraction.
    pub level: f64,
    /// Computed pair.
    pub computed: [f64; 2],
    /// Reference pair.
    pub reference: [f64; 2],
}

impl CurvePoint {
    /// |computed − reference| / |reference| for the pair as a vector.
    pub fn rel_error(&self) -> f64 {
        let d = ((self.computed[0] - self.reference[0]).powi(2) + (self.computed[1] - self.reference[1]).powi(2)).sqrt();
        d / (self.reference[0].powi(2) + self.reference[1].powi(2)).sqrt()
    }
}

/// Result of a curve benchmark.
#[derive(Clone, Debug)]
pub struct Curve {
    /// The run.
    pub summary: Summary,
    /// Points compared.
    pub points: Vec<CurvePoint>,
    /// Wall time (s).
    pub wall_s: f64,
}

impl Curve {
    /// Largest relative error over the points.
    pub fn max_error(&self) -> f64 {
        self.points.iter().map(CurvePoint::rel_error).fold(0.0, f64::max)
    }
}

/// End-moment roll-up (Sze et al. 2004 §3.2) on an nx×1 mesh with thickness `h`
/// (the moment is scaled with EI so M/M0 runs to 2π). Reference: the analytic circle,
/// −u = L(1 − sin m/m), w = L(1 − cos m)/m.
pub fn end_moment(nx: usize, h: f64, material: Material, shear_sri: bool) -> Result<Curve, String> {
    use crate::element::ShearTreatment::{Mitc4, Sri};
    end_moment_with(nx, h, material, if shear_sri { Sri } else { Mitc4 })
}

/// [`end_moment`] with element formulation `f`.
pub fn end_moment_with(nx: usize, h: f64, material: Material, f: crate::element::ShearTreatment) -> Result<Curve, String> {
    let t = Instant::now();
    let mmax = 2.0 * std::f64::consts::PI * 1.2e6 * h.powi(3) / 12.0 / 12.0;
    let mut rep = vec![("nx: 16", format!("nx: {nx}")), ("thickness: 0.1", thickness_with(h, f)), ("-52.35987755982988", format!("{:e}", -mmax))];
    rep.extend(material_swap(material));
    let summary = solve_variant(scenes::END_MOMENT, "cantilever_end_moment", &rep)?;
    let tip = &summary.monitors[0];
    let points = summary
        .increments
        .iter()
        .zip(&tip.values)
        .map(|(inc, v)| {
            let m = 2.0 * std::f64::consts::PI * inc.scales[0];
            CurvePoint { level: inc.scales[0], computed: [-v[0], v[1]], reference: [12.0 * (1.0 - m.sin() / m), 12.0 * (1.0 - m.cos()) / m] }
        })
        .collect();
    Ok(Curve { summary, points, wall_s: t.elapsed().as_secs_f64() })
}

/// End-shear cantilever (Sze et al. 2004 §3.1) on nx×1 with thickness `h` (force scaled with
/// EI); reference: the computed elastica table (−u, w) at each load level.
pub fn end_shear(nx: usize, h: f64, material: Material, shear_sri: bool) -> Result<Curve, String> {
    let t = Instant::now();
    let pmax = 4.0 * (h / 0.1f64).powi(3);
    let mut rep = vec![("nx: 16", format!("nx: {nx}")), ("thickness: 0.1", thickness_field(h, shear_sri)), ("force: (0.0, 0.0, 4.0)", format!("force: (0.0, 0.0, {pmax:e})"))];
    rep.extend(material_swap(material));
    let summary = solve_variant(scenes::END_SHEAR, "cantilever_end_shear", &rep)?;
    let table = parse_csv(references::END_SHEAR_ELASTICA);
    let tip = &summary.monitors[0];
    let mut points = Vec::new();
    for (inc, v) in summary.increments.iter().zip(&tip.values) {
        if let Some(row) = table.iter().find(|r| r.len() >= 5 && (r[0] - inc.scales[0]).abs() < 1e-9) {
            points.push(CurvePoint { level: inc.scales[0], computed: [-v[0], v[1]], reference: [row[3], row[4]] });
        }
    }
    Ok(Curve { summary, points, wall_s: t.elapsed().as_secs_f64() })
}

/// Slit annular plate (Sze et al. 2004 §3.3) on nr×nθ; compares w_A and w_B with the table.
/// The returned points hold (w_A, w_B); the error of each point is reported per component.
pub fn slit_annulus(nr: usize, ntheta: usize, material: Material) -> Result<Curve, String> {
    let t = Instant::now();
    let mut rep = vec![("nr: 10, ntheta: 80", format!("nr: {nr}, ntheta: {ntheta}"))];
    rep.extend(material_swap(material));
    let summary = solve_variant(scenes::SLIT_ANNULUS, "slit_annular_plate", &rep)?;
    let table = parse_csv(references::SLIT_ANNULUS);
    let (a, b) = (&summary.monitors[0], &summary.monitors[1]);
    let mut points = Vec::new();
    for ((inc, va), vb) in summary.increments.iter().zip(&a.values).zip(&b.values) {
        if let Some(row) = table.iter().find(|r| r.len() >= 4 && r[0] > 0.0 && (r[0] - inc.scales[0]).abs() < 1e-9) {
            points.push(CurvePoint { level: inc.scales[0], computed: [va[0], vb[0]], reference: [row[2], row[3]] });
        }
    }
    Ok(Curve { summary, points, wall_s: t.elapsed().as_secs_f64() })
}

/// Largest componentwise relative error of a two-point curve (slit annulus).
pub fn max_component_error(points: &[CurvePoint]) -> f64 {
    points
        .iter()
        .flat_map(|p| (0..2).map(move |k| ((p.computed[k] - p.reference[k]) / p.reference[k]).abs()))
        .fold(0.0, f64::max)
}

/// A linear benchmark value: the monitored quantity's magnitude.
pub fn linear_value(template: &str, name: &str, rep: &[(&str, String)], quantity: usize) -> Result<(f64, Summary, f64), String> {
    let t = Instant::now();
    let s = solve_variant(template, name, rep)?;
    let v = s.monitors[0].values.last().and_then(|v| v.get(quantity)).copied().ok_or("no monitored value")?;
    Ok((v.abs(), s, t.elapsed().as_secs_f64()))
}

/// Scordelis–Lo roof on an n×n quarter model: |u_z| at the free-edge midpoint.
pub fn scordelis_lo(n: usize) -> Result<(f64, Summary, f64), String> {
    linear_value(scenes::SCORDELIS_LO, "scordelis_lo_roof", &[("n_axial: 16, n_circ: 16", format!("n_axial: {n}, n_circ: {n}"))], 0)
}

/// Pinched cylinder on an n×n octant: |u_z| under the load.
pub fn pinched_cylinder(n: usize) -> Result<(f64, Summary, f64), String> {
    linear_value(scenes::PINCHED_CYLINDER, "pinched_cylinder", &[("n_axial: 32, n_circ: 32", format!("n_axial: {n}, n_circ: {n}"))], 0)
}

/// Twisted beam on nx×ny, thickness `t` (load scaled as t³ like the reference: P = 1 for
/// 0.32, 1e-6 for 0.0032), in-plane (along z) or out-of-plane (along y).
pub fn twisted_beam(nx: usize, ny: usize, t: f64, in_plane: bool) -> Result<(f64, Summary, f64), String> {
    let p = if t < 0.01 { 1e-6 } else { 1.0 };
    let (load, q) = if in_plane { ("in_plane", 1) } else { ("out_of_plane", 0) };
    let rep = vec![
        ("nx: 12, ny: 2", format!("nx: {nx}, ny: {ny}")),
        ("thickness: 0.32", format!("thickness: {t:e}")),
        ("scale: {\"in_plane\": 1.0}", format!("scale: {{\"{load}\": {p:e}}}")),
    ];
    linear_value(scenes::TWISTED_BEAM, "twisted_beam", &rep, q)
}

/// Clamped square plate under pressure, quarter n×n, thickness/side `t`: centre deflection
/// and the Kirchhoff reference 0.00126532 q a⁴ / D.
pub fn clamped_plate(n: usize, t: f64, shear_sri: bool) -> Result<(f64, f64, Summary, f64), String> {
    let q = 1e-6 * (t / 1e-4f64).powi(3);
    let rep = vec![
        ("nx: 16, ny: 16", format!("nx: {n}, ny: {n}")),
        ("thickness: 1.0e-4", thickness_field(t, shear_sri)),
        ("traction: (0.0, 0.0, -1.0e-6)", format!("traction: (0.0, 0.0, {:e})", -q)),
    ];
    let (v, s, w) = linear_value(scenes::CLAMPED_PLATE, "clamped_plate", &rep, 0)?;
    let d = 1.0e7 * t.powi(3) / (12.0 * (1.0 - 0.09));
    Ok((v, 0.00126532 * q / d, s, w))
}

/// A load–deflection path compared with a reference polyline.
#[derive(Clone, Debug)]
pub struct PathComparison {
    /// The run.
    pub summary: Summary,
    /// Computed path (deflection, load), starting at (0, 0).
    pub path: Vec<(f64, f64)>,
    /// Reference path (deflection, load).
    pub reference: Vec<(f64, f64)>,
    /// Largest distance between the two polylines (both directions, Hausdorff) in
    /// coordinates normalised by the reference's deflection and load ranges; computed points
    /// beyond the reference's largest deflection are left out.
    pub curve_error: f64,
    /// Computed limit load: vertex of the parabola P(w) through the highest point of the
    /// first rising branch and its two neighbours.
    pub limit_load: f64,
    /// Reference limit load (largest load before the first descent).
    pub reference_limit: f64,
    /// Wall time (s).
    pub wall_s: f64,
}

/// Distance from `q` to the polyline `poly`, coordinates divided by `scale`.
pub fn polyline_distance(q: (f64, f64), poly: &[(f64, f64)], scale: (f64, f64)) -> f64 {
    let (qx, qy) = (q.0 / scale.0, q.1 / scale.1);
    poly.windows(2)
        .map(|w| {
            let (ax, ay, bx, by) = (w[0].0 / scale.0, w[0].1 / scale.1, w[1].0 / scale.0, w[1].1 / scale.1);
            let (dx, dy) = (bx - ax, by - ay);
            let l2 = dx * dx + dy * dy;
            let t = if l2 > 0.0 { (((qx - ax) * dx + (qy - ay) * dy) / l2).clamp(0.0, 1.0) } else { 0.0 };
            (qx - ax - t * dx).hypot(qy - ay - t * dy)
        })
        .fold(f64::INFINITY, f64::min)
}

/// Vertex height of the parabola through three points (x, y); the middle y when they are
/// collinear.
fn parabola_peak(p: [(f64, f64); 3]) -> f64 {
    let [(x0, y0), (x1, y1), (x2, y2)] = p;
    // Newton divided differences: y = y0 + d1 (x − x0) + d2 (x − x0)(x − x1).
    let d01 = (y1 - y0) / (x1 - x0);
    let d12 = (y2 - y1) / (x2 - x1);
    let d2 = (d12 - d01) / (x2 - x0);
    if !(d2 < 0.0) || !d2.is_finite() {
        return y1;
    }
    // dy/dx = d01 + d2 (2x − x0 − x1) = 0.
    let xv = (x0 + x1) / 2.0 - d01 / (2.0 * d2);
    y0 + d01 * (xv - x0) + d2 * (xv - x0) * (xv - x1)
}

/// Hinged cylindrical roof, case a (Sze et al. 2004 §3.8a), on an n×n quarter mesh, by
/// arc length or by displacement control of the centre deflection. Load P = 1000 λ (whole
/// roof), deflection w = −u_z at the centre.
pub fn hinged_roof(n: usize, displacement_control: bool) -> Result<PathComparison, String> {
    hinged_roof_with(n, displacement_control, &[])
}

/// [`hinged_roof`] with further text substitutions applied to the scene after the mesh and
/// step ones (e.g. solver settings; the arc-length text then reads
/// `length: {0.5 n/8:e}, max_length: Some({n/8:e})`).
pub fn hinged_roof_with(n: usize, displacement_control: bool, extra: &[(&str, String)]) -> Result<PathComparison, String> {
    let t = Instant::now();
    let mut rep = vec![("n_axial: 8, n_circ: 8", format!("n_axial: {n}, n_circ: {n}"))];
    // The arc-length norm runs over all free translations, so it grows like the square root
    // of the node count: scale the arc lengths with n to keep the same path resolution.
    let f = n as f64 / 8.0;
    if !displacement_control {
        rep.push(("length: 0.5, max_length: Some(1.0)", format!("length: {:e}, max_length: Some({:e})", 0.5 * f, f)));
    }
    if displacement_control {
        rep.push((
            "kind: ArcLength(length: 0.5, max_length: Some(1.0), max_load_factor: 4.0, max_displacement: Some(30.0)),",
            "kind: DisplacementControl(set: \"centre\", dof: Uz, value: -29.4),".to_string(),
        ));
        rep.push(("increments: 300", "increments: 60".to_string()));
    }
    rep.extend(extra.iter().cloned());
    let summary = solve_variant(scenes::HINGED_ROOF, "hinged_roof", &rep)?;
    let table = parse_csv(references::HINGED_ROOF_A);
    let reference: Vec<(f64, f64)> = table.iter().filter(|r| r.len() >= 4).map(|r| (r[3], r[2])).collect();
    let centre = summary.monitors.first().ok_or("no monitor")?;
    let mut path = vec![(0.0, 0.0)];
    for (inc, v) in summary.increments.iter().zip(&centre.values) {
        path.push((-v[0], 1000.0 * inc.load_factor.ok_or("no load factor")?));
    }
    let w_max = reference.iter().map(|p| p.0).fold(0.0, f64::max);
    let p_hi = reference.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
    let p_lo = reference.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    let scale = (w_max, p_hi - p_lo);
    let inside: Vec<(f64, f64)> = path.iter().copied().filter(|p| p.0 <= w_max).collect();
    let e1 = reference.iter().map(|&q| polyline_distance(q, &path, scale)).fold(0.0, f64::max);
    let e2 = inside.iter().map(|&q| polyline_distance(q, &reference, scale)).fold(0.0, f64::max);
    let first_peak = |p: &[(f64, f64)]| -> usize {
        let mut i = 0;
        while i + 1 < p.len() && p[i + 1].1 >= p[i].1 {
            i += 1;
        }
        i
    };
    let ir = first_peak(&reference);
    let ic = first_peak(&path);
    if ic == 0 || ic + 1 >= path.len() {
        return Err(format!("hinged roof: no limit point on the computed path ({} points)", path.len()));
    }
    let limit_load = parabola_peak([path[ic - 1], path[ic], path[ic + 1]]);
    Ok(PathComparison { summary, path, reference: reference.clone(), curve_error: e1.max(e2), limit_load, reference_limit: reference[ir].1, wall_s: t.elapsed().as_secs_f64() })
}

/// Lowest eigenvalue of a bundled `Buckling` scene with substitutions, and the run.
fn lowest_buckling_eigenvalue(template: &str, name: &str, rep: &[(&str, String)]) -> Result<(f64, Summary, f64), String> {
    let t = Instant::now();
    let s = solve_variant(template, name, rep)?;
    let lam = s
        .increments
        .iter()
        .find_map(|i| i.buckling.as_ref())
        .and_then(|b| b.eigenvalues.first().copied())
        .ok_or("no buckling eigenvalue")?;
    Ok((lam, s, t.elapsed().as_secs_f64()))
}

/// Simply supported square plate (a = b = 1, t = 0.01, E = 1e7, ν = 0.3) under unit edge
/// compression on an n×n mesh: the buckling coefficient k = N_cr b² / (π² D), classical 4.
pub fn plate_buckling(n: usize) -> Result<(f64, Summary, f64), String> {
    let (lam, s, w) = lowest_buckling_eigenvalue(scenes::PLATE_BUCKLING, "plate_buckling", &[("nx: 16, ny: 16", format!("nx: {n}, ny: {n}"))])?;
    let d = 1.0e7 * 0.01f64.powi(3) / (12.0 * (1.0 - 0.09));
    Ok((lam / (std::f64::consts::PI.powi(2) * d), s, w))
}

/// Axially compressed cylinder (R = 1, t = 0.01, L = 1, E = 1e7, ν = 0) on a quarter mesh
/// n_axial × n_circ: the lowest critical stress over the classical E t / (R √3).
pub fn cylinder_buckling(n_axial: usize, n_circ: usize) -> Result<(f64, Summary, f64), String> {
    let rep = [("n_axial: 40, n_circ: 60", format!("n_axial: {n_axial}, n_circ: {n_circ}"))];
    let (lam, s, w) = lowest_buckling_eigenvalue(scenes::CYLINDER_BUCKLING, "cylinder_buckling", &rep)?;
    let classical = 1.0e7 * 0.01 * 0.01 / 3f64.sqrt();
    Ok((lam / classical, s, w))
}

/// The square plate of [`plate_buckling`] (16×16) under load control to 1.5 N_cr in 30
/// increments, seeded with its first buckling mode at 1 % of the thickness, or perfect.
pub fn plate_postbuckling(seeded: bool) -> Result<(Summary, f64), String> {
    let t = Instant::now();
    let mut rep = vec![];
    if !seeded {
        rep.push(("imperfection: Some(BucklingModes(scale: {\"compression\": 1.0}, modes: [(mode: 1, amplitude: 1.0e-4)])),", String::new()));
    }
    let s = solve_variant(scenes::PLATE_POSTBUCKLING, "plate_postbuckling", &rep)?;
    Ok((s, t.elapsed().as_secs_f64()))
}

fn record(benchmark: &str, mesh: String, s: &Summary, wall_s: f64, value: f64, reference: f64, rel_error: f64) -> Record {
    Record { benchmark: benchmark.into(), mesh, dofs: s.sizes.dofs, newton_iterations: s.newton_iterations, wall_s, value, reference, rel_error }
}

/// One plot series per distinct `key` of `recs` (in order of first appearance), of the
/// points `point` gives.
pub(crate) fn series_by<T>(recs: &[T], key: impl Fn(&T) -> &str, point: impl Fn(&T) -> Option<(f64, f64)>) -> Vec<Series> {
    let mut names: Vec<&str> = recs.iter().map(&key).collect();
    names.dedup();
    names
        .iter()
        .map(|n| Series { name: n.to_string(), points: recs.iter().filter(|r| key(r) == *n).filter_map(&point).collect(), reference: false })
        .filter(|s| !s.points.is_empty())
        .collect()
}

/// Writes `recs` as JSON to `json` (whole or not at all) and `series` as a log–log SVG
/// beside it, titled (title, x label, y label); returns the SVG's path.
pub(crate) fn write_records<T: Serialize>(json: &Path, recs: &[T], series: &[Series], (title, x, y): (&str, &str, &str)) -> Result<std::path::PathBuf, String> {
    let json_text = serde_json::to_vec_pretty(recs).map_err(|e| e.to_string())?;
    crate::io::atomic::write_atomic(json, &json_text).map_err(|e| format!("{}: {e}", json.display()))?;
    let svg = json.with_extension("svg");
    plot_xy(&svg, title, x, y, series, true, true).map_err(|e| format!("{}: {e}", svg.display()))?;
    Ok(svg)
}

/// Runs every benchmark at three or more meshes, prints the table, writes JSON and an
/// error-versus-time SVG beside it.
pub fn run_all(json: &Path, quick: bool) -> Result<(), String> {
    let mut recs: Vec<Record> = Vec::new();
    fn pick<T>(v: Vec<T>, quick: bool) -> Vec<T> {
        if quick { v.into_iter().take(1).collect() } else { v }
    }
    let print = |r: &Record| {
        println!(
            "{:<34} {:>10} {:>8} {:>6} {:>9.3} {:>13.6e} {:>13.6e} {:>9.2e}",
            r.benchmark, r.mesh, r.dofs, r.newton_iterations, r.wall_s, r.value, r.reference, r.rel_error
        )
    };
    println!("{:<34} {:>10} {:>8} {:>6} {:>9} {:>13} {:>13} {:>9}", "benchmark", "mesh", "dofs", "newton", "wall_s", "value", "reference", "rel_err");
    for n in pick(vec![4, 8, 16, 32], quick) {
        let (v, s, w) = scordelis_lo(n)?;
        recs.push(record("scordelis_lo_roof", format!("{n}x{n}"), &s, w, v, 0.3024, (v - 0.3024).abs() / 0.3024));
        print(recs.last().ok_or("empty")?);
    }
    for n in pick(vec![8, 16, 32, 64], quick) {
        let (v, s, w) = pinched_cylinder(n)?;
        recs.push(record("pinched_cylinder", format!("{n}x{n}"), &s, w, v, 1.8248e-5, (v - 1.8248e-5).abs() / 1.8248e-5));
        print(recs.last().ok_or("empty")?);
    }
    for (t, ip, reference) in [(0.32, true, 5.424e-3), (0.32, false, 1.754e-3), (0.0032, true, 5.256e-3), (0.0032, false, 1.294e-3)] {
        for (nx, ny) in pick(vec![(12, 2), (24, 4), (48, 8)], quick) {
            let (v, s, w) = twisted_beam(nx, ny, t, ip)?;
            let name = format!("twisted_beam_t{t}_{}", if ip { "in_plane" } else { "out_of_plane" });
            recs.push(record(&name, format!("{nx}x{ny}"), &s, w, v, reference, (v - reference).abs() / reference));
            print(recs.last().ok_or("empty")?);
        }
    }
    for (m, label) in [(Material::Svk, "svk"), (Material::NeoHookean, "neo_hookean")] {
        for nx in pick(vec![16, 32, 64], quick) {
            let c = end_moment(nx, 0.1, m, false)?;
            let last = c.points.last().ok_or("no points")?;
            recs.push(record(&format!("end_moment_{label}"), format!("{nx}x1"), &c.summary, c.wall_s, last.computed[0], last.reference[0], c.max_error()));
            print(recs.last().ok_or("empty")?);
        }
        for nx in pick(vec![16, 32, 64], quick) {
            let c = end_shear(nx, 0.1, m, false)?;
            let last = c.points.last().ok_or("no points")?;
            recs.push(record(&format!("end_shear_{label}"), format!("{nx}x1"), &c.summary, c.wall_s, last.computed[1], last.reference[1], c.max_error()));
            print(recs.last().ok_or("empty")?);
        }
        for (nr, nt) in pick(vec![(5, 40), (10, 80), (20, 160)], quick) {
            let c = slit_annulus(nr, nt, m)?;
            let last = c.points.last().ok_or("no points")?;
            recs.push(record(&format!("slit_annulus_{label}"), format!("{nr}x{nt}"), &c.summary, c.wall_s, last.computed[0], last.reference[0], max_component_error(&c.points)));
            print(recs.last().ok_or("empty")?);
        }
    }
    for n in pick(vec![8, 16, 32], quick) {
        for sri in [false, true] {
            let (v, reference, s, w) = clamped_plate(n, 1e-4, sri)?;
            let name = if sri { "clamped_plate_t1e-4_sri" } else { "clamped_plate_t1e-4_mitc4" };
            recs.push(record(name, format!("{n}x{n}"), &s, w, v, reference, (v - reference).abs() / reference));
            print(recs.last().ok_or("empty")?);
        }
    }
    for n in pick(vec![8, 16, 24, 32], quick) {
        let (k, s, w) = plate_buckling(n)?;
        recs.push(record("plate_buckling_k", format!("{n}x{n}"), &s, w, k, 4.0, (k - 4.0).abs() / 4.0));
        print(recs.last().ok_or("empty")?);
    }
    for (na, nc) in pick(vec![(20, 30), (40, 60), (60, 90)], quick) {
        let (r, s, w) = cylinder_buckling(na, nc)?;
        recs.push(record("cylinder_buckling_ratio", format!("{na}x{nc}q"), &s, w, r, 1.0, (r - 1.0).abs()));
        print(recs.last().ok_or("empty")?);
    }
    for dc in [false, true] {
        for n in pick(vec![8, 16], quick) {
            let c = hinged_roof(n, dc)?;
            let name = if dc { "hinged_roof_a_displacement_control" } else { "hinged_roof_a_arc_length" };
            recs.push(record(name, format!("{n}x{n}q"), &c.summary, c.wall_s, c.limit_load, c.reference_limit, c.curve_error));
            print(recs.last().ok_or("empty")?);
        }
    }
    // Membrane locking (`bench::locking`): MITC4 and both MITC4+ on distorted meshes (edges 1:2:…:N).
    {
        use crate::element::ShearTreatment::{Mitc4, Mitc4Plus, Mitc4PlusCentre};
        use crate::mesh::Spacing::Distorted;
        for f in [Mitc4, Mitc4Plus, Mitc4PlusCentre] {
            let tag = locking::formulation_name(f).to_lowercase();
            for n in pick(vec![8, 16, 32], quick) {
                let (v, s, w) = locking::pinched_hemisphere(n, f, Distorted)?;
                let reference = locking::HEMISPHERE_REFERENCE;
                recs.push(record(&format!("pinched_hemisphere_distorted_{tag}"), format!("{n}x{n}"), &s, w, v * reference, reference, (v - 1.0).abs()));
                print(recs.last().ok_or("empty")?);
            }
            for n in pick(vec![8, 16, 32], quick) {
                let (v, s, w) = locking::scordelis_lo(n, f, Distorted)?;
                let reference = locking::SCORDELIS_LO_REFERENCE;
                recs.push(record(&format!("scordelis_lo_distorted_{tag}"), format!("{n}x{n}"), &s, w, v * reference, reference, (v - 1.0).abs()));
                print(recs.last().ok_or("empty")?);
            }
            for n in pick(vec![8, 16, 32], quick) {
                let (v, s, w) = locking::fabric_arch(3e-3, n, f, Distorted)?;
                recs.push(record(&format!("fabric_arch_t_r3e-3_distorted_{tag}"), format!("{n}x{}", (n / 4).max(2)), &s, w, v, 1.0, (v - 1.0).abs()));
                print(recs.last().ok_or("empty")?);
            }
        }
    }
    // Error against time, one series per benchmark.
    let series = series_by(&recs, |r| &r.benchmark, |r| (r.rel_error > 0.0).then_some((r.wall_s.max(1e-4), r.rel_error)));
    let svg = write_records(json, &recs, &series, ("plyshell benchmarks: error against wall time", "wall time (s)", "relative error"))?;
    println!("records in {}, plot in {}", json.display(), svg.display());
    Ok(())
}
