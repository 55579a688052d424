//! Element sizes from the physics, shared by garment panels (`garment::sizing`) and generated
//! parts (`scene::part_sizing`): the `element_size` value (`Auto((tolerance: ..))` or a
//! number) and the fabric's length scales that turn a relative shape tolerance into a size.
//!
//! A bilinear element interpolates a shape f with an error of at most h² max|f''| / 8
//! (linear interpolation estimate, e.g. Ciarlet, *The Finite Element Method for Elliptic
//! Problems*, 1978, Thm 3.1.6 in one dimension). A shape of length scale ℓ (a circle of
//! radius ℓ, a decay exp(−s/ℓ), a wave sin(s/ℓ)) has |f''| = |f| / ℓ², so a relative shape
//! error `tolerance` asks for h = √(8 · tolerance) · ℓ ([`size_for`]). The length scales:
//! the bending length ([`bending_length`], Peirce 1930), the wrinkle wavelength
//! ([`wrinkle_wavelength`], Cerda & Mahadevan 2003), the bending boundary layer of a sheet
//! under tension ([`tension_length`]) and the radius of a contact body
//! ([`radius_from_normals`]).

use serde::{Deserialize, Serialize};

/// Standard gravity (m/s²).
pub const G: f64 = 9.80665;

/// Parameters of an automatic element size.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AutoSize {
    /// Relative shape error the size aims at (0 < tolerance < 0.5): h = √(8 tolerance) ℓ_min.
    pub tolerance: f64,
    /// Known membrane tension (N/m) for the wrinkle wavelength; None: the panel's own weight.
    #[serde(default)]
    pub tension: Option<f64>,
    /// Size on a seam line or at a notch, as a fraction of the panel's size (default 0.5;
    /// 1 turns the refinement off).
    #[serde(default = "half")]
    pub seam_factor: f64,
}

fn half() -> f64 {
    0.5
}

/// A panel's target element size: a fixed number (m) or `Auto(..)` from the physics.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum ElementSize {
    /// A fixed size (m), written as a plain number.
    Fixed(f64),
    /// From the fabric's bending length, wrinkle wavelength, body curvature and seams.
    Auto(AutoSize),
}

impl<'de> Deserialize<'de> for ElementSize {
    /// A number, or `Auto((tolerance: ..))` (also `Auto(tolerance: ..)`).
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = ElementSize;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("an element size in metres or Auto((tolerance: ..))")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<ElementSize, E> {
                Ok(ElementSize::Fixed(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<ElementSize, E> {
                Ok(ElementSize::Fixed(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<ElementSize, E> {
                Ok(ElementSize::Fixed(v as f64))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<ElementSize, A::Error> {
                let a: AutoSize = seq.next_element()?.ok_or_else(|| serde::de::Error::custom("Auto needs its parameters: Auto((tolerance: ..))"))?;
                if seq.next_element::<serde::de::IgnoredAny>()?.is_some() {
                    return Err(serde::de::Error::custom("Auto takes one parameter struct: Auto((tolerance: ..))"));
                }
                Ok(ElementSize::Auto(a))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, map: A) -> Result<ElementSize, A::Error> {
                AutoSize::deserialize(serde::de::value::MapAccessDeserializer::new(map)).map(ElementSize::Auto)
            }
        }
        d.deserialize_any(V)
    }
}

impl ElementSize {
    /// The fixed size, if any.
    pub fn fixed(&self) -> Option<f64> {
        match self {
            ElementSize::Fixed(h) => Some(*h),
            ElementSize::Auto(_) => None,
        }
    }

    /// What is wrong with the value, if anything: (key, message).
    pub fn problem(&self) -> Option<(&'static str, String)> {
        match self {
            ElementSize::Fixed(h) => (!(h.is_finite() && *h > 0.0)).then(|| ("element_size", "expected a positive element size".to_string())),
            ElementSize::Auto(a) => {
                if !(a.tolerance.is_finite() && a.tolerance > 0.0 && a.tolerance < 0.5) {
                    Some(("tolerance", format!("Auto: expected a relative tolerance between 0 and 0.5 (e.g. 0.02), found {}", a.tolerance)))
                } else if !(a.seam_factor.is_finite() && a.seam_factor > 0.0 && a.seam_factor <= 1.0) {
                    Some(("seam_factor", format!("Auto: expected a seam factor in (0, 1], found {}", a.seam_factor)))
                } else if let Some(t) = a.tension.filter(|t| !(t.is_finite() && *t > 0.0)) {
                    Some(("tension", format!("Auto: expected a positive tension (N/m), found {t}")))
                } else {
                    None
                }
            }
        }
    }
}

/// The length scales behind an automatic size (m), as reported.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct LengthScales {
    /// Bending length (B/(ρ_A g))^{1/3}.
    pub bending_length: f64,
    /// Cerda–Mahadevan wrinkle wavelength.
    pub wrinkle_wavelength: f64,
    /// Smallest radius of curvature of a contact body near the panel, if any.
    pub body_radius: Option<f64>,
}

/// Bending length ℓ_b = (B / (ρ_A g))^{1/3} (Peirce 1930).
pub fn bending_length(b: f64, areal_density: f64) -> f64 {
    (b / (areal_density * G)).cbrt()
}

/// Cerda–Mahadevan wrinkle wavelength λ = 2π (B/K)^{1/4}, K = T π²/L² (PRL 2003), for
/// bending rigidity `b`, tension `t` (N/m) over length `l`.
pub fn wrinkle_wavelength(b: f64, t: f64, l: f64) -> f64 {
    let k = t * std::f64::consts::PI.powi(2) / (l * l);
    2.0 * std::f64::consts::PI * (b / k).powf(0.25)
}

/// Size from the length scales: √(8 tolerance) · min(ℓ_b, λ/2π, R_body), at most a quarter
/// of `extent`.
pub fn size_from_scales(tolerance: f64, s: &LengthScales, extent: f64) -> f64 {
    let l = s.bending_length.min(s.wrinkle_wavelength / (2.0 * std::f64::consts::PI)).min(s.body_radius.unwrap_or(f64::INFINITY));
    ((8.0 * tolerance).sqrt() * l).min(0.25 * extent)
}

/// Size for a relative shape error `tolerance` on a shape of length scale `l`:
/// h = √(8 tolerance) · l (the bilinear interpolation error h² |f''| / 8 with |f''| = |f| / l²).
pub fn size_for(tolerance: f64, l: f64) -> f64 {
    (8.0 * tolerance).sqrt() * l
}

/// Bending boundary layer of a sheet of bending rigidity `b` (N·m) under membrane tension `t`
/// (N/m): ℓ_T = √(B / T), the length over which a tensioned sheet bends round an edge
/// sharper than itself (from B w'''' = T w'', the plate under tension; e.g. Audoly & Pomeau,
/// *Elasticity and Geometry*, 2010). Cerda & Mahadevan's λ/2π is the geometric mean
/// √(ℓ_T L / π) of it and the tensioned length L.
pub fn tension_length(b: f64, t: f64) -> f64 {
    (b / t).sqrt()
}

/// Radius of curvature of a body's surface seen from point `x`: the outward normal at x and
/// at x + δ t for two tangent directions t turn by θ = 2 asin(|Δn|/2), and the normal field
/// of a surface of radius ρ through x turns by tan θ = δ/ρ, so ρ = δ / tan θ (exact for the
/// distance gradient of a sphere or cylinder; the smaller of the two directions). δ starts at
/// `delta` and is halved while θ exceeds 45°. `normal(x)` returns the body's outward normal
/// (the gradient of its signed distance) at x, if the body is near. For a point off the
/// surface ρ is the radius of the offset surface through it (body radius + distance).
pub fn radius_from_normals(x: &nalgebra::Vector3<f64>, delta: f64, normal: &dyn Fn(&nalgebra::Vector3<f64>) -> Option<nalgebra::Vector3<f64>>) -> Option<f64> {
    let n = normal(x)?;
    let a = if n.x.abs() < 0.9 { nalgebra::Vector3::x() } else { nalgebra::Vector3::y() };
    let t1 = n.cross(&a).normalize();
    let t2 = n.cross(&t1);
    let mut delta = delta;
    for _ in 0..8 {
        let mut dn: f64 = 0.0;
        for t in [t1, t2] {
            if let Some(m) = normal(&(x + t * delta)) {
                dn = dn.max((m - n).norm());
            }
        }
        let theta = 2.0 * (0.5 * dn).min(1.0).asin();
        if theta > std::f64::consts::FRAC_PI_4 {
            delta *= 0.5;
            continue;
        }
        return (theta > 1e-9).then(|| delta / theta.tan());
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The wavelength of the reference's example (254 mm × 0.1 mm, ν = 0.5, γ = 0.10:
    /// λ ≈ 18.3 mm): with B = E t³/12(1−ν²) and T = E t γ, λ = 2π (B L²/(T π²))^{1/4}.
    #[test]
    fn wrinkle_wavelength_matches_the_reference_example() {
        let (e, t, nu, gamma, l): (f64, f64, f64, f64, f64) = (1.0e6, 1.0e-4, 0.5, 0.10, 0.254);
        let b = e * t.powi(3) / (12.0 * (1.0 - nu * nu));
        let lam = wrinkle_wavelength(b, e * t * gamma, l);
        assert!((lam - 0.0183).abs() < 0.0001, "λ = {lam}");
    }

    /// A sphere seen from its surface or from outside: the radius through the point, exactly
    /// (to rounding), also when the first step is longer than the radius.
    #[test]
    fn radius_from_normals_of_a_sphere() {
        let normal = |x: &nalgebra::Vector3<f64>| Some(x.normalize());
        for (r, delta) in [(0.1, 0.005), (0.011, 0.022)] {
            let x = nalgebra::Vector3::new(0.0, 0.0, r);
            let got = radius_from_normals(&x, delta, &normal).unwrap();
            assert!((got / r - 1.0).abs() < 1e-9, "{got} vs {r}");
        }
    }
}
