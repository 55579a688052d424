//! `plyshell study SCENE.ron`: the scene's garment solved at increasing fidelity — mesh
//! levels (element size multipliers, or `Auto` tolerances) × ply models (laminate, `Auto`
//! — laminate, then discrete plies where they would slide, `analysis_auto` —, discrete)
//! — and each run's wall time and error against the finest discrete model: drape shape
//! (RMS and largest distance between the deformed garment surfaces / garment size), seam
//! forces, clearance to the bodies, drape coefficient where the scene measures it. Writes a
//! Markdown table, JSON records and an error-against-time SVG, as `plyshell bench` does for
//! the verification benchmarks. A scene of generated parts instead of a garment (the Cusick
//! specimen) is studied over the element size of its sized parts (`SizedAnnulus`,
//! `SizedRectangle`), every node counting for the shape error.

use std::path::{Path, PathBuf};
use std::time::Instant;

use nalgebra::Vector3;
use parry3d_f64::math::Vector as PVec;
use parry3d_f64::query::PointQuery;
use parry3d_f64::shape::TriMesh;
use serde::Serialize;

use crate::analysis::{self, RunOptions};
use crate::garment::{ElementSize, PlyModel};
use crate::io::plot::{plot_xy, Series};
use crate::results::Summary;
use crate::scene::{self, BuiltScene, MeshSpec, Scene};

/// What to vary.
#[derive(Clone, Debug)]
pub struct StudyOptions {
    /// Element size multipliers of the scene's size (an `Auto` size: tolerance × m², the
    /// same size ratio), coarse first; the smallest is the reference mesh.
    pub sizes: Vec<f64>,
    /// Extra `Auto` tolerances to run (rows labelled `auto tol`), with the scene's other
    /// `Auto` parameters (seam factor, tension) or the defaults.
    pub tolerances: Vec<f64>,
    /// Ply models to run (the discrete model is always run at the reference mesh).
    pub ply_models: Vec<PlyModel>,
    /// A-posteriori refinement tolerances (`refine`): per tolerance T and per mesh level
    /// coarser than the reference, a discrete run whose last step is refined once at T
    /// (rows labelled `discrete h×m refined T`).
    pub refine: Vec<f64>,
    /// Output directory (table, JSON, plot; per-run VTU when `vtu`).
    pub out: PathBuf,
    /// Also write each run's VTU/PVD and summary.json into `out/<label>/`.
    pub vtu: bool,
}

/// One run of the study.
#[derive(Clone, Debug, Serialize)]
pub struct StudyRow {
    /// Run label, e.g. `laminate h×2`.
    pub label: String,
    /// Ply model ("laminate" / "discrete").
    pub ply_model: String,
    /// Mesh level: "h×m", "auto tol" or "h×m refined tol" (the element sizes and counts are
    /// then those of the refined mesh).
    pub mesh: String,
    /// Smallest and largest target element size over the panels (m).
    pub element_size: [f64; 2],
    /// Model nodes, elements and free DOFs.
    pub nodes: usize,
    pub elements: usize,
    pub dofs: usize,
    /// Newton iterations.
    pub newton_iterations: usize,
    /// Scene build (meshing) and solve wall time (s).
    pub build_s: f64,
    pub wall_s: f64,
    /// Process CPU time of build and solve (s, all threads).
    pub cpu_s: f64,
    /// "completed" or the failure.
    pub status: String,
    /// Shape error against the reference: RMS and largest closest-point distance between
    /// the deformed garment surfaces (both ways), over the reference garment's size.
    pub shape_rms: f64,
    pub shape_max: f64,
    /// Largest error over the seams of the mean force per length (plies of a seam summed)
    /// against the reference, relative to the load the seam's plies carry in the reference
    /// (the sum of the plies' own mean force magnitudes; for a one-ply seam its force):
    /// where the plies of a seam pull against each other the net force is a small difference
    /// of large ones, and an error relative to it measures nothing. None without seams.
    pub seam_force_error: Option<f64>,
    /// The same error relative to the reference's net (ply-summed) force itself.
    pub seam_force_error_net: Option<f64>,
    /// Mean force per length of each seam (N/m): plies summed, and the plies' magnitudes
    /// added (the load the plies carry).
    pub seam_forces: Vec<SeamForce>,
    /// Smallest and mean clearance of the garment's nodes (faces) to the bodies (m), if any
    /// body; and the difference of the mean from the reference's (m).
    pub clearance_min: Option<f64>,
    pub clearance_mean: Option<f64>,
    pub clearance_error: Option<f64>,
    /// Drape coefficient (%) and its difference from the reference (points), where measured.
    pub drape_coefficient: Option<f64>,
    pub drape_error: Option<f64>,
    /// `ply_model: Auto` runs: the model chosen per panel with its slip and peel ratios, and
    /// the solves run (1: the laminate was kept; 2: laminate, then the resolved model).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub auto: Option<serde_json::Value>,
}

/// The garment's deformed surface of one run: node positions and garment triangles.
struct Surface {
    points: Vec<Vector3<f64>>,
    /// Garment nodes (indices into `points`).
    nodes: Vec<usize>,
    mesh: Option<TriMesh>,
}

impl Surface {
    fn new(built: &BuiltScene, positions: &[[f64; 3]]) -> Self {
        let points: Vec<Vector3<f64>> = positions.iter().map(|p| Vector3::new(p[0], p[1], p[2])).collect();
        // The garment's nodes; every node of a scene of generated parts (no garment).
        let garment = |n: usize| built.garment.as_ref().is_none_or(|l| l.pattern_uv.get(n).copied().flatten().is_some());
        let nodes: Vec<usize> = (0..points.len()).filter(|&n| garment(n)).collect();
        let tris: Vec<[u32; 3]> = built
            .model
            .elements
            .iter()
            .filter(|e| e.nodes.iter().all(|&n| garment(n)))
            .flat_map(|e| {
                let q = e.nodes.map(|n| n as u32);
                [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
            })
            .collect();
        let vertices = points.iter().map(|p| PVec::new(p.x, p.y, p.z)).collect();
        let mesh = TriMesh::new(vertices, tris).ok();
        Self { points, nodes, mesh }
    }

    /// Distances of this surface's garment nodes to `other`'s surface.
    fn distances_to(&self, other: &Surface) -> Vec<f64> {
        use rayon::prelude::*;
        let Some(m) = &other.mesh else { return vec![f64::INFINITY; self.nodes.len()] };
        self.nodes
            .par_iter()
            .map(|&n| {
                let p = self.points[n];
                let q = m.project_local_point(PVec::new(p.x, p.y, p.z), false).point;
                (Vector3::new(q.x, q.y, q.z) - p).norm()
            })
            .collect()
    }

    /// Diagonal of the garment nodes' bounding box.
    fn size(&self) -> f64 {
        let (mut lo, mut hi) = (Vector3::repeat(f64::INFINITY), Vector3::repeat(f64::NEG_INFINITY));
        for &n in &self.nodes {
            lo = lo.inf(&self.points[n]);
            hi = hi.sup(&self.points[n]);
        }
        (hi - lo).norm()
    }
}

/// Shape error of `run` against `reference`: (RMS, max) of the closest-point distances of
/// both surfaces' garment nodes to the other surface, over the reference's size.
fn shape_error(run: &Surface, reference: &Surface) -> (f64, f64) {
    let mut d = run.distances_to(reference);
    d.extend(reference.distances_to(run));
    let size = reference.size().max(1e-300);
    let rms = (d.iter().map(|x| x * x).sum::<f64>() / d.len().max(1) as f64).sqrt();
    let max = d.iter().copied().fold(0.0, f64::max);
    (rms / size, max / size)
}

/// Mean force per length of each seam: a multi-ply seam (`seam/ply`) with its plies' forces
/// summed as vectors node by node (`seams_plies_summed` of the summary,
/// [`crate::garment::compliant::ply_summed`]: a ply pushed into compression at the seam counts
/// against one in tension), else — plies whose seam rows differ — the plies' mean magnitudes
/// added.
fn seam_forces(summary: &Summary) -> Vec<SeamForce> {
    let mut out: Vec<SeamForce> = Vec::new();
    let Some(list) = summary.extra.get("seams").and_then(|v| v.as_array()) else { return out };
    let summed = |base: &str| {
        summary.extra.get("seams_plies_summed").and_then(|v| v.as_array()).and_then(|a| a.iter().find(|s| s.get("name").and_then(|n| n.as_str()) == Some(base))).and_then(|s| s.get("force_per_length_mean").and_then(|v| v.as_f64()))
    };
    for s in list {
        let (Some(name), Some(f)) = (s.get("name").and_then(|v| v.as_str()), s.get("force_per_length_mean").and_then(|v| v.as_f64())) else { continue };
        let base = name.split('/').next().unwrap_or(name).to_string();
        let net = summed(&base);
        match out.iter_mut().find(|e| e.name == base) {
            Some(e) => {
                e.ply_load += f;
                if net.is_none() {
                    e.net += f;
                }
            }
            None => out.push(SeamForce { net: net.unwrap_or(f), ply_load: f, name: base }),
        }
    }
    out
}

/// One seam's mean force per length in a study run (N/m).
#[derive(Clone, Debug, Serialize)]
pub struct SeamForce {
    /// Seam name (without the `/ply` suffix of a multi-ply seam).
    pub name: String,
    /// Plies summed as vectors node by node (a one-ply seam: its force).
    pub net: f64,
    /// The plies' mean force magnitudes added: the load the plies carry through the seam.
    pub ply_load: f64,
}

/// Smallest and mean clearance of the garment's nodes to the scene's bodies: signed distance
/// minus half the largest thickness of the node's elements.
fn clearance(built: &BuiltScene, surface: &Surface) -> Option<(f64, f64)> {
    let c = built.contact.as_ref()?;
    if c.bodies.is_empty() || surface.nodes.is_empty() {
        return None;
    }
    let model = &built.model;
    let mut half = vec![0.0f64; model.n_nodes()];
    for e in &model.elements {
        let h = model.sections.get(e.section).map_or(0.0, |s| s.thickness);
        for &n in &e.nodes {
            half[n] = half[n].max(0.5 * h);
        }
    }
    let offset: Vec<f64> = surface.nodes.iter().map(|&n| half[n]).collect();
    let mut out = vec![f64::NAN; model.n_nodes()];
    crate::contact::body::clearances(&c.bodies, &surface.nodes, &offset, |n| surface.points[n], &mut out);
    let vals: Vec<f64> = surface.nodes.iter().map(|&n| out[n]).filter(|v| v.is_finite()).collect();
    if vals.is_empty() {
        return None;
    }
    Some((vals.iter().copied().fold(f64::INFINITY, f64::min), vals.iter().sum::<f64>() / vals.len() as f64))
}

/// A scene variant: the garment's element size scaled by `m` (or the `Auto` tolerance
/// `tol`), its ply model set (panel overrides cleared); without a garment, the element size
/// of every sized part (`SizedAnnulus`, `SizedRectangle`) the same way.
fn variant(scene: &Scene, m: Option<f64>, tol: Option<f64>, ply: PlyModel, refine: Option<f64>) -> Result<Scene, String> {
    let mut s = scene.clone();
    if let (Some(tolerance), Some(last)) = (refine, s.steps.last_mut()) {
        last.refine = Some(crate::scene::sequence::RefineSpec { tolerance, passes: 1, relax_directors: false, relax_membrane: true });
    }
    let scale = |e: &ElementSize| -> ElementSize {
        match (e, m, tol) {
            (_, _, Some(t)) => ElementSize::Auto(match e {
                ElementSize::Auto(a) => crate::garment::AutoSize { tolerance: t, ..a.clone() },
                ElementSize::Fixed(_) => crate::garment::AutoSize { tolerance: t, tension: None, seam_factor: 0.5 },
            }),
            (ElementSize::Fixed(h), Some(m), None) => ElementSize::Fixed(h * m),
            (ElementSize::Auto(a), Some(m), None) => ElementSize::Auto(crate::garment::AutoSize { tolerance: a.tolerance * m * m, ..a.clone() }),
            (e, None, None) => e.clone(),
        }
    };
    let Some(g) = s.garment.as_mut() else {
        for p in &mut s.parts {
            if let MeshSpec::SizedAnnulus { element_size, .. } | MeshSpec::SizedRectangle { element_size, .. } = &mut p.mesh {
                *element_size = scale(element_size);
            }
        }
        return Ok(s);
    };
    g.element_size = scale(&g.element_size);
    for p in &mut g.panels {
        p.element_size = if tol.is_some() { None } else { p.element_size.as_ref().map(scale) };
        p.ply_model = None;
    }
    g.ply_model = ply;
    Ok(s)
}

fn ply_name(p: PlyModel) -> &'static str {
    match p {
        PlyModel::Discrete => "discrete",
        PlyModel::Laminate => "laminate",
        PlyModel::Auto => "auto",
    }
}

/// One solved variant: its row (errors not yet filled) and deformed surface.
struct Run {
    row: StudyRow,
    surface: Surface,
}

#[allow(clippy::too_many_arguments)]
fn solve(file: &str, text: &str, scene: &Scene, label: &str, mesh: String, ply: PlyModel, out: Option<PathBuf>, log: &mut dyn FnMut(&str)) -> Result<Run, String> {
    let (c0, t0) = (crate::cpu_time::process_seconds(), Instant::now());
    if ply == PlyModel::Auto {
        return solve_auto(file, text, scene, label, mesh, out, log);
    }
    let built = scene::build(scene, file, text).map_err(|e| format!("{label}: {e}"))?;
    let build_s = t0.elapsed().as_secs_f64();
    log(&format!("{label}: {} nodes, {} elements, solving…", built.model.n_nodes(), built.model.elements.len()));
    let t1 = Instant::now();
    let refined = crate::refine::requested(scene).is_some();
    let (summary, status, last) = match crate::refine::run_refined(scene, &built, &RunOptions { out_dir: out }, &mut |_| {}) {
        Ok((s, last)) => (s, "completed".to_string(), last),
        // A failed refinement pass's state lives on a mesh not returned: no row to measure.
        Err(analysis::RunError::Solve { error, .. }) if refined => return Err(format!("{label}: {error}")),
        Err(analysis::RunError::Solve { error, summary }) => (*summary, format!("failed: {error}"), None),
        Err(e) => return Err(format!("{label}: {e}")),
    };
    let timing = Timing { build_s, wall_s: t1.elapsed().as_secs_f64(), cpu_s: crate::cpu_time::process_seconds() - c0 };
    let mut run = measured_run(label, ply, mesh, last.as_ref().map_or(&built, |l| &l.1), &summary, status, timing);
    if let Some(passes) = summary.extra.get("refinement").and_then(|r| r.get("passes")).and_then(|p| p.as_array()) {
        // Every pass's iterations: the first solve's and each continuation's.
        run.row.newton_iterations = passes.iter().filter_map(|p| p.get("newton_iterations").and_then(|v| v.as_u64())).sum::<u64>() as usize;
    }
    log(&format!("{label}: {} DOFs, {} Newton iterations, {:.1} s wall, {:.1} s CPU, {}", run.row.dofs, run.row.newton_iterations, timing.wall_s, timing.cpu_s, run.row.status));
    Ok(run)
}

/// Build, wall and CPU seconds of one variant.
#[derive(Clone, Copy)]
struct Timing {
    build_s: f64,
    wall_s: f64,
    cpu_s: f64,
}

/// The row of a solved variant (errors against the reference not yet filled; an `Auto`
/// run's choices from its summary) and its deformed surface.
fn measured_run(label: &str, ply: PlyModel, mesh: String, built: &BuiltScene, summary: &Summary, status: String, timing: Timing) -> Run {
    let extent = |sizes: &mut dyn Iterator<Item = f64>| sizes.filter(|&h| h > 0.0).fold([f64::INFINITY, 0.0], |a, h| [a[0].min(h), a[1].max(h)]);
    // Target sizes of the garment's panels; the square root of the element areas of parts.
    let element_size = match &built.garment {
        Some(l) => extent(&mut l.part_element_size.iter().flatten().copied()),
        None => extent(&mut (0..built.model.elements.len()).map(|e| built.model.element(e).reference_area().sqrt())),
    };
    let surface = Surface::new(built, &summary.final_positions);
    let clear = clearance(built, &surface);
    let drape = summary.extra.get("drape").and_then(|d| d.get("drape_coefficient_percent")).and_then(|v| v.as_f64());
    let row = StudyRow {
        label: label.to_string(),
        ply_model: ply_name(ply).into(),
        mesh,
        element_size,
        nodes: summary.sizes.nodes,
        elements: summary.sizes.elements,
        dofs: summary.sizes.dofs,
        newton_iterations: summary.newton_iterations,
        build_s: timing.build_s,
        wall_s: timing.wall_s,
        cpu_s: timing.cpu_s,
        status,
        shape_rms: 0.0,
        shape_max: 0.0,
        seam_force_error: None,
        seam_force_error_net: None,
        seam_forces: seam_forces(summary),
        clearance_min: clear.map(|c| c.0),
        clearance_mean: clear.map(|c| c.1),
        clearance_error: None,
        drape_coefficient: drape,
        drape_error: None,
        auto: summary.extra.get("ply_model_auto").cloned(),
    };
    Run { row, surface }
}

/// An `Auto` run (`analysis_auto`: laminate, then discrete plies where they would slide):
/// build and solve times of both passes together.
fn solve_auto(file: &str, text: &str, scene: &Scene, label: &str, mesh: String, out: Option<PathBuf>, log: &mut dyn FnMut(&str)) -> Result<Run, String> {
    let (c0, t0) = (crate::cpu_time::process_seconds(), Instant::now());
    log(&format!("{label}: ply_model Auto, solving (laminate first)…"));
    let (run, status) = match crate::analysis_auto::run(scene, file, text, &RunOptions { out_dir: out }, &mut |_| {}) {
        Ok(r) => (r, "completed".to_string()),
        Err(e) => return Err(format!("{label}: {e}")),
    };
    let timing = Timing { build_s: 0.0, wall_s: t0.elapsed().as_secs_f64(), cpu_s: crate::cpu_time::process_seconds() - c0 };
    for line in crate::analysis_auto::describe(&run) {
        log(&format!("{label}: {line}"));
    }
    let out = measured_run(label, PlyModel::Auto, mesh, &run.built, &run.summary, status, timing);
    log(&format!("{label}: {} DOFs, {} Newton iterations, {:.1} s wall, {:.1} s CPU, {} ({} pass(es))", out.row.dofs, out.row.newton_iterations, timing.wall_s, timing.cpu_s, out.row.status, run.passes));
    Ok(out)
}

/// Fills each row's errors against the reference run.
fn compare(runs: &mut [Run], reference: usize) {
    let (rs, rf, rc, rd) = {
        let r = &runs[reference];
        (Surface { points: r.surface.points.clone(), nodes: r.surface.nodes.clone(), mesh: r.surface.mesh.clone() }, r.row.seam_forces.clone(), r.row.clearance_mean, r.row.drape_coefficient)
    };
    for (i, run) in runs.iter_mut().enumerate() {
        let (rms, max) = if i == reference { (0.0, 0.0) } else { shape_error(&run.surface, &rs) };
        run.row.shape_rms = rms;
        run.row.shape_max = max;
        let largest = |scale: &dyn Fn(&SeamForce) -> f64| {
            (!rf.is_empty()).then(|| {
                rf.iter()
                    .map(|r| {
                        let f = run.row.seam_forces.iter().find(|e| e.name == r.name).map_or(0.0, |e| e.net);
                        (f - r.net).abs() / scale(r).abs().max(1e-300)
                    })
                    .fold(0.0, f64::max)
            })
        };
        run.row.seam_force_error = largest(&|r| r.ply_load);
        run.row.seam_force_error_net = largest(&|r| r.net);
        run.row.clearance_error = run.row.clearance_mean.zip(rc).map(|(a, b)| a - b);
        run.row.drape_error = run.row.drape_coefficient.zip(rd).map(|(a, b)| a - b);
    }
}

/// Runs the study of the scene file `path` and writes `study.md`, `study.json` and
/// `study.svg` into `options.out`; returns the rows (reference last).
pub fn run_study(path: &Path, options: &StudyOptions, log: &mut dyn FnMut(&str)) -> Result<Vec<StudyRow>, String> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| format!("{file}: cannot read the scene file: {e}"))?;
    let text = scene::decode(&file, bytes).map_err(|e| e.to_string())?;
    let text = scene::strip_bom(&text).to_string();
    let base = scene::parse(&file, &text).map_err(|e| e.to_string())?;
    // A garment, or generated parts whose size the study can vary (a single shell each: no
    // ply models).
    let sized = |p: &crate::scene::PartSpec| matches!(p.mesh, MeshSpec::SizedAnnulus { .. } | MeshSpec::SizedRectangle { .. });
    let multi_ply = match &base.garment {
        Some(g) => g.panels.iter().any(|p| p.plies.len() > 1),
        None if base.parts.iter().any(sized) => false,
        None => return Err(format!("{file}: the scene has no garment and no sized part (SizedAnnulus, SizedRectangle) to study")),
    };
    let parts_only = base.garment.is_none();
    let mut sizes = options.sizes.clone();
    if sizes.is_empty() || sizes.iter().any(|m| !(m.is_finite() && *m > 0.0)) {
        return Err(format!("study: expected positive size multipliers, found {sizes:?}"));
    }
    if let Some(t) = options.tolerances.iter().find(|t| !(t.is_finite() && **t > 0.0 && **t < 0.5)) {
        return Err(format!("study: expected Auto tolerances between 0 and 0.5, found {t}"));
    }
    sizes.sort_by(|a, b| b.total_cmp(a));
    sizes.dedup();
    let finest = sizes[sizes.len() - 1];
    let plies: Vec<PlyModel> = if multi_ply { options.ply_models.clone() } else { vec![PlyModel::Discrete] };
    std::fs::create_dir_all(&options.out).map_err(|e| format!("{}: {e}", options.out.display()))?;
    // Run labels: ply model and mesh level ("discrete h×2"); the mesh level alone for parts.
    let label = |p: PlyModel, mesh: &str| if parts_only { mesh.to_string() } else { format!("{} {mesh}", ply_name(p)) };
    if let Some(t) = options.refine.iter().find(|t| !(t.is_finite() && **t > 0.0 && **t < 0.5)) {
        return Err(format!("study: expected refinement tolerances between 0 and 0.5, found {t}"));
    }
    // (label, mesh level, size multiplier, Auto tolerance, ply model, refinement tolerance)
    let mut plan: Vec<(String, String, Option<f64>, Option<f64>, PlyModel, Option<f64>)> = Vec::new();
    for &m in &sizes {
        for &p in &plies {
            if m == finest && p == PlyModel::Discrete {
                continue;
            }
            plan.push((label(p, &format!("h×{m}")), format!("h×{m}"), Some(m), None, p, None));
        }
    }
    for &t in &options.tolerances {
        for &p in &plies {
            plan.push((label(p, &format!("auto {t}")), format!("auto {t}"), None, Some(t), p, None));
        }
    }
    for &t in &options.refine {
        for &m in sizes.iter().filter(|&&m| m != finest) {
            let mesh = format!("h×{m} refined {t}");
            plan.push((label(PlyModel::Discrete, &mesh), mesh, Some(m), None, PlyModel::Discrete, Some(t)));
        }
    }
    plan.push((format!("{} (reference)", label(PlyModel::Discrete, &format!("h×{finest}"))), format!("h×{finest}"), Some(finest), None, PlyModel::Discrete, None));
    // A variant that cannot be built (e.g. a stitch line passing no node of a coarse mesh)
    // is a failed row; the reference must build.
    let n_plan = plan.len();
    let mut runs = Vec::new();
    let mut failed: Vec<(usize, StudyRow)> = Vec::new();
    for (i, (label, mesh, m, tol, ply, refine)) in plan.into_iter().enumerate() {
        let sc = variant(&base, m, tol, ply, refine)?;
        let dir = options.vtu.then(|| options.out.join(label.replace([' ', '×', '(', ')'], "_").replace("__", "_").trim_matches('_').to_string()));
        match solve(&file, &text, &sc, &label, mesh.clone(), ply, dir, log) {
            Ok(r) => runs.push((i, r)),
            Err(e) if i + 1 < n_plan => {
                log(&e);
                failed.push((i, failed_row(label, mesh, ply, e)));
            }
            Err(e) => return Err(e),
        }
    }
    let mut solved: Vec<Run> = Vec::with_capacity(runs.len());
    let mut order: Vec<usize> = Vec::with_capacity(n_plan);
    for (i, r) in runs {
        order.push(i);
        solved.push(r);
    }
    let reference = solved.len() - 1;
    compare(&mut solved, reference);
    let mut rows: Vec<(usize, StudyRow)> = order.into_iter().zip(solved.into_iter().map(|r| r.row)).collect();
    rows.extend(failed);
    rows.sort_by_key(|r| r.0);
    let rows: Vec<StudyRow> = rows.into_iter().map(|r| r.1).collect();
    write_reports(&options.out, &file, &rows)?;
    Ok(rows)
}

/// The row of a variant that could not be built: its error, no sizes, NaN errors.
fn failed_row(label: String, mesh: String, ply: PlyModel, error: String) -> StudyRow {
    StudyRow {
        label,
        ply_model: ply_name(ply).into(),
        mesh,
        element_size: [f64::NAN; 2],
        nodes: 0,
        elements: 0,
        dofs: 0,
        newton_iterations: 0,
        build_s: 0.0,
        wall_s: 0.0,
        cpu_s: 0.0,
        status: format!("failed: {error}"),
        shape_rms: f64::NAN,
        shape_max: f64::NAN,
        seam_force_error: None,
        seam_force_error_net: None,
        seam_forces: Vec::new(),
        clearance_min: None,
        clearance_mean: None,
        clearance_error: None,
        drape_coefficient: None,
        drape_error: None,
        auto: None,
    }
}

/// Percent with 2 decimals, or "–".
fn pct(v: Option<f64>) -> String {
    v.map_or("–".into(), |x| format!("{:.2}", 100.0 * x))
}

/// The Markdown table of a study.
pub fn markdown(scene: &str, rows: &[StudyRow]) -> String {
    let mut t = format!(
        "# Study of `{scene}`\n\nErrors against the last row (finest mesh, discrete plies). Shape: closest-point distance between the deformed garment surfaces (both ways), RMS and max, in % of the reference garment's size; seam force: largest error of a seam's mean force per length (plies summed), relative to the load its plies carry (their mean force magnitudes added; a one-ply seam: its force), and in brackets relative to the net force itself, which is a small difference of large ones where plies pull against each other; clearance: mean clearance of the garment faces to the bodies, difference from the reference (mm); DC: drape coefficient (%), difference in points. Times: wall and process CPU (all threads) of the solve, on a shared machine.\n\n"
    );
    t.push_str("| run | h (mm) | nodes | DOFs | Newton | wall s | CPU s | shape RMS % | shape max % | seam force err % | clearance mm (Δ) | DC % (Δ) | status |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for r in rows {
        let h = if (r.element_size[1] - r.element_size[0]).abs() <= 1e-9 * r.element_size[1] { format!("{:.1}", 1e3 * r.element_size[0]) } else { format!("{:.1}–{:.1}", 1e3 * r.element_size[0], 1e3 * r.element_size[1]) };
        let clear = r.clearance_mean.map_or("–".into(), |c| format!("{:.1} ({:+.1})", 1e3 * c, 1e3 * r.clearance_error.unwrap_or(0.0)));
        let dc = r.drape_coefficient.map_or("–".into(), |c| format!("{c:.1} ({:+.1})", r.drape_error.unwrap_or(0.0)));
        let seam = match r.seam_force_error_net {
            Some(_) => format!("{} ({})", pct(r.seam_force_error), pct(r.seam_force_error_net)),
            None => pct(r.seam_force_error),
        };
        t.push_str(&format!(
            "| {} | {h} | {} | {} | {} | {:.1} | {:.1} | {:.3} | {:.3} | {} | {clear} | {dc} | {} |\n",
            r.label, r.nodes, r.dofs, r.newton_iterations, r.wall_s, r.cpu_s, 100.0 * r.shape_rms, 100.0 * r.shape_max, seam, r.status
        ));
    }
    let autos: Vec<&StudyRow> = rows.iter().filter(|r| r.auto.is_some()).collect();
    if !autos.is_empty() {
        t.push_str("\n`ply_model: Auto` (slip and peel ratios of the laminated first pass against their limits; `garment::ply_auto`):\n\n");
        for r in autos {
            let Some(a) = &r.auto else { continue };
            let passes = a.get("passes").and_then(|v| v.as_u64()).unwrap_or(0);
            let panels: Vec<String> = a.get("panels").and_then(|v| v.as_array()).map_or(Vec::new(), |ps| {
                ps.iter()
                    .map(|p| {
                        let f = |k: &str| p.get(k).and_then(|v| v.as_f64()).map_or("–".into(), |x| format!("{x:.3}"));
                        format!("{} → {} (slip {}, peel {})", p.get("panel").and_then(|v| v.as_str()).unwrap_or("?"), p.get("model").and_then(|v| v.as_str()).unwrap_or("?"), f("slip_ratio"), f("peel_ratio"))
                    })
                    .collect()
            });
            t.push_str(&format!("- {}: {} solve(s); {}\n", r.label, passes, panels.join("; ")));
        }
    }
    t
}

/// Writes `study.md`, `study.json` and `study.svg` (shape RMS error against wall time, one
/// series per ply model; the reference's zero error is left out of the log plot).
fn write_reports(dir: &Path, scene: &str, rows: &[StudyRow]) -> Result<(), String> {
    let md = markdown(scene, rows);
    crate::io::atomic::write_atomic(&dir.join("study.md"), md.as_bytes()).map_err(|e| format!("study.md: {e}"))?;
    let json = serde_json::to_vec_pretty(&serde_json::json!({ "scene": scene, "runs": rows })).map_err(|e| e.to_string())?;
    crate::io::atomic::write_atomic(&dir.join("study.json"), &json).map_err(|e| format!("study.json: {e}"))?;
    let mut series: Vec<Series> = Vec::new();
    // Series by label prefix; refined runs (`… refined T`) in a series of their own.
    for (name, pick, refined) in [("uniform refinement", "h×", false), ("Auto size", "auto 0.", false), ("laminate", "laminate h", false), ("Auto plies", "auto h", false), ("discrete", "discrete h", false), ("laminate, Auto size", "laminate auto", false), ("Auto plies, Auto size", "auto auto", false), ("discrete, Auto size", "discrete auto", false), ("discrete, refined", "discrete h", true), ("refined", "h×", true)] {
        let points: Vec<(f64, f64)> = rows.iter().filter(|r| r.label.starts_with(pick) && r.mesh.contains("refined") == refined && r.shape_rms > 0.0 && r.wall_s > 0.0).map(|r| (r.wall_s, 100.0 * r.shape_rms)).collect();
        if !points.is_empty() {
            series.push(Series { name: name.into(), points, reference: false });
        }
    }
    if !series.is_empty() {
        plot_xy(&dir.join("study.svg"), &format!("study: {scene}"), "wall time (s)", "shape RMS error (% of garment size)", &series, true, true).map_err(|e| format!("study.svg: {e}"))?;
    }
    // Where the scene measures a drape coefficient: its error (points) against wall time too.
    let drape: Vec<(f64, f64)> = rows.iter().filter_map(|r| r.drape_error.filter(|e| *e != 0.0 && r.wall_s > 0.0).map(|e| (r.wall_s, e.abs()))).collect();
    if !drape.is_empty() {
        let series = [Series { name: "runs".into(), points: drape, reference: false }];
        plot_xy(&dir.join("study_drape.svg"), &format!("study: {scene}"), "wall time (s)", "drape coefficient error (points)", &series, true, true).map_err(|e| format!("study_drape.svg: {e}"))?;
    }
    Ok(())
}
