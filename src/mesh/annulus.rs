//! Annular plate meshes: the slit annulus of the benchmark, full annuli (uniform or graded)
//! and ring meshes on given radii, with the ring radii focused on a circle (the Cusick disc
//! rim).

use super::generate::{count, edges, finish, positive, Grid, MAX_NODES};
use super::{MeshError, ShellMesh};
use nalgebra::Vector3;
use std::f64::consts::TAU;

/// Flat annular plate in the xy plane (centre at the origin, directors +z)
/// with `nr` radial and `ntheta` circumferential quads and a radial slit
/// along θ = 0: the nodes at θ = 0 and θ = 2π are distinct but at identical
/// positions. Requires `0 < ri < ro` and `ntheta >= 3`.
///
/// Edges: `"inner"`, `"outer"` (ordered by increasing θ, both slit nodes
/// included), `"slit_start"` (θ = 0) and `"slit_end"` (θ = 2π), each
/// ordered from `ri` to `ro`.
pub fn slit_annulus(ri: f64, ro: f64, nr: usize, ntheta: usize) -> Result<ShellMesh, MeshError> {
    positive("ri", ri)?;
    positive("ro", ro)?;
    if ro <= ri {
        return Err(MeshError::Invalid(format!(
            "ro ({ro}) must be greater than ri ({ri})"
        )));
    }
    count("nr", nr, 1)?;
    count("ntheta", ntheta, 3)?;
    let g = Grid::new(nr, ntheta, false)?;
    let mut m = g.build(|i, j| {
        let r = if i == nr {
            ro
        } else {
            ri + (ro - ri) * i as f64 / nr as f64
        };
        // θ = 2π is placed exactly on the θ = 0 nodes.
        let t = if j == ntheta {
            0.0
        } else {
            TAU * j as f64 / ntheta as f64
        };
        let (s, c) = t.sin_cos();
        (Vector3::new(r * c, r * s, 0.0), Vector3::z())
    })?;
    m.edges = edges(vec![
        ("inner", g.row_v(0)),
        ("outer", g.row_v(nr)),
        ("slit_start", g.row_u(0)),
        ("slit_end", g.row_u(ntheta)),
    ]);
    finish("slit_annulus", "check the parameters", m)
}

/// Full flat annulus (closed in θ) with `nr x ntheta` quads, for circular specimens
/// such as the Cusick drape test: inner radius `ri`, outer `ro`, node
/// `(r cos θ, r sin θ, 0)`, director +z. With `graded` the radii grow
/// geometrically, r_i = ri (ro/ri)^(i/nr), so that every ring of elements has the same
/// radial-to-circumferential aspect ratio (near square when nr ≈ ln(ro/ri)/(2π/ntheta));
/// otherwise they are uniform. Edges `"inner"`, `"outer"` (ordered by increasing θ).
pub fn annulus(ri: f64, ro: f64, nr: usize, ntheta: usize, graded: bool) -> Result<ShellMesh, MeshError> {
    positive("ri", ri)?;
    positive("ro", ro)?;
    if ro <= ri {
        return Err(MeshError::Invalid(format!("ro ({ro}) must be greater than ri ({ri})")));
    }
    count("nr", nr, 1)?;
    let radii: Vec<f64> = (0..=nr)
        .map(|i| {
            let f = i as f64 / nr as f64;
            if i == nr {
                ro
            } else if graded {
                ri * (ro / ri).powf(f)
            } else {
                ri + (ro - ri) * f
            }
        })
        .collect();
    annulus_rings(&radii, ntheta)
}

/// Full flat annulus (closed in θ) whose rings of nodes lie at the given `radii` (strictly
/// increasing, first > 0), with `ntheta` sectors: node `(r cos θ, r sin θ, 0)`, director +z.
/// Lets a mesh be fine only where the solution needs it (e.g. a Cusick specimen's overhang
/// and the support disc's rim) and coarse where the specimen is held flat. Edges `"inner"`,
/// `"outer"` (ordered by increasing θ).
pub fn annulus_rings(radii: &[f64], ntheta: usize) -> Result<ShellMesh, MeshError> {
    if radii.len() < 2 {
        return Err(MeshError::Invalid(format!("radii must list at least 2 ring radii, got {}", radii.len())));
    }
    positive("radii[0]", radii[0])?;
    for (i, w) in radii.windows(2).enumerate() {
        if !(w[1].is_finite() && w[1] > w[0]) {
            return Err(MeshError::Invalid(format!(
                "radii must be finite and strictly increasing: radii[{}] = {} follows radii[{i}] = {}",
                i + 1,
                w[1],
                w[0]
            )));
        }
    }
    count("ntheta", ntheta, 3)?;
    let nr = radii.len() - 1;
    let g = Grid::new(nr, ntheta, true)?;
    let mut m = g.build(|i, j| {
        let r = radii[i];
        let (s, c) = (TAU * j as f64 / ntheta as f64).sin_cos();
        (Vector3::new(r * c, r * s, 0.0), Vector3::z())
    })?;
    m.edges = edges(vec![("inner", g.row_v(0)), ("outer", g.row_v(nr))]);
    finish("annulus", "check the parameters", m)
}

/// Ring radii from `ri` to `ro` for an annulus of `ntheta` sectors refined toward the circle
/// r = `focus` (e.g. a support disc's rim, where a drape bends over a rounded edge):
/// marched outward from ri with the radial step
/// dr(r) = min(cap(r), w·focus/`refine` + ¼|r − focus|), w = 2π/ntheta,
/// so the step at the focus is `refine` times finer than the circumferential width there,
/// and away from it grows by at most ~25 % per ring up to cap(r) = `inner_aspect`·w·r inside
/// the focus and w·r outside it (near-square elements). Rings beyond focus + 10 % of
/// (ro − focus)... are stretched uniformly so the last lands on ro. Every step scales with w,
/// so the family refines uniformly with ntheta.
pub fn focused_rings(ri: f64, ro: f64, ntheta: usize, focus: f64, refine: f64, inner_aspect: f64) -> Result<Vec<f64>, MeshError> {
    positive("ri", ri)?;
    positive("ro", ro)?;
    if ro <= ri {
        return Err(MeshError::Invalid(format!("ro ({ro}) must be greater than ri ({ri})")));
    }
    if !(focus.is_finite() && focus > ri && focus < ro) {
        return Err(MeshError::Invalid(format!("focus ({focus}) must lie between ri ({ri}) and ro ({ro})")));
    }
    if !(refine.is_finite() && refine >= 1.0) {
        return Err(MeshError::Invalid(format!("refine must be a finite number ≥ 1, got {refine}")));
    }
    if !(inner_aspect.is_finite() && inner_aspect >= 1.0) {
        return Err(MeshError::Invalid(format!("inner_aspect must be a finite number ≥ 1, got {inner_aspect}")));
    }
    count("ntheta", ntheta, 3)?;
    let w = TAU / ntheta as f64;
    let step = |r: f64| {
        let cap = if r < focus { inner_aspect * w * r } else { w * r };
        cap.min(w * focus / refine + 0.25 * (r - focus).abs())
    };
    // Every step is at least w·focus/refine > 0, so the march ends; a ring count that would
    // make more than MAX_NODES nodes is refused as soon as it is reached.
    let max_rings = MAX_NODES / ntheta;
    let mut radii = vec![ri];
    let mut r = ri;
    while r < ro {
        let dr = step(r);
        if !(dr > 0.0 && dr.is_finite()) || radii.len() >= max_rings {
            return Err(MeshError::Invalid(format!(
                "focused_rings: more than {max_rings} rings of {ntheta} sectors would exceed {MAX_NODES} nodes; use fewer sectors (ntheta) or a smaller refine"
            )));
        }
        r += dr;
        radii.push(r);
    }
    // Snap the last ring to ro: drop it if it overshoots by more than half a step, then
    // stretch the rings beyond the refined zone.
    let anchor = focus + (ro - focus) / 6.0;
    let k = radii.len() - 1;
    if radii[k - 1] > anchor && radii[k] - ro > 0.5 * (radii[k] - radii[k - 1]) {
        radii.pop();
    }
    let end = radii[radii.len() - 1];
    for r in radii.iter_mut().filter(|r| **r > anchor) {
        *r = anchor + (*r - anchor) * (ro - anchor) / (end - anchor);
    }
    Ok(radii)
}

/// Ring radii from `ri` to `ro` following a radial size field `size(r)` (m, positive):
/// the rings equidistribute ∫ dr / size(r) (de Boor's equidistribution, *A Practical Guide
/// to Splines*, 1978, ch. XII): with N = ⌈∫_ri^ro dr / size⌉ rings of elements, ring i lies
/// where the integral reaches i/N of its total, so every radial step is at most the local
/// size (to the variation of the field over one step) and ri and ro are rings exactly. The
/// integral is taken by the midpoint rule on 64 cells per smallest sampled size (at least
/// 4096 cells). Errors: a size that is not a positive finite number, or more than
/// `max_rings` rings.
pub fn sized_rings(ri: f64, ro: f64, size: &dyn Fn(f64) -> f64, max_rings: usize) -> Result<Vec<f64>, MeshError> {
    positive("ri", ri)?;
    positive("ro", ro)?;
    if ro <= ri {
        return Err(MeshError::Invalid(format!("ro ({ro}) must be greater than ri ({ri})")));
    }
    // A first pass at 4096 cells finds the smallest size; the integral then resolves it.
    let probe = 4096usize;
    let mut h_min = f64::INFINITY;
    for k in 0..probe {
        let r = ri + (ro - ri) * (k as f64 + 0.5) / probe as f64;
        let h = size(r);
        if !(h.is_finite() && h > 0.0) {
            return Err(MeshError::Invalid(format!("the element size at r = {r} is {h}; expected a positive length")));
        }
        h_min = h_min.min(h);
    }
    let cells = ((64.0 * (ro - ri) / h_min).ceil() as usize).clamp(probe, 1 << 22);
    let dr = (ro - ri) / cells as f64;
    let mut cumulative = Vec::with_capacity(cells + 1);
    cumulative.push(0.0);
    for k in 0..cells {
        let h = size(ri + dr * (k as f64 + 0.5));
        if !(h.is_finite() && h > 0.0) {
            return Err(MeshError::Invalid(format!("the element size at r = {} is {h}; expected a positive length", ri + dr * (k as f64 + 0.5))));
        }
        let last = cumulative[k];
        cumulative.push(last + dr / h);
    }
    let total = cumulative[cells];
    let n = (total - 1e-9).ceil().max(1.0) as usize;
    if n > max_rings {
        return Err(MeshError::Invalid(format!("the element size asks for {n} rings of elements, more than the {max_rings} allowed")));
    }
    let mut radii = Vec::with_capacity(n + 1);
    radii.push(ri);
    let mut k = 0;
    for i in 1..n {
        let target = total * i as f64 / n as f64;
        while cumulative[k + 1] < target {
            k += 1;
        }
        let f = (target - cumulative[k]) / (cumulative[k + 1] - cumulative[k]);
        radii.push(ri + dr * (k as f64 + f));
    }
    radii.push(ro);
    Ok(radii)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::tests::counts;

    #[test]
    fn slit_annulus_edges_distinct_but_coincident() {
        let m = slit_annulus(6.0, 10.0, 4, 24).unwrap();
        counts(&m, 5 * 25, 4 * 24);
        let a = &m.edges["slit_start"];
        let b = &m.edges["slit_end"];
        assert_eq!(a.len(), 5);
        assert_eq!(b.len(), 5);
        for (&i, &j) in a.iter().zip(b) {
            assert_ne!(i, j);
            assert_eq!(m.nodes[i], m.nodes[j]);
            assert!(m.nodes[i].y == 0.0 && m.nodes[i].x > 0.0);
        }
        assert_eq!(m.nodes[a[0]].x, 6.0);
        assert_eq!(m.nodes[a[4]].x, 10.0);
        assert_eq!(m.nodes[b[0]].x, 6.0);
        assert!(a.iter().all(|i| !b.contains(i)));
        for &i in &m.edges["inner"] {
            assert!((m.nodes[i].norm() - 6.0).abs() < 1e-12);
        }
        for &i in &m.edges["outer"] {
            assert!((m.nodes[i].norm() - 10.0).abs() < 1e-12);
        }
        assert_eq!(m.edges["outer"].len(), 25);
        // no quad connects across the slit: the slit nodes are used by
        // quads of the first resp. last sector only
        for q in &m.quads {
            let has_a = q.iter().any(|i| a.contains(i));
            let has_b = q.iter().any(|i| b.contains(i));
            assert!(!(has_a && has_b));
        }
        assert!(
            slit_annulus(5.0, 5.0, 1, 8)
                .unwrap_err()
                .to_string()
                .contains("ro")
        );
        assert!(
            slit_annulus(0.0, 5.0, 1, 8)
                .unwrap_err()
                .to_string()
                .contains("ri")
        );
        assert!(
            slit_annulus(1.0, 5.0, 1, 2)
                .unwrap_err()
                .to_string()
                .contains("ntheta")
        );
        assert!(
            slit_annulus(1.0, 5.0, 0, 8)
                .unwrap_err()
                .to_string()
                .contains("nr")
        );
    }

    #[test]
    fn focused_rings_refine_at_the_focus_and_grade_smoothly() {
        let (n, k) = (96, 8.0);
        let w = TAU / n as f64;
        let r = focused_rings(0.02, 0.15, n, 0.09, k, 4.0).unwrap();
        assert_eq!(r[0], 0.02);
        assert!((r[r.len() - 1] - 0.15).abs() < 1e-15);
        // finest steps next to the focus: w·focus/k plus a quarter of the distance to it
        let fine = w * 0.09 / k;
        let (i, min) = r.windows(2).map(|s| s[1] - s[0]).enumerate().fold((0, f64::MAX), |a, (i, d)| if d < a.1 { (i, d) } else { a });
        assert!(min >= fine && min < 1.25 * fine && (r[i] - 0.09).abs() < 2.0 * fine, "{min} at {}", r[i]);
        for s in r.windows(3) {
            let (a, b) = (s[1] - s[0], s[2] - s[1]);
            assert!(a > 0.0 && b > 0.0);
            // grading: away from the focus a step grows by at most 25 % of itself (or by the
            // geometric ratio 1 + 4w of the capped rings between the discs), toward it it
            // shrinks by at most 25 % (ratio 4/3)
            assert!(b / a < 1.25f64.max(1.0 + 4.0 * w) + 0.01 && a / b < 1.34, "{s:?}");
        }
        // near-square over the overhang, 4 circumferential widths between the discs
        let last = r[r.len() - 1] - r[r.len() - 2];
        assert!((last / (w * r[r.len() - 2]) - 1.0).abs() < 0.1, "{last}");
        assert!((r[1] - r[0] - 4.0 * w * 0.02).abs() < 1e-15);
        // the family refines with ntheta: at twice the sectors every step stays below its cap
        // (∝ w) and the finest step halves
        let r2 = focused_rings(0.02, 0.15, 2 * n, 0.09, k, 4.0).unwrap();
        let w2 = 0.5 * w;
        for s in r2.windows(2) {
            let cap = if s[0] < 0.09 { 4.0 * w2 * s[0] } else { w2 * s[0] };
            assert!(s[1] - s[0] < 1.06 * cap, "{s:?}"); // the final stretch adds up to half a step over 50 mm
        }
        let min2 = r2.windows(2).map(|s| s[1] - s[0]).fold(f64::MAX, f64::min);
        assert!(min2 >= 0.5 * fine && min2 < 0.625 * fine, "{min2}");
        let m = annulus_rings(&r, n).unwrap();
        counts(&m, r.len() * n, (r.len() - 1) * n);
        for (bad, what) in [
            (focused_rings(0.02, 0.15, n, 0.2, k, 4.0), "focus"),
            (focused_rings(0.02, 0.15, n, 0.09, 0.5, 4.0), "refine"),
            (focused_rings(0.02, 0.15, n, 0.09, k, f64::NAN), "inner_aspect"),
            (focused_rings(0.02, 0.15, 2, 0.09, k, 4.0), "ntheta"),
        ] {
            assert!(bad.unwrap_err().to_string().contains(what), "{what}");
        }
        let e = annulus_rings(&[0.02, 0.05, 0.04], 8).unwrap_err().to_string();
        assert!(e.contains("radii[2]") && e.contains("increasing"), "{e}");
        assert!(annulus_rings(&[0.02], 8).unwrap_err().to_string().contains("at least 2"));
    }
    #[test]
    fn sized_rings_follow_the_size_field() {
        // A size growing linearly from 1 mm at r = 0.05 with slope 1/4: every step is at
        // most the size at its inner ring times 1 + 1/4 and at least 80 % of it.
        let size = |r: f64| 0.001 + 0.25 * (r - 0.05).abs();
        let r = sized_rings(0.02, 0.15, &size, 10_000).unwrap();
        assert_eq!(r[0], 0.02);
        assert_eq!(r[r.len() - 1], 0.15);
        for s in r.windows(2) {
            let d = s[1] - s[0];
            let (lo, hi) = (size(s[0]).min(size(s[1])), size(s[0]).max(size(s[1])));
            assert!(d > 0.8 * lo && d <= 1.001 * hi, "{s:?}: {d} against {lo}..{hi}");
        }
        // a uniform size that divides the length gives uniform rings
        let u = sized_rings(1.0, 2.0, &|_| 0.25, 100).unwrap();
        assert_eq!(u.len(), 5);
        assert!(u.windows(2).all(|s| (s[1] - s[0] - 0.25).abs() < 1e-9), "{u:?}");
        assert!(sized_rings(1.0, 2.0, &|_| 0.001, 100).unwrap_err().to_string().contains("rings of elements"));
        assert!(sized_rings(1.0, 2.0, &|_| f64::NAN, 100).unwrap_err().to_string().contains("element size"));
        assert!(sized_rings(2.0, 1.0, &|_| 0.1, 100).unwrap_err().to_string().contains("ro"));
    }
}
