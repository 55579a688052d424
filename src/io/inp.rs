//! CalculiX / Abaqus input deck (`.inp`) of an assembled model, after the CalculiX CrunchiX
//! User's Manual (version 2.20, §6 "Input deck format"): `*NODE`, `*ELEMENT, TYPE=S4` per
//! part, `*NSET`/`*ELSET` per part and for further named sets, one `*MATERIAL` (`*ELASTIC`,
//! isotropic) and `*SHELL SECTION` per section (each ply of a panel is a part of its own),
//! seams and other ties as `*EQUATION`, supports as `*BOUNDARY`, and one `*STEP` per solution
//! step with its loads as `*CLOAD` (`OP=NEW`, the totals at the step's end) and prescribed
//! translations as `*BOUNDARY`: `*STATIC` for linear steps, `*BUCKLE` for buckling steps, and
//! `*STEP, NLGEOM` with `*STATIC` at the step's increment for every other kind (arc-length and
//! pseudo-transient steps have no counterpart here).
//!
//! What a deck cannot say the same way is written as a comment and counted in
//! [`InpReport`]: tie offsets that sew a gap closed (the equations tie the reference gap),
//! through-thickness rigid links (director terms), a single fixed tilt (plyshell fixes the
//! director's tilts, CalculiX's rotations are global: both tilts fixed become rotations 1–3
//! fixed, one alone is left free), and non-isotropic materials (written with their
//! small-strain isotropic E and ν). Rotation ties (welded seams) tie the global rotations
//! of the slave to the same weighted master rotations.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io;
use std::path::Path;

use super::atomic::write_atomic;
use crate::element::NODE_DOFS;
use crate::model::{LoadKind, Model, FIXED};
use crate::solver::{StepKind, StepPlan};

/// A model and its steps to write as a deck, with further named sets.
pub struct InpDeck<'a> {
    /// First line of `*HEADING`.
    pub heading: String,
    /// The model.
    pub model: &'a Model,
    /// Solution steps.
    pub steps: &'a [StepPlan],
    /// Further node sets (name, nodes) — scene node sets, seam sides.
    pub node_sets: Vec<(String, Vec<usize>)>,
    /// Further element sets (name, elements) — e.g. all plies of a panel.
    pub element_sets: Vec<(String, Vec<usize>)>,
}

/// What the deck holds, and what it could not say as plyshell does.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct InpReport {
    /// `*EQUATION`s written.
    pub equations: usize,
    /// Ties written without their closing offset (the reference gap stays).
    pub offsets_dropped: usize,
    /// Ties whose director (rigid-link) terms were dropped.
    pub links_dropped: usize,
    /// Slave nodes of welded seams merged into their coincident master.
    pub nodes_merged: usize,
    /// Nodes whose rotation ties (welded seams between non-coincident nodes) were dropped.
    pub rotation_ties_dropped: usize,
    /// Nodes with one fixed tilt left free.
    pub single_tilts_free: usize,
    /// Sections whose material was written as its small-strain isotropic stand-in.
    pub materials_approximated: usize,
}

/// For each node, the node it is written as: itself, or for the slave of a welded seam tie
/// (translations and tilts tied) to a single coincident master with weight 1 and no offset,
/// that master.
fn merged_nodes(m: &Model) -> Vec<usize> {
    let mut to: Vec<usize> = (0..m.n_nodes()).collect();
    let tie = |g: usize| m.dofs.tie_of.get(g).filter(|&&i| i != crate::model::UNTIED).map(|&i| &m.dofs.ties[i as usize]);
    for (s, slot) in to.iter_mut().enumerate() {
        let Some(rot) = tie(NODE_DOFS * s + 3) else { continue };
        let single: Vec<Option<usize>> = (0..3)
            .map(|k| {
                let t = tie(NODE_DOFS * s + k)?;
                match t.masters.as_slice() {
                    [(g, c)] if (c - 1.0).abs() < 1e-12 && t.offset == 0.0 && t.links.is_empty() && g % NODE_DOFS == k => Some(g / NODE_DOFS),
                    _ => None,
                }
            })
            .collect();
        let Some(master) = single[0] else { continue };
        let coincident = (m.x0[s] - m.x0[master]).norm() <= 1e-9 * m.x0[master].norm().max(1e-3);
        let rot_master = rot.masters.iter().all(|&(g, _)| g / NODE_DOFS == master);
        if single.iter().all(|&x| x == Some(master)) && coincident && rot_master {
            *slot = master;
        }
    }
    to
}

/// A CalculiX set name from `name`: letters, digits and `_` (others become `_`), at most 80
/// characters, unique without regard to case (CalculiX upper-cases names).
fn set_name(name: &str, taken: &mut BTreeMap<String, ()>) -> String {
    let mut base: String = name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' { c } else { '_' }).collect();
    if !base.starts_with(|c: char| c.is_ascii_alphabetic()) {
        base.insert(0, 'S');
    }
    base.truncate(72);
    let mut candidate = base.clone();
    let mut k = 2;
    while taken.contains_key(&candidate.to_ascii_uppercase()) {
        candidate = format!("{base}_{k}");
        k += 1;
    }
    taken.insert(candidate.to_ascii_uppercase(), ());
    candidate
}

/// A number as CalculiX reads it: fields hold at most 20 characters, so 14 significant
/// digits in exponent form (relative rounding 5e-15).
fn num(x: f64) -> String {
    format!("{x:.13e}")
}

/// Writes `ids` (1-based on output) sixteen to a line.
fn id_lines(t: &mut String, ids: impl Iterator<Item = usize>) {
    let ids: Vec<String> = ids.map(|i| (i + 1).to_string()).collect();
    for chunk in ids.chunks(16) {
        let _ = writeln!(t, "{},", chunk.join(", "));
    }
}

/// The deck text and its report.
///
/// # Errors
/// A message if the model has no elements or a coordinate or load is not finite.
pub fn inp_string(deck: &InpDeck) -> Result<(String, InpReport), String> {
    let m = deck.model;
    if m.elements.is_empty() {
        return Err("the model has no elements".into());
    }
    if let Some(n) = m.x0.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
        return Err(format!("node {n} has a non-finite coordinate"));
    }
    let mut report = InpReport::default();
    let mut taken = BTreeMap::new();
    let mut t = String::new();
    let _ = writeln!(t, "*HEADING\n{}", deck.heading.replace(['\n', '\r'], " "));
    let _ = writeln!(t, "** Written by plyshell (CalculiX / Abaqus input deck); nodes and elements numbered from 1.");
    let _ = writeln!(t, "*NODE, NSET=NALL");
    for (n, p) in m.x0.iter().enumerate() {
        let _ = writeln!(t, "{}, {}, {}, {}", n + 1, num(p.x), num(p.y), num(p.z));
    }
    // Welded seams with coincident nodes: the slave node is merged into its master (the
    // elements use the master), exact for ties of translations and rotations.
    let merged = merged_nodes(m);
    report.nodes_merged = merged.iter().enumerate().filter(|&(n, &k)| n != k).count();
    // Elements per part, then per-part sets.
    let mut part_sets = Vec::new();
    for part in &m.parts {
        let name = set_name(&format!("P_{}", part.name), &mut taken);
        let _ = writeln!(t, "** part \"{}\"", part.name.escape_debug());
        let _ = writeln!(t, "*ELEMENT, TYPE=S4, ELSET={name}");
        for e in part.first_element..part.first_element + part.n_elements {
            let q = m.elements[e].nodes.map(|n| merged[n]);
            let _ = writeln!(t, "{}, {}, {}, {}, {}", e + 1, q[0] + 1, q[1] + 1, q[2] + 1, q[3] + 1);
        }
        let _ = writeln!(t, "*NSET, NSET={name}");
        id_lines(&mut t, part.first_node..part.first_node + part.n_nodes);
        part_sets.push(name);
    }
    for (name, nodes) in &deck.node_sets {
        let _ = writeln!(t, "*NSET, NSET={}", set_name(name, &mut taken));
        id_lines(&mut t, nodes.iter().copied());
    }
    for (name, elements) in &deck.element_sets {
        let _ = writeln!(t, "*ELSET, ELSET={}", set_name(name, &mut taken));
        id_lines(&mut t, elements.iter().copied());
    }
    // One material and shell section per section (elements grouped by section).
    for (s, section) in m.sections.iter().enumerate() {
        let elements: Vec<usize> = (0..m.elements.len()).filter(|&e| m.elements[e].section == s).collect();
        if elements.is_empty() {
            continue;
        }
        let (young, poisson) = section.material.small_strain_moduli();
        let set = set_name(&format!("SECTION_{}", s + 1), &mut taken);
        let mat = set_name(&format!("MATERIAL_{}", s + 1), &mut taken);
        let _ = writeln!(t, "*ELSET, ELSET={set}");
        id_lines(&mut t, elements.iter().copied());
        let _ = writeln!(t, "*MATERIAL, NAME={mat}\n*ELASTIC\n{}, {}", num(young), num(poisson));
        let h = section.thickness;
        let isotropic = young * h.powi(3) / (12.0 * (1.0 - poisson * poisson));
        if (section.material.bending_rigidity(h) - isotropic).abs() > 1e-9 * isotropic {
            report.materials_approximated += 1;
            let _ = writeln!(t, "** (a fabric or laminate: written as its small-strain isotropic stand-in E, nu)");
        }
        let _ = writeln!(t, "*SHELL SECTION, ELSET={set}, MATERIAL={mat}\n{}", num(section.thickness));
    }
    // Supports: fixed translations, and rotations where both tilts are fixed.
    let prescribed: std::collections::BTreeSet<usize> = m.loads.iter().flat_map(|l| match &l.kind {
        LoadKind::Displacements(list) => list.iter().map(|d| d.0).collect(),
        _ => Vec::new(),
    }).collect();
    let fixed = |g: usize| m.dofs.eq[g] == FIXED && m.dofs.tie_of[g] == crate::model::UNTIED && !prescribed.contains(&g);
    let _ = writeln!(t, "*BOUNDARY");
    for n in 0..m.n_nodes() {
        for k in 0..3 {
            if fixed(NODE_DOFS * n + k) {
                let _ = writeln!(t, "{}, {}, {}", n + 1, k + 1, k + 1);
            }
        }
        match (fixed(NODE_DOFS * n + 3), fixed(NODE_DOFS * n + 4)) {
            (true, true) => {
                let _ = writeln!(t, "{}, 4, 6", n + 1);
            }
            (false, false) => {}
            _ => report.single_tilts_free += 1,
        }
    }
    // Ties.
    for tie in &m.dofs.ties {
        let (s, k) = (tie.slave / NODE_DOFS, tie.slave % NODE_DOFS);
        if merged[s] != s {
            continue;
        }
        if !tie.links.is_empty() {
            report.links_dropped += 1;
            let _ = writeln!(t, "** tie of node {} dof {} has director (rigid-link) terms: not exported", s + 1, k + 1);
            continue;
        }
        if tie.offset != 0.0 {
            report.offsets_dropped += 1;
        }
        let masters: Vec<(usize, f64)> = tie.masters.iter().copied().filter(|&(_, c)| c.abs() > 1e-14).collect();
        let mut rows: Vec<Vec<(usize, usize, f64)>> = Vec::new();
        if k < 3 {
            rows.push(std::iter::once((s, k + 1, 1.0)).chain(masters.iter().map(|&(g, c)| (g / NODE_DOFS, g % NODE_DOFS + 1, -c))).collect());
        } else if k == 3 {
            report.rotation_ties_dropped += 1;
            let _ = writeln!(t, "** rotation tie of node {} (a welded seam between non-coincident nodes): not exported", s + 1);
        }
        for row in rows {
            if row.len() < 2 {
                continue;
            }
            report.equations += 1;
            let _ = writeln!(t, "*EQUATION\n{}", row.len());
            let terms: Vec<String> = row.iter().map(|&(n, d, c)| format!("{}, {d}, {}", n + 1, num(c))).collect();
            for chunk in terms.chunks(4) {
                let _ = writeln!(t, "{},", chunk.join(", "));
            }
        }
    }
    if report.offsets_dropped > 0 {
        let _ = writeln!(t, "** {} tie DOFs close a gap in plyshell (sewing); here they tie the reference gap", report.offsets_dropped);
    }
    // Steps.
    for (i, step) in deck.steps.iter().enumerate() {
        let _ = writeln!(t, "** step {}: \"{}\"", i + 1, step.name.escape_debug());
        match &step.kind {
            StepKind::Buckling { modes, .. } => {
                let _ = writeln!(t, "*STEP\n*BUCKLE\n{modes}");
            }
            _ if step.linear => {
                let _ = writeln!(t, "*STEP\n*STATIC");
            }
            _ => {
                let inc = 1.0 / step.increments.max(1) as f64;
                let _ = writeln!(t, "*STEP, NLGEOM, INC={}\n*STATIC\n{}, 1.0", 100 * step.increments.max(1), num(inc));
            }
        }
        let mut forces: BTreeMap<(usize, usize), f64> = BTreeMap::new();
        let mut displacements: BTreeMap<usize, f64> = BTreeMap::new();
        for (load, &scale) in m.loads.iter().zip(&step.target_scales) {
            if scale == 0.0 {
                continue;
            }
            match &load.kind {
                LoadKind::Forces(list) => list.iter().for_each(|(n, f)| (0..3).for_each(|k| *forces.entry((*n, k + 1)).or_default() += scale * f[k])),
                LoadKind::Moments(list) => list.iter().for_each(|(n, f)| (0..3).for_each(|k| *forces.entry((*n, k + 4)).or_default() += scale * f[k])),
                LoadKind::Displacements(list) => list.iter().for_each(|&(g, v)| *displacements.entry(g).or_default() += scale * v),
            }
        }
        if forces.values().any(|v| !v.is_finite()) || displacements.values().any(|v| !v.is_finite()) {
            return Err(format!("step \"{}\": a load is not finite", step.name));
        }
        let _ = writeln!(t, "*CLOAD, OP=NEW");
        for ((n, d), v) in forces.iter().filter(|(_, v)| **v != 0.0) {
            let _ = writeln!(t, "{}, {d}, {}", n + 1, num(*v));
        }
        if !displacements.is_empty() {
            let _ = writeln!(t, "*BOUNDARY");
            for (g, v) in &displacements {
                let _ = writeln!(t, "{}, {}, {}, {}", g / NODE_DOFS + 1, g % NODE_DOFS + 1, g % NODE_DOFS + 1, num(*v));
            }
        }
        let _ = writeln!(t, "*NODE PRINT, NSET=NALL\nU\n*NODE FILE\nU\n*EL FILE\nS\n*END STEP");
    }
    Ok((t, report))
}

/// Writes [`inp_string`] to `path`, whole or not at all; returns the report.
pub fn write_inp(path: &Path, deck: &InpDeck) -> io::Result<InpReport> {
    let (text, report) = inp_string(deck).map_err(|m| io::Error::new(io::ErrorKind::InvalidInput, format!("cannot write '{}': {m}", path.display())))?;
    write_atomic(path, text.as_bytes())?;
    Ok(report)
}
