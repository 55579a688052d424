//! `ply_model: Auto`: from a converged laminated state, where would the plies of each
//! laminated panel slide or separate? (Issue 18, ply fidelity.)
//!
//! The laminate (`garment::laminate`) bonds the plies: their strains are compatible, E(z) =
//! ε⁰ + z κ through the stack (classical lamination theory, Jones, *Mechanics of Composite
//! Materials*, 2nd ed. 1999, §4.2). Each ply then carries its own membrane force N_k (its law
//! integrated over its band), and what keeps the plies together is read off equilibrium:
//!
//! - **Interface force.** The plies outside interface j (towards the director) are in
//!   equilibrium under their membrane forces, their weight and the traction of the plies
//!   inside: f_j = Σ_{k outside j} (Div P_k + ρ_k g) per reference area must be balanced by
//!   the interface (P_k = F N_k the ply's first Piola–Kirchhoff membrane force; this is the
//!   equilibrium integration of the interlaminar stresses, τ_xz(z) = −∫ (∂σ_x/∂x + ∂τ_xy/∂y)
//!   dz, Jones §4.6 / Pipes & Pagano 1970, on the curved, deformed stack). Div P_k is taken
//!   per element by the divergence theorem (finite volumes: Σ over the element's edges of
//!   the mean of the two elements' tractions P ν ℓ, over the element's area), so its normal
//!   component contains the membrane (Laplace) pressure N : b of the curved outer plies.
//!   Boundary edges use the element's own traction: at a seam every ply is tied, and at a
//!   free edge the interlaminar stresses are a boundary layer about a laminate thickness
//!   wide (Pipes & Pagano 1970), below the panel's scale.
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
//! quilting line of the panel, a node of a seam row, a node whose translations are fixed),
//! averaged over the element's nodes: 0 where every node is tied. A panel is modelled with
//! discrete plies when S_j > [`SLIP_LIMIT`] or P_j > [`PEEL_LIMIT`] at any interface.

use std::collections::HashMap;

use nalgebra::{Matrix2, Matrix3x2, Vector2, Vector3};
use serde::Serialize;

use super::export::GarmentLayout;
use super::spec::GarmentSpec;
use super::SeamInfo;
use crate::material::{ShellMaterial, Voigt5};
use crate::model::{Model, FIXED};

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
    /// Whether the plies would slide or separate (S > SLIP_LIMIT or P > PEEL_LIMIT).
    pub discrete: bool,
    /// Per interface, innermost first.
    pub interfaces: Vec<InterfaceDemand>,
}

/// Bilinear shape function derivatives at the element centre (nodes at (−1,−1), (1,−1),
/// (1,1), (−1,1)).
const DXI: [f64; 4] = [-0.25, 0.25, 0.25, -0.25];
const DETA: [f64; 4] = [-0.25, -0.25, 0.25, 0.25];

/// Unit normals at the nodes: the mean of the adjacent elements' centre normals g_ξ × g_η.
fn node_normals(model: &Model, elements: &[usize], x: &dyn Fn(usize) -> Vector3<f64>) -> HashMap<usize, Vector3<f64>> {
    let mut out: HashMap<usize, Vector3<f64>> = HashMap::new();
    for &e in elements {
        let nodes = model.elements[e].nodes;
        let (mut gx, mut gy) = (Vector3::zeros(), Vector3::zeros());
        for a in 0..4 {
            gx += x(nodes[a]) * DXI[a];
            gy += x(nodes[a]) * DETA[a];
        }
        let n = gx.cross(&gy);
        for &a in &nodes {
            *out.entry(a).or_insert_with(Vector3::zeros) += n;
        }
    }
    for v in out.values_mut() {
        let l = v.norm();
        if l > 0.0 {
            *v /= l;
        }
    }
    out
}

/// Distance from `p` to the segment [a, b].
fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 { (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0) } else { 0.0 };
    ((p[0] - a[0] - t * dx).powi(2) + (p[1] - a[1] - t * dy).powi(2)).sqrt()
}

/// Per element of one laminated part: what the divergence needs.
struct ElementLoads {
    /// Reference area (centre rule, 4 |G_ξ × G_η|).
    area: f64,
    /// First Piola–Kirchhoff membrane force of each ply (bottom first), as a map from the
    /// reference lamina coordinates (e1, e2) to 3D force per reference length.
    p: Vec<Matrix3x2<f64>>,
    /// Reference lamina basis e1, e2.
    e: [Vector3<f64>; 2],
    /// Current director (unit) at the centre.
    d: Vector3<f64>,
    /// Outward reference conormal × length of each edge (a → a+1).
    conormal: [Vector3<f64>; 4],
}

impl ElementLoads {
    /// Traction (force) on edge `k` of ply `ply`: P (e1·ν, e2·ν).
    fn traction(&self, ply: usize, k: usize) -> Vector3<f64> {
        let nu = self.conormal[k];
        self.p[ply] * Vector2::new(self.e[0].dot(&nu), self.e[1].dot(&nu))
    }
}

/// The membrane forces of the plies of element `e` of a laminated part at the deformed
/// positions `x`, with reference and current nodal normals `n0`, `n1` as directors (the
/// bonded plies' mid-planes sit at z̄_k along them, Kirchhoff–Love): each ply's Green–Lagrange
/// strain at two Gauss levels of its band, its own law (`Laminate::plies`), integrated over
/// its thickness.
#[allow(clippy::too_many_arguments)]
fn element_loads(
    model: &Model,
    e: usize,
    x: &dyn Fn(usize) -> Vector3<f64>,
    n0: &HashMap<usize, Vector3<f64>>,
    n1: &HashMap<usize, Vector3<f64>>,
    plies: &[(std::sync::Arc<dyn ShellMaterial>, f64)],
) -> Result<ElementLoads, String> {
    let def = &model.elements[e];
    let nodes = def.nodes;
    let (mut gr, mut dr, mut gc, mut dc) = ([Vector3::zeros(); 2], [Vector3::zeros(); 2], [Vector3::zeros(); 2], [Vector3::zeros(); 2]);
    let mut d_mean = Vector3::zeros();
    for a in 0..4 {
        let (x0, x1) = (model.x0[nodes[a]], x(nodes[a]));
        let (m0, m1) = (n0.get(&nodes[a]).copied().unwrap_or_default(), n1.get(&nodes[a]).copied().unwrap_or_default());
        for (al, dn) in [DXI, DETA].iter().enumerate() {
            gr[al] += x0 * dn[a];
            dr[al] += m0 * dn[a];
            gc[al] += x1 * dn[a];
            dc[al] += m1 * dn[a];
        }
        d_mean += m1;
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
    let mut conormal = [Vector3::zeros(); 4];
    for (k, c) in conormal.iter_mut().enumerate() {
        *c = (model.x0[nodes[(k + 1) % 4]] - model.x0[nodes[k]]).cross(&e3);
    }
    let d = if d_mean.norm() > 0.0 { d_mean.normalize() } else { gc[0].cross(&gc[1]).normalize() };
    Ok(ElementLoads { area, p, e: [e1, e2], d, conormal })
}

/// Slip and peel demand of every laminated multi-ply part of the garment at the deformed
/// node positions `positions` (see the module documentation). `g` is the gravitational
/// acceleration of the scene's weight loads, `friction` the inter-ply Coulomb coefficient.
pub fn evaluate(spec: &GarmentSpec, model: &Model, positions: &[[f64; 3]], layout: &GarmentLayout, seams: &[SeamInfo], g: Vector3<f64>, friction: f64) -> Result<Vec<PanelDemand>, String> {
    let x = |n: usize| positions.get(n).map_or(model.x0[n], |p| Vector3::new(p[0], p[1], p[2]));
    let x0 = |n: usize| model.x0[n];
    let mut out = Vec::new();
    for (part, plies) in layout.part_plies.iter().enumerate() {
        let Some(panel_id) = layout.part_tags.get(part).map(|t| t[0]).filter(|&p| p >= 0 && plies.len() > 1) else { continue };
        let panel_name = layout.panels.get(panel_id as usize).cloned().unwrap_or_default();
        let info = &model.parts[part];
        let elements: Vec<usize> = (info.first_element..info.first_element + info.n_elements).collect();
        let Some(&first) = elements.first() else { continue };
        let section = &model.sections[model.elements[first].section];
        let laminate = section.material.as_laminate().ok_or_else(|| format!("panel \"{panel_name}\": its section is not a laminate"))?;
        let stack: Vec<(std::sync::Arc<dyn ShellMaterial>, f64)> = laminate.plies().iter().map(|p| (p.material.clone(), p.thickness)).collect();
        let density: Vec<f64> = laminate.plies().iter().map(|p| p.areal_density.or_else(|| p.material.areal_density()).unwrap_or(0.0)).collect();
        let names: Vec<String> = laminate.plies().iter().map(|p| p.name.clone()).collect();
        let n0 = node_normals(model, &elements, &x0);
        let n1 = node_normals(model, &elements, &x);
        let loads = elements.iter().map(|&e| element_loads(model, e, &x, &n0, &n1, &stack)).collect::<Result<Vec<_>, _>>().map_err(|m| format!("panel \"{panel_name}\": {m}"))?;
        // Tie distance δ of each node (pattern space).
        let mut tied: Vec<[f64; 2]> = Vec::new();
        for n in info.first_node..info.first_node + info.n_nodes {
            let fixed = (0..3).all(|k| model.dofs.eq.get(5 * n + k) == Some(&FIXED));
            let on_seam = seams.iter().any(|s| s.master.contains(&n) || s.slave.contains(&n));
            if let (true, Some(uv)) = (fixed || on_seam, layout.pattern_uv.get(n).copied().flatten()) {
                tied.push(uv);
            }
        }
        let lines: Vec<&Vec<[f64; 2]>> = spec.stitch_lines.iter().filter(|l| l.panel == panel_name).map(|l| &l.points).collect();
        let uvs: Vec<[f64; 2]> = (info.first_node..info.first_node + info.n_nodes).filter_map(|n| layout.pattern_uv.get(n).copied().flatten()).collect();
        // Without any tie the plies are held by friction alone: δ is the panel's extent (the
        // diagonal of its pattern's bounding box).
        let (lo, hi) = uvs.iter().fold(([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]), |(lo, hi), p| ([lo[0].min(p[0]), lo[1].min(p[1])], [hi[0].max(p[0]), hi[1].max(p[1])]));
        let extent = if uvs.is_empty() { 0.0 } else { ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2)).sqrt() };
        let delta = |n: usize| -> f64 {
            let Some(p) = layout.pattern_uv.get(n).copied().flatten() else { return 0.0 };
            let mut d = extent;
            for t in &tied {
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
        let node_delta: HashMap<usize, f64> = (info.first_node..info.first_node + info.n_nodes).map(|n| (n, delta(n))).collect();
        // Edge neighbours: sorted node pair → (element, edge).
        let mut edges: HashMap<(usize, usize), Vec<(usize, usize)>> = HashMap::new();
        for (i, &e) in elements.iter().enumerate() {
            let nodes = model.elements[e].nodes;
            for k in 0..4 {
                let (a, b) = (nodes[k], nodes[(k + 1) % 4]);
                edges.entry((a.min(b), a.max(b))).or_default().push((i, k));
            }
        }
        let neighbour = |i: usize, k: usize| -> Option<(usize, usize)> {
            let nodes = model.elements[elements[i]].nodes;
            let (a, b) = (nodes[k], nodes[(k + 1) % 4]);
            edges.get(&(a.min(b), a.max(b)))?.iter().copied().find(|&(j, _)| j != i)
        };
        let n_plies = stack.len();
        let mut interfaces = Vec::new();
        for j in 1..n_plies {
            let h_out: f64 = stack[j..].iter().map(|p| p.1).sum();
            let (mut slip_num, mut peel_num, mut force_den, mut slipping, mut area_sum, mut tau_sum, mut p_sum) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
            for (i, l) in loads.iter().enumerate() {
                let mut f = Vector3::zeros();
                for k in j..n_plies {
                    for edge in 0..4 {
                        f += match neighbour(i, edge) {
                            Some((m, me)) => 0.5 * (l.traction(k, edge) - loads[m].traction(k, me)),
                            None => l.traction(k, edge),
                        };
                    }
                }
                f /= l.area;
                for &rho in &density[j..] {
                    f += g * rho;
                }
                let fn_ = f.dot(&l.d);
                let tau = (f - l.d * fn_).norm();
                let p = (-fn_).max(0.0);
                let q = fn_.max(0.0);
                let excess = (tau - friction * p).max(0.0);
                let dl = model.elements[elements[i]].nodes.iter().map(|n| node_delta.get(n).copied().unwrap_or(0.0)).sum::<f64>() / 4.0;
                let p_out: Matrix3x2<f64> = l.p[j..].iter().sum();
                let n_out = p_out.norm();
                slip_num += l.area * excess * dl;
                peel_num += l.area * q * dl * dl / 2.0;
                force_den += l.area * n_out;
                if tau > friction * p {
                    slipping += l.area;
                }
                area_sum += l.area;
                tau_sum += l.area * tau;
                p_sum += l.area * p;
            }
            let ratio = |num: f64, den: f64| if num <= 1e-300 { 0.0 } else if den > 0.0 { num / den } else { f64::INFINITY };
            interfaces.push(InterfaceDemand {
                inner: names[j - 1].clone(),
                outer: names[j].clone(),
                slip_ratio: ratio(slip_num, force_den),
                peel_ratio: ratio(peel_num, force_den * h_out),
                slipping_area_fraction: slipping / area_sum.max(1e-300),
                mean_shear: tau_sum / area_sum.max(1e-300),
                mean_pressure: p_sum / area_sum.max(1e-300),
            });
        }
        let slip_ratio = interfaces.iter().map(|i| i.slip_ratio).fold(0.0, f64::max);
        let peel_ratio = interfaces.iter().map(|i| i.peel_ratio).fold(0.0, f64::max);
        out.push(PanelDemand { panel: panel_name, slip_ratio, peel_ratio, discrete: slip_ratio > SLIP_LIMIT || peel_ratio > PEEL_LIMIT, interfaces });
    }
    Ok(out)
}
