//! The garment as a graph (petgraph): panels are nodes, seams are edges. Validation before
//! meshing, and the queries users need (which panels a seam joins, seam loops, connected
//! components).

use std::collections::BTreeSet;

use petgraph::graph::{EdgeIndex, NodeIndex, UnGraph};
use petgraph::unionfind::UnionFind;
use petgraph::visit::EdgeRef;

use super::spec::{GarmentSpec, PanelSpec, SpanRef};
use crate::input::{Locator, SceneError};

/// Panels (node weight: index into `GarmentSpec::panels`) joined by seams (edge weight:
/// index into `GarmentSpec::seams`).
#[derive(Clone, Debug)]
pub struct GarmentGraph {
    /// The graph.
    pub graph: UnGraph<usize, usize>,
    /// Node of each panel.
    pub panel_node: Vec<NodeIndex>,
    /// Edge of each seam.
    pub seam_edge: Vec<EdgeIndex>,
}

/// Outline vertex `i` of a panel as a 2D point.
fn vertex(p: &PanelSpec, i: usize) -> [f64; 2] {
    p.outline[i % p.outline.len()]
}

/// Outline segments (vertex i → i+1) covered by an edge span, counter-clockwise.
pub fn span_segments(p: &PanelSpec, from: usize, to: usize) -> Vec<usize> {
    let n = p.outline.len();
    let mut out = Vec::new();
    let mut i = from;
    while i != to && out.len() < n {
        out.push(i);
        i = (i + 1) % n;
    }
    out
}

/// Sampled outline points and, per outline segment, its range of sampled segments.
pub type SampledOutline = (Vec<[f64; 2]>, Vec<std::ops::Range<usize>>);

/// The outline with its curved edges sampled at spacing about `h`: the points, and for each
/// outline segment the range of sampled segments that make it up. A curve is a circular arc
/// (minor arc: |sagitta| below half the chord) through the segment's end vertices.
pub fn sampled_outline(p: &PanelSpec, h: f64) -> Result<SampledOutline, String> {
    let n = p.outline.len();
    let mut sagitta = vec![0.0; n];
    for c in &p.curves {
        let span = p.edges.get(&c.edge).ok_or_else(|| format!("curve on unknown edge \"{}\"", c.edge))?;
        let segs = span_segments(p, span.from, span.to);
        if segs.len() != 1 {
            return Err(format!("curved edge \"{}\" must span exactly one outline segment", c.edge));
        }
        let (a, b) = (vertex(p, segs[0]), vertex(p, segs[0] + 1));
        let half = 0.5 * ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
        if !(c.sagitta.is_finite() && c.sagitta.abs() < half) {
            return Err(format!("curved edge \"{}\": |sagitta| must be below half the chord ({half:.4})", c.edge));
        }
        sagitta[segs[0]] = c.sagitta;
    }
    let mut points = Vec::new();
    let mut ranges = Vec::with_capacity(n);
    for (i, &s) in sagitta.iter().enumerate() {
        let (a, b) = (vertex(p, i), vertex(p, i + 1));
        let start = points.len();
        points.push(a);
        if s != 0.0 {
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let c = (dx * dx + dy * dy).sqrt();
            let out = [dy / c, -dx / c];
            let half = 0.5 * c;
            let r = (half * half + s * s) / (2.0 * s.abs());
            let mid = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
            let off = s - s.signum() * r;
            let centre = [mid[0] + out[0] * off, mid[1] + out[1] * off];
            let ta = (a[1] - centre[1]).atan2(a[0] - centre[0]);
            let tb = (b[1] - centre[1]).atan2(b[0] - centre[0]);
            let mut sweep = tb - ta;
            while sweep > std::f64::consts::PI {
                sweep -= std::f64::consts::TAU;
            }
            while sweep <= -std::f64::consts::PI {
                sweep += std::f64::consts::TAU;
            }
            let kf = ((r * sweep.abs()) / h).ceil().max(2.0);
            if !(kf <= MAX_OUTLINE_POINTS as f64) || points.len() + kf as usize > MAX_OUTLINE_POINTS {
                return Err(format!(
                    "sampling the curved edges at the element size {h} would take more than {MAX_OUTLINE_POINTS} outline points; use a larger element_size"
                ));
            }
            let k = kf as usize;
            for j in 1..k {
                let t = ta + sweep * j as f64 / k as f64;
                points.push([centre[0] + r * t.cos(), centre[1] + r * t.sin()]);
            }
        }
        ranges.push(start..points.len());
    }
    Ok((points, ranges))
}

/// Pattern length of an edge span on the sampled outline (`ranges` from [`sampled_outline`]).
pub fn span_length(p: &PanelSpec, from: usize, to: usize, points: &[[f64; 2]], ranges: &[std::ops::Range<usize>]) -> f64 {
    let m = points.len();
    span_segments(p, from, to)
        .iter()
        .flat_map(|&i| ranges[i].clone())
        .map(|k| {
            let (a, b) = (points[k], points[(k + 1) % m]);
            ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt()
        })
        .sum()
}

/// Signed area of a closed polyline (positive counter-clockwise).
pub fn signed_area(outline: &[[f64; 2]]) -> f64 {
    let n = outline.len();
    (0..n).map(|i| {
        let (a, b) = (outline[i], outline[(i + 1) % n]);
        a[0] * b[1] - b[0] * a[1]
    }).sum::<f64>()
        * 0.5
}

/// Whether segments p1p2 and q1q2 intersect (including touching), by orientation tests.
fn segments_intersect(p1: [f64; 2], p2: [f64; 2], q1: [f64; 2], q2: [f64; 2]) -> bool {
    let orient = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    let on = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        c[0] >= a[0].min(b[0]) && c[0] <= a[0].max(b[0]) && c[1] >= a[1].min(b[1]) && c[1] <= a[1].max(b[1])
    };
    let (d1, d2, d3, d4) = (orient(q1, q2, p1), orient(q1, q2, p2), orient(p1, p2, q1), orient(p1, p2, q2));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0)) && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0)) {
        return true;
    }
    (d1 == 0.0 && on(q1, q2, p1)) || (d2 == 0.0 && on(q1, q2, p2)) || (d3 == 0.0 && on(p1, p2, q1)) || (d4 == 0.0 && on(p1, p2, q2))
}

/// Most points an outline may have after its curved edges are sampled.
pub const MAX_OUTLINE_POINTS: usize = 1_000_000;

/// Largest |coordinate| of a pattern outline (m): pieces of cloth, not maps.
pub const MAX_COORDINATE: f64 = 1.0e4;

/// Most segment-pair tests [`self_intersection`] makes before it gives up.
const MAX_PAIR_TESTS: u64 = 200_000_000;

/// Whether segments i and j of an n-gon share a vertex.
fn adjacent(i: usize, j: usize, n: usize) -> bool {
    let (i, j) = (i.min(j), i.max(j));
    j == i + 1 || (i == 0 && j == n - 1)
}

/// First pair (i, j), i < j, of non-adjacent outline segments that intersect, if any, in
/// lexicographic order. Segments are bucketed in a uniform grid of about n cells over the
/// outline's bounding box and only segments sharing a cell are tested, so the cost is
/// near-linear when segments are short against the piece (sampled curves); an outline so
/// tangled that more than 2·10⁸ pairs would be tested is an error.
pub fn self_intersection(outline: &[[f64; 2]]) -> Result<Option<(usize, usize)>, String> {
    let n = outline.len();
    let seg = |i: usize| (outline[i], outline[(i + 1) % n]);
    if n < 64 {
        for i in 0..n {
            for j in i + 1..n {
                if !adjacent(i, j, n) && segments_intersect(seg(i).0, seg(i).1, seg(j).0, seg(j).1) {
                    return Ok(Some((i, j)));
                }
            }
        }
        return Ok(None);
    }
    if outline.iter().flatten().any(|v| !v.is_finite()) {
        return Err("the outline has a non-finite vertex".into());
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in outline {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let g = ((n as f64).sqrt().ceil() as usize).clamp(1, 4096);
    let size = [(hi[0] - lo[0]) / g as f64, (hi[1] - lo[1]) / g as f64];
    let cell = |x: f64, k: usize| if size[k] > 0.0 { (((x - lo[k]) / size[k]) as usize).min(g - 1) } else { 0 };
    let mut cells: Vec<Vec<u32>> = vec![Vec::new(); g * g];
    let mut inserted: u64 = 0;
    for i in 0..n {
        let (a, b) = seg(i);
        let (i0, i1) = (cell(a[0].min(b[0]), 0), cell(a[0].max(b[0]), 0));
        let (j0, j1) = (cell(a[1].min(b[1]), 1), cell(a[1].max(b[1]), 1));
        inserted += ((i1 - i0 + 1) * (j1 - j0 + 1)) as u64;
        if inserted > MAX_PAIR_TESTS {
            return Err(format!("the outline of {n} segments is too tangled to check for self-intersection"));
        }
        for cj in j0..=j1 {
            for ci in i0..=i1 {
                cells[cj * g + ci].push(i as u32);
            }
        }
    }
    let mut tests: u64 = 0;
    let mut best: Option<(usize, usize)> = None;
    for c in &cells {
        tests += (c.len() as u64).pow(2) / 2;
        if tests > MAX_PAIR_TESTS {
            return Err(format!("the outline of {n} segments is too tangled to check for self-intersection"));
        }
        for (x, &i) in c.iter().enumerate() {
            for &j in &c[x + 1..] {
                let (i, j) = ((i.min(j)) as usize, (i.max(j)) as usize);
                if adjacent(i, j, n) || best.is_some_and(|b| b <= (i, j)) {
                    continue;
                }
                if segments_intersect(seg(i).0, seg(i).1, seg(j).0, seg(j).1) {
                    best = Some((i, j));
                }
            }
        }
    }
    Ok(best)
}

impl GarmentGraph {
    /// Validates `spec` (file positions through `loc`; `materials` are the scene's material
    /// names) and builds the graph. Errors: unknown or non-positive plies, a panel with a
    /// degenerate, clockwise or self-intersecting outline, a bad edge span, a seam whose span
    /// is dangling (unknown panel or edge), spans of different length beyond
    /// `span_tolerance`, and spans used by two seams (overlap).
    pub fn validate(spec: &GarmentSpec, loc: &Locator, materials: &BTreeSet<String>) -> Result<Self, SceneError> {
        let h = spec.nominal_size();
        if !(h.is_finite() && h > 0.0) {
            let msg = match spec.element_size.problem() {
                Some((_, m)) => m,
                None if spec.element_size.fixed().is_none() => "Auto element size not resolved before meshing (garment::sizing)".to_string(),
                None => "expected a positive element size".to_string(),
            };
            return Err(loc.at(None, Some("element_size"), "garment.element_size", msg));
        }
        for (name, ply) in &spec.plies {
            let field = format!("garment.plies[{name}]");
            if !materials.contains(&ply.material) {
                let known: Vec<&str> = materials.iter().map(|s| s.as_str()).collect();
                return Err(loc.at_value(name, &ply.material, format!("{field}.material"), format!("ply \"{name}\" has unknown material \"{}\"; defined materials: {}", ply.material, known.join(", "))));
            }
            if !(ply.areal_density.is_finite() && ply.areal_density >= 0.0) {
                return Err(loc.at(Some(name), Some("areal_density"), format!("{field}.areal_density"), format!("ply \"{name}\" needs a non-negative mass per area")));
            }
            if !(ply.thickness.is_finite() && ply.thickness > 0.0) {
                return Err(loc.at(Some(name), Some("thickness"), format!("{field}.thickness"), format!("ply \"{name}\" needs a positive thickness")));
            }
        }
        let mut graph = UnGraph::new_undirected();
        let mut panel_node = Vec::new();
        for (pi, p) in spec.panels.iter().enumerate() {
            let field = format!("garment.panels[{}]", p.name);
            let err = |key: &str, msg: String| loc.at(Some(&p.name), Some(key), format!("{field}.{key}"), msg);
            if spec.panels[..pi].iter().any(|q| q.name == p.name) {
                return Err(err("name", format!("duplicate panel name \"{}\"", p.name)));
            }
            if p.outline.len() < 3 || p.outline.iter().flatten().any(|v| !v.is_finite()) {
                return Err(err("outline", format!("panel \"{}\": the outline needs at least 3 finite vertices", p.name)));
            }
            if let Some(v) = p.outline.iter().position(|v| v[0].abs().max(v[1].abs()) > MAX_COORDINATE) {
                return Err(err("outline", format!(
                    "panel \"{}\": outline vertex {v} ({:e}, {:e}) lies beyond ±{MAX_COORDINATE:e} m; pattern coordinates are in metres",
                    p.name, p.outline[v][0], p.outline[v][1]
                )));
            }
            let est = super::mesh::estimate_nodes(&p.outline, h);
            if !(est <= super::mesh::MAX_PATTERN_NODES as f64) {
                return Err(loc.at(None, Some("element_size"), "garment.element_size", format!(
                    "element size {} is too small for panel \"{}\": its mesh would have about {est:.2e} nodes (limit {} per panel)",
                    h, p.name, super::mesh::MAX_PATTERN_NODES
                )));
            }
            let crossing = self_intersection(&p.outline).map_err(|e| err("outline", format!("panel \"{}\": {e}", p.name)))?;
            if let Some((i, j)) = crossing {
                return Err(err("outline", format!("panel \"{}\": the outline intersects itself (segments {i}–{} and {j}–{})", p.name, i + 1, (j + 1) % p.outline.len())));
            }
            if signed_area(&p.outline) <= 0.0 {
                return Err(err("outline", format!("panel \"{}\": the outline runs clockwise; list it counter-clockwise", p.name)));
            }
            for (ename, span) in &p.edges {
                let n = p.outline.len();
                if span.from >= n || span.to >= n || span.from == span.to {
                    return Err(loc.at_value(&p.name, ename, format!("{field}.edges[{ename}]"), format!("panel \"{}\": edge \"{ename}\" needs two different vertices below {n}", p.name)));
                }
            }
            let (sampled, _) = sampled_outline(p, h).map_err(|e| err("curves", format!("panel \"{}\": {e}", p.name)))?;
            if self_intersection(&sampled).map_err(|e| err("curves", format!("panel \"{}\": {e}", p.name)))?.is_some() {
                return Err(err("curves", format!("panel \"{}\": a curved edge makes the outline intersect itself", p.name)));
            }
            if p.plies.is_empty() {
                return Err(err("plies", format!("panel \"{}\" has no ply", p.name)));
            }
            for ply in &p.plies {
                if !spec.plies.contains_key(ply) {
                    let known: Vec<&str> = spec.plies.keys().map(|s| s.as_str()).collect();
                    return Err(loc.at_value(&p.name, ply, format!("{field}.plies"), format!("panel \"{}\" uses unknown ply \"{ply}\"; plies: {}", p.name, known.join(", "))));
                }
            }
            panel_node.push(graph.add_node(pi));
        }
        let panel_index = |name: &str| spec.panels.iter().position(|p| p.name == name);
        // Outline segments already sewn, per panel: (segment, seam name).
        let mut used: Vec<Vec<(usize, String)>> = vec![Vec::new(); spec.panels.len()];
        let mut seam_edge = Vec::new();
        for (si, s) in spec.seams.iter().enumerate() {
            let field = format!("garment.seams[{}]", s.name);
            if spec.seams[..si].iter().any(|t| t.name == s.name) {
                return Err(loc.at(Some(&s.name), Some("name"), format!("{field}.name"), format!("duplicate seam name \"{}\"", s.name)));
            }
            let mut ends = Vec::new();
            for (key, side) in [("a", &s.a), ("b", &s.b)] {
                let SpanRef { panel, edge, .. } = side;
                let Some(pi) = panel_index(panel) else {
                    let known: Vec<&str> = spec.panels.iter().map(|p| p.name.as_str()).collect();
                    return Err(loc.at_value(&s.name, panel, format!("{field}.{key}.panel"), format!("seam \"{}\" is dangling: no panel \"{panel}\"; panels: {}", s.name, known.join(", "))));
                };
                let p = &spec.panels[pi];
                let Some(span) = p.edges.get(edge) else {
                    let known: Vec<&str> = p.edges.keys().map(|s| s.as_str()).collect();
                    return Err(loc.at_value(&s.name, edge, format!("{field}.{key}.edge"), format!("seam \"{}\" is dangling: panel \"{panel}\" has no edge \"{edge}\"; its edges: {}", s.name, known.join(", "))));
                };
                for seg in span_segments(p, span.from, span.to) {
                    if let Some((_, other)) = used[pi].iter().find(|(g, _)| *g == seg) {
                        return Err(loc.at(Some(&s.name), Some(key), format!("{field}.{key}"), format!(
                            "seam \"{}\" overlaps seam \"{other}\" on panel \"{panel}\" (outline segment {seg}–{})",
                            s.name,
                            (seg + 1) % p.outline.len()
                        )));
                    }
                    used[pi].push((seg, s.name.clone()));
                }
                let (points, ranges) = sampled_outline(p, h).map_err(|e| loc.at(Some(&p.name), Some("curves"), format!("garment.panels[{panel}].curves"), e))?;
                ends.push((pi, span_length(p, span.from, span.to, &points, &ranges)));
            }
            let (la, lb) = (ends[0].1, ends[1].1);
            if (la - lb).abs() > spec.span_tolerance * la.max(lb) {
                return Err(loc.at(Some(&s.name), Some("b"), format!("{field}.b"), format!(
                    "seam \"{}\" joins spans of different length: {}.{} is {la:.4} m, {}.{} is {lb:.4} m (tolerance {:.1} %)",
                    s.name, s.a.panel, s.a.edge, s.b.panel, s.b.edge, 100.0 * spec.span_tolerance
                )));
            }
            if let Some(msg) = kind_problem(s) {
                return Err(loc.at(Some(&s.name), Some("kind"), format!("{field}.kind"), msg));
            }
            seam_edge.push(graph.add_edge(panel_node[ends[0].0], panel_node[ends[1].0], si));
        }
        for (li, l) in spec.stitch_lines.iter().enumerate() {
            let field = format!("garment.stitch_lines[{}]", l.name);
            if panel_index(&l.panel).is_none() {
                return Err(loc.at_value(&l.name, &l.panel, format!("{field}.panel"), format!("stitch line \"{}\" is on unknown panel \"{}\"", l.name, l.panel)));
            }
            if l.points.len() < 2 || spec.stitch_lines[..li].iter().any(|m| m.name == l.name) {
                return Err(loc.at(Some(&l.name), Some("points"), format!("{field}.points"), "a stitch line needs a unique name and at least two points"));
            }
            // Every point on the panel (inside its outline, or within half an element of it).
            if let Some(pi) = panel_index(&l.panel) {
                let p = &spec.panels[pi];
                let (outline, _) = sampled_outline(p, h).map_err(|e| loc.at(Some(&p.name), Some("curves"), format!("garment.panels[{}].curves", p.name), e))?;
                let m = outline.len();
                for (k, q) in l.points.iter().enumerate() {
                    let near = q.iter().all(|v| v.is_finite())
                        && (super::mesh::point_in_polygon(*q, &outline)
                            || (0..m).any(|i| super::mesh::point_segment_distance(*q, outline[i], outline[(i + 1) % m]) <= 0.5 * h));
                    if !near {
                        return Err(loc.at(Some(&l.name), Some("points"), format!("{field}.points[{k}]"), format!(
                            "stitch line \"{}\": point {k} ({}, {}) lies outside panel \"{}\"",
                            l.name, q[0], q[1], l.panel
                        )));
                    }
                }
            }
        }
        Ok(Self { graph, panel_node, seam_edge })
    }

    /// Names of the two panels a seam joins.
    pub fn panels_of<'s>(&self, spec: &'s GarmentSpec, seam: &str) -> Option<(&'s str, &'s str)> {
        let si = spec.seams.iter().position(|s| s.name == seam)?;
        let (a, b) = self.graph.edge_endpoints(self.seam_edge[si])?;
        Some((spec.panels[self.graph[a]].name.as_str(), spec.panels[self.graph[b]].name.as_str()))
    }

    /// Connected components as lists of panel names (panels joined through seams).
    pub fn components<'s>(&self, spec: &'s GarmentSpec) -> Vec<Vec<&'s str>> {
        let mut uf = UnionFind::new(self.graph.node_count());
        for e in self.graph.edge_references() {
            uf.union(e.source().index(), e.target().index());
        }
        let mut groups: Vec<(usize, Vec<&str>)> = Vec::new();
        for n in self.graph.node_indices() {
            let root = uf.find(n.index());
            let name = spec.panels[self.graph[n]].name.as_str();
            match groups.iter_mut().find(|g| g.0 == root) {
                Some(g) => g.1.push(name),
                None => groups.push((root, vec![name])),
            }
        }
        groups.into_iter().map(|g| g.1).collect()
    }

    /// Seam loops: a fundamental cycle basis of the panel graph (one loop per seam that
    /// closes a cycle over a spanning forest; a seam joining a panel to itself is a loop of
    /// its own — e.g. a sleeve's underarm seam). Each loop lists its seam names.
    pub fn seam_loops<'s>(&self, spec: &'s GarmentSpec) -> Vec<Vec<&'s str>> {
        let n = self.graph.node_count();
        let mut parent: Vec<Option<(usize, EdgeIndex)>> = vec![None; n];
        let mut depth = vec![usize::MAX; n];
        let mut tree = BTreeSet::new();
        for root in self.graph.node_indices() {
            if depth[root.index()] != usize::MAX {
                continue;
            }
            depth[root.index()] = 0;
            let mut queue = std::collections::VecDeque::from([root]);
            while let Some(v) = queue.pop_front() {
                for e in self.graph.edges(v) {
                    let w = if e.source() == v { e.target() } else { e.source() };
                    if depth[w.index()] == usize::MAX {
                        depth[w.index()] = depth[v.index()] + 1;
                        parent[w.index()] = Some((v.index(), e.id()));
                        tree.insert(e.id());
                        queue.push_back(w);
                    }
                }
            }
        }
        let name = |e: EdgeIndex| spec.seams[self.graph[e]].name.as_str();
        let mut loops = Vec::new();
        for e in self.graph.edge_references() {
            if tree.contains(&e.id()) {
                continue;
            }
            let (mut a, mut b) = (e.source().index(), e.target().index());
            let (mut left, mut right) = (vec![name(e.id())], Vec::new());
            while a != b {
                if depth[a] >= depth[b] {
                    let Some((p, pe)) = parent[a] else { break };
                    left.push(name(pe));
                    a = p;
                } else {
                    let Some((p, pe)) = parent[b] else { break };
                    right.push(name(pe));
                    b = p;
                }
            }
            right.reverse();
            left.extend(right);
            loops.push(left);
        }
        loops
    }
}

/// What is wrong with a seam's allowance, stitch spacing or tape, if anything.
fn kind_problem(s: &super::spec::GarmentSeamSpec) -> Option<String> {
    if !(s.allowance.is_finite() && s.allowance >= 0.0 && s.stitch_spacing.is_finite() && s.stitch_spacing >= 0.0) {
        return Some(format!("seam \"{}\": allowance and stitch spacing must be non-negative", s.name));
    }
    s.kind.problem().map(|p| format!("seam \"{}\": {p}", s.name))
}
