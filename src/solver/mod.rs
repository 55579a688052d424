//! Nonlinear solution: load stepping with Newton–Raphson, line search and cut-back.

pub mod arclength;
mod automatic;
pub mod chord;
pub mod damped;
pub mod diagnose;
pub mod dynamics;
pub mod eigen;
mod growth;
pub mod imperfection;
mod inertia;
pub mod linear;
mod line_search;
pub mod newton;
pub mod nodal;
mod report;
mod reuse;
mod saddle;
mod separator;
pub mod split_cholesky;
mod time_step;

pub use chord::ChordSettings;
pub use dynamics::{DynamicInfo, DynamicSettings, LumpedMass, TimeScheme};
pub use eigen::BucklingReport;
pub use nodal::NodalForces;
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
    /// Worker threads for assembly (0 = all cores).
    pub threads: usize,
    /// Threads of the sparse Cholesky factorization (0, the default, = all cores; 1 = the
    /// monolithic factorization). With two or more, a system of at least 4,000 equations
    /// whose graph has a small balanced separator, with dense work small against the
    /// monolithic factorization's (`linear.rs`), is factorized in two halves on two cores
    /// at once (`linear.rs`, `split_cholesky.rs`: one level of nested dissection, a dense
    /// Schur complement); results then differ from one thread's in round-off, and are the
    /// same for a given thread count. Measured on the 2-core machine this project uses, 5-DOF
    /// quad grids (`examples/factor_speed.rs`, CPU time of each half on its core against the
    /// monolithic factorization on one): 2.0× at 5,280 and 20,800 equations, 1.9× at
    /// 50,500, 2.0× for two disconnected 64² grids. faer's own parallel numeric
    /// factorization (`Par::rayon`) is not used: on two threads it was slower than the
    /// sequential one at every size tried — 5,445 equations (6.8 against 12.9 ms), 12,750
    /// (20.6 against 36.1 ms), 50,500 (122 against 182 ms) and 199,200 (818 against
    /// 1,307 ms, 44 M factor entries).
    pub factor_threads: usize,
    /// Chord (modified) Newton in static load-controlled increments: keep a factorization
    /// while the residual contracts fast (`chord.rs`); None (the default) is full Newton.
    pub chord: Option<ChordSettings>,
    /// Geometric stiffness from mixed-integration-point stresses (extrapolated along the
    /// linearised strain instead of recomputed from the new strains; Magisano, Leonetti &
    /// Garcea 2017, `element::mixed`): fewer Newton iterations on thin shells turning
    /// through large rotations. The residual, and so the converged state, is unchanged.
    /// Used by Static, ArcLength and DisplacementControl steps (not by time steps).
    pub mixed_stress: bool,
}

impl Default for SolverSettings {
    fn default() -> Self {
        Self { max_iterations: 30, residual_tol: 1e-7, energy_tol: 1e-14, line_search: true, max_cutbacks: 10, threads: 0, factor_threads: 0, chord: None, mixed_stress: true }
    }
}

/// How a step is solved.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub enum StepKind {
    /// Load-controlled Newton–Raphson with cut-back (`newton.rs`).
    #[default]
    Static,
    /// Static Newton with a Levenberg–Marquardt shift K + μ·k̄·I when the tangent is not
    /// positive definite, μ adapted by a trust-region test on the potential energy and the
    /// residual (`damped.rs`).
    StaticDamped,
    /// Pseudo-transient continuation: implicit (backward-Euler) dynamics with lumped mass
    /// from the parts' areal density, integrated until the kinetic energy and the static
    /// residual vanish (`dynamics.rs`).
    Dynamic(DynamicSettings),
    /// Arc-length path following (Crisfield 1981, cylindrical constraint on the free
    /// translations): the load factor λ, with scales = start + λ (target − start), is an
    /// unknown. `increments` of the step is the maximum number of arc-length increments.
    ArcLength {
        /// Initial arc length (norm of the increment of free translations).
        length: f64,
        /// Smallest arc length before the step stops with a diagnosis (default length/1000).
        #[serde(default)]
        min_length: Option<f64>,
        /// Largest arc length (default 10 × length).
        #[serde(default)]
        max_length: Option<f64>,
        /// Iterations per increment the arc length is adapted to, Δl ← Δl √(N_d / N).
        #[serde(default = "default_desired_iterations")]
        desired_iterations: usize,
        /// Stop once |λ| reaches this (default 1: the step's target scales).
        #[serde(default = "one")]
        max_load_factor: f64,
        /// Stop once any node's displacement magnitude exceeds this.
        #[serde(default)]
        max_displacement: Option<f64>,
    },
    /// Displacement control (Batoz & Dhatt 1979): the translation `dof` of the single node
    /// in `set` is driven from its value at the start of the step by `value` over the
    /// increments; the load factor λ (scales = start + λ (target − start)) is an unknown.
    DisplacementControl {
        /// Node set holding exactly one node.
        set: String,
        /// Controlled translation (Ux, Uy or Uz).
        dof: crate::model::Dof,
        /// Change of the controlled displacement over the step.
        value: f64,
        /// Global DOF index, resolved when the scene is built.
        #[serde(skip)]
        global_dof: usize,
    },
    /// Linearized buckling at the current state: (K_T + λ K_Δ) φ = 0 for the lowest
    /// `modes` eigenpairs, K_Δ the derivative of the tangent along the prebuckling path of
    /// the step's load change (target − start). Writes the modes as VTU point fields.
    Buckling {
        /// Number of eigenpairs.
        modes: usize,
        /// Spectral shift σ (modes nearest above σ); K_T − σ(−K_Δ) must be positive definite.
        #[serde(default)]
        shift: f64,
    },
}

fn default_desired_iterations() -> usize {
    5
}

fn one() -> f64 {
    1.0
}
