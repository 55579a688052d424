//! Geometric imperfections seeded into the reference geometry before a nonlinear run:
//! scaled buckling modes (see `eigen.rs`) or a seeded Gaussian random field.
//!
//! Random field: w(X) = c Σ_m cos(k_m·X + φ_m), m = 1..M, with wave vectors k_m drawn
//! from N(0, I/ℓ²) and phases φ_m uniform in [0, 2π) — random Fourier features (Rahimi &
//! Recht 2007; Shinozuka & Deodatis 1991 spectral representation), whose ensemble covariance
//! is the squared exponential exp(−|r|²/2ℓ²) with correlation length ℓ. Each node moves by
//! w along its reference director, and the director is turned by −∇w (the normal of the
//! perturbed surface to first order); c is chosen so that the largest |w| over the nodes
//! equals the amplitude.

use nalgebra::Vector3;

use super::eigen::{seeded_model, BucklingReport, ModeImperfection};
use super::SolverSettings;
use crate::element::DirectorFrame;
use crate::model::Model;

/// Number of random Fourier features of the random field.
const FEATURES: usize = 256;

/// A seeded Gaussian random field along the directors.
#[derive(Clone, Debug, Default)]
pub struct RandomField {
    /// Largest |w| over the nodes.
    pub amplitude: f64,
    /// Correlation length ℓ of the squared-exponential covariance.
    pub correlation_length: f64,
    /// Random seed (same seed, same field).
    pub seed: u64,
}

/// An imperfection resolved from the scene.
#[derive(Clone, Debug)]
pub enum Imperfection {
    /// Scaled buckling modes of the perfect geometry.
    BucklingModes(ModeImperfection),
    /// A random field along the directors.
    RandomField(RandomField),
}

/// Uniform numbers in [0, 1) from a 64-bit LCG (Knuth's MMIX constants), 53-bit mantissa.
struct Lcg(u64);

impl Lcg {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Standard normal by Box–Muller.
    fn normal(&mut self) -> f64 {
        let u1 = self.uniform().max(1e-300);
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}

/// The field's (value, gradient) at every node of `model`, unscaled (c = 1).
fn field(model: &Model, rf: &RandomField) -> Vec<(f64, Vector3<f64>)> {
    let mut rng = Lcg(rf.seed ^ 0x9E37_79B9_7F4A_7C15);
    let waves: Vec<(Vector3<f64>, f64)> = (0..FEATURES)
        .map(|_| {
            let k = Vector3::new(rng.normal(), rng.normal(), rng.normal()) / rf.correlation_length;
            (k, 2.0 * std::f64::consts::PI * rng.uniform())
        })
        .collect();
    model
        .x0
        .iter()
        .map(|x| {
            let mut w = 0.0;
            let mut g = Vector3::zeros();
            for (k, phi) in &waves {
                let a = k.dot(x) + phi;
                w += a.cos();
                g -= k * a.sin();
            }
            (w, g)
        })
        .collect()
}

/// `model` with the random field `rf` added to its reference geometry.
pub fn seed_random_field(model: &Model, rf: &RandomField) -> Model {
    let f = field(model, rf);
    let wmax = f.iter().fold(0.0f64, |m, (w, _)| m.max(w.abs()));
    let c = if wmax > 0.0 { rf.amplitude / wmax } else { 0.0 };
    let mut m = model.clone();
    for (n, (w, g)) in f.iter().enumerate() {
        let fr: DirectorFrame = m.frames0[n];
        m.x0[n] += fr.d * (c * w);
        let tilt = [-c * g.dot(&fr.t1), -c * g.dot(&fr.t2)];
        m.frames0[n] = fr.tilted(tilt);
    }
    m
}

/// `model` with the imperfection `imp` seeded, and the buckling analysis behind it (for a
/// buckling-mode imperfection).
pub fn seeded(model: &Model, imp: &Imperfection, settings: &SolverSettings) -> Result<(Model, Option<BucklingReport>), String> {
    match imp {
        Imperfection::BucklingModes(mi) => seeded_model(model, mi, settings).map(|(m, r)| (m, Some(r))),
        Imperfection::RandomField(rf) => Ok((seed_random_field(model, rf), None)),
    }
}
