//! The node-to-surface penalty mechanics of inter-ply contact (see the parent module): a
//! ply's triangulated surface, a slave node's record against it and its committed history,
//! the closest-point search, and one pair's normal and friction forces with their exact
//! Jacobian (forward-mode dual numbers, `dual`).

use nalgebra::Vector3;
use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::math::Vector as PVec;
use parry3d_f64::partitioning::Bvh;
use parry3d_f64::query::PointQuery;
use parry3d_f64::shape::Triangle;

use super::dual::{add, cross, dot, scale, sub, D, V3};
use super::{EPS_FRAC, NV, SLIDE_ARG, SLIP_MIN};
/// A ply's surface: its quads split into triangles.
#[derive(Clone, Debug)]
pub(super) struct Surface {
    /// Model part.
    pub(super) part: usize,
    /// Triangles (global nodes).
    pub(super) tris: Vec<[usize; 3]>,
    /// Membrane stiffness of the ply (N/m).
    pub(super) membrane: f64,
    /// Half-thickness of the ply.
    pub(super) half: f64,
    /// Edges (node pairs, smaller first) of the ply's free boundary: quad sides of one
    /// element that are not sewn (both ends tied).
    pub(super) boundary: std::collections::BTreeSet<(usize, usize)>,
    /// Nodes on those edges.
    pub(super) boundary_nodes: std::collections::BTreeSet<usize>,
}

impl Surface {
    /// Whether the closest-point feature of triangle `tri` with barycentric coordinates
    /// `bary` (zero coordinates: the point lies on an edge or at a vertex) lies on the
    /// ply's free boundary.
    pub(super) fn on_boundary(&self, tri: usize, bary: &[f64; 3]) -> bool {
        let t = self.tris[tri];
        let f: Vec<usize> = (0..3).filter(|&j| bary[j] > 0.0).map(|j| t[j]).collect();
        match f[..] {
            [a, b] => self.boundary.contains(&(a.min(b), a.max(b))),
            [a] => self.boundary_nodes.contains(&a),
            _ => false,
        }
    }

    /// Distance of the node at `y` from the master ply, positive on side `side` — `d` (the
    /// signed closest-point distance from triangle `tri`, barycentric coordinates `bary`)
    /// inside the ply; for a node whose closest point lies on the free boundary, its distance
    /// from the plane of that facet, or `None` more than half an element past the edge; with
    /// whether that boundary plane was used.
    pub(super) fn distance(&self, tri: usize, bary: &[f64; 3], d: f64, side: f64, x: &dyn Fn(usize) -> Vector3<f64>, y: &Vector3<f64>) -> Option<(f64, bool)> {
        if !self.on_boundary(tri, bary) {
            return Some((side * d, false));
        }
        let p = self.tris[tri].map(x);
        let (lam, n) = project(&p, y)?;
        (lam.iter().all(|&l| l >= -0.5)).then(|| (side * n.dot(&(y - p[0])), true))
    }
}

/// One slave node against one master surface.
#[derive(Clone, Debug)]
pub(super) struct Record {
    pub(super) node: usize,
    pub(super) surface: usize,
    /// Side σ of the master the slave lies on (reference configuration).
    pub(super) side: f64,
    /// (h_s + h_m)/2.
    pub(super) offset: f64,
    /// Normal penalty (N/m).
    pub(super) k_n: f64,
    /// Tributary area of the slave node.
    pub(super) area: f64,
    /// Characteristic element size at the slave node.
    pub(super) size: f64,
}

/// Committed state of a record.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct History {
    /// Anchor: master triangle and barycentric coordinates of the stuck material point.
    pub(super) anchor: Option<(usize, [f64; 3])>,
    pub(super) active: bool,
    pub(super) sliding: bool,
    pub(super) slip: f64,
    /// Normal force λ̄ and unit normal n̄ of the last converged state (0 when out of
    /// contact there): the lagged friction bound and tangent plane.
    pub(super) lagged: (f64, Vector3<f64>),
}

/// Evaluation of a record at a configuration.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Eval {
    /// Projection triangle and barycentric coordinates, when within reach.
    pub(super) proj: Option<(usize, [f64; 3])>,
    pub(super) gap: f64,
    pub(super) lambda: f64,
    pub(super) tangential: Vector3<f64>,
    /// Unit contact direction on the slave.
    pub(super) normal: Vector3<f64>,
    pub(super) active: bool,
    pub(super) sliding: bool,
}

/// Forces of one record: the nodes, their forces and (optionally) the Jacobian
/// J[3i+α][3j+β] = ∂f_{iα}/∂x_{jβ}.
pub(super) struct PairForces {
    pub(super) nodes: Vec<usize>,
    pub(super) forces: Vec<Vector3<f64>>,
    pub(super) jacobian: Vec<[f64; NV]>,
}

pub(super) fn pv(v: &Vector3<f64>) -> PVec {
    PVec::new(v.x, v.y, v.z)
}

/// Bounding boxes of a surface's triangles at positions `x`.
pub(super) fn boxes(s: &Surface, x: &dyn Fn(usize) -> Vector3<f64>) -> Vec<Aabb> {
    s.tris
        .iter()
        .map(|t| {
            let p = t.map(x);
            let lo = p[0].inf(&p[1]).inf(&p[2]);
            let hi = p[0].sup(&p[1]).sup(&p[2]);
            Aabb::new(pv(&lo), pv(&hi))
        })
        .collect()
}

/// Plane projection of `x` on triangle `p`: barycentric coordinates and the unit normal.
pub(super) fn project(p: &[Vector3<f64>; 3], x: &Vector3<f64>) -> Option<([f64; 3], Vector3<f64>)> {
    let (e1, e2, r) = (p[1] - p[0], p[2] - p[0], x - p[0]);
    let m = e1.cross(&e2);
    let nm = m.norm();
    let (a11, a12, a22) = (e1.dot(&e1), e1.dot(&e2), e2.dot(&e2));
    let det = a11 * a22 - a12 * a12;
    if !(nm > 0.0 && det > 0.0) {
        return None;
    }
    let (b1, b2) = (r.dot(&e1), r.dot(&e2));
    let l1 = (a22 * b1 - a12 * b2) / det;
    let l2 = (a11 * b2 - a12 * b1) / det;
    Some(([1.0 - l1 - l2, l1, l2], m / nm))
}

/// Nearest triangle of `s` to `y` within `reach` (BVH candidates, parry3d closest points):
/// (triangle, barycentric coordinates of the closest point — a coordinate is exactly 0 when
/// the point lies on an edge or vertex — and the signed distance ±|y − x_c|, signed by the
/// side of the triangle's plane).
pub(super) fn closest(s: &Surface, bvh: &Bvh, x: &dyn Fn(usize) -> Vector3<f64>, y: &Vector3<f64>, reach: f64) -> Option<(usize, [f64; 3], f64)> {
    let q = Aabb::new(pv(&y.add_scalar(-reach)), pv(&y.add_scalar(reach)));
    // Ties (a closest point at a vertex or on an edge shared by several triangles) go to
    // the lowest triangle index, not to the BVH's visiting order, which a perturbation of the
    // nodes reorders: the choice, and with it the facet a boundary node is measured against,
    // is then a function of the configuration.
    let tie = 1e-12 * reach;
    let mut best: Option<(f64, usize)> = None;
    for leaf in bvh.intersect_aabb(&q) {
        let t = leaf as usize;
        let p = s.tris[t].map(x);
        let tri = Triangle::new(pv(&p[0]), pv(&p[1]), pv(&p[2]));
        let proj = tri.project_local_point(pv(y), true);
        let d = (proj.point - pv(y)).length();
        if d <= reach && best.is_none_or(|(bd, bt)| d < bd - tie || (d <= bd + tie && t < bt)) {
            best = Some((d, t));
        }
    }
    let (_, t) = best?;
    let p = s.tris[t].map(x);
    let (_, n) = project(&p, y)?;
    let bary = closest_point_barycentric(&p, y);
    let xc = p[0] * bary[0] + p[1] * bary[1] + p[2] * bary[2];
    let v = y - xc;
    Some((t, bary, v.norm() * n.dot(&v).signum()))
}

/// Barycentric coordinates of the point of triangle `p` closest to `y` (Ericson,
/// *Real-Time Collision Detection*, 2005, §5.1.5): clamped coordinates are exactly zero.
pub(super) fn closest_point_barycentric(p: &[Vector3<f64>; 3], y: &Vector3<f64>) -> [f64; 3] {
    let (ab, ac, ap) = (p[1] - p[0], p[2] - p[0], y - p[0]);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let bp = y - p[1];
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return [0.0, 1.0, 0.0];
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return [1.0 - v, v, 0.0];
    }
    let cp = y - p[2];
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return [0.0, 0.0, 1.0];
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return [1.0 - w, 0.0, w];
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return [0.0, 1.0 - w, w];
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    [1.0 - v - w, v, w]
}

/// Normal and friction forces of an active record, slave at node `r.node`, projection
/// triangle `tri` (`plane`: measured against the facet's plane, a node overhanging the
/// master's free edge), anchor (triangle nodes, barycentric coordinates) if any; `kt` the
/// tangential penalty. Forces and Jacobian through dual numbers (see the module doc).
#[allow(clippy::too_many_arguments)] // the pair's geometry, history and law, all distinct
pub(super) fn pair_forces(
    r: &Record,
    tri: [usize; 3],
    bary: [f64; 3],
    plane: bool,
    anchor: Option<([usize; 3], [f64; 3])>,
    lagged: (f64, Vector3<f64>),
    x: &dyn Fn(usize) -> Vector3<f64>,
    mu: f64,
    kt: f64,
    with_tangent: bool,
) -> (Eval, PairForces) {
    let mut nodes = vec![r.node];
    let slot = |a: usize, nodes: &mut Vec<usize>| match nodes.iter().position(|&b| b == a) {
        Some(i) => i,
        None => {
            nodes.push(a);
            nodes.len() - 1
        }
    };
    let ti = tri.map(|a| slot(a, &mut nodes));
    let ai = anchor.map(|(t, _)| t.map(|a| slot(a, &mut nodes)));
    let var = |i: usize| -> V3 {
        let p = x(nodes[i]);
        std::array::from_fn(|k| if with_tangent { D::var(p[k], 3 * i + k) } else { D::c(p[k]) })
    };
    let xs = var(0);
    let xt = ti.map(var);
    let mut f: Vec<V3> = vec![[D::c(0.0); 3]; nodes.len()];
    // Normal part: the closest point x_c of the triangle — inside it (plane projection,
    // normal n of the facet), on an edge or at a vertex (direction (x_s − x_c)/|…|, signed
    // by the facet side) — so the gap is continuous as the node passes between facets.
    let feature: Vec<usize> = (0..3).filter(|&j| bary[j] > 0.0).collect();
    let e1 = sub(&xt[1], &xt[0]);
    let e2 = sub(&xt[2], &xt[0]);
    let m = cross(&e1, &e2);
    let n_facet = scale(&m, D::c(1.0) / dot(&m, &m).sqrt());
    let mut lam = [D::c(0.0); 3];
    let (n, gap) = if feature.len() == 3 || plane {
        let rv = sub(&xs, &xt[0]);
        let (a11, a12, a22) = (dot(&e1, &e1), dot(&e1, &e2), dot(&e2, &e2));
        let (b1, b2) = (dot(&rv, &e1), dot(&rv, &e2));
        let det = a11 * a22 - a12 * a12;
        let l1 = (a22 * b1 - a12 * b2) / det;
        let l2 = (a11 * b2 - a12 * b1) / det;
        lam = [D::c(1.0) - l1 - l2, l1, l2];
        (n_facet, dot(&n_facet, &rv) * r.side - D::c(r.offset))
    } else {
        let xc = if feature.len() == 2 {
            let (i, j) = (feature[0], feature[1]);
            let e = sub(&xt[j], &xt[i]);
            let t = dot(&sub(&xs, &xt[i]), &e) / dot(&e, &e);
            lam[i] = D::c(1.0) - t;
            lam[j] = t;
            add(&xt[i], &scale(&e, t))
        } else {
            let i = feature.first().copied().unwrap_or(0);
            lam[i] = D::c(1.0);
            xt[i]
        };
        let v = sub(&xs, &xc);
        let dist = dot(&v, &v).sqrt();
        let sign = if dot(&n_facet, &v).v * r.side >= 0.0 { 1.0 } else { -1.0 };
        // Unit direction from x_c to the slave, on the slave's side.
        (scale(&v, D::c(sign * r.side) / dist), dist * sign - D::c(r.offset))
    };
    // C¹-regularised penalty (a quadratic ramp over the first ε of penetration, cf. the
    // smoothed penalty of Wriggers 2006 §5.2): λ_N = 0 for g ≥ 0, k_n g²/(2ε) for −ε < g < 0,
    // k_n(−g − ε/2) for g ≤ −ε — continuous with its derivative −k_n·min(1, −g/ε), and zero
    // at g = 0, where plies laid on each other start.
    let eps = EPS_FRAC * r.offset;
    let lambda_n = if gap.v <= -eps { (D::c(-0.5 * eps) - gap) * r.k_n } else { gap * gap * (0.5 * r.k_n / eps) };
    let fn_s = scale(&n, lambda_n * r.side);
    f[0] = add(&f[0], &fn_s);
    for j in 0..3 {
        f[ti[j]] = sub(&f[ti[j]], &scale(&fn_s, lam[j]));
    }
    let normal = Vector3::new(n[0].v, n[1].v, n[2].v) * r.side;
    let mut ev = Eval { gap: gap.v, lambda: lambda_n.v, normal, active: gap.v < 0.0, ..Default::default() };
    // Friction against the anchor (the master's material point where the slave stuck).
    if let (Some((_, nh)), Some(ai)) = (anchor, ai)
        && mu > 0.0
        && lambda_n.v > 0.0
    {
        let xa = (0..3).fold([D::c(0.0); 3], |acc, j| add(&acc, &scale(&var(ai[j]), D::c(nh[j]))));
        let dv = sub(&xs, &xa);
        // Lagged friction (as in `mechanics.rs`; Li et al. 2020 §5): a pair in contact at the
        // last converged state measures the slip in that state's tangent plane n̄ and bounds
        // it by μλ̄, so the friction force is the gradient of a potential of the slip and its
        // Jacobian is symmetric; a pair just coming into contact uses the current ones.
        let (lam_f, nf) = if lagged.0 > 0.0 { (lagged.0, std::array::from_fn(|k| D::c(lagged.1[k] * r.side))) } else { (lambda_n.v, n) };
        let s = sub(&dv, &scale(&nf, dot(&nf, &dv)));
        let sn = dot(&s, &s).sqrt();
        let cap = mu * lam_f;
        // Elastic slip range μλ/k_t, at least SLIP_MIN of the element size.
        let kt = kt.min(cap / (SLIP_MIN * r.size));
        let arg = kt * sn.v / cap;
        // Smooth Coulomb law t = −μλ tanh(k_t|s|/(μλ)) ŝ; its linear (sticking) limit −k_t s
        // near s = 0, where ŝ is undefined.
        let t = if arg < 1e-8 { scale(&s, D::c(-kt)) } else { scale(&s, (sn * (kt / cap)).tanh() * (-cap) / sn) };
        ev.tangential = Vector3::new(t[0].v, t[1].v, t[2].v);
        ev.sliding = arg > SLIDE_ARG;
        f[0] = add(&f[0], &t);
        for j in 0..3 {
            f[ai[j]] = sub(&f[ai[j]], &scale(&t, D::c(nh[j])));
        }
    }
    let forces = f.iter().map(|v| Vector3::new(v[0].v, v[1].v, v[2].v)).collect();
    let jacobian = if with_tangent { f.iter().flat_map(|v| v.iter().map(|c| c.d)).collect() } else { Vec::new() };
    (ev, PairForces { nodes, forces, jacobian })
}
