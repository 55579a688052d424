//! A pseudo-transient (Dynamic) step that reaches a saddle leaves it along the unstable mode
//! (src/solver/dynamics.rs, "Leaving a saddle"): the perfect simply supported square plate of
//! garments/benchmarks/plate_postbuckling.ron (a = b = 1, t = 0.01, E = 1e7, ν = 0.3,
//! N_cr = 4π²D/a² = 36.1528 per unit length) compressed at once to 1.5 N_cr.

use plyshell::bench::{scenes, solve_variant};

/// The in-plane load has no out-of-plane component, so the flat plate is an exact
/// equilibrium — past N_cr a saddle — that no round-off would ever leave. The Dynamic step
/// reaches it at rest, finds it unstable and must leave it along mode (1, 1), with
///   ρ_A ω² = π²(N_cr − N)   (m = n = 1, a = b = 1; Leissa, *Vibration of Plates*, NASA SP-160,
///   1969, §4.2: ρ_A ω² = Dπ⁴(m²/a² + n²/b²)² − N_x π² m²/a²),
/// N_cr the mesh's own critical load (the buckling eigenvalue of the seeded reference run,
/// 1.003 N_cr): the ω² of the move within 2 % (lumped mass). It then comes to rest at a stable
/// state (positive definite tangent) whose centre deflection equals, within 1 %, that of the
/// load-controlled static path of the plate seeded with its first mode at 10⁻⁴ t (the
/// imperfection changes the post-buckled deflection by O(10⁻⁴ t), 0.01 % of it).
#[test]
fn perfect_plate_past_buckling_leaves_the_flat_saddle() {
    let reference = solve_variant(
        scenes::PLATE_POSTBUCKLING,
        "plate_postbuckling_reference",
        &[("amplitude: 1.0e-4", "amplitude: 1.0e-6".to_string())],
    )
    .expect("seeded static reference");
    assert_eq!(reference.status, "completed");
    let lambda_cr = reference.imperfection_buckling.as_ref().expect("buckling").eigenvalues[0];
    let w_ref = reference.monitors[0].values.last().expect("centre")[0];
    let dynamic = solve_variant(
        scenes::PLATE_POSTBUCKLING,
        "plate_postbuckling_dynamic",
        &[
            ("    imperfection: Some(BucklingModes(scale: {\"compression\": 1.0}, modes: [(mode: 1, amplitude: 1.0e-4)])),\n", String::new()),
            ("thickness: 0.01)", "thickness: 0.01, areal_density: 1.0)".to_string()),
            (
                "steps: [(name: \"compress\", increments: 30, scale: {\"compression\": 1.5}, automatic_increments: false)]",
                "steps: [(name: \"compress\", increments: 1, scale: {\"compression\": 1.5}, kind: Dynamic((dt: 1e-3, dt_max: 1.0, mass_damping: 40.0, max_steps: 2000)))]".to_string(),
            ),
        ],
    )
    .expect("dynamic step");
    assert_eq!(dynamic.status, "completed");
    let last = dynamic.increments.last().and_then(|r| r.dynamics.clone()).expect("dynamics");
    assert!(last.at_rest, "not at rest");
    assert!(last.saddle_escapes >= 1, "no saddle left");
    let (omega2, move_size) = dynamic.increments.iter().find_map(|r| r.dynamics.as_ref().and_then(|d| d.saddle)).expect("saddle event");
    let expected = std::f64::consts::PI.powi(2) * 36.1528 * (lambda_cr - 1.5) / 1.0;
    let w = dynamic.monitors[0].values.last().expect("centre")[0];
    eprintln!(
        "saddle: ω² = {omega2:.2} (expected {expected:.2}), move {move_size:.3e}; w_c = {w:.5} vs static seeded {w_ref:.5}; {} time steps, {} Newton iterations, {} escapes",
        dynamic.increments.len(),
        dynamic.newton_iterations,
        last.saddle_escapes
    );
    assert!((omega2 / expected - 1.0).abs() < 0.02, "ω² = {omega2}, expected {expected}");
    assert!((w.abs() / w_ref.abs() - 1.0).abs() < 0.01, "centre deflection {w} vs {w_ref}");
}
