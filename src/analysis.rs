//! One analysis run: scene → model → solver → results → export.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::io::export::{write_state_vtu, ExportOptions};
use crate::io::{plot, pvd};
use crate::model::{Model, State};
use crate::results::{peak_memory_mib, MonitorHistory, Sizes, Summary};
use crate::scene::{BuiltScene, Scene};
use crate::solver::{Progress, SolveError, Solver};

/// Why a run stopped early.
#[derive(Debug)]
pub enum RunError {
    /// The solver could not be set up (e.g. a singular pattern).
    Setup(String),
    /// The solve diverged; the last converged state was exported.
    Solve { error: SolveError, summary: Box<Summary> },
    /// An output file could not be written.
    Io(String),
}

impl std::fmt::Display for RunError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RunError::Setup(s) => write!(f, "cannot set up the solve: {s}"),
            RunError::Solve { error, .. } => write!(f, "{error}; the last converged state was exported"),
            RunError::Io(s) => write!(f, "cannot write results: {s}"),
        }
    }
}

impl std::error::Error for RunError {}

/// Where and how to write results.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Output directory; None runs without writing files.
    pub out_dir: Option<PathBuf>,
}

/// Attaches the scene's nodal-force terms to `solver` for `model` (the built model, or a
/// seeded copy of it): contact with the rigid bodies, the garment's surface contact
/// (inter-ply and self contact) and its compliant seams — the same terms for every solve of
/// the scene's equations (the analysis, and the relaxation and residual of a mapped state in
/// mesh sequencing and refinement).
pub fn attach_terms<'m>(solver: &mut Solver<'m>, model: &'m crate::model::Model, built: &BuiltScene) -> Result<(), String> {
    if let Some(c) = &built.contact {
        crate::contact::attach(solver, model, c)?;
    }
    if let Some(s) = &built.interply {
        crate::contact::interply::attach(solver, model, s)?;
    }
    if let Some(c) = crate::garment::compliant::CompliantSeams::new(&built.seams) {
        solver.add_nodal_forces(Box::new(c));
    }
    Ok(())
}

/// Solves `built` (from `scene`), reporting progress, and writes VTU/PVD, summary.json and
/// the monitor plot into the output directory. A first step with `coarse_levels` is solved
/// by mesh sequencing (`analysis_sequence`), a last step with `refine` by a-posteriori
/// refinement passes (`refine`).
pub fn run(scene: &Scene, built: &BuiltScene, options: &RunOptions, progress: &mut dyn FnMut(&Progress)) -> Result<Summary, RunError> {
    if crate::refine::requested(scene).is_some() {
        return crate::refine::run(scene, built, options, progress);
    }
    run_unrefined(scene, built, options, progress)
}

/// [`run`] without the refinement passes (mesh sequencing still applies).
pub fn run_unrefined(scene: &Scene, built: &BuiltScene, options: &RunOptions, progress: &mut dyn FnMut(&Progress)) -> Result<Summary, RunError> {
    if crate::scene::sequence::coarse_levels(scene) > 0 {
        return crate::analysis_sequence::run(scene, built, options, progress);
    }
    run_from(scene, built, options, None, progress)
}

/// A start other than the reference state: the state (at rest) and a report of how it was
/// reached, kept in `summary.json` under `sequence`.
pub struct Start {
    /// The initial state.
    pub state: State,
    /// What produced it (mesh sequencing's levels).
    pub report: serde_json::Value,
}

/// [`run`] without mesh sequencing, from `start` (the reference state when None).
pub fn run_from(scene: &Scene, built: &BuiltScene, options: &RunOptions, start: Option<Start>, progress: &mut dyn FnMut(&Progress)) -> Result<Summary, RunError> {
    if crate::analysis_auto::is_auto(scene) {
        return Err(RunError::Setup("the garment has ply_model Auto, which is solved in two passes (laminate, then discrete plies where they would slide): run it with analysis_auto::run (as plyshell solve and study do)".into()));
    }
    let t0 = Instant::now();
    let seeded = match &built.imperfection {
        Some(imp) => Some(crate::solver::imperfection::seeded(&built.model, imp, &scene.solver).map_err(RunError::Setup)?),
        None => None,
    };
    let model = seeded.as_ref().map_or(&built.model, |s| &s.0);
    let mut solver = Solver::new(model, scene.solver.clone()).map_err(|e| {
        RunError::Setup(format!("{e}; the model has {} nodes, {} elements and {} free DOFs (set by the parts' mesh counts and the garment's element_size)", model.n_nodes(), model.elements.len(), model.dofs.n_free))
    })?;
    attach_terms(&mut solver, model, built).map_err(RunError::Setup)?;
    let (dofs, tangent_nnz, factor_nnz) = solver.sizes();
    let mut summary = Summary {
        scene: scene.name.clone(),
        sizes: Sizes { nodes: model.n_nodes(), elements: model.elements.len(), dofs, tangent_nnz, factor_nnz },
        loads: model.loads.iter().map(|l| l.name.clone()).collect(),
        monitors: built.monitors.iter().map(|m| MonitorHistory::new(m, model)).collect(),
        imperfection_buckling: seeded.as_ref().and_then(|s| s.1.clone()),
        ..Default::default()
    };
    if let Some(dir) = &options.out_dir {
        if dir.exists() && !dir.is_dir() {
            return Err(RunError::Io(format!("{}: exists and is not a directory (the output directory must be a directory)", dir.display())));
        }
        std::fs::create_dir_all(dir).map_err(|e| RunError::Io(format!("cannot create the output directory {}: {e}", dir.display())))?;
    }
    let export = ExportOptions { binary: scene.output.binary, ..Default::default() };
    let mut pvd_entries: Vec<(f64, String)> = Vec::new();
    let mut garment_entries: Vec<(f64, String)> = Vec::new();
    let garment_export = !built.seams.is_empty() || built.garment.is_some();
    // The garment's textured surface (OBJ, glTF): its vertices' model nodes, and their
    // positions at every exported state (the glTF pose series).
    let surface_nodes: Option<Vec<usize>> = built.garment.as_ref().map(|l| crate::garment::export::garment_surface(model, l, |_| [0.0; 3]).1);
    let mut poses: Vec<(f64, Vec<[f64; 3]>)> = Vec::new();
    let mut poses_dropped = 0usize;
    let mut export_s = 0.0;
    let mut io_error: Option<String> = None;
    let mut mode_files: Vec<String> = Vec::new();
    let mut state = model.initial_state();
    if let Some(start) = start {
        if start.state.u.len() != model.n_nodes() || start.state.frames.len() != model.n_nodes() {
            return Err(RunError::Setup(format!("the start state has {} nodes, the model {}", start.state.u.len(), model.n_nodes())));
        }
        state = start.state;
        solver.start_nodal_forces_from(&state);
        summary.extra.insert("sequence".into(), start.report);
    }
    let steps = &built.steps;
    let every = scene.output.every.max(1);
    // Series time (PVD, glTF poses): a step's pseudo-time (step index + fraction) except
    // that a `Dynamic` step spans its simulated seconds; `shift` carries the seconds of the
    // Dynamic steps before, so times stay increasing across steps.
    let mut shift = 0.0;
    let mut series_time = move |step: usize, pseudo: f64, dynamics: Option<(f64, bool)>| match dynamics {
        Some((seconds, end_of_step)) => {
            let t = step as f64 + shift + seconds;
            if end_of_step {
                shift += seconds - 1.0;
            }
            t
        }
        None => pseudo + shift,
    };
    let mut last_series_time = 0.0;
    // Movement protocol: the measures of each pose at the end of its step.
    let pose_of_step = |step: usize| built.protocol.as_ref().and_then(|p| p.poses.iter().position(|q| q.step == step));
    let mut poses_out: Vec<serde_json::Value> = Vec::new();
    let mut step_clock = (usize::MAX, Instant::now(), 0usize, 0usize);
    let result = solver.run(
        steps,
        &mut state,
        &mut |report, st, solved| {
            for (h, m) in summary.monitors.iter_mut().zip(&built.monitors) {
                h.record(m, model, st);
            }
            summary.newton_iterations += report.iterations;
            let last_of_step = report.increment == steps[report.step].increments || report.dynamics.as_ref().is_some_and(|d| d.end_of_step);
            let time = series_time(report.step, report.time, report.dynamics.as_ref().map(|d| (d.time, d.end_of_step)));
            last_series_time = time;
            if let (Some(dir), true) = (&options.out_dir, scene.output.vtu && (report.increment % every == 0 || last_of_step)) {
                let t = Instant::now();
                let name = format!("{}_{:04}.vtu", scene.name, pvd_entries.len() + 1);
                let mut export = export.clone();
                export.extra_point_data = solved.nodal_forces().iter().flat_map(|c| c.point_data(model, st)).collect();
                match write_state_vtu(&dir.join(&name), model, st, &export) {
                    Ok(()) => pvd_entries.push((time, name)),
                    Err(e) => io_error = io_error.take().or(Some(e.to_string())),
                }
                if garment_export {
                    let gname = format!("{}_garment_{:04}.vtu", scene.name, garment_entries.len() + 1);
                    let mut f_ext = vec![0.0; solved.internal_force().len()];
                    model.external_force(st, &report.scales, &mut f_ext);
                    let forces = Some((solved.internal_force(), f_ext.as_slice()));
                    match crate::garment::export::write_garment_vtu(&dir.join(&gname), model, Some(st), built.garment.as_ref(), &built.seams, forces, &export.extra_point_data, export.binary) {
                        Ok(()) => garment_entries.push((time, gname)),
                        Err(e) => io_error = io_error.take().or(Some(e.to_string())),
                    }
                    if let Some(nodes) = &surface_nodes {
                        if (poses.len() + 1) * nodes.len() <= MAX_POSE_VERTICES {
                            poses.push((time, nodes.iter().map(|&n| model.position(st, n).into()).collect()));
                        } else {
                            poses_dropped += 1;
                        }
                    }
                }
                export_s += t.elapsed().as_secs_f64();
            }
            if step_clock.0 != report.step {
                step_clock = (report.step, step_clock.1, 0, 0);
            }
            step_clock.2 += 1;
            step_clock.3 += report.iterations;
            // The end of a step: its last increment, or a Dynamic step's rest (its nominal
            // increment count does not apply).
            let step_ends = report.dynamics.as_ref().map_or(last_of_step, |d| d.end_of_step);
            if let (true, Some(k), Some(p)) = (step_ends, pose_of_step(report.step), built.protocol.as_ref()) {
                // Tie forces of rigid seams: f_int − f_ext with the contact forces in f_ext
                // (the solver's last assembly, at this converged state).
                let point_data: Vec<_> = solved.nodal_forces().iter().flat_map(|c| c.point_data(model, st)).collect();
                let m = crate::garment::measures::measure(model, st, built.garment.as_ref(), &built.seams, Some((solved.internal_force(), solved.external_force())), &point_data);
                let d = report.dynamics.as_ref();
                let pose = &p.poses[k];
                // A picture of the garment on the body in this pose (no external tools).
                let mut picture = None;
                if let Some(dir) = &options.out_dir {
                    let t = Instant::now();
                    let bodies: Vec<_> = built.contact.iter().flat_map(|c| &c.bodies).map(|b| b.at_time(solved.clock())).collect();
                    let pic = crate::garment::picture::garment_picture(model, st, built.garment.as_ref(), &built.seams, &bodies, PICTURE_SIZE);
                    let name = format!("{}_pose{:02}_{}.png", scene.name, k, pose.name);
                    match crate::io::png::write_png(&dir.join(&name), pic.width, pic.height, &pic.rgb) {
                        Ok(()) => picture = Some(name),
                        Err(e) => io_error = io_error.take().or(Some(e.to_string())),
                    }
                    export_s += t.elapsed().as_secs_f64();
                }
                poses_out.push(serde_json::json!({
                    "pose": pose.name,
                    "step": report.step_name,
                    "motion_time": pose.time,
                    "vtu": pvd_entries.last().filter(|e| e.0 == time).map(|e| e.1.clone()),
                    "garment_vtu": garment_entries.last().filter(|e| e.0 == time).map(|e| e.1.clone()),
                    "picture": picture,
                    "at_rest": d.is_none_or(|d| d.at_rest),
                    "time_steps": step_clock.2,
                    "newton_iterations": step_clock.3,
                    "simulated_time": d.map_or(0.0, |d| d.time),
                    "wall_s": step_clock.1.elapsed().as_secs_f64(),
                    "measures": m,
                }));
            }
            if step_ends {
                step_clock.1 = Instant::now();
            }
            if let Some(ev) = &report.stability_event {
                summary.stability_events.push((summary.increments.len(), format!("step {} increment {}: {ev}", report.step + 1, report.increment)));
            }
            if let (Some(dir), Some(b)) = (&options.out_dir, &report.buckling) {
                let name = format!("{}_buckling_step{}.vtu", scene.name, report.step + 1);
                match crate::io::modes::write_modes_vtu(&dir.join(&name), model, st, &b.modes, scene.output.binary) {
                    Ok(()) => mode_files.push(name),
                    Err(e) => io_error = io_error.take().or(Some(e.to_string())),
                }
            }
            summary.increments.push(report.clone());
        },
        progress,
    );
    summary.timings = solver.timings.clone();
    summary.timings.factorization_cpu_path = solver.factorization_cpu_path();
    // Output problems after the solve: reported, but never a reason to skip summary.json.
    let mut problems: Vec<String> = io_error.into_iter().collect();
    if let Some(c) = &built.contact {
        let mut extra = std::mem::take(&mut summary.extra);
        let measured = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            crate::contact::summarize(scene.drape.as_ref(), c, model, &state, solver.clock(), solver.nodal_forces(), &mut extra);
        }));
        if measured.is_err() {
            problems.push("the contact and drape measures failed (see the message above)".into());
        }
        summary.extra = extra;
    }
    if built.interply.is_some() {
        for (name, v) in solver.nodal_forces().iter().filter_map(|c| c.summary()) {
            summary.extra.entry(name).or_insert(v);
        }
    }
    if !built.seams.is_empty() {
        // Per seam at the final state: force per length (magnitude, along, across), utilisation
        // and opening (`garment::compliant`).
        let mut f_ext = vec![0.0; solver.internal_force().len()];
        if let Some(last) = summary.increments.last() {
            model.external_force(&state, &last.scales, &mut f_ext);
        }
        let forces = (!summary.increments.is_empty()).then_some((solver.internal_force(), f_ext.as_slice()));
        let position = |n: usize| model.position(&state, n);
        let points: Vec<_> = built.seams.iter().map(|s| crate::garment::compliant::seam_points(s, position, forces)).collect();
        let seams: Vec<_> = built.seams.iter().zip(&points).map(|(s, p)| crate::garment::compliant::summarize(s, p, position)).collect();
        if let Ok(v) = serde_json::to_value(seams) {
            summary.extra.insert("seams".into(), v);
        }
        // Multi-ply seams with their plies' forces summed node by node.
        let summed = crate::garment::compliant::ply_summed(&built.seams, &points);
        if !summed.is_empty() && let Ok(v) = serde_json::to_value(summed) {
            summary.extra.insert("seams_plies_summed".into(), v);
        }
    }
    if let Some(p) = &built.protocol {
        summary.extra.insert("poses".into(), serde_json::json!({ "body": p.body, "poses": poses_out }));
    }
    let status = match &result {
        Ok(()) => "completed".to_string(),
        Err(e) => format!("failed: {e}"),
    };
    summary.status = status;
    if let Some(dir) = &options.out_dir {
        let t = Instant::now();
        if result.is_err() {
            // Leave the last converged state for inspection.
            let name = format!("{}_last_converged.vtu", scene.name);
            match write_state_vtu(&dir.join(&name), model, &state, &export) {
                // The series time of the last converged state (a Dynamic step's seconds
                // are not in the error's pseudo-time).
                Ok(()) => pvd_entries.push((last_series_time, name)),
                Err(e) => problems.push(format!("{name}: {e}")),
            }
        }
        let pvd_name = format!("{}.pvd", scene.name);
        summary.files = pvd_entries.iter().map(|e| e.1.clone()).collect();
        summary.files.append(&mut mode_files);
        if let Some(serde_json::Value::Array(poses)) = summary.extra.get("poses").map(|p| &p["poses"]) {
            summary.files.extend(poses.iter().filter_map(|q| q["picture"].as_str().map(String::from)));
        }
        match pvd::write_pvd(&dir.join(&pvd_name), &pvd_entries) {
            Ok(()) => summary.files.push(pvd_name),
            Err(e) => problems.push(format!("{pvd_name}: {e}")),
        }
        if garment_export {
            let flat = format!("{}_pattern.vtu", scene.name);
            summary.files.extend(garment_entries.iter().map(|e| e.1.clone()));
            match crate::garment::export::write_garment_vtu(&dir.join(&flat), model, None, built.garment.as_ref(), &built.seams, None, &[], export.binary) {
                Ok(()) => summary.files.push(flat),
                Err(e) => problems.push(format!("{flat}: {e}")),
            }
            let gpvd = format!("{}_garment.pvd", scene.name);
            match pvd::write_pvd(&dir.join(&gpvd), &garment_entries) {
                Ok(()) => summary.files.push(gpvd),
                Err(e) => problems.push(format!("{gpvd}: {e}")),
            }
            if poses_dropped > 0 {
                problems.push(format!("{}_garment.glb: {poses_dropped} later states left out of the pose series (at most {MAX_POSE_VERTICES} vertex positions are kept)", scene.name));
            }
            if let Some(layout) = &built.garment {
                // A picture of the final (or last converged) state on its bodies.
                let bodies: Vec<_> = built.contact.iter().flat_map(|c| &c.bodies).map(|b| b.at_time(solver.clock())).collect();
                let pic = crate::garment::picture::garment_picture(model, &state, Some(layout), &built.seams, &bodies, PICTURE_SIZE);
                let name = format!("{}.png", scene.name);
                match crate::io::png::write_png(&dir.join(&name), pic.width, pic.height, &pic.rgb) {
                    Ok(()) => summary.files.push(name),
                    Err(e) => problems.push(format!("{name}: {e}")),
                }
                for (name, e) in write_surfaces(dir, &scene.name, model, &state, layout, &poses) {
                    match e {
                        None => summary.files.push(name),
                        Some(e) => problems.push(format!("{name}: {e}")),
                    }
                }
            }
        }
        let plotted = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| write_monitor_plot(dir, scene, built, &summary)));
        match plotted {
            Ok(Ok(Some(name))) => summary.files.push(name),
            Ok(Ok(None)) => {}
            Ok(Err(e)) => problems.push(format!("monitor plot: {e}")),
            Err(_) => problems.push("monitor plot: the plotting library failed (see the message above)".into()),
        }
        summary.files.push("summary.json".into());
        export_s += t.elapsed().as_secs_f64();
    }
    summary.export_s = export_s;
    summary.final_positions = (0..model.n_nodes()).map(|n| model.position(&state, n).into()).collect();
    summary.final_state = Some(state.clone());
    summary.wall_s = t0.elapsed().as_secs_f64();
    summary.peak_memory_mib = peak_memory_mib();
    if !problems.is_empty() {
        summary.extra.insert("output_problems".into(), serde_json::json!(problems));
    }
    if let Some(dir) = &options.out_dir {
        let json = serde_json::to_vec_pretty(&summary).map_err(|e| RunError::Io(e.to_string()))?;
        crate::io::atomic::write_atomic(&dir.join("summary.json"), &json).map_err(|e| RunError::Io(e.to_string()))?;
    }
    match result {
        Err(error) => Err(RunError::Solve { error, summary: Box::new(summary) }),
        Ok(()) if !problems.is_empty() => Err(RunError::Io(format!("{} (summary.json was written)", problems.join("; ")))),
        Ok(()) => Ok(summary),
    }
}

/// The load pattern the monitor plot uses on its x axis.
pub fn plot_load(scene: &Scene, built: &BuiltScene) -> Option<usize> {
    if let Some(name) = &scene.output.plot_against {
        return built.model.load_index(name);
    }
    let last = built.steps.last()?;
    last.target_scales.iter().position(|&s| s != 0.0)
}

/// Plots every monitored quantity against the chosen load scale (SVG).
fn write_monitor_plot(dir: &Path, scene: &Scene, built: &BuiltScene, summary: &Summary) -> Result<Option<String>, String> {
    let Some(li) = plot_load(scene, built) else { return Ok(None) };
    if summary.increments.is_empty() || summary.monitors.is_empty() {
        return Ok(None);
    }
    let mut series = Vec::new();
    for h in &summary.monitors {
        for (k, q) in h.quantities.iter().enumerate() {
            let mut points = vec![(0.0, 0.0)];
            points.extend(summary.increments.iter().zip(&h.values).map(|(inc, v)| (inc.scales[li], v[k])));
            series.push(plot::Series { name: format!("{} {}", h.name, q), points, reference: false });
        }
    }
    let name = format!("{}_monitors.svg", scene.name);
    let x_label = format!("load scale '{}'", built.model.loads[li].name);
    plot::plot_xy(&dir.join(&name), &scene.name, &x_label, "displacement", &series, false, false).map_err(|e| e.to_string())?;
    Ok(Some(name))
}

/// Pixels of each view in the pictures of a movement protocol's poses.
const PICTURE_SIZE: u32 = 480;

/// Most vertex positions (poses × garment nodes, 24 bytes each) kept for the glTF pose series.
const MAX_POSE_VERTICES: usize = 5_000_000;

/// Writes the garment's final state as `NAME_garment.obj` and, with the pose series `poses`
/// (time, vertex positions) as morph targets, `NAME_garment.glb`; returns each file name with
/// its error, if any.
fn write_surfaces(dir: &Path, name: &str, model: &Model, state: &State, layout: &crate::garment::export::GarmentLayout, poses: &[(f64, Vec<[f64; 3]>)]) -> Vec<(String, Option<String>)> {
    let (mesh, _) = crate::garment::export::garment_surface(model, layout, |n| model.position(state, n).into());
    let comment = [format!("plyshell garment '{name}': final state; one group per panel/ply; vt = flat pattern coordinates (m)")];
    let obj = format!("{name}_garment.obj");
    let obj_err = crate::io::obj::write_obj(&dir.join(&obj), &mesh, &comment).err().map(|e| e.to_string());
    let glb = format!("{name}_garment.glb");
    let (times, frames): (Vec<f64>, Vec<Vec<[f64; 3]>>) = poses.iter().cloned().unzip();
    let generator = concat!("plyshell ", env!("CARGO_PKG_VERSION"));
    let glb_err = crate::io::gltf::write_glb(&dir.join(&glb), &mesh, &frames, &times, generator).err().map(|e| e.to_string());
    vec![(obj, obj_err), (glb, glb_err)]
}

/// The CalculiX / Abaqus deck of a built scene: besides the parts, its node sets (`N_name`),
/// both sides of every seam (`SEAM_name_A` master, `SEAM_name_B` slave) and, for a garment,
/// the elements of each panel across its plies (`PANEL_name`).
pub fn inp_deck<'a>(scene: &Scene, built: &'a BuiltScene) -> crate::io::inp::InpDeck<'a> {
    let model = &built.model;
    let mut node_sets: Vec<(String, Vec<usize>)> = built.node_sets.iter().map(|(k, v)| (format!("N_{k}"), v.clone())).collect();
    for s in &built.seams {
        node_sets.push((format!("SEAM_{}_A", s.name), s.master.clone()));
        node_sets.push((format!("SEAM_{}_B", s.name), s.slave.clone()));
    }
    let mut element_sets = Vec::new();
    if let Some(l) = &built.garment {
        for (p, name) in l.panels.iter().enumerate() {
            let elements: Vec<usize> = (0..model.elements.len()).filter(|&e| l.part_tags.get(model.elements[e].part).is_some_and(|t| t[0] == p as i32)).collect();
            element_sets.push((format!("PANEL_{name}"), elements));
        }
    }
    crate::io::inp::InpDeck { heading: format!("plyshell scene '{}': {}", scene.name, scene.description), model, steps: &built.steps, node_sets, element_sets }
}
