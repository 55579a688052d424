//! Quad meshes of flat pattern pieces (simple polygons) at a target element size.
//!
//! Method:
//! - a convex four-sided outline gets a mapped (transfinite, bilinear) structured grid whose
//!   lines follow the outline's sides — grain-aligned when the piece is cut on the grain;
//! - any other simple polygon gets a grain-aligned core: the square cells of a grid of size
//!   2h laid along the grain that lie at least 0.6·2h inside the outline, each split into
//!   2×2 quads of size h (exact grain-aligned squares);
//! - the band between the outline and the core (or the whole polygon when no cell fits) is
//!   triangulated by a constrained Delaunay triangulation with Ruppert-style refinement (the
//!   `spade` crate: angle limit 25°, area bound from the target size, boundary and core
//!   sub-segments kept, the core excluded as a hole), and every triangle is split into three
//!   quads through its edge midpoints and centroid — an all-quad mesh whose angles stay within
//!   the triangles' bounds (the classical triangle → quad split, e.g. Owen's survey 1998).
//!   The core's boundary edges are constraint edges of length 2h, so the midpoint a band
//!   triangle puts on one is the midpoint of the core cell's split: the mesh is conforming;
//! - band nodes are Laplacian-smoothed; the outline and the core stay fixed.
//!
//! Each outline segment keeps its ordered node row, so seam spans are node rows.

use spade::{ConstrainedDelaunayTriangulation, Point2, RefinementParameters, AngleLimit, Triangulation};
use std::collections::HashMap;

use super::sizing::SizeField;

/// A flat quad mesh of one pattern piece.
#[derive(Clone, Debug)]
pub struct PatternMesh {
    /// Node positions in pattern coordinates.
    pub uv: Vec<[f64; 2]>,
    /// Quads, counter-clockwise.
    pub quads: Vec<[usize; 4]>,
    /// Node row of each outline segment i (vertex i → i+1), both ends included.
    pub segment_rows: Vec<Vec<usize>>,
    /// "mapped", "grain-core" (grain-aligned core with a split band) or "cdt-split".
    pub method: &'static str,
    /// Number of quads in the grain-aligned core.
    pub core_quads: usize,
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt()
}

fn lerp(a: [f64; 2], b: [f64; 2], t: f64) -> [f64; 2] {
    [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
}

/// Whether a 4-vertex outline is strictly convex (counter-clockwise).
fn convex_quad(o: &[[f64; 2]]) -> bool {
    o.len() == 4
        && (0..4).all(|k| {
            let (a, b, c) = (o[k], o[(k + 1) % 4], o[(k + 2) % 4]);
            (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0]) > 0.0
        })
}

/// Meshes a counter-clockwise simple polygon at element size `h` (see the module doc), with
/// the core grid along `grain` (pattern coordinates). `segments[i]`, where given, asks for
/// that many element edges along outline segment i (rounded up to even for the triangle
/// split; ignored by the mapped grid), so that a seam partner's node row can be matched.
///
/// Errors before any work when a coordinate is not finite or beyond
/// [`super::graph::MAX_COORDINATE`], or when the mesh would have more than
/// [`MAX_PATTERN_NODES`] nodes ([`estimate_nodes`]) or a requested segment count is absurd.
pub fn mesh_polygon(outline: &[[f64; 2]], h: f64, segments: &[Option<usize>], grain: [f64; 2]) -> Result<PatternMesh, String> {
    mesh_polygon_graded(outline, &SizeField::uniform(h), segments, grain)
}

/// [`mesh_polygon`] following a size field (`garment::sizing`): the mapped grid spaces its
/// node lines by the field along the sides (each direction graded by the refinements of the
/// sides it crosses, [`graded_parameters`]); the triangle split samples each outline segment
/// by the field, keeps grain-core cells only where the field is its base size, and lets the
/// constrained Delaunay refinement grade the band between (Ruppert's refinement grades from
/// short boundary segments inwards). A uniform field gives exactly the mesh of that size.
pub fn mesh_polygon_graded(outline: &[[f64; 2]], field: &SizeField, segments: &[Option<usize>], grain: [f64; 2]) -> Result<PatternMesh, String> {
    let h = field.min();
    if !(h.is_finite() && h > 0.0) {
        return Err("the element size must be positive".into());
    }
    let g = grain[0].hypot(grain[1]);
    if !(g.is_finite() && g > 0.0) {
        return Err("the grain direction must be non-zero".into());
    }
    if outline.len() < 3 {
        return Err("the outline needs at least 3 vertices".into());
    }
    let max = super::graph::MAX_COORDINATE;
    if let Some(v) = outline.iter().position(|v| !(v[0].abs() <= max && v[1].abs() <= max)) {
        return Err(format!("outline vertex {v} ({:e}, {:e}) is not finite or lies beyond ±{max:e} m", outline[v][0], outline[v][1]));
    }
    let est = estimate_nodes(outline, h);
    if !(est <= MAX_PATTERN_NODES as f64) {
        return Err(format!("the element size {h} is too small for this panel: about {est:.2e} nodes (limit {MAX_PATTERN_NODES})"));
    }
    let cells = core_grid_cells(outline, h);
    if !(cells * outline.len() as f64 <= MAX_CORE_WORK) {
        return Err(format!(
            "the element size {h} is too small for this panel: fitting its grain-aligned core would test {cells:.2e} cells against {} outline segments",
            outline.len()
        ));
    }
    let requested: usize = segments.iter().flatten().fold(0usize, |a, &b| a.saturating_add(b));
    if requested > MAX_PATTERN_NODES {
        return Err(format!("{requested} element edges requested along the outline (limit {MAX_PATTERN_NODES})"));
    }
    if !(field.base.is_finite() && field.base >= h) {
        return Err("the size field's base size must be finite and at least its smallest size".into());
    }
    if convex_quad(outline) {
        Ok(mapped(outline, field))
    } else {
        let base = field.base;
        let keep = |c: &[[f64; 2]; 4]| {
            let centre = [0.25 * (c[0][0] + c[1][0] + c[2][0] + c[3][0]), 0.25 * (c[0][1] + c[1][1] + c[2][1] + c[3][1])];
            c.iter().chain(std::iter::once(&centre)).all(|&p| field.at(p) >= base * (1.0 - 1e-9))
        };
        let core = GrainCore::fit(outline, 2.0 * base, [grain[0] / g, grain[1] / g], &keep);
        cdt_split(outline, field, segments, &core)
    }
}

/// Most nodes one pattern piece's mesh may have.
pub const MAX_PATTERN_NODES: usize = 2_000_000;

/// Most cell–segment tests of the grain core's fit (a few seconds).
const MAX_CORE_WORK: f64 = 2.0e9;

/// An estimate (from above, for straight-sided outlines) of the node count of
/// [`mesh_polygon`] at element size `h`: 1.5 nodes per h² of area (the grain core has 1, the
/// split band about 1.7) and 3 per h of perimeter; within 1.4× of the count for a 1 m² pentagon
/// at h = 4 mm (82 511 nodes, estimate 116 000). Infinite or NaN for absurd input, which the
/// callers reject.
pub fn estimate_nodes(outline: &[[f64; 2]], h: f64) -> f64 {
    let n = outline.len();
    let perimeter: f64 = (0..n).map(|i| dist(outline[i], outline[(i + 1) % n])).sum();
    let area = super::graph::signed_area(outline).abs();
    1.5 * (area / h) / h + 3.0 * perimeter / h + 4.0
}

/// Cells of the grain core's trial grid (square cells of 2h over the outline's extent in
/// any direction): the work of [`GrainCore::fit`] is this times the outline's length.
fn core_grid_cells(outline: &[[f64; 2]], h: f64) -> f64 {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in outline {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let d = (hi[0] - lo[0]).hypot(hi[1] - lo[1]) / (2.0 * h);
    d * d
}

/// Square cells of a grid of spacing `size` along the grain that fit inside an outline with a
/// margin (see the module doc).
struct GrainCore {
    origin: [f64; 2],
    /// Unit grain direction and its left normal: grid axes.
    axes: [[f64; 2]; 2],
    size: f64,
    /// Kept cells (i, j): the square origin + size·(i·e₁ + j·e₂) + [0, size]².
    cells: std::collections::BTreeSet<(i64, i64)>,
}

impl GrainCore {
    /// Margin between the outline and the core, as a fraction of the cell size.
    const MARGIN: f64 = 0.6;

    fn fit(o: &[[f64; 2]], size: f64, e1: [f64; 2], keep: &dyn Fn(&[[f64; 2]; 4]) -> bool) -> Self {
        let e2 = [-e1[1], e1[0]];
        let proj = |p: [f64; 2], e: [f64; 2]| p[0] * e[0] + p[1] * e[1];
        let (mut s0, mut s1, mut t0, mut t1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
        for &p in o {
            s0 = s0.min(proj(p, e1));
            s1 = s1.max(proj(p, e1));
            t0 = t0.min(proj(p, e2));
            t1 = t1.max(proj(p, e2));
        }
        // Centre the grid on the outline's extent along the grain axes.
        let (ns, nt) = (((s1 - s0) / size).floor(), ((t1 - t0) / size).floor());
        let (a, b) = (s0 + 0.5 * (s1 - s0 - ns * size), t0 + 0.5 * (t1 - t0 - nt * size));
        let mut core = GrainCore { origin: [a * e1[0] + b * e2[0], a * e1[1] + b * e2[1]], axes: [e1, e2], size, cells: Default::default() };
        let n = o.len();
        for i in 0..ns as i64 {
            for j in 0..nt as i64 {
                let c = core.corners(i, j);
                let inside = c.iter().all(|&p| point_in_polygon(p, o));
                let clear = (0..n).all(|k| segment_square_distance(o[k], o[(k + 1) % n], &c) >= Self::MARGIN * size);
                if inside && clear && keep(&c) {
                    core.cells.insert((i, j));
                }
            }
        }
        // Remove pinches (two cells meeting only at a corner), which would make the core's
        // boundary non-manifold.
        loop {
            let pinch = core.cells.iter().find_map(|&(i, j)| {
                let has = |a: i64, b: i64| core.cells.contains(&(a, b));
                [(1, 1), (1, -1)].into_iter().find(|&(di, dj)| has(i + di, j + dj) && !has(i + di, j) && !has(i, j + dj)).map(|_| (i, j))
            });
            match pinch {
                Some(c) => {
                    core.cells.remove(&c);
                }
                None => break,
            }
        }
        core
    }

    /// Grid point (i, j).
    fn point(&self, i: i64, j: i64) -> [f64; 2] {
        let (s, t) = (i as f64 * self.size, j as f64 * self.size);
        [self.origin[0] + s * self.axes[0][0] + t * self.axes[1][0], self.origin[1] + s * self.axes[0][1] + t * self.axes[1][1]]
    }

    /// Corners of cell (i, j), counter-clockwise.
    fn corners(&self, i: i64, j: i64) -> [[f64; 2]; 4] {
        [self.point(i, j), self.point(i + 1, j), self.point(i + 1, j + 1), self.point(i, j + 1)]
    }

    /// Boundary edges of the core (grid point pairs, the core on their left).
    fn boundary_edges(&self) -> Vec<[(i64, i64); 2]> {
        let mut out = Vec::new();
        for &(i, j) in &self.cells {
            let has = |a: i64, b: i64| self.cells.contains(&(a, b));
            if !has(i, j - 1) {
                out.push([(i, j), (i + 1, j)]);
            }
            if !has(i + 1, j) {
                out.push([(i + 1, j), (i + 1, j + 1)]);
            }
            if !has(i, j + 1) {
                out.push([(i + 1, j + 1), (i, j + 1)]);
            }
            if !has(i - 1, j) {
                out.push([(i, j + 1), (i, j)]);
            }
        }
        out
    }
}

/// Whether `p` lies inside the simple polygon `o` (even–odd ray crossing).
pub(crate) fn point_in_polygon(p: [f64; 2], o: &[[f64; 2]]) -> bool {
    let n = o.len();
    let mut inside = false;
    for k in 0..n {
        let (a, b) = (o[k], o[(k + 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1]) && p[0] < a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]) {
            inside = !inside;
        }
    }
    inside
}

/// Distance from point `p` to segment ab.
pub(crate) fn point_segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 { (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0) } else { 0.0 };
    dist(p, [a[0] + t * dx, a[1] + t * dy])
}

/// Distance between segment ab and the convex quadrilateral `c` (0 when they meet).
fn segment_square_distance(a: [f64; 2], b: [f64; 2], c: &[[f64; 2]; 4]) -> f64 {
    let cross = |o: [f64; 2], p: [f64; 2], q: [f64; 2]| (p[0] - o[0]) * (q[1] - o[1]) - (p[1] - o[1]) * (q[0] - o[0]);
    let inside = |p: [f64; 2]| (0..4).all(|k| cross(c[k], c[(k + 1) % 4], p) >= 0.0);
    if inside(a) || inside(b) {
        return 0.0;
    }
    let mut d = f64::INFINITY;
    for k in 0..4 {
        let (p, q) = (c[k], c[(k + 1) % 4]);
        let crosses = cross(a, b, p) * cross(a, b, q) < 0.0 && cross(p, q, a) * cross(p, q, b) < 0.0;
        if crosses {
            return 0.0;
        }
        d = d.min(point_segment_distance(p, a, b)).min(point_segment_distance(a, p, q)).min(point_segment_distance(b, p, q));
    }
    d
}

/// Element edges along each side of the mapped grid of a convex quadrilateral outline, or
/// None when the outline gets the triangle split.
pub fn mapped_counts(outline: &[[f64; 2]], h: f64) -> Option<[usize; 4]> {
    mapped_counts_graded(outline, &SizeField::uniform(h))
}

/// [`mapped_counts`] for a size field.
pub fn mapped_counts_graded(outline: &[[f64; 2]], field: &SizeField) -> Option<[usize; 4]> {
    if !convex_quad(outline) {
        return None;
    }
    let (su, sv) = mapped_parameters(outline, field);
    let (n_u, n_v) = (su.len() - 1, sv.len() - 1);
    Some([n_u, n_v, n_u, n_v])
}

/// Node parameters in [0, 1] of a graded division of a pair of opposite sides: `sides` are
/// (start, end, outline segment) of the two sides, run in the same direction; the node
/// density at s is the larger of the two sides' length / size there, the size taken from the
/// field without the side's own refinement (a seam grades the spacing across it, not along
/// it) and, for a field sampled across the panel (`SizeField::across`), also the length /
/// size on 15 points of the line between the sides. A uniform field gives ceil(L/h) equal
/// steps, L the longer side.
pub fn graded_parameters(sides: [([f64; 2], [f64; 2], usize); 2], field: &SizeField) -> Vec<f64> {
    let longest = sides.iter().map(|&(a, b, _)| dist(a, b)).fold(0.0, f64::max);
    if field.refinements.is_empty() {
        let n = (longest / field.base).ceil().max(1.0) as usize;
        return (0..=n).map(|i| i as f64 / n as f64).collect();
    }
    const SAMPLES: usize = 512;
    let on_sides = |s: f64| sides.iter().map(|&(a, b, k)| dist(a, b) / field.at_excluding(lerp(a, b, s), Some(k))).fold(0.0, f64::max);
    // Across the panel (`SizeField::across`): the line between the two sides' points at s,
    // its length interpolated between theirs.
    const ACROSS: usize = 16;
    let density = |s: f64| {
        let mut d = on_sides(s);
        if field.across {
            let (p, q) = (lerp(sides[0].0, sides[0].1, s), lerp(sides[1].0, sides[1].1, s));
            let (l0, l1) = (dist(sides[0].0, sides[0].1), dist(sides[1].0, sides[1].1));
            for j in 1..ACROSS {
                let t = j as f64 / ACROSS as f64;
                d = d.max((l0 + t * (l1 - l0)) / field.at(lerp(p, q, t)));
            }
        }
        d
    };
    let mut cum = vec![0.0; SAMPLES + 1];
    for i in 0..SAMPLES {
        let (s0, s1) = (i as f64 / SAMPLES as f64, (i + 1) as f64 / SAMPLES as f64);
        cum[i + 1] = cum[i] + 0.5 * (density(s0) + density(s1)) / SAMPLES as f64;
    }
    let total = cum[SAMPLES];
    let n = (total * (1.0 - 1e-9)).ceil().max(1.0) as usize;
    inverse_cumulative(&cum, n)
}

/// Parameters where the piecewise-linear cumulative `cum` (on equal steps over [0, 1])
/// reaches k/n of its total, k = 0..=n.
fn inverse_cumulative(cum: &[f64], n: usize) -> Vec<f64> {
    let m = cum.len() - 1;
    let total = cum[m];
    let mut out = Vec::with_capacity(n + 1);
    let mut j = 0;
    for k in 0..=n {
        let target = total * k as f64 / n as f64;
        while j < m - 1 && cum[j + 1] < target {
            j += 1;
        }
        let span = cum[j + 1] - cum[j];
        let f = if span > 0.0 { ((target - cum[j]) / span).clamp(0.0, 1.0) } else { 0.0 };
        out.push(((j as f64 + f) / m as f64).clamp(0.0, 1.0));
    }
    out[0] = 0.0;
    out[n] = 1.0;
    out
}

/// The mapped grid's node parameters along u (sides 0 and 2) and v (sides 1 and 3).
fn mapped_parameters(o: &[[f64; 2]], field: &SizeField) -> (Vec<f64>, Vec<f64>) {
    let su = graded_parameters([(o[0], o[1], 0), (o[3], o[2], 2)], field);
    let sv = graded_parameters([(o[1], o[2], 1), (o[0], o[3], 3)], field);
    (su, sv)
}

/// Transfinite bilinear grid on a convex quadrilateral; opposite sides get the larger count,
/// node lines spaced by [`graded_parameters`].
fn mapped(o: &[[f64; 2]], field: &SizeField) -> PatternMesh {
    let (su, sv) = mapped_parameters(o, field);
    let (n_u, n_v) = (su.len() - 1, sv.len() - 1);
    let id = |i: usize, j: usize| j * (n_u + 1) + i;
    let mut uv = Vec::with_capacity((n_u + 1) * (n_v + 1));
    for &t in &sv {
        for &s in &su {
            let bottom = lerp(o[0], o[1], s);
            let top = lerp(o[3], o[2], s);
            uv.push(lerp(bottom, top, t));
        }
    }
    let mut quads = Vec::with_capacity(n_u * n_v);
    for j in 0..n_v {
        for i in 0..n_u {
            quads.push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let segment_rows = vec![
        (0..=n_u).map(|i| id(i, 0)).collect(),
        (0..=n_v).map(|j| id(n_u, j)).collect(),
        (0..=n_u).rev().map(|i| id(i, n_v)).collect(),
        (0..=n_v).rev().map(|j| id(0, j)).collect(),
    ];
    PatternMesh { uv, quads, segment_rows, method: "mapped", core_quads: 0 }
}

/// Constrained Delaunay triangulation of the band between the outline and `core` with
/// refinement, then the triangle → 3 quads split; the core cells split 2×2.
fn cdt_split(o: &[[f64; 2]], field: &SizeField, segments: &[Option<usize>], core: &GrainCore) -> Result<PatternMesh, String> {
    let n = o.len();
    let h = field.base;
    // Boundary points: each segment in m pieces of about 2h (the split halves them).
    let mut boundary: Vec<[f64; 2]> = Vec::new();
    let mut seg_points: Vec<Vec<usize>> = Vec::with_capacity(n);
    for i in 0..n {
        let (a, b) = (o[i], o[(i + 1) % n]);
        let params: Vec<f64> = match segments.get(i).copied().flatten() {
            Some(n) => {
                let m = n.div_ceil(2).max(1);
                (0..=m).map(|k| k as f64 / m as f64).collect()
            }
            None if field.refinements.is_empty() => {
                let m = (dist(a, b) / (2.0 * h)).ceil().max(1.0) as usize;
                (0..=m).map(|k| k as f64 / m as f64).collect()
            }
            // Pieces of about twice the local size (the split halves them).
            None => {
                let doubled = SizeField { base: 2.0 * field.base, refinements: field.refinements.iter().map(|r| super::sizing::Refinement { h_near: 2.0 * r.h_near, ..r.clone() }).collect(), scales: None, across: field.across };
                graded_parameters([(a, b, usize::MAX), (a, b, usize::MAX)], &doubled)
            }
        };
        let m = params.len() - 1;
        let mut row = Vec::with_capacity(m + 1);
        for &t in &params[..m] {
            row.push(boundary.len());
            boundary.push(lerp(a, b, t));
        }
        seg_points.push(row);
    }
    for i in 0..n {
        let next_first = seg_points[(i + 1) % n][0];
        seg_points[i].push(next_first);
    }
    let mut cdt: ConstrainedDelaunayTriangulation<Point2<f64>> = ConstrainedDelaunayTriangulation::new();
    let mut handles = Vec::with_capacity(boundary.len());
    for p in &boundary {
        handles.push(cdt.insert(Point2::new(p[0], p[1])).map_err(|e| format!("triangulation failed: {e:?}"))?);
    }
    for k in 0..handles.len() {
        let (a, b) = (handles[k], handles[(k + 1) % handles.len()]);
        if cdt.can_add_constraint(a, b) {
            cdt.add_constraint(a, b);
        } else {
            return Err("the outline's boundary segments cross (self-intersecting outline)".into());
        }
    }
    // The core's boundary loops: constraint edges around a hole.
    let mut grid_handle = HashMap::new();
    for [p, q] in core.boundary_edges() {
        let mut handle = |g: (i64, i64), cdt: &mut ConstrainedDelaunayTriangulation<Point2<f64>>| -> Result<_, String> {
            if let Some(&h) = grid_handle.get(&g) {
                return Ok(h);
            }
            let x = core.point(g.0, g.1);
            let h = cdt.insert(Point2::new(x[0], x[1])).map_err(|e| format!("triangulation failed: {e:?}"))?;
            grid_handle.insert(g, h);
            Ok(h)
        };
        let (a, b) = (handle(p, &mut cdt)?, handle(q, &mut cdt)?);
        if !cdt.can_add_constraint(a, b) {
            return Err("the grain-aligned core crosses the outline".into());
        }
        cdt.add_constraint(a, b);
    }
    let target_area = (2.0 * h).powi(2) * 3f64.sqrt() / 4.0;
    let limit = 20 * ((polygon_area(o) / target_area).ceil() as usize + boundary.len()) + 1000;
    let result = cdt.refine(
        RefinementParameters::<f64>::new()
            .with_angle_limit(AngleLimit::from_deg(25.0))
            .with_max_allowed_area(target_area)
            .keep_constraint_edges()
            .exclude_outer_faces(true)
            .with_max_additional_vertices(limit),
    );
    let excluded: std::collections::HashSet<usize> = result.excluded_faces.iter().map(|f| f.index()).collect();
    // Nodes: triangulation vertices first, then edge midpoints, then centroids.
    let mut uv: Vec<[f64; 2]> = cdt.vertices().map(|v| [v.position().x, v.position().y]).collect();
    let mut mid: HashMap<(usize, usize), usize> = HashMap::new();
    let mut midpoint = |a: usize, b: usize, uv: &mut Vec<[f64; 2]>| -> usize {
        let key = (a.min(b), a.max(b));
        *mid.entry(key).or_insert_with(|| {
            uv.push(lerp(uv[a], uv[b], 0.5));
            uv.len() - 1
        })
    };
    let mut quads = Vec::new();
    for f in cdt.inner_faces() {
        if excluded.contains(&f.fix().index()) {
            continue;
        }
        let v = f.vertices().map(|v| v.fix().index());
        let c = [(uv[v[0]][0] + uv[v[1]][0] + uv[v[2]][0]) / 3.0, (uv[v[0]][1] + uv[v[1]][1] + uv[v[2]][1]) / 3.0];
        let m: Vec<usize> = (0..3).map(|k| midpoint(v[k], v[(k + 1) % 3], &mut uv)).collect();
        uv.push(c);
        let ci = uv.len() - 1;
        for k in 0..3 {
            quads.push([v[k], m[k], ci, m[(k + 2) % 3]]);
        }
    }
    // Core cells, each split 2×2 through its edge midpoints and centre; a grid point on the
    // core's boundary is the triangulation's vertex, so the edge midpoints are shared.
    let mut core_nodes: Vec<usize> = Vec::new();
    let mut grid_index: HashMap<(i64, i64), usize> = grid_handle.iter().map(|(&g, h)| (g, h.index())).collect();
    let mut grid_node = |g: (i64, i64), uv: &mut Vec<[f64; 2]>, core_nodes: &mut Vec<usize>| -> usize {
        let id = *grid_index.entry(g).or_insert_with(|| {
            uv.push(core.point(g.0, g.1));
            uv.len() - 1
        });
        core_nodes.push(id);
        id
    };
    let n_band = quads.len();
    for &(i, j) in &core.cells {
        let c = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)].map(|g| grid_node(g, &mut uv, &mut core_nodes));
        let m: Vec<usize> = (0..4).map(|k| midpoint(c[k], c[(k + 1) % 4], &mut uv)).collect();
        let x = core.corners(i, j);
        uv.push([0.25 * (x[0][0] + x[1][0] + x[2][0] + x[3][0]), 0.25 * (x[0][1] + x[1][1] + x[2][1] + x[3][1])]);
        let ci = uv.len() - 1;
        core_nodes.extend(m.iter().copied().chain([ci]));
        for k in 0..4 {
            quads.push([c[k], m[k], ci, m[(k + 3) % 4]]);
        }
    }
    let core_quads = quads.len() - n_band;
    // Boundary vertex handles keep their insertion order: spade numbers vertices in order.
    let segment_rows = seg_points
        .iter()
        .map(|row| {
            let mut out = Vec::with_capacity(2 * row.len());
            for w in row.windows(2) {
                let (a, b) = (handles[w[0]].index(), handles[w[1]].index());
                out.push(a);
                out.push(midpoint(a, b, &mut uv));
            }
            if let Some(&last) = row.last() {
                out.push(handles[last].index());
            }
            out
        })
        .collect();
    let method = if core_quads > 0 { "grain-core" } else { "cdt-split" };
    let mut mesh = PatternMesh { uv, quads, segment_rows, method, core_quads };
    smooth(&mut mesh, 10, &core_nodes);
    Ok(mesh)
}

/// Whether every corner of every quad turns counter-clockwise (convex, valid quads).
fn all_convex(uv: &[[f64; 2]], quads: &[[usize; 4]]) -> bool {
    quads.iter().all(|q| {
        (0..4).all(|k| {
            let (a, b, c) = (uv[q[k]], uv[q[(k + 1) % 4]], uv[q[(k + 2) % 4]]);
            (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0]) > 0.0
        })
    })
}

/// Laplacian smoothing of the interior nodes not in `fixed` (each moved to the mean of its
/// quad-edge neighbours; Field 1988), `passes` times; a pass that would make any quad
/// non-convex is undone and smoothing stops.
fn smooth(mesh: &mut PatternMesh, passes: usize, fixed: &[usize]) {
    let n = mesh.uv.len();
    let mut boundary = vec![false; n];
    for &v in fixed {
        boundary[v] = true;
    }
    for row in &mesh.segment_rows {
        for &v in row {
            boundary[v] = true;
        }
    }
    let mut nbrs: Vec<Vec<usize>> = vec![Vec::new(); n];
    for q in &mesh.quads {
        for k in 0..4 {
            let (a, b) = (q[k], q[(k + 1) % 4]);
            nbrs[a].push(b);
            nbrs[b].push(a);
        }
    }
    for l in nbrs.iter_mut() {
        l.sort_unstable();
        l.dedup();
    }
    for _ in 0..passes {
        let next: Vec<[f64; 2]> = (0..n)
            .map(|v| {
                if boundary[v] || nbrs[v].is_empty() {
                    return mesh.uv[v];
                }
                let k = nbrs[v].len() as f64;
                let s = nbrs[v].iter().fold([0.0, 0.0], |s, &w| [s[0] + mesh.uv[w][0], s[1] + mesh.uv[w][1]]);
                [s[0] / k, s[1] / k]
            })
            .collect();
        if !all_convex(&next, &mesh.quads) {
            break;
        }
        mesh.uv = next;
    }
}

fn polygon_area(o: &[[f64; 2]]) -> f64 {
    super::graph::signed_area(o).abs()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::garment::graph::signed_area;

    fn quality(m: &PatternMesh) -> crate::mesh::MeshQuality {
        let sm = crate::mesh::ShellMesh {
            nodes: m.uv.iter().map(|p| nalgebra::Vector3::new(p[0], p[1], 0.0)).collect(),
            directors: vec![nalgebra::Vector3::z(); m.uv.len()],
            quads: m.quads.clone(),
            edges: Default::default(),
        };
        sm.quality()
    }

    /// Checks that `m` tiles the outline of area `area` conformingly: positive quads summing
    /// to the area, every edge shared by two quads except the outline's, which are exactly
    /// the segment rows' edges.
    fn assert_conforming(m: &PatternMesh, area: f64) {
        let sum: f64 = m.quads.iter().map(|q| signed_area(&q.map(|i| m.uv[i]))).sum();
        assert!((sum - area).abs() < 1e-9 * area, "{sum} vs {area}");
        assert!(m.quads.iter().all(|q| signed_area(&q.map(|i| m.uv[i])) > 0.0));
        let mut count: HashMap<(usize, usize), usize> = HashMap::new();
        for q in &m.quads {
            for k in 0..4 {
                let (a, b) = (q[k], q[(k + 1) % 4]);
                *count.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        let outline: std::collections::HashSet<(usize, usize)> =
            m.segment_rows.iter().flat_map(|r| r.windows(2).map(|w| (w[0].min(w[1]), w[0].max(w[1])))).collect();
        for (e, c) in &count {
            assert_eq!(*c, if outline.contains(e) { 1 } else { 2 }, "edge {e:?}: a hanging node or a hole");
        }
        assert!(outline.iter().all(|e| count.contains_key(e)));
    }

    /// The L-shaped piece gets a grain-aligned core for grain along x and at 30°: the core
    /// quads are squares of side h with sides along the grain (to rounding), the mesh is
    /// conforming and its angles stay in the triangle split's bounds.
    #[test]
    fn grain_core_of_an_l_shape_is_aligned_and_conforming() {
        let o = [[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0], [1.0, 2.0], [0.0, 2.0]];
        for deg in [0.0_f64, 30.0] {
            let g = [deg.to_radians().cos(), deg.to_radians().sin()];
            let m = mesh_polygon(&o, 0.05, &[], g).unwrap();
            assert_eq!(m.method, "grain-core");
            assert_conforming(&m, 3.0);
            let core = &m.quads[m.quads.len() - m.core_quads..];
            for q in core {
                for k in 0..4 {
                    let (a, b) = (m.uv[q[k]], m.uv[q[(k + 1) % 4]]);
                    let e = [b[0] - a[0], b[1] - a[1]];
                    assert!((dist(a, b) - 0.05).abs() < 1e-12, "core edge length {}", dist(a, b));
                    let along = (e[0] * g[0] + e[1] * g[1]).abs() / 0.05;
                    assert!(along < 1e-12 || (along - 1.0).abs() < 1e-12, "core edge off the grain: {along}");
                }
            }
            let fraction = core.len() as f64 * 0.0025 / 3.0;
            let q = quality(&m);
            println!("grain {deg}°: {} quads, {} in the core ({:.0} % of the area), {q:?}", m.quads.len(), core.len(), 100.0 * fraction);
            // Measured: 0° 896 core quads of 1424 (75 % of the area), angles 38.6°..143.1°,
            // aspect 3.02; 30° 820 of 1642 (68 %), 30.4°..145.7°, aspect 3.55.
            assert!(fraction > 0.6, "core covers {fraction}");
            assert!(q.min_angle_deg > 25.0 && q.max_angle_deg < 150.0 && q.max_aspect_ratio < 4.0, "{q:?}");
            let row = &m.segment_rows[0];
            assert_eq!(m.uv[row[0]], [0.0, 0.0]);
            assert_eq!(m.uv[*row.last().unwrap()], [2.0, 0.0]);
        }
    }

    /// A piece too narrow for a core cell with its margin is split whole.
    #[test]
    fn split_mesh_of_a_narrow_l_shape_covers_its_area() {
        let o = [[0.0, 0.0], [2.0, 0.0], [2.0, 0.2], [0.2, 0.2], [0.2, 2.0], [0.0, 2.0]];
        let m = mesh_polygon(&o, 0.1, &[], [1.0, 0.0]).unwrap();
        assert_eq!(m.method, "cdt-split");
        assert_conforming(&m, 0.76);
        let q = quality(&m);
        println!("{} quads, {q:?}", m.quads.len());
        assert!(q.min_angle_deg > 25.0 && q.max_angle_deg < 145.0 && q.max_aspect_ratio < 4.0, "{q:?}");
    }
}
