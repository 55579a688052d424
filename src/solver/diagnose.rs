//! Failure diagnosis shared by the static, damped and dynamic solvers: the most distorted
//! element of a configuration and the likely cause of a failed solve.

use nalgebra::Vector3;

use crate::element::NODE_DOFS;
use crate::model::{Model, State, FIXED};

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

/// Global directions (x, y, z) along which no node's translation is fixed or prescribed:
/// the model can move rigidly along them (a mechanism).
pub fn unsupported_directions(model: &Model) -> Vec<&'static str> {
    let eq = &model.dofs.eq;
    ["x", "y", "z"]
        .into_iter()
        .enumerate()
        .filter(|&(k, _)| !(0..model.n_nodes()).any(|n| eq[NODE_DOFS * n + k] == FIXED))
        .map(|(_, name)| name)
        .collect()
}

/// Standard gravity (m/s²), the weight scale of the bending length.
const STANDARD_GRAVITY: f64 = 9.80665;

/// Bending length ℓ_b = (B / ρ_A g)^{1/3} of element `e`'s section (the length over which a
/// sheet under its own weight bends, the size of its folds; Peirce 1930) and the element's
/// size √A, when the part has mass.
pub fn bending_length(model: &Model, e: usize) -> Option<(f64, f64)> {
    let def = model.elements.get(e)?;
    let rho = model.parts.get(def.part)?.areal_density;
    if rho <= 0.0 {
        return None;
    }
    let sec = &model.sections[def.section];
    let b = sec.material.bending_rigidity(sec.thickness);
    let lb = (b / (rho * STANDARD_GRAVITY)).cbrt();
    let size = model.element(e).reference_area().sqrt();
    (lb.is_finite() && size.is_finite()).then_some((lb, size))
}

/// The failure of a `Dynamic` step whose time step collapsed at element `element`: the
/// cause, the element's distortion, and what to change. No mechanism verdict (mass
/// regularises a free body); when the element is larger than the fabric's bending length,
/// folds form inside single elements (neighbouring directors turn past what one element can
/// represent) and the mesh must be refined.
pub fn explain_dynamic(model: &Model, state: &State, cause: &str, element: Option<usize>) -> String {
    let mut s = cause.to_string();
    if let Some((e, r)) = worst_distortion(model, state) {
        if r.is_finite() {
            s.push_str(&format!("; most distorted element {e} (corner Jacobian ratio {r:.3})"));
        } else {
            s.push_str(&format!("; element {e} is folded through itself (corner Jacobian ratio not positive)"));
        }
    }
    let coarse = element.and_then(|e| bending_length(model, e).map(|(lb, size)| (e, lb, size))).filter(|&(_, lb, size)| size > lb);
    match coarse {
        Some((e, lb, size)) => s.push_str(&format!(
            "; likely cause: element {e} ({:.1} mm) is larger than the fabric's bending length (B/ρ_A g)^(1/3) = {:.1} mm, so a fold forms inside one element; refine the mesh to about {:.1} mm or less",
            size * 1e3,
            lb * 1e3,
            0.5 * lb * 1e3
        )),
        None => s.push_str(&format!(
            "; likely cause: {}",
            if cause.contains("failed:") {
                "an element cannot follow the motion (inversion or a fold sharper than the mesh resolves); refine the mesh there, add mass_damping, or lower dt_max"
            } else {
                "the motion is too violent for the time step (an impact or a snap); add mass_damping or lower dt_max"
            }
        )),
    }
    s
}

/// The failure message extended with the most distorted element of `state` and the
/// likely cause (a mechanism when a direction has no support at all).
pub fn explain(model: &Model, state: &State, cause: &str, indefinite: bool) -> String {
    let mut s = cause.to_string();
    if let Some((e, r)) = worst_distortion(model, state) {
        if r.is_finite() {
            s.push_str(&format!("; most distorted element {e} (corner Jacobian ratio {r:.3})"));
        } else {
            s.push_str(&format!("; element {e} is inverted or not finite"));
        }
    }
    let free = unsupported_directions(model);
    if free.is_empty() {
        s.push_str("; ");
        s.push_str(likely_cause(cause, indefinite));
    } else {
        s.push_str(&format!(
            "; likely cause: a mechanism — no support restrains rigid motion along {}; add supports (a Dynamic step lets it move under its loads)",
            free.join(", ")
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene;

    fn strip(boundary: &str) -> scene::BuiltScene {
        let text = format!(
            r#"Scene(name: "s", materials: {{"m": StVenantKirchhoff(young: 1.0e6, poisson: 0.0)}},
            parts: [(name: "p", mesh: Rectangle(lx: 4.0, ly: 1.0, nx: 4, ny: 1), material: "m", thickness: 0.1)],
            node_sets: {{"root": Edge(part: "p", edge: "xmin")}}, boundary: [{boundary}],
            steps: [(name: "a", increments: 1)])"#
        );
        let sc = scene::parse("s.ron", &text).unwrap();
        scene::build(&sc, "s.ron", &text).unwrap()
    }

    #[test]
    fn distortion_ratio_is_one_for_rectangles_and_negative_for_an_inverted_element() {
        let b = strip("Clamp(set: \"root\")");
        let mut st = b.model.initial_state();
        let (_, r) = worst_distortion(&b.model, &st).unwrap();
        assert!((r - 1.0).abs() < 1e-12);
        // Push node 1 (x = 1, y = 0) past node 0's far side: element 0 folds over.
        st.u[1].x = -2.0;
        let (e, r) = worst_distortion(&b.model, &st).unwrap();
        assert_eq!(e, 0);
        assert!(r < 0.0, "ratio {r}");
    }

    #[test]
    fn an_unsupported_model_is_diagnosed_as_a_mechanism() {
        let b = strip("");
        assert_eq!(unsupported_directions(&b.model), vec!["x", "y", "z"]);
        let msg = explain(&b.model, &b.model.initial_state(), "no convergence in 30 iterations", true);
        assert!(msg.contains("a mechanism") && msg.contains("x, y, z"), "{msg}");
        let b = strip("Clamp(set: \"root\")");
        assert!(unsupported_directions(&b.model).is_empty());
        let msg = explain(&b.model, &b.model.initial_state(), "element 3 failed: material inverted (det C = -1)", false);
        assert!(msg.contains("element inversion"), "{msg}");
    }
}
