//! A-posteriori error indicator of a shell state (issue 18): the relative shape error a
//! bilinear element of the current mesh makes on the computed curvature.
//!
//! A bilinear element of length h interpolating a surface of curvature κ (radius R = 1/κ)
//! misses it by the sagitta h²κ/8 (the linear-interpolation error h²|f''|/8), i.e. by
//! (hκ)²/8 relative to the curvature's own length scale R — the same measure as the
//! a-priori `Auto` tolerance, (h/ℓ)²/8 with ℓ the physical length scale (`garment::sizing`),
//! so the two are compared directly: η_e = (h_e κ_e)²/8 per element and pattern direction.
//! The curvature is the gradient of the mid-surface's nodal normals (area-weighted element
//! normals of the current positions, `map::nodal_normals`) in pattern coordinates at the
//! element's centre, |∂n/∂X| and |∂n/∂Y| (the normal curvature along X, Y per unit
//! reference length). Not the directors: MITC4 ties the transverse shear at edge midpoints,
//! so the directors of limp fabric may zigzag at no energy cost, and a director gradient
//! then marks flat regions (measured on the Peirce strip: a third pass refined its width
//! 4 → 16 elements on director noise). It is taken as the larger of the element's own value
//! and the recovered one — the nodal area-weighted average of the elements round each node
//! (Zienkiewicz & Zhu, IJNME 24, 1987, "a simple error estimator and adaptive procedure",
//! nodal averaging recovery), averaged over the element's nodes — so that the marks spread
//! one element round a kink, where the element's own gradient is smeared by the coarse mesh.
//! h_e is the element's extent along X (resp. Y) in pattern space.
//!
//! Setting η = tolerance gives the new size h_new = h (T/η)^{1/2} = √(8T)/κ
//! (`size_field`): the a-priori `Auto` size with the computed radius of curvature as ℓ.

use nalgebra::{Matrix2, Vector3};

use crate::model::{Model, State};

/// The indicator of one element.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ElementIndicator {
    /// Element extent along pattern X and Y (m).
    pub h: [f64; 2],
    /// Curvature estimate along X and Y (1/m): max(own, recovered) normal gradient.
    pub kappa: [f64; 2],
    /// Relative shape error (h κ)²/8 along X and Y.
    pub eta: [f64; 2],
}

impl ElementIndicator {
    /// The larger of the two directions' errors (the VTU's `indicator`).
    pub fn value(&self) -> f64 {
        self.eta[0].max(self.eta[1])
    }
}

/// Normal gradient (|∂n/∂X|, |∂n/∂Y|) at the centre of element `e` in pattern coordinates
/// `pattern`, and the element's pattern area (bilinear map at ξ = η = 0, Jacobian × 4).
fn normal_gradient(model: &Model, normals: &[Vector3<f64>], pattern: &[[f64; 2]], e: usize) -> Option<([f64; 2], f64)> {
    let nodes = model.elements[e].nodes;
    let p = nodes.map(|n| pattern[n]);
    let d = nodes.map(|n| normals[n]);
    let (dxi, deta) = ([-0.25, 0.25, 0.25, -0.25], [-0.25, -0.25, 0.25, 0.25]);
    let j: Matrix2<f64> = Matrix2::new(
        (0..4).map(|a| dxi[a] * p[a][0]).sum(),
        (0..4).map(|a| deta[a] * p[a][0]).sum(),
        (0..4).map(|a| dxi[a] * p[a][1]).sum(),
        (0..4).map(|a| deta[a] * p[a][1]).sum(),
    );
    let jinv = j.try_inverse()?;
    let d_xi: Vector3<f64> = (0..4).map(|a| d[a] * dxi[a]).sum();
    let d_eta: Vector3<f64> = (0..4).map(|a| d[a] * deta[a]).sum();
    // ∂d/∂X = ∂d/∂ξ ∂ξ/∂X + ∂d/∂η ∂η/∂X, with [∂ξ/∂X ∂ξ/∂Y; ∂η/∂X ∂η/∂Y] = J⁻¹.
    let g_x: Vector3<f64> = d_xi * jinv[(0, 0)] + d_eta * jinv[(1, 0)];
    let g_y: Vector3<f64> = d_xi * jinv[(0, 1)] + d_eta * jinv[(1, 1)];
    Some(([g_x.norm(), g_y.norm()], 4.0 * j.determinant().abs()))
}

/// Element extents along pattern X and Y (bounding box of its corners).
fn extents(pattern: &[[f64; 2]], nodes: [usize; 4]) -> [f64; 2] {
    let mut out = [0.0; 2];
    for (k, o) in out.iter_mut().enumerate() {
        let (lo, hi) = nodes.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &n| (a.min(pattern[n][k]), b.max(pattern[n][k])));
        *o = hi - lo;
    }
    out
}

/// The indicator of every element of `model` at `state` (module doc), pattern coordinates of
/// the nodes in `pattern`. Errors name an element whose pattern quad is degenerate.
pub fn indicators(model: &Model, state: &State, pattern: &[[f64; 2]]) -> Result<Vec<ElementIndicator>, String> {
    let normals = super::map::nodal_normals(model, state);
    let own: Vec<([f64; 2], f64)> = (0..model.elements.len())
        .map(|e| normal_gradient(model, &normals, pattern, e).ok_or_else(|| format!("element {e}: its pattern quad is degenerate (zero area)")))
        .collect::<Result<_, _>>()?;
    // Nodal recovery: area-weighted mean of the adjacent elements' gradients.
    let mut sum = vec![[0.0f64; 2]; model.n_nodes()];
    let mut area = vec![0.0f64; model.n_nodes()];
    for (e, (g, a)) in own.iter().enumerate() {
        for &n in &model.elements[e].nodes {
            sum[n][0] += a * g[0];
            sum[n][1] += a * g[1];
            area[n] += a;
        }
    }
    Ok(own
        .iter()
        .enumerate()
        .map(|(e, (g, _))| {
            let nodes = model.elements[e].nodes;
            let h = extents(pattern, nodes);
            let mut kappa = [0.0; 2];
            let mut eta = [0.0; 2];
            for k in 0..2 {
                let recovered = nodes.iter().map(|&n| if area[n] > 0.0 { sum[n][k] / area[n] } else { 0.0 }).sum::<f64>() / 4.0;
                kappa[k] = g[k].max(recovered);
                eta[k] = (h[k] * kappa[k]).powi(2) / 8.0;
            }
            ElementIndicator { h, kappa, eta }
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip rolled onto a cylinder of radius R about the y axis: directors turn at 1/R along
    /// X, not at all along Y; η = (h/R)²/8 along X to the chord's round-off.
    #[test]
    fn rolled_strip_has_the_sagitta_error() {
        let text = r#"Scene(name: "strip", materials: {"m": StVenantKirchhoff(young: 1.0e6, poisson: 0.0)},
            parts: [(name: "s", mesh: Rectangle(lx: 0.2, ly: 0.05, nx: 10, ny: 2), material: "m", thickness: 0.001)],
            steps: [(name: "s", increments: 1)])"#;
        let sc = crate::scene::parse("strip.ron", text).expect("scene");
        let model = crate::scene::build(&sc, "strip.ron", text).expect("built").model;
        let r = 0.1;
        let mut s = model.initial_state();
        for n in 0..model.n_nodes() {
            let x = model.x0[n].x;
            let th = x / r;
            s.u[n] = Vector3::new(r * th.sin() - x, 0.0, r * (1.0 - th.cos()));
            s.frames[n] = crate::element::DirectorFrame::new(Vector3::new(-th.sin(), 0.0, th.cos()), None);
        }
        let pattern = super::super::map::pattern_of(&model);
        let ind = indicators(&model, &s, &pattern).expect("indicators");
        let h: f64 = 0.02;
        // The chord of the nodal normal over an element: |Δn|/h = 2 sin(h/2R)/h (interior
        // nodes: the mean of the two adjacent facet normals is radial).
        let kappa = 2.0 * (h / (2.0 * r)).sin() / h;
        for i in ind.iter().enumerate().filter(|(e, _)| e % 10 != 0 && e % 10 != 9).map(|(_, i)| i) {
            assert!((i.kappa[0] - kappa).abs() < 1e-9 * kappa, "{:?}", i);
            assert!(i.kappa[1] < 1e-12);
            assert!((i.eta[0] - (h * kappa).powi(2) / 8.0).abs() < 1e-12);
        }
    }
}
