//! One time step of a `Dynamic` step (see `dynamics`): the Newton solve of backward Euler or
//! generalized-α on the effective tangent K + c M, and, for steps to rest and with barrier
//! contact, the minimisation of the step's incremental potential
//! ½‖u − ũ‖²_M/Δt² + damping + Ψ − f·u + contact (Li et al. 2020, *Incremental Potential
//! Contact*, §4): Newton directions from the exact tangent while it is positive definite,
//! else — without surface contact — from the tangent with a small diagonal shift
//! (`Solver::shifted_factor`), else from the tangent with the element Hessians — and if need be the contact pairs'
//! Hessians — projected onto the positive semi-definite cone (Teran et al. 2005), an Armijo
//! energy line search filtered by collision detection, and inexact steps away from rest
//! (Kelley & Keyes 1998).

use std::time::Instant;

use nalgebra::Vector3;

use super::dynamics::DynamicSettings;
use super::inertia::{Coefficients, LumpedMass, TimeScheme};
use super::linear::FactorKind;
use super::newton::Solver;
use crate::element::NODE_DOFS;
use crate::model::{State, FIXED, UNTIED};

/// Inexact time steps on the way to rest: the last Newton correction may move nodes by this
/// fraction of the step's largest nodal motion (see `time_step`). 10⁻² against the former
/// 10⁻³: on eight sheet-on-sphere drops not tuned for (SVK 16²–32², cotton and light cotton,
/// sphere off centre, a higher drop, friction 0.2–0.6) 5,744 instead of 6,905 Newton
/// iterations. 10⁻¹ saved more (5,194) but left the rest state of the hanging cloth of
/// `tests/pseudo_transient.rs` 5·10⁻⁶ m from the static equilibrium (bound 4·10⁻⁶ m).
const INEXACT_MOTION: f64 = 1e-2;

/// Largest relative residual of the best iterate at which a time step to rest that did not
/// converge is accepted instead of being retried with a smaller Δt (see
/// `Solver::accept_best`); 10³ × the default Newton residual tolerance, the bound the Newton
/// test already accepts with a converged energy norm.
const INEXACT_BEST: f64 = 1e-4;

/// Diagonal shifts τ of a descent step's indefinite effective tangent (see
/// `Solver::shifted_factor`): τ = 10⁻³, then 10⁻², of each diagonal entry's magnitude.
const SHIFTS: [f64; 2] = [1e-3, 1e-2];

/// The second shifted Newton iteration of a time step ([`SHIFT_POOR_ITERATIONS`]) whose
/// residual falls by less than this factor ends the shift for the rest of the time step: its
/// later indefinite tangents are projected instead.
const SHIFT_CONTRACTION: f64 = 0.5;
/// Slowly contracting shifted iterations a time step tolerates (the first one after an
/// increase of Δt often does not contract on any tangent).
const SHIFT_POOR_ITERATIONS: usize = 2;

/// Converged state of the previous time step: positions, directors and their rates.
#[derive(Clone)]
pub(super) struct Kinematics {
    pub(super) state: State,
    /// Translational velocities and accelerations.
    pub(super) v: Vec<Vector3<f64>>,
    pub(super) a: Vec<Vector3<f64>>,
    /// Director rates and accelerations.
    pub(super) w: Vec<Vector3<f64>>,
    pub(super) wa: Vec<Vector3<f64>>,
    /// Static residual f_int − f_ext on the free DOFs (generalized-α force average).
    pub(super) r: Vec<f64>,
}

/// Outcome of one time step's Newton solve.
pub(super) enum TimeStep {
    Converged { iterations: usize, residuals: Vec<f64>, static_residual: f64, energy: f64, static_r: Vec<f64> },
    /// The effective tangent was not positive definite: Δt too large for this state.
    /// `projected`: the element Hessians had been projected (a descent step), so what stays
    /// indefinite comes from terms outside the elements.
    Indefinite { iteration: usize, residuals: Vec<f64>, projected: bool },
    Failed { iteration: usize, residuals: Vec<f64>, worst_element: Option<usize>, cause: String },
}

impl<'m> Solver<'m> {
    /// Adds the scheme's inertia and damping forces (and, for generalized-α, the weighted
    /// static residual of the previous step) to the free residual `r`, and c·M to the
    /// diagonal of the assembled tangent; returns ‖f_inertia‖.
    fn add_inertia(&mut self, state: &State, prev: &Kinematics, mass: &LumpedMass, co: &Coefficients, r: &mut [f64]) -> f64 {
        let eq = &self.model.dofs.eq;
        let col_ptr = &self.assembler.pattern.col_ptr;
        let c = co.tangent();
        let wp = co.previous_force_weight();
        if wp != 0.0 {
            r.iter_mut().zip(&prev.r).for_each(|(x, p)| *x += wp * p);
        }
        let mut norm2 = 0.0;
        for n in 0..self.model.n_nodes() {
            let base = NODE_DOFS * n;
            let m = mass.translational[n];
            let a = co.inertia(state.u[n] - prev.state.u[n], prev.v[n], prev.a[n]);
            for k in 0..3 {
                let e = eq[base + k];
                if e != FIXED {
                    let f = m * a[k];
                    r[e] += f;
                    norm2 += f * f;
                    self.values[col_ptr[e + 1] - 1] += m * c;
                } else if self.model.dofs.tie_of[base + k] != UNTIED {
                    // A tied slave's inertia acts through its masters (Tᵀ M T).
                    let exp = self.model.dofs.expand(base + k);
                    let f = m * a[k];
                    exp.iter().for_each(|&(em, w)| r[em] += w * f);
                    norm2 += f * f;
                    self.assembler.pattern.add_weighted(&mut self.values, &exp, m * c);
                }
            }
            let j = mass.rotary[n];
            let fr = &state.frames[n];
            let ad = co.inertia(fr.d - prev.state.frames[n].d, prev.w[n], prev.wa[n]);
            for (k, t) in [fr.t1, fr.t2].iter().enumerate() {
                let e = eq[base + 3 + k];
                if e != FIXED {
                    let f = j * t.dot(&ad);
                    r[e] += f;
                    norm2 += f * f;
                    self.values[col_ptr[e + 1] - 1] += j * c;
                } else if self.model.dofs.tie_of[base + 3 + k] != UNTIED {
                    let exp = self.model.dofs.expand(base + 3 + k);
                    let f = j * t.dot(&ad);
                    exp.iter().for_each(|&(em, w)| r[em] += w * f);
                    norm2 += f * f;
                    self.assembler.pattern.add_weighted(&mut self.values, &exp, j * c);
                }
            }
        }
        norm2.sqrt()
    }

    /// Inertia and damping potential of a backward-Euler step (the kinetic part of the
    /// incremental potential, Li et al. 2020 eq. 3, with mass damping):
    /// Σ m (½|Δu − Δt v_n|²/Δt² + ½ α_M |Δu|²/Δt) + J (same for the director d), Δu = u − u_n;
    /// its gradient is the inertia force of [`Solver::add_inertia`].
    fn inertia_potential(&self, state: &State, prev: &Kinematics, mass: &LumpedMass, co: &Coefficients) -> f64 {
        let (dt, a) = (co.dt, co.damping);
        let term = |dx: Vector3<f64>, v: Vector3<f64>| 0.5 * (dx - v * dt).norm_squared() / (dt * dt) + 0.5 * a * dx.norm_squared() / dt;
        (0..self.model.n_nodes())
            .map(|n| {
                mass.translational[n] * term(state.u[n] - prev.state.u[n], prev.v[n])
                    + mass.rotary[n] * term(state.frames[n].d - prev.state.frames[n].d, prev.w[n])
            })
            .sum()
    }

    /// One time step of size `dt` from `prev` at load scales `scales`; `state` enters as the
    /// predictor and leaves as the solution.
    ///
    /// Backward Euler with conservative loads and nodal forces is solved as the minimisation
    /// of the incremental potential E(x) = inertia potential + Π(x) (Li et al. 2020, §3):
    /// Newton directions from the exact tangent K + c M while it is positive definite,
    /// otherwise (for the rest of the step) from the tangent with every element's Hessian
    /// projected onto the PSD cone (always a descent direction), each filtered by the
    /// collision-free bound of the contact terms and an Armijo energy line search. Other
    /// schemes (generalized-α) and non-conservative terms take the safeguarded Newton update.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn time_step(
        &mut self,
        state: &mut State,
        prev: &Kinematics,
        mass: &LumpedMass,
        dt: f64,
        ds: &DynamicSettings,
        scales: &[f64],
        progress: &mut dyn FnMut(usize, f64),
    ) -> TimeStep {
        let n = self.model.dofs.n_free;
        let mut r = vec![0.0; n];
        let mut du = vec![0.0; n];
        let mut residuals = Vec::new();
        let mut energy0: Option<f64> = None;
        let mut static_r = vec![0.0; n];
        let co = Coefficients::new(&ds.scheme, dt, ds.mass_damping);
        let incremental_potential = self.incremental_potential(ds);
        let to_rest = incremental_potential && ds.duration == 0.0;
        let mut last_correction = f64::INFINITY;
        // An iteration of this time step needed the contact pairs' Hessians projected.
        let mut project_contact = false;
        // The lowest relative residual of the step so far, and (kept only once it is within
        // INEXACT_BEST, the only case `accept_best` uses it) that iterate: (residual, state,
        // strain energy, static residual, static residual vector).
        let mut best_rel = f64::INFINITY;
        let mut best: Option<(f64, State, f64, f64, Vec<f64>)> = None;
        // Whether an indefinite tangent may still be shifted in this time step, and whether
        // the last iteration's was.
        let mut shift = !self.nodal_forces.iter().any(|c| c.indefinite_pairs());
        let mut shifted = false;
        // Shifted iterations of this time step that did not halve the residual.
        let mut poor = 0;
        self.assembler.project = false;
        // An indefinite tangent is projected by assembling the same state again: keep the
        // element responses so that the re-assembly only projects and scatters them.
        self.assembler.keep_responses = incremental_potential;
        self.model.apply_prescribed(state, scales);
        let mut energy = match self.assemble(state, scales, true) {
            Ok(e) => e,
            Err(f) => {
                return TimeStep::Failed { iteration: 0, residuals, worst_element: Some(f.element), cause: f.to_string() };
            }
        };
        for it in 0..=ds.max_iterations {
            let (static_rel, reference) = self.residual(&mut r);
            static_r.copy_from_slice(&r);
            let inertia = self.add_inertia(state, prev, mass, &co, &mut r);
            let rel = r.iter().map(|v| v * v).sum::<f64>().sqrt() / reference.max(inertia);
            if shifted && residuals.last().is_some_and(|&p| rel > SHIFT_CONTRACTION * p) {
                poor += 1;
                if poor >= SHIFT_POOR_ITERATIONS {
                    shift = false;
                }
            }
            shifted = false;
            residuals.push(rel);
            progress(it, rel);
            if !rel.is_finite() {
                let el = self.worst_element(&r);
                return TimeStep::Failed { iteration: it, residuals, worst_element: el, cause: "residual is NaN or infinite".into() };
            }
            if it > 0 {
                let de = du.iter().zip(&r).map(|(a, b)| a * b).sum::<f64>().abs();
                // Pseudo-transient steps away from rest need not be solved to round-off
                // (Kelley & Keyes 1998 take a single Newton step per pseudo-time step): accept
                // when the last correction moved no node by more than INEXACT_MOTION of this
                // step's largest motion and the residual is below 10⁻². Near rest the step's
                // motion vanishes and the test becomes the strict one; rest itself is judged
                // on the static residual and the kinetic energy.
                let motion = (0..self.model.n_nodes()).map(|k| (state.u[k] - prev.state.u[k]).norm()).fold(0.0, f64::max);
                let inexact_ok = to_rest && rel <= 1e-2 && last_correction <= INEXACT_MOTION * motion;
                if self.converged(rel, de, energy0.unwrap_or(1.0)) || inexact_ok {
                    self.assembler.project = false;
                    return TimeStep::Converged { iterations: it, residuals, static_residual: static_rel, energy, static_r };
                }
            }
            if to_rest && rel < best_rel {
                best_rel = rel;
                if rel <= INEXACT_BEST {
                    best = Some((rel, state.clone(), energy, static_rel, static_r.clone()));
                }
            }
            // Leaving a saddle of the incremental potential: the energy falls but the residual
            // grows geometrically from its best value (the descent follows negative
            // curvature towards a distant minimum). Stop at once: the best iterate ends the
            // step if it is close enough, else Δt is cut.
            let diverging = to_rest
                && residuals.len() >= 4
                && rel > 3.0 * best_rel
                && residuals[residuals.len() - 4..].windows(2).all(|w| w[1] > 1.2 * w[0]);
            if diverging {
                self.assembler.project = false;
                if let Some(done) = self.accept_best(state, scales, &mut best, it, &mut residuals) {
                    return done;
                }
                let el = self.worst_element(&r);
                return TimeStep::Failed { iteration: it, residuals, worst_element: el, cause: "the residual grew geometrically from its best value (a saddle of the step's potential)".into() };
            }
            if it == ds.max_iterations {
                break;
            }
            let descent = incremental_potential && self.potential(state, scales, energy).is_some();
            let t = Instant::now();
            // A descent step replaces an indefinite tangent by the projected one: only whether
            // K + c M is positive definite matters then, not its inertia (no LDLᵀ).
            let mut kind = if descent {
                if self.cholesky.factorize_definite(&self.values) { Ok(FactorKind::Llt) } else { Ok(FactorKind::Ldlt) }
            } else {
                self.cholesky.factorize(&self.values)
            };
            self.timings.factorization += t.elapsed().as_secs_f64();
            if descent && !matches!(kind, Ok(FactorKind::Llt)) && shift && self.shifted_factor() {
                kind = Ok(FactorKind::Llt);
                shifted = true;
                self.timings.projected_iterations += 1;
            }
            if descent && !matches!(kind, Ok(FactorKind::Llt)) {
                // Indefinite: project the element Hessians for this iteration's direction; if
                // that is still indefinite, the rest comes from terms outside the elements that
                // keep their exact Hessian (surface contact pairs): project theirs too — at
                // once in the later iterations of a time step that needed it. (The nodal
                // evaluation kept for this state has the exact blocks: it is evaluated anew,
                // and the projected one is not kept.)
                let mut contact = project_contact;
                loop {
                    self.assembler.project = true;
                    if contact {
                        self.nodal_cache.forget();
                        self.nodal_forces.iter_mut().for_each(|c| c.project_hessians(true));
                    }
                    let assembled = self.assemble(state, scales, true);
                    if contact {
                        self.nodal_forces.iter_mut().for_each(|c| c.project_hessians(false));
                        self.nodal_cache.forget();
                    }
                    if let Err(f) = assembled {
                        self.assembler.project = false;
                        return TimeStep::Failed { iteration: it, residuals, worst_element: Some(f.element), cause: f.to_string() };
                    }
                    self.residual(&mut r);
                    self.add_inertia(state, prev, mass, &co, &mut r);
                    let t = Instant::now();
                    // Only whether it is positive definite matters (an indefinite one ends
                    // the time step), so no LDLᵀ fallback.
                    kind = if self.cholesky.factorize_definite(&self.values) { Ok(FactorKind::Llt) } else { Ok(FactorKind::Ldlt) };
                    self.timings.factorization += t.elapsed().as_secs_f64();
                    if contact || matches!(kind, Ok(FactorKind::Llt)) {
                        break;
                    }
                    contact = true;
                    project_contact = true;
                }
            }
            if self.assembler.project {
                self.timings.projected_iterations += 1;
                // The next tangent (assembled at the accepted state) is the exact one again.
                self.assembler.project = false;
            }
            match kind {
                Ok(FactorKind::Llt) => {}
                Ok(FactorKind::Ldlt) | Err(_) => {
                    self.assembler.project = false;
                    return TimeStep::Indefinite { iteration: it, residuals, projected: descent };
                }
            }
            let t = Instant::now();
            du.iter_mut().zip(&r).for_each(|(d, r)| *d = -r);
            self.cholesky.solve(&mut du);
            self.timings.solve += t.elapsed().as_secs_f64();
            if du.iter().any(|v| !v.is_finite()) {
                self.assembler.project = false;
                return TimeStep::Failed { iteration: it, residuals, worst_element: None, cause: "linear solve produced NaN".into() };
            }
            let slope = du.iter().zip(&r).map(|(a, b)| a * b).sum::<f64>();
            if energy0.is_none() {
                energy0 = Some(slope.abs().max(1e-300));
            }
            let before = state.u.clone();
            let outcome = if descent {
                let kinetic = self.inertia_potential(state, prev, mass, &co);
                let load = self.model.load_potential(state, scales).unwrap_or(0.0);
                let nodal = self.nodal_potential.unwrap_or(0.0);
                let pi0 = energy + load + nodal + kinetic;
                let magnitude = energy.abs() + load.abs() + nodal.abs() + kinetic.abs();
                let searched = self.energy_line_search(state, &du, scales, slope, pi0, magnitude, &mut |s: &Self, st: &State| s.inertia_potential(st, prev, mass, &co));
                searched.map(|d| {
                    self.timings.line_search_cuts += d.cuts;
                    d.energy
                })
                .map_err(|(failing, cause)| (failing.or_else(|| self.worst_element(&r)), format!("energy line search failed: {cause}")))
            } else {
                // Backtracking along the Newton direction keeps the time step.
                self.safeguarded_update(state, &du, scales, true, true).map_err(|failure| match failure {
                    Some(f) => (Some(f.element), f.to_string()),
                    None => (None, "no admissible trial state along the Newton direction (a nodal-force term, e.g. contact with a node through a body, rejected every backtracked step)".into()),
                })
            };
            match outcome {
                Ok(e) => {
                    energy = e;
                    last_correction = (0..self.model.n_nodes()).map(|k| (state.u[k] - before[k]).norm()).fold(0.0, f64::max);
                }
                Err((el, cause)) => {
                    self.assembler.project = false;
                    if let Some(done) = self.accept_best(state, scales, &mut best, it + 1, &mut residuals) {
                        return done;
                    }
                    return TimeStep::Failed { iteration: it, residuals, worst_element: el, cause };
                }
            }
        }
        self.assembler.project = false;
        if let Some(done) = self.accept_best(state, scales, &mut best, ds.max_iterations, &mut residuals) {
            return done;
        }
        let el = self.worst_element(&r);
        TimeStep::Failed {
            iteration: ds.max_iterations,
            residuals,
            worst_element: el,
            cause: format!("no convergence in {} iterations", ds.max_iterations),
        }
    }

    /// Factorizes the assembled effective tangent K + c M, found indefinite, with its diagonal
    /// shifted by τ |A_ii| for τ in [`SHIFTS`] until one is positive definite (a
    /// Levenberg–Marquardt modification of the Hessian, Nocedal & Wright 2006 §3.4; its
    /// direction descends on the step's potential like the projected one's). Returns whether
    /// one was (the factor is then ready); the assembled values are left unshifted either way.
    ///
    /// Used before the element-wise PSD projection when no nodal term keeps indefinite pair
    /// Hessians: on limp fabric folding under gravity nearly every element has compressive
    /// negative curvature that its neighbours' bending and the inertia hold, and projecting
    /// each element's Hessian (eigenvalues mirrored) discards that, so the projected
    /// directions converged only linearly (10–20 % a Newton iteration) and most rejected time
    /// steps of the sheet dropped on a sphere were those. Measured (Newton iterations, one
    /// thread): SVK 64² sequenced, finest level 751 → 456 (103 → 63 time steps); SVK 48²
    /// sequenced 731 → 696; cotton 48² sequenced 858 → 698; cotton 32² 890 → 891 (but 15 %
    /// less CPU: no element re-projection); SVK 32² off-centre, μ 0.25, 1253 → 1161. With
    /// surface contact it did not pay (the three-ply sleeve on the arm 626 → 787, the hood
    /// 1525 → 1587), so it is not used there. On the seeded faille Cusick specimen (stiff
    /// membrane, penalty disc contact) the shifted iterations contracted only 5–15 % each and
    /// failed time steps the projection converged (128 sectors 296 → 426 iterations), so the
    /// second shifted iteration of a time step that does not halve the residual
    /// ([`SHIFT_CONTRACTION`], [`SHIFT_POOR_ITERATIONS`]) ends the shift for that time step
    /// (now / always shifted / never): Cusick 128 sectors 328 / 426 / 296, Auto 732 / 1121 /
    /// 673; SVK 64² sequenced finest level 449 / 456 / 751, SVK 48² 537 / 696 / 731, cotton
    /// 48² 695 / 698 / 858, cotton 32² 1048 / 891 / 890, SVK 32² off-centre 1083 / 1161 /
    /// 1253 (4872 / 5449 / 5452 in all; ending the shift at the first such iteration: 5155).
    fn shifted_factor(&mut self) -> bool {
        let col_ptr = &self.assembler.pattern.col_ptr;
        let diag: Vec<f64> = (0..self.model.dofs.n_free).map(|e| self.values[col_ptr[e + 1] - 1]).collect();
        let mut ok = false;
        for tau in SHIFTS {
            for (e, d) in diag.iter().enumerate() {
                self.values[col_ptr[e + 1] - 1] = d + tau * d.abs();
            }
            let t = Instant::now();
            ok = self.cholesky.factorize_definite(&self.values);
            self.timings.factorization += t.elapsed().as_secs_f64();
            if ok {
                break;
            }
        }
        for (e, d) in diag.iter().enumerate() {
            self.values[col_ptr[e + 1] - 1] = *d;
        }
        ok
    }

    /// Whether the time steps of a Dynamic step with settings `ds` minimise their incremental
    /// potential (`DynamicSettings::incremental_potential`; default: backward-Euler steps to
    /// rest, and any backward-Euler step with barrier contact).
    pub(super) fn incremental_potential(&self, ds: &DynamicSettings) -> bool {
        let wanted = ds.incremental_potential.unwrap_or_else(|| ds.duration == 0.0 || self.nodal_forces.iter().any(|c| c.is_barrier()));
        wanted && matches!(ds.scheme, TimeScheme::BackwardEuler)
    }

    /// A step to rest whose Newton iteration did not converge (it diverged from a saddle of
    /// the incremental potential after nearly reaching it, or stalled) ends at its best
    /// iterate when that iterate's relative residual is within [`INEXACT_BEST`] (`best` holds
    /// it only then): `state` is
    /// set to it and assembled again (forces and contact state consistent for the commit).
    /// Pseudo-transient steps away from rest need not be exact (Kelley & Keyes 1998); rest
    /// itself is still judged on the static residual and the kinetic energy.
    fn accept_best(&mut self, state: &mut State, scales: &[f64], best: &mut Option<(f64, State, f64, f64, Vec<f64>)>, iterations: usize, residuals: &mut Vec<f64>) -> Option<TimeStep> {
        let (rel, at, energy, static_residual, static_r) = best.take()?;
        *state = at;
        self.assembler.forget_mixed();
        self.assemble(state, scales, true).ok()?;
        residuals.push(rel);
        Some(TimeStep::Converged { iterations, residuals: std::mem::take(residuals), static_residual, energy, static_r })
    }
}
