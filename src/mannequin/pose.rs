//! Poses and motions: joint angles (degrees) read from RON, forward kinematics to one rigid
//! placement per segment, and linear interpolation of the angles between the timed poses of
//! a motion.

use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use super::skeleton::{Joint, Skeleton, JOINTS, SEGMENTS};
use crate::input::{Locator, SceneError};

/// Angles of one joint in degrees; axes and signs in [`Joint::axes`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointAngles {
    #[serde(default)]
    pub flexion: f64,
    #[serde(default)]
    pub abduction: f64,
    #[serde(default)]
    pub rotation: f64,
}

/// A pose: the angles of the named joints (absent joints at 0°), the pelvis orientation and
/// translation, and whether the body is lowered or raised onto the floor.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Pose {
    /// Pelvis orientation about its origin (midway between the hip joints), with the lumbar
    /// joint's axes: flexion tilts the body forward, abduction to its left, rotation turns it
    /// to its left.
    #[serde(default)]
    pub pelvis: JointAngles,
    /// Pelvis translation (m), applied before the floor contact.
    #[serde(default)]
    pub translation: (f64, f64, f64),
    /// Move the posed body vertically so that its lowest point is on the floor z = 0
    /// (default true: a squat lowers the body instead of lifting the feet).
    #[serde(default = "yes")]
    pub on_floor: bool,
    #[serde(default)]
    pub lumbar: JointAngles,
    #[serde(default)]
    pub neck: JointAngles,
    #[serde(default)]
    pub head: JointAngles,
    #[serde(default)]
    pub shoulder_l: JointAngles,
    #[serde(default)]
    pub elbow_l: JointAngles,
    #[serde(default)]
    pub wrist_l: JointAngles,
    #[serde(default)]
    pub shoulder_r: JointAngles,
    #[serde(default)]
    pub elbow_r: JointAngles,
    #[serde(default)]
    pub wrist_r: JointAngles,
    #[serde(default)]
    pub hip_l: JointAngles,
    #[serde(default)]
    pub knee_l: JointAngles,
    #[serde(default)]
    pub ankle_l: JointAngles,
    #[serde(default)]
    pub hip_r: JointAngles,
    #[serde(default)]
    pub knee_r: JointAngles,
    #[serde(default)]
    pub ankle_r: JointAngles,
}

fn yes() -> bool {
    true
}

impl Default for Pose {
    /// The rest pose: all angles zero, on the floor.
    fn default() -> Self {
        let z = JointAngles::default();
        Self {
            pelvis: z,
            translation: (0.0, 0.0, 0.0),
            on_floor: true,
            lumbar: z,
            neck: z,
            head: z,
            shoulder_l: z,
            elbow_l: z,
            wrist_l: z,
            shoulder_r: z,
            elbow_r: z,
            wrist_r: z,
            hip_l: z,
            knee_l: z,
            ankle_l: z,
            hip_r: z,
            knee_r: z,
            ankle_r: z,
        }
    }
}

impl Pose {
    /// The angles of joint `j`.
    pub fn angles(&self, j: Joint) -> JointAngles {
        *self.angles_ref(j)
    }

    /// Mutable angles of joint `j`.
    pub fn angles_mut(&mut self, j: Joint) -> &mut JointAngles {
        use Joint::*;
        match j {
            Lumbar => &mut self.lumbar,
            Neck => &mut self.neck,
            Head => &mut self.head,
            ShoulderL => &mut self.shoulder_l,
            ElbowL => &mut self.elbow_l,
            WristL => &mut self.wrist_l,
            ShoulderR => &mut self.shoulder_r,
            ElbowR => &mut self.elbow_r,
            WristR => &mut self.wrist_r,
            HipL => &mut self.hip_l,
            KneeL => &mut self.knee_l,
            AnkleL => &mut self.ankle_l,
            HipR => &mut self.hip_r,
            KneeR => &mut self.knee_r,
            AnkleR => &mut self.ankle_r,
        }
    }

    fn angles_ref(&self, j: Joint) -> &JointAngles {
        use Joint::*;
        match j {
            Lumbar => &self.lumbar,
            Neck => &self.neck,
            Head => &self.head,
            ShoulderL => &self.shoulder_l,
            ElbowL => &self.elbow_l,
            WristL => &self.wrist_l,
            ShoulderR => &self.shoulder_r,
            ElbowR => &self.elbow_r,
            WristR => &self.wrist_r,
            HipL => &self.hip_l,
            KneeL => &self.knee_l,
            AnkleL => &self.ankle_l,
            HipR => &self.hip_r,
            KneeR => &self.knee_r,
            AnkleR => &self.ankle_r,
        }
    }

    /// The pose a fraction `t` ∈ [0, 1] of the way from `a` to `b`: every angle and the
    /// translation interpolated linearly; `on_floor` from `a`.
    pub fn lerp(a: &Pose, b: &Pose, t: f64) -> Pose {
        let l = |x: f64, y: f64| x + (y - x) * t;
        let la = |x: JointAngles, y: JointAngles| JointAngles { flexion: l(x.flexion, y.flexion), abduction: l(x.abduction, y.abduction), rotation: l(x.rotation, y.rotation) };
        let mut p = a.clone();
        p.pelvis = la(a.pelvis, b.pelvis);
        p.translation = (l(a.translation.0, b.translation.0), l(a.translation.1, b.translation.1), l(a.translation.2, b.translation.2));
        for j in JOINTS {
            *p.angles_mut(j) = la(a.angles(j), b.angles(j));
        }
        p
    }

    /// Checks every angle is finite and within ±360° and the translation finite; errors
    /// located by `loc` at the joint's key.
    fn validate(&self, loc: &Locator) -> Result<(), SceneError> {
        let named = std::iter::once(("pelvis", self.pelvis)).chain(JOINTS.iter().map(|&j| (j.name(), self.angles(j))));
        for (name, a) in named {
            for (what, v) in [("flexion", a.flexion), ("abduction", a.abduction), ("rotation", a.rotation)] {
                if !(v.is_finite() && v.abs() <= 360.0) {
                    return Err(loc.at(None, Some(name), format!("{name}.{what}"), format!("an angle in degrees within ±360 is expected, found {v}")));
                }
            }
        }
        let t = self.translation;
        if !(t.0.is_finite() && t.1.is_finite() && t.2.is_finite() && t.0.abs().max(t.1.abs()).max(t.2.abs()) <= 100.0) {
            return Err(loc.at(None, Some("translation"), "translation", "finite metres within ±100 m are expected"));
        }
        Ok(())
    }
}

/// The rotation of joint angles `a` about axes `axes` (flexion, abduction, rotation):
/// R = R(flexion) · R(abduction) · R(rotation), i.e. first the rotation about the long axis,
/// then abduction, then flexion, all about axes fixed in the parent segment.
pub fn joint_rotation(axes: &[Vector3<f64>; 3], a: &JointAngles) -> UnitQuaternion<f64> {
    let r = |axis: &Vector3<f64>, deg: f64| UnitQuaternion::from_scaled_axis(axis * deg.to_radians());
    r(&axes[0], a.flexion) * r(&axes[1], a.abduction) * r(&axes[2], a.rotation)
}

/// Rigid motion `x ↦ R (x − c) + c`.
fn about(c: &Point3<f64>, rot: UnitQuaternion<f64>) -> Isometry3<f64> {
    Translation3::from(c.coords) * Isometry3::from_parts(Translation3::identity(), rot) * Translation3::from(-c.coords)
}

/// Forward kinematics: the rigid motion of every segment (indexed like [`SEGMENTS`]) from
/// the rest pose to `pose`, before the floor contact. The pelvis moves by its translation
/// and orientation about its origin; each child by its parent's motion composed with its
/// joint's rotation about the joint's rest centre: T_child = T_parent · (c ↦ R_j (x − c) + c),
/// so the joint centre seen from either segment is the same point.
pub fn rest_to_pose(sk: &Skeleton, pose: &Pose) -> Vec<Isometry3<f64>> {
    let mut t = vec![Isometry3::identity(); SEGMENTS.len()];
    let tr = Translation3::new(pose.translation.0, pose.translation.1, pose.translation.2);
    t[0] = tr * about(&sk.pelvis_origin, joint_rotation(&Joint::Lumbar.axes(), &pose.pelvis));
    for j in JOINTS {
        let (parent, child) = j.segments();
        t[child.index()] = t[parent.index()] * about(&sk.centre(j), joint_rotation(&j.axes(), &pose.angles(j)));
    }
    t
}

/// A motion: poses at times, interpolated linearly (angles and translation) between them.
#[derive(Clone, Debug)]
pub struct Motion {
    /// (time in s, name, pose), times strictly increasing.
    pub frames: Vec<(f64, String, Pose)>,
}

impl Motion {
    /// The pose at time `t`: the first pose before the first time, the last after the last.
    pub fn pose_at(&self, t: f64) -> Pose {
        let f = &self.frames;
        match f.iter().position(|(ti, ..)| *ti > t) {
            Some(0) => f[0].2.clone(),
            Some(i) => {
                let (t0, _, p0) = &f[i - 1];
                let (t1, _, p1) = &f[i];
                Pose::lerp(p0, p1, (t - t0) / (t1 - t0))
            }
            None => f.last().map(|x| x.2.clone()).unwrap_or_default(),
        }
    }
}

/// A motion file as written: frames naming pose files.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
#[serde(rename = "Motion")]
struct MotionSpec {
    frames: Vec<FrameSpec>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct FrameSpec {
    /// Time (s).
    time: f64,
    /// Pose file, relative to the motion file.
    pose: String,
}

/// Parses pose text (RON); `file` names it in errors.
pub fn parse_pose(file: &str, text: &str) -> Result<Pose, SceneError> {
    let text = crate::input::strip_bom(text);
    let loc = Locator::new(file, text);
    let pose: Pose = ron::Options::default().from_str(text).map_err(|e| loc.from_ron(&e))?;
    pose.validate(&loc)?;
    Ok(pose)
}

/// Reads a small text file, as an error naming it when it cannot be read or is not UTF-8.
pub(super) fn read_text(path: &Path) -> Result<String, SceneError> {
    let file = path.display().to_string();
    let err = |message: String| SceneError { file: file.clone(), line: 0, column: 0, field: "file".into(), message };
    let len = std::fs::metadata(path).map_err(|e| err(format!("cannot read: {e}")))?.len();
    if len > crate::input::MAX_SCENE_BYTES {
        return Err(err(format!("{len} bytes is larger than the {} bytes read", crate::input::MAX_SCENE_BYTES)));
    }
    let bytes = std::fs::read(path).map_err(|e| err(format!("cannot read: {e}")))?;
    crate::input::decode(&file, bytes)
}

/// Reads a pose file.
pub fn load_pose(path: &Path) -> Result<Pose, SceneError> {
    parse_pose(&path.display().to_string(), &read_text(path)?)
}

/// Parses motion text; its pose files are read relative to `base` (the motion file's
/// directory). Errors in a pose file name that file; errors of the motion name `file`.
pub fn parse_motion(file: &str, text: &str, base: &Path) -> Result<Motion, SceneError> {
    let text = crate::input::strip_bom(text);
    let loc = Locator::new(file, text);
    let spec: MotionSpec = ron::Options::default().from_str(text).map_err(|e| loc.from_ron(&e))?;
    if spec.frames.is_empty() {
        return Err(loc.at(None, Some("frames"), "frames", "at least one frame (time, pose) is expected"));
    }
    let mut frames: Vec<(f64, String, Pose)> = Vec::with_capacity(spec.frames.len());
    for (k, f) in spec.frames.iter().enumerate() {
        let field = format!("frames[{k}].time");
        if !f.time.is_finite() {
            return Err(loc.at(Some(&f.pose), Some("time"), field, format!("a finite time in seconds is expected, found {}", f.time)));
        }
        if let Some((prev, ..)) = frames.last() {
            if f.time <= *prev {
                return Err(loc.at(Some(&f.pose), Some("time"), field, format!("times must increase: {} follows {prev}", f.time)));
            }
        }
        let path: PathBuf = base.join(&f.pose);
        let pose = load_pose(&path).map_err(|e| if e.line == 0 && e.field == "file" { loc.at_name(&f.pose, format!("frames[{k}].pose"), format!("{}: {}", path.display(), e.message)) } else { e })?;
        let name = Path::new(&f.pose).file_stem().map_or_else(|| format!("frame{k}"), |s| s.to_string_lossy().into_owned());
        frames.push((f.time, name, pose));
    }
    Ok(Motion { frames })
}

/// Reads a motion file and its pose files.
pub fn load_motion(path: &Path) -> Result<Motion, SceneError> {
    let base = path.parent().unwrap_or(Path::new("."));
    parse_motion(&path.display().to_string(), &read_text(path)?, base)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pose_text_and_errors() {
        let p = parse_pose("p.ron", "(shoulder_l: (flexion: 90), knee_r: (flexion: 45.5))").expect("valid");
        assert_eq!(p.shoulder_l.flexion, 90.0);
        assert_eq!(p.knee_r.flexion, 45.5);
        assert!(p.on_floor);
        let e = parse_pose("p.ron", "(\n  shoulder_x: (flexion: 90),\n)").expect_err("unknown joint");
        assert_eq!(e.line, 2, "{e}");
        let e = parse_pose("p.ron", "(\n  elbow_l: (flexion: 1e9),\n)").expect_err("too large");
        assert_eq!((e.line, e.field.as_str()), (2, "elbow_l.flexion"), "{e}");
    }

    #[test]
    fn interpolation_is_linear_and_clamped() {
        let a = Pose::default();
        let mut b = Pose::default();
        b.hip_l.flexion = 100.0;
        b.translation.2 = -0.2;
        let m = Motion { frames: vec![(1.0, "a".into(), a), (3.0, "b".into(), b)] };
        assert_eq!(m.pose_at(2.5).hip_l.flexion, 75.0);
        assert!((m.pose_at(2.5).translation.2 + 0.15).abs() < 1e-15);
        assert_eq!(m.pose_at(0.0).hip_l.flexion, 0.0);
        assert_eq!(m.pose_at(9.0).hip_l.flexion, 100.0);
    }
}
