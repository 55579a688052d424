//! Inertia of a Dynamic step: the lumped mass of the model (translations and director
//! tilts) and the per-step coefficients of the time integration schemes (backward Euler;
//! generalized-α, Chung & Hulbert, J. Appl. Mech. 60, 1993, with the force average of Kuhl &
//! Crisfield 1999).

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::element::quadrature::{bilinear, gauss_legendre};
use crate::model::Model;

/// Implicit time integration schemes.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub enum TimeScheme {
    /// Backward Euler: first order, L-stable, damps every mode (pseudo-transient to rest).
    #[default]
    BackwardEuler,
    /// Generalized-α (Chung & Hulbert, J. Appl. Mech. 60, 1993), second order, with the
    /// spectral radius ρ∞ ∈ [0, 1] at infinite frequency (1: no numerical dissipation). The
    /// internal force is averaged, (1−α_f) f(u_{n+1}) + α_f f(u_n) (Kuhl & Crisfield 1999).
    GeneralizedAlpha { rho_inf: f64 },
}

/// Per-step coefficients of a scheme: inertia at n+1−α_m, forces at n+1−α_f, Newmark β, γ.
#[derive(Clone, Copy, Debug)]
pub(super) struct Coefficients {
    /// None: backward Euler.
    alpha: Option<(f64, f64, f64, f64)>,
    pub(super) dt: f64,
    pub(super) damping: f64,
}

impl Coefficients {
    pub(super) fn new(scheme: &TimeScheme, dt: f64, damping: f64) -> Self {
        let alpha = match *scheme {
            TimeScheme::BackwardEuler => None,
            TimeScheme::GeneralizedAlpha { rho_inf } => {
                let am = (2.0 * rho_inf - 1.0) / (rho_inf + 1.0);
                let af = rho_inf / (rho_inf + 1.0);
                let gamma = 0.5 - am + af;
                let beta = 0.25 * (1.0 - am + af).powi(2);
                Some((am, af, beta, gamma))
            }
        };
        Self { alpha, dt, damping }
    }

    /// Acceleration and velocity at n+1 of a quantity with increment `dx` over the step,
    /// previous velocity `v` and acceleration `a`.
    pub(super) fn rates(&self, dx: Vector3<f64>, v: Vector3<f64>, a: Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
        let dt = self.dt;
        match self.alpha {
            None => ((dx - v * dt) / (dt * dt), dx / dt),
            Some((_, _, beta, gamma)) => {
                let a1 = (dx - v * dt) / (beta * dt * dt) - a * (0.5 / beta - 1.0);
                (a1, v + (a * (1.0 - gamma) + a1 * gamma) * dt)
            }
        }
    }

    /// Inertia and damping force per unit mass in the residual (scaled by 1/(1−α_f) so the
    /// internal force at n+1 enters with weight 1).
    pub(super) fn inertia(&self, dx: Vector3<f64>, v: Vector3<f64>, a: Vector3<f64>) -> Vector3<f64> {
        let (a1, v1) = self.rates(dx, v, a);
        match self.alpha {
            None => a1 + v1 * self.damping,
            Some((am, af, _, _)) => (a1 * (1.0 - am) + a * am + (v1 * (1.0 - af) + v * af) * self.damping) / (1.0 - af),
        }
    }

    /// Mass factor of the effective tangent K + c M.
    pub(super) fn tangent(&self) -> f64 {
        let dt = self.dt;
        match self.alpha {
            None => 1.0 / (dt * dt) + self.damping / dt,
            Some((am, af, beta, gamma)) => ((1.0 - am) / (beta * dt * dt) + self.damping * (1.0 - af) * gamma / (beta * dt)) / (1.0 - af),
        }
    }

    /// Weight of the previous step's static residual: α_f/(1−α_f).
    pub(super) fn previous_force_weight(&self) -> f64 {
        self.alpha.map_or(0.0, |(_, af, _, _)| af / (1.0 - af))
    }
}

/// Lumped nodal masses of a model.
#[derive(Clone, Debug)]
pub struct LumpedMass {
    /// Translational mass per node: ρ_A ∫ N_a dA summed over the node's elements.
    pub translational: Vec<f64>,
    /// Rotary inertia of the director per node: scale · ρ_A h²/12 ∫ N_a dA.
    pub rotary: Vec<f64>,
}

impl LumpedMass {
    /// Row-sum lumped mass from each part's `areal_density` (2×2 Gauss on the reference
    /// mid-surface), with the director inertia scaled by `rotary_scale`.
    pub fn from_model(model: &Model, rotary_scale: f64) -> Self {
        Self::build(model, rotary_scale, false)
    }

    /// [`LumpedMass::from_model`] with the director inertia of an element-sized plate,
    /// ρ_A max(h², A_e)/12 per area instead of ρ_A h²/12: for pseudo-transient steps to rest,
    /// whose rest state does not depend on the inertia, so that the tilts of slack fabric get
    /// the mass regularisation the translations have (the fibre's own inertia is ~10⁻⁵ of it
    /// for cloth on centimetre elements).
    pub fn for_rest(model: &Model, rotary_scale: f64) -> Self {
        Self::build(model, rotary_scale, true)
    }

    fn build(model: &Model, rotary_scale: f64, element_sized: bool) -> Self {
        let mut translational = vec![0.0; model.n_nodes()];
        let mut rotary = vec![0.0; model.n_nodes()];
        let (p2, _) = gauss_legendre(2).unwrap_or((&[0.0], &[2.0]));
        for (e, el) in model.elements.iter().enumerate() {
            let rho = model.parts.get(el.part).map_or(0.0, |p| p.areal_density);
            let thickness = model.sections[el.section].thickness;
            let h = if element_sized { thickness.max(model.element(e).reference_area().sqrt()) } else { thickness };
            for &eta in p2 {
                for &xi in p2 {
                    let (n, dxi, deta) = bilinear(xi, eta);
                    let mut gx = Vector3::zeros();
                    let mut gy = Vector3::zeros();
                    for a in 0..4 {
                        gx += model.x0[el.nodes[a]] * dxi[a];
                        gy += model.x0[el.nodes[a]] * deta[a];
                    }
                    let da = gx.cross(&gy).norm();
                    for a in 0..4 {
                        translational[el.nodes[a]] += rho * n[a] * da;
                        rotary[el.nodes[a]] += rotary_scale * rho * h * h / 12.0 * n[a] * da;
                    }
                }
            }
        }
        Self { translational, rotary }
    }

    /// Total translational mass.
    pub fn total(&self) -> f64 {
        self.translational.iter().sum()
    }
}

