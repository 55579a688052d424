//! Pseudo-transient continuation by implicit dynamics (Kelley & Keyes, SIAM J. Numer. Anal.
//! 35, 1998; Bathe 2014 §9.2): the static problem f_int(u) = f_ext is embedded in
//!
//!   M ü + α_M M u̇ + f_int(u) = f_ext(t),
//!
//! integrated with backward Euler (first order, L-stable: it damps every mode and keeps the
//! equilibria of the static problem), u̇_{n+1} = (u_{n+1} − u_n)/Δt, ü_{n+1} = (u̇_{n+1} −
//! u̇_n)/Δt. Each time step is a Newton solve on the effective tangent
//! K + (1/Δt² + α_M/Δt) M, positive definite for small enough Δt even where K is singular
//! (a hanging cloth) or indefinite (a sheet at the wrinkling threshold). Δt grows after easy
//! steps, so the iteration turns into Newton's method as the motion dies out, and is cut
//! back when Newton fails or the effective tangent is not positive definite. The step stops
//! when the kinetic energy and the static residual ‖f_int − f_ext‖ are both below their
//! tolerances and (by default) the static tangent is positive definite there, so that an
//! unstable equilibrium (a saddle, e.g. a flat sheet past its wrinkling threshold) is left
//! along its unstable mode instead of being reported as rest.
//!
//! Leaving a saddle: the integration reaches a saddle with (nearly) no component along its
//! unstable mode, and an unstable mode K φ = ω² M φ, ω² < 0, grows from there only at the
//! rate s of s² + α_M s + ω² = 0, about |ω²|/α_M when heavily damped (ω² = −1 s⁻²,
//! α_M = 40 s⁻¹: one e-fold per 40 s, so growth from round-off takes ~1000 s of simulated
//! time), and not at all from an exactly symmetric state (a perfect plate compressed past
//! buckling). Where the rest criteria hold at an unstable
//! equilibrium, the state is therefore moved along the lowest mode φ (shifted inverse
//! iteration on K + c M, with c bracketed by Cholesky success just above −ω²_min) to the
//! minimum of the potential along it — the first zero of the directional derivative
//! φ·(f_int − f_ext)(u + s φ), s > 0 — repeatedly, along the lowest mode of each new state,
//! until the tangent is positive definite (at most 25 moves); a stable state within the rest
//! tolerance is the rest state, else the integration goes on from rest there (at most
//! `MAX_SADDLE_ESCAPES` times per step): the negative-curvature
//! step of descent methods at a saddle (Moré & Sorensen, Math. Prog. 16, 1979; Nocedal &
//! Wright, *Numerical Optimization* 2006, §4.3) and the branch switching of structural
//! stability, a perturbation along the critical eigenvector (Wriggers, *Nonlinear Finite
//! Element Methods* 2008, §7.4). The rest state finally accepted is still a strict minimum.
//!
//! For transient analysis the generalized-α scheme (Chung & Hulbert 1993) is available with
//! a chosen high-frequency dissipation ρ∞, and `duration` ends the step at a given time.
//!
//! Mass is lumped (row sums of the consistent mass, i.e. the nodal area weights ∫N_a dA
//! times the part's areal density ρ_A). Director tilts carry the fibre's rotary inertia
//! ρ_A h²/12 per area (a fibre of length h through a lamina of density ρ = ρ_A/h), scaled by
//! `rotary_inertia`; its inertial force acts on the director, J (d − d_n − Δt ḋ_n)/Δt²,
//! projected onto the tilt directions t1, t2.
//!
//! One time step's Newton solve (the incremental potential, its projections and line search)
//! is in `time_step`, the masses and the schemes' coefficients in `inertia`, the stability
//! test and the moves off a saddle in `saddle`, the reported time-step data in `report`.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use super::diagnose;
use super::inertia::Coefficients;
pub use super::inertia::{LumpedMass, TimeScheme};
use super::newton::{IncrementReport, Progress, SolveError, Solver, StepPlan};
use super::time_step::{Kinematics, TimeStep};
pub use super::report::DynamicInfo;
use crate::element::NODE_DOFS;
use crate::model::{State, FIXED};

/// Saddle escapes per Dynamic step; later unstable rests are only counted and the
/// integration goes on (bounds the cost when the damped motion keeps returning to the state,
/// as it did to the penalty-unstable contact states before the stability test used the
/// contact constraint limit, `contact::mechanics`).
const MAX_SADDLE_ESCAPES: usize = 10;

/// Most coarser meshes of a sequenced step (`DynamicSettings::coarse_levels`).
pub const MAX_COARSE_LEVELS: usize = 8;

/// Successive time-step failures at the same element after which a Dynamic step stops with a
/// diagnosis instead of cutting Δt further (each cut quarters it).
const FAILURE_STREAK: usize = 6;

/// Controls of a `Dynamic` step (SI units or any consistent set; times in the model's
/// time unit).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DynamicSettings {
    /// First time step.
    pub dt: f64,
    /// Smallest time step before the step fails with a diagnosis.
    pub dt_min: f64,
    /// Largest time step (large values let the iteration end as Newton's method).
    pub dt_max: f64,
    /// Time over which the load scales ramp from the previous step's values to this step's
    /// targets (0: applied at once).
    pub ramp_time: f64,
    /// Simulated time after which the step fails if the structure is not at rest.
    pub max_time: f64,
    /// Time steps after which the step fails if the structure is not at rest.
    pub max_steps: usize,
    /// Mass-proportional (Rayleigh) damping coefficient α_M (1/time): force α_M M u̇.
    pub mass_damping: f64,
    /// Scale on the director rotary inertia ρ_A h²/12 per area (1 = physical).
    pub rotary_inertia: f64,
    /// At rest when the kinetic energy ≤ kinetic_tol · max(strain energy, |f_ext·u|).
    pub kinetic_tol: f64,
    /// At rest when ‖f_int − f_ext‖ ≤ rest_residual_tol · max(‖f_ext‖, ‖f_int‖ incl. reactions).
    pub rest_residual_tol: f64,
    /// Factor on Δt after a step converged in at most 6 Newton iterations (Δt × 0.7 after
    /// more than 9).
    pub grow: f64,
    /// Newton iterations per time step before it is retried with Δt/4.
    pub max_iterations: usize,
    /// Rest also requires a stable equilibrium: the static tangent K, shifted by 1e-10·diag|K|
    /// against round-off, factors as LLᵀ.
    pub require_stable: bool,
    /// Time integration scheme.
    pub scheme: TimeScheme,
    /// Transient analysis: when > 0 the step ends (successfully) at this time instead of
    /// waiting for rest.
    pub duration: f64,
    /// Solve each backward-Euler step as the minimisation of its incremental potential
    /// (energy line search, PSD-projected element Hessians where the tangent is indefinite,
    /// inexact steps away from rest; see `time_step`). Default: on for steps to rest
    /// (`duration` 0) and with barrier contact, otherwise off (the safeguarded Newton
    /// update). Terms without a potential (friction other than the barrier's lagged one)
    /// fall back to the safeguarded update.
    pub incremental_potential: Option<bool>,
    /// Mesh sequencing (nested iteration) of a step to rest: solve it first to rest on the
    /// parts' grids coarsened `coarse_levels` times by 2 (elements per side halved, rounded
    /// up), map each rest state onto the next finer grid and continue there, the scene's
    /// own mesh last (`analysis_sequence`: mapped nodes pushed out of the bodies, directors
    /// relaxed with the mid-surface held, then the step goes on from rest). 0 (default):
    /// off. Only for the first step of a scene whose parts are all `Rectangle` grids.
    pub coarse_levels: usize,
}

impl Default for DynamicSettings {
    fn default() -> Self {
        Self {
            dt: 1e-3,
            dt_min: 1e-10,
            dt_max: 1e6,
            ramp_time: 0.0,
            max_time: 1e9,
            max_steps: 5000,
            mass_damping: 0.0,
            rotary_inertia: 1.0,
            kinetic_tol: 1e-10,
            rest_residual_tol: 1e-6,
            grow: 1.5,
            max_iterations: 12,
            require_stable: true,
            scheme: TimeScheme::BackwardEuler,
            duration: 0.0,
            incremental_potential: None,
            coarse_levels: 0,
        }
    }
}

/// The first invalid field of `ds` and what is expected there, if any.
pub fn check_settings(ds: &DynamicSettings) -> Option<(&'static str, &'static str)> {
    let pos = |x: f64| x.is_finite() && x > 0.0;
    if !pos(ds.dt) {
        Some(("dt", "expected a positive first time step"))
    } else if !pos(ds.dt_min) || ds.dt_min > ds.dt {
        Some(("dt_min", "expected a positive smallest time step no larger than dt"))
    } else if ds.dt_max.is_nan() || ds.dt_max < ds.dt {
        Some(("dt_max", "expected a largest time step no smaller than dt"))
    } else if !(ds.ramp_time.is_finite() && ds.ramp_time >= 0.0) {
        Some(("ramp_time", "expected a non-negative ramp time"))
    } else if !pos(ds.max_time) {
        Some(("max_time", "expected a positive maximum time"))
    } else if ds.max_steps == 0 {
        Some(("max_steps", "expected at least one time step"))
    } else if !(ds.mass_damping.is_finite() && ds.mass_damping >= 0.0) {
        Some(("mass_damping", "expected a non-negative damping coefficient (1/time)"))
    } else if !(ds.rotary_inertia.is_finite() && ds.rotary_inertia >= 0.0) {
        Some(("rotary_inertia", "expected a non-negative scale"))
    } else if !pos(ds.kinetic_tol) {
        Some(("kinetic_tol", "expected a positive tolerance"))
    } else if !pos(ds.rest_residual_tol) {
        Some(("rest_residual_tol", "expected a positive tolerance"))
    } else if !(ds.grow.is_finite() && ds.grow >= 1.0) {
        Some(("grow", "expected a growth factor of at least 1"))
    } else if ds.max_iterations == 0 {
        Some(("max_iterations", "expected at least one iteration"))
    } else if matches!(ds.scheme, TimeScheme::GeneralizedAlpha { rho_inf } if !(0.0..=1.0).contains(&rho_inf)) {
        Some(("scheme", "expected a spectral radius rho_inf in [0, 1]"))
    } else if !(ds.duration.is_finite() && ds.duration >= 0.0) {
        Some(("duration", "expected a non-negative duration (0: run to rest)"))
    } else if ds.coarse_levels > MAX_COARSE_LEVELS {
        Some(("coarse_levels", "expected at most 8 coarser meshes (each halves the elements per side)"))
    } else if ds.coarse_levels > 0 && (ds.duration > 0.0 || !matches!(ds.scheme, TimeScheme::BackwardEuler)) {
        Some(("coarse_levels", "mesh sequencing is for backward-Euler steps to rest (duration 0): a transient path cannot be mapped between meshes"))
    } else {
        None
    }
}

/// What to add to a not-at-rest message when rest criteria were met at unstable equilibria.
fn unstable_note(unstable_rests: usize) -> String {
    if unstable_rests == 0 {
        String::new()
    } else {
        format!(
            "; {unstable_rests} time steps met the rest criteria at an unstable equilibrium (static tangent not positive definite: a mechanism or a saddle); `require_stable: false` accepts such a state"
        )
    }
}

impl<'m> Solver<'m> {
    /// Relative static residual ‖f_int − f_ext‖ / max(‖f_ext‖, ‖f_int‖) of `state` at load
    /// scales `scales` (prescribed values applied first); reactions are then available from
    /// [`Solver::internal_force`].
    pub fn static_residual(&mut self, state: &mut State, scales: &[f64]) -> Result<f64, String> {
        self.model.apply_prescribed(state, scales);
        self.assemble(state, scales, false).map_err(|f| f.to_string())?;
        let mut r = vec![0.0; self.model.dofs.n_free];
        Ok(self.residual(&mut r).0)
    }

    /// Integrates step `si` (a `Dynamic` step) from `start` load scales to the step's targets
    /// until rest. Every accepted time step is reported through `on_increment` (increment =
    /// time-step number); on failure `state` holds the last accepted time step.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn run_dynamic_step(
        &mut self,
        si: usize,
        step: &StepPlan,
        ds: &DynamicSettings,
        start: &[f64],
        state: &mut State,
        on_increment: &mut dyn FnMut(&IncrementReport, &State, &Self),
        progress: &mut dyn FnMut(&Progress),
        fraction_done: f64,
        fraction_step: f64,
    ) -> Result<(), SolveError> {
        let model = self.model;
        let minimising = self.incremental_potential(ds) && ds.duration == 0.0;
        let mass = if minimising { LumpedMass::for_rest(model, ds.rotary_inertia) } else { LumpedMass::from_model(model, ds.rotary_inertia) };
        let error = |iteration: usize, residuals: Vec<f64>, worst_element: Option<usize>, cause: String, t: f64| SolveError {
            step: si,
            step_name: step.name.clone(),
            last_converged_time: si as f64 + (t / ds.max_time).min(0.999_999),
            simulated_time: Some(t),
            iteration,
            residuals,
            worst_element,
            cause,
        };
        if let Some((key, msg)) = check_settings(ds) {
            return Err(error(0, vec![], None, format!("invalid Dynamic setting {key}: {msg}"), 0.0));
        }
        let free_mass = model.dofs.eq.iter().enumerate().any(|(g, &e)| {
            let m = if g % NODE_DOFS < 3 { mass.translational[g / NODE_DOFS] } else { mass.rotary[g / NODE_DOFS] };
            e != FIXED && m > 0.0
        });
        if !free_mass {
            return Err(error(
                0,
                vec![],
                None,
                "a Dynamic step needs mass: give the parts an `areal_density` (or a Gravity load, whose density is used)".into(),
                0.0,
            ));
        }
        let at = |t: f64| -> Vec<f64> {
            let tau = if ds.ramp_time > 0.0 { (t / ds.ramp_time).min(1.0) } else { 1.0 };
            start.iter().zip(&step.target_scales).map(|(a, b)| a + tau * (b - a)).collect()
        };
        let nn = model.n_nodes();
        let zeros = vec![Vector3::zeros(); nn];
        let mut prev = Kinematics { state: state.clone(), v: zeros.clone(), a: zeros.clone(), w: zeros.clone(), wa: zeros, r: vec![0.0; model.dofs.n_free] };
        if matches!(ds.scheme, TimeScheme::GeneralizedAlpha { .. }) {
            // The force average needs the static residual r₀ of the initial state, and the
            // initial acceleration follows from the equation of motion, M a₀ = −r₀ (loads at
            // t = 0⁺, the state at rest).
            let first = at(0.0);
            if let Err(f) = self.assemble(state, &first, false) {
                return Err(error(0, vec![], Some(f.element), f.to_string(), 0.0));
            }
            self.residual(&mut prev.r);
            let eq = &model.dofs.eq;
            for n in 0..nn {
                let fr = &state.frames[n];
                let mut torque = Vector3::zeros();
                for k in 0..5 {
                    let e = eq[NODE_DOFS * n + k];
                    if e == FIXED {
                        continue;
                    }
                    match k {
                        0..=2 if mass.translational[n] > 0.0 => prev.a[n][k] = -prev.r[e] / mass.translational[n],
                        3 => torque += fr.t1 * prev.r[e],
                        4 => torque += fr.t2 * prev.r[e],
                        _ => {}
                    }
                }
                if mass.rotary[n] > 0.0 {
                    prev.wa[n] = -torque / mass.rotary[n];
                }
            }
        }
        let clock0 = self.clock;
        // A step to rest does not end before the bodies' prescribed motion does (within the
        // step's clock window, if it has one: it then ends no earlier than the window).
        let motion_end = match step.clock {
            Some([s, e]) => e - s,
            None => self.motion_end() - clock0,
        };
        let mut t = 0.0;
        let mut dt = ds.dt;
        let mut rejected = 0usize;
        let mut rejections: Vec<String> = Vec::new();
        let mut iterations = 0usize;
        let mut unstable_rests = 0usize;
        let mut saddle_escapes = 0usize;
        let mut indefinite = false;
        // (element, successive time-step failures at it) since the last accepted step.
        let mut failure_streak: (Option<usize>, usize) = (None, 0);
        for k in 1..=ds.max_steps {
            let scales = at(t + dt);
            let mut report_progress = |it: usize, res: f64| {
                progress(&Progress { step: si, fraction: fraction_done + fraction_step * ((t + dt) / ds.max_time).min(1.0), iteration: it, residual: res, dynamic: Some((t + dt, k)) })
            };
            // Predictor: constant velocity would overshoot at rest; start from the last state.
            *state = prev.state.clone();
            self.begin_nodal_increment(dt / ds.dt);
            self.begin_nodal_motion(step.dynamic_clock(clock0, t + dt), state);
            let outcome = self.time_step(state, &prev, &mass, dt, ds, &scales, &mut report_progress);
            match outcome {
                TimeStep::Converged { iterations: its, residuals, static_residual, energy, static_r } => {
                    failure_streak = (None, 0);
                    iterations += its;
                    self.commit_nodal_forces(state);
                    let co = Coefficients::new(&ds.scheme, dt, ds.mass_damping);
                    let mut ke = 0.0;
                    let (mut v, mut a, mut w, mut wa) = (prev.v.clone(), prev.a.clone(), prev.w.clone(), prev.wa.clone());
                    for n in 0..nn {
                        (a[n], v[n]) = co.rates(state.u[n] - prev.state.u[n], prev.v[n], prev.a[n]);
                        (wa[n], w[n]) = co.rates(state.frames[n].d - prev.state.frames[n].d, prev.w[n], prev.wa[n]);
                        ke += 0.5 * (mass.translational[n] * v[n].norm_squared() + mass.rotary[n] * w[n].norm_squared());
                    }
                    let work: f64 = (0..nn).map(|n| (0..3).map(|c| self.f_ext[NODE_DOFS * n + c] * state.u[n][c]).sum::<f64>()).sum();
                    let e_ref = energy.abs().max(work.abs()).max(1e-300);
                    t += dt;
                    let still = t >= ds.ramp_time && t >= motion_end && ke <= ds.kinetic_tol * e_ref && static_residual <= ds.rest_residual_tol;
                    // A saddle (e.g. a flat sheet past its wrinkling threshold) is no rest state:
                    // integration goes on and the unstable mode grows from round-off.
                    let mut at_rest = still && (!ds.require_stable || self.stable(state, &scales));
                    // An unstable equilibrium is left along its unstable mode (module doc).
                    let mut moved = None;
                    let mut static_residual = static_residual;
                    let saddle = if still && !at_rest {
                        unstable_rests += 1;
                        let mut off = state.clone();
                        let escape = if ds.duration == 0.0 && saddle_escapes < MAX_SADDLE_ESCAPES { self.escape_saddle(&mut off, &scales, &mass) } else { None };
                        if let Some((omega2, size, settled)) = escape {
                            saddle_escapes += 1;
                            // The moves ended at a stable state: if it is an equilibrium within
                            // the rest tolerance, it is the rest state (at rest, no velocity).
                            let residual_there = if settled { self.static_residual(&mut off, &scales).ok() } else { None };
                            match residual_there {
                                Some(r) if r <= ds.rest_residual_tol && self.stable(&off, &scales) => {
                                    *state = off;
                                    static_residual = r;
                                    ke = 0.0;
                                    at_rest = true;
                                }
                                _ => moved = Some(off),
                            }
                            Some((omega2, size))
                        } else {
                            None
                        }
                    } else {
                        None
                    };
                    let end_of_step = at_rest || (ds.duration > 0.0 && t >= ds.duration * (1.0 - 1e-12));
                    let report = IncrementReport {
                        step: si,
                        step_name: step.name.clone(),
                        increment: k,
                        time: si as f64 + if end_of_step { 1.0 } else { (t / ds.max_time).min(0.999_999) },
                        scales: scales.clone(),
                        iterations,
                        residuals,
                        cutbacks: rejected,
                        indefinite_tangent: indefinite,
                        energy,
                        dynamics: Some(DynamicInfo { time: t, dt, kinetic_energy: ke, static_residual, at_rest, end_of_step, rejected, rejections: std::mem::take(&mut rejections), unstable_rests, saddle_escapes, saddle }),
                        extra: std::mem::take(&mut self.extra_reports),
                        ..Default::default()
                    };
                    on_increment(&report, state, self);
                    if end_of_step {
                        return Ok(());
                    }
                    iterations = 0;
                    rejected = 0;
                    indefinite = false;
                    prev = Kinematics { state: state.clone(), v, a, w, wa, r: static_r };
                    if let Some(off) = moved {
                        // Moved off the saddle: integrate on from rest there.
                        *state = off;
                        prev.state = state.clone();
                        for x in [&mut prev.v, &mut prev.a, &mut prev.w, &mut prev.wa] {
                            x.iter_mut().for_each(|v| *v = Vector3::zeros());
                        }
                        if self.assemble(state, &scales, false).is_ok() {
                            self.residual(&mut prev.r);
                        }
                    }
                    if its <= 6 {
                        dt = (dt * ds.grow).min(ds.dt_max);
                    } else if its > 9 {
                        dt *= 0.7;
                    }
                    if ds.duration > 0.0 {
                        dt = dt.min(ds.duration - t).max(1e-12 * ds.duration);
                    }
                    if t >= ds.max_time {
                        return Err(error(
                            k,
                            vec![static_residual],
                            None,
                            format!(
                                "not at rest after the maximum time {:.3e} (kinetic energy {ke:.3e} of reference {e_ref:.3e}, static residual {static_residual:.3e}); raise max_time or add mass_damping{}",
                                ds.max_time,
                                unstable_note(unstable_rests)
                            ),
                            t,
                        ));
                    }
                }
                TimeStep::Failed { iteration, residuals, worst_element, cause }
                    if worst_element.is_some() && cause.contains("failed:") && failure_streak.0 == worst_element && failure_streak.1 + 1 >= FAILURE_STREAK =>
                {
                    // The same element failed at every one of the last time-step cuts: a
                    // smaller Δt does not cure it (4⁻⁶ of the Δt it first failed at).
                    let cause = format!(
                        "time step {k} at t = {t:.4e}: element {} failed at {FAILURE_STREAK} successive time-step cuts down to Δt = {dt:.3e}: {cause}",
                        worst_element.unwrap_or(0)
                    );
                    let cause = diagnose::explain_dynamic(model, &prev.state, &cause, worst_element);
                    *state = prev.state.clone();
                    return Err(error(iteration, residuals, worst_element, cause, t));
                }
                TimeStep::Indefinite { .. } | TimeStep::Failed { .. } if dt * 0.25 >= ds.dt_min => {
                    match &outcome {
                        TimeStep::Failed { worst_element, cause, .. } if worst_element.is_some() && cause.contains("failed:") => {
                            failure_streak = if failure_streak.0 == *worst_element { (*worst_element, failure_streak.1 + 1) } else { (*worst_element, 1) };
                        }
                        _ => failure_streak = (None, 0),
                    }
                    indefinite |= matches!(outcome, TimeStep::Indefinite { .. });
                    // The rejected step's iterations are spent work: count them.
                    iterations += match &outcome {
                        TimeStep::Indefinite { iteration, .. } | TimeStep::Failed { iteration, .. } => *iteration,
                        TimeStep::Converged { .. } => 0,
                    };
                    rejections.push(match &outcome {
                        TimeStep::Indefinite { iteration, projected, .. } => format!(
                            "Δt = {dt:.3e}: effective tangent not positive definite at iteration {iteration}{}",
                            if *projected { " with the element and contact Hessians projected" } else { " (no potential: not projected)" }
                        ),
                        TimeStep::Failed { iteration, worst_element, cause, .. } => match worst_element {
                            Some(el) => format!("Δt = {dt:.3e}: {cause} (iteration {iteration}, element {el})"),
                            None => format!("Δt = {dt:.3e}: {cause} (iteration {iteration})"),
                        },
                        TimeStep::Converged { .. } => String::new(),
                    });
                    *state = prev.state.clone();
                    self.assembler.forget_mixed();
                    rejected += 1;
                    dt *= 0.25;
                }
                TimeStep::Indefinite { iteration, residuals, .. } => {
                    let cause = format!(
                        "time step {k} at t = {t:.4e}: effective tangent K + M/Δt² not positive definite even at Δt = {dt:.3e} ≤ 4 dt_min"
                    );
                    let cause = diagnose::explain(model, state, &cause, true);
                    *state = prev.state.clone();
                    let el = diagnose::worst_distortion(model, state).map(|w| w.0);
                    return Err(error(iteration, residuals, el, cause, t));
                }
                TimeStep::Failed { iteration, residuals, worst_element, cause } => {
                    let cause = format!("time step {k} at t = {t:.4e}, Δt = {dt:.3e} (below 4 dt_min after cut-backs): {cause}");
                    let cause = diagnose::explain_dynamic(model, &prev.state, &cause, worst_element);
                    *state = prev.state.clone();
                    return Err(error(iteration, residuals, worst_element, cause, t));
                }
            }
        }
        Err(error(
            ds.max_steps,
            vec![],
            None,
            format!("not at rest after max_steps = {} time steps (t = {t:.4e}); raise max_steps, dt_max or mass_damping{}", ds.max_steps, unstable_note(unstable_rests)),
            t,
        ))
    }
}
