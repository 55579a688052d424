//! Static Newton with a Levenberg–Marquardt shift (Levenberg 1944; Marquardt 1963; Nocedal &
//! Wright 2006 §10.3 and §4): each correction solves (K + μ D) Δu = −r with D = diag|K|
//! (Marquardt's scaling, so translations and tilts are shifted in their own units). μ = 0
//! while K is positive definite and the full Newton step lowers the merit; otherwise μ is
//! raised tenfold until K + μD factors as LLᵀ (then the step is a descent direction of the
//! potential energy) and the step lowers the merit, and it is divided by three after every
//! accepted step. The merit is the potential energy Π = U − f_ext·u of the dead forces, or
//! the residual norm when that falls (moments about fixed axes have no potential).

use std::time::Instant;

use super::linear::FactorKind;
use super::newton::{failed, Attempt, Solver};
use crate::model::State;

impl<'m> Solver<'m> {
    /// Damped Newton iterations for one increment ending at `scales` (the `StaticDamped`
    /// step kind); same convergence tests as the plain Newton `attempt`.
    pub(super) fn attempt_damped(&mut self, state: &mut State, scales: &[f64], progress: &mut dyn FnMut(usize, f64)) -> Attempt {
        let n = self.model.dofs.n_free;
        let mut r = vec![0.0; n];
        let mut du = vec![0.0; n];
        let mut residuals = Vec::new();
        let mut indefinite = false;
        let mut energy0: Option<f64> = None;
        let mut mu = 0.0f64;
        self.model.apply_prescribed(state, scales);
        let mut energy = match self.assemble(state, scales, true) {
            Ok(e) => e,
            Err(f) => return failed(0, &residuals, Some(f.element), f.to_string()),
        };
        let mut it = 0;
        let mut trials = 0;
        let mut after_rejection = false;
        while it < self.settings.max_iterations && trials < 4 * self.settings.max_iterations {
            trials += 1;
            let (rel, _) = self.residual(&mut r);
            if residuals.len() <= it {
                residuals.push(rel);
            }
            progress(it, rel);
            if !rel.is_finite() {
                let el = self.worst_element(&r);
                return failed(it, &residuals, el, "residual is NaN or infinite".into());
            }
            if it > 0 && !after_rejection {
                let de = du.iter().zip(&r).map(|(a, b)| a * b).sum::<f64>().abs();
                if self.converged(rel, de, energy0.unwrap_or(1.0)) {
                    return Attempt::Converged { iterations: it, residuals, indefinite, energy };
                }
            }
            // Shift until K + μD is positive definite. (The pattern is read here, not once per
            // increment: a contact term's trial state may have grown it.)
            let col_ptr = self.assembler.pattern.col_ptr.clone();
            let base_values = self.values.clone();
            let diag: Vec<f64> = (0..n).map(|c| base_values[col_ptr[c + 1] - 1].abs()).collect();
            let floor = 1e-12 * diag.iter().sum::<f64>() / n.max(1) as f64;
            let mut factored = false;
            for _ in 0..40 {
                let mut shifted = base_values.clone();
                for c in 0..n {
                    shifted[col_ptr[c + 1] - 1] += mu * diag[c].max(floor);
                }
                let t = Instant::now();
                let kind = self.cholesky.factorize(&shifted);
                self.timings.factorization += t.elapsed().as_secs_f64();
                if let Ok(FactorKind::Llt) = kind {
                    factored = true;
                    break;
                }
                indefinite = true;
                mu = (mu * 10.0).max(1e-6);
            }
            if !factored {
                let el = self.worst_element(&r);
                return failed(it, &residuals, el, format!("tangent not positive definite even with a shift μ = {mu:.1e}·diag"));
            }
            let t = Instant::now();
            du.iter_mut().zip(&r).for_each(|(d, r)| *d = -r);
            self.cholesky.solve(&mut du);
            self.timings.solve += t.elapsed().as_secs_f64();
            if du.iter().any(|v| !v.is_finite()) {
                return failed(it, &residuals, None, "linear solve produced NaN".into());
            }
            if energy0.is_none() {
                energy0 = Some(du.iter().zip(&r).map(|(a, b)| a * b).sum::<f64>().abs().max(1e-300));
            }
            // Trust-region test on the trial state.
            let base = state.clone();
            let (base_f_int, base_f_ext) = (self.f_int.clone(), self.f_ext.clone());
            let (pi0, rel0) = (self.potential(state, scales, energy).unwrap_or(f64::NAN), rel);
            // Barrier terms: no further than the collision-free fraction of the correction
            // (continuous collision detection), so that no trial state tunnels through a
            // surface (a state carried across whole would see no barrier at all).
            let fraction = self.collision_free_fraction(&base, &du);
            self.model.update(state, &du, fraction);
            let trial = self.assemble(state, scales, true);
            let accept = match &trial {
                Ok(e) => {
                    let (rel1, _) = self.residual(&mut r);
                    rel1.is_finite() && (self.potential(state, scales, *e).unwrap_or(f64::NAN) < pi0 || rel1 < rel0)
                }
                Err(_) => false,
            };
            if accept {
                energy = trial.unwrap_or(energy);
                mu = if mu / 3.0 < 1e-10 { 0.0 } else { mu / 3.0 };
                it += 1;
                after_rejection = false;
            } else {
                *state = base;
                if self.values.len() == base_values.len() {
                    self.values = base_values;
                    self.f_int = base_f_int;
                    self.f_ext = base_f_ext;
                } else {
                    // The trial grew the pattern (new contact couplings): the base state's
                    // tangent is assembled again, into the grown pattern.
                    if let Err(f) = self.assemble(state, scales, true) {
                        return failed(it, &residuals, Some(f.element), f.to_string());
                    }
                }
                mu = (mu * 10.0).max(1e-4);
                after_rejection = true;
                if mu > 1e12 {
                    let cause = match trial {
                        Err(f) => f.to_string(),
                        Ok(_) => "no shift μ ≤ 1e12 lowers the energy or the residual".into(),
                    };
                    let el = self.worst_element(&r);
                    return failed(it, &residuals, el, cause);
                }
            }
        }
        let (rel, _) = self.residual(&mut r);
        residuals.push(rel);
        let el = self.worst_element(&r);
        failed(it, &residuals, el, format!("no convergence in {it} damped iterations ({trials} trials)"))
    }
}
