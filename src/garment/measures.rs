//! What a garment engineer reads off one rest state (one pose of a movement protocol):
//! seam force per length, utilisation and opening along every seam; the separation of the
//! plies of every multi-ply panel; the fabric's strain hot spot; the clearance between the
//! garment and the body; and the contact pressure on the body.
//!
//! - **Seams**: [`super::compliant::seam_points`] at each slave node, summarised per seam
//!   ([`super::compliant::summarize`]) and kept as a profile along the seam (arc length on
//!   the reference slave row) for plots.
//! - **Ply separation**: for each pair of adjacent plies (stack order) of a panel, the
//!   distance of every node of the outer ply to the inner ply's current mid-surface (its
//!   quads split into triangles, closest point by parry3d), less the two half thicknesses:
//!   the gap between the ply faces (0 where they touch, negative where they overlap).
//! - **Strain hot spot**: the largest principal membrane Green–Lagrange strain at an
//!   element centre, ε₁ = (E₁₁ + E₂₂)/2 + √(((E₁₁ − E₂₂)/2)² + E₁₂²), with its element,
//!   panel, ply and current centroid.
//! - **Clearance and body pressure**: the barrier contact's point data (`body_clearance`,
//!   the face-to-body distance of every contact node, and `contact_pressure`, its contact
//!   force over its tributary area); the total force on the body is Σ p_a A_a with A_a a
//!   quarter of the reference area of each element at node a (the barrier's tributary area).

use nalgebra::Vector3;
use parry3d_f64::math::Vector as PVec;
use parry3d_f64::query::PointQuery;
use parry3d_f64::shape::TriMesh;
use serde::{Deserialize, Serialize};

use super::compliant::{seam_points, summarize, SeamSummary};
use super::export::GarmentLayout;
use super::SeamInfo;
use crate::model::{Model, State};

/// A seam at one state: its summary and its profile along the seam.
#[derive(Clone, Debug, Serialize)]
pub struct SeamMeasure {
    /// Force, utilisation and opening: means, maxima and where.
    #[serde(flatten)]
    pub summary: SeamSummary,
    /// Resultant Σ q_s ℓ_s of the force per length over the seam (N): the total force the
    /// master side exerts on the slave side.
    pub resultant: [f64; 3],
    /// Profile along the seam (one entry per slave node).
    pub profile: SeamProfile,
}

/// Values along a seam at its slave nodes.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct SeamProfile {
    /// Arc length from the seam's start on the reference slave row (m).
    pub s: Vec<f64>,
    /// |force per length| (N/m).
    pub force: Vec<f64>,
    /// Component of the force per length along the seam (N/m, signed).
    pub along: Vec<f64>,
    /// Component across the seam (N/m).
    pub across: Vec<f64>,
    /// Opening (m).
    pub opening: Vec<f64>,
}

/// Gap between two adjacent plies of one panel.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PlyGap {
    /// Panel name.
    pub panel: String,
    /// Inner and outer ply names.
    pub plies: [String; 2],
    /// Largest, mean and smallest face-to-face gap over the outer ply's nodes (m).
    pub max: f64,
    pub mean: f64,
    pub min: f64,
    /// Where the gap is largest (current position of the outer ply's node).
    pub max_at: [f64; 3],
}

/// The fabric's largest principal membrane strain.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct StrainHotSpot {
    /// Largest principal Green–Lagrange membrane strain at an element centre.
    pub max_principal: f64,
    /// Its 95th percentile over the elements (the hot spot against the typical level).
    pub p95_principal: f64,
    /// Element, its panel and ply (empty outside a garment) and current centroid.
    pub element: usize,
    pub panel: String,
    pub ply: String,
    pub at: [f64; 3],
}

/// Garment–body clearance and the contact pressure on the body.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct BodyContact {
    /// Smallest and mean face-to-body clearance over the contact nodes (m; the mean counts
    /// clearances up to `contact::body::CLEARANCE_RANGE`).
    pub clearance_min: f64,
    pub clearance_mean: f64,
    /// Nodes touching the body (carrying a contact force).
    pub nodes_in_contact: usize,
    /// Largest contact pressure (Pa) and where.
    pub pressure_max: f64,
    pub pressure_max_at: [f64; 3],
    /// Total contact force on the body, Σ p A (N): the sum of the nodal contact force
    /// magnitudes.
    pub total_force: f64,
}

/// All measures of one state.
#[derive(Clone, Debug, Serialize)]
pub struct StateMeasures {
    /// Per seam.
    pub seams: Vec<SeamMeasure>,
    /// Per pair of adjacent plies of a multi-ply panel (empty for single plies).
    pub ply_separation: Vec<PlyGap>,
    /// The strain hot spot.
    pub strain: StrainHotSpot,
    /// Clearance and pressure (None without body contact data).
    pub body: Option<BodyContact>,
}

/// The measures of `state` (module doc). `forces`: all-DOF internal and external forces
/// (for the tie forces of rigid seams); `point_data`: the nodal-force terms' point data
/// (contact pressure, clearance) at `state`.
pub fn measure(
    model: &Model,
    state: &State,
    layout: Option<&GarmentLayout>,
    seams: &[SeamInfo],
    forces: Option<(&[f64], &[f64])>,
    point_data: &[(String, usize, Vec<f64>)],
) -> StateMeasures {
    let position = |n: usize| model.position(state, n);
    let seams = seams
        .iter()
        .map(|s| {
            let points = seam_points(s, position, forces);
            let mut arc = vec![0.0; s.slave.len()];
            for i in 1..s.slave.len() {
                arc[i] = arc[i - 1] + (model.x0[s.slave[i]] - model.x0[s.slave[i - 1]]).norm();
            }
            let profile = SeamProfile {
                s: arc,
                force: points.iter().map(|p| p.force.norm()).collect(),
                along: points.iter().map(|p| p.along).collect(),
                across: points.iter().map(|p| p.across).collect(),
                opening: points.iter().map(|p| p.opening).collect(),
            };
            let r: Vector3<f64> = points.iter().zip(&s.tributary).map(|(p, l)| p.force * *l).sum();
            SeamMeasure { summary: summarize(s, &points, position), resultant: [r.x, r.y, r.z], profile }
        })
        .collect();
    StateMeasures { seams, ply_separation: layout.map(|l| ply_gaps(model, state, l)).unwrap_or_default(), strain: strain_hot_spot(model, state, layout), body: body_contact(model, state, point_data) }
}

/// Largest principal value of a membrane strain (E₁₁, E₂₂, 2E₁₂).
pub fn principal_max(e: [f64; 3]) -> f64 {
    let (m, d, h) = (0.5 * (e[0] + e[1]), 0.5 * (e[0] - e[1]), 0.5 * e[2]);
    m + d.hypot(h)
}

fn names(layout: Option<&GarmentLayout>, part: usize) -> (String, String) {
    let Some(l) = layout else { return (String::new(), String::new()) };
    let tag = l.part_tags.get(part).copied().unwrap_or([-1; 3]);
    let name = |v: &[String], i: i32| usize::try_from(i).ok().and_then(|i| v.get(i)).cloned().unwrap_or_default();
    (name(&l.panels, tag[0]), name(&l.plies, tag[1]))
}

fn centroid(model: &Model, state: &State, e: usize) -> Vector3<f64> {
    model.elements[e].nodes.iter().map(|&n| model.position(state, n)).sum::<Vector3<f64>>() / 4.0
}

fn strain_hot_spot(model: &Model, state: &State, layout: Option<&GarmentLayout>) -> StrainHotSpot {
    use rayon::prelude::*;
    let eps: Vec<f64> = (0..model.elements.len())
        .into_par_iter()
        .map(|e| {
            let nodes = model.elements[e].nodes;
            let u = nodes.map(|n| state.u[n]);
            let f = nodes.map(|n| state.frames[n]);
            model.element(e).centre_state(&u, &f).map_or(f64::NAN, |(s, _)| principal_max([s[0], s[1], s[2]]))
        })
        .collect();
    let Some(e) = (0..eps.len()).filter(|&e| eps[e].is_finite()).max_by(|&a, &b| eps[a].total_cmp(&eps[b])) else { return StrainHotSpot::default() };
    let mut sorted: Vec<f64> = eps.iter().copied().filter(|v| v.is_finite()).collect();
    sorted.sort_by(f64::total_cmp);
    let p95 = sorted[((sorted.len() - 1) as f64 * 0.95).round() as usize];
    let (panel, ply) = names(layout, model.elements[e].part);
    let c = centroid(model, state, e);
    StrainHotSpot { max_principal: eps[e], p95_principal: p95, element: e, panel, ply, at: [c.x, c.y, c.z] }
}

fn ply_gaps(model: &Model, state: &State, layout: &GarmentLayout) -> Vec<PlyGap> {
    let mut out = Vec::new();
    for (panel, pname) in layout.panels.iter().enumerate() {
        // This panel's single-ply parts in stack order (innermost first).
        let mut parts: Vec<(i32, usize)> = layout.part_tags.iter().enumerate().filter(|(_, t)| t[0] == panel as i32 && t[1] >= 0).map(|(p, t)| (t[1], p)).collect();
        parts.sort();
        for w in parts.windows(2) {
            let ((ply_in, inner), (ply_out, outer)) = (w[0], w[1]);
            let info_in = &model.parts[inner];
            let info_out = &model.parts[outer];
            let h = |ply: i32| layout.ply_thickness.get(ply as usize).copied().unwrap_or(0.0);
            let half = 0.5 * (h(ply_in) + h(ply_out));
            let first = info_in.first_node;
            let vertices: Vec<PVec> = (first..first + info_in.n_nodes).map(|n| {
                let x = model.position(state, n);
                PVec::new(x.x, x.y, x.z)
            }).collect();
            let mut triangles = Vec::new();
            for el in model.elements.iter().filter(|el| el.part == inner) {
                let q = el.nodes.map(|n| (n - first) as u32);
                triangles.push([q[0], q[1], q[2]]);
                triangles.push([q[0], q[2], q[3]]);
            }
            let Ok(mesh) = TriMesh::new(vertices, triangles) else { continue };
            let (mut max, mut min, mut sum, mut count, mut max_at) = (f64::NEG_INFINITY, f64::INFINITY, 0.0, 0usize, [0.0; 3]);
            for n in info_out.first_node..info_out.first_node + info_out.n_nodes {
                let x = model.position(state, n);
                let p = mesh.project_local_point(PVec::new(x.x, x.y, x.z), false);
                let d = (x - Vector3::new(p.point.x, p.point.y, p.point.z)).norm() - half;
                sum += d;
                count += 1;
                min = min.min(d);
                if d > max {
                    max = d;
                    max_at = [x.x, x.y, x.z];
                }
            }
            if count > 0 {
                let name = |i: i32| layout.plies.get(i as usize).cloned().unwrap_or_default();
                out.push(PlyGap { panel: pname.clone(), plies: [name(ply_in), name(ply_out)], max, mean: sum / count as f64, min, max_at });
            }
        }
    }
    out
}

fn body_contact(model: &Model, state: &State, point_data: &[(String, usize, Vec<f64>)]) -> Option<BodyContact> {
    let field = |name: &str| point_data.iter().find(|(n, c, _)| n == name && *c == 1).map(|(_, _, v)| v);
    let clearance = field("body_clearance")?;
    let pressure = field("contact_pressure")?;
    let mut area = vec![0.0; model.n_nodes()];
    for (e, el) in model.elements.iter().enumerate() {
        let a = model.element(e).reference_area();
        for &n in &el.nodes {
            area[n] += 0.25 * a;
        }
    }
    let finite: Vec<f64> = clearance.iter().copied().filter(|c| c.is_finite()).collect();
    let mut out = BodyContact { clearance_min: finite.iter().copied().fold(f64::INFINITY, f64::min), ..Default::default() };
    out.clearance_mean = if finite.is_empty() { f64::NAN } else { finite.iter().sum::<f64>() / finite.len() as f64 };
    for (n, &p) in pressure.iter().enumerate() {
        if p > 0.0 {
            out.nodes_in_contact += 1;
            out.total_force += p * area[n];
        }
        if p > out.pressure_max {
            out.pressure_max = p;
            let x = model.position(state, n);
            out.pressure_max_at = [x.x, x.y, x.z];
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mohr's circle: uniaxial strain is its own principal value; a pure engineering shear γ
    /// has principal strains ±γ/2; a rotated uniaxial strain keeps its value.
    #[test]
    fn principal_strain_follows_mohrs_circle() {
        assert!((principal_max([0.01, 0.0, 0.0]) - 0.01).abs() < 1e-15);
        assert!((principal_max([0.0, 0.0, 0.02]) - 0.01).abs() < 1e-15);
        // ε along 30°: E11 = ε cos², E22 = ε sin², 2E12 = 2ε sin cos.
        let (e, c, s) = (0.03f64, 30f64.to_radians().cos(), 30f64.to_radians().sin());
        assert!((principal_max([e * c * c, e * s * s, 2.0 * e * s * c]) - e).abs() < 1e-15);
    }
}
