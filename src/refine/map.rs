//! Mapping a state between two quad meshes of the same parts in pattern space (issue 18,
//! a-posteriori refinement): each node of the new mesh is located in the old mesh's
//! pattern-space quads of its part and takes the old element's bilinear interpolation there
//! (the isoparametric inverse map, Zienkiewicz, Taylor & Zhu, *The Finite Element Method:
//! Its Basis and Fundamentals* 7th ed. 2013, §6.5 / §15.3 "mesh-to-mesh transfer"): its
//! displacement from the same combination of the old displacements, its director the
//! normalised combination of the old directors, its first frame tangent from the
//! interpolated first tangents. Unlike `model::prolong` (nested `Rectangle` grids) the
//! meshes may be arbitrary: unstructured, graded, non-nested.
//!
//! The current position is the bilinear interpolation p = Σ N_a x_a lifted towards the
//! curved surface by the Phong correction ½ Σ N_a ((x_a − p)·n_a) n_a, n_a the old mesh's
//! nodal normals (Phong tessellation, Boubekeur & Alexa, ACM TOG 27(5) 2008, with shape
//! factor ½, which makes it the sagitta of a circular arc to leading order). Without it
//! every new node between old nodes lies on the old element's chord: the new mesh then
//! carries the old mesh's kinks (angle hκ) at the old nodes and, where a new element
//! straddles one, the chord's shortening; with it the mapped surface is smooth to O(h³).
//!
//! Bilinear interpolation reproduces the pattern coordinates (X = Σ N_a X_a), hence every
//! field affine in them, and the Phong correction vanishes on a plane (every x_a − p lies
//! in it): an affinely deformed sheet and a constant director field map exactly, whatever
//! the two meshes (`tests/refine.rs`).
//!
//! Point location: a uniform bucket grid over the old part's element bounding boxes (about
//! one element per bucket), then Newton on the bilinear map X(ξ, η) = P (Zienkiewicz et al.
//! §6.5); a node outside every old quad by round-off (or by a chord of a curved outline)
//! takes the nearest quad's clamped local coordinates.

use nalgebra::{Matrix2, Vector2, Vector3};

use crate::model::prolong::interpolate;
use crate::model::{Model, State};

/// Pattern-space coordinates of every node of a model: the reference position's (x, y) for
/// the flat parts `refine` remeshes (Rectangle grids in the xy plane, offset alike in both
/// meshes).
pub fn pattern_of(model: &Model) -> Vec<[f64; 2]> {
    model.x0.iter().map(|x| [x.x, x.y]).collect()
}

/// Bilinear shape functions of the 4-node quad at (ξ, η) ∈ [−1, 1]² (node order
/// (−1,−1), (1,−1), (1,1), (−1,1)).
pub fn shape(xi: f64, eta: f64) -> [f64; 4] {
    [0.25 * (1.0 - xi) * (1.0 - eta), 0.25 * (1.0 + xi) * (1.0 - eta), 0.25 * (1.0 + xi) * (1.0 + eta), 0.25 * (1.0 - xi) * (1.0 + eta)]
}

/// Local coordinates (ξ, η) of the point `p` in the bilinear quad with corners `c` (Newton
/// on X(ξ, η) − p = 0 from the centre), and how far outside [−1, 1]² they lie (0 inside).
/// None when the map is singular on the way (a degenerate quad).
pub fn inverse_bilinear(c: &[[f64; 2]; 4], p: [f64; 2]) -> Option<(f64, f64, f64)> {
    let (mut xi, mut eta) = (0.0f64, 0.0f64);
    let at = |xi: f64, eta: f64| {
        let n = shape(xi, eta);
        let x = Vector2::new((0..4).map(|a| n[a] * c[a][0]).sum(), (0..4).map(|a| n[a] * c[a][1]).sum());
        let dxi = [-(1.0 - eta), 1.0 - eta, 1.0 + eta, -(1.0 + eta)].map(|v| 0.25 * v);
        let deta = [-(1.0 - xi), -(1.0 + xi), 1.0 + xi, 1.0 - xi].map(|v| 0.25 * v);
        let j: Matrix2<f64> = Matrix2::new(
            (0..4).map(|a| dxi[a] * c[a][0]).sum(),
            (0..4).map(|a| deta[a] * c[a][0]).sum(),
            (0..4).map(|a| dxi[a] * c[a][1]).sum(),
            (0..4).map(|a| deta[a] * c[a][1]).sum(),
        );
        (x, j)
    };
    let size = (c[2][0] - c[0][0]).hypot(c[2][1] - c[0][1]).max((c[3][0] - c[1][0]).hypot(c[3][1] - c[1][1]));
    for _ in 0..30 {
        let (x, j) = at(xi, eta);
        let r = Vector2::new(p[0], p[1]) - x;
        let step = j.try_inverse()? * r;
        xi += step.x;
        eta += step.y;
        if !(xi.is_finite() && eta.is_finite()) || xi.abs() > 1e3 || eta.abs() > 1e3 {
            return None;
        }
        if step.norm() < 1e-15 && r.norm() <= 1e-13 * size.max(f64::MIN_POSITIVE) {
            break;
        }
    }
    // Only a converged solution locates the point (far outside, the bilinear extension may
    // fold and Newton wander: seen on a Delaunay quad mesh, a point 8 mm outside a 4 cm quad
    // "found" at (−0.05, 0.24)).
    let (x, _) = at(xi, eta);
    if (Vector2::new(p[0], p[1]) - x).norm() > 1e-10 * size.max(f64::MIN_POSITIVE) {
        return None;
    }
    let outside = (xi.abs() - 1.0).max(eta.abs() - 1.0).max(0.0);
    Some((xi, eta, outside))
}

/// Finds, for pattern points, the old element of a part containing each (bucket grid over the
/// elements' bounding boxes).
pub struct Locator {
    elements: Vec<(usize, [[f64; 2]; 4])>,
    origin: [f64; 2],
    cell: f64,
    dims: (usize, usize),
    buckets: Vec<Vec<usize>>,
}

impl Locator {
    /// The locator of the quads `elements` (element index, pattern corners).
    pub fn new(elements: Vec<(usize, [[f64; 2]; 4])>) -> Self {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for (_, c) in &elements {
            for p in c {
                for k in 0..2 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
        }
        let n = elements.len().max(1) as f64;
        let (wx, wy) = ((hi[0] - lo[0]).max(1e-300), (hi[1] - lo[1]).max(1e-300));
        let cell = (wx * wy / n).sqrt().max(wx.max(wy) / 4096.0);
        let dims = (((wx / cell).ceil() as usize).clamp(1, 4096), ((wy / cell).ceil() as usize).clamp(1, 4096));
        let mut buckets = vec![Vec::new(); dims.0 * dims.1];
        let index = |v: f64, o: f64, d: usize| (((v - o) / cell).floor().max(0.0) as usize).min(d - 1);
        for (k, (_, c)) in elements.iter().enumerate() {
            let (mut a, mut b) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            for p in c {
                for q in 0..2 {
                    a[q] = a[q].min(p[q]);
                    b[q] = b[q].max(p[q]);
                }
            }
            for j in index(a[1], lo[1], dims.1)..=index(b[1], lo[1], dims.1) {
                for i in index(a[0], lo[0], dims.0)..=index(b[0], lo[0], dims.0) {
                    buckets[i + j * dims.0].push(k);
                }
            }
        }
        Locator { elements, origin: lo, cell, dims, buckets }
    }

    /// The element containing `p` and the local coordinates there (clamped to the quad when
    /// `p` lies outside every quad: the nearest one by the outside measure). None only when
    /// the part has no usable quad.
    pub fn locate(&self, p: [f64; 2]) -> Option<(usize, f64, f64)> {
        let index = |v: f64, o: f64, d: usize| (((v - o) / self.cell).floor().max(0.0) as usize).min(d - 1);
        let (i0, j0) = (index(p[0], self.origin[0], self.dims.0), index(p[1], self.origin[1], self.dims.1));
        let mut best: Option<(f64, usize, f64, f64)> = None;
        let try_bucket = |b: &Vec<usize>, best: &mut Option<(f64, usize, f64, f64)>| {
            for &k in b {
                if let Some((xi, eta, out)) = inverse_bilinear(&self.elements[k].1, p)
                    && best.is_none_or(|b| out < b.0)
                {
                    *best = Some((out, k, xi, eta));
                }
            }
        };
        try_bucket(&self.buckets[i0 + j0 * self.dims.0], &mut best);
        // Widen the search ring by ring until a containing quad is found (or all were tried).
        let mut ring = 1;
        while best.is_none_or(|b| b.0 > 1e-9) && ring <= self.dims.0.max(self.dims.1) {
            for j in j0.saturating_sub(ring)..=(j0 + ring).min(self.dims.1 - 1) {
                for i in i0.saturating_sub(ring)..=(i0 + ring).min(self.dims.0 - 1) {
                    if i.abs_diff(i0) == ring || j.abs_diff(j0) == ring {
                        try_bucket(&self.buckets[i + j * self.dims.0], &mut best);
                    }
                }
            }
            // A quad found outside by more than round-off: one more ring may hold a closer one.
            if best.is_some_and(|b| b.0 > 1e-9) && ring > 2 {
                break;
            }
            ring += 1;
        }
        best.map(|(_, k, xi, eta)| (self.elements[k].0, xi.clamp(-1.0, 1.0), eta.clamp(-1.0, 1.0)))
    }
}

/// The state of `new` interpolated from `state` of `old`, part by part (parts with the same
/// index; `new_pattern` / `old_pattern` the nodes' pattern coordinates, e.g. [`pattern_of`]):
/// displacements bilinearly, directors bilinearly and normalised, first tangents likewise.
/// Also returns, per new node, the old nodes and weights used, so that other nodal fields
/// (the body distances of the push-out) can follow.
pub fn map_state(old: &Model, state: &State, old_pattern: &[[f64; 2]], new: &Model, new_pattern: &[[f64; 2]]) -> Result<(State, Vec<Vec<(usize, f64)>>), String> {
    if old.parts.len() != new.parts.len() {
        return Err(format!("the meshes have {} and {} parts", old.parts.len(), new.parts.len()));
    }
    let mut out = new.initial_state();
    let mut weights = vec![Vec::new(); new.n_nodes()];
    let normals = nodal_normals(old, state);
    for (op, np) in old.parts.iter().zip(&new.parts) {
        let quads: Vec<(usize, [[f64; 2]; 4])> = (op.first_element..op.first_element + op.n_elements).map(|e| (e, old.elements[e].nodes.map(|n| old_pattern[n]))).collect();
        if quads.is_empty() {
            return Err(format!("part {}: the old mesh has no elements", op.name));
        }
        let locator = Locator::new(quads);
        for n in np.first_node..np.first_node + np.n_nodes {
            let (e, xi, eta) = locator.locate(new_pattern[n]).ok_or_else(|| format!("part {}: node {n} of the new mesh is in no quad of the old one", np.name))?;
            let nw = shape(xi, eta);
            let w: Vec<(usize, f64)> = old.elements[e].nodes.iter().zip(nw).filter(|&(_, x)| x != 0.0).map(|(&a, x)| (a, x)).collect();
            let (u, frame) = interpolate(state, &w).ok_or_else(|| format!("part {}: the old directors round new node {n} cancel (a folded element)", np.name))?;
            // Phong correction (module doc): Σ N_a ((x_a − p)·n_a) n_a / 2 about p = Σ N_a x_a.
            let p: Vector3<f64> = old_reference_at(old, &w) + u;
            let lift: Vector3<f64> = w.iter().map(|&(a, x)| normals[a] * (x * (old.position(state, a) - p).dot(&normals[a]))).sum();
            out.u[n] = p + lift * PHONG_ALPHA - new.x0[n];
            out.frames[n] = frame;
            weights[n] = w;
        }
    }
    Ok((out, weights))
}

/// Blending factor of the Phong correction: ½ makes it the sagitta of a circular arc to
/// leading order (a chord of angle θ: bilinear midpoint off by −θ²R/8, the projections onto
/// the two tangent planes by +θ²R/8 · 2).
const PHONG_ALPHA: f64 = 0.5;

/// Unit normals of the current mid-surface at the nodes of `model`: the sum over the
/// adjacent elements of (x₂ − x₀) × (x₃ − x₁) (twice the element's projected area along its
/// normal), normalised; zero at nodes of no element.
pub fn nodal_normals(model: &Model, state: &State) -> Vec<Vector3<f64>> {
    let mut n = vec![Vector3::zeros(); model.n_nodes()];
    for e in &model.elements {
        let x = e.nodes.map(|a| model.position(state, a));
        let c = crate::mesh::quad_normal(&x);
        for &a in &e.nodes {
            n[a] += c;
        }
    }
    n.into_iter().map(|v| v.try_normalize(1e-300).unwrap_or_else(Vector3::zeros)).collect()
}

/// The interpolated old reference position Σ w_a X_a (equal to the new node's reference
/// position on flat parts; on others the displacement absorbs the chord difference so that
/// the current position is the interpolated current position).
fn old_reference_at(old: &Model, w: &[(usize, f64)]) -> Vector3<f64> {
    w.iter().map(|&(a, x)| old.x0[a] * x).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_bilinear_recovers_local_coordinates() {
        let c = [[0.0, 0.0], [2.0, 0.1], [2.3, 1.7], [-0.2, 1.2]];
        for (xi, eta) in [(0.3, -0.4), (-0.9, 0.95), (1.0, 1.0), (0.0, 0.0)] {
            let n = shape(xi, eta);
            let p = [(0..4).map(|a| n[a] * c[a][0]).sum(), (0..4).map(|a| n[a] * c[a][1]).sum()];
            let (a, b, out) = inverse_bilinear(&c, p).expect("regular quad");
            assert!((a - xi).abs() < 1e-12 && (b - eta).abs() < 1e-12 && out < 1e-12, "({a}, {b}) vs ({xi}, {eta})");
        }
        let (_, _, out) = inverse_bilinear(&c, [5.0, 5.0]).expect("regular quad");
        assert!(out > 0.5);
    }

    #[test]
    fn locator_finds_the_containing_quad() {
        // A 3 × 2 grid of unit squares, element k = i + 3 j.
        let quads: Vec<(usize, [[f64; 2]; 4])> = (0..6).map(|k| {
            let (i, j) = ((k % 3) as f64, (k / 3) as f64);
            (k, [[i, j], [i + 1.0, j], [i + 1.0, j + 1.0], [i, j + 1.0]])
        }).collect();
        let l = Locator::new(quads);
        let (e, xi, eta) = l.locate([2.25, 1.5]).expect("inside");
        assert_eq!(e, 5);
        assert!((xi + 0.5).abs() < 1e-12 && eta.abs() < 1e-12);
        let (e, xi, _) = l.locate([3.0 + 1e-13, 0.5]).expect("on the boundary");
        assert_eq!(e, 2);
        assert!((xi - 1.0).abs() < 1e-12);
    }
}
