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
/// each free edge): 2 × mean spacing of consecutive crossings; also amplitude and crest count.
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
    let crests = p.windows(3).filter(|w| w[1].1 > w[0].1 && w[1].1 > w[2].1 && w[1].1 > 0.1 * amp).count();
    let lambda = if crossings.len() >= 2 { 2.0 * (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64 } else { f64::NAN };
    (lambda, amp, crests, crossings.len())
}

#[test]
fn stretched_sheet_wrinkles_with_the_cerda_mahadevan_wavelength() {
    let nx: usize = std::env::var("WR_NX").ok().and_then(|s| s.parse().ok()).unwrap_or(32);
    let ny: usize = std::env::var("WR_NY").ok().and_then(|s| s.parse().ok()).unwrap_or(48);
    let inc: usize = std::env::var("WR_INC").ok().and_then(|s| s.parse().ok()).unwrap_or(10);
    let kind = std::env::var("WR_KIND").unwrap_or_default();
    let dt: f64 = std::env::var("WR_DT").ok().and_then(|s| s.parse().ok()).unwrap_or(1e-3);
    let md: f64 = std::env::var("WR_MD").ok().and_then(|s| s.parse().ok()).unwrap_or(0.0);
    let amp0: f64 = std::env::var("WR_AMP").ok().and_then(|s| s.parse().ok()).unwrap_or(1e-3);
    let text = format!(
        r#"Scene(
        name: "wrinkling",
        materials: {{"rubber": NeoHookean(young: 1.0, poisson: {NU})}},
        parts: [(name: "sheet", mesh: Rectangle(lx: {hl}, ly: {W}, nx: {nx}, ny: {ny}), material: "rubber", thickness: {T}, areal_density: 1e-10)],
        node_sets: {{"clamp": Edge(part: "sheet", edge: "xmin"), "mid": Edge(part: "sheet", edge: "xmax")}},
        boundary: [Clamp(set: "clamp"), Symmetry(set: "mid", normal: X)],
        loads: {{"stretch": Displacement(set: "clamp", dof: Ux, value: {hl})}},
        steps: [
            (name: "to5", {kind} increments: {inc}, scale: {{"stretch": -0.05}}),
            (name: "settle5", kind: Dynamic((dt: {dt}, dt_max: 1e3, max_steps: 3000, mass_damping: {md})), increments: 1),
            (name: "to10", {kind} increments: {inc}, scale: {{"stretch": -0.10}}),
            (name: "settle10", kind: Dynamic((dt: {dt}, dt_max: 1e3, max_steps: 3000, mass_damping: {md})), increments: 1),
        ],
    )"#,
        hl = L / 2.0
    );
    let sc = scene::parse("wrinkling.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let mut built = scene::build(&sc, "wrinkling.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    // Imperfection: seeded pseudo-random out-of-plane offsets of amplitude amp0·t, zero on the clamp.
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
    let mut rows = Vec::new();
    let res = solver.run(
        &built.steps,
        &mut state,
        &mut |r, st, _| {
            let gamma = -r.scales[0];
            let p = profile(model, st, L / 2.0);
            let (lambda, amp, crests, nc) = wrinkle_measures(&p, 5.0);
            println!(
                "γ = {gamma:.4}: λ = {lambda:.2} mm (CM {:.2}), amplitude {amp:.4} mm, crests {crests}, crossings {nc}, its {}, cut {}, indef {}, t {:.1}s",
                cerda_mahadevan_wavelength(gamma),
                r.iterations,
                r.cutbacks,
                r.indefinite_tangent,
                t0.elapsed().as_secs_f64()
            );
            if let Some(d) = &r.dynamics {
                println!("   dyn step {} t {:.3e} dt {:.2e} KE {:.2e} res {:.2e} rest {}", r.increment, d.time, d.dt, d.kinetic_energy, d.static_residual, d.at_rest);
            }
            rows.push((gamma, lambda, amp, crests));
        },
        &mut |_| {},
    );
    println!("dofs {}, wall {:.1} s, result {:?}", solver.sizes().0, t0.elapsed().as_secs_f64(), res.as_ref().err().map(|e| e.to_string()));
}
