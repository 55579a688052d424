//! Node-set selectors for boundary conditions, loads and output.
//!
//! Every selector returns node indices sorted ascending without duplicates.
//! An empty result is not an error here: the caller decides how to report it.

use super::{MeshError, ShellMesh};
use nalgebra::Vector3;

/// Nodes inside the axis-aligned box `[min, max]`, boundaries included with a
/// tolerance of 1e-9 times the mesh bounding-box diagonal. A box with
/// `min > max` in some component selects nothing.
pub fn select_box(mesh: &ShellMesh, min: Vector3<f64>, max: Vector3<f64>) -> Vec<usize> {
    let tol = 1e-9 * mesh.diagonal();
    mesh.nodes
        .iter()
        .enumerate()
        .filter(|(_, p)| (0..3).all(|k| p[k] >= min[k] - tol && p[k] <= max[k] + tol))
        .map(|(i, _)| i)
        .collect()
}

/// Nodes within distance `tol` of the plane through `point` with normal
/// `normal` (any non-zero length): `|(x - point) · n̂| <= tol`. A zero or
/// non-finite normal, or a negative/NaN `tol`, selects nothing.
pub fn select_plane(
    mesh: &ShellMesh,
    point: Vector3<f64>,
    normal: Vector3<f64>,
    tol: f64,
) -> Vec<usize> {
    let len = normal.norm();
    if !(len.is_finite() && len > 0.0) {
        return Vec::new();
    }
    let n = normal / len;
    mesh.nodes
        .iter()
        .enumerate()
        .filter(|(_, p)| (*p - point).dot(&n).abs() <= tol)
        .map(|(i, _)| i)
        .collect()
}

/// The single node nearest to `point` (the lowest index on a tie); empty
/// only for a mesh without nodes.
pub fn select_nearest(mesh: &ShellMesh, point: Vector3<f64>) -> Vec<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (i, p) in mesh.nodes.iter().enumerate() {
        let d2 = (p - point).norm_squared();
        if best.is_none_or(|(_, b)| d2 < b) {
            best = Some((i, d2));
        }
    }
    best.map(|(i, _)| vec![i]).unwrap_or_default()
}

/// The nodes of the named boundary edge, sorted ascending (the ordered row
/// along the edge is `mesh.edges[name]`). An unknown name is an error that
/// lists the available edge names.
pub fn select_edge(mesh: &ShellMesh, name: &str) -> Result<Vec<usize>, MeshError> {
    match mesh.edges.get(name) {
        Some(row) => {
            let mut v = row.clone();
            v.sort_unstable();
            v.dedup();
            Ok(v)
        }
        None => {
            let names: Vec<String> = mesh.edges.keys().map(|k| format!("\"{k}\"")).collect();
            let avail = if names.is_empty() {
                "none".to_string()
            } else {
                names.join(", ")
            };
            Err(MeshError::Invalid(format!(
                "no edge named \"{name}\"; available edges: {avail}"
            )))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::{cylindrical_panel, rectangle};
    use super::*;
    use std::collections::BTreeMap;

    #[test]
    fn box_selection_is_inclusive_with_tolerance() {
        let m = rectangle(1.0, 1.0, 10, 10).unwrap();
        // the line x = 0.3 is computed as 3.0/10.0 etc.; tolerance catches it
        let s = select_box(
            &m,
            Vector3::new(0.3, -1.0, -1.0),
            Vector3::new(0.3, 2.0, 1.0),
        );
        assert_eq!(s.len(), 11);
        assert!(s.iter().all(|&i| (m.nodes[i].x - 0.3).abs() < 1e-12));
        assert!(s.windows(2).all(|w| w[0] < w[1]));
        let all = select_box(&m, Vector3::new(0.0, 0.0, 0.0), Vector3::new(1.0, 1.0, 0.0));
        assert_eq!(all.len(), 121);
        let none = select_box(&m, Vector3::new(2.0, 0.0, 0.0), Vector3::new(1.0, 1.0, 0.0));
        assert!(none.is_empty());
        let corner = select_box(
            &m,
            Vector3::new(0.95, 0.95, -1.0),
            Vector3::new(1.0, 1.0, 1.0),
        );
        assert_eq!(corner, vec![120]);
    }

    #[test]
    fn plane_selection() {
        let m = cylindrical_panel(1.0, 2.0, 0.0, std::f64::consts::TAU, 4, 8).unwrap();
        let s = select_plane(
            &m,
            Vector3::new(1.0, 5.0, 5.0),
            Vector3::new(-3.0, 0.0, 0.0),
            1e-9,
        );
        assert_eq!(s.len(), 8);
        assert!(s.iter().all(|&i| (m.nodes[i].x - 1.0).abs() < 1e-12));
        assert!(s.windows(2).all(|w| w[0] < w[1]));
        // y = 0 plane cuts the tube at theta = 0 and pi
        let s = select_plane(&m, Vector3::zeros(), Vector3::y(), 1e-9);
        assert_eq!(s.len(), 10);
        let wide = select_plane(&m, Vector3::zeros(), Vector3::x(), 0.6);
        assert_eq!(wide.len(), 16);
        assert!(select_plane(&m, Vector3::zeros(), Vector3::zeros(), 1.0).is_empty());
        assert!(select_plane(&m, Vector3::zeros(), Vector3::x(), -1.0).is_empty());
    }

    #[test]
    fn nearest_selection() {
        let m = rectangle(2.0, 1.0, 2, 1).unwrap();
        assert_eq!(select_nearest(&m, Vector3::new(1.9, 0.8, 3.0)), vec![5]);
        assert_eq!(select_nearest(&m, Vector3::new(-10.0, -10.0, 0.0)), vec![0]);
        // tie between nodes 0 and 1: lowest index
        assert_eq!(select_nearest(&m, Vector3::new(0.5, 0.0, 0.0)), vec![0]);
        let empty = ShellMesh {
            nodes: vec![],
            directors: vec![],
            quads: vec![],
            edges: BTreeMap::new(),
        };
        assert!(select_nearest(&empty, Vector3::zeros()).is_empty());
        assert!(select_box(&empty, Vector3::zeros(), Vector3::zeros()).is_empty());
    }

    #[test]
    fn edge_selection() {
        let m = rectangle(2.0, 1.0, 2, 2).unwrap();
        assert_eq!(select_edge(&m, "xmax").unwrap(), vec![2, 5, 8]);
        assert_eq!(select_edge(&m, "ymax").unwrap(), vec![6, 7, 8]);
        let e = select_edge(&m, "left").unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains("\"left\""), "{msg}");
        for name in ["xmin", "xmax", "ymin", "ymax"] {
            assert!(msg.contains(name), "{msg}");
        }
        // theta edges do not exist on a closed tube
        let t = cylindrical_panel(1.0, 1.0, 0.0, std::f64::consts::TAU, 2, 6).unwrap();
        let msg = select_edge(&t, "theta0").unwrap_err().to_string();
        assert!(msg.contains("\"x0\", \"x1\""), "{msg}");
        // closed tube end row is returned sorted
        let x1 = select_edge(&t, "x1").unwrap();
        assert!(x1.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(x1.len(), 6);
    }
}
