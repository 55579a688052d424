//! Contact between shell surfaces — ply against ply and a ply against itself — as a sum of
//! smooth barrier potentials over point–triangle and edge–edge pairs of the triangulated
//! mid-surfaces (Li et al., *Incremental Potential Contact*, ACM Trans. Graph. 39(4), 2020;
//! Li, Kaufman & Jiang, *Codimensional Incremental Potential Contact*, ACM Trans. Graph.
//! 40(4), 2021, for shells with thickness).
//!
//! Each quad is split into two triangles along its 1–3 diagonal; every triangle edge is an
//! edge. A pair's gap is d = dist − c_p, dist the distance between the primitives'
//! mid-surface positions and c_p its contact offset; its energy is κ_p m_p b(d, d̂_p) with the
//! log barrier b of IPC (eq. 6) and, for edge–edge pairs, the mollifier m_p of nearly
//! parallel edges (IPC supplement eq. 17; 1 otherwise). Summed over all pairs the energy is
//! smooth as a node slides from facet to facet: there is no closest facet to switch.
//!
//! Offsets: with c = h_a/2 + h_b/2 (the two plies' half thicknesses) and D⁰ the pair's
//! distance in the reference configuration, c̄ = min(c, D⁰) (the facets of stacked curved
//! plies lie on chords, closer than c), d̂_p = f c̄ and c_p = c̄ − d̂_p, f = `distance_factor`.
//! Plies stacked at their thickness spacing therefore start at d = d̂_p, just outside the
//! barrier, and are never pressed closer than (1 − f) of their thickness (the through-
//! thickness compliance of fabric, lumped into the barrier). Pairs sharing a node, a quad, or
//! nodes joined by a tie (seams, stitch lines, ply links) are excluded, and so are pairs
//! coincident in the reference.
//!
//! Stiffness: κ_a = 10 w_a / d̂_a per node (w_a the node's weight, or E h ℓ × 10⁻⁶ when
//! massless), κ_p the mean over the pair's nodes; doubled for every node of a pair found at a
//! converged state closer than 5 % of d̂_p (IPC §4.3) or compressed (d̂_p − d) by more than
//! `compression_tolerance` of the thinner ply's thickness — so a pressed stack settles to
//! within that tolerance of its thickness. The tangent is the exact Hessian (see `evaluate`).
//!
//! Friction: lagged smoothed Coulomb friction (IPC §5) on the relative position r = Σ w̄_k x_k
//! of the pair's closest points, with the weights w̄, normal n̄ and normal force λ̄ of the last
//! converged state: slip s = (I − n̄n̄ᵀ)(r − r̂) from an anchor r̂ (where it stuck), potential
//! μλ̄ δ ln cosh(|s|/δ), δ = `friction_slip` × d̂_p; a sliding pair's anchor trails r on
//! commit (return mapping), as for rigid bodies (`barrier.rs`).
//!
//! Collision detection: every Newton step is shortened to the largest fraction along which no
//! pair's gap falls below 10 % of its value (conservative advancement with the bound
//! |Δdist| ≤ max|Δx| of each primitive's nodes; the additive CCD of Li, Kaufman & Jiang 2021
//! in its plain form).

use std::collections::HashMap;
use std::time::Instant;

use nalgebra::{Matrix3, SMatrix, Vector3};
use rayon::prelude::*;
use serde::Serialize;

use super::broad_phase::candidates;
use super::friction::{Friction, FrictionTerm};
use super::primitives::{cross_squared, edge_edge_feature, mollifier, point_triangle_feature, squared_distance, squared_distance_value, Feature};
use crate::contact::barrier::barrier;
use crate::element::NODE_DOFS;
use crate::model::{Model, State};
use crate::solver::NodalForces;

/// Initial κ_a d̂_a / w_a (as for rigid bodies).
const INITIAL_STIFFNESS: f64 = 10.0;
/// A pair closer than this fraction of d̂ at a converged state doubles its nodes' κ.
const ADAPT_GAP: f64 = 0.05;
/// Bound on the adaptive growth of κ.
const MAX_KAPPA_GROWTH: f64 = 1e6;
/// Fraction of a pair's gap one step may close.
const CCD_CLOSE: f64 = 0.9;
/// A sliding pair's anchor trails where tanh(|s|/δ) = tanh 2.
const SLIDE_ARG: f64 = 2.0;
/// Edge–edge mollifier threshold ε = 10⁻³ |e_a|²|e_b|² (reference lengths), as in IPC.
const MOLLIFIER: f64 = 1e-3;

/// Surface contact controls.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SurfaceSettings {
    /// Barrier thickness d̂ as a fraction f of the contact distance c̄ (0 < f < 1).
    pub distance_factor: f64,
    /// Factor on the automatic barrier stiffness.
    pub stiffness_factor: f64,
    /// Coulomb friction coefficient between surfaces.
    pub friction: f64,
    /// Stick regularisation δ of the friction as a multiple of d̂.
    pub friction_slip: f64,
    /// Whether a part's surface also contacts itself (folds).
    pub self_contact: bool,
    /// Largest compression of the plies' thickness, as a fraction of the thinner ply's
    /// thickness, that a converged state may show before its nodes' κ is doubled.
    pub compression_tolerance: f64,
}

impl Default for SurfaceSettings {
    /// d̂ = 0.2 c̄, κ factor 1, friction 0.3 (woven fabrics on each other measure about
    /// 0.2–0.5, e.g. Ajayi 1992, *Textile Res. J.* 62), δ = d̂, self-contact on.
    fn default() -> Self {
        Self { distance_factor: 0.2, stiffness_factor: 1.0, friction: 0.3, friction_slip: 1.0, self_contact: true, compression_tolerance: 0.05 }
    }
}

impl SurfaceSettings {
    /// The first setting out of range: (key, what was expected).
    pub fn problem(&self) -> Option<(&'static str, &'static str)> {
        let pos = |x: f64| x.is_finite() && x > 0.0;
        if !(pos(self.distance_factor) && self.distance_factor < 1.0) {
            return Some(("distance_factor", "expected a barrier thickness factor between 0 and 1 (exclusive)"));
        }
        if !pos(self.stiffness_factor) {
            return Some(("stiffness_factor", "expected a positive stiffness factor"));
        }
        if !(self.friction.is_finite() && self.friction >= 0.0) {
            return Some(("friction", "expected a non-negative friction coefficient"));
        }
        if !pos(self.friction_slip) {
            return Some(("friction_slip", "expected a positive stick regularisation factor"));
        }
        if !pos(self.compression_tolerance) {
            return Some(("compression_tolerance", "expected a positive fraction of the ply thickness"));
        }
        None
    }
}

/// Which parts take part in surface contact, with the controls.
#[derive(Clone, Debug)]
pub struct SurfaceSetup {
    /// Model part indices (every pair of them, and each with itself when self-contact is on).
    pub parts: Vec<usize>,
    /// Controls.
    pub settings: SurfaceSettings,
}

/// Kind of a pair.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) enum Kind {
    PointTriangle,
    EdgeEdge,
}

/// Reference constants of a pair.
#[derive(Clone, Copy, Debug)]
struct Constants {
    offset: f64,
    dhat: f64,
    /// Mollifier threshold (edge–edge), 0 for point–triangle.
    eps: f64,
}

/// Evaluation of one active pair.
#[derive(Clone, Debug)]
struct Term {
    kind: Kind,
    key: (usize, usize),
    nodes: [usize; 4],
    gap: f64,
    dhat: f64,
    /// Thickness of the thinner ply of the pair.
    thin: f64,
    energy: f64,
    /// Normal force λ = −∂E/∂d.
    force: f64,
    normal: Vector3<f64>,
    weights: [f64; 4],
    grad: [f64; 12],
    hess: Option<Box<SMatrix<f64, 12, 12>>>,
}

/// Per converged state: active pairs and forces.
#[derive(Clone, Debug, Default, Serialize)]
pub struct SurfaceIncrement {
    /// Point–triangle pairs within their barrier thickness.
    pub point_triangle: usize,
    /// Edge–edge pairs within their barrier thickness.
    pub edge_edge: usize,
    /// Active pairs per contact node.
    pub pairs_per_node: f64,
    /// Smallest gap (m) over the active pairs.
    pub min_gap: f64,
    /// Smallest gap as a fraction of its pair's d̂.
    pub min_gap_ratio: f64,
    /// Sum of the pairs' normal forces (N).
    pub normal_force: f64,
    /// Pairs with friction sliding.
    pub sliding: usize,
    /// Contact potential (barrier and friction), J.
    pub potential: f64,
    /// Nodes whose κ was doubled at this state.
    pub stiffened: usize,
}

/// Barrier contact between shell surfaces (a [`NodalForces`] term).
pub struct SurfaceContact {
    x_ref: Vec<Vector3<f64>>,
    points: Vec<usize>,
    tris: Vec<[usize; 3]>,
    tri_quad: Vec<usize>,
    edges: Vec<[usize; 2]>,
    edge_quads: Vec<[usize; 2]>,
    quad_reps: Vec<[usize; 4]>,
    quad_part: Vec<usize>,
    rep: Vec<usize>,
    part_of: Vec<usize>,
    half: Vec<f64>,
    area: Vec<f64>,
    kappa: Vec<f64>,
    kappa0: Vec<f64>,
    settings: SurfaceSettings,
    reach: f64,
    friction: HashMap<(Kind, usize, usize), Friction>,
    last: Vec<Term>,
    last_potential: f64,
    search_s: f64,
    /// Per-converged-state reports.
    pub increments: Vec<SurfaceIncrement>,
}

fn find(rep: &mut [usize], a: usize) -> usize {
    let mut r = a;
    while rep[r] != r {
        r = rep[r];
    }
    let mut b = a;
    while rep[b] != r {
        let next = rep[b];
        rep[b] = r;
        b = next;
    }
    r
}

impl SurfaceContact {
    /// Surface contact of `setup.parts` of `model`.
    pub fn new(model: &Model, setup: &SurfaceSetup) -> Self {
        let gravity = 9.80665;
        let n = model.n_nodes();
        let mut rep: Vec<usize> = (0..n).collect();
        for t in &model.dofs.ties {
            let s = t.slave / NODE_DOFS;
            for m in t.masters.iter().map(|&(m, _)| m / NODE_DOFS).chain(t.links.iter().map(|&(m, _)| m)) {
                let (a, b) = (find(&mut rep, s), find(&mut rep, m));
                if a != b {
                    rep[a.max(b)] = a.min(b);
                }
            }
        }
        let rep: Vec<usize> = (0..n).map(|a| find(&mut rep, a)).collect();
        let mut part_of = vec![usize::MAX; n];
        let mut half = vec![0.0f64; n];
        let mut area = vec![0.0f64; n];
        let mut weight = vec![0.0f64; n];
        let mut stiff = vec![0.0f64; n];
        let (mut tris, mut tri_quad, mut quad_reps, mut quad_part) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut edge_map: HashMap<(usize, usize), [usize; 2]> = HashMap::new();
        for &p in &setup.parts {
            let info = &model.parts[p];
            for e in info.first_element..info.first_element + info.n_elements {
                let def = &model.elements[e];
                let sec = &model.sections[def.section];
                let a_el = model.element(e).reference_area();
                let (young, _) = sec.material.small_strain_moduli();
                let q = quad_reps.len();
                let nd = def.nodes;
                for &a in &nd {
                    part_of[a] = p;
                    half[a] = half[a].max(0.5 * sec.thickness);
                    area[a] += 0.25 * a_el;
                    weight[a] += 0.25 * a_el * info.areal_density * gravity;
                    stiff[a] = stiff[a].max(young * sec.thickness * a_el.sqrt());
                }
                quad_reps.push(nd.map(|a| rep[a]));
                quad_part.push(p);
                for t in [[nd[0], nd[1], nd[2]], [nd[0], nd[2], nd[3]]] {
                    tris.push(t);
                    tri_quad.push(q);
                    for k in 0..3 {
                        let (a, b) = (t[k], t[(k + 1) % 3]);
                        let slot = edge_map.entry((a.min(b), a.max(b))).or_insert([usize::MAX; 2]);
                        if slot[0] == usize::MAX {
                            slot[0] = q;
                        } else if slot[0] != q {
                            slot[1] = q;
                        }
                    }
                }
            }
        }
        let mut edge_list: Vec<((usize, usize), [usize; 2])> = edge_map.into_iter().collect();
        edge_list.sort_unstable_by_key(|e| e.0);
        let edges: Vec<[usize; 2]> = edge_list.iter().map(|((a, b), _)| [*a, *b]).collect();
        let edge_quads: Vec<[usize; 2]> = edge_list.iter().map(|(_, q)| *q).collect();
        let points: Vec<usize> = (0..n).filter(|&a| part_of[a] != usize::MAX).collect();
        let f = setup.settings.distance_factor;
        let kappa: Vec<f64> = (0..n)
            .map(|a| {
                if part_of[a] == usize::MAX {
                    return 0.0;
                }
                let w = if weight[a] > 0.0 { weight[a] } else { 1e-6 * stiff[a] };
                INITIAL_STIFFNESS * setup.settings.stiffness_factor * w / (f * 2.0 * half[a]).max(f64::MIN_POSITIVE)
            })
            .collect();
        let reach = 2.0 * half.iter().copied().fold(0.0, f64::max);
        Self {
            x_ref: model.x0.clone(),
            points,
            tris,
            tri_quad,
            edges,
            edge_quads,
            quad_reps,
            quad_part,
            rep,
            part_of,
            half,
            area,
            kappa0: kappa.clone(),
            kappa,
            settings: setup.settings.clone(),
            reach,
            friction: HashMap::new(),
            last: Vec::new(),
            last_potential: 0.0,
            search_s: 0.0,
            increments: Vec::new(),
        }
    }

    /// Number of contact nodes, triangles and edges.
    pub fn sizes(&self) -> (usize, usize, usize) {
        (self.points.len(), self.tris.len(), self.edges.len())
    }

    fn point_ok(&self, i: usize, t: usize) -> bool {
        let p = self.points[i];
        let q = self.tri_quad[t];
        (self.settings.self_contact || self.part_of[p] != self.quad_part[q]) && !self.quad_reps[q].contains(&self.rep[p])
    }

    fn edge_ok(&self, a: usize, b: usize) -> bool {
        let (ea, eb) = (self.edges[a], self.edges[b]);
        if !self.settings.self_contact && self.part_of[ea[0]] == self.part_of[eb[0]] {
            return false;
        }
        let (ra, rb) = (ea.map(|n| self.rep[n]), eb.map(|n| self.rep[n]));
        if ra.iter().any(|r| rb.contains(r)) {
            return false;
        }
        let (qa, qb) = (self.edge_quads[a], self.edge_quads[b]);
        !qa.iter().any(|&q| q != usize::MAX && qb.contains(&q))
    }

    fn nodes(&self, kind: Kind, key: (usize, usize)) -> [usize; 4] {
        match kind {
            Kind::PointTriangle => {
                let t = self.tris[key.1];
                [self.points[key.0], t[0], t[1], t[2]]
            }
            Kind::EdgeEdge => {
                let (a, b) = (self.edges[key.0], self.edges[key.1]);
                [a[0], a[1], b[0], b[1]]
            }
        }
    }

    fn feature(kind: Kind, x: &[Vector3<f64>; 4]) -> (Feature, [f64; 4]) {
        match kind {
            Kind::PointTriangle => point_triangle_feature(x),
            Kind::EdgeEdge => edge_edge_feature(x),
        }
    }

    /// Reference constants of the pair on `nodes`; None for a pair coincident in the
    /// reference (excluded).
    fn constants(&self, kind: Kind, nodes: &[usize; 4]) -> Option<Constants> {
        let xr = nodes.map(|a| self.x_ref[a]);
        let (feat, _) = Self::feature(kind, &xr);
        let dref = squared_distance_value(feat, &xr).sqrt();
        let h = nodes.map(|a| self.half[a]);
        let c = match kind {
            Kind::PointTriangle => h[0] + h[1].max(h[2]).max(h[3]),
            Kind::EdgeEdge => h[0].max(h[1]) + h[2].max(h[3]),
        };
        let cm = c.min(dref);
        if !(cm > 1e-6 * c) {
            return None;
        }
        let dhat = self.settings.distance_factor * cm;
        let eps = match kind {
            Kind::PointTriangle => 0.0,
            Kind::EdgeEdge => MOLLIFIER * (xr[1] - xr[0]).norm_squared() * (xr[3] - xr[2]).norm_squared(),
        };
        Some(Constants { offset: cm - dhat, dhat, eps })
    }

    /// Candidate pairs near configuration(s) `configs`, with their nodes and constants.
    fn pairs(&self, configs: &[&dyn Fn(usize) -> Vector3<f64>], reach: f64) -> Vec<(Kind, (usize, usize), [usize; 4], Constants)> {
        let (pt, ee) = candidates(&self.points, &self.tris, &self.edges, configs, reach, &|i, t| self.point_ok(i, t), &|a, b| self.edge_ok(a, b));
        pt.into_iter()
            .map(|k| (Kind::PointTriangle, k))
            .chain(ee.into_iter().map(|k| (Kind::EdgeEdge, k)))
            .collect::<Vec<_>>()
            .into_par_iter()
            .filter_map(|(kind, key)| {
                let nodes = self.nodes(kind, key);
                self.constants(kind, &nodes).map(|c| (kind, key, nodes, c))
            })
            .collect()
    }

    /// The active pairs at `state` (gap below d̂), with energy, gradient and — when
    /// `hessian` — the PSD-projected Hessian. A pair at or through zero gap has infinite energy.
    fn evaluate(&self, model: &Model, state: &State, hessian: bool) -> Vec<Term> {
        let x = |a: usize| model.x0[a] + state.u[a];
        self.pairs(&[&x], self.reach)
            .into_par_iter()
            .filter_map(|(kind, key, nodes, c)| {
                let xs = nodes.map(x);
                let (feat, weights) = Self::feature(kind, &xs);
                let dist = squared_distance_value(feat, &xs).sqrt();
                let gap = dist - c.offset;
                if gap >= c.dhat {
                    return None;
                }
                let kap = nodes.iter().map(|&a| self.kappa[a]).sum::<f64>() / 4.0;
                let r: Vector3<f64> = (0..4).map(|k| xs[k] * weights[k]).sum();
                let normal = if dist > 0.0 { r / dist } else { Vector3::zeros() };
                let thin = 2.0 * nodes.iter().map(|&a| self.half[a]).fold(f64::INFINITY, f64::min);
                let mut term = Term { kind, key, nodes, gap, dhat: c.dhat, thin, energy: f64::INFINITY, force: f64::INFINITY, normal, weights, grad: [0.0; 12], hess: None };
                if gap <= 0.0 {
                    return Some(term);
                }
                let (b, b1, b2) = barrier(gap, c.dhat);
                // κ b(√s − c_p) (× m(|e_a × e_b|²) for nearly parallel edges) in second-order
                // automatic differentiation: the exact gradient and Hessian. The Hessian is
                // not projected: a pair pressed onto a vertex or an edge of the other surface
                // has a negative tangential stiffness κ b′ ∇²dist (the force turns as the point
                // slides), and Newton without it stalls where plies slide on each other
                // (the NBC sleeve in a static step stopped at a residual of 10⁻⁶ with a
                // projected or Gauss–Newton tangent; it converges with the exact one).
                let sd = squared_distance(feat, &xs);
                let (dd, ddd) = (0.5 / dist, -0.25 / (dist * dist * dist));
                let mut e = sd.chain(kap * b, kap * b1 * dd, kap * (b2 * dd * dd + b1 * ddd));
                let mut m = 1.0;
                if kind == Kind::EdgeEdge {
                    let (u, v) = (xs[1] - xs[0], xs[3] - xs[2]);
                    if u.cross(&v).norm_squared() < c.eps {
                        let cs = cross_squared(&xs);
                        let (mv, m1, m2) = mollifier(cs.v, c.eps);
                        m = mv;
                        e = e * cs.chain(mv, m1, m2);
                    }
                }
                term.energy = e.v;
                term.force = -kap * m * b1;
                term.grad = e.g;
                if hessian {
                    term.hess = Some(Box::new(SMatrix::<f64, 12, 12>::from_fn(|i, j| 0.5 * (e.h[i][j] + e.h[j][i]))));
                }
                Some(term)
            })
            .collect()
    }

    /// Friction potentials of the committed pairs at `x`.
    fn friction_terms(&self, x: &(dyn Fn(usize) -> Vector3<f64> + Sync), hessian: bool) -> Vec<FrictionTerm> {
        super::friction::terms(&self.friction, self.settings.friction, x, hessian)
    }

    /// Pairs closer than zero gap at `state` (start intersecting): (nodes, gap).
    pub fn intersections(&self, model: &Model, state: &State) -> Vec<([usize; 4], f64)> {
        self.evaluate(model, state, false).into_iter().filter(|t| t.gap <= 0.0).map(|t| (t.nodes, t.gap)).collect()
    }

    /// Smallest gap over the active pairs of the last evaluation.
    pub fn min_gap(&self) -> Option<f64> {
        self.last.iter().map(|t| t.gap).reduce(f64::min)
    }
}

/// Accumulates a pair's gradient and Hessian: forces −∇E into `f_ext`, blocks −∇²E per node
/// (`diag`) and per node pair a < b (`off`, the block of row a, column b).
fn scatter(nodes: &[usize; 4], grad: &[f64; 12], hess: Option<&SMatrix<f64, 12, 12>>, f_ext: &mut [f64], diag: &mut HashMap<usize, Matrix3<f64>>, off: &mut HashMap<(usize, usize), Matrix3<f64>>) {
    for (k, &a) in nodes.iter().enumerate() {
        for c in 0..3 {
            f_ext[NODE_DOFS * a + c] -= grad[3 * k + c];
        }
    }
    let Some(h) = hess else { return };
    for (i, &a) in nodes.iter().enumerate() {
        for (j, &b) in nodes.iter().enumerate() {
            if a > b || (a == b && i != j) {
                continue;
            }
            let block = Matrix3::from_fn(|p, q| h[(3 * i + p, 3 * j + q)]);
            if a == b {
                *diag.entry(a).or_insert_with(Matrix3::zeros) -= block;
            } else {
                *off.entry((a, b)).or_insert_with(Matrix3::zeros) -= block;
            }
        }
    }
}

impl NodalForces for SurfaceContact {
    fn add(&mut self, model: &Model, state: &State, f_ext: &mut [f64], jacobian: &mut Vec<(usize, Matrix3<f64>)>) {
        let mut pairs = Vec::new();
        self.add_coupled(model, state, f_ext, jacobian, &mut pairs);
        // Without pair blocks only the diagonal ones remain (a lumped tangent).
    }

    fn add_coupled(&mut self, model: &Model, state: &State, f_ext: &mut [f64], jacobian: &mut Vec<(usize, Matrix3<f64>)>, pairs: &mut Vec<(usize, usize, Matrix3<f64>)>) {
        let t = Instant::now();
        let terms = self.evaluate(model, state, true);
        let x = |a: usize| model.x0[a] + state.u[a];
        let fr = self.friction_terms(&x, true);
        self.search_s += t.elapsed().as_secs_f64();
        let mut pot = 0.0;
        let (mut diag, mut off) = (HashMap::new(), HashMap::new());
        for term in &terms {
            if !term.energy.is_finite() {
                // Through the offset surface: inadmissible (the line search backs off).
                f_ext[NODE_DOFS * term.nodes[0]] = f64::NAN;
                pot = f64::INFINITY;
                continue;
            }
            pot += term.energy;
            scatter(&term.nodes, &term.grad, term.hess.as_deref(), f_ext, &mut diag, &mut off);
        }
        for ft in &fr {
            pot += ft.energy;
            scatter(&ft.nodes, &ft.grad, ft.hess.as_ref(), f_ext, &mut diag, &mut off);
        }
        jacobian.extend(diag);
        // The solver adds the symmetric part −½(J + Jᵀ) of a pushed block J at (a, b) and
        // (b, a): pushing 2J once for a < b gives J at (a, b) and Jᵀ at (b, a).
        pairs.extend(off.into_iter().map(|((a, b), j)| (a, b, j * 2.0)));
        self.last = terms;
        self.last_potential = pot;
    }

    fn potential(&self) -> Option<f64> {
        Some(self.last_potential)
    }

    fn is_barrier(&self) -> bool {
        true
    }

    /// Additive CCD in its plain form: along the straight move from `from` to `to`, a pair's
    /// distance falls at most by the sum of its two primitives' largest nodal moves per unit
    /// of the step, so from a gap g it may advance by (g − g_min)/ℓ, g_min = (1 − CCD_CLOSE) g₀,
    /// repeatedly; the smallest fraction over all candidate pairs of the sweep is the bound.
    fn max_step(&self, model: &Model, from: &State, to: &State) -> f64 {
        let x0 = |a: usize| model.x0[a] + from.u[a];
        let x1 = |a: usize| model.x0[a] + to.u[a];
        let s = self
            .pairs(&[&x0, &x1], self.reach)
            .into_par_iter()
            .map(|(kind, _, nodes, c)| {
                let a = nodes.map(x0);
                let d: [Vector3<f64>; 4] = std::array::from_fn(|k| x1(nodes[k]) - a[k]);
                let (m1, m2) = match kind {
                    Kind::PointTriangle => (d[0].norm(), d[1].norm().max(d[2].norm()).max(d[3].norm())),
                    Kind::EdgeEdge => (d[0].norm().max(d[1].norm()), d[2].norm().max(d[3].norm())),
                };
                let len = m1 + m2;
                if len == 0.0 {
                    return 1.0;
                }
                let gap_at = |s: f64| {
                    let xs: [Vector3<f64>; 4] = std::array::from_fn(|k| a[k] + d[k] * s);
                    let (feat, _) = Self::feature(kind, &xs);
                    squared_distance_value(feat, &xs).sqrt() - c.offset
                };
                let g0 = gap_at(0.0);
                if g0 <= 0.0 {
                    return 0.0;
                }
                let gmin = (1.0 - CCD_CLOSE) * g0;
                let (mut s, mut g) = (0.0f64, g0);
                for _ in 0..100 {
                    let ds = (g - gmin) / len;
                    if s + ds >= 1.0 {
                        return 1.0;
                    }
                    s += ds;
                    if ds < 1e-6 {
                        break;
                    }
                    g = gap_at(s);
                    if g <= gmin * 1.000_001 {
                        break;
                    }
                }
                s
            })
            .reduce(|| 1.0, f64::min);
        s
    }

    fn commit(&mut self, model: &Model, state: &State) -> Option<serde_json::Value> {
        let t = Instant::now();
        let terms = self.evaluate(model, state, false);
        let x = |a: usize| model.x0[a] + state.u[a];
        let fr = self.friction_terms(&x, false);
        self.search_s += t.elapsed().as_secs_f64();
        let mut rep = SurfaceIncrement { min_gap: f64::INFINITY, min_gap_ratio: f64::INFINITY, ..Default::default() };
        // Sliding pairs' anchors trail (return mapping); others keep theirs.
        let mut old = std::mem::take(&mut self.friction);
        for ft in fr {
            rep.potential += ft.energy;
            let Some(h) = old.get_mut(&ft.key) else { continue };
            h.sliding = ft.force.norm() > self.settings.friction * h.force * SLIDE_ARG.tanh();
            if h.sliding {
                let r: Vector3<f64> = (0..4).map(|j| x(h.nodes[j]) * h.weights[j]).sum();
                let p = Matrix3::identity() - h.normal * h.normal.transpose();
                let s = p * (r - h.anchor);
                let sn = s.norm();
                if sn > 0.0 {
                    // The anchor trails the slip by 2δ (return mapping).
                    let trail = s * (SLIDE_ARG * h.delta / sn);
                    h.slip += sn - trail.norm();
                    h.anchor = r - trail;
                }
            }
        }
        let mut stiffen = Vec::new();
        for term in &terms {
            match term.kind {
                Kind::PointTriangle => rep.point_triangle += 1,
                Kind::EdgeEdge => rep.edge_edge += 1,
            }
            rep.potential += term.energy;
            rep.normal_force += term.force;
            rep.min_gap = rep.min_gap.min(term.gap);
            rep.min_gap_ratio = rep.min_gap_ratio.min(term.gap / term.dhat);
            if term.gap < ADAPT_GAP * term.dhat || term.dhat - term.gap > self.settings.compression_tolerance * term.thin {
                stiffen.extend(term.nodes);
            }
            let prev = old.remove(&(term.kind, term.key.0, term.key.1));
            let pr = Matrix3::identity() - term.normal * term.normal.transpose();
            let r_of = |w: &[f64; 4]| -> Vector3<f64> { (0..4).map(|k| x(term.nodes[k]) * w[k]).sum() };
            // A stuck pair keeps the weights of its anchor (the material points where it
            // stuck), so its slip accumulates across steps; a sliding or new pair takes the
            // current closest points, the sliding one with its anchor trailing as before.
            let (weights, anchor) = match &prev {
                Some(p) if !p.sliding => {
                    let r = r_of(&p.weights);
                    (p.weights, r - pr * (r - p.anchor))
                }
                Some(p) => {
                    let (r_old, r) = (r_of(&p.weights), r_of(&term.weights));
                    (term.weights, r - pr * (r_old - p.anchor))
                }
                None => (term.weights, r_of(&term.weights)),
            };
            let (sliding, slip) = prev.as_ref().map_or((false, 0.0), |p| (p.sliding, p.slip));
            if sliding {
                rep.sliding += 1;
            }
            self.friction.insert(
                (term.kind, term.key.0, term.key.1),
                Friction { nodes: term.nodes, weights, normal: term.normal, force: term.force, anchor, delta: self.settings.friction_slip * term.dhat, sliding, slip },
            );
        }
        stiffen.sort_unstable();
        stiffen.dedup();
        for a in stiffen {
            if self.kappa[a] < MAX_KAPPA_GROWTH * self.kappa0[a] {
                self.kappa[a] *= 2.0;
                rep.stiffened += 1;
            }
        }
        if terms.is_empty() {
            rep.min_gap = 0.0;
            rep.min_gap_ratio = 0.0;
        }
        rep.pairs_per_node = terms.len() as f64 / self.points.len().max(1) as f64;
        self.last = terms;
        self.increments.push(rep.clone());
        serde_json::to_value(serde_json::json!({ "surface_contact": rep })).ok()
    }

    fn search_seconds(&self) -> f64 {
        self.search_s
    }

    /// `ply_contact_pressure` (Pa: each pair's normal force shared over its nodes by their
    /// closest-point weights, per tributary area) and `ply_contact_gap` (smallest gap of an
    /// active pair at the node, m; 0 when none).
    fn point_data(&self, model: &Model, _state: &State) -> Vec<(String, usize, Vec<f64>)> {
        let n = model.n_nodes();
        let (mut p, mut gap) = (vec![0.0; n], vec![0.0; n]);
        for t in &self.last {
            for k in 0..4 {
                let a = t.nodes[k];
                if self.area[a] > 0.0 && t.force.is_finite() {
                    p[a] += 0.5 * t.force * t.weights[k].abs() / self.area[a];
                }
                if t.weights[k] != 0.0 {
                    gap[a] = if gap[a] == 0.0 { t.gap } else { gap[a].min(t.gap) };
                }
            }
        }
        vec![("ply_contact_pressure".into(), 1, p), ("ply_contact_gap".into(), 1, gap)]
    }

    fn summary(&self) -> Option<(String, serde_json::Value)> {
        let last = self.increments.last().cloned().unwrap_or_default();
        let active: Vec<&SurfaceIncrement> = self.increments.iter().filter(|r| r.point_triangle + r.edge_edge > 0).collect();
        let min_ratio = active.iter().map(|r| r.min_gap_ratio).fold(f64::INFINITY, f64::min);
        let max_pairs = self.increments.iter().map(|r| r.pairs_per_node).fold(0.0, f64::max);
        let (kmin, kmax) = self.points.iter().map(|&a| self.kappa[a]).fold((f64::INFINITY, 0.0f64), |(a, b), k| (a.min(k), b.max(k)));
        Some((
            "surface_contact".into(),
            serde_json::json!({
                "formulation": "barrier (point-triangle and edge-edge)",
                "nodes": self.points.len(),
                "triangles": self.tris.len(),
                "edges": self.edges.len(),
                "self_contact": self.settings.self_contact,
                "friction": self.settings.friction,
                "barrier_stiffness_range": [kmin, kmax],
                "min_gap_ratio": if min_ratio.is_finite() { min_ratio } else { 0.0 },
                "max_pairs_per_node": max_pairs,
                "final": last,
                "search_s": self.search_s,
            }),
        ))
    }

    fn couplings(&self, model: &Model) -> Vec<(usize, usize)> {
        let x = |a: usize| model.x0[a];
        let mut out: Vec<(usize, usize)> = self
            .pairs(&[&x], 2.0 * self.reach)
            .into_iter()
            .flat_map(|(_, _, nodes, _)| {
                let mut v = Vec::with_capacity(6);
                for i in 0..4 {
                    for j in i + 1..4 {
                        v.push((nodes[i].min(nodes[j]), nodes[i].max(nodes[j])));
                    }
                }
                v
            })
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }
}

/// Surface contact of `setup` as a term of `solver`; refuses a start where a pair is
/// already closer than its contact offset (the plies intersect).
pub fn attach<'m>(solver: &mut crate::solver::Solver<'m>, model: &'m Model, setup: &SurfaceSetup, state: &State) -> Result<(), String> {
    let term = SurfaceContact::new(model, setup);
    if let Some((nodes, gap)) = term.intersections(model, state).first() {
        return Err(format!(
            "surface contact: the start intersects — nodes {:?} (parts {:?}) are {:.3e} m inside their contact distance; move the plies apart or lower distance_factor",
            nodes,
            nodes.map(|a| model.parts.get(term.part_of[a]).map_or("?", |p| p.name.as_str())),
            -gap
        ));
    }
    solver.add_nodal_forces(Box::new(term));
    Ok(())
}
