//! The energy line search's trial states (see the parent module doc): a trial after the
//! first is judged by its potential alone (`NodalForces::potential_at`), and the one it
//! accepts is then assembled in full at the very same state. The trial's measured pairs
//! (closest features, gaps, energies, normals, weights) are kept for that assembly, which
//! then only differentiates them: on the NBC sleeve on the arm 460 of the 813 evaluations
//! with derivatives are such accepted trials. The trial sums the friction potentials alone;
//! the accepted one's assembly forms the friction terms (gradients, Hessians) alongside the
//! per-feature grouping (`add_coupled`).

use std::sync::Arc;
use std::time::Instant;

use nalgebra::Vector3;
use rayon::prelude::*;

use super::super::potential::{mollified_derivative, Derivative, Scalar};
use super::{Pair, SurfaceContact, Term};
use crate::contact::barrier::barrier;
use crate::model::{Model, State};

/// One trial state's evaluation without derivatives, kept for an assembly of that state.
pub(super) struct Trial {
    /// The contact nodes' displacements at the trial.
    u: Vec<Vector3<f64>>,
    /// Its candidates, their gaps (measured, or lower bounds) and its active pairs.
    pub(super) pairs: Arc<Vec<Pair>>,
    pub(super) gaps: Vec<(f64, bool)>,
    pub(super) terms: Vec<Term>,
}

impl SurfaceContact {
    /// The barrier and friction energies at `state` summed as `add_coupled` sums them (the
    /// same value, bit for bit: the same terms in the same order), without the barrier's
    /// gradients and Hessians, and the friction potentials alone ([`friction::energies`](super::super::friction::energies));
    /// infinite at a pair through zero gap. The pairs are kept for an assembly of this state
    /// ([`SurfaceContact::take_trial`]).
    pub(super) fn trial_potential(&mut self, model: &Model, state: &State) -> f64 {
        let t = Instant::now();
        let pos = super::positions(model, state);
        let x = |a: usize| pos[a];
        let pairs = self.candidates_at(&x);
        let skip = self.inactive_by_bound(&pairs, &x);
        let mut gaps = Vec::new();
        let terms = self.evaluate_pairs(&pairs, &x, false, skip.as_deref(), Some(&mut gaps));
        // The friction potentials alone: an accepted trial's assembly forms the terms.
        let friction = super::super::friction::energies(&self.committed, self.settings.friction, &x);
        self.search_s += t.elapsed().as_secs_f64();
        let mut pot = 0.0;
        for term in &terms {
            if !term.energy.is_finite() {
                pot = f64::INFINITY;
                continue;
            }
            pot += term.energy;
        }
        for e in &friction {
            pot += e;
        }
        let u = self.points.iter().map(|&a| state.u[a]).collect();
        self.trial = Some(Trial { u, pairs, gaps, terms });
        pot
    }

    /// The kept trial when `state` is bit for bit its state and `pairs` its candidates; None
    /// otherwise. The kept trial is forgotten either way. Its mollified edge–edge pairs still
    /// lack their derivatives ([`SurfaceContact::trial_mollified`]).
    pub(super) fn take_trial(&mut self, state: &State, pairs: &Arc<Vec<Pair>>) -> Option<Trial> {
        let same = |a: &Vector3<f64>, b: &Vector3<f64>| a.iter().zip(b.iter()).all(|(p, q)| p.to_bits() == q.to_bits());
        self.trial.take().filter(|t| Arc::ptr_eq(&t.pairs, pairs) && t.u.len() == self.points.len() && self.points.iter().zip(&t.u).all(|(&a, u)| same(&state.u[a], u)))
    }

    /// The derivatives of a kept trial's mollified edge–edge pairs among `terms` at `x`, by
    /// index (what `evaluate_pairs` with derivatives computes for them).
    pub(super) fn trial_mollified(&self, terms: &[Term], x: &(dyn Fn(usize) -> Vector3<f64> + Sync)) -> Vec<(usize, Box<Derivative>)> {
        terms
            .par_iter()
            .enumerate()
            .filter(|(_, t)| t.parallel && t.energy.is_finite() && t.gap > 0.0)
            .map(|(i, term)| {
                let kap = term.nodes.iter().map(|&a| self.kappa[a]).sum::<f64>() / 4.0;
                let (b, b1, b2) = barrier(term.gap, term.dhat);
                let f = Scalar { e: kap * b, e1: kap * b1, e2: kap * b2 };
                (i, Box::new(mollified_derivative(&term.nodes, &term.feature, &f, term.eps, x)))
            })
            .collect()
    }

    /// Forgets the kept trial (κ or the friction anchors changed).
    pub(super) fn forget_trial(&mut self) {
        self.trial = None;
    }
}
