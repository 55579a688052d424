//! Isotropic St. Venant–Kirchhoff lamina under plane stress.

use super::{MaterialFailure, PointResponse, ShellMaterial, Tangent5, Voigt5};

/// S = D E with the isotropic plane-stress matrix for the membrane components and
/// k·G for the transverse shear components (k the shear correction factor; 5/6 by default).
/// Energy W = ½ Eᵀ D E. The model used by the published small-strain shell benchmarks.
#[derive(Clone, Debug)]
pub struct StVenantKirchhoff {
    /// Young's modulus.
    pub young: f64,
    /// Poisson ratio.
    pub poisson: f64,
    /// Transverse shear correction factor.
    pub shear_factor: f64,
    d: Tangent5,
}

impl StVenantKirchhoff {
    /// Builds the material from Young's modulus, Poisson ratio and shear correction factor.
    pub fn new(young: f64, poisson: f64, shear_factor: f64) -> Self {
        let c = young / (1.0 - poisson * poisson);
        let g = young / (2.0 * (1.0 + poisson));
        let mut d = Tangent5::zeros();
        d[(0, 0)] = c;
        d[(1, 1)] = c;
        d[(0, 1)] = c * poisson;
        d[(1, 0)] = c * poisson;
        d[(2, 2)] = g;
        d[(3, 3)] = shear_factor * g;
        d[(4, 4)] = shear_factor * g;
        Self { young, poisson, shear_factor, d }
    }
}

impl ShellMaterial for StVenantKirchhoff {
    fn response(&self, strain: &Voigt5) -> Result<PointResponse, MaterialFailure> {
        if strain.iter().any(|v| !v.is_finite()) {
            return Err(MaterialFailure::NotFinite);
        }
        let stress = self.d * strain;
        Ok(PointResponse { energy: 0.5 * strain.dot(&stress), stress, tangent: self.d })
    }

    fn small_strain_moduli(&self) -> (f64, f64) {
        (self.young, self.poisson)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::test_util::consistency;

    #[test]
    fn tangent_and_stress_are_derivatives() {
        let m = StVenantKirchhoff::new(2.0e5, 0.3, 5.0 / 6.0);
        let e = Voigt5::new(0.02, -0.01, 0.03, 0.004, -0.002);
        let (t, s) = consistency(&m, &e);
        assert!(t < 1e-8 && s < 1e-6, "tangent {t}, stress {s}");
    }
}
