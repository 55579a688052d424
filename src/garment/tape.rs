//! Seam tape: a stiffer strip of the seam-allowance width along a taped seam.

use std::sync::Arc;

use nalgebra::Vector3;

use super::{SeamInfo, SeamKind};
use crate::element::Section;
use crate::material::{MaterialFailure, PointResponse, ShellMaterial, Voigt5};
use crate::model::ElementDef;

/// A lamina law scaled by a constant factor: S = f S₀(E), dS/dE = f dS₀/dE, W = f W₀ — the
/// base fabric plus a bonded tape of proportional stiffness (a rule-of-mixtures laminate).
/// Every thickness-dependent part of the base law is scaled too: `response_at` and
/// `stress_at` (a fabric's bending split C(ζ) = α + β ζ², so the taped bending rigidity is
/// f B, not f A h²/12), its thickness rule, intrinsic thickness and areal density (the
/// tape's own mass is not modelled) and its bending rigidity.
#[derive(Debug)]
pub struct Scaled {
    /// The base material.
    pub base: Arc<dyn ShellMaterial>,
    /// Stiffness factor (> 0).
    pub factor: f64,
}

impl Scaled {
    fn scale(&self, mut r: PointResponse) -> PointResponse {
        r.stress *= self.factor;
        r.tangent *= self.factor;
        r.energy *= self.factor;
        r
    }
}

impl ShellMaterial for Scaled {
    fn response(&self, strain: &Voigt5) -> Result<PointResponse, MaterialFailure> {
        Ok(self.scale(self.base.response(strain)?))
    }

    fn response_at(&self, strain: &Voigt5, zeta: f64) -> Result<PointResponse, MaterialFailure> {
        Ok(self.scale(self.base.response_at(strain, zeta)?))
    }

    fn stress_at(&self, strain: &Voigt5, zeta: f64) -> Result<(Voigt5, f64), MaterialFailure> {
        let (stress, energy) = self.base.stress_at(strain, zeta)?;
        Ok((stress * self.factor, energy * self.factor))
    }

    fn as_laminate(&self) -> Option<(&crate::material::Laminate, f64)> {
        self.base.as_laminate().map(|(l, f)| (l, f * self.factor))
    }
    fn small_strain_moduli(&self) -> (f64, f64) {
        let (e, nu) = self.base.small_strain_moduli();
        (self.factor * e, nu)
    }

    fn bending_rigidity(&self, h: f64) -> f64 {
        self.factor * self.base.bending_rigidity(h)
    }

    fn thickness_points(&self) -> Option<usize> {
        self.base.thickness_points()
    }

    fn thickness_rule(&self) -> Option<Vec<[f64; 2]>> {
        self.base.thickness_rule()
    }

    fn intrinsic_thickness(&self) -> Option<f64> {
        self.base.intrinsic_thickness()
    }

    fn areal_density(&self) -> Option<f64> {
        self.base.areal_density()
    }
}

/// Distance from `p` to the polyline through `row`.
fn distance_to_row(x0: &[Vector3<f64>], row: &[usize], p: &Vector3<f64>) -> f64 {
    if row.len() == 1 {
        return (x0[row[0]] - p).norm();
    }
    row.windows(2)
        .map(|w| {
            let (a, b) = (x0[w[0]], x0[w[1]]);
            let ab = b - a;
            let t = if ab.norm_squared() > 0.0 { ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0) } else { 0.0 };
            (a + ab * t - p).norm()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Gives every element whose reference centre lies within a taped seam's width of either
/// span a section whose material is scaled by the tape's stiffness factor. Returns the
/// number of taped elements.
pub fn apply_tapes(seams: &[SeamInfo], x0: &[Vector3<f64>], elements: &mut [ElementDef], sections: &mut Vec<Section>) -> usize {
    let mut count = 0;
    for s in seams {
        let SeamKind::Taped { width, stiffness_factor } = s.kind else { continue };
        let mut taped_section: Vec<Option<usize>> = vec![None; sections.len()];
        for el in elements.iter_mut() {
            let c: Vector3<f64> = el.nodes.iter().map(|&n| x0[n]).sum::<Vector3<f64>>() / 4.0;
            let d = distance_to_row(x0, &s.master, &c).min(distance_to_row(x0, &s.slave, &c));
            if d > width || el.section >= taped_section.len() {
                continue;
            }
            let k = match taped_section[el.section] {
                Some(k) => k,
                None => {
                    let base = &sections[el.section];
                    let material: Arc<dyn ShellMaterial> = Arc::new(Scaled { base: base.material.clone(), factor: stiffness_factor });
                    sections.push(Section { material, ..base.clone() });
                    taped_section[el.section] = Some(sections.len() - 1);
                    sections.len() - 1
                }
            };
            el.section = k;
            count += 1;
        }
    }
    count
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::quadrature::gauss_legendre;
    use crate::material::{Fabric, FabricProperties};

    /// Bending rigidity of a lamina law integrated through the thickness h with the
    /// material's own thickness rule: D₁₁ = (h/2)∫ C₁₁(ζ) (ζh/2)² dζ.
    fn integrated_bending(m: &dyn ShellMaterial, h: f64) -> f64 {
        let (pz, wz) = gauss_legendre(m.thickness_points().unwrap_or(2)).expect("rule");
        pz.iter()
            .zip(wz)
            .map(|(&z, &w)| {
                let c = m.response_at(&Voigt5::zeros(), z).expect("response").tangent[(0, 0)];
                0.5 * h * w * c * (0.5 * z * h).powi(2)
            })
            .sum()
    }

    /// A taped fabric bends with f times the fabric's bending rigidity B₁ (the fabric's own
    /// split, `material::fabric`), not with f A₁₁ h²/12 from its membrane-equivalent
    /// response, and keeps its thickness rule and areal density.
    #[test]
    fn taped_fabric_bends_with_scaled_fabric_rigidity() {
        let props = FabricProperties::preset("cotton_broadcloth").expect("preset");
        let (h, b1) = (props.thickness, props.warp_bending);
        let base: Arc<dyn ShellMaterial> = Arc::new(Fabric::new(props));
        let taped = Scaled { base: base.clone(), factor: 4.0 };
        let d = integrated_bending(&taped, h);
        assert!((d / (4.0 * b1) - 1.0).abs() < 1e-10, "taped bending {d:e} vs 4 B1 = {:e}", 4.0 * b1);
        assert_eq!(taped.thickness_points(), Some(3));
        assert_eq!(taped.areal_density(), base.areal_density());
        let e = Voigt5::new(0.01, -0.002, 0.003, 0.001, 0.0);
        let (s, w) = taped.stress_at(&e, 0.7).expect("stress");
        let r = taped.response_at(&e, 0.7).expect("response");
        assert!((s - r.stress).norm() < 1e-12 * r.stress.norm() && (w - r.energy).abs() < 1e-12 * r.energy.abs());
    }
}
