//! Continuous collision detection by conservative advancement, shared by the barrier
//! contact with rigid bodies (`barrier.rs`) and between shell surfaces (`ipc::surface`).
//!
//! A gap g(s) along a straight motion s ∈ [0, 1] whose rate of change is bounded,
//! |g′(s)| ≤ ℓ, cannot fall from g(s) to g_min before s + (g(s) − g_min)/ℓ; advancing by
//! that amount and re-measuring the gap, repeatedly, reaches the largest safe fraction from
//! below (conservative advancement, Mirtich, *Impulse-based dynamic simulation of rigid body
//! systems*, PhD thesis, UC Berkeley 1996, §2.3; the additive CCD of Li, Kaufman & Jiang,
//! *Codimensional Incremental Potential Contact*, ACM Trans. Graph. 40(4), 2021, §4, in its
//! plain form, with ℓ the sum of the two primitives' largest nodal moves).

/// Advances stop once a step is shorter than this fraction of the motion.
const MIN_ADVANCE: f64 = 1e-6;

/// Largest fraction s ∈ [0, 1] of a straight motion along which the gap g stays above
/// g_min = (1 − `close`) g(0), for a gap changing by at most `rate` per unit of the motion.
///
/// Arguments: `g0` the gap at s = 0; `rate` the bound ℓ on |dg/ds|; `close` the fraction of
/// the gap one motion may close (0 < close < 1); `max_iterations` the number of advances;
/// `gap_at(s)` the gap at s, or None when it is known to stay above g_min from s on (out of
/// reach: the motion is free).
///
/// Returns 0 when g(0) ≤ 0 (already through), 1 when the whole motion is safe (or `rate`
/// is 0), otherwise the fraction reached when the gap comes within round-off of g_min, an
/// advance falls below 10⁻⁶ of the motion, or the iterations run out — always from below,
/// so the bound is conservative.
pub fn conservative_advancement(g0: f64, rate: f64, close: f64, max_iterations: usize, mut gap_at: impl FnMut(f64) -> Option<f64>) -> f64 {
    if g0 <= 0.0 {
        return 0.0;
    }
    if rate == 0.0 {
        return 1.0;
    }
    let gmin = (1.0 - close) * g0;
    let (mut s, mut g) = (0.0f64, g0);
    for _ in 0..max_iterations {
        let ds = (g - gmin) / rate;
        if s + ds >= 1.0 {
            return 1.0;
        }
        s += ds;
        if ds < MIN_ADVANCE {
            break;
        }
        match gap_at(s) {
            Some(next) => g = next,
            None => return 1.0,
        }
        if g <= gmin * 1.000_001 {
            break;
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A point approaching a plane head-on at unit speed from gap 1 over a motion of length
    /// 2: the gap g(s) = 1 − 2s is exactly Lipschitz with ℓ = 2, so advancement reaches
    /// g = 0.1 (90 % closed) at s = 0.45 from below.
    #[test]
    fn head_on_approach_stops_at_the_closing_fraction() {
        let s = conservative_advancement(1.0, 2.0, 0.9, 100, |s| Some(1.0 - 2.0 * s));
        assert!(s <= 0.45 && s > 0.45 - 1e-5, "{s}");
    }

    /// A grazing motion that never closes the gap below its bound is free; so is one out of
    /// reach, and one that does not move.
    #[test]
    fn free_motions_reach_one() {
        assert_eq!(conservative_advancement(1.0, 2.0, 0.9, 100, |_| Some(1.0)), 1.0);
        assert_eq!(conservative_advancement(1.0, 2.0, 0.9, 100, |_| None), 1.0);
        assert_eq!(conservative_advancement(1.0, 0.0, 0.9, 100, |_| Some(0.0)), 1.0);
        assert_eq!(conservative_advancement(-1e-9, 1.0, 0.9, 100, |_| Some(1.0)), 0.0);
    }
}
