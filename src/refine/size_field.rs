//! The size field of a refinement pass and the graded node lines that follow it.
//!
//! Per element and pattern direction k the indicator's relative shape error η_k
//! (`indicator`) asks for h_new = h (T/η_k)^{1/2} (bilinear elements: error ∝ h², so this
//! makes η_k = T), clamped to [h/4, min(2h, h_max)]: at most four times finer or twice
//! coarser per pass (a flat region coarsens by 2 per pass down to h_max), never coarser than
//! h_max (a quarter of the part's extent in that direction, the `Auto` cap). For a tensor
//! grid the size of a column of elements is the smallest asked for in it; the field
//! h(x) is then limited to grow by at most `GRADING` per unit length (|dh/dx| ≤ 0.2) and the
//! old intervals are split or merged by it, keeping the old node lines (`node_lines`: a
//! nested, graded refinement; Frey & George, *Mesh Generation* 2nd ed. 2008, §1.6 on size
//! maps and gradation).

use super::indicator::ElementIndicator;

/// Largest growth rate |dh/dx| of the size field between elements.
pub const GRADING: f64 = 0.2;

/// Largest size ratio of neighbouring new elements (2:1 balance of nested refinement).
pub const BALANCE: f64 = 2.0;

/// The size an element asks for along direction `k` (module doc), with `h_max` the cap.
pub fn target_size(ind: &ElementIndicator, k: usize, tolerance: f64, h_max: f64) -> f64 {
    let h = ind.h[k];
    let upper = (2.0 * h).min(h_max).max(h / 4.0);
    let wanted = if ind.eta[k] > 0.0 { h * (tolerance / ind.eta[k]).sqrt() } else { f64::INFINITY };
    wanted.clamp(h / 4.0, upper)
}

/// New node lines for the per-interval target sizes `sizes` of the old node lines `lines`
/// (module doc): the field graded, then the old lines kept — an interval merged with its
/// right neighbour where both ask for at least the merged length, every other interval split
/// into m equal parts, m = ⌈length / size⌉ raised until neighbouring new elements differ by at
/// most 25 %; at least `min_cells` intervals in all.
///
/// Keeping the old lines (nested refinement) matters for fabric: a new element straddling an
/// old node would be the chord of two old elements kinked by the angle θ = hκ between them,
/// shortened by about θ²/8 — a membrane strain that, at fabric's membrane-to-weight
/// stiffness ratio (E t / ρ_A g ℓ ~ 10⁴), is a residual of order 1 (measured on the Peirce
/// strip: 0.82 relative with non-nested graded lines). Nested new nodes lie on the old
/// straight elements; only merged (flat) intervals take such a chord.
pub fn node_lines(lines: &[f64], sizes: &[f64], min_cells: usize) -> Vec<f64> {
    let n = lines.len() - 1;
    // Lipschitz limit h(x) ≤ h(y) + GRADING |x − y| on interval midpoints (two sweeps).
    let mid: Vec<f64> = lines.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
    let mut h: Vec<f64> = sizes.to_vec();
    for k in 1..n {
        h[k] = h[k].min(h[k - 1] + GRADING * (mid[k] - mid[k - 1]));
    }
    for k in (0..n.saturating_sub(1)).rev() {
        h[k] = h[k].min(h[k + 1] + GRADING * (mid[k + 1] - mid[k]));
    }
    // Merge pairs of flat intervals (each asks for at least their joint length).
    let mut spans: Vec<(f64, f64, f64)> = Vec::new(); // (start, end, size asked)
    let mut k = 0;
    while k < n {
        let joint = lines.get(k + 2).map(|e| e - lines[k]);
        if let Some(j) = joint
            && n > min_cells.max(2)
            && h[k] >= j * (1.0 - 1e-9)
            && h[k + 1] >= j * (1.0 - 1e-9)
        {
            spans.push((lines[k], lines[k + 2], h[k].min(h[k + 1])));
            k += 2;
        } else {
            spans.push((lines[k], lines[k + 1], h[k]));
            k += 1;
        }
    }
    let len = |s: &(f64, f64, f64)| s.1 - s.0;
    let mut m: Vec<usize> = spans.iter().map(|s| ((len(s) / s.2 - 1e-9).ceil() as usize).max(1)).collect();
    // 2:1 balance between neighbouring new elements (nested splits are integer: 12.5/4 next
    // to 12.5/3 is already 33 %; the smooth grading is the field's, above).
    let mut changed = true;
    while changed {
        changed = false;
        for i in 0..spans.len() {
            for j in [i.wrapping_sub(1), i + 1] {
                if j >= spans.len() {
                    continue;
                }
                let (si, sj) = (len(&spans[i]) / m[i] as f64, len(&spans[j]) / m[j] as f64);
                if si > BALANCE * sj * (1.0 + 1e-12) {
                    m[i] = (len(&spans[i]) / (BALANCE * sj) - 1e-9).ceil() as usize;
                    changed = true;
                }
            }
        }
    }
    while m.iter().sum::<usize>() < min_cells {
        let i = (0..spans.len()).max_by(|&a, &b| (len(&spans[a]) / m[a] as f64).total_cmp(&(len(&spans[b]) / m[b] as f64))).unwrap_or(0);
        m[i] += 1;
    }
    let mut out = vec![lines[0]];
    for (s, &mi) in spans.iter().zip(&m) {
        for q in 1..=mi {
            out.push(if q == mi { s.1 } else { s.0 + len(s) * q as f64 / mi as f64 });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_field_gives_uniform_lines_and_grading_holds() {
        let lines: Vec<f64> = (0..=10).map(|i| i as f64 * 0.1).collect();
        let out = node_lines(&lines, &[0.05; 10], 1);
        assert_eq!(out.len(), 21);
        // Flat intervals merge in pairs (coarsening by 2).
        assert_eq!(node_lines(&lines, &[0.2; 10], 1).len(), 6);
        assert!(out.windows(2).all(|w| ((w[1] - w[0]) - 0.05).abs() < 1e-12));
        // A jump from 0.01 to 0.2: sizes grow by at most 2:1 between neighbours.
        let mut sizes = [0.2; 10];
        sizes[0] = 0.01;
        let out = node_lines(&lines, &sizes, 1);
        let d: Vec<f64> = out.windows(2).map(|w| w[1] - w[0]).collect();
        assert!(d[0] <= 0.01 + 1e-12, "first {}", d[0]);
        // The old lines are kept where not merged (nested refinement).
        assert!(lines[..2].iter().all(|l| out.iter().any(|o| (o - l).abs() < 1e-12)));
        for w in d.windows(2) {
            assert!(w[1] / w[0] <= 2.0 + 1e-9 && w[0] / w[1] <= 2.0 + 1e-9, "{} → {}", w[0], w[1]);
        }
    }

    #[test]
    fn target_size_makes_the_error_the_tolerance() {
        let ind = ElementIndicator { h: [0.01, 0.01], kappa: [20.0, 0.0], eta: [(0.01f64 * 20.0).powi(2) / 8.0, 0.0] };
        // √(8T)/κ = 0.2828/20 = 14.1 mm, within [h/4, 2h].
        assert!((target_size(&ind, 0, 0.01, 1.0) - (0.08f64).sqrt() / 20.0).abs() < 1e-12);
        assert_eq!(target_size(&ind, 1, 0.01, 1.0), 0.02);
        assert_eq!(target_size(&ind, 1, 0.01, 0.015), 0.015);
    }
}
