//! Helpers shared by the end-to-end test files (`mod common;` in each).

use plyshell::model::State;
use plyshell::scene::{BuiltScene, Scene};
use plyshell::solver::{IncrementReport, Solver};

/// Solves `built` from its initial state with its rigid-body contact attached (if any), and a
/// garment's surface contact (barrier inter-ply and self contact, on by default). Returns the
/// final state, every converged increment's report, the largest penetration of a shell
/// face into a body over all accepted states (`contact::max_penetration`, a parry3d query
/// independent of the contact term; ≤ 0 when no face ever reached a body, −∞ without bodies),
/// and the number of
/// overlapping triangle prisms of the surface-contact parts at the contact thickness
/// (1 − f) h (`contact::intersection`, GJK, also independent of it) summed over those states.
pub fn solve_on_bodies(sc: &Scene, built: &BuiltScene) -> (State, Vec<IncrementReport>, f64, usize) {
    let model = &built.model;
    let setup = built.contact.as_ref();
    let mut solver = Solver::new(model, sc.solver.clone()).expect("solver");
    if let Some(setup) = setup {
        plyshell::contact::attach(&mut solver, model, setup).expect("contact attaches");
    }
    if let Some(surface) = &built.interply {
        plyshell::contact::interply::attach(&mut solver, model, surface).expect("surface contact attaches");
    }
    let mut state = model.initial_state();
    let mut reports = Vec::new();
    let mut penetration = f64::NEG_INFINITY;
    let mut overlaps = 0usize;
    let surface = built.interply.as_ref().and_then(|s| s.barrier.as_ref());
    solver
        .run(
            &built.steps,
            &mut state,
            &mut |r, st, solver| {
                reports.push(r.clone());
                // Bodies at their placement at this state (moving bodies: `contact::motion`).
                if let Some(setup) = setup {
                    let placed: Vec<_> = setup.bodies.iter().map(|b| b.at_time(solver.clock())).collect();
                    penetration = penetration.max(plyshell::contact::max_penetration(model, st, &placed));
                }
                if let Some(b) = surface {
                    overlaps += plyshell::contact::intersection::intersecting_prisms(model, st, &b.parts, 1.0 - b.settings.distance_factor).len();
                }
            },
            &mut |_| {},
        )
        .unwrap_or_else(|e| panic!("{e}"));
    (state, reports, penetration, overlaps)
}
