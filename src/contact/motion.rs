//! Prescribed rigid motion of contact bodies: keyframed placements on the analysis clock.
//!
//! **The analysis clock.** A body's motion is a function of one time that runs through the
//! whole analysis: a static step (fixed or automatic increments) advances it by one unit,
//! its load fraction τ ∈ [0, 1] (the pseudo-time of the step); a `Dynamic` step by its
//! simulated physical time (to rest, or `duration`). Step k thus starts at the sum of the
//! durations of the steps before it. Arc-length, displacement-control and buckling steps
//! hold the bodies at their placement and advance the clock by one unit. A scene whose
//! bodies move in a `Dynamic` step therefore gives keyframe times in seconds after the start
//! of that step (plus the units of the steps before it).
//!
//! **Placement.** At time t the body's placement is K(t)·P₀: the keyframe isometry K(t)
//! (rotation about the global origin, then translation) applied after the body's own
//! placement P₀ (its `translation` and `rotation`). Between keyframes the translation of
//! K is interpolated linearly and its rotation spherically (slerp, the constant-angular-
//! velocity path between two orientations, Shoemake, *Animating rotation with quaternion
//! curves*, SIGGRAPH 1985); before the first and after the last keyframe K holds.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

/// A keyframed rigid motion: (time, isometry) in strictly increasing time.
#[derive(Clone, Debug)]
pub struct Motion {
    keys: Vec<(f64, Isometry3<f64>)>,
}

impl Motion {
    /// A motion from keyframes (time, translation, rotation vector in degrees). Errors name
    /// the offending keyframe: fewer than one keyframe, non-finite values, or times not
    /// strictly increasing.
    pub fn new(keys: &[(f64, [f64; 3], [f64; 3])]) -> Result<Self, (usize, String)> {
        if keys.is_empty() {
            return Err((0, "expected at least one keyframe".into()));
        }
        let mut out = Vec::with_capacity(keys.len());
        for (k, (t, tr, rot)) in keys.iter().enumerate() {
            if !t.is_finite() {
                return Err((k, format!("expected a finite time, found {t}")));
            }
            if !tr.iter().chain(rot).all(|v| v.is_finite()) {
                return Err((k, "expected a finite translation and rotation".into()));
            }
            if let Some((prev, _)) = out.last()
                && *t <= *prev
            {
                return Err((k, format!("keyframe times must increase strictly: {t} follows {prev}")));
            }
            let rv = Vector3::from(*rot).map(f64::to_radians);
            out.push((*t, Isometry3::from_parts(Translation3::from(Vector3::from(*tr)), UnitQuaternion::from_scaled_axis(rv))));
        }
        Ok(Self { keys: out })
    }

    /// The keyframe isometry K(t): piecewise linear in translation, slerp in rotation, held
    /// constant outside the keyframe times.
    pub fn at(&self, t: f64) -> Isometry3<f64> {
        let first = self.keys[0];
        if t <= first.0 {
            return first.1;
        }
        for w in self.keys.windows(2) {
            let ((t0, a), (t1, b)) = (w[0], w[1]);
            if t <= t1 {
                return interpolate(&a, &b, (t - t0) / (t1 - t0));
            }
        }
        self.keys[self.keys.len() - 1].1
    }

    /// Time of the last keyframe (the body is still from then on).
    pub fn end_time(&self) -> f64 {
        self.keys[self.keys.len() - 1].0
    }
}

/// The placement a fraction `s` ∈ [0, 1] of the way from `a` to `b`: translation
/// interpolated linearly, rotation by slerp, R(s) = R_a exp(s log(R_a⁻¹ R_b)) (the shorter
/// way round; a half-turn, whose path is ambiguous, turns about the axis of log).
pub fn interpolate(a: &Isometry3<f64>, b: &Isometry3<f64>, s: f64) -> Isometry3<f64> {
    let tr = a.translation.vector.lerp(&b.translation.vector, s);
    let rel = a.rotation.inverse() * b.rotation;
    let rot = a.rotation * UnitQuaternion::from_scaled_axis(rel.scaled_axis() * s);
    Isometry3::from_parts(Translation3::from(tr), rot)
}

/// Bound ℓ on |dp/ds| of a point's coordinates p(s) = P(s)⁻¹ x(s) in the frame of a body
/// interpolated from `a` to `b` ([`interpolate`]) while the point moves on the segment
/// x(s) = x₀ + s Δx: with c the body's origin and θ the angle between the two orientations,
/// |dp/ds| ≤ |Δx − Δc| + θ (|x₀ − c₀| + |Δx − Δc|). The signed distance to the body is
/// 1-Lipschitz in p, so ℓ bounds the rate of the gap along the relative motion
/// (conservative advancement, `ccd`).
pub fn relative_rate(a: &Isometry3<f64>, b: &Isometry3<f64>, x0: &Vector3<f64>, dx: &Vector3<f64>) -> f64 {
    let dc = b.translation.vector - a.translation.vector;
    let rel = (dx - dc).norm();
    let theta = a.rotation.angle_to(&b.rotation);
    rel + theta * ((x0 - a.translation.vector).norm() + rel)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Halfway between the identity and a 90° turn about z with a 2 m lift: a 45° turn and
    /// a 1 m lift (slerp is uniform in angle); outside the keyframes the ends hold.
    #[test]
    fn keyframes_interpolate_linearly_and_by_slerp() {
        let m = Motion::new(&[(0.0, [0.0; 3], [0.0; 3]), (2.0, [0.0, 0.0, 2.0], [0.0, 0.0, 90.0])]).unwrap();
        let half = m.at(1.0);
        assert!((half.translation.vector - Vector3::new(0.0, 0.0, 1.0)).norm() < 1e-14);
        assert!((half.rotation.angle() - std::f64::consts::FRAC_PI_4).abs() < 1e-14);
        assert!((m.at(-1.0).translation.vector.norm()) < 1e-14);
        assert!((m.at(5.0).translation.vector.z - 2.0).abs() < 1e-14);
    }

    /// A half-turn between keyframes is interpolated continuously (a quarter-turn halfway).
    #[test]
    fn half_turns_interpolate() {
        let m = Motion::new(&[(0.0, [0.0; 3], [0.0; 3]), (1.0, [0.0; 3], [0.0, 0.0, 180.0])]).unwrap();
        assert!((m.at(0.5).rotation.angle() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert!((m.at(1.0).rotation.angle() - std::f64::consts::PI).abs() < 1e-12);
    }

    #[test]
    fn bad_keyframes_are_refused_with_their_index() {
        assert_eq!(Motion::new(&[]).unwrap_err().0, 0);
        assert_eq!(Motion::new(&[(1.0, [0.0; 3], [0.0; 3]), (1.0, [0.0; 3], [0.0; 3])]).unwrap_err().0, 1);
        assert_eq!(Motion::new(&[(0.0, [f64::NAN, 0.0, 0.0], [0.0; 3])]).unwrap_err().0, 0);
    }

    /// The rate bound holds for a turning, translating body: sampled |dp/ds| never exceeds it.
    #[test]
    fn relative_rate_bounds_the_local_motion() {
        let a = Isometry3::translation(0.1, 0.0, 0.0);
        let b = Isometry3::from_parts(Translation3::new(0.3, 0.1, 0.0), UnitQuaternion::from_scaled_axis(Vector3::new(0.0, 0.4, 0.3)));
        let (x0, dx) = (Vector3::new(0.5, -0.2, 0.4), Vector3::new(-0.1, 0.2, 0.05));
        let ell = relative_rate(&a, &b, &x0, &dx);
        let p = |s: f64| interpolate(&a, &b, s).inverse_transform_point(&(x0 + dx * s).into()).coords;
        let h = 1e-6;
        for k in 0..=100 {
            let s = k as f64 / 100.0 * (1.0 - h);
            assert!(((p(s + h) - p(s)) / h).norm() <= ell * (1.0 + 1e-6));
        }
    }
}
