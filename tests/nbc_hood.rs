//! The layered NBC hood over a mannequin built from primitives (issue 5, example 4):
//! `garments/nbc_hood.ron` (three plies: ripstop outer shell, carbon adsorbent layer, knit
//! liner; two panels rolled onto a cone, a taped front and a welded back seam sewn shut
//! through all plies, quilting lines), solved at a coarser element size (`COARSE`) so the
//! test stays within the time budget; the scene file's own size is used by
//! `plyshell solve garments/nbc_hood.ron`.
//!
//! References: the virtual-sewing bound (every seam gap, every ply, below 1e-6 of the panel
//! size: the tie offset is exact once the closure scale reaches 1); the penetration
//! bound (no ply's shell face inside a body by more than 5 % of that ply's thickness), by an
//! independent parry3d point projection onto the mannequin's primitives rebuilt here;
//! static equilibrium at rest: the mannequin's contact reaction equals the hood's weight
//! Σ ρ_A,ply g A_ply (Newton's first law; 2 %), with the kinetic energy down to 1e-3 of its
//! peak.

use parry3d_f64::math::Vector as PVec;
use parry3d_f64::query::PointQuery;
use parry3d_f64::shape::{Ball, Capsule, Cylinder};
use plyshell::scene;
use plyshell::solver::{IncrementReport, Solver};

/// Element size of the test variant (m); the scene file uses 0.025.
const COARSE: &str = "element_size: 0.05";

fn report(r: &IncrementReport, key: &str) -> Option<serde_json::Value> {
    r.extra.iter().rev().find_map(|v| v.get(key).cloned())
}

// 110 s on a quiet 2-core machine with the default barrier inter-ply and self contact (670 time
// steps, 2616 Newton iterations; ~15 min and 719 / 3250 before this session's solver changes).
#[test]
fn nbc_hood_is_sewn_and_rests_on_the_mannequin() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/garments/nbc_hood.ron");
    let text = std::fs::read_to_string(path).expect("garments/nbc_hood.ron").replace("element_size: 0.025", COARSE);
    let sc = scene::parse(path, &text).unwrap_or_else(|e| panic!("{e}"));
    let built = scene::build(&sc, path, &text).unwrap_or_else(|e| panic!("{e}"));
    let model = &built.model;
    assert_eq!(built.seams.len(), 6, "two seams × three plies");
    let t = std::time::Instant::now();
    let mut reports = Vec::new();
    let mut state = model.initial_state();
    let mut solver = Solver::new(model, sc.solver.clone()).expect("solver");
    plyshell::contact::attach(&mut solver, model, built.contact.as_ref().expect("contact")).expect("contact attaches");
    // The garment's surface contact (barrier inter-ply and self contact, the default), as
    // `plyshell solve` attaches it.
    let surface = built.interply.as_ref().expect("the garment default: inter-ply and self contact");
    plyshell::contact::interply::attach(&mut solver, model, surface).expect("surface contact attaches");
    solver.run(&built.steps, &mut state, &mut |r, _, _| reports.push(r.clone()), &mut |_| {}).unwrap_or_else(|e| panic!("{e}"));
    let iterations: usize = reports.iter().map(|r| r.iterations).sum();
    println!(
        "parts {}, nodes {}, elements {}, free DOFs {}, tied DOFs {}, time steps {}, Newton iterations {iterations}, {:.1} s",
        model.parts.len(),
        model.n_nodes(),
        model.elements.len(),
        model.dofs.n_free,
        model.dofs.ties.len(),
        reports.len(),
        t.elapsed().as_secs_f64()
    );

    // Every ply of both seams closed.
    let size = 0.5;
    for seam in &built.seams {
        let gap0 = seam.gaps(|n| model.x0[n]).into_iter().fold(0.0, f64::max);
        let worst = seam.gaps(|n| model.position(&state, n)).into_iter().fold(0.0, f64::max);
        println!("seam {}: initial gap {gap0:.3e} m, final {worst:.3e} m", seam.name);
        assert!(gap0 > 0.005, "{}: initial gap {gap0}", seam.name);
        assert!(worst < 1e-6 * size, "{}: gap {worst}", seam.name);
    }

    // Independent penetration check against the mannequin (parry3d cylinders and capsules
    // run along their local y: the global axis is mapped onto it, a reflection under which
    // the shapes are symmetric).
    let head = Ball::new(0.10);
    let neck = Cylinder::new(0.07, 0.05);
    let shoulders = Capsule::new_y(0.16, 0.065);
    let torso = Cylinder::new(0.21, 0.13);
    let signed = |s: &dyn PointQuery, q: PVec| {
        let p = s.project_local_point(q, false);
        let d = (q - p.point).length();
        if p.is_inside { -d } else { d }
    };
    let mut worst_pen = f64::NEG_INFINITY;
    let mut worst_part = String::new();
    let mut in_contact = 0;
    for part in &model.parts {
        let h = sc.garment.as_ref().and_then(|g| {
            let ply = part.name.split('/').nth(1)?;
            g.plies.get(ply).map(|p| p.thickness)
        });
        let h = h.expect("ply thickness");
        for n in part.first_node..part.first_node + part.n_nodes {
            let x = model.position(&state, n);
            let d = [
                signed(&head, PVec::new(x.x, x.y, x.z - 1.62)),
                signed(&neck, PVec::new(x.x, x.z - 1.49, x.y)),
                signed(&shoulders, PVec::new(x.y, x.x, x.z - 1.42)),
                signed(&torso, PVec::new(x.x, x.z - 1.21, x.y)),
            ]
            .into_iter()
            .fold(f64::INFINITY, f64::min);
            let pen = (0.5 * h - d) / h;
            if d < 0.5 * h + 1e-4 {
                in_contact += 1;
            }
            if pen > worst_pen {
                worst_pen = pen;
                worst_part = part.name.clone();
            }
        }
    }
    println!("largest penetration of a shell face {:.3} % of its ply's h ({worst_part}); {in_contact} nodes within 0.1 mm of the mannequin", 100.0 * worst_pen.max(0.0));
    assert!(in_contact > 0, "the hood does not touch the mannequin");
    // Independent intersection check of the plies at rest (triangle prisms at the contact
    // thickness, GJK; `contact::intersection`).
    if let Some(b) = surface.barrier.as_ref() {
        let overlaps = plyshell::contact::intersection::intersecting_prisms(model, &state, &b.parts, 1.0 - b.settings.distance_factor).len();
        println!("overlapping ply prisms at rest: {overlaps}");
        assert_eq!(overlaps, 0, "plies intersect at rest");
    }
    assert!(worst_pen < 0.05, "penetration {worst_pen} h in {worst_part}");

    // At rest on the mannequin: contact reaction = weight.
    let ke: Vec<f64> = reports.iter().filter_map(|r| r.dynamics.as_ref().map(|d| d.kinetic_energy)).collect();
    let peak = ke.iter().copied().fold(0.0, f64::max);
    let last = *ke.last().expect("time steps");
    let contact = reports.iter().rev().find_map(|r| report(r, "contact")).expect("contact report");
    let lift = contact["resultant"][2].as_f64().expect("resultant");
    let garment = sc.garment.as_ref().expect("garment");
    let weight: f64 = model
        .parts
        .iter()
        .map(|p| {
            let ply = p.name.split('/').nth(1).and_then(|k| garment.plies.get(k)).expect("ply");
            let area: f64 = (p.first_element..p.first_element + p.n_elements).map(|e| model.element(e).reference_area()).sum();
            ply.areal_density * 9.81 * area
        })
        .sum();
    println!("kinetic energy: peak {peak:.3e} J, final {last:.3e} J; mannequin reaction {lift:.6e} N vs weight {weight:.6e} N ({:+.3} %)", 100.0 * (lift / weight - 1.0));
    assert!(last < 1e-3 * peak, "not at rest: {last} J vs peak {peak} J");
    assert!((lift / weight - 1.0).abs() < 0.02, "reaction {lift} vs weight {weight}");
}
