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
//! - `Auto` panels are resolved before meshing ([`resolve_auto`]): laminated for the first
//!   pass, then discrete where `garment::ply_auto` finds that the plies would slide or
//!   separate (`analysis_auto`).
//! - The part is named after the panel; every `panel/ply` name of a discrete model stays
//!   valid as an alias of the laminated part (node sets, loads, monitors), so one scene runs
//!   in both models: a `Gravity` load on each ply's alias with that ply's areal density sums
//!   to the laminate's weight, and `SelfWeight` on an alias takes the ply's own density.
//! - Mass: the laminate's areal density is the sum of its plies' (each from the ply, a
//!   `Gravity` load on its alias, or its material).

use std::collections::BTreeMap;
use std::sync::Arc;

use super::assemble::GarmentPart;
use super::spec::{GarmentSpec, PanelSpec, PlyModel};
use crate::material::{LaminaPly, Laminate, ShellMaterial};
use crate::input::{Locator, SceneError};

/// Rejects ply models that cannot be built: an explicit `Laminate` or `Auto` on a panel of a
/// single ply, and a sewn (`closing`) seam between an explicitly laminated and an explicitly
/// discrete multi-ply panel (`Auto` panels are resolved per sewn group, [`resolve_auto`]).
pub fn check(spec: &GarmentSpec, loc: &Locator) -> Result<(), SceneError> {
    for p in &spec.panels {
        let field = format!("garment.panels[{}].ply_model", p.name);
        match p.ply_model {
            Some(m @ (PlyModel::Laminate | PlyModel::Auto)) if p.plies.len() < 2 => {
                let what = if m == PlyModel::Laminate { "a laminate stacks at least two plies" } else { "Auto chooses between a laminate and discrete plies, which needs at least two plies" };
                return Err(loc.at(Some(&p.name), Some("ply_model"), field, format!(
                    "panel \"{}\" has {} ply: {what} (leave ply_model out, or list the plies it bonds)",
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
    let explicit = |p: &PanelSpec, m: PlyModel| p.plies.len() > 1 && model_of(spec, p) == m;
    for seam in spec.seams.iter().filter(|s| s.closing.is_some()) {
        let (Some(a), Some(b)) = (panel(&seam.a.panel), panel(&seam.b.panel)) else { continue };
        if (explicit(a, PlyModel::Laminate) && explicit(b, PlyModel::Discrete)) || (explicit(b, PlyModel::Laminate) && explicit(a, PlyModel::Discrete)) {
            return Err(loc.at(Some(&seam.name), Some("closing"), format!("garment.seams[{}].closing", seam.name), format!(
                "seam \"{}\" sews laminated and discrete multi-ply panels (\"{}\", \"{}\"): sewing (closing) between the two ply models is not supported yet; make both panels Laminate or both Discrete (or Auto)",
                seam.name, seam.a.panel, seam.b.panel
            )));
        }
    }
    Ok(())
}

/// The ply model a panel asks for: its own, else the garment's.
pub fn model_of(spec: &GarmentSpec, panel: &PanelSpec) -> PlyModel {
    panel.ply_model.unwrap_or(spec.ply_model)
}

/// Group of every panel under the sewn (`closing`) seams: panels joined by a chain of sewn
/// seams share a group id (union–find; the smallest panel index of the group).
pub fn sewn_groups(spec: &GarmentSpec) -> Vec<usize> {
    let mut parent: Vec<usize> = (0..spec.panels.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let index = |name: &str| spec.panels.iter().position(|p| p.name == name);
    for seam in spec.seams.iter().filter(|s| s.closing.is_some()) {
        if let (Some(a), Some(b)) = (index(&seam.a.panel), index(&seam.b.panel)) {
            let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
            parent[ra.max(rb)] = ra.min(rb);
        }
    }
    (0..spec.panels.len()).map(|i| root(&mut parent, i)).collect()
}

/// The model chosen for one `Auto` panel and why.
#[derive(Clone, Debug, serde::Serialize)]
pub struct AutoChoice {
    /// Panel name.
    pub panel: String,
    /// "laminate" or "discrete".
    pub model: String,
    /// Why (criterion, or the sewn group).
    pub reason: String,
}

/// Resolves `ply_model: Auto`: every multi-ply `Auto` panel becomes `Laminate`, or `Discrete`
/// if it is in `slides` (the panels whose plies would slide or separate,
/// `garment::ply_auto`). Sewing a laminate to discrete plies is not modelled, so the choice
/// is made per sewn group (panels joined by `closing` seams): a group with a discrete
/// member (an explicit `Discrete` multi-ply panel, or an `Auto` panel in `slides`) is
/// discrete throughout — fidelity is only ever raised — unless it also has an explicit
/// `Laminate` panel, which keeps its `Auto` panels laminated. Returns the spec with every
/// panel's model explicit (no `Auto` left) and the choices, panel by panel.
pub fn resolve_auto(spec: &GarmentSpec, slides: &[String]) -> (GarmentSpec, Vec<AutoChoice>) {
    let groups = sewn_groups(spec);
    let auto = |p: &PanelSpec| p.plies.len() > 1 && model_of(spec, p) == PlyModel::Auto;
    let wants_discrete = |p: &PanelSpec| p.plies.len() > 1 && (model_of(spec, p) == PlyModel::Discrete || (auto(p) && slides.contains(&p.name)));
    let mut out = spec.clone();
    let mut choices = Vec::new();
    for (i, p) in spec.panels.iter().enumerate() {
        let model = model_of(spec, p);
        if !auto(p) {
            out.panels[i].ply_model = (p.plies.len() > 1).then_some(model);
            continue;
        }
        let members: Vec<&PanelSpec> = spec.panels.iter().zip(&groups).filter(|(_, g)| **g == groups[i]).map(|(q, _)| q).collect();
        let pinned = members.iter().find(|q| q.plies.len() > 1 && model_of(spec, q) == PlyModel::Laminate);
        let raiser = members.iter().find(|q| wants_discrete(q));
        let (m, reason) = match (pinned, raiser) {
            (Some(l), Some(_)) if slides.contains(&p.name) => (PlyModel::Laminate, format!("its plies would slide, but it is sewn to the laminated panel \"{}\" (sewing a laminate to discrete plies is not modelled)", l.name)),
            (Some(_), _) | (None, None) => (PlyModel::Laminate, if slides.contains(&p.name) { "plies would slide".to_string() } else { "the plies move as one".to_string() }),
            (None, Some(q)) if q.name == p.name => (PlyModel::Discrete, "its plies would slide or separate".to_string()),
            (None, Some(q)) => (PlyModel::Discrete, format!("sewn (through its group) to \"{}\", whose plies are discrete", q.name)),
        };
        out.panels[i].ply_model = Some(m);
        choices.push(AutoChoice { panel: p.name.clone(), model: if m == PlyModel::Laminate { "laminate" } else { "discrete" }.into(), reason });
    }
    out.ply_model = PlyModel::Discrete;
    (out, choices)
}

/// Whether the garment asks for `Auto` on any multi-ply panel.
pub fn has_auto(spec: &GarmentSpec) -> bool {
    spec.panels.iter().any(|p| p.plies.len() > 1 && model_of(spec, p) == PlyModel::Auto)
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Three two-ply panels: a and b sewn shut (`closing`), c only tied to b.
    fn spec(models: [&str; 3]) -> GarmentSpec {
        let panel = |name: &str, m: &str| format!(r#"(name: "{name}", outline: [(0.0, 0.0), (0.1, 0.0), (0.1, 0.1), (0.0, 0.1)], edges: {{"l": (from: 3, to: 0), "r": (from: 1, to: 2)}}, plies: ["p", "q"], ply_model: Some({m}))"#);
        let text = format!(
            r#"(element_size: 0.05, plies: {{"p": (material: "m", thickness: 0.001), "q": (material: "m", thickness: 0.001)}}, panels: [{}, {}, {}],
               seams: [(name: "ab", a: (panel: "a", edge: "r"), b: (panel: "b", edge: "l"), kind: Plain, closing: Some("sew")),
                       (name: "bc", a: (panel: "b", edge: "r"), b: (panel: "c", edge: "l"), kind: Plain)])"#,
            panel("a", models[0]),
            panel("b", models[1]),
            panel("c", models[2])
        );
        ron::from_str(&text).expect("garment spec")
    }

    fn models(s: &GarmentSpec) -> Vec<Option<PlyModel>> {
        s.panels.iter().map(|p| p.ply_model).collect()
    }

    /// Auto per sewn group: a sliding panel makes its sewn partner discrete (sewing a laminate
    /// to discrete plies is not modelled), a panel only tied (not sewn) keeps its own choice;
    /// an explicit Laminate in the group keeps the group laminated, and an explicit Discrete
    /// one makes its Auto partners discrete from the first pass.
    #[test]
    fn auto_is_resolved_per_sewn_group() {
        use PlyModel::*;
        let s = spec(["Auto", "Auto", "Auto"]);
        assert_eq!(sewn_groups(&s), vec![0, 0, 2]);
        assert!(has_auto(&s));
        assert_eq!(models(&resolve_auto(&s, &[]).0), vec![Some(Laminate); 3]);
        let (r, choices) = resolve_auto(&s, &["a".to_string()]);
        assert_eq!(models(&r), vec![Some(Discrete), Some(Discrete), Some(Laminate)]);
        assert!(choices[1].reason.contains("\"a\""), "{:?}", choices[1]);
        assert!(!has_auto(&r));
        let (r, _) = resolve_auto(&s, &["c".to_string()]);
        assert_eq!(models(&r), vec![Some(Laminate), Some(Laminate), Some(Discrete)]);
        let pinned = spec(["Laminate", "Auto", "Auto"]);
        let (r, choices) = resolve_auto(&pinned, &["b".to_string()]);
        assert_eq!(models(&r), vec![Some(Laminate), Some(Laminate), Some(Laminate)]);
        assert!(choices[0].reason.contains("sewn to the laminated panel"), "{:?}", choices[0]);
        let raised = spec(["Discrete", "Auto", "Auto"]);
        assert_eq!(models(&resolve_auto(&raised, &[]).0), vec![Some(Discrete), Some(Discrete), Some(Laminate)]);
    }
}
