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
use parry3d_f64::math::Vector as PVec;
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy};
use parry3d_f64::query::PointQuery;
use parry3d_f64::shape::Triangle;
use rayon::prelude::*;
use serde::Serialize;

use crate::element::NODE_DOFS;
use crate::model::{Model, State};
use crate::solver::NodalForces;

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

/// Inter-ply contact controls.
#[derive(Clone, Debug)]
pub struct InterplySettings {
    /// Penalty factor c in k_n = c·min(A_s, A_m)·a/ℓ².
    pub penalty_factor: f64,
    /// Explicit nodal normal penalty (N/m), overriding the automatic choice.
    pub penalty: Option<f64>,
    /// Coulomb friction coefficient between plies.
    pub friction: f64,
    /// Tangential penalty as a fraction of the normal one.
    pub tangential_factor: f64,
}

impl Default for InterplySettings {
    /// Penalty factor 1, friction 0.3 (a representative fabric-on-fabric coefficient: woven
    /// fabrics on each other measure about 0.2–0.5, e.g. Ajayi 1992, *Textile Res. J.* 62),
    /// tangential penalty equal to the normal one.
    fn default() -> Self {
        Self { penalty_factor: 1.0, penalty: None, friction: 0.3, tangential_factor: 1.0 }
    }
}

/// Which plies touch: pairs of adjacent plies (model part indices) and the controls.
#[derive(Clone, Debug)]
pub struct InterplySetup {
    /// Adjacent plies (part a, part b); each ply's nodes meet the other's surface.
    pub ply_pairs: Vec<(usize, usize)>,
    /// Penalty and friction controls.
    pub settings: InterplySettings,
    /// Barrier contact between all the garment's surfaces instead of the node-to-surface
    /// penalty (`contact::ipc`).
    pub barrier: Option<crate::contact::ipc::SurfaceSetup>,
}

/// How plies (and panels) touch each other.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub enum InterplyFormulation {
    /// Node-to-surface penalty between adjacent plies of a panel (this module).
    Penalty,
    /// Barrier potentials over point–triangle and edge–edge pairs of every ply of every
    /// panel (`contact::ipc`): intersection-free, smooth, with self-contact.
    Barrier {
        /// Barrier thickness d̂ as a fraction of the contact distance (default 0.2).
        #[serde(default = "default_distance_factor")]
        distance_factor: f64,
        /// Factor on the automatic barrier stiffness (default 1).
        #[serde(default = "one")]
        stiffness_factor: f64,
        /// Friction stick regularisation δ as a multiple of d̂ (default 1).
        #[serde(default = "one")]
        friction_slip: f64,
        /// Whether each ply also contacts itself (default true).
        #[serde(default = "yes")]
        self_contact: bool,
        /// Largest compression of the thickness, as a fraction of the thinner ply's, before
        /// the barrier stiffens (default 0.05).
        #[serde(default = "default_compression")]
        compression_tolerance: f64,
    },
}

fn default_distance_factor() -> f64 {
    crate::contact::ipc::SurfaceSettings::default().distance_factor
}
fn default_compression() -> f64 {
    crate::contact::ipc::SurfaceSettings::default().compression_tolerance
}
fn one() -> f64 {
    1.0
}
fn yes() -> bool {
    true
}

impl Default for InterplyFormulation {
    /// The barrier with its default controls: d̂ from the plies' thicknesses and κ from the
    /// nodes' weights or membrane stiffness (`contact::ipc::surface`).
    fn default() -> Self {
        let s = crate::contact::ipc::SurfaceSettings::default();
        Self::Barrier {
            distance_factor: s.distance_factor,
            stiffness_factor: s.stiffness_factor,
            friction_slip: s.friction_slip,
            self_contact: s.self_contact,
            compression_tolerance: s.compression_tolerance,
        }
    }
}

/// Inter-ply contact settings of a garment (`garment.interply` in a scene file).
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct InterplySpec {
    /// Contact between the plies, the panels and each ply with itself (default on, with the
    /// `Barrier` formulation). The `Penalty` formulation (an explicit opt-in) does not
    /// converge on the hanging NBC sleeve: a liner node inside the faceted carbon cylinder
    /// projects into two neighbouring facets at nearly equal distance, its closest facet — and
    /// with it the force direction — switches by the 19° between their normals, and Newton
    /// 2-cycles. The `Barrier` formulation has no closest facet (a smooth sum over all
    /// point–triangle and edge–edge pairs) and solves it (`garments/nbc_sleeve.ron`).
    pub enabled: bool,
    /// Barrier (default) or penalty formulation.
    pub formulation: InterplyFormulation,
    /// Penalty factor c in k_n = c·min(A_s, A_m)·a/ℓ² (default 1).
    pub penalty_factor: f64,
    /// Explicit nodal normal penalty (N/m), overriding the automatic choice.
    pub penalty: Option<f64>,
    /// Coulomb friction coefficient between plies (default 0.3, see [`InterplySettings`]).
    pub friction: f64,
    /// Tangential penalty as a fraction of the normal one (default 1).
    pub tangential_factor: f64,
}

impl Default for InterplySpec {
    fn default() -> Self {
        let s = InterplySettings::default();
        Self { enabled: true, formulation: InterplyFormulation::default(), penalty_factor: s.penalty_factor, penalty: s.penalty, friction: s.friction, tangential_factor: s.tangential_factor }
    }
}

/// The inter-ply contact of a meshed garment: every pair of adjacent plies (k, k+1) of each
/// multi-ply panel (model parts `first_part + i` for garment part i), with the garment's
/// settings; None when disabled or no panel has two plies. Bad settings are errors located
/// at their key in the scene file.
pub fn garment_setup(
    spec: &crate::garment::GarmentSpec,
    mesh: &crate::garment::GarmentMesh,
    first_part: usize,
    loc: &crate::scene::Locator,
) -> Result<Option<InterplySetup>, crate::scene::SceneError> {
    let s = &spec.interply;
    let bad = |key: &str, msg: &str| loc.at(Some("interply"), Some(key), format!("garment.interply.{key}"), msg.to_string());
    let ok = |x: f64| x.is_finite() && x > 0.0;
    if !ok(s.penalty_factor) {
        return Err(bad("penalty_factor", "expected a positive penalty factor"));
    }
    if s.penalty.is_some_and(|k| !ok(k)) {
        return Err(bad("penalty", "expected a positive nodal penalty (N/m)"));
    }
    if !(s.friction.is_finite() && s.friction >= 0.0) {
        return Err(bad("friction", "expected a non-negative friction coefficient"));
    }
    if !ok(s.tangential_factor) {
        return Err(bad("tangential_factor", "expected a positive tangential factor"));
    }
    let mut ply_pairs = Vec::new();
    for (i, p) in mesh.parts.iter().enumerate() {
        if let Some(j) = mesh.parts.iter().position(|q| q.panel == p.panel && q.ply == p.ply + 1) {
            ply_pairs.push((first_part + i, first_part + j));
            ply_pairs.push((first_part + j, first_part + i));
        }
    }
    let settings = InterplySettings { penalty_factor: s.penalty_factor, penalty: s.penalty, friction: s.friction, tangential_factor: s.tangential_factor };
    if let InterplyFormulation::Barrier { distance_factor, stiffness_factor, friction_slip, self_contact, compression_tolerance } = s.formulation {
        let surface = crate::contact::ipc::SurfaceSettings { distance_factor, stiffness_factor, friction: s.friction, friction_slip, self_contact, compression_tolerance };
        if let Some((key, msg)) = surface.problem() {
            return Err(bad(&format!("formulation.{key}"), msg));
        }
        if !s.enabled || (ply_pairs.is_empty() && mesh.parts.len() < 2 && !self_contact) {
            return Ok(None);
        }
        let parts = (first_part..first_part + mesh.parts.len()).collect();
        return Ok(Some(InterplySetup { ply_pairs, settings, barrier: Some(crate::contact::ipc::SurfaceSetup { parts, settings: surface }) }));
    }
    if !s.enabled || ply_pairs.is_empty() {
        return Ok(None);
    }
    Ok(Some(InterplySetup { ply_pairs, settings, barrier: None }))
}

/// A ply's surface: its quads split into triangles.
#[derive(Clone, Debug)]
struct Surface {
    /// Model part.
    part: usize,
    /// Triangles (global nodes).
    tris: Vec<[usize; 3]>,
    /// Membrane stiffness of the ply (N/m).
    membrane: f64,
    /// Half-thickness of the ply.
    half: f64,
    /// Edges (node pairs, smaller first) of the ply's free boundary: quad sides of one
    /// element that are not sewn (both ends tied).
    boundary: std::collections::BTreeSet<(usize, usize)>,
    /// Nodes on those edges.
    boundary_nodes: std::collections::BTreeSet<usize>,
}

impl Surface {
    /// Whether the closest-point feature of triangle `tri` with barycentric coordinates
    /// `bary` (zero coordinates: the point lies on an edge or at a vertex) lies on the
    /// ply's free boundary.
    fn on_boundary(&self, tri: usize, bary: &[f64; 3]) -> bool {
        let t = self.tris[tri];
        let f: Vec<usize> = (0..3).filter(|&j| bary[j] > 0.0).map(|j| t[j]).collect();
        match f[..] {
            [a, b] => self.boundary.contains(&(a.min(b), a.max(b))),
            [a] => self.boundary_nodes.contains(&a),
            _ => false,
        }
    }

    /// Distance of the node at `y` from the master ply, positive on side `side` — `d` (the
    /// signed closest-point distance from triangle `tri`, barycentric coordinates `bary`)
    /// inside the ply; for a node whose closest point lies on the free boundary, its distance
    /// from the plane of that facet, or `None` more than half an element past the edge; with
    /// whether that boundary plane was used.
    fn distance(&self, tri: usize, bary: &[f64; 3], d: f64, side: f64, x: &dyn Fn(usize) -> Vector3<f64>, y: &Vector3<f64>) -> Option<(f64, bool)> {
        if !self.on_boundary(tri, bary) {
            return Some((side * d, false));
        }
        let p = self.tris[tri].map(x);
        let (lam, n) = project(&p, y)?;
        (lam.iter().all(|&l| l >= -0.5)).then(|| (side * n.dot(&(y - p[0])), true))
    }
}

/// One slave node against one master surface.
#[derive(Clone, Debug)]
struct Record {
    node: usize,
    surface: usize,
    /// Side σ of the master the slave lies on (reference configuration).
    side: f64,
    /// (h_s + h_m)/2.
    offset: f64,
    /// Normal penalty (N/m).
    k_n: f64,
    /// Tributary area of the slave node.
    area: f64,
    /// Characteristic element size at the slave node.
    size: f64,
}

/// Committed state of a record.
#[derive(Clone, Copy, Debug, Default)]
struct History {
    /// Anchor: master triangle and barycentric coordinates of the stuck material point.
    anchor: Option<(usize, [f64; 3])>,
    active: bool,
    sliding: bool,
    slip: f64,
    /// Normal force λ̄ and unit normal n̄ of the last converged state (0 when out of
    /// contact there): the lagged friction bound and tangent plane.
    lagged: (f64, Vector3<f64>),
}

/// Evaluation of a record at a configuration.
#[derive(Clone, Copy, Debug, Default)]
struct Eval {
    /// Projection triangle and barycentric coordinates, when within reach.
    proj: Option<(usize, [f64; 3])>,
    gap: f64,
    lambda: f64,
    tangential: Vector3<f64>,
    /// Unit contact direction on the slave.
    normal: Vector3<f64>,
    active: bool,
    sliding: bool,
}

/// Forces of one record: the nodes, their forces and (optionally) the Jacobian
/// J[3i+α][3j+β] = ∂f_{iα}/∂x_{jβ}.
struct PairForces {
    nodes: Vec<usize>,
    forces: Vec<Vector3<f64>>,
    jacobian: Vec<[f64; NV]>,
}

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

fn pv(v: &Vector3<f64>) -> PVec {
    PVec::new(v.x, v.y, v.z)
}

/// Bounding boxes of a surface's triangles at positions `x`.
fn boxes(s: &Surface, x: &dyn Fn(usize) -> Vector3<f64>) -> Vec<Aabb> {
    s.tris
        .iter()
        .map(|t| {
            let p = t.map(x);
            let lo = p[0].inf(&p[1]).inf(&p[2]);
            let hi = p[0].sup(&p[1]).sup(&p[2]);
            Aabb::new(pv(&lo), pv(&hi))
        })
        .collect()
}

/// Plane projection of `x` on triangle `p`: barycentric coordinates and the unit normal.
fn project(p: &[Vector3<f64>; 3], x: &Vector3<f64>) -> Option<([f64; 3], Vector3<f64>)> {
    let (e1, e2, r) = (p[1] - p[0], p[2] - p[0], x - p[0]);
    let m = e1.cross(&e2);
    let nm = m.norm();
    let (a11, a12, a22) = (e1.dot(&e1), e1.dot(&e2), e2.dot(&e2));
    let det = a11 * a22 - a12 * a12;
    if !(nm > 0.0 && det > 0.0) {
        return None;
    }
    let (b1, b2) = (r.dot(&e1), r.dot(&e2));
    let l1 = (a22 * b1 - a12 * b2) / det;
    let l2 = (a11 * b2 - a12 * b1) / det;
    Some(([1.0 - l1 - l2, l1, l2], m / nm))
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

/// Nearest triangle of `s` to `y` within `reach` (BVH candidates, parry3d closest points):
/// (triangle, barycentric coordinates of the closest point — a coordinate is exactly 0 when
/// the point lies on an edge or vertex — and the signed distance ±|y − x_c|, signed by the
/// side of the triangle's plane).
fn closest(s: &Surface, bvh: &Bvh, x: &dyn Fn(usize) -> Vector3<f64>, y: &Vector3<f64>, reach: f64) -> Option<(usize, [f64; 3], f64)> {
    let q = Aabb::new(pv(&y.add_scalar(-reach)), pv(&y.add_scalar(reach)));
    // Ties (a closest point at a vertex or on an edge shared by several triangles) go to
    // the lowest triangle index, not to the BVH's visiting order, which a perturbation of the
    // nodes reorders: the choice, and with it the facet a boundary node is measured against,
    // is then a function of the configuration.
    let tie = 1e-12 * reach;
    let mut best: Option<(f64, usize)> = None;
    for leaf in bvh.intersect_aabb(&q) {
        let t = leaf as usize;
        let p = s.tris[t].map(x);
        let tri = Triangle::new(pv(&p[0]), pv(&p[1]), pv(&p[2]));
        let proj = tri.project_local_point(pv(y), true);
        let d = (proj.point - pv(y)).length();
        if d <= reach && best.is_none_or(|(bd, bt)| d < bd - tie || (d <= bd + tie && t < bt)) {
            best = Some((d, t));
        }
    }
    let (_, t) = best?;
    let p = s.tris[t].map(x);
    let (_, n) = project(&p, y)?;
    let bary = closest_point_barycentric(&p, y);
    let xc = p[0] * bary[0] + p[1] * bary[1] + p[2] * bary[2];
    let v = y - xc;
    Some((t, bary, v.norm() * n.dot(&v).signum()))
}

/// Barycentric coordinates of the point of triangle `p` closest to `y` (Ericson,
/// *Real-Time Collision Detection*, 2005, §5.1.5): clamped coordinates are exactly zero.
fn closest_point_barycentric(p: &[Vector3<f64>; 3], y: &Vector3<f64>) -> [f64; 3] {
    let (ab, ac, ap) = (p[1] - p[0], p[2] - p[0], y - p[0]);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let bp = y - p[1];
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return [0.0, 1.0, 0.0];
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return [1.0 - v, v, 0.0];
    }
    let cp = y - p[2];
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return [0.0, 0.0, 1.0];
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return [1.0 - w, 0.0, w];
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return [0.0, 1.0 - w, w];
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    [1.0 - v - w, v, w]
}

/// Normal and friction forces of an active record, slave at node `r.node`, projection
/// triangle `tri` (`plane`: measured against the facet's plane, a node overhanging the
/// master's free edge), anchor (triangle nodes, barycentric coordinates) if any; `kt` the
/// tangential penalty. Forces and Jacobian through dual numbers (see the module doc).
#[allow(clippy::too_many_arguments)] // the pair's geometry, history and law, all distinct
fn pair_forces(
    r: &Record,
    tri: [usize; 3],
    bary: [f64; 3],
    plane: bool,
    anchor: Option<([usize; 3], [f64; 3])>,
    lagged: (f64, Vector3<f64>),
    x: &dyn Fn(usize) -> Vector3<f64>,
    mu: f64,
    kt: f64,
    with_tangent: bool,
) -> (Eval, PairForces) {
    let mut nodes = vec![r.node];
    let slot = |a: usize, nodes: &mut Vec<usize>| match nodes.iter().position(|&b| b == a) {
        Some(i) => i,
        None => {
            nodes.push(a);
            nodes.len() - 1
        }
    };
    let ti = tri.map(|a| slot(a, &mut nodes));
    let ai = anchor.map(|(t, _)| t.map(|a| slot(a, &mut nodes)));
    let var = |i: usize| -> V3 {
        let p = x(nodes[i]);
        std::array::from_fn(|k| if with_tangent { D::var(p[k], 3 * i + k) } else { D::c(p[k]) })
    };
    let xs = var(0);
    let xt = ti.map(var);
    let mut f: Vec<V3> = vec![[D::c(0.0); 3]; nodes.len()];
    // Normal part: the closest point x_c of the triangle — inside it (plane projection,
    // normal n of the facet), on an edge or at a vertex (direction (x_s − x_c)/|…|, signed
    // by the facet side) — so the gap is continuous as the node passes between facets.
    let feature: Vec<usize> = (0..3).filter(|&j| bary[j] > 0.0).collect();
    let e1 = sub(&xt[1], &xt[0]);
    let e2 = sub(&xt[2], &xt[0]);
    let m = cross(&e1, &e2);
    let n_facet = scale(&m, D::c(1.0) / dot(&m, &m).sqrt());
    let mut lam = [D::c(0.0); 3];
    let (n, gap) = if feature.len() == 3 || plane {
        let rv = sub(&xs, &xt[0]);
        let (a11, a12, a22) = (dot(&e1, &e1), dot(&e1, &e2), dot(&e2, &e2));
        let (b1, b2) = (dot(&rv, &e1), dot(&rv, &e2));
        let det = a11 * a22 - a12 * a12;
        let l1 = (a22 * b1 - a12 * b2) / det;
        let l2 = (a11 * b2 - a12 * b1) / det;
        lam = [D::c(1.0) - l1 - l2, l1, l2];
        (n_facet, dot(&n_facet, &rv) * r.side - D::c(r.offset))
    } else {
        let xc = if feature.len() == 2 {
            let (i, j) = (feature[0], feature[1]);
            let e = sub(&xt[j], &xt[i]);
            let t = dot(&sub(&xs, &xt[i]), &e) / dot(&e, &e);
            lam[i] = D::c(1.0) - t;
            lam[j] = t;
            add(&xt[i], &scale(&e, t))
        } else {
            let i = feature.first().copied().unwrap_or(0);
            lam[i] = D::c(1.0);
            xt[i]
        };
        let v = sub(&xs, &xc);
        let dist = dot(&v, &v).sqrt();
        let sign = if dot(&n_facet, &v).v * r.side >= 0.0 { 1.0 } else { -1.0 };
        // Unit direction from x_c to the slave, on the slave's side.
        (scale(&v, D::c(sign * r.side) / dist), dist * sign - D::c(r.offset))
    };
    // C¹-regularised penalty (a quadratic ramp over the first ε of penetration, cf. the
    // smoothed penalty of Wriggers 2006 §5.2): λ_N = 0 for g ≥ 0, k_n g²/(2ε) for −ε < g < 0,
    // k_n(−g − ε/2) for g ≤ −ε — continuous with its derivative −k_n·min(1, −g/ε), and zero
    // at g = 0, where plies laid on each other start.
    let eps = EPS_FRAC * r.offset;
    let lambda_n = if gap.v <= -eps { (D::c(-0.5 * eps) - gap) * r.k_n } else { gap * gap * (0.5 * r.k_n / eps) };
    let fn_s = scale(&n, lambda_n * r.side);
    f[0] = add(&f[0], &fn_s);
    for j in 0..3 {
        f[ti[j]] = sub(&f[ti[j]], &scale(&fn_s, lam[j]));
    }
    let normal = Vector3::new(n[0].v, n[1].v, n[2].v) * r.side;
    let mut ev = Eval { gap: gap.v, lambda: lambda_n.v, normal, active: gap.v < 0.0, ..Default::default() };
    // Friction against the anchor (the master's material point where the slave stuck).
    if let (Some((_, nh)), Some(ai)) = (anchor, ai)
        && mu > 0.0
        && lambda_n.v > 0.0
    {
        let xa = (0..3).fold([D::c(0.0); 3], |acc, j| add(&acc, &scale(&var(ai[j]), D::c(nh[j]))));
        let dv = sub(&xs, &xa);
        // Lagged friction (as in `mechanics.rs`; Li et al. 2020 §5): a pair in contact at the
        // last converged state measures the slip in that state's tangent plane n̄ and bounds
        // it by μλ̄, so the friction force is the gradient of a potential of the slip and its
        // Jacobian is symmetric; a pair just coming into contact uses the current ones.
        let (lam_f, nf) = if lagged.0 > 0.0 { (lagged.0, std::array::from_fn(|k| D::c(lagged.1[k] * r.side))) } else { (lambda_n.v, n) };
        let s = sub(&dv, &scale(&nf, dot(&nf, &dv)));
        let sn = dot(&s, &s).sqrt();
        let cap = mu * lam_f;
        // Elastic slip range μλ/k_t, at least SLIP_MIN of the element size.
        let kt = kt.min(cap / (SLIP_MIN * r.size));
        let arg = kt * sn.v / cap;
        // Smooth Coulomb law t = −μλ tanh(k_t|s|/(μλ)) ŝ; its linear (sticking) limit −k_t s
        // near s = 0, where ŝ is undefined.
        let t = if arg < 1e-8 { scale(&s, D::c(-kt)) } else { scale(&s, (sn * (kt / cap)).tanh() * (-cap) / sn) };
        ev.tangential = Vector3::new(t[0].v, t[1].v, t[2].v);
        ev.sliding = arg > SLIDE_ARG;
        f[0] = add(&f[0], &t);
        for j in 0..3 {
            f[ai[j]] = sub(&f[ai[j]], &scale(&t, D::c(nh[j])));
        }
    }
    let forces = f.iter().map(|v| Vector3::new(v[0].v, v[1].v, v[2].v)).collect();
    let jacobian = if with_tangent { f.iter().flat_map(|v| v.iter().map(|c| c.d)).collect() } else { Vec::new() };
    (ev, PairForces { nodes, forces, jacobian })
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

/// A scalar with its gradient with respect to up to [`NV`] variables (forward-mode dual
/// number): exact first derivatives of the contact forces.
#[derive(Clone, Copy, Debug)]
struct D {
    v: f64,
    d: [f64; NV],
}

type V3 = [D; 3];

impl D {
    fn c(v: f64) -> Self {
        Self { v, d: [0.0; NV] }
    }
    fn var(v: f64, i: usize) -> Self {
        let mut d = [0.0; NV];
        d[i] = 1.0;
        Self { v, d }
    }
    fn map(self, v: f64, dv: f64) -> Self {
        Self { v, d: self.d.map(|x| x * dv) }
    }
    fn sqrt(self) -> Self {
        let s = self.v.sqrt();
        self.map(s, 0.5 / s)
    }
    fn tanh(self) -> Self {
        let t = self.v.tanh();
        self.map(t, 1.0 - t * t)
    }
}

impl std::ops::Add for D {
    type Output = D;
    fn add(self, o: D) -> D {
        let mut d = self.d;
        d.iter_mut().zip(&o.d).for_each(|(a, b)| *a += b);
        D { v: self.v + o.v, d }
    }
}

impl std::ops::Sub for D {
    type Output = D;
    fn sub(self, o: D) -> D {
        let mut d = self.d;
        d.iter_mut().zip(&o.d).for_each(|(a, b)| *a -= b);
        D { v: self.v - o.v, d }
    }
}

impl std::ops::Mul for D {
    type Output = D;
    fn mul(self, o: D) -> D {
        let mut d = self.d;
        d.iter_mut().zip(&o.d).for_each(|(a, b)| *a = *a * o.v + self.v * b);
        D { v: self.v * o.v, d }
    }
}

impl std::ops::Mul<f64> for D {
    type Output = D;
    fn mul(self, o: f64) -> D {
        self.map(self.v * o, o)
    }
}

impl std::ops::Div for D {
    type Output = D;
    fn div(self, o: D) -> D {
        let inv = 1.0 / o.v;
        let mut d = self.d;
        d.iter_mut().zip(&o.d).for_each(|(a, b)| *a = (*a - self.v * inv * b) * inv);
        D { v: self.v * inv, d }
    }
}

fn add(a: &V3, b: &V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn sub(a: &V3, b: &V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn scale(a: &V3, s: D) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

fn dot(a: &V3, b: &V3) -> D {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: &V3, b: &V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
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
