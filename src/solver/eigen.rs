//! Linearized buckling: the generalized eigenproblem (K_T + λ K_Δ) φ = 0 at a given state.
//!
//! K_T is the tangent at the state (the material stiffness at the reference state).
//! K_Δ = dK_T/dλ is the derivative of the tangent along the prebuckling path of the load
//! change f: v = K_T⁻¹ f, K_Δ = d/dε K_T(u ⊕ ε v) at ε = 0, evaluated by a central
//! difference (K_T(u ⊕ εv) − K_T(u ⊖ εv)) / 2ε of two assemblies. Since the element tangent
//! is BᵀDB + G(S) with S linear in the strain, K_Δ is the geometric (initial-stress)
//! stiffness G(S_v) of the prebuckling stress S_v plus the initial-displacement part
//! ∂(BᵀDB)/∂u·v; at a flat or membrane prebuckling state the latter is of the order of the
//! prebuckling strain relative to the former. This is the "linear prebuckling" eigenproblem
//! of Brendel & Ramm (1980) and the K_Δ of Abaqus' *BUCKLE (Abaqus Theory Manual §2.2.3):
//! the critical load is start + λ f. The central difference error is O(ε²) with ε chosen so
//! that ε v moves the structure by 1e-6 of its size.
//!
//! Eigen solver: shift-invert Lanczos with full reorthogonalization (Ericsson & Ruhe 1980;
//! Grimes, Lewis & Simon 1994). With B = −K_Δ and shift σ, A = K_T − σB is factorized
//! once (sparse LLᵀ; it must be positive definite, i.e. σ below the lowest eigenvalue and the
//! base state stable). T = A⁻¹B is self-adjoint in the A-inner product, so Lanczos in that
//! inner product gives a tridiagonal matrix whose largest eigenvalues θ are the largest
//! μ = 1/(λ − σ), i.e. the eigenvalues λ = σ + 1/θ nearest above σ. Each Lanczos vector is
//! orthogonalized twice against all previous ones; iteration stops when the residual
//! estimate β_m |s_m,i| of every wanted Ritz pair is below 1e-9 θ_i (eigenvalue error of
//! order its square). A single start vector sees one copy of a multiple eigenvalue.

use nalgebra::{DMatrix, SymmetricEigen};

use super::linear::FactorKind;
use super::newton::{IncrementReport, SolveError, Solver, StepPlan};
pub use super::report::BucklingReport;
use crate::element::NODE_DOFS;
use crate::model::{Model, State, FIXED};

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Deterministic pseudo-random start vector entries in [−1, 1) (an LCG, Knuth MMIX).
fn start_vector(n: usize, seed: u64) -> Vec<f64> {
    let mut s = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    (0..n)
        .map(|_| {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        })
        .collect()
}

impl<'m> Solver<'m> {
    /// Shift-invert Lanczos on T = A⁻¹B (A factorized in `self.cholesky`, both stored as
    /// upper triangles): the `nev` largest positive θ as λ = σ + 1/θ with Ritz vectors, and
    /// the number of Lanczos steps.
    fn lanczos(&mut self, a: &[f64], b: &[f64], start: &[f64], nev: usize, sigma: f64) -> Result<(Vec<f64>, Vec<Vec<f64>>, usize), String> {
        let n = start.len();
        let max_steps = n.min(200 + 40 * nev).min(2000);
        let mut tmp = vec![0.0; n];
        // Start: A⁻¹B of the prebuckling direction plus a pseudo-random perturbation, so no
        // mode is missed by symmetry.
        let r = start_vector(n, 7);
        let smax = start.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
        let mut q: Vec<f64> = start.iter().zip(&r).map(|(s, r)| s / smax + 1e-3 * r).collect();
        self.cholesky.multiply(b, &q, &mut tmp);
        q.copy_from_slice(&tmp);
        self.cholesky.solve(&mut q);
        self.cholesky.multiply(a, &q, &mut tmp);
        let nrm = dot(&q, &tmp).sqrt();
        if !(nrm > 0.0) || !nrm.is_finite() {
            return Err("the start vector has no component the geometric stiffness acts on".into());
        }
        q.iter_mut().for_each(|v| *v /= nrm);
        let mut basis: Vec<Vec<f64>> = vec![q];
        let mut alpha: Vec<f64> = Vec::new();
        let mut beta: Vec<f64> = Vec::new();
        let mut w = vec![0.0; n];
        let mut found: Option<(Vec<f64>, DMatrix<f64>)> = None;
        for j in 0..max_steps {
            self.cholesky.multiply(b, &basis[j], &mut w);
            self.cholesky.solve(&mut w);
            let mut aj = 0.0;
            for _pass in 0..2 {
                self.cholesky.multiply(a, &w, &mut tmp);
                for (i, qi) in basis.iter().enumerate() {
                    let c = dot(qi, &tmp);
                    if i == j {
                        aj += c;
                    }
                    w.iter_mut().zip(qi).for_each(|(x, y)| *x -= c * y);
                }
            }
            alpha.push(aj);
            self.cholesky.multiply(a, &w, &mut tmp);
            let bj = dot(&w, &tmp).max(0.0).sqrt();
            let m = j + 1;
            let exhausted = bj <= 1e-14 * aj.abs().max(1e-300);
            let last = exhausted || m == max_steps;
            if m >= nev && (m % 5 == 0 || last) {
                let mut t = DMatrix::zeros(m, m);
                for i in 0..m {
                    t[(i, i)] = alpha[i];
                    if i + 1 < m {
                        t[(i, i + 1)] = beta[i];
                        t[(i + 1, i)] = beta[i];
                    }
                }
                let eig = SymmetricEigen::new(t);
                let mut order: Vec<usize> = (0..m).collect();
                order.sort_by(|&x, &y| eig.eigenvalues[y].total_cmp(&eig.eigenvalues[x]));
                let wanted: Vec<usize> = order.iter().copied().take(nev).collect();
                let ok = wanted.iter().all(|&i| {
                    let th = eig.eigenvalues[i];
                    th > 0.0 && (bj * eig.eigenvectors[(m - 1, i)]).abs() <= 1e-9 * th
                });
                if ok || last {
                    let th: Vec<f64> = wanted.iter().map(|&i| eig.eigenvalues[i]).collect();
                    let s = DMatrix::from_fn(m, wanted.len(), |r, c| eig.eigenvectors[(r, wanted[c])]);
                    found = Some((th, s));
                    break;
                }
            }
            if exhausted {
                break;
            }
            beta.push(bj);
            basis.push(w.iter().map(|v| v / bj).collect());
        }
        let (theta, s) = found.ok_or("Lanczos found no eigenvalue")?;
        if theta.len() < nev || theta.iter().any(|t| !(*t > 0.0)) {
            return Err("fewer positive eigenvalues than modes asked for: the load change causes no buckling".into());
        }
        let steps = alpha.len();
        let vectors = (0..theta.len())
            .map(|c| {
                let mut x = vec![0.0; n];
                for (r, qr) in basis.iter().enumerate().take(s.nrows()) {
                    let wgt = s[(r, c)];
                    x.iter_mut().zip(qr).for_each(|(a, b)| *a += wgt * b);
                }
                x
            })
            .collect();
        Ok((theta.iter().map(|t| sigma + 1.0 / t).collect(), vectors, steps))
    }

    /// Lowest `nev` buckling eigenpairs at `state` for the load change from `start` to
    /// `target` scales, nearest above the shift `sigma`.
    pub fn buckling(&mut self, state: &State, start: &[f64], target: &[f64], nev: usize, sigma: f64) -> Result<BucklingReport, String> {
        let model = self.model;
        let n = model.dofs.n_free;
        if n == 0 {
            return Err("no free DOFs".into());
        }
        // Tangent at the state and the prebuckling direction v = K⁻¹ f.
        self.assemble(state, start, true).map_err(|f| format!("element {} failed at the base state: {}", f.element, f.failure))?;
        let k_t = self.values.clone();
        let f = self.load_change(state, start, target);
        if f.iter().all(|v| *v == 0.0) {
            return Err("the step changes no load: give the reference load in the step's scale table".into());
        }
        match self.cholesky.factorize(&k_t) {
            Ok(FactorKind::Llt) => {}
            Ok(FactorKind::Ldlt) if sigma != 0.0 => {}
            Ok(FactorKind::Ldlt) => {
                return Err(format!(
                    "the tangent at the base state is not positive definite ({} negative pivots): the state is already unstable",
                    self.cholesky.negative_pivots()
                ))
            }
            Err(e) => return Err(format!("{e} at the base state (a mechanism: missing supports?)")),
        }
        let mut v = f.clone();
        self.cholesky.solve(&mut v);
        // K_Δ by central differences along v.
        let mut umax = 0.0f64;
        for (g, &e) in model.dofs.eq.iter().enumerate() {
            if e != FIXED && g % NODE_DOFS < 3 {
                umax = umax.max(v[e].abs());
            }
        }
        let (lo, hi) = model.x0.iter().fold((model.x0[0], model.x0[0]), |(l, h), p| (l.inf(p), h.sup(p)));
        let size = (hi - lo).norm().max(1e-300);
        if !(umax > 0.0) || !umax.is_finite() {
            return Err("the load change produces no finite translation".into());
        }
        let eps = 1e-6 * size / umax;
        let mut plus = state.clone();
        model.update(&mut plus, &v, eps);
        let mut minus = state.clone();
        model.update(&mut minus, &v, -eps);
        self.assemble(&plus, start, true).map_err(|f| format!("element {} failed on the prebuckling path: {}", f.element, f.failure))?;
        let k_plus = self.values.clone();
        self.assemble(&minus, start, true).map_err(|f| format!("element {} failed on the prebuckling path: {}", f.element, f.failure))?;
        // B = −K_Δ.
        let b: Vec<f64> = self.values.iter().zip(&k_plus).map(|(m, p)| -(p - m) / (2.0 * eps)).collect();
        let a: Vec<f64> = k_t.iter().zip(&b).map(|(k, bb)| k - sigma * bb).collect();
        match self.cholesky.factorize(&a) {
            Ok(FactorKind::Llt) => {}
            _ => return Err(format!("K_T − σ(−K_Δ) is not positive definite for σ = {sigma}: choose a shift below the lowest critical load")),
        }
        let (eigenvalues, vectors, iterations) = self.lanczos(&a, &b, &v, nev, sigma)?;
        let mut bx = vec![0.0; n];
        if eigenvalues.iter().any(|l| !l.is_finite()) {
            return Err("fewer positive eigenvalues than modes asked for: the load change causes no buckling".into());
        }
        // Residuals and modes over all DOFs.
        let mut residuals = Vec::new();
        let mut modes = Vec::new();
        let mut kx = vec![0.0; n];
        for (lam, phi) in eigenvalues.iter().zip(&vectors) {
            self.cholesky.multiply(&k_t, phi, &mut kx);
            self.cholesky.multiply(&b, phi, &mut bx);
            let res: f64 = kx.iter().zip(&bx).map(|(k, bb)| (k - lam * bb).powi(2)).sum::<f64>().sqrt();
            residuals.push(res / dot(&kx, &kx).sqrt().max(1e-300));
            let mut full = vec![0.0; NODE_DOFS * model.n_nodes()];
            for (g, &e) in model.dofs.eq.iter().enumerate() {
                if e != FIXED {
                    full[g] = phi[e];
                }
            }
            let scale = (0..model.n_nodes())
                .map(|nn| (full[NODE_DOFS * nn].powi(2) + full[NODE_DOFS * nn + 1].powi(2) + full[NODE_DOFS * nn + 2].powi(2)).sqrt())
                .fold(0.0, f64::max);
            // Sign: largest translation component positive, for reproducible seeding.
            let imax = (0..full.len()).filter(|g| g % NODE_DOFS < 3).max_by(|&i, &j| full[i].abs().total_cmp(&full[j].abs())).unwrap_or(0);
            let s = if full[imax] < 0.0 { -1.0 } else { 1.0 } / scale.max(1e-300);
            full.iter_mut().for_each(|v| *v *= s);
            modes.push(full);
        }
        let critical_scales = eigenvalues.iter().map(|l| start.iter().zip(target).map(|(a, b)| a + l * (b - a)).collect()).collect();
        Ok(BucklingReport { eigenvalues, critical_scales, residuals, iterations, modes })
    }

    /// A `Buckling` step: eigenpairs at `state` for the step's load change, reported as one
    /// increment (the state and the scales are left unchanged).
    pub(super) fn run_buckling(&mut self, si: usize, step: &StepPlan, start: &[f64], state: &State, nev: usize, sigma: f64) -> Result<IncrementReport, SolveError> {
        let rep = self.buckling(state, start, &step.target_scales, nev, sigma).map_err(|cause| SolveError {
            step: si,
            step_name: step.name.clone(),
            last_converged_time: si as f64,
            simulated_time: None,
            iteration: 0,
            residuals: vec![],
            worst_element: None,
            cause: format!("linearized buckling failed: {cause}"),
        })?;
        // Restore the base-state assembly for whatever follows.
        let _ = self.assemble(state, start, true);
        Ok(IncrementReport {
            step: si,
            step_name: step.name.clone(),
            increment: 1,
            time: si as f64 + 1.0,
            scales: start.to_vec(),
            buckling: Some(rep),
            ..Default::default()
        })
    }
}

/// `model` with the reference geometry perturbed by Σ a_k φ_k: node positions moved by the
/// modes' translations and reference directors turned by their tilts (exponential map), so
/// the imperfect shell stays a shell with directors close to its normals.
pub fn seed_modes(model: &Model, modes: &[Vec<f64>], amplitudes: &[f64]) -> Model {
    let mut m = model.clone();
    for (phi, &a) in modes.iter().zip(amplitudes) {
        for nn in 0..m.n_nodes() {
            let g = NODE_DOFS * nn;
            for k in 0..3 {
                m.x0[nn][k] += a * phi[g + k];
            }
            let tilt = [a * phi[g + 3], a * phi[g + 4]];
            if tilt != [0.0, 0.0] {
                m.frames0[nn] = m.frames0[nn].tilted(tilt);
            }
        }
    }
    m
}

/// A buckling-mode imperfection resolved from the scene: the reference load scales of the
/// buckling analysis on the perfect geometry and (1-based mode, amplitude) pairs.
#[derive(Clone, Debug, Default)]
pub struct ModeImperfection {
    /// Load scales of the reference load (one per load pattern).
    pub scales: Vec<f64>,
    /// (mode number from 1, amplitude = largest translation of the mode's contribution).
    pub modes: Vec<(usize, f64)>,
}

/// The perfect `model`'s buckling modes at the reference state under `imp.scales`, and the
/// model seeded with Σ a_k φ_k (see [`seed_modes`]).
pub fn seeded_model(model: &Model, imp: &ModeImperfection, settings: &super::SolverSettings) -> Result<(Model, BucklingReport), String> {
    let nev = imp.modes.iter().map(|m| m.0).max().unwrap_or(1).max(1);
    let mut solver = Solver::new(model, settings.clone())?;
    let state = model.initial_state();
    let zero = vec![0.0; model.loads.len()];
    let rep = solver.buckling(&state, &zero, &imp.scales, nev, 0.0).map_err(|e| format!("imperfection: linearized buckling of the perfect geometry failed: {e}"))?;
    let modes: Vec<Vec<f64>> = imp
        .modes
        .iter()
        .map(|&(k, _)| rep.modes.get(k.wrapping_sub(1)).cloned().ok_or(format!("imperfection: mode {k} was not computed")))
        .collect::<Result<_, _>>()?;
    let amps: Vec<f64> = imp.modes.iter().map(|m| m.1).collect();
    Ok((seed_modes(model, &modes, &amps), rep))
}
