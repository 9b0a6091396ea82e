//! Infrastructure: a two-way fork-join for the step's passes over large cloths, on one helper
//! thread that spins between jobs, and the fixed split of a pass into halves. The force terms
//! (`effects`), the integrators and the implicit solve's products and multigrid sweeps
//! (`integrate`) all split their passes here.
//!
//! Why not `rayon::join`: called from outside the pool (the simulation's own thread), each join
//! hands the work to a pool thread and puts the caller to sleep until it is done; from inside
//! the pool, a join whose other worker went to sleep wakes it (a PCG iteration forks a dozen
//! times: at 64x64 rayon's two threads solve no faster than one). On a 2-vCPU virtual machine
//! a sleeping thread's wake-up costs microseconds when the other vCPU is busy and tens of
//! microseconds when it idles (the hypervisor must wake a halted vCPU); an explicit substep
//! joins twice, so on an idle machine the wake-ups cost more than the work. Here the caller runs
//! the first half itself and only waits, spinning, for a second half already running: if the
//! helper has not picked it up by the time the first half is done (asleep, or preempted by
//! other processes) the caller takes it back and runs it too. The helper spins for
//! [`SPIN`] after each job, so back-to-back substeps never sleep, then parks.
//!
//! Which thread runs which half never changes a result: the halves are fixed by the data size.

use std::cell::UnsafeCell;
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use std::sync::OnceLock;
use std::thread::Thread;
use std::time::{Duration, Instant};

/// Vertex count from which the energy-and-force pass and the explicit update are split in two
/// halves run on two threads (below it, waking a thread costs about as much as the pass). The
/// split depends on the size only, so results do not depend on the number of threads.
pub(crate) const PAR_VERTICES: usize = 2048;

/// The index range of the `part`-th of `parts` near-equal slices of `len` elements.
pub(crate) fn part_range(len: usize, part: usize, parts: usize) -> std::ops::Range<usize> {
    len * part / parts..len * (part + 1) / parts
}

/// How long the helper spins for the next job before parking.
const SPIN: Duration = Duration::from_micros(50);

// Job slot states.
const EMPTY: u8 = 0;
/// A caller is writing the job pointer.
const WRITING: u8 = 1;
const POSTED: u8 = 2;
/// The helper runs the job.
const TAKEN: u8 = 3;
const DONE: u8 = 4;

/// A posted job: a type-erased `FnMut()` on the posting caller's stack. The caller does not
/// return before the job is done or taken back, which keeps the pointer valid while used.
#[derive(Clone, Copy)]
struct JobPtr(*mut (dyn FnMut() + Send));

// SAFETY: the pointee is `Send` and is used by one thread at a time (the slot's state says which).
unsafe impl Send for JobPtr {}

struct Helper {
    state: AtomicU8,
    job: UnsafeCell<Option<JobPtr>>,
    /// Set when the job panicked on the helper (the caller re-raises it).
    panicked: AtomicBool,
    /// The helper is parked (or about to): posting must unpark it.
    sleeping: AtomicBool,
    thread: OnceLock<Thread>,
}

// SAFETY: `job` is written only by the caller that moved `state` from EMPTY to WRITING and read
// only by whoever moved it from POSTED (helper: to TAKEN; caller: back to EMPTY).
unsafe impl Sync for Helper {}

static HELPER: OnceLock<Option<&'static Helper>> = OnceLock::new();

/// The helper, started on first use; `None` if the thread could not be spawned (everything then
/// runs on the caller).
fn helper() -> Option<&'static Helper> {
    *HELPER.get_or_init(|| {
        let h: &'static Helper = Box::leak(Box::new(Helper {
            state: AtomicU8::new(EMPTY),
            job: UnsafeCell::new(None),
            panicked: AtomicBool::new(false),
            sleeping: AtomicBool::new(false),
            thread: OnceLock::new(),
        }));
        let t = std::thread::Builder::new()
            .name("drape-pair".into())
            .spawn(move || run(h))
            .ok()?;
        let _ = h.thread.set(t.thread().clone());
        Some(h)
    })
}

/// The helper's loop: take posted jobs, spin [`SPIN`] after each, then park.
fn run(h: &'static Helper) {
    let mut idle_since = Instant::now();
    let mut polls = 0u32;
    loop {
        if h.state.load(Ordering::Acquire) == POSTED
            && h.state
                .compare_exchange(POSTED, TAKEN, Ordering::Acquire, Ordering::Relaxed)
                .is_ok()
        {
            // SAFETY: we moved the slot to TAKEN, so the job is ours until we store DONE.
            if let Some(JobPtr(job)) = unsafe { *h.job.get() } {
                // SAFETY: the poster keeps the closure alive until it sees DONE.
                let r = catch_unwind(AssertUnwindSafe(|| unsafe { (*job)() }));
                h.panicked.store(r.is_err(), Ordering::Relaxed);
            }
            h.state.store(DONE, Ordering::Release);
            idle_since = Instant::now();
            polls = 0;
            continue;
        }
        polls = polls.wrapping_add(1);
        if !polls.is_multiple_of(64) || idle_since.elapsed() < SPIN {
            pause(polls);
            continue;
        }
        h.sleeping.store(true, Ordering::SeqCst);
        if h.state.load(Ordering::SeqCst) != POSTED {
            std::thread::park();
        }
        h.sleeping.store(false, Ordering::SeqCst);
        idle_since = Instant::now();
        polls = 0;
    }
}

/// One wait of a polling loop: a CPU pause for the first polls (an answer is due within
/// microseconds), then a yield per poll, so that a poller sharing its core with the thread it
/// waits for (or with other processes, on a loaded machine) does not eat that thread's time.
#[inline]
fn pause(polls: u32) {
    if polls < 128 {
        std::hint::spin_loop();
    } else {
        std::thread::yield_now();
    }
}

/// Runs `a` and `b`, `b` possibly on the helper thread; returns both results. Falls back to
/// running both on the caller when the helper is busy with another caller's job.
pub(crate) fn join<RA, RB>(a: impl FnOnce() -> RA, b: impl FnOnce() -> RB + Send) -> (RA, RB)
where
    RB: Send,
{
    let Some(h) = helper() else {
        return (a(), b());
    };
    if h.state
        .compare_exchange(EMPTY, WRITING, Ordering::Acquire, Ordering::Relaxed)
        .is_err()
    {
        return (a(), b());
    }
    let mut b = Some(b);
    let mut rb = None;
    let mut job = || {
        if let Some(b) = b.take() {
            rb = Some(b());
        }
    };
    let ptr: *mut (dyn FnMut() + Send + '_) = &mut job;
    // SAFETY: only the lifetime is erased; this function does not return (nor unwind) before the
    // job is DONE or taken back, so the helper never uses the pointer after `job` is dropped.
    let ptr: *mut (dyn FnMut() + Send + 'static) = unsafe { std::mem::transmute(ptr) };
    // SAFETY: we hold the slot (WRITING).
    unsafe { *h.job.get() = Some(JobPtr(ptr)) };
    h.state.store(POSTED, Ordering::SeqCst);
    if h.sleeping.load(Ordering::SeqCst) {
        if let Some(t) = h.thread.get() {
            t.unpark();
        }
    }
    // `a` may panic: the job must be settled first, so catch and re-raise.
    let ra = catch_unwind(AssertUnwindSafe(a));
    if h.state
        .compare_exchange(POSTED, WRITING, Ordering::Acquire, Ordering::Relaxed)
        .is_ok()
    {
        // Not picked up: take it back and run it here.
        // SAFETY: we hold the slot again (WRITING).
        unsafe { *h.job.get() = None };
        h.state.store(EMPTY, Ordering::Release);
        job();
    } else {
        let mut spins = 0u32;
        while h.state.load(Ordering::Acquire) != DONE {
            spins = spins.wrapping_add(1);
            pause(spins);
        }
        let panicked = h.panicked.load(Ordering::Relaxed);
        // SAFETY: DONE: the helper no longer touches the slot.
        unsafe { *h.job.get() = None };
        h.state.store(EMPTY, Ordering::Release);
        if panicked {
            resume_unwind(Box::new("a job on the drape-pair helper thread panicked"));
        }
    }
    let ra = match ra {
        Ok(r) => r,
        Err(p) => resume_unwind(p),
    };
    match rb {
        Some(r) => (ra, r),
        None => unreachable!("the second half ran (on the helper or here)"),
    }
}

/// Slices (and tuples of slices) cut at an index: what [`sum_in_halves`] hands each half.
pub(crate) trait Halve: Sized {
    fn halve(self, mid: usize) -> (Self, Self);
}

impl<T> Halve for &[T] {
    fn halve(self, mid: usize) -> (Self, Self) {
        self.split_at(mid)
    }
}

impl<T> Halve for &mut [T] {
    fn halve(self, mid: usize) -> (Self, Self) {
        self.split_at_mut(mid)
    }
}

impl<A: Halve, B: Halve> Halve for (A, B) {
    fn halve(self, mid: usize) -> (Self, Self) {
        let ((a0, a1), (b0, b1)) = (self.0.halve(mid), self.1.halve(mid));
        ((a0, b0), (a1, b1))
    }
}

impl<A: Halve, B: Halve, C: Halve> Halve for (A, B, C) {
    fn halve(self, mid: usize) -> (Self, Self) {
        let ((a0, a1), (b0, b1)) = (self.0.halve(mid), (self.1, self.2).halve(mid));
        ((a0, b0.0, b0.1), (a1, b1.0, b1.1))
    }
}

impl<A: Halve, B: Halve, C: Halve, D: Halve> Halve for (A, B, C, D) {
    fn halve(self, mid: usize) -> (Self, Self) {
        let ((a0, a1), (b0, b1)) = ((self.0, self.1).halve(mid), (self.2, self.3).halve(mid));
        ((a0.0, a0.1, b0.0, b0.1), (a1.0, a1.1, b1.0, b1.1))
    }
}

/// `pass` over `data`, `n` elements long: in two halves on two threads from `from` elements on,
/// one pass below (element-wise passes, whose results do not depend on the cut).
pub(crate) fn in_halves<D: Halve + Send>(n: usize, from: usize, data: D, pass: impl Fn(D) + Sync) {
    if n < from {
        return pass(data);
    }
    let (a, b) = data.halve(n / 2);
    join(|| pass(a), || pass(b));
}

/// `pass` over `data`, `n` rows long: in two halves on two threads from [`PAR_VERTICES`] rows
/// on, one pass below; returns the halves' results added (the first half's plus the second's),
/// so a sum depends on `n` only, never on which thread ran what.
pub(crate) fn sum_in_halves<D: Halve + Send>(
    n: usize,
    data: D,
    pass: impl Fn(D) -> f64 + Sync,
) -> f64 {
    if n < PAR_VERTICES {
        return pass(data);
    }
    let (a, b) = data.halve(n / 2);
    let (x, y) = join(|| pass(a), || pass(b));
    x + y
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both halves run exactly once and see their own data, also from several callers at once
    /// (one gets the helper, the others run both halves themselves).
    #[test]
    fn both_halves_run_once_from_concurrent_callers() {
        std::thread::scope(|s| {
            for t in 0..4u64 {
                s.spawn(move || {
                    for i in 0..2000u64 {
                        let mut left = vec![0u64; 64];
                        let mut right = vec![0u64; 64];
                        let (x, y) = join(
                            || {
                                left.iter_mut().for_each(|v| *v += i + t);
                                left.iter().sum::<u64>()
                            },
                            || {
                                right.iter_mut().for_each(|v| *v += 2 * i + t);
                                right.iter().sum::<u64>()
                            },
                        );
                        assert_eq!(x, 64 * (i + t));
                        assert_eq!(y, 64 * (2 * i + t));
                        assert!(left.iter().all(|&v| v == i + t));
                        assert!(right.iter().all(|&v| v == 2 * i + t));
                    }
                });
            }
        });
    }

    /// A pass in halves sees every row once, each half its own rows of every slice in the
    /// tuple, and its sum is the first half's plus the second's (exactly, for integers).
    #[test]
    fn a_pass_in_halves_covers_every_row_once() {
        for n in [PAR_VERTICES - 1, PAR_VERTICES + 3] {
            let mut out = vec![0.0f64; n];
            let a: Vec<f64> = (0..n).map(|i| i as f64).collect();
            let (b, c) = (vec![1.0f64; n], vec![2.0f64; n]);
            let sum = sum_in_halves(n, (&mut out[..], &a[..], &b[..], &c[..]), |(o, a, b, c)| {
                let mut s = 0.0;
                for (((o, a), b), c) in o.iter_mut().zip(a).zip(b).zip(c) {
                    *o += a + b * c;
                    s += a;
                }
                s
            });
            assert_eq!(sum, (n * (n - 1) / 2) as f64);
            assert!(out.iter().enumerate().all(|(i, &o)| o == i as f64 + 2.0));
        }
    }

    /// A panic in either half reaches the caller, and the helper keeps working afterwards.
    #[test]
    fn a_panicking_half_is_reraised_and_the_helper_survives() {
        for left in [true, false] {
            let r = catch_unwind(|| {
                join(
                    || {
                        if left {
                            panic!("left")
                        }
                    },
                    || {
                        if !left {
                            panic!("right")
                        }
                    },
                )
            });
            assert!(r.is_err());
        }
        assert_eq!(join(|| 1, || 2), (1, 2));
    }
}
