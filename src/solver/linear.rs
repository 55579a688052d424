//! Sparse symmetric factorization with faer: symbolic analysis (AMD ordering, elimination
//! tree, supernodes) once per pattern, numeric Cholesky each Newton iteration into
//! preallocated storage. LLᵀ is tried first (its failure is a free positive-definiteness
//! test); an indefinite tangent falls back to LDLᵀ on the same symbolic structure.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LdltRef, LltRef, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

use crate::assembly::Pattern;

/// Which factorization the last numeric step produced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FactorKind {
    /// Positive definite: LLᵀ.
    Llt,
    /// Not positive definite: LDLᵀ without pivoting.
    Ldlt,
}

/// Errors of the linear solver.
#[derive(Clone, Debug)]
pub enum LinearError {
    /// The symbolic analysis failed (out of memory or index overflow).
    Symbolic(String),
    /// The tangent is singular (a zero pivot in LDLᵀ).
    Singular,
}

impl std::fmt::Display for LinearError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LinearError::Symbolic(s) => write!(f, "symbolic factorization failed: {s}"),
            LinearError::Singular => write!(f, "tangent matrix is singular"),
        }
    }
}

/// A reusable sparse Cholesky solver for one pattern.
pub struct SparseCholesky {
    pattern: SymbolicSparseColMat<usize>,
    symbolic: SymbolicCholesky<usize>,
    l_values: Vec<f64>,
    buffer: MemBuffer,
    kind: FactorKind,
    par: Par,
}

impl SparseCholesky {
    /// Symbolic analysis of the upper-triangular pattern; `threads` for the numeric phase.
    pub fn analyse(pattern: &Pattern, threads: usize) -> Result<Self, LinearError> {
        let n = pattern.n;
        let sym = SymbolicSparseColMat::new_checked(n, n, pattern.col_ptr.clone(), None, pattern.row_idx.clone());
        let symbolic = factorize_symbolic_cholesky(
            sym.as_ref(),
            Side::Upper,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .map_err(|e| LinearError::Symbolic(format!("{e:?}")))?;
        let par = if threads > 1 { Par::rayon(threads) } else { Par::Seq };
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()),
            symbolic.factorize_numeric_ldlt_scratch::<f64>(par, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, par),
        ]);
        let buffer = MemBuffer::try_new(req).map_err(|_| LinearError::Symbolic("out of memory for workspace".into()))?;
        let l_values = vec![0.0; symbolic.len_val()];
        Ok(Self { pattern: sym, symbolic, l_values, buffer, kind: FactorKind::Llt, par })
    }

    /// Which factorization the last successful numeric step produced.
    pub fn kind(&self) -> FactorKind {
        self.kind
    }

    /// Number of stored values of the factor.
    pub fn factor_nnz(&self) -> usize {
        self.l_values.len()
    }

    fn matrix<'a>(&'a self, values: &'a [f64]) -> SparseColMatRef<'a, usize, f64> {
        let s: SymbolicSparseColMatRef<'a, usize> = self.pattern.as_ref();
        SparseColMatRef::new(s, values)
    }

    /// Numeric factorization of the matrix with the analysed pattern and `values`.
    pub fn factorize(&mut self, values: &[f64]) -> Result<FactorKind, LinearError> {
        let par = self.par;
        let a = SparseColMatRef::new(self.pattern.as_ref(), values);
        let llt = self.symbolic.factorize_numeric_llt::<f64>(
            &mut self.l_values,
            a,
            Side::Upper,
            LltRegularization::default(),
            par,
            MemStack::new(&mut self.buffer),
            Default::default(),
        );
        if llt.is_ok() {
            self.kind = FactorKind::Llt;
            return Ok(FactorKind::Llt);
        }
        let a = SparseColMatRef::new(self.pattern.as_ref(), values);
        self.symbolic
            .factorize_numeric_ldlt::<f64>(
                &mut self.l_values,
                a,
                Side::Upper,
                LdltRegularization::default(),
                par,
                MemStack::new(&mut self.buffer),
                Default::default(),
            )
            .map_err(|_| LinearError::Singular)?;
        self.kind = FactorKind::Ldlt;
        Ok(FactorKind::Ldlt)
    }

    /// Solves A x = rhs in place with the last factorization.
    pub fn solve(&mut self, rhs: &mut [f64]) {
        let n = rhs.len();
        let mat = MatMut::from_column_major_slice_mut(rhs, n, 1);
        let stack = MemStack::new(&mut self.buffer);
        match self.kind {
            FactorKind::Llt => LltRef::new(&self.symbolic, &self.l_values).solve_in_place_with_conj(Conj::No, mat, self.par, stack),
            FactorKind::Ldlt => LdltRef::new(&self.symbolic, &self.l_values).solve_in_place_with_conj(Conj::No, mat, self.par, stack),
        }
    }

    /// y = A x for the symmetric matrix stored as its upper triangle with `values`.
    pub fn multiply(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        let a = self.matrix(values);
        y.iter_mut().for_each(|v| *v = 0.0);
        let (cp, ri) = (a.symbolic().col_ptr(), a.symbolic().row_idx());
        for c in 0..x.len() {
            for p in cp[c]..cp[c + 1] {
                let r = ri[p];
                y[r] += values[p] * x[c];
                if r != c {
                    y[c] += values[p] * x[r];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 5-point Laplacian plus a shift on an m×m grid, upper triangle.
    fn laplacian(m: usize) -> (Pattern, Vec<f64>) {
        let n = m * m;
        let mut col_ptr = vec![0];
        let mut row_idx = Vec::new();
        let mut values = Vec::new();
        for c in 0..n {
            let (i, j) = (c % m, c / m);
            if j > 0 {
                row_idx.push(c - m);
                values.push(-1.0);
            }
            if i > 0 {
                row_idx.push(c - 1);
                values.push(-1.0);
            }
            row_idx.push(c);
            values.push(4.01);
            col_ptr.push(row_idx.len());
        }
        (Pattern { n, col_ptr, row_idx }, values)
    }

    #[test]
    fn solves_small_and_large_systems_to_round_off() {
        for m in [5, 60, 150] {
            let (p, v) = laplacian(m);
            let mut chol = SparseCholesky::analyse(&p, 2).unwrap();
            assert_eq!(chol.factorize(&v).unwrap(), FactorKind::Llt);
            let b: Vec<f64> = (0..p.n).map(|i| ((i * 7919) % 13) as f64 - 6.0).collect();
            let mut x = b.clone();
            chol.solve(&mut x);
            let mut ax = vec![0.0; p.n];
            chol.multiply(&v, &x, &mut ax);
            let err = ax.iter().zip(&b).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            assert!(err < 1e-10, "m={m}: residual {err}");
            // Indefinite: shift the diagonal negative, LDLT takes over.
            let vneg: Vec<f64> = v.iter().map(|&a| if a > 0.0 { a - 6.0 } else { a }).collect();
            assert_eq!(chol.factorize(&vneg).unwrap(), FactorKind::Ldlt);
            let mut x = b.clone();
            chol.solve(&mut x);
            chol.multiply(&vneg, &x, &mut ax);
            let err = ax.iter().zip(&b).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            assert!(err < 1e-8, "m={m} indefinite: residual {err}");
        }
    }
}
