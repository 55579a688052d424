//! Scene → model: meshes, sections, node sets, supports, loads, steps and monitors.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use nalgebra::Vector3;

use crate::input::{Locator, SceneError};
use super::spec::*;
use crate::element::quadrature::{bilinear, gauss_legendre};
use crate::element::{DirectorFrame, Section, NODE_DOFS};
use crate::material::{bulk_shear_from_young_poisson, Fabric, NeoHookean, ShellMaterial, StVenantKirchhoff};
use crate::mesh::{self, MeshQuality, ShellMesh};
use crate::model::{DofMap, ElementDef, Load, LoadKind, Model, PartInfo};
use crate::results::Monitor;
use crate::solver::StepPlan;
use super::steps::{check_solver, plan_steps};

/// Everything the solver and the exporter need from a scene.
#[derive(Clone, Debug)]
pub struct BuiltScene {
    /// The model.
    pub model: Model,
    /// The steps.
    pub steps: Vec<StepPlan>,
    /// Monitored nodes.
    pub monitors: Vec<Monitor>,
    /// Resolved node sets (global node numbers).
    pub node_sets: BTreeMap<String, Vec<usize>>,
    /// Mesh quality per part.
    pub quality: Vec<(String, MeshQuality)>,
    /// The mesh chosen for each sized part (`SizedAnnulus`, `SizedRectangle`) and the length
    /// scales behind it, by part name.
    pub sized_parts: Vec<(String, String)>,
    /// Rigid bodies and contact controls.
    pub contact: Option<crate::contact::ContactSetup>,
    /// Buckling-mode imperfection to seed before the solve.
    pub imperfection: Option<crate::solver::imperfection::Imperfection>,
    /// Seams (ties) of the model.
    pub seams: Vec<crate::garment::SeamInfo>,
    /// Warnings (e.g. garment panels neither seamed nor supported), located in the file.
    pub warnings: Vec<String>,
    /// Panel, ply and material ids and the flat pattern, when the scene has a garment.
    pub garment: Option<crate::garment::export::GarmentLayout>,
    /// Contact between adjacent plies of the garment's multi-ply panels.
    pub interply: Option<crate::contact::interply::InterplySetup>,
    /// The movement protocol's poses and their steps (appended to `steps`), if any.
    pub protocol: Option<super::protocol::Protocol>,
}

fn v3(a: [f64; 3]) -> Vector3<f64> {
    Vector3::new(a[0], a[1], a[2])
}

fn positive(x: f64) -> bool {
    x.is_finite() && x > 0.0
}

/// Builds the model of `scene`, whose text `text` came from `file` (for error positions;
/// OBJ paths are relative to the file's directory).
pub fn build(scene: &Scene, file: &str, text: &str) -> Result<BuiltScene, SceneError> {
    build_sized(scene, file, text, None)
}

/// [`build`] with the garment panels meshed by the given size fields (one per panel, in the
/// spec's order) instead of the garment's `element_size` (a-posteriori refinement,
/// `refine::garment`).
pub fn build_sized(scene: &Scene, file: &str, text: &str, garment_sizes: Option<Vec<crate::garment::sizing::SizeField>>) -> Result<BuiltScene, SceneError> {
    let text = super::strip_bom(text);
    let loc = Locator::new(file, text);
    let base_dir = Path::new(file).parent().unwrap_or(Path::new("."));

    // Materials.
    let mut materials: BTreeMap<&str, Arc<dyn ShellMaterial>> = BTreeMap::new();
    for (name, spec) in &scene.materials {
        let field = format!("materials[{name}]");
        let bad = |key: &str, msg: &str| loc.at(Some(name), Some(key), format!("{field}.{key}"), msg.to_string());
        let m: Arc<dyn ShellMaterial> = match *spec {
            MaterialSpec::StVenantKirchhoff { young, poisson, shear_factor } => {
                check_young_poisson(young, poisson, &bad)?;
                if !positive(shear_factor) {
                    return Err(bad("shear_factor", "expected a positive shear correction factor (e.g. 0.8333)"));
                }
                Arc::new(StVenantKirchhoff::new(young, poisson, shear_factor))
            }
            MaterialSpec::NeoHookean { young, poisson } => {
                check_young_poisson(young, poisson, &bad)?;
                let (k, mu) = bulk_shear_from_young_poisson(young, poisson);
                Arc::new(NeoHookean::new(k, mu))
            }
            MaterialSpec::NeoHookeanBulkShear { bulk, shear } => {
                if !positive(bulk) {
                    return Err(bad("bulk", "expected a positive bulk modulus"));
                }
                if !positive(shear) {
                    return Err(bad("shear", "expected a positive shear modulus"));
                }
                Arc::new(NeoHookean::new(bulk, shear))
            }
            MaterialSpec::Fabric(ref f) => {
                let props = super::fabric_spec::fabric_properties(f).map_err(|(key, msg)| bad(key, &msg))?;
                Arc::new(Fabric::new(props))
            }
        };
        materials.insert(name.as_str(), m);
    }

    // The areal density of the first Gravity load on a part (by name).
    let gravity_density = |name: &str| {
        scene.loads.values().find_map(|l| match l {
            LoadSpec::Gravity { part, areal_density, .. } if part == name => Some(*areal_density),
            _ => None,
        })
    };
    // Parts and meshes.
    if scene.parts.is_empty() && scene.garment.is_none() {
        return Err(loc.at(None, Some("parts"), "parts", "expected at least one part"));
    }
    let mut x0 = Vec::new();
    let mut d0 = Vec::new();
    let mut elements = Vec::new();
    let mut sections = Vec::new();
    let mut parts = Vec::new();
    let mut meshes: Vec<ShellMesh> = Vec::new();
    let mut quality = Vec::new();
    // The meshes chosen for sized parts, as reported.
    let mut sized_parts = Vec::new();
    // Nodes and elements planned so far, for the memory budget.
    let mut planned: (u64, u64) = (0, 0);
    for (pi, p) in scene.parts.iter().enumerate() {
        let field = format!("parts[{}]", p.name);
        if scene.parts[..pi].iter().any(|q| q.name == p.name) {
            return Err(loc.at(Some(&p.name), Some("name"), format!("{field}.name"), "duplicate part name"));
        }
        let material = materials.get(p.material.as_str()).cloned().ok_or_else(|| {
            let known: Vec<&str> = materials.keys().copied().collect();
            loc.at_value(
                &p.name,
                &p.material,
                format!("{field}.material"),
                format!("unknown material \"{}\"; defined materials: {}", p.material, known.join(", ")),
            )
        })?;
        if !positive(p.thickness) {
            return Err(loc.at(
                Some(&p.name),
                Some("thickness"),
                format!("{field}.thickness"),
                format!("expected a positive thickness, found {}", p.thickness),
            ));
        }
        if !(1..=5).contains(&p.thickness_points) {
            return Err(loc.at(Some(&p.name), Some("thickness_points"), format!("{field}.thickness_points"), "expected 1 to 5 Gauss points"));
        }
        if let Some(t) = material.intrinsic_thickness()
            && (p.thickness - t).abs() > 1e-9 * t
        {
            return Err(loc.at(
                Some(&p.name),
                Some("thickness"),
                format!("{field}.thickness"),
                format!("material \"{}\" is a sheet of thickness {t}; the part's thickness must equal it, found {}", p.material, p.thickness),
            ));
        }
        // Materials with a through-thickness law (fabric) fix their own rule.
        let thickness_points = material.thickness_points().unwrap_or(p.thickness_points);
        // The part's own areal density, else a Gravity load's, else its material's (a fabric's).
        let areal_density = if p.areal_density > 0.0 { Some(p.areal_density) } else { gravity_density(&p.name).or(material.areal_density()) };
        // A sized mesh (`SizedAnnulus`) becomes the generator it resolves to.
        let sized = super::sizing::resolve_part_mesh(p, scene, &loc, base_dir, &parts, material.as_ref(), areal_density)?;
        let mesh_spec = sized.as_ref().map_or(&p.mesh, |(m, _)| m);
        if let Some((_, report)) = &sized {
            sized_parts.push((p.name.clone(), report.clone()));
        }
        // The resource budget, before the mesh is allocated: this part and those before it.
        let (counts, keys) = mesh_counts(mesh_spec);
        let fits = counts
            .and_then(|(n, e)| Some((planned.0.checked_add(n)?, planned.1.checked_add(e)?)))
            .ok_or_else(|| "more nodes than can be numbered".to_string())
            .and_then(|(n, e)| crate::budget::check_model(n, e).map(|_| (n, e)));
        planned = fits.map_err(|msg| loc.at(Some(&p.name), Some("mesh"), format!("{field}.mesh"), format!("{keys}: {msg}")))?;
        for (key, v) in [("offset", p.offset), ("grain", p.grain)] {
            if let Some(v) = v
                && v.iter().any(|x| !x.is_finite())
            {
                return Err(loc.at(Some(&p.name), Some(key), format!("{field}.{key}"), format!("expected finite numbers, found {v:?}")));
            }
        }
        let mut m = make_mesh(mesh_spec, base_dir).map_err(|e| loc.at(Some(&p.name), Some("mesh"), format!("{field}.mesh"), e.to_string()))?;
        if let Some(o) = p.offset {
            m.nodes.iter_mut().for_each(|x| *x += v3(o));
        }
        quality.push((p.name.clone(), m.quality()));
        let first_node = x0.len();
        let first_element = elements.len();
        sections.push(Section { thickness: p.thickness, shear: p.shear, thickness_points, material });
        let grain = p.grain.map(v3);
        for q in &m.quads {
            elements.push(ElementDef { nodes: q.map(|n| n + first_node), section: pi, part: pi, grain });
        }
        x0.extend_from_slice(&m.nodes);
        d0.extend_from_slice(&m.directors);
        if !(p.areal_density.is_finite() && p.areal_density >= 0.0) {
            return Err(loc.at(Some(&p.name), Some("areal_density"), format!("{field}.areal_density"), "expected a non-negative mass per area"));
        }
        let areal_density = areal_density.unwrap_or(0.0);
        parts.push(PartInfo { name: p.name.clone(), first_node, n_nodes: m.nodes.len(), first_element, n_elements: m.quads.len(), areal_density });
        meshes.push(m);
    }
    // Garment plies as further parts.
    let material_names: std::collections::BTreeSet<String> = materials.keys().map(|k| k.to_string()).collect();
    // A garment's pattern file fills in the outlines of its panels.
    let resolved = match &scene.garment {
        Some(g) => {
            let mut g = crate::pattern::resolve(g, base_dir).map_err(|(field, message)| loc.at(None, Some("pattern"), field, message))?;
            crate::garment::arrange::resolve(&mut g, scene.contact.as_ref(), base_dir, &loc)?;
            // `ply_model: Auto` builds its first pass: the Auto panels laminated (but those
            // sewn to explicitly discrete plies); `analysis_auto` decides the second.
            if crate::garment::laminate::has_auto(&g) {
                crate::garment::laminate::check(&g, &loc)?;
                g = crate::garment::laminate::resolve_auto(&g, &[]).0;
            }
            Some(g)
        }
        None => None,
    };
    // An `Auto` element size becomes a size field per panel (`garment::sizing`); the spec
    // then carries the smallest size as its nominal one (budget, curve sampling).
    let mut size_fields: Option<Vec<crate::garment::sizing::SizeField>> = None;
    let resolved = match resolved {
        Some(mut g) => {
            let fields = match garment_sizes {
                Some(f) => Some(f),
                None => super::sizing::resolve_sizes(&g, scene, &loc, base_dir, &parts, &materials)?,
            };
            if let Some(fields) = fields {
                let h = fields.iter().map(|f| f.min()).fold(f64::INFINITY, f64::min);
                g.element_size = crate::garment::ElementSize::Fixed(h);
                size_fields = Some(fields);
            }
            Some(g)
        }
        None => None,
    };
    let garment = match &resolved {
        Some(g) => {
            // A ply of a fabric with its own thickness must have that thickness (as a part must).
            for (name, ply) in &g.plies {
                if let Some(t) = materials.get(ply.material.as_str()).and_then(|m| m.intrinsic_thickness())
                    && (ply.thickness - t).abs() > 1e-9 * t
                {
                    return Err(loc.at(Some(name), Some("thickness"), format!("garment.plies[{name}].thickness"), format!(
                        "ply \"{name}\": material \"{}\" is a sheet of thickness {t} (its stiffness and bending rigidity are for that thickness); the ply's thickness must equal it, found {}",
                        ply.material, ply.thickness
                    )));
                }
            }
            // The budget before meshing: an upper estimate of each panel's nodes, times its plies.
            let (mut n, mut e) = planned;
            for p in &g.panels {
                if p.outline.iter().flatten().any(|v| !(v.abs() <= crate::garment::graph::MAX_COORDINATE)) {
                    continue; // the garment's validation names the vertex
                }
                let est = crate::garment::mesh::estimate_nodes(&p.outline, g.nominal_size()) * p.plies.len().max(1) as f64;
                let fits = if est < 1e15 { n.checked_add(est as u64).zip(e.checked_add(est as u64)) } else { None };
                let msg = match fits {
                    Some((n2, e2)) => crate::budget::check_model(n2, e2).map(|_| (n2, e2)),
                    None => Err(format!("about {est:.2e} nodes, beyond any memory")),
                };
                (n, e) = msg.map_err(|m| loc.at(None, Some("element_size"), "garment.element_size", format!("panel \"{}\" at this element size: {m}", p.name)))?;
            }
            Some((g, crate::garment::GarmentMesh::build(g, &loc, &material_names, size_fields.take())?))
        }
        None => None,
    };
    let mut garment_first_node = Vec::new();
    let garment_first_part = parts.len();
    // The `panel/ply` names of laminated plies → (laminated part, ply name).
    let mut ply_aliases = BTreeMap::new();
    if let Some((g, gm)) = &garment {
        ply_aliases = crate::garment::laminate::aliases(g, &gm.parts, garment_first_part);
        for gp in &gm.parts {
            let material: Arc<dyn ShellMaterial> = if gp.plies.len() > 1 {
                let field = format!("garment.panels[{}].plies", g.panels[gp.panel].name);
                Arc::new(crate::garment::laminate::section_material(g, gp, &materials, &gravity_density).map_err(|m| loc.at(Some(&g.panels[gp.panel].name), Some("plies"), field, m))?)
            } else {
                materials.get(gp.material.as_str()).cloned().ok_or_else(|| loc.at_value(&gp.name, &gp.material, "garment.plies", "unknown material"))?
            };
            let (first_node, first_element) = (x0.len(), elements.len());
            // The material's own rule (a fabric's split of membrane and bending stiffness needs
            // its thickness points; with two, any fabric bent as A h²/12 whatever its B).
            let thickness_points = material.thickness_points().unwrap_or(2);
            sections.push(Section { thickness: gp.thickness, shear: g.shear, thickness_points, material });
            for (q, g) in gp.mesh.quads.iter().zip(&gp.grains) {
                elements.push(ElementDef { nodes: q.map(|n| n + first_node), section: sections.len() - 1, part: parts.len(), grain: Some(*g) });
            }
            x0.extend_from_slice(&gp.mesh.nodes);
            d0.extend_from_slice(&gp.mesh.directors);
            quality.push((gp.name.clone(), gp.mesh.quality()));
            let material_density = sections.last().and_then(|s| s.material.areal_density());
            let areal_density = if gp.areal_density > 0.0 { gp.areal_density } else { gravity_density(&gp.name).or(material_density).unwrap_or(0.0) };
            parts.push(PartInfo { name: gp.name.clone(), first_node, n_nodes: gp.mesh.nodes.len(), first_element, n_elements: gp.mesh.quads.len(), areal_density });
            garment_first_node.push(first_node);
            meshes.push(gp.mesh.clone());
        }
    }
    let n_nodes = x0.len();
    // The exact sizes (OBJ meshes and focused rings are known only now).
    crate::budget::check_model(n_nodes as u64, elements.len() as u64).map_err(|m| loc.at(None, Some("parts"), "parts", m))?;
    let part_index = |name: &str| parts.iter().position(|p: &PartInfo| p.name == name).or_else(|| ply_aliases.get(name).map(|a| a.0));

    // Node sets.
    let mut node_sets: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    for (name, sel) in &scene.node_sets {
        let field = format!("node_sets[{name}]");
        let unknown_part = |part: &str| {
            let known: Vec<&str> = parts.iter().map(|p| p.name.as_str()).collect();
            loc.at_value(name, part, format!("{field}.part"), format!("unknown part \"{part}\"; parts: {}", known.join(", ")))
        };
        let scope = |part: &Option<String>| -> Result<Vec<usize>, SceneError> {
            match part {
                Some(pn) => {
                    let i = part_index(pn).ok_or_else(|| unknown_part(pn))?;
                    Ok((0..meshes.len()).filter(|&k| k == i).collect())
                }
                None => Ok((0..meshes.len()).collect()),
            }
        };
        let numbers: Vec<(&str, Vec<f64>)> = match sel {
            Selector::Box { min, max, .. } => vec![("min", min.to_vec()), ("max", max.to_vec())],
            Selector::Plane { point, normal, tol, .. } => vec![("point", point.to_vec()), ("normal", normal.to_vec()), ("tol", vec![*tol])],
            Selector::Nearest { point, .. } => vec![("point", point.to_vec())],
            Selector::Edge { .. } | Selector::Part { .. } => Vec::new(),
        };
        if let Some((key, v)) = numbers.iter().find(|(_, v)| v.iter().any(|x| !x.is_finite())) {
            return Err(loc.at(Some(name), Some(key), format!("{field}.{key}"), format!("expected finite numbers, found {v:?}")));
        }
        let mut nodes = Vec::new();
        match sel {
            Selector::Box { min, max, part } => {
                for k in scope(part)? {
                    nodes.extend(mesh::select_box(&meshes[k], v3(*min), v3(*max)).into_iter().map(|n| n + parts[k].first_node));
                }
            }
            Selector::Plane { point, normal, tol, part } => {
                if v3(*normal).norm() == 0.0 {
                    return Err(loc.at(Some(name), Some("normal"), format!("{field}.normal"), "expected a non-zero normal"));
                }
                for k in scope(part)? {
                    nodes.extend(mesh::select_plane(&meshes[k], v3(*point), v3(*normal), *tol).into_iter().map(|n| n + parts[k].first_node));
                }
            }
            Selector::Nearest { point, part } => {
                let mut best: Option<(f64, usize)> = None;
                for k in scope(part)? {
                    for n in mesh::select_nearest(&meshes[k], v3(*point)) {
                        let g = n + parts[k].first_node;
                        let dist = (x0[g] - v3(*point)).norm();
                        if best.is_none_or(|(d, _)| dist < d) {
                            best = Some((dist, g));
                        }
                    }
                }
                nodes.extend(best.map(|b| b.1));
            }
            Selector::Edge { part, edge } => {
                let k = part_index(part).ok_or_else(|| unknown_part(part))?;
                let row = meshes[k].edges.get(edge).ok_or_else(|| {
                    let known: Vec<&str> = meshes[k].edges.keys().map(|s| s.as_str()).collect();
                    loc.at_value(name, edge, format!("{field}.edge"), format!("part \"{part}\" has no edge \"{edge}\"; its edges: {}", known.join(", ")))
                })?;
                nodes.extend(row.iter().map(|n| n + parts[k].first_node));
            }
            Selector::Part { part } => {
                let k = part_index(part).ok_or_else(|| unknown_part(part))?;
                nodes.extend(parts[k].first_node..parts[k].first_node + parts[k].n_nodes);
            }
        }
        if nodes.is_empty() {
            return Err(loc.at(Some(name), None, field, "the selector selects no node; check its coordinates against the mesh"));
        }
        node_sets.insert(name.clone(), nodes);
    }
    let get_set = |set: &str, owner_anchor: &str, field: String| -> Result<&Vec<usize>, SceneError> {
        node_sets.get(set).ok_or_else(|| {
            let known: Vec<&str> = node_sets.keys().map(|s| s.as_str()).collect();
            loc.at_value(owner_anchor, set, field, format!("no node set named \"{set}\"; node sets: {}", known.join(", ")))
        })
    };

    // Supports: fixed DOFs and director tilt constraints.
    let mut fixed = vec![false; NODE_DOFS * n_nodes];
    let mut tilt_dirs: Vec<Vec<Vector3<f64>>> = vec![Vec::new(); n_nodes];
    let axis = |a: Axis| match a {
        Axis::X => Vector3::x(),
        Axis::Y => Vector3::y(),
        Axis::Z => Vector3::z(),
    };
    for (bi, bc) in scene.boundary.iter().enumerate() {
        let (set, dofs): (&String, Vec<Dof>) = match bc {
            BoundarySpec::Clamp { set } => {
                let nodes = get_set(set, set, format!("boundary[{bi}].set"))?;
                for &n in nodes {
                    fixed[NODE_DOFS * n..NODE_DOFS * n + NODE_DOFS].iter_mut().for_each(|f| *f = true);
                }
                continue;
            }
            BoundarySpec::Pin { set } => (set, vec![Dof::Ux, Dof::Uy, Dof::Uz]),
            BoundarySpec::Fix { set, dofs } => (set, dofs.clone()),
            BoundarySpec::Symmetry { set, normal } => {
                let (u, t) = match normal {
                    Axis::X => (Dof::Ux, Dof::TiltX),
                    Axis::Y => (Dof::Uy, Dof::TiltY),
                    Axis::Z => (Dof::Uz, Dof::TiltZ),
                };
                (set, vec![u, t])
            }
        };
        let nodes = get_set(set, set, format!("boundary[{bi}].set"))?;
        for &n in nodes {
            for d in &dofs {
                match d {
                    Dof::Ux => fixed[NODE_DOFS * n] = true,
                    Dof::Uy => fixed[NODE_DOFS * n + 1] = true,
                    Dof::Uz => fixed[NODE_DOFS * n + 2] = true,
                    Dof::TiltX => tilt_dirs[n].push(axis(Axis::X)),
                    Dof::TiltY => tilt_dirs[n].push(axis(Axis::Y)),
                    Dof::TiltZ => tilt_dirs[n].push(axis(Axis::Z)),
                }
            }
        }
    }
    // Director frames: t1 along the first constrained tilt direction, so each tilt
    // constraint removes one α.
    let mut frames0 = Vec::with_capacity(n_nodes);
    for n in 0..n_nodes {
        let d = d0[n];
        let proj: Vec<Vector3<f64>> = tilt_dirs[n].iter().map(|t| t - d * d.dot(t)).filter(|p| p.norm() > 1e-3).collect();
        let frame = DirectorFrame::new(d, proj.first().copied());
        if let Some(p1) = proj.first() {
            fixed[NODE_DOFS * n + 3] = true;
            if proj.iter().skip(1).any(|p| p.normalize().cross(&p1.normalize()).norm() > 1e-3) {
                fixed[NODE_DOFS * n + 4] = true;
            }
        }
        frames0.push(frame);
    }

    // Loads.
    let mut loads = Vec::new();
    for (name, spec) in &scene.loads {
        let field = format!("loads[{name}]");
        let set_of = |set: &String| get_set(set, name, format!("{field}.set"));
        let part_of = |part: &String| {
            part_index(part).ok_or_else(|| {
                let known: Vec<&str> = parts.iter().map(|p| p.name.as_str()).collect();
                loc.at_value(name, part, format!("{field}.part"), format!("unknown part \"{part}\"; parts: {}", known.join(", ")))
            })
        };
        let numbers: (&str, Vec<f64>) = match spec {
            LoadSpec::NodalForce { force: v, .. } | LoadSpec::TotalForce { force: v, .. } => ("force", v.to_vec()),
            LoadSpec::NodalMoment { moment: v, .. } => ("moment", v.to_vec()),
            LoadSpec::EdgeMoment { moment_per_length: v, .. } => ("moment_per_length", v.to_vec()),
            LoadSpec::EdgeForce { force_per_length: v, .. } => ("force_per_length", v.to_vec()),
            LoadSpec::SurfaceTraction { traction: v, .. } => ("traction", v.to_vec()),
            LoadSpec::Gravity { g: v, .. } | LoadSpec::SelfWeight { g: v, .. } | LoadSpec::GarmentWeight { g: v } => ("g", v.to_vec()),
            LoadSpec::Displacement { value, .. } => ("value", vec![*value]),
            LoadSpec::Closure => ("", Vec::new()),
        };
        if numbers.1.iter().any(|v| !v.is_finite()) {
            return Err(loc.at(Some(name), Some(numbers.0), format!("{field}.{}", numbers.0), format!("expected finite numbers, found {:?}", numbers.1)));
        }
        let kind = match spec {
            LoadSpec::NodalForce { set, force } => LoadKind::Forces(set_of(set)?.iter().map(|&n| (n, v3(*force))).collect()),
            LoadSpec::TotalForce { set, force } => {
                let nodes = set_of(set)?;
                let f = v3(*force) / nodes.len() as f64;
                LoadKind::Forces(nodes.iter().map(|&n| (n, f)).collect())
            }
            LoadSpec::NodalMoment { set, moment } => LoadKind::Moments(set_of(set)?.iter().map(|&n| (n, v3(*moment))).collect()),
            LoadSpec::EdgeMoment { set, moment_per_length } => {
                let w = tributary_lengths(&x0, set_of(set)?);
                LoadKind::Moments(w.into_iter().map(|(n, l)| (n, v3(*moment_per_length) * l)).collect())
            }
            LoadSpec::EdgeForce { set, force_per_length } => {
                let w = tributary_lengths(&x0, set_of(set)?);
                LoadKind::Forces(w.into_iter().map(|(n, l)| (n, v3(*force_per_length) * l)).collect())
            }
            LoadSpec::SurfaceTraction { part, traction } => {
                let k = part_of(part)?;
                LoadKind::Forces(area_weights(&x0, &elements, &parts[k]).into_iter().map(|(n, a)| (n, v3(*traction) * a)).collect())
            }
            LoadSpec::Gravity { part, areal_density, g } => {
                let k = part_of(part)?;
                if !(areal_density.is_finite() && *areal_density >= 0.0) {
                    return Err(loc.at(Some(name), Some("areal_density"), format!("{field}.areal_density"), "expected a non-negative mass per area"));
                }
                let w = v3(*g) * *areal_density;
                LoadKind::Forces(area_weights(&x0, &elements, &parts[k]).into_iter().map(|(n, a)| (n, w * a)).collect())
            }
            LoadSpec::SelfWeight { part, g } => {
                let k = part_of(part)?;
                // A laminated ply's alias weighs as the ply's own material.
                let ply_material = ply_aliases.get(part.as_str()).and_then(|(_, ply)| garment.as_ref()?.0.plies.get(ply)).and_then(|p| materials.get(p.material.as_str()));
                let Some(rho) = ply_material.unwrap_or(&sections[k].material).areal_density() else {
                    return Err(loc.at(Some(name), Some("part"), format!("{field}.part"), "the part's material has no areal density (use Gravity with areal_density)"));
                };
                let w = v3(*g) * rho;
                LoadKind::Forces(area_weights(&x0, &elements, &parts[k]).into_iter().map(|(n, a)| (n, w * a)).collect())
            }
            LoadSpec::Displacement { set, dof, value } => {
                let k = match dof {
                    Dof::Ux => 0,
                    Dof::Uy => 1,
                    Dof::Uz => 2,
                    _ => return Err(loc.at(Some(name), Some("dof"), format!("{field}.dof"), "only translations (Ux, Uy, Uz) can be prescribed")),
                };
                let nodes = set_of(set)?;
                for &n in nodes {
                    fixed[NODE_DOFS * n + k] = true;
                }
                LoadKind::Displacements(nodes.iter().map(|&n| (NODE_DOFS * n + k, *value)).collect())
            }
            LoadSpec::GarmentWeight { g } => {
                if garment.is_none() {
                    return Err(loc.at(Some(name), None, field, "GarmentWeight needs a garment (use Gravity or SelfWeight on parts)"));
                }
                let mut forces = Vec::new();
                for part in &parts[garment_first_part..] {
                    if part.areal_density <= 0.0 {
                        return Err(loc.at(Some(name), None, field, format!("garment part \"{}\" has no areal density (give its ply an areal_density)", part.name)));
                    }
                    let w = v3(*g) * part.areal_density;
                    forces.extend(area_weights(&x0, &elements, part).into_iter().map(|(n, a)| (n, w * a)));
                }
                LoadKind::Forces(forces)
            }
            LoadSpec::Closure => LoadKind::Forces(Vec::new()),
        };
        loads.push(Load { name: name.clone(), kind });
    }

    check_solver(&scene.solver, &loc)?;
    let (mut steps, current) = plan_steps(scene, &loc, &node_sets, &loads, &fixed)?;

    // Monitors.
    let mut monitors = Vec::new();
    for m in &scene.monitors {
        if m.point.iter().any(|x| !x.is_finite()) {
            return Err(loc.at(Some(&m.name), Some("point"), format!("monitors[{}].point", m.name), format!("expected finite numbers, found {:?}", m.point)));
        }
        if m.dofs.is_empty() {
            return Err(loc.at(Some(&m.name), Some("dofs"), format!("monitors[{}].dofs", m.name), "expected at least one quantity to record (Ux, Uy, Uz or Umag)"));
        }
        let candidates: Vec<usize> = match (&m.part, &m.set) {
            (_, Some(set)) => get_set(set, &m.name, format!("monitors[{}].set", m.name))?.clone(),
            (Some(pn), None) => {
                let k = part_index(pn).ok_or_else(|| loc.at_value(&m.name, pn, format!("monitors[{}].part", m.name), format!("unknown part \"{pn}\"")))?;
                (parts[k].first_node..parts[k].first_node + parts[k].n_nodes).collect()
            }
            (None, None) => (0..n_nodes).collect(),
        };
        let p = v3(m.point);
        let node = candidates
            .into_iter()
            .min_by(|&a, &b| (x0[a] - p).norm().total_cmp(&(x0[b] - p).norm()))
            .ok_or_else(|| loc.at(Some(&m.name), None, format!("monitors[{}]", m.name), "no node to monitor"))?;
        monitors.push(Monitor { name: m.name.clone(), node, dofs: m.dofs.clone() });
    }

    let contact = match &scene.contact {
        Some(c) => Some(crate::contact::build_contact(c, &loc, base_dir, &parts)?),
        None => None,
    };
    let protocol = match &scene.protocol {
        Some(p) => Some(super::protocol::expand(p, scene.contact.as_ref(), &loc, base_dir, &mut steps, &current)?),
        None => None,
    };
    if let Some(d) = &scene.drape {
        let ok = |v: f64| v.is_finite() && v > 0.0;
        if contact.is_none() {
            return Err(loc.at(None, Some("drape"), "drape", "drape measures need a contact section (the support disc)"));
        }
        if !ok(d.disc_radius) || !ok(d.specimen_radius) || d.disc_radius >= d.specimen_radius || d.resolution.is_some_and(|r| !ok(r)) {
            return Err(loc.at(None, Some("drape"), "drape", "expected 0 < disc_radius < specimen_radius and a positive resolution"));
        }
        if d.center.iter().any(|x| !x.is_finite()) {
            return Err(loc.at(None, Some("center"), "drape.center", format!("expected finite numbers, found {:?}", d.center)));
        }
        // The specimen must be the mesh: its outermost node at specimen_radius from the centre.
        let outer = x0.iter().map(|x| (x.x - d.center[0]).hypot(x.y - d.center[1])).fold(0.0, f64::max);
        if (outer - d.specimen_radius).abs() > 0.01 * d.specimen_radius {
            return Err(loc.at(None, Some("specimen_radius"), "drape.specimen_radius", format!(
                "the specimen radius is {} but the mesh's outermost node lies {outer:.6} from the drape centre",
                d.specimen_radius
            )));
        }
    }
    let imperfection = scene.imperfection.as_ref().map(|imp| super::path::resolve_imperfection(imp, &loc, &loads)).transpose()?;
    let (mut ties, mut seams) = crate::garment::build_scene_seams(&scene.seams, &loc, &node_sets, &loads, &x0, &mut frames0)?;
    let mut warnings = Vec::new();
    let mut layout = None;
    if let Some((g, gm)) = &garment {
        layout = Some(gm.layout(g, garment_first_part, &garment_first_node, x0.len()));
        let (t, s) = gm.ties(g, &loc, &garment_first_node, &loads, &x0, &mut frames0, &fixed)?;
        ties.extend(t);
        seams.extend(s);
        let supported: Vec<bool> = gm
            .parts
            .iter()
            .zip(&garment_first_node)
            .map(|(p, &f)| {
                // Carried by a support, or by contact with the rigid bodies.
                let on_bodies = scene.contact.as_ref().is_some_and(|c| !c.bodies.is_empty() && (c.parts.is_empty() || c.parts.contains(&p.name)));
                on_bodies || fixed[NODE_DOFS * f..NODE_DOFS * (f + p.mesh.nodes.len())].iter().any(|&x| x)
            })
            .collect();
        warnings.extend(gm.crossed_seams(g, &loc).into_iter().map(|e| e.to_string()));
        warnings.extend(gm.unsupported(g, &loc, &supported).into_iter().map(|e| e.to_string()));
    }
    let interply = match &garment {
        Some((g, gm)) => crate::garment::ply_contact::interply_setup(g, gm, garment_first_part, &loc)?,
        None => None,
    };
    // A linear step is one update from the current state: the barrier's collision detection
    // would shorten it (silently giving a fraction of the linear solution) and its
    // potential has no stiffness there to act in a single solve.
    if interply.as_ref().is_some_and(|s| s.barrier.is_some())
        && let Some(s) = scene.steps.iter().find(|s| s.linear)
    {
        return Err(loc.at(Some(&s.name), Some("linear"), format!("steps[{}].linear", s.name), "a linear step cannot run with the garment's barrier surface contact (on by default): set garment.interply: (enabled: false) or make the step nonlinear"));
    }
    crate::garment::apply_tapes(&seams, &x0, &mut elements, &mut sections);
    let dofs = DofMap::with_ties(&fixed, ties).map_err(|e| loc.at(None, Some("seams"), "seams", e))?;
    if dofs.n_free == 0 {
        return Err(loc.at(None, Some("boundary"), "boundary", "every DOF is supported, prescribed or tied: there is nothing to solve"));
    }
    for s in &steps {
        if let crate::solver::StepKind::DisplacementControl { global_dof, set, .. } = &s.kind
            && dofs.eq.get(*global_dof).is_none_or(|&e| e == crate::model::FIXED)
        {
            return Err(loc.at_value(&s.name, set, format!("steps[{}].kind.set", s.name), "the controlled DOF is tied by a seam or stitch line (it has no equation of its own); control a master node"));
        }
    }
    if let Some(pname) = &scene.output.plot_against {
        match loads.iter().position(|l| &l.name == pname) {
            None => {
                let known: Vec<&str> = loads.iter().map(|l| l.name.as_str()).collect();
                return Err(loc.at(None, Some("plot_against"), "output.plot_against", format!("no load named \"{pname}\"; loads: {}", known.join(", "))));
            }
            Some(i) if steps.iter().all(|s| s.target_scales[i] == 0.0) => {
                return Err(loc.at(None, Some("plot_against"), "output.plot_against", format!("no step scales the load \"{pname}\": the monitor plot would have no x range")));
            }
            Some(_) => {}
        }
    }
    let model = Model { x0, frames0, elements, sections, parts, dofs, loads };
    Ok(BuiltScene { model, steps, monitors, node_sets, quality, sized_parts, imperfection, seams, warnings, garment: layout, contact, interply, protocol })
}

fn check_young_poisson(young: f64, poisson: f64, bad: &dyn Fn(&str, &str) -> SceneError) -> Result<(), SceneError> {
    if !positive(young) {
        return Err(bad("young", "expected a positive Young's modulus"));
    }
    if !(poisson.is_finite() && poisson > -1.0 && poisson < 0.5) {
        return Err(bad("poisson", "expected a Poisson ratio in (-1, 0.5)"));
    }
    Ok(())
}

/// Nodes and elements a generated mesh will have (None on overflow), and the fields that set
/// them. OBJ meshes count as nothing here (their size is bounded by the file's) and a focused
/// annulus by its two bounding rings (the ring march bounds itself).
fn mesh_counts(spec: &MeshSpec) -> (Option<(u64, u64)>, &'static str) {
    let grid = |a: usize, b: usize, periodic: bool| {
        let (a, b) = (a as u64, b as u64);
        let cols = if periodic { Some(b) } else { b.checked_add(1) };
        Some((a.checked_add(1)?.checked_mul(cols?)?, a.checked_mul(b)?))
    };
    match *spec {
        MeshSpec::Rectangle { nx, ny, .. } => (grid(nx, ny, false), "nx × ny"),
        MeshSpec::GradedRectangle { ref x, ref y, .. } => (grid(x.len().saturating_sub(1), y.len().saturating_sub(1), false), "x × y"),
        MeshSpec::CylindricalPanel { n_axial, n_circ, .. } => (grid(n_axial, n_circ, false), "n_axial × n_circ"),
        MeshSpec::Hemisphere { n_merid, n_circ, .. } => (grid(n_merid, n_circ, false), "n_merid × n_circ"),
        MeshSpec::SlitAnnulus { nr, ntheta, .. } => (grid(nr, ntheta, false), "nr × ntheta"),
        MeshSpec::TwistedStrip { nx, ny, .. } => (grid(nx, ny, false), "nx × ny"),
        MeshSpec::Annulus { nr, ntheta, .. } => (grid(nr, ntheta, true), "nr × ntheta"),
        MeshSpec::AnnulusRings { ref radii, ntheta } => (grid(radii.len().saturating_sub(1), ntheta, true), "radii × ntheta"),
        MeshSpec::FocusedAnnulus { ntheta, .. } => (grid(1, ntheta, true), "ntheta"),
        // Resolved to AnnulusRings / Rectangle before the budget is checked.
        MeshSpec::SizedAnnulus { .. } | MeshSpec::SizedRectangle { .. } => (Some((0, 0)), "element_size"),
        MeshSpec::Obj { .. } => (Some((0, 0)), "the OBJ file"),
    }
}

fn make_mesh(spec: &MeshSpec, base_dir: &Path) -> Result<ShellMesh, mesh::MeshError> {
    let rad = f64::to_radians;
    match *spec {
        MeshSpec::Rectangle { lx, ly, nx, ny } => mesh::rectangle(lx, ly, nx, ny),
        MeshSpec::GradedRectangle { lx, ly, ref x, ref y } => mesh::graded_rectangle(lx, ly, x, y),
        MeshSpec::CylindricalPanel { radius, length, theta0, theta1, n_axial, n_circ, spacing } => {
            mesh::cylindrical_panel_spaced(radius, length, rad(theta0), rad(theta1), n_axial, n_circ, spacing)
        }
        MeshSpec::Hemisphere { radius, hole_angle, phi0, phi1, n_merid, n_circ, spacing } => {
            mesh::hemisphere_spaced(radius, rad(hole_angle), rad(phi0), rad(phi1), n_merid, n_circ, spacing)
        }
        MeshSpec::SlitAnnulus { ri, ro, nr, ntheta } => mesh::slit_annulus(ri, ro, nr, ntheta),
        MeshSpec::Annulus { ri, ro, nr, ntheta, graded } => mesh::annulus(ri, ro, nr, ntheta, graded),
        MeshSpec::AnnulusRings { ref radii, ntheta } => mesh::annulus_rings(radii, ntheta),
        MeshSpec::FocusedAnnulus { ri, ro, ntheta, focus, refine, inner_aspect } => {
            mesh::annulus_rings(&mesh::focused_rings(ri, ro, ntheta, focus, refine, inner_aspect)?, ntheta)
        }
        MeshSpec::SizedAnnulus { .. } | MeshSpec::SizedRectangle { .. } => Err(mesh::MeshError::Invalid("a sized mesh is generated once its size is resolved (scene::sizing)".to_string())),
        MeshSpec::TwistedStrip { length, width, twist, nx, ny } => mesh::twisted_strip(length, width, rad(twist), nx, ny),
        MeshSpec::Obj { ref path } => mesh::read_obj(&base_dir.join(path)),
    }
}

/// Tributary reference length of each node of an edge: half of each adjacent segment.
/// Sets that are not ordered edges are ordered along their longest extent first.
fn tributary_lengths(x: &[Vector3<f64>], nodes: &[usize]) -> Vec<(usize, f64)> {
    let mut order = nodes.to_vec();
    // An ordered edge has short consecutive gaps; otherwise sort along the longest extent.
    let (mut lo, mut hi) = (Vector3::repeat(f64::INFINITY), Vector3::repeat(f64::NEG_INFINITY));
    for &n in nodes {
        lo = lo.inf(&x[n]);
        hi = hi.sup(&x[n]);
    }
    let chain: f64 = nodes.windows(2).map(|w| (x[w[1]] - x[w[0]]).norm()).sum();
    if chain > 1.5 * (hi - lo).norm() + 1e-12 {
        let axis = (hi - lo).iamax();
        order.sort_by(|&a, &b| x[a][axis].total_cmp(&x[b][axis]));
    }
    let mut out: Vec<(usize, f64)> = order.iter().map(|&n| (n, 0.0)).collect();
    for i in 0..order.len().saturating_sub(1) {
        let l = (x[order[i + 1]] - x[order[i]]).norm();
        out[i].1 += 0.5 * l;
        out[i + 1].1 += 0.5 * l;
    }
    out
}

/// Consistent nodal area weights ∫ N_a dA over a part's reference mid-surface.
fn area_weights(x: &[Vector3<f64>], elements: &[ElementDef], part: &PartInfo) -> Vec<(usize, f64)> {
    let mut w = vec![0.0; part.n_nodes];
    let (p2, _) = gauss_legendre(2).unwrap_or((&[0.0], &[2.0]));
    for el in &elements[part.first_element..part.first_element + part.n_elements] {
        for &eta in p2 {
            for &xi in p2 {
                let (n, dxi, deta) = bilinear(xi, eta);
                let mut gx = Vector3::zeros();
                let mut gy = Vector3::zeros();
                for a in 0..4 {
                    gx += x[el.nodes[a]] * dxi[a];
                    gy += x[el.nodes[a]] * deta[a];
                }
                let da = gx.cross(&gy).norm();
                for a in 0..4 {
                    w[el.nodes[a] - part.first_node] += n[a] * da;
                }
            }
        }
    }
    w.into_iter().enumerate().map(|(i, a)| (i + part.first_node, a)).collect()
}
