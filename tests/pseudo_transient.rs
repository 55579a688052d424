//! Pseudo-transient continuation (Kelley & Keyes 1998) on a hanging cloth: the static
//! tangent of a slack fabric is singular, implicit dynamics with lumped mass brings it to
//! rest, and the rest state is a static equilibrium.

use std::time::Instant;

use plyshell::scene;
use plyshell::solver::{IncrementReport, Solver, StepKind, StepPlan};

const HANGING_CLOTH: &str = include_str!("../garments/examples/hanging_cloth.ron");

/// A 0.4 m square of fabric (ρ_A = 0.2 kg/m², E h = 10³ N/m, D = 10⁻⁵ N·m, see the scene)
/// pinned at two adjacent corners, released flat, swings down and comes to rest.
/// Asserts: the rest state's static residual ‖f_int − f_ext‖ ≤ 1e-6 of the force scale; a
/// static Newton step from it converges in at most 2 iterations and moves no node by more than 1e-5 L (4 µm: the bending
/// modes of a fabric are so soft that a 1e-7 residual still leaves µm-sized corrections); the
/// vertical support reaction equals the weight ρ_A g L² within 0.5 %; the two corner
/// reactions are mirror images (the problem is symmetric about x = L/2) within 1 %; every
/// node hangs below the support line and no node at least L/4 from the supports is further
/// from its nearer support than its reference (geodesic) distance × 1.01 (the cloth barely
/// stretches; nearer, the membrane strain of a point support is singular, ~1/r), and the free
/// corners hang within 1 % of L below the supports (the side edges end up vertical).
#[test]
fn hanging_cloth_comes_to_rest_in_static_equilibrium() {
    let t0 = Instant::now();
    let sc = scene::parse("hanging_cloth.ron", HANGING_CLOTH).expect("scene");
    let built = scene::build(&sc, "hanging_cloth.ron", HANGING_CLOTH).expect("build");
    let model = &built.model;
    let mut solver = Solver::new(model, sc.solver.clone()).expect("solver");
    let mut state = model.initial_state();
    let mut reports: Vec<IncrementReport> = Vec::new();
    solver
        .run(&built.steps, &mut state, &mut |r, _, _| reports.push(r.clone()), &mut |_| {})
        .unwrap_or_else(|e| panic!("dynamic step failed: {e}"));
    let last = reports.last().expect("reports");
    let dynamics = last.dynamics.clone().expect("dynamic info");
    assert!(dynamics.at_rest);
    let newton: usize = reports.iter().map(|r| r.iterations).sum();
    let rejected: usize = reports.iter().map(|r| r.cutbacks).sum();
    println!(
        "hanging cloth: {} dofs, {} time steps ({rejected} rejected), {newton} Newton iterations, t = {:.3} s, KE = {:.2e} J, static residual {:.2e}, wall {:.2} s",
        solver.sizes().0,
        reports.len(),
        dynamics.time,
        dynamics.kinetic_energy,
        dynamics.static_residual,
        t0.elapsed().as_secs_f64()
    );

    // Static check of the rest state.
    let scales = built.steps[0].target_scales.clone();
    let mut check = state.clone();
    let rel = solver.static_residual(&mut check, &scales).expect("evaluable");
    assert!(rel <= 1e-6, "static residual of the rest state {rel:e}");
    let l = 0.4;
    let weight = 0.2 * 9.81 * l * l;
    let f_int = solver.internal_force().to_vec();
    let mut f_ext = vec![0.0; f_int.len()];
    model.external_force(&check, &scales, &mut f_ext);
    let supports: Vec<usize> = ["corner_a", "corner_b"].iter().map(|s| built.node_sets[*s][0]).collect();
    let reaction = |n: usize, k: usize| f_int[5 * n + k] - f_ext[5 * n + k];
    let rz: f64 = supports.iter().map(|&n| reaction(n, 2)).sum();
    println!("vertical reaction {rz:.6} N vs weight {weight:.6} N; corner reactions {:?}", supports.iter().map(|&n| [reaction(n, 0), reaction(n, 1), reaction(n, 2)]).collect::<Vec<_>>());
    assert!((rz - weight).abs() <= 0.005 * weight, "vertical reaction {rz} vs weight {weight}");
    let (a, b) = (supports[0], supports[1]);
    for k in 0..3 {
        let (ra, rb) = (reaction(a, k), reaction(b, k));
        let mirrored = if k == 0 { -rb } else { rb };
        assert!((ra - mirrored).abs() <= 0.01 * weight, "corner reactions not mirror images: {ra} vs {rb} (component {k})");
    }

    let plan = vec![StepPlan { name: "static check".into(), increments: 1, linear: false, automatic_increments: false, target_scales: scales.clone(), kind: StepKind::Static, clock: None }];
    let before = state.clone();
    let mut its = 0;
    solver.run(&plan, &mut state, &mut |r, _, _| its += r.iterations, &mut |_| {}).unwrap_or_else(|e| panic!("static check failed: {e}"));
    let moved = (0..model.n_nodes()).map(|n| (state.u[n] - before.u[n]).norm()).fold(0.0, f64::max);
    println!("static Newton from the rest state: {its} iterations, largest move {moved:.2e} m");
    assert!(its <= 2, "static Newton from the rest state needed {its} iterations");
    assert!(moved <= 1e-5 * l, "static Newton moved a node by {moved}");

    // Shape.
    let top = model.x0[a];
    let mut lowest: f64 = 0.0;
    let (mut stretch_far, mut stretch_near) = (0.0f64, 0.0f64);
    for n in 0..model.n_nodes() {
        let x = model.position(&state, n);
        lowest = lowest.min(x.z);
        assert!(x.z <= 1e-9, "node {n} above the supports: {x:?}");
        let (near, d0) = supports.iter().map(|&s| (s, (model.x0[n] - model.x0[s]).norm())).min_by(|p, q| p.1.total_cmp(&q.1)).expect("two supports");
        let d = (x - model.position(&state, near)).norm();
        if d0 > 0.0 {
            stretch_near = stretch_near.max(d / d0);
        }
        if d0 >= 0.25 * l {
            stretch_far = stretch_far.max(d / d0);
        }
    }
    println!("largest distance ratio to the nearer support: {stretch_far:.5} beyond L/4, {stretch_near:.5} overall");
    assert!(stretch_far <= 1.01, "the cloth stretched: distance ratio {stretch_far}");
    let free_corners = [built.monitors[0].node];
    for &n in &free_corners {
        let dz = model.position(&state, n).z - top.z;
        println!("free corner hangs {dz:.5} m below the supports; lowest point {lowest:.5} m");
        assert!((dz + l).abs() <= 0.01 * l, "free corner at depth {dz}, expected about −L");
    }
}

/// Lumped mass (row sums of the consistent mass): the total is ρ_A × area exactly, and the
/// corner node of a regular mesh carries a quarter of an element's mass.
#[test]
fn lumped_mass_sums_to_the_areal_density_times_the_area() {
    use plyshell::solver::LumpedMass;
    let sc = scene::parse("hanging_cloth.ron", HANGING_CLOTH).expect("scene");
    let built = scene::build(&sc, "hanging_cloth.ron", HANGING_CLOTH).expect("build");
    let mass = LumpedMass::from_model(&built.model, 1.0);
    let exact = 0.2 * 0.4 * 0.4;
    assert!((mass.total() - exact).abs() < 1e-14, "{} vs {exact}", mass.total());
    let corner = built.monitors[0].node;
    assert!((mass.translational[corner] - exact / 256.0 / 4.0).abs() < 1e-15);
    // Director inertia ρ_A h²/12 per area.
    let h: f64 = 3.3045e-4;
    assert!((mass.rotary.iter().sum::<f64>() - exact * h * h / 12.0).abs() < 1e-18);
}

/// The pseudo-transient step keeps the equilibria of the static problem: the end-shear
/// cantilever of Sze et al. (2004) §3.1 (P L²/EI = 4, 16×1) solved by a Dynamic step with the
/// full load at once, and by the StaticDamped (Levenberg–Marquardt) step in 5 increments,
/// lands on the tip of the 20-increment static Newton solve within 1e-6 L.
#[test]
fn dynamic_and_damped_steps_reach_the_static_equilibrium() {
    use plyshell::bench::{scenes, solve_variant};
    let reference = solve_variant(scenes::END_SHEAR, "end_shear", &[]).expect("static");
    let tip_ref = reference.monitors[0].values.last().expect("tip").clone();
    let variants = [
        ("Dynamic", "(name: \"load\", kind: Dynamic((dt: 0.01, dt_max: 1e3, rest_residual_tol: 1e-9)), increments: 1,"),
        ("StaticDamped", "(name: \"load\", kind: StaticDamped, increments: 5,"),
    ];
    for (name, step) in variants {
        let t = Instant::now();
        let s = solve_variant(
            scenes::END_SHEAR,
            name,
            &[("(name: \"load\", increments: 20,", step.to_string()), ("thickness: 0.1)", "thickness: 0.1, areal_density: 1.0)".into())],
        )
        .unwrap_or_else(|e| panic!("{name}: {e}"));
        let tip = s.monitors[0].values.last().expect("tip");
        let err = ((tip[0] - tip_ref[0]).powi(2) + (tip[1] - tip_ref[1]).powi(2)).sqrt() / 10.0;
        let rejected: usize = s.increments.iter().map(|i| i.cutbacks).sum();
        println!(
            "end shear by {name}: {} reports ({rejected} rejected/cut back), {} Newton iterations, {:.2} s, tip {tip:?} vs static {tip_ref:?}, error {err:.1e} L",
            s.increments.len(),
            s.newton_iterations,
            t.elapsed().as_secs_f64()
        );
        assert!(err < 1e-6, "{name}: tip {tip:?} vs {tip_ref:?}");
    }
}

/// Step kinds in the scene: `Dynamic(())` takes every default, `StaticDamped` is a unit
/// variant, and an invalid Dynamic setting is reported at its line and column with the field.
#[test]
fn step_kinds_parse_and_bad_settings_are_located() {
    use plyshell::solver::DynamicSettings;
    let with = |kind: &str| HANGING_CLOTH.replace("kind: Dynamic((dt: 1e-3, dt_max: 10.0, max_steps: 2000, mass_damping: 5.0))", kind);
    let text = with("kind: Dynamic(())");
    let sc = scene::parse("a.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(sc.steps[0].kind, StepKind::Dynamic(DynamicSettings::default()));
    let text = with("kind: StaticDamped");
    let sc = scene::parse("a.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(sc.steps[0].kind, StepKind::StaticDamped);
    let text = with("kind: Dynamic((scheme: GeneralizedAlpha(rho_inf: 0.8), duration: 2.0))");
    let sc = scene::parse("a.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let expect = DynamicSettings { scheme: plyshell::solver::TimeScheme::GeneralizedAlpha { rho_inf: 0.8 }, duration: 2.0, ..Default::default() };
    assert_eq!(sc.steps[0].kind, StepKind::Dynamic(expect));
    let text = with("kind: Dynamic((scheme: GeneralizedAlpha(rho_inf: 1.5)))");
    let sc = scene::parse("a.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let err = scene::build(&sc, "a.ron", &text).expect_err("rho_inf > 1");
    assert!(err.field.ends_with("kind.scheme") && err.message.contains("rho_inf"), "{err}");
    let text = with("kind: Dynamic((dt: 1e-3,\n dt_max: 1e-4))");
    let sc = scene::parse("a.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    let err = scene::build(&sc, "a.ron", &text).expect_err("dt_max < dt");
    let line = text.lines().position(|l| l.contains("dt_max: 1e-4")).expect("line") + 1;
    assert_eq!(err.line, line, "{err}");
    assert!(err.field.ends_with("kind.dt_max") && err.message.contains("largest time step"), "{err}");
}

/// Linear springs k on translation z of a node list, f = −k u_z: the simplest `NodalForces`.
struct TipSprings {
    nodes: Vec<usize>,
    k: f64,
}

impl plyshell::solver::NodalForces for TipSprings {
    fn add(&mut self, _: &plyshell::model::Model, state: &plyshell::model::State, f_ext: &mut [f64], jacobian: &mut Vec<(usize, nalgebra::Matrix3<f64>)>) {
        for &n in &self.nodes {
            f_ext[5 * n + 2] -= self.k * state.u[n].z;
            let mut j = nalgebra::Matrix3::zeros();
            j[(2, 2)] = -self.k;
            jacobian.push((n, j));
        }
    }
}

/// Configuration-dependent nodal forces (the hook contact builds on) enter the residual and
/// the tangent of every step kind. A linear cantilever (Sze §3.1 geometry, tip load P) has
/// tip stiffness k_b = P / w₀; with springs of total stiffness k_s = k_b at the tip, linear
/// superposition gives w = P / (k_b + k_s) = w₀/2 exactly (1e-9) for a linear step, and a
/// Dynamic step with the full nonlinear load (P L²/EI = 4) comes to rest with the springs'
/// k_s·w and the clamp reaction balancing the load to 1e-6 (rest residual 1e-9 of the
/// largest generalised force, the clamp moment).
#[test]
fn nodal_force_hook_adds_springs_to_residual_and_tangent() {
    use plyshell::bench::scenes;
    let linear = scenes::END_SHEAR
        .replace("(name: \"load\", increments: 20,", "(name: \"load\", linear: true, increments: 1,")
        .replace("force: (0.0, 0.0, 4.0)", "force: (0.0, 0.0, 1e-4)")
        .replace("thickness: 0.1)", "thickness: 0.1, areal_density: 1.0)");
    let sc = scene::parse("s.ron", &linear).expect("scene");
    let built = scene::build(&sc, "s.ron", &linear).expect("build");
    let tip = built.node_sets["tip"].clone();
    let solve = |springs: Option<f64>, steps: &[StepPlan]| {
        let mut solver = Solver::new(&built.model, sc.solver.clone()).expect("solver");
        if let Some(k) = springs {
            solver.add_nodal_forces(Box::new(TipSprings { nodes: tip.clone(), k: k / tip.len() as f64 }));
        }
        let mut state = built.model.initial_state();
        let mut its = 0;
        solver.run(steps, &mut state, &mut |r, _, _| its += r.iterations, &mut |_| {}).unwrap_or_else(|e| panic!("{e}"));
        (state.u[tip[0]].z, its)
    };
    let (w0, _) = solve(None, &built.steps);
    let k_b = 1e-4 / w0;
    let (w, _) = solve(Some(k_b), &built.steps);
    println!("linear tip: free {w0:.6e}, with springs {w:.6e} (ratio {:.9})", w / w0);
    assert!((w / w0 - 0.5).abs() < 1e-9, "{w} vs {w0}/2");

    let dynamic = vec![StepPlan {
        name: "dyn".into(),
        increments: 1,
        linear: false,
        automatic_increments: false,
        target_scales: vec![4.0e4],
        kind: StepKind::Dynamic(plyshell::solver::DynamicSettings { dt: 0.01, dt_max: 1e3, rest_residual_tol: 1e-9, ..Default::default() }),
        clock: None,
    }];
    let mut solver = Solver::new(&built.model, sc.solver.clone()).expect("solver");
    solver.add_nodal_forces(Box::new(TipSprings { nodes: tip.clone(), k: k_b / tip.len() as f64 }));
    let mut state = built.model.initial_state();
    if let Err(e) = solver.run(&dynamic, &mut state, &mut |_, _, _| {}, &mut |_| {}) {
        panic!("{e}");
    }
    let rel = solver.static_residual(&mut state, &[4.0e4]).expect("evaluable");
    println!("static residual at rest {rel:e}");
    let f_int = solver.internal_force().to_vec();
    let spring: f64 = tip.iter().map(|&n| k_b / tip.len() as f64 * state.u[n].z).sum();
    let root: f64 = built.node_sets["root"].iter().map(|&n| f_int[5 * n + 2]).sum();
    println!("dynamic with springs: tip w = {:.4}, spring force {spring:.5}, root shear {root:.5}, load 4", state.u[tip[0]].z);
    // The support reaction (f_int at the clamp, downward here) and the springs balance the load.
    assert!((spring - root - 4.0).abs() < 1e-6 * 4.0, "springs {spring} − root {root} vs 4");
    assert!(spring > 0.1 && spring < 4.0);
}

/// The integrator itself: an unsupported plate under gravity falls freely. Backward Euler
/// with fixed Δt (grow = 1) gives v_n = −g t_n and u_n = −½ g t_n (t_n + Δt) exactly (the
/// discrete solution of ü = −g), and with mass-proportional damping α_M,
/// v_{n+1} = (v_n − g Δt)/(1 + α_M Δt): every node to 1e-9 relative. The step ends at
/// max_time, not at rest, and says so.
#[test]
fn free_fall_follows_the_discrete_backward_euler_solution() {
    use plyshell::solver::DynamicSettings;
    let text = r#"Scene(
        name: "free_fall",
        materials: {"m": StVenantKirchhoff(young: 1.0e6, poisson: 0.3)},
        parts: [(name: "plate", mesh: Rectangle(lx: 1.0, ly: 1.0, nx: 4, ny: 4), material: "m", thickness: 0.01)],
        loads: {"g": Gravity(part: "plate", areal_density: 2.0, g: (0.0, 0.0, -9.81))},
        steps: [(name: "fall", increments: 1, scale: {"g": 1.0})],
    )"#;
    let sc = scene::parse("fall.ron", text).expect("scene");
    let built = scene::build(&sc, "fall.ron", text).expect("build");
    let (g, dt) = (9.81, 0.01);
    for alpha in [0.0, 3.0] {
        let mut plan = built.steps.clone();
        plan[0].kind = StepKind::Dynamic(DynamicSettings { dt, grow: 1.0, max_time: 0.2 - 0.5 * dt, mass_damping: alpha, ..Default::default() });
        let mut solver = Solver::new(&built.model, sc.solver.clone()).expect("solver");
        let mut state = built.model.initial_state();
        let (mut v, mut u, mut worst, mut steps) = (0.0f64, 0.0f64, 0.0f64, 0);
        let out = solver.run(
            &plan,
            &mut state,
            &mut |r, st, _| {
                let d = r.dynamics.as_ref().expect("dynamic");
                assert!((d.dt - dt).abs() < 1e-15);
                v = (v - g * dt) / (1.0 + alpha * dt);
                u += dt * v;
                for n in 0..st.u.len() {
                    let e = (st.u[n].z - u).abs() / u.abs();
                    worst = worst.max(e + st.u[n].x.abs() + st.u[n].y.abs());
                }
                steps += 1;
            },
            &mut |_| {},
        );
        let msg = out.expect_err("a falling plate never comes to rest").to_string();
        println!("free fall α_M = {alpha}: {steps} steps, u = {u:.6} m, largest relative deviation {worst:.1e}; {msg}");
        assert!(msg.contains("not at rest"), "{msg}");
        assert_eq!(steps, 20);
        assert!(worst < 1e-9, "deviation {worst}");
        if alpha == 0.0 {
            let t = 20.0 * dt;
            assert!((u + 0.5 * g * t * (t + dt)).abs() < 1e-12);
        }
    }
}

/// Transient dynamics with generalized-α (Chung & Hulbert 1993): a cantilever (L = 10,
/// b = 1, h = 0.1, E = 1.2e6, ν = 0, ρ_A = 1; 16×1, lumped mass) deflected by a small static
/// tip load and released vibrates at its first bending frequency
/// ω₁ = 1.87510² √(EI/(ρ_A b L⁴)) (Euler–Bernoulli; shear and rotary inertia change it by
/// < 1e-4 at L/h = 100). With ρ∞ = 1 (no numerical dissipation) and Δt = T₁/100 over two
/// periods: the period from the tip's zero crossings within 1 %, and the total energy
/// (kinetic + strain) within 1 % of the released strain energy at every step. Backward Euler
/// with the same Δt loses most of it (reported, asserted below 50 % after two periods).
#[test]
fn released_cantilever_vibrates_at_its_first_frequency() {
    use plyshell::bench::scenes;
    use plyshell::solver::{DynamicSettings, TimeScheme};
    let text = scenes::END_SHEAR
        .replace("(name: \"load\", increments: 20,", "(name: \"load\", linear: true, increments: 1,")
        .replace("force: (0.0, 0.0, 4.0)", "force: (0.0, 0.0, 1e-4)")
        .replace("thickness: 0.1)", "thickness: 0.1, areal_density: 1.0)");
    let sc = scene::parse("v.ron", &text).expect("scene");
    let built = scene::build(&sc, "v.ron", &text).expect("build");
    let tip = built.node_sets["tip"][0];
    let ei: f64 = 1.2e6 * 0.1f64.powi(3) / 12.0;
    let omega = 1.875_104_07f64.powi(2) * (ei / 1.0e4).sqrt();
    let period = 2.0 * std::f64::consts::PI / omega;
    for (name, scheme) in [("generalized-α ρ∞=1", TimeScheme::GeneralizedAlpha { rho_inf: 1.0 }), ("backward Euler", TimeScheme::BackwardEuler)] {
        let mut plan = built.steps.clone();
        let mut release = plan[0].clone();
        release.name = "release".into();
        release.target_scales = vec![0.0];
        release.kind = StepKind::Dynamic(DynamicSettings { dt: period / 100.0, grow: 1.0, duration: 2.0 * period, scheme, ..Default::default() });
        plan.push(release);
        let mut solver = Solver::new(&built.model, sc.solver.clone()).expect("solver");
        let mut state = built.model.initial_state();
        let (mut history, mut u0, mut worst_energy, mut last_energy) = (Vec::new(), 0.0, 0.0f64, 0.0);
        let t0 = Instant::now();
        solver
            .run(
                &plan,
                &mut state,
                &mut |r, st, _| match &r.dynamics {
                    None => u0 = r.energy,
                    Some(d) => {
                        history.push((d.time, st.u[tip].z));
                        last_energy = (d.kinetic_energy + r.energy) / u0;
                        worst_energy = worst_energy.max((last_energy - 1.0).abs());
                    }
                },
                &mut |_| {},
            )
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        // Upward zero crossings of the tip deflection (it starts at +w₀, moving down).
        let ups: Vec<f64> = history
            .windows(2)
            .filter(|p| p[0].1 < 0.0 && p[1].1 >= 0.0)
            .map(|p| p[0].0 + (p[1].0 - p[0].0) * (-p[0].1) / (p[1].1 - p[0].1))
            .collect();
        let downs: Vec<f64> = history
            .windows(2)
            .filter(|p| p[0].1 > 0.0 && p[1].1 <= 0.0)
            .map(|p| p[0].0 + (p[1].0 - p[0].0) * p[0].1 / (p[0].1 - p[1].1))
            .collect();
        let measured = if downs.len() >= 2 { downs[1] - downs[0] } else { f64::NAN };
        println!(
            "{name}: {} steps, {:.2} s; period {measured:.4} vs {period:.4} ({:+.4}), upward crossings {}, energy at end {last_energy:.4} of the released strain energy (largest deviation {worst_energy:.2e})",
            history.len(),
            t0.elapsed().as_secs_f64(),
            measured / period - 1.0,
            ups.len()
        );
        if name.starts_with("generalized") {
            assert!((measured / period - 1.0).abs() < 0.01, "period {measured} vs {period}");
            assert!(worst_energy < 0.01, "energy drift {worst_energy}");
        } else {
            assert!(last_energy < 0.5, "backward Euler kept {last_energy} of the energy");
        }
    }
}
