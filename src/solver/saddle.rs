//! Stability at rest and leaving a saddle (see the module doc of `dynamics`): the static
//! tangent's positive definiteness (Lyapunov/Dirichlet), its lowest mode by shifted inverse
//! iteration, and moves along it to the minimum of the potential on that line (the
//! negative-curvature step of Moré & Sorensen, Math. Prog. 16, 1979; branch switching along
//! the critical eigenvector, Wriggers 2008, §7.4).

use std::time::Instant;

use nalgebra::Vector3;

use super::inertia::LumpedMass;
use super::linear::FactorKind;
use super::newton::Solver;
use crate::element::NODE_DOFS;
use crate::model::{State, FIXED};

impl<'m> Solver<'m> {
    /// Static tangent at `state` for the stability test: the nodal-force terms report their
    /// stability tangent ([`super::NodalForces::stability_tangent`]: an augmented-Lagrangian
    /// contact, whose Uzawa fixed point enforces the gap exactly, in its constraint limit).
    fn assemble_stability_tangent(&mut self, state: &State, scales: &[f64]) -> bool {
        // The terms' blocks change with the switch: no kept evaluation serves either side.
        self.nodal_cache.forget();
        self.nodal_forces.iter_mut().for_each(|f| f.stability_tangent(true));
        let ok = self.assemble(state, scales, true).is_ok();
        self.nodal_forces.iter_mut().for_each(|f| f.stability_tangent(false));
        self.nodal_cache.forget();
        ok
    }

    /// Whether `state` is a stable equilibrium candidate: K + 1e-10·diag|K| (static tangent
    /// at load scales `scales`, constraints in their limit, see
    /// [`Solver::assemble_stability_tangent`]) is positive definite (Lyapunov/Dirichlet: a
    /// strict minimum of the potential energy).
    pub(super) fn stable(&mut self, state: &State, scales: &[f64]) -> bool {
        self.assemble_stability_tangent(state, scales) && self.assembled_tangent_positive_definite()
    }

    /// Whether the assembled tangent K (left unchanged), shifted by 1e-10·diag|K| against
    /// round-off, factors as LLᵀ.
    fn assembled_tangent_positive_definite(&mut self) -> bool {
        let mut shifted = self.values.clone();
        let col_ptr = &self.assembler.pattern.col_ptr;
        for c in 0..self.model.dofs.n_free {
            let p = col_ptr[c + 1] - 1;
            shifted[p] += 1e-10 * shifted[p].abs();
        }
        let t = Instant::now();
        let kind = self.cholesky.factorize(&shifted);
        self.timings.factorization += t.elapsed().as_secs_f64();
        matches!(kind, Ok(FactorKind::Llt))
    }

    /// Lowest eigenpair (ω², φ) of K φ = ω² M φ with K the static tangent of the stability
    /// test assembled at `state` and M the diagonal `mdiag` over the free equations, when ω² < 0: the shift c of
    /// K + c M is bracketed by Cholesky success (LLᵀ exists iff c > −ω²_min) to 1 %, then
    /// inverse iteration x ← (K + c M)⁻¹ M x, M-normalised, converges to φ at the rate
    /// (ω²_min + c)/(ω²_2 + c) per iteration; ω² is the Rayleigh quotient φ·Kφ (φ·Mφ = 1).
    fn lowest_mode(&mut self, state: &State, scales: &[f64], mdiag: &[f64]) -> Option<(f64, Vec<f64>)> {
        // Stable (the test of `stable`): no unstable mode.
        if !self.assemble_stability_tangent(state, scales) || self.assembled_tangent_positive_definite() {
            return None;
        }
        let k = self.values.clone();
        let nf = self.model.dofs.n_free;
        let diag: Vec<usize> = (0..nf).map(|e| self.assembler.pattern.col_ptr[e + 1] - 1).collect();
        let positive_definite = |s: &mut Self, c: f64| -> bool {
            let mut v = k.clone();
            diag.iter().zip(mdiag).for_each(|(&p, m)| v[p] += c * m);
            let t = Instant::now();
            let kind = s.cholesky.factorize(&v);
            s.timings.factorization += t.elapsed().as_secs_f64();
            matches!(kind, Ok(FactorKind::Llt))
        };
        let scale = diag.iter().zip(mdiag).map(|(&p, m)| k[p].abs() / m).fold(0.0, f64::max);
        let mut hi = 1e-10 * scale;
        let mut lo = 0.0;
        let mut tries = 0;
        while !positive_definite(self, hi) {
            lo = hi;
            hi *= 4.0;
            tries += 1;
            if tries > 40 {
                return None;
            }
        }
        for _ in 0..60 {
            if hi - lo <= 0.01 * hi {
                break;
            }
            let mid = 0.5 * (lo + hi);
            if positive_definite(self, mid) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        if !positive_definite(self, hi) {
            return None;
        }
        // Deterministic start with a component along every equation.
        let mut x: Vec<f64> = (0..nf).map(|i| 1.0 + ((i * 7919) % 101) as f64 / 101.0).collect();
        for _ in 0..12 {
            let mut y: Vec<f64> = x.iter().zip(mdiag).map(|(a, m)| a * m).collect();
            self.cholesky.solve(&mut y);
            let norm = y.iter().zip(mdiag).map(|(a, m)| a * a * m).sum::<f64>().sqrt();
            if !(norm.is_finite() && norm > 0.0) {
                return None;
            }
            x = y.iter().map(|a| a / norm).collect();
        }
        let p = &self.assembler.pattern;
        let mut omega2 = 0.0;
        for c in 0..nf {
            for q in p.col_ptr[c]..p.col_ptr[c + 1] {
                let r = p.row_idx[q];
                omega2 += if r == c { k[q] * x[c] * x[c] } else { 2.0 * k[q] * x[r] * x[c] };
            }
        }
        (omega2 < 0.0).then_some((omega2, x))
    }

    /// Moves `state`, an equilibrium whose static tangent is not positive definite, along its
    /// lowest mode φ (see [`Solver::lowest_mode`]) to the first minimum of the potential along
    /// the line, and repeats from there along the new lowest mode until the tangent is positive
    /// definite (at most 25 moves). On each line the minimum is where the directional
    /// derivative g(s) = φ·(f_int − f_ext)(u + s φ) (contact forces included) turns from
    /// negative to non-negative. The direction ±φ is downhill from the slope g(0) that the
    /// rest tolerance leaves (or, at g(0) = 0, the side of the more negative slope at the first
    /// trial move); the moves double from 10⁻⁹ of the model's size in largest nodal
    /// translation, up to 5 % of it (or the last admissible state), and the bracket is bisected
    /// 12 times. Returns (ω² of the first move, largest nodal translation of all moves,
    /// whether the moves ended at a positive definite tangent), or None (state unchanged) when
    /// no unstable mode is found.
    pub(super) fn escape_saddle(&mut self, state: &mut State, scales: &[f64], mass: &LumpedMass) -> Option<(f64, f64, bool)> {
        let start = state.clone();
        let mut first = None;
        let mut settled = false;
        for _ in 0..25 {
            match self.negative_curvature_move(state, scales, mass) {
                Some((omega2, _)) => {
                    first.get_or_insert(omega2);
                }
                None => {
                    settled = true;
                    break;
                }
            }
        }
        let omega2 = first?;
        let moved = (0..self.model.n_nodes()).map(|n| (state.u[n] - start.u[n]).norm()).fold(0.0, f64::max);
        Some((omega2, moved, settled))
    }

    /// One move of [`Solver::escape_saddle`]: along the lowest mode of `state`, if unstable, to
    /// the first minimum of the potential on that line; returns (ω², largest nodal
    /// translation of the move).
    fn negative_curvature_move(&mut self, state: &mut State, scales: &[f64], mass: &LumpedMass) -> Option<(f64, f64)> {
        let model = self.model;
        let nf = model.dofs.n_free;
        let mut mdiag = vec![0.0; nf];
        for (g, &e) in model.dofs.eq.iter().enumerate() {
            if e != FIXED {
                let n = g / NODE_DOFS;
                mdiag[e] = if g % NODE_DOFS < 3 { mass.translational[n] } else { mass.rotary[n] };
            }
        }
        // A metric needs every free equation weighted: massless ones (no rotary inertia) get
        // a small weight.
        let floor = 1e-12 * mdiag.iter().copied().fold(0.0, f64::max);
        mdiag.iter_mut().for_each(|m| *m = m.max(floor));
        let (omega2, phi) = self.lowest_mode(state, scales, &mdiag)?;
        let amax = (0..model.n_nodes())
            .map(|n| (0..3).map(|k| model.dofs.eq[NODE_DOFS * n + k]).filter(|&e| e != FIXED).map(|e| phi[e] * phi[e]).sum::<f64>().sqrt())
            .fold(0.0, f64::max);
        let (lo, hi) = model.x0.iter().fold((Vector3::repeat(f64::INFINITY), Vector3::repeat(f64::NEG_INFINITY)), |(a, b), x| (a.inf(x), b.sup(x)));
        let size = (hi - lo).norm();
        if !(amax > 0.0 && size > 0.0) {
            return None;
        }
        let base = state.clone();
        let mut r = vec![0.0; nf];
        // Directional derivative of the potential at a move of largest nodal translation t.
        let mut slope = |s: &mut Self, t: f64| -> Option<f64> {
            let mut trial = base.clone();
            model.update(&mut trial, &phi, t / amax);
            s.assemble(&trial, scales, false).ok()?;
            if !s.f_int.iter().chain(&s.f_ext).all(|v| v.is_finite()) {
                return None;
            }
            s.residual(&mut r);
            Some(phi.iter().zip(&r).map(|(a, b)| a * b).sum::<f64>())
        };
        let t0 = 1e-9 * size;
        // Downhill side: against the slope g(0) the rest tolerance leaves along φ; at an exact
        // saddle (g(0) = 0) the side whose slope is more negative at the first trial move.
        let sign = match slope(self, 0.0)? {
            g0 if g0 < 0.0 => 1.0,
            g0 if g0 > 0.0 => -1.0,
            _ => match (slope(self, t0), slope(self, -t0)) {
                (Some(gp), Some(gm)) => if -gm < gp { -1.0 } else { 1.0 },
                (None, Some(_)) => -1.0,
                (Some(_), None) => 1.0,
                (None, None) => return None,
            },
        };
        let (mut a, mut b) = (0.0, t0);
        let mut bracketed = false;
        while b <= 0.05 * size {
            match slope(self, sign * b) {
                Some(g) if sign * g >= 0.0 => {
                    bracketed = true;
                    break;
                }
                Some(_) => {
                    a = b;
                    b *= 2.0;
                }
                None => break,
            }
        }
        if bracketed {
            for _ in 0..12 {
                let m = 0.5 * (a + b);
                match slope(self, sign * m) {
                    Some(g) if sign * g < 0.0 => a = m,
                    _ => b = m,
                }
            }
        }
        if a == 0.0 {
            return None;
        }
        model.update(state, &phi, sign * a / amax);
        Some((omega2, a))
    }
}
