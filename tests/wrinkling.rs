//! Wrinkling of a stretched sheet (Cerda & Mahadevan, Phys. Rev. Lett. 90, 074302, 2003;
//! numerical studies: Nayyar, Ravi-Chandar & Huang, IJSS 48, 2011; Healey, Li & Das,
//! J. Nonlinear Sci. 23, 2013). A neo-Hookean sheet clamped at both short ends and
//! stretched wrinkles in its middle; λ = (2π L t)^½ / [3(1−ν²)γ]^¼.

use std::time::Instant;

use plyshell::model::State;
use plyshell::scene;
use plyshell::solver::Solver;

const L: f64 = 254.0;
const W: f64 = 101.6;
const T: f64 = 0.1;
const NU: f64 = 0.49;

fn cerda_mahadevan_wavelength(gamma: f64) -> f64 {
    (2.0 * std::f64::consts::PI * L * T).sqrt() / (3.0 * (1.0 - NU * NU) * gamma).powf(0.25)
}

/// Out-of-plane position along the line x = `x` (nodes of that column, sorted by y).
fn profile(model: &plyshell::model::Model, state: &State, x: f64) -> Vec<(f64, f64)> {
    let mut p: Vec<(f64, f64)> = (0..model.n_nodes())
        .filter(|&n| (model.x0[n].x - x).abs() < 1e-6)
        .map(|n| (model.x0[n].y, model.position(state, n).z))
        .collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0));
    p
}

/// Wavelength from the zero crossings of the profile's interior (excluding a band `edge` at
/// each free edge): 2 × mean spacing of consecutive crossings; also the amplitude max|w|, the
/// ridge count and the number of interior crossings.
fn wrinkle_measures(p: &[(f64, f64)], edge: f64) -> (f64, f64, usize, usize) {
    let amp = p.iter().map(|v| v.1.abs()).fold(0.0, f64::max);
    let mut crossings = Vec::new();
    for w in p.windows(2) {
        let ((y0, z0), (y1, z1)) = (w[0], w[1]);
        if z0 * z1 < 0.0 {
            let y = y0 + (y1 - y0) * z0 / (z0 - z1);
            if y > edge && y < W - edge {
                crossings.push(y);
            }
        }
    }
    // Ridges: positive lobes of w(y) across the whole width whose peak exceeds 5 % of the amplitude.
    let mut crests = 0;
    let mut lobe_peak: f64 = 0.0;
    for &(_, z) in p.iter().chain(std::iter::once(&(W, -1.0))) {
        if z > 0.0 {
            lobe_peak = lobe_peak.max(z);
        } else {
            if lobe_peak > 0.05 * amp {
                crests += 1;
            }
            lobe_peak = 0.0;
        }
    }
    let lambda = if crossings.len() >= 2 { 2.0 * (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64 } else { f64::NAN };
    (lambda, amp, crests, crossings.len())
}

/// A neo-Hookean sheet (E = 1 MPa, ν = 0.49; L = 254 mm clamped length, W = 101.6 mm,
/// t = 0.1 mm: the example of the reference README, W/t = 1016) clamped at both short ends
/// and stretched to γ = 5 % and 10 %. Half model (symmetry at x = L/2), 32 × 48 MITC4
/// (Δy = 2.1 mm ≈ λ/10). Imperfection: seeded pseudo-random out-of-plane offsets uniform in
/// ±1e-3 t (±0.1 µm) per node, ramped linearly from 0 at the clamp to full at mid-length.
/// Each strain is reached by static Newton (4 increments; the flat branch is already an
/// unstable equilibrium there: the tangent is indefinite), then a Dynamic step holds the
/// strain and integrates to a *stable* rest (static tangent positive definite), which is the
/// wrinkled state. Measured along the mid-length line over the interior (5 mm from each free
/// edge): λ = 2 × mean spacing of the zero crossings of w(y). Asserts λ within 15 % of
/// Cerda–Mahadevan at both strains and a wrinkle amplitude above 100× the imperfection.
/// Mesh study (same run, other ny; wall times on 2 shared cores): ny = 24: no wrinkles at 5 %
/// (the coarse mesh's flat state is stable), +14.7 % at 10 %; ny = 48: +1.6 %, +7.0 %;
/// ny = 96: −0.7 %, +0.4 % (15 326 DOFs, 305 s).
#[test]
fn stretched_sheet_wrinkles_with_the_cerda_mahadevan_wavelength() {
    let (nx, ny, inc, amp0) = (32, 48, 4, 1e-3);
    let text = format!(
        r#"Scene(
        name: "wrinkling",
        materials: {{"rubber": NeoHookean(young: 1.0, poisson: {NU})}},
        parts: [(name: "sheet", mesh: Rectangle(lx: {hl}, ly: {W}, nx: {nx}, ny: {ny}), material: "rubber", thickness: {T}, areal_density: 1e-10)],
        node_sets: {{"clamp": Edge(part: "sheet", edge: "xmin"), "mid": Edge(part: "sheet", edge: "xmax")}},
        boundary: [Clamp(set: "clamp"), Symmetry(set: "mid", normal: X)],
        loads: {{"stretch": Displacement(set: "clamp", dof: Ux, value: {hl})}},
        steps: [
            (name: "to5", increments: {inc}, scale: {{"stretch": -0.05}}),
            (name: "settle5", kind: Dynamic((dt: 1e-3, dt_max: 1e3, max_steps: 3000)), increments: 1),
            (name: "to10", increments: {inc}, scale: {{"stretch": -0.10}}),
            (name: "settle10", kind: Dynamic((dt: 1e-3, dt_max: 1e3, max_steps: 3000)), increments: 1),
        ],
    )"#,
        hl = L / 2.0
    );
    let sc = scene::parse("wrinkling.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let mut built = scene::build(&sc, "wrinkling.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    // xorshift64 random field, zero on the clamp.
    let mut seed: u64 = 0x2545F4914F6CDD1D;
    for n in 0..built.model.n_nodes() {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        let r = (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
        let x = built.model.x0[n].x;
        built.model.x0[n].z += 2.0 * amp0 * T * r * (x / (L / 2.0)).min(1.0);
    }
    let model = &built.model;
    let mut solver = Solver::new(model, sc.solver.clone()).expect("solver");
    let mut state = model.initial_state();
    let t0 = Instant::now();
    let mut rest = Vec::new();
    let (mut iterations, mut steps) = (0, 0);
    solver
        .run(
            &built.steps,
            &mut state,
            &mut |r, st, _| {
                iterations += r.iterations;
                steps += 1;
                if let Some(d) = r.dynamics.as_ref().filter(|d| d.at_rest) {
                    let gamma = -r.scales[0];
                    let (lambda, amp, crests, crossings) = wrinkle_measures(&profile(model, st, L / 2.0), 5.0);
                    rest.push((gamma, lambda, amp, crests, crossings, d.time, t0.elapsed().as_secs_f64(), iterations, steps));
                }
            },
            &mut |_| {},
        )
        .unwrap_or_else(|e| panic!("{e}"));
    println!("wrinkling: {} dofs, {:.1} s", solver.sizes().0, t0.elapsed().as_secs_f64());
    assert_eq!(rest.len(), 2);
    for &(gamma, lambda, amp, crests, crossings, time, wall, its, nsteps) in &rest {
        let reference = cerda_mahadevan_wavelength(gamma);
        let a_cm = (NU * L * T).sqrt() * (16.0 * gamma / (3.0 * std::f64::consts::PI.powi(2) * (1.0 - NU * NU))).powf(0.25);
        let err = lambda / reference - 1.0;
        println!(
            "γ = {gamma}: λ = {lambda:.2} mm vs Cerda–Mahadevan {reference:.2} ({err:+.3}), amplitude {amp:.3} mm (C–M {a_cm:.2}), {crests} crests, {crossings} interior zero crossings, rest after {time:.3} s simulated; cumulative {nsteps} increments/time steps, {its} Newton iterations, {wall:.1} s",
        );
        assert!(err.abs() < 0.15, "γ = {gamma}: λ = {lambda} vs {reference}");
        assert!(amp > 100.0 * amp0 * T, "γ = {gamma}: amplitude {amp} is the imperfection, not a wrinkle");
        assert!(crossings >= 6, "γ = {gamma}: only {crossings} crossings");
    }
}
