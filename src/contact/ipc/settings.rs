//! Controls of barrier contact between shell surfaces (`garment.interply.formulation:
//! Barrier(…)`, see `surface.rs` for the model they parameterise) and the parts it covers.

use serde::Serialize;

/// Surface contact controls.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SurfaceSettings {
    /// Barrier thickness d̂ as a fraction f of the contact distance c̄ (0 < f < 1).
    pub distance_factor: f64,
    /// Factor on the automatic barrier stiffness.
    pub stiffness_factor: f64,
    /// Coulomb friction coefficient between surfaces.
    pub friction: f64,
    /// Stick regularisation δ of the friction as a multiple of d̂.
    pub friction_slip: f64,
    /// Whether a part's surface also contacts itself (folds).
    pub self_contact: bool,
    /// Largest compression of the plies' thickness, as a fraction of the thinner ply's
    /// thickness, that a converged state may show before its nodes' κ is doubled.
    pub compression_tolerance: f64,
}

impl Default for SurfaceSettings {
    /// d̂ = 0.2 c̄, κ factor 1, friction 0.3 (woven fabrics on each other measure about
    /// 0.2–0.5, e.g. Ajayi 1992, *Textile Res. J.* 62), δ = d̂, self-contact on.
    fn default() -> Self {
        Self { distance_factor: 0.2, stiffness_factor: 1.0, friction: 0.3, friction_slip: 1.0, self_contact: true, compression_tolerance: 0.05 }
    }
}

impl SurfaceSettings {
    /// The first setting out of range: (key, what was expected).
    pub fn problem(&self) -> Option<(&'static str, &'static str)> {
        let pos = |x: f64| x.is_finite() && x > 0.0;
        if !(pos(self.distance_factor) && self.distance_factor < 1.0) {
            return Some(("distance_factor", "expected a barrier thickness factor between 0 and 1 (exclusive)"));
        }
        if !pos(self.stiffness_factor) {
            return Some(("stiffness_factor", "expected a positive stiffness factor"));
        }
        if !(self.friction.is_finite() && self.friction >= 0.0) {
            return Some(("friction", "expected a non-negative friction coefficient"));
        }
        if !pos(self.friction_slip) {
            return Some(("friction_slip", "expected a positive stick regularisation factor"));
        }
        if !pos(self.compression_tolerance) {
            return Some(("compression_tolerance", "expected a positive fraction of the ply thickness"));
        }
        None
    }
}

/// Which parts take part in surface contact, with the controls.
#[derive(Clone, Debug)]
pub struct SurfaceSetup {
    /// Model part indices (every pair of them, and each with itself when self-contact is on).
    pub parts: Vec<usize>,
    /// Controls.
    pub settings: SurfaceSettings,
}
