//! Contact as the scene file states it: the rigid bodies (shape, placement, friction,
//! prescribed motion), the body-contact formulation and its controls, and the Cusick drape
//! measures. `scene` re-exports these types; `contact::setup` resolves them.

use serde::{Deserialize, Serialize};

/// Rigid bodies the shell parts touch, and the contact controls.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// The rigid bodies.
    pub bodies: Vec<BodySpec>,
    /// Parts whose nodes take part (default: all).
    #[serde(default)]
    pub parts: Vec<String>,
    /// Factor c of the automatic nodal penalty k = c·A·a/ℓ² (A membrane stiffness).
    #[serde(default = "one")]
    pub penalty_factor: f64,
    /// Explicit nodal normal penalty (N/m), overriding the automatic one.
    #[serde(default)]
    pub penalty: Option<f64>,
    /// Tangential (stick) penalty as a fraction of the normal one.
    #[serde(default = "one")]
    pub tangential_factor: f64,
    /// Viscous pseudo-time stabilization coefficient c (N/m³): force c·a·(u − u_prev).
    #[serde(default)]
    pub stabilization: Option<f64>,
    /// Normal contact formulation.
    #[serde(default)]
    pub formulation: ContactFormulation,
}

/// How normal contact with the bodies is enforced.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub enum ContactFormulation {
    /// Penalty with one Uzawa update per converged increment (`contact::mechanics`).
    #[default]
    AugmentedLagrangian,
    /// Smooth log barrier with continuous collision detection (`contact::barrier`):
    /// intersection-free at every iterate.
    Barrier {
        /// Barrier thickness d̂ as a multiple of the shell thickness.
        #[serde(default = "one")]
        distance_factor: f64,
        /// Factor on the automatic barrier stiffness.
        #[serde(default = "one")]
        stiffness_factor: f64,
        /// Friction stick regularisation δ as a multiple of d̂.
        #[serde(default = "one")]
        friction_slip: f64,
    },
}

fn one() -> f64 {
    1.0
}

/// A rigid body: shape in its local frame, placed by a rotation then a translation.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// Body name.
    pub name: String,
    /// Geometry (local frame).
    pub shape: ShapeSpec,
    /// Translation of the local origin.
    #[serde(default)]
    pub translation: [f64; 3],
    /// Rotation vector (axis × angle in degrees) applied before the translation.
    #[serde(default)]
    pub rotation: [f64; 3],
    /// Static Coulomb friction coefficient.
    #[serde(default)]
    pub friction: f64,
    /// Kinetic coefficient (default: equal to `friction`).
    #[serde(default)]
    pub kinetic_friction: Option<f64>,
    /// Edge rounding radius of a box or cylinder (its outer dimensions are kept).
    #[serde(default)]
    pub rounding: f64,
    /// Prescribed rigid motion (barrier contact only): keyframes in increasing time; the
    /// body's placement at time t is the interpolated keyframe motion applied after the
    /// placement above (`contact::motion`). Empty: the body stands still.
    #[serde(default)]
    pub motion: Vec<KeyframeSpec>,
}

/// One keyframe of a body's prescribed motion: at `time` the body is rotated by `rotation`
/// (rotation vector, axis × angle in degrees, about the global origin) and then translated
/// by `translation` from its placement given by the body's `translation` and `rotation`.
/// Between keyframes translation is interpolated linearly and rotation spherically (slerp);
/// before the first and after the last keyframe the body holds that keyframe's placement.
/// Time is the analysis clock (`contact::motion`): physical time in `Dynamic` steps, the
/// step's load fraction (one unit per step) in static steps.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeyframeSpec {
    /// Analysis time of the keyframe.
    pub time: f64,
    /// Translation (m) after the rotation.
    #[serde(default)]
    pub translation: [f64; 3],
    /// Rotation vector (axis × angle in degrees) about the global origin.
    #[serde(default)]
    pub rotation: [f64; 3],
}

/// Rigid-body shapes. Cylinder and capsule axes are the local z axis; the plane is z = 0
/// with its outward side +z.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum ShapeSpec {
    Plane,
    Sphere { radius: f64 },
    Box { half_extents: [f64; 3] },
    Cylinder { radius: f64, height: f64 },
    Capsule { radius: f64, height: f64 },
    /// Triangle mesh from OBJ or STL (ASCII or binary), path relative to the scene file.
    TriMesh { path: String, #[serde(default = "one")] scale: f64 },
    /// The parametric mannequin (`src/mannequin/`): one triangle-mesh body per segment, named
    /// `BODY.SEGMENT` (e.g. `body.torso`), placed by the pose (default: all joint angles zero,
    /// standing on z = 0) and then by this body's translation and rotation. Paths relative to
    /// the scene file.
    Mannequin {
        /// Measurements file (RON, ISO 8559-1 names).
        measurements: String,
        /// Pose file (RON, joint angles in degrees).
        #[serde(default)]
        pose: Option<String>,
        /// Motion file (RON: pose files at times, `garments/body/motion.ron`): each segment
        /// then moves with its own forward kinematics on the analysis clock
        /// (`contact::motion`), starting from the first frame's pose (`pose` is then unused).
        #[serde(default)]
        motion: Option<String>,
    },
}

/// Drape measures: the Cusick drape coefficient and fold count about a vertical axis
/// through `center`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DrapeSpec {
    /// Centre of the support disc (its axis is vertical, z).
    pub center: [f64; 3],
    /// Support disc radius.
    pub disc_radius: f64,
    /// Undeformed specimen radius.
    pub specimen_radius: f64,
    /// Raster cell size for the shadow area (default specimen_radius/1000).
    #[serde(default)]
    pub resolution: Option<f64>,
}
