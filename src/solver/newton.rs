//! Incremental–iterative static solution (Crisfield 1991, ch. 3 and 9; Bathe 2014 §8.4).
//!
//! Each step ramps the load patterns' scales linearly from their values at the end of the
//! previous step to the step's targets over a number of increments. In an increment the
//! prescribed displacements are imposed, then Newton–Raphson iterates on the free DOFs
//! with the consistent tangent until the residual and energy norms are small. A failed
//! increment (no convergence, divergence, NaN, element inversion, singular tangent) is
//! undone and halved; increments grow back after easy convergence.

use std::time::Instant;

use serde::Serialize;

use super::linear::{FactorKind, SparseCholesky};
use super::{StepKind, SolverSettings};
use super::growth::NodalTangent;
use crate::assembly::{Assembler, AssemblyFailure};
pub use super::report::{IncrementReport, Progress, SolveError};
use crate::element::NODE_DOFS;
use crate::model::{Model, State, FIXED};

/// One step of the load history.
#[derive(Clone, Debug)]
pub struct StepPlan {
    /// Step name.
    pub name: String,
    /// Nominal increments (results are reported at each).
    pub increments: usize,
    /// One Newton iteration per increment (linear analysis).
    pub linear: bool,
    /// Static steps: size the increments automatically from a first one of `1/increments`
    /// ([`Solver::run_automatic`]) instead of solving at the `increments` equal load levels.
    pub automatic_increments: bool,
    /// Target scale per load pattern at the end of the step (same order as `Model::loads`).
    pub target_scales: Vec<f64>,
    /// How the step is solved (static Newton by default).
    pub kind: StepKind,
    /// Analysis-clock window [start, end] of the step (`contact::motion`), or None for the
    /// default clock (one unit per static step, simulated seconds in a `Dynamic` step, from
    /// wherever the previous step left it). With a window the clock is set to `start` when
    /// the step begins; a static step runs it linearly to `end` over its load fraction, a
    /// `Dynamic` step runs it with its simulated time and holds it at `end` once there, and
    /// a `Dynamic` step to rest does not end before the clock has reached `end`. A movement
    /// protocol (`scene::protocol`) gives each pose step the window of its motion segment,
    /// so the step moves the body to its pose and then settles with the body held there.
    pub clock: Option<[f64; 2]>,
}

impl StepPlan {
    /// Analysis time after a fraction `tau` ∈ [0, 1] of a static (or path-following) step
    /// that began at `clock0`.
    pub fn static_clock(&self, clock0: f64, tau: f64) -> f64 {
        match self.clock {
            Some([s, e]) => s + tau * (e - s),
            None => clock0 + tau,
        }
    }

    /// Analysis time after simulated time `t` of a `Dynamic` step that began at `clock0`.
    pub fn dynamic_clock(&self, clock0: f64, t: f64) -> f64 {
        match self.clock {
            Some([s, e]) => (s + t).min(e),
            None => clock0 + t,
        }
    }
}

/// Wall time split (s).
#[derive(Clone, Debug, Default, Serialize)]
pub struct Timings {
    /// Element evaluation and scatter.
    pub assembly: f64,
    /// Numeric factorization.
    pub factorization: f64,
    /// CPU seconds on the numeric factorizations' critical path (the calling thread's for
    /// the monolithic factorization, the slower half's plus the Schur complement's for the
    /// split one): what `factorization` would be on free cores.
    #[serde(default)]
    pub factorization_cpu_path: f64,
    /// Triangular solves.
    pub solve: f64,
    /// Symbolic analysis (once).
    pub analysis: f64,
    /// Extra contributions (contact, stabilization), including their proximity search.
    #[serde(default)]
    pub contact: f64,
    /// Proximity search of the contact contributions (part of `contact`): for body contact
    /// the nodes' closest points; for barrier surface contact the candidate pairs, their gap
    /// bounds and the distances and barrier values of those measured (everything but the
    /// derivatives and tangent blocks) — on a three-ply sleeve mostly the distances.
    #[serde(default)]
    pub contact_search: f64,
    /// Times the tangent's pattern grew (and the symbolic analysis was redone, its time in
    /// `analysis`) because a nodal-force term reported a node-pair block outside it.
    #[serde(default)]
    pub pattern_growths: usize,
    /// Node-pair blocks left out of the tangent because the grown pattern could not be
    /// analysed (the forces are exact; Newton is then quasi-Newton).
    #[serde(default)]
    pub dropped_pair_blocks: usize,
    /// Step halvings of the energy line search (after the collision-free bound).
    #[serde(default)]
    pub line_search_cuts: usize,
    /// Energy line searches that accepted a shortened step (their first, tangent-assembled
    /// trial was rejected).
    #[serde(default)]
    pub line_searches_cut: usize,
    /// Newton iterations whose indefinite effective tangent was modified for a descent
    /// direction: its diagonal shifted (no surface contact) or its element (and contact pair)
    /// Hessians projected to PSD (`time_step`).
    #[serde(default)]
    pub projected_iterations: usize,
    /// Numeric factorizations of the time steps' effective tangents (`time_step`): one per
    /// Newton iteration, and more where an indefinite one is shifted or projected.
    #[serde(default)]
    pub factorizations: usize,
}

impl SolveError {
    /// The failure of a static increment of step `si` (`step`) whose last converged state is
    /// at fraction `tau` of the step: the failed attempt's iteration, residual history,
    /// worst element and diagnosis.
    pub(super) fn static_increment(si: usize, step: &StepPlan, tau: f64, iteration: usize, residuals: Vec<f64>, worst_element: Option<usize>, cause: String) -> Self {
        Self { step: si, step_name: step.name.clone(), last_converged_time: si as f64 + tau, simulated_time: None, iteration, residuals, worst_element, cause }
    }
}

/// Outcome of one attempted increment.
pub(super) enum Attempt {
    Converged { iterations: usize, residuals: Vec<f64>, indefinite: bool, energy: f64 },
    Failed { iteration: usize, residuals: Vec<f64>, worst_element: Option<usize>, cause: String },
}

/// A failed attempt at iteration `iteration` with the residual history so far.
pub(super) fn failed(iteration: usize, residuals: &[f64], worst_element: Option<usize>, cause: String) -> Attempt {
    Attempt::Failed { iteration, residuals: residuals.to_vec(), worst_element, cause }
}


/// A static solver bound to one model.
pub struct Solver<'m> {
    pub(super) model: &'m Model,
    pub(super) settings: SolverSettings,
    pub(super) assembler: Assembler,
    pub(super) cholesky: SparseCholesky,
    pub(super) values: Vec<f64>,
    pub(super) f_int: Vec<f64>,
    pub(super) f_ext: Vec<f64>,
    /// Configuration-dependent nodal forces (contact, stabilization, springs).
    pub(super) nodal_forces: Vec<Box<dyn super::NodalForces + 'm>>,
    /// Accumulated wall-time split.
    pub timings: Timings,
    /// ‖nodal forces‖ of the last assembly (all DOFs): part of the residual's reference, as
    /// contact can carry the whole load of an otherwise unsupported body.
    pub(super) nodal_norm: f64,
    /// Reports of the nodal-force terms since the last reported increment.
    pub(super) extra_reports: Vec<serde_json::Value>,
    /// Node pairs coupled in the pattern for the nodal-force terms' pair blocks.
    pub(super) couplings: Vec<(usize, usize)>,
    /// CSC positions of the last assembly's contact blocks (`nodal::BlockSlots`).
    pub(super) block_slots: super::nodal::BlockSlots,
    /// The nodal-force terms' last evaluation, for an assembly of the same state (`reuse`).
    pub(super) nodal_cache: super::reuse::NodalCache,
    /// Sum of the nodal-force terms' potentials at the last assembly (None: a term is not
    /// conservative).
    pub(super) nodal_potential: Option<f64>,
    /// Analysis time of the last converged state (`contact::motion`: one unit per static
    /// step, simulated time in `Dynamic` steps).
    pub(super) clock: f64,
    /// Analysis time at the end of the current attempt; becomes `clock` on commit.
    pub(super) clock_trial: f64,
    /// Energy line searches so far and those whose first (full-step) trial was rejected
    /// ([`Solver::energy_line_search`] evaluates first trials by their potential alone once
    /// rejections are frequent).
    pub(super) first_trials: [usize; 2],
}

/// A first Newton correction of an automatic increment turning a director by more than this
/// (radians) cuts the increment back at once.
const MAX_FIRST_ROTATION: f64 = 1.0;

/// Successive iterations with the relative residual below the tolerance after which a
/// static increment is converged even when the energy test is not met (see `attempt`).
const SETTLED_ITERATIONS: usize = 3;

impl<'m> Solver<'m> {
    /// CPU seconds on the critical path of the numeric factorizations so far
    /// ([`Timings::factorization_cpu_path`]).
    pub fn factorization_cpu_path(&self) -> f64 {
        self.cholesky.cpu_path_seconds()
    }

    /// Builds the pattern and the symbolic factorization of `model`.
    pub fn new(model: &'m Model, settings: SolverSettings) -> Result<Self, String> {
        let threads = if settings.factor_threads == 0 { rayon::current_num_threads() } else { settings.factor_threads };
        let t0 = Instant::now();
        let assembler = Assembler::new(model);
        let cholesky = SparseCholesky::analyse(&assembler.pattern, threads).map_err(|e| e.to_string())?;
        let timings = Timings { analysis: t0.elapsed().as_secs_f64(), ..Default::default() };
        let ndof = NODE_DOFS * model.n_nodes();
        Ok(Self {
            model,
            settings,
            values: vec![0.0; assembler.nnz()],
            assembler,
            cholesky,
            f_int: vec![0.0; ndof],
            f_ext: vec![0.0; ndof],
            nodal_forces: Vec::new(),
            nodal_norm: 0.0,
            timings,
            extra_reports: Vec::new(),
            couplings: Vec::new(),
            block_slots: Default::default(),
            nodal_cache: Default::default(),
            nodal_potential: Some(0.0),
            clock: 0.0,
            clock_trial: 0.0,
            first_trials: [0; 2],
        })
    }

    /// Adds configuration-dependent nodal forces (contact, stabilization, springs) to every
    /// later assembly.
    pub fn add_nodal_forces(&mut self, forces: Box<dyn super::NodalForces + 'm>) {
        let pairs = forces.couplings(self.model);
        self.nodal_forces.push(forces);
        self.nodal_cache.forget();
        if !pairs.is_empty() {
            self.grow_pattern(pairs);
        }
    }

    /// The configuration-dependent nodal-force terms.
    pub fn nodal_forces(&self) -> &[Box<dyn super::NodalForces + 'm>] {
        &self.nodal_forces
    }

    /// Tells the nodal-force terms that an attempt of relative size `fraction` begins.
    pub(super) fn begin_nodal_increment(&mut self, fraction: f64) {
        self.nodal_cache.forget();
        for c in self.nodal_forces.iter_mut() {
            c.begin_increment(fraction);
        }
    }

    /// Tells the nodal-force terms that the current attempt ends at analysis time `to`
    /// (from the last converged time): moving bodies place themselves there and may adjust
    /// the initial iterate `state`.
    pub(super) fn begin_nodal_motion(&mut self, to: f64, state: &mut State) {
        self.clock_trial = to;
        self.nodal_cache.forget();
        let from = self.clock;
        for c in self.nodal_forces.iter_mut() {
            c.begin_motion(self.model, from, to, state);
        }
    }

    /// Analysis time of the last converged state (`contact::motion`).
    pub fn clock(&self) -> f64 {
        self.clock
    }

    /// Latest analysis time at which a nodal-force term still moves (−∞: none moves).
    pub(super) fn motion_end(&self) -> f64 {
        self.nodal_forces.iter().map(|c| c.motion_end()).fold(f64::NEG_INFINITY, f64::max)
    }

    /// Tells the nodal-force terms that `state` has converged; keeps their reports for the
    /// next increment report.
    pub(super) fn commit_nodal_forces(&mut self, state: &State) {
        self.clock = self.clock_trial;
        self.nodal_cache.forget();
        for c in self.nodal_forces.iter_mut() {
            if let Some(r) = c.commit(self.model, state) {
                self.extra_reports.push(r);
            }
        }
    }

    /// Tells the nodal-force terms that the solve starts from `state`, not the reference
    /// state ([`super::nodal::NodalForces::start_from`]).
    pub fn start_nodal_forces_from(&mut self, state: &State) {
        self.nodal_cache.forget();
        for c in self.nodal_forces.iter_mut() {
            c.start_from(self.model, state);
        }
    }

    /// Equations, stored tangent entries (upper triangle) and factor entries.
    pub fn sizes(&self) -> (usize, usize, usize) {
        (self.assembler.pattern.n, self.assembler.nnz(), self.cholesky.factor_nnz())
    }

    /// Reactions and internal forces of the last assembly (all DOFs).
    pub fn internal_force(&self) -> &[f64] {
        &self.f_int
    }

    /// All-DOF external forces of the last assembly: the loads plus every nodal-force term
    /// (contact, compliant seams, surface contact), so that f_int − f_ext at a tied slave
    /// node is the force its ties carry.
    pub fn external_force(&self) -> &[f64] {
        &self.f_ext
    }

    /// Free-DOF residual r = f_int − f_ext; returns (‖r‖ / reference, reference).
    pub(super) fn residual(&self, r: &mut [f64]) -> (f64, f64) {
        let eq = &self.model.dofs.eq;
        let mut rr = 0.0;
        let mut fe = 0.0;
        let mut fi = 0.0;
        for (g, &e) in eq.iter().enumerate() {
            fi += self.f_int[g] * self.f_int[g];
            if e != FIXED {
                r[e] = self.f_int[g] - self.f_ext[g];
                rr += r[e] * r[e];
                fe += self.f_ext[g] * self.f_ext[g];
            }
        }
        let reference = fe.sqrt().max(fi.sqrt()).max(self.nodal_norm).max(1e-300);
        (rr.sqrt() / reference, reference)
    }

    pub(super) fn assemble(&mut self, state: &State, scales: &[f64], tangent: bool) -> Result<f64, AssemblyFailure> {
        let info = self.assembler.assemble(
            self.model,
            state,
            &mut self.f_int,
            if tangent { Some(&mut self.values) } else { None },
        )?;
        self.timings.assembly += info.seconds;
        self.model.external_force(state, scales, &mut self.f_ext);
        if !self.nodal_forces.is_empty() {
            let t = Instant::now();
            let analysis = self.timings.analysis;
            // The same state as the last evaluation (`reuse`): its forces and blocks again.
            let evaluation = match self.nodal_cache.take(state) {
                Some(kept) => kept,
                None => {
                    let mut ev = super::reuse::NodalEvaluation { f: vec![0.0; self.f_ext.len()], ..Default::default() };
                    for forces in self.nodal_forces.iter_mut() {
                        forces.add_coupled(self.model, state, &mut ev.f, &mut ev.jacobian, &mut ev.pairs);
                    }
                    ev.norm = ev.f.iter().map(|v| v * v).sum::<f64>().sqrt();
                    // Forces on tied slaves fold onto their masters like the other loads.
                    self.model.dofs.fold(&mut ev.f);
                    ev
                }
            };
            self.nodal_norm = evaluation.norm;
            self.nodal_potential = self.nodal_forces.iter().map(|c| c.potential()).sum();
            self.f_ext.iter_mut().zip(&evaluation.f).for_each(|(e, v)| *e += v);
            let outcome = if tangent { self.add_nodal_tangent(&evaluation) } else { NodalTangent::Added };
            self.nodal_cache.keep(state, evaluation);
            // A growth's symbolic analysis has its own timer.
            self.timings.contact += t.elapsed().as_secs_f64() - (self.timings.analysis - analysis);
            self.timings.contact_search = self.nodal_forces.iter().map(|c| c.search_seconds()).sum();
            match outcome {
                NodalTangent::Added => {}
                // Blocks dropped: no link stiffness either (as before the growth).
                NodalTangent::Dropped => return Ok(info.energy),
                // The kept evaluation of this state serves the assembly into the grown pattern.
                NodalTangent::Reassemble => return self.assemble(state, scales, tangent),
            }
        }
        if tangent {
            // Rigid links: second-order term of the state-dependent tie weights.
            let (pattern, values) = (&self.assembler.pattern, &mut self.values);
            self.model.dofs.add_link_stiffness(&self.f_int, &self.f_ext, &mut |exp, c| pattern.add_weighted(values, exp, c));
        }
        Ok(info.energy)
    }

    /// Element touching the node with the largest free residual.
    pub(super) fn worst_element(&self, r: &[f64]) -> Option<usize> {
        let eq = &self.model.dofs.eq;
        let mut best = (0.0, None);
        for (g, &e) in eq.iter().enumerate() {
            if e != FIXED && (r[e].abs() > best.0 || r[e].is_nan()) {
                best = (r[e].abs(), Some(g / NODE_DOFS));
                if r[e].is_nan() {
                    break;
                }
            }
        }
        let node = best.1?;
        self.model.elements.iter().position(|el| el.nodes.contains(&node))
    }

    /// Newton convergence test shared by every step kind: both the relative residual `rel`
    /// and the energy norm `de` = |δu·r| of the last correction (relative to the first, `e0`)
    /// small; or the residual at its round-off floor (thin shells at large rotation:
    /// ½(p·q − P·Q) loses digits in proportion to the membrane-to-bending stiffness ratio)
    /// while the energy norm of the correction is negligible.
    pub(super) fn converged(&self, rel: f64, de: f64, e0: f64) -> bool {
        let tol = self.settings.residual_tol;
        let energy_ok = de <= self.settings.energy_tol * e0;
        (rel <= tol && energy_ok) || rel <= 1e-3 * tol || (energy_ok && rel <= 1e3 * tol)
    }

    /// Safeguarded Newton update shared by the static and dynamic steps: `state` += s·`du`
    /// with s = s₀, s₀/2, s₀/4, … (six tries; one when `backtrack` is false; s₀ = 1, or the
    /// collision-free fraction when a barrier term is present), taking the first
    /// trial state that can be evaluated — every element assembles and the internal and
    /// external forces are finite (a nodal-force term writes NaN for an inadmissible state,
    /// e.g. a node carried through a body). Residual growth alone is no reason to back off:
    /// large rotations legitimately raise it for an iteration or two, and divergence is
    /// caught by the iteration limit and the cut-back. Returns the trial state's strain
    /// energy, or, with `state` restored, the last element failure (None: forces not finite).
    /// The trial state is assembled with its tangent when `tangent` is true, else the
    /// residual alone (a linear step's last state; a chord iteration that keeps its factor).
    pub(super) fn safeguarded_update(&mut self, state: &mut State, du: &[f64], scales: &[f64], backtrack: bool, tangent: bool) -> Result<f64, Option<AssemblyFailure>> {
        let base = state.clone();
        // Barrier terms: start at the largest collision-free fraction (continuous collision
        // detection), so that no iterate tunnels through a surface between two admissible
        // states.
        let mut step = self.collision_free_fraction(&base, du);
        let mut last_failure = None;
        for _ in 0..6 {
            *state = base.clone();
            self.model.update(state, du, step);
            match self.assemble(state, scales, tangent) {
                Ok(e) if self.f_int.iter().chain(&self.f_ext).all(|v| v.is_finite()) => return Ok(e),
                Ok(_) => last_failure = None,
                Err(f) => last_failure = Some(f),
            }
            if !backtrack {
                break;
            }
            step *= 0.5;
        }
        *state = base;
        self.assembler.forget_mixed();
        Err(last_failure)
    }

    /// Largest fraction s ∈ [0, 1] of the update `du` from `base` that every barrier term
    /// allows (continuous collision detection, [`super::NodalForces::max_step`]); 1 without
    /// barrier terms (the others allow any step).
    pub(super) fn collision_free_fraction(&self, base: &State, du: &[f64]) -> f64 {
        if !self.nodal_forces.iter().any(|c| c.is_barrier()) {
            return 1.0;
        }
        let mut full = base.clone();
        self.model.update(&mut full, du, 1.0);
        self.nodal_forces.iter().map(|c| c.max_step(self.model, base, &full)).fold(1.0, f64::min)
    }

    /// Largest nodal tilt |(δα₁, δα₂)| of the free-DOF increment `du` (radians).
    pub(super) fn largest_rotation(&self, du: &[f64]) -> f64 {
        let eq = &self.model.dofs.eq;
        (0..self.model.n_nodes())
            .map(|n| {
                let a = [3, 4].map(|k| eq[NODE_DOFS * n + k]).map(|e| if e == FIXED { 0.0 } else { du[e] });
                a[0].hypot(a[1])
            })
            .fold(0.0, f64::max)
    }

    /// Report of a converged static increment `increment` of step `si` ending at fraction
    /// `tau` with load `scales`: its Newton record (iterations, residuals, cut-backs,
    /// indefinite tangent, strain energy), its stability (negative pivots, stiffness
    /// parameter, event) and the nodal-force terms' reports of its commit.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn static_report(
        &mut self,
        si: usize,
        step: &StepPlan,
        increment: usize,
        tau: f64,
        scales: &[f64],
        (iterations, residuals, cutbacks, indefinite, energy): (usize, Vec<f64>, usize, bool, f64),
        (negative_pivots, stiffness_parameter, stability_event): (Option<usize>, Option<f64>, Option<String>),
    ) -> IncrementReport {
        IncrementReport {
            step: si,
            step_name: step.name.clone(),
            increment,
            time: si as f64 + tau,
            scales: scales.to_vec(),
            iterations,
            residuals,
            cutbacks,
            indefinite_tangent: indefinite,
            energy,
            extra: std::mem::take(&mut self.extra_reports),
            negative_pivots,
            stiffness_parameter,
            stability_event,
            ..Default::default()
        }
    }

    /// Newton iterations for one increment ending at `scales`, starting from `state`.
    /// With `automatic` (automatic increments) the attempt stops as soon as divergence shows,
    /// and its force scale is at least the step's time-averaged force scale `automatic.0`
    /// (see below); the force scale it used is left in `automatic.1`.
    pub(super) fn attempt(&mut self, state: &mut State, scales: &[f64], linear: bool, mut automatic: Option<&mut (f64, f64)>, progress: &mut dyn FnMut(usize, f64)) -> Attempt {
        let early_exit = automatic.is_some();
        let n = self.model.dofs.n_free;
        let mut r = vec![0.0; n];
        let mut du = vec![0.0; n];
        let mut residuals = Vec::new();
        let mut indefinite = false;
        let mut energy0 = None;
        let mut chord = super::chord::Chord::new(self.settings.chord);
        self.model.apply_prescribed(state, scales);
        let mut energy = match self.assemble(state, scales, true) {
            Ok(e) => e,
            Err(f) => return failed(0, &residuals, Some(f.element), f.to_string()),
        };
        // Force scale of the increment: the reference of its first iteration (the loads at
        // the new level and the internal forces and reactions of the state it starts from)
        // is a floor for the later ones, so that an increment whose forces vanish at the
        // solution (a seam closing by a rigid motion, an unloading to zero) still measures
        // its residual against the forces it had to balance (the time-averaged force of
        // general-purpose FE codes), not against round-off. Automatic increments start from an
        // extrapolated state whose forces may all but balance (a seam closed by a rigid slide:
        // nothing but round-off is left to measure), so their floor is also the mean force scale
        // of the step's converged increments (the time-averaged force of Abaqus, §7.2.3 of its
        // Analysis User's Guide).
        let mut force_scale = None;
        for it in 0..self.settings.max_iterations {
            let (rel_now, reference) = self.residual(&mut r);
            let floor = *force_scale.get_or_insert_with(|| match automatic.as_deref_mut() {
                Some(scale) => {
                    scale.1 = reference;
                    reference.max(scale.0)
                }
                None => reference,
            });
            let rel = rel_now * reference / reference.max(floor);
            residuals.push(rel);
            progress(it, rel);
            if !rel.is_finite() {
                let el = self.worst_element(&r);
                return failed(it, &residuals, el, "residual is NaN or infinite".into());
            }
            if it > 0 && linear {
                return Attempt::Converged { iterations: it, residuals, indefinite, energy };
            }
            if it > 0 {
                let de: f64 = du.iter().zip(&r).map(|(a, b)| a * b).sum::<f64>().abs();
                // The residual below the tolerance at [`SETTLED_ITERATIONS`] successive
                // iterations counts as converged whatever the energy norm: the residual sits at
                // the floor that its terms' round-off allows (barrier contact: 10⁻⁹–10⁻⁸), and
                // an increment cut back to 10⁻⁷ of its step starts so close to equilibrium that
                // its first correction's energy norm — the energy test's reference — is
                // round-off too (measured: a two-ply flap with inter-ply contact, the residual
                // at 1–3·10⁻⁹ for 30 iterations, increment after increment).
                let settled = residuals.len() >= SETTLED_ITERATIONS && residuals[residuals.len() - SETTLED_ITERATIONS..].iter().all(|&q| q <= self.settings.residual_tol);
                if settled || self.converged(rel, de, energy0.unwrap_or(1.0)) {
                    // The increment report's inertia needs the converged state's tangent.
                    if let Err(f) = self.chord_tangent(&mut chord, state, scales) {
                        return failed(it, &residuals, Some(f.element), f.to_string());
                    }
                    return Attempt::Converged { iterations: it, residuals, indefinite, energy };
                }
                if it >= 3 && rel > 1e6 * residuals[0].max(1e-12) {
                    let el = self.worst_element(&r);
                    return failed(it, &residuals, el, "Newton diverging (residual grew a millionfold)".into());
                }
            }
            // Solve K du = −r, with the last factorization while the chord iteration keeps it.
            if chord.reuse(&residuals, self.timings.pattern_growths) {
                chord.reused_factor();
            } else {
                if let Err(f) = self.chord_tangent(&mut chord, state, scales) {
                    return failed(it, &residuals, Some(f.element), f.to_string());
                }
                let t = Instant::now();
                let kind = match self.cholesky.factorize(&self.values) {
                    Ok(k) => k,
                    Err(e) => {
                        self.timings.factorization += t.elapsed().as_secs_f64();
                        return failed(it, &residuals, None, format!("{e} (a mechanism: missing supports or an unconstrained node?)"));
                    }
                };
                self.timings.factorization += t.elapsed().as_secs_f64();
                chord.factorized(self.timings.pattern_growths);
                indefinite |= kind == FactorKind::Ldlt;
            }
            let t = Instant::now();
            du.iter_mut().zip(&r).for_each(|(d, r)| *d = -r);
            self.cholesky.solve(&mut du);
            self.timings.solve += t.elapsed().as_secs_f64();
            if du.iter().any(|v| !v.is_finite()) {
                return failed(it, &residuals, None, "linear solve produced NaN (singular tangent)".into());
            }
            let g0: f64 = du.iter().zip(&r).map(|(a, b)| a * b).sum();
            if energy0.is_none() {
                energy0 = Some(g0.abs().max(1e-300));
            }
            if early_exit {
                // Divergence caught early (automatic increments cut back at once): a first
                // correction that turns a director by more than a radian means the increment
                // is far outside Newton's basin; so does a residual grown twice in a row.
                let turn = self.largest_rotation(&du);
                if it == 0 && turn > MAX_FIRST_ROTATION {
                    let el = self.worst_element(&r);
                    return failed(it, &residuals, el, format!("increment too large: the first Newton correction turns a director by {turn:.2} rad"));
                }
                let n_r = residuals.len();
                if n_r >= 4 && residuals[n_r - 1] > residuals[n_r - 2] && residuals[n_r - 2] > residuals[n_r - 3] && residuals[n_r - 1] > residuals[0] {
                    let el = self.worst_element(&r);
                    return failed(it, &residuals, el, "Newton diverging (residual grew in two successive iterations)".into());
                }
            }
            // The admissibility-only update: an Armijo energy line search (with the 0.5 rad
            // director trust region) was measured slower here (sagging plate, 20×20: 476
            // against 237 Newton iterations with automatic increments; fixed increments
            // failed from one increment), as Newton on thin shells legitimately overshoots
            // the energy for an iteration or two.
            // A linear step needs no tangent at its solution; a chord iteration none while it
            // keeps its factorization.
            let tangent = !linear && chord.tangent_for_update(&residuals);
            let update = self.safeguarded_update(state, &du, scales, self.settings.line_search, tangent).map_err(|f| match f {
                Some(f) => f.to_string(),
                None => "line search found no finite state".into(),
            });
            match update {
                Ok(e) => {
                    energy = e;
                    chord.tangent_current = tangent;
                }
                Err(cause) => {
                    let el = self.worst_element(&r);
                    return failed(it, &residuals, el, cause);
                }
            }
        }
        let (rel, _) = self.residual(&mut r);
        residuals.push(rel);
        let el = self.worst_element(&r);
        failed(self.settings.max_iterations, &residuals, el, format!("no convergence in {} iterations", self.settings.max_iterations))
    }

    /// Runs all steps from `state`. `on_increment` receives each converged nominal increment
    /// with its state; `progress` is told about every iteration. On failure `state` holds
    /// the last converged configuration.
    pub fn run(
        &mut self,
        steps: &[StepPlan],
        state: &mut State,
        on_increment: &mut dyn FnMut(&IncrementReport, &State, &Self),
        progress: &mut dyn FnMut(&Progress),
    ) -> Result<(), SolveError> {
        let nl = self.model.loads.len();
        let mut scales = vec![0.0; nl];
        let total: usize = steps.iter().map(|s| s.increments.max(1)).sum();
        let mut done_before = 0usize;
        let mut tracker = super::arclength::StabilityTracker::default();
        for (si, step) in steps.iter().enumerate() {
            let start = scales.clone();
            let n_inc = step.increments.max(1);
            tracker.new_step();
            // The analysis clock at the start of the step; a step that does not move it
            // itself (arc length, buckling) ends one unit later (`contact::motion`).
            if let Some([start, _]) = step.clock {
                self.clock = start;
            }
            let clock0 = self.clock;
            self.clock_trial = self.clock;
            // Mixed-integration-point stresses in the static Newton iterations only: a time
            // step's energy line search wants the Hessian of its incremental potential
            // (measured on the sheet dropped onto a sphere, 32²: 764 Newton iterations
            // without, 1,193 with; on the sagging plate 20², 188–243 without, 72–118 with).
            // A linear step has a single tangent, so no later one to extrapolate to (the
            // records of the clamped plate at 200² would be 270 MB written for nothing).
            self.assembler.mixed = self.settings.mixed_stress && !step.linear && matches!(step.kind, StepKind::Static | StepKind::ArcLength { .. } | StepKind::DisplacementControl { .. });
            if !self.assembler.mixed {
                // Records are not kept up to date in this step: a later static step must not
                // extrapolate from them.
                self.assembler.forget_mixed();
            }
            match &step.kind {
                StepKind::Static | StepKind::StaticDamped => {}
                StepKind::Dynamic(ds) => {
                    let frac = (done_before as f64 / total as f64, n_inc as f64 / total as f64);
                    self.run_dynamic_step(si, step, ds, &start, state, on_increment, progress, frac.0, frac.1)?;
                    scales = step.target_scales.clone();
                    done_before += n_inc;
                    continue;
                }
                StepKind::ArcLength { .. } | StepKind::DisplacementControl { .. } => {
                    let frac0 = done_before as f64 / total as f64;
                    let frac1 = (done_before + n_inc) as f64 / total as f64;
                    scales = self.run_path(si, step, &start, state, &mut tracker, on_increment, &mut |p: &Progress| {
                        progress(&Progress { fraction: frac0 + p.fraction * (frac1 - frac0), ..p.clone() })
                    })?;
                    done_before += n_inc;
                    (self.clock, self.clock_trial) = (step.static_clock(clock0, 1.0), step.static_clock(clock0, 1.0));
                    continue;
                }
                StepKind::Buckling { modes, shift } => {
                    let report = self.run_buckling(si, step, &start, state, *modes, *shift)?;
                    on_increment(&report, state, self);
                    done_before += n_inc;
                    (self.clock, self.clock_trial) = (step.static_clock(clock0, 1.0), step.static_clock(clock0, 1.0));
                    continue;
                }
            }
            let at = |tau: f64| -> Vec<f64> { start.iter().zip(&step.target_scales).map(|(a, b)| a + tau * (b - a)).collect() };
            if !step.linear && step.automatic_increments && matches!(step.kind, StepKind::Static) {
                scales = self.run_automatic(si, step, &start, state, &mut tracker, on_increment, &mut |p: &Progress| {
                    progress(&Progress { fraction: (done_before as f64 + p.fraction * n_inc as f64) / total as f64, ..p.clone() })
                })?;
                done_before += n_inc;
                continue;
            }
            let mut tau = 0.0;
            let mut dtau = 1.0 / n_inc as f64;
            let mut cutback_level = 0usize;
            for inc in 1..=n_inc {
                let goal = inc as f64 / n_inc as f64;
                let mut iterations = 0;
                let mut cutbacks = 0;
                let mut indefinite = false;
                loop {
                    let next = (tau + dtau).min(goal);
                    let trial_scales = at(next);
                    let saved = state.clone();
                    let frac = (done_before as f64 + next * n_inc as f64) / total as f64;
                    let mut report_progress = |it: usize, res: f64| progress(&Progress { step: si, fraction: frac, iteration: it, residual: res, dynamic: None });
                    self.begin_nodal_increment((next - tau) * n_inc as f64);
                    self.begin_nodal_motion(step.static_clock(clock0, next), state);
                    let outcome = match step.kind {
                        StepKind::StaticDamped => self.attempt_damped(state, &trial_scales, &mut report_progress),
                        _ => self.attempt(state, &trial_scales, step.linear, None, &mut report_progress),
                    };
                    match outcome {
                        Attempt::Converged { iterations: its, residuals, indefinite: ind, energy } => {
                            iterations += its;
                            indefinite |= ind;
                            tau = next;
                            scales = trial_scales;
                            self.commit_nodal_forces(state);
                            if its <= 6 && cutback_level > 0 {
                                cutback_level -= 1;
                                dtau *= 2.0;
                            }
                            if (tau - goal).abs() < 1e-12 {
                                tau = goal;
                                let stability = if step.linear {
                                    (None, None, None)
                                } else {
                                    self.stability_at(state, &start, &step.target_scales, &mut tracker)
                                };
                                let mut report = self.static_report(si, step, inc, tau, &scales, (iterations, residuals, cutbacks, indefinite, energy), stability);
                                report.damped = matches!(step.kind, StepKind::StaticDamped);
                                on_increment(&report, state, self);
                                break;
                            }
                        }
                        Attempt::Failed { iteration, residuals, worst_element, cause } => {
                            let cause = if cutback_level >= self.settings.max_cutbacks {
                                super::diagnose::explain(self.model, state, &cause, indefinite || self.cholesky.kind() == FactorKind::Ldlt)
                            } else {
                                cause
                            };
                            *state = saved;
                            self.assembler.forget_mixed();
                            iterations += iteration;
                            if cutback_level >= self.settings.max_cutbacks {
                                let cause = format!("{cause}; increment cut back {} times", cutback_level);
                                return Err(SolveError::static_increment(si, step, tau, iteration, residuals, worst_element, cause));
                            }
                            cutback_level += 1;
                            cutbacks += 1;
                            dtau *= 0.5;
                        }
                    }
                }
            }
            done_before += n_inc;
        }
        Ok(())
    }
}
