//! Arrangement points round a mannequin: a panel placed `Around` a named point
//! (`SEGMENT.SIDE`, e.g. `torso.front`, `upper_arm_l.back`, `thigh_r.outer`) is wrapped on
//! that point's placement template at a clearance from the body, instead of by
//! hand-computed angles:
//!
//! - **limbs** (upper arms, forearms, thighs, shanks): a circular cylinder about the
//!   segment's long axis, radius = the largest distance of the segment's surface from the
//!   axis over the panel's axial range, plus the clearance;
//! - **shells** (pelvis and torso — the trunk —, neck, head): an elliptic cylinder about the
//!   segment axis with the body's principal directions (breadth x, depth y) as its axes,
//!   centred on the section's mid-range and scaled so that every surface vertex in the
//!   panel's axial range lies inside the ellipse (superellipse sections bulge past the
//!   ellipse of their half-breadth and half-depth), then grown by the clearance.
//!
//! The trunk's shell spans pelvis and torso together (a coverall's body panels run from the
//! crotch to the shoulders), the head's shell head and neck. Geometry is taken in the
//! segment's rest frame and carried into the scene by the segment's placement in the body's
//! pose (the pose file, or the first frame of the motion) and by the body's own translation
//! and rotation, so a panel follows a posed limb.
//!
//! The pattern's v axis runs up the segment (towards the proximal joint for limbs, towards
//! the head for trunk, neck and head); u runs counter-clockwise round it seen from the axis
//! tip, so the director of a counter-clockwise outline points away from the body.

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

use super::place::ellipse_arc;
use super::spec::{GarmentSpec, PanelSpec, Placement};
use crate::mannequin::{self, Mannequin, Pose, Segment, SEGMENTS};
use crate::contact::spec::{BodySpec, ContactSpec, ShapeSpec};
use crate::input::{Locator, SceneError};

/// The side of a segment an arrangement point names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// Anterior (+y at rest).
    Front,
    /// Posterior (−y).
    Back,
    /// The body's left (−x).
    Left,
    /// The body's right (+x).
    Right,
    /// Lateral, away from the midline (limbs only).
    Outer,
    /// Medial, towards the midline (limbs only).
    Inner,
}

/// The placement template of a segment.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Template {
    /// Circular cylinder about a limb.
    Limb,
    /// Elliptic shell about the trunk, neck or head.
    Shell,
}

const SIDES: [(&str, Side); 6] = [("front", Side::Front), ("back", Side::Back), ("left", Side::Left), ("right", Side::Right), ("outer", Side::Outer), ("inner", Side::Inner)];

/// The template of segment `s`; None for hands and feet (no panel is wrapped round them).
pub fn template(s: Segment) -> Option<Template> {
    use Segment::*;
    match s {
        Pelvis | Torso | Neck | Head => Some(Template::Shell),
        UpperArmL | ForearmL | UpperArmR | ForearmR | ThighL | ShankL | ThighR | ShankR => Some(Template::Limb),
        HandL | HandR | FootL | FootR => None,
    }
}

/// Every valid arrangement point name, for error messages.
pub fn point_names() -> Vec<String> {
    let mut out = Vec::new();
    for s in SEGMENTS {
        let Some(t) = template(s) else { continue };
        for (name, side) in SIDES {
            if t == Template::Limb || !matches!(side, Side::Outer | Side::Inner) {
                out.push(format!("{}.{name}", s.name()));
            }
        }
    }
    out
}

/// Parses `SEGMENT.SIDE`; the error says what is wrong and lists what is valid.
pub fn parse_point(name: &str) -> Result<(Segment, Side), String> {
    let listing = || format!("arrangement points are SEGMENT.SIDE: {}", point_names().join(", "));
    let Some((seg, side)) = name.split_once('.') else {
        return Err(format!("unknown arrangement point \"{name}\"; {}", listing()));
    };
    let segment = SEGMENTS.iter().copied().find(|s| s.name() == seg).ok_or_else(|| format!("unknown segment \"{seg}\" in arrangement point \"{name}\"; {}", listing()))?;
    let t = template(segment).ok_or_else(|| format!("no placement template round the {seg} (hands and feet take none); {}", listing()))?;
    let side = SIDES.iter().find(|(n, _)| *n == side).map(|x| x.1).ok_or_else(|| format!("unknown side \"{side}\" in arrangement point \"{name}\" (front, back, left, right, outer, inner)"))?;
    if t == Template::Shell && matches!(side, Side::Outer | Side::Inner) {
        return Err(format!("\"{name}\": outer and inner name the sides of a limb; the {seg} takes front, back, left or right"));
    }
    Ok((segment, side))
}

/// Unit direction of `side` of segment `s` in its rest frame (= rest world directions).
fn side_direction(s: Segment, side: Side) -> Vector3<f64> {
    let left_limb = s.name().ends_with("_l");
    match side {
        Side::Front => Vector3::y(),
        Side::Back => -Vector3::y(),
        Side::Left => -Vector3::x(),
        Side::Right => Vector3::x(),
        Side::Outer if left_limb => -Vector3::x(),
        Side::Outer => Vector3::x(),
        Side::Inner if left_limb => Vector3::x(),
        Side::Inner => -Vector3::x(),
    }
}

/// The segments whose surfaces bound the shell or cylinder of a point on `s`.
fn group(s: Segment) -> Vec<Segment> {
    use Segment::*;
    match s {
        Pelvis | Torso => vec![Pelvis, Torso],
        Head => vec![Head, Neck],
        other => vec![other],
    }
}

/// Where a panel goes: the arrangement point and the pattern's anchor.
#[derive(Clone, Copy, Debug)]
pub struct Arrangement {
    /// Segment and side.
    pub segment: Segment,
    pub side: Side,
    /// Distance kept from the body surface (m).
    pub clearance: f64,
    /// Pattern point on the arrangement point.
    pub anchor: [f64; 2],
    /// Axial position of the anchor up the segment from its proximal joint (m).
    pub along: f64,
    /// Extra turn about the axis (degrees).
    pub turn_deg: f64,
}

/// The elliptic-cylinder placement of a panel whose pattern spans `v_range` at arrangement
/// `arr` on mannequin `body`, whose segments sit at `placements` (local → world, one per
/// [`SEGMENTS`] entry, as from [`Mannequin::placements`]).
pub fn wrap(body: &Mannequin, placements: &[Isometry3<f64>], arr: &Arrangement, v_range: (f64, f64)) -> Placement {
    let seg = &body.segments[arr.segment.index()];
    let up = if seg.axis.z < 0.0 { -seg.axis } else { seg.axis };
    let side = side_direction(arr.segment, arr.side);
    // Ellipse axes: the side itself for a limb; for a shell the body direction (x or y) of
    // the side, so the ellipse keeps the body's breadth and depth.
    let e1 = (side - up * up.dot(&side)).normalize();
    let e2 = up.cross(&e1);
    // Surface vertices of the group in this segment's rest frame, within the axial range.
    let t_lo = arr.along + v_range.0 - arr.anchor[1];
    let t_hi = arr.along + v_range.1 - arr.anchor[1];
    // The surface's part within the slab t_lo ≤ t ≤ t_hi is bounded by the vertices inside
    // it and the points where triangle edges cross its two planes: the radius (a norm of the
    // point's components across the axis) is convex, so its maximum over each clipped
    // triangle lies at one of these points.
    let to_local = seg.rest.inverse();
    let mut all = Vec::new();
    let mut within = Vec::new();
    for g in group(arr.segment) {
        let other = &body.segments[g.index()];
        let m = to_local * other.rest;
        let v: Vec<Point3<f64>> = other.surface.vertices.iter().map(|v| m * v).collect();
        let t = |p: &Point3<f64>| p.coords.dot(&up);
        within.extend(v.iter().copied().filter(|p| (t_lo..=t_hi).contains(&t(p))));
        for tri in &other.surface.triangles {
            for k in 0..3 {
                let (p, q) = (v[tri[k] as usize], v[tri[(k + 1) % 3] as usize]);
                for plane in [t_lo, t_hi] {
                    let (dp, dq) = (t(&p) - plane, t(&q) - plane);
                    if dp * dq < 0.0 {
                        within.push(p + (q - p) * (dp / (dp - dq)));
                    }
                }
            }
        }
        all.extend(v);
    }
    let pts = if within.is_empty() { all } else { within };
    let comps: Vec<(f64, f64)> = pts.iter().map(|p| (p.coords.dot(&e1), p.coords.dot(&e2))).collect();
    let (centre, semi) = match template(arr.segment) {
        Some(Template::Limb) | None => {
            let r = comps.iter().map(|(a, b)| a.hypot(*b)).fold(0.0, f64::max);
            ((0.0, 0.0), (r + arr.clearance, r + arr.clearance))
        }
        Some(Template::Shell) => {
            let range = |f: &dyn Fn(&(f64, f64)) -> f64| comps.iter().map(f).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| (lo.min(x), hi.max(x)));
            let (lo1, hi1) = range(&|c| c.0);
            let (lo2, hi2) = range(&|c| c.1);
            let c = (0.5 * (lo1 + hi1), 0.5 * (lo2 + hi2));
            let (a0, b0) = ((0.5 * (hi1 - lo1)).max(1e-6), (0.5 * (hi2 - lo2)).max(1e-6));
            let k = comps.iter().map(|(x, y)| ((x - c.0) / a0).hypot((y - c.1) / b0)).fold(1.0, f64::max);
            (c, (k * a0 + arr.clearance, k * b0 + arr.clearance))
        }
    };
    // The turn moves the anchor along the ellipse: the point at polar angle θ has the
    // parameter t = atan2(a sin θ, b cos θ).
    let th = arr.turn_deg.to_radians();
    let t = (semi.0 * th.sin()).atan2(semi.1 * th.cos()) + 2.0 * std::f64::consts::PI * (th / (2.0 * std::f64::consts::PI)).round();
    let shift = ellipse_arc(semi.0, semi.1, t);
    let origin_local = Point3::from(up * arr.along + e1 * centre.0 + e2 * centre.1);
    let world = placements[arr.segment.index()];
    let o = world * origin_local;
    let a = world.rotation * up;
    let s = world.rotation * e1;
    Placement::EllipticCylinder { origin: [o.x, o.y, o.z], axis: [a.x, a.y, a.z], side: [s.x, s.y, s.z], semi_axes: [semi.0, semi.1], anchor: [arr.anchor[0] - shift, arr.anchor[1]] }
}

/// A mannequin contact body: the mannequin and its segments' placements in the scene.
type Posed = (Mannequin, Vec<Isometry3<f64>>);

/// Loads mannequin body `b` (measurements; pose, or the motion's first frame) and places its
/// segments in the scene (pose, then the body's rotation and translation).
fn posed(b: &BodySpec, base_dir: &Path) -> Result<Option<Posed>, (String, String)> {
    let ShapeSpec::Mannequin { measurements, pose, motion } = &b.shape else { return Ok(None) };
    let err = |key: &str, e: SceneError| (key.to_string(), e.to_string());
    let m = mannequin::load_measurements(&base_dir.join(measurements)).map_err(|e| err("measurements", e))?;
    let pose = match (motion, pose) {
        (Some(mv), _) => mannequin::load_motion(&base_dir.join(mv)).map_err(|e| err("motion", e))?.frames.first().map(|f| f.2.clone()).unwrap_or_default(),
        (None, Some(p)) => mannequin::load_pose(&base_dir.join(p)).map_err(|e| err("pose", e))?,
        (None, None) => Pose::default(),
    };
    let body = Mannequin::new(&m);
    let rv = Vector3::from(b.rotation).map(f64::to_radians);
    let iso = Isometry3::from_parts(Translation3::from(Vector3::from(b.translation)), UnitQuaternion::from_scaled_axis(rv));
    let placements = body.placements(&pose).into_iter().map(|p| iso * p).collect();
    Ok(Some((body, placements)))
}

/// Replaces every `Around` placement of `spec` by its elliptic cylinder (see [`wrap`]).
/// Errors, located at the panel's placement: no contact body of that name, a body that is
/// not a mannequin (or whose files fail), an unknown arrangement point, a negative or
/// non-finite clearance, anchor, along or turn.
pub fn resolve(spec: &mut GarmentSpec, contact: Option<&ContactSpec>, base_dir: &Path, loc: &Locator) -> Result<(), SceneError> {
    let mut bodies: BTreeMap<String, Posed> = BTreeMap::new();
    for panel in &mut spec.panels {
        let Placement::Around { body, point, clearance, anchor, along, turn_deg } = &panel.placement else { continue };
        let field = |key: &str| format!("garment.panels[{}].placement.{key}", panel.name);
        let (segment, side) = parse_point(point).map_err(|m| loc.at_value(&panel.name, point, field("point"), m))?;
        if !(clearance.is_finite() && (0.0..=1.0).contains(clearance)) {
            return Err(loc.at(Some(&panel.name), Some("clearance"), field("clearance"), format!("expected a clearance from the body between 0 and 1 m, found {clearance}")));
        }
        let bound = super::graph::MAX_COORDINATE;
        if !anchor.iter().chain([along]).all(|v| v.abs() <= bound) || !(turn_deg.abs() <= 3600.0) {
            return Err(loc.at(Some(&panel.name), Some("anchor"), field("anchor"), format!("expected an anchor and along within ±{bound} m and turn_deg within ±3600°")));
        }
        if !bodies.contains_key(body) {
            let bodies_spec = contact.map(|c| c.bodies.as_slice()).unwrap_or_default();
            let mannequins: Vec<&str> = bodies_spec.iter().filter(|b| matches!(b.shape, ShapeSpec::Mannequin { .. })).map(|b| b.name.as_str()).collect();
            let b = bodies_spec.iter().find(|b| &b.name == body).ok_or_else(|| {
                loc.at_value(&panel.name, body, field("body"), format!("no contact body named \"{body}\"; mannequin bodies: {}", if mannequins.is_empty() { "none".to_string() } else { mannequins.join(", ") }))
            })?;
            let p = posed(b, base_dir)
                .map_err(|(key, m)| loc.at_value(&panel.name, body, field("body"), format!("contact body \"{body}\": {key}: {m}")))?
                .ok_or_else(|| loc.at_value(&panel.name, body, field("body"), format!("contact body \"{body}\" is not a Mannequin; arrangement points need one (mannequin bodies: {})", if mannequins.is_empty() { "none".to_string() } else { mannequins.join(", ") })))?;
            bodies.insert(body.clone(), p);
        }
        let Some((man, placements)) = bodies.get(body) else { continue };
        let arr = Arrangement { segment, side, clearance: *clearance, anchor: *anchor, along: *along, turn_deg: *turn_deg };
        panel.placement = wrap(man, placements, &arr, v_range(panel));
    }
    Ok(())
}

/// Range of the outline's v coordinates (0, 0 for an empty outline).
fn v_range(p: &PanelSpec) -> (f64, f64) {
    let (lo, hi) = p.outline.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), q| (lo.min(q[1]), hi.max(q[1])));
    if lo.is_finite() { (lo, hi) } else { (0.0, 0.0) }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distance from `p` to triangle (a, b, c) (Ericson, Real-Time Collision Detection, §5.1.5).
    fn point_triangle(p: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>, c: &Point3<f64>) -> f64 {
        let (ab, ac, ap) = (b - a, c - a, p - a);
        let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
        if d1 <= 0.0 && d2 <= 0.0 {
            return ap.norm();
        }
        let bp = p - b;
        let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
        if d3 >= 0.0 && d4 <= d3 {
            return bp.norm();
        }
        let vc = d1 * d4 - d3 * d2;
        if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            return (p - (a + ab * (d1 / (d1 - d3)))).norm();
        }
        let cp = p - c;
        let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
        if d6 >= 0.0 && d5 <= d6 {
            return cp.norm();
        }
        let vb = d5 * d2 - d1 * d6;
        if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            return (p - (a + ac * (d2 / (d2 - d6)))).norm();
        }
        let va = d3 * d6 - d5 * d4;
        if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
            return (p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))))).norm();
        }
        let denom = 1.0 / (va + vb + vc);
        (p - (a + ab * (vb * denom) + ac * (vc * denom))).norm()
    }

    /// Distance from `p` (world) to the surface of segment `s` placed at `iso`, and whether
    /// `p` lies inside it (winding number).
    fn distance(body: &Mannequin, placements: &[Isometry3<f64>], s: Segment, p: &Point3<f64>) -> (f64, bool) {
        let seg = &body.segments[s.index()];
        let q = placements[s.index()].inverse() * p;
        let v = &seg.surface.vertices;
        let d = seg.surface.triangles.iter().map(|t| point_triangle(&q, &v[t[0] as usize], &v[t[1] as usize], &v[t[2] as usize])).fold(f64::INFINITY, f64::min);
        (d, seg.surface.winding_number(&q).abs() > 0.5)
    }

    /// A 0.16 × 0.3 m panel at each template's points: every node of a 2 cm grid lies
    /// outside every segment of the body, at no less than the clearance from the named
    /// segment's group (less 1 mm for the facets across the ring: the template contains the
    /// surface's vertices and edge crossings, and a facet lies inside their hull), and the closest
    /// node is within 15 mm of the clearance (the template hugs the body: a cylinder is
    /// exact at the limb's widest ring; the trunk's ellipse, grown to contain the
    /// superellipse sections (exponent 2.5, up to 7 % past their axes' ellipse), stands up to
    /// about 1 cm further off at the front and back).
    #[test]
    fn placed_panels_keep_the_clearance() {
        let body = Mannequin::default_size();
        let pose = Pose::default();
        let placements = body.placements(&pose);
        let clearance = 0.02;
        let outline = [(0.0, 0.0), (0.16, 0.0), (0.16, 0.3), (0.0, 0.3)];
        for (point, along, height) in [("thigh_l.front", -0.25, 0.3), ("shank_r.outer", -0.1, 0.3), ("upper_arm_l.outer", -0.2, 0.3), ("forearm_r.outer", -0.05, 0.3), ("torso.front", 0.0, 0.3), ("torso.back", 0.1, 0.3), ("pelvis.front", 0.05, 0.3), ("head.left", 0.1, 0.3), ("neck.back", 0.06, 0.05)] {
            let outline = [outline[0], outline[1], (0.16, height), (0.0, height)];
            let (segment, side) = parse_point(point).unwrap();
            let arr = Arrangement { segment, side, clearance, anchor: [0.08, 0.5 * height], along, turn_deg: 0.0 };
            let pl = wrap(&body, &placements, &arr, (0.0, height));
            assert!(pl.problem().is_none(), "{point}: {:?}", pl.problem());
            let mut closest = f64::INFINITY;
            for i in 0..=8 {
                for j in 0..=15 {
                    let uv = [outline[1].0 * i as f64 / 8.0, outline[2].1 * j as f64 / 15.0];
                    let x = Point3::from(pl.map(uv));
                    for s in SEGMENTS {
                        let (d, inside) = distance(&body, &placements, s, &x);
                        assert!(!inside, "{point}: node {uv:?} inside {}", s.name());
                        if group(segment).contains(&s) {
                            assert!(d > clearance - 1e-3, "{point}: node {uv:?} {d} m from {}", s.name());
                            closest = closest.min(d);
                        }
                    }
                }
            }
            assert!(closest < clearance + 0.015, "{point}: closest node {closest} m from the body");
            // The anchor lies on the point's side: its outward director points that way.
            let dir = pl.director(arr.anchor, 1e-7);
            assert!(dir.dot(&side_direction(segment, side)) > 0.95, "{point}: director {dir}");
        }
    }

    /// A panel placed on a posed limb follows it: with the left shoulder abducted 90°, the
    /// upper arm's cylinder axis is horizontal and the node at the anchor lies as far from
    /// the moved surface as at rest.
    #[test]
    fn placement_follows_the_pose() {
        let body = Mannequin::default_size();
        let mut pose = Pose::default();
        pose.angles_mut(mannequin::Joint::ShoulderL).abduction = 90.0;
        let rest = body.placements(&Pose::default());
        let posed = body.placements(&pose);
        let arr = Arrangement { segment: Segment::UpperArmL, side: Side::Front, clearance: 0.02, anchor: [0.0, 0.0], along: -0.15, turn_deg: 0.0 };
        let (Placement::EllipticCylinder { axis, .. }, p_rest, p_posed) = (wrap(&body, &posed, &arr, (-0.1, 0.1)), wrap(&body, &rest, &arr, (-0.1, 0.1)), wrap(&body, &posed, &arr, (-0.1, 0.1))) else { panic!() };
        assert!(axis[2].abs() < 1e-9 && axis[0] > 0.999, "{axis:?}");
        let d_rest = distance(&body, &rest, Segment::UpperArmL, &Point3::from(p_rest.map([0.0, 0.0]))).0;
        let d_posed = distance(&body, &posed, Segment::UpperArmL, &Point3::from(p_posed.map([0.0, 0.0]))).0;
        assert!((d_rest - d_posed).abs() < 1e-9, "{d_rest} vs {d_posed}");
    }

    #[test]
    fn bad_points_are_named() {
        assert!(parse_point("torso").unwrap_err().contains("torso.front"));
        assert!(parse_point("tigh_l.front").unwrap_err().contains("unknown segment \"tigh_l\""));
        assert!(parse_point("hand_l.front").unwrap_err().contains("no placement template"));
        assert!(parse_point("torso.outer").unwrap_err().contains("front, back, left or right"));
        assert!(parse_point("thigh_l.up").unwrap_err().contains("unknown side \"up\""));
        assert_eq!(parse_point("thigh_l.inner").unwrap(), (Segment::ThighL, Side::Inner));
    }
}
