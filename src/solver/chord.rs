//! Chord (modified) Newton for static load-controlled increments: once the relative
//! residual contracts fast, the iteration keeps solving with the factorization it already
//! has instead of assembling and factorizing a new tangent (Crisfield 1991, §9.2, the
//! modified Newton–Raphson method; Kelley 2003, Solving Nonlinear Equations with Newton's
//! Method, §2.3, the chord method with a contraction test).
//!
//! The rule, applied iteration by iteration inside [`super::Solver::attempt`]:
//! - *reuse*: iteration k solves with the last factorization when the residual of the last
//!   correction contracted by at least `contraction` (‖r_k‖ ≤ contraction · ‖r_{k−1}‖), the
//!   factorization has served fewer than `max_reuse` corrections and the tangent's pattern
//!   has not changed since it was made; otherwise the tangent at the current state is
//!   assembled (if the last assembly skipped it) and factorized — a full Newton iteration.
//! - *skip the tangent*: the update after a correction assembles the residual alone when
//!   the correction itself contracted the residual by `contraction`, since the next iteration
//!   is then expected to reuse the factorization; a wrong guess costs one residual assembly.
//! - A converged state whose last assembly skipped the tangent gets it assembled, so the
//!   inertia and stiffness parameter of the increment report are those of the converged
//!   state's tangent, as with full Newton.
//!
//! The converged states satisfy the same convergence test as full Newton's, so they agree
//! with them to within the Newton tolerance, not bit for bit; the mode is off by default
//! (`solver: (chord: Some(()))` in a scene turns it on). Measured on a clamped quarter plate
//! under large-deflection pressure (102×102, 51,612 DOFs, one thread, 2 increments): full
//! Newton 18 iterations and 19 factorizations, 5.3 s CPU; chord (contraction 0.1) 19
//! iterations and 12 factorizations, 4.2–4.4 s CPU; strain energy equal to 3·10⁻⁸. It loses
//! where the residual history is erratic: the plate of `tests/automatic_increments.rs`
//! sagging to nearly vertical (40×40, 10 increments) takes 501 instead of 337 iterations and
//! 15.0 instead of 9.9 s CPU, since one good contraction is followed by poor chord steps.
//! The same rule inside the time steps of a Dynamic step to rest (a correction that cut the
//! relative residual tenfold reused the time step's last factorization, at most three times,
//! the energy line search as the safeguard) lost too, for the same reason: the sheet dropped
//! onto the sphere (SVK, friction 0.4, sequenced 16² → 32² → 64², one thread) took 835
//! instead of 449 Newton iterations on the finest level (32²: 430 instead of 334, 16²: 904
//! instead of 284) and 57 instead of 32 s CPU.

use serde::{Deserialize, Serialize};

use super::Solver;
use crate::assembly::AssemblyFailure;
use crate::model::State;

/// Chord-Newton controls (`SolverSettings::chord`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ChordSettings {
    /// Reuse the factorization while each correction reduces the relative residual at least
    /// by this factor (0 < contraction < 1).
    pub contraction: f64,
    /// Most corrections solved with one factorization (≥ 1).
    pub max_reuse: usize,
}

impl Default for ChordSettings {
    fn default() -> Self {
        Self { contraction: 0.1, max_reuse: 6 }
    }
}

impl ChordSettings {
    /// Checks the controls; returns the offending field and why.
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        if !(self.contraction.is_finite() && self.contraction > 0.0 && self.contraction < 1.0) {
            return Err(("contraction", format!("expected a factor in (0, 1), found {}", self.contraction)));
        }
        if !(1..=100).contains(&self.max_reuse) {
            return Err(("max_reuse", format!("expected 1 to 100 corrections per factorization, found {}", self.max_reuse)));
        }
        Ok(())
    }
}

/// Bookkeeping of one increment's chord iteration.
#[derive(Clone, Debug)]
pub(super) struct Chord {
    settings: Option<ChordSettings>,
    /// Corrections solved with the current factorization beyond the first.
    reused: usize,
    /// Pattern growths counted when the current factorization was made (None: no
    /// factorization in this increment yet).
    factored_at: Option<usize>,
    /// Whether the last assembly included the tangent.
    pub tangent_current: bool,
}

impl Chord {
    /// A fresh increment whose first assembly included the tangent; `settings` None is
    /// full Newton (every decision below says "assemble and factorize").
    pub(super) fn new(settings: Option<ChordSettings>) -> Self {
        Self { settings, reused: 0, factored_at: None, tangent_current: true }
    }

    /// Whether the last two relative residuals of `residuals` contracted by the chord factor.
    fn contracted(&self, residuals: &[f64]) -> bool {
        let (Some(s), [.., prev, last]) = (self.settings, residuals) else { return false };
        last.is_finite() && *last <= s.contraction * prev
    }

    /// Whether the current iteration (relative residuals so far in `residuals`, the current
    /// one last) solves with the existing factorization; `growths` is the solver's pattern
    /// growth count (a grown pattern has a new, unfactorized analysis).
    pub(super) fn reuse(&self, residuals: &[f64], growths: usize) -> bool {
        let Some(s) = self.settings else { return false };
        self.factored_at == Some(growths) && self.reused < s.max_reuse && self.contracted(residuals)
    }

    /// Records a correction solved with the existing factorization.
    pub(super) fn reused_factor(&mut self) {
        self.reused += 1;
    }

    /// Records a new factorization made at pattern growth count `growths`.
    pub(super) fn factorized(&mut self, growths: usize) {
        self.factored_at = Some(growths);
        self.reused = 0;
    }

    /// Whether the update after the current correction should assemble the tangent (false
    /// when the next iteration is expected to reuse the factorization: the residual
    /// contracted by the chord factor in the last correction and the factorization may
    /// serve another one).
    pub(super) fn tangent_for_update(&self, residuals: &[f64]) -> bool {
        let Some(s) = self.settings else { return true };
        !(self.reused < s.max_reuse && self.contracted(residuals))
    }
}

impl Solver<'_> {
    /// Assembles the tangent at `state` (loads at `scales`) when the last assembly skipped
    /// it, so that `values` hold the tangent of the current state.
    pub(super) fn chord_tangent(&mut self, chord: &mut Chord, state: &State, scales: &[f64]) -> Result<(), AssemblyFailure> {
        if !chord.tangent_current {
            self.assemble(state, scales, true)?;
            chord.tangent_current = true;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn full_newton_without_settings() {
        let c = Chord::new(None);
        assert!(!c.reuse(&[1.0, 1e-3, 1e-9], 0));
        assert!(c.tangent_for_update(&[1.0, 1e-9]));
    }

    #[test]
    fn reuses_only_a_factorization_of_the_same_pattern_while_contracting() {
        let mut c = Chord::new(Some(ChordSettings { contraction: 0.2, max_reuse: 2 }));
        // No factorization yet.
        assert!(!c.reuse(&[1.0, 0.1], 0));
        c.factorized(0);
        assert!(c.reuse(&[1.0, 0.1], 0));
        assert!(!c.reuse(&[1.0, 0.3], 0), "contraction 0.3 > 0.2");
        assert!(!c.reuse(&[1.0, 0.1], 1), "pattern grew since the factorization");
        assert!(!c.tangent_for_update(&[1.0, 0.1]));
        assert!(c.tangent_for_update(&[1.0, 0.5]));
        c.reused_factor();
        c.reused_factor();
        assert!(!c.reuse(&[1.0, 0.01], 0), "max_reuse reached");
        assert!(c.tangent_for_update(&[1.0, 0.01]));
        assert!(ChordSettings::default().validate().is_ok());
        assert!(ChordSettings { contraction: 1.0, max_reuse: 2 }.validate().is_err());
        assert!(ChordSettings { contraction: 0.5, max_reuse: 0 }.validate().is_err());
    }
}
