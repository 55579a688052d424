//! Thin limit, thickness/length = 1e-4 (fabric-like): no shear locking with either MITC4 or
//! SRI. The cantilevers keep M/M0 and P L²/EI of Sze et al. (2004); the clamped plate is
//! compared with the Kirchhoff solution (Timoshenko & Woinowsky-Krieger, Table 35).

use plyshell::bench::{self, Material};

/// End-moment roll-up (Sze et al. 2004 §3.2) at h/L = 1e-4 on 16×1: tip within 1 % of the
/// analytic circle at all 20 levels, MITC4 and SRI.
#[test]
fn end_moment_cantilever_at_thickness_ratio_1e_4() {
    for sri in [false, true] {
        let c = bench::end_moment(16, 12.0e-4, Material::Svk, sri).expect("solve");
        assert_eq!(c.points.len(), 20);
        for p in &c.points {
            assert!(p.rel_error() < 0.01, "sri = {sri} at M/Mmax = {}: {:?} vs {:?}", p.level, p.computed, p.reference);
        }
    }
}

#[test]
fn end_shear_cantilever_at_thickness_ratio_1e_4() {
    for sri in [false, true] {
        let c = bench::end_shear(16, 10.0e-4, Material::Svk, sri).expect("solve");
        assert_eq!(c.points.len(), 20);
        for p in &c.points {
            assert!(p.rel_error() < 0.015, "sri = {sri} at P/Pmax = {}: {:?} vs {:?}", p.level, p.computed, p.reference);
        }
    }
}

/// Clamped square plate, t/a = 1e-4, uniform pressure, 16×16 quarter: centre deflection
/// within 1 % of 0.00126532 q a⁴/D.
#[test]
fn clamped_plate_at_thickness_ratio_1e_4() {
    for sri in [false, true] {
        let (w, reference, _, _) = bench::clamped_plate(16, 1e-4, sri).expect("solve");
        let err = (w - reference).abs() / reference;
        assert!(err < 0.01, "sri = {sri}: w = {w:e}, Kirchhoff {reference:e}, error {err:.4}");
    }
}
