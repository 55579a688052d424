//! Membrane relaxation of a mapped state (a-posteriori refinement, issue 18 item 1): the
//! interpolated state made consistent with the refined mesh's membrane before the last step
//! continues there.
//!
//! Why: interpolation puts the refined mesh through the coarse rest state, whose chord
//! lengths are the coarse mesh's. A finer mesh through the same surface is longer by
//! ≈ (hκ)²/24 per element and its old node lines sit where the coarse discretisation put
//! them, O(h²) off the finer one's equilibrium *along* the surface, an error that
//! accumulates over the part. Fabric's membrane (E t) is ~10⁴ times its weight per bending
//! length, so that tangential O(h²) mismatch is a membrane force far above the load (the
//! interpolated Peirce strip: ‖f_int − f_ext‖ = 3.7·10³ ‖f_ext‖), while the normal shape —
//! what bending and the load decide — is already close. Relaxing only the new nodes cannot
//! remove it (the old lines' spacing is the error: measured 3.7·10³ → 9·10² ‖f_ext‖).
//!
//! How: proximal-point iterations (Rockafellar, SIAM J. Control Optim. 14, 1976) of the
//! refined mesh's total potential with a *normal* proximal term: each stage is a static
//! Newton solve of
//!
//!   min Π(x, d) + ½ Σ_n k_n ((x_n − x̄_n)·n̄_n)²,   k_n = m_n / τ²,
//!
//! x̄_n, n̄_n the node's position and unit mid-surface normal at the stage's start, m_n its
//! lumped mass, τ the stage's time scale. Translations in the tangent plane and the
//! directors are free: the membrane and transverse-shear mismatch (stiff, well conditioned)
//! relaxes in a few Newton iterations, including the global slide of the old node lines;
//! the normal spring is a backward-Euler step of size τ with mass on the normal motion only
//! and no velocity (pseudo-transient continuation, Kelley & Keyes, SIAM J. Numer. Anal. 35,
//! 1998), which keeps the soft bending modes, whose forces are of the load's order, from
//! taking the large steps that a bare static Newton takes from the mapped state. What the
//! spring holds is left as residual: m_n/τ² times the normal correction still wanted.
//!
//! The mapping is the interpolation and one such stage ([`TAU_S`]); the continuation then
//! starts with the same minimisation without the spring ([`stage`] with no τ) and the last step's
//! time steps to rest, from Δt = [`CONTINUATION_DT_FACTOR`] τ.
//!
//! Each stage is solved as one backward-Euler step of [`STAGE_DT_S`] from rest with the
//! incremental potential of the `Dynamic` steps (PSD-projected element Hessians, energy line
//! search): its inertia, ρ_A/(1 s)², is ~10⁻⁵ of the spring's, and the plain static Newton
//! with its Δu·r line search stalled on the sheet on the sphere (relative residual 1.0 → 0.65
//! in 30 iterations, contact and folds) where this converged in 17 iterations.

use nalgebra::{Matrix3, Vector3};
use serde_json::json;

use crate::element::NODE_DOFS;
use crate::model::{Model, State};
use crate::scene::{BuiltScene, Scene};
use crate::solver::{DynamicSettings, LumpedMass, NodalForces, Solver, StepKind, StepPlan};

/// Time scale τ of the proximal stage (s): k_n = m_n/τ² is the stiffness of the normal
/// spring; under gravity it lets a node move g τ² = 0.25 mm normal to the surface per unit
/// of its own weight. Measured on the Peirce strip (`tests/refine.rs`): mapped n × 2 →
/// 2n × 2, τ = 4.5 ms (k = 10⁴ N/m³) left ‖r‖/‖f_ext‖ = 1.4, 0.29, 0.061 for n = 8, 16, 32
/// (interpolated: 3.7·10³, 3.0·10³, 2.1·10³), 10 times stiffer 83, 24, 4.8, 10 times softer
/// failed from the 8 × 2 state (a director through the tangent plane).
pub const TAU_S: f64 = 5e-3;

/// The continuation's first time step after a converged relaxation, in units of τ (the
/// default 1 ms first step grows ×1.5 per step: on the strip 13 of its 16 steps to rest
/// were that ramp).
pub const CONTINUATION_DT_FACTOR: f64 = 10.0;

/// Length of the backward-Euler step that solves a stage (s; module doc): one step, not cut
/// back (a stage that does not converge is skipped).
pub const STAGE_DT_S: f64 = 1.0;

/// Newton iterations allowed to a stage.
pub const STAGE_ITERATIONS: usize = 30;

/// The normal proximal spring ½ k_n ((x_n − x̄_n)·n̄_n)² on every node (module doc).
struct NormalAnchor {
    centre: Vec<Vector3<f64>>,
    normal: Vec<Vector3<f64>>,
    stiffness: Vec<f64>,
    energy: f64,
}

impl NodalForces for NormalAnchor {
    fn add(&mut self, model: &Model, state: &State, f_ext: &mut [f64], jacobian: &mut Vec<(usize, Matrix3<f64>)>) {
        self.energy = 0.0;
        for (a, (&k, n)) in self.stiffness.iter().zip(&self.normal).enumerate() {
            if k == 0.0 {
                continue;
            }
            let offset = (model.position(state, a) - self.centre[a]).dot(n);
            self.energy += 0.5 * k * offset * offset;
            for c in 0..3 {
                f_ext[NODE_DOFS * a + c] -= k * offset * n[c];
            }
            jacobian.push((a, -k * n * n.transpose()));
        }
    }

    fn potential(&self) -> Option<f64> {
        Some(self.energy)
    }
}

/// What one stage did: its Newton iterations, the relative static residual of the state
/// after it (the rest test's measure, `analysis_sequence::mapped_residual`) and, if it did
/// not converge, why (the state is then the one it started from).
#[derive(Clone, Debug)]
pub struct Stage {
    /// Newton iterations of the stage (also those of a stage that failed).
    pub newton_iterations: usize,
    /// ‖f_int − f_ext‖ / max(‖f_ext‖, ‖f_int‖ incl. reactions) after the stage.
    pub static_residual: f64,
    /// The solver's diagnosis when the stage did not converge.
    pub failed: Option<String>,
}

/// One proximal stage (module doc) on the state `state` of the refined scene (`sc`, `b`)
/// under its last step's target loads, with the scene's contact and compliant seams
/// (`analysis::attach_terms`): the minimiser of Π + the normal
/// spring of time scale `tau` (None: no spring, the minimisation of Π alone from `state`).
/// A stage that does not converge leaves `state` as it was (`Stage::failed`); Err only when
/// the solver cannot be set up.
pub fn stage(sc: &Scene, b: &BuiltScene, state: &mut State, tau: Option<f64>) -> Result<Stage, String> {
    let model = &b.model;
    let scales = b.steps.last().map(|s| s.target_scales.clone()).unwrap_or_default();
    let mut solver = Solver::new(model, sc.solver.clone())?;
    crate::analysis::attach_terms(&mut solver, model, b)?;
    if let Some(tau) = tau {
        let mass = LumpedMass::from_model(model, 1.0).translational;
        solver.add_nodal_forces(Box::new(NormalAnchor {
            centre: (0..model.n_nodes()).map(|a| model.position(state, a)).collect(),
            normal: super::map::nodal_normals(model, state),
            stiffness: mass.iter().map(|m| m / (tau * tau)).collect(),
            energy: 0.0,
        }));
    }
    solver.start_nodal_forces_from(state);
    let settings = DynamicSettings { dt: STAGE_DT_S, dt_min: STAGE_DT_S, duration: STAGE_DT_S, incremental_potential: Some(true), max_iterations: STAGE_ITERATIONS, require_stable: false, ..Default::default() };
    let plan = StepPlan { name: "membrane relaxation".into(), increments: 1, linear: false, automatic_increments: false, target_scales: scales, kind: StepKind::Dynamic(settings), clock: None };
    let mut newton_iterations = 0;
    let saved = state.clone();
    let failed = match solver.run(&[plan], state, &mut |r, _, _| newton_iterations += r.iterations, &mut |_| {}) {
        Ok(()) => None,
        Err(e) => {
            *state = saved;
            newton_iterations += e.iteration;
            Some(e.to_string())
        }
    };
    let static_residual = crate::analysis_sequence::mapped_residual(sc, b, state)?;
    Ok(Stage { newton_iterations, static_residual, failed })
}

/// The stage's report entry: τ, iterations, residual and the failure if any.
pub fn report(tau: Option<f64>, s: &Stage) -> serde_json::Value {
    json!({ "tau_s": tau, "newton_iterations": s.newton_iterations, "static_residual": s.static_residual, "failed": s.failed })
}
