//! Drape measures of a draped circular specimen (Cusick test, BS 5058 / ISO 9073-9):
//! drape coefficient from the vertical shadow and fold count from the draped edge.

use nalgebra::Vector3;
use serde::Serialize;

use crate::model::{Model, State};

/// Drape measures of one state.
#[derive(Clone, Debug, Default, Serialize)]
pub struct DrapeReport {
    /// How the shadow area was computed.
    pub method: String,
    /// Raster cell size (m).
    pub resolution: f64,
    /// Vertical projection area of the deformed specimen (m²).
    pub shadow_area: f64,
    /// Support disc area (m²).
    pub disc_area: f64,
    /// Undeformed specimen area (m²).
    pub specimen_area: f64,
    /// DC = (A_shadow − A_disc)/(A_specimen − A_disc) × 100 %.
    pub drape_coefficient_percent: f64,
    /// Folds (nodes) counted on the draped edge.
    pub folds: usize,
    /// How folds were counted.
    pub fold_method: String,
    /// Harmonic with the largest amplitude in r(θ) of the draped edge (orders 2–15).
    pub dominant_harmonic: usize,
    /// Smallest and largest projected radius of the draped edge (m).
    pub edge_radius_range: [f64; 2],
    /// Largest penetration of the shell face into a body (m), from the contact evaluation.
    pub max_penetration: f64,
}

/// Most cells along a side of the shadow raster (16.8 M cells, 16 MB).
pub const MAX_RASTER_SIDE: usize = 4096;

/// The raster cell size used for a requested `res` over a half-width `extent`: `res`, or the
/// coarsest cell that keeps the raster within [`MAX_RASTER_SIDE`] cells a side.
pub fn raster_resolution(extent: f64, res: f64) -> f64 {
    res.max(2.0 * extent / MAX_RASTER_SIDE as f64)
}

/// Area of the vertical (xy) projection of the deformed mid-surface: every quad is split
/// into two triangles and a square raster of cell `res` about `center` is marked where the
/// cell centre falls in a projected triangle or in the support disc of radius `disc_radius`
/// (the apparatus' shadow includes the disc, so a specimen's central hole hidden on the disc
/// does not count as a gap). The error is O(perimeter·res).
///
/// The raster has at most [`MAX_RASTER_SIDE`]² cells: a finer `res` is coarsened to
/// [`raster_resolution`]; a non-finite or non-positive extent or resolution gives NaN.
pub fn shadow_area(model: &Model, state: &State, center: &Vector3<f64>, extent: f64, res: f64, disc_radius: f64) -> f64 {
    let res = raster_resolution(extent, res);
    if !(res.is_finite() && res > 0.0 && extent.is_finite() && extent > 0.0) {
        return f64::NAN;
    }
    let n = ((2.0 * extent / res).ceil() as usize).clamp(1, MAX_RASTER_SIDE);
    let origin = (center.x - extent, center.y - extent);
    let mut covered = vec![false; n * n];
    for j in 0..n {
        for i in 0..n {
            let (px, py) = (origin.0 + (i as f64 + 0.5) * res - center.x, origin.1 + (j as f64 + 0.5) * res - center.y);
            covered[j * n + i] = px * px + py * py <= disc_radius * disc_radius;
        }
    }
    let pos: Vec<Vector3<f64>> = (0..model.n_nodes()).map(|a| model.position(state, a)).collect();
    for el in &model.elements {
        let q = el.nodes.map(|a| pos[a]);
        for tri in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
            let (xs, ys) = (tri.map(|p| p.x), tri.map(|p| p.y));
            let lo_i = (((xs.iter().copied().fold(f64::INFINITY, f64::min) - origin.0) / res - 0.5).floor().max(0.0)) as usize;
            let hi_i = (((xs.iter().copied().fold(f64::NEG_INFINITY, f64::max) - origin.0) / res - 0.5).ceil().max(0.0) as usize).min(n.saturating_sub(1));
            let lo_j = (((ys.iter().copied().fold(f64::INFINITY, f64::min) - origin.1) / res - 0.5).floor().max(0.0)) as usize;
            let hi_j = (((ys.iter().copied().fold(f64::NEG_INFINITY, f64::max) - origin.1) / res - 0.5).ceil().max(0.0) as usize).min(n.saturating_sub(1));
            let area2 = (xs[1] - xs[0]) * (ys[2] - ys[0]) - (xs[2] - xs[0]) * (ys[1] - ys[0]);
            if area2.abs() < 1e-300 {
                continue;
            }
            for j in lo_j..=hi_j {
                let py = origin.1 + (j as f64 + 0.5) * res;
                for i in lo_i..=hi_i {
                    let px = origin.0 + (i as f64 + 0.5) * res;
                    let mut inside = true;
                    for k in 0..3 {
                        let (ax, ay, bx, by) = (xs[k], ys[k], xs[(k + 1) % 3], ys[(k + 1) % 3]);
                        let c = (bx - ax) * (py - ay) - (by - ay) * (px - ax);
                        if c * area2 < 0.0 {
                            inside = false;
                            break;
                        }
                    }
                    if inside {
                        covered[j * n + i] = true;
                    }
                }
            }
        }
    }
    covered.iter().filter(|&&c| c).count() as f64 * res * res
}

/// Fold count of the draped edge: the projected radius r(θ) of the specimen's edge nodes
/// (reference radius ≥ (1 − 1e-6)·R), ordered by deformed polar angle, smoothed by a
/// 3-point circular moving average; a fold is a local maximum whose prominence (height
/// above the higher of the two neighbouring minima) exceeds 10 % of max r − min r and
/// 0.5 mm. Also returns the dominant Fourier harmonic (2–15) and the radius range.
pub fn folds(model: &Model, state: &State, center: &Vector3<f64>, specimen_radius: f64) -> (usize, usize, [f64; 2]) {
    let mut edge: Vec<(f64, f64)> = (0..model.n_nodes())
        .filter(|&a| {
            let d = model.x0[a] - center;
            (d.x * d.x + d.y * d.y).sqrt() >= (1.0 - 1e-6) * specimen_radius
        })
        .map(|a| {
            let p = model.position(state, a) - center;
            (p.y.atan2(p.x), (p.x * p.x + p.y * p.y).sqrt())
        })
        .collect();
    let m = edge.len();
    if m < 8 {
        return (0, 0, [0.0, 0.0]);
    }
    edge.sort_by(|a, b| a.0.total_cmp(&b.0));
    let r: Vec<f64> = (0..m).map(|i| (edge[(i + m - 1) % m].1 + edge[i].1 + edge[(i + 1) % m].1) / 3.0).collect();
    let (rmin, rmax) = r.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    let threshold = (0.1 * (rmax - rmin)).max(5e-4);
    let mut count = 0;
    for i in 0..m {
        let (prev, next) = (r[(i + m - 1) % m], r[(i + 1) % m]);
        if !(r[i] > prev && r[i] >= next) {
            continue;
        }
        // Walk both ways to the next higher point (or all the way round), tracking minima.
        let walk = |dir: isize| {
            let mut lo = r[i];
            for s in 1..m {
                let j = ((i as isize + dir * s as isize).rem_euclid(m as isize)) as usize;
                if r[j] > r[i] {
                    break;
                }
                lo = lo.min(r[j]);
            }
            lo
        };
        let prominence = r[i] - walk(-1).max(walk(1));
        if prominence >= threshold {
            count += 1;
        }
    }
    let mut best = (0.0, 0);
    for k in 2..=15 {
        let (mut c, mut s) = (0.0, 0.0);
        for (th, rr) in &edge {
            c += rr * (k as f64 * th).cos();
            s += rr * (k as f64 * th).sin();
        }
        let amp = (c * c + s * s).sqrt();
        if amp > best.0 {
            best = (amp, k);
        }
    }
    (count, best.1, [rmin, rmax])
}

/// The drape report of `state` for a specimen of radius `specimen_radius` on a disc of
/// radius `disc_radius` centred at `center`, raster cell `res`.
pub fn drape_report(model: &Model, state: &State, center: &Vector3<f64>, disc_radius: f64, specimen_radius: f64, res: f64, max_penetration: f64) -> DrapeReport {
    let pi = std::f64::consts::PI;
    let res = raster_resolution(1.05 * specimen_radius, res);
    let shadow = shadow_area(model, state, center, 1.05 * specimen_radius, res, disc_radius);
    let disc = pi * disc_radius * disc_radius;
    let spec = pi * specimen_radius * specimen_radius;
    let (folds, harmonic, range) = folds(model, state, center, specimen_radius);
    DrapeReport {
        method: "raster of the projected deformed mid-surface triangles (cell-centre test)".into(),
        resolution: res,
        shadow_area: shadow,
        disc_area: disc,
        specimen_area: spec,
        drape_coefficient_percent: 100.0 * (shadow - disc) / (spec - disc),
        folds,
        fold_method: "peaks of the 3-point-smoothed edge radius r(θ) with prominence ≥ max(10 % of range, 0.5 mm)".into(),
        dominant_harmonic: harmonic,
        edge_radius_range: range,
        max_penetration,
    }
}

/// `model` with the seeded random field `rf` (see `solver::imperfection`, scaled so its
/// largest |w| over the nodes is `rf.amplitude`) seeded only outside the support of a Cusick
/// specimen: the field w is multiplied by the taper s(r) = 3t² − 2t³, t = (r − r0)/(r1 − r0)
/// clamped to [0, 1], of the horizontal distance r from `center`, so the part held on the
/// disc (r ≤ r0) stays flat between the discs and does not start inside them. Each node moves
/// by s w along its reference director and the director is turned by −∇(s w) = −(s ∇w +
/// w ∇s) (the perturbed surface's normal to first order, as for the untapered field).
pub fn seed_outside_support(model: &Model, rf: &crate::solver::imperfection::RandomField, center: &Vector3<f64>, r0: f64, r1: f64) -> Model {
    let full = crate::solver::imperfection::seed_random_field(model, rf);
    let mut m = model.clone();
    let width = (r1 - r0).max(1e-12);
    for n in 0..model.n_nodes() {
        let fr = model.frames0[n];
        let w = (full.x0[n] - model.x0[n]).dot(&fr.d);
        // Tilt of the full field, (−∇w·t1, −∇w·t2).
        let dd = full.frames0[n].d - fr.d;
        let mut rel = model.x0[n] - center;
        rel.z = 0.0;
        let r = rel.norm();
        let t = ((r - r0) / width).clamp(0.0, 1.0);
        let s = t * t * (3.0 - 2.0 * t);
        let ds = if r > 0.0 { 6.0 * t * (1.0 - t) / width } else { 0.0 };
        let grad_s = if r > 0.0 { rel * (ds / r) } else { Vector3::zeros() };
        m.x0[n] = model.x0[n] + fr.d * (s * w);
        let tilt = [s * dd.dot(&fr.t1) - w * grad_s.dot(&fr.t1), s * dd.dot(&fr.t2) - w * grad_s.dot(&fr.t2)];
        m.frames0[n] = fr.tilted(tilt);
    }
    m
}
