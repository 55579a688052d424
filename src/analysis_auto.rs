//! `ply_model: Auto` (issue 18, ply fidelity): a scene whose garment has `Auto` panels is
//! solved in up to two passes.
//!
//! 1. Every multi-ply `Auto` panel laminated (`garment::laminate::resolve_auto` with no
//!    sliding panel; a sewn group with an explicitly discrete member is discrete from the
//!    start), solved to the end of its steps.
//! 2. From that converged state, `garment::ply_auto::evaluate` estimates per laminated panel
//!    where the plies would slide (interlaminar shear against friction × pressure, the rest
//!    carried by the quilting) or separate (peel against the quilting). The flagged panels
//!    (and the panels sewn to them) are rebuilt with discrete plies, the rest stay
//!    laminated, and the scene is solved again from its start (the laminate's state is not
//!    mapped onto the plies). If nothing is flagged the first pass is the result; if the
//!    first pass fails (e.g. the laminate never comes to rest), its Auto panels go discrete.
//!
//! The summary's `ply_model_auto` section records per panel the chosen model, its reason,
//! the slip and peel ratios per interface, and the first pass's cost; with an output
//! directory the first pass's files go to `auto_first_pass/` inside it.

use std::path::PathBuf;

use nalgebra::Vector3;

use crate::analysis::{self, RunError, RunOptions};
use crate::garment::laminate::{has_auto, resolve_auto, AutoChoice};
use crate::garment::ply_auto::{self, PanelDemand};
use crate::results::Summary;
use crate::scene::{self, BuiltScene, LoadSpec, Scene};
use crate::solver::Progress;

/// The outcome of an `Auto` run.
pub struct AutoRun {
    /// The scene as finally built (the second pass's, or the first's).
    pub built: BuiltScene,
    /// Its summary (`ply_model_auto` section added; wall time and Newton iterations of both
    /// passes).
    pub summary: Summary,
    /// Model chosen per `Auto` panel.
    pub choices: Vec<AutoChoice>,
    /// Slip and peel demand of the first pass's laminated panels.
    pub demands: Vec<PanelDemand>,
    /// Solves run (1 or 2).
    pub passes: usize,
}

/// Whether `scene` needs the two-pass `Auto` run.
pub fn is_auto(scene: &Scene) -> bool {
    scene.garment.as_ref().is_some_and(has_auto)
}

/// The gravitational acceleration of the scene's weight loads (the first `Gravity`,
/// `SelfWeight` or `GarmentWeight`), or zero.
fn gravity(scene: &Scene) -> Vector3<f64> {
    scene
        .loads
        .values()
        .find_map(|l| match l {
            LoadSpec::Gravity { g, .. } | LoadSpec::SelfWeight { g, .. } | LoadSpec::GarmentWeight { g } => Some(Vector3::new(g[0], g[1], g[2])),
            _ => None,
        })
        .unwrap_or_else(Vector3::zeros)
}

/// `scene` with its garment replaced by `garment`.
fn with_garment(scene: &Scene, garment: crate::garment::GarmentSpec) -> Scene {
    let mut s = scene.clone();
    s.garment = Some(garment);
    s
}

/// Solves a scene with `Auto` panels in two passes (see the module documentation); `file`
/// and `text` are the scene file's name and text (for located build errors).
pub fn run(scene: &Scene, file: &str, text: &str, options: &RunOptions, progress: &mut dyn FnMut(&Progress)) -> Result<AutoRun, RunError> {
    let build = |s: &Scene| scene::build(s, file, text).map_err(|e| RunError::Setup(e.to_string()));
    let Some(spec) = scene.garment.as_ref().filter(|g| has_auto(g)) else {
        let built = build(scene)?;
        let summary = analysis::run(scene, &built, options, progress)?;
        return Ok(AutoRun { built, summary, choices: Vec::new(), demands: Vec::new(), passes: 1 });
    };
    let (first_spec, first_choices) = resolve_auto(spec, &[]);
    let first_scene = with_garment(scene, first_spec.clone());
    let first = build(&first_scene)?;
    let first_dir: Option<PathBuf> = options.out_dir.as_ref().map(|d| d.join("auto_first_pass"));
    let laminated = first_choices.iter().any(|c| c.model == "laminate");
    let first_options = RunOptions { out_dir: if laminated { first_dir.clone() } else { options.out_dir.clone() } };
    // A laminated first pass that does not solve (e.g. never comes to rest) is no model of
    // the garment: its Auto panels go discrete (the criterion is still evaluated at its last
    // converged state, for the record). Without a laminated panel the first pass is final.
    let (first_summary, first_failure) = match analysis::run(&first_scene, &first, &first_options, progress) {
        Ok(s) => (s, None),
        Err(RunError::Solve { error, summary }) if laminated => (*summary, Some(error.to_string())),
        Err(e) => return Err(e),
    };
    let friction = if spec.interply.enabled { spec.interply.friction } else { 0.0 };
    let demands = match &first.garment {
        Some(layout) if laminated => {
            let state = first_summary.final_state.as_ref().ok_or_else(|| RunError::Setup("ply_model Auto: the first pass left no state".into()))?;
            match ply_auto::evaluate(&first_spec, &first.model, state, layout, &first.seams, gravity(scene), friction) {
                Ok(d) => d,
                // After a failed first pass the criterion is only for the record.
                Err(_) if first_failure.is_some() => Vec::new(),
                Err(m) => return Err(RunError::Setup(format!("ply_model Auto: {m}"))),
            }
        }
        _ => Vec::new(),
    };
    let slides: Vec<String> = match &first_failure {
        Some(_) => first_choices.iter().filter(|c| c.model == "laminate").map(|c| c.panel.clone()).collect(),
        None => demands.iter().filter(|d| d.discrete).map(|d| d.panel.clone()).collect(),
    };
    let (second_spec, mut choices) = resolve_auto(spec, &slides);
    if let Some(f) = &first_failure {
        for c in choices.iter_mut().filter(|c| slides.contains(&c.panel)) {
            c.reason = format!("the laminated first pass failed ({f})");
        }
    }
    let changed = second_spec.panels.iter().zip(&first_spec.panels).any(|(a, b)| a.ply_model != b.ply_model);
    let section = |passes: usize, first: &Summary| {
        let panels: Vec<serde_json::Value> = choices
            .iter()
            .map(|c| {
                let d = demands.iter().find(|d| d.panel == c.panel);
                serde_json::json!({ "panel": c.panel, "model": c.model, "reason": c.reason, "slip_ratio": d.map(|d| d.slip_ratio), "peel_ratio": d.map(|d| d.peel_ratio), "interfaces": d.map(|d| &d.interfaces) })
            })
            .collect();
        serde_json::json!({
            "passes": passes,
            "slip_limit": ply_auto::SLIP_LIMIT,
            "peel_limit": ply_auto::PEEL_LIMIT,
            "friction": friction,
            "panels": panels,
            "first_pass": { "status": first.status, "failure": first_failure, "newton_iterations": first.newton_iterations, "wall_s": first.wall_s, "dofs": first.sizes.dofs },
        })
    };
    let write = |summary: &Summary| -> Result<(), RunError> {
        if let Some(dir) = &options.out_dir {
            let json = serde_json::to_vec_pretty(summary).map_err(|e| RunError::Io(e.to_string()))?;
            crate::io::atomic::write_atomic(&dir.join("summary.json"), &json).map_err(|e| RunError::Io(e.to_string()))?;
        }
        Ok(())
    };
    if !changed {
        let mut summary = first_summary;
        summary.extra.insert("ply_model_auto".into(), section(1, &summary));
        if laminated && options.out_dir.is_some() {
            summary.files = summary.files.iter().map(|f| format!("auto_first_pass/{f}")).collect();
        }
        write(&summary)?;
        return Ok(AutoRun { built: first, summary, choices, demands, passes: 1 });
    }
    let second_scene = with_garment(scene, second_spec);
    let second = build(&second_scene)?;
    let mut summary = analysis::run(&second_scene, &second, options, progress).map_err(|e| match e {
        RunError::Solve { error, mut summary } => {
            summary.extra.insert("ply_model_auto".into(), section(2, &first_summary));
            RunError::Solve { error, summary }
        }
        e => e,
    })?;
    summary.extra.insert("ply_model_auto".into(), section(2, &first_summary));
    summary.wall_s += first_summary.wall_s;
    summary.newton_iterations += first_summary.newton_iterations;
    write(&summary)?;
    Ok(AutoRun { built: second, summary, choices, demands, passes: 2 })
}

/// One line per `Auto` panel: its model, the ratios and the reason.
pub fn describe(run: &AutoRun) -> Vec<String> {
    run.choices
        .iter()
        .map(|c| {
            let d = run.demands.iter().find(|d| d.panel == c.panel);
            let ratios = d.map_or(String::new(), |d| format!(" (slip {:.3} / {}, peel {:.3} / {})", d.slip_ratio, ply_auto::SLIP_LIMIT, d.peel_ratio, ply_auto::PEEL_LIMIT));
            format!("ply_model Auto: panel \"{}\" → {}{ratios}: {}", c.panel, c.model, c.reason)
        })
        .collect()
}
