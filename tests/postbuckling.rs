//! Post-buckling of the simply supported square plate (garments/benchmarks/
//! plate_postbuckling.ron): a = b = 1, t = 0.01, uniform edge compression to 1.5 N_cr under
//! load control, 30 increments of 0.05 N_cr.

use plyshell::bench;

/// Seeded with its first buckling mode at 1 % of the thickness (w₀ = 1e-4 at the centre),
/// the plate follows the stable post-buckling path past N_cr with every increment converged
/// and a positive definite tangent throughout (0 negative pivots, no stability event): the
/// symmetric bifurcation of a plate is stable (Koiter 1945), so the imperfect path has no
/// critical point. Below N_cr the added centre deflection follows the classical
/// amplification w₀ r/(1 − r), r = N/N_cr (Timoshenko & Gere 1961, §9.7, exact for a
/// mode-shaped imperfection in linear theory) within 2 % for r ≤ 0.5, with N_cr the
/// computed eigenvalue; past N_cr it grows monotonically to more than the thickness.
#[test]
fn seeded_plate_follows_a_stable_post_buckling_path() {
    let (s, w) = bench::plate_postbuckling(true).expect("solve");
    assert_eq!(s.status, "completed");
    assert_eq!(s.increments.len(), 30);
    let ncr_factor = s.imperfection_buckling.as_ref().expect("seeding buckling").eigenvalues[0];
    let centre = &s.monitors[0].values;
    let mut last = 0.0;
    for (inc, v) in s.increments.iter().zip(centre) {
        assert_eq!(inc.negative_pivots, Some(0), "at N/N_nominal = {}", inc.scales[0]);
        assert!(inc.stability_event.is_none());
        let r = inc.scales[0] / ncr_factor;
        let dw = v[0];
        assert!(dw > last, "centre deflection not increasing at r = {r}");
        last = dw;
        if r <= 0.5 {
            let expected = 1e-4 * r / (1.0 - r);
            assert!((dw / expected - 1.0).abs() < 0.02, "r = {r}: Δw = {dw:e}, amplification {expected:e}");
        }
    }
    assert!(s.stability_events.is_empty());
    assert!(last > 0.01, "centre deflection at 1.5 N_cr: {last}");
    eprintln!("seeded plate: {} increments, {} Newton iterations, {w:.2} s, w_c(1.5 N_cr) = {last:.5} = {:.2} t", s.increments.len(), s.newton_iterations, last / 0.01);
}

/// The perfect plate stays flat under load control (the in-plane load has no out-of-plane
/// component), so past N_cr it sits on the unstable fundamental path: the negative-pivot
/// count is 0 up to N_cr (the computed λ_cr = 1.003 N_cr of the 16×16 mesh), exactly 1 from
/// the first increment past it up to 1.5 N_cr (below the second critical load, 1.56 N_cr),
/// and summary.json flags a bifurcation (pivot count change without a sign change of the
/// stiffness parameter, the mode being orthogonal to the load) at that increment.
#[test]
fn perfect_plate_reports_the_bifurcation_by_its_negative_pivot() {
    let (s, w) = bench::plate_postbuckling(false).expect("solve");
    assert_eq!(s.status, "completed");
    for (inc, v) in s.increments.iter().zip(&s.monitors[0].values) {
        let expected = usize::from(inc.scales[0] > 1.003);
        assert_eq!(inc.negative_pivots, Some(expected), "at N/N_cr = {}", inc.scales[0]);
        assert!(v[0].abs() < 1e-12, "perfect plate left the flat path: w = {}", v[0]);
    }
    assert_eq!(s.stability_events.len(), 1, "{:?}", s.stability_events);
    let (i, ev) = &s.stability_events[0];
    assert!(ev.contains("bifurcation"), "{ev}");
    assert!((s.increments[*i].scales[0] - 1.05).abs() < 1e-9, "flagged at {}", s.increments[*i].scales[0]);
    eprintln!("perfect plate: {} increments, {} Newton iterations, {w:.2} s, event: {ev}", s.increments.len(), s.newton_iterations);
}
