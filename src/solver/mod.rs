//! Nonlinear solution: load stepping with Newton–Raphson, line search and cut-back.

pub mod extra;
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
    /// Converged when ‖r‖ ≤ residual_tol · max(‖f_ext‖, ‖f_int‖ incl. reactions) and the
    /// energy criterion holds; or when ‖r‖ is a thousand times below that; or when the energy
    /// criterion holds with ‖r‖ within a thousandfold of it (residual at round-off floor).
    pub residual_tol: f64,
    /// Energy criterion: |Δu·r| ≤ energy_tol · |Δu₀·r₀| (first iteration of the increment).
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
