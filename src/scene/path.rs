//! Validation and resolution of the solution-step kinds (arc length, displacement control,
//! linearized buckling) of a scene.

use std::collections::BTreeMap;

use crate::input::{Locator, SceneError};
use super::spec::{Dof, ImperfectionSpec, StepSpec};
use crate::element::NODE_DOFS;
use crate::model::{Load, LoadKind};
use crate::solver::eigen::ModeImperfection;
use crate::solver::imperfection::{Imperfection, RandomField};
use crate::solver::StepKind;

fn positive(x: f64) -> bool {
    x.is_finite() && x > 0.0
}

/// Checks the step kind of `s` and resolves its node set to a global DOF. `fixed` flags the
/// supported and prescribed DOFs.
pub(super) fn resolve_step_kind(
    s: &StepSpec,
    field: &str,
    loc: &Locator,
    node_sets: &BTreeMap<String, Vec<usize>>,
    loads: &[Load],
    fixed: &[bool],
) -> Result<StepKind, SceneError> {
    let bad = |key: &str, msg: String| loc.at(Some(&s.name), Some(key), format!("{field}.kind.{key}"), msg);
    let mut kind = s.kind.clone();
    let path_following = matches!(kind, StepKind::ArcLength { .. } | StepKind::DisplacementControl { .. } | StepKind::Buckling { .. });
    if path_following {
        for lname in s.scale.keys() {
            if let Some(l) = loads.iter().find(|l| &l.name == lname)
                && matches!(l.kind, LoadKind::Displacements(_))
            {
                return Err(loc.at_value(
                    &s.name,
                    lname,
                    format!("{field}.scale[{lname}]"),
                    "a prescribed-displacement load cannot be scaled in an arc-length, displacement-control or buckling step; change it in a Static step",
                ));
            }
        }
        if s.linear {
            return Err(bad("linear", "a linear step must be Static".into()));
        }
    }
    match &mut kind {
        StepKind::Static | StepKind::StaticDamped | StepKind::Dynamic(_) => {}
        StepKind::ArcLength { length, min_length, max_length, desired_iterations, max_load_factor, max_displacement } => {
            if !positive(*length) {
                return Err(bad("length", format!("expected a positive arc length, found {length}")));
            }
            let lo = min_length.unwrap_or(*length / 1000.0);
            let hi = max_length.unwrap_or(*length * 10.0);
            if !positive(lo) || lo > *length {
                return Err(bad("min_length", format!("expected 0 < min_length ≤ length, found {lo}")));
            }
            if !hi.is_finite() || hi < *length {
                return Err(bad("max_length", format!("expected max_length ≥ length, found {hi}")));
            }
            if *desired_iterations == 0 {
                return Err(bad("desired_iterations", "expected at least one iteration".into()));
            }
            if !positive(*max_load_factor) {
                return Err(bad("max_load_factor", format!("expected a positive load factor, found {max_load_factor}")));
            }
            if let Some(d) = max_displacement
                && !positive(*d)
            {
                return Err(bad("max_displacement", format!("expected a positive displacement, found {d}")));
            }
        }
        StepKind::DisplacementControl { set, dof, value, global_dof } => {
            let Some(nodes) = node_sets.get(set.as_str()) else {
                let known: Vec<&str> = node_sets.keys().map(|k| k.as_str()).collect();
                return Err(loc.at_value(&s.name, set, format!("{field}.kind.set"), format!("no node set named \"{set}\"; node sets: {}", known.join(", "))));
            };
            if nodes.len() != 1 {
                return Err(loc.at_value(
                    &s.name,
                    set,
                    format!("{field}.kind.set"),
                    format!("displacement control needs a set of exactly one node; \"{set}\" has {} (use a Nearest selector)", nodes.len()),
                ));
            }
            let k = match dof {
                Dof::Ux => 0,
                Dof::Uy => 1,
                Dof::Uz => 2,
                _ => return Err(bad("dof", "only a translation (Ux, Uy, Uz) can be controlled".into())),
            };
            let g = NODE_DOFS * nodes[0] + k;
            if fixed.get(g).copied().unwrap_or(true) {
                return Err(bad("dof", format!("the controlled DOF {dof:?} of node {} is supported or prescribed", nodes[0])));
            }
            if !value.is_finite() || *value == 0.0 {
                return Err(bad("value", format!("expected a non-zero finite displacement change, found {value}")));
            }
            *global_dof = g;
        }
        StepKind::Buckling { modes, shift } => {
            if *modes == 0 {
                return Err(bad("modes", "expected at least one mode".into()));
            }
            if !shift.is_finite() {
                return Err(bad("shift", "expected a finite shift".into()));
            }
        }
    }
    Ok(kind)
}

/// Checks a buckling-mode imperfection and resolves its load names to scales.
pub(super) fn resolve_imperfection(imp: &ImperfectionSpec, loc: &Locator, loads: &[Load]) -> Result<Imperfection, SceneError> {
    let (scale, modes) = match imp {
        ImperfectionSpec::BucklingModes { scale, modes } => (scale, modes),
        ImperfectionSpec::RandomField { amplitude, correlation_length, seed } => {
            if !amplitude.is_finite() {
                return Err(loc.at(None, Some("amplitude"), "imperfection.amplitude", "expected a finite amplitude"));
            }
            if !positive(*correlation_length) {
                return Err(loc.at(None, Some("correlation_length"), "imperfection.correlation_length", "expected a positive correlation length"));
            }
            return Ok(Imperfection::RandomField(RandomField { amplitude: *amplitude, correlation_length: *correlation_length, seed: *seed }));
        }
    };
    let mut scales = vec![0.0; loads.len()];
    for (lname, &v) in scale {
        let Some(i) = loads.iter().position(|l| &l.name == lname) else {
            let known: Vec<&str> = loads.iter().map(|l| l.name.as_str()).collect();
            return Err(loc.at_value("BucklingModes", lname, "imperfection.scale", format!("no load named \"{lname}\"; loads: {}", known.join(", "))));
        };
        if matches!(loads[i].kind, LoadKind::Displacements(_)) {
            return Err(loc.at_value("BucklingModes", lname, "imperfection.scale", "a prescribed displacement cannot be a buckling reference load"));
        }
        if !v.is_finite() {
            return Err(loc.at_value("BucklingModes", lname, "imperfection.scale", "expected a finite scale"));
        }
        scales[i] = v;
    }
    if scales.iter().all(|v| *v == 0.0) {
        return Err(loc.at(None, Some("imperfection"), "imperfection.scale", "expected a non-zero reference load"));
    }
    if modes.is_empty() {
        return Err(loc.at(None, Some("modes"), "imperfection.modes", "expected at least one mode"));
    }
    for m in modes {
        if m.mode == 0 || m.mode > 50 {
            return Err(loc.at(None, Some("mode"), "imperfection.modes.mode", format!("expected a mode number from 1 to 50, found {}", m.mode)));
        }
        if !m.amplitude.is_finite() {
            return Err(loc.at(None, Some("amplitude"), "imperfection.modes.amplitude", "expected a finite amplitude"));
        }
    }
    Ok(Imperfection::BucklingModes(ModeImperfection { scales, modes: modes.iter().map(|m| (m.mode, m.amplitude)).collect() }))
}
