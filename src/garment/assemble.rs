//! Garment → shell parts: each ply of each panel is meshed in pattern space, placed in 3D and
//! offset through the stack; seams become node-row ties, stitch lines node-to-node ties.

use std::collections::{BTreeMap, BTreeSet};

use nalgebra::Vector3;

use std::ops::Range;

use super::graph::{sampled_outline, span_segments, GarmentGraph};
use super::mesh::{mapped_counts_graded, mesh_polygon_graded, PatternMesh};
use super::sizing::SizeField;
use super::spec::{GarmentSpec, SpanRef};
use super::seam::rigid_link;
use super::{seam_ties, SeamInfo};
use crate::element::{DirectorFrame, NODE_DOFS};
use crate::mesh::ShellMesh;
use crate::model::{Load, Tie};
use crate::input::{Locator, SceneError};

/// One ply of one panel, or a laminated panel, as a shell part.
#[derive(Clone, Debug)]
pub struct GarmentPart {
    /// Part name: the panel name, or `panel/ply` for the plies of discrete multi-ply panels.
    pub name: String,
    /// Panel index.
    pub panel: usize,
    /// Ply position in the panel's stack (0 = outermost; a laminate's is 0).
    pub ply: usize,
    /// Stack positions of the plies the part stands for: `[ply]`, or all of a laminated
    /// panel's (see `garment::laminate`).
    pub plies: Vec<usize>,
    /// Material name (empty for a laminate: its plies have theirs).
    pub material: String,
    /// Thickness (a laminate's: the sum of its plies').
    pub thickness: f64,
    /// Mass per area (0: unset).
    pub areal_density: f64,
    /// Placed mesh (edges: the panel's named spans).
    pub mesh: ShellMesh,
    /// Grain (warp) direction per quad, in 3D.
    pub grains: Vec<Vector3<f64>>,
}

/// A meshed garment.
#[derive(Clone, Debug)]
pub struct GarmentMesh {
    /// The validated panel/seam graph.
    pub graph: GarmentGraph,
    /// Shell parts, panel by panel, ply by ply.
    pub parts: Vec<GarmentPart>,
    /// Flat pattern mesh of each panel.
    pub patterns: Vec<PatternMesh>,
    /// Per panel, the sampled-outline segments of each outline segment (curved edges).
    pub sample_ranges: Vec<Vec<Range<usize>>>,
    /// Per panel, the element size field its mesh follows (`garment::sizing`).
    pub sizes: Vec<SizeField>,
}

/// Node row (pattern-mesh nodes) of a panel's named span, in span direction.
fn span_row(pattern: &PatternMesh, ranges: &[Range<usize>], panel: &super::spec::PanelSpec, side: &SpanRef) -> Vec<usize> {
    let Some(span) = panel.edges.get(&side.edge) else { return Vec::new() };
    let mut row: Vec<usize> = Vec::new();
    for seg in span_segments(panel, span.from, span.to).into_iter().flat_map(|s| ranges[s].clone()) {
        for &n in &pattern.segment_rows[seg] {
            if row.last() != Some(&n) {
                row.push(n);
            }
        }
    }
    if side.reversed {
        row.reverse();
    }
    row
}

/// Requested element edges per sampled outline segment of panel `pi`, so that its seam rows
/// match a mapped-grid partner: where a seam joins a single straight segment of this panel to
/// a single side of a partner meshed by the mapped grid, that side's count (matching when
/// it is even, as the triangle split puts two element edges on each boundary piece).
fn matching_counts(spec: &GarmentSpec, pi: usize, sizes: &[SizeField]) -> Vec<Option<usize>> {
    let sampled = |p: &super::spec::PanelSpec| sampled_outline(p, sizes[spec.panels.iter().position(|q| q.name == p.name).unwrap_or(pi)].base).ok();
    let Some((outline, ranges)) = sampled(&spec.panels[pi]) else { return Vec::new() };
    let mut counts = vec![None; outline.len()];
    let single = |p: &super::spec::PanelSpec, side: &SpanRef, ranges: &[Range<usize>]| -> Option<usize> {
        let span = p.edges.get(&side.edge)?;
        let segs = span_segments(p, span.from, span.to);
        (segs.len() == 1 && ranges[segs[0]].len() == 1).then(|| ranges[segs[0]].start)
    };
    for s in &spec.seams {
        for (mine, other) in [(&s.a, &s.b), (&s.b, &s.a)] {
            if mine.panel != spec.panels[pi].name {
                continue;
            }
            let Some(oi) = spec.panels.iter().position(|p| p.name == other.panel) else { continue };
            let po = &spec.panels[oi];
            let Some((o_outline, o_ranges)) = sampled(po) else { continue };
            let (Some(k), Some(ko), Some(n)) = (single(&spec.panels[pi], mine, &ranges), single(po, other, &o_ranges), mapped_counts_graded(&o_outline, &sizes[oi])) else {
                continue;
            };
            if let Some(c) = counts.get_mut(k) {
                *c = Some(n[ko % 4]);
            }
        }
    }
    counts
}

/// Makes the seam ties a master–slave system (every DOF the slave of at most one tie, no
/// cycle) without losing a junction. A node where several seams meet (a crotch point: two
/// front, two back and two inner-leg panels) is the end of several rows, so several ties
/// name it as their slave, each with the single master DOF at the end of its partner row
/// (weight 1). Keeping only the first of them left the other panels' corners unsewn there.
/// Such ties are kept as equations between nodes: a point-to-point tie u_s = u_m + c λ that
/// joins two DOFs already joined by earlier ones is redundant and dropped (the offsets, minus
/// initial gaps, add up to zero round any loop); a translation tie whose slave is taken is
/// solved for its dominant master instead (u_m = u_s − c λ for a point tie) when that master
/// is free and no cycle results; only otherwise is it dropped, as are repeated slaves of
/// rotation ties and of links through the thickness.
fn join_at_junctions(ties: Vec<Tie>, fixed: &[bool]) -> Vec<Tie> {
    let n = ties.iter().flat_map(|t| std::iter::once(t.slave).chain(t.masters.iter().map(|m| m.0))).max().map_or(0, |m| m + 1);
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut a: usize) -> usize {
        while parent[a] != a {
            parent[a] = parent[parent[a]];
            a = parent[a];
        }
        a
    }
    // Masters of each kept tie's slave, to refuse a tie that would close a cycle.
    let mut masters_of: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut slave = vec![false; n];
    let depends = |masters_of: &[Vec<usize>], from: &[(usize, f64)], on: usize| {
        let mut stack: Vec<usize> = from.iter().map(|m| m.0).collect();
        let mut seen = BTreeSet::new();
        while let Some(a) = stack.pop() {
            if a == on {
                return true;
            }
            if seen.insert(a) {
                stack.extend(&masters_of[a]);
            }
        }
        false
    };
    let mut out = Vec::with_capacity(ties.len());
    for t in ties {
        let point = t.links.is_empty() && t.masters.len() == 1 && (t.masters[0].1 - 1.0).abs() <= 1e-12;
        let joined = point.then(|| (root(&mut parent, t.slave), root(&mut parent, t.masters[0].0)));
        if joined.is_some_and(|(ra, rb)| ra == rb) {
            continue;
        }
        // The same equation solved for its dominant master m*: a translation tie
        // u_s = Σ w_i u_i + c λ is also u_m* = (u_s − Σ_{i≠*} w_i u_i − c λ) / w* (row ends of
        // non-matching rows weigh their end master by nearly, not exactly, 1).
        let reversed = (t.links.is_empty() && t.slave % NODE_DOFS < 3)
            .then(|| t.masters.iter().copied().max_by(|a, b| a.1.total_cmp(&b.1)))
            .flatten()
            .filter(|&(_, w)| w >= 0.5)
            .map(|(m, w)| {
                let masters = std::iter::once((t.slave, 1.0 / w)).chain(t.masters.iter().filter(|x| x.0 != m).map(|&(i, c)| (i, -c / w))).collect();
                Tie { slave: m, masters, offset: -t.offset / w, load: t.load, links: Vec::new() }
            });
        // A supported DOF stays a master (unless the tie already named it slave).
        let candidates = std::iter::once(t).chain(reversed.filter(|r| !fixed.get(r.slave).copied().unwrap_or(false)));
        if let Some(tie) = candidates.into_iter().find(|c| !slave[c.slave] && !depends(&masters_of, &c.masters, c.slave)) {
            slave[tie.slave] = true;
            masters_of[tie.slave] = tie.masters.iter().map(|m| m.0).collect();
            if let Some((ra, rb)) = joined {
                parent[ra] = rb;
            }
            out.push(tie);
        }
    }
    out
}

/// Distance from a point to a polyline in the plane.
fn distance_to_polyline(p: [f64; 2], line: &[[f64; 2]]) -> f64 {
    line.windows(2)
        .map(|w| {
            let (a, b) = (w[0], w[1]);
            let ab = [b[0] - a[0], b[1] - a[1]];
            let l2 = ab[0] * ab[0] + ab[1] * ab[1];
            let t = if l2 > 0.0 { (((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1]) / l2).clamp(0.0, 1.0) } else { 0.0 };
            ((a[0] + t * ab[0] - p[0]).powi(2) + (a[1] + t * ab[1] - p[1]).powi(2)).sqrt()
        })
        .fold(f64::INFINITY, f64::min)
}

impl GarmentMesh {
    /// Validates and meshes `spec`: every panel is meshed flat at the element size, placed,
    /// and each ply is offset along the director by its position in the stack (outermost ply
    /// on the director side).
    ///
    /// `sizes` gives each panel's element size field (`garment::sizing`); None: the
    /// garment's fixed `element_size` everywhere.
    pub fn build(spec: &GarmentSpec, loc: &Locator, materials: &BTreeSet<String>, sizes: Option<Vec<SizeField>>) -> Result<Self, SceneError> {
        let graph = GarmentGraph::validate(spec, loc, materials)?;
        super::laminate::check(spec, loc)?;
        let sizes = sizes.unwrap_or_else(|| vec![SizeField::uniform(spec.nominal_size()); spec.panels.len()]);
        if sizes.len() != spec.panels.len() {
            return Err(loc.at(None, Some("element_size"), "garment.element_size", format!("{} size fields for {} panels", sizes.len(), spec.panels.len())));
        }
        let mut parts = Vec::new();
        let mut patterns = Vec::new();
        let mut sample_ranges = Vec::new();
        for (pi, p) in spec.panels.iter().enumerate() {
            let field = format!("garment.panels[{}]", p.name);
            if let Some(msg) = p.placement.problem() {
                return Err(loc.at(Some(&p.name), Some("placement"), format!("{field}.placement"), format!("panel \"{}\": {msg}", p.name)));
            }
            let g = p.grain;
            if !(g[0].is_finite() && g[1].is_finite()) || g[0].hypot(g[1]) == 0.0 {
                return Err(loc.at(Some(&p.name), Some("grain"), format!("{field}.grain"), "expected a non-zero grain direction"));
            }
            let h = sizes[pi].base;
            let (outline, ranges) = sampled_outline(p, h).map_err(|e| loc.at(Some(&p.name), Some("curves"), format!("{field}.curves"), format!("panel \"{}\": {e}", p.name)))?;
            let pattern = mesh_polygon_graded(&outline, &sizes[pi], &matching_counts(spec, pi, &sizes), p.grain).map_err(|e| loc.at(Some(&p.name), Some("outline"), format!("{field}.outline"), format!("panel \"{}\": {e}", p.name)))?;
            let fd = 1e-6 * sizes[pi].min();
            let mid: Vec<Vector3<f64>> = pattern.uv.iter().map(|&q| p.placement.map(q)).collect();
            let dirs: Vec<Vector3<f64>> = pattern.uv.iter().map(|&q| p.placement.director(q, fd)).collect();
            let grains: Vec<Vector3<f64>> = pattern
                .quads
                .iter()
                .map(|q| {
                    let c = q.iter().fold([0.0, 0.0], |s, &n| [s[0] + 0.25 * pattern.uv[n][0], s[1] + 0.25 * pattern.uv[n][1]]);
                    let (xu, xv) = p.placement.jacobian(c, fd);
                    (xu * g[0] + xv * g[1]).normalize()
                })
                .collect();
            let thick: Vec<f64> = p.plies.iter().map(|n| spec.plies.get(n).map_or(0.0, |x| x.thickness)).collect();
            let total: f64 = thick.iter().sum();
            let mut edges = BTreeMap::new();
            for name in p.edges.keys() {
                edges.insert(name.clone(), span_row(&pattern, &ranges, p, &SpanRef { panel: p.name.clone(), edge: name.clone(), reversed: false }));
            }
            // Discrete: each ply offset by its place in the stack; laminate: one shell on the
            // stack's mid-surface.
            let mut below = 0.0;
            let layers: Vec<(usize, f64)> = p
                .plies
                .iter()
                .enumerate()
                .map(|(k, _)| {
                    below += thick[k];
                    (k, 0.5 * total - below + 0.5 * thick[k])
                })
                .collect();
            let laminate = spec.is_laminate(p);
            let layers = if laminate { vec![(0, 0.0)] } else { layers };
            for (k, z) in layers {
                let ply = &p.plies[k];
                let mesh = ShellMesh {
                    nodes: mid.iter().zip(&dirs).map(|(x, d)| x + d * z).collect(),
                    directors: dirs.clone(),
                    quads: pattern.quads.clone(),
                    edges: edges.clone(),
                };
                mesh.validate().map_err(|e| loc.at(Some(&p.name), Some("outline"), format!("{field}.outline"), format!("panel \"{}\": {e}", p.name)))?;
                let part = if laminate {
                    GarmentPart { name: p.name.clone(), panel: pi, ply: 0, plies: (0..p.plies.len()).collect(), material: String::new(), thickness: total, areal_density: 0.0, mesh, grains: grains.clone() }
                } else {
                    let name = if p.plies.len() == 1 { p.name.clone() } else { super::laminate::alias(&p.name, ply) };
                    let material = spec.plies.get(ply).map(|x| x.material.clone()).unwrap_or_default();
                    let areal_density = spec.plies.get(ply).map_or(0.0, |x| x.areal_density);
                    GarmentPart { name, panel: pi, ply: k, plies: vec![k], material, thickness: thick[k], areal_density, mesh, grains: grains.clone() }
                };
                parts.push(part);
            }
            patterns.push(pattern);
            sample_ranges.push(ranges);
        }
        Ok(Self { graph, parts, patterns, sample_ranges, sizes })
    }

    /// Global part index of (panel, ply), given the index of the first garment part.
    fn part_of(&self, panel: usize, ply: usize) -> Option<usize> {
        self.parts.iter().position(|p| p.panel == panel && p.ply == ply)
    }

    /// Number of shell parts of a panel: its plies, or 1 when laminated.
    fn n_parts(&self, panel: usize) -> usize {
        self.parts.iter().filter(|p| p.panel == panel).count()
    }

    /// Seam and stitch-line ties. `first_node[k]` is the first global node of garment part k.
    /// The side whose span has more mesh nodes is the slave (b when they have as many): a
    /// tie constrains only the slave nodes, each to the master row's piecewise-linear
    /// interpolation, so a master row finer than its slave row would leave its nodes between
    /// the slave nodes unsewn — free edge nodes that a closing seam drags the panel's edge
    /// past (the rule for scene seams: make the finer row the slave) — unless only the finer
    /// row has supported nodes (`fixed`: a supported slave needs supported masters). Below,
    /// "a" is the master side and "b" the slave side.
    /// Each seam ties ply k of panel b to ply k of panel a (or a's innermost ply) with the
    /// seam's kind and closing load, and links a's plies 1.. rigidly to its ply 0 along the
    /// span (all plies sewn together; the links keep the stack's thickness offsets along ply
    /// 0's current director, exactly at any rotation). Sewing a multi-ply seam therefore
    /// drives every ply of b to its partner ply of a together: the resolved tie of ply k of
    /// b is u = u_a0 + Z_k (d_a0 − d_a0⁰) − g_k⁰ λ, which closes each ply's own initial gap
    /// g_k⁰ at λ = 1. One [`SeamInfo`] per ply of b (named `seam/ply` for multi-ply panels). A stitch line links every node of plies 1.. within
    /// half an element of the line rigidly to the node of ply 0 at the same pattern point
    /// ([`rigid_link`]: the stack's section stays straight there).
    #[allow(clippy::too_many_arguments)]
    pub fn ties(
        &self,
        spec: &GarmentSpec,
        loc: &Locator,
        first_node: &[usize],
        loads: &[Load],
        x0: &[Vector3<f64>],
        frames0: &mut [DirectorFrame],
        fixed: &[bool],
    ) -> Result<(Vec<Tie>, Vec<SeamInfo>), SceneError> {
        let mut ties = Vec::new();
        let mut infos = Vec::new();
        let panel_index = |name: &str| spec.panels.iter().position(|p| p.name == name);
        for s in &spec.seams {
            let field = format!("garment.seams[{}]", s.name);
            let err = |msg: String| loc.at(Some(&s.name), None, field.clone(), msg);
            let (Some(pa), Some(pb)) = (panel_index(&s.a.panel), panel_index(&s.b.panel)) else {
                return Err(err(format!("seam \"{}\" is dangling", s.name)));
            };
            let closing = match &s.closing {
                None => None,
                Some(l) => Some(loads.iter().position(|x| &x.name == l).ok_or_else(|| {
                    loc.at_value(&s.name, l, format!("{field}.closing"), format!("no load pattern named \"{l}\" (declare it as `\"{l}\": Closure` in loads)"))
                })?),
            };
            let row_a = span_row(&self.patterns[pa], &self.sample_ranges[pa], &spec.panels[pa], &s.a);
            let row_b = span_row(&self.patterns[pb], &self.sample_ranges[pb], &spec.panels[pb], &s.b);
            // The finer row is the slave (see above), unless it is supported and the other
            // is not (a supported slave must have supported masters).
            let supported = |p: usize, row: &[usize]| {
                (0..self.n_parts(p)).filter_map(|k| self.part_of(p, k)).any(|part| row.iter().any(|&n| fixed.get(NODE_DOFS * (n + first_node[part])..NODE_DOFS * (n + first_node[part] + 1)).is_some_and(|f| f.iter().any(|&x| x))))
            };
            let swap = row_a.len() > row_b.len() && !(supported(pa, &row_a) && !supported(pb, &row_b));
            let (pa, row_a, pb, row_b) = if swap { (pb, row_b, pa, row_a) } else { (pa, row_a, pb, row_b) };
            let global = |part: usize, row: &[usize]| -> Vec<usize> { row.iter().map(|n| n + first_node[part]).collect() };
            let (na, nb) = (self.n_parts(pa), self.n_parts(pb));
            let master_part = self.part_of(pa, 0).ok_or_else(|| err("panel without plies".into()))?;
            let master = global(master_part, &row_a);
            for k in 1..na {
                let part = self.part_of(pa, k).ok_or_else(|| err("missing ply".into()))?;
                for (&m, &sl) in master.iter().zip(&global(part, &row_a)) {
                    ties.extend(rigid_link(m, sl, x0, frames0));
                }
            }
            for k in 0..nb {
                let part_b = self.part_of(pb, k).ok_or_else(|| err("missing ply".into()))?;
                let part_a = self.part_of(pa, k.min(na - 1)).ok_or_else(|| err("missing ply".into()))?;
                let name = if nb == 1 { s.name.clone() } else { format!("{}/{}", s.name, spec.panels[pb].plies[k]) };
                let (mut t, mut info) = seam_ties(&name, s.kind, x0, frames0, &global(part_a, &row_a), &global(part_b, &row_b), closing).map_err(err)?;
                super::seam::make_compliant(&mut t, &mut info, s.stiffness, s.strength, closing.is_some())
                    .map_err(|(key, msg)| loc.at(Some(&s.name), Some(key), format!("{field}.{key}"), msg))?;
                ties.extend(t);
                infos.push(info);
            }
        }
        for l in &spec.stitch_lines {
            let Some(pi) = panel_index(&l.panel) else { continue };
            let pattern = &self.patterns[pi];
            let near: Vec<usize> = (0..pattern.uv.len()).filter(|&n| distance_to_polyline(pattern.uv[n], &l.points) <= 0.5 * self.sizes[pi].at(pattern.uv[n])).collect();
            if near.is_empty() {
                return Err(loc.at(Some(&l.name), Some("points"), format!("garment.stitch_lines[{}].points", l.name), format!("stitch line \"{}\" passes no mesh node of panel \"{}\"", l.name, l.panel)));
            }
            let Some(p0) = self.part_of(pi, 0) else { continue };
            for k in 1..self.n_parts(pi) {
                let Some(pk) = self.part_of(pi, k) else { continue };
                for &n in &near {
                    ties.extend(rigid_link(first_node[p0] + n, first_node[pk] + n, x0, frames0));
                }
            }
        }
        Ok((join_at_junctions(ties, fixed), infos))
    }

    /// Export layout: ids of panels, plies (in stack order, innermost first, see
    /// [`GarmentSpec::plies_in_stack_order`]) and materials per model part (garment parts
    /// start at model part `first_part`), each ply's thickness, and the flat pattern laid out panel beside panel (gap of
    /// a tenth of the largest panel) with ply k shifted by −k·(that gap) in z.
    pub fn layout(&self, spec: &GarmentSpec, first_part: usize, first_node: &[usize], n_nodes: usize) -> super::export::GarmentLayout {
        let plies = spec.plies_in_stack_order();
        let ply_thickness = plies.iter().map(|p| spec.plies.get(p).map_or(0.0, |x| x.thickness)).collect();
        let mut materials: Vec<String> = spec.plies.values().map(|p| p.material.clone()).collect();
        materials.sort();
        materials.dedup();
        let mut part_tags = vec![[-1; 3]; first_part];
        let mut part_plies = vec![Vec::new(); first_part];
        for gp in &self.parts {
            let ids: Vec<i32> = gp.plies.iter().map(|&k| plies.iter().position(|p| *p == spec.panels[gp.panel].plies[k]).map_or(-1, |i| i as i32)).collect();
            // A laminate stands for several plies and materials: −1, its plies in `part_plies`.
            let ply = if ids.len() == 1 { ids[0] } else { -1 };
            let mat = materials.iter().position(|m| *m == gp.material).map_or(-1, |i| i as i32);
            part_tags.push([gp.panel as i32, ply, mat]);
            part_plies.push(ids);
        }
        let extent = |pat: &PatternMesh| {
            let (lo, hi) = pat.uv.iter().fold(([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]), |(lo, hi), p| ([lo[0].min(p[0]), lo[1].min(p[1])], [hi[0].max(p[0]), hi[1].max(p[1])]));
            (lo, hi)
        };
        let gap = 0.1 * self.patterns.iter().map(|p| { let (lo, hi) = extent(p); (hi[0] - lo[0]).max(hi[1] - lo[1]) }).fold(0.0, f64::max);
        let mut shift = Vec::with_capacity(self.patterns.len());
        let mut x = 0.0;
        for p in &self.patterns {
            let (lo, hi) = extent(p);
            shift.push([x - lo[0], -lo[1]]);
            x += hi[0] - lo[0] + gap;
        }
        let mut flat = vec![None; n_nodes];
        let mut pattern_uv = vec![None; n_nodes];
        for (gp, &f) in self.parts.iter().zip(first_node) {
            let pat = &self.patterns[gp.panel];
            for (n, uv) in pat.uv.iter().enumerate() {
                if let Some(slot) = flat.get_mut(f + n) {
                    *slot = Some([uv[0] + shift[gp.panel][0], uv[1] + shift[gp.panel][1], -(gp.ply as f64) * gap]);
                }
                if let Some(slot) = pattern_uv.get_mut(f + n) {
                    *slot = Some(*uv);
                }
            }
        }
        let mut part_element_size = vec![Vec::new(); first_part];
        for gp in &self.parts {
            let pat = &self.patterns[gp.panel];
            let field = &self.sizes[gp.panel];
            part_element_size.push(pat.quads.iter().map(|q| field.at(q.iter().fold([0.0, 0.0], |s, &n| [s[0] + 0.25 * pat.uv[n][0], s[1] + 0.25 * pat.uv[n][1]]))).collect());
        }
        super::export::GarmentLayout { panels: spec.panels.iter().map(|p| p.name.clone()).collect(), plies, ply_thickness, materials, part_tags, part_plies, flat, pattern_uv, part_element_size }
    }

    /// Warnings for seams that look sewn crossed: with each side's row as given (`reversed`),
    /// the placed span ends meet much farther apart than they would the other way round
    /// (the sum of the two end gaps more than twice the crossed one and more than a fifth of
    /// the span) — typically a wrong `b.reversed`.
    pub fn crossed_seams(&self, spec: &GarmentSpec, loc: &Locator) -> Vec<SceneError> {
        let mut out = Vec::new();
        let panel_index = |name: &str| spec.panels.iter().position(|p| p.name == name);
        for s in &spec.seams {
            let (Some(pa), Some(pb)) = (panel_index(&s.a.panel), panel_index(&s.b.panel)) else { continue };
            let ends = |pi: usize, side: &SpanRef| -> Option<(Vector3<f64>, Vector3<f64>, f64)> {
                let p = &spec.panels[pi];
                let row = span_row(&self.patterns[pi], &self.sample_ranges[pi], p, side);
                let uv = &self.patterns[pi].uv;
                let pts: Vec<Vector3<f64>> = row.iter().map(|&n| p.placement.map(uv[n])).collect();
                let length = pts.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
                Some((*pts.first()?, *pts.last()?, length))
            };
            let (Some((a0, a1, la)), Some((b0, b1, lb))) = (ends(pa, &s.a), ends(pb, &s.b)) else { continue };
            let given = (a0 - b0).norm() + (a1 - b1).norm();
            let crossed = (a0 - b1).norm() + (a1 - b0).norm();
            if given > 2.0 * crossed && given > 0.2 * la.max(lb) {
                out.push(loc.at(Some(&s.name), Some("b"), format!("garment.seams[{}].b.reversed", s.name), format!(
                    "warning: seam \"{}\" looks sewn crossed: as given its ends are {given:.4} m apart (sum of both ends), the other way round {crossed:.4} m; check `reversed` (now {})",
                    s.name, s.b.reversed
                )));
            }
        }
        out
    }

    /// Warnings for connected groups of panels of which no node is supported (`supported`
    /// tells, per garment part, whether any of its nodes has a fixed DOF).
    pub fn unsupported(&self, spec: &GarmentSpec, loc: &Locator, supported: &[bool]) -> Vec<SceneError> {
        let mut out = Vec::new();
        for group in self.graph.components(spec) {
            let any = self.parts.iter().zip(supported).any(|(p, &s)| s && group.contains(&spec.panels[p.panel].name.as_str()));
            if !any {
                let seamed = group.len() > 1 || spec.seams.iter().any(|s| group.contains(&s.a.panel.as_str()));
                let first = group.first().copied().unwrap_or_default();
                out.push(loc.at(Some(first), None, format!("garment.panels[{first}]"), format!(
                    "warning: panel{} {} {} neither supported nor seamed to a supported panel{}",
                    if group.len() > 1 { "s" } else { "" },
                    group.iter().map(|g| format!("\"{g}\"")).collect::<Vec<_>>().join(", "),
                    if group.len() > 1 { "are" } else { "is" },
                    if seamed { "" } else { " (and not seamed at all)" }
                )));
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(s: usize, m: usize, c: f64) -> Tie {
        Tie { slave: s, masters: vec![(m, 1.0)], offset: c, load: Some(0), links: Vec::new() }
    }

    /// Solves the kept ties for the slaves with every free DOF at 0 (λ = 1).
    fn solve(ties: &[Tie], n: usize) -> Vec<f64> {
        let mut u = vec![0.0; n];
        for _ in 0..n {
            for t in ties {
                u[t.slave] = t.masters.iter().map(|&(m, w)| w * u[m]).sum::<f64>() + t.offset;
            }
        }
        u
    }

    /// Four corners (DOFs 0, 5, 10, 15: x of nodes 0–3) meeting at one point, sewn by four
    /// seams (b to a, b to c, d to c, d to a: two name a taken slave, the last closes the
    /// loop), and the end of a non-matching row (weights 0.9999 and 0.0001). Every tie is
    /// kept as an equation (reversed where its slave is taken) or dropped only when implied,
    /// so every equation holds at λ = 1; keeping only each slave's first tie (b to a, d to c)
    /// left {a, b} and {c, d} apart.
    #[test]
    fn junction_ties_keep_every_equation() {
        let (a, b, c, d) = (0, 5, 10, 15);
        let x = [0.0, 0.3, -0.2, 0.1];
        // u_s = u_m + (x_m − x_s) closes the gap (offset −g₀).
        let tie = |s: usize, m: usize| point(s, m, x[m / 5] - x[s / 5]);
        let all = vec![tie(b, a), tie(b, c), tie(d, c), tie(d, a)];
        let kept = join_at_junctions(all.clone(), &[]);
        let mut slaves: Vec<usize> = kept.iter().map(|t| t.slave).collect();
        slaves.sort_unstable();
        slaves.dedup();
        assert_eq!(slaves.len(), kept.len(), "a DOF is the slave of two ties: {kept:?}");
        assert_eq!(kept.len(), 3, "three ties join four corners: {kept:?}");
        let u = solve(&kept, 16);
        for t in &all {
            let r = u[t.slave] - t.masters.iter().map(|&(m, w)| w * u[m]).sum::<f64>() - t.offset;
            assert!(r.abs() < 1e-14, "tie {t:?} violated by {r}");
        }
        // A row end weighing its end master by nearly 1: solved for that master.
        let end = Tie { slave: a, masters: vec![(20, 0.9999), (25, 0.0001)], offset: 0.05, load: Some(0), links: Vec::new() };
        let kept = join_at_junctions(vec![tie(a, c), end.clone()], &[]);
        assert_eq!(kept.len(), 2);
        assert_eq!(kept[1].slave, 20, "{kept:?}");
        let u = solve(&kept, 26);
        let r = u[a] - end.masters.iter().map(|&(m, w)| w * u[m]).sum::<f64>() - end.offset;
        assert!(r.abs() < 1e-14, "{r}");
    }
}
