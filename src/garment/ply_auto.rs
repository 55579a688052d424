//! `ply_model: Auto`: from a converged laminated state, where would the plies of each
//! laminated panel slide or separate? (Issue 18, ply fidelity.)
//!
//! The laminate (`garment::laminate`) bonds the plies: their strains are compatible, E(z) =
//! ε⁰ + z κ through the stack (classical lamination theory, Jones, *Mechanics of Composite
//! Materials*, 2nd ed. 1999, §4.2). Each ply then carries its own membrane force N_k (its law
//! integrated over its band), and what keeps the plies together is read off equilibrium:
//!
//! - **Interface force.** The plies outside interface j (towards the director) are in
//!   equilibrium under their internal forces, their weight and the traction of the plies
//!   inside: f_j = Σ_{k outside j} (f_ext,k − f_int,k) at each node, over the node's
//!   tributary area, must be balanced by the interface. f_int,k is ply k's share of the
//!   element's own internal force vector (the element evaluated with a section that keeps
//!   the laminate's thickness rule but only ply k's stress: Σ_k f_int,k is the laminate's
//!   internal force, so at a free node of the converged state Σ_all f_j = 0 up to the
//!   solver's tolerance — the discrete form of integrating the interlaminar stresses from
//!   equilibrium, τ_xz(z) = −∫ (∂σ_x/∂x + ∂τ_xy/∂y) dz, Jones §4.6 / Pipes & Pagano 1970, on
//!   the curved, deformed stack: its normal component holds the membrane (Laplace) pressure
//!   of the curved outer plies and their transverse shear). f_ext,k = ρ_k g A_a, the ply's
//!   weight on the node's tributary area A_a. Nodes of seam rows and fixed nodes carry tie
//!   and support reactions through all plies and are left out (every ply is tied there).
//! - **Friction.** With the director d, the interface pressure is p = max(−f_j·d, 0) and the
//!   shear τ = |f_j − (f_j·d) d|; Coulomb friction holds τ ≤ μ p (μ the garment's inter-ply
//!   friction; 0 without inter-ply contact). The excess τ_ex = max(τ − μ p, 0) must be
//!   carried by the ties (quilting, seams, clamps). Between ties a distance δ apart the
//!   outer plies' force then changes by τ_ex δ (shear lag with the ties as the only shear
//!   connectors, as in the partial-interaction beams of Newmark, Siess & Viest 1951): the
//!   **slip ratio** S_j = ∫ τ_ex δ dA / ∫ |P_out| dA compares it with the outer plies'
//!   membrane force (|P_out| the Frobenius norm of Σ_{k outside j} P_k).
//! - **Peel.** Where f_j·d > 0 the outer plies are pulled off the inner ones by q = f_j·d;
//!   held at ties δ apart under the membrane force |P_out| they lift by w = q δ²/(2|P_out|)
//!   (a membrane strip of span 2δ, w = q (2δ)²/(8N)): the **peel ratio**
//!   P_j = ∫ q δ²/2 dA / ∫ |P_out| h_out dA compares it with the outer plies' thickness.
//!
//! δ is the pattern-space distance of each node to the nearest tie through the stack (a
//! quilting line of the panel, a node of a seam row, a node whose translations are fixed):
//! 0 where a node is tied. |P_out| at a node is the area mean of its elements' centre values
//! (each ply's strain at two Gauss levels of its band from the element's positions and
//! directors, E(z) of x + z d, its own law integrated over its thickness). A panel is modelled with
//! discrete plies when S_j > [`SLIP_LIMIT`] or P_j > [`PEEL_LIMIT`] at any interface.

use std::sync::Arc;

use nalgebra::{Matrix2, Matrix3x2, Vector3};
use serde::Serialize;

use super::export::GarmentLayout;
use super::spec::GarmentSpec;
use super::SeamInfo;
use crate::element::{Section, ShellElement};
use crate::material::{MaterialFailure, PointResponse, ShellMaterial, Tangent5, Voigt5};
use crate::model::{Model, State, FIXED};

/// Largest slip ratio (ply force changed by the unheld interlaminar shear between ties, over
/// the outer plies' membrane force) of a panel kept laminated: the 5 % on seam forces.
pub const SLIP_LIMIT: f64 = 0.05;
/// Largest peel ratio (lift-off between ties over the outer plies' thickness) of a panel kept
/// laminated.
pub const PEEL_LIMIT: f64 = 1.0;

/// Demand against capacity at one interface of a laminated panel.
#[derive(Clone, Debug, Serialize)]
pub struct InterfaceDemand {
    /// The ply inside and the ply outside the interface.
    pub inner: String,
    pub outer: String,
    /// Slip ratio S (see the module documentation).
    pub slip_ratio: f64,
    /// Peel ratio P.
    pub peel_ratio: f64,
    /// Fraction of the panel's area where the shear exceeds the friction, τ > μ p.
    pub slipping_area_fraction: f64,
    /// Area means of the interface shear τ and pressure p (Pa).
    pub mean_shear: f64,
    pub mean_pressure: f64,
}

/// The verdict on one laminated panel.
#[derive(Clone, Debug, Serialize)]
pub struct PanelDemand {
    /// Panel name.
    pub panel: String,
    /// Largest slip and peel ratios over the interfaces.
    pub slip_ratio: f64,
    pub peel_ratio: f64,
    /// Area mean over the free nodes of |Σ_k (f_ext,k − f_int,k)| / A over the whole stack (Pa):
    /// the body's contact force (and the solver's residual), for reference.
    pub stack_residual: f64,
    /// Its normal component's area mean (Pa).
    pub stack_residual_normal: f64,
    /// Whether the plies would slide or separate (S > SLIP_LIMIT or P > PEEL_LIMIT).
    pub discrete: bool,
    /// Per interface, innermost first.
    pub interfaces: Vec<InterfaceDemand>,
}

/// Bilinear shape function derivatives at the element centre (nodes at (−1,−1), (1,−1),
/// (1,1), (−1,1)).
const DXI: [f64; 4] = [-0.25, 0.25, 0.25, -0.25];
const DETA: [f64; 4] = [-0.25, -0.25, 0.25, 0.25];

/// Distance from `p` to the segment [a, b].
fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 { (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0) } else { 0.0 };
    ((p[0] - a[0] - t * dx).powi(2) + (p[1] - a[1] - t * dy).powi(2)).sqrt()
}

/// One ply of a laminate alone: the laminate's thickness rule, the ply's own law inside its
/// band [lo, hi] of the section coordinate ζ, no stress outside it. An element with this
/// section gives ply k's share of the laminate element's internal force.
#[derive(Debug)]
struct OnePly {
    rule: Vec<[f64; 2]>,
    band: (f64, f64),
    material: Arc<dyn ShellMaterial>,
    /// Stress factor of the element's section (a taped seam's band).
    factor: f64,
}

impl OnePly {
    /// The ply's own coordinate of ζ, if ζ lies in its band.
    fn local(&self, zeta: f64) -> Option<f64> {
        let (lo, hi) = self.band;
        (zeta > lo && zeta <= hi).then(|| ((2.0 * zeta - lo - hi) / (hi - lo)).clamp(-1.0, 1.0))
    }
}

impl ShellMaterial for OnePly {
    fn response(&self, strain: &Voigt5) -> Result<PointResponse, MaterialFailure> {
        self.response_at(strain, 0.0)
    }
    fn small_strain_moduli(&self) -> (f64, f64) {
        self.material.small_strain_moduli()
    }
    fn response_at(&self, strain: &Voigt5, zeta: f64) -> Result<PointResponse, MaterialFailure> {
        match self.local(zeta) {
            Some(z) => self.material.response_at(strain, z).map(|mut r| {
                r.stress *= self.factor;
                r.tangent *= self.factor;
                r.energy *= self.factor;
                r
            }),
            None => Ok(PointResponse { stress: Voigt5::zeros(), tangent: Tangent5::zeros(), energy: 0.0 }),
        }
    }
    fn stress_at(&self, strain: &Voigt5, zeta: f64) -> Result<(Voigt5, f64), MaterialFailure> {
        match self.local(zeta) {
            Some(z) => self.material.stress_at(strain, z).map(|(s, w)| (s * self.factor, w * self.factor)),
            None => Ok((Voigt5::zeros(), 0.0)),
        }
    }
    fn thickness_rule(&self) -> Option<Vec<[f64; 2]>> {
        Some(self.rule.clone())
    }
}

/// The membrane forces of the plies of element `e` of a laminated part at the deformed
/// positions `x` with current directors `d1` (reference directors `d0`): each ply's
/// Green–Lagrange strain E(z) of x + z d at two Gauss levels of its band, its own law,
/// integrated over its thickness; returned as first Piola–Kirchhoff forces P_k = F N_k (3×2,
/// from the reference lamina axes to 3D force per reference length), bottom ply first, with
/// the element's reference area.
fn ply_forces(model: &Model, e: usize, x: &dyn Fn(usize) -> Vector3<f64>, d0: &dyn Fn(usize) -> Vector3<f64>, d1: &dyn Fn(usize) -> Vector3<f64>, plies: &[(Arc<dyn ShellMaterial>, f64)]) -> Result<(f64, Vec<Matrix3x2<f64>>), String> {
    let def = &model.elements[e];
    let nodes = def.nodes;
    let (mut gr, mut dr, mut gc, mut dc) = ([Vector3::zeros(); 2], [Vector3::zeros(); 2], [Vector3::zeros(); 2], [Vector3::zeros(); 2]);
    for a in 0..4 {
        let (x0, x1, m0, m1) = (model.x0[nodes[a]], x(nodes[a]), d0(nodes[a]), d1(nodes[a]));
        for (al, dn) in [DXI, DETA].iter().enumerate() {
            gr[al] += x0 * dn[a];
            dr[al] += m0 * dn[a];
            gc[al] += x1 * dn[a];
            dc[al] += m1 * dn[a];
        }
    }
    let normal = gr[0].cross(&gr[1]);
    let area = 4.0 * normal.norm();
    if !(area > 0.0) {
        return Err(format!("element {e}: degenerate reference geometry"));
    }
    let e3 = normal / (area / 4.0);
    let dir1 = def.grain.unwrap_or(gr[0]);
    let mut e1 = dir1 - e3 * e3.dot(&dir1);
    if e1.norm() < 1e-8 * dir1.norm().max(1e-300) {
        e1 = gr[0] - e3 * e3.dot(&gr[0]);
    }
    let e1 = e1.normalize();
    let e2 = e3.cross(&e1);
    // J[i][α] = e_i · G_α; its inverse maps lamina to natural components.
    let j = Matrix2::new(e1.dot(&gr[0]), e1.dot(&gr[1]), e2.dot(&gr[0]), e2.dot(&gr[1]));
    let jinv = j.try_inverse().ok_or_else(|| format!("element {e}: singular reference metric"))?;
    // Deformation gradient on the mid-surface: F e_i = Σ_α g_α (J⁻¹)_{αi}.
    let f = Matrix3x2::from_columns(&[gc[0] * jinv[(0, 0)] + gc[1] * jinv[(1, 0)], gc[0] * jinv[(0, 1)] + gc[1] * jinv[(1, 1)]]);
    let total: f64 = plies.iter().map(|p| p.1).sum();
    let gauss = [-1.0 / 3f64.sqrt(), 1.0 / 3f64.sqrt()];
    let mut p = Vec::with_capacity(plies.len());
    let mut below = -0.5 * total;
    for (material, h) in plies {
        let mut n = Matrix2::zeros();
        for zeta in gauss {
            let z = below + 0.5 * h * (1.0 + zeta);
            let (a, b) = ([gc[0] + dc[0] * z, gc[1] + dc[1] * z], [gr[0] + dr[0] * z, gr[1] + dr[1] * z]);
            let c = Matrix2::new(a[0].dot(&a[0]) - b[0].dot(&b[0]), a[0].dot(&a[1]) - b[0].dot(&b[1]), a[1].dot(&a[0]) - b[1].dot(&b[0]), a[1].dot(&a[1]) - b[1].dot(&b[1]));
            let el = 0.5 * jinv.transpose() * c * jinv;
            let strain = Voigt5::new(el[(0, 0)], el[(1, 1)], 2.0 * el[(0, 1)], 0.0, 0.0);
            let (s, _) = material.stress_at(&strain, zeta).map_err(|m| format!("element {e}: {m}"))?;
            n += Matrix2::new(s[0], s[2], s[2], s[1]) * (0.5 * h);
        }
        p.push(f * n);
        below += h;
    }
    Ok((area, p))
}

/// Slip and peel demand of every laminated multi-ply part of the garment at the converged
/// state `state` (see the module documentation). `g` is the gravitational acceleration of
/// the scene's weight loads, `friction` the inter-ply Coulomb coefficient.
pub fn evaluate(spec: &GarmentSpec, model: &Model, state: &State, layout: &GarmentLayout, seams: &[SeamInfo], g: Vector3<f64>, friction: f64) -> Result<Vec<PanelDemand>, String> {
    let x = |n: usize| model.position(state, n);
    let d0 = |n: usize| model.frames0[n].d;
    let d1 = |n: usize| state.frames[n].d;
    let mut out = Vec::new();
    for (part, plies) in layout.part_plies.iter().enumerate() {
        let Some(panel_id) = layout.part_tags.get(part).map(|t| t[0]).filter(|&p| p >= 0 && plies.len() > 1) else { continue };
        let panel_name = layout.panels.get(panel_id as usize).cloned().unwrap_or_default();
        let located = |m: String| format!("panel \"{panel_name}\": {m}");
        let info = &model.parts[part];
        let elements: Vec<usize> = (info.first_element..info.first_element + info.n_elements).collect();
        // The panel's laminate (any element's; a taped band scales it) and, per section, the
        // one-ply sections of its plies and the section's stress factor.
        let laminate = elements.iter().find_map(|&e| model.sections[model.elements[e].section].material.as_laminate().map(|l| l.0)).ok_or_else(|| located("its section is not a laminate".into()))?;
        let stack: Vec<(Arc<dyn ShellMaterial>, f64)> = laminate.plies().iter().map(|p| (p.material.clone(), p.thickness)).collect();
        let density: Vec<f64> = laminate.plies().iter().map(|p| p.areal_density.or_else(|| p.material.areal_density()).unwrap_or(0.0)).collect();
        let names: Vec<String> = laminate.plies().iter().map(|p| p.name.clone()).collect();
        let mut per_section: std::collections::HashMap<usize, (Vec<Section>, f64)> = std::collections::HashMap::new();
        for &e in &elements {
            let si = model.elements[e].section;
            if per_section.contains_key(&si) {
                continue;
            }
            let section = &model.sections[si];
            let (lam, factor) = section.material.as_laminate().ok_or_else(|| located(format!("element {e}: its section is not a laminate")))?;
            let rule = lam.thickness_rule().unwrap_or_default();
            let total = lam.thickness();
            let mut below = 0.0;
            let plies: Vec<Section> = lam
                .plies()
                .iter()
                .map(|p| {
                    let band = (2.0 * below / total - 1.0, 2.0 * (below + p.thickness) / total - 1.0);
                    below += p.thickness;
                    Section { material: Arc::new(OnePly { rule: rule.clone(), band, material: p.material.clone(), factor }), ..section.clone() }
                })
                .collect();
            per_section.insert(si, (plies, factor));
        }
        let n_plies = stack.len();
        let first_node = info.first_node;
        let n_nodes = info.n_nodes;
        // Per node: tributary area, each ply's internal force, the outer plies' |P_out| (area
        // weighted, per interface).
        let mut area = vec![0.0; n_nodes];
        let mut f_int = vec![vec![Vector3::zeros(); n_plies]; n_nodes];
        let mut p_out = vec![vec![0.0; n_plies]; n_nodes];
        for &e in &elements {
            let def = &model.elements[e];
            let u = def.nodes.map(|n| state.u[n]);
            let frames = def.nodes.map(|n| state.frames[n]);
            let Some((ply_sections, factor)) = per_section.get(&def.section) else { continue };
            let (a_e, mut p) = ply_forces(model, e, &x, &d0, &d1, &stack).map_err(located)?;
            p.iter_mut().for_each(|pk| *pk *= *factor);
            for (k, sec) in ply_sections.iter().enumerate() {
                let el = ShellElement { x0: def.nodes.map(|n| model.x0[n]), d0: def.nodes.map(|n| model.frames0[n].d), grain: def.grain, section: sec };
                let r = el.response(&u, &frames, false).map_err(|m| located(format!("element {e}: {m}")))?;
                for (a, &n) in def.nodes.iter().enumerate() {
                    f_int[n - first_node][k] += Vector3::new(r.force[5 * a], r.force[5 * a + 1], r.force[5 * a + 2]);
                }
            }
            for &n in &def.nodes {
                area[n - first_node] += 0.25 * a_e;
                for j in 1..n_plies {
                    let s: Matrix3x2<f64> = p[j..].iter().sum();
                    p_out[n - first_node][j] += 0.25 * a_e * s.norm();
                }
            }
        }
        // Tied nodes (seam rows, fixed) carry reactions through every ply: left out.
        let tied_node = |n: usize| (0..3).all(|k| model.dofs.eq.get(5 * n + k) == Some(&FIXED)) || seams.iter().any(|s| s.master.contains(&n) || s.slave.contains(&n));
        let tied: Vec<bool> = (first_node..first_node + n_nodes).map(tied_node).collect();
        // Tie distance δ of each node (pattern space).
        let ties_uv: Vec<[f64; 2]> = (first_node..first_node + n_nodes).filter(|&n| tied[n - first_node]).filter_map(|n| layout.pattern_uv.get(n).copied().flatten()).collect();
        let lines: Vec<&Vec<[f64; 2]>> = spec.stitch_lines.iter().filter(|l| l.panel == panel_name).map(|l| &l.points).collect();
        let uvs: Vec<[f64; 2]> = (first_node..first_node + n_nodes).filter_map(|n| layout.pattern_uv.get(n).copied().flatten()).collect();
        // Without any tie the plies are held by friction alone: δ is the panel's extent (the
        // diagonal of its pattern's bounding box).
        let (lo, hi) = uvs.iter().fold(([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]), |(lo, hi), p| ([lo[0].min(p[0]), lo[1].min(p[1])], [hi[0].max(p[0]), hi[1].max(p[1])]));
        let extent = if uvs.is_empty() { 0.0 } else { ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2)).sqrt() };
        let delta = |n: usize| -> f64 {
            let Some(p) = layout.pattern_uv.get(n).copied().flatten() else { return 0.0 };
            let mut d = extent;
            for t in &ties_uv {
                d = d.min(((p[0] - t[0]).powi(2) + (p[1] - t[1]).powi(2)).sqrt());
            }
            for l in &lines {
                for w in l.windows(2) {
                    d = d.min(segment_distance(p, w[0], w[1]));
                }
                if l.len() == 1 {
                    d = d.min(segment_distance(p, l[0], l[0]));
                }
            }
            d
        };
        // Force on the plies from ply j outwards, less the interface, per tributary area.
        let outer_force = |i: usize, j: usize| -> Vector3<f64> { (j..n_plies).map(|k| g * (density[k] * area[i]) - f_int[i][k]).sum::<Vector3<f64>>() / area[i].max(1e-300) };
        let free: Vec<usize> = (0..n_nodes).filter(|&i| !tied[i] && area[i] > 0.0).collect();
        let free_area: f64 = free.iter().map(|&i| area[i]).sum();
        let mean = |v: &dyn Fn(usize) -> f64| free.iter().map(|&i| area[i] * v(i)).sum::<f64>() / free_area.max(1e-300);
        let stack_residual = mean(&|i| outer_force(i, 0).norm());
        let stack_residual_normal = mean(&|i| outer_force(i, 0).dot(&d1(first_node + i)).abs());
        let mut interfaces = Vec::new();
        for j in 1..n_plies {
            let h_out: f64 = stack[j..].iter().map(|p| p.1).sum();
            let (mut slip_num, mut peel_num, mut force_den, mut slipping, mut tau_sum, mut p_sum) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
            for &i in &free {
                let n = first_node + i;
                let d = d1(n);
                let f = outer_force(i, j);
                let fn_ = f.dot(&d);
                let tau = (f - d * fn_).norm();
                let p = (-fn_).max(0.0);
                let q = fn_.max(0.0);
                let excess = (tau - friction * p).max(0.0);
                let dl = delta(n);
                slip_num += area[i] * excess * dl;
                peel_num += area[i] * q * dl * dl / 2.0;
                force_den += p_out[i][j];
                if tau > friction * p {
                    slipping += area[i];
                }
                tau_sum += area[i] * tau;
                p_sum += area[i] * p;
            }
            let ratio = |num: f64, den: f64| if num <= 1e-300 { 0.0 } else if den > 0.0 { num / den } else { f64::INFINITY };
            interfaces.push(InterfaceDemand {
                inner: names[j - 1].clone(),
                outer: names[j].clone(),
                slip_ratio: ratio(slip_num, force_den),
                peel_ratio: ratio(peel_num, force_den * h_out),
                slipping_area_fraction: slipping / free_area.max(1e-300),
                mean_shear: tau_sum / free_area.max(1e-300),
                mean_pressure: p_sum / free_area.max(1e-300),
            });
        }
        let slip_ratio = interfaces.iter().map(|i| i.slip_ratio).fold(0.0, f64::max);
        let peel_ratio = interfaces.iter().map(|i| i.peel_ratio).fold(0.0, f64::max);
        out.push(PanelDemand { panel: panel_name, slip_ratio, peel_ratio, stack_residual, stack_residual_normal, discrete: slip_ratio > SLIP_LIMIT || peel_ratio > PEEL_LIMIT, interfaces });
    }
    Ok(out)
}
