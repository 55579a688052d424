//! A sleeve draped on an arm (issue 5, example 1): `garments/sleeve_on_arm.ron`, one
//! cotton-broadcloth panel with one plain underarm seam, sewn shut around a horizontal rigid
//! cylinder and left to come to rest on it under gravity (frictional penalty contact,
//! damped pseudo-dynamics).
//!
//! References: the penetration bound (no node's shell face inside the body by more
//! than 5 % of the thickness), checked by an independent parry3d point projection onto the
//! cylinder built here; the sewing bound of the virtual-sewing test (every seam gap below
//! 1e-6 of the panel size, the tie offset being exact once the closure scale reaches 1);
//! static equilibrium at rest (the arm's reaction equals the sleeve's weight ρ g A, 2 %).

use parry3d_f64::math::Vector as PVec;
use parry3d_f64::query::PointQuery;
use parry3d_f64::shape::Cylinder;
use plyshell::scene;
use plyshell::solver::{IncrementReport, Solver};

/// Arm radius, half length (m); sleeve ply thickness (m), areal density (kg/m²) and pattern
/// size (m), as in the scene file.
const ARM_RADIUS: f64 = 0.045;
const ARM_HALF_LENGTH: f64 = 0.3;
const H: f64 = 0.0003;
const RHO: f64 = 0.12;
const WIDTH: f64 = 0.3282964323;
const LENGTH: f64 = 0.30;

fn report(r: &IncrementReport, key: &str) -> serde_json::Value {
    r.extra.iter().rev().find_map(|v| v.get(key).cloned()).unwrap_or_else(|| panic!("no {key} report"))
}

#[test]
fn sleeve_rests_on_the_arm_without_penetrating_it_and_stays_sewn() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/garments/sleeve_on_arm.ron");
    let text = std::fs::read_to_string(path).expect("garments/sleeve_on_arm.ron");
    let sc = scene::parse(path, &text).unwrap_or_else(|e| panic!("{e}"));
    let built = scene::build(&sc, path, &text).unwrap_or_else(|e| panic!("{e}"));
    let model = &built.model;
    let seam = &built.seams[0];
    let gap0 = seam.gaps(|n| model.x0[n]).into_iter().fold(0.0, f64::max);
    let t = std::time::Instant::now();
    let mut reports = Vec::new();
    let mut state = model.initial_state();
    let mut solver = Solver::new(model, sc.solver.clone()).expect("solver");
    plyshell::contact::attach(&mut solver, model, built.contact.as_ref().expect("contact")).expect("contact attaches");
    solver.run(&built.steps, &mut state, &mut |r, _, _| reports.push(r.clone()), &mut |_| {}).unwrap_or_else(|e| panic!("{e}"));
    let iterations: usize = reports.iter().map(|r| r.iterations).sum();
    println!(
        "nodes {}, elements {}, free DOFs {}, tied DOFs {}, increments {}, Newton iterations {iterations}, {:.1} s",
        model.n_nodes(),
        model.elements.len(),
        model.dofs.n_free,
        model.dofs.ties.len(),
        reports.len(),
        t.elapsed().as_secs_f64()
    );

    // Independent penetration check: the arm as a parry3d cylinder (axis along global x,
    // which is the cylinder's local y; the swap of x and y is a reflection, under which the
    // cylinder is symmetric), the shell face at h/2 from the node.
    let arm = Cylinder::new(ARM_HALF_LENGTH, ARM_RADIUS);
    let mut pen: f64 = f64::NEG_INFINITY;
    let mut top_clearance: f64 = f64::NEG_INFINITY;
    for a in 0..model.n_nodes() {
        let x = model.position(&state, a);
        let q = PVec::new(x.y, x.x, x.z);
        let proj = arm.project_local_point(q, false);
        let d = (q - proj.point).length();
        let signed = if proj.is_inside { -d } else { d };
        pen = pen.max(0.5 * H - signed);
        if x.z > 0.04 {
            top_clearance = top_clearance.max(signed - 0.5 * H);
        }
    }
    println!("largest penetration of the shell face {pen:.3e} m ({:.2} % of h)", 100.0 * pen.max(0.0) / H);
    assert!(pen < 0.05 * H, "penetration {pen} m vs thickness {H} m");

    // The sleeve hangs on the arm: where it crosses the top of the arm (z > 0.04 m) its face
    // lies on it, within 0.1 mm (it started 10 mm above).
    println!("largest clearance of the shell face over the top of the arm {top_clearance:.3e} m");
    assert!(top_clearance.is_finite() && top_clearance < 1e-4, "clearance {top_clearance}");

    // The underarm seam stays closed.
    let size = WIDTH.max(LENGTH);
    let worst = seam.gaps(|n| model.position(&state, n)).into_iter().fold(0.0, f64::max);
    println!("seam gap: initial {gap0:.4e} m, final {worst:.3e} m ({:.2e} of the panel size)", worst / size);
    assert!(gap0 > 0.01, "initial gap {gap0}");
    assert!(worst < 1e-6 * size, "seam gap {worst}");

    // At rest: kinetic energy a small fraction of its peak, the arm carries the weight.
    let ke: Vec<f64> = reports.iter().map(|r| r.dynamics.as_ref().expect("a Dynamic step report").kinetic_energy).collect();
    let peak = ke.iter().copied().fold(0.0, f64::max);
    let last = *ke.last().expect("increments");
    let contact = report(reports.last().expect("increments"), "contact");
    let lift = contact["resultant"][2].as_f64().expect("resultant");
    let weight = RHO * 9.81 * WIDTH * LENGTH;
    println!("kinetic energy: peak {peak:.3e} J, final {last:.3e} J; arm reaction {lift:.6e} N vs weight {weight:.6e} N ({:+.2} %)", 100.0 * (lift / weight - 1.0));
    assert!(last < 1e-3 * peak, "not at rest: {last} J vs peak {peak} J");
    assert!((lift / weight - 1.0).abs() < 0.02, "reaction {lift} vs weight {weight}");
}
