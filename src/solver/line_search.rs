//! The energy line search of minimising Newton steps (the incremental potential of a time
//! step, Li et al. 2020 §4.3): the potential Π of the last assembly and the backtracking
//! search along the Newton direction, filtered by the collision-free bound of the
//! nodal-force terms.

use super::newton::Solver;
use crate::model::State;

/// Largest director rotation of one Newton update in the energy line search (radians): a
/// trust region on the director, whose energy is far from quadratic beyond it.
const MAX_ROTATION: f64 = 0.5;

/// Line searches after which the share of rejected first trials decides how first trials are
/// evaluated ([`Solver::energy_line_search`]).
const FIRST_SAMPLE: usize = 10;

/// Share of rejected first trials above which a first trial is judged by its potential alone
/// before its tangent is assembled: a potential-only evaluation costs about a third of one
/// with the tangent (element kernel 1.5 against 4.7 µs; contact pairs measured but not
/// differentiated), so the extra evaluation of an accepted trial pays for itself above that.
const FIRST_REJECTED: f64 = 0.3;

/// An accepted step of the energy line search ([`Solver::energy_line_search`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct Descent {
    /// Strain energy at the accepted state.
    pub energy: f64,
    /// Halvings of the step (after the collision-free bound).
    pub cuts: usize,
}

impl<'m> Solver<'m> {
    /// Potential Π = Ψ + V_loads + Σ V_nodal of the last assembly at `state` (strain energy
    /// `energy`), or None when a load or nodal-force term is not conservative.
    pub(super) fn potential(&self, state: &State, scales: &[f64], energy: f64) -> Option<f64> {
        Some(energy + self.model.load_potential(state, scales)? + self.nodal_potential?)
    }

    /// Energy line search along the Newton direction `du` (Nocedal & Wright 2006, §3.1,
    /// backtracking with the Armijo condition; IPC's filtered line search, Li et al. 2020
    /// §4.3): the step starts at the largest collision-free fraction of `du` that every
    /// nodal-force term allows ([`super::NodalForces::max_step`]) and is halved until
    /// Π(s) ≤ Π₀ + 10⁻⁴ s·slope (slope = ∇Π·du < 0), Π = [`Solver::potential`] + `extra`
    /// (the inertia potential of a time step), within a round-off allowance of 10⁻¹⁰ of the
    /// magnitudes making up Π₀. The accepted state is assembled with its tangent. On failure
    /// `state` is restored (and reassembled) and the reason returned, with the element whose
    /// failure ended the search, if one did.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn energy_line_search(
        &mut self,
        state: &mut State,
        du: &[f64],
        scales: &[f64],
        slope: f64,
        pi0: f64,
        magnitude: f64,
        extra: &mut dyn FnMut(&Self, &State) -> f64,
    ) -> Result<Descent, (Option<usize>, String)> {
        let base = state.clone();
        let mut s = self.collision_free_fraction(&base, du);
        // Trust region on the director update: no node turns by more than MAX_ROTATION.
        let turn = self.largest_rotation(du);
        if turn > MAX_ROTATION {
            s = s.min(MAX_ROTATION / turn);
        }
        let tol = 1e-10 * magnitude.abs().max(pi0.abs());
        let mut cuts = 0;
        let mut last = String::from("no admissible state along the Newton direction");
        let mut failing = None;
        // The first trial is assembled with its tangent while first trials are mostly
        // accepted; once more than [`FIRST_REJECTED`] of them have been rejected (after
        // [`FIRST_SAMPLE`] searches), it too only compares potentials
        // (`reuse::trial_potential`, about a third of a tangent assembly), and the state
        // accepted is then assembled with its tangent — the same states and tangents, in a
        // different order of work. Later trials always compare potentials only.
        let [searches, rejected] = self.first_trials;
        let tangent_first = searches < FIRST_SAMPLE || (rejected as f64) <= FIRST_REJECTED * searches as f64;
        self.first_trials[0] += 1;
        if s > 0.0 {
            for tries in 0..40 {
                *state = base.clone();
                self.model.update(state, du, s);
                let tangent = tries == 0 && tangent_first;
                let trial = if tangent {
                    self.assemble(state, scales, true).map(|e| {
                        let finite = self.f_int.iter().chain(&self.f_ext).all(|v| v.is_finite());
                        (e, finite.then(|| self.potential(state, scales, e)))
                    })
                } else {
                    self.trial_potential(state, scales)
                };
                match trial {
                    Ok((e, Some(potential))) => {
                        let pi = potential.map(|p| p + extra(self, state)).unwrap_or(f64::NAN);
                        if pi.is_finite() && pi <= pi0 + 1e-4 * s * slope + tol {
                            if !tangent && let Err(f) = self.assemble(state, scales, true) {
                                last = f.to_string();
                                failing = Some(f.element);
                                break;
                            }
                            self.timings.line_searches_cut += usize::from(cuts > 0);
                            return Ok(Descent { energy: e, cuts });
                        }
                        last = format!("no decrease of the potential down to step {s:.2e} (Π₀ = {pi0:.6e}, slope {slope:.3e})");
                    }
                    Ok(_) => last = "forces not finite along the Newton direction".into(),
                    Err(f) => {
                        last = f.to_string();
                        failing = Some(f.element);
                    }
                }
                if tries == 0 {
                    self.first_trials[1] += 1;
                }
                s *= 0.5;
                cuts += 1;
                if s < 1e-12 {
                    break;
                }
            }
        } else {
            last = "the collision-free step along the Newton direction is zero".into();
        }
        *state = base;
        self.assembler.forget_mixed();
        let _ = self.assemble(state, scales, true);
        Err((failing, last))
    }
}
