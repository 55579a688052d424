//! The joint skeleton: rigid segments, the joints between them with their rest centres and
//! rotation axes, and the body's landmark heights, all from the measurements.
//!
//! Axes: z up, y forward (anterior), x to the body's right; the feet stand on z = 0 and the
//! body's midline is x = 0. The rest pose (all angles zero) stands upright, arms hanging
//! straight down with the palms facing the thighs, feet pointing forward.

use nalgebra::{Point3, Vector3};

use super::measurements::Resolved;

/// The rigid segments, in the order of [`SEGMENTS`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Segment {
    Pelvis,
    Torso,
    Neck,
    Head,
    UpperArmL,
    ForearmL,
    HandL,
    UpperArmR,
    ForearmR,
    HandR,
    ThighL,
    ShankL,
    FootL,
    ThighR,
    ShankR,
    FootR,
}

/// Every segment, parents before children (the pelvis is the root).
pub const SEGMENTS: [Segment; 16] = [
    Segment::Pelvis,
    Segment::Torso,
    Segment::Neck,
    Segment::Head,
    Segment::UpperArmL,
    Segment::ForearmL,
    Segment::HandL,
    Segment::UpperArmR,
    Segment::ForearmR,
    Segment::HandR,
    Segment::ThighL,
    Segment::ShankL,
    Segment::FootL,
    Segment::ThighR,
    Segment::ShankR,
    Segment::FootR,
];

impl Segment {
    /// Index in [`SEGMENTS`].
    pub fn index(self) -> usize {
        SEGMENTS.iter().position(|&s| s == self).unwrap_or(0)
    }

    /// Name as used in files and OBJ groups.
    pub fn name(self) -> &'static str {
        use Segment::*;
        match self {
            Pelvis => "pelvis",
            Torso => "torso",
            Neck => "neck",
            Head => "head",
            UpperArmL => "upper_arm_l",
            ForearmL => "forearm_l",
            HandL => "hand_l",
            UpperArmR => "upper_arm_r",
            ForearmR => "forearm_r",
            HandR => "hand_r",
            ThighL => "thigh_l",
            ShankL => "shank_l",
            FootL => "foot_l",
            ThighR => "thigh_r",
            ShankR => "shank_r",
            FootR => "foot_r",
        }
    }

    /// The joint that attaches this segment to its parent (none for the pelvis).
    pub fn joint(self) -> Option<Joint> {
        JOINTS.iter().copied().find(|j| j.child() == self)
    }
}

/// The joints, each between a parent and a child segment.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Joint {
    /// Pelvis–torso (lumbar spine, at the waist).
    Lumbar,
    /// Torso–neck (base of the neck).
    Neck,
    /// Neck–head (atlanto-occipital).
    Head,
    ShoulderL,
    ElbowL,
    WristL,
    ShoulderR,
    ElbowR,
    WristR,
    HipL,
    KneeL,
    AnkleL,
    HipR,
    KneeR,
    AnkleR,
}

/// Every joint, parents before children.
pub const JOINTS: [Joint; 15] = [
    Joint::Lumbar,
    Joint::Neck,
    Joint::Head,
    Joint::ShoulderL,
    Joint::ElbowL,
    Joint::WristL,
    Joint::ShoulderR,
    Joint::ElbowR,
    Joint::WristR,
    Joint::HipL,
    Joint::KneeL,
    Joint::AnkleL,
    Joint::HipR,
    Joint::KneeR,
    Joint::AnkleR,
];

impl Joint {
    /// Index in [`JOINTS`].
    pub fn index(self) -> usize {
        JOINTS.iter().position(|&j| j == self).unwrap_or(0)
    }

    /// Name as used in pose files.
    pub fn name(self) -> &'static str {
        use Joint::*;
        match self {
            Lumbar => "lumbar",
            Neck => "neck",
            Head => "head",
            ShoulderL => "shoulder_l",
            ElbowL => "elbow_l",
            WristL => "wrist_l",
            ShoulderR => "shoulder_r",
            ElbowR => "elbow_r",
            WristR => "wrist_r",
            HipL => "hip_l",
            KneeL => "knee_l",
            AnkleL => "ankle_l",
            HipR => "hip_r",
            KneeR => "knee_r",
            AnkleR => "ankle_r",
        }
    }

    /// (parent, child) segments.
    pub fn segments(self) -> (Segment, Segment) {
        use Joint::*;
        use Segment as S;
        match self {
            Lumbar => (S::Pelvis, S::Torso),
            Neck => (S::Torso, S::Neck),
            Head => (S::Neck, S::Head),
            ShoulderL => (S::Torso, S::UpperArmL),
            ElbowL => (S::UpperArmL, S::ForearmL),
            WristL => (S::ForearmL, S::HandL),
            ShoulderR => (S::Torso, S::UpperArmR),
            ElbowR => (S::UpperArmR, S::ForearmR),
            WristR => (S::ForearmR, S::HandR),
            HipL => (S::Pelvis, S::ThighL),
            KneeL => (S::ThighL, S::ShankL),
            AnkleL => (S::ShankL, S::FootL),
            HipR => (S::Pelvis, S::ThighR),
            KneeR => (S::ThighR, S::ShankR),
            AnkleR => (S::ShankR, S::FootR),
        }
    }

    /// The child segment.
    pub fn child(self) -> Segment {
        self.segments().1
    }

    /// Rotation axes (flexion, abduction, rotation), unit vectors in the parent's rest
    /// frame, signed so that positive angles are: flexion — limb forward/up (shoulder, elbow,
    /// wrist, hip), heel toward the buttock (knee), toes up (ankle dorsiflexion), trunk or
    /// head bent forward (lumbar, neck, head); abduction — limb away from the midline (for the
    /// trunk, neck and head: bent to the body's left; ankle: sole turned outward); rotation —
    /// internal (medial) rotation about the rest long axis (trunk, neck, head: turned to the
    /// body's left).
    pub fn axes(self) -> [Vector3<f64>; 3] {
        use Joint::*;
        let (x, y, z) = (Vector3::x(), Vector3::y(), Vector3::z());
        match self {
            Lumbar | Neck | Head => [-x, -y, z],
            ShoulderL | ElbowL | WristL | HipL => [x, y, -z],
            ShoulderR | ElbowR | WristR | HipR => [x, -y, z],
            KneeL => [-x, y, -z],
            KneeR => [-x, -y, z],
            AnkleL => [x, y, -z],
            AnkleR => [x, -y, z],
        }
    }
}

/// Landmark heights and joint centres of the rest pose (metres, world frame).
#[derive(Clone, Debug)]
pub struct Skeleton {
    /// The measurements it was built from.
    pub m: Resolved,
    /// Joint centres in the rest pose, indexed like [`JOINTS`].
    pub centres: [Point3<f64>; 15],
    /// Origin of the pelvis frame: midway between the hip joints.
    pub pelvis_origin: Point3<f64>,
    /// Heights: chest girth level.
    pub z_chest: f64,
    /// Waist girth level and lumbar joint.
    pub z_waist: f64,
    /// Hip girth level.
    pub z_hip_girth: f64,
    /// Neck girth level.
    pub z_neck_girth: f64,
    /// Head girth level.
    pub z_head_girth: f64,
    /// Chin (bottom of the head's main body).
    pub z_chin: f64,
    /// Upper-arm and forearm lengths (joint to joint).
    pub upper_arm: f64,
    pub forearm: f64,
    /// Hand length (wrist joint to fingertip).
    pub hand: f64,
    /// Foot length (heel to toe).
    pub foot: f64,
}

impl Skeleton {
    /// The rest skeleton of measurements `m` (proportions in the module doc of
    /// `measurements`): shoulder joints at 0.815 H, 0.45 × biacromial breadth from the
    /// midline; the arm length split 0.56 : 0.44 (Winter's 0.186 : 0.146) into upper arm and
    /// forearm; hip joints 0.05 H above the crotch and max(0.053 H, thigh radius + 4 mm) from
    /// the midline; knee at 0.56 of the hip joint height (Winter: 0.285 / 0.51); ankle at
    /// 0.045 H; neck base 0.835 H, head joint 0.885 H; waist (lumbar joint) 0.605 H.
    pub fn new(m: &Resolved) -> Self {
        let h = m.stature;
        let z_sh = 0.815 * h;
        let x_sh = 0.45 * m.biacromial_breadth;
        let upper_arm = 0.56 * m.arm_length;
        let forearm = m.arm_length - upper_arm;
        let z_hip = m.inseam + 0.05 * h;
        let x_hip = (0.053 * h).max(m.thigh_girth / (2.0 * std::f64::consts::PI) + 0.004);
        let z_knee = 0.56 * z_hip;
        let z_ankle = 0.045 * h;
        let z_waist = 0.605 * h;
        let mut centres = [Point3::origin(); 15];
        let mut set = |j: Joint, x: f64, z: f64| centres[j.index()] = Point3::new(x, 0.0, z);
        set(Joint::Lumbar, 0.0, z_waist);
        set(Joint::Neck, 0.0, 0.835 * h);
        set(Joint::Head, 0.0, 0.885 * h);
        for (s, sh, el, wr, hip, kn, an) in [
            (-1.0, Joint::ShoulderL, Joint::ElbowL, Joint::WristL, Joint::HipL, Joint::KneeL, Joint::AnkleL),
            (1.0, Joint::ShoulderR, Joint::ElbowR, Joint::WristR, Joint::HipR, Joint::KneeR, Joint::AnkleR),
        ] {
            set(sh, s * x_sh, z_sh);
            set(el, s * x_sh, z_sh - upper_arm);
            set(wr, s * x_sh, z_sh - m.arm_length);
            set(hip, s * x_hip, z_hip);
            set(kn, s * x_hip, z_knee);
            set(an, s * x_hip, z_ankle);
        }
        Self {
            m: *m,
            centres,
            pelvis_origin: Point3::new(0.0, 0.0, z_hip),
            z_chest: 0.72 * h,
            z_waist,
            z_hip_girth: m.inseam + 0.04 * h,
            z_neck_girth: 0.86 * h,
            z_head_girth: 0.945 * h,
            z_chin: 0.87 * h,
            upper_arm,
            forearm,
            hand: 0.108 * h,
            foot: 0.152 * h,
        }
    }

    /// Rest centre of joint `j`.
    pub fn centre(&self, j: Joint) -> Point3<f64> {
        self.centres[j.index()]
    }

    /// Rest origin of segment `s`'s frame: its proximal joint centre (the pelvis: midway
    /// between the hip joints).
    pub fn origin(&self, s: Segment) -> Point3<f64> {
        s.joint().map_or(self.pelvis_origin, |j| self.centre(j))
    }
}
