//! Assembly of the element's internal force and consistent tangent from its pieces (see
//! `shell4`): the material part Σ BᵀDB over the integration points, accumulated on the upper
//! triangle only; the generalised forces of the pair strains on the kinematic vectors, level
//! by level or from their through-thickness resultants; the second derivatives of the strain
//! terms in the kinematic vectors, S; and the geometric part Aᵀ(S⊗I)A + f·∂²V with
//! A = ∂V/∂DOF.

use nalgebra::{Matrix3, Matrix3x2, Vector3};

use super::kinematics::{Kinematics, Lin, EDGES, NV, VD, VE};
use super::rule::SplitPair;
use super::shell4::ElemMat;
use super::ELEMENT_DOFS;

/// A DOF-space row (one strain component's variation, or its stress-weighted image).
pub(super) type Row = [f64; ELEMENT_DOFS];

/// Upper triangle of the material tangent, row-major.
pub(super) type Upper = [[f64; ELEMENT_DOFS]; ELEMENT_DOFS];

/// K_ij += Σ_r B_ri C_rj for i ≤ j: the upper triangle of BᵀC for B, C stored as rows
/// (C = DB with D symmetric makes BᵀC symmetric, so the lower half is the mirror image).
/// Works on 4×4 tiles on and above the diagonal, each accumulated in registers over all
/// rows r; entries below the diagonal inside diagonal tiles are written too and ignored.
#[inline(always)]
pub(super) fn add_upper_btc(k: &mut Upper, b: &[Row], c: &[Row]) {
    const T: usize = 4;
    for ib in (0..ELEMENT_DOFS).step_by(T) {
        for jb in (ib..ELEMENT_DOFS).step_by(T) {
            let mut acc = [[0.0; T]; T];
            for (br, cr) in b.iter().zip(c) {
                let bi: &[f64; T] = br[ib..ib + T].try_into().unwrap_or(&[0.0; T]);
                let cj: &[f64; T] = cr[jb..jb + T].try_into().unwrap_or(&[0.0; T]);
                for (ax, &bx) in acc.iter_mut().zip(bi) {
                    for (axy, &cy) in ax.iter_mut().zip(cj) {
                        *axy += bx * cy;
                    }
                }
            }
            for (x, ax) in acc.iter().enumerate() {
                for (y, &a) in ax.iter().enumerate() {
                    k[ib + x][jb + y] += a;
                }
            }
        }
    }
}

/// Writes the symmetric matrix whose upper triangle is `u` into `k` (overwriting it).
#[inline(always)]
pub(super) fn mirror_into(u: &Upper, k: &mut ElemMat) {
    for j in 0..ELEMENT_DOFS {
        for i in 0..=j {
            k[(i, j)] = u[i][j];
            k[(j, i)] = u[i][j];
        }
    }
}

/// Adds the gradients σ ∂(½ p·q)/∂V_i = ½σ (c^p_i q + c^q_i p) of the pair strains (form
/// indices `pairs`, stress weights `sigma`, current form values `current`) to the generalised
/// forces `fv` and, when `x` is given, their second derivatives to `x`.
#[inline(always)]
pub(super) fn add_pair_forces(sigma: &[f64], pairs: &[(usize, usize)], forms: &[Lin], current: impl Fn(usize) -> Vector3<f64>, fv: &mut [Vector3<f64>; NV], mut x: Option<&mut [[f64; NV]; NV]>) {
    for (&sg, &(p, q)) in sigma.iter().zip(pairs) {
        if sg == 0.0 {
            continue;
        }
        let (lp, lq) = (&forms[p], &forms[q]);
        let half = 0.5 * sg;
        let (pc, qc) = (current(p), current(q));
        for (i, ci) in lp.terms() {
            fv[i] += qc * (half * ci);
        }
        for (i, ci) in lq.terms() {
            fv[i] += pc * (half * ci);
        }
        if let Some(x) = x.as_deref_mut() {
            add_pair_second_derivative(x, lp, lq, sg);
        }
    }
}

/// Adds σ ∂(½ p·q)/∂V summed through the thickness to the generalised forces `fv` and, when
/// `x` is given, the second derivatives to `x`, from the pairs' thickness resultants
/// `s[t]` = [S⁰, S¹, S²] = Σ_ζ σ_t(ζ) ζⁿ and their split forms `split` (see
/// `SectionRule::resultants`): with p = a_p + ζ b_p, q = a_q + ζ b_q (current values
/// `forms0` + `df`), Σ_ζ ½σ (c^p q + c^q p) = ½[c^{a_p}(S⁰q_a + S¹q_b) +
/// c^{b_p}(S¹q_a + S²q_b) + (p ↔ q)] and Σ_ζ ½σ c^p ⊗ c^q = ½[S⁰ a_p⊗a_q +
/// S¹(a_p⊗b_q + b_p⊗a_q) + S² b_p⊗b_q].
#[inline(always)]
pub(super) fn add_resultant_forces(s: &[[f64; 3]], split: &[SplitPair], forms: &[Lin], forms0: &[Vector3<f64>], df: &[Vector3<f64>], fv: &mut [Vector3<f64>; NV], mut x: Option<&mut [[f64; NV]; NV]>) {
    let value = |f: Option<usize>| f.map_or(Vector3::zeros(), |f| forms0[f] + df[f]);
    let mut add = |f: Option<usize>, y: Vector3<f64>| {
        if let Some(f) = f {
            for (i, ci) in forms[f].terms() {
                fv[i] += y * ci;
            }
        }
    };
    for (&[s0, s1, s2], &[ap, bp, aq, bq]) in s.iter().zip(split) {
        if s0 == 0.0 && s1 == 0.0 && s2 == 0.0 {
            continue;
        }
        let (pa, pb, qa, qb) = (value(ap), value(bp), value(aq), value(bq));
        add(ap, (qa * s0 + qb * s1) * 0.5);
        add(bp, (qa * s1 + qb * s2) * 0.5);
        add(aq, (pa * s0 + pb * s1) * 0.5);
        add(bq, (pa * s1 + pb * s2) * 0.5);
        if let Some(x) = x.as_deref_mut() {
            for (f, g, sg) in [(ap, aq, s0), (ap, bq, s1), (bp, aq, s1), (bp, bq, s2)] {
                if let (Some(f), Some(g)) = (f, g) {
                    if sg != 0.0 {
                        add_pair_second_derivative(x, &forms[f], &forms[g], sg);
                    }
                }
            }
        }
    }
}

/// Adds ½σ c^p ⊗ c^q of the pair strain ½(p·q − P·Q) with stress weight σ to `x`, the
/// non-symmetric half of the second-derivative matrix over the kinematic vectors:
/// σ·∂²(½ p·q) = ½σ (c^p ⊗ c^q + c^q ⊗ c^p), so S = X + Xᵀ (see [`symmetric_part`]).
#[inline(always)]
pub(super) fn add_pair_second_derivative(x: &mut [[f64; NV]; NV], p: &Lin, q: &Lin, sigma: f64) {
    let sw = 0.5 * sigma;
    let mut qd = [0.0; NV];
    for (j, cj) in q.terms() {
        qd[j] += cj;
    }
    for (i, ci) in p.terms() {
        let f = sw * ci;
        for (xij, qj) in x[i].iter_mut().zip(&qd) {
            *xij += f * qj;
        }
    }
}

/// S = X + Xᵀ.
#[inline(always)]
pub(super) fn symmetric_part(x: &[[f64; NV]; NV]) -> [[f64; NV]; NV] {
    std::array::from_fn(|i| std::array::from_fn(|j| x[i][j] + x[j][i]))
}

/// Adds Aᵀ(S⊗I)A and the f·∂²V terms to the tangent `k`: `fv` are the generalised forces on
/// the kinematic vectors and `feff` their director-side sums (`Kinematics::director_chain`);
/// ∂²d_a = −(δα·Δα) d_a from the exponential director map and ∂²E_k = J_k ∂²v_k +
/// ∂²F[δv_k, Δv_k].
#[inline(always)]
pub(super) fn add_geometric_tangent(k: &mut ElemMat, s: &[[f64; NV]; NV], fv: &[Vector3<f64>; NV], feff: &[Vector3<f64>; 4], kin: &Kinematics, d: &[Vector3<f64>; 4]) {
    let (tm, jt) = (&kin.tm, &kin.jt);
    // Y[i][b] = Σ_j S_ij ∂V_j/∂α_b over the director-side vectors j.
    let mut y = [[Matrix3x2::<f64>::zeros(); 4]; NV];
    for (i, yi) in y.iter_mut().enumerate() {
        for (b, yib) in yi.iter_mut().enumerate() {
            *yib = tm[b] * s[i][VD + b];
        }
        for (e, &(a, b)) in EDGES.iter().enumerate() {
            let se = s[i][VE + e];
            if se != 0.0 {
                yi[a] += jt[e][0] * se;
                yi[b] += jt[e][1] * se;
            }
        }
    }
    for a in 0..4 {
        for b in 0..4 {
            let (ra, cb) = (5 * a, 5 * b);
            for i in 0..3 {
                k[(ra + i, cb + i)] += s[a][b];
            }
            // Translation–tilt coupling.
            let ud = &y[a][b];
            for i in 0..3 {
                for j in 0..2 {
                    k[(ra + i, cb + 3 + j)] += ud[(i, j)];
                    k[(cb + 3 + j, ra + i)] += ud[(i, j)];
                }
            }
            // Tilt–tilt: Σ_i (∂V_i/∂α_a)ᵀ Y[i][b].
            let mut dd = tm[a].transpose() * y[VD + a][b];
            for (e, &(ea, eb)) in EDGES.iter().enumerate() {
                if ea == a {
                    dd += jt[e][0].transpose() * y[VE + e][b];
                }
                if eb == a {
                    dd += jt[e][1].transpose() * y[VE + e][b];
                }
            }
            for i in 0..2 {
                for j in 0..2 {
                    k[(ra + 3 + i, cb + 3 + j)] += dd[(i, j)];
                }
            }
        }
        // f·∂²d_a through the director and the edges: −(δα·Δα)(feff_a·d_a).
        let diag = -feff[a].dot(&d[a]);
        k[(5 * a + 3, 5 * a + 3)] += diag;
        k[(5 * a + 4, 5 * a + 4)] += diag;
    }
    // f_E·∂²F[δv, Δv] with ∂²(f·F)/∂v² = 2φ'(f vᵀ + v fᵀ + (f·v) I) + 4φ''(f·v) v vᵀ.
    for (e, &(a, b)) in EDGES.iter().enumerate() {
        let f = fv[VE + e];
        if f == Vector3::zeros() {
            continue;
        }
        let v = kin.v[e];
        let [d1, d2] = kin.dphi[e];
        let fvd = f.dot(&v);
        let q = (f * v.transpose() + v * f.transpose() + Matrix3::identity() * fvd) * (2.0 * d1) + v * v.transpose() * (4.0 * d2 * fvd);
        for (na, sa) in [(a, -1.0), (b, 1.0)] {
            for (nb, sb) in [(a, -1.0), (b, 1.0)] {
                let blk = tm[na].transpose() * q * tm[nb] * (sa * sb);
                for i in 0..2 {
                    for j in 0..2 {
                        k[(5 * na + 3 + i, 5 * nb + 3 + j)] += blk[(i, j)];
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use nalgebra::Vector3;

    use super::super::mixed::{extrapolate, point_count, unknown_change, Mixed, PointRecord};
    use super::super::shell4::tests::{apply, frames, geometry, section_of, strongly_deformed};
    use super::super::shell4::{ElemVec, Section, SectionRule, ShearTreatment, ShellElement};
    use crate::material::{LaminaPly, Laminate, Voigt5};

    /// The internal force and geometric stiffness from through-thickness resultants of the
    /// pair stresses (`SectionRule::resultants`) equal the level-by-level sums to rounding:
    /// force, energy and tangent to 1e-12 of their largest entry, for laminates of every
    /// lamina (six or more thickness levels) and every formulation, on a strongly deformed
    /// distorted element, with current and with extrapolated (mixed) stresses.
    #[test]
    fn resultant_forces_equal_the_level_by_level_sums() {
        let (x0, d0) = geometry();
        for shear in [ShearTreatment::Mitc4, ShearTreatment::Sri, ShearTreatment::Mitc4Plus, ShearTreatment::Mitc4PlusCentre] {
            // Laminates of six or more levels: the mixed stack of `section_of` (2 + 2 + 3
            // levels) and three plies of one lamina each (3 × 2 levels; fabric 2 × 3).
            let mut sections = vec![("laminate", section_of(shear, "laminate"))];
            for name in ["SVK", "neo-Hookean", "fabric"] {
                let material = section_of(shear, name).material;
                let n = if name == "fabric" { 2 } else { 3 };
                let ply = |i: usize| LaminaPly { name: format!("{name} {i}"), material: material.clone(), thickness: 0.05 / n as f64, areal_density: None };
                let laminate = Laminate::new((0..n).map(ply).collect()).unwrap();
                sections.push((name, Section { thickness: 0.05, shear, thickness_points: 2, material: Arc::new(laminate) }));
            }
            for (name, sec) in &sections {
                let el = ShellElement { x0, d0, grain: None, section: sec };
                let rule = SectionRule::new(sec).unwrap();
                assert!(rule.resultants.is_some(), "{name} {shear:?}: {} levels without resultants", rule.levels.len());
                let plain = rule.clone().level_by_level();
                let geom = el.geometry(&rule).unwrap();
                let u = strongly_deformed(&x0);
                let (x, f) = apply(&[Vector3::zeros(); 4], &frames(&d0), &u);
                let close = |what: &str, a: &[f64], b: &[f64]| {
                    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                    let diff = a.iter().zip(b).fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
                    assert!(scale > 0.0 && diff <= 1e-12 * scale, "{name} {shear:?} {what}: difference {diff:e} of {scale:e}");
                };
                for tangent in [true, false] {
                    let (mut k1, mut k2) = (super::ElemMat::zeros(), super::ElemMat::zeros());
                    let (f1, e1) = el.response_into(&rule, &geom, &x, &f, tangent.then_some(&mut k1)).unwrap();
                    let (f2, e2) = el.response_into(&plain, &geom, &x, &f, tangent.then_some(&mut k2)).unwrap();
                    close("force", f1.as_slice(), f2.as_slice());
                    close("energy", &[e1], &[e2]);
                    if tangent {
                        close("tangent", k1.as_slice(), k2.as_slice());
                    }
                }
                // Mixed stresses: a record here, the tangent a step away with extrapolated stresses.
                let n = point_count(&geom);
                let mut records = vec![PointRecord::default(); n];
                let mut k = super::ElemMat::zeros();
                el.response_mixed(&rule, &geom, &x, &f, Some(&mut k), Some(Mixed { geo: None, record: &mut records })).unwrap();
                let step = ElemVec::from_fn(|i, _| 0.01 * ((i % 7) as f64 - 3.0));
                let (xb, fb) = apply(&x, &f, &step);
                let mut geo = vec![Voigt5::zeros(); n];
                extrapolate(&rule, &geom, &x, &f, &unknown_change(&x, &f, &xb, &fb), &records, &mut geo).unwrap();
                let mut out = Vec::new();
                for r in [&rule, &plain] {
                    let mut scratch = vec![PointRecord::default(); n];
                    let mut k = super::ElemMat::zeros();
                    let (force, _) = el.response_mixed(r, &geom, &xb, &fb, Some(&mut k), Some(Mixed { geo: Some(&geo), record: &mut scratch })).unwrap();
                    out.push((force, k));
                }
                close("mixed force", out[0].0.as_slice(), out[1].0.as_slice());
                close("mixed tangent", out[0].1.as_slice(), out[1].1.as_slice());
            }
        }
    }

    /// The residual-only evaluation (the kernel compiled without the tangent) gives the
    /// force and energy of the evaluation with the tangent bit for bit, for every lamina and
    /// formulation on a strongly deformed distorted element.
    #[test]
    fn residual_only_path_equals_the_tangent_path() {
        let (x0, d0) = geometry();
        for shear in [ShearTreatment::Mitc4, ShearTreatment::Sri, ShearTreatment::Mitc4Plus, ShearTreatment::Mitc4PlusCentre] {
            for material in ["SVK", "neo-Hookean", "fabric", "laminate"] {
                let sec = section_of(shear, material);
                let el = ShellElement { x0, d0, grain: None, section: &sec };
                let rule = SectionRule::new(&sec).unwrap();
                let geom = el.geometry(&rule).unwrap();
                let (x, f) = apply(&[Vector3::zeros(); 4], &frames(&d0), &strongly_deformed(&x0));
                let mut k = super::ElemMat::zeros();
                let with = el.response_into(&rule, &geom, &x, &f, Some(&mut k)).unwrap();
                let without = el.response_into(&rule, &geom, &x, &f, None).unwrap();
                assert!(with == without, "{material} {shear:?}: residual-only force or energy differs");
                assert!(k.abs().max() > 0.0);
            }
        }
    }
}
