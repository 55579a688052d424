//! A-posteriori mesh refinement of a solve (issue 18 item 1): `refine: Some((tolerance: T,
//! passes: N))` on a scene's last step solves the scene, then N times: computes the error
//! indicator of the rest state (`indicator`: the relative shape error (hκ)²/8 of each
//! element on the computed curvature, the a-priori `Auto` tolerance's measure), derives a
//! size field from it (`size_field`: h (T/η)^{1/2}, clamped to [h/4, 2h], graded ≤ 25 %),
//! remeshes the parts with it (`GradedRectangle` tensor grids), maps the state onto the new
//! mesh (`map`: point location and inverse bilinear interpolation in pattern space; then the
//! barrier push-out of mesh sequencing, `analysis_sequence`, on request its director
//! relaxation, and the membrane relaxation of `relax`, which removes the interpolated state's
//! O(h²) membrane mismatch) and continues the last step to rest there (`relax::stage`
//! without the spring, then time steps from Δt = 10 τ). Elements whose indicator is below T grow (at
//! most ×2 per pass), so flat regions coarsen.
//!
//! What can be refined: scenes whose parts are all `Rectangle`, `SizedRectangle` or
//! `GradedRectangle` (flat, pattern = reference xy), or a garment without other parts
//! (`garment`: the panels meshed again by the pattern mesher from a size field, pattern =
//! the panels' (u, v)); the last step `Static` or a `Dynamic` step to rest; no scene-level
//! seams, imperfection, protocol, moving bodies, augmented-Lagrangian contact (states, ties or
//! multipliers the mapping does not carry) or `ply_model: Auto` — refused by `check` with the
//! field located.
//!
//! `summary.json` gets `refinement` (per pass: elements before/after, marked for
//! refinement, coarsened, DOFs, the mapped state's relative static residual after
//! interpolation and after the relaxations, the relaxation and descent stages, time steps,
//! Newton iterations, CPU seconds) and the output directory
//! `NAME_refinement.vtu`: the final state with cell data `indicator` (η at the final
//! state), `element_size` (the size the indicator asks for there, min over directions)
//! and `element_extent` (the element's pattern extents along X and Y).

pub mod indicator;
pub mod garment;
pub mod map;
pub mod relax;
pub mod size_field;

pub use crate::scene::sequence::{RefineSpec, MAX_PASSES};

use serde_json::json;

use crate::analysis::{run_from, RunError, RunOptions, Start};
use crate::model::{Model, State};
use crate::results::Summary;
use crate::scene::{MeshSpec, Scene};
use crate::scene::BuiltScene;
use crate::solver::{Progress, StepKind};

/// Largest aspect ratio a refined tensor grid may create (the 4:1 of `SizedAnnulus`).
pub const ASPECT: f64 = 4.0;

/// The last step's refinement request, if any.
pub fn requested(scene: &Scene) -> Option<&RefineSpec> {
    scene.steps.last().and_then(|s| s.refine.as_ref())
}


/// Node lines (x, y) of part `p`'s grid from its nodes' reference positions, measured from the
/// part's origin (its smallest x and y), and its extents (lx, ly).
fn grid_lines(model: &Model, p: usize) -> (Vec<f64>, Vec<f64>, f64, f64) {
    let part = &model.parts[p];
    let nodes = part.first_node..part.first_node + part.n_nodes;
    let lines = |k: usize| {
        let mut v: Vec<f64> = nodes.clone().map(|n| model.x0[n][k]).collect();
        v.sort_by(f64::total_cmp);
        let (lo, hi) = (v[0], v[v.len() - 1]);
        let tol = 1e-9 * (hi - lo).max(f64::MIN_POSITIVE);
        v.dedup_by(|a, b| (*a - *b).abs() <= tol);
        let l = hi - lo;
        let mut v: Vec<f64> = v.into_iter().map(|x| x - lo).collect();
        if let Some(last) = v.last_mut() {
            *last = l;
        }
        (v, l)
    };
    let ((xs, lx), (ys, ly)) = (lines(0), lines(1));
    (xs, ys, lx, ly)
}

/// What one pass asks for: the new node lines of every part and the counts of the report.
struct Plan {
    lines: Vec<(Vec<f64>, Vec<f64>, f64, f64)>,
    /// The garment panels' size fields (`garment`), for a garment scene.
    fields: Option<Vec<crate::garment::sizing::SizeField>>,
    marked: usize,
    coarsened: usize,
}

/// The refined meshes of the scene built as `b`, at its state `state`: garment panels by size
/// fields (`garment`), generated rectangles as graded grids ([`plan`]).
fn plan_of(b: &BuiltScene, state: &State, tolerance: f64) -> Result<(Plan, Vec<indicator::ElementIndicator>), String> {
    let Some(layout) = &b.garment else { return plan(&b.model, state, tolerance) };
    let pattern = garment::pattern_of(b);
    let ind = indicator::indicators(&b.model, state, &pattern)?;
    let (fields, marked, coarsened) = garment::panel_fields(&b.model, &pattern, &garment::part_panels(b), layout.panels.len(), &ind, tolerance)?;
    Ok((Plan { lines: Vec::new(), fields: Some(fields), marked, coarsened }, ind))
}

/// The refined grids of `model` at `state` for `tolerance` (module doc).
fn plan(model: &Model, state: &State, tolerance: f64) -> Result<(Plan, Vec<indicator::ElementIndicator>), String> {
    let pattern = map::pattern_of(model);
    let ind = indicator::indicators(model, state, &pattern)?;
    let (mut marked, mut coarsened) = (0, 0);
    let mut lines = Vec::new();
    for (p, part) in model.parts.iter().enumerate() {
        let (xs, ys, lx, ly) = grid_lines(model, p);
        let reference = &model.x0[part.first_node..part.first_node + part.n_nodes];
        let ox = reference.iter().map(|x| x.x).fold(f64::INFINITY, f64::min);
        let oy = reference.iter().map(|x| x.y).fold(f64::INFINITY, f64::min);
        let mut col = vec![f64::INFINITY; xs.len() - 1];
        let mut row = vec![f64::INFINITY; ys.len() - 1];
        let interval = |lines: &[f64], v: f64| lines.partition_point(|&l| l <= v).saturating_sub(1).min(lines.len() - 2);
        for e in part.first_element..part.first_element + part.n_elements {
            let c = model.elements[e].nodes.iter().fold([0.0; 2], |a, &n| [a[0] + 0.25 * (pattern[n][0] - ox), a[1] + 0.25 * (pattern[n][1] - oy)]);
            let i = &ind[e];
            let hx = size_field::target_size(i, 0, tolerance, lx / 4.0);
            let hy = size_field::target_size(i, 1, tolerance, ly / 4.0);
            if i.value() > tolerance {
                marked += 1;
            } else if hx >= 2.0 * i.h[0] || hy >= 2.0 * i.h[1] {
                coarsened += 1;
            }
            let (a, b) = (interval(&xs, c[0]), interval(&ys, c[1]));
            col[a] = col[a].min(hx);
            row[b] = row[b].min(hy);
        }
        // Aspect bound of the tensor grid: no element longer than ASPECT × the other
        // direction's smallest size (a column refined at the clamp crosses every row).
        let (cmin, rmin) = (col.iter().copied().fold(f64::INFINITY, f64::min), row.iter().copied().fold(f64::INFINITY, f64::min));
        col.iter_mut().for_each(|c| *c = c.min(ASPECT * rmin));
        row.iter_mut().for_each(|r| *r = r.min(ASPECT * cmin));
        let nx = size_field::node_lines(&xs, &col, 2);
        let ny = size_field::node_lines(&ys, &row, 1);
        lines.push((nx, ny, lx, ly));
    }
    Ok((Plan { lines, fields: None, marked, coarsened }, ind))
}

/// The scene on the refined grids `lines`, continuing its last step from a mapped rest state:
/// only that step, with the load scales the steps before it left, `refine` cleared; a `Static` step becomes a `Dynamic` step to rest with
/// the default settings (its loads are already on; from the interpolated state, whose
/// membrane mismatch exceeds fabric's weight by orders, a static Newton turned a director by
/// > 1 rad in its first correction on the Peirce strip; `run` relaxes that mismatch first,
/// `relax`, and starts the time steps at Δt = 10 τ). The rest state is the same static
/// equilibrium.
fn refined_scene(scene: &Scene, lines: &[(Vec<f64>, Vec<f64>, f64, f64)]) -> Scene {
    let mut s = scene.clone();
    for (p, (x, y, lx, ly)) in s.parts.iter_mut().zip(lines) {
        p.mesh = MeshSpec::GradedRectangle { lx: *lx, ly: *ly, x: x.clone(), y: y.clone() };
    }
    let last = s.steps.len().saturating_sub(1);
    // Load scales carry over from step to step (`scene::steps`): the kept step gets those of
    // the steps dropped before it, its own last.
    let mut scale = std::collections::BTreeMap::new();
    for st in &s.steps {
        scale.extend(st.scale.iter().map(|(k, v)| (k.clone(), *v)));
    }
    s.steps.drain(..last);
    if let Some(st) = s.steps.first_mut() {
        st.scale = scale.into_iter().collect();
    }
    for st in &mut s.steps {
        st.refine = None;
        st.increments = 1;
        if let StepKind::Dynamic(ds) = &mut st.kind {
            ds.coarse_levels = 0;
        } else {
            st.kind = StepKind::Dynamic(Default::default());
        }
    }
    s
}

/// Total potential energy Π = Σ strain energy − load potential of `state` of `model` under
/// `scales` (None when an element cannot be evaluated or a load has no potential).
pub fn potential(model: &Model, state: &State, scales: &[f64]) -> Option<f64> {
    let mut u = 0.0;
    for (e, def) in model.elements.iter().enumerate() {
        let out = model.element(e).response(&def.nodes.map(|n| state.u[n]), &def.nodes.map(|n| state.frames[n]), false).ok()?;
        u += out.energy;
    }
    Some(u + model.load_potential(state, scales)?)
}

/// The scene one refinement pass makes of `scene` (solved on `model`, whose rest state is
/// `state`): its parts on the refined grids, continuing its last step (for tests and tools
/// that rebuild the pass's mesh).
pub fn refined_scene_of(scene: &Scene, model: &Model, state: &State, tolerance: f64) -> Result<Scene, String> {
    Ok(refined_scene(scene, &plan(model, state, tolerance)?.0.lines))
}

/// The model of a refined scene (garment panels meshed by `fields`); contact bodies are the
/// original scene's (already read).
fn build_refined(sc: &Scene, original: &BuiltScene, fields: Option<Vec<crate::garment::sizing::SizeField>>) -> Result<BuiltScene, RunError> {
    let mut bare = sc.clone();
    bare.contact = None;
    bare.drape = None;
    let mut b = crate::scene::build_sized(&bare, &sc.name, "", fields).map_err(|e| RunError::Setup(format!("refinement: the refined scene: {e}")))?;
    b.contact = original.contact.clone();
    Ok(b)
}

/// Solves `scene` with the refinement passes of its last step (module doc); the summary is
/// the last pass's, with `refinement` added. Writes files only for the last pass.
pub fn run(scene: &Scene, built: &BuiltScene, options: &RunOptions, progress: &mut dyn FnMut(&Progress)) -> Result<Summary, RunError> {
    run_refined(scene, built, options, progress).map(|r| r.0)
}

/// [`run`], also returning the last pass's scene and model (None without refinement: the
/// summary is then of `built` itself), whose mesh the summary's final state lives on.
pub fn run_refined(scene: &Scene, built: &BuiltScene, options: &RunOptions, progress: &mut dyn FnMut(&Progress)) -> Result<(Summary, Option<(Scene, BuiltScene)>), RunError> {
    let Some(spec) = requested(scene).cloned() else {
        return crate::analysis::run_unrefined(scene, built, options, progress).map(|s| (s, None));
    };
    let cpu0 = crate::cpu_time::process_seconds();
    let first = crate::analysis::run_unrefined(scene, built, &RunOptions::default(), progress)?;
    let mut passes = vec![json!({
        "pass": 0, "elements": built.model.elements.len(), "dofs": first.sizes.dofs,
        "time_steps": first.increments.len(), "newton_iterations": first.newton_iterations,
        "cpu_s": crate::cpu_time::process_seconds() - cpu0,
    })];
    let mut state = first.final_state.ok_or_else(|| RunError::Setup("refinement: the first solve kept no final state".into()))?;
    let mut current: Option<(Scene, BuiltScene)> = None;
    for pass in 1..=spec.passes {
        let cpu = crate::cpu_time::process_seconds();
        let fail = |e: String| RunError::Setup(format!("refinement pass {pass}: {e}"));
        let old_built = current.as_ref().map_or(built, |c| &c.1);
        let old = &old_built.model;
        let (pl, _) = plan_of(old_built, &state, spec.tolerance).map_err(fail)?;
        let sc = refined_scene(scene, &pl.lines);
        let mut b = build_refined(&sc, built, pl.fields.clone())?;
        let (mut mapped, weights) = map::map_state(old, &state, &garment::pattern_of(old_built), &b.model, &garment::pattern_of(&b)).map_err(fail)?;
        let (pushed, _, min_gap) = match &b.contact {
            Some(c) => crate::analysis_sequence::push_out(old, &state, &b.model, &mut mapped, &weights, c),
            None => (0, 0.0, f64::INFINITY),
        };
        if min_gap <= 0.0 {
            return Err(fail(format!("a mapped node's face is on or inside a body (gap {min_gap:.3e} m) after the push-out")));
        }
        let residual_mapped = crate::analysis_sequence::mapped_residual(&sc, &b, &mut mapped).map_err(fail)?;
        let relaxation = if spec.relax_directors { crate::analysis_sequence::relax_directors(&sc, &b, &mut mapped).map_err(fail)? } else { (0, 0) };
        // Membrane-consistent mapping (`relax`): one proximal stage with the normal spring.
        let cpu_relax = crate::cpu_time::process_seconds();
        let membrane = if spec.relax_membrane { Some(relax::stage(&sc, &b, &mut mapped, Some(relax::TAU_S)).map_err(fail)?) } else { None };
        // The stage measured the residual of the state it leaves (a new solver each time).
        let residual = match &membrane {
            Some(m) => m.static_residual,
            None => crate::analysis_sequence::mapped_residual(&sc, &b, &mut mapped).map_err(fail)?,
        };
        let cpu_relax = crate::cpu_time::process_seconds() - cpu_relax;
        let last = pass == spec.passes;
        let scales = b.steps.last().map(|s| s.target_scales.clone()).unwrap_or_default();
        let old_scales = match &current { Some(c) => c.1.steps.last(), None => built.steps.last() }.map(|s| s.target_scales.clone()).unwrap_or_default();
        let pi_before = potential(old, &state, &old_scales);
        let pi_mapped = potential(&b.model, &mapped, &scales);
        // The continuation: the minimisation without the spring (skipped if it does not
        // converge in one solve), then the step to rest from Δt = 10 τ (the default first
        // step's ramp, 1 ms × 1.5ᵏ, is what the relaxed state no longer needs).
        let cpu_descent = crate::cpu_time::process_seconds();
        let relaxed = membrane.as_ref().is_some_and(|m| m.failed.is_none());
        let descent = if relaxed { Some(relax::stage(&sc, &b, &mut mapped, None).map_err(fail)?) } else { None };
        let cpu_descent = crate::cpu_time::process_seconds() - cpu_descent;
        if relaxed
            && let Some(StepKind::Dynamic(ds)) = b.steps.last_mut().map(|s| &mut s.kind)
        {
            ds.dt = ds.dt.max(relax::CONTINUATION_DT_FACTOR * relax::TAU_S);
        }
        let report = json!({
            "pass": pass, "elements_before": old.elements.len(), "elements": b.model.elements.len(),
            "marked": pl.marked, "coarsened": pl.coarsened,
            "grids": if pl.fields.is_some() { b.model.parts.iter().map(|p| format!("{}: {} elements", p.name, p.n_elements)).collect::<Vec<_>>() } else { pl.lines.iter().map(|l| format!("{}x{}", l.0.len() - 1, l.1.len() - 1)).collect::<Vec<_>>() },
            "nodes_pushed_out": pushed,
            "static_residual_interpolated": residual_mapped,
            "static_residual": residual,
            "potential_before_j": pi_before,
            "potential_mapped_j": pi_mapped,
            "director_relaxation": { "time_steps": relaxation.0, "newton_iterations": relaxation.1 },
            "membrane_relaxation": membrane.as_ref().map(|m| relax::report(Some(relax::TAU_S), m)),
            "membrane_relaxation_cpu_s": cpu_relax,
            "descent": descent.as_ref().map(|d| relax::report(None, d)),
            "descent_cpu_s": cpu_descent,
        });
        let out = if last { options.clone() } else { RunOptions::default() };
        let mut summary = run_from(&sc, &b, &out, Some(Start { state: mapped, report: json!(null) }), progress).map_err(|e| match e {
            RunError::Setup(m) => fail(m),
            other => other,
        })?;
        summary.extra.remove("sequence");
        let mut report = report;
        report["dofs"] = json!(summary.sizes.dofs);
        report["time_steps"] = json!(summary.increments.len());
        report["newton_iterations"] = json!(summary.newton_iterations);
        report["cpu_s"] = json!(crate::cpu_time::process_seconds() - cpu);
        if let Some(rest) = summary.final_state.as_ref() {
            report["potential_rest_j"] = json!(potential(&b.model, rest, &scales));
        }
        passes.push(report);
        state = summary.final_state.clone().ok_or_else(|| fail("the continued solve kept no final state".into()))?;
        if last {
            let (_, ind) = plan_of(&b, &state, spec.tolerance).map_err(fail)?;
            summary.extra.insert("refinement".into(), json!({ "tolerance": spec.tolerance, "passes": passes, "cpu_s": crate::cpu_time::process_seconds() - cpu0 }));
            if let Some(dir) = &options.out_dir {
                write_indicator_vtu(dir, &sc, &b, &state, &ind, spec.tolerance)?;
                summary.files.push(format!("{}_refinement.vtu", sc.name));
                let text = serde_json::to_vec_pretty(&summary).map_err(|e| RunError::Io(e.to_string()))?;
                crate::io::atomic::write_atomic(&dir.join("summary.json"), &text).map_err(|e| RunError::Io(e.to_string()))?;
            }
            return Ok((summary, Some((sc, b))));
        }
        current = Some((sc, b));
    }
    Err(RunError::Setup("refinement: no pass ran".into()))
}

/// `NAME_refinement.vtu`: the final state with the indicator, the size it asks for and the
/// elements' extents as cell data.
fn write_indicator_vtu(dir: &std::path::Path, sc: &Scene, b: &BuiltScene, state: &State, ind: &[indicator::ElementIndicator], tolerance: f64) -> Result<(), RunError> {
    let size: Vec<f64> = match &b.garment {
        Some(layout) => garment::element_sizes(&b.model, &garment::pattern_of(b), &garment::part_panels(b), layout.panels.len(), ind, tolerance),
        None => {
            let lines: Vec<(f64, f64)> = (0..b.model.parts.len()).map(|p| { let (_, _, lx, ly) = grid_lines(&b.model, p); (lx, ly) }).collect();
            ind.iter().enumerate().map(|(e, i)| {
                let (lx, ly) = lines[b.model.elements[e].part];
                size_field::target_size(i, 0, tolerance, lx / 4.0).min(size_field::target_size(i, 1, tolerance, ly / 4.0))
            }).collect()
        }
    };
    let options = crate::io::export::ExportOptions {
        binary: sc.output.binary,
        extra_cell_data: vec![
            ("indicator".into(), 1, ind.iter().map(|i| i.value()).collect()),
            ("element_size".into(), 1, size),
            ("element_extent".into(), 2, ind.iter().flat_map(|i| i.h).collect()),
        ],
        ..Default::default()
    };
    let path = dir.join(format!("{}_refinement.vtu", sc.name));
    crate::io::export::write_state_vtu(&path, &b.model, state, &options).map_err(|e| RunError::Io(format!("{}: {e}", path.display())))
}
