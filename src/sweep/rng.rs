//! A small, stable random number generator for sweep draws: SplitMix64 (Steele, Lea, Flood
//! 2014). Stable across versions and platforms, so a sweep file and its seed always give the same
//! jobs; a job's stream depends only on the seed and the job index.

/// SplitMix64 state.
#[derive(Debug, Clone)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// The stream of job `index` of a sweep with `seed`.
    pub fn for_job(seed: u64, index: usize) -> Self {
        let mut s = SplitMix64(seed ^ 0x6a09_e667_f3bc_c909);
        let base = s.next_u64();
        SplitMix64(base ^ (index as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15))
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1) with 53 random bits.
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform integer in `0..n` (`n > 0`), by multiply-shift (bias below 2^-64 * n).
    pub fn below(&mut self, n: u64) -> u64 {
        ((u128::from(self.next_u64()) * u128::from(n)) >> 64) as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_stable_and_distinct() {
        let mut r0 = SplitMix64::for_job(7, 0);
        let mut r0b = SplitMix64::for_job(7, 0);
        let mut r1 = SplitMix64::for_job(7, 1);
        let x = r0.next_u64();
        assert_eq!(x, r0b.next_u64());
        assert_ne!(x, r1.next_u64());
        let mut r = SplitMix64::for_job(1, 2);
        for _ in 0..1000 {
            let f = r.next_f64();
            assert!((0.0..1.0).contains(&f));
            assert!(r.below(3) < 3);
        }
    }
}
