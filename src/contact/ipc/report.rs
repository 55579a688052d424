//! What barrier contact between shell surfaces reports: per converged state (active pairs,
//! closest features, gaps, forces) and the wall time of its parts.

use serde::Serialize;

/// Per converged state: active pairs and forces.
#[derive(Clone, Debug, Default, Serialize)]
pub struct SurfaceIncrement {
    /// Point–triangle pairs within their barrier thickness.
    pub point_triangle: usize,
    /// Edge–edge pairs within their barrier thickness.
    pub edge_edge: usize,
    /// Active pairs per contact node.
    pub pairs_per_node: f64,
    /// Smallest gap (m) over the active pairs.
    pub min_gap: f64,
    /// Smallest gap as a fraction of its pair's d̂.
    pub min_gap_ratio: f64,
    /// Sum of the pairs' normal forces (N).
    pub normal_force: f64,
    /// Pairs with friction sliding.
    pub sliding: usize,
    /// Contact potential (barrier and friction), J.
    pub potential: f64,
    /// Nodes whose κ was doubled at this state.
    pub stiffened: usize,
    /// Distinct closest features of the active pairs (the distances differentiated).
    pub features: usize,
    /// Distinct closest features per contact node.
    pub features_per_node: f64,
}

/// Wall time (s) of the parts of surface contact.
#[derive(Clone, Debug, Default, Serialize)]
pub struct SurfaceTimings {
    /// Evaluations of the pairs' energies, forces and tangent blocks (in assemblies).
    pub evaluate: f64,
    /// Collision detection (`max_step`).
    pub ccd: f64,
    /// Commits (reports, friction anchors, adaptive stiffness).
    pub commit: f64,
    /// Commits that reused the last evaluation (the converged state had been evaluated).
    pub commits_reused: usize,
    /// Commits that evaluated the pairs anew.
    pub commits_evaluated: usize,
    /// Evaluations that took the candidates of the collision-detection sweep they lie on.
    pub evaluations_on_sweep: usize,
    /// Evaluations that ran their own broad phase.
    pub evaluations_searched: usize,
    /// Collision-detection calls (one per Newton step).
    pub ccd_calls: usize,
    /// Of them, those that shortened the step (a fraction below 1).
    pub ccd_limited: usize,
    /// Of them, those that searched the trees for their candidates (the others filtered
    /// the candidates kept from an earlier sweep, `surface::Near`).
    pub ccd_searches: usize,
    /// Candidate pairs measured by the evaluations on a sweep, and those among them left
    /// out as certainly inactive by the bound of [`super::surface`]'s `StartGaps`.
    pub pairs_measured: usize,
    pub pairs_bounded: usize,
}
