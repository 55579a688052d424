//! Seam tape: a stiffer strip of the seam-allowance width along a taped seam.

use std::sync::Arc;

use nalgebra::Vector3;

use super::{SeamInfo, SeamKind};
use crate::element::Section;
use crate::material::{MaterialFailure, PointResponse, ShellMaterial, Voigt5};
use crate::model::ElementDef;

/// A lamina law scaled by a constant factor: S = f S₀(E), dS/dE = f dS₀/dE, W = f W₀ — the
/// base fabric plus a bonded tape of proportional stiffness (a rule-of-mixtures laminate).
#[derive(Debug)]
pub struct Scaled {
    /// The base material.
    pub base: Arc<dyn ShellMaterial>,
    /// Stiffness factor (> 0).
    pub factor: f64,
}

impl ShellMaterial for Scaled {
    fn response(&self, strain: &Voigt5) -> Result<PointResponse, MaterialFailure> {
        let mut r = self.base.response(strain)?;
        r.stress *= self.factor;
        r.tangent *= self.factor;
        r.energy *= self.factor;
        Ok(r)
    }

    fn small_strain_moduli(&self) -> (f64, f64) {
        let (e, nu) = self.base.small_strain_moduli();
        (self.factor * e, nu)
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
