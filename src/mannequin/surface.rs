//! Closed triangle surfaces of rigid segments and the checks made on them: closedness and
//! orientation (every edge used once in each direction), enclosed volume (divergence
//! theorem), plane sections (the perimeter of a cut, i.e. a girth) and triangle–triangle
//! intersection between triangles that share no vertex.

use nalgebra::{Point3, Vector3};

/// A triangle surface: vertices and 0-based triangles, counter-clockwise seen from outside.
#[derive(Clone, Debug, Default)]
pub struct TriSurface {
    /// Vertex positions.
    pub vertices: Vec<Point3<f64>>,
    /// Triangles (vertex indices), outward by the right-hand rule.
    pub triangles: Vec<[u32; 3]>,
}

impl TriSurface {
    /// `Ok` when every directed edge occurs in exactly one triangle and its reverse in exactly
    /// one other, i.e. the surface is closed, two-manifold along edges and consistently
    /// oriented; otherwise the first offending edge.
    pub fn check_closed(&self) -> Result<(), String> {
        let mut directed: std::collections::HashMap<(u32, u32), usize> = std::collections::HashMap::new();
        for t in &self.triangles {
            for k in 0..3 {
                *directed.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        for (&(a, b), &n) in &directed {
            if n != 1 {
                return Err(format!("edge {a}→{b} is used by {n} triangles in the same direction"));
            }
            if directed.get(&(b, a)) != Some(&1) {
                return Err(format!("edge {a}→{b} has no reverse edge: the surface is open there"));
            }
        }
        Ok(())
    }

    /// Enclosed volume by the divergence theorem, V = Σ v₀·(v₁×v₂)/6 over the triangles;
    /// positive when the triangles face outward.
    pub fn volume(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.vertices[i as usize].coords);
                a.dot(&b.cross(&c)) / 6.0
            })
            .sum()
    }

    /// Length of the section of the surface by the plane through `point` with normal
    /// `normal`: the sum over triangles of the segment each cuts from the plane. A vertex on
    /// the plane counts as on the positive side, consistently for every triangle, so the
    /// segments form closed polygons on a closed surface; for a single convex section the
    /// result is its perimeter (a girth). A ring of vertices in the plane is measured when
    /// the surface continues on the negative side; a face lying in the plane with nothing
    /// below it is not cut.
    pub fn section_length(&self, point: &Point3<f64>, normal: &Vector3<f64>) -> f64 {
        let n = normal.normalize();
        let d: Vec<f64> = self.vertices.iter().map(|v| (v - point).dot(&n)).collect();
        let mut total = 0.0;
        for t in &self.triangles {
            let mut cut = Vec::with_capacity(2);
            for k in 0..3 {
                let (i, j) = (t[k] as usize, t[(k + 1) % 3] as usize);
                if (d[i] >= 0.0) != (d[j] >= 0.0) {
                    let s = d[i] / (d[i] - d[j]);
                    cut.push(self.vertices[i] + (self.vertices[j] - self.vertices[i]) * s);
                }
            }
            if cut.len() == 2 {
                total += (cut[1] - cut[0]).norm();
            }
        }
        total
    }

    /// Generalized winding number of the surface about `p`: the sum of the triangles' signed
    /// solid angles over 4π (Van Oosterom & Strackee 1983, tan(Ω/2) = a·(b×c) / (abc +
    /// (a·b)c + (a·c)b + (b·c)a) with a, b, c the vertices relative to p); 1 inside a closed
    /// outward surface, 0 outside.
    pub fn winding_number(&self, p: &Point3<f64>) -> f64 {
        let total: f64 = self
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.vertices[i as usize] - p);
                let (la, lb, lc) = (a.norm(), b.norm(), c.norm());
                let den = la * lb * lc + a.dot(&b) * lc + a.dot(&c) * lb + b.dot(&c) * la;
                2.0 * a.dot(&b.cross(&c)).atan2(den)
            })
            .sum();
        total / (4.0 * std::f64::consts::PI)
    }

    /// Pairs of triangles that share no vertex and intersect (touching counts). Pairs whose
    /// bounding boxes are apart are skipped; coplanar pairs are not tested (see
    /// [`triangles_intersect`]).
    pub fn self_intersections(&self) -> Vec<(usize, usize)> {
        let tris: Vec<[Point3<f64>; 3]> = self.triangles.iter().map(|t| t.map(|i| self.vertices[i as usize])).collect();
        let boxes: Vec<(Vector3<f64>, Vector3<f64>)> = tris
            .iter()
            .map(|t| (t[0].coords.inf(&t[1].coords).inf(&t[2].coords), t[0].coords.sup(&t[1].coords).sup(&t[2].coords)))
            .collect();
        let mut order: Vec<usize> = (0..tris.len()).collect();
        order.sort_by(|&a, &b| boxes[a].0.x.total_cmp(&boxes[b].0.x));
        let mut hits = Vec::new();
        for (k, &a) in order.iter().enumerate() {
            for &b in &order[k + 1..] {
                if boxes[b].0.x > boxes[a].1.x {
                    break;
                }
                let apart = (0..3).any(|c| boxes[b].0[c] > boxes[a].1[c] || boxes[a].0[c] > boxes[b].1[c]);
                let shared = self.triangles[a].iter().any(|v| self.triangles[b].contains(v));
                if !apart && !shared && triangles_intersect(&tris[a], &tris[b]) {
                    hits.push((a.min(b), a.max(b)));
                }
            }
        }
        hits
    }
}

/// Six times the signed volume of the tetrahedron (a, b, c, d): positive when d lies on the
/// side of the plane abc its right-hand normal points to.
fn orient(a: &Point3<f64>, b: &Point3<f64>, c: &Point3<f64>, d: &Point3<f64>) -> f64 {
    (b - a).cross(&(c - a)).dot(&(d - a))
}

/// Whether the segment pq meets the triangle abc (touching counts). A segment lying in the
/// triangle's plane is reported as not meeting it.
fn segment_meets_triangle(p: &Point3<f64>, q: &Point3<f64>, t: &[Point3<f64>; 3]) -> bool {
    let (op, oq) = (orient(&t[0], &t[1], &t[2], p), orient(&t[0], &t[1], &t[2], q));
    if op == 0.0 && oq == 0.0 || op * oq > 0.0 {
        return false;
    }
    // The line pq passes through the triangle when it sees its three edges turning the same way.
    let s = [orient(p, q, &t[0], &t[1]), orient(p, q, &t[1], &t[2]), orient(p, q, &t[2], &t[0])];
    s.iter().all(|&x| x >= 0.0) || s.iter().all(|&x| x <= 0.0)
}

/// Whether two triangles intersect: for triangles not in one plane, they do exactly when an
/// edge of one meets the other (Möller 1997, "A fast triangle-triangle intersection test",
/// reduced to segment–triangle tests by orientation predicates). Coplanar pairs give false.
pub fn triangles_intersect(a: &[Point3<f64>; 3], b: &[Point3<f64>; 3]) -> bool {
    (0..3).any(|k| segment_meets_triangle(&a[k], &a[(k + 1) % 3], b)) || (0..3).any(|k| segment_meets_triangle(&b[k], &b[(k + 1) % 3], a))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64, z: f64) -> Point3<f64> {
        Point3::new(x, y, z)
    }

    /// A unit cube [0,1]³ with outward triangles.
    fn cube() -> TriSurface {
        let vertices = (0..8).map(|i| p((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64)).collect();
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let triangles = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
        TriSurface { vertices, triangles }
    }

    #[test]
    fn cube_is_closed_outward_with_unit_volume_and_square_sections() {
        let c = cube();
        c.check_closed().expect("closed");
        assert!((c.volume() - 1.0).abs() < 1e-14);
        // A horizontal cut is the unit square (perimeter 4), also through the top vertices
        // (the surface continues on the negative side); the bottom face, lying in the plane
        // with the surface on its positive side, is not cut.
        assert!((c.section_length(&p(0.5, 0.5, 0.3), &Vector3::z()) - 4.0).abs() < 1e-12);
        assert!((c.section_length(&p(0.5, 0.5, 1.0), &Vector3::z()) - 4.0).abs() < 1e-12);
        assert_eq!(c.section_length(&p(0.5, 0.5, 0.0), &Vector3::z()), 0.0);
        // A diagonal cut through the middle: a hexagon of side √2/2, perimeter 3√2.
        let hex = c.section_length(&p(0.5, 0.5, 0.5), &Vector3::new(1.0, 1.0, 1.0));
        assert!((hex - 3.0 * 2f64.sqrt()).abs() < 1e-12, "{hex}");
        assert!(c.self_intersections().is_empty());
        assert!((c.winding_number(&p(0.3, 0.6, 0.2)) - 1.0).abs() < 1e-12);
        assert!(c.winding_number(&p(1.3, 0.6, 0.2)).abs() < 1e-12);
        let mut flipped = c.clone();
        flipped.triangles[0].swap(1, 2);
        assert!(flipped.check_closed().is_err());
        let mut open = c;
        open.triangles.pop();
        assert!(open.check_closed().is_err());
    }

    #[test]
    fn triangle_pairs() {
        let t = [p(0.0, 0.0, 0.0), p(1.0, 0.0, 0.0), p(0.0, 1.0, 0.0)];
        // Pierced through the middle by a vertical triangle.
        assert!(triangles_intersect(&t, &[p(0.2, 0.2, -1.0), p(0.2, 0.2, 1.0), p(0.3, 0.25, 1.0)]));
        // Crossing in a cross shape (no vertex of either inside the other).
        assert!(triangles_intersect(&t, &[p(0.1, -0.5, 0.5), p(0.1, 2.0, 0.5), p(0.1, 0.5, -0.5)]));
        // Above it, and beside it.
        assert!(!triangles_intersect(&t, &[p(0.2, 0.2, 0.1), p(0.8, 0.1, 0.3), p(0.1, 0.7, 0.2)]));
        assert!(!triangles_intersect(&t, &[p(0.8, 0.8, -1.0), p(0.8, 0.8, 1.0), p(2.0, 2.0, 0.0)]));
    }
}
