//! Automatic load incrementation of static steps (`automatic_increments: true`; Crisfield
//! 1991, §9.4–9.5): increment sizes that follow the Newton iteration counts, an extrapolating
//! predictor, and early cut-back on divergence.

use super::linear::FactorKind;
use super::newton::{Attempt, IncrementReport, Progress, SolveError, Solver, StepPlan};
use crate::model::State;

/// Extrapolating predictor of an automatic increment (Crisfield 1991, §9.4; the linear
/// extrapolation of general-purpose FE codes): `state`, converged at the current load level,
/// moves on by `ratio` × its change since `old` — translations linearly, each director by
/// `ratio` × the rotation that took its previous direction to the current one (applied to the
/// whole frame).
fn extrapolate(state: &mut State, old: &State, ratio: f64) {
    if !(ratio.is_finite() && ratio > 0.0) {
        return;
    }
    let ratio = ratio.min(4.0);
    for n in 0..state.u.len() {
        let du = state.u[n] - old.u[n];
        state.u[n] += du * ratio;
        let (d0, d1) = (old.frames[n].d, state.frames[n].d);
        let axis = d0.cross(&d1);
        let s = axis.norm();
        if s > 1e-14 {
            let angle = s.atan2(d0.dot(&d1));
            let r = nalgebra::Rotation3::from_scaled_axis(axis * (angle * ratio / s));
            state.frames[n] = state.frames[n].rotated(&r);
        }
    }
}

/// Consecutive failed attempts after a converged increment (each retried at a quarter of the
/// increment, so the last at 4⁻⁴ of the one that last converged) after which a Static step
/// leaves plain Newton for the
/// damped iteration, and the damped iteration for the pseudo-transient step to rest, instead
/// of cutting on to `max_cutbacks` quarterings of the first increment. Measured on the 5 mm
/// two-ply flap with barrier inter-ply contact: the ten plain and ten damped cut-backs that
/// preceded its pseudo-transient fallback took 13 of its 20 s.
const FALLBACK_AFTER: usize = 4;

impl Solver<'_> {
    /// Automatic load incrementation of a static step (Crisfield 1991, §9.5; Abaqus-style
    /// automatic increments): the first increment is 1/`increments` of the step, an increment
    /// that converged within 8 iterations doubles the next (within 12: ×1.5; above 18: ×½),
    /// and a failed one — stopped early when divergence shows ([`Solver::attempt`]) — is
    /// retried at a quarter of its size. Every converged increment is reported; the step ends
    /// exactly at its target scales. Returns the scales reached.
    ///
    /// Where plain Newton would give up — the increment cut [`FALLBACK_AFTER`] times in a row
    /// after the step has moved (or below `max_cutbacks` quarterings of the first increment)
    /// in a model
    /// supported against every rigid motion (not a mechanism: a limit or bifurcation point
    /// passed, wrinkling, plies sliding over each other, contact's round-off) —
    /// the rest of the step runs damped Newton (the `StaticDamped` iteration, Levenberg–
    /// Marquardt, [`Solver::attempt_damped`]) from the step's first increment size, before
    /// the step is given up. Measured: a two-ply flap hanging under its weight with barrier
    /// inter-ply contact stopped at 42 % of its load with the increment cut to 2.7·10⁻⁷ of
    /// the step (residual at 10⁻⁷–10⁻⁶ for 30 iterations); with the fallback it completes.
    ///
    /// Where damped Newton gives up too (cut [`FALLBACK_AFTER`] times in a row), the converged state the
    /// step stands at is left by a descent that does not end within an increment's
    /// iterations — an unstable equilibrium (a saddle) whose next stable one lies a snap away
    /// — and the rest of the step runs as a pseudo-transient `Dynamic` step to rest from it
    /// (default [`super::DynamicSettings`]: backward Euler with the mass for rest, from the
    /// last converged load level to the step's targets, applied at once, until the kinetic
    /// energy and the residual (10⁻⁶) vanish; [`Solver::run_dynamic_step`], whose time steps
    /// are reported as the step's increments). Measured: the two-ply flap
    /// meshed at 5 mm with its barrier inter-ply contact, whose Static step stood at 8.4 % of
    /// its weight after both fallbacks (the damped iteration walking off the state by up to
    /// 0.6 m in 100 iterations without settling), comes to rest under its full weight.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn run_automatic(
        &mut self,
        si: usize,
        step: &StepPlan,
        start: &[f64],
        state: &mut State,
        tracker: &mut super::arclength::StabilityTracker,
        on_increment: &mut dyn FnMut(&IncrementReport, &State, &Self),
        progress: &mut dyn FnMut(&Progress),
    ) -> Result<Vec<f64>, SolveError> {
        let at = |tau: f64| -> Vec<f64> { start.iter().zip(&step.target_scales).map(|(a, b)| a + tau * (b - a)).collect() };
        let clock0 = self.clock;
        let mut tau = 0.0f64;
        let first_dtau = 1.0 / step.increments.max(1) as f64;
        let mut dtau = first_dtau;
        // Damped Newton for the rest of the step (the fallback above).
        let mut damped = false;
        let min_dtau = dtau * 0.25f64.powi(self.settings.max_cutbacks as i32);
        let mut inc = 0;
        let mut iterations = 0;
        let mut cutbacks = 0;
        // Failed attempts since the last converged increment (or since the switch to the
        // damped iteration): the fallbacks start after FALLBACK_AFTER of them.
        let mut failures_in_row = 0;
        let mut indefinite = false;
        // The previous converged state and its load level, for the extrapolating predictor.
        let mut previous: Option<(State, f64)> = None;
        // The step's time-averaged force scale (mean over its converged increments) and the
        // force scale of the current attempt ([`Solver::attempt`]).
        let (mut force_sum, mut converged) = (0.0, 0usize);
        let mut force_scale = (0.0, 0.0);
        loop {
            let next = if tau + dtau >= 1.0 - 1e-9 { 1.0 } else { tau + dtau };
            let trial_scales = at(next);
            let saved = state.clone();
            let tau_start = tau;
            if let Some((old, tau_old)) = &previous {
                extrapolate(state, old, (next - tau) / (tau - tau_old));
            }
            let mut report_progress = |it: usize, res: f64| progress(&Progress { step: si, fraction: next, iteration: it, residual: res, dynamic: None });
            self.begin_nodal_increment((next - tau) * step.increments.max(1) as f64);
            self.begin_nodal_motion(step.static_clock(clock0, next), state);
            force_scale.0 = if converged > 0 { force_sum / converged as f64 } else { 0.0 };
            let outcome = if damped {
                self.attempt_damped(state, &trial_scales, &mut report_progress)
            } else {
                self.attempt(state, &trial_scales, false, Some(&mut force_scale), &mut report_progress)
            };
            match outcome {
                Attempt::Converged { iterations: its, residuals, indefinite: ind, energy } => {
                    if !damped {
                        force_sum += force_scale.1;
                        converged += 1;
                    }
                    iterations += its;
                    indefinite |= ind;
                    tau = next;
                    inc += 1;
                    self.commit_nodal_forces(state);
                    let stability = self.stability_at(state, start, &step.target_scales, tracker);
                    let mut report = self.static_report(si, step, inc, tau, &trial_scales, (iterations, residuals, cutbacks, indefinite, energy), stability);
                    report.damped = damped;
                    on_increment(&report, state, self);
                    if tau >= 1.0 {
                        return Ok(trial_scales);
                    }
                    previous = Some((saved, tau_start));
                    iterations = 0;
                    cutbacks = 0;
                    failures_in_row = 0;
                    indefinite = false;
                    dtau *= match its {
                        0..=8 => 2.0,
                        9..=12 => 1.5,
                        13..=18 => 1.0,
                        _ => 0.5,
                    };
                }
                Attempt::Failed { iteration, residuals, worst_element, cause } => {
                    *state = saved;
                    self.assembler.forget_mixed();
                    iterations += iteration;
                    cutbacks += 1;
                    failures_in_row += 1;
                    dtau *= 0.25;
                    let spent = dtau < min_dtau * (1.0 - 1e-9);
                    // In a row only once the step has moved: before its first converged
                    // increment the cut-backs search for an increment size that works.
                    let stalled = spent || (inc > 0 && failures_in_row >= FALLBACK_AFTER);
                    if stalled && !damped && super::diagnose::unsupported_directions(self.model).is_empty() {
                        damped = true;
                        dtau = first_dtau;
                        failures_in_row = 0;
                        continue;
                    }
                    if stalled && damped {
                        // The pseudo-transient fallback above; its time steps take the
                        // consistent (not mixed-stress) tangent, as a Dynamic step does.
                        self.assembler.mixed = false;
                        self.assembler.forget_mixed();
                        let ds = super::DynamicSettings::default();
                        // Its time steps continue the step's increments: numbered on, their
                        // times (the step index plus the fraction t / max_time of the
                        // Dynamic step, 1 at rest) mapped onto the rest of the step.
                        let (tau0, inc0) = (tau, inc);
                        let mut relaxed = |r: &IncrementReport, s: &State, solver: &Self| {
                            let mut r = r.clone();
                            r.increment += inc0;
                            r.time = si as f64 + tau0 + (1.0 - tau0) * (r.time - si as f64);
                            on_increment(&r, s, solver);
                        };
                        self.run_dynamic_step(si, step, &ds, &at(tau), state, &mut relaxed, progress, 0.0, 1.0)?;
                        return Ok(step.target_scales.clone());
                    }
                    if spent {
                        let cause = super::diagnose::explain(self.model, state, &cause, indefinite || self.cholesky.kind() == FactorKind::Ldlt);
                        let cause = format!("{cause}; automatic increment cut to {:.3e} of the step (max_cutbacks = {} quarterings of the first)", dtau * 4.0, self.settings.max_cutbacks);
                        return Err(SolveError::static_increment(si, step, tau, iteration, residuals, worst_element, cause));
                    }
                }
            }
        }
    }
}
