//! Garments: panels, plies and seams. Seams become master–slave ties in the shell model.

pub mod arrange;
pub mod assemble;
pub mod compliant;
pub mod export;
pub mod graph;
pub mod laminate;
pub mod measures;
pub mod mesh;
pub mod picture;
pub mod place;
pub mod ply_auto;
pub mod ply_contact;
pub mod seam;
pub mod sizing;
pub mod spec;
pub mod tape;

pub use seam::{seam_ties, SeamInfo, SeamKind};
pub use assemble::{GarmentMesh, GarmentPart};
pub use graph::GarmentGraph;
pub use spec::*;
pub use tape::apply_tapes;

use std::collections::BTreeMap;

use nalgebra::Vector3;

use crate::element::DirectorFrame;
use crate::model::{Load, Tie};
use crate::input::{Locator, SceneError};

/// Ties of the scene's seams (`Scene::seams`): each seam's master and slave node sets are
/// rows in span order; a named `closing` load pattern closes the initial gap. Errors name
/// the seam and its position in the scene file.
pub fn build_scene_seams(
    seams: &[SeamSpec],
    loc: &Locator,
    node_sets: &BTreeMap<String, Vec<usize>>,
    loads: &[Load],
    x0: &[Vector3<f64>],
    frames0: &mut [DirectorFrame],
) -> Result<(Vec<Tie>, Vec<SeamInfo>), SceneError> {
    let mut ties = Vec::new();
    let mut infos = Vec::new();
    for (i, s) in seams.iter().enumerate() {
        let field = format!("seams[{}]", s.name);
        if seams[..i].iter().any(|t| t.name == s.name) {
            return Err(loc.at(Some(&s.name), Some("name"), format!("{field}.name"), "duplicate seam name"));
        }
        let set = |name: &str, key: &str| {
            node_sets.get(name).ok_or_else(|| {
                let known: Vec<&str> = node_sets.keys().map(|k| k.as_str()).collect();
                loc.at_value(&s.name, name, format!("{field}.{key}"), format!("no node set named \"{name}\"; node sets: {}", known.join(", ")))
            })
        };
        let master = set(&s.master, "master")?;
        let slave = set(&s.slave, "slave")?;
        if let Some(p) = s.kind.problem() {
            return Err(loc.at(Some(&s.name), Some("kind"), format!("{field}.kind"), p));
        }
        let closing = match &s.closing {
            None => None,
            Some(l) => Some(loads.iter().position(|x| &x.name == l).ok_or_else(|| {
                loc.at_value(&s.name, l, format!("{field}.closing"), format!("no load pattern named \"{l}\" (declare it as `\"{l}\": Closure` in loads)"))
            })?),
        };
        let (mut t, mut info) = seam_ties(&s.name, s.kind, x0, frames0, master, slave, closing).map_err(|e| loc.at(Some(&s.name), None, field.clone(), e))?;
        seam::make_compliant(&mut t, &mut info, s.stiffness, s.strength, closing.is_some()).map_err(|(key, msg)| loc.at(Some(&s.name), Some(key), format!("{field}.{key}"), msg))?;
        ties.extend(t);
        infos.push(info);
    }
    Ok((ties, infos))
}
