//! Node spacing of structured grids in their two surface parameters: uniform, or the
//! distorted pattern of the shell convergence studies (each edge divided in the ratio
//! 1:2:3:…:N, as in the convergence studies of Ko, Lee & Bathe 2017, C&S 182), with the
//! nodes then placed on the exact surface by the generator.

use serde::{Deserialize, Serialize};

/// How the nodes of a structured grid are spaced in the surface parameters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Spacing {
    /// Equal steps.
    #[default]
    Uniform,
    /// Each boundary edge divided 1:2:…:N, the grading reversed on opposite edges; the
    /// interior node (i, j) is where the straight parameter line joining the i-th points of
    /// the two u-edges crosses the one joining the j-th points of the two v-edges. Elements
    /// are neither parallelograms nor of equal size.
    Distorted,
}

/// Fraction of an edge at its k-th division point when it is divided 1:2:…:n:
/// k(k+1)/(n(n+1)).
fn graded(k: usize, n: usize) -> f64 {
    (k * (k + 1)) as f64 / (n * (n + 1)) as f64
}

impl Spacing {
    /// Parameters (s, t) ∈ [0, 1]² of node (i, j) of an nu × nv grid.
    pub fn point(self, i: usize, j: usize, nu: usize, nv: usize) -> (f64, f64) {
        let (fu, fv) = (i as f64 / nu as f64, j as f64 / nv as f64);
        match self {
            Spacing::Uniform => (fu, fv),
            Spacing::Distorted => {
                // u-line i: from (a, 0) to (b, 1); v-line j: from (0, c) to (1, d).
                let (a, b) = (graded(i, nu), 1.0 - graded(nu - i, nu));
                let (c, d) = (graded(j, nv), 1.0 - graded(nv - j, nv));
                let s = (a + (b - a) * c) / (1.0 - (b - a) * (d - c));
                (s, c + (d - c) * s)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distorted_edges_are_divided_one_two_three() {
        let n = 4;
        let bottom: Vec<f64> = (0..=n).map(|i| Spacing::Distorted.point(i, 0, n, 3).0).collect();
        let steps: Vec<f64> = bottom.windows(2).map(|w| (w[1] - w[0]) * 10.0).collect();
        for (k, s) in steps.iter().enumerate() {
            assert!((s - (k + 1) as f64).abs() < 1e-12, "{steps:?}");
        }
        // Corners stay corners, boundary nodes stay on their edges.
        assert_eq!(Spacing::Distorted.point(n, 3, n, 3), (1.0, 1.0));
        for j in 0..=3 {
            assert!(Spacing::Distorted.point(0, j, n, 3).0.abs() < 1e-15);
            assert!((Spacing::Distorted.point(n, j, n, 3).0 - 1.0).abs() < 1e-15);
        }
    }
}
