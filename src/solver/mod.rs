//! Nonlinear solution: load stepping with Newton–Raphson, line search and cut-back.

pub mod linear;
pub mod newton;

pub use newton::{IncrementReport, Progress, SolveError, Solver, StepPlan, Timings};

use serde::{Deserialize, Serialize};

/// Newton and stepping controls.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SolverSettings {
    /// Newton iterations allowed per increment before a cut-back.
    pub max_iterations: usize,
    /// Converged when ‖r‖ ≤ residual_tol · max(‖f_ext‖, ‖f_int‖ incl. reactions) ...
    pub residual_tol: f64,
    /// ... and |Δu·r| ≤ energy_tol · |Δu₀·r₀| (energy norm, first iteration of the increment).
    pub energy_tol: f64,
    /// Backtracking line search on the energy product Δu·r(s).
    pub line_search: bool,
    /// Times an increment may be halved before the solve stops with a diagnosis.
    pub max_cutbacks: usize,
    /// Worker threads for assembly and factorization (0 = all cores).
    pub threads: usize,
}

impl Default for SolverSettings {
    fn default() -> Self {
        Self { max_iterations: 30, residual_tol: 1e-7, energy_tol: 1e-14, line_search: true, max_cutbacks: 10, threads: 0 }
    }
}
