//! The scene file format (RON, deserialised with serde). What a user writes.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::element::ShearTreatment;
use crate::mesh::Spacing;
use crate::solver::{SolverSettings, StepKind};

/// A whole analysis: parts, materials, supports, loads, steps and outputs.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Scene name (used for output file names).
    pub name: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// Materials by name.
    pub materials: BTreeMap<String, MaterialSpec>,
    /// Shell parts.
    pub parts: Vec<PartSpec>,
    /// Node sets by name.
    #[serde(default)]
    pub node_sets: BTreeMap<String, Selector>,
    /// Supports.
    #[serde(default)]
    pub boundary: Vec<BoundarySpec>,
    /// Load patterns by name (scaled by the steps).
    #[serde(default)]
    pub loads: BTreeMap<String, LoadSpec>,
    /// Solution steps, in order.
    pub steps: Vec<StepSpec>,
    /// Monitored points.
    #[serde(default)]
    pub monitors: Vec<MonitorSpec>,
    /// Output controls.
    #[serde(default)]
    pub output: OutputSpec,
    /// Solver controls.
    #[serde(default)]
    pub solver: SolverSettings,
    /// Contact with rigid bodies.
    #[serde(default)]
    pub contact: Option<ContactSpec>,
    /// Drape measures to report (Cusick drape coefficient, folds, penetration).
    #[serde(default)]
    pub drape: Option<DrapeSpec>,
    /// Geometric imperfection seeded into the reference geometry before the solve.
    #[serde(default)]
    pub imperfection: Option<ImperfectionSpec>,
    /// Seams: master–slave ties between node rows of the parts.
    #[serde(default)]
    pub seams: Vec<SeamSpec>,
    /// A garment (panels, plies, seams, stitch lines) whose plies become further parts.
    #[serde(default)]
    pub garment: Option<crate::garment::GarmentSpec>,
    /// A movement protocol: after `steps` (at the motion's first pose), one step to rest at
    /// each further pose of a mannequin body's motion file (`scene::protocol`).
    #[serde(default)]
    pub protocol: Option<ProtocolSpec>,
}

/// A movement protocol (issue 17): the garment is taken through the poses of a mannequin
/// contact body's motion file, solving to rest at each. The scene's own `steps` run first,
/// with the body held in the motion's first pose (sewing, drape); then one `Dynamic` step
/// per further frame, named after its pose file, moves the body from the previous pose to
/// that one over the frames' time interval (the garment carried by contact) and goes on
/// until the garment is at rest with the body held in the pose. `summary.json` gets a
/// `poses` section with the seam, ply, strain, clearance and pressure measures at the rest
/// state of the first pose and of every pose step.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProtocolSpec {
    /// Name of the contact body: a `Mannequin` with a `motion` file.
    pub body: String,
    /// Controls of each pose step (a `Dynamic` step to rest; `duration` must stay 0).
    #[serde(default)]
    pub settle: crate::solver::DynamicSettings,
}

/// Geometric imperfections (added to the reference mid-surface and directors).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum ImperfectionSpec {
    /// Buckling modes of the perfect geometry: a linearized buckling analysis at the
    /// reference state under the load patterns scaled by `scale`; mode k (from 1) is added
    /// scaled to a largest translation of `amplitude` (a length).
    BucklingModes { scale: BTreeMap<String, f64>, modes: Vec<ModeAmplitude> },
    /// A seeded Gaussian random field along the reference directors with squared-exponential
    /// covariance of correlation length `correlation_length`, scaled to a largest
    /// displacement of `amplitude`; the directors follow the perturbed surface.
    RandomField { amplitude: f64, correlation_length: f64, #[serde(default)] seed: u64 },
}

/// One mode of a buckling-mode imperfection.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModeAmplitude {
    /// Mode number, 1 = lowest critical load.
    pub mode: usize,
    /// Largest translation of the mode's contribution.
    pub amplitude: f64,
}


pub use crate::garment::spec::SeamSpec;

pub use crate::contact::spec::{BodySpec, ContactFormulation, ContactSpec, DrapeSpec, KeyframeSpec, ShapeSpec};

/// A material model and its constants.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum MaterialSpec {
    /// Isotropic St. Venant–Kirchhoff: Young's modulus, Poisson ratio, transverse shear
    /// correction factor (default 5/6).
    StVenantKirchhoff {
        young: f64,
        poisson: f64,
        #[serde(default = "five_sixths")]
        shear_factor: f64,
    },
    /// Ciarlet compressible neo-Hookean from Young's modulus and Poisson ratio.
    NeoHookean { young: f64, poisson: f64 },
    /// Ciarlet compressible neo-Hookean from bulk modulus K and shear modulus μ.
    NeoHookeanBulkShear { bulk: f64, shear: f64 },
    /// Orthotropic fabric (warp = the part's grain), from a named preset and/or explicit
    /// sheet constants (explicit values override the preset's).
    Fabric(FabricSpec),
}

/// Sheet constants of a fabric (SI units); every field optional when `preset` is given.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FabricSpec {
    /// Preset name: light_cotton, cotton_broadcloth, polyester_faille, ripstop, knit_liner.
    pub preset: Option<String>,
    /// Warp tensile stiffness, N/m.
    pub warp_tensile: Option<f64>,
    /// Weft tensile stiffness, N/m.
    pub weft_tensile: Option<f64>,
    /// In-plane shear stiffness, N/m.
    pub shear: Option<f64>,
    /// Poisson coupling ν12.
    pub poisson: Option<f64>,
    /// Warp bending rigidity, N·m.
    pub warp_bending: Option<f64>,
    /// Weft bending rigidity, N·m.
    pub weft_bending: Option<f64>,
    /// Twisting rigidity, N·m (default ½√(B1·B2), capped at 0.15·shear·thickness²).
    pub twist_bending: Option<f64>,
    /// Transverse shear stiffness, N/m (default the larger tensile stiffness).
    pub transverse_shear: Option<f64>,
    /// Areal density, kg/m².
    pub areal_density: Option<f64>,
    /// Thickness, m (the part's thickness must equal it).
    pub thickness: Option<f64>,
    /// Tension stiffening (strain, factor) table, strains ascending from 0.
    pub tension_table: Option<Vec<(f64, f64)>>,
    /// Sub-element buckling: (compressive strain, factor) table on the membrane stiffness
    /// under compression, strains ascending from 0.
    pub compression_table: Option<Vec<(f64, f64)>>,
}

fn five_sixths() -> f64 {
    5.0 / 6.0
}

/// One shell part: a mesh with a section.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartSpec {
    /// Part name.
    pub name: String,
    /// How the mesh is made.
    pub mesh: MeshSpec,
    /// Material name (a key of `materials`).
    pub material: String,
    /// Shell thickness.
    pub thickness: f64,
    /// Transverse shear treatment (default MITC4).
    #[serde(default)]
    pub shear: ShearTreatment,
    /// Gauss points through the thickness (default 2).
    #[serde(default = "two")]
    pub thickness_points: usize,
    /// Lamina e1 direction (material grain); default the element's ξ direction.
    #[serde(default)]
    pub grain: Option<[f64; 3]>,
    /// Rigid translation applied to the generated mesh.
    #[serde(default)]
    pub offset: Option<[f64; 3]>,
    /// Mass per reference area for `Dynamic` steps; 0 (default): the areal density of a
    /// Gravity load on this part, else massless.
    #[serde(default)]
    pub areal_density: f64,
}

fn two() -> usize {
    2
}

/// Mesh generators and imports. Angles in degrees.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum MeshSpec {
    /// Plate in the xy plane, x ∈ [0, lx], y ∈ [0, ly]. Edges xmin, xmax, ymin, ymax.
    Rectangle { lx: f64, ly: f64, nx: usize, ny: usize },
    /// `Rectangle` whose grid follows from `element_size`: a number h (m) gives
    /// ⌈lx/h⌉ × ⌈ly/h⌉ elements; `Auto((tolerance: T))` the garment panels' size from the
    /// fabric's bending length, fold wavelength and the contact bodies' curvature
    /// (`scene::sizing`). Edges xmin, xmax, ymin, ymax.
    SizedRectangle { lx: f64, ly: f64, element_size: crate::sizing::ElementSize },
    /// `Rectangle` with its node lines at given coordinates: `x` from 0 to `lx` and `y` from 0
    /// to `ly`, strictly increasing (a graded grid; written by a-posteriori refinement,
    /// `crate::refine`). Edges xmin, xmax, ymin, ymax.
    GradedRectangle { lx: f64, ly: f64, x: Vec<f64>, y: Vec<f64> },
    /// Cylindrical panel about the x axis, point (x, R sin θ, R cos θ). Edges x0, x1,
    /// theta0, theta1. `spacing: Distorted` divides each edge 1:2:…:N (open panels).
    CylindricalPanel {
        radius: f64,
        length: f64,
        theta0: f64,
        theta1: f64,
        n_axial: usize,
        n_circ: usize,
        #[serde(default)]
        spacing: Spacing,
    },
    /// Spherical shell with a polar hole. Edges hole, equator, phi0, phi1. `spacing` as for
    /// the cylindrical panel.
    Hemisphere {
        radius: f64,
        hole_angle: f64,
        phi0: f64,
        phi1: f64,
        n_merid: usize,
        n_circ: usize,
        #[serde(default)]
        spacing: Spacing,
    },
    /// Flat annulus with a radial slit at θ = 0. Edges inner, outer, slit_start, slit_end.
    SlitAnnulus { ri: f64, ro: f64, nr: usize, ntheta: usize },
    /// Strip along x, cross-section twisted linearly by `twist`. Edges x0, x1, smin, smax.
    TwistedStrip { length: f64, width: f64, twist: f64, nx: usize, ny: usize },
    /// Full flat annulus about the z axis (closed in θ); `graded` radii grow geometrically
    /// for near-square elements. Edges inner, outer.
    Annulus { ri: f64, ro: f64, nr: usize, ntheta: usize, #[serde(default)] graded: bool },
    /// Full flat annulus about the z axis with rings of nodes at the listed `radii`
    /// (strictly increasing): fine where the drape bends, coarse where it is held flat.
    /// Edges inner, outer.
    AnnulusRings { radii: Vec<f64>, ntheta: usize },
    /// Full flat annulus about the z axis refined toward the circle r = `focus` (e.g. the
    /// rim of a support disc): radial steps `refine` times finer than the circumferential
    /// width at the focus, growing ≤ 25 % per ring to `inner_aspect` (default 1) times the
    /// circumferential width inside the focus and to it outside (`mesh::focused_rings`).
    /// Edges inner, outer.
    FocusedAnnulus {
        ri: f64,
        ro: f64,
        ntheta: usize,
        focus: f64,
        refine: f64,
        #[serde(default = "unit_aspect")]
        inner_aspect: f64,
    },
    /// Full flat annulus about the z axis (closed in θ) whose rings and sectors follow from
    /// `element_size`: a number h (m) gives uniform rings at most h apart and sectors at
    /// most h wide at ro; `Auto((tolerance: T))` sizes them from the fabric and the contact
    /// bodies (rings from the bending length and the support's rim, sectors from the folds
    /// of the overhang; `scene::sizing`). Edges inner, outer.
    SizedAnnulus { ri: f64, ro: f64, element_size: crate::sizing::ElementSize },
    /// Quad mesh from a Wavefront OBJ file (path relative to the scene file). Edge boundary.
    Obj { path: String },
}

fn unit_aspect() -> f64 {
    1.0
}

/// Node selectors.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Selector {
    /// Nodes inside an axis-aligned box (inclusive, small tolerance).
    Box { min: [f64; 3], max: [f64; 3], #[serde(default)] part: Option<String> },
    /// Nodes within `tol` of a plane.
    Plane { point: [f64; 3], normal: [f64; 3], #[serde(default = "plane_tol")] tol: f64, #[serde(default)] part: Option<String> },
    /// The single node nearest to a point.
    Nearest { point: [f64; 3], #[serde(default)] part: Option<String> },
    /// A named edge of a part's generated mesh, in order along the edge.
    Edge { part: String, edge: String },
    /// Every node of a part.
    Part { part: String },
}

fn plane_tol() -> f64 {
    1e-6
}

pub use crate::model::Dof;

/// Global axes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Axis {
    X,
    Y,
    Z,
}

/// Supports.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum BoundarySpec {
    /// All five DOFs fixed.
    Clamp { set: String },
    /// Translations fixed, director free.
    Pin { set: String },
    /// Chosen DOFs fixed.
    Fix { set: String, dofs: Vec<Dof> },
    /// Mirror symmetry about the plane with the given normal: normal translation and the
    /// director tilt towards the normal fixed.
    Symmetry { set: String, normal: Axis },
}

/// Load patterns at unit scale.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum LoadSpec {
    /// The same force on every node of the set.
    NodalForce { set: String, force: [f64; 3] },
    /// A total force shared equally by the nodes of the set.
    TotalForce { set: String, force: [f64; 3] },
    /// The same moment on every node of the set (about fixed global axes).
    NodalMoment { set: String, moment: [f64; 3] },
    /// A total moment shared along an edge in proportion to each node's tributary length.
    EdgeMoment { set: String, moment_per_length: [f64; 3] },
    /// A force per unit length along an edge (consistent lumping on the reference edge).
    EdgeForce { set: String, force_per_length: [f64; 3] },
    /// A dead traction per unit reference area on a part (consistent nodal loads).
    SurfaceTraction { part: String, traction: [f64; 3] },
    /// Self-weight from areal density (mass per reference area) and gravity vector.
    Gravity { part: String, areal_density: f64, g: [f64; 3] },
    /// Prescribed translation of the set's nodes.
    Displacement { set: String, dof: Dof, value: f64 },
    /// Self-weight of a part from its material's areal density (fabric) and gravity vector.
    SelfWeight { part: String, g: [f64; 3] },
    /// Self-weight of every garment part (each panel's plies, or its laminate) from its
    /// areal density (the ply's, or its material's), under gravity vector `g`: the
    /// shorthand for one `SelfWeight` per panel and ply.
    GarmentWeight { g: [f64; 3] },
    /// No force: its scale (0 → 1) closes the gaps of the seams that name it (sewing).
    Closure,
}

/// A solution step: load scales ramped linearly over its increments.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StepSpec {
    /// Step name.
    pub name: String,
    /// Nominal increments (results reported at each).
    pub increments: usize,
    /// Linear step: one Newton iteration from the current state (K u = f), no equilibrium
    /// iterations; for small-displacement reference problems.
    #[serde(default)]
    pub linear: bool,
    /// Static steps: `increments` is only the first guess; increments grow after quick
    /// convergence and shrink after slow or failed ones (divergence detected early), results
    /// at every converged increment (the default). `false`: exactly `increments` equal load
    /// levels (a curve sampled where a reference is tabulated).
    #[serde(default = "automatic_default")]
    pub automatic_increments: bool,
    /// Scale of each load pattern at the end of the step; unnamed patterns keep the value
    /// they had at the end of the previous step.
    #[serde(default)]
    pub scale: BTreeMap<String, f64>,
    /// How the step is solved: `Static` (default), `StaticDamped` (Levenberg–Marquardt
    /// shift) or `Dynamic((dt: .., ..))` (pseudo-transient; `increments` is then unused and
    /// every accepted time step is reported), `ArcLength(..)` / `DisplacementControl(..)` (path
    /// following through limit points) or `Buckling(modes: ..)` (linearized buckling).
    #[serde(default)]
    pub kind: StepKind,
    /// A-posteriori refinement after this (last) step: `Some((tolerance: T, passes: N))`
    /// (`crate::refine`).
    #[serde(default)]
    pub refine: Option<super::sequence::RefineSpec>,
}

/// A monitored point: the node nearest to `point`, with the displacement components kept.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MonitorSpec {
    /// Monitor name.
    pub name: String,
    /// Point in the reference configuration.
    pub point: [f64; 3],
    /// Restrict the search to one part.
    #[serde(default)]
    pub part: Option<String>,
    /// Restrict the search to a node set (e.g. one side of a slit).
    #[serde(default)]
    pub set: Option<String>,
    /// Displacement components recorded.
    pub dofs: Vec<MonitorDof>,
}

pub use crate::results::MonitorDof;

/// Output controls.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OutputSpec {
    /// Write a VTU every this many nominal increments (the last of each step always).
    pub every: usize,
    /// Write VTU files at all.
    pub vtu: bool,
    /// Base64 binary VTU (false: ASCII).
    pub binary: bool,
    /// Plot monitored values against this load pattern's scale (default: the first
    /// pattern scaled by the last step).
    pub plot_against: Option<String>,
}

impl Default for OutputSpec {
    fn default() -> Self {
        Self { every: 1, vtu: true, binary: true, plot_against: None }
    }
}

fn automatic_default() -> bool {
    true
}
