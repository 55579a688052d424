//! Compliant seams: stitches as springs between the two sides of a seam, and the per-seam
//! measures of force per length, utilisation and opening.
//!
//! A seam with a stitch stiffness k (N/m per metre of seam, N/m²) joins each slave node s to
//! its mortar point on the master row, x̄_s = Σ_m w_sm x_m ([`super::seam`]), by a spring of
//! the slave's tributary length ℓ_s:
//!
//!   E = Σ_s ½ k ℓ_s |Δ_s|²,  Δ_s = x_s − x̄_s − g₀_s  (g₀ the initial gap, kept at rest),
//!
//! a penalty tie whose compliance is the seam's (a stitched seam opens under load in
//! proportion to its force per length, as seam-slippage tests measure, e.g. ISO 13936-2).
//! The force per length the master side exerts on the slave side is q_s = −k Δ_s; its
//! components along the seam (the slave row's current tangent t) and across it, and the
//! opening |Δ_s − (Δ_s·t) t| (relative displacement across the seam), are the seam's
//! measures; the utilisation is |q_s| / strength. Rigid (tied) seams report their tie force
//! per length ([`SeamInfo::line_forces`]) and zero opening.

use nalgebra::{Matrix3, Vector3};
use serde::Serialize;

use super::SeamInfo;
use crate::element::NODE_DOFS;
use crate::model::{Model, State};
use crate::solver::NodalForces;

/// The springs of all compliant seams of a model.
pub struct CompliantSeams {
    seams: Vec<SeamInfo>,
    energy: f64,
}

impl CompliantSeams {
    /// The compliant seams among `seams` (those with a stiffness); None when there are none.
    pub fn new(seams: &[SeamInfo]) -> Option<Self> {
        let seams: Vec<SeamInfo> = seams.iter().filter(|s| s.stiffness.is_some()).cloned().collect();
        (!seams.is_empty()).then_some(Self { seams, energy: 0.0 })
    }
}

/// Relative displacement Δ_s = x_s − Σ w x_m − g₀ of each slave node of `seam`.
pub fn openings(seam: &SeamInfo, position: impl Fn(usize) -> Vector3<f64>) -> Vec<Vector3<f64>> {
    seam.slave
        .iter()
        .zip(&seam.weights)
        .zip(&seam.rest)
        .map(|((&s, w), g0)| position(s) - w.iter().map(|&(m, c)| position(m) * c).sum::<Vector3<f64>>() - g0)
        .collect()
}

impl NodalForces for CompliantSeams {
    fn add(&mut self, model: &Model, state: &State, f_ext: &mut [f64], jacobian: &mut Vec<(usize, Matrix3<f64>)>) {
        let mut pairs = Vec::new();
        self.add_coupled(model, state, f_ext, jacobian, &mut pairs);
    }

    /// Gradient and Hessian of E: on the slave −kℓΔ, on master m +kℓ w_m Δ; blocks
    /// ∂f_a/∂u_b = −kℓ c_a c_b I with c_s = 1, c_m = −w_m (exact, constant).
    fn add_coupled(
        &mut self,
        model: &Model,
        state: &State,
        f_ext: &mut [f64],
        jacobian: &mut Vec<(usize, Matrix3<f64>)>,
        pairs: &mut Vec<(usize, usize, Matrix3<f64>)>,
    ) {
        let mut energy = 0.0;
        for seam in &self.seams {
            let Some(k) = seam.stiffness else { continue };
            let d = openings(seam, |n| model.position(state, n));
            for (i, &s) in seam.slave.iter().enumerate() {
                let kl = k * seam.tributary[i];
                energy += 0.5 * kl * d[i].norm_squared();
                let nodes: Vec<(usize, f64)> = std::iter::once((s, 1.0)).chain(seam.weights[i].iter().map(|&(m, c)| (m, -c))).collect();
                for &(a, ca) in &nodes {
                    let f = -d[i] * (kl * ca);
                    for c in 0..3 {
                        f_ext[NODE_DOFS * a + c] += f[c];
                    }
                    for &(b, cb) in &nodes {
                        let block = Matrix3::identity() * (-kl * ca * cb);
                        if a == b {
                            jacobian.push((a, block));
                        } else {
                            pairs.push((a, b, block));
                        }
                    }
                }
            }
        }
        self.energy = energy;
    }

    fn potential(&self) -> Option<f64> {
        Some(self.energy)
    }

    fn couplings(&self, _model: &Model) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        for seam in &self.seams {
            for (i, &s) in seam.slave.iter().enumerate() {
                let nodes: Vec<usize> = std::iter::once(s).chain(seam.weights[i].iter().map(|&(m, _)| m)).collect();
                for &a in &nodes {
                    for &b in &nodes {
                        if a != b {
                            out.push((a, b));
                        }
                    }
                }
            }
        }
        out
    }
}

/// Measures at one slave node of a seam.
#[derive(Clone, Copy, Debug, Default)]
pub struct SeamPoint {
    /// Force per length on the slave side (N/m).
    pub force: Vector3<f64>,
    /// Its component along the seam (N/m, signed).
    pub along: f64,
    /// Magnitude of its component across the seam (N/m).
    pub across: f64,
    /// Relative displacement across the seam (m).
    pub opening: f64,
    /// |force| / strength (0 without a strength).
    pub utilisation: f64,
}

/// Per slave node of `seam` at a state given by `position`: the force per length (the
/// springs' for a compliant seam, the ties' from the all-DOF internal and external forces
/// `forces` for a rigid one, zero when they are not given), its components along and
/// across the seam, the opening and the utilisation (module doc).
pub fn seam_points(seam: &SeamInfo, position: impl Fn(usize) -> Vector3<f64> + Copy, forces: Option<(&[f64], &[f64])>) -> Vec<SeamPoint> {
    let n = seam.slave.len();
    let (force, open): (Vec<Vector3<f64>>, Vec<Vector3<f64>>) = match seam.stiffness {
        Some(k) => {
            let d = openings(seam, position);
            (d.iter().map(|v| -v * k).collect(), d)
        }
        None => (forces.map_or_else(|| vec![Vector3::zeros(); n], |(fi, fe)| seam.line_forces(fi, fe)), vec![Vector3::zeros(); n]),
    };
    (0..n)
        .map(|i| {
            let (a, b) = (seam.slave[i.saturating_sub(1)], seam.slave[(i + 1).min(n - 1)]);
            let t = position(b) - position(a);
            let t = if t.norm() > 0.0 { t.normalize() } else { Vector3::zeros() };
            let f = force[i];
            let along = f.dot(&t);
            let opening = (open[i] - t * open[i].dot(&t)).norm();
            let utilisation = seam.strength.map_or(0.0, |s| f.norm() / s);
            SeamPoint { force: f, along, across: (f - t * along).norm(), opening, utilisation }
        })
        .collect()
}

/// The plies of one multi-ply seam taken together: the seams named `base/ply` with the same
/// number of slave nodes (the plies of a panel share its pattern mesh, so their slave rows
/// run through the same pattern points in the same order), their forces per length summed
/// as vectors node by node — the force the whole seam transmits, in which a ply pushed into
/// compression at the seam counts against one in tension (the sum of the plies' magnitudes
/// does not) — and the tributary-weighted mean and max of its magnitude (N/m). Single-ply
/// seams and plies whose rows differ are left out.
#[derive(Clone, Debug, Serialize)]
pub struct PlySummedSeam {
    /// Seam name without the ply (`base`).
    pub name: String,
    /// The plies summed.
    pub plies: usize,
    /// Mean and max of |Σ_plies force per length| (N/m).
    pub force_per_length_mean: f64,
    pub force_per_length_max: f64,
}

/// [`PlySummedSeam`] of every multi-ply seam among `seams` with their points `points`
/// ([`seam_points`]), in the order the seams first appear.
pub fn ply_summed(seams: &[SeamInfo], points: &[Vec<SeamPoint>]) -> Vec<PlySummedSeam> {
    let base = |s: &SeamInfo| s.name.split_once('/').map(|(b, _)| b.to_string());
    let mut names: Vec<String> = Vec::new();
    for s in seams {
        if let Some(b) = base(s) && !names.contains(&b) {
            names.push(b);
        }
    }
    let mut out = Vec::new();
    for name in names {
        let members: Vec<usize> = (0..seams.len()).filter(|&i| base(&seams[i]).as_deref() == Some(name.as_str())).collect();
        let n = seams[members[0]].slave.len();
        if members.len() < 2 || members.iter().any(|&i| seams[i].slave.len() != n || points[i].len() != n) {
            continue;
        }
        let tributary = &seams[members[0]].tributary;
        let total: f64 = tributary.iter().sum::<f64>().max(1e-300);
        let summed: Vec<f64> = (0..n).map(|k| members.iter().map(|&i| points[i][k].force).sum::<Vector3<f64>>().norm()).collect();
        out.push(PlySummedSeam {
            name,
            plies: members.len(),
            force_per_length_mean: summed.iter().zip(tributary).map(|(f, l)| f * l).sum::<f64>() / total,
            force_per_length_max: summed.iter().copied().fold(0.0, f64::max),
        });
    }
    out
}

/// One seam's summary: means (weighted by tributary length), maxima and where.
#[derive(Clone, Debug, Serialize)]
pub struct SeamSummary {
    /// Seam name.
    pub name: String,
    /// Whether the seam is compliant (springs) rather than tied.
    pub compliant: bool,
    /// Stitch stiffness per length (N/m²), if compliant.
    pub stiffness: Option<f64>,
    /// Strength (N/m), if given.
    pub strength: Option<f64>,
    /// Seam length (m, reference).
    pub length: f64,
    /// Mean and max of |force per length| (N/m).
    pub force_per_length_mean: f64,
    pub force_per_length_max: f64,
    /// Mean of the along component (signed) and max of its magnitude (N/m).
    pub along_mean: f64,
    pub along_max: f64,
    /// Mean and max of the across component (N/m).
    pub across_mean: f64,
    pub across_max: f64,
    /// Mean and max utilisation (force per length / strength; null without a strength).
    pub utilisation_mean: Option<f64>,
    pub utilisation_max: Option<f64>,
    /// Mean and max opening (m).
    pub opening_mean: f64,
    pub opening_max: f64,
    /// Where |force per length| is largest: global node and its position.
    pub max_at_node: usize,
    pub max_at: [f64; 3],
}

/// The summary of `seam` from its points ([`seam_points`]).
pub fn summarize(seam: &SeamInfo, points: &[SeamPoint], position: impl Fn(usize) -> Vector3<f64>) -> SeamSummary {
    let total: f64 = seam.tributary.iter().sum::<f64>().max(1e-300);
    let mean = |f: &dyn Fn(&SeamPoint) -> f64| points.iter().zip(&seam.tributary).map(|(p, l)| f(p) * l).sum::<f64>() / total;
    let max = |f: &dyn Fn(&SeamPoint) -> f64| points.iter().map(f).fold(0.0, f64::max);
    let imax = (0..points.len()).max_by(|&a, &b| points[a].force.norm().total_cmp(&points[b].force.norm())).unwrap_or(0);
    let node = seam.slave.get(imax).copied().unwrap_or(0);
    let x = position(node);
    SeamSummary {
        name: seam.name.clone(),
        compliant: seam.stiffness.is_some(),
        stiffness: seam.stiffness,
        strength: seam.strength,
        length: seam.tributary.iter().sum(),
        force_per_length_mean: mean(&|p| p.force.norm()),
        force_per_length_max: max(&|p| p.force.norm()),
        along_mean: mean(&|p| p.along),
        along_max: max(&|p| p.along.abs()),
        across_mean: mean(&|p| p.across),
        across_max: max(&|p| p.across),
        utilisation_mean: seam.strength.map(|_| mean(&|p| p.utilisation)),
        utilisation_max: seam.strength.map(|_| max(&|p| p.utilisation)),
        opening_mean: mean(&|p| p.opening),
        opening_max: max(&|p| p.opening),
        max_at_node: node,
        max_at: [x.x, x.y, x.z],
    }
}
