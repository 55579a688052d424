//! Placement of flat pattern pieces in 3D: rigid, or rolled (isometrically) onto a cylinder
//! or a cone.

use nalgebra::{Rotation3, Vector3};

use super::spec::Placement;

fn v3(a: [f64; 3]) -> Vector3<f64> {
    Vector3::new(a[0], a[1], a[2])
}

/// Orthonormal pair (e1, e2) perpendicular to the unit axis `a`, with a × e1 = e2.
fn basis(a: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let mut e1 = Vector3::x() - a * a.x;
    if e1.norm() < 0.5 {
        e1 = Vector3::y() - a * a.y;
    }
    let e1 = e1.normalize();
    (e1, a.cross(&e1))
}

impl Placement {
    /// Checks the placement's parameters; returns what is wrong.
    pub fn problem(&self) -> Option<String> {
        match self {
            Placement::Rigid { translation, rotation_deg } => {
                (!translation.iter().chain(rotation_deg).all(|v| v.is_finite())).then(|| "translation and rotation must be finite".to_string())
            }
            Placement::Cylinder { origin, axis, radius, start_angle_deg } => {
                if !(radius.is_finite() && *radius > 0.0) {
                    Some("the cylinder radius must be positive".into())
                } else if v3(*axis).norm() == 0.0 || !origin.iter().chain(axis).all(|v| v.is_finite()) || !start_angle_deg.is_finite() {
                    Some("the cylinder needs a finite origin and a non-zero axis".into())
                } else {
                    None
                }
            }
            Placement::Cone { apex, axis, half_angle_deg, pattern_apex } => {
                if !(half_angle_deg.is_finite() && *half_angle_deg > 0.0 && *half_angle_deg < 90.0) {
                    Some("the cone half angle must lie in (0°, 90°)".into())
                } else if v3(*axis).norm() == 0.0 || !apex.iter().chain(axis).chain(pattern_apex).all(|v| v.is_finite()) {
                    Some("the cone needs a finite apex and a non-zero axis".into())
                } else {
                    None
                }
            }
        }
    }

    /// 3D point of the pattern point (u, v).
    pub fn map(&self, p: [f64; 2]) -> Vector3<f64> {
        let (u, v) = (p[0], p[1]);
        match self {
            Placement::Rigid { translation, rotation_deg } => {
                let r = Rotation3::new(v3(*rotation_deg).map(f64::to_radians));
                r * Vector3::new(u, v, 0.0) + v3(*translation)
            }
            Placement::Cylinder { origin, axis, radius, start_angle_deg } => {
                let a = v3(*axis).normalize();
                let (e1, e2) = basis(&a);
                let th = start_angle_deg.to_radians() + u / radius;
                v3(*origin) + a * v + (e1 * th.cos() + e2 * th.sin()) * *radius
            }
            Placement::Cone { apex, axis, half_angle_deg, pattern_apex } => {
                let a = v3(*axis).normalize();
                let (e1, e2) = basis(&a);
                let beta = half_angle_deg.to_radians();
                let (du, dv) = (u - pattern_apex[0], v - pattern_apex[1]);
                let rho = (du * du + dv * dv).sqrt();
                let psi = dv.atan2(du) / beta.sin();
                v3(*apex) + (a * beta.cos() + (e1 * psi.cos() + e2 * psi.sin()) * beta.sin()) * rho
            }
        }
    }

    /// Tangent map ∂x/∂(u, v) at a pattern point (central differences with step `h`).
    pub fn jacobian(&self, p: [f64; 2], h: f64) -> (Vector3<f64>, Vector3<f64>) {
        let xu = (self.map([p[0] + h, p[1]]) - self.map([p[0] - h, p[1]])) / (2.0 * h);
        let xv = (self.map([p[0], p[1] + h]) - self.map([p[0], p[1] - h])) / (2.0 * h);
        (xu, xv)
    }

    /// Unit director at a pattern point: ∂x/∂u × ∂x/∂v normalised (so counter-clockwise
    /// pattern quads stay counter-clockwise about it).
    pub fn director(&self, p: [f64; 2], h: f64) -> Vector3<f64> {
        let (xu, xv) = self.jacobian(p, h);
        xu.cross(&xv).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rolling_is_isometric() {
        let cyl = Placement::Cylinder { origin: [0.0; 3], axis: [0.0, 0.0, 1.0], radius: 0.1, start_angle_deg: 0.0 };
        let cone = Placement::Cone { apex: [0.0; 3], axis: [0.0, 0.0, 1.0], half_angle_deg: 20.0, pattern_apex: [0.0, -1.0] };
        for pl in [cyl, cone] {
            let (xu, xv) = pl.jacobian([0.05, 0.02], 1e-6);
            assert!((xu.norm() - 1.0).abs() < 1e-8 && (xv.norm() - 1.0).abs() < 1e-8 && xu.dot(&xv).abs() < 1e-8);
        }
    }
}
