//! Contact of shell nodes with rigid bodies (parry3d), viscous stabilization for static steps
//! and drape measures.

pub mod barrier;
pub mod body;
pub mod ccd;
pub mod drape;
pub mod interply;
pub mod intersection;
pub mod ipc;
pub mod mechanics;
pub mod motion;
pub mod spec;
pub mod stabilize;
pub mod trimesh_io;

use std::path::Path;

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use parry3d_f64::math::Vector as PVec;
use parry3d_f64::shape::{Ball, Capsule, Cuboid, Cylinder};

pub use barrier::{BarrierContact, BarrierSettings, NearNode};
pub use body::{Proximity, RigidBody, Shape};
pub use mechanics::{ContactIncrement, ContactSet, ContactSettings};
pub use stabilize::Stabilization;

use crate::model::PartInfo;
use trimesh_io::TriSoup;
use crate::input::{Locator, SceneError};
use spec::{ContactFormulation, ContactSpec, DrapeSpec, ShapeSpec};

/// Rigid bodies, the participating parts and the contact controls of a scene.
#[derive(Clone, Debug)]
pub struct ContactSetup {
    /// Placed bodies.
    pub bodies: Vec<RigidBody>,
    /// Participating part indices (empty: all).
    pub parts: Vec<usize>,
    /// Penalty controls (augmented Lagrangian).
    pub settings: ContactSettings,
    /// Barrier controls; None: the augmented-Lagrangian penalty formulation.
    pub barrier: Option<BarrierSettings>,
    /// Viscous stabilization coefficient (N/m³), if any.
    pub stabilization: Option<f64>,
    /// Warnings from mesh repair (file: what was repaired).
    pub warnings: Vec<String>,
}

/// Builds the bodies of `spec`; mesh paths are relative to `base_dir`. Errors are located
/// at the body's name in the scene text.
pub fn build_contact(spec: &ContactSpec, loc: &Locator, base_dir: &Path, parts: &[PartInfo]) -> Result<ContactSetup, SceneError> {
    let pos = |x: f64| x.is_finite() && x > 0.0;
    let mut bodies = Vec::new();
    let mut warnings = Vec::new();
    for (bi, b) in spec.bodies.iter().enumerate() {
        let field = format!("contact.bodies[{}]", b.name);
        let bad = |key: &str, msg: String| loc.at(Some(&b.name), Some(key), format!("{field}.{key}"), msg);
        let rounding = b.rounding;
        if !(rounding.is_finite() && rounding >= 0.0) {
            return Err(bad("rounding", format!("expected a non-negative rounding radius, found {rounding}")));
        }
        if rounding > 0.0 && !matches!(b.shape, ShapeSpec::Box { .. } | ShapeSpec::Cylinder { .. }) {
            return Err(bad("rounding", "rounding applies to Box and Cylinder bodies only".into()));
        }
        // The shapes of this body: (name, shape, placement relative to the body's placement).
        let single = |shape: Shape| vec![(b.name.clone(), shape, Isometry3::identity())];
        // Per-shape motions of a posed mannequin (one per segment), if it has a motion file.
        let mut segment_motions: Option<Vec<motion::Motion>> = None;
        let shapes = match &b.shape {
            ShapeSpec::Plane => single(Shape::Plane),
            ShapeSpec::Sphere { radius } => {
                if !pos(*radius) {
                    return Err(bad("radius", format!("expected a positive radius, found {radius}")));
                }
                single(Shape::Sphere(Ball::new(*radius)))
            }
            ShapeSpec::Box { half_extents } => {
                if !half_extents.iter().all(|&h| h.is_finite() && h > rounding) {
                    return Err(bad("half_extents", format!("expected half extents larger than the rounding {rounding}, found {half_extents:?}")));
                }
                let r = rounding;
                single(Shape::Box(Cuboid::new(PVec::new(half_extents[0] - r, half_extents[1] - r, half_extents[2] - r))))
            }
            ShapeSpec::Cylinder { radius, height } => {
                if !(radius.is_finite() && height.is_finite() && *radius > rounding && 0.5 * height > rounding) {
                    return Err(bad("radius", format!("expected a radius and half height larger than the rounding {rounding}, found {radius}, {height}")));
                }
                single(Shape::Cylinder(Cylinder::new(0.5 * height - rounding, radius - rounding)))
            }
            ShapeSpec::Capsule { radius, height } => {
                if !pos(*radius) || !pos(*height) {
                    return Err(bad("radius", format!("expected a positive radius and height, found {radius}, {height}")));
                }
                single(Shape::Capsule(Capsule::new_y(0.5 * height, *radius)))
            }
            ShapeSpec::TriMesh { path, scale } => {
                if !pos(*scale) {
                    return Err(bad("scale", format!("expected a positive scale, found {scale}")));
                }
                let full = base_dir.join(path);
                let (mut soup, w) = trimesh_io::read_trimesh(&full).map_err(|e| bad("path", format!("triangle mesh rejected: {e}")))?;
                soup.vertices.iter_mut().for_each(|v| *v *= *scale);
                warnings.extend(w.into_iter().map(|m| format!("{}: {m}", full.display())));
                single(Shape::mesh(&soup).map_err(|e| bad("path", format!("{}: {e}", full.display())))?)
            }
            ShapeSpec::Mannequin { measurements, pose, motion } => {
                let (shapes, motions) = mannequin_shapes(&b.name, base_dir, measurements, pose.as_deref(), motion.as_deref(), &bad)?;
                segment_motions = motions;
                shapes
            }
        };
        if !(b.friction.is_finite() && b.friction >= 0.0) {
            return Err(bad("friction", format!("expected a non-negative friction coefficient, found {}", b.friction)));
        }
        let kinetic = b.kinetic_friction.unwrap_or(b.friction);
        if !(kinetic.is_finite() && kinetic >= 0.0 && kinetic <= b.friction) {
            return Err(bad("kinetic_friction", format!("expected 0 ≤ kinetic ≤ static friction, found {kinetic} (static {})", b.friction)));
        }
        if !b.translation.iter().chain(&b.rotation).all(|v| v.is_finite()) {
            return Err(bad("translation", "expected finite translation and rotation".into()));
        }
        let rv = Vector3::from(b.rotation).map(f64::to_radians);
        let pose = Isometry3::from_parts(Translation3::from(Vector3::from(b.translation)), UnitQuaternion::from_scaled_axis(rv));
        if spec.bodies[..bi].iter().any(|o| o.name == b.name) {
            return Err(loc.at(Some(&b.name), None, field, "duplicate body name"));
        }
        let motion = if b.motion.is_empty() {
            None
        } else {
            if matches!(spec.formulation, ContactFormulation::AugmentedLagrangian) {
                return Err(bad(
                    "motion",
                    "a moving body needs barrier contact (formulation: Barrier()); the augmented-Lagrangian penalty contact holds bodies still".into(),
                ));
            }
            let keys: Vec<_> = b.motion.iter().map(|k| (k.time, k.translation, k.rotation)).collect();
            let m = motion::Motion::new(&keys).map_err(|(k, msg)| {
                let t = b.motion[k].time;
                loc.at(Some(&b.name), Some("motion"), format!("{field}.motion[{k}]"), format!("keyframe {k} (time {t}): {msg}"))
            })?;
            Some(std::sync::Arc::new(m))
        };
        if let Some(motions) = &segment_motions {
            if motion.is_some() {
                return Err(bad("motion", "a mannequin with a motion file moves by its poses; give its keyframes there (pose translations), not as body keyframes".into()));
            }
            if matches!(spec.formulation, ContactFormulation::AugmentedLagrangian) {
                return Err(bad("shape", "a mannequin with a motion file needs barrier contact (formulation: Barrier()); the augmented-Lagrangian penalty contact holds bodies still".into()));
            }
            // Segment keyframes K_s(t) are global isometries that carry the first frame's
            // placement P·F_s(t₀) to P·F_s(t); the body's own placement P conjugates them.
            for ((name, shape, local), m) in shapes.into_iter().zip(motions) {
                let base = pose * local;
                let keys: Vec<_> = m.keys().iter().map(|(t, k)| (*t, pose * k * pose.inverse())).collect();
                let m = motion::Motion::from_isometries(keys).map(std::sync::Arc::new);
                let placed = m.as_ref().map_or(base, |m| m.at(0.0) * base);
                bodies.push(RigidBody { name, shape, pose: placed, mu_static: b.friction, mu_kinetic: kinetic, rounding, motion: m, base });
            }
            continue;
        }
        for (name, shape, local) in shapes {
            // A segment of a composite body (mannequin) sits at `local` in the body's frame;
            // a motion moves the whole body.
            let base = pose * local;
            let placed = motion.as_ref().map_or(base, |m| m.at(0.0) * base);
            bodies.push(RigidBody { name, shape, pose: placed, mu_static: b.friction, mu_kinetic: kinetic, rounding, motion: motion.clone(), base });
        }
    }
    let mut part_ids = Vec::new();
    for p in &spec.parts {
        let i = parts.iter().position(|q| &q.name == p).ok_or_else(|| {
            let known: Vec<&str> = parts.iter().map(|q| q.name.as_str()).collect();
            loc.at_value("contact", p, "contact.parts", format!("unknown part \"{p}\"; parts: {}", known.join(", ")))
        })?;
        part_ids.push(i);
    }
    if !pos(spec.penalty_factor) {
        return Err(loc.at(None, Some("penalty_factor"), "contact.penalty_factor", "expected a positive penalty factor"));
    }
    if spec.penalty.is_some_and(|k| !pos(k)) {
        return Err(loc.at(None, Some("penalty"), "contact.penalty", "expected a positive nodal penalty (N/m)"));
    }
    if !pos(spec.tangential_factor) {
        return Err(loc.at(None, Some("tangential_factor"), "contact.tangential_factor", "expected a positive tangential factor"));
    }
    let barrier = match &spec.formulation {
        ContactFormulation::AugmentedLagrangian => None,
        ContactFormulation::Barrier { distance_factor, stiffness_factor, friction_slip } => {
            for (key, v) in [("distance_factor", distance_factor), ("stiffness_factor", stiffness_factor), ("friction_slip", friction_slip)] {
                if !pos(*v) {
                    return Err(loc.at(None, Some(key), format!("contact.formulation.{key}"), format!("expected a positive number, found {v}")));
                }
            }
            Some(BarrierSettings { distance_factor: *distance_factor, stiffness_factor: *stiffness_factor, friction_slip: *friction_slip })
        }
    };
    if spec.stabilization.is_some_and(|c| !pos(c)) {
        return Err(loc.at(None, Some("stabilization"), "contact.stabilization", "expected a positive stabilization coefficient (N/m³)"));
    }
    Ok(ContactSetup {
        bodies,
        parts: part_ids,
        settings: ContactSettings { penalty_factor: spec.penalty_factor, penalty: spec.penalty, tangential_factor: spec.tangential_factor },
        barrier,
        stabilization: spec.stabilization,
        warnings,
    })
}

/// The segments of a mannequin body as triangle-mesh shapes named `NAME.SEGMENT`, each with
/// its placement in the pose (local → body frame). A file that cannot be read is an error
/// at the body's `measurements` or `pose` field; an error inside a file names that file.
fn mannequin_shapes(
    name: &str,
    base_dir: &Path,
    measurements: &str,
    pose: Option<&str>,
    motion: Option<&str>,
    bad: &dyn Fn(&str, String) -> SceneError,
) -> Result<MannequinShapes, SceneError> {
    use crate::mannequin::{self, Mannequin};
    let located = |key: &str, e: SceneError| if e.line == 0 && e.field == "file" { bad(key, format!("{}: {}", e.file, e.message)) } else { e };
    let m = mannequin::load_measurements(&base_dir.join(measurements)).map_err(|e| located("measurements", e))?;
    let moves = match motion {
        Some(p) => Some(mannequin::load_motion(&base_dir.join(p)).map_err(|e| located("motion", e))?),
        None => None,
    };
    let pose = match (&moves, pose) {
        (Some(mv), _) => mv.frames.first().map(|f| f.2.clone()).unwrap_or_default(),
        (None, Some(p)) => mannequin::load_pose(&base_dir.join(p)).map_err(|e| located("pose", e))?,
        (None, None) => mannequin::Pose::default(),
    };
    let body = Mannequin::new(&m);
    let placements = body.placements(&pose);
    // Segment motions: forward kinematics sampled at every frame and at SAMPLES − 1 points
    // between frames (the contact interpolates linearly/slerp between samples, the
    // mannequin linearly in joint angles: the two agree at the samples).
    const SAMPLES: usize = 32;
    let segment_motions = moves.as_ref().map(|mv| {
        let mut times = Vec::new();
        for w in mv.frames.windows(2) {
            let (t0, t1) = (w[0].0, w[1].0);
            times.extend((0..SAMPLES).map(|k| t0 + (t1 - t0) * k as f64 / SAMPLES as f64));
        }
        times.extend(mv.frames.last().map(|f| f.0));
        let mut keys: Vec<Vec<(f64, Isometry3<f64>)>> = vec![Vec::with_capacity(times.len()); body.segments.len()];
        for &t in &times {
            for (s, (now, first)) in body.placements(&mv.pose_at(t)).iter().zip(&placements).enumerate() {
                keys[s].push((t, now * first.inverse()));
            }
        }
        keys.into_iter().filter_map(motion::Motion::from_isometries).collect::<Vec<_>>()
    });
    if let Some(m) = &segment_motions
        && m.len() != body.segments.len()
    {
        return Err(bad("motion", "the motion's frame times must increase strictly".into()));
    }
    let mut out = Vec::with_capacity(body.segments.len());
    for (seg, place) in body.segments.iter().zip(placements) {
        let soup = TriSoup { vertices: seg.surface.vertices.iter().map(|v| v.coords).collect(), triangles: seg.surface.triangles.clone() };
        let shape = Shape::mesh(&soup).map_err(|e| bad("measurements", format!("segment {}: {e}", seg.segment.name())))?;
        out.push((format!("{name}.{}", seg.segment.name()), shape, place));
    }
    Ok((out, segment_motions))
}

/// The segments of a mannequin body, (name, shape, placement in the body's frame), and, with
/// a motion file, one keyframed motion per segment.
type MannequinShapes = (Vec<(String, Shape, Isometry3<f64>)>, Option<Vec<motion::Motion>>);

/// Adds the contact and stabilization terms of `setup` to `solver` (drape falls and settles
/// in a `Dynamic` step of the solver, `solver::dynamics`). A barrier formulation needs an
/// intersection-free start: a node whose shell face starts on or inside a body is an error.
pub fn attach<'m>(solver: &mut crate::solver::Solver<'m>, model: &'m crate::model::Model, setup: &ContactSetup) -> Result<(), String> {
    match &setup.barrier {
        Some(b) => {
            let c = BarrierContact::new(model, setup.bodies.clone(), &setup.parts, b);
            let bad = c.intersections(model, &model.initial_state());
            if let Some((node, body, gap)) = bad.first() {
                return Err(format!(
                    "{} node(s) start with the shell face on or inside a body (node {node} in '{body}' by {:.3e} m); barrier contact needs a gap: move the body or the part",
                    bad.len(),
                    -gap
                ));
            }
            solver.add_nodal_forces(Box::new(c));
        }
        None => solver.add_nodal_forces(Box::new(ContactSet::new(model, setup.bodies.clone(), &setup.parts, &setup.settings))),
    }
    if let Some(k) = setup.stabilization {
        solver.add_nodal_forces(Box::new(Stabilization::new(model, k)));
    }
    Ok(())
}

/// Largest penetration of any shell node's face (offset h/2) into any body at `state`, by
/// a fresh, unbounded proximity query per node and body (independent of the penalty
/// bookkeeping and its search reach).
pub fn max_penetration(model: &crate::model::Model, state: &crate::model::State, bodies: &[RigidBody]) -> f64 {
    use rayon::prelude::*;
    let mut half = vec![0.0f64; model.n_nodes()];
    for def in &model.elements {
        for &a in &def.nodes {
            half[a] = half[a].max(0.5 * model.sections[def.section].thickness);
        }
    }
    (0..model.n_nodes())
        .into_par_iter()
        .map(|a| {
            let x = model.position(state, a);
            bodies.iter().filter_map(|b| b.proximity(&x, f64::MAX)).map(|p| half[a] - p.distance).fold(0.0, f64::max)
        })
        .reduce(|| 0.0, f64::max)
}

/// Writes the contact, stabilization and (for a `drape` spec) drape sections of summary.json
/// into `extra`; `time` is the analysis time of `state` (moving bodies are placed there, `motion`).
pub fn summarize(
    drape: Option<&DrapeSpec>,
    setup: &ContactSetup,
    model: &crate::model::Model,
    state: &crate::model::State,
    time: f64,
    contributions: &[Box<dyn crate::solver::NodalForces + '_>],
    extra: &mut std::collections::BTreeMap<String, serde_json::Value>,
) {
    for c in contributions {
        if let Some((name, v)) = c.summary() {
            extra.insert(name, v);
        }
    }
    if !setup.warnings.is_empty() {
        extra.insert("contact_warnings".into(), serde_json::json!(setup.warnings));
    }
    if let Some(d) = drape {
        let res = d.resolution.unwrap_or(d.specimen_radius / 1000.0);
        let placed: Vec<RigidBody> = setup.bodies.iter().map(|b| b.at_time(time)).collect();
        let pen = max_penetration(model, state, &placed);
        let rep = drape::drape_report(model, state, &Vector3::from(d.center), d.disc_radius, d.specimen_radius, res, pen);
        if let Ok(v) = serde_json::to_value(rep) {
            extra.insert("drape".into(), v);
        }
    }
}
