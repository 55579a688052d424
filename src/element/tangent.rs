//! Assembly of the element's consistent tangent from its pieces (see `shell4`):
//! the material part Σ BᵀDB over the integration points, accumulated on the upper triangle
//! only; the second derivatives of the strain terms in the kinematic vectors, S; and the
//! geometric part Aᵀ(S⊗I)A + f·∂²V with A = ∂V/∂DOF.

use nalgebra::{Matrix3, Matrix3x2, Vector3};

use super::kinematics::{Kinematics, Lin, EDGES, NV, VD, VE};
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
