//! Which vertices changed since a pass detected on a state: a pair none of whose vertices
//! changed gets the same answer from the next pass, so the next pass skips it.
//!
//! That is exact (the positions a pass ends in are the same with or without the skip, bit for
//! bit, since the pairs a pass answered are answered again): a repulsion pass answers a pair
//! from its positions and velocities alone, and a CCD pass a pair from its start and end
//! positions, which within one step share the start. It is what keeps
//! the Jacobi repulsion's later passes and the CCD passes after an obstacle re-test at the cost
//! of what moved, not of the cloth (without it, on a crumpling sheet every repulsion pass
//! re-answers every one of its many candidates).

use crate::Vec3;

/// The state a pass detected on, and per vertex whether the current state differs from it.
#[derive(Default)]
pub(super) struct Changed {
    x: Vec<Vec3>,
    v: Vec<Vec3>,
    /// Whether `x` (and `v`) hold a state the next pass may compare with.
    valid: bool,
    flags: Vec<bool>,
}

impl Changed {
    /// Forgets the recorded state: the next pass answers every pair.
    pub fn forget(&mut self) {
        self.valid = false;
    }

    /// Compares `x` (and `v`) with the recorded state and records them for the pass after.
    /// Returns None when nothing was recorded (every pair is to be answered), else whether any
    /// vertex changed ([`Changed::flags`] tells which).
    pub fn update(&mut self, x: &[Vec3], v: Option<&[Vec3]>) -> Option<bool> {
        let n = x.len();
        let had = self.valid && self.x.len() == n && v.is_none_or(|v| self.v.len() == v.len());
        let mut any = false;
        if had {
            self.flags.clear();
            // Bitwise inequality: a NaN counts as changed.
            self.flags.extend((0..n).map(|i| {
                let moved = x[i] != self.x[i] || v.is_some_and(|v| v[i] != self.v[i]);
                any |= moved;
                moved
            }));
        }
        self.x.clear();
        self.x.extend_from_slice(x);
        self.v.clear();
        if let Some(v) = v {
            self.v.extend_from_slice(v);
        }
        self.valid = true;
        had.then_some(any)
    }

    /// Per vertex: changed since the state before the last [`Changed::update`].
    pub fn flags(&self) -> &[bool] {
        &self.flags
    }

    /// Counts `idx` as changed at the next [`Changed::update`]: the vertices of the pairs a pass
    /// answered are answered again (whether or not the answer moved them), so the passes do
    /// exactly what they did without the skip.
    pub fn answer_again(&mut self, idx: &[u32]) {
        for &i in idx {
            if let Some(x) = self.x.get_mut(i as usize) {
                *x = Vec3::NAN;
            }
        }
    }
}

/// Whether any of `idx` changed (an index past `flags` counts as changed).
pub(super) fn any_of(flags: &[bool], idx: &[u32]) -> bool {
    idx.iter()
        .any(|&i| flags.get(i as usize).copied().unwrap_or(true))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_what_changed_since_the_recorded_state() {
        let mut c = Changed::default();
        let mut x = vec![Vec3::ZERO; 4];
        assert_eq!(c.update(&x, None), None, "nothing recorded yet");
        assert_eq!(c.update(&x, None), Some(false));
        x[2].z = 1e-300;
        x[3] = Vec3::NAN;
        assert_eq!(c.update(&x, None), Some(true));
        assert_eq!(c.flags(), &[false, false, true, true]);
        assert!(any_of(c.flags(), &[0, 2]) && !any_of(c.flags(), &[0, 1]));
        assert!(any_of(c.flags(), &[9]), "out of range counts as changed");
        // NaN != NaN: a non-finite vertex is never taken as settled.
        assert_eq!(c.update(&x, None), Some(true));
        x[3] = Vec3::ZERO;
        c.update(&x, None);
        c.answer_again(&[1]);
        assert_eq!(c.update(&x, None), Some(true));
        assert_eq!(c.flags(), &[false, true, false, false]);
        c.forget();
        assert_eq!(c.update(&x, None), None);
    }

    #[test]
    fn velocities_count_when_given() {
        let mut c = Changed::default();
        let x = vec![Vec3::ZERO; 2];
        let mut v = vec![Vec3::ZERO; 2];
        c.update(&x, Some(&v));
        v[1].x = 1.0;
        assert_eq!(c.update(&x, Some(&v)), Some(true));
        assert_eq!(c.flags(), &[false, true]);
    }
}
