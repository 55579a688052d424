//! Mesh sequencing (nested iteration) of a step to rest: `Dynamic((coarse_levels: L))` on a
//! scene's first step solves the step to rest on the parts' grids coarsened L, L − 1, …, 1
//! times by 2, maps each rest state onto the next finer grid and continues the step there,
//! the scene's own mesh last (Briggs, Henson & McCormick, *A Multigrid Tutorial* 2000,
//! §3 "nested iteration"; the full-multigrid start of a nonlinear solve). The coarse solves
//! find the large motion (fall, wrap, settle) at a fraction of the cost per iteration; the
//! fine mesh then only corrects the discretisation error, from a state near its own rest.
//!
//! The path differs from the direct solve on the fine mesh: the fine step starts from the
//! mapped coarse rest state at rest (no velocity), with fresh friction history anchored
//! there, and the fine mesh may settle into another of the (many, with friction) rest
//! states near it. Rest on the fine mesh is judged by the step's own criteria (kinetic
//! energy, static residual, stable equilibrium).
//!
//! Mapping (`model::prolong`): bilinear in the pattern coordinates of the structured grids,
//! directors renormalised. A chord of a coarse facet lying on a convex body dips into it
//! (by L²/8R on a sphere of radius R for a facet of length L), so every mapped node is then
//! moved along the body's outward normal until its signed distance to the body is at least
//! the same bilinear combination of the coarse nodes' distances: on the body the fine
//! nodes keep the gap the coarse ones had, and no mapped node starts inside a body. The
//! directors are then relaxed with the mid-surface held (`relax_directors`).
//!
//! The mapped state is not an equilibrium of the finer mesh: a coarse mesh of limp fabric
//! folds at its own element size (16² elements of 5 cm against a bending length of 1.5 cm)
//! and the finer mesh refolds it, so the fine step still has to move (measured on the
//! sheet dropped onto the sphere: relative static residual ≈ 1 right after the mapping, the
//! hanging skirt moving 2 cm RMS, 5 cm at most, between 32² mapped from 16² and its rest;
//! the part on the sphere 1 mm).

use serde_json::json;

use crate::analysis::{run_from, RunError, RunOptions, Start};
use crate::model::prolong::{prolong, GridPart};
use crate::model::{Model, State};
use crate::results::Summary;
use crate::scene::sequence::{coarse_levels, coarsened, grids};
use crate::scene::{BuiltScene, Scene};
use crate::solver::{Progress, Solver, StepKind, StepPlan};

/// Solves `scene` (whose first step has `coarse_levels` > 0) by mesh sequencing; the summary
/// is the fine run's, with the coarse levels and each mapping under `sequence`.
pub fn run(scene: &Scene, built: &BuiltScene, options: &RunOptions, progress: &mut dyn FnMut(&Progress)) -> Result<Summary, RunError> {
    let levels = coarse_levels(scene);
    if built.contact.as_ref().is_some_and(|c| c.bodies.iter().any(|b| b.motion.is_some())) {
        return Err(RunError::Setup("mesh sequencing: a contact body moves (a mannequin motion); the coarse rest state would not be the fine step's start".into()));
    }
    let mut records = Vec::new();
    let mut coarse: Option<(Scene, BuiltScene, State)> = None;
    for level in (1..=levels).rev() {
        let sc = coarsened(scene, level);
        let b = build_level(&sc, built)?;
        let start = match &coarse {
            Some((ps, pb, st)) => Some(map_level(ps, pb, st, &sc, &b)?),
            None => None,
        };
        let mapping = start.as_ref().map(|s| s.report.clone());
        let summary = run_from(&sc, &b, &RunOptions::default(), start, progress).map_err(|e| RunError::Setup(format!("mesh sequencing, level {} ({}): {e}", levels - level + 1, mesh_name(&sc))))?;
        records.push(level_record(&sc, &summary, mapping));
        let state = summary.final_state.ok_or_else(|| RunError::Setup("mesh sequencing: the coarse run kept no final state".into()))?;
        coarse = Some((sc, b, state));
    }
    let Some((ps, pb, st)) = coarse else {
        return run_from(scene, built, options, None, progress);
    };
    let mut start = map_level(&ps, &pb, &st, scene, built)?;
    start.report = json!({ "coarse_levels": levels, "levels": records, "mapping": start.report });
    run_from(scene, built, options, Some(start), progress)
}

/// The model of a coarsened scene; its contact bodies are the fine scene's (already read,
/// so mesh bodies need not be found again relative to the scene file).
fn build_level(sc: &Scene, fine: &BuiltScene) -> Result<BuiltScene, RunError> {
    let mut bare = sc.clone();
    bare.contact = None;
    bare.drape = None;
    let mut b = crate::scene::build(&bare, &sc.name, "").map_err(|e| RunError::Setup(format!("mesh sequencing: the coarse scene {}: {e}", mesh_name(sc))))?;
    b.contact = fine.contact.clone();
    Ok(b)
}

/// "nx×ny" of each part, joined.
fn mesh_name(sc: &Scene) -> String {
    grids(sc).iter().flatten().map(|(x, y)| format!("{x}x{y}")).collect::<Vec<_>>().join("+")
}

/// One level's counts from its summary.
fn level_record(sc: &Scene, s: &Summary, mapping: Option<serde_json::Value>) -> serde_json::Value {
    json!({
        "mesh": mesh_name(sc),
        "dofs": s.sizes.dofs,
        "time_steps": s.increments.len(),
        "newton_iterations": s.newton_iterations,
        "line_search_cuts": s.timings.line_search_cuts,
        "projected_iterations": s.timings.projected_iterations,
        "factorizations": s.timings.factorizations,
        "assembly_s": s.timings.assembly,
        "factorization_s": s.timings.factorization,
        "solve_s": s.timings.solve,
        "contact_s": s.timings.contact,
        "wall_s": s.wall_s,
        "mapping": mapping,
    })
}

/// Maps the rest state `st` of the coarse scene (`ps`, `pb`) onto the scene (`sc`, `b`):
/// prolongation, then the push-out of the module doc. The report gives the nodes moved out,
/// the largest move and the relative static residual of the mapped state on the fine model.
fn map_level(ps: &Scene, pb: &BuiltScene, st: &State, sc: &Scene, b: &BuiltScene) -> Result<Start, RunError> {
    let fail = |e: String| RunError::Setup(format!("mesh sequencing: mapping {} onto {}: {e}", mesh_name(ps), mesh_name(sc)));
    let pairs: Vec<(GridPart, GridPart)> = grids(ps)
        .into_iter()
        .zip(grids(sc))
        .enumerate()
        .filter_map(|(p, (c, f))| Some((GridPart { part: p, nx: c?.0, ny: c?.1 }, GridPart { part: p, nx: f?.0, ny: f?.1 })))
        .collect();
    let (coarse, fine) = (&pb.model, &b.model);
    let (mut state, weights) = prolong(coarse, st, fine, &pairs).map_err(fail)?;
    let (pushed, largest, min_gap) = match &b.contact {
        Some(c) => push_out(coarse, st, fine, &mut state, &weights, c),
        None => (0, 0.0, f64::INFINITY),
    };
    if min_gap <= 0.0 {
        return Err(fail(format!("a mapped node's face is on or inside a body (gap {min_gap:.3e} m) after the push-out")));
    }
    let relaxation = relax_directors(sc, b, &mut state).map_err(fail)?;
    let residual = mapped_residual(sc, b, &mut state).map_err(fail)?;
    Ok(Start { state, report: json!({ "from": mesh_name(ps), "to": mesh_name(sc), "nodes_pushed_out": pushed, "largest_push_m": largest, "director_relaxation": { "time_steps": relaxation.0, "newton_iterations": relaxation.1 }, "min_gap_m": if min_gap.is_finite() { Some(min_gap) } else { None }, "static_residual": residual }) })
}

/// Moves each mapped node of `fine` (weights into `coarse` in `weights`) that lies within
/// the barrier zone of a body (signed distance below h/2 + d̂) out along the body's normal to
/// the interpolated signed distance of its coarse nodes, capped at h/2 + d̂ (module doc):
/// on the body the fine nodes keep the coarse gaps; nodes clear of the body are left where
/// they are (the interpolated distance of a convex body exceeds the distance of the
/// interpolated point everywhere, not only where the sheet touches it). Returns the nodes
/// moved, the largest move (m) and the smallest gap of a face to a body after the moves (m).
pub(crate) fn push_out(coarse: &Model, st: &State, fine: &Model, state: &mut State, weights: &[Vec<(usize, f64)>], contact: &crate::contact::ContactSetup) -> (usize, f64, f64) {
    let Some(settings) = &contact.barrier else { return (0, 0.0, f64::INFINITY) };
    // Face offsets h/2 and barrier thicknesses d̂ of the participating fine nodes.
    let zones = crate::contact::BarrierContact::new(fine, Vec::new(), &contact.parts, settings);
    let (mut pushed, mut largest) = (0usize, 0.0f64);
    for body in &contact.bodies {
        let coarse_distance: Vec<f64> = (0..coarse.n_nodes()).map(|a| body.proximity(&coarse.position(st, a), f64::MAX).map_or(f64::INFINITY, |p| p.distance)).collect();
        for (i, &n) in zones.nodes.iter().enumerate() {
            let w = &weights[n];
            if w.is_empty() {
                continue;
            }
            let zone = zones.offset[i] + zones.dhat[i];
            let target = w.iter().map(|&(a, x)| x * coarse_distance[a]).sum::<f64>().min(zone);
            let x = fine.position(state, n);
            if let Some(p) = body.proximity(&x, f64::MAX)
                && p.distance < target
            {
                let m = target - p.distance;
                state.u[n] += p.normal * m;
                if m > 1e-12 * zone {
                    pushed += 1;
                }
                largest = largest.max(m);
            }
        }
    }
    let mut min_gap = f64::INFINITY;
    for (i, &n) in zones.nodes.iter().enumerate() {
        let x = fine.position(state, n);
        for p in contact.bodies.iter().filter_map(|b| b.proximity(&x, f64::MAX)) {
            min_gap = min_gap.min(p.distance - zones.offset[i]);
        }
    }
    (pushed, largest, min_gap)
}

/// Relaxes the directors of the mapped `state` with the mid-surface held: the fine model with
/// every translation fixed (its director tilts the only unknowns) integrated to rest in a
/// `Dynamic` step under the first step's target loads, from the interpolated directors.
/// Interpolated coarse directors are not in equilibrium on the finer mesh: MITC4 samples
/// the transverse shear at edge midpoints only, so a coarse rest state may hold zigzag
/// director tilts that cost it no energy but strain every finer mesh in shear; released at
/// once, that energy spins the directors (tiny rotary inertia) and cuts the time step to
/// nothing. Returns the time steps and Newton iterations.
pub(crate) fn relax_directors(sc: &Scene, b: &BuiltScene, state: &mut State) -> Result<(usize, usize), String> {
    let mut held = b.model.clone();
    if !held.dofs.ties.is_empty() {
        return Err("the model has ties: directors are not relaxed".into());
    }
    let fixed: Vec<bool> = held.dofs.eq.iter().enumerate().map(|(g, &e)| e == crate::model::FIXED || g % crate::element::NODE_DOFS < 3).collect();
    held.dofs = crate::model::DofMap::new(&fixed);
    if held.dofs.n_free == 0 {
        return Ok((0, 0));
    }
    let mut solver = Solver::new(&held, sc.solver.clone())?;
    let target_scales = b.steps.first().map(|s| s.target_scales.clone()).unwrap_or_default();
    let settle = crate::solver::DynamicSettings { dt: 1e-6, dt_min: 1e-12, ..Default::default() };
    let plan = StepPlan { name: "director relaxation".into(), increments: 1, linear: false, automatic_increments: false, target_scales, kind: StepKind::Dynamic(settle), clock: None };
    let (mut steps, mut iterations) = (0, 0);
    solver.run(&[plan], state, &mut |r, _, _| { steps += 1; iterations += r.iterations }, &mut |_| {}).map_err(|e| format!("director relaxation: {e}"))?;
    Ok((steps, iterations))
}

/// Relative static residual of the mapped `state` on the scene's model under its first
/// step's target loads, with its contact (the measure the step's rest test uses). A
/// non-finite residual is an error naming the term that makes it so (mapped plies that
/// touch or intersect give an infinite inter-ply barrier), not a number for the next solve
/// to fail on.
pub fn mapped_residual(sc: &Scene, b: &BuiltScene, state: &mut State) -> Result<f64, String> {
    let residual = |b: &BuiltScene, state: &mut State| -> Result<f64, String> {
        let mut solver = Solver::new(&b.model, sc.solver.clone()).map_err(|e| e.to_string())?;
        crate::analysis::attach_terms(&mut solver, &b.model, b)?;
        solver.start_nodal_forces_from(state);
        let scales = b.steps.first().map(|s| s.target_scales.clone()).unwrap_or_default();
        solver.static_residual(state, &scales)
    };
    let r = residual(b, state)?;
    if r.is_finite() {
        return Ok(r);
    }
    // Which term: the model alone, then with each kind of contact.
    let bare = BuiltScene { contact: None, interply: None, ..b.clone() };
    if !residual(&bare, &mut state.clone())?.is_finite() {
        return Err("the mapped state's residual is not finite without contact: an element or a seam of the new mesh".into());
    }
    let culprit = if b.interply.is_some() && !residual(&BuiltScene { contact: None, ..b.clone() }, &mut state.clone())?.is_finite() {
        "inter-ply or self contact: mapped plies touch or intersect (a pair at zero distance or less, where the barrier is infinite)"
    } else {
        "body contact: a mapped node's face is on or inside a body"
    };
    Err(format!("the mapped state's residual is not finite: {culprit}"))
}
