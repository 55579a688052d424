//! Results of a run: monitored histories and the summary written as `summary.json`.

use serde::Serialize;

use crate::model::{Model, State};
use crate::solver::{IncrementReport, Timings};

/// A monitored node.
#[derive(Clone, Debug)]
pub struct Monitor {
    /// Monitor name.
    pub name: String,
    /// Global node.
    pub node: usize,
    /// Recorded quantities.
    pub dofs: Vec<MonitorDof>,
}

/// Recorded quantities.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum MonitorDof {
    Ux,
    Uy,
    Uz,
    /// Displacement magnitude.
    Umag,
}

/// History of one monitored node.
#[derive(Clone, Debug, Serialize)]
pub struct MonitorHistory {
    /// Monitor name.
    pub name: String,
    /// Global node number.
    pub node: usize,
    /// Reference position of the node.
    pub position: [f64; 3],
    /// Recorded quantities, in the order of `values` rows.
    pub quantities: Vec<String>,
    /// values[i][k]: quantity k at reported increment i.
    pub values: Vec<Vec<f64>>,
}

impl MonitorHistory {
    /// An empty history for `monitor`.
    pub fn new(monitor: &Monitor, model: &Model) -> Self {
        let p = model.x0[monitor.node];
        Self {
            name: monitor.name.clone(),
            node: monitor.node,
            position: [p.x, p.y, p.z],
            quantities: monitor.dofs.iter().map(|d| format!("{d:?}")).collect(),
            values: Vec::new(),
        }
    }

    /// Records the monitored quantities of `state`.
    pub fn record(&mut self, monitor: &Monitor, model: &Model, state: &State) {
        let u = model.displacement(state, monitor.node);
        self.values.push(
            monitor
                .dofs
                .iter()
                .map(|d| match d {
                    MonitorDof::Ux => u.x,
                    MonitorDof::Uy => u.y,
                    MonitorDof::Uz => u.z,
                    MonitorDof::Umag => u.norm(),
                })
                .collect(),
        );
    }
}

/// Model sizes.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Sizes {
    /// Nodes.
    pub nodes: usize,
    /// Elements.
    pub elements: usize,
    /// Free DOFs (equations).
    pub dofs: usize,
    /// Stored entries of the tangent's upper triangle.
    pub tangent_nnz: usize,
    /// Stored entries of the Cholesky factor.
    pub factor_nnz: usize,
}

/// Everything `summary.json` holds.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Summary {
    /// Scene name.
    pub scene: String,
    /// "completed" or the failure diagnosis.
    pub status: String,
    /// Sizes.
    pub sizes: Sizes,
    /// Load pattern names (order of `increments[].scales`).
    pub loads: Vec<String>,
    /// Converged nominal increments.
    pub increments: Vec<IncrementReport>,
    /// Monitored histories (one row per increment).
    pub monitors: Vec<MonitorHistory>,
    /// Total Newton iterations.
    pub newton_iterations: usize,
    /// Wall-time split of the solve (s).
    pub timings: Timings,
    /// Wall time of the whole run including export (s).
    pub wall_s: f64,
    /// Time spent writing output files (s).
    pub export_s: f64,
    /// Peak resident memory of the process (MiB), where the OS reports it.
    pub peak_memory_mib: Option<f64>,
    /// Files written (relative to the output directory).
    pub files: Vec<String>,
    /// Sections of optional features (contact, stabilization, drape), by name.
    #[serde(flatten)]
    pub extra: std::collections::BTreeMap<String, serde_json::Value>,
    /// Limit points and bifurcations detected along the path: (increment index in
    /// `increments`, description).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub stability_events: Vec<(usize, String)>,
    /// Buckling analysis of the perfect geometry that seeded the imperfection.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub imperfection_buckling: Option<crate::solver::BucklingReport>,
    /// Position of every model node in the last converged state (not written to JSON; for
    /// comparisons between runs, `plyshell study`).
    #[serde(skip)]
    pub final_positions: Vec<[f64; 3]>,
    /// The last converged state itself (not written; for post-processing such as the
    /// `ply_model: Auto` criterion, `garment::ply_auto`).
    #[serde(skip)]
    pub final_state: Option<crate::model::State>,
}

/// Peak resident set size of this process in MiB (Linux `VmHWM`).
pub fn peak_memory_mib() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}
