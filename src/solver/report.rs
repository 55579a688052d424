//! What a solve reports: each converged increment or accepted time step (with its
//! time-integration and buckling data), progress for a bar, and why a solve stopped. The
//! solver's drivers (`newton`, `arclength`, `dynamics`, `eigen`) all write these, so they sit
//! below them.

use serde::Serialize;

/// The residual history for a message: all of it, or the first 4 and last 10 values.
fn residual_history(r: &[f64]) -> String {
    let f = |v: &[f64]| v.iter().map(|x| format!("{x:.2e}")).collect::<Vec<_>>().join(", ");
    if r.len() <= 16 { f(r) } else { format!("{}, … {} more …, {}", f(&r[..4]), r.len() - 14, f(&r[r.len() - 10..])) }
}

/// A converged nominal increment.
#[derive(Clone, Debug, Default, Serialize)]
pub struct IncrementReport {
    /// Step index.
    pub step: usize,
    /// Step name.
    pub step_name: String,
    /// Nominal increment within the step (1-based).
    pub increment: usize,
    /// Pseudo-time: step index + fraction of the step completed.
    pub time: f64,
    /// Load scales reached.
    pub scales: Vec<f64>,
    /// Newton iterations used since the previous report (all sub-increments).
    pub iterations: usize,
    /// Relative residual norms of the last sub-increment's iterations.
    pub residuals: Vec<f64>,
    /// Cut-backs since the previous report.
    pub cutbacks: usize,
    /// Whether any tangent in this increment was not positive definite.
    pub indefinite_tangent: bool,
    /// Strain energy.
    pub energy: f64,
    /// Reports of the extra contributions for this increment (e.g. contact active set).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub extra: Vec<serde_json::Value>,
    /// Load factor λ of a path-following step (scales = start + λ (target − start)).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub load_factor: Option<f64>,
    /// Negative pivots of the tangent at the converged state (its number of negative
    /// eigenvalues by Sylvester's law; 0 when LLᵀ succeeds).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub negative_pivots: Option<usize>,
    /// Current stiffness parameter S_p = (f·K⁻¹f)₁ / (f·K⁻¹f) for the step's load change f,
    /// 1 at the step's first increment (Bergan et al. 1978); its sign changes at a limit point.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stiffness_parameter: Option<f64>,
    /// "limit point" (negative-pivot count and sign of the stiffness parameter change),
    /// "bifurcation" (count changes alone) or "displacement turning point" (sign alone,
    /// a snap-back) when this increment crossed one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stability_event: Option<String>,
    /// Linearized buckling results of a `Buckling` step.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub buckling: Option<BucklingReport>,
    /// Time-integration data of a `Dynamic` step (None for static steps).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dynamics: Option<DynamicInfo>,
    /// Whether this static increment was solved by damped (Levenberg–Marquardt) Newton: a
    /// `StaticDamped` step, or a `Static` step that fell back to it (see
    /// `Solver::run_automatic`).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub damped: bool,
}

/// Progress notification for a bar.
#[derive(Clone, Debug)]
pub struct Progress {
    /// Step index.
    pub step: usize,
    /// Fraction of the whole analysis done.
    pub fraction: f64,
    /// Newton iteration in the current increment.
    pub iteration: usize,
    /// Current relative residual.
    pub residual: f64,
    /// In a `Dynamic` step: the simulated time (s) the current time step reaches and its
    /// number (a step to rest has no known fraction done).
    pub dynamic: Option<(f64, usize)>,
}

/// Why a solve stopped.
#[derive(Clone, Debug)]
pub struct SolveError {
    /// Step index.
    pub step: usize,
    /// Step name.
    pub step_name: String,
    /// Pseudo-time reached by the last converged state.
    pub last_converged_time: f64,
    /// Simulated time of the last accepted time step within a `Dynamic` step.
    pub simulated_time: Option<f64>,
    /// Newton iteration at failure.
    pub iteration: usize,
    /// Relative residual history of the last attempt.
    pub residuals: Vec<f64>,
    /// Element with the largest residual near the worst node, or the failing element.
    pub worst_element: Option<usize>,
    /// Diagnosis.
    pub cause: String,
}

impl std::fmt::Display for SolveError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let at = match self.simulated_time {
            Some(t) => format!("simulated time t = {t:.4e}"),
            None => format!("time {:.6}", self.last_converged_time),
        };
        write!(
            f,
            "step {} '{}' failed after the last converged state at {}: {} (iteration {}, residual history [{}]",
            self.step + 1,
            self.step_name,
            at,
            self.cause,
            self.iteration,
            residual_history(&self.residuals)
        )?;
        match self.worst_element {
            Some(e) => write!(f, "; worst element {e})"),
            None => write!(f, ")"),
        }
    }
}

/// Time-integration data of one accepted time step, reported with the increment.
#[derive(Clone, Debug, Default, Serialize)]
pub struct DynamicInfo {
    /// Simulated time since the step began.
    pub time: f64,
    /// Time step just taken.
    pub dt: f64,
    /// Kinetic energy ½ u̇·M u̇ (translations and director rates).
    pub kinetic_energy: f64,
    /// Relative static residual ‖f_int − f_ext‖ / reference.
    pub static_residual: f64,
    /// Both rest criteria hold.
    pub at_rest: bool,
    /// The last report of the step (at rest, or the `duration` of a transient step reached).
    pub end_of_step: bool,
    /// Time steps rejected (Newton failure or indefinite effective tangent) since the
    /// previous report.
    pub rejected: usize,
    /// Why each of those attempts was rejected, with its Δt (e.g. "Δt = 2.5e-3: energy line
    /// search failed: …"), oldest first.
    pub rejections: Vec<String>,
    /// Time steps so far in this step that met the rest criteria at an unstable
    /// equilibrium (static tangent not positive definite) and were not accepted as rest.
    pub unstable_rests: usize,
    /// Saddles left so far in this step by a move along their unstable mode.
    pub saddle_escapes: usize,
    /// Lowest ω² = φ·Kφ / φ·Mφ (1/time²) of the unstable equilibrium met at this time step,
    /// and the largest nodal translation of the move along φ that left it.
    pub saddle: Option<(f64, f64)>,
}

/// Results of a linearized buckling analysis.
#[derive(Clone, Debug, Default, Serialize)]
pub struct BucklingReport {
    /// Eigenvalues λ_i in ascending order: the critical scales are start + λ_i (target − start).
    pub eigenvalues: Vec<f64>,
    /// Critical load scales per mode (same order as the model's loads).
    pub critical_scales: Vec<Vec<f64>>,
    /// Relative residual ‖K_T φ + λ K_Δ φ‖ / ‖K_T φ‖ of each pair.
    pub residuals: Vec<f64>,
    /// Lanczos steps used.
    pub iterations: usize,
    /// Mode shapes over all DOFs (5 per node: translations, then tilts in the node's current
    /// frame), scaled to a largest translation of 1.
    #[serde(skip)]
    pub modes: Vec<Vec<f64>>,
}

