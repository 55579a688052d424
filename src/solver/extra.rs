//! Extra force/tangent contributions added after element assembly (contact, stabilization).
//!
//! A contribution adds to the internal force over all DOFs and to the values of the
//! upper-triangular tangent (on entries already in the element pattern, e.g. node-local
//! 3×3 translation blocks), and is told when an increment has converged so it can update
//! its history (friction anchors, the previous configuration).

use crate::assembly::Pattern;
use crate::model::{Model, State};

/// A force/tangent term the solver adds to every assembly.
pub trait Contribution: Send {
    /// Adds the term's internal force (all DOFs, global numbering) to `f_int` and, when
    /// `values` is given, its tangent to the upper-triangle values of `pattern`. A term that
    /// finds the trial state inadmissible (e.g. a node through a body) writes NaN into
    /// `f_int`; the solver's safeguarded step then backtracks (halves the step).
    fn add(&mut self, model: &Model, state: &State, pattern: &Pattern, f_int: &mut [f64], values: Option<&mut [f64]>);
    /// Called once per converged (sub-)increment with the converged state; returns a report
    /// for the increment (e.g. active-set changes), if any.
    fn commit(&mut self, model: &Model, state: &State) -> Option<serde_json::Value>;
    /// Called before each (sub-)increment attempt with its size as a fraction of the nominal
    /// increment (1 normally, ½, ¼, … after cut-backs), so time-stepping terms can shorten
    /// their step with the increment.
    fn begin_increment(&mut self, fraction: f64) {
        let _ = fraction;
    }
    /// Wall time spent in proximity search so far (s), reported separately from assembly.
    fn search_seconds(&self) -> f64 {
        0.0
    }
    /// Any extra point data to export for `state`: (name, components, values per node).
    fn point_data(&self, _model: &Model, _state: &State) -> Vec<(String, usize, Vec<f64>)> {
        Vec::new()
    }
    /// A summary of the whole run (written under the contribution's name in summary.json).
    fn summary(&self) -> Option<(String, serde_json::Value)> {
        None
    }
}

/// Slot of entry (row, col) in the upper-triangular pattern (row ≤ col), if present.
pub fn slot(pattern: &Pattern, row: usize, col: usize) -> Option<usize> {
    let (r, c) = if row <= col { (row, col) } else { (col, row) };
    let rows = &pattern.row_idx[pattern.col_ptr[c]..pattern.col_ptr[c + 1]];
    rows.binary_search(&r).ok().map(|p| pattern.col_ptr[c] + p)
}
