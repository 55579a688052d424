//! The nodal-force terms' last evaluation, kept for an assembly of the same state: a time
//! step whose exact tangent was indefinite assembles its state again with projected element
//! Hessians, and an energy line search that accepts a shortened step assembles the accepted
//! state once for its residual and once more for its tangent. The terms' forces and tangent
//! blocks depend only on the state and on their own history, which changes only through the
//! solver's hooks (increment and motion begin, commit, stability tangent, a new term); each of
//! those forgets the kept evaluation, so a kept one is exactly what the terms would return
//! (their own record of the last evaluation is of the same state, too).
//!
//! A later trial state of the energy line search (after the first was rejected) needs only
//! the potential, to compare it with the Armijo bound: [`Solver::trial_potential`] evaluates
//! element forces and energies without tangents and the nodal-force terms' energies alone
//! ([`super::NodalForces::potential_at`]); the state it accepts is assembled in full.

use nalgebra::{Matrix3, Vector3};

use super::newton::Solver;
use crate::assembly::AssemblyFailure;
use crate::element::DirectorFrame;
use crate::model::State;

/// One evaluation of all nodal-force terms: forces (all DOFs, folded onto the masters of
/// tied slaves) and their norm before the fold, node blocks ∂f_n/∂u_n and node-pair blocks
/// (a, b, ∂f_a/∂u_b).
#[derive(Default)]
pub(super) struct NodalEvaluation {
    pub f: Vec<f64>,
    pub norm: f64,
    pub jacobian: Vec<(usize, Matrix3<f64>)>,
    pub pairs: Vec<(usize, usize, Matrix3<f64>)>,
}

/// The last [`NodalEvaluation`] and a copy of the state it belongs to.
#[derive(Default)]
pub(super) struct NodalCache {
    u: Vec<Vector3<f64>>,
    frames: Vec<DirectorFrame>,
    kept: Option<NodalEvaluation>,
}

impl NodalCache {
    /// Forgets the kept evaluation (the terms' history changed).
    pub(super) fn forget(&mut self) {
        self.kept = None;
    }

    /// The kept evaluation, taken out, when `state` is bit for bit its state.
    pub(super) fn take(&mut self, state: &State) -> Option<NodalEvaluation> {
        let same = |a: &Vector3<f64>, b: &Vector3<f64>| a.iter().zip(b.iter()).all(|(x, y)| x.to_bits() == y.to_bits());
        let holds = self.kept.is_some()
            && self.u.len() == state.u.len()
            && self.frames.len() == state.frames.len()
            && self.u.iter().zip(&state.u).all(|(a, b)| same(a, b))
            && self.frames.iter().zip(&state.frames).all(|(a, b)| same(&a.d, &b.d) && same(&a.t1, &b.t1) && same(&a.t2, &b.t2));
        if holds {
            self.kept.take()
        } else {
            None
        }
    }

    /// Keeps `evaluation`, the terms' evaluation at `state`.
    pub(super) fn keep(&mut self, state: &State, evaluation: NodalEvaluation) {
        self.u.clone_from(&state.u);
        self.frames.clone_from(&state.frames);
        self.kept = Some(evaluation);
    }
}

impl<'m> Solver<'m> {
    /// Strain energy at the trial state `state` and its potential Π = Ψ + V_loads + Σ V_nodal
    /// (None inside when a force is not finite — an element, a load, or a nodal-force term
    /// finding the state inadmissible — and None in the potential when a term is not
    /// conservative): the values an assembly without tangent followed by
    /// [`Solver::potential`] gives, the same bit for bit, without the nodal-force terms'
    /// derivatives. Leaves `f_int` and the loads in `f_ext` at `state`, without the nodal
    /// forces: the caller assembles the state it accepts.
    pub(super) fn trial_potential(&mut self, state: &State, scales: &[f64]) -> Result<(f64, Option<Option<f64>>), AssemblyFailure> {
        let info = self.assembler.assemble(self.model, state, &mut self.f_int, None)?;
        self.timings.assembly += info.seconds;
        self.model.external_force(state, scales, &mut self.f_ext);
        let mut nodal = Some(0.0);
        if !self.nodal_forces.is_empty() {
            let t = std::time::Instant::now();
            nodal = self.nodal_forces.iter_mut().map(|c| c.potential_at(self.model, state)).sum::<Option<f64>>();
            self.timings.contact += t.elapsed().as_secs_f64();
        }
        let finite = self.f_int.iter().chain(&self.f_ext).all(|v| v.is_finite()) && nodal.is_none_or(f64::is_finite);
        let potential = || Some(info.energy + self.model.load_potential(state, scales)? + nodal?);
        Ok((info.energy, finite.then(potential)))
    }
}
