//! Earliest time a Lipschitz distance function drops to a threshold, without false negatives.
//!
//! For linearly moving primitives, `d(t)` (the static distance at time `t`) is Lipschitz with
//! constant `L = max |v_i - v_j|` over vertex pairs of the two primitives (the closest points are
//! convex combinations of vertices). Knowing `d(a)` and `d(b)`, no time in `[a, b]` outside
//! `[a + (d(a) - eta)/L, b - (d(b) - eta)/L]` can have `d <= eta`, so both ends are advanced
//! (conservative advancement); when that stalls the interval is bisected, earliest half first.
//! Exhausting the evaluation budget reports a hit at the earliest unresolved time:
//! a possible false positive, never a false negative.

/// Time resolution: a hit is reported at most this much earlier than the true first contact.
pub const TIME_TOL: f64 = 1e-10;
/// Distance evaluations allowed before giving up conservatively.
pub const MAX_EVALS: usize = 1024;
const STACK: usize = 64;

/// Earliest `t` in `[0, 1]` with `dist(t) <= eta`, assuming `dist` is `lip`-Lipschitz on `[0, 1]`.
///
/// Any time with `dist(t) <= accept` (`accept >= eta`) met on the way is reported as a hit: the
/// advancement converges to the first `dist = eta` crossing from above only geometrically, and
/// the gap `accept - eta` lets it stop after a few steps instead of bisecting to `TIME_TOL`.
pub fn earliest_within(dist: impl Fn(f64) -> f64, lip: f64, eta: f64, accept: f64) -> Option<f64> {
    let accept = accept.max(eta);
    let d0 = dist(0.0);
    if d0 <= accept {
        return Some(0.0);
    }
    if lip <= 0.0 || !lip.is_finite() {
        // No relative motion: the distance is constant.
        return None;
    }
    let d1 = dist(1.0);
    let mut evals = 2;
    let mut stack = [(0.0, 0.0, 0.0, 0.0); STACK];
    stack[0] = (0.0, d0, 1.0, d1);
    let mut depth = 1;
    while depth > 0 {
        depth -= 1;
        let (mut a, mut da, mut b, mut db) = stack[depth];
        loop {
            if da <= accept {
                return Some(a);
            }
            let a2 = a + (da - eta) / lip;
            let b2 = if db > eta { b - (db - eta) / lip } else { b };
            if a2 > b2 {
                break; // d > eta on all of [a, b]
            }
            if b2 - a2 <= TIME_TOL || evals >= MAX_EVALS {
                return Some(a2);
            }
            let da2 = dist(a2);
            let db2 = if b2 < b { dist(b2) } else { db };
            evals += 2;
            if da2 <= accept {
                return Some(a2);
            }
            if b2 - a2 > 0.5 * (b - a) {
                // Advancement stalls (several near contacts, or d hovers near eta): bisect.
                if depth >= STACK {
                    return Some(a2);
                }
                let m = 0.5 * (a2 + b2);
                let dm = dist(m);
                evals += 1;
                stack[depth] = (m, dm, b2, db2);
                depth += 1;
                (a, da, b, db) = (a2, da2, m, dm);
            } else {
                (a, da, b, db) = (a2, da2, b2, db2);
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_first_of_two_dips() {
        // |t - 0.3| and |t - 0.8| dips: Lipschitz 1.
        let d = |t: f64| (t - 0.3).abs().min((t - 0.8).abs() + 0.05);
        let t = earliest_within(d, 1.0, 0.01, 0.01).unwrap();
        assert!((t - 0.29).abs() <= TIME_TOL * 2.0, "{t}");
        // Only the second dip reaches the threshold.
        let d = |t: f64| ((t - 0.3).abs() + 0.1).min((t - 0.8).abs());
        let t = earliest_within(d, 1.0, 0.01, 0.01).unwrap();
        assert!((t - 0.79).abs() <= TIME_TOL * 2.0, "{t}");
    }

    #[test]
    fn misses_and_endpoints() {
        assert_eq!(earliest_within(|t| 1.0 + t, 1.0, 0.5, 0.5), None);
        assert_eq!(earliest_within(|_| 0.2, 0.0, 0.5, 0.5), Some(0.0));
        let t = earliest_within(|t| 1.0 - t, 1.0, 0.0, 0.0).unwrap();
        assert!((1.0 - 2.0 * TIME_TOL..=1.0).contains(&t), "{t}");
        // Grazing from above: minimum exactly eta at t = 0.5.
        let t = earliest_within(|t| 0.1 + (t - 0.5).abs(), 1.0, 0.1, 0.1).unwrap();
        assert!((t - 0.5).abs() <= 2.0 * TIME_TOL, "{t}");
        // A slow approach (rate 0.1 against a bound of 1) stops once within `accept`.
        let t = earliest_within(|t| 1.0 - 0.1 * t, 1.0, 0.95, 0.95 + 1e-9).unwrap();
        assert!(t <= 0.5 && 1.0 - 0.1 * t <= 0.95 + 1e-9, "{t}");
    }
}
