//! A parametric, posable mannequin: body measurements (ISO 8559-1 names) → a joint skeleton
//! and one closed, outward triangle surface per rigid segment (head, neck, torso, pelvis,
//! upper arms, forearms, hands, thighs, shanks, feet); a pose (joint angles) → one rigid
//! placement per segment by forward kinematics; a motion → poses interpolated in time.
//!
//! Each segment's surface is stored in its own local frame: origin at the segment's proximal
//! joint centre (the pelvis: midway between the hip joints), axes parallel to the world axes
//! in the rest pose. A pose places it by an isometry (local → world), so a moving contact
//! body is the fixed local mesh and one isometry per time.
//!
//! Data flow: measurements → [`skeleton`] → [`segments`] (rest surfaces) → [`Mannequin`];
//! poses and motions ([`pose`]) → placements; the OBJ export is in [`obj`].

pub mod measurements;
pub mod obj;
pub mod pose;
pub mod segments;
pub mod skeleton;
pub mod surface;

use nalgebra::{Isometry3, Point3, Translation3, Vector3};

pub use measurements::{parse_measurements, Measurements, Resolved};
pub use pose::{load_motion, load_pose, parse_pose, JointAngles, Motion, Pose};
pub use segments::Girth;
pub use skeleton::{Joint, Segment, Skeleton, JOINTS, SEGMENTS};
pub use surface::TriSurface;

use crate::input::SceneError;

/// One rigid segment: its surface in its local frame and where that frame sits at rest.
#[derive(Clone, Debug)]
pub struct SegmentBody {
    /// Which segment.
    pub segment: Segment,
    /// Rest placement of the local frame (a translation to the proximal joint centre).
    pub rest: Isometry3<f64>,
    /// Closed, outward surface in the local frame.
    pub surface: TriSurface,
    /// Unit loft axis (local frame = rest world directions).
    pub axis: Vector3<f64>,
    /// Ring centres (and apexes) with their axial positions `x · axis` (local frame), in
    /// axial order.
    pub centre_line: Vec<(f64, Point3<f64>)>,
    /// Measurement rings of this segment (local frame).
    pub girths: Vec<Girth>,
}

/// The mannequin: skeleton and segment bodies (indexed like [`SEGMENTS`]).
#[derive(Clone, Debug)]
pub struct Mannequin {
    /// Rest skeleton (joint centres, landmark heights, measurements).
    pub skeleton: Skeleton,
    /// The segments in [`SEGMENTS`] order.
    pub segments: Vec<SegmentBody>,
}

impl Mannequin {
    /// Generates the mannequin of measurements `m`.
    pub fn new(m: &Resolved) -> Self {
        let skeleton = Skeleton::new(m);
        let segments = segments::build_segments(&skeleton)
            .into_iter()
            .map(|s| {
                let o = skeleton.origin(s.segment).coords;
                let mut surface = s.surface;
                for v in &mut surface.vertices {
                    *v -= o;
                }
                SegmentBody {
                    segment: s.segment,
                    rest: Isometry3::from(Translation3::from(o)),
                    surface,
                    axis: s.axis,
                    centre_line: s.centre_line.into_iter().map(|(_, c)| ((c - o).coords.dot(&s.axis), c - o)).collect(),
                    girths: s.girths.into_iter().map(|g| Girth { point: g.point - o, ..g }).collect(),
                }
            })
            .collect();
        Self { skeleton, segments }
    }

    /// The mannequin of the default size ([`Measurements::default_size`]).
    pub fn default_size() -> Self {
        Self::new(&Measurements::default_size().fill())
    }

    /// The placement (local → world) of every segment in `pose`: forward kinematics
    /// ([`pose::rest_to_pose`]) composed with the rest placement, then, when the pose is
    /// `on_floor`, a vertical shift putting the lowest vertex of the body on z = 0.
    pub fn placements(&self, pose: &Pose) -> Vec<Isometry3<f64>> {
        let t = pose::rest_to_pose(&self.skeleton, pose);
        let mut p: Vec<Isometry3<f64>> = t.iter().zip(&self.segments).map(|(t, s)| t * s.rest).collect();
        if pose.on_floor {
            let lowest = p
                .iter()
                .zip(&self.segments)
                .flat_map(|(iso, s)| s.surface.vertices.iter().map(move |v| (iso * v).z))
                .fold(f64::INFINITY, f64::min);
            if lowest.is_finite() {
                let shift = Translation3::new(0.0, 0.0, -lowest);
                for q in &mut p {
                    *q = shift * *q;
                }
            }
        }
        p
    }

    /// Total number of triangles.
    pub fn n_triangles(&self) -> usize {
        self.segments.iter().map(|s| s.surface.triangles.len()).sum()
    }

    /// Every measurement ring: (segment, girth, measured perimeter of the surface's section
    /// by the ring's plane).
    pub fn girth_report(&self) -> Vec<(Segment, Girth, f64)> {
        self.segments
            .iter()
            .flat_map(|s| s.girths.iter().map(move |g| (s.segment, g.clone(), s.surface.section_length(&g.point, &g.normal))))
            .collect()
    }
}

/// Checks a mannequin file — measurements, pose or motion, told apart by the name of its
/// top-level RON struct — and describes it in one line; None when `path` is none of these
/// (e.g. a scene). Errors are located as by the loaders.
pub fn check_file(path: &std::path::Path) -> Option<Result<String, SceneError>> {
    let text = pose::read_text(path).ok()?;
    let kind = ron_struct_name(crate::input::strip_bom(&text))?;
    Some(match kind {
        "Measurements" => load_measurements(path).map(|m| format!("measurements: stature {} m, chest {} m, waist {} m, hip {} m", m.stature, m.chest_girth, m.waist_girth, m.hip_girth)),
        "Pose" => load_pose(path).map(|_| "pose: joint angles valid".to_string()),
        "Motion" => load_motion(path).map(|m| format!("motion: {} poses from t = {} to {} s", m.frames.len(), m.frames.first().map_or(0.0, |f| f.0), m.frames.last().map_or(0.0, |f| f.0))),
        _ => return None,
    })
}

/// The identifier that opens a RON text after whitespace and `//` or `/* */` comments.
fn ron_struct_name(text: &str) -> Option<&str> {
    let mut rest = text;
    loop {
        rest = rest.trim_start();
        if let Some(r) = rest.strip_prefix("//") {
            rest = r.split_once('\n').map_or("", |x| x.1);
        } else if let Some(r) = rest.strip_prefix("/*") {
            rest = r.split_once("*/").map_or("", |x| x.1);
        } else {
            break;
        }
    }
    let end = rest.find(|c: char| !(c.is_alphanumeric() || c == '_')).unwrap_or(rest.len());
    (end > 0).then(|| &rest[..end])
}

/// Reads a measurements file.
pub fn load_measurements(path: &std::path::Path) -> Result<Resolved, SceneError> {
    parse_measurements(&path.display().to_string(), &pose::read_text(path)?)
}
