//! Element size from the physics (`element_size: Auto((tolerance: ..))`): a size field per
//! panel, in pattern coordinates, from the fabric's own length scales.
//!
//! A bilinear element interpolates a shape f with an error of at most h² max|f''| / 8
//! (linear interpolation estimate, e.g. Ciarlet, *The Finite Element Method for Elliptic
//! Problems*, 1978, Thm 3.1.6 in one dimension). Every length scale ℓ of the drape turns that
//! into a size: a circle of radius ℓ, a decay exp(−s/ℓ) or a wave sin(s/ℓ) have
//! |f''| = |f| / ℓ², so a relative shape error `tolerance` asks for
//!
//!   h = √(8 · tolerance) · ℓ_min,   ℓ_min = min(ℓ_b, λ / 2π, R_body),
//!
//! with
//! - the **bending length** ℓ_b = (B / (ρ_A g))^{1/3} (Peirce 1930, "The handle of cloth",
//!   J. Text. Inst. 21, T377; the fold size of cloth under its own weight): B the sum of the
//!   panel's ply bending rigidities (plies free to slide — the lower bound, so that the mesh
//!   is the same for the laminate and the discrete ply model), ρ_A the sum of their areal
//!   densities;
//! - the **wrinkle wavelength** of Cerda & Mahadevan (PRL 90, 074302, 2003),
//!   λ = 2π (B / K)^{1/4}, K = T π² / L², i.e. λ = 2 √(π L) (B / T)^{1/4}, for a membrane
//!   tension T (N/m) acting over a length L: the given `tension` over the panel's extent, or,
//!   without one, the tension of the panel's own weight hanging over its extent L,
//!   T = ρ_A g L, which gives λ = 2 √π L^{1/4} ℓ_b^{3/4};
//! - the radius of curvature R_body of the contact body the panel lies on, where a body's
//!   surface is within 2 ℓ_b of the placed panel: from the turn θ of the body's outward
//!   normal (its distance gradient) over a tangential step δ ≤ ℓ_b, R = δ / tan θ
//!   ([`radius_from_normals`]; the radius of the offset surface through the panel), the
//!   smallest over the panel's outline and interior points;
//!
//! capped at a quarter of the panel's extent. Near seams and notches (ends of named edge
//! spans on a straight run of the outline, or at a reflex corner) the size drops to
//! `seam_factor` · h on the seam line or notch point and grows back linearly to h over the
//! band width max(ℓ_b, 2h), the length over which a seam's kink relaxes under gravity. A
//! mapped grid (convex four-sided panel) grades each direction by the refinements of the
//! sides it crosses; other panels sample their outline by the field and let the Delaunay
//! refinement grade inwards (`garment::mesh::mesh_polygon_graded`).

use super::graph::{sampled_outline, span_segments};
use super::spec::GarmentSpec;
pub use crate::sizing::{bending_length, radius_from_normals, size_from_scales, wrinkle_wavelength, AutoSize, ElementSize, LengthScales, G};


/// One refinement: the size falls to `h_near` on a polyline (seam span) or at a point
/// (notch), growing back linearly to the panel size over `band`.
#[derive(Clone, Debug)]
pub struct Refinement {
    /// Pattern-space polyline (one point for a notch).
    pub points: Vec<[f64; 2]>,
    /// Outline segment the refinement lies on (None for a notch).
    pub segment: Option<usize>,
    /// Size on the line.
    pub h_near: f64,
    /// Width of the graded band (m).
    pub band: f64,
}

/// A panel's element size as a function of pattern coordinates.
#[derive(Clone, Debug)]
pub struct SizeField {
    /// Size away from seams and notches (m).
    pub base: f64,
    /// Seam and notch refinements.
    pub refinements: Vec<Refinement>,
    /// The length scales of an automatic size (None for a fixed size).
    pub scales: Option<LengthScales>,
    /// A mapped grid samples the field across the panel, not only along its sides (a field
    /// sampled from a solution, `refine::garment`, whose refinements lie inside the panel;
    /// seam and notch refinements lie on the outline and grade from the sides).
    pub across: bool,
}

impl SizeField {
    /// A uniform size h.
    pub fn uniform(h: f64) -> Self {
        Self { base: h, refinements: Vec::new(), scales: None, across: false }
    }

    /// Size at pattern point `p`.
    pub fn at(&self, p: [f64; 2]) -> f64 {
        self.at_excluding(p, None)
    }

    /// Size at `p` ignoring the refinement of outline segment `skip` (a mapped grid grades
    /// each direction by the seams across it, not along it).
    pub fn at_excluding(&self, p: [f64; 2], skip: Option<usize>) -> f64 {
        let mut h = self.base;
        for r in self.refinements.iter().filter(|r| skip.is_none() || r.segment != skip) {
            let d = if r.points.len() == 1 {
                ((p[0] - r.points[0][0]).powi(2) + (p[1] - r.points[0][1]).powi(2)).sqrt()
            } else {
                r.points.windows(2).map(|w| super::mesh::point_segment_distance(p, w[0], w[1])).fold(f64::INFINITY, f64::min)
            };
            if d < r.band {
                h = h.min(r.h_near + (self.base - r.h_near) * d / r.band);
            }
        }
        h
    }

    /// The smallest size anywhere.
    pub fn min(&self) -> f64 {
        self.refinements.iter().map(|r| r.h_near).fold(self.base, f64::min)
    }
}

/// Inputs of an automatic size: per ply name its bending rigidity (N·m) and areal density
/// (kg/m²), and the radius of curvature of the bodies near a placed pattern point set.
pub struct PlyPhysics<'a> {
    /// Bending rigidity of a ply (by name), if known.
    pub bending: &'a dyn Fn(&str) -> Option<f64>,
    /// Areal density of a ply (by name), if known.
    pub density: &'a dyn Fn(&str) -> Option<f64>,
    /// Smallest radius of curvature of a contact body within `reach` of the placed points
    /// (None: no body near).
    pub body_radius: &'a dyn Fn(&[nalgebra::Vector3<f64>], f64, f64) -> Option<f64>,
}

/// Largest distance between two outline vertices' bounding-box corners (the panel's extent).
fn extent(outline: &[[f64; 2]]) -> f64 {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in outline {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (hi[0] - lo[0]).hypot(hi[1] - lo[1])
}

/// The size field of panel `pi` of `spec`: its own `element_size`, else the garment's. A
/// fixed size is uniform; `Auto` follows the module doc. Errors: (key, message) of a
/// missing bending rigidity or areal density, or of bad parameters.
pub fn panel_field(spec: &GarmentSpec, pi: usize, physics: &PlyPhysics) -> Result<SizeField, (&'static str, String)> {
    let p = &spec.panels[pi];
    let size = p.element_size.as_ref().unwrap_or(&spec.element_size);
    if let Some(e) = size.problem() {
        return Err(e);
    }
    let a = match size {
        ElementSize::Fixed(h) => return Ok(SizeField::uniform(*h)),
        ElementSize::Auto(a) => a,
    };
    let (mut b, mut rho) = (0.0, 0.0);
    for name in &p.plies {
        b += (physics.bending)(name).filter(|x| x.is_finite() && *x > 0.0).ok_or_else(|| ("tolerance", format!("Auto: ply \"{name}\" of panel \"{}\" has no bending rigidity", p.name)))?;
        rho += (physics.density)(name).filter(|x| x.is_finite() && *x > 0.0).ok_or_else(|| {
            ("tolerance", format!("Auto: ply \"{name}\" of panel \"{}\" has no areal density (give the ply an `areal_density`, a fabric material, or a Gravity load)", p.name))
        })?;
    }
    let l = extent(&p.outline);
    if !(l.is_finite() && l > 0.0) {
        return Err(("tolerance", format!("Auto: panel \"{}\" has no extent", p.name)));
    }
    let lb = bending_length(b, rho);
    let tension = a.tension.unwrap_or(rho * G * l);
    let mut scales = LengthScales { bending_length: lb, wrinkle_wavelength: wrinkle_wavelength(b, tension, l), body_radius: None };
    let coarse = size_from_scales(a.tolerance, &scales, l);
    // Body curvature: the placed outline sampled at the size so far.
    let (outline, _) = sampled_outline(p, coarse).map_err(|e| ("tolerance", e))?;
    let mut placed: Vec<nalgebra::Vector3<f64>> = outline.iter().map(|&q| p.placement.map(q)).collect();
    placed.extend(interior_samples(&outline, coarse).into_iter().map(|q| p.placement.map(q)));
    scales.body_radius = (physics.body_radius)(&placed, 2.0 * lb, lb);
    let h = size_from_scales(a.tolerance, &scales, l);
    let mut field = SizeField { base: h, refinements: Vec::new(), scales: Some(scales), across: false };
    if a.seam_factor < 1.0 {
        let h_near = a.seam_factor * h;
        let band = lb.max(2.0 * h);
        let (pts, ranges) = sampled_outline(p, h).map_err(|e| ("tolerance", e))?;
        let mut notch = Vec::new();
        for s in &spec.seams {
            for side in [&s.a, &s.b] {
                if side.panel != p.name {
                    continue;
                }
                let Some(span) = p.edges.get(&side.edge) else { continue };
                for seg in span_segments(p, span.from, span.to) {
                    let points: Vec<[f64; 2]> = ranges[seg].clone().chain(std::iter::once(ranges[seg].end % pts.len())).map(|k| pts[k % pts.len()]).collect();
                    field.refinements.push(Refinement { points, segment: Some(seg), h_near, band });
                }
                notch.push(span.from);
                notch.push(span.to);
            }
        }
        // Notches: span ends where the outline runs straight on (a mark within an edge, as
        // imported pattern notches are) or turns inwards (a reflex corner, where stress
        // concentrates); a seam's ends are such points too when they lie on a straight run.
        for span in p.edges.values() {
            notch.push(span.from);
            notch.push(span.to);
        }
        notch.sort_unstable();
        notch.dedup();
        let n = p.outline.len();
        for v in notch.into_iter().filter(|&v| v < n && is_notch(&p.outline, v)) {
            field.refinements.push(Refinement { points: vec![p.outline[v]], segment: None, h_near, band });
        }
    }
    Ok(field)
}

/// Whether outline vertex `v` (counter-clockwise outline) is a notch: the outline turns there
/// by less than 10° (a straight run) or turns clockwise (a reflex corner).
fn is_notch(o: &[[f64; 2]], v: usize) -> bool {
    let n = o.len();
    let (a, b, c) = (o[(v + n - 1) % n], o[v], o[(v + 1) % n]);
    let (d1, d2) = ([b[0] - a[0], b[1] - a[1]], [c[0] - b[0], c[1] - b[1]]);
    let cross = d1[0] * d2[1] - d1[1] * d2[0];
    let dot = d1[0] * d2[0] + d1[1] * d2[1];
    let turn = cross.atan2(dot);
    turn < 10f64.to_radians()
}

/// Grid points of spacing `h` inside an outline (for the body-curvature probe).
fn interior_samples(outline: &[[f64; 2]], h: f64) -> Vec<[f64; 2]> {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in outline {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let n = [((hi[0] - lo[0]) / h).ceil().min(200.0) as usize, ((hi[1] - lo[1]) / h).ceil().min(200.0) as usize];
    let mut out = Vec::new();
    for i in 0..=n[0] {
        for j in 0..=n[1] {
            let q = [lo[0] + (hi[0] - lo[0]) * i as f64 / n[0].max(1) as f64, lo[1] + (hi[1] - lo[1]) * j as f64 / n[1].max(1) as f64];
            if super::mesh::point_in_polygon(q, outline) {
                out.push(q);
            }
        }
    }
    out
}

