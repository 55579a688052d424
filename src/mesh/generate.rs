//! Structured quad mesh generators for the standard shell benchmark shapes.
//!
//! Every generator lays out an `(nu+1) x (nv+1)` grid of nodes in two
//! surface parameters `(u, v)` (node `(i, j)` has index `j*(nu+1) + i`), with
//! quads `(i,j) (i+1,j) (i+1,j+1) (i,j+1)` oriented so that `r_u x r_v` is
//! the director. For a full revolution the last node column is merged with
//! the first (node count `(nu+1)*nv`). Each generated mesh is checked with
//! [`ShellMesh::validate`] before it is returned.

use super::{MeshError, ShellMesh, Spacing};
use nalgebra::Vector3;
use std::collections::BTreeMap;
use std::f64::consts::{FRAC_PI_2, TAU};

/// Largest node count a generator will allocate (about 2 GB of mesh); the scene's memory
/// budget (`crate::budget`) usually refuses far smaller models first.
pub const MAX_NODES: usize = 20_000_000;

/// Relative tolerance for recognising an angular span of a full turn.
const FULL_TURN_TOL: f64 = 1e-9;

/// A closed (full-turn) grid must be uniformly spaced: the distorted pattern is not periodic.
pub(super) fn closed_uniform(closed: bool, spacing: Spacing) -> Result<(), MeshError> {
    if closed && spacing != Spacing::Uniform {
        return Err(MeshError::Invalid("a distorted spacing needs an open panel (not a full turn)".into()));
    }
    Ok(())
}

pub(super) fn positive(name: &str, value: f64) -> Result<(), MeshError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(MeshError::Invalid(format!(
            "{name} must be a finite positive number, got {value}"
        )))
    }
}

pub(super) fn finite(name: &str, value: f64) -> Result<(), MeshError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(MeshError::Invalid(format!(
            "{name} must be finite, got {value}"
        )))
    }
}

pub(super) fn count(name: &str, value: usize, min: usize) -> Result<(), MeshError> {
    if value >= min {
        Ok(())
    } else if min == 1 {
        Err(MeshError::Invalid(format!(
            "{name} must be at least 1, got {value}"
        )))
    } else {
        Err(MeshError::Invalid(format!(
            "{name} must be at least {min} here, got {value}"
        )))
    }
}

/// Checks an angular span `a1 - a0` in (0, 2π]; returns `(span, closed)`.
pub(super) fn angular_span(name0: &str, a0: f64, name1: &str, a1: f64) -> Result<(f64, bool), MeshError> {
    finite(name0, a0)?;
    finite(name1, a1)?;
    let span = a1 - a0;
    if span <= 0.0 {
        return Err(MeshError::Invalid(format!(
            "{name1} ({a1}) must be greater than {name0} ({a0})"
        )));
    }
    let closed = (span - TAU).abs() <= FULL_TURN_TOL * TAU;
    if span > TAU && !closed {
        return Err(MeshError::Invalid(format!(
            "{name1} - {name0} = {span} exceeds a full turn (2π)"
        )));
    }
    Ok((if closed { TAU } else { span }, closed))
}

/// Structured grid in parameters `(u, v)`.
pub(super) struct Grid {
    nu: usize,
    nv: usize,
    /// Last column `j = nv` merged with `j = 0`.
    periodic: bool,
}

impl Grid {
    pub(super) fn new(nu: usize, nv: usize, periodic: bool) -> Result<Self, MeshError> {
        let cols = if periodic { Some(nv) } else { nv.checked_add(1) };
        let nodes = nu.checked_add(1).zip(cols).and_then(|(r, c)| r.checked_mul(c));
        let elements = nu.checked_mul(nv);
        match (nodes, elements) {
            (Some(n), Some(_)) if n <= MAX_NODES => {
                // Positions, directors and quads: about 80 bytes per node.
                crate::budget::check_alloc(&format!("a {nu} x {nv} element grid"), n as u64, 80).map_err(MeshError::Invalid)?;
                Ok(Grid { nu, nv, periodic })
            }
            _ => Err(MeshError::Invalid(format!(
                "a {nu} x {nv} element grid is too large (limit {MAX_NODES} nodes)"
            ))),
        }
    }

    /// Number of distinct node columns in `v`.
    pub(super) fn cols(&self) -> usize {
        if self.periodic { self.nv } else { self.nv + 1 }
    }

    pub(super) fn id(&self, i: usize, j: usize) -> usize {
        let j = if self.periodic && j == self.nv { 0 } else { j };
        j * (self.nu + 1) + i
    }

    /// Nodes at fixed `v` index `j`, ordered by increasing `u`.
    pub(super) fn row_u(&self, j: usize) -> Vec<usize> {
        (0..=self.nu).map(|i| self.id(i, j)).collect()
    }

    /// Nodes at fixed `u` index `i`, ordered by increasing `v` (each node once).
    pub(super) fn row_v(&self, i: usize) -> Vec<usize> {
        (0..self.cols()).map(|j| self.id(i, j)).collect()
    }

    /// Builds the mesh; `f(i, j)` gives the position and (not necessarily
    /// unit) director of node `(i, j)`.
    pub(super) fn build(
        &self,
        f: impl Fn(usize, usize) -> (Vector3<f64>, Vector3<f64>),
    ) -> Result<ShellMesh, MeshError> {
        let n = (self.nu + 1) * self.cols();
        let mut nodes = Vec::with_capacity(n);
        let mut directors = Vec::with_capacity(n);
        for j in 0..self.cols() {
            for i in 0..=self.nu {
                let (p, d) = f(i, j);
                let len = d.norm();
                if !(len.is_finite() && len > 0.0) {
                    return Err(MeshError::Invalid(format!(
                        "zero or non-finite surface normal at grid node ({i}, {j})"
                    )));
                }
                nodes.push(p);
                directors.push(d / len);
            }
        }
        let mut quads = Vec::with_capacity(self.nu * self.nv);
        for j in 0..self.nv {
            for i in 0..self.nu {
                quads.push([
                    self.id(i, j),
                    self.id(i + 1, j),
                    self.id(i + 1, j + 1),
                    self.id(i, j + 1),
                ]);
            }
        }
        Ok(ShellMesh {
            nodes,
            directors,
            quads,
            edges: BTreeMap::new(),
        })
    }
}

pub(super) fn finish(generator: &str, hint: &str, mesh: ShellMesh) -> Result<ShellMesh, MeshError> {
    match mesh.validate() {
        Ok(()) => Ok(mesh),
        Err(e) => Err(MeshError::Invalid(format!(
            "{generator}: generated mesh is unusable ({e}); {hint}"
        ))),
    }
}

pub(super) fn edges(list: Vec<(&str, Vec<usize>)>) -> BTreeMap<String, Vec<usize>> {
    list.into_iter().map(|(k, v)| (k.to_string(), v)).collect()
}

/// Flat rectangular plate in the xy plane with `nx x ny` quads: x in
/// `[0, lx]`, y in `[0, ly]`, directors `+z`.
///
/// Edges: `"xmin"`, `"xmax"` (ordered by increasing y), `"ymin"`, `"ymax"`
/// (ordered by increasing x).
pub fn rectangle(lx: f64, ly: f64, nx: usize, ny: usize) -> Result<ShellMesh, MeshError> {
    positive("lx", lx)?;
    positive("ly", ly)?;
    count("nx", nx, 1)?;
    count("ny", ny, 1)?;
    let g = Grid::new(nx, ny, false)?;
    let mut m = g.build(|i, j| {
        let x = lx * i as f64 / nx as f64;
        let y = ly * j as f64 / ny as f64;
        (Vector3::new(x, y, 0.0), Vector3::z())
    })?;
    m.edges = edges(vec![
        ("xmin", g.row_v(0)),
        ("xmax", g.row_v(nx)),
        ("ymin", g.row_u(0)),
        ("ymax", g.row_u(ny)),
    ]);
    finish("rectangle", "check the parameters", m)
}

/// Rectangle in the xy plane with its node lines at the given coordinates: `xs` from 0 to
/// `lx`, `ys` from 0 to `ly`, each strictly increasing (a graded tensor-product grid, e.g. the
/// refined mesh of `crate::refine`). Node (i, j) is (xs[i], ys[j], 0); edges as [`rectangle`].
pub fn graded_rectangle(lx: f64, ly: f64, xs: &[f64], ys: &[f64]) -> Result<ShellMesh, MeshError> {
    positive("lx", lx)?;
    positive("ly", ly)?;
    for (name, lines, end) in [("x", xs, lx), ("y", ys, ly)] {
        count(&format!("the number of {name} lines"), lines.len(), 2)?;
        let tol = 1e-9 * end;
        if (lines[0]).abs() > tol || (lines[lines.len() - 1] - end).abs() > tol {
            return Err(MeshError::Invalid(format!("the {name} lines must run from 0 to {end}, got {} to {}", lines[0], lines[lines.len() - 1])));
        }
        if let Some(k) = lines.windows(2).position(|w| !(w[1] > w[0])) {
            return Err(MeshError::Invalid(format!("the {name} lines must increase strictly: line {} ({}) is not above line {k} ({})", k + 1, lines[k + 1], lines[k])));
        }
    }
    let (nx, ny) = (xs.len() - 1, ys.len() - 1);
    let g = Grid::new(nx, ny, false)?;
    let mut m = g.build(|i, j| (Vector3::new(xs[i], ys[j], 0.0), Vector3::z()))?;
    m.edges = edges(vec![
        ("xmin", g.row_v(0)),
        ("xmax", g.row_v(nx)),
        ("ymin", g.row_u(0)),
        ("ymax", g.row_u(ny)),
    ]);
    finish("graded rectangle", "check the node lines", m)
}

/// Cylindrical panel of radius `radius` about the global x axis with
/// `n_axial x n_circ` quads: x in `[0, length]`, angle θ from `theta0` to
/// `theta1` (radians, measured from +z towards +y), node
/// `(x, R sin θ, R cos θ)`, director the outward radial `(0, sin θ, cos θ)`.
///
/// Edges: `"x0"`, `"x1"` (ordered by increasing θ), `"theta0"`, `"theta1"`
/// (ordered by increasing x). If `theta1 - theta0` is a full turn (2π, to a
/// relative 1e-9) the seam is merged into a closed tube with
/// `(n_axial+1)*n_circ` nodes, `n_circ >= 3` is required and there are no
/// θ edges.
pub fn cylindrical_panel(
    radius: f64,
    length: f64,
    theta0: f64,
    theta1: f64,
    n_axial: usize,
    n_circ: usize,
) -> Result<ShellMesh, MeshError> {
    cylindrical_panel_spaced(radius, length, theta0, theta1, n_axial, n_circ, Spacing::Uniform)
}

/// [`cylindrical_panel`] with the nodes spaced in (x, θ) by `spacing` (an open panel only
/// for [`Spacing::Distorted`]); nodes and directors on the exact cylinder.
pub fn cylindrical_panel_spaced(
    radius: f64,
    length: f64,
    theta0: f64,
    theta1: f64,
    n_axial: usize,
    n_circ: usize,
    spacing: Spacing,
) -> Result<ShellMesh, MeshError> {
    positive("radius", radius)?;
    positive("length", length)?;
    let (span, closed) = angular_span("theta0", theta0, "theta1", theta1)?;
    count("n_axial", n_axial, 1)?;
    count("n_circ", n_circ, if closed { 3 } else { 1 })?;
    closed_uniform(closed, spacing)?;
    let g = Grid::new(n_axial, n_circ, closed)?;
    let mut m = g.build(|i, j| {
        let (fx, ft) = spacing.point(i, j, n_axial, n_circ);
        let x = length * fx;
        let t = theta0 + span * ft;
        let (s, c) = t.sin_cos();
        (
            Vector3::new(x, radius * s, radius * c),
            Vector3::new(0.0, s, c),
        )
    })?;
    let mut e = vec![("x0", g.row_v(0)), ("x1", g.row_v(n_axial))];
    if !closed {
        e.push(("theta0", g.row_u(0)));
        e.push(("theta1", g.row_u(n_circ)));
    }
    m.edges = edges(e);
    finish("cylindrical_panel", "increase n_circ", m)
}

/// Spherical shell of radius `radius` centred at the origin with its pole on
/// +z and a polar hole of half-angle `hole_angle`: colatitude from
/// `hole_angle` to π/2 in `n_merid` elements, azimuth φ (from +x towards +y)
/// from `phi0` to `phi1` in `n_circ` elements. Node
/// `R (sin α cos φ, sin α sin φ, cos α)`, director outward radial.
///
/// Edges: `"hole"`, `"equator"` (ordered by increasing φ), `"phi0"`,
/// `"phi1"` (ordered from the hole to the equator). A full turn in φ merges
/// the seam (`(n_merid+1)*n_circ` nodes, `n_circ >= 3`, no φ edges).
/// `hole_angle` must lie in (0, π/2).
pub fn hemisphere(
    radius: f64,
    hole_angle: f64,
    phi0: f64,
    phi1: f64,
    n_merid: usize,
    n_circ: usize,
) -> Result<ShellMesh, MeshError> {
    hemisphere_spaced(radius, hole_angle, phi0, phi1, n_merid, n_circ, Spacing::Uniform)
}

/// [`hemisphere`] with the nodes spaced in (α, φ) by `spacing` (an open segment only for
/// [`Spacing::Distorted`]); nodes and directors on the exact sphere.
pub fn hemisphere_spaced(
    radius: f64,
    hole_angle: f64,
    phi0: f64,
    phi1: f64,
    n_merid: usize,
    n_circ: usize,
    spacing: Spacing,
) -> Result<ShellMesh, MeshError> {
    positive("radius", radius)?;
    if !(hole_angle.is_finite() && hole_angle > 0.0 && hole_angle < FRAC_PI_2) {
        return Err(MeshError::Invalid(format!(
            "hole_angle must lie strictly between 0 and π/2 radians, got {hole_angle}"
        )));
    }
    let (span, closed) = angular_span("phi0", phi0, "phi1", phi1)?;
    count("n_merid", n_merid, 1)?;
    count("n_circ", n_circ, if closed { 3 } else { 1 })?;
    closed_uniform(closed, spacing)?;
    let g = Grid::new(n_merid, n_circ, closed)?;
    let mut m = g.build(|i, j| {
        let (fa, fp) = spacing.point(i, j, n_merid, n_circ);
        let a = hole_angle + (FRAC_PI_2 - hole_angle) * fa;
        let p = phi0 + span * fp;
        // exact z = 0 on the equator
        let (sa, ca) = if i == n_merid {
            (1.0, 0.0)
        } else {
            a.sin_cos()
        };
        let (sp, cp) = p.sin_cos();
        let d = Vector3::new(sa * cp, sa * sp, ca);
        (radius * d, d)
    })?;
    let mut e = vec![("hole", g.row_v(0)), ("equator", g.row_v(n_merid))];
    if !closed {
        e.push(("phi0", g.row_u(0)));
        e.push(("phi1", g.row_u(n_circ)));
    }
    m.edges = edges(e);
    finish("hemisphere", "increase n_circ or n_merid", m)
}

/// Pre-twisted strip along x with `nx x ny` quads: x from 0 to `length`,
/// width coordinate s in `[-width/2, width/2]`, the cross-section rotated
/// about the x axis by φ(x) = `twist` x / `length` (radians, any sign, may be
/// several turns): node `(x, s cos φ, s sin φ)`. Directors are the exact
/// unit normals `r_x × r_s / |r_x × r_s|` = `(-s φ', -sin φ, cos φ)` normalised
/// (all +z for `twist = 0`).
///
/// Edges: `"x0"`, `"x1"` (ordered by increasing s), `"smin"`, `"smax"`
/// (ordered by increasing x).
pub fn twisted_strip(
    length: f64,
    width: f64,
    twist: f64,
    nx: usize,
    ny: usize,
) -> Result<ShellMesh, MeshError> {
    positive("length", length)?;
    positive("width", width)?;
    finite("twist", twist)?;
    count("nx", nx, 1)?;
    count("ny", ny, 1)?;
    let g = Grid::new(nx, ny, false)?;
    let rate = twist / length;
    let mut m = g.build(|i, j| {
        let x = if i == nx {
            length
        } else {
            length * i as f64 / nx as f64
        };
        let s = width * (j as f64 / ny as f64 - 0.5);
        let (sp, cp) = (rate * x).sin_cos();
        // r_x = (1, -s φ' sin φ, s φ' cos φ), r_s = (0, cos φ, sin φ)
        let normal = Vector3::new(-s * rate, -sp, cp);
        (Vector3::new(x, s * cp, s * sp), normal)
    })?;
    m.edges = edges(vec![
        ("x0", g.row_v(0)),
        ("x1", g.row_v(nx)),
        ("smin", g.row_u(0)),
        ("smax", g.row_u(ny)),
    ]);
    finish(
        "twisted_strip",
        "increase nx (each element should twist well under a quarter turn)",
        m,
    )
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn check_directors_normal(m: &ShellMesh) {
        // Each director is unit and orthogonal to the mesh edges leaving its
        // node, up to the discretisation chord error.
        for (i, d) in m.directors.iter().enumerate() {
            assert!((d.norm() - 1.0).abs() < 1e-12, "node {i}");
        }
    }

    /// Node, director and quad counts of `m`, which must validate.
    pub(in crate::mesh) fn counts(m: &ShellMesh, nodes: usize, quads: usize) {
        assert_eq!(m.nodes.len(), nodes);
        assert_eq!(m.directors.len(), nodes);
        assert_eq!(m.quads.len(), quads);
        m.validate().unwrap();
        let q = m.quality();
        assert!(q.min_jacobian_ratio > 0.0, "{q:?}");
    }

    #[test]
    fn rectangle_counts_edges_orientation() {
        let m = rectangle(2.0, 1.0, 4, 3).unwrap();
        counts(&m, 20, 12);
        check_directors_normal(&m);
        assert_eq!(
            m.edges.keys().collect::<Vec<_>>(),
            ["xmax", "xmin", "ymax", "ymin"]
        );
        assert_eq!(m.edges["ymin"], vec![0, 1, 2, 3, 4]);
        assert_eq!(m.edges["xmin"], vec![0, 5, 10, 15]);
        assert_eq!(m.edges["xmax"], vec![4, 9, 14, 19]);
        assert_eq!(m.edges["ymax"], vec![15, 16, 17, 18, 19]);
        for &i in &m.edges["xmax"] {
            assert_eq!(m.nodes[i].x, 2.0);
        }
        for &i in &m.edges["ymax"] {
            assert_eq!(m.nodes[i].y, 1.0);
        }
        for q in &m.quads {
            let x0 = m.nodes[q[0]];
            let n = (m.nodes[q[1]] - x0).cross(&(m.nodes[q[3]] - x0));
            assert!(n.z > 0.0);
        }
        let q = m.quality();
        assert!((q.min_angle_deg - 90.0).abs() < 1e-9);
        assert!((q.max_aspect_ratio - 1.5).abs() < 1e-9);
    }

    #[test]
    fn rectangle_rejects_bad_parameters() {
        let e = rectangle(0.0, 1.0, 1, 1).unwrap_err();
        assert!(e.to_string().contains("lx"), "{e}");
        assert!(
            rectangle(1.0, -1.0, 1, 1)
                .unwrap_err()
                .to_string()
                .contains("ly")
        );
        assert!(
            rectangle(1.0, f64::NAN, 1, 1)
                .unwrap_err()
                .to_string()
                .contains("ly")
        );
        assert!(
            rectangle(1.0, 1.0, 0, 1)
                .unwrap_err()
                .to_string()
                .contains("nx")
        );
        assert!(
            rectangle(1.0, 1.0, 1, 0)
                .unwrap_err()
                .to_string()
                .contains("ny")
        );
        assert!(
            rectangle(1.0, 1.0, usize::MAX, 2)
                .unwrap_err()
                .to_string()
                .contains("too large")
        );
    }

    #[test]
    fn cylinder_panel() {
        let r = 3.0;
        let m = cylindrical_panel(r, 5.0, -0.3, 0.5, 6, 4).unwrap();
        counts(&m, 7 * 5, 24);
        for (p, d) in m.nodes.iter().zip(&m.directors) {
            let rad = (p.y * p.y + p.z * p.z).sqrt();
            assert!((rad - r).abs() < 1e-12);
            // director radial, hence normal to the cylinder surface
            let radial = Vector3::new(0.0, p.y, p.z) / rad;
            assert!((d - radial).norm() < 1e-12);
            assert!(d.x.abs() < 1e-15);
        }
        assert_eq!(m.edges.len(), 4);
        for &i in &m.edges["x1"] {
            assert_eq!(m.nodes[i].x, 5.0);
        }
        for &i in &m.edges["theta0"] {
            let p = m.nodes[i];
            assert!((p.y.atan2(p.z) + 0.3).abs() < 1e-12);
        }
        for &i in &m.edges["theta1"] {
            let p = m.nodes[i];
            assert!((p.y.atan2(p.z) - 0.5).abs() < 1e-12);
        }
        let xs: Vec<f64> = m.edges["theta0"].iter().map(|&i| m.nodes[i].x).collect();
        assert!(xs.windows(2).all(|w| w[0] < w[1]));
        // theta = 0 is on +z
        let m = cylindrical_panel(1.0, 1.0, 0.0, 0.5, 1, 1).unwrap();
        assert!((m.nodes[0] - Vector3::new(0.0, 0.0, 1.0)).norm() < 1e-15);
    }

    #[test]
    fn closed_cylinder_merges_seam() {
        let (na, nc) = (5, 12);
        let m = cylindrical_panel(2.0, 4.0, 0.0, TAU, na, nc).unwrap();
        counts(&m, (na + 1) * nc, na * nc);
        assert!(!m.edges.contains_key("theta0") && !m.edges.contains_key("theta1"));
        assert_eq!(m.edges["x0"].len(), nc);
        assert_eq!(m.edges["x1"].len(), nc);
        // every node used by exactly 4 quads except the end rows (2)
        let mut uses = vec![0; m.nodes.len()];
        for q in &m.quads {
            for &i in q {
                uses[i] += 1;
            }
        }
        for (i, u) in uses.iter().enumerate() {
            let end = m.edges["x0"].contains(&i) || m.edges["x1"].contains(&i);
            assert_eq!(*u, if end { 2 } else { 4 }, "node {i}");
        }
        for p in &m.nodes {
            assert!(((p.y * p.y + p.z * p.z).sqrt() - 2.0).abs() < 1e-12);
        }
        // symmetric range and a tiny rounding error are also full turns
        let m = cylindrical_panel(1.0, 1.0, -PI, PI, 2, 8).unwrap();
        assert_eq!(m.nodes.len(), 3 * 8);
        let m = cylindrical_panel(1.0, 1.0, 0.1, 0.1 + TAU, 2, 8).unwrap();
        assert_eq!(m.nodes.len(), 3 * 8);
        assert!(
            cylindrical_panel(1.0, 1.0, 0.0, TAU, 2, 2)
                .unwrap_err()
                .to_string()
                .contains("n_circ")
        );
    }

    #[test]
    fn cylinder_rejects_bad_parameters() {
        for (r, l, t0, t1, name) in [
            (0.0, 1.0, 0.0, 1.0, "radius"),
            (1.0, -1.0, 0.0, 1.0, "length"),
            (1.0, 1.0, 1.0, 1.0, "theta1"),
            (1.0, 1.0, 0.0, 7.0, "full turn"),
            (1.0, 1.0, f64::INFINITY, 7.0, "theta0"),
        ] {
            let e = cylindrical_panel(r, l, t0, t1, 2, 2).unwrap_err();
            assert!(e.to_string().contains(name), "{e}");
        }
        assert!(
            cylindrical_panel(1.0, 1.0, 0.0, 1.0, 0, 2)
                .unwrap_err()
                .to_string()
                .contains("n_axial")
        );
        assert!(
            cylindrical_panel(1.0, 1.0, 0.0, 1.0, 2, 0)
                .unwrap_err()
                .to_string()
                .contains("n_circ")
        );
        // an open panel whose elements span over half a turn is unusable
        let e = cylindrical_panel(1.0, 1.0, 0.0, 4.0, 2, 1).unwrap_err();
        assert!(e.to_string().contains("increase n_circ"), "{e}");
    }

    #[test]
    fn hemisphere_open_and_closed() {
        let r = 10.0;
        let hole = 18f64.to_radians();
        let m = hemisphere(r, hole, 0.0, FRAC_PI_2, 8, 8).unwrap();
        counts(&m, 81, 64);
        for (p, d) in m.nodes.iter().zip(&m.directors) {
            assert!((p.norm() - r).abs() < 1e-12);
            assert!((d - p / r).norm() < 1e-12);
            assert!(p.z >= -1e-12);
        }
        for &i in &m.edges["equator"] {
            assert_eq!(m.nodes[i].z, 0.0);
        }
        for &i in &m.edges["hole"] {
            assert!((m.nodes[i].z - r * hole.cos()).abs() < 1e-12);
        }
        for &i in &m.edges["phi0"] {
            assert!(m.nodes[i].y.abs() < 1e-12);
        }
        for &i in &m.edges["phi1"] {
            assert!(m.nodes[i].x.abs() < 1e-12);
        }
        let zs: Vec<f64> = m.edges["phi0"].iter().map(|&i| m.nodes[i].z).collect();
        assert!(
            zs.windows(2).all(|w| w[0] > w[1]),
            "phi0 ordered from hole to equator"
        );

        let m = hemisphere(r, hole, 0.0, TAU, 6, 16).unwrap();
        counts(&m, 7 * 16, 6 * 16);
        assert!(!m.edges.contains_key("phi0"));
        assert_eq!(m.edges["hole"].len(), 16);

        assert!(
            hemisphere(r, 0.0, 0.0, 1.0, 2, 2)
                .unwrap_err()
                .to_string()
                .contains("hole_angle")
        );
        assert!(
            hemisphere(r, 2.0, 0.0, 1.0, 2, 2)
                .unwrap_err()
                .to_string()
                .contains("hole_angle")
        );
        assert!(
            hemisphere(r, 0.3, 1.0, 0.5, 2, 2)
                .unwrap_err()
                .to_string()
                .contains("phi1")
        );
        assert!(
            hemisphere(r, 0.3, 0.0, 1.0, 0, 2)
                .unwrap_err()
                .to_string()
                .contains("n_merid")
        );
        assert!(
            hemisphere(-r, 0.3, 0.0, 1.0, 2, 2)
                .unwrap_err()
                .to_string()
                .contains("radius")
        );
    }

    #[test]
    fn twisted_strip_geometry() {
        let (l, w, tw) = (12.0, 1.1, FRAC_PI_2);
        let m = twisted_strip(l, w, tw, 12, 2).unwrap();
        counts(&m, 13 * 3, 24);
        // end cross-sections
        for &i in &m.edges["x0"] {
            let p = m.nodes[i];
            assert!(p.x == 0.0 && p.z.abs() < 1e-15);
            // the helicoid normal tilts with the twist rate away from the axis
            let n = Vector3::new(-p.y * tw / l, 0.0, 1.0).normalize();
            assert!((m.directors[i] - n).norm() < 1e-15);
        }
        for &i in &m.edges["x1"] {
            let p = m.nodes[i];
            assert!(p.x == l && p.y.abs() < 1e-12);
        }
        let s: Vec<f64> = m.edges["x1"].iter().map(|&i| m.nodes[i].z).collect();
        assert!((s[0] + 0.55).abs() < 1e-12 && (s[2] - 0.55).abs() < 1e-12);
        // directors are normal to r_x and r_s computed by finite differences
        let rate = tw / l;
        let pos = |x: f64, s: f64| Vector3::new(x, s * (rate * x).cos(), s * (rate * x).sin());
        for (p, d) in m.nodes.iter().zip(&m.directors) {
            let (x, phi) = (p.x, rate * p.x);
            let s = p.y * phi.cos() + p.z * phi.sin();
            let h = 1e-6;
            let rx = (pos(x + h, s) - pos(x - h, s)) / (2.0 * h);
            let rs = (pos(x, s + h) - pos(x, s - h)) / (2.0 * h);
            assert!(d.dot(&rx).abs() < 1e-8 && d.dot(&rs).abs() < 1e-8);
            assert!((d.norm() - 1.0).abs() < 1e-12);
        }
        // several turns, negative twist and zero twist all work
        let m = twisted_strip(10.0, 1.0, 4.0 * PI, 64, 4).unwrap();
        counts(&m, 65 * 5, 64 * 4);
        let m = twisted_strip(10.0, 1.0, -4.0 * PI, 64, 4).unwrap();
        m.validate().unwrap();
        let m = twisted_strip(10.0, 1.0, 0.0, 4, 1).unwrap();
        assert!(m.directors.iter().all(|d| *d == Vector3::z()));
        assert!(
            twisted_strip(10.0, 0.0, 1.0, 4, 1)
                .unwrap_err()
                .to_string()
                .contains("width")
        );
        assert!(
            twisted_strip(10.0, 1.0, f64::NAN, 4, 1)
                .unwrap_err()
                .to_string()
                .contains("twist")
        );
        // half a turn per element makes bow-tie quads
        let e = twisted_strip(10.0, 1.0, 4.0 * PI, 4, 1).unwrap_err();
        assert!(e.to_string().contains("increase nx"), "{e}");
    }

    #[test]
    fn directors_normal_to_surface_on_curved_generators() {
        // For every quad, the director at each corner is nearly orthogonal
        // to the quad's two edges at that corner (chord error only).
        let meshes = [
            cylindrical_panel(1.0, 1.0, 0.0, TAU, 4, 64).unwrap(),
            hemisphere(1.0, 0.2, 0.0, TAU, 32, 64).unwrap(),
        ];
        for m in &meshes {
            for q in &m.quads {
                for k in 0..4 {
                    let d = m.directors[q[k]];
                    let e = (m.nodes[q[(k + 1) % 4]] - m.nodes[q[k]]).normalize();
                    assert!(d.dot(&e).abs() < 0.06, "{}", d.dot(&e));
                }
            }
        }
    }
}
