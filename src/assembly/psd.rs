//! Positive semi-definite projection of a symmetric element tangent (eigenvalue filtering
//! for projected Newton): K = V Λ Vᵀ ↦ V |Λ| Vᵀ = K + 2 Σ_{λ_i<0} |λ_i| v_i v_iᵀ.
//!
//! Only the negative eigenpairs enter the correction, and an element tangent of a projected
//! iteration has few (2.6 of 20 on average on a sheet dropped onto a sphere), so instead of a
//! full eigen decomposition:
//!
//! 1. Householder reduction K = Q T Qᵀ to a tridiagonal T, the reflectors kept but not
//!    accumulated into Q (Golub & Van Loan, *Matrix Computations*, 4th ed., alg. 8.3.1);
//! 2. all eigenvalues of T by the implicit QL iteration without vectors (`tql1` of EISPACK;
//!    Bowdler, Martin, Reinsch & Wilkinson, Numer. Math. 11, 1968), accurate to round-off
//!    of ‖K‖;
//! 3. for each eigenvalue below −ε·m (m the largest diagonal entry of K, ε =
//!    [`PSD_TOLERANCE`]) its eigenvector of T by two steps of inverse iteration on the
//!    tridiagonal LU factors with partial pivoting, orthogonalised against the vectors found
//!    before (as LAPACK's `dstein`, so clustered or repeated eigenvalues get an orthonormal
//!    basis), carried back by the reflectors: v = Q y.
//!
//! Eigenvalues in [−ε·m, 0) are left as they are: each changes the result by at most 2ε·m,
//! so with ε = 10⁻¹² the projection equals V|Λ|Vᵀ within about 2·10⁻¹²·‖K‖₂ plus round-off
//! — the rigid-body modes of a free element, whose eigenvalues are round-off of either sign
//! (≈10⁻¹⁵·m), cost nothing. Before all this a Cholesky factorization of K + ε·m·I that
//! succeeds in floating point proves λ_min(K) ≥ −(ε + n γ_{n+1})·m (Higham, *Accuracy and
//! Stability of Numerical Algorithms*, 2nd ed., thm. 10.5, |L||Lᵀ| bounded entrywise by
//! √(a_ii a_jj); n γ_{n+1} ≈ 4.7·10⁻¹⁴ for n = 20), and K is returned at once.

use crate::element::{ElemMat, ELEMENT_DOFS};

const N: usize = ELEMENT_DOFS;
type Square = [[f64; N]; N];

/// Relative threshold ε: eigenvalues above −ε·max(diag K) are not mirrored, and a tangent
/// whose Cholesky factorization of K + ε·max(diag K)·I succeeds is returned as it is (see
/// the module doc).
pub const PSD_TOLERANCE: f64 = 1e-12;

/// QL sweeps allowed per eigenvalue before the fixed-size solver gives up (and the general
/// solver of nalgebra takes over); two or three are the rule.
const MAX_SWEEPS: usize = 60;

/// Inverse iteration steps per negative eigenvalue: each multiplies the components along
/// the other eigenvectors by (round-off of ‖K‖)/(gap g to their eigenvalues), and such a
/// component changes the result by about g times itself, so after two steps the error is
/// below g·(u‖K‖/g)² ≤ u‖K‖ for any gap g ≥ u‖K‖ (closer eigenvalues are harmless).
const INVERSE_STEPS: usize = 2;

/// Which way [`project_psd_traced`] obtained its result.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Projection {
    /// The Cholesky test passed: the symmetric part is returned as it is.
    Definite,
    /// Eigenvalues computed; those below −ε·m were mirrored (none, possibly).
    Mirrored,
    /// The QL iteration did not converge: nalgebra's `SymmetricEigen` and V|Λ|Vᵀ were
    /// used; or the tangent has a non-finite entry and is returned as it is.
    Fallback,
}

/// The positive semi-definite replacement of the symmetric element tangent `k` = V Λ Vᵀ:
/// V |Λ| Vᵀ of the symmetric part ½(k + kᵀ), the negative curvatures mirrored (Chen,
/// Kaufman et al., *Trust-region eigenvalue filtering for projected Newton*, SIGGRAPH Asia
/// 2024: far from a minimum the absolute value keeps the scale of the curvature, where
/// clamping to zero, Teran et al. SCA 2005, leaves nearly singular directions and huge
/// steps along them). Eigenvalues in [−10⁻¹²·max(diag k), 0) are kept (module doc).
pub fn project_psd(k: &ElemMat) -> ElemMat {
    project_psd_traced(k).0
}

/// [`project_psd`] and which way it went.
pub fn project_psd_traced(k: &ElemMat) -> (ElemMat, Projection) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2, the only requirement of `project_avx2`.
        return unsafe { project_avx2(k) };
    }
    project_kernel(k)
}

/// `project_kernel` compiled for AVX2 (wider vectors for the 20-wide row operations; no
/// fused multiply–adds, so the results are the same bit for bit).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn project_avx2(k: &ElemMat) -> (ElemMat, Projection) {
    project_kernel(k)
}

#[inline(always)]
fn project_kernel(k: &ElemMat) -> (ElemMat, Projection) {
    // Symmetric part, as rows (column-major storage of a symmetric matrix read as rows).
    let mut a: Square = [[0.0; N]; N];
    for (j, col) in a.iter_mut().enumerate() {
        for (i, v) in col.iter_mut().enumerate() {
            *v = 0.5 * (k[(i, j)] + k[(j, i)]);
        }
    }
    let sym = ElemMat::from_fn(|i, j| a[j][i]);
    if a.iter().flatten().any(|x| !x.is_finite()) {
        // Nothing to project (and no eigensolver terminates on it): the assembled tangent
        // carries the non-finite entries to the solver, which reports them.
        return (sym, Projection::Fallback);
    }
    let max_diag = (0..N).map(|i| a[i][i]).fold(0.0, f64::max);
    let threshold = PSD_TOLERANCE * max_diag;
    if cholesky_succeeds(&a, threshold) {
        return (sym, Projection::Definite);
    }
    let Some((count, lambda, v)) = negative_eigenpairs(&a, -threshold) else {
        let e = nalgebra::SymmetricEigen::new(sym);
        let mirrored = e.eigenvalues.map(f64::abs);
        return (&e.eigenvectors * nalgebra::Matrix::from_diagonal(&mirrored) * e.eigenvectors.transpose(), Projection::Fallback);
    };
    if count == 0 {
        return (sym, Projection::Mirrored);
    }
    // K + 2 Σ_{λ<0} |λ| v vᵀ, built on the rows of the symmetric part.
    for (l, vi) in lambda[..count].iter().zip(&v[..count]) {
        let w = -2.0 * l;
        for (row, &vr) in a.iter_mut().zip(vi) {
            let s = w * vr;
            row.iter_mut().zip(vi).for_each(|(x, &y)| *x += s * y);
        }
    }
    (ElemMat::from_fn(|i, j| 0.5 * (a[i][j] + a[j][i])), Projection::Mirrored)
}

/// Whether the Cholesky factorization of the symmetric `a` + `shift`·I runs to the end with
/// positive pivots (outer-product form, Golub & Van Loan, *Matrix Computations*, 4th ed.,
/// alg. 4.2.1: each step a rank-one update of the trailing rows, which vectorises).
#[inline(always)]
fn cholesky_succeeds(a: &Square, shift: f64) -> bool {
    let mut s = *a;
    for j in 0..N {
        let d = s[j][j] + shift;
        if !(d > 0.0) {
            return false;
        }
        let (top, rest) = s.split_at_mut(j + 1);
        let lj = &top[j];
        let inv = 1.0 / d;
        for (i, row) in rest.iter_mut().enumerate() {
            let c = lj[j + 1 + i] * inv;
            row[j + 1..].iter_mut().zip(&lj[j + 1..]).for_each(|(x, &y)| *x -= c * y);
        }
    }
    true
}

/// √(x² + y²) without destructive overflow or underflow.
#[inline(always)]
fn hypot(x: f64, y: f64) -> f64 {
    let (x, y) = (x.abs(), y.abs());
    let (big, small) = if x > y { (x, y) } else { (y, x) };
    if big == 0.0 {
        return 0.0;
    }
    let r = small / big;
    big * (1.0 + r * r).sqrt()
}

/// Householder reduction of the symmetric `a` (overwritten) to tridiagonal T = Qᵀ a Q
/// with Q = H₀ H₁ ⋯ H_{n−3}, H_k = I − β_k v_k v_kᵀ acting on components k+1…n−1
/// (Golub & Van Loan, alg. 8.3.1). Returns the diagonal d, the off-diagonal e (e[k] =
/// T[k][k+1], e[n−1] = 0), the reflector vectors (v_k in row k, zero up to column k) and β.
#[inline(always)]
fn tridiagonalize(a: &mut Square) -> ([f64; N], [f64; N], Square, [f64; N]) {
    let mut d = [0.0; N];
    let mut e = [0.0; N];
    let mut vs: Square = [[0.0; N]; N];
    let mut betas = [0.0; N];
    for k in 0..N - 2 {
        d[k] = a[k][k];
        let v = &mut vs[k];
        v[k + 1..].copy_from_slice(&a[k][k + 1..]);
        let x0 = v[k + 1];
        let tail: f64 = v[k + 2..].iter().fold(0.0, |s, x| s + x * x);
        if tail == 0.0 {
            // Already tridiagonal in this column: H_k = I.
            e[k] = x0;
            v[k + 1..].iter_mut().for_each(|x| *x = 0.0);
            continue;
        }
        let norm = (x0 * x0 + tail).sqrt();
        let alpha = if x0 > 0.0 { -norm } else { norm };
        v[k + 1] = x0 - alpha;
        let vtv = v[k + 1] * v[k + 1] + tail;
        let beta = 2.0 / vtv;
        e[k] = alpha;
        betas[k] = beta;
        // p = β B v, w = p − (β/2)(pᵀv) v, B ← B − v wᵀ − w vᵀ on the trailing block B.
        // B v as a sum of the rows of the symmetric B weighted by v (vectorises).
        let mut p = [0.0; N];
        for (row, &vi) in a[k + 1..].iter().zip(&v[k + 1..]) {
            p[k + 1..].iter_mut().zip(&row[k + 1..]).for_each(|(x, &y)| *x += vi * y);
        }
        p[k + 1..].iter_mut().for_each(|x| *x *= beta);
        let kk = 0.5 * beta * p[k + 1..].iter().zip(&v[k + 1..]).fold(0.0, |s, (x, y)| s + x * y);
        let mut w = [0.0; N];
        for i in k + 1..N {
            w[i] = p[i] - kk * v[i];
        }
        for (i, row) in a.iter_mut().enumerate().skip(k + 1) {
            let (vi, wi) = (v[i], w[i]);
            row[k + 1..].iter_mut().zip(&w[k + 1..]).zip(&v[k + 1..]).for_each(|((x, &wj), &vj)| *x -= vi * wj + wi * vj);
        }
    }
    d[N - 2] = a[N - 2][N - 2];
    d[N - 1] = a[N - 1][N - 1];
    e[N - 2] = a[N - 2][N - 1];
    (d, e, vs, betas)
}

/// Eigenvalues, ascending, of the symmetric tridiagonal matrix with diagonal `d` and
/// off-diagonal `e` (e[k] = T[k][k+1], e[n−1] = 0) by the implicit QL iteration
/// (`tql1`, in the formulation of the public-domain JAMA library); None if an eigenvalue
/// takes more than [`MAX_SWEEPS`] sweeps.
#[inline(always)]
fn tridiagonal_eigenvalues(mut d: [f64; N], mut e: [f64; N]) -> Option<[f64; N]> {
    e[N - 1] = 0.0;
    let mut f = 0.0;
    // Off-diagonals below ε‖T‖ are negligible: every eigenvalue to round-off of ‖T‖.
    let tst1 = (0..N).map(|i| d[i].abs() + e[i].abs()).fold(0.0, f64::max);
    let eps = f64::EPSILON;
    for l in 0..N {
        let mut m = l;
        while m < N - 1 && e[m].abs() > eps * tst1 {
            m += 1;
        }
        if m > l {
            let mut sweeps = 0;
            loop {
                sweeps += 1;
                if sweeps > MAX_SWEEPS {
                    return None;
                }
                // Implicit shift.
                let mut g = d[l];
                let mut p = (d[l + 1] - g) / (2.0 * e[l]);
                let mut r = hypot(p, 1.0);
                if p < 0.0 {
                    r = -r;
                }
                d[l] = e[l] / (p + r);
                d[l + 1] = e[l] * (p + r);
                let dl1 = d[l + 1];
                let mut h = g - d[l];
                for di in &mut d[l + 2..] {
                    *di -= h;
                }
                f += h;
                // Implicit QL transformation.
                p = d[m];
                let (mut c, mut c2, mut c3) = (1.0, 1.0, 1.0);
                let el1 = e[l + 1];
                let (mut s, mut s2) = (0.0, 0.0);
                for i in (l..m).rev() {
                    c3 = c2;
                    c2 = c;
                    s2 = s;
                    g = c * e[i];
                    h = c * p;
                    // No overflow: |p|, |e| ≤ ‖T‖ ≪ 10¹⁵⁰ for any element tangent.
                    r = (p * p + e[i] * e[i]).sqrt();
                    e[i + 1] = s * r;
                    let inv = 1.0 / r;
                    s = e[i] * inv;
                    c = p * inv;
                    p = c * d[i] - s * g;
                    d[i + 1] = h + s * (c * g + s * d[i]);
                }
                p = -s * s2 * c3 * el1 * e[l] / dl1;
                e[l] = s * p;
                d[l] = c * p;
                if !(e[l].abs() > eps * tst1) {
                    break;
                }
            }
        }
        d[l] += f;
        e[l] = 0.0;
    }
    if d.iter().any(|x| !x.is_finite()) {
        return None;
    }
    d.sort_by(f64::total_cmp);
    Some(d)
}

/// LU factors with partial pivoting of the shifted symmetric tridiagonal T − σI (LAPACK
/// `dgttrf`): multipliers, the diagonal and two superdiagonals of U, and the row swaps.
struct ShiftedLu {
    dl: [f64; N],
    /// Diagonal of U while factoring; its reciprocals once factored.
    dd: [f64; N],
    du: [f64; N],
    du2: [f64; N],
    swap: [bool; N],
}

impl ShiftedLu {
    /// Factors T − σI for T with diagonal `d` and off-diagonal `e`; a zero pivot is replaced
    /// by `tiny` (inverse iteration wants the nearly singular system).
    #[inline(always)]
    fn new(d: &[f64; N], e: &[f64; N], sigma: f64, tiny: f64) -> Self {
        let mut f = ShiftedLu { dl: [0.0; N], dd: [0.0; N], du: [0.0; N], du2: [0.0; N], swap: [false; N] };
        for i in 0..N {
            f.dd[i] = d[i] - sigma;
        }
        f.dl[..N - 1].copy_from_slice(&e[..N - 1]);
        f.du[..N - 1].copy_from_slice(&e[..N - 1]);
        for i in 0..N - 1 {
            if f.dd[i].abs() >= f.dl[i].abs() {
                if f.dd[i] == 0.0 {
                    f.dd[i] = tiny;
                }
                let fact = f.dl[i] / f.dd[i];
                f.dl[i] = fact;
                f.dd[i + 1] -= fact * f.du[i];
            } else {
                let fact = f.dd[i] / f.dl[i];
                f.dd[i] = f.dl[i];
                f.dl[i] = fact;
                let temp = f.du[i];
                f.du[i] = f.dd[i + 1];
                f.dd[i + 1] = temp - fact * f.dd[i + 1];
                if i < N - 2 {
                    f.du2[i] = f.du[i + 1];
                    f.du[i + 1] = -fact * f.du[i + 1];
                }
                f.swap[i] = true;
            }
        }
        if f.dd[N - 1] == 0.0 {
            f.dd[N - 1] = tiny;
        }
        // The back substitution multiplies by the reciprocal pivots.
        f.dd.iter_mut().for_each(|x| *x = 1.0 / *x);
        f
    }

    /// Solves (T − σI) y = b in place (LAPACK `dgttrs`).
    #[inline(always)]
    fn solve(&self, b: &mut [f64; N]) {
        for i in 0..N - 1 {
            if self.swap[i] {
                let t = b[i];
                b[i] = b[i + 1];
                b[i + 1] = t - self.dl[i] * b[i + 1];
            } else {
                b[i + 1] -= self.dl[i] * b[i];
            }
        }
        b[N - 1] *= self.dd[N - 1];
        b[N - 2] = (b[N - 2] - self.du[N - 2] * b[N - 1]) * self.dd[N - 2];
        for i in (0..N - 2).rev() {
            b[i] = (b[i] - self.du[i] * b[i + 1] - self.du2[i] * b[i + 2]) * self.dd[i];
        }
    }
}

/// The number k of eigenvalues of the symmetric `a` below `below` (≤ 0), those eigenvalues
/// (the first k entries, ascending) and orthonormal eigenvectors (the first k rows: row i
/// belongs to λ_i), by the steps of the module doc; None if the QL iteration does not
/// converge or the input is not finite.
#[inline(always)]
fn negative_eigenpairs(a: &Square, below: f64) -> Option<(usize, [f64; N], Square)> {
    if a.iter().flatten().any(|x| !x.is_finite()) {
        return None;
    }
    let mut t = *a;
    let (d, e, vs, betas) = tridiagonalize(&mut t);
    // Reversed (same eigenvalues): QL likes the larger entries last.
    let mut dr = d;
    dr.reverse();
    let mut er = [0.0; N];
    for i in 0..N - 1 {
        er[i] = e[N - 2 - i];
    }
    let lambda = tridiagonal_eigenvalues(dr, er)?;
    let count = lambda.iter().take_while(|&&l| l < below).count();
    let norm = (0..N).map(|i| d[i].abs() + e[i].abs() + if i > 0 { e[i - 1].abs() } else { 0.0 }).fold(0.0, f64::max);
    let tiny = f64::EPSILON * norm.max(f64::MIN_POSITIVE);
    let mut vectors: Square = [[0.0; N]; N];
    let mut previous = f64::NEG_INFINITY;
    for (j, &l) in lambda[..count].iter().enumerate() {
        // Shifts of (nearly) equal eigenvalues are separated by ten ulps (LAPACK `dstein`).
        let sigma = l.max(previous + 10.0 * f64::EPSILON * l.abs());
        previous = sigma;
        // A start vector with components along every eigenvector (deterministic).
        let mut y: [f64; N] = std::array::from_fn(|i| 1.0 + 0.5 * ((7 * i + 13 * j) % 11) as f64 / 11.0);
        let lu = ShiftedLu::new(&d, &e, sigma, tiny);
        for _ in 0..INVERSE_STEPS {
            let scale = 1.0 / y.iter().fold(0.0, |s: f64, x| s.max(x.abs()));
            y.iter_mut().for_each(|x| *x *= scale);
            lu.solve(&mut y);
            for v in &vectors[..j] {
                let c: f64 = v.iter().zip(&y).fold(0.0, |s, (p, q)| s + p * q);
                y.iter_mut().zip(v).for_each(|(q, p)| *q -= c * p);
            }
        }
        let n2 = y.iter().fold(0.0, |s, x| s + x * x).sqrt();
        if !(n2 > 0.0 && n2.is_finite()) {
            return None;
        }
        y.iter_mut().for_each(|x| *x /= n2);
        vectors[j] = y;
    }
    // Back to the coordinates of a: v = H₀ (H₁ (⋯ H_{n−3} y)).
    for y in &mut vectors[..count] {
        for k in (0..N - 2).rev() {
            if betas[k] != 0.0 {
                let v = &vs[k];
                let c = betas[k] * v[k + 1..].iter().zip(&y[k + 1..]).fold(0.0, |s, (p, q)| s + p * q);
                y[k + 1..].iter_mut().zip(&v[k + 1..]).for_each(|(q, p)| *q -= c * p);
            }
        }
    }
    Some((count, lambda, vectors))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A reproducible pseudo-random number in [−1, 1) (64-bit LCG, Knuth's MMIX constants).
    fn random(state: &mut u64) -> f64 {
        *state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((*state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

    /// Reference V|Λ|Vᵀ of the symmetric part by nalgebra's general eigensolver.
    fn reference(k: &ElemMat) -> ElemMat {
        let e = nalgebra::SymmetricEigen::new((k + k.transpose()) * 0.5);
        &e.eigenvectors * nalgebra::Matrix::from_diagonal(&e.eigenvalues.map(f64::abs)) * e.eigenvectors.transpose()
    }

    /// Q diag(λ) Qᵀ with a random orthogonal Q (QR of a random matrix).
    fn with_spectrum(lambda: &[f64; N], seed: &mut u64) -> ElemMat {
        let g = ElemMat::from_fn(|_, _| random(seed));
        let q = g.qr().q();
        let l = nalgebra::SVector::<f64, N>::from_row_slice(lambda);
        &q * ElemMat::from_diagonal(&l) * q.transpose()
    }

    /// The projection equals the reference V|Λ|Vᵀ within 10⁻¹³·‖K‖ (entrywise, against
    /// the largest entry) on random indefinite, definite, semi-definite (rank 14, like a
    /// free element's six rigid-body modes) and nearly singular indefinite matrices of
    /// spectra spread over twelve orders of magnitude, and on matrices with a triple and two
    /// clustered negative eigenvalues; the result is symmetric and has no negative
    /// eigenvalue beyond round-off.
    #[test]
    fn projection_equals_reference_on_random_symmetric_matrices() {
        let mut seed = 7;
        let mut mats = Vec::new();
        for _ in 0..50 {
            // Indefinite: entries in [−1, 1), unsymmetric input.
            mats.push(ElemMat::from_fn(|_, _| random(&mut seed)));
            // Definite.
            let g = ElemMat::from_fn(|_, _| random(&mut seed));
            mats.push(g * g.transpose() + ElemMat::identity());
            // Rank-deficient PSD: six zero eigenvalues.
            let mut l = [0.0; N];
            for (i, li) in l.iter_mut().enumerate().skip(6) {
                *li = 10f64.powf(6.0 * (random(&mut seed) + 1.0)) * (i as f64);
            }
            mats.push(with_spectrum(&l, &mut seed));
            // Indefinite with rigid-body-like zeros and a wide spread of scales.
            for (i, li) in l.iter_mut().enumerate() {
                *li = if i < 6 { 0.0 } else { 10f64.powf(6.0 * (random(&mut seed) + 1.0)) * random(&mut seed).signum() };
            }
            mats.push(with_spectrum(&l, &mut seed));
            // Repeated and clustered negative eigenvalues (triple, 10⁻⁹ and 10⁻¹³ apart).
            let scale = 10f64.powf(6.0 * random(&mut seed));
            for (i, li) in l.iter_mut().enumerate() {
                *li = scale * match i {
                    0..3 => -1.0,
                    3 => -1.0 + 1e-9,
                    4 => -1.0 + 1e-13,
                    5..8 => 0.0,
                    _ => 1.0 + random(&mut seed),
                };
            }
            mats.push(with_spectrum(&l, &mut seed));
        }
        let mut ways = [0; 3];
        for (n, k) in mats.iter().enumerate() {
            let (p, way) = project_psd_traced(k);
            ways[way as usize] += 1;
            let r = reference(k);
            let scale = r.abs().max();
            let err = (p - r).abs().max() / scale;
            assert!(err < 1e-13, "matrix {n} ({way:?}): relative difference {err:e}");
            assert_eq!(p, p.transpose(), "matrix {n}: not symmetric");
            let lmin = nalgebra::SymmetricEigen::new(p).eigenvalues.min();
            assert!(lmin > -1e-13 * scale, "matrix {n}: eigenvalue {lmin:e}");
        }
        assert_eq!(ways[2], 0, "fixed-size solver fell back {} times", ways[2]);
        assert!(ways[0] >= 100 && ways[1] >= 100, "definite / mirrored: {ways:?}");
    }

    /// A diagonal matrix and the zero matrix take the shortcut exactly; a matrix with one
    /// negative diagonal entry comes back with it mirrored; a NaN entry comes back as it is.
    #[test]
    fn diagonal_matrices_are_mirrored_exactly() {
        let mut bad = ElemMat::identity();
        bad[(2, 5)] = f64::NAN;
        let (p, way) = project_psd_traced(&bad);
        assert!(way == Projection::Fallback && p[(2, 5)].is_nan() && p[(0, 0)] == 1.0);
        let mut k = ElemMat::from_diagonal(&nalgebra::SVector::<f64, N>::from_fn(|i, _| 1.0 + i as f64));
        assert_eq!(project_psd_traced(&k), (k, Projection::Definite));
        assert_eq!(project_psd(&ElemMat::zeros()), ElemMat::zeros());
        k[(3, 3)] = -4.0;
        let p = project_psd(&k);
        assert!((p[(3, 3)] - 4.0).abs() < 1e-14 && (p - p.transpose()).abs().max() == 0.0, "{}", p[(3, 3)]);
    }
}
