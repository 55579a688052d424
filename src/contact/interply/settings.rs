//! Settings of inter-ply contact: the controls of the node-to-surface penalty law, the
//! formulation chosen in a garment scene (penalty or barrier) and the setup of a garment's
//! ply pairs.

use serde::Serialize;

/// Inter-ply contact controls.
#[derive(Clone, Debug)]
pub struct InterplySettings {
    /// Penalty factor c in k_n = c·min(A_s, A_m)·a/ℓ².
    pub penalty_factor: f64,
    /// Explicit nodal normal penalty (N/m), overriding the automatic choice.
    pub penalty: Option<f64>,
    /// Coulomb friction coefficient between plies.
    pub friction: f64,
    /// Tangential penalty as a fraction of the normal one.
    pub tangential_factor: f64,
}

impl Default for InterplySettings {
    /// Penalty factor 1, friction 0.3 (a representative fabric-on-fabric coefficient: woven
    /// fabrics on each other measure about 0.2–0.5, e.g. Ajayi 1992, *Textile Res. J.* 62),
    /// tangential penalty equal to the normal one.
    fn default() -> Self {
        Self { penalty_factor: 1.0, penalty: None, friction: 0.3, tangential_factor: 1.0 }
    }
}

/// Which plies touch: pairs of adjacent plies (model part indices) and the controls.
#[derive(Clone, Debug)]
pub struct InterplySetup {
    /// Adjacent plies (part a, part b); each ply's nodes meet the other's surface.
    pub ply_pairs: Vec<(usize, usize)>,
    /// Penalty and friction controls.
    pub settings: InterplySettings,
    /// Barrier contact between all the garment's surfaces instead of the node-to-surface
    /// penalty (`contact::ipc`).
    pub barrier: Option<crate::contact::ipc::SurfaceSetup>,
}

/// How plies (and panels) touch each other.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub enum InterplyFormulation {
    /// Node-to-surface penalty between adjacent plies of a panel (this module).
    Penalty,
    /// Barrier potentials over point–triangle and edge–edge pairs of every ply of every
    /// panel (`contact::ipc`): intersection-free, smooth, with self-contact.
    Barrier {
        /// Barrier thickness d̂ as a fraction of the contact distance (default 0.2).
        #[serde(default = "default_distance_factor")]
        distance_factor: f64,
        /// Factor on the automatic barrier stiffness (default 1).
        #[serde(default = "one")]
        stiffness_factor: f64,
        /// Friction stick regularisation δ as a multiple of d̂ (default 1).
        #[serde(default = "one")]
        friction_slip: f64,
        /// Whether each ply also contacts itself (default true).
        #[serde(default = "yes")]
        self_contact: bool,
        /// Largest compression of the thickness, as a fraction of the thinner ply's, before
        /// the barrier stiffens (default 0.05).
        #[serde(default = "default_compression")]
        compression_tolerance: f64,
    },
}

fn default_distance_factor() -> f64 {
    crate::contact::ipc::SurfaceSettings::default().distance_factor
}
fn default_compression() -> f64 {
    crate::contact::ipc::SurfaceSettings::default().compression_tolerance
}
fn one() -> f64 {
    1.0
}
fn yes() -> bool {
    true
}

impl Default for InterplyFormulation {
    /// The barrier with its default controls: d̂ from the plies' thicknesses and κ from the
    /// nodes' weights or membrane stiffness (`contact::ipc::surface`).
    fn default() -> Self {
        let s = crate::contact::ipc::SurfaceSettings::default();
        Self::Barrier {
            distance_factor: s.distance_factor,
            stiffness_factor: s.stiffness_factor,
            friction_slip: s.friction_slip,
            self_contact: s.self_contact,
            compression_tolerance: s.compression_tolerance,
        }
    }
}

/// Inter-ply contact settings of a garment (`garment.interply` in a scene file).
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct InterplySpec {
    /// Contact between the plies, the panels and each ply with itself (default on, with the
    /// `Barrier` formulation). The `Penalty` formulation (an explicit opt-in) does not
    /// converge on the hanging NBC sleeve: a liner node inside the faceted carbon cylinder
    /// projects into two neighbouring facets at nearly equal distance, its closest facet — and
    /// with it the force direction — switches by the 19° between their normals, and Newton
    /// 2-cycles. The `Barrier` formulation has no closest facet (a smooth sum over all
    /// point–triangle and edge–edge pairs) and solves it (`garments/nbc_sleeve.ron`).
    pub enabled: bool,
    /// Barrier (default) or penalty formulation.
    pub formulation: InterplyFormulation,
    /// Penalty factor c in k_n = c·min(A_s, A_m)·a/ℓ² (default 1).
    pub penalty_factor: f64,
    /// Explicit nodal normal penalty (N/m), overriding the automatic choice.
    pub penalty: Option<f64>,
    /// Coulomb friction coefficient between plies (default 0.3, see [`InterplySettings`]).
    pub friction: f64,
    /// Tangential penalty as a fraction of the normal one (default 1).
    pub tangential_factor: f64,
}

impl Default for InterplySpec {
    fn default() -> Self {
        let s = InterplySettings::default();
        Self { enabled: true, formulation: InterplyFormulation::default(), penalty_factor: s.penalty_factor, penalty: s.penalty, friction: s.friction, tangential_factor: s.tangential_factor }
    }
}
