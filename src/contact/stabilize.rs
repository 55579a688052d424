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
//! Unlike a `Dynamic` step (`solver::dynamics`: inertia, time-accurate fall) it has no mass:
//! each load increment is one relaxation step, as in a quasi-static friction test.

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
    last_potential: f64,
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
        Self { coefficient: c, area, previous: vec![Vector3::zeros(); model.n_nodes()], history: Vec::new(), last_potential: 0.0 }
    }
}

impl NodalForces for Stabilization {
    fn add(&mut self, _model: &Model, state: &State, f_ext: &mut [f64], jacobian: &mut Vec<(usize, Matrix3<f64>)>) {
        let mut pot = 0.0;
        for (n, (&a, prev)) in self.area.iter().zip(&self.previous).enumerate() {
            let f = (state.u[n] - prev) * (self.coefficient * a);
            pot += 0.5 * self.coefficient * a * (state.u[n] - prev).norm_squared();
            for k in 0..3 {
                f_ext[NODE_DOFS * n + k] -= f[k];
            }
            jacobian.push((n, Matrix3::identity() * (-self.coefficient * a)));
        }
        self.last_potential = pot;
    }

    /// ½ c a |u − u_prev|² summed over the nodes, at the current previous state.
    fn potential(&self) -> Option<f64> {
        Some(self.last_potential)
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
