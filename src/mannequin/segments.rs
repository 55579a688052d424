//! Segment surfaces: each rigid segment is a loft of superellipse cross-sections along its
//! axis, closed by elliptic domes ending in an apex. A section given by a girth is scaled so
//! that the perimeter of its polygon (the triangulated section, not an ellipse formula)
//! equals the girth.
//!
//! Every ring lies in a plane normal to the axis at increasing axial positions and is
//! star-shaped about its centre, so the surface is a graph over (axial position, angle) and
//! does not intersect itself; the rings are counter-clockwise about the axis, which makes
//! the triangles face outward.

use nalgebra::{Point3, Vector3};

use super::skeleton::{Joint, Segment, Skeleton};
use super::surface::TriSurface;

/// The size of a cross-section.
#[derive(Clone, Copy, Debug)]
enum Size {
    /// Polygon perimeter and depth/breadth ratio.
    Girth(f64, f64),
    /// Half-breadth (along u) and half-depth (along v).
    Axes(f64, f64),
}

/// A cross-section of a loft at axial position `s`.
#[derive(Clone, Copy, Debug)]
struct Station {
    s: f64,
    size: Size,
    /// Centre offset from the axis (world vector normal to the axis).
    offset: Vector3<f64>,
    /// The measurement this ring realises, if any.
    measure: Option<&'static str>,
}

fn st(s: f64, size: Size) -> Station {
    Station { s, size, offset: Vector3::zeros(), measure: None }
}

fn measured(s: f64, size: Size, name: &'static str) -> Station {
    Station { s, size, offset: Vector3::zeros(), measure: Some(name) }
}

/// A loft: axis from `p0` along unit `d`; `u` the breadth direction (normal to d), the depth
/// direction v = d × u; superellipse exponent `e`; `n` vertices per ring; caps of axial
/// height `caps.0` below the first station and `caps.1` above the last, each with `cap_rings`
/// rings before its apex.
struct Loft {
    p0: Point3<f64>,
    d: Vector3<f64>,
    u: Vector3<f64>,
    e: f64,
    n: usize,
    cap_rings: usize,
    caps: (f64, f64),
    stations: Vec<Station>,
}

/// A measurement realised by a ring of a segment.
#[derive(Clone, Debug)]
pub struct Girth {
    /// Measurement name (ISO 8559-1, as in the measurements file).
    pub name: &'static str,
    /// Requested girth (m).
    pub requested: f64,
    /// A point of the ring's plane (rest world frame).
    pub point: Point3<f64>,
    /// The ring plane's normal (the segment axis).
    pub normal: Vector3<f64>,
}

/// A generated segment surface in the rest world frame.
#[derive(Clone, Debug)]
pub struct SegmentMesh {
    /// Which segment.
    pub segment: Segment,
    /// The closed, outward surface.
    pub surface: TriSurface,
    /// Unit axis direction of the loft.
    pub axis: Vector3<f64>,
    /// Ring centres (and the two apexes) with their axial positions, in axial order.
    pub centre_line: Vec<(f64, Point3<f64>)>,
    /// Measurements realised by rings of this segment.
    pub girths: Vec<Girth>,
}

/// Points of the unit-breadth superellipse |x|^e + |y/aspect|^e = 1 at `n` equal angle
/// steps, as (x, y) coefficients along (u, v).
fn superellipse(n: usize, e: f64, a: f64, b: f64) -> Vec<(f64, f64)> {
    (0..n)
        .map(|k| {
            let phi = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
            let (s, c) = phi.sin_cos();
            (a * c.signum() * c.abs().powf(2.0 / e), b * s.signum() * s.abs().powf(2.0 / e))
        })
        .collect()
}

/// Perimeter of a closed polygon of (x, y) points.
fn perimeter(p: &[(f64, f64)]) -> f64 {
    (0..p.len()).map(|k| {
        let (a, b) = (p[k], p[(k + 1) % p.len()]);
        (b.0 - a.0).hypot(b.1 - a.1)
    }).sum()
}

impl Loft {
    fn axes(&self, size: Size) -> (f64, f64) {
        match size {
            Size::Axes(a, b) => (a, b),
            Size::Girth(g, aspect) => {
                let k = g / perimeter(&superellipse(self.n, self.e, 1.0, aspect));
                (k, k * aspect)
            }
        }
    }

    /// Triangulates the loft.
    fn build(&self, segment: Segment) -> SegmentMesh {
        let v = self.d.cross(&self.u);
        // Rings: (s, centre offset, a, b), in axial order, caps included.
        let mut rings: Vec<(f64, Vector3<f64>, f64, f64)> = Vec::new();
        let first = self.stations[0];
        let last = self.stations[self.stations.len() - 1];
        let m = self.cap_rings;
        let dome = |t: f64| (1.0 - t * t).sqrt();
        let (a0, b0) = self.axes(first.size);
        for k in (1..=m).rev() {
            let t = k as f64 / (m + 1) as f64;
            rings.push((first.s - self.caps.0 * t, first.offset, a0 * dome(t), b0 * dome(t)));
        }
        for s in &self.stations {
            let (a, b) = self.axes(s.size);
            rings.push((s.s, s.offset, a, b));
        }
        let (a1, b1) = self.axes(last.size);
        for k in 1..=m {
            let t = k as f64 / (m + 1) as f64;
            rings.push((last.s + self.caps.1 * t, last.offset, a1 * dome(t), b1 * dome(t)));
        }
        let n = self.n;
        let mut vertices = Vec::with_capacity(rings.len() * n + 2);
        let mut centre_line = Vec::with_capacity(rings.len() + 2);
        let bottom = self.p0 + self.d * (first.s - self.caps.0) + first.offset;
        centre_line.push((first.s - self.caps.0, bottom));
        vertices.push(bottom);
        for &(s, off, a, b) in &rings {
            let c = self.p0 + self.d * s + off;
            centre_line.push((s, c));
            vertices.extend(superellipse(n, self.e, a, b).into_iter().map(|(x, y)| c + self.u * x + v * y));
        }
        let top = self.p0 + self.d * (last.s + self.caps.1) + last.offset;
        centre_line.push((last.s + self.caps.1, top));
        vertices.push(top);
        let top_index = (vertices.len() - 1) as u32;
        let ring = |r: usize, k: usize| (1 + r * n + k % n) as u32;
        let mut triangles = Vec::with_capacity(2 * n * rings.len());
        for k in 0..n {
            triangles.push([0, ring(0, k + 1), ring(0, k)]);
        }
        for r in 0..rings.len() - 1 {
            for k in 0..n {
                triangles.push([ring(r, k), ring(r, k + 1), ring(r + 1, k + 1)]);
                triangles.push([ring(r, k), ring(r + 1, k + 1), ring(r + 1, k)]);
            }
        }
        let lr = rings.len() - 1;
        for k in 0..n {
            triangles.push([ring(lr, k), ring(lr, k + 1), top_index]);
        }
        let girths = self
            .stations
            .iter()
            .filter_map(|s| {
                let name = s.measure?;
                let requested = match s.size {
                    Size::Girth(g, _) => g,
                    Size::Axes(..) => return None,
                };
                Some(Girth { name, requested, point: self.p0 + self.d * s.s + s.offset, normal: self.d })
            })
            .collect();
        SegmentMesh { segment, surface: TriSurface { vertices, triangles }, axis: self.d, centre_line, girths }
    }
}

/// The surfaces of all segments of the rest body of skeleton `sk` (profiles in the body of
/// this function; heights as ratios of stature H).
pub fn build_segments(sk: &Skeleton) -> Vec<SegmentMesh> {
    use Segment as S;
    let m = &sk.m;
    let h = m.stature;
    let res = m.resolution as usize;
    let (n_trunk, n_limb, cap_rings) = (24 * res, 16 * res, 2 * res);
    let (x, y, z) = (Vector3::x(), Vector3::y(), Vector3::z());
    let c = |j: Joint| sk.centre(j);
    let loft = |p0: Point3<f64>, d: Vector3<f64>, u: Vector3<f64>, e: f64, n: usize, caps: (f64, f64), stations: Vec<Station>| Loft {
        p0,
        d,
        u,
        e,
        n,
        cap_rings,
        caps,
        stations,
    };
    let mut out = Vec::with_capacity(16);

    // Pelvis: from the crotch point (its lowest point, the bottom apex) up past the waist.
    let z_waist = sk.z_waist - m.inseam;
    let z_hipg = sk.z_hip_girth - m.inseam;
    out.push(
        loft(Point3::new(0.0, 0.0, m.inseam), z, x, 2.4, n_trunk, (0.02 * h, 0.015 * h), vec![
            st(0.02 * h, Size::Girth(0.8 * m.hip_girth, 0.70)),
            measured(z_hipg, Size::Girth(m.hip_girth, 0.72), "hip_girth"),
            st(0.5 * (z_hipg + z_waist), Size::Girth(0.5 * (m.hip_girth + m.waist_girth), 0.72)),
            st(z_waist, Size::Girth(0.97 * m.waist_girth, 0.74)),
            st(z_waist + 0.025 * h, Size::Girth(0.95 * m.waist_girth, 0.74)),
        ])
        .build(S::Pelvis),
    );

    // Torso: from below the waist to the shoulders, closed by a dome over the shoulders.
    let trunk = Loft { p0: c(Joint::Lumbar), d: z, u: x, e: 2.5, n: n_trunk, cap_rings, caps: (0.035 * h, 0.04 * h), stations: vec![] };
    let (_, chest_half_depth) = trunk.axes(Size::Girth(m.chest_girth, 0.70));
    let z_chest = sk.z_chest - sk.z_waist;
    let z_sh = c(Joint::ShoulderL).z - sk.z_waist;
    out.push(
        Loft {
            stations: vec![
                st(-0.035 * h, Size::Girth(m.waist_girth, 0.74)),
                measured(0.0, Size::Girth(m.waist_girth, 0.74), "waist_girth"),
                st(0.5 * z_chest, Size::Girth(0.5 * (m.waist_girth + m.chest_girth), 0.72)),
                measured(z_chest, Size::Girth(m.chest_girth, 0.70), "chest_girth"),
                st(z_chest + 0.045 * h, Size::Girth(0.98 * m.chest_girth, 0.66)),
                st(z_sh, Size::Axes(0.5 * m.biacromial_breadth, 0.8 * chest_half_depth)),
            ],
            ..trunk
        }
        .build(S::Torso),
    );

    // Neck and head.
    let zn = c(Joint::Neck).z;
    out.push(
        loft(c(Joint::Neck), z, x, 2.0, n_limb, (0.02 * h, 0.015 * h), vec![
            st(0.0, Size::Girth(1.08 * m.neck_girth, 0.9)),
            measured(sk.z_neck_girth - zn, Size::Girth(m.neck_girth, 0.9), "neck_girth"),
            st(c(Joint::Head).z - zn, Size::Girth(0.97 * m.neck_girth, 0.9)),
        ])
        .build(S::Neck),
    );
    let zh = c(Joint::Head).z;
    let mut jaw = st(sk.z_chin - zh, Size::Girth(0.72 * m.head_girth, 1.15));
    jaw.offset = y * 0.012 * h;
    let mut face = st(0.91 * h - zh, Size::Girth(0.92 * m.head_girth, 1.2));
    face.offset = y * 0.006 * h;
    out.push(
        loft(c(Joint::Head), z, x, 2.2, n_limb, (0.02 * h, h - sk.z_head_girth), vec![
            jaw,
            face,
            measured(sk.z_head_girth - zh, Size::Girth(m.head_girth, 1.2), "head_girth"),
        ])
        .build(S::Head),
    );

    // Arms: hanging along −z; hands flat with their breadth along y (palms facing the thighs).
    for (sh, el, wr, ua, fa, hd) in [
        (Joint::ShoulderL, Joint::ElbowL, Joint::WristL, S::UpperArmL, S::ForearmL, S::HandL),
        (Joint::ShoulderR, Joint::ElbowR, Joint::WristR, S::UpperArmR, S::ForearmR, S::HandR),
    ] {
        let g = m.upper_arm_girth;
        out.push(
            loft(c(sh), -z, x, 2.0, n_limb, (0.035 * h, 0.02 * h), vec![
                st(0.0, Size::Girth(1.1 * g, 1.0)),
                measured(0.5 * sk.upper_arm, Size::Girth(g, 0.95), "upper_arm_girth"),
                st(sk.upper_arm, Size::Girth(0.88 * g, 0.9)),
            ])
            .build(ua),
        );
        out.push(
            loft(c(el), -z, x, 2.0, n_limb, (0.02 * h, 0.02 * h), vec![
                st(0.0, Size::Girth(0.85 * g, 0.9)),
                st(0.25 * sk.forearm, Size::Girth(0.85 * g, 0.85)),
                measured(sk.forearm, Size::Girth(m.wrist_girth, 0.7), "wrist_girth"),
            ])
            .build(fa),
        );
        let l = sk.hand;
        out.push(
            loft(c(wr), -z, y, 2.5, n_limb, (0.015 * h, 0.3 * l), vec![
                st(0.0, Size::Girth(0.95 * m.wrist_girth, 0.55)),
                st(0.4 * l, Size::Girth(1.25 * m.wrist_girth, 0.35)),
                st(0.7 * l, Size::Girth(1.05 * m.wrist_girth, 0.35)),
            ])
            .build(hd),
        );
    }

    // Legs: thighs and shanks along −z, feet along +y with their soles on z = 0.
    for (hip, knee, ankle, th, sn, ft) in [
        (Joint::HipL, Joint::KneeL, Joint::AnkleL, S::ThighL, S::ShankL, S::FootL),
        (Joint::HipR, Joint::KneeR, Joint::AnkleR, S::ThighR, S::ShankR, S::FootR),
    ] {
        let thigh_len = c(hip).z - c(knee).z;
        out.push(
            loft(c(hip), -z, x, 2.0, n_limb, (0.05 * h, 0.025 * h), vec![
                st(0.0, Size::Girth(m.thigh_girth, 0.95)),
                measured(c(hip).z - (m.inseam - 0.01 * h), Size::Girth(m.thigh_girth, 0.95), "thigh_girth"),
                st(0.55 * thigh_len, Size::Girth(0.525 * (m.thigh_girth + m.knee_girth), 0.95)),
                measured(thigh_len, Size::Girth(m.knee_girth, 0.95), "knee_girth"),
            ])
            .build(th),
        );
        let shank_len = c(knee).z - c(ankle).z;
        out.push(
            loft(c(knee), -z, x, 2.0, n_limb, (0.02 * h, 0.02 * h), vec![
                st(0.0, Size::Girth(0.97 * m.knee_girth, 0.95)),
                measured(0.07 * h, Size::Girth(m.calf_girth, 0.95), "calf_girth"),
                measured(shank_len - 0.02 * h, Size::Girth(m.ankle_girth, 0.9), "ankle_girth"),
                st(shank_len, Size::Girth(1.05 * m.ankle_girth, 0.85)),
            ])
            .build(sn),
        );
        let l = sk.foot;
        let a = c(ankle);
        let foot = |s: f64, half_width: f64, half_height: f64| Station {
            s: s * l,
            size: Size::Axes(half_width * h, half_height * h),
            offset: z * (half_height * h),
            measure: None,
        };
        out.push(
            loft(Point3::new(a.x, -0.22 * l, 0.0), y, x, 2.5, n_limb, (0.03 * l, 0.12 * l), vec![
                foot(0.03, 0.018, 0.028),
                foot(0.22, 0.021, 0.036),
                foot(0.5, 0.025, 0.024),
                foot(0.75, 0.0275, 0.015),
                foot(0.88, 0.025, 0.012),
            ])
            .build(ft),
        );
    }
    out
}
