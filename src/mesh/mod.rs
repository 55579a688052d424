//! Quad shell meshes in the reference configuration.
//!
//! A [`ShellMesh`] holds the mid-surface nodes, one unit reference director
//! (shell normal) per node, 4-node quadrilaterals and named boundary node
//! rows. Meshes come from the structured generators in [`generate`]
//! (re-exported here: [`rectangle`], [`cylindrical_panel`], [`hemisphere`],
//! [`slit_annulus`], [`twisted_strip`]) or from Wavefront OBJ text
//! ([`from_obj`]). Node sets for boundary conditions and loads are picked
//! with the selectors in [`select`].

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt;

pub mod annulus;
pub mod generate;
pub mod obj;
pub mod select;
pub mod spacing;

pub use annulus::{annulus, annulus_rings, focused_rings, sized_rings, slit_annulus};
pub use generate::{cylindrical_panel, cylindrical_panel_spaced, hemisphere, hemisphere_spaced, graded_rectangle, rectangle, twisted_strip};
pub use spacing::Spacing;
pub use obj::{from_obj, read_obj};
pub use select::{select_box, select_edge, select_nearest, select_plane};

/// Largest deviation of a director's length from 1 that [`ShellMesh::validate`] accepts.
pub const DIRECTOR_UNIT_TOL: f64 = 1e-6;

/// A quad shell mesh of one part, in the reference configuration.
#[derive(Clone, Debug)]
pub struct ShellMesh {
    /// Mid-surface node positions.
    pub nodes: Vec<Vector3<f64>>,
    /// Unit reference director (shell normal) per node.
    pub directors: Vec<Vector3<f64>>,
    /// Node indices of each quad, counter-clockwise seen from the director
    /// side, so `(x1-x0)x(x3-x0)` points along the director.
    pub quads: Vec<[usize; 4]>,
    /// Named boundary node rows, ordered along the edge.
    pub edges: BTreeMap<String, Vec<usize>>,
}

/// Errors from building, reading or checking a mesh.
#[derive(Debug, Clone, PartialEq)]
pub enum MeshError {
    /// Bad generator parameters or an inconsistent mesh.
    Invalid(String),
    /// A file could not be read or written.
    Io(String),
    /// A syntax or content error in mesh text, with its 1-based line number.
    Parse {
        /// 1-based line number in the input text.
        line: usize,
        /// What is wrong on that line.
        message: String,
    },
}

impl fmt::Display for MeshError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MeshError::Invalid(m) => write!(f, "invalid mesh: {m}"),
            MeshError::Io(m) => write!(f, "mesh I/O error: {m}"),
            MeshError::Parse { line, message } => {
                write!(f, "mesh parse error on line {line}: {message}")
            }
        }
    }
}

impl std::error::Error for MeshError {}

/// Element shape measures of a mesh, the worst value over all quads.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MeshQuality {
    /// Smallest interior corner angle (degrees) of any quad.
    pub min_angle_deg: f64,
    /// Largest interior corner angle (degrees) of any quad; above 180 means a
    /// non-convex quad.
    pub max_angle_deg: f64,
    /// Largest ratio of longest to shortest edge within one quad
    /// (infinite if a quad has a zero-length edge).
    pub max_aspect_ratio: f64,
    /// Smallest ratio, within one quad, of the smallest to the largest corner
    /// Jacobian (1 for a parallelogram, <= 0 for a non-convex or degenerate quad).
    pub min_jacobian_ratio: f64,
}

/// Corner `k` of a quad: the vectors to the next and previous corner and
/// their cross product (the corner Jacobian vector).
fn corner(x: &[Vector3<f64>; 4], k: usize) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
    let e = x[(k + 1) % 4] - x[k];
    let f = x[(k + 3) % 4] - x[k];
    (e, f, e.cross(&f))
}

/// Element normal of a quad from the cross product of its diagonals
/// (not normalised; its length is twice the projected area).
pub(crate) fn quad_normal(x: &[Vector3<f64>; 4]) -> Vector3<f64> {
    (x[2] - x[0]).cross(&(x[3] - x[1]))
}

impl ShellMesh {
    /// Corner positions of quad `q` (indices must be in range).
    fn quad_points(&self, q: &[usize; 4]) -> [Vector3<f64>; 4] {
        [
            self.nodes[q[0]],
            self.nodes[q[1]],
            self.nodes[q[2]],
            self.nodes[q[3]],
        ]
    }

    /// Axis-aligned bounding box `(min, max)` of the nodes; both are zero for
    /// a mesh without nodes.
    pub fn bounding_box(&self) -> (Vector3<f64>, Vector3<f64>) {
        let Some(first) = self.nodes.first() else {
            return (Vector3::zeros(), Vector3::zeros());
        };
        let mut lo = *first;
        let mut hi = *first;
        for p in &self.nodes {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        (lo, hi)
    }

    /// Length of the bounding-box diagonal (0 for an empty mesh).
    pub fn diagonal(&self) -> f64 {
        let (lo, hi) = self.bounding_box();
        (hi - lo).norm()
    }

    /// Worst corner angles, edge-length aspect ratio and corner-Jacobian
    /// ratio over all quads. Corner angles and Jacobians are measured about
    /// each quad's diagonal-cross-product normal. Quads with out-of-range node
    /// indices are skipped; with no (valid) quads every field is NaN.
    pub fn quality(&self) -> MeshQuality {
        let mut qual = MeshQuality {
            min_angle_deg: f64::NAN,
            max_angle_deg: f64::NAN,
            max_aspect_ratio: f64::NAN,
            min_jacobian_ratio: f64::NAN,
        };
        let n = self.nodes.len();
        for q in self.quads.iter().filter(|q| q.iter().all(|&i| i < n)) {
            let x = self.quad_points(q);
            let ne = quad_normal(&x);
            let nn = ne.norm();
            let nhat = if nn > 0.0 { ne / nn } else { Vector3::zeros() };
            let mut lmin = f64::INFINITY;
            let mut lmax = 0.0_f64;
            let mut jmin = f64::INFINITY;
            let mut jmax = f64::NEG_INFINITY;
            for k in 0..4 {
                let (e, f, c) = corner(&x, k);
                let mut ang = c.dot(&nhat).atan2(e.dot(&f)).to_degrees();
                if ang < 0.0 {
                    ang += 360.0;
                }
                qual.min_angle_deg = qual.min_angle_deg.min(ang);
                qual.max_angle_deg = qual.max_angle_deg.max(ang);
                let l = e.norm();
                lmin = lmin.min(l);
                lmax = lmax.max(l);
                let j = c.dot(&nhat);
                jmin = jmin.min(j);
                jmax = jmax.max(j);
            }
            let aspect = if lmin > 0.0 {
                lmax / lmin
            } else {
                f64::INFINITY
            };
            qual.max_aspect_ratio = qual.max_aspect_ratio.max(aspect);
            let jr = if jmax > 0.0 { jmin / jmax } else { 0.0 };
            qual.min_jacobian_ratio = qual.min_jacobian_ratio.min(jr);
        }
        qual
    }

    /// Checks the mesh for use by the shell elements: one director per node,
    /// finite coordinates, unit directors, quad and edge indices in range,
    /// four distinct nodes per quad, no degenerate or non-convex quads
    /// (every corner Jacobian positive), and every quad oriented so that its
    /// normal agrees with the directors of its nodes (dot product > 0).
    /// Returns the first problem found.
    pub fn validate(&self) -> Result<(), MeshError> {
        let n = self.nodes.len();
        if self.directors.len() != n {
            return Err(MeshError::Invalid(format!(
                "{} nodes but {} directors",
                n,
                self.directors.len()
            )));
        }
        for (i, (p, d)) in self.nodes.iter().zip(&self.directors).enumerate() {
            if !p.iter().all(|v| v.is_finite()) {
                return Err(MeshError::Invalid(format!(
                    "node {i} has a non-finite coordinate"
                )));
            }
            let len = d.norm();
            if !len.is_finite() || (len - 1.0).abs() > DIRECTOR_UNIT_TOL {
                return Err(MeshError::Invalid(format!(
                    "director of node {i} is not a unit vector (length {len})"
                )));
            }
        }
        for (qi, q) in self.quads.iter().enumerate() {
            if let Some(&bad) = q.iter().find(|&&i| i >= n) {
                return Err(MeshError::Invalid(format!(
                    "quad {qi} refers to node {bad} but the mesh has {n} nodes"
                )));
            }
            for a in 0..4 {
                for b in (a + 1)..4 {
                    if q[a] == q[b] {
                        return Err(MeshError::Invalid(format!(
                            "quad {qi} uses node {} twice",
                            q[a]
                        )));
                    }
                }
            }
            let x = self.quad_points(q);
            let lmax = (0..4)
                .map(|k| (x[(k + 1) % 4] - x[k]).norm())
                .fold(0.0, f64::max);
            let ne = quad_normal(&x);
            let nn = ne.norm();
            if lmax == 0.0 || nn <= 1e-12 * lmax * lmax {
                return Err(MeshError::Invalid(format!(
                    "quad {qi} {q:?} is degenerate (zero area)"
                )));
            }
            let nhat = ne / nn;
            for k in 0..4 {
                let (_, _, c) = corner(&x, k);
                if c.dot(&nhat) <= 1e-10 * lmax * lmax {
                    return Err(MeshError::Invalid(format!(
                        "quad {qi} {q:?} is degenerate or non-convex at node {}",
                        q[k]
                    )));
                }
                if self.directors[q[k]].dot(&nhat) <= 0.0 {
                    return Err(MeshError::Invalid(format!(
                        "quad {qi} {q:?} is oriented against the director of node {} \
                         (nodes must run counter-clockwise seen from the director side)",
                        q[k]
                    )));
                }
            }
        }
        for (name, row) in &self.edges {
            if let Some(&bad) = row.iter().find(|&&i| i >= n) {
                return Err(MeshError::Invalid(format!(
                    "edge \"{name}\" refers to node {bad} but the mesh has {n} nodes"
                )));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_square() -> ShellMesh {
        ShellMesh {
            nodes: vec![
                Vector3::new(0.0, 0.0, 0.0),
                Vector3::new(1.0, 0.0, 0.0),
                Vector3::new(1.0, 1.0, 0.0),
                Vector3::new(0.0, 1.0, 0.0),
            ],
            directors: vec![Vector3::z(); 4],
            quads: vec![[0, 1, 2, 3]],
            edges: BTreeMap::new(),
        }
    }

    #[test]
    fn square_is_valid_and_perfect() {
        let m = unit_square();
        m.validate().unwrap();
        let q = m.quality();
        assert!((q.min_angle_deg - 90.0).abs() < 1e-12);
        assert!((q.max_angle_deg - 90.0).abs() < 1e-12);
        assert!((q.max_aspect_ratio - 1.0).abs() < 1e-12);
        assert!((q.min_jacobian_ratio - 1.0).abs() < 1e-12);
        let (lo, hi) = m.bounding_box();
        assert_eq!(lo, Vector3::zeros());
        assert_eq!(hi, Vector3::new(1.0, 1.0, 0.0));
    }

    #[test]
    fn validate_catches_problems() {
        let mut m = unit_square();
        m.quads = vec![[0, 3, 2, 1]];
        let e = m.validate().unwrap_err();
        assert!(e.to_string().contains("oriented"), "{e}");

        let mut m = unit_square();
        m.quads = vec![[0, 1, 2, 7]];
        assert!(m.validate().unwrap_err().to_string().contains("node 7"));

        let mut m = unit_square();
        m.directors[2] = Vector3::new(0.0, 0.0, 2.0);
        assert!(m.validate().unwrap_err().to_string().contains("unit"));

        let mut m = unit_square();
        m.nodes[2] = Vector3::new(0.5, 0.0, 0.0); // collinear corner
        assert!(m.validate().unwrap_err().to_string().contains("degenerate"));

        let mut m = unit_square();
        m.nodes[2] = Vector3::new(0.2, 0.2, 0.0); // non-convex (dart)
        assert!(m.validate().is_err());
        let q = m.quality();
        assert!(q.max_angle_deg > 180.0, "{q:?}");
        assert!(q.min_jacobian_ratio < 0.0, "{q:?}");

        let mut m = unit_square();
        m.edges.insert("e".into(), vec![0, 9]);
        assert!(m.validate().unwrap_err().to_string().contains("\"e\""));

        let mut m = unit_square();
        m.directors.pop();
        assert!(m.validate().is_err());
    }

    #[test]
    fn quality_of_stretched_parallelogram() {
        let mut m = unit_square();
        m.nodes[1].x = 4.0;
        m.nodes[2] = Vector3::new(5.0, 1.0, 0.0);
        m.nodes[3] = Vector3::new(1.0, 1.0, 0.0);
        let q = m.quality();
        assert!((q.min_angle_deg - 45.0).abs() < 1e-9);
        assert!((q.max_angle_deg - 135.0).abs() < 1e-9);
        assert!((q.max_aspect_ratio - 4.0 / 2f64.sqrt()).abs() < 1e-9);
        assert!((q.min_jacobian_ratio - 1.0).abs() < 1e-9);
    }

    #[test]
    fn empty_mesh() {
        let m = ShellMesh {
            nodes: vec![],
            directors: vec![],
            quads: vec![],
            edges: BTreeMap::new(),
        };
        assert!(m.validate().is_ok());
        assert!(m.quality().min_angle_deg.is_nan());
        assert_eq!(m.bounding_box().0, Vector3::zeros());
    }

    #[test]
    fn error_display() {
        let e = MeshError::Parse {
            line: 3,
            message: "bad".into(),
        };
        assert_eq!(e.to_string(), "mesh parse error on line 3: bad");
        let b: Box<dyn std::error::Error> = Box::new(MeshError::Io("x".into()));
        assert!(b.to_string().contains("x"));
    }
}
