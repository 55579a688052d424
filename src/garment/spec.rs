//! The garment section of a scene file (RON): panels, plies, seams and stitch lines, all
//! referred to by name.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::SeamKind;
pub use super::sizing::{AutoSize, ElementSize};

/// A garment: panels cut from plies and joined by seams.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GarmentSpec {
    /// Target element size of the panel meshes: a number (m) or `Auto((tolerance: ..))`,
    /// the size from the fabric's bending length, wrinkle wavelength, the body's curvature
    /// and the seams (`garment::sizing`).
    pub element_size: ElementSize,
    /// Largest relative difference in length allowed between the two spans of a seam.
    #[serde(default = "two_percent")]
    pub span_tolerance: f64,
    /// Plies by name: material and thickness.
    pub plies: BTreeMap<String, PlySpec>,
    /// Pattern pieces.
    pub panels: Vec<PanelSpec>,
    /// Seams joining panel edge spans.
    #[serde(default)]
    pub seams: Vec<GarmentSeamSpec>,
    /// Quilting lines joining a panel's plies through the thickness.
    #[serde(default)]
    pub stitch_lines: Vec<StitchLineSpec>,
    /// Contact between adjacent plies of multi-ply panels (on by default).
    #[serde(default)]
    pub interply: crate::contact::interply::InterplySpec,
    /// A pattern file whose pieces give the outline, notched edge spans and grain of every
    /// panel written without an `outline` (matched by piece name).
    #[serde(default)]
    pub pattern: Option<PatternSource>,
    /// Element formulation of every ply (default MITC4; `Mitc4PlusCentre` (or the paper's
    /// `Mitc4Plus`) for assumed membrane strains on curved, distorted panel meshes, `Sri`).
    #[serde(default)]
    pub shear: crate::element::ShearTreatment,
    /// How the plies of multi-ply panels are modelled unless a panel says otherwise
    /// (default `Discrete`: one shell per ply).
    #[serde(default)]
    pub ply_model: PlyModel,
}

/// Ply fidelity of a multi-ply panel (see `garment::laminate`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum PlyModel {
    /// One shell per ply, offset through the stack, joined by seams and stitch lines (and
    /// inter-ply contact when enabled).
    #[default]
    Discrete,
    /// One shell per panel whose section stacks the bonded plies (classical lamination
    /// theory); no stitch lines or inter-ply contact within it.
    Laminate,
    /// Laminate where the plies move as one, discrete plies where they would slide or
    /// separate: a laminated first solve, then per panel (and sewn group) the slip and peel
    /// criterion of `garment::ply_auto` and, if any panel changes, a second solve
    /// (`analysis_auto`).
    Auto,
}

/// A pattern file (see `crate::pattern`).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum PatternSource {
    /// DXF in the AAMA / ASTM D6673 layer convention; `file` relative to the scene file.
    Dxf {
        file: String,
        /// Size to take from a graded file.
        #[serde(default)]
        size: Option<String>,
        /// Drawing units, overriding the header's `$INSUNITS` (required when it is unitless).
        #[serde(default)]
        units: Option<LengthUnit>,
    },
}

/// A unit of length of pattern files.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum LengthUnit {
    /// Millimetre.
    Mm,
    /// Centimetre.
    Cm,
    /// Metre.
    M,
    /// Inch (25.4 mm).
    In,
}

impl LengthUnit {
    /// Metres per unit.
    pub fn metres(self) -> f64 {
        match self {
            LengthUnit::Mm => 1e-3,
            LengthUnit::Cm => 1e-2,
            LengthUnit::M => 1.0,
            LengthUnit::In => 0.0254,
        }
    }
}

impl GarmentSpec {
    /// Ply names in stack order, innermost first: each panel's stack (listed outermost
    /// first) read from the inside out and merged, so that a ply lies after every ply that
    /// is inside it in some panel (a ply first met in a later panel goes just after the ply
    /// below it there, or first if it is innermost); plies used by no panel follow by name.
    pub fn plies_in_stack_order(&self) -> Vec<String> {
        let mut order: Vec<String> = Vec::new();
        for p in &self.panels {
            let mut below: Option<usize> = None;
            for name in p.plies.iter().rev() {
                below = Some(match order.iter().position(|o| o == name) {
                    Some(i) => i,
                    None => {
                        let at = below.map_or(0, |b| b + 1);
                        order.insert(at, name.clone());
                        at
                    }
                });
            }
        }
        let unused: Vec<String> = self.plies.keys().filter(|k| !order.contains(k)).cloned().collect();
        order.extend(unused);
        order
    }
}

impl GarmentSpec {
    /// The garment's fixed element size, or for `Auto` (resolved into per-panel size fields
    /// by `garment::sizing` before meshing) NaN.
    pub fn nominal_size(&self) -> f64 {
        self.element_size.fixed().unwrap_or(f64::NAN)
    }

    /// Whether `panel` is one laminated shell: `Laminate` by its own or the garment's
    /// `ply_model`, and more than one ply (a single ply is the same either way).
    pub fn is_laminate(&self, panel: &PanelSpec) -> bool {
        panel.plies.len() > 1 && panel.ply_model.unwrap_or(self.ply_model) == PlyModel::Laminate
    }
}

fn two_percent() -> f64 {
    0.02
}

/// One ply: a fabric layer.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlySpec {
    /// Material name (a key of the scene's `materials`).
    pub material: String,
    /// Thickness (m).
    pub thickness: f64,
    /// Mass per area (kg/m²) for dynamic steps; 0: that of a Gravity load on the part.
    #[serde(default)]
    pub areal_density: f64,
}

/// A named edge span of a panel outline: from outline vertex `from` counter-clockwise to
/// vertex `to` (0-based vertex numbers of `outline`).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EdgeSpan {
    /// First vertex.
    pub from: usize,
    /// Last vertex (counter-clockwise from `from`).
    pub to: usize,
}

/// Initial 3D placement of a flat pattern piece (pattern coordinates (u, v)).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Placement {
    /// (u, v) → origin + u e_u + v e_v with e_u, e_v from a rotation vector (degrees).
    Rigid {
        #[serde(default)]
        translation: [f64; 3],
        #[serde(default)]
        rotation_deg: [f64; 3],
    },
    /// Rolled onto a cylinder: u wraps round the circumference (θ = θ₀ + u/R), v runs along
    /// the axis; the director points outwards.
    Cylinder {
        origin: [f64; 3],
        axis: [f64; 3],
        radius: f64,
        #[serde(default)]
        start_angle_deg: f64,
    },
    /// Rolled onto a cone (isometric development): a pattern point at distance ρ from
    /// `pattern_apex` and angle φ lies on the cone at slant distance ρ and azimuth
    /// φ / sin(half angle); the director points outwards.
    Cone {
        apex: [f64; 3],
        axis: [f64; 3],
        half_angle_deg: f64,
        pattern_apex: [f64; 2],
    },
    /// At a named arrangement point round a mannequin contact body (`garment::arrange`):
    /// the panel is wrapped on the point's template — a circular cylinder round a limb, an
    /// elliptic shell round the trunk, neck or head — at `clearance` outside the segment's
    /// surface, with the pattern point `anchor` on the point (`along` metres up the segment
    /// axis from the segment's proximal joint). Resolved to `EllipticCylinder` before
    /// meshing, from the body's measurements and pose.
    Around {
        /// Name of a contact body whose shape is a `Mannequin`.
        body: String,
        /// Arrangement point `SEGMENT.SIDE`, e.g. `torso.front`, `thigh_l.outer`, `head.left`
        /// (sides: front, back, left, right, outer, inner).
        point: String,
        /// Distance kept from the segment's surface (m).
        clearance: f64,
        /// Pattern point placed on the arrangement point.
        #[serde(default)]
        anchor: [f64; 2],
        /// Axial position of the anchor, up the segment axis from its proximal joint (m).
        #[serde(default)]
        along: f64,
        /// Extra turn of the anchor about the segment axis (degrees, counter-clockwise seen
        /// from the axis tip).
        #[serde(default)]
        turn_deg: f64,
    },
    /// Rolled isometrically onto an elliptic cylinder about `axis` through `origin`, with
    /// semi-axes (a, b) along `side` and axis × side: the pattern point `anchor` lies at
    /// origin + a·side; u runs counter-clockwise round the axis by arc length, v along the
    /// axis; the director points outwards.
    EllipticCylinder {
        origin: [f64; 3],
        axis: [f64; 3],
        side: [f64; 3],
        semi_axes: [f64; 2],
        #[serde(default)]
        anchor: [f64; 2],
    },
}

impl Default for Placement {
    fn default() -> Self {
        Placement::Rigid { translation: [0.0; 3], rotation_deg: [0.0; 3] }
    }
}

/// A pattern piece.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PanelSpec {
    /// Panel name.
    pub name: String,
    /// Closed outline in pattern coordinates (m), counter-clockwise, last vertex ≠ first.
    /// Empty: the piece of the same name from the garment's `pattern` file.
    #[serde(default)]
    pub outline: Vec<[f64; 2]>,
    /// Named edge spans of the outline.
    #[serde(default)]
    pub edges: BTreeMap<String, EdgeSpan>,
    /// Grain (warp) direction in pattern coordinates.
    #[serde(default = "warp_along_v")]
    pub grain: [f64; 2],
    /// Curved edges: a named edge spanning one outline segment becomes a circular arc.
    #[serde(default)]
    pub curves: Vec<CurveSpec>,
    /// Ply stack, outermost first (names of `plies`).
    pub plies: Vec<String>,
    /// Initial placement in 3D.
    #[serde(default)]
    pub placement: Placement,
    /// Ply fidelity of this panel (None: the garment's `ply_model`).
    #[serde(default)]
    pub ply_model: Option<PlyModel>,
    /// Element size of this panel (None: the garment's `element_size`).
    #[serde(default)]
    pub element_size: Option<ElementSize>,
}

fn warp_along_v() -> [f64; 2] {
    [0.0, 1.0]
}

/// A curved edge: the named single-segment edge is a circular arc through its end vertices
/// whose mid-point lies `sagitta` from the chord (positive: bulging outwards), sampled at the
/// element size.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CurveSpec {
    /// Edge name (one outline segment).
    pub edge: String,
    /// Arc height over the chord (|sagitta| < half the chord).
    pub sagitta: f64,
}

/// One side of a seam.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpanRef {
    /// Panel name.
    pub panel: String,
    /// Edge span name on that panel.
    pub edge: String,
    /// Run the span from `to` back to `from` (so both sides run the same way).
    #[serde(default)]
    pub reversed: bool,
}

/// A seam joining two spans.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GarmentSeamSpec {
    /// Seam name.
    pub name: String,
    /// Master side.
    pub a: SpanRef,
    /// Slave side.
    pub b: SpanRef,
    /// Plain, Welded or Taped.
    pub kind: SeamKind,
    /// Seam allowance width (m), for the record and the tape width.
    #[serde(default)]
    pub allowance: f64,
    /// Stitch spacing (m), for the record.
    #[serde(default)]
    pub stitch_spacing: f64,
    /// A `Closure` load pattern that sews the seam (drives the gap to zero).
    #[serde(default)]
    pub closing: Option<String>,
    /// Stitch stiffness per length (N/m per metre of seam = N/m²): a compliant seam of
    /// springs instead of rigid translation ties (`garment::compliant`).
    #[serde(default)]
    pub stiffness: Option<f64>,
    /// Seam strength (N per metre of seam, as from a seam strength test): utilisation =
    /// force per length / strength in the results.
    #[serde(default)]
    pub strength: Option<f64>,
}

/// A quilting line: the plies of `panel` are tied through the thickness along it.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StitchLineSpec {
    /// Name.
    pub name: String,
    /// Panel name.
    pub panel: String,
    /// Polyline in pattern coordinates.
    pub points: Vec<[f64; 2]>,
}

/// A seam between two ordered node sets (e.g. `Edge` selectors), running the same way.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SeamSpec {
    /// Seam name.
    pub name: String,
    /// Master node row (a node set).
    pub master: String,
    /// Slave node row (a node set); make the finer row the slave.
    pub slave: String,
    /// Plain (hinge), Welded or Taped.
    pub kind: crate::garment::SeamKind,
    /// A `Closure` load pattern whose scale drives the initial gap between the rows to zero
    /// (virtual sewing); without it the initial gap is kept.
    #[serde(default)]
    pub closing: Option<String>,
    /// Stitch stiffness per length (N/m per metre of seam = N/m²): a compliant seam of
    /// springs instead of rigid translation ties (`garment::compliant`).
    #[serde(default)]
    pub stiffness: Option<f64>,
    /// Seam strength (N per metre of seam, as from a seam strength test): utilisation =
    /// force per length / strength in the results.
    #[serde(default)]
    pub strength: Option<f64>,
}
