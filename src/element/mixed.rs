//! Mixed-integration-point stresses for Newton's geometric stiffness.
//!
//! Magisano, Leonetti & Garcea (2017), *How to improve efficiency and robustness of the
//! Newton method in geometrically nonlinear structural problems discretized via
//! displacement-based finite elements* (CMAME 313, 986–1005): the stresses at the
//! integration points are treated as independent variables of the Newton iteration (the
//! Hellinger–Reissner form condensed point by point). Linearising r_u = Σ Bᵀσ − f and
//! r_σ = E(q) − C⁻¹σ at (q_k, σ_k) and eliminating Δσ leaves the displacement system
//! (K_σ(σ_k) + BᵀCB) Δq = f − Bᵀ S(E(q_k)) — the standard residual with the geometric
//! stiffness K_σ evaluated with σ_k — and the stress update σ_{k+1} = S(E_k) + C_k B_k Δq,
//! the stress *extrapolated* along the linearised strain instead of recomputed from
//! E(q_{k+1}). After a Newton step that turns part of a thin shell rigidly, E(q_{k+1})
//! carries the spurious membrane stretch of the linearised rotation (½|Δθ|² per unit
//! length); the displacement-based tangent feeds that stress into K_σ and the next steps
//! zigzag, while the extrapolated σ_{k+1} does not contain it. Since
//! σ̃_{k+1} − S(E_{k+1}) = O(|Δq|²), quadratic convergence is kept.
//!
//! An element records, at each tangent evaluation, its w·detJ-weighted stress S·w and
//! material tangent D·w per integration point ([`PointRecord`], 240 B); the assembler
//! extrapolates them to the next evaluation's configuration ([`extrapolate`]) with the
//! change Δq of the element's unknowns since the record ([`unknown_change`]), the linearised
//! strain change B_k Δq being evaluated afresh from the recorded configuration (one pass
//! over the rule's forms and pairs) instead of storing the 5×20 rows D·B·w of every point
//! (840 B per point, read and written by every tangent assembly).

use nalgebra::{Vector2, Vector3};

use super::director::DirectorFrame;
use super::kinematics::{Kinematics, EDGES, NV, VD, VE};
use super::rule::{ElementGeometry, SectionRule, MAX_FORMS, MAX_PAIRS};
use super::shell4::{natural_strain, ElementFailure};
use super::{ELEMENT_DOFS, NODE_DOFS};
use crate::material::{Tangent5, Voigt5};

/// What a tangent evaluation records at one integration point: the w·detJ-weighted stress
/// (lamina Voigt components as the material returns them) and material tangent, so that the
/// stress of a nearby configuration q is predicted as sw + dw·B_k(q − q_rec) ([`extrapolate`]).
#[derive(Clone, Copy, Debug)]
pub struct PointRecord {
    /// Stress × w·detJ.
    pub sw: Voigt5,
    /// Material tangent D × w·detJ.
    pub dw: Tangent5,
}

impl Default for PointRecord {
    fn default() -> Self {
        Self { sw: Voigt5::zeros(), dw: Tangent5::zeros() }
    }
}

/// Mixed-stress input and output of one element evaluation with its tangent.
pub struct Mixed<'a> {
    /// The extrapolated w·detJ-weighted stress per integration point, used for the geometric
    /// stiffness in place of the stress of the current strains; None: the current stress.
    pub geo: Option<&'a [Voigt5]>,
    /// Receives this evaluation's [`PointRecord`] per integration point.
    pub record: &'a mut [PointRecord],
}

/// Number of integration points of an element's rule: the length of its [`Mixed`] slices.
pub fn point_count(geom: &ElementGeometry) -> usize {
    geom.points.len()
}

/// Change of an element's 20 unknowns from the recorded configuration (`u0`, `f0`) to
/// (`u`, `f`): the translations' difference and, per node, the tilt (α1, α2) in the
/// recorded frame (t1, t2) that carries the recorded director onto the current one along
/// the great circle — the inverse of the exponential map d = cos|θ| d₀ + sin|θ| θ/|θ|
/// of [`DirectorFrame::tilted`].
pub fn unknown_change(u0: &[Vector3<f64>; 4], f0: &[DirectorFrame; 4], u: &[Vector3<f64>; 4], f: &[DirectorFrame; 4]) -> [f64; ELEMENT_DOFS] {
    let mut dq = [0.0; ELEMENT_DOFS];
    for a in 0..4 {
        let du = u[a] - u0[a];
        let d0 = f0[a].d;
        let d = f[a].d;
        let tangential = d - d0 * d0.dot(&d);
        let s = tangential.norm();
        let (a1, a2) = if s > 1e-300 {
            let angle = s.atan2(d0.dot(&d)) / s;
            (angle * tangential.dot(&f0[a].t1), angle * tangential.dot(&f0[a].t2))
        } else {
            (0.0, 0.0)
        };
        let q = &mut dq[NODE_DOFS * a..NODE_DOFS * (a + 1)];
        q.copy_from_slice(&[du.x, du.y, du.z, a1, a2]);
    }
    dq
}

/// The predicted w·detJ-weighted stress σ̃ = sw + dw·(B_k Δq) of each recorded point
/// (the stress update of Magisano, Leonetti & Garcea 2017, σ_{k+1} = S(E_k) + C_k B_k Δq),
/// written into `out`. B_k Δq, the linearised change of the point's lamina strains at the
/// recorded configuration (`u0`, `f0`) along the unknowns' change `dq`, is evaluated as the
/// kernel builds B_k: the kinematic vectors vary by δx̄_a = Δu_a, δd_a = T_a Δα_a,
/// δE_k = J_k (δd_b − δd_a); each form p by δp; each pair strain ½ p·q by
/// ½(δp·q + p·δq); the natural strains are the points' weighted pair sums, mapped to the
/// lamina by the point's strain map (in-plane shear from the level's centre when sampled
/// there). Elements with MITC4+ membrane tying, which ignore mixed stresses, get the
/// recorded stresses unchanged.
///
/// On x86-64 CPUs with AVX2 the same code runs compiled for AVX2, as the element kernel
/// (no fused multiply–adds, so the results are bit-identical).
pub fn extrapolate(
    rule: &SectionRule,
    geom: &ElementGeometry,
    u0: &[Vector3<f64>; 4],
    f0: &[DirectorFrame; 4],
    dq: &[f64; ELEMENT_DOFS],
    records: &[PointRecord],
    out: &mut [Voigt5],
) -> Result<(), ElementFailure> {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2, the only requirement of `extrapolate_avx2`.
        return unsafe { extrapolate_avx2(rule, geom, u0, f0, dq, records, out) };
    }
    extrapolate_kernel(rule, geom, u0, f0, dq, records, out)
}

/// `extrapolate_kernel` compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn extrapolate_avx2(
    rule: &SectionRule,
    geom: &ElementGeometry,
    u0: &[Vector3<f64>; 4],
    f0: &[DirectorFrame; 4],
    dq: &[f64; ELEMENT_DOFS],
    records: &[PointRecord],
    out: &mut [Voigt5],
) -> Result<(), ElementFailure> {
    extrapolate_kernel(rule, geom, u0, f0, dq, records, out)
}

/// The body of [`extrapolate`].
#[inline(always)]
fn extrapolate_kernel(
    rule: &SectionRule,
    geom: &ElementGeometry,
    u0: &[Vector3<f64>; 4],
    f0: &[DirectorFrame; 4],
    dq: &[f64; ELEMENT_DOFS],
    records: &[PointRecord],
    out: &mut [Voigt5],
) -> Result<(), ElementFailure> {
    if rule.membrane.is_some() || records.len() != geom.points.len() || !rule.fits() {
        out.iter_mut().zip(records).for_each(|(o, r)| *o = r.sw);
        return Ok(());
    }
    let kin = Kinematics::new(&geom.r, &geom.phi0, u0, f0)?;
    let mut dvar = [Vector3::zeros(); NV];
    for a in 0..4 {
        let q = &dq[NODE_DOFS * a..NODE_DOFS * (a + 1)];
        dvar[a] = Vector3::new(q[0], q[1], q[2]);
        dvar[VD + a] = kin.tm[a] * Vector2::new(q[3], q[4]);
    }
    for (k, &(a, b)) in EDGES.iter().enumerate() {
        dvar[VE + k] = kin.jac[k] * (dvar[VD + b] - dvar[VD + a]);
    }
    // The recorded forms p and their variations δp (stack scratch, or heap scratch for the
    // long rules of many-ply laminates).
    let n_forms = rule.forms.len();
    let (mut cur_stack, mut var_stack) = ([Vector3::zeros(); MAX_FORMS], [Vector3::zeros(); MAX_FORMS]);
    let (mut cur_heap, mut var_heap) = (Vec::new(), Vec::new());
    let (cur, var): (&mut [Vector3<f64>], &mut [Vector3<f64>]) = if n_forms <= MAX_FORMS {
        (&mut cur_stack[..n_forms], &mut var_stack[..n_forms])
    } else {
        cur_heap.resize(n_forms, Vector3::zeros());
        var_heap.resize(n_forms, Vector3::zeros());
        (&mut cur_heap, &mut var_heap)
    };
    for (f, form) in rule.forms.iter().enumerate() {
        cur[f] = geom.forms[f] + form.eval(&kin.dv);
        var[f] = form.eval(&dvar);
    }
    let mut first = 0;
    for (level, centre) in rule.levels.iter().zip(geom.centres.iter()) {
        let mut de = [0.0; MAX_PAIRS];
        for (d, &(p, q)) in de.iter_mut().zip(&level.pairs) {
            *d = if p == q { var[p].dot(&cur[p]) } else { 0.5 * (var[p].dot(&cur[q]) + var[q].dot(&cur[p])) };
        }
        let shear = if rule.centre_shear { (centre.m.row(2) * natural_strain(&level.centre.comps, &de))[0] } else { 0.0 };
        let n = level.points.len();
        let points = geom.points[first..first + n].iter().zip(&records[first..first + n]).zip(&mut out[first..first + n]);
        for (rp, ((pg, rec), o)) in level.points.iter().zip(points) {
            let mut deps = pg.m * natural_strain(&rp.comps, &de);
            if rule.centre_shear {
                deps[2] = shear;
            }
            *o = rec.sw + rec.dw * deps;
        }
        first += n;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::shell4::tests::{apply, frames, geometry, section_of, strongly_deformed};
    use crate::element::shell4::{ElemMat, ElemVec, ShearTreatment, ShellElement};

    /// The extrapolated stress sw + dw·B_k Δq is the first-order Taylor expansion of the
    /// point stresses about the record: its error against the stresses recorded at the state
    /// a step h away falls by 4 when h halves (and is round-off at h = 0), for every material,
    /// MITC4 and SRI, on a strongly deformed distorted element.
    #[test]
    fn extrapolated_stress_is_second_order_accurate() {
        let (x0, d0) = geometry();
        for shear in [ShearTreatment::Mitc4, ShearTreatment::Sri] {
            for material in ["SVK", "neo-Hookean", "fabric", "laminate"] {
                let sec = section_of(shear, material);
                let el = ShellElement { x0, d0, grain: None, section: &sec };
                let rule = SectionRule::new(&sec).unwrap();
                let geom = el.geometry(&rule).unwrap();
                let n = point_count(&geom);
                let (xa, fa) = apply(&[Vector3::zeros(); 4], &frames(&d0), &(strongly_deformed(&x0) * 0.5));
                let record = |x: &[Vector3<f64>; 4], f: &[DirectorFrame; 4]| {
                    let mut records = vec![PointRecord::default(); n];
                    let mut k = ElemMat::zeros();
                    el.response_mixed(&rule, &geom, x, f, Some(&mut k), Some(super::Mixed { geo: None, record: &mut records })).unwrap();
                    records
                };
                let at_a = record(&xa, &fa);
                let dir = ElemVec::from_fn(|i, _| 0.3 * (((7 * i + 3) % 5) as f64 - 2.0));
                let error = |h: f64| {
                    let (xb, fb) = apply(&xa, &fa, &(dir * h));
                    let at_b = record(&xb, &fb);
                    let mut out = vec![Voigt5::zeros(); n];
                    extrapolate(&rule, &geom, &xa, &fa, &unknown_change(&xa, &fa, &xb, &fb), &at_a, &mut out).unwrap();
                    let scale = at_b.iter().fold(0.0f64, |m, r| m.max(r.sw.abs().max()));
                    out.iter().zip(&at_b).fold(0.0f64, |m, (o, r)| m.max((o - r.sw).abs().max())) / scale
                };
                let (at, h1, h2) = (error(0.0), error(1e-2), error(5e-3));
                assert!(at < 1e-14, "{material} {shear:?}: {at:e} at the record");
                assert!(h1 > 0.0 && (h1 / h2 - 4.0).abs() < 0.4, "{material} {shear:?}: error {h1:e} at h, {h2:e} at h/2 (not second order)");
            }
        }
    }

    #[test]
    fn unknown_change_inverts_the_tilt_and_the_translation() {
        let f0 = [DirectorFrame::new(Vector3::new(0.1, -0.2, 1.0), Some(Vector3::x())); 4];
        let alpha = [[0.3, -0.4], [0.0, 0.0], [1e-9, 2e-9], [-1.2, 0.7]];
        let f: [DirectorFrame; 4] = std::array::from_fn(|a| f0[a].tilted(alpha[a]));
        let u0 = [Vector3::new(1.0, 2.0, 3.0); 4];
        let u: [Vector3<f64>; 4] = std::array::from_fn(|a| u0[a] + Vector3::new(a as f64, -0.5, 0.25));
        let dq = unknown_change(&u0, &f0, &u, &f);
        for a in 0..4 {
            for i in 0..3 {
                assert!((dq[5 * a + i] - (u[a] - u0[a])[i]).abs() < 1e-14);
            }
            assert!((dq[5 * a + 3] - alpha[a][0]).abs() < 1e-12 && (dq[5 * a + 4] - alpha[a][1]).abs() < 1e-12, "node {a}: {:?}", &dq[5 * a + 3..5 * a + 5]);
        }
    }
}
