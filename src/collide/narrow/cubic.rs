//! Robust roots of the CCD coplanarity cubic on `[0, 1]`.
//!
//! The closed form loses roots near double roots and when the leading coefficients vanish,
//! so instead: split `[0, 1]` at the roots of the derivative (a quadratic, itself degrading to a
//! linear or constant), which leaves pieces on which the cubic is monotone; each piece holds at
//! most one root, found by bracketed Newton with bisection fallback. Points where `|f| <= ftol`
//! (endpoints, extrema grazing zero) are reported too, so touching contacts are not lost.

/// Coefficients `[c0, c1, c2, c3]` of `c0 + c1 t + c2 t^2 + c3 t^3`.
pub type Cubic = [f64; 4];

/// At most: 3 monotone pieces with one root each, plus 4 split points.
pub const MAX_CANDIDATES: usize = 8;

#[inline]
pub fn eval(c: &Cubic, t: f64) -> f64 {
    ((c[3] * t + c[2]) * t + c[1]) * t + c[0]
}

#[inline]
fn eval_deriv(c: &Cubic, t: f64) -> f64 {
    (3.0 * c[3] * t + 2.0 * c[2]) * t + c[1]
}

/// Roots of `a t^2 + b t + c` strictly inside `(0, 1)`, ascending. Degrades to linear/constant.
fn quadratic_roots_open01(a: f64, b: f64, c: f64) -> ([f64; 2], usize) {
    let mut out = [0.0; 2];
    let mut n = 0;
    let mut push = |r: f64| {
        if r > 0.0 && r < 1.0 && r.is_finite() {
            out[n] = r;
            n += 1;
        }
    };
    if a == 0.0 {
        if b != 0.0 {
            push(-c / b);
        }
    } else {
        let disc = b * b - 4.0 * a * c;
        if disc >= 0.0 {
            // Citardauq form: no cancellation, and a tiny `a` gives one huge root (discarded).
            let q = -0.5 * (b + b.signum() * disc.sqrt());
            if q == 0.0 {
                push(0.0);
            } else {
                let (r1, r2) = (q / a, c / q);
                let (lo, hi) = if r1 <= r2 { (r1, r2) } else { (r2, r1) };
                push(lo);
                if hi != lo {
                    push(hi);
                }
            }
        } else if disc > -1e-14 * b * b.max(4.0 * a * c) {
            // Numerically a double root: still a split point.
            push(-b / (2.0 * a));
        }
    }
    (out, n)
}

/// Bracketed Newton on `[lo, hi]` where `f(lo)` and `f(hi)` have opposite signs.
fn refine_root(c: &Cubic, mut lo: f64, mut hi: f64, f_lo: f64) -> f64 {
    let lo_neg = f_lo < 0.0;
    let mut t = 0.5 * (lo + hi);
    for _ in 0..64 {
        let f = eval(c, t);
        if f == 0.0 {
            return t;
        }
        if (f < 0.0) == lo_neg {
            lo = t;
        } else {
            hi = t;
        }
        let d = eval_deriv(c, t);
        let newton = t - f / d;
        t = if newton > lo && newton < hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
        if hi - lo <= 4.0 * f64::EPSILON * hi.abs().max(1e-300) {
            break;
        }
    }
    t
}

/// Candidate times in `[0, 1]`, ascending: every sign change of `c` and every split point
/// (0, 1, interior extrema) where `|c| <= ftol`. Returns the buffer and its length.
pub fn candidate_times(c: &Cubic, ftol: f64) -> ([f64; MAX_CANDIDATES], usize) {
    let (crit, ncrit) = quadratic_roots_open01(3.0 * c[3], 2.0 * c[2], c[1]);
    let mut splits = [0.0; 4];
    splits[1..=ncrit].copy_from_slice(&crit[..ncrit]);
    splits[ncrit + 1] = 1.0;
    let nsplit = ncrit + 2;

    let mut out = [0.0; MAX_CANDIDATES];
    let mut n = 0;
    let mut push = |t: f64| {
        if n == 0 || out[n - 1] < t {
            out[n] = t;
            n += 1;
        }
    };
    let mut f_l = eval(c, splits[0]);
    for w in splits[..nsplit].windows(2) {
        let (l, r) = (w[0], w[1]);
        let f_r = eval(c, r);
        if f_l.abs() <= ftol {
            push(l);
        }
        if f_r.abs() > ftol && f_l != 0.0 && (f_l < 0.0) != (f_r < 0.0) {
            push(refine_root(c, l, r, f_l));
        }
        f_l = f_r;
    }
    if f_l.abs() <= ftol {
        push(1.0);
    }
    (out, n)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn roots(c: Cubic, ftol: f64) -> Vec<f64> {
        let (buf, n) = candidate_times(&c, ftol);
        buf[..n].to_vec()
    }

    /// Coefficients of k (t - r1)(t - r2)(t - r3).
    fn from_roots(k: f64, r: [f64; 3]) -> Cubic {
        let s1 = r[0] + r[1] + r[2];
        let s2 = r[0] * r[1] + r[0] * r[2] + r[1] * r[2];
        let s3 = r[0] * r[1] * r[2];
        [-k * s3, k * s2, -k * s1, k]
    }

    #[test]
    fn three_close_roots() {
        let r = roots(from_roots(1.0, [0.1, 0.1001, 0.9]), 0.0);
        assert_eq!(r.len(), 3, "{r:?}");
        for (got, want) in r.iter().zip([0.1, 0.1001, 0.9]) {
            assert!((got - want).abs() < 1e-12, "{got} vs {want}");
        }
    }

    #[test]
    fn degenerate_orders() {
        // Quadratic (c3 = 0): (t - 0.25)(t - 0.75).
        let r = roots([0.1875, -1.0, 1.0, 0.0], 0.0);
        assert!(r.len() == 2 && (r[0] - 0.25).abs() < 1e-15 && (r[1] - 0.75).abs() < 1e-15);
        // Linear.
        let r = roots([-0.3, 1.0, 0.0, 0.0], 0.0);
        assert!(r.len() == 1 && (r[0] - 0.3).abs() < 1e-15);
        // Constant non-zero: nothing; constant zero: endpoints.
        assert!(roots([1.0, 0.0, 0.0, 0.0], 1e-12).is_empty());
        assert_eq!(roots([0.0; 4], 1e-12), vec![0.0, 1.0]);
        // Tiny leading coefficient next to a well-scaled linear part.
        let r = roots([-0.5, 1.0, 0.0, 1e-300], 0.0);
        assert!(r.len() == 1 && (r[0] - 0.5).abs() < 1e-15);
    }

    #[test]
    fn endpoints_and_grazing_double_root() {
        assert_eq!(roots(from_roots(1.0, [0.0, 2.0, 3.0]), 1e-15)[0], 0.0);
        assert_eq!(
            *roots(from_roots(1.0, [1.0, 2.0, 3.0]), 1e-15)
                .last()
                .unwrap(),
            1.0
        );
        // (t - 0.5)^2 (t + 1): touches zero without a sign change.
        let r = roots(from_roots(1.0, [0.5, 0.5, -1.0]), 1e-14);
        assert_eq!(r.len(), 1);
        assert!((r[0] - 0.5).abs() < 1e-7, "{r:?}");
    }

    #[test]
    fn random_cubics_find_every_sampled_sign_change() {
        let mut s: u64 = 99;
        let mut rnd = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for _ in 0..2000 {
            let c = [rnd(), rnd() * 4.0, rnd() * 8.0, rnd() * 8.0];
            let r = roots(c, 0.0);
            for w in r.windows(2) {
                assert!(w[0] < w[1]);
            }
            for &t in &r {
                assert!(eval(&c, t).abs() < 1e-12, "not a root: {t}");
            }
            let n = 1000;
            let mut prev = eval(&c, 0.0);
            for i in 1..=n {
                let t = i as f64 / n as f64;
                let f = eval(&c, t);
                if (prev < 0.0) != (f < 0.0) {
                    let t0 = (i - 1) as f64 / n as f64;
                    assert!(
                        r.iter().any(|&x| x >= t0 - 1e-12 && x <= t + 1e-12),
                        "{c:?} missed root in [{t0}, {t}]: {r:?}"
                    );
                }
                prev = f;
            }
        }
    }
}
