//! Integration rules and bilinear shape functions.

/// Gauss–Legendre points and weights on [−1, 1] for 1 to 5 points.
pub fn gauss_legendre(n: usize) -> Option<(&'static [f64], &'static [f64])> {
    const P1: [f64; 1] = [0.0];
    const W1: [f64; 1] = [2.0];
    const P2: [f64; 2] = [-0.577_350_269_189_625_8, 0.577_350_269_189_625_8];
    const W2: [f64; 2] = [1.0, 1.0];
    const P3: [f64; 3] = [-0.774_596_669_241_483_4, 0.0, 0.774_596_669_241_483_4];
    const W3: [f64; 3] = [0.555_555_555_555_555_6, 0.888_888_888_888_888_9, 0.555_555_555_555_555_6];
    const P4: [f64; 4] = [-0.861_136_311_594_052_6, -0.339_981_043_584_856_3, 0.339_981_043_584_856_3, 0.861_136_311_594_052_6];
    const W4: [f64; 4] = [0.347_854_845_137_453_9, 0.652_145_154_862_546_1, 0.652_145_154_862_546_1, 0.347_854_845_137_453_9];
    const P5: [f64; 5] = [-0.906_179_845_938_664, -0.538_469_310_105_683_1, 0.0, 0.538_469_310_105_683_1, 0.906_179_845_938_664];
    const W5: [f64; 5] = [0.236_926_885_056_189_1, 0.478_628_670_499_366_5, 0.568_888_888_888_888_9, 0.478_628_670_499_366_5, 0.236_926_885_056_189_1];
    match n {
        1 => Some((&P1, &W1)),
        2 => Some((&P2, &W2)),
        3 => Some((&P3, &W3)),
        4 => Some((&P4, &W4)),
        5 => Some((&P5, &W5)),
        _ => None,
    }
}

/// Natural coordinates of the four corner nodes, counter-clockwise.
pub const CORNERS: [(f64, f64); 4] = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];

/// Bilinear shape functions N_a and their derivatives (∂N_a/∂ξ, ∂N_a/∂η) at (ξ, η).
pub fn bilinear(xi: f64, eta: f64) -> ([f64; 4], [f64; 4], [f64; 4]) {
    let mut n = [0.0; 4];
    let mut dxi = [0.0; 4];
    let mut deta = [0.0; 4];
    for (a, &(xa, ya)) in CORNERS.iter().enumerate() {
        n[a] = 0.25 * (1.0 + xa * xi) * (1.0 + ya * eta);
        dxi[a] = 0.25 * xa * (1.0 + ya * eta);
        deta[a] = 0.25 * ya * (1.0 + xa * xi);
    }
    (n, dxi, deta)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rules_integrate_polynomials_exactly() {
        for n in 1..=5 {
            let (p, w) = gauss_legendre(n).unwrap();
            for deg in 0..(2 * n) {
                let q: f64 = p.iter().zip(w).map(|(x, w)| w * x.powi(deg as i32)).sum();
                let exact = if deg % 2 == 1 { 0.0 } else { 2.0 / (deg as f64 + 1.0) };
                assert!((q - exact).abs() < 1e-14, "n={n} deg={deg}");
            }
        }
    }
}
