//! Ply-to-ply contact: node-to-surface penalty contact with regularised Coulomb friction
//! between the adjacent plies of a multi-ply panel (Wriggers, *Computational Contact
//! Mechanics*, 2nd ed. 2006, §4.2 (node-to-segment gap and its variation), §5.2 (penalty)
//! and §10.3 (regularised friction); Laursen 2002, ch. 5).
//!
//! For each pair of adjacent plies (k, k+1) of a panel, the nodes of each ply are tried
//! against the surface of the other — two passes. With a one-pass (outer-ply slave) scheme
//! the inner ply's nodes passed through the outer ply where the stack wraps a body (39.6 %
//! of the ply thickness on the three-ply strip over a cylinder, `tests/interply.rs`); with
//! the C¹ penalty law and lagged friction below, the two passes no longer make Newton
//! alternate between the duplicate constraints. From the concave side the normal prisms of
//! neighbouring facets overlap and the closest facet — with it the force direction — can
//! jump; the smoothing keeps the force continuous in the gap. Each master quad is split
//! into two triangles along its 1–3 diagonal; the slave node x_s is matched with the closest
//! point x_c = Σ λ_j x_j of the nearest triangle (unit normal n = (x₂−x₁)×(x₃−x₁)/|…|).
//! Gap: g = σ n·(x_s − x₁) − c when x_c lies inside the triangle, g = σ'|x_s − x_c| − c on
//! an edge or at a vertex (σ' the side of the facet plane), so g is continuous as the node
//! passes from facet to facet; c = (h_s + h_m)/2, the plies' half-thicknesses (or the
//! reference distance where the facets of a curved ply lie on chords closer than that), and
//! σ = ±1 the side of the master the slave lies on in the reference (the ply order): a node
//! that has crossed is pushed back, not pulled through. The variation is
//! δg = ν·(δx_s − Σ λ_j δx_j) with ν the unit direction (exact for the closest point), so
//! the penalty law λ_N(g) gives the force λ_N ν on the slave and −λ_j λ_N ν on master
//! node j: action equals reaction, the forces sum to zero. λ_N is the penalty k_n⟨−g⟩
//! made C¹ by a quadratic ramp over the first ε = 0.02 c of penetration (k_n g²/(2ε) for
//! −ε < g < 0, k_n(−g − ε/2) beyond), so that force and stiffness are continuous at first
//! contact (with the kink Newton 2-cycled on pairs at g ≈ 0). A slave node whose closest
//! point lies on the master ply's free edge (it overhangs the edge) is measured against the
//! plane of that boundary facet, whose side is defined, up to half an element past the edge.
//!
//! Friction: the slip is measured against the master's material point x̂ = Σ N̂_j x_j where
//! the slave stuck (anchor: a master triangle and fixed barycentric coordinates N̂, so the
//! anchor moves with the master): s = (I − nnᵀ)(x_s − x̂), traction
//! t = −μλ_N tanh(k_t|s|/(μλ_N)) ŝ on the slave and −N̂_j t on master node j (the smooth
//! Coulomb law of `mechanics.rs`, with the elastic slip μλ_N/k_t at least 10⁻³ of the
//! element size). A pair counts as sliding when k_t|s| > 2μλ_N; on
//! convergence its anchor is dragged to trail the slave's projection by 2μλ_N/k_t.
//!
//! Tangent: the exact Jacobian ∂f/∂u of these forces over the slave and the master nodes
//! (forward-mode dual numbers through projection, normal and friction), with μλ_N held fixed
//! in the friction law (the friction–normal coupling is left out, as in `mechanics.rs`); the
//! solver adds its symmetric part, node-pair blocks included (`NodalForces::add_coupled`).
//!
//! Penalty: k_n = c·min(A_s, A_m)·a/ℓ² per slave node, A the membrane stiffness (E·h, or the
//! fabric's larger tensile stiffness) of the slave's and the master's ply, a the node's
//! tributary area and ℓ² the mean area of its elements (a uniform pressure p penetrates by
//! p ℓ²/(c A) per pass); c = 1 unless overridden, or k_n given directly. Candidate master
//! triangles are found through a parry3d BVH of their bounding boxes, rebuilt from the
//! current configuration at each evaluation.

use std::time::Instant;

use nalgebra::{Matrix3, Vector3};
use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy};
use rayon::prelude::*;
use serde::Serialize;

use crate::element::NODE_DOFS;
use crate::model::{Model, State};
use crate::solver::NodalForces;

mod dual;
mod pair;
mod settings;

use pair::{boxes, closest, pair_forces, project, pv, Eval, History, PairForces, Record, Surface};
pub use settings::{InterplyFormulation, InterplySettings, InterplySetup, InterplySpec};

/// A pair counts as sliding when k_t|s| > 2μλ_N (the friction force exceeds tanh 2 = 96 %
/// of μλ_N), as for rigid bodies.
const SLIDE_ARG: f64 = 2.0;
/// Regularisation depth ε of the normal law, as a fraction of the contact distance c: the
/// penalty force is smoothed by a quadratic ramp over −ε < g < 0 (`pair_forces`), so force and
/// stiffness are continuous at first contact. With the plain kink ⟨−g⟩ Newton 2-cycled on a
/// pair lying at g ≈ 0 (active: the stiff step lifts it just clear; inactive: no stiffness,
/// it falls back in), so a draped three-ply strip never got past first contact.
const EPS_FRAC: f64 = 0.02;
/// Smallest elastic slip of the regularised friction law, as a fraction of the element size:
/// plies pressed together only by their weight carry normal forces so small that μλ_N/k_t
/// would be nanometres, and Newton would chatter between the two slip directions.
const SLIP_MIN: f64 = 1e-3;
/// Most nodes one pair's forces act on: the slave, the projection triangle, the anchor
/// triangle.
const MAX_NODES: usize = 7;
/// Variables of the dual numbers (3 translations per node).
const NV: usize = 3 * MAX_NODES;

/// Active set and resultants of one converged increment.
#[derive(Clone, Debug, Default, Serialize)]
pub struct InterplyIncrement {
    /// Node–ply pairs in contact.
    pub active: usize,
    /// Pairs that came into contact.
    pub activated: usize,
    /// Pairs that separated.
    pub released: usize,
    /// Active pairs sliding.
    pub sliding: usize,
    /// Largest penetration between plies (−gap), m.
    pub max_penetration: f64,
    /// Largest penetration as a fraction of its pair's mean ply thickness (h_s + h_m)/2.
    pub max_penetration_ratio: f64,
    /// Sum of the normal contact forces (N).
    pub normal_force: f64,
}

/// Ply-to-ply contact of a model (a [`NodalForces`] term).
pub struct InterplyContact {
    surfaces: Vec<Surface>,
    records: Vec<Record>,
    history: Vec<History>,
    last: Vec<Eval>,
    mu: f64,
    tangential_factor: f64,
    search_s: f64,
    /// Per-increment reports (also returned by `commit`).
    pub increments: Vec<InterplyIncrement>,
}


impl InterplyContact {
    /// Contact between the plies of `setup.ply_pairs` of `model` (nodes of a against b).
    pub fn new(model: &Model, setup: &InterplySetup) -> Self {
        let n = model.n_nodes();
        let mut area = vec![0.0f64; n];
        let mut el_area_sum = vec![0.0f64; n];
        let mut el_count = vec![0usize; n];
        for (e, def) in model.elements.iter().enumerate() {
            let a_el = model.element(e).reference_area();
            for &a in &def.nodes {
                area[a] += 0.25 * a_el;
                el_area_sum[a] += a_el;
                el_count[a] += 1;
            }
        }
        // Nodes joined to others by a tie (seams, stitch lines): a boundary edge between two
        // of them is sewn to a partner edge, not a free edge of the ply.
        let tied: std::collections::BTreeSet<usize> = model
            .dofs
            .ties
            .iter()
            .filter(|t| t.slave % NODE_DOFS < 3)
            .flat_map(|t| std::iter::once(t.slave / NODE_DOFS).chain(t.masters.iter().map(|&(m, _)| m / NODE_DOFS)))
            .collect();
        let mut surface_of_part = std::collections::BTreeMap::new();
        let mut surfaces: Vec<Surface> = Vec::new();
        for &(pa, pb) in &setup.ply_pairs {
            for p in [pa, pb] {
                surface_of_part.entry(p).or_insert_with(|| {
                    let info = &model.parts[p];
                    let els = &model.elements[info.first_element..info.first_element + info.n_elements];
                    let tris = els.iter().flat_map(|d| [[d.nodes[0], d.nodes[1], d.nodes[2]], [d.nodes[0], d.nodes[2], d.nodes[3]]]).collect();
                    let (membrane, half) = els.iter().fold((0.0f64, 0.0f64), |(m, h), d| {
                        let sec = &model.sections[d.section];
                        (m.max(sec.material.small_strain_moduli().0 * sec.thickness), h.max(0.5 * sec.thickness))
                    });
                    let mut count = std::collections::BTreeMap::new();
                    for d in els {
                        for k in 0..4 {
                            let (a, b) = (d.nodes[k], d.nodes[(k + 1) % 4]);
                            *count.entry((a.min(b), a.max(b))).or_insert(0usize) += 1;
                        }
                    }
                    let boundary: std::collections::BTreeSet<(usize, usize)> = count.into_iter().filter(|&((a, b), c)| c == 1 && !(tied.contains(&a) && tied.contains(&b))).map(|(e, _)| e).collect();
                    let boundary_nodes = boundary.iter().flat_map(|&(a, b)| [a, b]).collect();
                    surfaces.push(Surface { part: p, tris, membrane, half, boundary, boundary_nodes });
                    surfaces.len() - 1
                });
            }
        }
        let mut records = Vec::new();
        let mut history = Vec::new();
        let x0 = |a: usize| model.x0[a];
        for &(pa, pb) in &setup.ply_pairs {
            {
                let (slave_part, master_part) = (pa, pb);
                let (ss, ms) = (surface_of_part[&slave_part], surface_of_part[&master_part]);
                let master = &surfaces[ms];
                let bvh = Bvh::from_leaves(BvhBuildStrategy::default(), &boxes(master, &x0));
                let info = &model.parts[slave_part];
                for a in info.first_node..info.first_node + info.n_nodes {
                    if el_count[a] == 0 {
                        continue;
                    }
                    let size = (el_area_sum[a] / el_count[a] as f64).sqrt();
                    let offset = surfaces[ss].half + master.half;
                    let Some((tri, bary, d)) = closest(master, &bvh, &x0, &model.x0[a], offset + size) else { continue };
                    if d == 0.0 {
                        continue;
                    }
                    // Facets of a curved ply lie on chords: a reference mid-surface distance
                    // below the half-thicknesses (measured as `evaluate` measures it, against
                    // the facet's plane for a node over the free edge) is taken as the
                    // contact distance (a stress-free reference, no initial penetration).
                    let Some((distance, _)) = master.distance(tri, &bary, d, d.signum(), &x0, &model.x0[a]) else { continue };
                    let offset = offset.min(distance);
                    let k_n = setup.settings.penalty.unwrap_or_else(|| setup.settings.penalty_factor * surfaces[ss].membrane.min(master.membrane) * area[a] / (size * size));
                    records.push(Record { node: a, surface: ms, side: d.signum(), offset, k_n, area: area[a], size });
                    history.push(History { anchor: Some((tri, bary)), ..Default::default() });
                }
            }
        }
        let nr = records.len();
        Self {
            surfaces,
            records,
            history,
            last: vec![Eval::default(); nr],
            mu: setup.settings.friction,
            tangential_factor: setup.settings.tangential_factor,
            search_s: 0.0,
            increments: Vec::new(),
        }
    }

    /// Number of node–ply pairs (slave nodes counted once per adjacent ply).
    pub fn n_pairs(&self) -> usize {
        self.records.len()
    }

    /// Range of the nodal normal penalties (N/m).
    pub fn penalty_range(&self) -> (f64, f64) {
        let k = self.records.iter().map(|r| r.k_n);
        (k.clone().fold(f64::INFINITY, f64::min), k.fold(0.0, f64::max))
    }

    /// Largest penetration (−gap) of the last evaluation, m.
    pub fn max_penetration(&self) -> f64 {
        self.last.iter().filter(|e| e.active).map(|e| -e.gap).fold(0.0, f64::max)
    }

    /// Evaluates every record at `state`: per record its evaluation and, when active, its
    /// forces (and Jacobian when `with_tangent`).
    fn evaluate(&mut self, model: &Model, state: &State, with_tangent: bool) -> Vec<(Eval, Option<PairForces>)> {
        let t = Instant::now();
        let x = |a: usize| model.x0[a] + state.u[a];
        let bvhs: Vec<Bvh> = self.surfaces.iter().map(|s| Bvh::from_leaves(BvhBuildStrategy::default(), &boxes(s, &x))).collect();
        let projections: Vec<Option<(usize, [f64; 3], f64)>> = self
            .records
            .par_iter()
            .map(|r| {
                let s = &self.surfaces[r.surface];
                closest(s, &bvhs[r.surface], &x, &x(r.node), 2.0 * r.offset + r.size)
            })
            .collect();
        self.search_s += t.elapsed().as_secs_f64();
        let (mu, tf) = (self.mu, self.tangential_factor);
        self.records
            .par_iter()
            .zip(&self.history)
            .zip(&projections)
            .map(|((r, h), p)| {
                let Some((tri, bary, d)) = *p else { return (Eval::default(), None) };
                let s = &self.surfaces[r.surface];
                // A node whose closest point is on the master ply's free edge overhangs it
                // (a ply's end row lies over its neighbour's): the sign of n·(x_s − x_c) there
                // flips as the node swings past the edge's plane, and with it the gap by
                // 2|x_s − x_c| (the force jumped, Newton cycled). Such a node is measured
                // against the plane of the boundary facet instead (the facet's gap extended
                // past its edge, continuous with the interior one), up to half an element
                // beyond the edge.
                let Some((distance, plane)) = s.distance(tri, &bary, d, r.side, &x, &x(r.node)) else { return (Eval::default(), None) };
                let gap = distance - r.offset;
                // Beyond the depth limit the master is a distant part of the ply (a fold), not
                // the surface this node is pressed against.
                if gap >= 0.0 || gap < -(2.0 * r.offset + 0.5 * r.size) {
                    return (Eval { proj: Some((tri, bary)), gap, ..Default::default() }, None);
                }
                let anchor = h.anchor.map(|(t, n)| (s.tris[t], n));
                let (ev, pf) = pair_forces(r, s.tris[tri], bary, plane, anchor, h.lagged, &x, mu, tf * r.k_n, with_tangent);
                (Eval { proj: Some((tri, bary)), ..ev }, Some(pf))
            })
            .collect()
    }
}


impl NodalForces for InterplyContact {
    /// Forces only with the node's own 3×3 blocks (the pair blocks come from `add_coupled`).
    fn add(&mut self, model: &Model, state: &State, f_ext: &mut [f64], jacobian: &mut Vec<(usize, Matrix3<f64>)>) {
        let mut pairs = Vec::new();
        self.add_coupled(model, state, f_ext, jacobian, &mut pairs);
    }

    /// Contact forces on slave and master nodes with their full Jacobian: diagonal blocks
    /// into `jacobian`, blocks between different nodes into `pairs`.
    fn add_coupled(
        &mut self,
        model: &Model,
        state: &State,
        f_ext: &mut [f64],
        jacobian: &mut Vec<(usize, Matrix3<f64>)>,
        pairs: &mut Vec<(usize, usize, Matrix3<f64>)>,
    ) {
        let out = self.evaluate(model, state, true);
        for (i, (ev, pf)) in out.into_iter().enumerate() {
            self.last[i] = ev;
            let Some(pf) = pf else { continue };
            for (a, fa) in pf.nodes.iter().zip(&pf.forces) {
                for k in 0..3 {
                    f_ext[NODE_DOFS * a + k] += fa[k];
                }
            }
            for (i, &a) in pf.nodes.iter().enumerate() {
                for (j, &b) in pf.nodes.iter().enumerate() {
                    let block = Matrix3::from_fn(|p, q| pf.jacobian[3 * i + p][3 * j + q]);
                    if i == j {
                        jacobian.push((a, block));
                    } else {
                        pairs.push((a, b, block));
                    }
                }
            }
        }
    }

    fn commit(&mut self, model: &Model, state: &State) -> Option<serde_json::Value> {
        let out = self.evaluate(model, state, false);
        let mut rep = InterplyIncrement::default();
        for (i, (ev, _)) in out.into_iter().enumerate() {
            let r = &self.records[i];
            let h = &mut self.history[i];
            if ev.active {
                rep.active += 1;
                rep.activated += usize::from(!h.active);
                rep.max_penetration = rep.max_penetration.max(-ev.gap);
                rep.max_penetration_ratio = rep.max_penetration_ratio.max(-ev.gap / r.offset);
                rep.normal_force += ev.lambda;
                if ev.sliding {
                    rep.sliding += 1;
                    // Return mapping: the anchor trails the slave's projection by the slip at
                    // which the regularised force reaches tanh 2 of μλ, along the traction.
                    if let Some((tri, bary)) = ev.proj {
                        let s = &self.surfaces[r.surface];
                        let p = s.tris[tri].map(|a| model.x0[a] + state.u[a]);
                        let kt = (self.tangential_factor * r.k_n).min(self.mu * ev.lambda / (SLIP_MIN * r.size));
                        let tn = ev.tangential.norm();
                        let lag = SLIDE_ARG * self.mu * ev.lambda / kt;
                        let xp = p[0] * bary[0] + p[1] * bary[1] + p[2] * bary[2];
                        let target = if tn > 0.0 { xp + ev.tangential * (lag / tn) } else { xp };
                        let old = h.anchor.map(|(t, n)| {
                            let q = s.tris[t].map(|a| model.x0[a] + state.u[a]);
                            q[0] * n[0] + q[1] * n[1] + q[2] * n[2]
                        });
                        if let Some((nb, _)) = project(&p, &target) {
                            h.slip += old.map_or(0.0, |o| (target - o).norm());
                            h.anchor = Some((tri, nb));
                        }
                    }
                }
                h.sliding = ev.sliding;
                h.active = true;
                h.lagged = (ev.lambda, ev.normal);
            } else {
                rep.released += usize::from(h.active);
                h.active = false;
                h.sliding = false;
                h.lagged = (0.0, Vector3::zeros());
                // Out of contact: the anchor follows the projection, so friction counts the
                // slip from the last converged state once the node touches.
                h.anchor = ev.proj.or(h.anchor);
            }
            self.last[i] = ev;
        }
        self.increments.push(rep.clone());
        serde_json::to_value(serde_json::json!({ "interply": rep })).ok()
    }

    fn search_seconds(&self) -> f64 {
        self.search_s
    }

    /// `interply_pressure` (Pa: normal force over the slave's tributary area, summed over the
    /// adjacent plies), `interply_gap` (smallest gap to an adjacent ply within reach, m; 0
    /// where none) and `interply_status` (0 free, 1 stick, 2 slip).
    fn point_data(&self, model: &Model, _state: &State) -> Vec<(String, usize, Vec<f64>)> {
        let n = model.n_nodes();
        let (mut p, mut gap, mut status) = (vec![0.0; n], vec![f64::INFINITY; n], vec![0.0; n]);
        for (r, ev) in self.records.iter().zip(&self.last) {
            if ev.proj.is_some() {
                gap[r.node] = f64::min(gap[r.node], ev.gap);
            }
            if ev.active {
                p[r.node] += ev.lambda / r.area;
                status[r.node] = f64::max(status[r.node], if ev.sliding { 2.0 } else { 1.0 });
            }
        }
        gap.iter_mut().filter(|g| !g.is_finite()).for_each(|g| *g = 0.0);
        vec![("interply_pressure".into(), 1, p), ("interply_gap".into(), 1, gap), ("interply_status".into(), 1, status)]
    }

    fn summary(&self) -> Option<(String, serde_json::Value)> {
        let last = self.increments.last().cloned().unwrap_or_default();
        let max_pen = self.increments.iter().map(|r| r.max_penetration).fold(0.0, f64::max);
        let max_ratio = self.increments.iter().map(|r| r.max_penetration_ratio).fold(0.0, f64::max);
        let (k_min, k_max) = self.penalty_range();
        Some((
            "interply".into(),
            serde_json::json!({
                "plies": self.surfaces.iter().map(|s| s.part).collect::<Vec<_>>(),
                "pairs": self.records.len(),
                "friction": self.mu,
                "penalty_range": [k_min, k_max],
                "max_penetration": max_pen,
                "max_penetration_of_thickness": max_ratio,
                "active_pairs": last.active,
                "final": last,
                "search_s": self.search_s,
            }),
        ))
    }

    /// Each slave node with the nodes of the master quads within half its element size of
    /// its reference position, and those master nodes among themselves (friction couples a
    /// projection triangle with an anchor triangle in a neighbouring quad).
    fn couplings(&self, model: &Model) -> Vec<(usize, usize)> {
        let x0 = |a: usize| model.x0[a];
        let bvhs: Vec<Bvh> = self.surfaces.iter().map(|s| Bvh::from_leaves(BvhBuildStrategy::default(), &boxes(s, &x0))).collect();
        let mut out: Vec<(usize, usize)> = self
            .records
            .par_iter()
            .flat_map_iter(|r| {
                let y = model.x0[r.node];
                let reach = r.offset + 0.5 * r.size;
                let q = Aabb::new(pv(&y.add_scalar(-reach)), pv(&y.add_scalar(reach)));
                let s = &self.surfaces[r.surface];
                let mut near: Vec<usize> = bvhs[r.surface].intersect_aabb(&q).flat_map(|t| s.tris[t as usize]).collect();
                near.sort_unstable();
                near.dedup();
                let mut v = Vec::with_capacity(near.len() * (near.len() + 1));
                for &a in &near {
                    v.push((r.node.min(a), r.node.max(a)));
                    for &b in &near {
                        if a < b {
                            v.push((a, b));
                        }
                    }
                }
                v.into_iter()
            })
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }
}

/// The inter-ply contact of `setup` as a term of `solver` (its node-pair couplings enter the
/// tangent's pattern); a barrier setup refuses an intersecting start.
pub fn attach<'m>(solver: &mut crate::solver::Solver<'m>, model: &'m Model, setup: &InterplySetup) -> Result<(), String> {
    match &setup.barrier {
        Some(b) => crate::contact::ipc::attach(solver, model, b, &model.initial_state()),
        None => {
            solver.add_nodal_forces(Box::new(InterplyContact::new(model, setup)));
            Ok(())
        }
    }
}


#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene;

    const H: f64 = 0.001;
    const CLEAR: f64 = 1e-4;

    /// A 0.1 m master quad (part 0, z = 0) and a 1 cm slave quad (part 1, the first of the
    /// ply pair) whose nodes lie over the master's interior, its mid-surface H + CLEAR above (a clearance of CLEAR).
    fn pair() -> scene::BuiltScene {
        let text = format!(
            r#"Scene(name: "s", materials: {{"m": StVenantKirchhoff(young: 1.0e6, poisson: 0.3)}},
            parts: [(name: "master", mesh: Rectangle(lx: 0.1, ly: 0.1, nx: 1, ny: 1), material: "m", thickness: {H}),
                    (name: "slave", mesh: Rectangle(lx: 0.01, ly: 0.01, nx: 1, ny: 1), material: "m", thickness: {H},
                     offset: Some((0.03, 0.04, {z})))],
            steps: [(name: "a", increments: 1)])"#,
            z = H + CLEAR
        );
        let sc = scene::parse("s.ron", &text).unwrap();
        scene::build(&sc, "s.ron", &text).unwrap()
    }

    fn setup(friction: f64) -> InterplySetup {
        InterplySetup { ply_pairs: vec![(1, 0)], settings: InterplySettings { friction, ..Default::default() }, barrier: None }
    }

    /// Forces (all DOFs) and the dense Jacobian ∂f/∂x over the translations of `nodes`.
    fn forces_and_jacobian(c: &mut InterplyContact, model: &Model, st: &State, nodes: &[usize]) -> (Vec<f64>, Vec<Vec<f64>>) {
        let mut f = vec![0.0; NODE_DOFS * model.n_nodes()];
        let (mut jac, mut pairs) = (Vec::new(), Vec::new());
        c.add_coupled(model, st, &mut f, &mut jac, &mut pairs);
        let m = 3 * nodes.len();
        let mut j = vec![vec![0.0; m]; m];
        let idx = |a: usize| nodes.iter().position(|&b| b == a);
        let blocks = jac.iter().map(|(a, b)| (*a, *a, *b)).chain(pairs.iter().copied());
        for (a, b, blk) in blocks {
            let (Some(ia), Some(ib)) = (idx(a), idx(b)) else { panic!("block outside the involved nodes") };
            for p in 0..3 {
                for q in 0..3 {
                    j[3 * ia + p][3 * ib + q] += blk[(p, q)];
                }
            }
        }
        (f, j)
    }

    fn force(f: &[f64], a: usize) -> Vector3<f64> {
        Vector3::new(f[NODE_DOFS * a], f[NODE_DOFS * a + 1], f[NODE_DOFS * a + 2])
    }

    /// Penalty law (module doc): slave node 4 (at (0.03, 0.04)) pushed δ ≥ ε into the
    /// master's face gets k_n(δ − ε/2) along +z (the regularised law beyond its ramp), the master nodes −λ_j k_n δ with λ the barycentric
    /// coordinates of its projection in the master triangle under it; the sum is zero.
    #[test]
    fn one_node_against_one_element_follows_the_penalty_law() {
        let b = pair();
        let model = &b.model;
        let mut c = InterplyContact::new(model, &setup(0.0));
        let delta = 5e-5;
        let mut st = model.initial_state();
        st.u[4].z = -(CLEAR + delta);
        let (f, _) = forces_and_jacobian(&mut c, model, &st, &(0..8).collect::<Vec<_>>());
        let k = c.records.iter().find(|r| r.node == 4).unwrap().k_n;
        // Automatic penalty: A·a/ℓ² = E h for a node of a single square element.
        assert!((k - 1.0e6 * H * 0.25).abs() < 1e-9 * k, "k_n {k}");
        // Effective penetration beyond the ramp: δ − ε/2, ε = EPS_FRAC·H (H the contact distance).
        let delta = delta - 0.5 * EPS_FRAC * H;
        let fs = force(&f, 4);
        assert!((fs - Vector3::new(0.0, 0.0, k * delta)).norm() < 1e-9 * k * delta, "slave force {fs}");
        // (0.3, 0.4) of the unit square (scaled 0.1) lies in the triangle of corners
        // (0, 0), (1, 1), (0, 1) with λ = (0.6, 0.3, 0.1).
        for a in 0..4 {
            let p = model.x0[a] / 0.1;
            let l = match (p.x.round() as i32, p.y.round() as i32) {
                (0, 0) => 0.6,
                (1, 1) => 0.3,
                (0, 1) => 0.1,
                _ => 0.0,
            };
            let fa = force(&f, a);
            assert!((fa + Vector3::new(0.0, 0.0, l * k * delta)).norm() < 1e-9 * k * delta, "master node {a}: {fa}");
        }
        let total: Vector3<f64> = (0..8).map(|a| force(&f, a)).sum();
        assert!(total.norm() < 1e-12 * k * delta, "sum {total}");
        // The other slave nodes are clear of the master: no force.
        for a in 5..8 {
            assert_eq!(force(&f, a).norm(), 0.0);
        }
    }

    /// With friction the forces still sum to zero (action = reaction): a sliding slave.
    #[test]
    fn contact_forces_with_friction_sum_to_zero() {
        let b = pair();
        let model = &b.model;
        let mut c = InterplyContact::new(model, &setup(0.3));
        let mut st = model.initial_state();
        st.u[4] = Vector3::new(2e-3, -1e-3, -(CLEAR + 3e-5));
        st.u[2] = Vector3::new(1e-4, 2e-4, 1e-5);
        let (f, _) = forces_and_jacobian(&mut c, model, &st, &(0..8).collect::<Vec<_>>());
        let fs = force(&f, 4);
        let total: Vector3<f64> = (0..8).map(|a| force(&f, a)).sum();
        assert!(fs.x < 0.0 && fs.y > 0.0, "friction opposes the slip: {fs}");
        assert!(total.norm() < 1e-12 * fs.norm(), "sum {total} vs {fs}");
        assert!(c.last.iter().any(|e| e.sliding));
    }

    /// The Jacobian (diagonal and node-pair blocks) equals central differences of the forces
    /// (step 1e-9 m) to 1e-6 of its largest entry: frictionless, and sticking (penetration
    /// 50 µm, slip 1e-9 m far inside the elastic range μλ/k_t = 15 µm, where the regularised
    /// law is linear and k_t = k_n is not limited by the smallest elastic slip 10 µm).
    #[test]
    fn node_pair_tangent_matches_central_differences() {
        let b = pair();
        let model = &b.model;
        // Frictionless: the master also moves in its plane (the projection point moves);
        // sticking: only normal motions of the master, so the slip stays elastic.
        for (mu, slip, in_plane) in [(0.0, 0.0, 1e-4), (0.3, 1e-9, 0.0)] {
            let mut c = InterplyContact::new(model, &setup(mu));
            let mut st = model.initial_state();
            st.u[4] = Vector3::new(slip, 0.5 * slip, -(CLEAR + 5e-5));
            st.u[0] = Vector3::new(0.0, 0.0, 3e-6);
            st.u[3] = Vector3::new(0.0, in_plane, -2e-6);
            let nodes = [4, 0, 2, 3];
            let (_, j) = forces_and_jacobian(&mut c, model, &st, &nodes);
            let scale = j.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
            let eps = 1e-9;
            let mut worst = 0.0f64;
            for (ib, &b) in nodes.iter().enumerate() {
                for q in 0..3 {
                    let mut plus = st.clone();
                    plus.u[b][q] += eps;
                    let mut minus = st.clone();
                    minus.u[b][q] -= eps;
                    let (fp, _) = forces_and_jacobian(&mut c, model, &plus, &nodes);
                    let (fm, _) = forces_and_jacobian(&mut c, model, &minus, &nodes);
                    for (ia, &a) in nodes.iter().enumerate() {
                        for p in 0..3 {
                            let fd = (fp[NODE_DOFS * a + p] - fm[NODE_DOFS * a + p]) / (2.0 * eps);
                            worst = worst.max((fd - j[3 * ia + p][3 * ib + q]).abs());
                        }
                    }
                }
            }
            println!("μ = {mu}: largest |J − J_fd| = {:.2e} of max |J| = {scale:.3e}", worst / scale);
            assert!(worst < 1e-6 * scale, "μ = {mu}: {worst} vs {scale}");
        }
    }

    /// The slave lies on the +z side of the master in the reference; a slave node pushed
    /// through the master's mid-surface is still pushed back up (two-sided safe).
    #[test]
    fn a_node_that_crossed_is_pushed_back() {
        let b = pair();
        let model = &b.model;
        let mut c = InterplyContact::new(model, &setup(0.0));
        let mut st = model.initial_state();
        st.u[4].z = -(H + CLEAR) - 2e-4;
        let (f, _) = forces_and_jacobian(&mut c, model, &st, &(0..8).collect::<Vec<_>>());
        assert!(force(&f, 4).z > 0.0, "{}", force(&f, 4));
    }
}
