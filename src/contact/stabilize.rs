//! Viscous pseudo-time stabilization for drape: a nodal force c·a·(u − u_prev) resisting
//! the motion since the last converged increment (a = the node's tributary area, c in
//! N/m³), tangent c·a·I on the translations.
//!
//! Each increment is then one backward-Euler step of the gradient flow
//! c·a·u̇ = f_ext − f_int with unit pseudo-time step (dynamic relaxation without inertia;
//! Underwood 1983, and the "artificial damping" of Abaqus *STATIC, STABILIZE). It
//! regularises the unsupported flat sheet (zero transverse stiffness at zero load), rigid
//! in-plane sliding on frictionless bodies and snap-through into folds. The force vanishes
//! when the motion stops, so a settled state is a static equilibrium; the summary reports
//! the remaining ratio ‖f_visc‖/‖f_ext‖ so a user can see how settled it is.
//! This is a stop-gap until the damped implicit dynamics solver (issue 3) is merged.

use nalgebra::{Matrix3, Vector3};
use serde::Serialize;

use crate::element::NODE_DOFS;
use crate::model::{Model, State};
use crate::solver::NodalForces;

/// Viscous stabilization of a model's nodes.
pub struct Stabilization {
    /// Coefficient c (N/m³).
    pub coefficient: f64,
    area: Vec<f64>,
    previous: Vec<Vector3<f64>>,
    /// Per committed increment: ‖f_visc‖ and the largest nodal motion.
    pub history: Vec<StabilizationIncrement>,
}

/// What the stabilization did in one increment.
#[derive(Clone, Debug, Default, Serialize)]
pub struct StabilizationIncrement {
    /// ‖c·a·(u − u_prev)‖ over all nodes (N).
    pub force_norm: f64,
    /// Largest nodal motion in the increment (m).
    pub max_motion: f64,
}

impl Stabilization {
    /// Stabilization with coefficient `c` over all nodes of `model`.
    pub fn new(model: &Model, c: f64) -> Self {
        let mut area = vec![0.0; model.n_nodes()];
        for (e, def) in model.elements.iter().enumerate() {
            let a = model.element(e).reference_area();
            for &n in &def.nodes {
                area[n] += 0.25 * a;
            }
        }
        Self { coefficient: c, area, previous: vec![Vector3::zeros(); model.n_nodes()], history: Vec::new() }
    }
}

impl NodalForces for Stabilization {
    fn add(&mut self, _model: &Model, state: &State, f_ext: &mut [f64], jacobian: &mut Vec<(usize, Matrix3<f64>)>) {
        for (n, (&a, prev)) in self.area.iter().zip(&self.previous).enumerate() {
            let f = (state.u[n] - prev) * (self.coefficient * a);
            for k in 0..3 {
                f_ext[NODE_DOFS * n + k] -= f[k];
            }
            jacobian.push((n, Matrix3::identity() * (-self.coefficient * a)));
        }
    }

    fn commit(&mut self, _model: &Model, state: &State) -> Option<serde_json::Value> {
        let mut rep = StabilizationIncrement::default();
        let mut f2 = 0.0;
        for (n, prev) in self.previous.iter_mut().enumerate() {
            let du = state.u[n] - *prev;
            f2 += (du * self.coefficient * self.area[n]).norm_squared();
            rep.max_motion = rep.max_motion.max(du.norm());
            *prev = state.u[n];
        }
        rep.force_norm = f2.sqrt();
        self.history.push(rep.clone());
        serde_json::to_value(serde_json::json!({ "stabilization": rep })).ok()
    }

    fn summary(&self) -> Option<(String, serde_json::Value)> {
        Some((
            "stabilization".into(),
            serde_json::json!({
                "coefficient": self.coefficient,
                "final": self.history.last(),
            }),
        ))
    }
}

/// Damped implicit pseudo-dynamics for drape: lumped nodal mass m = ρ_A·a (areal density
/// times tributary area) and mass-proportional damping, integrated by backward Euler with
/// one time step Δt per converged increment (Hughes 2000 §9.1; backward Euler damps high
/// frequencies, the damping ζ-term the slow swinging):
/// f = m (u − u_n − Δt v_n)/Δt² + η m (u − u_n)/Δt, tangent (m/Δt² + η m/Δt)·I,
/// and on convergence v_n ← (u − u_n)/Δt, u_n ← u. A cut-back increment (the solver halves
/// it after a failed attempt) takes a proportionally shorter time step, which raises m/Δt²
/// and carries the solve through fold formation. Gravity then accelerates the cloth
/// (a fall of L takes about √(2L/g)/Δt increments) instead of creeping at the terminal
/// speed of the viscous term. The inertia and damping forces vanish at rest, so the
/// settled state is a static equilibrium; the summary reports how settled it is.
/// This is the contact module's stop-gap until the solver's dynamics path is merged.
pub struct Inertia {
    /// Time step per nominal increment (s).
    pub time_step: f64,
    /// Time step of the current (sub-)increment: shortened with the solver's cut-backs.
    current_step: f64,
    /// Mass-proportional damping η (1/s).
    pub damping: f64,
    mass: Vec<f64>,
    previous: Vec<Vector3<f64>>,
    velocity: Vec<Vector3<f64>>,
    /// Per committed increment: kinetic energy and largest speed.
    pub history: Vec<InertiaIncrement>,
}

/// Motion of one time step.
#[derive(Clone, Debug, Default, Serialize)]
pub struct InertiaIncrement {
    /// Kinetic energy ½ Σ m v² (J).
    pub kinetic_energy: f64,
    /// Largest nodal speed (m/s).
    pub max_speed: f64,
}

impl Inertia {
    /// Inertia of `model` with masses from each section material's areal density (or
    /// `fallback_density` kg/m² where the material has none).
    pub fn new(model: &Model, time_step: f64, damping: f64, fallback_density: f64) -> Self {
        let mut mass = vec![0.0; model.n_nodes()];
        for (e, def) in model.elements.iter().enumerate() {
            let rho = model.sections[def.section].material.areal_density().unwrap_or(fallback_density);
            let a = model.element(e).reference_area();
            for &n in &def.nodes {
                mass[n] += 0.25 * a * rho;
            }
        }
        let n = model.n_nodes();
        Self { time_step, current_step: time_step, damping, mass, previous: vec![Vector3::zeros(); n], velocity: vec![Vector3::zeros(); n], history: Vec::new() }
    }

    fn stiffness(&self, n: usize) -> f64 {
        let dt = self.current_step;
        self.mass[n] * (1.0 / (dt * dt) + self.damping / dt)
    }
}

impl NodalForces for Inertia {
    fn begin_increment(&mut self, fraction: f64) {
        self.current_step = self.time_step * fraction.clamp(1e-6, 1.0);
    }

    fn add(&mut self, model: &Model, state: &State, f_ext: &mut [f64], jacobian: &mut Vec<(usize, Matrix3<f64>)>) {
        let dt = self.current_step;
        for n in 0..model.n_nodes() {
            let du = state.u[n] - self.previous[n];
            let f = (du - self.velocity[n] * dt) * (self.mass[n] / (dt * dt)) + du * (self.damping * self.mass[n] / dt);
            for k in 0..3 {
                f_ext[NODE_DOFS * n + k] -= f[k];
            }
            jacobian.push((n, Matrix3::identity() * -self.stiffness(n)));
        }
    }

    fn commit(&mut self, _model: &Model, state: &State) -> Option<serde_json::Value> {
        let mut rep = InertiaIncrement::default();
        for n in 0..self.mass.len() {
            let v = (state.u[n] - self.previous[n]) / self.current_step;
            rep.kinetic_energy += 0.5 * self.mass[n] * v.norm_squared();
            rep.max_speed = rep.max_speed.max(v.norm());
            self.velocity[n] = v;
            self.previous[n] = state.u[n];
        }
        self.history.push(rep.clone());
        serde_json::to_value(serde_json::json!({ "dynamics": rep })).ok()
    }

    fn summary(&self) -> Option<(String, serde_json::Value)> {
        let peak = self.history.iter().map(|h| h.kinetic_energy).fold(0.0, f64::max);
        Some((
            "dynamics".into(),
            serde_json::json!({
                "integrator": "backward Euler, lumped mass, mass-proportional damping (contact-module stop-gap)",
                "time_step": self.time_step,
                "damping": self.damping,
                "steps": self.history.len(),
                "peak_kinetic_energy": peak,
                "final": self.history.last(),
            }),
        ))
    }
}
