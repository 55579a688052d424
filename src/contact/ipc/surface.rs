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
//! in its plain form; `contact::ccd`). Its candidates come from a list kept between sweeps
//! with a margin (a Verlet list, [`Near`]), filtered by each sweep's own box test, so that
//! the trees are searched only when a node has moved beyond the margin; the trees themselves
//! are refitted, not rebuilt (`broad_phase::Trees`).
//!
//! Cost: the pairs' energies are summed per closest feature before the distance is
//! differentiated, in closed form (`distance.rs`; `potential.rs`: stacked plies give dozens of pairs per stacked vertex pair,
//! nearly all measuring one vertex–vertex or vertex–edge distance); each candidate's reference
//! constants are computed once and kept; and the converged state's pairs, already evaluated
//! by the last Newton iteration, are reused on commit.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, RwLock};
use std::time::Instant;

use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;

use super::broad_phase::{Sweep, Trees};
use super::friction::{Friction, FrictionTerm};
use super::blocks::Blocks;
use super::potential::{derivative_into, group, Derivative, FeatureKey, FxMap, Scalar};
pub use super::report::{SurfaceIncrement, SurfaceTimings};
pub use super::settings::{SurfaceSettings, SurfaceSetup};
use crate::element::NODE_DOFS;
use crate::model::{Model, State};
use crate::solver::NodalForces;

mod candidates;
mod pairs;
mod sweep;
mod trial;

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

/// Slack of the sweep boxes, as a fraction of the smallest pad (see [`Sweep`]).
const SWEEP_SLACK: f64 = 1e-6;

/// Margin of the collision-detection candidates kept between sweeps (see [`Near`]), as a
/// multiple of `reach` (twice the largest half thickness).
const NEAR_MARGIN: f64 = 1.0;

/// A candidate pair: kind, key, nodes and reference constants.
type Pair = (Kind, (usize, usize), [usize; 4], Constants);

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

/// Candidates kept between collision-detection sweeps (a Verlet list): found with each
/// primitive's sweep pad widened by a margin M around each point's box `lo`..`hi` over the
/// sweep they were found for, they hold every candidate of any later sweep whose every point
/// stays within M of its box: a point's new box lies inside its old box grown by M, so a
/// triangle's or an edge's (spanned by its nodes' boxes) inside its old one grown by M, and
/// two new boxes, each inflated by its pad, overlap only if the old ones inflated by pad + M
/// do. Such a sweep filters these pairs by its own box test instead of searching the trees.
struct Near {
    lo: Vec<Vector3<f64>>,
    hi: Vec<Vector3<f64>>,
    pairs: Vec<Pair>,
}

/// Lower bounds ℓ of the gaps of a collision-detection sweep's candidates at its start `from`
/// (a Newton iterate; the gaps themselves where they were measured), with the contact nodes'
/// positions there: an evaluation on the sweep leaves out the pairs that cannot be active.
/// A pair's distance changes by at most the sum δ of its two primitives' largest nodal moves
/// (each closest point is a convex combination of its primitive's nodes), so at a state
/// whose moves from `from` give δ its gap is at least ℓ − δ − μ, the margin μ (10⁻⁵ of four
/// times the longest reference edge) covering round-off and the switch of nearly parallel
/// edges to their endpoint distances (`primitives::edge_edge_feature`, below a sine of
/// 10⁻⁵). A pair with ℓ − δ − μ > 1.05 d̂ is inactive and left out — the same result: it
/// contributes nothing (gap ≥ d̂) — and that bound is kept as its ℓ at the new state.
struct StartGaps {
    pairs: Arc<Vec<Pair>>,
    gaps: Vec<f64>,
    from: Vec<Vector3<f64>>,
}

/// Evaluation of one active pair.
#[derive(Clone, Debug)]
struct Term {
    kind: Kind,
    key: (usize, usize),
    nodes: [usize; 4],
    /// The closest feature, whose distance the energy depends on.
    feature: FeatureKey,
    /// Energy and its first two derivatives in the feature's distance.
    scalar: Scalar,
    /// Gradient and Hessian in all four nodes of a pair with the edge–edge mollifier (it
    /// depends on more than the distance), when derivatives were asked for.
    mollified: Option<Box<Derivative>>,
    /// A nearly parallel edge–edge pair inside the mollifier's range, differentiated on its
    /// own (`mollified`), not with its feature.
    parallel: bool,
    gap: f64,
    dhat: f64,
    /// Mollifier threshold (edge–edge), 0 for point–triangle.
    eps: f64,
    /// Thickness of the thinner ply of the pair.
    thin: f64,
    energy: f64,
    /// Normal force λ = −∂E/∂d.
    force: f64,
    normal: Vector3<f64>,
    weights: [f64; 4],
}

/// What an evaluation's terms still lack once its pairs are measured (`add_coupled`).
enum Pending {
    /// Nothing: the last evaluation's terms again.
    Nothing,
    /// The derivatives of the mollified pairs of a kept trial ([`SurfaceContact::trial_mollified`])
    /// and the friction terms (the trial measured their potentials alone).
    Trial,
    /// The friction terms.
    Friction,
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
    /// Broad-phase pads: each point's, triangle's and edge's largest half thickness (a pair
    /// is active only within c = the sum of its two primitives' pads).
    point_pad: Vec<f64>,
    tri_pad: Vec<f64>,
    edge_pad: Vec<f64>,
    /// The pads widened by the sweep slack σ, and σ.
    sweep_pads: (Vec<f64>, Vec<f64>, Vec<f64>),
    slack: f64,
    /// The candidates of the last collision-detection sweep.
    sweep: Mutex<Option<Sweep<Pair>>>,
    /// The sweep pads widened by the margin M of [`Near`], and M.
    near_pads: (Vec<f64>, Vec<f64>, Vec<f64>),
    near_margin: f64,
    /// Candidates kept between collision-detection sweeps.
    near: Mutex<Option<Near>>,
    /// The broad phase's trees, refitted from search to search.
    trees: Mutex<Trees>,
    friction: FxMap<(Kind, usize, usize), Friction>,
    /// The pairs of `friction` with a normal force, in its order (`friction::committed`).
    committed: Vec<((Kind, usize, usize), Friction)>,
    /// Reference constants per candidate pair (None: excluded), filled as pairs come near.
    constants: RwLock<FxMap<(Kind, usize, usize), Option<Constants>>>,
    last: Vec<Term>,
    /// Friction terms of the last evaluation.
    last_friction: Vec<FrictionTerm>,
    /// Contact nodes' displacements at the last evaluation.
    last_u: Vec<Vector3<f64>>,
    /// The candidates of the last evaluation with derivatives (a Newton iterate, at
    /// `last_u`) and their gaps there: the start of the next collision-detection sweep.
    /// Each gap with whether it was measured (else a lower bound, `StartGaps`).
    start_gaps: Option<(Arc<Vec<Pair>>, Vec<(f64, bool)>)>,
    /// The last trial state of the energy line search, kept for its assembly (`trial.rs`).
    trial: Option<trial::Trial>,
    /// Buffer of the per-feature barrier derivatives (`barrier_derivatives`), and whether it
    /// holds the exact (not projected) ones of the terms `last`.
    derivatives: Vec<Derivative>,
    derivatives_exact: bool,
    /// The tangent blocks, summed in the layout of the last evaluation's blocks.
    blocks: Blocks,
    /// The last sweep's gaps at its start (see [`StartGaps`]).
    start: Mutex<Option<StartGaps>>,
    /// Absolute part of the [`StartGaps`] margin: 10⁻⁵ of four times the longest reference
    /// edge.
    bound_margin: f64,
    /// Node → index in `points` (usize::MAX for a node without contact).
    point_index: Vec<usize>,
    last_potential: f64,
    /// Report the pair Hessians projected onto the PSD cone ([`NodalForces::project_hessians`]).
    project: bool,
    /// Wall time (s) of the candidate pairs, their gap bounds and the measured pairs'
    /// distances, barrier values and friction terms (`NodalForces::search_seconds`).
    search_s: f64,
    /// Wall time split, for the summary.
    timings: std::sync::Mutex<SurfaceTimings>,
    /// Per-converged-state reports.
    pub increments: Vec<SurfaceIncrement>,
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
                let (a, b) = (candidates::find(&mut rep, s), candidates::find(&mut rep, m));
                if a != b {
                    rep[a.max(b)] = a.min(b);
                }
            }
        }
        let rep: Vec<usize> = (0..n).map(|a| candidates::find(&mut rep, a)).collect();
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
        let point_pad: Vec<f64> = points.iter().map(|&a| half[a]).collect();
        let tri_pad: Vec<f64> = tris.iter().map(|t| t.iter().map(|&a| half[a]).fold(0.0, f64::max)).collect();
        let edge_pad: Vec<f64> = edges.iter().map(|e| half[e[0]].max(half[e[1]])).collect();
        let slack = SWEEP_SLACK * point_pad.iter().copied().filter(|&r| r > 0.0).fold(f64::INFINITY, f64::min).min(1.0);
        let widen = |v: &[f64]| v.iter().map(|r| r + slack).collect::<Vec<f64>>();
        let sweep_pads = (widen(&point_pad), widen(&tri_pad), widen(&edge_pad));
        let near_margin = NEAR_MARGIN * reach;
        let grow = |v: &[f64]| v.iter().map(|r| r + near_margin).collect::<Vec<f64>>();
        let near_pads = (grow(&sweep_pads.0), grow(&sweep_pads.1), grow(&sweep_pads.2));
        let longest = edges.iter().map(|e| (model.x0[e[0]] - model.x0[e[1]]).norm()).fold(0.0, f64::max);
        let bound_margin = 1e-5 * 4.0 * longest;
        let mut point_index = vec![usize::MAX; n];
        for (i, &a) in points.iter().enumerate() {
            point_index[a] = i;
        }
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
            point_pad,
            tri_pad,
            edge_pad,
            sweep_pads,
            slack,
            sweep: Mutex::new(None),
            near_pads,
            near_margin,
            near: Mutex::new(None),
            trees: Mutex::new(Trees::default()),
            friction: FxMap::default(),
            committed: Vec::new(),
            constants: RwLock::new(FxMap::default()),
            last: Vec::new(),
            last_friction: Vec::new(),
            last_u: Vec::new(),
            start_gaps: None,
            trial: None,
            derivatives: Vec::new(),
            derivatives_exact: false,
            blocks: Blocks::default(),
            start: Mutex::new(None),
            bound_margin,
            point_index,
            last_potential: 0.0,
            project: false,
            search_s: 0.0,
            timings: std::sync::Mutex::new(SurfaceTimings::default()),
            increments: Vec::new(),
        }
    }

    /// Number of contact nodes, triangles and edges.
    pub fn sizes(&self) -> (usize, usize, usize) {
        (self.points.len(), self.tris.len(), self.edges.len())
    }

    /// Forces and tangent blocks of the barrier terms: per closest feature for the pairs
    /// without mollifier, per pair for those with it.
    /// The per-feature derivatives go into `out` (a buffer kept between evaluations and
    /// written in place: a derivative is 1.3 KB, and building, zeroing and moving each one
    /// cost more than its arithmetic); the mollified pairs' are those of their terms.
    fn barrier_derivatives(&self, terms: &[Term], x: &(dyn Fn(usize) -> Vector3<f64> + Sync), out: &mut Vec<Derivative>) {
        let grouped = group(terms.iter().filter(|t| !t.parallel && t.energy.is_finite()).map(|t| (t.feature, t.scalar)));
        if out.len() < grouped.len() {
            out.resize(grouped.len(), Derivative::zero());
        }
        out.truncate(grouped.len());
        out.par_iter_mut().zip(&grouped).for_each(|(d, (k, s))| derivative_into(k, s, x, d));
    }

    /// Friction potentials of the committed pairs at `x`.
    fn friction_terms(&self, x: &(dyn Fn(usize) -> Vector3<f64> + Sync), hessian: bool) -> Vec<FrictionTerm> {
        super::friction::terms(&self.committed, self.settings.friction, x, hessian)
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

impl NodalForces for SurfaceContact {
    fn add(&mut self, model: &Model, state: &State, f_ext: &mut [f64], jacobian: &mut Vec<(usize, Matrix3<f64>)>) {
        let mut pairs = Vec::new();
        self.add_coupled(model, state, f_ext, jacobian, &mut pairs);
        // Without pair blocks only the diagonal ones remain (a lumped tangent).
    }

    fn add_coupled(&mut self, model: &Model, state: &State, f_ext: &mut [f64], jacobian: &mut Vec<(usize, Matrix3<f64>)>, pairs: &mut Vec<(usize, usize, Matrix3<f64>)>) {
        let t = Instant::now();
        let pos = positions(model, state);
        let x = |a: usize| pos[a];
        let same = |a: &Vector3<f64>, b: &Vector3<f64>| a.iter().zip(b.iter()).all(|(p, q)| p.to_bits() == q.to_bits());
        let again = self.last_u.len() == self.points.len() && self.points.iter().zip(&self.last_u).all(|(&a, u)| same(&state.u[a], u));
        // What the terms still lack: the derivatives of a kept trial's mollified pairs, or
        // the friction terms of a state measured here.
        let (mut terms, fr, pending) = if again {
            // The state of the last evaluation again, with κ and the friction anchors as they
            // were (a commit clears `last_u`): the tangent projected onto the PSD cone
            // (`project_hessians`, 351 of the 5 cm NBC hood's 1525 iterations). Its pairs and
            // friction terms do not depend on the projection; only their derivatives are
            // formed again.
            (std::mem::take(&mut self.last), std::mem::take(&mut self.last_friction), Pending::Nothing)
        } else {
            let candidates = self.candidates_at(&x);
            match self.take_trial(state, &candidates) {
                // A trial state of the line search, measured by `potential_at`.
                Some(trial) => {
                    self.start_gaps = Some((candidates, trial.gaps));
                    (trial.terms, Vec::new(), Pending::Trial)
                }
                None => {
                    let mut gaps = self.start_gaps.take().map(|g| g.1).unwrap_or_default();
                    let skip = self.inactive_by_bound(&candidates, &x);
                    let terms = self.evaluate_pairs(&candidates, &x, true, skip.as_deref(), Some(&mut gaps));
                    // Kept for the collision detection of the step from this state (`max_step`).
                    self.start_gaps = Some((candidates, gaps));
                    (terms, Vec::new(), Pending::Friction)
                }
            }
        };
        self.search_s += t.elapsed().as_secs_f64();
        let mut pot = 0.0;
        let mut blocks = std::mem::take(&mut self.blocks);
        for term in &terms {
            if !term.energy.is_finite() {
                // Through the offset surface: inadmissible (the line search backs off).
                f_ext[NODE_DOFS * term.nodes[0]] = f64::NAN;
                pot = f64::INFINITY;
                continue;
            }
            pot += term.energy;
        }
        // By reference: a derivative is 1.3 KB, and moving each out of the list cost more
        // than adding it.
        let mut derivatives = std::mem::take(&mut self.derivatives);
        // The same terms again (see above): their exact derivatives, when kept, again.
        let derive = pot.is_finite() && !(again && self.derivatives_exact);
        let finite = pot.is_finite();
        let project = self.project;
        // The per-feature derivatives alongside what the terms still lack (both parallel),
        // then their blocks and forces, summed in parts of the rows (`Blocks`), each part
        // taking every contribution in order: the same values, summed in the same order, as
        // one after the other.
        let (_, (mollified, fr, pending_s)) = rayon::join(
            || {
                if derive {
                    self.barrier_derivatives(&terms, &x, &mut derivatives);
                }
                if finite && project {
                    derivatives.par_iter_mut().for_each(Derivative::project_hessian);
                }
            },
            || {
                let t = Instant::now();
                let (m, f) = match pending {
                    Pending::Nothing => (Vec::new(), fr),
                    Pending::Trial => (self.trial_mollified(&terms, &x), self.friction_terms(&x, true)),
                    Pending::Friction => (Vec::new(), self.friction_terms(&x, true)),
                };
                (m, f, t.elapsed().as_secs_f64())
            },
        );
        self.search_s += pending_s;
        for (i, d) in mollified {
            terms[i].mollified = Some(d);
        }
        // The mollified pairs' derivatives, projected copies when projecting.
        let projected: Vec<Derivative> = if finite && project {
            terms.par_iter().filter_map(|t| t.mollified.as_deref()).map(|d| {
                let mut d = d.clone();
                d.project_hessian();
                d
            }).collect()
        } else {
            Vec::new()
        };
        self.derivatives_exact = finite && !project;
        blocks.sum_in_parts(f_ext, rayon::current_num_threads(), |part| {
            if finite {
                for d in derivatives.iter() {
                    part.add_derivative(d);
                }
                if project {
                    projected.iter().for_each(|d| part.add_derivative(d));
                } else {
                    terms.iter().filter_map(|t| t.mollified.as_deref()).for_each(|d| part.add_derivative(d));
                }
            }
            for ft in &fr {
                part.add_weighted(&ft.nodes, &ft.weights, &ft.g, ft.k.as_ref());
            }
        });
        self.derivatives = derivatives;
        for ft in &fr {
            pot += ft.energy;
        }
        // The solver adds the symmetric part −½(J + Jᵀ) of a pushed block J at (a, b) and
        // (b, a): pushing 2J once for a < b gives J at (a, b) and Jᵀ at (b, a).
        blocks.take(|a, j| jacobian.push((a, j)), |a, b, j| pairs.push((a, b, j * 2.0)));
        self.blocks = blocks;
        self.last = terms;
        self.last_friction = fr;
        self.last_u = self.points.iter().map(|&a| state.u[a]).collect();
        self.last_potential = pot;
        if let Ok(mut tm) = self.timings.lock() {
            tm.evaluate += t.elapsed().as_secs_f64();
        }
    }

    fn potential(&self) -> Option<f64> {
        Some(self.last_potential)
    }

    fn project_hessians(&mut self, on: bool) {
        self.project = on;
    }

    fn indefinite_pairs(&self) -> bool {
        true
    }

    /// The barrier and friction energies at `state` summed as `add_coupled` sums them (the
    /// same value, bit for bit: the same terms in the same order), without their gradients
    /// and Hessians; infinite at a pair through zero gap. The record of the last evaluation
    /// (`last`, used by `commit`) is left alone.
    fn potential_at(&mut self, model: &Model, state: &State) -> Option<f64> {
        let t = Instant::now();
        let pot = self.trial_potential(model, state);
        if let Ok(mut tm) = self.timings.lock() {
            tm.evaluate += t.elapsed().as_secs_f64();
        }
        Some(pot)
    }

    fn is_barrier(&self) -> bool {
        true
    }

    /// Additive CCD: along the straight move from `from` to `to`, a pair's distance falls at
    /// most by the sum of its two primitives' largest nodal moves relative to the pair's mean
    /// move per unit of the step, so from a gap g it may advance by (g − g_min)/ℓ, g_min = (1 − CCD_CLOSE) g₀,
    /// repeatedly; the smallest fraction over all candidate pairs of the sweep is the bound.
    fn max_step(&self, model: &Model, from: &State, to: &State) -> f64 {
        self.collision_free_fraction(model, from, to)
    }

    /// Reports the converged `state`, moves the friction anchors of sliding pairs (return
    /// mapping), commits every active pair's friction data and doubles κ where a pair came
    /// too close. The pairs are those of the last evaluation when it was at this very state
    /// (the last Newton iterate, bit for bit), else evaluated anew.
    fn commit(&mut self, model: &Model, state: &State) -> Option<serde_json::Value> {
        let t = Instant::now();
        self.forget_trial();
        let x = |a: usize| model.x0[a] + state.u[a];
        let same = self.last_u.len() == self.points.len() && self.points.iter().zip(&self.last_u).all(|(&a, u)| state.u[a] == *u);
        let (terms, fr) = if same {
            (std::mem::take(&mut self.last), std::mem::take(&mut self.last_friction))
        } else {
            let terms = self.evaluate(model, state, false);
            let fr = self.friction_terms(&x, false);
            self.search_s += t.elapsed().as_secs_f64();
            (terms, fr)
        };
        if let Ok(mut tm) = self.timings.lock() {
            if same {
                tm.commits_reused += 1;
            } else {
                tm.commits_evaluated += 1;
            }
        }
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
        self.committed = super::friction::committed(&self.friction);
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
        let mut features: Vec<FeatureKey> = terms.iter().map(|t| t.feature).collect();
        features.sort_unstable();
        features.dedup();
        rep.features = features.len();
        rep.features_per_node = rep.features as f64 / self.points.len().max(1) as f64;
        self.last = terms;
        // κ and the friction data changed: the next commit evaluates anew unless an
        // assembly comes first.
        self.last_u.clear();
        self.last_friction.clear();
        if let Ok(mut tm) = self.timings.lock() {
            tm.commit += t.elapsed().as_secs_f64();
        }
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
                "timings": self.timings.lock().map(|t| t.clone()).unwrap_or_default(),
            }),
        ))
    }

    /// None: the tangent's pattern takes the contact blocks as they come (the solver grows
    /// it, and redoes the symbolic analysis, when an assembly reports a block outside it),
    /// so it holds only node pairs some Newton iterate actually coupled. No pair is active in
    /// the reference (stacked plies start at gap d̂, see `constants`), so any prediction from
    /// it is a guess, and the guesses cost fill: coupling every candidate within the broad
    /// phase's reach of twice the largest half thickness — which takes in plies with a third
    /// one between them (ply 1 against ply 3 of the NBC sleeve: 7,296 node pairs that can
    /// only touch where the middle ply slides out) and the facets of tilted boxes — grew the
    /// NBC sleeve's Cholesky factor from 528,429 entries to 2,259,606 (×4.3); with the blocks
    /// as they come it ends at 975,219 (×1.8) after 16 growths (about 0.03 s of analysis
    /// each), and the static solve takes 41 instead of 76 Newton iterations, 7.2 instead of
    /// 13.7 s (factorization 2.1 instead of 8.0 s; the same machine, loaded 3–5;
    /// `examples/contact_cost.rs`); on the sleeve sewn on the arm (1029 iterations either way)
    /// the factor ends at 1,562,519 entries instead of 2,668,486 after 106 growths, and
    /// factorizing takes 135 instead of 233 s (loaded 5–6). Any ordering change moves the
    /// static sleeve's path: its tangent is indefinite in some iterations (the exact barrier
    /// Hessian's tangential term κ b′ ∇²d < 0 where a node presses on a vertex), and an
    /// indefinite tangent is factorized as LDLᵀ without pivoting, which depends on the
    /// elimination order; a pattern of the candidates within twice the pairs' contact
    /// distance (factor 1,143,978) did not converge in its first increment.
    fn couplings(&self, _model: &Model) -> Vec<(usize, usize)> {
        Vec::new()
    }
}

/// The nodes' positions x = X + u at `state`, formed once per evaluation: the pairs, friction
/// terms and derivatives read each node's position many times (the same sums as forming
/// X + u at each read).
fn positions(model: &Model, state: &State) -> Vec<Vector3<f64>> {
    model.x0.iter().zip(&state.u).map(|(x, u)| x + u).collect()
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
