//! Global assembly: the sparsity pattern is built once, values are scattered many times.
//!
//! Each element keeps a precomputed map from its 20×20 entries to slots of the upper
//! triangle of the CSC matrix, so a Newton iteration only zeroes and adds values (fenris
//! style). Elements are coloured once so that no two elements of a colour share a node; the
//! elements of a colour are evaluated and scattered in parallel (rayon) without locks, since
//! they write disjoint slots and disjoint force entries, colour after colour. Elements with
//! tied DOFs (whose entries go through the constraint weights to other nodes' equations)
//! come afterwards: evaluated in parallel, a chunk at a time, and scattered serially in
//! index order. Every slot receives its contributions in the same order whatever the
//! number of threads, so the assembly is deterministic.

use std::time::Instant;

use rayon::prelude::*;

use std::sync::Mutex;

use crate::element::mixed::{extrapolate, point_count, unknown_change, Mixed, PointRecord};
use crate::element::{orientation, ElemMat, ElemVec, ElementFailure, ElementGeometry, SectionRule, ELEMENT_DOFS, NODE_DOFS};
use crate::material::Voigt5;
use crate::model::{Model, State, FIXED, UNTIED};

mod grow;
pub mod psd;
mod store;
pub use store::CACHE_ELEMENTS;
use psd::project_psd;
use store::{MixedAccess, MixedStore, ResponseCache, ResponsePtr, MAX_MIXED_POINTS};

const NO_SLOT: u32 = u32::MAX;
/// Largest number of element colours (a node's colours are a 64-bit mask); elements that
/// find no free colour are assembled serially.
const MAX_COLOURS: usize = 64;
/// Fewest elements a rayon task takes.
const MIN_TASK: usize = 32;
/// Elements with tied DOFs evaluated in parallel before their serial scatter (bounds the
/// buffer of element tangents: 128 × 3.2 KB).
const SERIAL_CHUNK: usize = 128;
/// Fewest elements with tied DOFs a rayon task takes.
const MIN_SERIAL_TASK: usize = 4;
/// Integration points of the small stack buffer of an element's extrapolated mixed stresses
/// (four in-plane points times up to four thickness points).
const SMALL_MIXED_POINTS: usize = 16;

/// Upper-triangular CSC pattern of the free-DOF tangent.
#[derive(Clone, Debug)]
pub struct Pattern {
    /// Number of equations.
    pub n: usize,
    /// Column pointers (n + 1).
    pub col_ptr: Vec<usize>,
    /// Row indices, sorted within each column, row ≤ column.
    pub row_idx: Vec<usize>,
}

impl Pattern {
    /// Adds `m` w_r w_c to every stored entry (r, c), r ≤ c, of the weighted equations
    /// `exp` — a diagonal term m of a tied slave DOF taken through the tie (Tᵀ M T).
    pub fn add_weighted(&self, values: &mut [f64], exp: &[(usize, f64)], m: f64) {
        for &(r, wr) in exp {
            for &(c, wc) in exp {
                if r > c {
                    continue;
                }
                let rows = &self.row_idx[self.col_ptr[c]..self.col_ptr[c + 1]];
                if let Ok(p) = rows.binary_search(&r) {
                    values[self.col_ptr[c] + p] += m * wr * wc;
                }
            }
        }
    }
}

/// An element failure located in the model.
#[derive(Clone, Debug)]
pub struct AssemblyFailure {
    /// Global element index.
    pub element: usize,
    /// What went wrong.
    pub failure: ElementFailure,
}

impl std::fmt::Display for AssemblyFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "element {} failed: {}", self.element, self.failure)
    }
}

/// Pattern, scatter maps and scratch for assembling one model.
#[derive(Debug)]
pub struct Assembler {
    /// Sparsity pattern of the free-DOF tangent (upper triangle).
    pub pattern: Pattern,
    slots: Vec<[u32; ELEMENT_DOFS * ELEMENT_DOFS]>,
    /// Integration rule of each section (built once).
    rules: Vec<Result<SectionRule, ElementFailure>>,
    /// Reference geometry of each element (built once; a degenerate element keeps its failure).
    geometry: Vec<Result<ElementGeometry, ElementFailure>>,
    /// Director orientation and corner-collapse barriers of each element
    /// (`element::orientation`).
    orientation: Vec<orientation::CornerBarriers>,
    /// Entries of elements with tied DOFs that go through the constraint weights:
    /// (local entry i·20+j, slot, w_i w_j), the element's part of Tᵀ K T. Empty for
    /// elements without tied DOFs (their entries all take the direct path).
    tied: Vec<Vec<(u16, u32, f64)>>,
    /// Elements with a DOF tied by a rigid link (state-dependent weights): their Tᵀ K T
    /// entries (local entry i·20+j, slot, index of the row's and the column's weight in the
    /// expansions of local DOFs i and j), weighted at every assembly with the current
    /// weights instead of through `tied`. Empty for other elements.
    linked: Vec<Vec<(u16, u32, u8, u8)>>,
    /// Elements without tied DOFs grouped by colour: no two elements of a colour share a
    /// node, so their slots and force entries are disjoint.
    colours: Vec<Vec<usize>>,
    /// Elements scattered serially after the colours (tied DOFs, or no colour left), in
    /// index order; their element responses are evaluated in parallel.
    serial: Vec<usize>,
    /// Replace each element's tangent by a positive semi-definite one before the scatter
    /// (eigenvalue filtering, [`project_psd`]): a descent direction for the energy where the
    /// assembled tangent is indefinite.
    pub project: bool,
    /// Build the geometric stiffness from mixed-integration-point stresses
    /// ([`crate::element::mixed`]; Magisano, Leonetti & Garcea 2017): each tangent
    /// evaluation records its point stresses, and the next one extrapolates them.
    pub mixed: bool,
    /// The records of the mixed-integration-point stresses.
    records: Mutex<MixedStore>,
    /// Keep every element's response (force, energy, unprojected tangent) of a tangent
    /// assembly, so that a tangent assembly of the same state — the projected re-assembly
    /// of a time step whose tangent was indefinite — scatters them again instead of
    /// evaluating every element anew (models of up to [`CACHE_ELEMENTS`] elements; the
    /// result is the same bit for bit).
    pub keep_responses: bool,
    /// The responses kept by `keep_responses` and the state they belong to.
    cache: Mutex<ResponseCache>,
}


/// Greedy colouring of the elements in index order: each element takes the lowest colour
/// that none of the elements already coloured at its nodes has. Elements marked in
/// `exclude`, and any element that finds no colour below [`MAX_COLOURS`], go to the serial
/// list. Returns (colours, serial).
fn colour_elements(model: &Model, exclude: &[bool]) -> (Vec<Vec<usize>>, Vec<usize>) {
    let mut used = vec![0u64; model.n_nodes()];
    let mut colours: Vec<Vec<usize>> = Vec::new();
    let mut serial = Vec::new();
    for (e, el) in model.elements.iter().enumerate() {
        let taken = el.nodes.iter().fold(0u64, |m, &n| m | used[n]);
        let c = taken.trailing_ones() as usize;
        if exclude[e] || c >= MAX_COLOURS {
            serial.push(e);
            continue;
        }
        for &n in &el.nodes {
            used[n] |= 1 << c;
        }
        if colours.len() <= c {
            colours.resize_with(c + 1, Vec::new);
        }
        colours[c].push(e);
    }
    (colours, serial)
}

/// A pointer to assembly output shared by the tasks of one colour. Sound only because the
/// tasks of a colour write disjoint entries (see [`colour_elements`]).
#[derive(Clone, Copy)]
struct Shared(*mut f64);

// SAFETY: the pointer is only dereferenced at indices that no other task of the same colour
// touches while the colour is being assembled (elements of a colour share no node).
unsafe impl Send for Shared {}
// SAFETY: as above.
unsafe impl Sync for Shared {}

impl Shared {
    /// Adds `v` to entry `i`.
    ///
    /// # Safety
    /// `i` is in bounds of the slice the pointer came from, and no other thread accesses
    /// entry `i` concurrently.
    unsafe fn add(self, i: usize, v: f64) {
        // SAFETY: guaranteed by the caller.
        unsafe { *self.0.add(i) += v }
    }
}


/// What one assembly produced besides the matrix values.
#[derive(Clone, Debug, Default)]
pub struct AssemblyInfo {
    /// Total strain energy.
    pub energy: f64,
    /// Wall time spent (s).
    pub seconds: f64,
    /// Whether the element responses kept from the last tangent assembly of the same state
    /// were scattered instead of evaluated ([`Assembler::keep_responses`]).
    pub reused: bool,
}

impl Assembler {
    /// Builds the pattern and the element scatter maps of `model`.
    pub fn new(model: &Model) -> Self {
        Self::with_couplings(model, &[])
    }

    /// [`Assembler::new`] with the translations of each node pair (a, b) of `couplings`
    /// coupled in the pattern as well (through the ties), for nodal-force terms with
    /// node-pair blocks (inter-ply contact).
    pub fn with_couplings(model: &Model, couplings: &[(usize, usize)]) -> Self {
        let n_nodes = model.n_nodes();
        let eq = &model.dofs.eq;
        // Node adjacency through elements.
        let mut adj: Vec<Vec<usize>> = vec![Vec::new(); n_nodes];
        for el in &model.elements {
            for &a in &el.nodes {
                adj[a].extend_from_slice(&el.nodes);
            }
        }
        let mut cols: Vec<Vec<usize>> = vec![Vec::new(); model.dofs.n_free];
        for (b, nb) in adj.iter_mut().enumerate() {
            nb.sort_unstable();
            nb.dedup();
            for kb in 0..NODE_DOFS {
                let c = eq[NODE_DOFS * b + kb];
                if c == FIXED {
                    continue;
                }
                for &a in nb.iter() {
                    for ka in 0..NODE_DOFS {
                        let r = eq[NODE_DOFS * a + ka];
                        if r != FIXED && r <= c {
                            cols[c].push(r);
                        }
                    }
                }
            }
        }
        // Couplings through tied DOFs: every pair of expanded equations of an element.
        let has_ties = !model.dofs.ties.is_empty();
        let is_tied = |el: &crate::model::ElementDef| {
            has_ties && el.nodes.iter().any(|&n| (0..NODE_DOFS).any(|k| model.dofs.tie_of[NODE_DOFS * n + k] != UNTIED))
        };
        for el in model.elements.iter().filter(|el| is_tied(el)) {
            let mut all: Vec<usize> = (0..ELEMENT_DOFS)
                .flat_map(|i| model.dofs.expand(NODE_DOFS * el.nodes[i / NODE_DOFS] + i % NODE_DOFS))
                .map(|(e, _)| e)
                .collect();
            all.sort_unstable();
            all.dedup();
            for (a, &r) in all.iter().enumerate() {
                for &c in &all[a..] {
                    cols[c].push(r);
                }
            }
        }
        for &(a, b) in couplings {
            grow::push_coupling(model, a, b, &mut cols);
        }
        let mut col_ptr = Vec::with_capacity(cols.len() + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for c in cols.iter_mut() {
            c.sort_unstable();
            c.dedup();
            row_idx.extend_from_slice(c);
            col_ptr.push(row_idx.len());
        }
        let pattern = Pattern { n: model.dofs.n_free, col_ptr, row_idx };
        let slots = model
            .elements
            .par_iter()
            .map(|el| {
                let mut s = [NO_SLOT; ELEMENT_DOFS * ELEMENT_DOFS];
                let eqs: [usize; ELEMENT_DOFS] = std::array::from_fn(|i| eq[NODE_DOFS * el.nodes[i / NODE_DOFS] + i % NODE_DOFS]);
                for i in 0..ELEMENT_DOFS {
                    for j in 0..ELEMENT_DOFS {
                        let (r, c) = (eqs[i], eqs[j]);
                        if r == FIXED || c == FIXED || r > c {
                            continue;
                        }
                        let rows = &pattern.row_idx[pattern.col_ptr[c]..pattern.col_ptr[c + 1]];
                        if let Ok(p) = rows.binary_search(&r) {
                            s[i * ELEMENT_DOFS + j] = (pattern.col_ptr[c] + p) as u32;
                        }
                    }
                }
                s
            })
            .collect();
        let slot_of = |r: usize, c: usize| -> Option<u32> {
            let rows = &pattern.row_idx[pattern.col_ptr[c]..pattern.col_ptr[c + 1]];
            rows.binary_search(&r).ok().map(|p| (pattern.col_ptr[c] + p) as u32)
        };
        let is_linked = |el: &crate::model::ElementDef| {
            el.nodes.iter().any(|&n| (0..NODE_DOFS).any(|k| {
                let t = model.dofs.tie_of[NODE_DOFS * n + k];
                t != UNTIED && model.dofs.has_links(t as usize)
            }))
        };
        let linked_flag: Vec<bool> = model.elements.iter().map(|el| is_tied(el) && is_linked(el)).collect();
        // Entries of an element with tied DOFs, taken through the constraint expansion:
        // (local entry i·20+j, slot, index a of row equation in exp_i, index b in exp_j,
        // w_a w_b), for every pair of expanded equations r ≤ c stored in the pattern.
        let expanded_entries = |el: &crate::model::ElementDef| -> Vec<(u16, u32, u8, u8, f64)> {
            let globals: [usize; ELEMENT_DOFS] = std::array::from_fn(|i| NODE_DOFS * el.nodes[i / NODE_DOFS] + i % NODE_DOFS);
            let exp: Vec<Vec<(usize, f64)>> = globals.iter().map(|&g| model.dofs.expand(g)).collect();
            let mut list = Vec::new();
            for i in 0..ELEMENT_DOFS {
                for j in 0..ELEMENT_DOFS {
                    if model.dofs.tie_of[globals[i]] == UNTIED && model.dofs.tie_of[globals[j]] == UNTIED {
                        continue;
                    }
                    for (a, &(r, wr)) in exp[i].iter().enumerate() {
                        for (b, &(c, wc)) in exp[j].iter().enumerate() {
                            if r <= c
                                && let Some(s) = slot_of(r, c)
                            {
                                list.push(((i * ELEMENT_DOFS + j) as u16, s, a as u8, b as u8, wr * wc));
                            }
                        }
                    }
                }
            }
            list
        };
        let tied = model
            .elements
            .iter()
            .zip(&linked_flag)
            .map(|(el, &lk)| {
                if !is_tied(el) || lk {
                    return Vec::new();
                }
                expanded_entries(el).into_iter().map(|(ij, s, _, _, w)| (ij, s, w)).collect()
            })
            .collect();
        // The equations of a link-tied expansion do not change with the state (zero weights
        // are kept), so the slots are found once; only the weights are refreshed.
        let linked = model
            .elements
            .iter()
            .zip(&linked_flag)
            .map(|(el, &lk)| {
                if !lk {
                    return Vec::new();
                }
                expanded_entries(el).into_iter().map(|(ij, s, a, b, _)| (ij, s, a, b)).collect()
            })
            .collect();
        let rules: Vec<Result<SectionRule, ElementFailure>> = model.sections.iter().map(SectionRule::new).collect();
        let geometry: Vec<Result<ElementGeometry, ElementFailure>> = (0..model.elements.len())
            .into_par_iter()
            .map(|e| match &rules[model.elements[e].section] {
                Ok(rule) => model.element(e).geometry(rule),
                Err(f) => Err(f.clone()),
            })
            .collect();
        let orientation = (0..model.elements.len())
            .map(|e| {
                let el = model.element(e);
                let material = &el.section.material;
                let kappa = orientation::STIFFNESS * material.bending_rigidity(el.section.thickness);
                let membrane = material.small_strain_moduli().0 * el.section.thickness;
                orientation::CornerBarriers::new(&el.x0, &el.d0, kappa, membrane)
            })
            .collect();
        let constrained: Vec<bool> = model.elements.iter().map(|el| is_tied(el)).collect();
        let (colours, serial) = colour_elements(model, &constrained);
        let mut offsets = vec![0];
        for g in &geometry {
            let n = g.as_ref().map_or(0, point_count);
            offsets.push(offsets.last().copied().unwrap_or(0) + if n <= MAX_MIXED_POINTS { n } else { 0 });
        }
        let records = Mutex::new(MixedStore { offsets, ..Default::default() });
        Self { pattern, slots, rules, geometry, orientation, tied, linked, colours, serial, project: false, mixed: false, records, keep_responses: false, cache: Mutex::new(ResponseCache::default()) }
    }

    /// Takes over the settings (`project`, `mixed`, `keep_responses`) and the kept element
    /// responses of `old`, the assembler of the same model before its pattern grew: element
    /// responses do not depend on the pattern, so a re-assembly of the kept state still only
    /// scatters them. The mixed-stress records are not taken over (a new pattern starts from
    /// the standard tangent, as before).
    pub fn take_over(&mut self, old: &mut Assembler) {
        self.project = old.project;
        self.mixed = old.mixed;
        self.keep_responses = old.keep_responses;
        let kept = std::mem::take(&mut *old.cache.lock().unwrap_or_else(|p| p.into_inner()));
        *self.cache.lock().unwrap_or_else(|p| p.into_inner()) = kept;
    }

    /// Drops every mixed-stress record, so the next tangent of each element is the standard
    /// one (after a state is restored, e.g. on a cut-back: the records of the abandoned
    /// iterates would extrapolate from the wrong configuration).
    pub fn forget_mixed(&self) {
        let mut store = self.records.lock().unwrap_or_else(|p| p.into_inner());
        store.at.iter_mut().for_each(|a| *a = None);
    }

    /// Number of stored entries of the upper triangle.
    pub fn nnz(&self) -> usize {
        self.pattern.row_idx.len()
    }

    /// Number of element colours of the parallel assembly (elements of a colour share no node).
    pub fn n_colours(&self) -> usize {
        self.colours.len()
    }

    /// Number of elements scattered serially after the colours (elements with tied DOFs).
    pub fn n_serial(&self) -> usize {
        self.serial.len()
    }

    /// Internal force, energy and (when `k` is given) tangent of element `e` in `state`.
    /// The tangent is left in `k` as a full 20×20 matrix, so it can be transformed before
    /// [`Assembler::scatter`].
    pub fn element_response(&self, model: &Model, state: &State, e: usize, k: Option<&mut ElemMat>) -> Result<(ElemVec, f64), AssemblyFailure> {
        self.element_response_mixed(model, state, e, k, None)
    }

    /// [`Assembler::element_response`], recording and using the element's mixed-stress
    /// records through `mixed` when given (and a tangent is asked for).
    fn element_response_mixed(&self, model: &Model, state: &State, e: usize, k: Option<&mut ElemMat>, mixed: Option<MixedAccess<'_>>) -> Result<(ElemVec, f64), AssemblyFailure> {
        let def = &model.elements[e];
        let x = def.nodes.map(|n| state.u[n]);
        let frames = def.nodes.map(|n| state.frames[n]);
        let fail = |failure: ElementFailure| AssemblyFailure { element: e, failure };
        let rule = self.rules[def.section].as_ref().map_err(|f| fail(f.clone()))?;
        let geom = self.geometry[e].as_ref().map_err(|f| fail(f.clone()))?;
        let mut k = k;
        let element = model.element(e);
        let (mut force, energy) = match mixed {
            Some(m) if k.is_some() && m.offsets[e + 1] > m.offsets[e] => {
                let (lo, hi) = (m.offsets[e], m.offsets[e + 1]);
                // SAFETY: element e's records and configuration are touched by this call only
                // (see `MixedAccess`), and lie inside the store's arrays.
                let (records, at) = unsafe { (std::slice::from_raw_parts_mut(m.records.add(lo), hi - lo), &mut *m.at.add(e)) };
                // The extrapolated stresses, on a stack buffer of the element's size class:
                // 16 points hold every Gauss rule of up to four thickness points (zeroing the
                // 64-point buffer for them wrote 2.5 KB per element).
                let (mut small, mut large);
                let buf: &mut [Voigt5] = if hi - lo <= SMALL_MIXED_POINTS {
                    small = [Voigt5::zeros(); SMALL_MIXED_POINTS];
                    &mut small[..hi - lo]
                } else {
                    large = [Voigt5::zeros(); MAX_MIXED_POINTS];
                    &mut large[..hi - lo]
                };
                let geo = match at.as_ref() {
                    Some((u0, f0)) => {
                        extrapolate(rule, geom, u0, f0, &unknown_change(u0, f0, &x, &frames), records, buf).map_err(fail)?;
                        Some(&*buf)
                    }
                    None => None,
                };
                let out = element.response_mixed(rule, geom, &x, &frames, k.as_deref_mut(), Some(Mixed { geo, record: records }));
                *at = out.is_ok().then_some((x, frames));
                out
            }
            _ => element.response_into(rule, geom, &x, &frames, k.as_deref_mut()),
        }
        .map_err(fail)?;
        // The director orientation barrier, zero in every regular state.
        let current = std::array::from_fn(|a| model.x0[def.nodes[a]] + x[a]);
        let barrier = orientation::add(&current, &frames, &self.orientation[e], &mut force, k).map_err(fail)?;
        Ok((force, energy + barrier))
    }

    /// Adds element `e`'s force to `f_int` and its tangent `k` (if any) to the matrix values,
    /// both given as [`Shared`] pointers, through its direct slots only.
    ///
    /// # Safety
    /// `f_int` points to the force vector (5 × nodes entries), `values` to the matrix values
    /// (nnz entries), and no other thread touches the entries of element `e`'s nodes.
    unsafe fn scatter_direct(&self, model: &Model, e: usize, force: &ElemVec, k: Option<&ElemMat>, f_int: Shared, values: Option<Shared>) {
        let nodes = model.elements[e].nodes;
        for (i, &f) in force.iter().enumerate() {
            // SAFETY: a DOF of element e's node, in bounds and exclusive (caller).
            unsafe { f_int.add(NODE_DOFS * nodes[i / NODE_DOFS] + i % NODE_DOFS, f) };
        }
        if let (Some(v), Some(k)) = (values, k) {
            let slots = &self.slots[e];
            for j in 0..ELEMENT_DOFS {
                for i in 0..ELEMENT_DOFS {
                    let s = slots[i * ELEMENT_DOFS + j];
                    if s != NO_SLOT {
                        // SAFETY: a slot of a pair of element e's equations, exclusive (caller).
                        unsafe { v.add(s as usize, k[(i, j)]) };
                    }
                }
            }
        }
    }

    /// Adds element `e`'s force and tangent (if any) to `f_int` and `values`, through its
    /// direct slots and its tied and linked entries (Tᵀ K T).
    pub fn scatter(&self, model: &Model, e: usize, force: &ElemVec, k: Option<&ElemMat>, f_int: &mut [f64], mut values: Option<&mut [f64]>) {
        let f_ptr = Shared(f_int.as_mut_ptr());
        let v_ptr = values.as_deref_mut().map(|v| Shared(v.as_mut_ptr()));
        // SAFETY: the pointers come from the exclusive borrows above, held for the call.
        unsafe { self.scatter_direct(model, e, force, k, f_ptr, v_ptr) };
        let (Some(v), Some(k)) = (values, k) else { return };
        for &(ij, s, w) in &self.tied[e] {
            let ij = ij as usize;
            v[s as usize] += w * k[(ij / ELEMENT_DOFS, ij % ELEMENT_DOFS)];
        }
        if !self.linked[e].is_empty() {
            let nodes = model.elements[e].nodes;
            let weights: Vec<Vec<f64>> = nodes
                .iter()
                .flat_map(|&n| (0..NODE_DOFS).map(move |k| NODE_DOFS * n + k))
                .map(|g| model.dofs.expand(g).into_iter().map(|(_, w)| w).collect())
                .collect();
            for &(ij, s, a, b) in &self.linked[e] {
                let (i, j) = (ij as usize / ELEMENT_DOFS, ij as usize % ELEMENT_DOFS);
                v[s as usize] += weights[i][a as usize] * weights[j][b as usize] * k[(i, j)];
            }
        }
    }

    /// Assembles the internal force over all DOFs into `f_int` and, when `values` is given,
    /// the tangent's upper triangle into `values` (both overwritten). Without `values` only
    /// forces and energies are evaluated (the residual-only path).
    pub fn assemble(
        &self,
        model: &Model,
        state: &State,
        f_int: &mut [f64],
        mut values: Option<&mut [f64]>,
    ) -> Result<AssemblyInfo, AssemblyFailure> {
        let t0 = Instant::now();
        model.dofs.refresh_links(&state.frames);
        let with_tangent = values.is_some();
        f_int.iter_mut().for_each(|v| *v = 0.0);
        if let Some(v) = values.as_deref_mut() {
            v.iter_mut().for_each(|x| *x = 0.0);
        }
        let n_el = model.elements.len();
        assert!(f_int.len() >= NODE_DOFS * model.n_nodes() && values.as_deref().is_none_or(|v| v.len() >= self.nnz()), "assembly output too short");
        let mut energies = vec![0.0; n_el];
        let mut store = self.records.lock().unwrap_or_else(|p| p.into_inner());
        let mixed = if self.mixed && with_tangent {
            let store = &mut *store;
            let n = store.offsets.last().copied().unwrap_or(0);
            if store.records.len() != n || store.at.len() != n_el {
                store.records = vec![PointRecord::default(); n];
                store.at = vec![None; n_el];
            }
            Some(MixedAccess { offsets: &store.offsets, records: store.records.as_mut_ptr(), at: store.at.as_mut_ptr() })
        } else {
            None
        };
        let e_ptr = Shared(energies.as_mut_ptr());
        let f_ptr = Shared(f_int.as_mut_ptr());
        let v_ptr = values.as_deref_mut().map(|v| Shared(v.as_mut_ptr()));
        // The failure of the lowest-numbered failing element.
        let failure: Mutex<Option<AssemblyFailure>> = Mutex::new(None);
        let record = |f: AssemblyFailure| {
            let mut slot = failure.lock().unwrap_or_else(|p| p.into_inner());
            if slot.as_ref().is_none_or(|g| f.element < g.element) {
                *slot = Some(f);
            }
        };
        // Kept element responses: reused when this is a tangent assembly of their state,
        // else (re)filled by a tangent assembly.
        let mut cache = self.cache.lock().unwrap_or_else(|p| p.into_inner());
        let keep = with_tangent && self.keep_responses && n_el <= CACHE_ELEMENTS;
        let reuse = keep && cache.items.len() == n_el && cache.holds(state);
        if !reuse {
            cache.valid = false;
            if keep && cache.items.len() != n_el {
                cache.items = vec![(ElemVec::zeros(), 0.0, ElemMat::zeros()); n_el];
            }
        }
        let c_ptr = ResponsePtr(cache.items.as_mut_ptr());
        // Element e's response, its tangent (unprojected) written into `k` when given.
        let respond = |e: usize, k: Option<&mut ElemMat>| -> Result<(ElemVec, f64), AssemblyFailure> {
            if reuse {
                // SAFETY: e < n_el = cache.items.len(), and only this task touches entry e.
                let (force, energy, kept) = unsafe { &*c_ptr.entry(e) };
                if let Some(k) = k {
                    *k = *kept;
                }
                return Ok((*force, *energy));
            }
            let mut k = k;
            let (force, energy) = self.element_response_mixed(model, state, e, k.as_deref_mut(), mixed)?;
            if keep && let Some(k) = k {
                // SAFETY: as above (keep: the cache holds n_el entries).
                unsafe { *c_ptr.entry(e) = (force, energy, *k) };
            }
            Ok((force, energy))
        };
        for colour in &self.colours {
            colour.par_iter().with_min_len(MIN_TASK).for_each_init(ElemMat::zeros, |k, &e| {
                match respond(e, with_tangent.then_some(&mut *k)) {
                    Ok((force, energy)) => {
                        if with_tangent && self.project {
                            *k = project_psd(k);
                        }
                        // SAFETY: elements of a colour share no node and have no tied DOFs, so
                        // their force entries, matrix slots and energy entries are disjoint;
                        // the pointers come from exclusive borrows held for the whole loop.
                        unsafe {
                            e_ptr.add(e, energy);
                            self.scatter_direct(model, e, &force, with_tangent.then_some(&*k), f_ptr, v_ptr);
                        }
                    }
                    Err(f) => record(f),
                }
            });
        }
        // Elements with tied DOFs: evaluated in parallel a chunk at a time, then scattered
        // serially in index order (their entries go through the constraint weights to other
        // nodes' equations), so every slot still receives its contributions in index order.
        if !self.serial.is_empty() {
            let len = SERIAL_CHUNK.min(self.serial.len());
            let mut mats = if with_tangent { vec![ElemMat::zeros(); len] } else { Vec::new() };
            let mut out: Vec<Option<Result<(ElemVec, f64), AssemblyFailure>>> = vec![None; len];
            for chunk in self.serial.chunks(SERIAL_CHUNK) {
                let n = chunk.len();
                if with_tangent {
                    chunk.par_iter().zip(out[..n].par_iter_mut()).zip(mats[..n].par_iter_mut()).with_min_len(MIN_SERIAL_TASK).for_each(|((&e, o), k)| {
                        let r = respond(e, Some(k));
                        if r.is_ok() && self.project {
                            *k = project_psd(k);
                        }
                        *o = Some(r);
                    });
                } else {
                    chunk.par_iter().zip(out[..n].par_iter_mut()).with_min_len(MIN_SERIAL_TASK).for_each(|(&e, o)| {
                        *o = Some(respond(e, None));
                    });
                }
                for (i, &e) in chunk.iter().enumerate() {
                    match out[i].take() {
                        Some(Ok((force, energy))) => {
                            energies[e] = energy;
                            self.scatter(model, e, &force, mats.get(i), f_int, values.as_deref_mut());
                        }
                        Some(Err(f)) => record(f),
                        None => {}
                    }
                }
            }
        }
        let failed = failure.into_inner().unwrap_or_else(|p| p.into_inner());
        if keep && !reuse {
            cache.valid = failed.is_none();
            if cache.valid {
                cache.u.clone_from(&state.u);
                cache.frames.clone_from(&state.frames);
            }
        }
        drop(cache);
        drop(store);
        if let Some(f) = failed {
            return Err(f);
        }
        let energy = energies.iter().fold(0.0, |s, e| s + e);
        model.dofs.fold(f_int);
        Ok(AssemblyInfo { energy, seconds: t0.elapsed().as_secs_f64(), reused: reuse })
    }
}

#[cfg(test)]
mod tests {
    use std::collections::HashSet;

    use super::*;
    use crate::scene;

    /// On a plain plate and on a two-panel sleeve with tied (non-matching) seams: every
    /// element is assembled exactly once, no two elements of a colour share a node, tied
    /// elements are in the serial list, and the assembly (forces, tangent values, energy) is
    /// the same bit for bit on one and on two threads.
    #[test]
    fn colours_share_no_node_and_assembly_is_deterministic() {
        let sleeve = include_str!("../../garments/sleeve_two_panel.ron");
        for (name, text) in [("plate", crate::bench::scenes::CLAMPED_PLATE), ("sleeve", sleeve)] {
            let sc = scene::parse(name, text).expect("scene");
            let built = scene::build(&sc, name, text).expect("build");
            let model = &built.model;
            let asm = Assembler::new(model);
            let mut seen = vec![0usize; model.elements.len()];
            for colour in &asm.colours {
                let mut nodes = HashSet::new();
                for &e in colour {
                    seen[e] += 1;
                    assert!(asm.tied[e].is_empty() && asm.linked[e].is_empty(), "{name}: tied element {e} in a colour");
                    for &n in &model.elements[e].nodes {
                        assert!(nodes.insert(n), "{name}: node {n} twice in one colour");
                    }
                }
            }
            for &e in &asm.serial {
                seen[e] += 1;
            }
            assert!(seen.iter().all(|&s| s == 1), "{name}: an element assembled twice or never");
            if name == "sleeve" {
                assert!(!asm.serial.is_empty(), "the sleeve's seams tie DOFs");
            }
            let mut state = model.initial_state();
            let du: Vec<f64> = (0..model.dofs.n_free).map(|i| 1e-4 * ((i % 13) as f64 - 6.0)).collect();
            model.update(&mut state, &du, 1.0);
            let run = |threads: usize| {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
                let mut f = vec![0.0; NODE_DOFS * model.n_nodes()];
                let mut v = vec![0.0; asm.nnz()];
                let info = pool.install(|| asm.assemble(model, &state, &mut f, Some(&mut v))).expect("assembly");
                (f, v, info.energy)
            };
            let (one, two) = (run(1), run(2));
            assert!(one == two, "{name}: assembly differs between one and two threads");
            assert!(asm.n_colours() >= 2 && one.2 > 0.0);
        }
    }

    /// Kept element responses: a projected tangent assembly of the state of the last tangent
    /// assembly scatters the kept responses and gives bit for bit what evaluating every
    /// element again gives; another state is evaluated afresh (two-panel sleeve with tied
    /// seams, in two deformed states).
    #[test]
    fn kept_responses_give_the_same_projected_assembly() {
        let text = include_str!("../../garments/sleeve_two_panel.ron");
        let sc = scene::parse("sleeve", text).expect("scene");
        let built = scene::build(&sc, "sleeve", text).expect("build");
        let model = &built.model;
        let state_of = |scale: f64| {
            let mut state = model.initial_state();
            let du: Vec<f64> = (0..model.dofs.n_free).map(|i| scale * ((i % 13) as f64 - 6.0)).collect();
            model.update(&mut state, &du, 1.0);
            state
        };
        let assemble = |asm: &Assembler, state: &State| {
            let mut f = vec![0.0; NODE_DOFS * model.n_nodes()];
            let mut v = vec![0.0; asm.nnz()];
            let info = asm.assemble(model, state, &mut f, Some(&mut v)).expect("assembly");
            ((f, v, info.energy), info.reused)
        };
        let (a, b) = (state_of(1e-4), state_of(0.5e-4));
        // Reference: every element evaluated, tangents projected.
        let mut fresh = Assembler::new(model);
        fresh.project = true;
        let (want_a, want_b) = (assemble(&fresh, &a).0, assemble(&fresh, &b).0);
        let mut plain = Assembler::new(model);
        let unprojected = assemble(&plain, &a);
        plain.keep_responses = true;
        assert!(assemble(&plain, &a) == (unprojected.0, false), "a first assembly evaluates every element");
        plain.project = true;
        assert!(assemble(&plain, &a) == (want_a, true), "kept responses, projected, differ from a fresh projected assembly");
        assert!(assemble(&plain, &b) == (want_b, false), "another state must be evaluated afresh");
    }
}
