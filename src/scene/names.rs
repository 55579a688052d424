//! Names in a scene (of materials, parts, node sets, loads, steps, monitors, seams, bodies,
//! garment plies, panels, edges and stitch lines): non-empty, without control characters,
//! quotes or backslashes, so that every message can quote them and the scene name can
//! name output files. Errors print the name escaped, at its position in the file.

use crate::input::{Locator, SceneError};
use super::spec::Scene;

/// What is wrong with `name`, if anything.
fn problem(name: &str) -> Option<&'static str> {
    if name.is_empty() {
        Some("is empty")
    } else if name.chars().any(char::is_control) {
        Some("holds a control character")
    } else if name.contains('"') {
        Some("holds a quote")
    } else if name.contains('\\') {
        Some("holds a backslash")
    } else if name.trim() != name {
        Some("starts or ends with white space")
    } else {
        None
    }
}

/// Checks every name of `scene`; the scene name must also make a file name.
pub fn check(scene: &Scene, loc: &Locator) -> Result<(), SceneError> {
    let mut names: Vec<(String, &str)> = vec![("name".into(), scene.name.as_str())];
    names.extend(scene.materials.keys().map(|k| ("materials".into(), k.as_str())));
    names.extend(scene.parts.iter().enumerate().map(|(i, p)| (format!("parts[{i}].name"), p.name.as_str())));
    names.extend(scene.node_sets.keys().map(|k| ("node_sets".into(), k.as_str())));
    names.extend(scene.loads.keys().map(|k| ("loads".into(), k.as_str())));
    names.extend(scene.steps.iter().enumerate().map(|(i, s)| (format!("steps[{i}].name"), s.name.as_str())));
    names.extend(scene.monitors.iter().enumerate().map(|(i, m)| (format!("monitors[{i}].name"), m.name.as_str())));
    names.extend(scene.seams.iter().enumerate().map(|(i, s)| (format!("seams[{i}].name"), s.name.as_str())));
    if let Some(c) = &scene.contact {
        names.extend(c.bodies.iter().enumerate().map(|(i, b)| (format!("contact.bodies[{i}].name"), b.name.as_str())));
    }
    if let Some(g) = &scene.garment {
        names.extend(g.plies.keys().map(|k| ("garment.plies".into(), k.as_str())));
        for (i, p) in g.panels.iter().enumerate() {
            names.push((format!("garment.panels[{i}].name"), p.name.as_str()));
            names.extend(p.edges.keys().map(|k| (format!("garment.panels[{i}].edges"), k.as_str())));
        }
        names.extend(g.seams.iter().enumerate().map(|(i, s)| (format!("garment.seams[{i}].name"), s.name.as_str())));
        names.extend(g.stitch_lines.iter().enumerate().map(|(i, s)| (format!("garment.stitch_lines[{i}].name"), s.name.as_str())));
    }
    for (field, name) in names {
        if let Some(p) = problem(name) {
            return Err(loc.at_name(name, field, format!("the name \"{}\" {p}; names may not be empty or hold quotes, backslashes or control characters", name.escape_debug())));
        }
    }
    let n = scene.name.as_str();
    if n == "." || n == ".." || n.contains('/') {
        return Err(loc.at_name(n, "name", format!("the scene name \"{}\" names the output files and may not be \".\", \"..\" or hold a slash", n.escape_debug())));
    }
    Ok(())
}
