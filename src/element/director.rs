//! Finite rotations of the fibre director.
//!
//! Each node carries its current unit director `d` and an orthonormal tangent pair
//! (`t1`, `t2`) with t1 × t2 = d. The two rotational unknowns of a node are the components
//! (α1, α2) of the director's tilt θ = α1 t1 + α2 t2 in that basis. An increment is applied
//! with the exponential map of the unit sphere (Rodrigues' formula for the rotation about
//! d × θ by |θ|), which maps d to cos|θ| d + sin|θ| θ/|θ| and transports t1, t2 rigidly, so
//! rotations of any size accumulate without singularity (Simo & Fox 1989; Bathe 2014 §6.5).
//! Linearised about α = 0: δd = t1 δα1 + t2 δα2 and ΔΔd = −(δα·Δα) d.

use nalgebra::{Matrix3, Rotation3, Unit, Vector3};

/// Current director frame of a node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectorFrame {
    /// Unit director.
    pub d: Vector3<f64>,
    /// First tangent vector (t1 × t2 = d).
    pub t1: Vector3<f64>,
    /// Second tangent vector.
    pub t2: Vector3<f64>,
}

impl DirectorFrame {
    /// Builds a frame around the unit director `d`, with t1 the projection of `hint` onto the
    /// plane normal to d (or of a global axis when `hint` is nearly parallel to d).
    pub fn new(d: Vector3<f64>, hint: Option<Vector3<f64>>) -> Self {
        let d = d.normalize();
        let project = |v: Vector3<f64>| v - d * d.dot(&v);
        let mut t1 = hint.map(project).unwrap_or_else(Vector3::zeros);
        if t1.norm() < 1e-6 {
            t1 = project(Vector3::x());
            if t1.norm() < 0.5 {
                t1 = project(Vector3::y());
            }
        }
        let t1 = t1.normalize();
        Self { d, t1, t2: d.cross(&t1) }
    }

    /// The 3×2 matrix [t1 t2] mapping tilt components to director variations.
    pub fn tangent_map(&self) -> nalgebra::Matrix3x2<f64> {
        nalgebra::Matrix3x2::from_columns(&[self.t1, self.t2])
    }

    /// Rotation tilting the director by θ = α1 t1 + α2 t2 (exponential map).
    pub fn tilt_rotation(&self, alpha: [f64; 2]) -> Rotation3<f64> {
        let theta = self.t1 * alpha[0] + self.t2 * alpha[1];
        let angle = theta.norm();
        if angle < 1e-300 {
            return Rotation3::identity();
        }
        let axis = Unit::new_normalize(self.d.cross(&theta));
        Rotation3::from_axis_angle(&axis, angle)
    }

    /// Applies a rotation to the whole frame (director and tangents), re-orthonormalising.
    pub fn rotated(&self, r: &Rotation3<f64>) -> Self {
        let d = (r * self.d).normalize();
        let t1 = r * self.t1;
        let t1 = (t1 - d * d.dot(&t1)).normalize();
        Self { d, t1, t2: d.cross(&t1) }
    }

    /// Frame after a tilt increment (α1, α2).
    pub fn tilted(&self, alpha: [f64; 2]) -> Self {
        self.rotated(&self.tilt_rotation(alpha))
    }

    /// Generalised forces on (α1, α2) of a moment vector `m`: the virtual work m·δω with
    /// δω = d × δd, i.e. (m·(d × t1), m·(d × t2)) = (m·t2, −m·t1).
    pub fn moment_to_tilt_forces(&self, m: &Vector3<f64>) -> [f64; 2] {
        [m.dot(&self.t2), -m.dot(&self.t1)]
    }

    /// Rotation matrix whose columns are (t1, t2, d).
    pub fn matrix(&self) -> Matrix3<f64> {
        Matrix3::from_columns(&[self.t1, self.t2, self.d])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tilt_is_exponential_map() {
        let f = DirectorFrame::new(Vector3::z(), Some(Vector3::x()));
        let g = f.tilted([0.3, -0.4]);
        let expect = Vector3::z() * 0.5f64.cos() + (Vector3::x() * 0.3 - Vector3::y() * 0.4) / 0.5 * 0.5f64.sin();
        assert!((g.d - expect).norm() < 1e-14);
        assert!((g.t1.cross(&g.t2) - g.d).norm() < 1e-14);
    }

    #[test]
    fn many_small_tilts_accumulate_to_full_turns() {
        // 720 steps of 1° about the t2 axis: two full turns return the frame to its start.
        let mut f = DirectorFrame::new(Vector3::z(), Some(Vector3::x()));
        for _ in 0..720 {
            f = f.tilted([1f64.to_radians(), 0.0]);
        }
        assert!((f.d - Vector3::z()).norm() < 1e-10);
        assert!((f.t1 - Vector3::x()).norm() < 1e-10);
    }
}
