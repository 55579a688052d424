//! Laminated panels (`ply_model: Laminate`): one shell per panel whose section stacks the
//! panel's plies (`material::Laminate`, classical lamination theory), instead of one offset
//! shell per ply.
//!
//! - The shell lies on the panel's placed surface, the mid-surface of the stack (where the
//!   discrete plies are centred); its thickness is the sum of the ply thicknesses (contact
//!   with bodies and other panels offsets by half of it).
//! - Stitch lines and quilting within the panel disappear (the plies are bonded), and no
//!   inter-ply contact is generated within it; seams tie the laminate shell as a single ply
//!   (to a discrete partner's outermost ply, or its plies all to the laminate, keeping their
//!   initial offsets; sewing such a mixed seam shut is refused).
//! - The part is named after the panel; every `panel/ply` name of a discrete model stays
//!   valid as an alias of the laminated part (node sets, loads, monitors), so one scene runs
//!   in both models: a `Gravity` load on each ply's alias with that ply's areal density sums
//!   to the laminate's weight, and `SelfWeight` on an alias takes the ply's own density.
//! - Mass: the laminate's areal density is the sum of its plies' (each from the ply, a
//!   `Gravity` load on its alias, or its material).

use std::collections::BTreeMap;
use std::sync::Arc;

use super::assemble::GarmentPart;
use super::spec::{GarmentSpec, PlyModel};
use crate::material::{LaminaPly, Laminate, ShellMaterial};
use crate::scene::{Locator, SceneError};

/// Rejects ply models that cannot be built: `Auto` (not implemented yet), an explicit
/// `Laminate` on a panel of a single ply, and a sewn (`closing`) seam between a laminated
/// and a discrete multi-ply panel.
pub fn check(spec: &GarmentSpec, loc: &Locator) -> Result<(), SceneError> {
    if spec.ply_model == PlyModel::Auto {
        return Err(loc.at(None, Some("ply_model"), "garment.ply_model", "ply_model Auto is not implemented yet; use Discrete or Laminate"));
    }
    for p in &spec.panels {
        let field = format!("garment.panels[{}].ply_model", p.name);
        match p.ply_model {
            Some(PlyModel::Auto) => {
                return Err(loc.at(Some(&p.name), Some("ply_model"), field, format!("panel \"{}\": ply_model Auto is not implemented yet; use Discrete or Laminate", p.name)));
            }
            Some(PlyModel::Laminate) if p.plies.len() < 2 => {
                return Err(loc.at(Some(&p.name), Some("ply_model"), field, format!(
                    "panel \"{}\" has {} ply: a laminate stacks at least two plies (leave ply_model out, or list the plies it bonds)",
                    p.name,
                    p.plies.len()
                )));
            }
            _ => {}
        }
    }
    // Sewing a laminate to a discrete stack would close every ply's gap onto the laminate's
    // one row (or the laminate onto the outermost ply): not modelled yet.
    let panel = |name: &str| spec.panels.iter().find(|p| p.name == name);
    for seam in spec.seams.iter().filter(|s| s.closing.is_some()) {
        let (Some(a), Some(b)) = (panel(&seam.a.panel), panel(&seam.b.panel)) else { continue };
        let discrete_stack = |p: &super::spec::PanelSpec| p.plies.len() > 1 && !spec.is_laminate(p);
        if (spec.is_laminate(a) && discrete_stack(b)) || (spec.is_laminate(b) && discrete_stack(a)) {
            return Err(loc.at(Some(&seam.name), Some("closing"), format!("garment.seams[{}].closing", seam.name), format!(
                "seam \"{}\" sews laminated and discrete multi-ply panels (\"{}\", \"{}\"): sewing (closing) between the two ply models is not supported yet; make both panels Laminate or both Discrete",
                seam.name, seam.a.panel, seam.b.panel
            )));
        }
    }
    Ok(())
}

/// Name of the alias of ply `ply` of panel `panel` (the discrete model's part name).
pub fn alias(panel: &str, ply: &str) -> String {
    format!("{panel}/{ply}")
}

/// Aliases `panel/ply` of every laminated part's plies → (model part index, ply name);
/// `first_part` is the model index of the first garment part.
pub fn aliases(spec: &GarmentSpec, parts: &[GarmentPart], first_part: usize) -> BTreeMap<String, (usize, String)> {
    let mut out = BTreeMap::new();
    for (i, gp) in parts.iter().enumerate().filter(|(_, gp)| gp.plies.len() > 1) {
        let panel = &spec.panels[gp.panel];
        for &k in &gp.plies {
            out.insert(alias(&panel.name, &panel.plies[k]), (first_part + i, panel.plies[k].clone()));
        }
    }
    out
}

/// Areal density of ply `ply` of a laminated panel: the ply's own, else that of a `Gravity`
/// load on its alias (`gravity(alias)`), else its material's.
fn ply_density(spec: &GarmentSpec, panel: &str, ply: &str, material: &dyn ShellMaterial, gravity: &dyn Fn(&str) -> Option<f64>) -> Option<f64> {
    let own = spec.plies.get(ply).map(|p| p.areal_density).filter(|&d| d > 0.0);
    own.or_else(|| gravity(&alias(panel, ply))).or_else(|| material.areal_density())
}

/// The section law of laminated part `gp`: its plies' materials (from `materials`) stacked
/// from the inside (ζ = −1) to the outermost ply on the director side (ζ = +1), as the
/// discrete plies lie. Errors name the ply.
pub fn section_material(
    spec: &GarmentSpec,
    gp: &GarmentPart,
    materials: &BTreeMap<&str, Arc<dyn ShellMaterial>>,
    gravity: &dyn Fn(&str) -> Option<f64>,
) -> Result<Laminate, String> {
    let panel = &spec.panels[gp.panel];
    let mut plies = Vec::with_capacity(gp.plies.len());
    for &k in gp.plies.iter().rev() {
        let name = &panel.plies[k];
        let ply = spec.plies.get(name).ok_or_else(|| format!("unknown ply \"{name}\""))?;
        let material = materials.get(ply.material.as_str()).cloned().ok_or_else(|| format!("ply \"{name}\": unknown material \"{}\"", ply.material))?;
        let areal_density = ply_density(spec, &panel.name, name, &*material, gravity);
        plies.push(LaminaPly { name: name.clone(), material, thickness: ply.thickness, areal_density });
    }
    Laminate::new(plies).map_err(|e| format!("panel \"{}\": {e}", panel.name))
}
