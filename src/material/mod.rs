//! Constitutive models for the shell lamina.
//!
//! Every model maps the Green–Lagrange strain of a material point, written in the local
//! lamina frame (e1, e2 in the lamina, e3 normal to it) as the Voigt vector
//! `[E11, E22, 2E12, 2E13, 2E23]`, to the conjugate second Piola–Kirchhoff stress
//! `[S11, S22, S12, S13, S23]`, the consistent tangent dS/dE and the stored energy density.
//! The plane-stress condition S33 = 0 is the model's business: the element never sees E33.

mod fabric;
mod laminate;
mod neo_hookean;
mod svk;

pub use fabric::{twist_default, Fabric, FabricProperties, FABRIC_PRESETS, SPLIT_LIMIT};
pub use laminate::{Abd, LaminaPly, Laminate};
pub use neo_hookean::NeoHookean;
pub use svk::StVenantKirchhoff;

use nalgebra::{SMatrix, SVector};

/// Voigt vector of the five lamina strain or stress components.
pub type Voigt5 = SVector<f64, 5>;
/// 5×5 lamina tangent.
pub type Tangent5 = SMatrix<f64, 5, 5>;

/// Stress, tangent and energy density at one material point.
#[derive(Clone, Debug)]
pub struct PointResponse {
    /// Second Piola–Kirchhoff stress `[S11, S22, S12, S13, S23]`.
    pub stress: Voigt5,
    /// Consistent tangent dS/dE (engineering shear strains).
    pub tangent: Tangent5,
    /// Stored energy per unit reference volume.
    pub energy: f64,
}

/// Why a material point could not be evaluated.
#[derive(Clone, Debug, PartialEq)]
pub enum MaterialFailure {
    /// The deformation inverts the material (J ≤ 0) or makes C singular.
    Inverted { det_c: f64 },
    /// The local plane-stress iteration for C33 did not converge.
    PlaneStress { residual: f64 },
    /// A strain or stress component is NaN or infinite.
    NotFinite,
}

impl std::fmt::Display for MaterialFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            MaterialFailure::Inverted { det_c } => {
                write!(f, "material inverted (det C = {det_c:.3e})")
            }
            MaterialFailure::PlaneStress { residual } => {
                write!(f, "plane-stress iteration did not converge (|S33| = {residual:.3e})")
            }
            MaterialFailure::NotFinite => write!(f, "non-finite strain or stress"),
        }
    }
}

/// A hyperelastic lamina law under the plane-stress condition.
pub trait ShellMaterial: Send + Sync + std::fmt::Debug {
    /// Evaluates stress, tangent and energy for the lamina Green–Lagrange strain `strain`.
    fn response(&self, strain: &Voigt5) -> Result<PointResponse, MaterialFailure>;
    /// Small-strain Young's modulus and Poisson ratio (for penalty scaling and reporting).
    fn small_strain_moduli(&self) -> (f64, f64);
    /// Smallest small-strain bending rigidity (N·m) of a sheet of thickness `h`: E h³/12(1 − ν²)
    /// for an isotropic lamina; fabrics report their own.
    fn bending_rigidity(&self, h: f64) -> f64 {
        let (e, nu) = self.small_strain_moduli();
        e * h.powi(3) / (12.0 * (1.0 - nu * nu))
    }
    /// Response at the section's thickness coordinate ζ ∈ [−1, 1]; materials whose
    /// stiffness varies through the thickness (the fabric's bending split) override it.
    fn response_at(&self, strain: &Voigt5, zeta: f64) -> Result<PointResponse, MaterialFailure> {
        let _ = zeta;
        self.response(strain)
    }
    /// Stress and energy density at thickness coordinate ζ without the tangent (the
    /// residual-only path); the same values as [`ShellMaterial::response_at`].
    fn stress_at(&self, strain: &Voigt5, zeta: f64) -> Result<(Voigt5, f64), MaterialFailure> {
        let r = self.response_at(strain, zeta)?;
        Ok((r.stress, r.energy))
    }
    /// Thickness Gauss points the material needs (None: the section's choice).
    fn thickness_points(&self) -> Option<usize> {
        None
    }
    /// The section's whole thickness rule as (ζ, weight) pairs, weights summing to 2, when
    /// the material defines it (a laminate: each ply's Gauss rule in its own band); it
    /// replaces the Gauss rule of `thickness_points`.
    fn thickness_rule(&self) -> Option<Vec<[f64; 2]>> {
        None
    }
    /// Thickness the material's sheet constants refer to, if it has one (fabric).
    fn intrinsic_thickness(&self) -> Option<f64> {
        None
    }
    /// Mass per reference area, if the material carries one (fabric).
    fn areal_density(&self) -> Option<f64> {
        None
    }
    /// The laminate, if this section law stacks plies, and the factor its stresses are
    /// scaled by (1, or a taped seam's stiffness factor): for per-ply post-processing such as
    /// the `ply_model: Auto` criterion.
    fn as_laminate(&self) -> Option<(&Laminate, f64)> {
        None
    }
}

/// Converts Young's modulus and Poisson ratio to bulk and shear moduli (K, μ).
pub fn bulk_shear_from_young_poisson(e: f64, nu: f64) -> (f64, f64) {
    (e / (3.0 * (1.0 - 2.0 * nu)), e / (2.0 * (1.0 + nu)))
}

#[cfg(test)]
pub(crate) mod test_util {
    use super::*;

    /// Checks the tangent against central differences of the stress and the stress against
    /// central differences of the energy, at strain `e`; returns the worst relative errors.
    pub fn consistency(m: &dyn ShellMaterial, e: &Voigt5) -> (f64, f64) {
        let r = m.response(e).expect("response");
        let h = 1e-6;
        let mut tang_err: f64 = 0.0;
        let mut stress_err: f64 = 0.0;
        let scale_t = r.tangent.abs().max();
        let scale_s = r.stress.abs().max().max(1e-12 * scale_t);
        for j in 0..5 {
            let mut ep = *e;
            let mut em = *e;
            ep[j] += h;
            em[j] -= h;
            let rp = m.response(&ep).expect("response +");
            let rm = m.response(&em).expect("response -");
            let col = (rp.stress - rm.stress) / (2.0 * h);
            tang_err = tang_err.max((col - r.tangent.column(j)).abs().max() / scale_t);
            let ds = (rp.energy - rm.energy) / (2.0 * h);
            stress_err = stress_err.max((ds - r.stress[j]).abs() / scale_s.max(scale_t * h));
        }
        (tang_err, stress_err)
    }
}
