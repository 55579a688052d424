//! Path following through limit points: arc-length and displacement control, and the
//! stability information (inertia, current stiffness parameter) reported per increment.
//!
//! The load is proportional within a step: scales = start + λ (target − start), so the
//! external force is F(λ) = F_start + λ f with f the step's load change (configuration-
//! dependent moments are re-evaluated in the current state). Each increment solves
//! r(u, λ) = f_int(u) − F(λ) = 0 together with one constraint:
//! - arc length (Crisfield 1981, "cylindrical"): ‖Δu‖² = Δl², the norm taken over the free
//!   translations only (tilts are dimensionless). Each corrector solves K δu_r = −r and
//!   K δu_t = f, sets δu = δu_r + δλ δu_t and takes δλ from the quadratic
//!   a δλ² + b δλ + c = 0; of its two roots the one keeping δu closest to the direction of
//!   the increment so far (largest (Δu + δu)·Δu) is chosen. Complex roots fall back to the
//!   updated normal plane, δλ = −(Δu·δu_r)/(Δu·δu_t) (Ramm 1981).
//! - displacement control (Batoz & Dhatt 1979): the controlled DOF is moved by the
//!   predictor only, δλ = −δu_r(c) / δu_t(c) in every corrector.
//!
//! Predictor: Δλ₀ = ± Δl / ‖δu_t‖, the sign from the previous converged increment,
//! sign(Δu_prev·δu_t) (Feng, Perić & Owen 1996), and on the first increment from the sign
//! of det K, i.e. (−1)^(negative pivots). The arc length adapts to the iteration count,
//! Δl ← Δl √(N_desired/N), clamped to [Δl/2, 2Δl] and the step's bounds; a failed increment is
//! retried with half the arc length until the minimum.
//!
//! Stability: after each converged increment the tangent is factorized once more; its
//! negative pivots (Sylvester inertia, see `SparseCholesky::negative_pivots`) and the
//! current stiffness parameter S_p = (f·K⁻¹f)₁/(f·K⁻¹f) (Bergan, Horrigmoe, Bråkeland &
//! Søreide 1978) are reported. A change of the pivot count with a sign change of S_p is a
//! limit point (the critical mode is not orthogonal to f, f·K⁻¹f passes through ±∞); a
//! change without one is a bifurcation (the mode is orthogonal to f). A sign change of S_p
//! with an unchanged pivot count is no critical point: f·K⁻¹f passes through zero, the
//! displacement conjugate to f turns back (the turning points of a snap-back).

use std::time::Instant;

use super::newton::{Attempt, IncrementReport, Progress, SolveError, Solver, StepPlan};
use super::StepKind;
use crate::element::NODE_DOFS;
use crate::model::{State, FIXED};

/// Negative-pivot count and stiffness-parameter sign carried from increment to increment.
#[derive(Clone, Debug, Default)]
pub struct StabilityTracker {
    previous_pivots: Option<usize>,
    previous_sign: Option<f64>,
    reference: Option<f64>,
}

impl StabilityTracker {
    /// A new step: the stiffness parameter is normalised again (its load vector changes),
    /// the pivot count carries over.
    pub fn new_step(&mut self) {
        self.previous_sign = None;
        self.reference = None;
    }

    /// Records the inertia and f·K⁻¹f of a converged state; returns S_p and the event.
    fn record(&mut self, pivots: usize, fkf: Option<f64>) -> (Option<f64>, Option<String>) {
        let sp = fkf.and_then(|v| {
            let r = *self.reference.get_or_insert(v);
            (v != 0.0 && r != 0.0).then(|| r / v)
        });
        let sign = sp.map(f64::signum);
        let sign_flip = matches!((self.previous_sign, sign), (Some(a), Some(b)) if a != b);
        let changed = self.previous_pivots.is_some_and(|p| p != pivots);
        let event = match (changed, sign_flip) {
            (true, true) => Some(format!(
                "limit point: S_p changed sign, negative pivots {} -> {pivots}",
                self.previous_pivots.map_or("?".into(), |p| p.to_string())
            )),
            (false, true) => Some(format!(
                "displacement turning point (snap-back): S_p changed sign through infinity with {pivots} negative pivots; not a critical point"
            )),
            (true, false) => Some(format!(
                "bifurcation: negative pivots {} -> {pivots} without a sign change of S_p",
                self.previous_pivots.map_or("?".into(), |p| p.to_string())
            )),
            (false, false) => None,
        };
        self.previous_pivots = Some(pivots);
        if sign.is_some() {
            self.previous_sign = sign;
        }
        (sp, event)
    }
}

/// Outcome of one path-following increment.
enum PathAttempt {
    Converged { iterations: usize, residuals: Vec<f64>, energy: f64, indefinite: bool },
    Failed { iteration: usize, residuals: Vec<f64>, worst_element: Option<usize>, cause: String },
}

/// The constraint closing the equations of one increment.
#[derive(Clone, Copy)]
enum Constraint {
    /// ‖Δu‖ = length over the free translations.
    Arc { length: f64 },
    /// The equation `eq` moves by `delta` in the increment.
    Displacement { eq: usize, delta: f64 },
}

impl<'m> Solver<'m> {
    /// Free-DOF load vector f = F(target) − F(start) in `state`.
    pub(super) fn load_change(&mut self, state: &State, start: &[f64], target: &[f64]) -> Vec<f64> {
        let eq = &self.model.dofs.eq;
        let mut f = vec![0.0; self.model.dofs.n_free];
        self.model.external_force(state, target, &mut self.f_ext);
        for (g, &e) in eq.iter().enumerate() {
            if e != FIXED {
                f[e] = self.f_ext[g];
            }
        }
        self.model.external_force(state, start, &mut self.f_ext);
        for (g, &e) in eq.iter().enumerate() {
            if e != FIXED {
                f[e] -= self.f_ext[g];
            }
        }
        f
    }

    /// 1 for free translations, 0 for tilts: the arc-length metric.
    fn translation_mask(&self) -> Vec<f64> {
        let mut m = vec![0.0; self.model.dofs.n_free];
        for (g, &e) in self.model.dofs.eq.iter().enumerate() {
            if e != FIXED && g % NODE_DOFS < 3 {
                m[e] = 1.0;
            }
        }
        m
    }

    /// Factorizes the tangent currently held in `values` (assembled at `state`) and returns
    /// its negative pivots and f·K⁻¹f, or None when it is singular.
    fn factor_and_probe(&mut self, f: &[f64]) -> Option<(usize, f64, Vec<f64>)> {
        let t = Instant::now();
        let ok = self.cholesky.factorize(&self.values).is_ok();
        self.timings.factorization += t.elapsed().as_secs_f64();
        if !ok {
            return None;
        }
        let pivots = self.cholesky.negative_pivots();
        let t = Instant::now();
        let mut v = f.to_vec();
        self.cholesky.solve(&mut v);
        self.timings.solve += t.elapsed().as_secs_f64();
        let fkf: f64 = v.iter().zip(f).map(|(a, b)| a * b).sum();
        fkf.is_finite().then_some((pivots, fkf, v))
    }

    /// Likely cause of a failed increment from the last factorized tangent: its inertia and
    /// pivot range.
    fn tangent_diagnosis(&self) -> String {
        let neg = self.cholesky.negative_pivots();
        let ratio = self.cholesky.pivot_ratio();
        if ratio < 1e-13 {
            format!("likely cause: nearly singular tangent (smallest/largest pivot {ratio:.1e}, {neg} negative): a mechanism, missing support, or a critical point hit exactly")
        } else if neg > 0 {
            format!("likely cause: indefinite tangent ({neg} negative pivots) and a too long step; smallest/largest pivot {ratio:.1e}")
        } else {
            format!("likely cause: strong nonlinearity for this step length (tangent positive definite, smallest/largest pivot {ratio:.1e})")
        }
    }

    /// Inertia and current stiffness parameter of a converged state whose tangent is in
    /// `values` (the last assembly), for the load change of a step from `start` to
    /// `target`; returns (negative pivots, S_p, event).
    pub(super) fn stability_at(
        &mut self,
        state: &State,
        start: &[f64],
        target: &[f64],
        tracker: &mut StabilityTracker,
    ) -> (Option<usize>, Option<f64>, Option<String>) {
        let f = self.load_change(state, start, target);
        let nonzero = f.iter().any(|v| *v != 0.0);
        match self.factor_and_probe(&f) {
            Some((p, fkf, _)) => {
                let (sp, ev) = tracker.record(p, nonzero.then_some(fkf));
                (Some(p), sp, ev)
            }
            None => (None, None, Some("singular tangent at the converged state".into())),
        }
    }

    /// Runs an arc-length or displacement-control step from `start` scales; returns the
    /// scales reached. Each converged increment is reported with its load factor.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn run_path(
        &mut self,
        si: usize,
        step: &StepPlan,
        start: &[f64],
        state: &mut State,
        tracker: &mut StabilityTracker,
        on_increment: &mut dyn FnMut(&IncrementReport, &State, &Self),
        progress: &mut dyn FnMut(&Progress),
    ) -> Result<Vec<f64>, SolveError> {
        let scales_at = |lam: f64| -> Vec<f64> { start.iter().zip(&step.target_scales).map(|(a, b)| a + lam * (b - a)).collect() };
        let mask = self.translation_mask();
        let n_inc = step.increments.max(1);
        let mut lambda = 0.0;
        let mut prev_du: Option<Vec<f64>> = None;
        let mut last_time = si as f64;
        let error = |iteration, residuals, worst_element, cause: String, time| SolveError {
            step: si,
            step_name: step.name.clone(),
            last_converged_time: time,
            simulated_time: None,
            iteration,
            residuals,
            worst_element,
            cause,
        };
        match step.kind.clone() {
            StepKind::ArcLength { length, min_length, max_length, desired_iterations, max_load_factor, max_displacement } => {
                let lo = min_length.unwrap_or(length / 1000.0);
                let hi = max_length.unwrap_or(10.0 * length);
                let mut dl = length;
                let mut cutbacks = 0;
                for inc in 1..=n_inc {
                    let mut iterations = 0;
                    let saved = state.clone();
                    let frac = inc as f64 / n_inc as f64;
                    let outcome = loop {
                        let mut report = |it: usize, res: f64| progress(&Progress { step: si, fraction: frac, iteration: it, residual: res, dynamic: None });
                        self.begin_nodal_increment(dl / length);
                        let attempt = self.path_increment(state, start, &step.target_scales, lambda, Constraint::Arc { length: dl }, prev_du.as_deref(), &mask, &mut report);
                        match attempt {
                            (PathAttempt::Converged { iterations: its, residuals, energy, indefinite }, dlam, du) => {
                                iterations += its;
                                break Ok((its, residuals, energy, indefinite, dlam, du));
                            }
                            (PathAttempt::Failed { iteration, residuals, worst_element, cause }, _, _) => {
                                *state = saved.clone();
                                self.assembler.forget_mixed();
                                iterations += iteration;
                                cutbacks += 1;
                                dl *= 0.5;
                                if dl < lo || cutbacks > self.settings.max_cutbacks {
                                    break Err(error(
                                        iteration,
                                        residuals,
                                        worst_element,
                                        format!("{cause}; arc length cut back to {dl:.3e} (minimum {lo:.3e}, {cutbacks} cut-backs) at load factor {lambda:.6}"),
                                        last_time,
                                    ));
                                }
                            }
                        }
                    };
                    let (mut its, mut residuals, mut energy, mut indefinite, mut dlam, du) = outcome?;
                    if (lambda + dlam).abs() > max_load_factor && lambda.abs() < max_load_factor {
                        // The increment passed the target load factor: solve the last part by
                        // load control to exactly ±max_load_factor from the previous state (on the
                        // branch just followed); keep the arc-length result if that fails.
                        let arc_state = std::mem::replace(state, saved.clone());
                        let target = (lambda + dlam).signum() * max_load_factor;
                        let mut report = |it: usize, res: f64| progress(&Progress { step: si, fraction: frac, iteration: it, residual: res, dynamic: None });
                        match self.attempt(state, &scales_at(target), false, None, &mut report) {
                            Attempt::Converged { iterations: k, residuals: r, indefinite: ind, energy: e } => {
                                iterations += k;
                                (its, residuals, energy, indefinite, dlam) = (k, r, e, indefinite || ind, target - lambda);
                            }
                            Attempt::Failed { iteration, .. } => {
                                iterations += iteration;
                                *state = arc_state;
                            }
                        }
                    }
                    self.commit_nodal_forces(state);
                    lambda += dlam;
                    let scales = scales_at(lambda);
                    let (negative_pivots, stiffness_parameter, stability_event) = self.stability_at(state, start, &step.target_scales, tracker);
                    last_time = si as f64 + frac;
                    let report = IncrementReport {
                        step: si,
                        step_name: step.name.clone(),
                        increment: inc,
                        time: last_time,
                        scales: scales.clone(),
                        iterations,
                        residuals,
                        cutbacks,
                        indefinite_tangent: indefinite,
                        energy,
                        load_factor: Some(lambda),
                        negative_pivots,
                        stiffness_parameter,
                        stability_event,
                        extra: std::mem::take(&mut self.extra_reports),
                        ..Default::default()
                    };
                    on_increment(&report, state, self);
                    cutbacks = 0;
                    prev_du = Some(du);
                    let ratio = (desired_iterations as f64 / its.max(1) as f64).sqrt().clamp(0.5, 2.0);
                    dl = (dl * ratio).clamp(lo, hi);
                    let umax = state.u.iter().map(|u| u.norm()).fold(0.0, f64::max);
                    if lambda.abs() >= max_load_factor || max_displacement.is_some_and(|d| umax >= d) {
                        return Ok(scales);
                    }
                }
                Ok(scales_at(lambda))
            }
            StepKind::DisplacementControl { value, global_dof, .. } => {
                let eq = self.model.dofs.eq.get(global_dof).copied().unwrap_or(FIXED);
                if eq == FIXED {
                    return Err(error(0, vec![], None, "the controlled DOF has no equation".into(), last_time));
                }
                let mut tau = 0.0;
                let mut dtau = 1.0 / n_inc as f64;
                let mut level = 0usize;
                for inc in 1..=n_inc {
                    let goal = inc as f64 / n_inc as f64;
                    let (mut iterations, mut cutbacks, mut indefinite) = (0, 0, false);
                    loop {
                        let next = (tau + dtau).min(goal);
                        let saved = state.clone();
                        let mut report = |it: usize, res: f64| progress(&Progress { step: si, fraction: next, iteration: it, residual: res, dynamic: None });
                        let c = Constraint::Displacement { eq, delta: (next - tau) * value };
                        self.begin_nodal_increment((next - tau) * n_inc as f64);
                        match self.path_increment(state, start, &step.target_scales, lambda, c, prev_du.as_deref(), &mask, &mut report) {
                            (PathAttempt::Converged { iterations: its, residuals, energy, indefinite: ind }, dlam, du) => {
                                iterations += its;
                                indefinite |= ind;
                                self.commit_nodal_forces(state);
                                lambda += dlam;
                                tau = next;
                                prev_du = Some(du);
                                if its <= 6 && level > 0 {
                                    level -= 1;
                                    dtau *= 2.0;
                                }
                                if (tau - goal).abs() < 1e-12 {
                                    tau = goal;
                                    let (negative_pivots, stiffness_parameter, stability_event) =
                                        self.stability_at(state, start, &step.target_scales, tracker);
                                    last_time = si as f64 + tau;
                                    let report = IncrementReport {
                                        step: si,
                                        step_name: step.name.clone(),
                                        increment: inc,
                                        time: last_time,
                                        scales: scales_at(lambda),
                                        iterations,
                                        residuals,
                                        cutbacks,
                                        indefinite_tangent: indefinite,
                                        energy,
                                        load_factor: Some(lambda),
                                        negative_pivots,
                                        stiffness_parameter,
                                        stability_event,
                                        extra: std::mem::take(&mut self.extra_reports),
                                        ..Default::default()
                                    };
                                    on_increment(&report, state, self);
                                    break;
                                }
                            }
                            (PathAttempt::Failed { iteration, residuals, worst_element, cause }, _, _) => {
                                *state = saved;
                                iterations += iteration;
                                if level >= self.settings.max_cutbacks {
                                    return Err(error(
                                        iteration,
                                        residuals,
                                        worst_element,
                                        format!("{cause}; displacement increment cut back {level} times at load factor {lambda:.6}"),
                                        last_time,
                                    ));
                                }
                                level += 1;
                                cutbacks += 1;
                                dtau *= 0.5;
                            }
                        }
                    }
                }
                Ok(scales_at(lambda))
            }
            _ => Err(error(0, vec![], None, "not a path-following step".into(), last_time)),
        }
    }

    /// One increment of path following from the converged (`state`, `lambda0`); returns the
    /// outcome, the load-factor increment Δλ and the free-DOF increment Δu (translations
    /// masked for the arc-length metric). On failure `state` is left for the caller to reset.
    #[allow(clippy::too_many_arguments)]
    fn path_increment(
        &mut self,
        state: &mut State,
        start: &[f64],
        target: &[f64],
        lambda0: f64,
        constraint: Constraint,
        prev_du: Option<&[f64]>,
        mask: &[f64],
        progress: &mut dyn FnMut(usize, f64),
    ) -> (PathAttempt, f64, Vec<f64>) {
        let n = self.model.dofs.n_free;
        let dot = |a: &[f64], b: &[f64]| -> f64 { a.iter().zip(b).zip(mask).map(|((x, y), m)| x * y * m).sum() };
        let mut residuals = Vec::new();
        let mut indefinite = false;
        let fail = |it: usize, residuals: &Vec<f64>, el: Option<usize>, cause: String| {
            (PathAttempt::Failed { iteration: it, residuals: residuals.clone(), worst_element: el, cause }, 0.0, vec![0.0; n])
        };
        let scales_at = |lam: f64| -> Vec<f64> { start.iter().zip(target).map(|(a, b)| a + lam * (b - a)).collect() };
        // Predictor from the tangent at the converged state.
        if let Err(f) = self.assemble(state, &scales_at(lambda0), true) {
            return fail(0, &residuals, Some(f.element), f.to_string());
        }
        let f = self.load_change(state, start, target);
        let Some((pivots, _, ut)) = self.factor_and_probe(&f) else {
            return fail(0, &residuals, None, "singular tangent at the start of the increment (exactly at a critical point?)".into());
        };
        indefinite |= pivots > 0;
        let mut dlam = match constraint {
            Constraint::Arc { length } => {
                let norm = dot(&ut, &ut).sqrt();
                if !(norm > 0.0) {
                    return fail(0, &residuals, None, "the load change moves no free translation".into());
                }
                let sign = match prev_du {
                    Some(p) => {
                        let s = dot(p, &ut);
                        if s < 0.0 { -1.0 } else { 1.0 }
                    }
                    None => {
                        if pivots % 2 == 1 { -1.0 } else { 1.0 }
                    }
                };
                sign * length / norm
            }
            Constraint::Displacement { eq, delta } => {
                if ut[eq].abs() < 1e-300 {
                    return fail(0, &residuals, None, "the controlled DOF does not respond to the load (δu_t = 0)".into());
                }
                delta / ut[eq]
            }
        };
        let mut du: Vec<f64> = ut.iter().map(|v| v * dlam).collect();
        self.model.update(state, &du, 1.0);
        let mut r = vec![0.0; n];
        let mut energy0: Option<f64> = None;
        let mut last_correction: Vec<f64> = du.clone();
        for it in 0..self.settings.max_iterations {
            let lam = lambda0 + dlam;
            let energy = match self.assemble(state, &scales_at(lam), true) {
                Ok(e) => e,
                Err(fl) => return fail(it, &residuals, Some(fl.element), fl.to_string()),
            };
            let (rel, _) = self.residual(&mut r);
            residuals.push(rel);
            progress(it, rel);
            if !rel.is_finite() {
                let el = self.worst_element(&r);
                return fail(it, &residuals, el, "residual is NaN or infinite".into());
            }
            if it > 0 {
                let de: f64 = last_correction.iter().zip(&r).map(|(a, b)| a * b).sum::<f64>().abs();
                if self.converged(rel, de, energy0.unwrap_or(1.0)) {
                    return (PathAttempt::Converged { iterations: it, residuals, energy, indefinite }, dlam, du);
                }
                if it >= 3 && rel > 1e6 * residuals[0].max(1e-12) {
                    let el = self.worst_element(&r);
                    let why = self.tangent_diagnosis();
                    return fail(it, &residuals, el, format!("corrector diverging (residual grew a millionfold); {why}"));
                }
            }
            let f = self.load_change(state, start, target);
            let t = Instant::now();
            let kind = self.cholesky.factorize(&self.values);
            self.timings.factorization += t.elapsed().as_secs_f64();
            if kind.is_err() {
                let el = self.worst_element(&r);
                return fail(it, &residuals, el, "singular tangent in the corrector".into());
            }
            indefinite |= self.cholesky.negative_pivots() > 0;
            let t = Instant::now();
            let mut ur: Vec<f64> = r.iter().map(|v| -v).collect();
            self.cholesky.solve(&mut ur);
            let mut ut = f;
            self.cholesky.solve(&mut ut);
            self.timings.solve += t.elapsed().as_secs_f64();
            let dl = match constraint {
                Constraint::Arc { length } => {
                    // ‖du + ur + δλ ut‖² = length² over the translations.
                    let a0: Vec<f64> = du.iter().zip(&ur).map(|(x, y)| x + y).collect();
                    let a = dot(&ut, &ut);
                    let b = 2.0 * dot(&a0, &ut);
                    let c = dot(&a0, &a0) - length * length;
                    let disc = b * b - 4.0 * a * c;
                    if disc >= 0.0 && a > 0.0 {
                        let sq = disc.sqrt();
                        let q = -0.5 * (b + b.signum() * sq);
                        let r1 = q / a;
                        let r2 = if q != 0.0 { c / q } else { -r1 };
                        // Root keeping the increment's direction.
                        let score = |x: f64| dot(&a0, &du) + x * dot(&ut, &du);
                        if score(r1) >= score(r2) { r1 } else { r2 }
                    } else {
                        let den = dot(&du, &ut);
                        if den.abs() < 1e-300 {
                            let el = self.worst_element(&r);
                            return fail(it, &residuals, el, "arc-length constraint has no real root and no normal-plane solution".into());
                        }
                        -dot(&du, &ur) / den
                    }
                }
                Constraint::Displacement { eq, .. } => {
                    if ut[eq].abs() < 1e-300 {
                        let el = self.worst_element(&r);
                        return fail(it, &residuals, el, "the controlled DOF does not respond to the load (δu_t = 0)".into());
                    }
                    -ur[eq] / ut[eq]
                }
            };
            let corr: Vec<f64> = ur.iter().zip(&ut).map(|(a, b)| a + dl * b).collect();
            if corr.iter().any(|v| !v.is_finite()) || !dl.is_finite() {
                return fail(it, &residuals, None, "linear solve produced NaN (singular tangent)".into());
            }
            let g0: f64 = corr.iter().zip(&r).map(|(a, b)| a * b).sum();
            if energy0.is_none() {
                energy0 = Some(g0.abs().max(1e-300));
            }
            self.model.update(state, &corr, 1.0);
            du.iter_mut().zip(&corr).for_each(|(a, b)| *a += b);
            dlam += dl;
            last_correction = corr;
        }
        let (rel, _) = self.residual(&mut r);
        residuals.push(rel);
        let el = self.worst_element(&r);
        let why = self.tangent_diagnosis();
        fail(self.settings.max_iterations, &residuals, el, format!("no convergence in {} iterations; {why}", self.settings.max_iterations))
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{DMatrix, SymmetricEigen};

    use crate::bench::scenes;
    use crate::scene;
    use crate::solver::Solver;

    /// On a real indefinite shell tangent — the flat square plate of
    /// `plate_buckling.ron` (8×8) compressed to twice its critical load, past the first two
    /// eigenvalues (k = 4.08 and 6.73 on this mesh) — the negative pivots of faer's LDLᵀ
    /// without pivoting equal the negative eigenvalues of the dense tangent (Sylvester's law
    /// of inertia), and the near-zero-free spectrum makes the count unambiguous.
    #[test]
    fn negative_pivots_match_dense_eigenvalues_of_a_compressed_plate() {
        let text = scenes::PLATE_BUCKLING
            .replace("nx: 16, ny: 16", "nx: 8, ny: 8")
            .replace("kind: Buckling(modes: 4)", "kind: Static")
            .replace("increments: 1, scale: {\"compression\": 1.0}", "increments: 2, scale: {\"compression\": 72.3}");
        let sc = scene::parse("plate", &text).unwrap();
        let built = scene::build(&sc, "plate", &text).unwrap();
        let model = &built.model;
        let mut solver = Solver::new(model, sc.solver.clone()).unwrap();
        let mut state = model.initial_state();
        let mut counts = Vec::new();
        solver.run(&built.steps, &mut state, &mut |r, _, _| counts.push(r.negative_pivots), &mut |_| {}).unwrap();
        let scales = built.steps[0].target_scales.clone();
        solver.assemble(&state, &scales, true).unwrap();
        solver.cholesky.factorize(&solver.values).unwrap();
        let pivots = solver.cholesky.negative_pivots();
        let p = &solver.assembler.pattern;
        let mut k = DMatrix::zeros(p.n, p.n);
        for c in 0..p.n {
            for q in p.col_ptr[c]..p.col_ptr[c + 1] {
                let r = p.row_idx[q];
                k[(r, c)] = solver.values[q];
                k[(c, r)] = solver.values[q];
            }
        }
        let eig = SymmetricEigen::new(k).eigenvalues;
        let negative = eig.iter().filter(|l| **l < 0.0).count();
        let smallest = eig.iter().fold(f64::INFINITY, |m, l| m.min(l.abs()));
        let largest = eig.iter().fold(0.0f64, |m, l| m.max(l.abs()));
        assert!(smallest > 1e-10 * largest, "nearly singular: {smallest:e} / {largest:e}");
        assert_eq!(negative, 2, "dense eigenvalues");
        assert_eq!(pivots, negative);
        assert_eq!(counts.last().copied().flatten(), Some(2));
    }
}
