//! Configuration-dependent forces on node translations — contact with rigid bodies, viscous
//! stabilization, penalty springs, tethers — added to the external loads in every assembly of
//! every step kind (static, damped, dynamic, path following), with their stiffness in the
//! tangent. The single hook for such terms: stateful ones (friction anchors, the previous
//! configuration) are told when an increment begins and when it has converged.

use nalgebra::Matrix3;
use rayon::prelude::*;

use crate::contact::ipc::FxMap;
use crate::element::NODE_DOFS;
use crate::model::{Model, State};

/// Forces on node translations that depend on the current configuration.
pub trait NodalForces: Send {
    /// Adds the forces acting on the nodes in `state` to `f_ext` (all DOFs, [`NODE_DOFS`] per
    /// node, same sign as applied loads) and pushes, for every node n they depend on, the 3×3
    /// block ∂f_n/∂u_n (forces depending only on their own node; the solver adds the
    /// symmetric part of −∂f/∂u to the tangent, through the tie transformation for tied
    /// slaves). A term that finds the trial state inadmissible (e.g. a node through a body)
    /// writes NaN into `f_ext`; the solver's safeguarded step then backtracks.
    fn add(&mut self, model: &Model, state: &State, f_ext: &mut [f64], jacobian: &mut Vec<(usize, Matrix3<f64>)>);
    /// Called before each (sub-)increment or time-step attempt with its size as a fraction of
    /// the nominal one (1 normally, ½, ¼, … after cut-backs).
    fn begin_increment(&mut self, fraction: f64) {
        let _ = fraction;
    }
    /// Called before each attempt (after [`NodalForces::begin_increment`]) with the analysis
    /// times of the last converged state and of the attempt's end (`contact::motion` defines
    /// the clock): a term with prescribed motion (moving contact bodies) places itself at
    /// `to` and may move nodes of the initial iterate `state` so that it stays admissible
    /// (e.g. carry the nodes a moving body would sweep over). Default: nothing.
    fn begin_motion(&mut self, model: &Model, from: f64, to: f64, state: &mut State) {
        let _ = (model, from, to, state);
    }
    /// Analysis time at which the term's prescribed motion ends (a `Dynamic` step does not
    /// stop at rest before it). Default: −∞ (no motion).
    fn motion_end(&self) -> f64 {
        f64::NEG_INFINITY
    }
    /// Called once before the solve when it starts from `state` instead of the reference
    /// state (a state mapped from a coarser mesh, `analysis_sequence`): the term takes
    /// `state` as its last converged state (e.g. friction anchors start there). Default:
    /// nothing.
    fn start_from(&mut self, model: &Model, state: &State) {
        let _ = (model, state);
    }
    /// Called once per converged (sub-)increment or time step with the converged state, so
    /// the term can update its history; returns a report for the increment, if any.
    fn commit(&mut self, model: &Model, state: &State) -> Option<serde_json::Value> {
        let _ = (model, state);
        None
    }
    /// Potential energy of the forces at the state of the last [`NodalForces::add`] (their
    /// work is −∇ of it), or None when the forces are not conservative; the energy line
    /// search of the solver needs every term's potential and falls back to an admissibility
    /// search otherwise.
    fn potential(&self) -> Option<f64> {
        None
    }
    /// The potential of the forces at `state` alone, for a trial state of the energy line
    /// search that only compares potentials: what [`NodalForces::potential`] returns after
    /// an `add_coupled` at `state` (NaN where that would write NaN into the forces, an
    /// inadmissible state). Default: that `add_coupled`, into scratch arrays. A term may
    /// evaluate its energy alone, without derivatives, leaving its record of the last
    /// evaluation (that of a Newton iterate) as it was.
    fn potential_at(&mut self, model: &Model, state: &State) -> Option<f64> {
        let mut f = vec![0.0; NODE_DOFS * model.n_nodes()];
        let (mut jacobian, mut pairs) = (Vec::new(), Vec::new());
        self.add_coupled(model, state, &mut f, &mut jacobian, &mut pairs);
        if f.iter().any(|v| !v.is_finite()) {
            return Some(f64::NAN);
        }
        self.potential()
    }
    /// Largest fraction s ∈ [0, 1] of the straight move of every node from `from` to `to`
    /// that stays admissible for this term (continuous collision detection of a barrier).
    /// Default 1.
    fn max_step(&self, model: &Model, from: &State, to: &State) -> f64 {
        let _ = (model, from, to);
        1.0
    }
    /// Whether the term is a barrier (intersection-free contact): Dynamic steps then minimise
    /// the incremental potential by default.
    fn is_barrier(&self) -> bool {
        false
    }
    /// Wall time spent in proximity search so far (s), reported separately from assembly.
    fn search_seconds(&self) -> f64 {
        0.0
    }
    /// Extra point data to export for `state`: (name, components, values per node).
    fn point_data(&self, model: &Model, state: &State) -> Vec<(String, usize, Vec<f64>)> {
        let _ = (model, state);
        Vec::new()
    }
    /// Switches the tangent blocks of [`NodalForces::add`] to those of the stability test of
    /// a rest state (`on`) or back to the Newton tangent. Terms that enforce a constraint
    /// exactly at their fixed point (augmented Lagrangian contact) report there the stiffness
    /// of the constraint limit instead of their regularising penalty. Default: no change.
    fn stability_tangent(&mut self, on: bool) {
        let _ = on;
    }
    /// Switches the Hessian blocks of [`NodalForces::add_coupled`] to their projection onto
    /// the positive semi-definite cone (`on`) or back to the exact ones: a descent step whose
    /// effective tangent stays indefinite after the element Hessians were projected asks for
    /// it (terms that keep an exact, possibly indefinite Hessian for Newton's rate near a
    /// solution, e.g. surface contact pairs). Default: no change (already PSD or none).
    fn project_hessians(&mut self, on: bool) {
        let _ = on;
    }
    /// Whether the term keeps exact, possibly indefinite Hessian blocks between nodes (surface
    /// contact pairs): an indefinite effective tangent is then projected term by term, not
    /// shifted on its diagonal (see `time_step`). Default: false.
    fn indefinite_pairs(&self) -> bool {
        false
    }
    /// A summary of the whole run: (section name in summary.json, value).
    fn summary(&self) -> Option<(String, serde_json::Value)> {
        None
    }
    /// Node pairs (a, b), a ≠ b, whose coupling blocks ∂f_a/∂u_b this term may report from
    /// [`NodalForces::add_coupled`] (e.g. a contact node and the nodes of the surface it may
    /// touch). The solver puts them into the tangent's sparsity pattern before the symbolic
    /// analysis when the term is added; a block reported later outside the pattern makes it
    /// grow the pattern and redo the analysis.
    fn couplings(&self, model: &Model) -> Vec<(usize, usize)> {
        let _ = model;
        Vec::new()
    }
    /// [`NodalForces::add`] for terms that couple different nodes: also pushes the blocks
    /// (a, b, ∂f_a/∂u_b), a ≠ b, into `pairs`. The solver adds the symmetric part of −∂f/∂u
    /// over all blocks to the tangent (through the ties). Default: `add`, no pair blocks.
    fn add_coupled(
        &mut self,
        model: &Model,
        state: &State,
        f_ext: &mut [f64],
        jacobian: &mut Vec<(usize, Matrix3<f64>)>,
        pairs: &mut Vec<(usize, usize, Matrix3<f64>)>,
    ) {
        let _ = pairs;
        self.add(model, state, f_ext, jacobian);
    }
}

/// The equations of node `n`'s three translations when all three are free (neither fixed
/// nor tied), else None.
fn free_translations(model: &Model, n: usize) -> Option<[usize; 3]> {
    let e: [usize; 3] = std::array::from_fn(|k| model.dofs.eq[NODE_DOFS * n + k]);
    e.iter().all(|&g| g != crate::model::FIXED).then_some(e)
}

/// Adds −½(J + Jᵀ) of node `n`'s translations to the upper-triangular CSC tangent `values`,
/// through the tie transformation (free nodes take [`BlockSlots`], without it).
pub(super) fn add_node_block(model: &Model, col_ptr: &[usize], row_idx: &[usize], values: &mut [f64], n: usize, j: &Matrix3<f64>) {
    for_each_node_entry(model, n, j, |r, c, v| {
        let rows = &row_idx[col_ptr[c]..col_ptr[c + 1]];
        if let Ok(p) = rows.binary_search(&r) {
            values[col_ptr[c] + p] -= v;
        }
    });
}

/// Visits the stored entries (row r ≤ column c) of node `n`'s block ½(J + Jᵀ) through the tie
/// transformation (Tᵀ J T when the node is a tied slave), in a fixed order, with each entry's
/// value; shared by [`add_node_block`] and the pattern growth's carry-over (`growth`), which
/// must subtract the same terms in the same order.
pub(super) fn for_each_node_entry(model: &Model, n: usize, j: &Matrix3<f64>, mut visit: impl FnMut(usize, usize, f64)) {
    let expanded: [Vec<(usize, f64)>; 3] = std::array::from_fn(|a| model.dofs.expand(NODE_DOFS * n + a));
    for b in 0..3 {
        for &(c, wc) in &expanded[b] {
            for a in 0..3 {
                for &(r, wr) in &expanded[a] {
                    if r <= c {
                        visit(r, c, 0.5 * wr * wc * (j[(a, b)] + j[(b, a)]));
                    }
                }
            }
        }
    }
}

/// Adds the symmetric part of −J for the node-pair block J = ∂f_a/∂u_b, i.e. −½J at
/// (a, b) and −½Jᵀ at (b, a), to the upper-triangular CSC tangent `values`, through the tie
/// transformation (Tᵀ K T: rows and columns of tied slaves expand onto their masters; of the
/// full matrix only entries with row ≤ column are stored). Returns false when an entry falls
/// outside the pattern (nothing is added for it). Blocks of two free nodes take
/// [`BlockSlots`], without the transformation.
pub(super) fn add_node_pair_block(model: &Model, col_ptr: &[usize], row_idx: &[usize], values: &mut [f64], a: usize, b: usize, j: &Matrix3<f64>) -> bool {
    let mut inside = true;
    for_each_pair_entry(model, a, b, j, |r, c, v| {
        let rows = &row_idx[col_ptr[c]..col_ptr[c + 1]];
        match rows.binary_search(&r) {
            Ok(s) => values[col_ptr[c] + s] += v,
            Err(_) => inside = false,
        }
    });
    inside
}

/// Visits the stored entries (row r ≤ column c) of the node-pair block −½ (J, Jᵀ) of nodes
/// `a`, `b` through the tie transformation, in a fixed order, with each entry's value
/// w_r w_c (−½ J_pq); shared by [`add_node_pair_block`] and the pattern growth's carry-over
/// (`growth`), which must add the same terms in the same order.
pub(super) fn for_each_pair_entry(model: &Model, a: usize, b: usize, j: &Matrix3<f64>, mut visit: impl FnMut(usize, usize, f64)) {
    let ea: [Vec<(usize, f64)>; 3] = std::array::from_fn(|k| model.dofs.expand(NODE_DOFS * a + k));
    let eb: [Vec<(usize, f64)>; 3] = std::array::from_fn(|k| model.dofs.expand(NODE_DOFS * b + k));
    for (rows_of, cols_of, transposed) in [(&ea, &eb, false), (&eb, &ea, true)] {
        for p in 0..3 {
            for q in 0..3 {
                let v = -0.5 * if transposed { j[(q, p)] } else { j[(p, q)] };
                for &(r, wr) in &rows_of[p] {
                    for &(c, wc) in &cols_of[q] {
                        if r <= c {
                            visit(r, c, wr * wc * v);
                        }
                    }
                }
            }
        }
    }
}

/// Slot of a block entry that is not stored: below the diagonal of a node's own block, or
/// (node blocks) outside the pattern.
const SKIP: usize = usize::MAX;
/// Slot of a node-pair block entry outside the pattern.
const OUTSIDE: usize = usize::MAX - 1;

/// CSC positions of a free node's block entries (a, b) at `3 b + a` (SKIP below the
/// diagonal and outside the pattern), or None for a fixed or tied node.
fn node_slots(model: &Model, col_ptr: &[usize], row_idx: &[usize], n: usize) -> Option<[usize; 9]> {
    let e = free_translations(model, n)?;
    Some(std::array::from_fn(|k| {
        let (r, c) = (e[k % 3], e[k / 3]);
        if r > c {
            return SKIP;
        }
        row_idx[col_ptr[c]..col_ptr[c + 1]].binary_search(&r).map_or(SKIP, |p| col_ptr[c] + p)
    }))
}

/// CSC positions of the entries (p, q) at `3 q + p` of a node-pair block of two free nodes
/// (OUTSIDE for an entry outside the pattern), or None when a node is fixed or tied.
fn pair_slots(model: &Model, col_ptr: &[usize], row_idx: &[usize], a: usize, b: usize) -> Option<[usize; 9]> {
    let (ea, eb) = (free_translations(model, a)?, free_translations(model, b)?);
    Some(std::array::from_fn(|k| {
        let (p, q) = (k % 3, k / 3);
        let (r, c) = if ea[p] <= eb[q] { (ea[p], eb[q]) } else { (eb[q], ea[p]) };
        row_idx[col_ptr[c]..col_ptr[c + 1]].binary_search(&r).map_or(OUTSIDE, |s| col_ptr[c] + s)
    }))
}

/// The CSC positions of the last assembly's contact blocks, so that the next assembly with
/// the same blocks in the same order — a Newton iteration whose set of contact pairs did
/// not change — scatters them without searching the pattern (the nine binary searches per
/// block of [`add_node_pair_block`] cost about 5 % of a solve of the NBC sleeve). The
/// result is the same to the bit: each entry is added by the same operation in the same
/// order. Valid for one pattern: [`BlockSlots::clear`] when it changes.
#[derive(Default)]
pub(super) struct BlockSlots {
    nodes: Vec<usize>,
    node_slots: Vec<Option<[usize; 9]>>,
    pairs: Vec<(usize, usize)>,
    pair_slots: Vec<Option<[usize; 9]>>,
    /// The positions of every node and pair block met since the pattern changed: an
    /// assembly whose set of blocks differs from the last one's (a pair came or went, and the
    /// order of all of them changed) looks each block up here with one hash-map look-up
    /// instead of nine binary searches in the pattern's columns (a sorted list, searched and
    /// sorted again as blocks were met, cost 2.7 of the 8 s of the NBC sleeve's contact
    /// scatter).
    known_nodes: FxMap<usize, Option<[usize; 9]>>,
    known: FxMap<(usize, usize), Option<[usize; 9]>>,
}

impl BlockSlots {
    /// Forgets every position (the pattern changed).
    pub(super) fn clear(&mut self) {
        *self = Self::default();
    }

    /// Adds −½(J + Jᵀ) of every node block (n, J) of `blocks` to `values`, as
    /// [`add_node_block`] does.
    pub(super) fn add_node_blocks(&mut self, model: &Model, col_ptr: &[usize], row_idx: &[usize], values: &mut [f64], blocks: &[(usize, Matrix3<f64>)]) {
        if self.nodes.len() != blocks.len() || self.nodes.iter().zip(blocks).any(|(&n, b)| n != b.0) {
            self.nodes = blocks.iter().map(|b| b.0).collect();
            let known = &mut self.known_nodes;
            self.node_slots = blocks.iter().map(|b| *known.entry(b.0).or_insert_with(|| node_slots(model, col_ptr, row_idx, b.0))).collect();
        }
        for ((n, j), slots) in blocks.iter().zip(&self.node_slots) {
            let Some(slots) = slots else {
                add_node_block(model, col_ptr, row_idx, values, *n, j);
                continue;
            };
            for b in 0..3 {
                for a in 0..3 {
                    let s = slots[3 * b + a];
                    if s != SKIP {
                        values[s] -= 0.5 * (j[(a, b)] + j[(b, a)]);
                    }
                }
            }
        }
    }

    /// Adds every node-pair block (a, b, J) of `blocks` to `values`, as
    /// [`add_node_pair_block`] does; returns the pairs with an entry outside the pattern.
    pub(super) fn add_pair_blocks(&mut self, model: &Model, col_ptr: &[usize], row_idx: &[usize], values: &mut [f64], blocks: &[(usize, usize, Matrix3<f64>)]) -> Vec<(usize, usize)> {
        if self.pairs.len() != blocks.len() || self.pairs.iter().zip(blocks).any(|(&(a, b), blk)| (a, b) != (blk.0, blk.1)) {
            self.pairs = blocks.iter().map(|b| (b.0, b.1)).collect();
            // Looked up in parallel (the map is only read), the blocks met for the first time
            // searched in the pattern in parallel too, then kept: the same positions as one
            // look-up after the other (the contact's blocks come in a new order whenever a
            // pair comes or goes, and the serial look-ups cost 1–2 ms per assembly of the NBC
            // sleeve on the arm).
            let known = &self.known;
            let found: Vec<Option<Option<[usize; 9]>>> = blocks.par_iter().map(|b| known.get(&(b.0, b.1)).copied()).collect();
            let fresh: Vec<((usize, usize), Option<[usize; 9]>)> =
                blocks.par_iter().zip(&found).filter(|(_, f)| f.is_none()).map(|(b, _)| ((b.0, b.1), pair_slots(model, col_ptr, row_idx, b.0, b.1))).collect();
            let mut met = fresh.iter();
            self.pair_slots = found.into_iter().map(|f| f.unwrap_or_else(|| met.next().and_then(|&(_, s)| s))).collect();
            self.known.extend(fresh);
        }
        let mut outside = Vec::new();
        for (&(a, b, ref j), slots) in blocks.iter().zip(&self.pair_slots) {
            let inside = match slots {
                Some(slots) => {
                    let mut inside = true;
                    for q in 0..3 {
                        for p in 0..3 {
                            match slots[3 * q + p] {
                                OUTSIDE => inside = false,
                                s => values[s] += -0.5 * j[(p, q)],
                            }
                        }
                    }
                    inside
                }
                None => add_node_pair_block(model, col_ptr, row_idx, values, a, b, j),
            };
            if !inside {
                outside.push((a, b));
            }
        }
        outside
    }
}

#[cfg(test)]
mod tests {
    use crate::contact::interply::{InterplyContact, InterplySettings, InterplySetup};
    use crate::element::NODE_DOFS;
    use crate::model::FIXED;
    use crate::scene;
    use crate::solver::Solver;

    /// The assembled tangent (elements + inter-ply contact with its node-pair blocks, upper
    /// triangle) times a unit vector equals central differences of the residual
    /// f_int − f_ext (step 1e-9 m), to 1e-5 of the column's largest entry: two 4×2 plies
    /// pressed 20 µm into each other, clamped at one end, frictionless (a symmetric problem);
    /// the slave ply is shifted in plan so that its nodes project inside master facets (on a
    /// vertex the one-sided derivatives differ and central differences average them).
    #[test]
    fn assembled_tangent_with_pair_blocks_matches_the_residual() {
        let h = 0.001;
        let text = format!(
            r#"Scene(name: "s", materials: {{"m": StVenantKirchhoff(young: 1.0e7, poisson: 0.3)}},
            parts: [(name: "a", mesh: Rectangle(lx: 0.04, ly: 0.02, nx: 4, ny: 2), material: "m", thickness: {h}),
                    (name: "b", mesh: Rectangle(lx: 0.04, ly: 0.02, nx: 4, ny: 2), material: "m", thickness: {h},
                     offset: Some((0.002, 0.003, {h})))],
            node_sets: {{"root": Plane(point: (0.0, 0.0, 0.0), normal: (1.0, 0.0, 0.0)), "root_b": Plane(point: (0.002, 0.0, 0.0), normal: (1.0, 0.0, 0.0))}},
            boundary: [Clamp(set: "root"), Clamp(set: "root_b")],
            steps: [(name: "a", increments: 1)])"#
        );
        let sc = scene::parse("s.ron", &text).unwrap();
        let built = scene::build(&sc, "s.ron", &text).unwrap();
        let model = &built.model;
        let setup = InterplySetup { ply_pairs: vec![(0, 1)], settings: InterplySettings { friction: 0.0, ..Default::default() }, barrier: None };
        let mut solver = Solver::new(model, Default::default()).unwrap();
        solver.add_nodal_forces(Box::new(InterplyContact::new(model, &setup)));
        let mut st = model.initial_state();
        for a in 15..30 {
            let x = model.x0[a].x;
            st.u[a].z = -2e-5 * (1.0 + 10.0 * x) + 3e-4 * x * x;
            st.u[a].x = 1e-5 * x;
        }
        let scales = vec![0.0; model.loads.len()];
        solver.assemble(&st, &scales, true).unwrap();
        let (col_ptr, row_idx, values) = (solver.assembler.pattern.col_ptr.clone(), solver.assembler.pattern.row_idx.clone(), solver.values.clone());
        let n = model.dofs.n_free;
        let k = |r: usize, c: usize| -> f64 {
            let (r, c) = (r.min(c), r.max(c));
            row_idx[col_ptr[c]..col_ptr[c + 1]].binary_search(&r).map_or(0.0, |p| values[col_ptr[c] + p])
        };
        let eps = 1e-9;
        let mut worst = 0.0f64;
        for g in 0..NODE_DOFS * model.n_nodes() {
            let e = model.dofs.eq[g];
            if e == FIXED || g % NODE_DOFS >= 3 {
                continue;
            }
            let mut res = |s: f64| {
                let mut p = st.clone();
                p.u[g / NODE_DOFS][g % NODE_DOFS] += s;
                solver.assemble(&p, &scales, false).unwrap();
                let mut r = vec![0.0; n];
                solver.residual(&mut r);
                r
            };
            let (rp, rm) = (res(eps), res(-eps));
            let col: Vec<f64> = (0..n).map(|i| (rp[i] - rm[i]) / (2.0 * eps)).collect();
            let scale = col.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let err = (0..n).map(|i| (col[i] - k(i, e)).abs()).fold(0.0, f64::max);
            worst = worst.max(err / scale);
        }
        println!("largest relative column error {worst:.2e}");
        assert!(worst < 1e-5, "{worst}");
    }
}
