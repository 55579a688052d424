//! Mesh sequencing of a scene's first step (`Dynamic((coarse_levels: L))`): which scenes
//! admit it, and the coarser scenes it solves first (`analysis_sequence` runs them); and the
//! format and checks of a-posteriori refinement (`refine` on the last step; `crate::refine`
//! runs it). Both map a rest state onto another mesh of the scene's generated parts.

use serde::{Deserialize, Serialize};

use super::spec::{MeshSpec, Scene};
use crate::input::{Locator, SceneError};
use crate::solver::StepKind;

/// Coarser meshes requested by the scene's first step (0: not sequenced).
pub fn coarse_levels(scene: &Scene) -> usize {
    match scene.steps.first().map(|s| &s.kind) {
        Some(StepKind::Dynamic(ds)) => ds.coarse_levels,
        _ => 0,
    }
}

/// Elements per side of a grid of `n` elements coarsened `level` times by 2 (rounded up).
pub fn coarse_count(n: usize, level: usize) -> usize {
    n.div_ceil(1usize << level.min(usize::BITS as usize - 1))
}

/// Refuses `coarse_levels` where the mapping between meshes is not defined: on any step but
/// the first, or when a part is not a `Rectangle` grid (the prolongation is the structured
/// grid's, `model::prolong`), the coarsest grid would have fewer than 2 elements per side,
/// or the scene has seams, a garment, an imperfection, a movement protocol moving bodies or
/// augmented-Lagrangian contact (states, placements or multipliers not carried over).
pub(super) fn check(scene: &Scene, loc: &Locator) -> Result<(), SceneError> {
    for (k, s) in scene.steps.iter().enumerate() {
        let StepKind::Dynamic(ds) = &s.kind else { continue };
        if ds.coarse_levels == 0 {
            continue;
        }
        let field = format!("steps[{}].kind.coarse_levels", s.name);
        let bad = |msg: String| Err(loc.at(Some(&s.name), Some("coarse_levels"), field.clone(), msg));
        if k > 0 {
            return bad("mesh sequencing starts from the scene's initial state: only the first step may have coarse_levels".into());
        }
        if let Some(what) = unmapped(scene) {
            return bad(format!("mesh sequencing maps generated Rectangle parts only; this scene has {what}"));
        }
        for p in &scene.parts {
            match p.mesh {
                MeshSpec::Rectangle { nx, ny, .. } => {
                    if coarse_count(nx, ds.coarse_levels) < 2 || coarse_count(ny, ds.coarse_levels) < 2 {
                        return bad(format!(
                            "part {}: {nx} × {ny} elements coarsened {} times by 2 leaves fewer than 2 elements per side; use fewer levels",
                            p.name, ds.coarse_levels
                        ));
                    }
                }
                _ => return bad(format!("part {}: mesh sequencing maps Rectangle grids only", p.name)),
            }
        }
    }
    if let Some(p) = &scene.protocol
        && p.settle.coarse_levels > 0
    {
        return Err(loc.at(None, Some("coarse_levels"), "protocol.settle.coarse_levels", "pose steps continue from the previous pose: they cannot be sequenced"));
    }
    Ok(())
}

/// The scene solved at sequencing level `level` (1 = one halving): every `Rectangle` part
/// with its elements per side halved `level` times (rounded up), only the first step, with
/// `coarse_levels` 0, no VTU output.
pub fn coarsened(scene: &Scene, level: usize) -> Scene {
    let mut s = scene.clone();
    for p in &mut s.parts {
        if let MeshSpec::Rectangle { nx, ny, .. } = &mut p.mesh {
            *nx = coarse_count(*nx, level);
            *ny = coarse_count(*ny, level);
        }
    }
    s.steps.truncate(1);
    for st in &mut s.steps {
        if let StepKind::Dynamic(ds) = &mut st.kind {
            ds.coarse_levels = 0;
        }
    }
    s.output.vtu = false;
    s
}

/// (elements along x, along y) of each `Rectangle` part of `scene` (None for other parts).
pub fn grids(scene: &Scene) -> Vec<Option<(usize, usize)>> {
    scene.parts.iter().map(|p| match p.mesh {
        MeshSpec::Rectangle { nx, ny, .. } => Some((nx, ny)),
        _ => None,
    }).collect()
}

/// What in `scene` a mapping of its state onto another mesh of its parts does not carry
/// over (garment panels, seam ties, imperfections, protocols, moving bodies, Lagrange
/// multipliers), if anything.
fn unmapped(scene: &Scene) -> Option<&'static str> {
    if scene.garment.is_some() {
        Some("a garment")
    } else if !scene.seams.is_empty() {
        Some("seams")
    } else if scene.imperfection.is_some() {
        Some("an imperfection")
    } else if scene.protocol.is_some() {
        Some("a movement protocol")
    } else if scene.contact.as_ref().is_some_and(|c| c.bodies.iter().any(|b| !b.motion.is_empty())) {
        Some("a moving contact body")
    } else if scene.contact.as_ref().is_some_and(|c| matches!(c.formulation, crate::contact::spec::ContactFormulation::AugmentedLagrangian)) {
        Some("augmented-Lagrangian contact (its multipliers are not mapped; use formulation: Barrier())")
    } else {
        None
    }
}

/// `refine: Some((tolerance: T, passes: N))` of a step.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RefineSpec {
    /// Relative shape error asked for, (hκ)²/8 per element (as `Auto`'s tolerance).
    pub tolerance: f64,
    /// Refinement passes (solve → indicator → remesh → map → continue), default 1.
    #[serde(default = "one")]
    pub passes: usize,
    /// Relax the mapped directors with the mid-surface held before continuing (as mesh
    /// sequencing does; default false: measured without it, the Peirce strip's two passes
    /// took 0.04 instead of 0.13 s CPU and 37 instead of 40 Newton iterations per
    /// continuation, the sheet on the sphere 2.5 instead of 3.3 s, 146 / 348 instead of 138 /
    /// 311 time steps / iterations, the same rest states to the reported digits).
    #[serde(default)]
    pub relax_directors: bool,
    /// Relax the mapped state's membrane before continuing (`refine::relax`: proximal Newton
    /// stages with a normal spring; default true). False continues from the interpolated
    /// state (the behaviour before; for comparison).
    #[serde(default = "yes")]
    pub relax_membrane: bool,
}

fn yes() -> bool {
    true
}

fn one() -> usize {
    1
}

/// Most passes accepted (each may refine by 4 per direction).
pub const MAX_PASSES: usize = 6;

/// Refuses `refine` where it is not defined (`crate::refine`'s module doc), the field
/// located.
pub fn check_refine(scene: &Scene, loc: &Locator) -> Result<(), SceneError> {
    let last = scene.steps.len().saturating_sub(1);
    for (k, s) in scene.steps.iter().enumerate() {
        let Some(r) = &s.refine else { continue };
        let field = format!("steps[{}].refine", s.name);
        let bad = |key: &str, msg: String| Err(loc.at(Some(&s.name), Some(key), format!("{field}{}", if key == "refine" { String::new() } else { format!(".{key}") }), msg));
        if k != last {
            return bad("refine", "refinement continues the last step on the refined mesh: only the last step may have refine".into());
        }
        if !(r.tolerance.is_finite() && r.tolerance > 0.0 && r.tolerance < 0.5) {
            return bad("tolerance", format!("expected a relative shape error between 0 and 0.5, found {}", r.tolerance));
        }
        if r.passes == 0 || r.passes > MAX_PASSES {
            return bad("passes", format!("expected 1 to {MAX_PASSES} passes, found {}", r.passes));
        }
        match &s.kind {
            StepKind::Static => {}
            StepKind::Dynamic(ds) if ds.duration == 0.0 && matches!(ds.scheme, crate::solver::TimeScheme::BackwardEuler) => {}
            _ => return bad("refine", "refinement continues a Static step or a Dynamic step to rest (backward Euler, no duration); this step is neither".into()),
        }
        if s.linear {
            return bad("refine", "a linear step has no nonlinear state to continue: remove linear: true or refine".into());
        }
        if let Some(g) = &scene.garment {
            // Garment panels are remeshed by the pattern mesher (`refine::garment`).
            if !scene.parts.is_empty() {
                return bad("refine", "refinement remeshes either a garment's panels or generated rectangles; this scene has both".into());
            }
            if crate::garment::laminate::has_auto(g) {
                return bad("refine", "a garment with ply_model Auto is solved in two passes (analysis_auto), which refinement does not continue".into());
            }
        }
        let other = unmapped(scene).filter(|&w| w != "a garment");
        if let Some(what) = other {
            return bad("refine", format!("refinement remeshes generated rectangles and garment panels only; this scene has {what}"));
        }
        for p in &scene.parts {
            if !matches!(p.mesh, MeshSpec::Rectangle { .. } | MeshSpec::SizedRectangle { .. } | MeshSpec::GradedRectangle { .. }) {
                return bad("refine", format!("part {}: refinement remeshes Rectangle, SizedRectangle and GradedRectangle parts only", p.name));
            }
        }
    }
    Ok(())
}
