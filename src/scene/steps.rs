//! Solver controls and step plans from a scene: bounds that keep every loop finite, and each
//! step's target load scales and resolved kind.

use std::collections::BTreeMap;

use super::spec::Scene;
use crate::input::{Locator, SceneError};
use crate::model::Load;
use crate::solver::{SolverSettings, StepPlan};

/// Most increments of one step (each reported and possibly written as a VTU).
pub const MAX_INCREMENTS: usize = 1_000_000;
/// Most Newton iterations per increment.
pub const MAX_ITERATIONS: usize = 10_000;
/// Most cut-backs (halvings) of an increment.
pub const MAX_CUTBACKS: usize = 60;
/// Most solver threads.
pub const MAX_THREADS: usize = 1024;
/// Most modes of a buckling step (each a vector of all DOFs, plus the Lanczos basis).
pub const MAX_BUCKLING_MODES: usize = 100;

/// Checks the solver controls: bounded Newton loops, cut-backs and threads, tolerances in
/// (0, 1) and a valid chord (modified-Newton) setting.
pub(super) fn check_solver(sv: &SolverSettings, loc: &Locator) -> Result<(), SceneError> {
    let bad_solver = |key: &str, msg: String| loc.at(None, Some(key), format!("solver.{key}"), msg);
    if !(1..=MAX_ITERATIONS).contains(&sv.max_iterations) {
        return Err(bad_solver("max_iterations", format!("expected 1 to {MAX_ITERATIONS} Newton iterations per increment, found {}", sv.max_iterations)));
    }
    if !(sv.residual_tol.is_finite() && sv.residual_tol > 0.0 && sv.residual_tol < 1.0) {
        return Err(bad_solver("residual_tol", format!("expected a relative tolerance in (0, 1), found {}", sv.residual_tol)));
    }
    if !(sv.energy_tol.is_finite() && sv.energy_tol > 0.0 && sv.energy_tol < 1.0) {
        return Err(bad_solver("energy_tol", format!("expected a relative tolerance in (0, 1), found {}", sv.energy_tol)));
    }
    if sv.max_cutbacks > MAX_CUTBACKS {
        return Err(bad_solver("max_cutbacks", format!("expected at most {MAX_CUTBACKS} halvings (2^-{MAX_CUTBACKS} of an increment is below rounding), found {}", sv.max_cutbacks)));
    }
    if sv.threads > MAX_THREADS {
        return Err(bad_solver("threads", format!("expected 0 (all cores) to {MAX_THREADS} threads, found {}", sv.threads)));
    }
    if let Some(Err((field, msg))) = sv.chord.map(|c| c.validate()) {
        return Err(loc.at(None, Some(field), format!("solver.chord.{field}"), msg));
    }
    Ok(())
}

/// The steps' plans: each step's increments and kind checked, its load-scale table applied on
/// top of the previous step's target scales (a load keeps its scale until a step changes it),
/// and its kind resolved against node sets, loads and the fixed DOFs; with the load scales
/// after the last step.
pub(super) fn plan_steps(scene: &Scene, loc: &Locator, node_sets: &BTreeMap<String, Vec<usize>>, loads: &[Load], fixed: &[bool]) -> Result<(Vec<StepPlan>, Vec<f64>), SceneError> {
    if scene.steps.is_empty() {
        return Err(loc.at(None, Some("steps"), "steps", "expected at least one step"));
    }
    super::sequence::check(scene, loc)?;
    super::sequence::check_refine(scene, loc)?;
    let mut steps = Vec::new();
    let mut current = vec![0.0; loads.len()];
    for s in &scene.steps {
        let field = format!("steps[{}]", s.name);
        if s.increments == 0 || s.increments > MAX_INCREMENTS {
            return Err(loc.at(Some(&s.name), Some("increments"), format!("{field}.increments"), format!("expected 1 to {MAX_INCREMENTS} increments, found {}", s.increments)));
        }
        if let crate::solver::StepKind::Buckling { modes, .. } = &s.kind
            && *modes > MAX_BUCKLING_MODES
        {
            return Err(loc.at(Some(&s.name), Some("modes"), format!("{field}.kind.modes"), format!("expected 1 to {MAX_BUCKLING_MODES} buckling modes, found {modes}")));
        }
        if let crate::solver::StepKind::Dynamic(ds) = &s.kind {
            if let Some((key, msg)) = crate::solver::dynamics::check_settings(ds) {
                return Err(loc.at(Some(&s.name), Some(key), format!("{field}.kind.{key}"), msg));
            }
        }
        let previous = current.clone();
        for (lname, &v) in &s.scale {
            let Some(i) = loads.iter().position(|l| &l.name == lname) else {
                let known: Vec<&str> = loads.iter().map(|l| l.name.as_str()).collect();
                return Err(loc.at_value(&s.name, lname, format!("{field}.scale"), format!("no load named \"{lname}\"; loads: {}", known.join(", "))));
            };
            if !v.is_finite() {
                return Err(loc.at_value(&s.name, lname, format!("{field}.scale[{lname}]"), "expected a finite scale"));
            }
            current[i] = v;
        }
        let kind = super::path::resolve_step_kind(s, &field, &loc, &node_sets, &loads, &fixed)?;
        // What the solver would refuse only when it reaches the step: a buckling or
        // arc-length step without a load change.
        if matches!(kind, crate::solver::StepKind::Buckling { .. } | crate::solver::StepKind::ArcLength { .. }) && current == previous {
            return Err(loc.at(Some(&s.name), Some("scale"), format!("{field}.scale"), "the step changes no load: give the reference load's target scale in its scale table"));
        }
        steps.push(StepPlan { name: s.name.clone(), increments: s.increments, linear: s.linear, automatic_increments: s.automatic_increments, target_scales: current.clone(), kind, clock: None });
    }
    Ok((steps, current))
}
