//! Node-to-rigid-body contact as a smooth barrier potential (Incremental Potential Contact,
//! Li et al., ACM Trans. Graph. 39(4), 2020, §4–5; Li, Kaufman & Jiang, *Codimensional IPC*,
//! ACM Trans. Graph. 40(4), 2021, for thin shells).
//!
//! Gap of node a with body b: d = d_b(x_a) − h_a/2 (the shell face, not the mid-surface,
//! touches the body; d_b the body's signed distance). The contact energy is
//!
//!   B = Σ κ_a b(d),  b(d) = −(d − d̂)² ln(d/d̂) for 0 < d < d̂, 0 for d ≥ d̂ (IPC eq. 6),
//!
//! C² at d̂ and unbounded as d → 0, so no iterate that lowers the incremental potential can
//! reach the body: every Newton step is first shortened by continuous collision detection
//! ([`BarrierContact::max_step`], conservative advancement on the 1-Lipschitz distance), and
//! the energy line search does the rest. No active set, no multipliers, no Uzawa updates.
//!
//! Stiffness: initially κ_a = 10 w_a / d̂_a with w_a the node's weight (areal density × standard
//! gravity × tributary area, or a membrane-stiffness estimate E h ℓ × 10⁻⁶ when the part is
//! massless), so a node resting on a body under its own weight sits at about 0.8 d̂; larger
//! loads push it closer, never through. A node found closer than 5 % of d̂ at a converged
//! state has its κ doubled (IPC's adaptive stiffness), so an impact or a concentrated load
//! is held without an ever steeper barrier. Thickness d̂_a = `distance_factor` × h_a.
//!
//! Friction: the lagged, smoothed Coulomb potential of IPC §5, with the normal force
//! λ̄ = −κ b'(d) and the tangent plane n̄ of the last converged state: slip s = (I − n̄n̄ᵀ)(x − x̂)
//! from the pair's anchor x̂ (where it stuck), D = μλ̄ δ ln cosh(|s|/δ), force
//! −μλ̄ tanh(|s|/δ) ŝ: elastic below a slip δ, saturating smoothly at μλ̄ (δ the stick
//! regularisation, `friction_slip` × d̂). On commit a sliding pair's anchor is dragged to
//! trail the node (return mapping), so the law is path-dependent across steps. With λ̄ and n̄
//! lagged, D is a potential and its Hessian is symmetric and exact.
//!
//! Moving bodies (`motion`, [`super::motion`]): each attempt places the bodies at its end
//! time ([`NodalForces::begin_motion`]); distances, barrier and friction are evaluated at
//! that placement. The body's own displacement over the attempt is seen by conservative
//! advancement on the relative motion (node still, body interpolated from its committed to
//! its trial placement): nodes it would sweep over, and nodes in the barrier zone, start the
//! iteration carried rigidly with the body — seam nodes too, a tied slave by carrying its
//! masters (left behind, a seam node on a limb that moves into it was overtaken by the body
//! within a fraction of d̂ per time step, which held Δt of the NBC suit's arm raise at
//! ~4·10⁻⁴ s) —, so the initial iterate is intersection-free;
//! Newton's own collision bound then works with the body at rest at its trial placement.
//! Friction anchors and lagged normals are stored in the body frame, so the slip is measured
//! relative to the body's surface and a moving body carries the cloth by friction.

use std::time::Instant;

use nalgebra::{Isometry3, Matrix3, SymmetricEigen, Vector3};
use rayon::prelude::*;
use serde::Serialize;

use super::body::RigidBody;
use super::ccd::conservative_advancement;
use super::motion;
use super::mechanics::distance_hessian;
use crate::element::NODE_DOFS;
use crate::model::{Model, State};
use crate::solver::NodalForces;

/// A sliding pair's anchor trails the node where tanh(|s|/δ) = tanh 2 (96 % of μλ̄).
const SLIDE_ARG: f64 = 2.0;

/// Initial κ_a d̂_a / w_a: a node resting under its own weight sits at about 0.8 d̂.
const INITIAL_STIFFNESS: f64 = 10.0;

/// A node whose gap falls below this fraction of d̂ at a converged state gets κ doubled.
const ADAPT_GAP: f64 = 0.05;

/// Bound on the adaptive growth of κ over its initial value.
const MAX_KAPPA_GROWTH: f64 = 1e6;

/// Fraction of the current gap a collision-free step may close in one Newton iteration.
const CCD_CLOSE: f64 = 0.9;

/// Barrier contact controls.
#[derive(Clone, Debug)]
pub struct BarrierSettings {
    /// Barrier thickness d̂ as a multiple of the node's shell thickness.
    pub distance_factor: f64,
    /// Factor on the automatic barrier stiffness.
    pub stiffness_factor: f64,
    /// Stick regularisation δ of the friction as a multiple of d̂.
    pub friction_slip: f64,
}

impl Default for BarrierSettings {
    fn default() -> Self {
        Self { distance_factor: 1.0, stiffness_factor: 1.0, friction_slip: 1.0 }
    }
}

/// Log barrier b(d) = −(d − d̂)² ln(d/d̂) and its first two derivatives (0 for d ≥ d̂;
/// +∞ for d ≤ 0).
pub fn barrier(d: f64, dhat: f64) -> (f64, f64, f64) {
    if d >= dhat {
        return (0.0, 0.0, 0.0);
    }
    if d <= 0.0 {
        return (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY);
    }
    let l = (d / dhat).ln();
    let e = d - dhat;
    (-e * e * l, -2.0 * e * l - e * e / d, -2.0 * l - 4.0 * e / d + e * e / (d * d))
}

/// Committed state of one node–body pair. Normal and anchor are in the body's local frame,
/// so that they move with a moving body (friction acts on the slip relative to its surface).
#[derive(Clone, Copy, Debug, Default)]
struct PairHistory {
    /// Barrier force λ̄ = −κ b'(d) of the last converged state (0: not in the barrier zone).
    force: f64,
    /// Body normal there (lagged tangent plane), body frame.
    normal: Vector3<f64>,
    /// Where the pair sticks, body frame.
    anchor: Option<Vector3<f64>>,
    sliding: bool,
    slip: f64,
}

/// Evaluation of one node–body pair.
#[derive(Clone, Copy, Debug, Default)]
struct PairEval {
    gap: f64,
    force: f64,
    normal: Vector3<f64>,
    tangential: Vector3<f64>,
    sliding: bool,
    active: bool,
}

/// Per converged state: barrier pairs and resultants.
#[derive(Clone, Debug, Default, Serialize)]
pub struct BarrierIncrement {
    /// Node–body pairs within the barrier thickness.
    pub active: usize,
    /// Active pairs sliding.
    pub sliding: usize,
    /// Smallest gap over the active pairs, as a fraction of their d̂.
    pub min_gap_ratio: f64,
    /// Smallest gap (m) of the shell face to a body over the active pairs.
    pub min_gap: f64,
    /// Sum of the normal barrier forces (N).
    pub normal_force: f64,
    /// Resultant contact force on the shell (N), normal plus friction.
    pub resultant: [f64; 3],
    /// Contact potential (barrier plus friction), J.
    pub potential: f64,
    /// Nodes whose barrier stiffness was doubled at this state (gap below 5 % of d̂).
    pub stiffened: usize,
    /// Placement of each moving body at this state (empty when no body moves).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub bodies: Vec<BodyPlacement>,
    /// Nodes carried with a moving body at the start of this increment (their relative
    /// motion would have closed the gap, or they were in contact).
    #[serde(skip_serializing_if = "is_zero")]
    pub carried: usize,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// Placement of a moving body at a converged state.
#[derive(Clone, Debug, Default, Serialize)]
pub struct BodyPlacement {
    /// Body name.
    pub name: String,
    /// Analysis time (`contact::motion`).
    pub time: f64,
    /// Translation of the body's local origin (m).
    pub translation: [f64; 3],
    /// Rotation vector of its orientation (axis × angle, degrees).
    pub rotation: [f64; 3],
}

/// A shell node whose face is on, inside or within the barrier distance of a body
/// ([`BarrierContact::within`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NearNode {
    /// Global node.
    pub node: usize,
    /// Index of the body in [`BarrierContact::bodies`].
    pub body: usize,
    /// Gap g = signed distance − h/2 (m); ≤ 0 on or inside the body.
    pub gap: f64,
    /// The node's barrier distance d̂ (m).
    pub dhat: f64,
    /// The node's face offset h/2 (m): g < −h/2 puts the mid-surface itself inside.
    pub offset: f64,
}

/// Barrier contact of a model's shell nodes with rigid bodies.
pub struct BarrierContact {
    /// The rigid bodies.
    pub bodies: Vec<RigidBody>,
    /// Participating global nodes.
    pub nodes: Vec<usize>,
    /// Face offset h/2 per participating node.
    pub offset: Vec<f64>,
    /// Barrier thickness d̂ per node.
    pub dhat: Vec<f64>,
    /// Barrier stiffness κ per node (N/m).
    pub kappa: Vec<f64>,
    kappa0: Vec<f64>,
    /// Tributary reference area per node.
    pub area: Vec<f64>,
    friction_slip: f64,
    history: Vec<PairHistory>,
    committed_x: Vec<Vector3<f64>>,
    last: Vec<PairEval>,
    last_potential: f64,
    search_s: f64,
    /// Body placements at the last converged state (`bodies[b].pose` is the trial one).
    committed_pose: Vec<Isometry3<f64>>,
    /// Per participating node: whether it may be carried by a moving body in the initial
    /// iterate (each translation a free equation or the slave of a tie on translations, so
    /// a seam node rides along like any other; a prescribed or fixed node does not).
    carriable: Vec<bool>,
    /// Analysis time of the trial placement.
    time: f64,
    /// Nodes carried at the start of the current attempt.
    carried: usize,
    /// Per-converged-state reports.
    pub increments: Vec<BarrierIncrement>,
}

/// Projection of a symmetric 3×3 matrix onto the positive semi-definite cone.
fn psd3(m: &Matrix3<f64>) -> Matrix3<f64> {
    let e = SymmetricEigen::new(*m);
    if e.eigenvalues.iter().all(|&l| l >= 0.0) {
        return *m;
    }
    let mut out = Matrix3::zeros();
    for k in 0..3 {
        let l = e.eigenvalues[k].max(0.0);
        let v = e.eigenvectors.column(k);
        out += v * v.transpose() * l;
    }
    out
}

impl BarrierContact {
    /// Barrier contact of the nodes of `parts` (all parts when empty) of `model` with
    /// `bodies`.
    pub fn new(model: &Model, bodies: Vec<RigidBody>, parts: &[usize], settings: &BarrierSettings) -> Self {
        let gravity = 9.80665;
        let n = model.n_nodes();
        let mut in_set = vec![parts.is_empty(); n];
        for &p in parts {
            let info = &model.parts[p];
            in_set[info.first_node..info.first_node + info.n_nodes].iter_mut().for_each(|b| *b = true);
        }
        let mut thick = vec![0.0f64; n];
        let mut weight = vec![0.0f64; n];
        let mut stiff = vec![0.0f64; n];
        let mut area = vec![0.0f64; n];
        for (e, def) in model.elements.iter().enumerate() {
            let sec = &model.sections[def.section];
            let (young, _) = sec.material.small_strain_moduli();
            let a_el = model.element(e).reference_area();
            let rho = model.parts.get(def.part).map_or(0.0, |p| p.areal_density);
            for &a in &def.nodes {
                thick[a] = thick[a].max(sec.thickness);
                area[a] += 0.25 * a_el;
                weight[a] += 0.25 * a_el * rho * gravity;
                stiff[a] = stiff[a].max(young * sec.thickness * a_el.sqrt());
            }
        }
        let nodes: Vec<usize> = (0..n).filter(|&a| in_set[a] && area[a] > 0.0).collect();
        let dhat: Vec<f64> = nodes.iter().map(|&a| settings.distance_factor * thick[a]).collect();
        let kappa: Vec<f64> = nodes
            .iter()
            .zip(&dhat)
            .map(|(&a, &dh)| {
                let w = if weight[a] > 0.0 { weight[a] } else { 1e-6 * stiff[a] };
                INITIAL_STIFFNESS * settings.stiffness_factor * w / dh
            })
            .collect();
        let np = nodes.len() * bodies.len();
        let carriable = nodes.iter().map(|&a| (0..3).all(|k| model.dofs.eq[NODE_DOFS * a + k] != crate::model::FIXED || translation_slave(model, NODE_DOFS * a + k))).collect();
        Self {
            committed_pose: bodies.iter().map(|b| b.pose).collect(),
            carriable,
            time: 0.0,
            carried: 0,
            offset: nodes.iter().map(|&a| 0.5 * thick[a]).collect(),
            area: nodes.iter().map(|&a| area[a]).collect(),
            committed_x: nodes.iter().map(|&a| model.x0[a]).collect(),
            dhat,
            kappa0: kappa.clone(),
            kappa,
            nodes,
            bodies,
            friction_slip: settings.friction_slip,
            history: vec![PairHistory::default(); np],
            last: vec![PairEval::default(); np],
            last_potential: 0.0,
            search_s: 0.0,
            increments: Vec::new(),
        }
    }

    /// Nodes that start inside or on a body: (global node, body name, gap).
    pub fn intersections(&self, model: &Model, state: &State) -> Vec<(usize, String, f64)> {
        self.within(model, state, false).into_iter().filter(|n| n.gap <= 0.0).map(|n| (n.node, self.bodies[n.body].name.clone(), n.gap)).collect()
    }

    /// Nodes whose shell face is on or inside a body or, with `barrier_zone`, within the
    /// barrier distance d̂ of it (0 < g < d̂, where the barrier b(g, d̂) is already active),
    /// at `state`, however deep inside. The gap g is the body's signed distance at the node minus the face
    /// offset h/2.
    pub fn within(&self, model: &Model, state: &State, barrier_zone: bool) -> Vec<NearNode> {
        let mut out = Vec::new();
        for (i, &a) in self.nodes.iter().enumerate() {
            let x = model.x0[a] + state.u[a];
            for (bi, b) in self.bodies.iter().enumerate() {
                // Unbounded query: a bounded one finds no surface for a node deeper inside
                // than the bound, and would miss it.
                if let Some(p) = b.proximity(&x, f64::MAX) {
                    let gap = p.distance - self.offset[i];
                    if gap <= 0.0 || (barrier_zone && gap < self.dhat[i]) {
                        out.push(NearNode { node: a, body: bi, gap, dhat: self.dhat[i], offset: self.offset[i] });
                    }
                }
            }
        }
        out
    }

    /// Evaluates every pair at `state`: per node the contact force on the shell (as an
    /// applied load), the Hessian of the node's contact potential (PSD-projected), the pair
    /// evaluations and the node's potential.
    fn evaluate(&self, model: &Model, state: &State, with_tangent: bool) -> Vec<(Vector3<f64>, Matrix3<f64>, Vec<PairEval>, f64)> {
        let nb = self.bodies.len();
        (0..self.nodes.len())
            .into_par_iter()
            .map(|i| {
                let a = self.nodes[i];
                let x = model.x0[a] + state.u[a];
                let (r, dh, kap) = (self.offset[i], self.dhat[i], self.kappa[i]);
                let mut f = Vector3::zeros();
                let mut kk = Matrix3::zeros();
                let mut pot = 0.0;
                let mut evals = vec![PairEval::default(); nb];
                for (b, body) in self.bodies.iter().enumerate() {
                    let hist = self.history[i * nb + b];
                    let prox = body.proximity(&x, r + dh);
                    if let Some(p) = prox {
                        let g = p.distance - r;
                        let n = p.normal;
                        evals[b].gap = g;
                        if g < dh {
                            let (bv, b1, b2) = barrier(g, dh);
                            if !bv.is_finite() {
                                // Through the face: inadmissible (the line search backs off).
                                return (Vector3::repeat(f64::NAN), Matrix3::zeros(), evals, f64::INFINITY);
                            }
                            pot += kap * bv;
                            f -= n * (kap * b1);
                            if with_tangent {
                                let hd = distance_hessian(body, &x, &n, p.distance);
                                kk += psd3(&(n * n.transpose() * (kap * b2) + hd * (kap * b1)));
                            }
                            evals[b] = PairEval { gap: g, force: -kap * b1, normal: n, active: true, ..Default::default() };
                        }
                    }
                    // Lagged friction: pairs with a normal force in the last converged state;
                    // anchor and tangent plane ride on the body (slip relative to its surface).
                    let mu = if hist.sliding { body.mu_kinetic } else { body.mu_static };
                    if mu > 0.0 && hist.force > 0.0 {
                        let local = hist.anchor.unwrap_or_else(|| self.committed_pose[b].inverse_transform_point(&self.committed_x[i].into()).coords);
                        let anchor = body.pose.transform_point(&local.into()).coords;
                        let nf = body.pose.transform_vector(&hist.normal);
                        let p = Matrix3::identity() - nf * nf.transpose();
                        let s = p * (x - anchor);
                        let sn = s.norm();
                        let cap = mu * hist.force;
                        let delta = self.friction_slip * dh;
                        let arg = sn / delta;
                        // ln cosh(z) = |z| + ln(1 + e^{−2|z|}) − ln 2, stable for large z.
                        pot += cap * delta * (arg + (-2.0 * arg).exp().ln_1p() - std::f64::consts::LN_2);
                        if sn > 0.0 {
                            let sh = s / sn;
                            let th = arg.tanh();
                            f -= sh * (cap * th);
                            evals[b].tangential = -sh * (cap * th);
                            evals[b].sliding = arg > SLIDE_ARG;
                            if with_tangent {
                                let along = cap / delta * (1.0 - th * th);
                                let across = cap * th / sn;
                                kk += sh * sh.transpose() * (along - across) + p * across;
                            }
                        } else if with_tangent {
                            kk += p * (cap / delta);
                        }
                    }
                }
                if with_tangent {
                    kk = (kk + kk.transpose()) * 0.5;
                }
                (f, kk, evals, pot)
            })
            .collect()
    }

    /// Resultant contact force on the shell (N) at `state`.
    pub fn resultant(&self, model: &Model, state: &State) -> Vector3<f64> {
        self.evaluate(model, state, false).iter().map(|(f, _, _, _)| *f).sum()
    }

    /// Smallest gap of the shell face to any body over the last evaluation's active pairs.
    pub fn min_gap(&self) -> Option<f64> {
        self.last.iter().filter(|e| e.active).map(|e| e.gap).reduce(f64::min)
    }
}

impl NodalForces for BarrierContact {
    fn add(&mut self, model: &Model, state: &State, f_ext: &mut [f64], jacobian: &mut Vec<(usize, Matrix3<f64>)>) {
        let t = Instant::now();
        let out = self.evaluate(model, state, true);
        self.search_s += t.elapsed().as_secs_f64();
        let nb = self.bodies.len();
        let mut pot = 0.0;
        for (i, (f, kk, ev, p)) in out.iter().enumerate() {
            let a = self.nodes[i];
            for k in 0..3 {
                f_ext[NODE_DOFS * a + k] += f[k];
            }
            pot += p;
            self.last[i * nb..(i + 1) * nb].copy_from_slice(ev);
            if kk.iter().any(|v| *v != 0.0) {
                jacobian.push((a, -kk));
            }
        }
        self.last_potential = pot;
    }

    fn potential(&self) -> Option<f64> {
        Some(self.last_potential)
    }

    /// Places the moving bodies at analysis time `to` and carries with them (rigidly, from
    /// their committed to their trial placement) every free node of the initial iterate whose
    /// relative motion — the node at rest, the body moving along [`motion::interpolate`] —
    /// would close its gap by more than `CCD_CLOSE` (conservative advancement on the
    /// relative motion, [`motion::relative_rate`]) or that lies in the barrier zone (it
    /// rides along, like cloth on a lifting hand). A carried node keeps its body-frame
    /// coordinates, hence its gap; its director frame turns with the body when its
    /// rotations are free. A node that the carry would put into another body stays. A tied
    /// slave (a seam node) is carried through its masters, which the carry moves with it
    /// (`Model::apply_prescribed` then places the slave from them).
    /// Newton then minimises with the bodies at their trial placement; its own collision
    /// bound ([`NodalForces::max_step`]) sees them still.
    fn begin_motion(&mut self, model: &Model, _from: f64, to: f64, state: &mut State) {
        self.time = to;
        self.carried = 0;
        let mut moving = Vec::new();
        for (b, body) in self.bodies.iter_mut().enumerate() {
            if body.motion.is_some() {
                body.pose = body.placement_at(to);
                if body.pose != self.committed_pose[b] {
                    moving.push(b);
                }
            }
        }
        if moving.is_empty() {
            return;
        }
        let carry: Vec<Option<(usize, Isometry3<f64>)>> = (0..self.nodes.len())
            .into_par_iter()
            .map(|i| {
                if !self.carriable[i] {
                    return None;
                }
                let a = self.nodes[i];
                let x = model.x0[a] + state.u[a];
                let (r, dh) = (self.offset[i], self.dhat[i]);
                for &b in &moving {
                    let body = &self.bodies[b];
                    let (pc, pt) = (self.committed_pose[b], body.pose);
                    let ell = motion::relative_rate(&pc, &pt, &x, &Vector3::zeros());
                    let Some(p) = body.proximity_at(&pc, &x, r + dh + ell) else { continue };
                    let g0 = p.distance - r;
                    let hit = g0 < dh
                        || conservative_advancement(g0, ell, CCD_CLOSE, 50, |s| {
                            body.proximity_at(&motion::interpolate(&pc, &pt, s), &x, r + ell).map(|q| q.distance - r)
                        }) < 1.0;
                    if hit {
                        let m = pt * pc.inverse();
                        let y = m.transform_point(&x.into()).coords;
                        let clear = self.bodies.iter().enumerate().all(|(c, o)| c == b || o.proximity(&y, r).is_none_or(|q| q.distance - r > 0.0));
                        return clear.then_some((b, m));
                    }
                }
                None
            })
            .collect();
        // A tied slave (a seam node) follows its masters (`Model::apply_prescribed` places it
        // before the iteration): it is carried by carrying its masters with it, each master
        // once (by its own body if it is itself in a barrier zone) and only where the carry
        // puts it into no other body.
        let nn = model.n_nodes();
        let mut moves: Vec<Option<(usize, Isometry3<f64>)>> = vec![None; nn];
        for (i, c) in carry.iter().enumerate() {
            if let Some((b, m)) = c {
                moves[self.nodes[i]] = Some((*b, *m));
            }
        }
        for (i, c) in carry.iter().enumerate() {
            let Some((b, m)) = c else { continue };
            let a = self.nodes[i];
            for k in 0..3 {
                let t = model.dofs.tie_of[NODE_DOFS * a + k];
                if t == crate::model::UNTIED {
                    continue;
                }
                for &(g, _) in &model.dofs.ties[t as usize].masters {
                    let mn = g / NODE_DOFS;
                    if moves[mn].is_some() || !(0..3).all(|j| model.dofs.eq[NODE_DOFS * mn + j] != crate::model::FIXED) {
                        continue;
                    }
                    let y = m.transform_point(&(model.x0[mn] + state.u[mn]).into()).coords;
                    let r = self.offset.get(i).copied().unwrap_or(0.0);
                    if self.bodies.iter().enumerate().all(|(c, o)| c == *b || o.proximity(&y, r).is_none_or(|q| q.distance - r > 0.0)) {
                        moves[mn] = Some((*b, *m));
                    }
                }
            }
        }
        for (a, mv) in moves.into_iter().enumerate() {
            let Some((_, m)) = mv else { continue };
            if (0..3).any(|k| model.dofs.eq[NODE_DOFS * a + k] == crate::model::FIXED) {
                // A tied slave: placed from its (carried) masters.
                continue;
            }
            let x = model.x0[a] + state.u[a];
            state.u[a] = m.transform_point(&x.into()).coords - model.x0[a];
            if (3..5).all(|k| model.dofs.eq[NODE_DOFS * a + k] != crate::model::FIXED) {
                let f = &mut state.frames[a];
                (f.d, f.t1, f.t2) = (m.rotation * f.d, m.rotation * f.t1, m.rotation * f.t2);
            }
            self.carried += 1;
        }
    }

    fn motion_end(&self) -> f64 {
        self.bodies.iter().filter_map(|b| b.motion.as_ref()).map(|m| m.end_time()).fold(f64::NEG_INFINITY, f64::max)
    }

    fn is_barrier(&self) -> bool {
        true
    }

    /// Conservative advancement (Mirtich 1996; the additive CCD of IPC in its simplest form):
    /// each node moves on the segment from its position in `from` to that in `to`; the signed
    /// distance is 1-Lipschitz, so from a gap g the node may advance by (g − g_min)/|Δx| of
    /// the segment, g_min = (1 − CCD_CLOSE) g₀, repeatedly until the end of the segment or
    /// until it no longer advances (then that fraction is the bound;
    /// [`conservative_advancement`], shared with surface contact).
    fn max_step(&self, model: &Model, from: &State, to: &State) -> f64 {
        let s = (0..self.nodes.len())
            .into_par_iter()
            .map(|i| {
                let a = self.nodes[i];
                let x0 = model.x0[a] + from.u[a];
                let dx = to.u[a] - from.u[a];
                let len = dx.norm();
                if len == 0.0 {
                    return 1.0;
                }
                let r = self.offset[i];
                let mut smin = 1.0f64;
                for body in &self.bodies {
                    let Some(p) = body.proximity(&x0, r + len + self.dhat[i]) else { continue };
                    let g0 = p.distance - r;
                    if g0 <= 0.0 {
                        return 0.0;
                    }
                    // The distance to a body is 1-Lipschitz: it changes by at most |Δx| = len.
                    let s = conservative_advancement(g0, len, CCD_CLOSE, 50, |s| body.proximity(&(x0 + dx * s), r + len).map(|q| q.distance - r));
                    smin = smin.min(s);
                }
                smin
            })
            .reduce(|| 1.0, f64::min);
        s
    }

    /// The start's positions become the committed ones (no friction history yet), so that
    /// the first anchors are where the nodes start, not at the reference positions.
    fn start_from(&mut self, model: &Model, state: &State) {
        for (i, &a) in self.nodes.iter().enumerate() {
            self.committed_x[i] = model.x0[a] + state.u[a];
        }
        self.history.iter_mut().for_each(|h| *h = PairHistory::default());
    }

    fn commit(&mut self, model: &Model, state: &State) -> Option<serde_json::Value> {
        let t = Instant::now();
        let out = self.evaluate(model, state, false);
        self.search_s += t.elapsed().as_secs_f64();
        let nb = self.bodies.len();
        let mut rep = BarrierIncrement { min_gap_ratio: f64::INFINITY, min_gap: f64::INFINITY, ..Default::default() };
        let mut resultant = Vector3::zeros();
        for (i, (f, _, evals, p)) in out.iter().enumerate() {
            let x = model.x0[self.nodes[i]] + state.u[self.nodes[i]];
            resultant += f;
            rep.potential += p;
            for (b, ev) in evals.iter().enumerate() {
                let h = &mut self.history[i * nb + b];
                if ev.active {
                    rep.active += 1;
                    rep.normal_force += ev.force;
                    rep.min_gap = rep.min_gap.min(ev.gap);
                    rep.min_gap_ratio = rep.min_gap_ratio.min(ev.gap / self.dhat[i]);
                    // Anchors live in the body frame: from the committed placement of the last
                    // state to the body's placement now (`pose`, committed below).
                    let pose = &self.bodies[b].pose;
                    let local = h.anchor.unwrap_or_else(|| self.committed_pose[b].inverse_transform_point(&self.committed_x[i].into()).coords);
                    let anchor = pose.transform_point(&local.into()).coords;
                    if ev.sliding {
                        rep.sliding += 1;
                        let t = ev.tangential.norm();
                        let lag = SLIDE_ARG * self.friction_slip * self.dhat[i];
                        let new_anchor = if t > 0.0 { x + ev.tangential * (lag / t) } else { x };
                        h.slip += (new_anchor - anchor).norm();
                        h.anchor = Some(pose.inverse_transform_point(&new_anchor.into()).coords);
                    } else {
                        h.anchor = Some(local);
                    }
                    h.sliding = ev.sliding;
                    h.force = ev.force;
                    h.normal = pose.inverse_transform_vector(&ev.normal);
                } else {
                    *h = PairHistory { slip: h.slip, ..Default::default() };
                }
                self.last[i * nb + b] = *ev;
            }
            self.committed_x[i] = x;
            // Adaptive stiffness (IPC §4.3): a pair pressed within 5 % of d̂ makes the barrier
            // steep and Newton slow; doubling κ holds the same force farther out.
            let closest = evals.iter().filter(|e| e.active).map(|e| e.gap).fold(f64::INFINITY, f64::min);
            if closest < ADAPT_GAP * self.dhat[i] && self.kappa[i] < MAX_KAPPA_GROWTH * self.kappa0[i] {
                self.kappa[i] *= 2.0;
                rep.stiffened += 1;
            }
        }
        if rep.active == 0 {
            rep.min_gap_ratio = 0.0;
            rep.min_gap = 0.0;
        }
        rep.resultant = [resultant.x, resultant.y, resultant.z];
        for (b, body) in self.bodies.iter().enumerate() {
            self.committed_pose[b] = body.pose;
            if body.motion.is_some() {
                let (t, r) = (body.pose.translation.vector, body.pose.rotation.scaled_axis().map(f64::to_degrees));
                rep.bodies.push(BodyPlacement { name: body.name.clone(), time: self.time, translation: [t.x, t.y, t.z], rotation: [r.x, r.y, r.z] });
            }
        }
        rep.carried = self.carried;
        self.increments.push(rep.clone());
        serde_json::to_value(serde_json::json!({ "contact": rep })).ok()
    }

    fn search_seconds(&self) -> f64 {
        self.search_s
    }

    /// `contact_pressure` (Pa), `contact_slip` (m), `contact_status` (0 free, 1 stick, 2 slip)
    /// and `contact_gap` (smallest gap of the shell face within the barrier thickness, m; 0
    /// when none).
    fn point_data(&self, model: &Model, state: &State) -> Vec<(String, usize, Vec<f64>)> {
        let n = model.n_nodes();
        let nb = self.bodies.len();
        let (mut p, mut slip, mut status, mut gap) = (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        for (i, &a) in self.nodes.iter().enumerate() {
            for b in 0..nb {
                let (ev, h) = (&self.last[i * nb + b], &self.history[i * nb + b]);
                slip[a] += h.slip;
                if ev.active {
                    p[a] += ev.force / self.area[i];
                    status[a] = f64::max(status[a], if ev.sliding { 2.0 } else { 1.0 });
                    gap[a] = if gap[a] == 0.0 { ev.gap } else { gap[a].min(ev.gap) };
                }
            }
        }
        let mut clearance = vec![f64::NAN; n];
        super::body::clearances(&self.bodies, &self.nodes, &self.offset, |a| model.position(state, a), &mut clearance);
        vec![
            ("contact_pressure".into(), 1, p),
            ("contact_slip".into(), 1, slip),
            ("contact_status".into(), 1, status),
            ("contact_gap".into(), 1, gap),
            ("body_clearance".into(), 1, clearance),
        ]
    }

    fn summary(&self) -> Option<(String, serde_json::Value)> {
        let last = self.increments.last().cloned().unwrap_or_default();
        let min_ratio = self.increments.iter().filter(|r| r.active > 0).map(|r| r.min_gap_ratio).fold(f64::INFINITY, f64::min);
        let (kmin, kmax) = self.kappa.iter().fold((f64::INFINITY, 0.0f64), |(a, b), &k| (a.min(k), b.max(k)));
        Some((
            "contact".into(),
            serde_json::json!({
                "formulation": "barrier",
                "bodies": self.bodies.iter().map(|b| format!("{}: {:?}", b.name, b.shape)).collect::<Vec<_>>(),
                "nodes": self.nodes.len(),
                "barrier_stiffness_range": [kmin, kmax],
                "barrier_distance_range": [self.dhat.iter().copied().fold(f64::INFINITY, f64::min), self.dhat.iter().copied().fold(0.0, f64::max)],
                "min_gap_ratio": if min_ratio.is_finite() { min_ratio } else { 0.0 },
                "final": last,
                "search_s": self.search_s,
            }),
        ))
    }
}

/// Whether global DOF `g` is the slave of a tie whose masters are all translations (its
/// value follows them in `Model::apply_prescribed`, so carrying them carries it).
fn translation_slave(model: &Model, g: usize) -> bool {
    let t = model.dofs.tie_of[g];
    t != crate::model::UNTIED && model.dofs.ties[t as usize].masters.iter().all(|&(m, _)| m % NODE_DOFS < 3)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn barrier_derivatives_match_finite_differences() {
        let dh = 1e-3;
        for &d in &[1e-6f64, 1e-5, 3e-4, 9e-4] {
            let h = 1e-9 * d.max(1e-6);
            let (_, b1, b2) = barrier(d, dh);
            let fd1 = (barrier(d + h, dh).0 - barrier(d - h, dh).0) / (2.0 * h);
            let fd2 = (barrier(d + h, dh).1 - barrier(d - h, dh).1) / (2.0 * h);
            assert!((b1 - fd1).abs() <= 1e-5 * b1.abs(), "b' at {d}: {b1} vs {fd1}");
            assert!((b2 - fd2).abs() <= 1e-5 * b2.abs(), "b'' at {d}: {b2} vs {fd2}");
        }
        assert_eq!(barrier(dh, dh), (0.0, 0.0, 0.0));
        assert!(barrier(0.0, dh).0.is_infinite());
    }

    #[test]
    fn psd_projection_clamps_negative_curvature_only() {
        let m = Matrix3::new(2.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.5);
        let p = psd3(&m);
        assert!((p - Matrix3::new(2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5)).norm() < 1e-14);
    }
}
