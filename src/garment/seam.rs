//! Seams as master–slave ties between two node rows (spans).
//!
//! Non-matching rows are tied by the dual mortar method (Wohlmuth 2000, SIAM J. Numer. Anal.
//! 38:989; Popp et al. 2010): along the seam, parametrised by normalised arc length on each
//! span, the constraint ∫ ψ_s (u_slave − u_master) ds = 0 with the dual shape functions
//! ψ_s of the slave row (on a slave segment ψ_a = 2N_a − N_b, biorthogonal: ∫ψ_a N_b =
//! δ_ab ∫N_a) gives the slave node explicitly: u_s = Σ_m (M_sm / D_s) u_m, D_s = ∫ N_s,
//! M_sm = ∫ ψ_s N_m (master–slave MFC elimination; Felippa, IFEM ch. 8–9). The weights
//! reproduce linear fields and fold a uniform seam traction onto the master nodes as its
//! consistent nodal forces, so the tie passes the patch test across non-matching rows; for
//! matching rows they are the identity. Kinds:
//! - plain: translations tied, director free on both sides — a hinge line;
//! - welded (bonded): translations and the two director tilts tied, so the director is
//!   continuous across the seam;
//! - taped: welded, plus a stiffer strip of elements within the seam allowance (the caller
//!   assigns those elements the tape section).
//!
//! Tilts live in each node's own tangent frame, so a tilt tie maps the interpolated master
//! director variation into the slave frame: α_s,k = Σ_m w_m Σ_l (t_s,k · t_m,l) α_m,l. For
//! coincident nodes the slave frame is made equal to the master's, and the tie is then exact
//! for rotations of any size; across non-matching rows on a curved seam it is the
//! linearisation about the reference frames.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::element::{DirectorFrame, NODE_DOFS};
use crate::model::Tie;

/// How a seam joins its spans.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum SeamKind {
    /// Translations tied, rotations free (a hinge).
    Plain,
    /// Translations and director tilts tied (bonded, welded).
    Welded,
    /// Welded plus a stiffer strip of the seam-allowance width: elements whose centre lies
    /// within `width` of the seam get their stiffness scaled by `stiffness_factor`.
    Taped { width: f64, stiffness_factor: f64 },
}

impl SeamKind {
    /// Whether the director tilts are tied.
    pub fn ties_rotations(&self) -> bool {
        !matches!(self, SeamKind::Plain)
    }

    /// What is wrong with the kind's parameters, if anything.
    pub fn problem(&self) -> Option<&'static str> {
        match *self {
            SeamKind::Taped { width, stiffness_factor }
                if !(width.is_finite() && width >= 0.0 && stiffness_factor.is_finite() && stiffness_factor > 0.0) =>
            {
                Some("a tape needs a non-negative width and a positive stiffness factor")
            }
            _ => None,
        }
    }
}

/// A built seam: its spans, slave tributary lengths and the range of its ties.
#[derive(Clone, Debug)]
pub struct SeamInfo {
    /// Seam name.
    pub name: String,
    /// Kind.
    pub kind: SeamKind,
    /// Master node row (global nodes, in span order).
    pub master: Vec<usize>,
    /// Slave node row (global nodes, in span order).
    pub slave: Vec<usize>,
    /// Reference length along the slave span belonging to each slave node.
    pub tributary: Vec<f64>,
    /// Interpolation of each slave node on the master row: (master node, weight) pairs.
    pub weights: Vec<Vec<(usize, f64)>>,
    /// Initial gap g₀ = x_s − Σ w x_m of each slave node (the rest offset of a compliant tie).
    pub rest: Vec<Vector3<f64>>,
    /// Stitch stiffness per length (N/m per metre of seam, i.e. N/m²): the translations are
    /// joined by springs ([`super::compliant`]) instead of ties. None: rigid ties.
    pub stiffness: Option<f64>,
    /// Seam strength (N per metre of seam), for the utilisation; None: not given.
    pub strength: Option<f64>,
}

/// Cumulative normalised arc length of a polyline through `row`.
fn arc_fractions(x: &[Vector3<f64>], row: &[usize]) -> Vec<f64> {
    let mut s = vec![0.0; row.len()];
    for i in 1..row.len() {
        s[i] = s[i - 1] + (x[row[i]] - x[row[i - 1]]).norm();
    }
    let total = s.last().copied().unwrap_or(0.0);
    if total > 0.0 {
        s.iter_mut().for_each(|v| *v /= total);
    }
    s
}

/// Dual mortar weights (see the module doc) of each slave node on the master row, rows
/// parametrised by normalised arc length `ss` (slave) and `sm` (master); weights below
/// 1e-12 are dropped and one within `snap` of 1 is snapped, so matching nodes get a single
/// master of weight 1; the rows' end nodes are point ties ([`point_tie_row_ends`]).
fn mortar_weights(master: &[usize], sm: &[f64], ss: &[f64], snap: f64) -> Vec<Vec<(usize, f64)>> {
    let (nm, ns) = (master.len(), ss.len());
    if nm == 1 {
        return vec![vec![(master[0], 1.0)]; ns];
    }
    if ns == 1 {
        // A single slave node has no segment to integrate over: interpolate at its s.
        let k = sm.windows(2).position(|w| w[1] >= ss[0]).unwrap_or(nm - 2);
        let len = sm[k + 1] - sm[k];
        let xi = if len > 0.0 { ((ss[0] - sm[k]) / len).clamp(0.0, 1.0) } else { 0.0 };
        return vec![vec![(master[k], 1.0 - xi), (master[k + 1], xi)]];
    }
    let mut d = vec![0.0; ns];
    let mut m = vec![vec![0.0; nm]; ns];
    // Two-point Gauss rule on each overlap: ψ_s N_m is quadratic there, so it is exact.
    let gauss = [0.5 - 0.5 / 3f64.sqrt(), 0.5 + 0.5 / 3f64.sqrt()];
    for j in 0..ns - 1 {
        let (a, b) = (ss[j], ss[j + 1]);
        let ls = b - a;
        if ls <= 0.0 {
            continue;
        }
        d[j] += 0.5 * ls;
        d[j + 1] += 0.5 * ls;
        for k in 0..nm - 1 {
            let (c, e) = (sm[k], sm[k + 1]);
            let (lo, hi) = (a.max(c), b.min(e));
            if hi <= lo || e <= c {
                continue;
            }
            for g in gauss {
                let t = lo + g * (hi - lo);
                let wq = 0.5 * (hi - lo);
                let (na, nb) = ((b - t) / ls, (t - a) / ls);
                let (psi_a, psi_b) = (2.0 * na - nb, 2.0 * nb - na);
                let (nc, ne) = ((e - t) / (e - c), (t - c) / (e - c));
                m[j][k] += wq * psi_a * nc;
                m[j][k + 1] += wq * psi_a * ne;
                m[j + 1][k] += wq * psi_b * nc;
                m[j + 1][k + 1] += wq * psi_b * ne;
            }
        }
    }
    let mut w: Vec<Vec<f64>> = m.iter().zip(&d).map(|(row, &ds)| row.iter().map(|v| if ds > 0.0 { v / ds } else { 0.0 }).collect()).collect();
    point_tie_row_ends(&mut w, &d);
    w.iter()
        .map(|row| {
            let w: Vec<(usize, f64)> = row.iter().enumerate().filter(|(_, v)| v.abs() > 1e-12).map(|(k, &v)| (master[k], v)).collect();
            match w.iter().find(|(_, v)| (v - 1.0).abs() <= snap) {
                Some(&(n, _)) => vec![(n, 1.0)],
                None => w,
            }
        })
        .collect()
}

/// Makes the slave row's end nodes point ties on the master row's end nodes (weight 1),
/// so that seams meeting at a row end close exactly there (a tie whose slave is already
/// taken is dropped as redundant, and a dual-mortar end weight of, say, 0.93 instead of 1
/// left the dropped tie's seam open by the other weights times the deformation: 1.2 mm on
/// the suit's underarm). The end's change of weight, Δw_0m = δ_m0 − w_0m, is moved to its
/// neighbour with the ratio of their tributary lengths, w_1m −= (d_0/d_1) Δw_0m, so that
/// the fold Σ_s w_sm d_s of a uniform slave traction onto the master nodes is unchanged;
/// Σ_m Δw_0m = 0 and Σ_m Δw_0m s_m = 0 (both rows start at s = 0), so the neighbour still
/// reproduces constant and linear fields. Rows of fewer than three slave nodes are left as
/// they are (no neighbour to take the share).
fn point_tie_row_ends(w: &mut [Vec<f64>], d: &[f64]) {
    let ns = w.len();
    if ns < 3 {
        return;
    }
    let nm = w[0].len();
    for (end, next, m_end) in [(0, 1, 0), (ns - 1, ns - 2, nm - 1)] {
        if d[next] <= 0.0 {
            continue;
        }
        let ratio = d[end] / d[next];
        for k in 0..nm {
            let target = if k == m_end { 1.0 } else { 0.0 };
            let change = target - w[end][k];
            w[next][k] -= ratio * change;
            w[end][k] = target;
        }
    }
}

/// Half-segment (tributary) lengths of the nodes of a row.
pub fn tributary_lengths(x: &[Vector3<f64>], row: &[usize]) -> Vec<f64> {
    let mut w = vec![0.0; row.len()];
    for i in 1..row.len() {
        let l = (x[row[i]] - x[row[i - 1]]).norm();
        w[i - 1] += 0.5 * l;
        w[i] += 0.5 * l;
    }
    w
}

/// Ties of one seam: slave row ↔ master row by normalised arc length (both rows in the same
/// running direction). With `closing = Some(load)`, the initial gap g₀ = x_s − Σ w x_m is
/// closed in proportion to that load pattern's scale (offset −g₀·λ); otherwise the initial
/// gap is kept. For welded and taped seams with coincident nodes the slave frame is set to
/// the master's so the tilt ties are exact. Returns the ties and the seam's description.
pub fn seam_ties(
    name: &str,
    kind: SeamKind,
    x0: &[Vector3<f64>],
    frames0: &mut [DirectorFrame],
    master: &[usize],
    slave: &[usize],
    closing: Option<usize>,
) -> Result<(Vec<Tie>, SeamInfo), String> {
    if master.is_empty() || slave.is_empty() {
        return Err(format!("seam \"{name}\": both spans need at least one node"));
    }
    if let Some(n) = slave.iter().find(|n| master.contains(n)) {
        return Err(format!("seam \"{name}\": node {n} is on both spans"));
    }
    let sm = arc_fractions(x0, master);
    let ss = arc_fractions(x0, slave);
    let length = |row: &[usize]| row.windows(2).map(|w| (x0[w[1]] - x0[w[0]]).norm()).sum::<f64>();
    let scale = length(master).max(length(slave)).max(1e-300);
    let mut ties = Vec::new();
    let weights = mortar_weights(master, &sm, &ss, 1e-9);
    for (&s, w) in slave.iter().zip(&weights) {
        let target: Vector3<f64> = w.iter().map(|&(m, c)| x0[m] * c).sum();
        let gap0 = x0[s] - target;
        for k in 0..3 {
            let (offset, load) = match closing {
                Some(l) => (-gap0[k], Some(l)),
                None => (0.0, None),
            };
            ties.push(Tie { slave: NODE_DOFS * s + k, masters: w.iter().map(|&(m, c)| (NODE_DOFS * m + k, c)).collect(), offset, load, links: Vec::new() });
        }
        if kind.ties_rotations() {
            // Coincident with a single master: share its frame so the tilts are the same.
            if w.len() == 1 && gap0.norm() <= 1e-9 * scale && frames0[s].d.dot(&frames0[w[0].0].d) > 1.0 - 1e-12 {
                frames0[s] = DirectorFrame::new(frames0[s].d, Some(frames0[w[0].0].t1));
            }
            let fs = frames0[s];
            let ts = [fs.t1, fs.t2];
            for (k, tk) in ts.iter().enumerate() {
                let mut masters = Vec::new();
                for &(m, c) in w {
                    let tm = [frames0[m].t1, frames0[m].t2];
                    for (l, tl) in tm.iter().enumerate() {
                        let coef = c * tk.dot(tl);
                        if coef.abs() > 1e-14 {
                            masters.push((NODE_DOFS * m + 3 + l, coef));
                        }
                    }
                }
                ties.push(Tie { slave: NODE_DOFS * s + 3 + k, masters, offset: 0.0, load: None, links: Vec::new() });
            }
        }
    }
    let info = SeamInfo {
        name: name.to_string(),
        kind,
        master: master.to_vec(),
        slave: slave.to_vec(),
        tributary: tributary_lengths(x0, slave),
        rest: slave.iter().zip(&weights).map(|(&s, w)| x0[s] - w.iter().map(|&(m, c)| x0[m] * c).sum::<Vector3<f64>>()).collect(),
        weights,
        stiffness: None,
        strength: None,
    };
    Ok((ties, info))
}

/// Makes a seam compliant and/or gives it a strength: with `stiffness` k (N/m², finite and
/// positive) the translation ties of its slaves are removed from `ties` (the caller's ties
/// of this seam) and the seam becomes springs of energy ½ k ℓ_i |x_s − Σ w x_m − g₀|²
/// ([`super::compliant`]); `strength` (N/m, finite and positive) is recorded for the
/// utilisation. A compliant seam cannot be sewn by a `closing` load. Errors name the key.
pub fn make_compliant(
    ties: &mut Vec<Tie>,
    info: &mut SeamInfo,
    stiffness: Option<f64>,
    strength: Option<f64>,
    closing: bool,
) -> Result<(), (&'static str, String)> {
    if let Some(k) = stiffness {
        if !(k.is_finite() && k > 0.0) {
            return Err(("stiffness", format!("expected a positive stitch stiffness per length (N/m²), found {k}")));
        }
        if closing {
            return Err(("stiffness", "a compliant seam (stiffness) cannot be sewn by a closing load yet; drop one of them".into()));
        }
        let slaves: std::collections::HashSet<usize> = info.slave.iter().flat_map(|&s| (0..3).map(move |k| NODE_DOFS * s + k)).collect();
        ties.retain(|t| !slaves.contains(&t.slave));
        info.stiffness = Some(k);
    }
    if let Some(f) = strength {
        if !(f.is_finite() && f > 0.0) {
            return Err(("strength", format!("expected a positive seam strength (N/m), found {f}")));
        }
        info.strength = Some(f);
    }
    Ok(())
}

/// Ties of a rigid link from master node `m` to slave node `s` (e.g. two plies of a stack
/// joined through the thickness at a stitch). The offset r = x_s − x_m splits into Z d_m
/// along the master's director and a tangential rest r_⊥. The director part is exact at any
/// rotation: x_s = x_m + Z d_m (a [`Tie`] director term, relinearised at every assembly:
/// δu_s = δu_m + Z (t1 δα1 + t2 δα2)). A tangential rest (zero for plies offset along a
/// common director) is linearised about the reference frames, δu_s += δθ_m × r_⊥ with
/// δθ = t2 δα1 − t1 δα2. The slave director is tilted with the master's: with parallel
/// directors the slave frame is made equal to the master's, so both stay equal (exact).
pub fn rigid_link(m: usize, s: usize, x0: &[Vector3<f64>], frames0: &mut [DirectorFrame]) -> Vec<Tie> {
    let r = x0[s] - x0[m];
    if frames0[s].d.dot(&frames0[m].d) > 1.0 - 1e-12 {
        frames0[s] = DirectorFrame::new(frames0[s].d, Some(frames0[m].t1));
    }
    let fm = frames0[m];
    let z = r.dot(&fm.d);
    let rt = r - fm.d * z;
    let tangential = rt.norm() > 1e-9 * r.norm();
    let (a1, a2) = (fm.t2.cross(&rt), -fm.t1.cross(&rt));
    let mut ties = Vec::with_capacity(5);
    for k in 0..3 {
        let mut masters = vec![(NODE_DOFS * m + k, 1.0)];
        if tangential && a1[k].abs() > 1e-15 * r.norm() {
            masters.push((NODE_DOFS * m + 3, a1[k]));
        }
        if tangential && a2[k].abs() > 1e-15 * r.norm() {
            masters.push((NODE_DOFS * m + 4, a2[k]));
        }
        let links = if z != 0.0 { vec![(m, z)] } else { Vec::new() };
        ties.push(Tie { slave: NODE_DOFS * s + k, masters, offset: 0.0, load: None, links });
    }
    let fs = frames0[s];
    for (k, tk) in [fs.t1, fs.t2].iter().enumerate() {
        let masters: Vec<(usize, f64)> = [fm.t1, fm.t2]
            .iter()
            .enumerate()
            .map(|(l, tl)| (NODE_DOFS * m + 3 + l, tk.dot(tl)))
            .filter(|&(_, c)| c.abs() > 1e-14)
            .collect();
        ties.push(Tie { slave: NODE_DOFS * s + 3 + k, masters, offset: 0.0, load: None, links: Vec::new() });
    }
    ties
}

impl SeamInfo {
    /// Seam force per unit length at each slave node: the tie force f_int,s − f_ext,s that
    /// the master side exerts on the slave node (translations; all-DOF vectors before or
    /// after folding, slave entries are kept), divided by the node's tributary length.
    pub fn line_forces(&self, f_int: &[f64], f_ext: &[f64]) -> Vec<Vector3<f64>> {
        self.slave
            .iter()
            .zip(&self.tributary)
            .map(|(&s, &l)| {
                let f = Vector3::from_fn(|k, _| f_int[NODE_DOFS * s + k] - f_ext[NODE_DOFS * s + k]);
                if l > 0.0 { f / l } else { f }
            })
            .collect()
    }

    /// Current gap |x_s − Σ w x_m| at each slave node.
    pub fn gaps(&self, position: impl Fn(usize) -> Vector3<f64>) -> Vec<f64> {
        self.slave
            .iter()
            .zip(&self.weights)
            .map(|(&s, w)| (position(s) - w.iter().map(|&(m, c)| position(m) * c).sum::<Vector3<f64>>()).norm())
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Dual mortar weights (Wohlmuth 2000) of a slave row on a master row, matching and
    /// non-matching, the slave graded: they reproduce constant and linear fields exactly,
    /// and fold the consistent nodal forces of a uniform traction on the slave row onto the
    /// consistent nodal forces of the master row (the patch test); matching rows get the
    /// identity, and the rows' end nodes are point ties.
    #[test]
    fn mortar_weights_pass_the_patch_test() {
        for (n_master, n_slave) in [(3, 5), (4, 3), (5, 7), (3, 3)] {
            let xm: Vec<f64> = (0..n_master).map(|i| i as f64 / (n_master - 1) as f64).collect();
            let grade = if n_master == n_slave { 1.0 } else { 1.2 };
            let xs: Vec<f64> = (0..n_slave).map(|i| (i as f64 / (n_slave - 1) as f64).powf(grade)).collect();
            let x: Vec<Vector3<f64>> = xm.iter().chain(&xs).map(|&v| Vector3::new(v, 0.0, 0.0)).collect();
            let mut frames: Vec<DirectorFrame> = x.iter().map(|_| DirectorFrame::new(Vector3::z(), None)).collect();
            let master: Vec<usize> = (0..n_master).collect();
            let slave: Vec<usize> = (n_master..n_master + n_slave).collect();
            let (ties, info) = seam_ties("s", SeamKind::Welded, &x, &mut frames, &master, &slave, None).unwrap();
            assert_eq!(ties.len(), 5 * n_slave);
            for (k, w) in info.weights.iter().enumerate() {
                let sum: f64 = w.iter().map(|p| p.1).sum();
                let lin: f64 = w.iter().map(|&(m, c)| c * x[m].x).sum();
                assert!((sum - 1.0).abs() < 1e-13 && (lin - xs[k]).abs() < 1e-13, "{w:?}");
            }
            let mut folded = vec![0.0; n_master];
            for (w, t) in info.weights.iter().zip(&info.tributary) {
                for &(m, c) in w {
                    folded[m] += c * t;
                }
            }
            let consistent = tributary_lengths(&x, &master);
            for (f, c) in folded.iter().zip(&consistent) {
                assert!((f - c).abs() < 1e-13, "{folded:?} vs {consistent:?}");
            }
            if n_master == n_slave {
                assert!(info.weights.iter().enumerate().all(|(k, w)| w == &vec![(k, 1.0)]));
            }
            // Row ends are point ties on the master row's ends (seam junctions close exactly).
            assert_eq!(info.weights[0], vec![(0, 1.0)]);
            assert_eq!(info.weights[n_slave - 1], vec![(n_master - 1, 1.0)]);
        }
    }
}
