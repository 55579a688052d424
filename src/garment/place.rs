//! Placement of flat pattern pieces in 3D: rigid, or rolled (isometrically) onto a cylinder,
//! an elliptic cylinder or a cone. (Placements at named arrangement points round a body are
//! resolved to elliptic cylinders by `garment::arrange`.)

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
            Placement::Around { .. } => Some("an arrangement point needs a mannequin contact body (the placement was not resolved)".into()),
            Placement::EllipticCylinder { origin, axis, side, semi_axes, anchor } => {
                let (a, s) = (v3(*axis), v3(*side));
                if !origin.iter().chain(axis).chain(side).chain(semi_axes).chain(anchor).all(|v| v.is_finite()) {
                    Some("the elliptic cylinder needs finite parameters".into())
                } else if !(semi_axes[0] > 0.0 && semi_axes[1] > 0.0) {
                    Some("the elliptic cylinder's semi-axes must be positive".into())
                } else if a.norm() == 0.0 || a.normalize().cross(&s).norm() < 1e-6 * s.norm().max(1e-300) || s.norm() == 0.0 {
                    Some("the elliptic cylinder needs a non-zero axis and a side direction not along it".into())
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
            // Unresolved (rejected by `problem`).
            Placement::Around { .. } => Vector3::zeros(),
            Placement::EllipticCylinder { origin, axis, side, semi_axes, anchor } => {
                let a = v3(*axis).normalize();
                let e1 = (v3(*side) - a * a.dot(&v3(*side))).normalize();
                let e2 = a.cross(&e1);
                let (sa, sb) = (semi_axes[0], semi_axes[1]);
                let phi = ellipse_angle(sa, sb, u - anchor[0]);
                v3(*origin) + a * (v - anchor[1]) + e1 * (sa * phi.cos()) + e2 * (sb * phi.sin())
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

/// Arc length of the ellipse (a cos t, b sin t) from t = 0 to t = φ, by 5-point
/// Gauss–Legendre quadrature on panels of at most π/64.
pub fn ellipse_arc(a: f64, b: f64, phi: f64) -> f64 {
    const X: [f64; 5] = [0.0, -0.538_469_310_105_683, 0.538_469_310_105_683, -0.906_179_845_938_664, 0.906_179_845_938_664];
    const W: [f64; 5] = [0.568_888_888_888_889, 0.478_628_670_499_366, 0.478_628_670_499_366, 0.236_926_885_056_189, 0.236_926_885_056_189];
    let speed = |t: f64| (a * a * t.sin().powi(2) + b * b * t.cos().powi(2)).sqrt();
    let panels = ((phi.abs() / (std::f64::consts::PI / 64.0)).ceil() as usize).max(1);
    let h = phi / panels as f64;
    (0..panels)
        .map(|k| {
            let mid = (k as f64 + 0.5) * h;
            X.iter().zip(&W).map(|(x, w)| w * speed(mid + 0.5 * h * x)).sum::<f64>() * 0.5 * h
        })
        .sum()
}

/// The angle parameter φ of the point at arc length `s` (either sign, any number of turns)
/// counter-clockwise from t = 0 on the ellipse (a cos t, b sin t): Newton's method on
/// [`ellipse_arc`], started from the circle of equal perimeter.
pub fn ellipse_angle(a: f64, b: f64, s: f64) -> f64 {
    let two_pi = 2.0 * std::f64::consts::PI;
    let perimeter = ellipse_arc(a, b, two_pi);
    let turns = (s / perimeter).floor();
    let r = s - turns * perimeter;
    let mut phi = two_pi * r / perimeter;
    for _ in 0..30 {
        let f = ellipse_arc(a, b, phi) - r;
        let speed = (a * a * phi.sin().powi(2) + b * b * phi.cos().powi(2)).sqrt();
        let step = f / speed;
        phi -= step;
        if step.abs() < 1e-14 {
            break;
        }
    }
    two_pi * turns + phi
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rolling_is_isometric() {
        let cyl = Placement::Cylinder { origin: [0.0; 3], axis: [0.0, 0.0, 1.0], radius: 0.1, start_angle_deg: 0.0 };
        let cone = Placement::Cone { apex: [0.0; 3], axis: [0.0, 0.0, 1.0], half_angle_deg: 20.0, pattern_apex: [0.0, -1.0] };
        let ell = Placement::EllipticCylinder { origin: [0.1, 0.0, 0.0], axis: [0.0, 0.0, 1.0], side: [0.0, 1.0, 0.0], semi_axes: [0.2, 0.12], anchor: [0.1, 0.0] };
        for pl in [cyl, cone, ell] {
            let (xu, xv) = pl.jacobian([0.05, 0.02], 1e-6);
            assert!((xu.norm() - 1.0).abs() < 1e-8 && (xv.norm() - 1.0).abs() < 1e-8 && xu.dot(&xv).abs() < 1e-8);
        }
    }

    #[test]
    fn elliptic_cylinder_wraps_by_arc_length() {
        // The perimeter of the ellipse 0.2 × 0.12 is 1.0265749 (Ramanujan's second
        // approximation, exact to 1e-7 at this eccentricity): a strip of that width closes.
        let (a, b) = (0.2, 0.12);
        let h = (a - b) * (a - b) / ((a + b) * (a + b));
        let ramanujan = std::f64::consts::PI * (a + b) * (1.0 + 3.0 * h / (10.0 + (4.0 - 3.0 * h).sqrt()));
        let perimeter = ellipse_arc(a, b, 2.0 * std::f64::consts::PI);
        assert!((perimeter - ramanujan).abs() < 1e-7, "{perimeter} vs {ramanujan}");
        let ell = Placement::EllipticCylinder { origin: [0.0; 3], axis: [0.0, 0.0, 1.0], side: [1.0, 0.0, 0.0], semi_axes: [a, b], anchor: [0.0, 0.0] };
        let p0 = ell.map([0.0, 0.0]);
        let p1 = ell.map([perimeter, 0.0]);
        assert!((p0 - Vector3::new(a, 0.0, 0.0)).norm() < 1e-12 && (p1 - p0).norm() < 1e-10);
        // A quarter of the perimeter reaches the end of the minor axis, counter-clockwise.
        let q = ell.map([0.25 * perimeter, 0.3]);
        assert!((q - Vector3::new(0.0, b, 0.3)).norm() < 1e-10, "{q}");
        assert!(ell.director([0.0, 0.0], 1e-7).dot(&Vector3::x()) > 0.999_999);
    }
}
