//! Pre-solve report of a built scene (`plyshell check`): each seam's initial gap in the placed,
//! unsewn configuration, and every part whose nodes start on, inside or within the barrier
//! distance of a contact body.
//!
//! Seam gap: for slave node s of a seam, g₀ = |x_s − Σ_m w_sm x_m| with the seam's dual mortar
//! weights w_sm ([`crate::garment::SeamInfo::gaps`]), at the reference positions x₀; the closure
//! load of virtual sewing drives it to zero. Body proximity: the barrier contact's own start
//! test ([`crate::contact::BarrierContact::within`]), gap g = signed distance − h/2 against the
//! barrier distance d̂ (Li et al. 2020, IPC, ACM TOG 39(4):49, the log barrier active for g < d̂).

use serde::Serialize;

use crate::contact::{BarrierContact, BarrierSettings};
use crate::scene::BuiltScene;

/// Relative length difference of a seam's two sides above which the seam is flagged as
/// mis-matched: |L_a − L_b| / max(L_a, L_b) > 3 %. (The build refuses spans differing by more
/// than the garment's `span_tolerance`, 2 % by default; a raised tolerance admits them.)
pub const SEAM_MISMATCH: f64 = 0.03;

/// Initial state of one seam (one ply of a multi-ply seam).
#[derive(Clone, Debug, Serialize)]
pub struct SeamCheck {
    /// Seam name (`seam/ply` for the plies of a multi-ply seam).
    pub name: String,
    /// Number of matched node pairs (slave nodes, each tied to its interpolated master point).
    pub pairs: usize,
    /// Length of side a, the master row, along its nodes at x₀ (m).
    pub length_a: f64,
    /// Length of side b, the slave row (m).
    pub length_b: f64,
    /// |L_a − L_b| / max(L_a, L_b).
    pub length_mismatch: f64,
    /// Whether the mismatch exceeds [`SEAM_MISMATCH`].
    pub mismatched: bool,
    /// Largest initial gap over the pairs (m).
    pub max_gap: f64,
    /// Mean initial gap over the pairs (m).
    pub mean_gap: f64,
}

/// Severity of a finding.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Level {
    /// The solve would refuse the scene (barrier contact starting on or inside a body).
    Error,
    /// The solve runs, but the start is suspect.
    Warning,
    /// Penalty contact with only the faces touching (the mid-surface outside): a support the
    /// part is placed resting on.
    Info,
}

/// A part with nodes starting on, inside or near one contact body.
#[derive(Clone, Debug, Serialize)]
pub struct PartNearBody {
    /// Contact body name.
    pub body: String,
    /// Part name (`panel` or `panel/ply`).
    pub part: String,
    /// Where the part is defined in the scene: `garment.panels[panel]` or `parts[name]`.
    pub field: String,
    /// Nodes whose shell face starts on or inside the body (g ≤ 0).
    pub inside: usize,
    /// Nodes within the barrier distance (0 < g < d̂); 0 for the penalty formulation.
    pub within_barrier: usize,
    /// Deepest penetration −min g of the face into the body (m), 0 when none is inside.
    pub deepest_penetration: f64,
    /// Smallest gap g over the reported nodes (m; negative: inside).
    pub min_gap: f64,
    /// Nodes whose mid-surface itself starts inside the body (g < −h/2).
    pub midsurface_inside: usize,
    /// Error when barrier contact would refuse the start; under penalty contact a warning
    /// when a mid-surface node is inside, else info; within the barrier distance a warning.
    pub level: Level,
}

/// The report of `plyshell check` beyond sizes and mesh quality.
#[derive(Clone, Debug, Serialize)]
pub struct CheckReport {
    /// Scene name.
    pub scene: String,
    /// Parts, nodes, elements and free DOFs.
    pub parts: usize,
    /// Number of nodes.
    pub nodes: usize,
    /// Number of elements.
    pub elements: usize,
    /// Free equations.
    pub free_dofs: usize,
    /// Mismatch tolerance used for the seams ([`SEAM_MISMATCH`]).
    pub seam_mismatch_tolerance: f64,
    /// Seams in build order.
    pub seams: Vec<SeamCheck>,
    /// Contact formulation: "barrier", "penalty", or None without contact bodies.
    pub contact: Option<String>,
    /// Contact body names.
    pub bodies: Vec<String>,
    /// Parts starting on, inside or near a body, by body then part.
    pub near_bodies: Vec<PartNearBody>,
}

impl CheckReport {
    /// Number of error-level findings.
    pub fn errors(&self) -> usize {
        self.near_bodies.iter().filter(|p| p.level == Level::Error).count()
    }
}

/// Polyline length through the rows' nodes at x₀.
fn row_length(x: &[nalgebra::Vector3<f64>], row: &[usize]) -> f64 {
    row.windows(2).map(|w| (x[w[1]] - x[w[0]]).norm()).sum()
}

/// The panel a part name (`panel` or `panel/ply`) belongs to.
fn base(name: &str) -> &str {
    name.split('/').next().unwrap_or(name)
}

/// The scene field defining part `name`: its garment panel, or the `parts` entry.
fn scene_field(built: &BuiltScene, name: &str) -> String {
    match &built.garment {
        Some(g) if g.panels.iter().any(|p| p == base(name)) => format!("garment.panels[{}]", base(name)),
        _ => format!("parts[{name}]"),
    }
}

/// Seam gaps and part–body proximity of `built` at its reference configuration.
pub fn report(scene_name: &str, built: &BuiltScene) -> CheckReport {
    let m = &built.model;
    let x0 = &m.x0;
    let seams = built
        .seams
        .iter()
        .map(|s| {
            let gaps = s.gaps(|n| x0[n]);
            let (la, lb) = (row_length(x0, &s.master), row_length(x0, &s.slave));
            let longer = la.max(lb);
            let mismatch = if longer > 0.0 { (la - lb).abs() / longer } else { 0.0 };
            SeamCheck {
                name: s.name.clone(),
                pairs: gaps.len(),
                length_a: la,
                length_b: lb,
                length_mismatch: mismatch,
                mismatched: mismatch > SEAM_MISMATCH,
                max_gap: gaps.iter().copied().fold(0.0, f64::max),
                mean_gap: if gaps.is_empty() { 0.0 } else { gaps.iter().sum::<f64>() / gaps.len() as f64 },
            }
        })
        .collect();
    let mut near_bodies = Vec::new();
    let (mut contact, mut bodies) = (None, Vec::new());
    if let Some(setup) = built.contact.as_ref().filter(|c| !c.bodies.is_empty()) {
        let barrier = setup.barrier.is_some();
        contact = Some(if barrier { "barrier" } else { "penalty" }.to_string());
        bodies = setup.bodies.iter().map(|b| b.name.clone()).collect();
        // The same participating nodes, offsets and d̂ as the solve's contact (`contact::attach`).
        let c = BarrierContact::new(m, setup.bodies.clone(), &setup.parts, &setup.barrier.clone().unwrap_or_else(BarrierSettings::default));
        let part_of = |node: usize| m.parts.iter().position(|p| (p.first_node..p.first_node + p.n_nodes).contains(&node));
        // (body, part) → (inside, within, min gap, mid-surface inside)
        let mut acc: std::collections::BTreeMap<(usize, usize), (usize, usize, f64, usize)> = Default::default();
        for n in c.within(m, &m.initial_state(), barrier) {
            let Some(p) = part_of(n.node) else { continue };
            let e = acc.entry((n.body, p)).or_insert((0, 0, f64::INFINITY, 0));
            if n.gap <= 0.0 {
                e.0 += 1;
            } else {
                e.1 += 1;
            }
            if n.gap < -n.offset {
                e.3 += 1;
            }
            e.2 = e.2.min(n.gap);
        }
        near_bodies = acc
            .into_iter()
            .map(|((b, p), (inside, within, min_gap, mid))| PartNearBody {
                body: c.bodies[b].name.clone(),
                part: m.parts[p].name.clone(),
                field: scene_field(built, &m.parts[p].name),
                inside,
                within_barrier: within,
                deepest_penetration: if inside > 0 { -min_gap } else { 0.0 },
                min_gap,
                midsurface_inside: mid,
                level: match (barrier, inside > 0) {
                    (true, true) => Level::Error,
                    (true, false) => Level::Warning,
                    (false, _) if mid > 0 => Level::Warning,
                    (false, _) => Level::Info,
                },
            })
            .collect();
    }
    CheckReport {
        scene: scene_name.to_string(),
        parts: m.parts.len(),
        nodes: m.n_nodes(),
        elements: m.elements.len(),
        free_dofs: m.dofs.n_free,
        seam_mismatch_tolerance: SEAM_MISMATCH,
        seams,
        contact,
        bodies,
        near_bodies,
    }
}

/// The report as table lines (stdout) and diagnostics (stderr, each starting `error:` or
/// `warning:`); `locate(anchor, field, message)` places a message in the scene file (the
/// anchor is the quoted seam or panel/part name), e.g. with [`crate::scene::Locator::at_name`].
pub fn table(r: &CheckReport, locate: &dyn Fn(&str, &str, &str) -> String) -> (Vec<String>, Vec<String>) {
    let (mut out, mut diag) = (Vec::new(), Vec::new());
    if !r.seams.is_empty() {
        let w = r.seams.iter().map(|s| s.name.chars().count()).max().unwrap_or(4).max(4);
        out.push(format!("  {:<w$} {:>6} {:>9} {:>9} {:>7} {:>11} {:>11}", "seam", "pairs", "len a m", "len b m", "diff %", "max gap m", "mean gap m"));
        for s in &r.seams {
            let flag = if s.mismatched { "  MISMATCHED" } else { "" };
            out.push(format!(
                "  {:<w$} {:>6} {:>9.4} {:>9.4} {:>7.2} {:>11.4e} {:>11.4e}{flag}",
                s.name,
                s.pairs,
                s.length_a,
                s.length_b,
                100.0 * s.length_mismatch,
                s.max_gap,
                s.mean_gap
            ));
            if s.mismatched {
                let message = format!(
                    "seam '{}': its sides differ in length by {:.1} % ({:.4} m vs {:.4} m; more than {:.0} %): a mis-matched seam",
                    s.name,
                    100.0 * s.length_mismatch,
                    s.length_a,
                    s.length_b,
                    100.0 * r.seam_mismatch_tolerance
                );
                diag.push(format!("warning: {}", locate(base(&s.name), &format!("garment.seams[{}]", base(&s.name)), &message)));
            }
        }
    }
    if let Some(f) = &r.contact {
        out.push(format!("  contact ({f}) with {} bodies: {}", r.bodies.len(), r.bodies.join(", ")));
        if r.near_bodies.is_empty() {
            let zone = if f == "barrier" { "on, inside or within the barrier distance of" } else { "on or inside" };
            out.push(format!("  no part starts {zone} a body"));
        } else {
            let wb = r.near_bodies.iter().map(|p| p.body.chars().count()).max().unwrap_or(4).max(4);
            let wp = r.near_bodies.iter().map(|p| p.part.chars().count()).max().unwrap_or(4).max(4);
            out.push(format!("  {:<wb$} {:<wp$} {:>7} {:>8} {:>12} {:>11}  level", "body", "part", "inside", "near", "deepest m", "min gap m"));
            for p in &r.near_bodies {
                let level = match p.level {
                    Level::Error => "error",
                    Level::Warning => "warning",
                    Level::Info => "info",
                };
                out.push(format!("  {:<wb$} {:<wp$} {:>7} {:>8} {:>12.4e} {:>11.4e}  {level}", p.body, p.part, p.inside, p.within_barrier, p.deepest_penetration, p.min_gap));
                if p.level == Level::Info {
                    continue;
                }
                let message = if p.inside > 0 {
                    let why = if p.level == Level::Error { "barrier contact refuses this start" } else { "their mid-surface is inside; the penalty contact pushes them out in the first increment" };
                    format!(
                        "part '{}' starts inside body '{}': {} node(s) on or inside, deepest by {:.3e} m; {why}: move the part or the body",
                        p.part, p.body, p.inside, p.deepest_penetration
                    )
                } else {
                    format!("part '{}' starts within the barrier distance of body '{}': {} node(s), smallest gap {:.3e} m", p.part, p.body, p.within_barrier, p.min_gap)
                };
                diag.push(format!("{level}: {}", locate(base(&p.part), &p.field, &message)));
            }
        }
    }
    (out, diag)
}
