//! Second-order forward-mode automatic differentiation: a scalar with its gradient and
//! Hessian with respect to `N` variables (the "hyper-dual" numbers of Fike & Alonso, AIAA
//! 2011-886, carried as full gradient and Hessian). The primitive distances of contact are
//! short rational expressions of node coordinates; evaluating them in this type gives their
//! exact gradient and Hessian without hand-derived formulas.

use std::ops::{Add, Mul, Neg, Sub};

/// A scalar `v` with gradient `g` and (symmetric) Hessian `h` with respect to `N` variables.
/// `lin` records that `h` is identically zero (constants, variables and their sums), so the
/// operations skip the Hessian terms that vanish — the same results, less work: the
/// distances of contact begin with differences of points.
#[derive(Clone, Copy, Debug)]
pub struct Hd<const N: usize> {
    pub v: f64,
    pub g: [f64; N],
    pub h: [[f64; N]; N],
    pub lin: bool,
}

/// A 3-vector of [`Hd`] scalars.
pub type Hv<const N: usize> = [Hd<N>; 3];

impl<const N: usize> Hd<N> {
    /// A constant.
    pub fn c(v: f64) -> Self {
        Self { v, g: [0.0; N], h: [[0.0; N]; N], lin: true }
    }

    /// Variable number `i` with value `v`.
    pub fn var(v: f64, i: usize) -> Self {
        let mut s = Self::c(v);
        s.g[i] = 1.0;
        s
    }

    /// f(self) from f, f′ and f″ at `self.v` (chain rule to second order).
    pub fn chain(mut self, f: f64, f1: f64, f2: f64) -> Self {
        for i in 0..N {
            for j in 0..N {
                self.h[i][j] = if self.lin { f2 * self.g[i] * self.g[j] } else { f1 * self.h[i][j] + f2 * self.g[i] * self.g[j] };
            }
        }
        for i in 0..N {
            self.g[i] *= f1;
        }
        self.v = f;
        self.lin = false;
        self
    }

    /// 1 / self.
    pub fn recip(self) -> Self {
        let r = 1.0 / self.v;
        self.chain(r, -r * r, 2.0 * r * r * r)
    }

    /// self².
    pub fn square(self) -> Self {
        self.chain(self.v * self.v, 2.0 * self.v, 2.0)
    }

    /// self · c for a constant c.
    pub fn scale(mut self, c: f64) -> Self {
        self.v *= c;
        self.g.iter_mut().for_each(|x| *x *= c);
        if !self.lin {
            self.h.iter_mut().flatten().for_each(|x| *x *= c);
        }
        self
    }
}

impl<const N: usize> Add for Hd<N> {
    type Output = Self;
    fn add(mut self, o: Self) -> Self {
        self.v += o.v;
        for i in 0..N {
            self.g[i] += o.g[i];
        }
        if !o.lin {
            for i in 0..N {
                for j in 0..N {
                    self.h[i][j] += o.h[i][j];
                }
            }
        }
        self.lin &= o.lin;
        self
    }
}

impl<const N: usize> Sub for Hd<N> {
    type Output = Self;
    fn sub(mut self, o: Self) -> Self {
        self.v -= o.v;
        for i in 0..N {
            self.g[i] -= o.g[i];
        }
        if !o.lin {
            for i in 0..N {
                for j in 0..N {
                    self.h[i][j] -= o.h[i][j];
                }
            }
        }
        self.lin &= o.lin;
        self
    }
}

impl<const N: usize> Neg for Hd<N> {
    type Output = Self;
    fn neg(self) -> Self {
        self.scale(-1.0)
    }
}

impl<const N: usize> Mul for Hd<N> {
    type Output = Self;
    /// Product rule: (ab)″ = a″b + ab″ + a′b′ᵀ + b′a′ᵀ.
    fn mul(mut self, o: Self) -> Self {
        let (a, b) = (self.v, o.v);
        for i in 0..N {
            for j in 0..N {
                // Left to right as in the full form, so the results are the same to the bit.
                let (c, d) = (self.g[i] * o.g[j], o.g[i] * self.g[j]);
                self.h[i][j] = match (self.lin, o.lin) {
                    (true, true) => c + d,
                    (true, false) => a * o.h[i][j] + c + d,
                    (false, true) => self.h[i][j] * b + c + d,
                    (false, false) => self.h[i][j] * b + a * o.h[i][j] + c + d,
                };
            }
        }
        for i in 0..N {
            self.g[i] = self.g[i] * b + a * o.g[i];
        }
        self.v = a * b;
        self.lin = false;
        self
    }
}

/// The point of node `k` (variables 3k, 3k+1, 3k+2) at position `x`.
pub fn point<const N: usize>(x: &nalgebra::Vector3<f64>, k: usize) -> Hv<N> {
    [Hd::var(x.x, 3 * k), Hd::var(x.y, 3 * k + 1), Hd::var(x.z, 3 * k + 2)]
}

pub fn sub<const N: usize>(a: &Hv<N>, b: &Hv<N>) -> Hv<N> {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub fn dot<const N: usize>(a: &Hv<N>, b: &Hv<N>) -> Hd<N> {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub fn cross<const N: usize>(a: &Hv<N>, b: &Hv<N>) -> Hv<N> {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quotient_of_products_matches_finite_differences() {
        // f(x, y) = x² y / (1 + y²)
        let f = |x: f64, y: f64| x * x * y / (1.0 + y * y);
        let (x0, y0) = (0.7, -1.3);
        let (x, y) = (Hd::<2>::var(x0, 0), Hd::<2>::var(y0, 1));
        let r = x.square() * y * (Hd::c(1.0) + y.square()).recip();
        assert!((r.v - f(x0, y0)).abs() < 1e-15);
        let e = 1e-5;
        let fx = (f(x0 + e, y0) - f(x0 - e, y0)) / (2.0 * e);
        let fy = (f(x0, y0 + e) - f(x0, y0 - e)) / (2.0 * e);
        let fxy = (f(x0 + e, y0 + e) - f(x0 + e, y0 - e) - f(x0 - e, y0 + e) + f(x0 - e, y0 - e)) / (4.0 * e * e);
        let fyy = (f(x0, y0 + e) - 2.0 * f(x0, y0) + f(x0, y0 - e)) / (e * e);
        assert!((r.g[0] - fx).abs() < 1e-8 && (r.g[1] - fy).abs() < 1e-8);
        assert!((r.h[0][1] - fxy).abs() < 1e-5 && (r.h[1][0] - fxy).abs() < 1e-5);
        assert!((r.h[1][1] - fyy).abs() < 1e-4);
    }
}
