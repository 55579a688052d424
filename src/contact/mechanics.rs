//! Node-to-rigid-body contact: penalty normal contact and penalty-regularised Coulomb
//! friction, evaluated per shell node against every body (Wriggers, *Computational
//! Contact Mechanics*, 2nd ed. 2006, §5.2 and §10.3; Laursen 2002, ch. 5).
//!
//! The bodies stand still: a body with a prescribed `motion` is refused at scene build
//! (`contact.bodies[..].motion`) unless the contact is the barrier (`barrier.rs`).
//!
//! Gap of node a with body b: g = d_b(x_a) − h_a/2, with d_b the body's signed distance
//! (parry3d closest-point query, bounded by the half-thickness) and h_a the largest
//! thickness of the sections around the node (the shell's face, not its mid-surface,
//! touches the body). Normal: augmented Lagrangian with one Uzawa update per converged
//! increment or time step (Simo & Laursen, Comput. Struct. 42, 1992; Wriggers 2006 §6.3.2):
//! λ = ⟨λ̂ − k_n g⟩ with the pair's multiplier λ̂ ≥ 0, internal force −λ n, tangent
//! k_n n nᵀ − λ ∇n with ∇n the Hessian of the signed distance (analytic for the sphere
//! and the plane, central differences of the projected normal otherwise). On commit
//! λ̂ ← λ, so a pair that stays in contact is pushed out by k_n|g| more at the next step and
//! its penetration decays geometrically towards zero over the increments of a pseudo-
//! transient drape, whatever the load the node carries (a cloth hanging from a few nodes on
//! a neck rim loads them far above the uniform pressure the penalty is sized for); a
//! separated pair's multiplier is reset to zero. The stability test of a rest state uses the
//! constraint limit of the normal term (`CONSTRAINT_LIMIT_FACTOR`): at the Uzawa fixed point
//! the gap is enforced exactly, not through the penalty.
//! Friction: regularised Coulomb law measured from an anchor point x̂ (where the node
//! stuck): s = (I − n̄n̄ᵀ)(x − x̂), t = −μλ̄ tanh(k_t|s|/(μλ̄)) ŝ — the elastic-slip penalty
//! k_t for small s, saturating smoothly at the Coulomb limit μλ̄ (a hard stick/slip switch
//! made Newton cycle between the two branches on drapes). μ is the static coefficient unless
//! the pair slid in the previous increment (then kinetic). The normal force λ̄ and the
//! tangent plane n̄ are lagged — those of the last converged state, the pair's multiplier λ̂
//! and normal — as in the lagged dissipative potential of Incremental Potential Contact (Li et
//! al., ACM Trans. Graph. 39(4), 2020, §5): the friction force is then the gradient of
//! Φ(s) = (μλ̄)²/k_t · ln cosh(k_t|s|/(μλ̄)) and its tangent
//! P̄ [k_t sech²(·) ŝŝᵀ + μλ̄ tanh(·)/|s| (I − ŝŝᵀ)] P̄ is exact and symmetric. With the
//! current λ and n instead, the exact tangent has the unsymmetric couplings
//! −μ k_n (tanh − arg sech²) ŝ nᵀ (friction change from a normal motion) and the rotation of
//! the tangent plane on a curved body; the symmetric solver had to leave them out and Newton
//! 2-cycled on spheres with friction (time steps rejected every few steps). The lag bounds
//! the friction by the normal force of the previous step, which at rest is the current one.
//! A pair just coming into contact (λ̂ = 0) uses its current λ and n, with the coupling
//! left out of the tangent. A pair counts as
//! sliding when k_t|s| > 2μλ̄; on convergence its anchor is dragged to trail the node by
//! 2μ_kλ/k_t (return mapping), so friction is path-dependent across increments.
//! Penalty: k_n = c·A·a/ℓ² per node, with A the membrane stiffness (N/m) of the stiffest
//! section at the node (E·h, or the fabric's larger tensile stiffness), a the node's
//! tributary area and ℓ² the mean area of its elements (so a uniform pressure p penetrates
//! uniformly by p ℓ²/(c A)); c = 1 unless the scene overrides it, or k_n is given directly.

use std::time::Instant;

use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;
use serde::Serialize;

use super::body::{RigidBody, Shape};
use crate::element::NODE_DOFS;
use crate::model::{Model, State};
use crate::solver::NodalForces;

/// Factor on the normal penalty in the stability tangent (`NodalForces::stability_tangent`).
/// The augmented Lagrangian's Uzawa fixed point enforces g = 0 exactly, so a rest state's
/// stability is that of the Hessian reduced to the tangent motions n·δx = 0 of the active
/// pairs; by Debreu's lemma (Econometrica 20, 1952; Bertsekas, *Constrained Optimization and
/// Lagrange Multiplier Methods* 1982, Lemma 1.25) that reduced Hessian is positive definite
/// iff H + c Σ k n nᵀ is for all large enough c. With the penalty itself (c = 1) a mode that
/// sinks a contact node into the body by a few µm while the overhang turns about it shows as
/// unstable, although the Uzawa updates push the node back out and the damped motion returns
/// to the state (the 80-sector Cusick cotton drape: ω² = −1.2 s⁻² with c = 1, positive definite
/// with c = 10).
const CONSTRAINT_LIMIT_FACTOR: f64 = 1e3;

/// A pair counts as sliding (and its anchor is dragged along on commit) when k_t|s| > 2μλ,
/// i.e. the regularised friction force exceeds tanh 2 = 96 % of μλ.
const SLIDE_ARG: f64 = 2.0;

/// Contact controls.
#[derive(Clone, Debug)]
pub struct ContactSettings {
    /// Penalty factor c in k_n = c·A·a/ℓ².
    pub penalty_factor: f64,
    /// Explicit nodal normal penalty (N/m), overriding the automatic choice.
    pub penalty: Option<f64>,
    /// Tangential penalty as a fraction of the normal one.
    pub tangential_factor: f64,
}

impl Default for ContactSettings {
    fn default() -> Self {
        Self { penalty_factor: 1.0, penalty: None, tangential_factor: 1.0 }
    }
}

/// Committed state of one node–body pair.
#[derive(Clone, Copy, Debug, Default)]
struct PairHistory {
    anchor: Option<Vector3<f64>>,
    sliding: bool,
    active: bool,
    slip: f64,
    /// Augmented-Lagrangian multiplier λ̂ (N) of the last converged state.
    multiplier: f64,
    /// Body normal at the node in the last converged state (the lagged tangent plane).
    normal: Vector3<f64>,
}

/// Evaluation of one node–body pair.
#[derive(Clone, Copy, Debug, Default)]
struct PairEval {
    gap: f64,
    lambda: f64,
    tangential: Vector3<f64>,
    sliding: bool,
    active: bool,
    normal: Vector3<f64>,
}

/// Active-set changes and contact resultants of one converged increment.
#[derive(Clone, Debug, Default, Serialize)]
pub struct ContactIncrement {
    /// Node–body pairs in contact.
    pub active: usize,
    /// Pairs that came into contact.
    pub activated: usize,
    /// Pairs that separated.
    pub released: usize,
    /// Active pairs sliding.
    pub sliding: usize,
    /// Pairs that changed between stick and slip.
    pub stick_slip_changes: usize,
    /// Largest penetration of the shell face into a body (−gap), m.
    pub max_penetration: f64,
    /// Sum of the normal contact forces (N).
    pub normal_force: f64,
    /// Resultant contact force on the shell (N), normal plus friction.
    pub resultant: [f64; 3],
}

/// Node-to-rigid-body contact of a model's shell nodes.
pub struct ContactSet {
    /// The rigid bodies.
    pub bodies: Vec<RigidBody>,
    /// Participating global nodes.
    pub nodes: Vec<usize>,
    /// Contact offset h/2 per participating node.
    pub offset: Vec<f64>,
    /// Tributary reference area per participating node.
    pub area: Vec<f64>,
    /// Normal penalty per participating node (N/m).
    pub k_normal: Vec<f64>,
    tangential_factor: f64,
    history: Vec<PairHistory>,
    committed_x: Vec<Vector3<f64>>,
    last: Vec<PairEval>,
    search_s: f64,
    /// Reject trial states with a mid-surface through a body (see `add`).
    pub reject_through: bool,
    /// Per-increment reports (also returned by `commit`).
    pub increments: Vec<ContactIncrement>,
    /// The tangent is that of the stability test (normal penalty × `CONSTRAINT_LIMIT_FACTOR`).
    stability: bool,
    last_potential: f64,
}

impl ContactSet {
    /// Contact of the nodes of `parts` (all parts when empty) of `model` with `bodies`.
    pub fn new(model: &Model, bodies: Vec<RigidBody>, parts: &[usize], settings: &ContactSettings) -> Self {
        let n = model.n_nodes();
        let mut in_set = vec![parts.is_empty(); n];
        for &p in parts {
            let info = &model.parts[p];
            in_set[info.first_node..info.first_node + info.n_nodes].iter_mut().for_each(|b| *b = true);
        }
        let mut half = vec![0.0f64; n];
        let mut stiff = vec![0.0f64; n];
        let mut area = vec![0.0f64; n];
        let mut el_area_sum = vec![0.0f64; n];
        let mut el_count = vec![0usize; n];
        for (e, def) in model.elements.iter().enumerate() {
            let sec = &model.sections[def.section];
            let (young, _) = sec.material.small_strain_moduli();
            let a_el = model.element(e).reference_area();
            for &a in &def.nodes {
                half[a] = half[a].max(0.5 * sec.thickness);
                stiff[a] = stiff[a].max(young * sec.thickness);
                area[a] += 0.25 * a_el;
                el_area_sum[a] += a_el;
                el_count[a] += 1;
            }
        }
        let nodes: Vec<usize> = (0..n).filter(|&a| in_set[a] && el_count[a] > 0).collect();
        let k_normal = nodes
            .iter()
            .map(|&a| settings.penalty.unwrap_or_else(|| settings.penalty_factor * stiff[a] * area[a] / (el_area_sum[a] / el_count[a] as f64)))
            .collect();
        let nb = bodies.len();
        let np = nodes.len() * nb;
        Self {
            offset: nodes.iter().map(|&a| half[a]).collect(),
            area: nodes.iter().map(|&a| area[a]).collect(),
            committed_x: nodes.iter().map(|&a| model.x0[a]).collect(),
            k_normal,
            nodes,
            bodies,
            tangential_factor: settings.tangential_factor,
            history: vec![PairHistory::default(); np],
            last: vec![PairEval::default(); np],
            search_s: 0.0,
            reject_through: true,
            increments: Vec::new(),
            stability: false,
            last_potential: 0.0,
        }
    }

    /// Evaluates every pair at `state`: per participating node the force (to add to f_int),
    /// the 3×3 tangent, and per pair the evaluation.
    fn evaluate(&self, model: &Model, state: &State, with_tangent: bool) -> Vec<(Vector3<f64>, Matrix3<f64>, Vec<PairEval>, f64)> {
        let nb = self.bodies.len();
        (0..self.nodes.len())
            .into_par_iter()
            .map(|i| {
                let a = self.nodes[i];
                let x = model.x0[a] + state.u[a];
                let r = self.offset[i];
                let k = self.k_normal[i];
                let kt = self.tangential_factor * k;
                let mut f = Vector3::zeros();
                let mut kk = Matrix3::zeros();
                let mut evals = vec![PairEval::default(); nb];
                let mut pot = 0.0;
                for (b, body) in self.bodies.iter().enumerate() {
                    // Search reach: the offset plus twice the node's spacing, so that a node a
                    // Newton step carried deeper than the offset is still seen (a bounded
                    // trimesh query returns nothing for points farther inside than the bound).
                    let reach = r + 2.0 * self.area[i].sqrt();
                    let Some(prox) = body.proximity(&x, reach) else { continue };
                    let g = prox.distance - r;
                    let hist = self.history[i * nb + b];
                    let lambda = hist.multiplier - k * g;
                    if lambda <= 0.0 {
                        evals[b].gap = g;
                        continue;
                    }
                    let n = prox.normal;
                    // Φ = ⟨λ̂ − k g⟩²/(2k): −∂Φ/∂g = λ.
                    pot += lambda * lambda / (2.0 * k);
                    f -= n * lambda;
                    if with_tangent {
                        let kn = if self.stability { k * CONSTRAINT_LIMIT_FACTOR } else { k };
                        kk += n * n.transpose() * kn - distance_hessian(body, &x, &n, prox.distance) * lambda;
                    }
                    let mut ev = PairEval { gap: g, lambda, active: true, normal: n, ..Default::default() };
                    // Saturation level: static unless the pair slid in the last increment.
                    let mu = if hist.sliding { body.mu_kinetic } else { body.mu_static };
                    if mu > 0.0 {
                        let anchor = hist.anchor.unwrap_or(self.committed_x[i]);
                        // Lagged normal force and tangent plane of the last converged state
                        // (a pair already in contact there); a pair just coming into contact
                        // uses the current ones.
                        let (lambda_f, nf) = if hist.multiplier > 0.0 { (hist.multiplier, hist.normal) } else { (lambda, n) };
                        let p = Matrix3::identity() - nf * nf.transpose();
                        let s = p * (x - anchor);
                        let sn = s.norm();
                        let cap = mu * lambda_f;
                        let arg = kt * sn / cap;
                        // Φ_t = (μλ̄)²/k_t ln cosh(k_t|s|/(μλ̄)) (stable form).
                        pot += cap * cap / kt * (arg + (-2.0 * arg).exp().ln_1p() - std::f64::consts::LN_2);
                        if sn > 0.0 {
                            let sh = s / sn;
                            // Smooth Coulomb law t = −μλ tanh(k_t|s|/(μλ)) ŝ.
                            let th = arg.tanh();
                            f += sh * (cap * th);
                            ev.tangential = -sh * (cap * th);
                            ev.sliding = arg > SLIDE_ARG;
                            if with_tangent {
                                let along = kt * (1.0 - th * th);
                                let across = cap * th / sn;
                                // P (along ŝŝᵀ + across (I − ŝŝᵀ)) P, ŝ ⊥ n_f.
                                kk += sh * sh.transpose() * (along - across) + p * across;
                            }
                        } else if with_tangent {
                            kk += p * kt;
                        }
                    }
                    evals[b] = ev;
                }
                if with_tangent {
                    kk = (kk + kk.transpose()) * 0.5;
                }
                (f, kk, evals, pot)
            })
            .collect()
    }

    /// Largest penetration (−gap) of the last evaluation, m.
    pub fn max_penetration(&self) -> f64 {
        self.last.iter().filter(|e| e.active).map(|e| -e.gap).fold(0.0, f64::max)
    }

    /// Resultant contact force on the shell (N) at the last evaluation, summed over nodes.
    pub fn resultant(&self, model: &Model, state: &State) -> Vector3<f64> {
        self.evaluate(model, state, false).iter().map(|(f, _, _, _)| -f).sum()
    }
}

/// Hessian ∇n of the signed distance of `body` at `x` (outward normal `n`, distance `d`):
/// zero for the plane, (I − nnᵀ)/(R + d) for the sphere, central differences of the
/// projected normal (step 1e-6 of the distance scale) otherwise.
pub(super) fn distance_hessian(body: &RigidBody, x: &Vector3<f64>, n: &Vector3<f64>, d: f64) -> Matrix3<f64> {
    match &body.shape {
        Shape::Plane => Matrix3::zeros(),
        Shape::Sphere(b) => (Matrix3::identity() - n * n.transpose()) / (b.radius + body.rounding + d).max(1e-12),
        _ => {
            let h = 1e-6 * x.norm().max(d.abs()).max(1e-3);
            let mut m = Matrix3::zeros();
            for j in 0..3 {
                let mut e = Vector3::zeros();
                e[j] = h;
                let probe = |y: Vector3<f64>| body.proximity(&y, f64::MAX).map(|p| p.normal).unwrap_or(*n);
                let col = (probe(x + e) - probe(x - e)) / (2.0 * h);
                m.set_column(j, &col);
            }
            (m + m.transpose()) * 0.5
        }
    }
}

impl NodalForces for ContactSet {
    /// Contact forces −f (f the internal force k_n g n plus friction of each pair) and their
    /// 3×3 Jacobian −K per node.
    fn add(&mut self, model: &Model, state: &State, f_ext: &mut [f64], jacobian: &mut Vec<(usize, Matrix3<f64>)>) {
        let t = Instant::now();
        let out = self.evaluate(model, state, true);
        self.search_s += t.elapsed().as_secs_f64();
        let nb = self.bodies.len();
        self.last_potential = out.iter().map(|o| o.3).sum();
        for (i, (f, kk, ev, _)) in out.iter().enumerate() {
            let a = self.nodes[i];
            // A Newton step that carries a free node from above a body to below its surface
            // (mid-surface through the body) would be answered by a huge penalty force and
            // the iteration would chatter between contact and separation: reject the trial
            // state so the step is shortened instead.
            let through = self.reject_through && ev.iter().any(|e| e.active && -e.gap > self.offset[i]);
            if through {
                self.last_potential = f64::INFINITY;
            }
            for k in 0..3 {
                f_ext[NODE_DOFS * a + k] -= if through { f64::NAN } else { f[k] };
            }
            self.last[i * nb..(i + 1) * nb].copy_from_slice(ev);
            if ev.iter().any(|e| e.active) {
                jacobian.push((a, -kk));
            }
        }
    }

    fn commit(&mut self, model: &Model, state: &State) -> Option<serde_json::Value> {
        let t = Instant::now();
        let out = self.evaluate(model, state, false);
        self.search_s += t.elapsed().as_secs_f64();
        let nb = self.bodies.len();
        let mut rep = ContactIncrement::default();
        let mut resultant = Vector3::zeros();
        for (i, (f, _, evals, _)) in out.iter().enumerate() {
            let a = self.nodes[i];
            let x = model.x0[a] + state.u[a];
            resultant -= f;
            for (b, ev) in evals.iter().enumerate() {
                let h = &mut self.history[i * nb + b];
                if ev.active {
                    rep.active += 1;
                    rep.activated += usize::from(!h.active);
                    rep.max_penetration = rep.max_penetration.max(-ev.gap);
                    rep.normal_force += ev.lambda;
                    h.multiplier = ev.lambda;
                    h.normal = ev.normal;
                    let anchor = h.anchor.unwrap_or(self.committed_x[i]);
                    if ev.sliding {
                        rep.sliding += 1;
                        // Return mapping: the anchor trails the node by the slip at which the
                        // regularised force reaches tanh 2 of μλ.
                        let kt = self.tangential_factor * self.k_normal[i];
                        let t = ev.tangential.norm();
                        let lag = SLIDE_ARG * self.bodies[b].mu_kinetic * ev.lambda / kt;
                        let new_anchor = if t > 0.0 { x + ev.tangential * (lag / t) } else { x };
                        h.slip += (new_anchor - anchor).norm();
                        h.anchor = Some(new_anchor);
                    } else {
                        h.anchor = Some(anchor);
                    }
                    rep.stick_slip_changes += usize::from(h.active && h.sliding != ev.sliding);
                    h.sliding = ev.sliding;
                    h.active = true;
                } else {
                    rep.released += usize::from(h.active);
                    h.multiplier = 0.0;
                    h.active = false;
                    h.sliding = false;
                    h.anchor = None;
                }
                self.last[i * nb + b] = *ev;
            }
            self.committed_x[i] = x;
        }
        rep.resultant = [resultant.x, resultant.y, resultant.z];
        self.increments.push(rep.clone());
        serde_json::to_value(serde_json::json!({ "contact": rep })).ok()
    }

    fn search_seconds(&self) -> f64 {
        self.search_s
    }

    /// Σ ⟨λ̂ − k g⟩²/(2k) + friction potential (lagged normal force and plane) at the last
    /// evaluation.
    fn potential(&self) -> Option<f64> {
        Some(self.last_potential)
    }

    fn stability_tangent(&mut self, on: bool) {
        self.stability = on;
    }

    /// `contact_pressure` (Pa, normal force over tributary area, summed over bodies),
    /// `contact_slip` (accumulated slip, m), `contact_status` (0 free, 1 stick, 2 slip) and
    /// `contact_gap` (smallest gap of the shell face to any body within reach, m; 0 when
    /// none is within the half-thickness).
    fn point_data(&self, model: &Model, state: &State) -> Vec<(String, usize, Vec<f64>)> {
        let n = model.n_nodes();
        let nb = self.bodies.len();
        let (mut p, mut slip, mut status, mut gap) = (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        for (i, &a) in self.nodes.iter().enumerate() {
            for b in 0..nb {
                let (ev, h) = (&self.last[i * nb + b], &self.history[i * nb + b]);
                slip[a] += h.slip;
                if ev.active {
                    p[a] += ev.lambda / self.area[i];
                    status[a] = f64::max(status[a], if ev.sliding { 2.0 } else { 1.0 });
                    gap[a] = f64::min(gap[a], ev.gap);
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
        let max_pen = self.increments.iter().map(|r| r.max_penetration).fold(0.0, f64::max);
        let k_min = self.k_normal.iter().copied().fold(f64::INFINITY, f64::min);
        let k_max = self.k_normal.iter().copied().fold(0.0, f64::max);
        Some((
            "contact".into(),
            serde_json::json!({
                "bodies": self.bodies.iter().map(|b| format!("{}: {:?}", b.name, b.shape)).collect::<Vec<_>>(),
                "nodes": self.nodes.len(),
                "penalty_range": [k_min, k_max],
                "max_penetration": max_pen,
                "final": last,
                "search_s": self.search_s,
            }),
        ))
    }
}
