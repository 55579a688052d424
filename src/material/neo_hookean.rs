//! Ciarlet's compressible neo-Hookean lamina under plane stress (the seed note's model).

use nalgebra::{Matrix3, SMatrix};

use super::{MaterialFailure, PointResponse, ShellMaterial, Tangent5, Voigt5};

/// Voigt pairs in the order 11, 22, 33, 12, 13, 23.
const PAIRS: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];
/// The five lamina components kept after condensing out 33.
const KEPT: [usize; 5] = [0, 1, 3, 4, 5];

/// Ciarlet's compressible neo-Hookean solid,
/// W = K/2·[(J²−1)/2 − ln J] + μ/2·(J^(−2/3) tr C − 3),
/// S = K/2 (J²−1) C⁻¹ + μ J^(−2/3) (I − ⅓ tr C C⁻¹),
/// evaluated under plane stress: C33 is found at each point by a safeguarded Newton
/// iteration on S33(C33) = 0 and the 6×6 tangent is condensed to the five lamina
/// components, D = D_rr − D_r3 D_3r / D_33 (exact derivative of the reduced energy).
#[derive(Clone, Debug)]
pub struct NeoHookean {
    /// Bulk modulus K.
    pub bulk: f64,
    /// Shear modulus μ.
    pub shear: f64,
}

/// Full 3D state of the material at given C.
struct Full {
    stress: Matrix3<f64>,
    /// 6×6 tangent (zero unless requested).
    tangent: SMatrix<f64, 6, 6>,
    energy: f64,
}

impl NeoHookean {
    /// Builds the material from bulk and shear moduli.
    pub fn new(bulk: f64, shear: f64) -> Self {
        Self { bulk, shear }
    }

    /// Stress, 6×6 Voigt tangent (engineering shear, when `with_tangent`) and energy
    /// (when `with_energy`) at right Cauchy–Green C.
    fn full(&self, c: &Matrix3<f64>, with_tangent: bool, with_energy: bool) -> Result<Full, MaterialFailure> {
        let det = c.determinant();
        if !(det > 0.0) || !det.is_finite() {
            return Err(MaterialFailure::Inverted { det_c: det });
        }
        let ci = c.try_inverse().ok_or(MaterialFailure::Inverted { det_c: det })?;
        let (k, mu) = (self.bulk, self.shear);
        let j2 = det;
        let i1 = c.trace();
        let jm23 = det.powf(-1.0 / 3.0);
        let stress = ci * (0.5 * k * (j2 - 1.0)) + (Matrix3::identity() - ci * (i1 / 3.0)) * (mu * jm23);
        let a = k * j2 + 2.0 / 9.0 * mu * jm23 * i1;
        let b = k * (j2 - 1.0) - 2.0 / 3.0 * mu * jm23 * i1;
        let cc = 2.0 / 3.0 * mu * jm23;
        let mut tangent = SMatrix::<f64, 6, 6>::zeros();
        if with_tangent {
            // ℂ = a C⁻¹⊗C⁻¹ − b C⁻¹⊙C⁻¹ − c (I⊗C⁻¹ + C⁻¹⊗I), symmetric in (p, q).
            let cv: [f64; 6] = PAIRS.map(|(i, j)| ci[(i, j)]);
            const DIAG: [f64; 6] = [1.0, 1.0, 1.0, 0.0, 0.0, 0.0];
            for (p, &(i, jj)) in PAIRS.iter().enumerate() {
                for (q, &(kk, l)) in PAIRS.iter().enumerate().skip(p) {
                    let v = a * cv[p] * cv[q] - b * 0.5 * (ci[(i, kk)] * ci[(jj, l)] + ci[(i, l)] * ci[(jj, kk)]) - cc * (DIAG[p] * cv[q] + cv[p] * DIAG[q]);
                    tangent[(p, q)] = v;
                    tangent[(q, p)] = v;
                }
            }
        }
        let energy = if with_energy { 0.25 * k * (j2 - 1.0) - 0.25 * k * det.ln() + 0.5 * mu * (jm23 * i1 - 3.0) } else { 0.0 };
        Ok(Full { stress, tangent, energy })
    }

    /// Solves the plane-stress condition S33(C33) = 0 for the lamina strain `strain` by a
    /// safeguarded Newton iteration and returns the converged state (tangent when
    /// `with_tangent`, energy always).
    fn plane_stress(&self, strain: &Voigt5, with_tangent: bool) -> Result<Full, MaterialFailure> {
        if strain.iter().any(|v| !v.is_finite()) {
            return Err(MaterialFailure::NotFinite);
        }
        let mut c = Matrix3::new(
            1.0 + 2.0 * strain[0],
            strain[2],
            strain[3],
            strain[2],
            1.0 + 2.0 * strain[1],
            strain[4],
            strain[3],
            strain[4],
            1.0,
        );
        // In-plane part must be positive definite for any C33 to exist.
        let minor = c[(0, 0)] * c[(1, 1)] - c[(0, 1)] * c[(0, 1)];
        if !(c[(0, 0)] > 0.0 && minor > 0.0) {
            return Err(MaterialFailure::Inverted { det_c: minor });
        }
        // det C is affine in C33: det = C33·m + r. Lower bound keeps det > 0.
        c[(2, 2)] = 0.0;
        let r0 = c.determinant();
        let c33_min = (-r0 / minor).max(0.0);
        // Start from the incompressible guess det C = 1, above the bound.
        let mut lo = c33_min;
        let mut hi = f64::INFINITY;
        let mut c33 = ((1.0 - r0) / minor).max(c33_min + 1e-8 * (1.0 + c33_min.abs()));
        let tol = 1e-13 * (self.bulk + self.shear);
        let (k, mu) = (self.bulk, self.shear);
        let i1_plane = c[(0, 0)] + c[(1, 1)];
        for _ in 0..100 {
            c[(2, 2)] = c33;
            // S33 and ℂ3333 from the affine det C = C33·minor + r0 and (C⁻¹)33 = minor/det C.
            let det = c33 * minor + r0;
            if !(det > 0.0) || !det.is_finite() {
                lo = lo.max(c33);
                c33 = if hi.is_finite() { 0.5 * (lo + hi) } else { 2.0 * c33 + 1e-8 };
                continue;
            }
            let ci33 = minor / det;
            let i1 = i1_plane + c33;
            let jm23 = det.powf(-1.0 / 3.0);
            let s33 = 0.5 * k * (det - 1.0) * ci33 + mu * jm23 * (1.0 - i1 / 3.0 * ci33);
            let a = k * det + 2.0 / 9.0 * mu * jm23 * i1;
            let b = k * (det - 1.0) - 2.0 / 3.0 * mu * jm23 * i1;
            let c3333 = (a - b) * ci33 * ci33 - 4.0 / 3.0 * mu * jm23 * ci33;
            if s33.abs() <= tol {
                // Same C as the converged iterate: tangent and energy only once.
                return self.full(&c, with_tangent, true);
            }
            if s33 > 0.0 {
                hi = hi.min(c33);
            } else {
                lo = lo.max(c33);
            }
            // dS33/dC33 = ½ ℂ3333.
            let slope = 0.5 * c3333;
            let mut next = c33 - s33 / slope;
            if !(slope > 0.0) || !(next > lo && next < hi) {
                next = if hi.is_finite() { 0.5 * (lo + hi) } else { 2.0 * c33 };
            }
            c33 = next;
        }
        c[(2, 2)] = c33;
        let residual = self.full(&c, false, false).map(|f| f.stress[(2, 2)].abs()).unwrap_or(f64::NAN);
        Err(MaterialFailure::PlaneStress { residual })
    }

    /// Lamina stress [S11, S22, S12, S13, S23] of a full state.
    fn lamina_stress(f: &Full) -> Voigt5 {
        let s = &f.stress;
        Voigt5::new(s[(0, 0)], s[(1, 1)], s[(0, 1)], s[(0, 2)], s[(1, 2)])
    }
}

impl ShellMaterial for NeoHookean {
    fn response(&self, strain: &Voigt5) -> Result<PointResponse, MaterialFailure> {
        let f = self.plane_stress(strain, true)?;
        let d33 = f.tangent[(2, 2)];
        let mut tangent = Tangent5::zeros();
        for (p, &i) in KEPT.iter().enumerate() {
            for (q, &j) in KEPT.iter().enumerate() {
                tangent[(p, q)] = f.tangent[(i, j)] - f.tangent[(i, 2)] * f.tangent[(2, j)] / d33;
            }
        }
        Ok(PointResponse { stress: Self::lamina_stress(&f), tangent, energy: f.energy })
    }

    fn stress_at(&self, strain: &Voigt5, _zeta: f64) -> Result<(Voigt5, f64), MaterialFailure> {
        let f = self.plane_stress(strain, false)?;
        Ok((Self::lamina_stress(&f), f.energy))
    }

    fn small_strain_moduli(&self) -> (f64, f64) {
        let (k, mu) = (self.bulk, self.shear);
        (9.0 * k * mu / (3.0 * k + mu), (3.0 * k - 2.0 * mu) / (2.0 * (3.0 * k + mu)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::bulk_shear_from_young_poisson;
    use crate::material::test_util::consistency;

    #[test]
    fn small_strain_limit_is_plane_stress_hooke() {
        let (k, mu) = bulk_shear_from_young_poisson(1000.0, 0.3);
        let m = NeoHookean::new(k, mu);
        let r = m.response(&Voigt5::zeros()).unwrap();
        let c = 1000.0 / (1.0 - 0.09);
        assert!((r.tangent[(0, 0)] - c).abs() < 1e-9 * c);
        assert!((r.tangent[(0, 1)] - 0.3 * c).abs() < 1e-9 * c);
        assert!((r.tangent[(2, 2)] - mu).abs() < 1e-9 * c);
        assert!((r.tangent[(3, 3)] - mu).abs() < 1e-9 * c);
        assert!(r.stress.norm() < 1e-12 && r.energy.abs() < 1e-12);
    }

    #[test]
    fn tangent_and_stress_are_derivatives_at_large_strain() {
        let m = NeoHookean::new(4.0e5, 6.0e5);
        for e in [
            Voigt5::new(0.3, -0.1, 0.2, 0.05, -0.04),
            Voigt5::new(-0.2, 0.5, -0.3, 0.0, 0.1),
            Voigt5::new(1e-4, 2e-4, -1e-4, 0.0, 0.0),
        ] {
            let (t, s) = consistency(&m, &e);
            assert!(t < 1e-6 && s < 1e-6, "tangent {t}, stress {s} at {e:?}");
        }
    }

    #[test]
    fn nearly_incompressible_uniaxial_thins() {
        let m = NeoHookean::new(1.0e6, 1.0);
        // Uniaxial stretch 1.5 in e1; the plane-stress solve must still converge.
        let e = Voigt5::new(0.5 * (1.5f64 * 1.5 - 1.0), -0.2, 0.0, 0.0, 0.0);
        assert!(m.response(&e).is_ok());
        assert!(m.response(&Voigt5::new(-0.6, 0.0, 0.0, 0.0, 0.0)).is_err());
    }
}
