//! Movement protocols: the pose steps a scene's `protocol` adds after its own steps.
//!
//! A protocol names a mannequin contact body with a motion file (frames: time, pose). The
//! scene's own steps run with the body held in the first frame's pose (their analysis clock
//! window is [t₀, t₀]); then pose step k (k = 1, …) is a `Dynamic` step to rest whose clock
//! window is [t_{k−1}, t_k]: the body moves from pose k−1 to pose k by its forward
//! kinematics over that interval (`contact::motion`), and the step goes on, the body held
//! in pose k, until the garment is at rest. Each pose's measures are then taken at the end
//! of its step (`garment::measures`); the first pose's at the end of the scene's steps.

use std::path::Path;

use crate::input::{Locator, SceneError};
use super::spec::{ProtocolSpec, ShapeSpec};
use crate::solver::{StepKind, StepPlan};

/// The poses of a protocol and the steps that end at them.
#[derive(Clone, Debug)]
pub struct Protocol {
    /// The mannequin contact body that moves.
    pub body: String,
    /// In order: the first pose (reached at the end of the scene's own steps) and one per
    /// pose step.
    pub poses: Vec<PoseStep>,
}

/// One pose of a protocol.
#[derive(Clone, Debug)]
pub struct PoseStep {
    /// Pose name (the pose file's stem; a repeated pose gets `_2`, `_3`, …), also the name
    /// of its step.
    pub name: String,
    /// Index of the step at whose end the garment rests in this pose.
    pub step: usize,
    /// Time of the pose in the motion file (s).
    pub time: f64,
}

/// Appends the pose steps of `spec` to `steps` (the scene's own steps, which get the clock
/// window of the first pose) and returns the protocol. `scales` are the load scales at the
/// end of the scene's steps (kept through the protocol). Errors are located at the
/// protocol's fields: an unknown body, a body that is not a mannequin with a motion file,
/// a motion of a single frame, or invalid settling controls.
pub fn expand(spec: &ProtocolSpec, contact: Option<&super::ContactSpec>, loc: &Locator, base_dir: &Path, steps: &mut Vec<StepPlan>, scales: &[f64]) -> Result<Protocol, SceneError> {
    let bad = |key: &str, msg: String| loc.at(None, Some(key), format!("protocol.{key}"), msg);
    let bodies: Vec<&super::BodySpec> = contact.map(|c| c.bodies.iter().collect()).unwrap_or_default();
    let Some(body) = bodies.iter().find(|b| b.name == spec.body) else {
        let known: Vec<&str> = bodies.iter().map(|b| b.name.as_str()).collect();
        return Err(bad("body", format!("no contact body named \"{}\"; bodies: {}", spec.body, if known.is_empty() { "none (the scene has no contact section)".into() } else { known.join(", ") })));
    };
    let ShapeSpec::Mannequin { motion: Some(motion), .. } = &body.shape else {
        return Err(bad("body", format!("body \"{}\" is not a Mannequin with a motion file: a protocol moves a mannequin through the frames of its motion", spec.body)));
    };
    let mv = crate::mannequin::load_motion(&base_dir.join(motion)).map_err(|e| bad("body", format!("motion of body \"{}\": {e}", spec.body)))?;
    if mv.frames.len() < 2 {
        return Err(bad("body", format!("the motion of body \"{}\" has a single frame: a protocol needs at least one pose to move to", spec.body)));
    }
    if let Some((key, msg)) = crate::solver::dynamics::check_settings(&spec.settle) {
        return Err(loc.at(None, Some(key), format!("protocol.settle.{key}"), msg));
    }
    if spec.settle.duration != 0.0 {
        return Err(loc.at(None, Some("duration"), "protocol.settle.duration", "a pose step runs to rest: leave duration at 0"));
    }
    let t0 = mv.frames[0].0;
    for s in steps.iter_mut() {
        s.clock = Some([t0, t0]);
    }
    let mut used: Vec<String> = steps.iter().map(|s| s.name.clone()).collect();
    let mut unique = |name: &str| {
        let mut candidate = name.to_string();
        let mut k = 1;
        while used.contains(&candidate) {
            k += 1;
            candidate = format!("{name}_{k}");
        }
        used.push(candidate.clone());
        candidate
    };
    let first = unique(&mv.frames[0].1);
    let mut poses = vec![PoseStep { name: first, step: steps.len() - 1, time: t0 }];
    for w in mv.frames.windows(2) {
        let ((ta, ..), (tb, name, _)) = (&w[0], &w[1]);
        let name = unique(name);
        steps.push(StepPlan {
            name: name.clone(),
            increments: 1,
            linear: false,
            automatic_increments: false,
            target_scales: scales.to_vec(),
            kind: StepKind::Dynamic(spec.settle.clone()),
            clock: Some([*ta, *tb]),
        });
        poses.push(PoseStep { name, step: steps.len() - 1, time: *tb });
    }
    Ok(Protocol { body: spec.body.clone(), poses })
}
