//! The discrete model: nodes, elements, sections, degrees of freedom and loads.
//!
//! Global unknown numbering: node n owns DOFs 5n..5n+5 = (ux, uy, uz, α1, α2), the tilts
//! taken in the node's current director frame. Fixed and prescribed DOFs are removed from
//! the equation system; the rest are numbered 0..n_free.

pub mod prolong;

use nalgebra::Vector3;

use crate::element::{DirectorFrame, Section, ShellElement, NODE_DOFS};

/// Translational and director-tilt DOFs for supports (scene files name them; the solver's
/// displacement control drives one).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Dof {
    Ux,
    Uy,
    Uz,
    /// Tilt of the director towards global x stays zero.
    TiltX,
    /// Tilt of the director towards global y stays zero.
    TiltY,
    /// Tilt of the director towards global z stays zero.
    TiltZ,
}

/// Marker for a DOF that has no equation (fixed or prescribed).
pub const FIXED: usize = usize::MAX;

/// One shell element of the model.
#[derive(Clone, Debug)]
pub struct ElementDef {
    /// Global node numbers, counter-clockwise about the director.
    pub nodes: [usize; 4],
    /// Index into [`Model::sections`].
    pub section: usize,
    /// Index into [`Model::parts`].
    pub part: usize,
    /// Material grain direction (lamina e1), if any.
    pub grain: Option<Vector3<f64>>,
}

/// Where a part's nodes and elements sit in the global numbering.
#[derive(Clone, Debug)]
pub struct PartInfo {
    /// Part name from the scene.
    pub name: String,
    /// First global node.
    pub first_node: usize,
    /// Number of nodes.
    pub n_nodes: usize,
    /// First global element.
    pub first_element: usize,
    /// Number of elements.
    pub n_elements: usize,
    /// Mass per reference area (0: massless), for lumped masses.
    pub areal_density: f64,
}

/// A named load pattern; its magnitude is scaled by the step's factor for this name.
#[derive(Clone, Debug)]
pub struct Load {
    /// Name used by the steps' scale tables.
    pub name: String,
    /// What the pattern applies at unit scale.
    pub kind: LoadKind,
}

/// Kinds of load pattern, all given at unit scale.
#[derive(Clone, Debug)]
pub enum LoadKind {
    /// Dead forces on node translations.
    Forces(Vec<(usize, Vector3<f64>)>),
    /// Moments on nodes about fixed global axes (virtual work m·δω, δω = d × δd).
    Moments(Vec<(usize, Vector3<f64>)>),
    /// Prescribed translations: (global DOF, value).
    Displacements(Vec<(usize, f64)>),
}

/// Marker in [`DofMap::tie_of`] for a DOF that is not the slave of a tie.
pub const UNTIED: u32 = u32::MAX;

/// A multipoint constraint on one DOF component (master–slave tie, e.g. a seam):
/// u_s = Σ_m w_m u_m + c·λ, with λ the scale of load pattern `load` (a moving offset that
/// drives a seam gap closed) or 0. Eliminated by the master–slave transformation u = T û
/// (Cook et al. 2002, §9.2; Felippa, IFEM ch. 8): K̂ = Tᵀ K T, f̂ = Tᵀ f, so the reduced
/// system stays symmetric positive definite without multipliers.
///
/// A translation tie may also carry director terms (`links`, exact rigid links through the
/// thickness): u_s,k = Σ_m w_m u_m,k + Σ_(n,Z) Z (d_n − d_n⁰)_k + c·λ, i.e. the slave sits at
/// the offset Z along master node n's current director — exact at any rotation. Its
/// linearisation δu_s,k = … + Z (t1,k δα1 + t2,k δα2) is refreshed from the current frames at
/// every assembly, with the consistent second-order term −Z (r_s·d_n) I₂ on n's tilts
/// (r_s: the slave's tie force), so the reduced tangent stays symmetric.
#[derive(Clone, Debug, Default)]
pub struct Tie {
    /// Global DOF (5 n + k) of the slave.
    pub slave: usize,
    /// Global master DOFs and weights.
    pub masters: Vec<(usize, f64)>,
    /// Offset c of the slave from the weighted masters at unit load scale.
    pub offset: f64,
    /// Load pattern scaling the offset.
    pub load: Option<usize>,
    /// Director terms (master node n, offset Z along its director) of a translation tie.
    pub links: Vec<(usize, f64)>,
}

/// Current frames (t1, t2, d) of the nodes whose directors carry rigid-link offsets
/// ([`Tie::links`]), refreshed from the state at every assembly: the linearisation point of
/// the state-dependent tie weights. Interior mutability so that a solver holding `&Model`
/// can relinearise.
#[derive(Debug, Default)]
pub struct LinkFrames(std::sync::RwLock<Vec<[Vector3<f64>; 3]>>);

impl Clone for LinkFrames {
    fn clone(&self) -> Self {
        Self(std::sync::RwLock::new(self.get()))
    }
}

impl LinkFrames {
    fn get(&self) -> Vec<[Vector3<f64>; 3]> {
        match self.0.read() {
            Ok(g) => g.clone(),
            Err(p) => p.into_inner().clone(),
        }
    }

    fn with<R>(&self, f: impl FnOnce(&[[Vector3<f64>; 3]]) -> R) -> R {
        match self.0.read() {
            Ok(g) => f(&g),
            Err(p) => f(&p.into_inner()),
        }
    }

    fn set(&self, v: Vec<[Vector3<f64>; 3]>) {
        match self.0.write() {
            Ok(mut g) => *g = v,
            Err(p) => *p.into_inner() = v,
        }
    }
}

/// Numbering of the free DOFs.
#[derive(Clone, Debug)]
pub struct DofMap {
    /// Equation number of each global DOF, or [`FIXED`] (fixed, prescribed or tied slave).
    pub eq: Vec<usize>,
    /// Number of equations.
    pub n_free: usize,
    /// Ties after substitution of chained slaves (no master is a slave).
    pub ties: Vec<Tie>,
    /// For each global DOF, the index of the tie it is the slave of, or [`UNTIED`].
    pub tie_of: Vec<u32>,
    /// For each tie, its free masters as (equation, weight).
    pub tie_eqs: Vec<Vec<(usize, f64)>>,
    /// Nodes whose directors carry rigid-link offsets (sorted).
    pub link_nodes: Vec<usize>,
    /// For each tie, its director terms as (index into `link_nodes`, offset Z).
    pub tie_links: Vec<Vec<(usize, f64)>>,
    /// Ties with director terms.
    pub link_ties: Vec<usize>,
    /// Current frames of `link_nodes` (the linearisation point).
    pub link_frames: LinkFrames,
}

impl DofMap {
    /// Numbers every DOF not flagged in `fixed`.
    pub fn new(fixed: &[bool]) -> Self {
        let mut n_free = 0;
        let eq = fixed
            .iter()
            .map(|&f| {
                if f {
                    FIXED
                } else {
                    n_free += 1;
                    n_free - 1
                }
            })
            .collect();
        Self {
            eq,
            n_free,
            ties: Vec::new(),
            tie_of: vec![UNTIED; fixed.len()],
            tie_eqs: Vec::new(),
            link_nodes: Vec::new(),
            tie_links: Vec::new(),
            link_ties: Vec::new(),
            link_frames: LinkFrames::default(),
        }
    }

    /// Numbers every DOF that is neither flagged in `fixed` nor the slave of one of `ties`.
    /// Chains (a master that is itself a slave) are substituted; a slave that is also fixed
    /// is dropped when all its masters are fixed (consistent), and is an error otherwise.
    pub fn with_ties(fixed: &[bool], ties: Vec<Tie>) -> Result<Self, String> {
        let n = fixed.len();
        let mut slave_of = vec![UNTIED; n];
        for (i, t) in ties.iter().enumerate() {
            if t.slave >= n || t.masters.iter().any(|&(m, _)| m >= n) || t.links.iter().any(|&(m, _)| NODE_DOFS * m >= n) {
                return Err(format!("tie {i} refers to a DOF beyond the model's {n} DOFs"));
            }
            if slave_of[t.slave] != UNTIED {
                return Err(format!("DOF {} (node {}) is the slave of two ties", t.slave, t.slave / NODE_DOFS));
            }
            slave_of[t.slave] = i as u32;
        }
        // Substitute chained masters until every master is independent.
        let mut resolved = ties.clone();
        for t in resolved.iter_mut() {
            for _round in 0..=ties.len() {
                if !t.masters.iter().any(|&(m, _)| slave_of[m] != UNTIED) {
                    break;
                }
                let mut next: Vec<(usize, f64)> = Vec::new();
                for &(m, w) in &t.masters {
                    let j = slave_of[m];
                    if j == UNTIED {
                        next.push((m, w));
                    } else {
                        let u = &ties[j as usize];
                        if u.offset != 0.0 {
                            if t.offset == 0.0 {
                                t.load = u.load;
                            } else if t.load != u.load {
                                return Err(format!(
                                    "chained ties at node {} close their gaps with different load patterns",
                                    t.slave / NODE_DOFS
                                ));
                            }
                            t.offset += w * u.offset;
                        }
                        next.extend(u.masters.iter().map(|&(mm, ww)| (mm, w * ww)));
                        t.links.extend(u.links.iter().map(|&(nn, z)| (nn, w * z)));
                    }
                }
                if next.iter().any(|&(m, _)| m == t.slave) {
                    return Err(format!("ties form a cycle through DOF {} (node {})", t.slave, t.slave / NODE_DOFS));
                }
                t.masters = next;
            }
            if t.masters.iter().any(|&(m, _)| slave_of[m] != UNTIED) {
                return Err(format!("ties form a cycle through DOF {} (node {})", t.slave, t.slave / NODE_DOFS));
            }
            // Merge repeated masters.
            t.masters.sort_by_key(|&(m, _)| m);
            t.masters.dedup_by(|b, a| {
                if a.0 == b.0 {
                    a.1 += b.1;
                    true
                } else {
                    false
                }
            });
            t.masters.retain(|&(_, w)| w != 0.0);
            t.links.sort_by_key(|&(m, _)| m);
            t.links.dedup_by(|b, a| {
                if a.0 == b.0 {
                    a.1 += b.1;
                    true
                } else {
                    false
                }
            });
            t.links.retain(|&(_, z)| z != 0.0);
            if !t.links.is_empty() && t.slave % NODE_DOFS >= 3 {
                return Err(format!("tie of DOF {} (node {}): director offsets apply to translations only", t.slave, t.slave / NODE_DOFS));
            }
        }
        let mut kept = Vec::with_capacity(resolved.len());
        for t in resolved {
            if fixed[t.slave] {
                let link_fixed = t.links.iter().all(|&(m, _)| fixed[NODE_DOFS * m + 3] && fixed[NODE_DOFS * m + 4]);
                if t.masters.iter().all(|&(m, _)| fixed[m]) && link_fixed {
                    continue;
                }
                return Err(format!(
                    "node {} is supported but tied to free nodes; support both sides of the seam or neither",
                    t.slave / NODE_DOFS
                ));
            }
            kept.push(t);
        }
        let mut no_eq = fixed.to_vec();
        for t in &kept {
            no_eq[t.slave] = true;
        }
        let mut map = Self::new(&no_eq);
        map.tie_of = vec![UNTIED; n];
        for (i, t) in kept.iter().enumerate() {
            map.tie_of[t.slave] = i as u32;
        }
        map.tie_eqs = kept
            .iter()
            .map(|t| t.masters.iter().filter(|&&(m, _)| map.eq[m] != FIXED).map(|&(m, w)| (map.eq[m], w)).collect())
            .collect();
        let mut link_nodes: Vec<usize> = kept.iter().flat_map(|t| t.links.iter().map(|&(m, _)| m)).collect();
        link_nodes.sort_unstable();
        link_nodes.dedup();
        map.tie_links = kept
            .iter()
            .map(|t| t.links.iter().filter_map(|&(m, z)| link_nodes.binary_search(&m).ok().map(|i| (i, z))).collect())
            .collect();
        map.link_ties = (0..kept.len()).filter(|&i| !kept[i].links.is_empty()).collect();
        map.link_frames.set(vec![[Vector3::zeros(); 3]; link_nodes.len()]);
        map.link_nodes = link_nodes;
        map.ties = kept;
        Ok(map)
    }

    /// Sets the linearisation point of the rigid-link ties to the director frames `frames`
    /// (called at every assembly).
    pub fn refresh_links(&self, frames: &[DirectorFrame]) {
        if self.link_nodes.is_empty() {
            return;
        }
        self.link_frames.set(self.link_nodes.iter().map(|&n| [frames[n].t1, frames[n].t2, frames[n].d]).collect());
    }

    /// Whether tie `t` has director terms.
    pub fn has_links(&self, t: usize) -> bool {
        self.tie_links.get(t).is_some_and(|l| !l.is_empty())
    }

    /// Current weights of tie `t`'s director terms on global tilt DOFs: for each term
    /// (n, Z) of a slave component k, (5n+3, Z t1,k) and (5n+4, Z t2,k).
    fn link_weights(&self, t: usize) -> Vec<(usize, f64)> {
        let k = self.ties[t].slave % NODE_DOFS;
        self.link_frames.with(|fr| {
            let mut out = Vec::with_capacity(2 * self.tie_links[t].len());
            for &(i, z) in &self.tie_links[t] {
                let n = self.link_nodes[i];
                let f = fr.get(i).copied().unwrap_or([Vector3::zeros(); 3]);
                out.push((NODE_DOFS * n + 3, z * f[0][k]));
                out.push((NODE_DOFS * n + 4, z * f[1][k]));
            }
            out
        })
    }

    /// Equations and weights of a global DOF that is not itself the slave of a link tie.
    fn expand_plain(&self, g: usize, w: f64, out: &mut Vec<(usize, f64)>) {
        if self.eq[g] != FIXED {
            out.push((self.eq[g], w));
        } else if self.tie_of[g] != UNTIED {
            out.extend(self.tie_eqs[self.tie_of[g] as usize].iter().map(|&(e, v)| (e, w * v)));
        }
    }

    /// Adds the consistent second-order term of the rigid-link ties to the reduced tangent
    /// (upper triangle `values` on `pattern`): for a tie with director term (n, Z) on slave
    /// component k, ∂²(Z d_n,k)/∂α_a∂α_b = −Z d_n,k δ_ab (exponential map), times the slave's
    /// tie force r_s = f_int,s − f_ext,s (all-DOF vectors, slave entries kept by folding).
    /// Each term reaches the caller as `add(equations, c)`: add c·wᵢwⱼ at every pair of the
    /// weighted equations (i, wᵢ), (j, wⱼ) (the assembler's `Pattern::add_weighted`).
    pub fn add_link_stiffness(&self, f_int: &[f64], f_ext: &[f64], add: &mut dyn FnMut(&[(usize, f64)], f64)) {
        if self.link_ties.is_empty() {
            return;
        }
        let mut coef = vec![0.0; self.link_nodes.len()];
        self.link_frames.with(|fr| {
            for &t in &self.link_ties {
                let s = self.ties[t].slave;
                let k = s % NODE_DOFS;
                let rs = f_int[s] - f_ext[s];
                for &(i, z) in &self.tie_links[t] {
                    if let Some(f) = fr.get(i) {
                        coef[i] -= z * rs * f[2][k];
                    }
                }
            }
        });
        for (i, &c) in coef.iter().enumerate() {
            if c == 0.0 {
                continue;
            }
            let n = self.link_nodes[i];
            for l in 0..2 {
                let mut exp = Vec::new();
                self.expand_plain(NODE_DOFS * n + 3 + l, 1.0, &mut exp);
                add(&exp, c);
            }
        }
    }

    /// Increment of global DOF `g` from the free-DOF increment `du`: its own entry, the
    /// weighted masters' entries for a tied slave, or None for a fixed DOF.
    #[inline]
    pub fn increment(&self, g: usize, du: &[f64]) -> Option<f64> {
        let e = self.eq[g];
        if e != FIXED {
            return Some(du[e]);
        }
        let t = self.tie_of[g];
        if t == UNTIED {
            return None;
        }
        if self.has_links(t as usize) {
            return Some(self.expand(g).iter().map(|&(m, w)| w * du[m]).sum());
        }
        Some(self.tie_eqs[t as usize].iter().map(|&(m, w)| w * du[m]).sum())
    }

    /// Equations and weights global DOF `g` maps to: its own equation (weight 1), a tied
    /// slave's free masters, or none for a fixed DOF (a row of the transformation T).
    pub fn expand(&self, g: usize) -> Vec<(usize, f64)> {
        if self.eq[g] != FIXED {
            return vec![(self.eq[g], 1.0)];
        }
        match self.tie_of[g] {
            UNTIED => Vec::new(),
            t if self.has_links(t as usize) => {
                // Translation masters, then each director term through its node's tilts
                // (their own equations or their tilt ties), repeated equations merged; zero
                // weights are kept so that the sparsity pattern covers every rotation.
                let mut out = self.tie_eqs[t as usize].clone();
                for (gm, w) in self.link_weights(t as usize) {
                    self.expand_plain(gm, w, &mut out);
                }
                out.sort_by_key(|&(e, _)| e);
                out.dedup_by(|b, a| {
                    if a.0 == b.0 {
                        a.1 += b.1;
                        true
                    } else {
                        false
                    }
                });
                out
            }
            t => self.tie_eqs[t as usize].clone(),
        }
    }

    /// Folds the generalised forces of tied slaves onto their masters, f_m += w f_s (the
    /// Tᵀ f of the master–slave transformation); slave entries are kept (tie forces).
    pub fn fold(&self, f: &mut [f64]) {
        for (i, t) in self.ties.iter().enumerate() {
            let fs = f[t.slave];
            for &(m, w) in &t.masters {
                f[m] += w * fs;
            }
            if self.has_links(i) {
                for (gm, w) in self.link_weights(i) {
                    match self.tie_of[gm] {
                        UNTIED => f[gm] += w * fs,
                        j => {
                            for &(mm, ww) in &self.ties[j as usize].masters {
                                f[mm] += w * ww * fs;
                            }
                        }
                    }
                }
            }
        }
    }

    /// Director part Σ_(n,Z) Z (d_n − d_n⁰)_k of tie `t` in `state` (0 without links).
    fn link_displacement(&self, t: usize, state: &State, frames0: &[DirectorFrame]) -> f64 {
        let k = self.ties[t].slave % NODE_DOFS;
        self.tie_links[t].iter().map(|&(i, z)| {
            let n = self.link_nodes[i];
            z * (state.frames[n].d[k] - frames0[n].d[k])
        }).sum()
    }
}

/// Current configuration: mid-surface displacements and director frames. Displacements,
/// not positions, are stored so that small strains are computed without cancellation.
#[derive(Clone, Debug)]
pub struct State {
    /// Node displacements from the reference positions.
    pub u: Vec<Vector3<f64>>,
    /// Current director frames.
    pub frames: Vec<DirectorFrame>,
}

/// The assembled finite-element model.
#[derive(Clone, Debug)]
pub struct Model {
    /// Reference node positions.
    pub x0: Vec<Vector3<f64>>,
    /// Reference director frames (tangent pairs aligned with any tilt constraints).
    pub frames0: Vec<DirectorFrame>,
    /// Elements.
    pub elements: Vec<ElementDef>,
    /// Sections.
    pub sections: Vec<Section>,
    /// Parts.
    pub parts: Vec<PartInfo>,
    /// Free-DOF numbering.
    pub dofs: DofMap,
    /// Load patterns.
    pub loads: Vec<Load>,
}

impl Model {
    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.x0.len()
    }

    /// The reference state.
    pub fn initial_state(&self) -> State {
        State { u: vec![Vector3::zeros(); self.x0.len()], frames: self.frames0.clone() }
    }

    /// Element `e` as a shell element view.
    pub fn element(&self, e: usize) -> ShellElement<'_> {
        let def = &self.elements[e];
        ShellElement {
            x0: def.nodes.map(|n| self.x0[n]),
            d0: def.nodes.map(|n| self.frames0[n].d),
            grain: def.grain,
            section: &self.sections[def.section],
        }
    }

    /// Index of a load pattern by name.
    pub fn load_index(&self, name: &str) -> Option<usize> {
        self.loads.iter().position(|l| l.name == name)
    }

    /// External generalised force (all DOFs) for load scales `scales` (one per pattern) in
    /// configuration `state` (moments map to tilt forces through the current frames).
    pub fn external_force(&self, state: &State, scales: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        for (load, &s) in self.loads.iter().zip(scales) {
            if s == 0.0 {
                continue;
            }
            match &load.kind {
                LoadKind::Forces(list) => {
                    for (n, f) in list {
                        for k in 0..3 {
                            out[NODE_DOFS * n + k] += s * f[k];
                        }
                    }
                }
                LoadKind::Moments(list) => {
                    for (n, m) in list {
                        let t = state.frames[*n].moment_to_tilt_forces(&(m * s));
                        out[NODE_DOFS * n + 3] += t[0];
                        out[NODE_DOFS * n + 4] += t[1];
                    }
                }
                LoadKind::Displacements(_) => {}
            }
        }
        self.dofs.fold(out);
    }

    /// Potential of the applied loads at load scales `scales`: −Σ s f·u over the dead forces
    /// (every node, tied slaves included: their displacement follows the ties, so the
    /// gradient is the folded force). None when a pattern applies moments (moments about
    /// fixed axes acting on finite director rotations are not conservative in general).
    pub fn load_potential(&self, state: &State, scales: &[f64]) -> Option<f64> {
        let mut w = 0.0;
        for (load, &s) in self.loads.iter().zip(scales) {
            if s == 0.0 {
                continue;
            }
            match &load.kind {
                LoadKind::Forces(list) => w += s * list.iter().map(|(n, f)| f.dot(&state.u[*n])).sum::<f64>(),
                LoadKind::Moments(_) => return None,
                LoadKind::Displacements(_) => {}
            }
        }
        Some(-w)
    }

    /// Sets prescribed translations to their values at load scales `scales`.
    pub fn apply_prescribed(&self, state: &mut State, scales: &[f64]) {
        for (load, &s) in self.loads.iter().zip(scales) {
            if let LoadKind::Displacements(list) = &load.kind {
                for &(dof, v) in list {
                    let (n, k) = (dof / NODE_DOFS, dof % NODE_DOFS);
                    state.u[n][k] = s * v;
                }
            }
        }
        // Tied slave translations follow their masters (and any moving offset) exactly.
        for (i, t) in self.dofs.ties.iter().enumerate() {
            if t.slave % NODE_DOFS >= 3 || t.masters.iter().any(|&(m, _)| m % NODE_DOFS >= 3) {
                continue;
            }
            let lambda = t.load.and_then(|l| scales.get(l).copied()).unwrap_or(0.0);
            let v: f64 = t.masters.iter().map(|&(m, w)| w * state.u[m / NODE_DOFS][m % NODE_DOFS]).sum::<f64>()
                + t.offset * lambda
                + self.dofs.link_displacement(i, state, &self.frames0);
            state.u[t.slave / NODE_DOFS][t.slave % NODE_DOFS] = v;
        }
    }

    /// Adds `step` × the free-DOF increment `du` to `state` (translations added, tilts
    /// applied with the exponential map).
    pub fn update(&self, state: &mut State, du: &[f64], step: f64) {
        let eq = &self.dofs.eq;
        // Rigid-link slaves are placed exactly afterwards: keep their moving offset c·λ.
        let linked: Vec<(usize, f64)> = self
            .dofs
            .link_ties
            .iter()
            .filter(|&&t| self.dofs.ties[t].masters.iter().all(|&(m, _)| m % NODE_DOFS < 3))
            .map(|&t| (t, self.link_residue(t, state)))
            .collect();
        for n in 0..self.n_nodes() {
            let base = NODE_DOFS * n;
            for k in 0..3 {
                if eq[base + k] != FIXED {
                    state.u[n][k] += step * du[eq[base + k]];
                } else if let Some(d) = self.dofs.increment(base + k, du) {
                    state.u[n][k] += step * d;
                }
            }
            let a1 = self.dofs.increment(base + 3, du).map_or(0.0, |d| step * d);
            let a2 = self.dofs.increment(base + 4, du).map_or(0.0, |d| step * d);
            if a1 != 0.0 || a2 != 0.0 {
                state.frames[n] = state.frames[n].tilted([a1, a2]);
            }
        }
        for (t, c) in linked {
            let s = self.dofs.ties[t].slave;
            let v = state.u[s / NODE_DOFS][s % NODE_DOFS] - self.link_residue(t, state) + c;
            state.u[s / NODE_DOFS][s % NODE_DOFS] = v;
        }
    }

    /// u_s − Σ w u_m − Σ Z (d_n − d_n⁰)_k of a translation tie: its moving offset c·λ when
    /// the slave satisfies the tie exactly.
    fn link_residue(&self, t: usize, state: &State) -> f64 {
        let tie = &self.dofs.ties[t];
        let s = tie.slave;
        state.u[s / NODE_DOFS][s % NODE_DOFS]
            - tie.masters.iter().map(|&(m, w)| w * state.u[m / NODE_DOFS][m % NODE_DOFS]).sum::<f64>()
            - self.dofs.link_displacement(t, state, &self.frames0)
    }

    /// Displacement of node `n` in `state`.
    pub fn displacement(&self, state: &State, n: usize) -> Vector3<f64> {
        state.u[n]
    }

    /// Current position of node `n` in `state`.
    pub fn position(&self, state: &State, n: usize) -> Vector3<f64> {
        self.x0[n] + state.u[n]
    }
}
