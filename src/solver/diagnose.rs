//! Failure diagnosis shared by the static, damped and dynamic solvers: the most distorted
//! element of a configuration and the likely cause of a failed solve.

use nalgebra::Vector3;

use crate::model::{Model, State};

/// The element with the smallest corner-Jacobian ratio min_a J_a / max_a J_a in `state`,
/// where J_a = ((x_{a+1} − x_a) × (x_{a−1} − x_a)) · n̄ and n̄ is the mean current director
/// of the element. 1 is an undistorted parallelogram; ≤ 0 means the element has folded
/// through itself (inverted) in its own mid-surface (Bathe 2014 §5.3.3, Jacobian checks).
pub fn worst_distortion(model: &Model, state: &State) -> Option<(usize, f64)> {
    let mut worst: Option<(usize, f64)> = None;
    for (e, el) in model.elements.iter().enumerate() {
        let x: [Vector3<f64>; 4] = el.nodes.map(|n| model.x0[n] + state.u[n]);
        let n: Vector3<f64> = el.nodes.iter().map(|&a| state.frames[a].d).sum();
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for a in 0..4 {
            let j = (x[(a + 1) % 4] - x[a]).cross(&(x[(a + 3) % 4] - x[a])).dot(&n);
            lo = lo.min(j);
            hi = hi.max(j);
        }
        let ratio = if hi > 0.0 && lo.is_finite() { lo / hi } else { f64::NEG_INFINITY };
        if worst.is_none_or(|(_, r)| ratio < r) {
            worst = Some((e, ratio));
        }
    }
    worst
}

/// Likely cause of a failure from its message and whether the last tangent was indefinite.
pub fn likely_cause(cause: &str, indefinite: bool) -> &'static str {
    let c = cause.to_lowercase();
    if c.contains("nan") || c.contains("infinite") || c.contains("non-finite") {
        "likely cause: NaN — a non-finite load, coordinate or material state; check units and loads"
    } else if c.contains("inverted") || c.contains("degenerate") {
        "likely cause: element inversion — the increment or time step moves the mesh through itself; reduce it or refine the mesh"
    } else if c.contains("singular") {
        "likely cause: a mechanism — missing supports, or a slack membrane without bending stiffness; add supports or use a Dynamic or StaticDamped step"
    } else if indefinite {
        "likely cause: indefinite tangent — a limit or bifurcation point (buckling, wrinkling) was passed; use a Dynamic, StaticDamped or path-following step"
    } else {
        "likely cause: the increment is too large for Newton or the tangent is nearly singular; use more increments or a Dynamic step"
    }
}

/// The failure message extended with the most distorted element of `state` and the
/// likely cause.
pub fn explain(model: &Model, state: &State, cause: &str, indefinite: bool) -> String {
    let mut s = cause.to_string();
    if let Some((e, r)) = worst_distortion(model, state) {
        s.push_str(&format!("; most distorted element {e} (corner Jacobian ratio {r:.3})"));
    }
    s.push_str("; ");
    s.push_str(likely_cause(cause, indefinite));
    s
}
