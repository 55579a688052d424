//! Element sizes from the physics (`element_size: Auto((tolerance: ..))`) resolved against
//! the scene: the garment panels' size fields ([`resolve_sizes`], `garment::sizing`) and the
//! meshes of sized generated parts ([`resolve_part_mesh`]).
//!
//! A `SizedAnnulus` part (a circular specimen such as the Cusick one) with
//! `element_size: Auto((tolerance: T))` becomes an `AnnulusRings` mesh whose ring spacing
//! follows a radial size field and whose sector count follows the folds of its free overhang
//! (`crate::sizing` for the length scales); a `SizedRectangle` becomes a `Rectangle` at the
//! garment panels' isotropic size ([`sized_rectangle`]).
//!
//! The annulus' grid directions are those of a drape over a round support: radially the
//! fabric hangs, circumferentially it folds. Each direction takes the length scale of its own
//! shape, h = √(8 T) ℓ (`sizing::size_for`):
//!
//! - **sectors** (across the folds): the Cerda–Mahadevan wavelength λ of the overhang,
//!   λ = 2π (B L² / (π² T_e))^{1/4} with L = ro − r_e the overhang beyond the support's edge
//!   r_e and T_e = ρ_A g L the tension its weight puts on the edge (or the given `tension`):
//!   the folds leave the edge λ apart, so the circumferential width there is
//!   √(8T) λ/2π, n_θ = ⌈2π r_e / (√(8T) λ/2π)⌉. Folds keep their count outwards, so the
//!   relative error (w n)²/8 of a fold of n waves on a sector width w is the same at every
//!   radius. Without a support the edge is the inner radius (a specimen held at its hole).
//! - **rings** (along the hang): the bending length ℓ_b = (B/(ρ_A g))^{1/3} over the free
//!   and singly supported fabric (the length over which it curls or lifts off); within 2ℓ_b of
//!   a curved contact body (the support's rounded rim) the larger of the body's radius
//!   R_body (`sizing::radius_from_normals`) and the tensioned sheet's own boundary layer
//!   ℓ_T = √(B / T_e) (`sizing::tension_length`): a sheet under tension does not bend more
//!   tightly than ℓ_T however sharp the edge it hangs over; no size of its own where the
//!   specimen is held flat between two bodies (bodies within its thickness on both faces).
//!   The field is graded by at most 1/4 per unit of radius (neighbouring rings differ by
//!   ≤ 25 %, as in `mesh::focused_rings`), and no element is longer radially than
//!   [`MAX_ASPECT`] circumferential widths (the shipped specimen's shape between the discs).
//!
//! A fixed `element_size: h` gives uniform rings at most h apart and sectors at most h wide
//! at ro.

use std::collections::BTreeMap;
use std::f64::consts::TAU;
use std::path::Path;
use std::sync::Arc;

use nalgebra::Vector3;

use super::spec::{LoadSpec, MeshSpec, PartSpec, Scene};
use crate::input::{Locator, SceneError};
use crate::material::ShellMaterial;
use crate::model::PartInfo;

use crate::contact::body::{RigidBody, Shape};
use crate::sizing::{bending_length, radius_from_normals, size_for, size_from_scales, tension_length, wrinkle_wavelength, ElementSize, LengthScales, G};

/// Largest radial-to-circumferential aspect ratio of an element of a sized annulus.
pub const MAX_ASPECT: f64 = 4.0;

/// Largest growth of the radial size per unit radius (25 % between neighbouring rings).
pub const GRADING: f64 = 0.25;

/// What a sized part needs from the scene: its section's bending rigidity and areal density,
/// its thickness, placement offset, and the scene's contact bodies.
pub struct PartPhysics<'a> {
    /// Bending rigidity B (N·m) of the part's material at its thickness.
    pub bending: Option<f64>,
    /// Areal density ρ_A (kg/m²): the part's, a Gravity load's or its material's.
    pub areal_density: Option<f64>,
    /// Shell thickness (m).
    pub thickness: f64,
    /// Offset of the generated mesh.
    pub offset: Vector3<f64>,
    /// Rigid contact bodies of the scene.
    pub bodies: &'a [RigidBody],
}

/// The length scales and the mesh chosen for a sized annulus.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AnnulusSizing {
    /// Ring radii (ri … ro).
    pub radii: Vec<f64>,
    /// Sectors.
    pub ntheta: usize,
    /// Bending length ℓ_b (m).
    pub bending_length: f64,
    /// Wrinkle wavelength λ of the overhang (m).
    pub wrinkle_wavelength: f64,
    /// Bending boundary layer ℓ_T at the support's edge (m).
    pub tension_length: f64,
    /// Radius of the support's edge r_e (m), the inner radius without a support.
    pub edge_radius: f64,
    /// Smallest radius of a contact body near the specimen (m), if any.
    pub body_radius: Option<f64>,
}

/// Mesh of `SizedAnnulus { ri, ro, element_size }` (see the module doc). Errors: (key,
/// message) of the offending field (`ri`, `ro`, `element_size`, `tolerance`, `tension`).
pub fn sized_annulus(ri: f64, ro: f64, size: &ElementSize, physics: &PartPhysics) -> Result<AnnulusSizing, (&'static str, String)> {
    if !(ri.is_finite() && ri > 0.0) {
        return Err(("ri", format!("expected a positive inner radius, found {ri}")));
    }
    if !(ro.is_finite() && ro > ri) {
        return Err(("ro", format!("expected an outer radius greater than ri ({ri}), found {ro}")));
    }
    if let Some(e) = size.problem() {
        return Err(e);
    }
    let rings = |size: &dyn Fn(f64) -> f64, ntheta: usize| crate::mesh::sized_rings(ri, ro, size, crate::mesh::generate::MAX_NODES / ntheta.max(1)).map_err(|e| ("element_size", e.to_string()));
    let a = match size {
        ElementSize::Fixed(h) => {
            let ntheta = sectors(TAU * ro / h)?;
            return Ok(AnnulusSizing { radii: rings(&|_| *h, ntheta)?, ntheta, ..Default::default() });
        }
        ElementSize::Auto(a) => a,
    };
    let (b, rho) = fabric(physics)?;
    let lb = bending_length(b, rho);
    // The radial profile, sampled every (ro − ri)/2000 (65 µm on the Cusick specimen, a
    // twentieth of its finest ring step; a body's curvature varying faster than that is
    // seen at the samples only).
    let samples = 2000usize;
    let dr = (ro - ri) / samples as f64;
    let radii_s: Vec<f64> = (0..=samples).map(|k| ri + dr * k as f64).collect();
    let probes: Vec<Probe> = radii_s.iter().map(|&r| probe(r, lb, physics)).collect();
    // The support's edge: the outermost radius up to which every angle is supported.
    let edge = probes.iter().zip(&radii_s).take_while(|(p, _)| p.supported).last().map_or(ri, |(_, &r)| r);
    let overhang = ro - edge;
    if overhang <= 0.0 {
        return Err(("tolerance", "Auto: the whole specimen lies on a support; there is no overhang to size the folds by".to_string()));
    }
    let tension = a.tension.unwrap_or(rho * G * overhang);
    let lambda = wrinkle_wavelength(b, tension, overhang);
    let lt = tension_length(b, tension);
    let ntheta = sectors(TAU * edge.max(ri) / size_for(a.tolerance, lambda / TAU))?;
    let w = TAU / ntheta as f64;
    // The physical size per sample, then the grading (two sweeps: h_k ≤ h_j + GRADING |r_k − r_j|).
    let cap = 0.5 * ro;
    let mut h: Vec<f64> = probes
        .iter()
        .zip(&radii_s)
        .map(|(p, &r)| {
            let mut l = if p.held { f64::INFINITY } else { lb };
            if let Some(rb) = p.body_radius {
                l = l.min(rb.max(lt));
            }
            size_for(a.tolerance, l).min(cap).min(MAX_ASPECT * w * r)
        })
        .collect();
    for k in 1..h.len() {
        h[k] = h[k].min(h[k - 1] + GRADING * dr);
    }
    for k in (0..h.len() - 1).rev() {
        h[k] = h[k].min(h[k + 1] + GRADING * dr);
    }
    let field = |r: f64| {
        let x = ((r - ri) / dr).clamp(0.0, samples as f64);
        let k = (x.floor() as usize).min(samples - 1);
        let f = x - k as f64;
        h[k] * (1.0 - f) + h[k + 1] * f
    };
    let radii = rings(&field, ntheta)?;
    let body_radius = probes.iter().filter_map(|p| p.body_radius).reduce(f64::min);
    Ok(AnnulusSizing { radii, ntheta, bending_length: lb, wrinkle_wavelength: lambda, tension_length: lt, edge_radius: edge, body_radius })
}

/// Grid of `SizedRectangle { lx, ly, element_size }`: (nx, ny) = (⌈lx/h⌉, ⌈ly/h⌉) with the
/// garment panels' isotropic size (`sizing::size_from_scales`, the formula of
/// `garment::sizing` for a panel without seams): h = √(8T) · min(ℓ_b, λ/2π, R_body), λ the
/// Cerda–Mahadevan wavelength under the given `tension` or the sheet's own weight over its
/// diagonal L (T = ρ_A g L), R_body the smallest radius of a contact body within 2ℓ_b of the
/// placed sheet (probed on its outline and a grid at the size without it), at most a quarter
/// of L. A fixed h gives ⌈lx/h⌉ × ⌈ly/h⌉. Errors as [`sized_annulus`]'s (`lx`, `ly`).
pub fn sized_rectangle(lx: f64, ly: f64, size: &ElementSize, physics: &PartPhysics) -> Result<(usize, usize, Option<LengthScales>), (&'static str, String)> {
    for (key, v) in [("lx", lx), ("ly", ly)] {
        if !(v.is_finite() && v > 0.0) {
            return Err((key, format!("expected a positive length, found {v}")));
        }
    }
    if let Some(e) = size.problem() {
        return Err(e);
    }
    let count = |l: f64, h: f64| {
        let n = (l / h).ceil();
        if n.is_finite() && n < crate::mesh::generate::MAX_NODES as f64 { Ok((n as usize).max(1)) } else { Err(("element_size", format!("the element size asks for {n} elements along {l} m"))) }
    };
    let a = match size {
        ElementSize::Fixed(h) => return Ok((count(lx, *h)?, count(ly, *h)?, None)),
        ElementSize::Auto(a) => a,
    };
    let (b, rho) = fabric(physics)?;
    let lb = bending_length(b, rho);
    let l = lx.hypot(ly);
    let tension = a.tension.unwrap_or(rho * G * l);
    let mut scales = LengthScales { bending_length: lb, wrinkle_wavelength: wrinkle_wavelength(b, tension, l), body_radius: None };
    let coarse = size_from_scales(a.tolerance, &scales, l);
    let (nx, ny) = (count(lx, coarse)?, count(ly, coarse)?);
    let mut radius = f64::INFINITY;
    for i in 0..=nx {
        for j in 0..=ny {
            let x = physics.offset + Vector3::new(lx * i as f64 / nx as f64, ly * j as f64 / ny as f64, 0.0);
            for b in physics.bodies.iter().filter(|b| !matches!(b.shape, Shape::Plane)) {
                let normal = |y: &Vector3<f64>| b.proximity(y, 2.0 * lb).filter(|q| q.distance.abs() <= 2.0 * lb).map(|q| q.normal);
                if let Some(r) = radius_from_normals(&x, lb, &normal) {
                    radius = radius.min(r);
                }
            }
        }
    }
    scales.body_radius = radius.is_finite().then_some(radius);
    let h = size_from_scales(a.tolerance, &scales, l);
    Ok((count(lx, h)?, count(ly, h)?, Some(scales)))
}

/// The part's bending rigidity and areal density, both positive, or the `Auto` error.
fn fabric(physics: &PartPhysics) -> Result<(f64, f64), (&'static str, String)> {
    let b = physics.bending.filter(|b| b.is_finite() && *b > 0.0).ok_or(("tolerance", "Auto: the part's material has no bending rigidity".to_string()))?;
    let rho = physics.areal_density.filter(|r| r.is_finite() && *r > 0.0).ok_or((
        "tolerance",
        "Auto: the part has no areal density (give it an `areal_density`, a fabric material, or a Gravity load)".to_string(),
    ))?;
    Ok((b, rho))
}

/// Sectors for `n` widths round the circumference: ⌈n⌉, at least 8.
fn sectors(n: f64) -> Result<usize, (&'static str, String)> {
    if !(n.is_finite() && n < crate::mesh::generate::MAX_NODES as f64) {
        return Err(("element_size", format!("the element size asks for {n:.0} sectors round the annulus")));
    }
    Ok((n.ceil() as usize).max(8))
}

/// What the bodies do to the specimen on the circle of radius `r`.
struct Probe {
    /// Every angle lies on a support (a body within the thickness below or above it).
    supported: bool,
    /// Every angle is held between two bodies (one within the thickness on each face).
    held: bool,
    /// Smallest radius of a curved body within 2ℓ_b of the circle.
    body_radius: Option<f64>,
}

/// Probes the circle of radius `r` of the placed specimen at 16 angles: supports (a body's
/// surface within the thickness, its outward normal within 45° of the specimen's normal ±z)
/// and the radius of a curved body within 2ℓ_b (`radius_from_normals`, tangential step ℓ_b
/// halved while the normal turns by more than 45°; flat faces and planes have none).
fn probe(r: f64, lb: f64, physics: &PartPhysics) -> Probe {
    let (mut supported, mut held, mut radius) = (true, true, f64::INFINITY);
    for k in 0..16 {
        let t = TAU * k as f64 / 16.0;
        let x = physics.offset + Vector3::new(r * t.cos(), r * t.sin(), 0.0);
        let (mut below, mut above) = (false, false);
        for b in physics.bodies {
            if let Some(q) = b.proximity(&x, physics.thickness).filter(|q| q.distance <= physics.thickness) {
                below |= q.normal.z > std::f64::consts::FRAC_1_SQRT_2;
                above |= q.normal.z < -std::f64::consts::FRAC_1_SQRT_2;
            }
            if matches!(b.shape, Shape::Plane) {
                continue;
            }
            let normal = |y: &Vector3<f64>| b.proximity(y, 2.0 * lb).filter(|q| q.distance.abs() <= 2.0 * lb).map(|q| q.normal);
            if let Some(rx) = radius_from_normals(&x, lb, &normal) {
                radius = radius.min(rx);
            }
        }
        supported &= below || above;
        held &= below && above;
    }
    Probe { supported, held, body_radius: radius.is_finite().then_some(radius) }
}

/// The size fields of a garment whose `element_size` (its own or a panel's) is `Auto`, or
/// None when every size is a fixed number (`garment::sizing`): per ply the bending rigidity
/// of its material at its thickness and its areal density (the ply's, its material's, or a
/// `Gravity` load's on a panel or `panel/ply` part using it); the scene's contact bodies
/// (built here once more, for their surface normals) give the body curvature. Errors are
/// located at the `element_size` that asked for `Auto`.
pub(super) fn resolve_sizes(
    g: &crate::garment::GarmentSpec,
    scene: &Scene,
    loc: &Locator,
    base_dir: &Path,
    parts: &[PartInfo],
    materials: &BTreeMap<&str, Arc<dyn ShellMaterial>>,
) -> Result<Option<Vec<crate::garment::sizing::SizeField>>, SceneError> {
    use crate::garment::sizing::{panel_field, radius_from_normals, PlyPhysics};
    use crate::garment::ElementSize;
    let auto = |e: &ElementSize| matches!(e, ElementSize::Auto(_));
    if !auto(&g.element_size) && !g.panels.iter().any(|p| p.element_size.as_ref().is_some_and(auto)) {
        // Fixed sizes: a bad panel size is reported here, the garment's by the validation.
        for p in &g.panels {
            if let Some((key, msg)) = p.element_size.as_ref().and_then(|e| e.problem()) {
                let _ = key;
                return Err(loc.at(Some(&p.name), Some("element_size"), format!("garment.panels[{}].element_size", p.name), msg));
            }
        }
        if g.panels.iter().all(|p| p.element_size.is_none()) {
            return Ok(None);
        }
    }
    let bending = |ply: &str| {
        let spec = g.plies.get(ply)?;
        materials.get(spec.material.as_str()).map(|m| m.bending_rigidity(spec.thickness))
    };
    let density = |ply: &str| -> Option<f64> {
        let spec = g.plies.get(ply)?;
        if spec.areal_density > 0.0 {
            return Some(spec.areal_density);
        }
        if let Some(d) = materials.get(spec.material.as_str()).and_then(|m| m.areal_density()) {
            return Some(d);
        }
        let names: Vec<String> = g.panels.iter().filter(|p| p.plies.iter().any(|q| q == ply)).flat_map(|p| [p.name.clone(), crate::garment::laminate::alias(&p.name, ply)]).collect();
        scene.loads.values().find_map(|l| match l {
            LoadSpec::Gravity { part, areal_density, .. } if names.contains(part) => Some(*areal_density),
            _ => None,
        })
    };
    let bodies = scene_bodies(scene, loc, base_dir, parts);
    let body_radius = |points: &[nalgebra::Vector3<f64>], reach: f64, delta: f64| -> Option<f64> {
        let bodies = bodies.as_ref()?;
        let mut r = f64::INFINITY;
        for b in bodies.iter().filter(|b| !matches!(b.shape, crate::contact::body::Shape::Plane)) {
            let normal = |x: &nalgebra::Vector3<f64>| b.proximity(x, reach).filter(|q| q.distance.abs() <= reach).map(|q| q.normal);
            for x in points {
                if let Some(rx) = radius_from_normals(x, delta, &normal) {
                    r = r.min(rx);
                }
            }
        }
        r.is_finite().then_some(r)
    };
    let physics = PlyPhysics { bending: &bending, density: &density, body_radius: &body_radius };
    let mut fields = Vec::with_capacity(g.panels.len());
    for (pi, p) in g.panels.iter().enumerate() {
        let field = panel_field(g, pi, &physics).map_err(|(key, msg)| {
            let own = p.element_size.is_some();
            let path = if own { format!("garment.panels[{}].element_size", p.name) } else { "garment.element_size".to_string() };
            let path = if key == "element_size" { path } else { format!("{path}.{key}") };
            loc.at(if own { Some(&p.name) } else { None }, Some(key), path, format!("panel \"{}\": {msg}", p.name))
        })?;
        fields.push(field);
    }
    Ok(Some(fields))
}

/// The scene's rigid contact bodies alone, for the sizes (None without contact or when a body
/// does not build: the contact's own build reports that, located, later).
fn scene_bodies(scene: &Scene, loc: &Locator, base_dir: &Path, parts: &[PartInfo]) -> Option<Vec<RigidBody>> {
    scene.contact.as_ref().and_then(|c| {
        let mut c = c.clone();
        c.parts.clear();
        crate::contact::build_contact(&c, loc, base_dir, parts).ok().map(|s| s.bodies)
    })
}

/// The generator spec of part `p` with its size resolved: a `SizedAnnulus` becomes the
/// `AnnulusRings` of [`sized_annulus`], a `SizedRectangle` the `Rectangle` of
/// [`sized_rectangle`], each with a line reporting the mesh and the length scales behind it;
/// any other spec None.
/// `areal_density` is the part's (its own, a Gravity load's or its material's); errors are
/// located at the part's `mesh` field that is wrong (`ri`, `ro`, `element_size`, its
/// `tolerance` or `tension`).
pub(super) fn resolve_part_mesh(
    p: &PartSpec,
    scene: &Scene,
    loc: &Locator,
    base_dir: &Path,
    parts: &[PartInfo],
    material: &dyn ShellMaterial,
    areal_density: Option<f64>,
) -> Result<Option<(MeshSpec, String)>, SceneError> {
    if !matches!(p.mesh, MeshSpec::SizedAnnulus { .. } | MeshSpec::SizedRectangle { .. }) {
        return Ok(None);
    }
    let bodies = scene_bodies(scene, loc, base_dir, parts).unwrap_or_default();
    let offset = p.offset.map_or(Vector3::zeros(), |o| Vector3::new(o[0], o[1], o[2]));
    let physics = PartPhysics { bending: Some(material.bending_rigidity(p.thickness)), areal_density, thickness: p.thickness, offset, bodies: &bodies };
    let located = |(key, msg): (&'static str, String)| {
        let path = match key {
            "ri" | "ro" | "lx" | "ly" | "element_size" => format!("parts[{}].mesh.{key}", p.name),
            _ => format!("parts[{}].mesh.element_size.{key}", p.name),
        };
        loc.at(Some(&p.name), Some(key), path, format!("part \"{}\": {msg}", p.name))
    };
    let mm = |x: f64| format!("{:.2} mm", 1e3 * x);
    let body = |r: Option<f64>| r.map_or("none near".to_string(), mm);
    match p.mesh {
        MeshSpec::SizedAnnulus { ri, ro, ref element_size } => {
            let z = sized_annulus(ri, ro, element_size, &physics).map_err(located)?;
            let mut report = format!("SizedAnnulus: {} rings × {} sectors", z.radii.len() - 1, z.ntheta);
            if matches!(element_size, ElementSize::Auto(_)) {
                report += &format!(
                    " (ℓ_b {}, fold wavelength λ {}, ℓ_T {}, support edge r {}, body radius {})",
                    mm(z.bending_length),
                    mm(z.wrinkle_wavelength),
                    mm(z.tension_length),
                    mm(z.edge_radius),
                    body(z.body_radius)
                );
            }
            Ok(Some((MeshSpec::AnnulusRings { radii: z.radii, ntheta: z.ntheta }, report)))
        }
        MeshSpec::SizedRectangle { lx, ly, ref element_size } => {
            let (nx, ny, scales) = sized_rectangle(lx, ly, element_size, &physics).map_err(located)?;
            let mut report = format!("SizedRectangle: {nx} × {ny} elements");
            if let Some(l) = scales {
                report += &format!(" (ℓ_b {}, fold wavelength λ {}, body radius {})", mm(l.bending_length), mm(l.wrinkle_wavelength), body(l.body_radius));
            }
            Ok(Some((MeshSpec::Rectangle { lx, ly, nx, ny }, report)))
        }
        _ => Ok(None),
    }
}
