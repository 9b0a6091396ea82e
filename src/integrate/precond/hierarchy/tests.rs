//! Unit tests of `hierarchy.rs`, in their own file so that the test helpers they use
//! (which use `hierarchy.rs` themselves) do not make an import cycle with it.

use super::*;
use crate::integrate::cg::Pcg;
use crate::integrate::test_systems::*;
use crate::linalg::{BlockCsr, Filter, PatternBuilder};
use crate::{Mat3, Vec3};

/// `a` with every block `(i, j)` replaced by `f(i, j, block)`, same pattern.
fn mapped(a: &BlockCsr, f: impl Fn(usize, u32, Mat3) -> Mat3) -> BlockCsr {
    let n = a.rows();
    let mut p = PatternBuilder::new();
    for i in 0..n {
        for &j in a.row(i).0 {
            p.couple(i as u32, j);
        }
    }
    let mut out = p.build(n);
    for i in 0..n {
        let (cols, vals) = a.row(i);
        for (&j, m) in cols.iter().zip(vals) {
            out.add(i as u32, j, f(i, j, *m));
        }
    }
    out
}

/// Asserts that two hierarchies' V-cycles give the same output, bit for bit, on a random
/// vector drawn from `seed`.
fn assert_same_cycle(a: &mut Multigrid, b: &mut Multigrid, seed: u64, what: &str) {
    let n = a.rows();
    let mut rng = Rng(seed);
    let u: Vec<Vec3> = (0..n).map(|_| rng.vec3()).collect();
    let (mut za, mut zb) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
    a.apply(&u, &mut za);
    b.apply(&u, &mut zb);
    assert_eq!(za, zb, "{what}");
}

/// A rebuild along the kept aggregates reproduces a full build of the same matrix exactly
/// (same aggregates and damping, so the same numbers); rebuilt for a rotated cloth
/// (`R A R^T` blockwise) it preconditions as well as a fresh build (iterations within one),
/// while the stale hierarchy of the unrotated cloth takes several times as many.
#[test]
fn rebuild_along_kept_aggregates_follows_a_rotation() {
    let a = cloth_system(32);
    let n = a.rows();
    let filt = vec![Filter::Free; n];
    let mut fine = Csr::default();
    fine.filtered(&a, &filt);
    let mut full = Multigrid::build(fine.clone()).expect("hierarchy");
    let mut kept = Multigrid::build(fine.clone()).expect("hierarchy");
    kept.rebuild(fine).expect("rebuild");
    let mut rng = Rng(17);
    let u: Vec<Vec3> = (0..n).map(|_| rng.vec3()).collect();
    let (mut zf, mut zk) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
    full.apply(&u, &mut zf);
    kept.apply(&u, &mut zk);
    assert_eq!(zf, zk);
    // Rotate every block by 60 degrees about x: the springs point elsewhere.
    let r = Mat3::from_rotation_x(std::f64::consts::FRAC_PI_3);
    let rotated = mapped(&a, |_, _, m| r * m * r.transpose());
    let mut fine = Csr::default();
    fine.filtered(&rotated, &filt);
    let b: Vec<Vec3> = (0..n).map(|_| rng.vec3()).collect();
    let z = vec![Vec3::ZERO; n];
    let iterations = |mg: &mut Multigrid| {
        let mut dv = vec![Vec3::ZERO; n];
        Pcg::default()
            .solve(&rotated, &filt, &b, &z, Some(mg), 1e-8, 1000, &mut dv, None)
            .iterations
    };
    let mut fresh = Multigrid::build(fine.clone()).expect("hierarchy");
    kept.refresh_finest(fine.clone()).expect("refresh");
    let stale_its = iterations(&mut kept);
    kept.rebuild(fine).expect("rebuild");
    let (kept_its, fresh_its) = (iterations(&mut kept), iterations(&mut fresh));
    assert!(kept_its <= fresh_its + 1, "{kept_its} vs fresh {fresh_its}");
    assert!(
        stale_its > fresh_its + 1,
        "stale {stale_its} vs fresh {fresh_its}"
    );
}

/// Rows whose diagonal dominates all their couplings (vertices held by a sticking friction
/// drag, `mu N / STICK_SPEED` per m/s on the diagonal) have no strong connection: they are in no
/// aggregate, so the coarse levels are those of the rest of the cloth (smaller than without the
/// drags, where singleton aggregates would fill the first coarse level with them), and the
/// preconditioned solve converges at least as fast as without the drags.
#[test]
fn rows_without_strong_connections_stay_out_of_the_coarse_levels() {
    let a = cloth_system(32);
    let n = a.rows();
    // The first half of the rows held by a drag 1e4 times their diagonal.
    let stuck = mapped(&a, |i, j, m| {
        if j as usize == i && i < n / 2 {
            m + m * 1e4
        } else {
            m
        }
    });
    let filt = vec![Filter::Free; n];
    let build = |m: &BlockCsr| {
        let mut fine = Csr::default();
        fine.filtered(m, &filt);
        Multigrid::build(fine).expect("hierarchy")
    };
    let (mut plain, mut held) = (build(&a), build(&stuck));
    let (sizes, held_sizes) = (plain.level_sizes(), held.level_sizes());
    assert!(
        held_sizes[1] * 10 <= sizes[1] * 6,
        "first coarse level {} rows with half the cloth held, {} without",
        held_sizes[1],
        sizes[1]
    );
    let mut rng = Rng(5);
    let b: Vec<Vec3> = (0..n).map(|_| rng.vec3()).collect();
    let z = vec![Vec3::ZERO; n];
    let iterations = |m: &BlockCsr, mg: &mut Multigrid| {
        let mut dv = vec![Vec3::ZERO; n];
        Pcg::default()
            .solve(m, &filt, &b, &z, Some(mg), 1e-8, 1000, &mut dv, None)
            .iterations
    };
    let (its, held_its) = (iterations(&a, &mut plain), iterations(&stuck, &mut held));
    assert!(held_its <= its, "{held_its} iterations held, {its} without");
}

#[test]
fn degenerate_matrix_falls_back_to_block_jacobi() {
    // A zero diagonal block (massless, unconnected vertex) makes the hierarchy fail...
    let mut a = cloth_system(6);
    let mut p = PatternBuilder::new();
    p.couple(0, 1);
    let mut bad = p.build(2);
    bad.add(0, 0, Mat3::IDENTITY);
    let mut fine = Csr::default();
    fine.filtered(&bad, &[Filter::Free, Filter::Free]);
    assert_eq!(
        Multigrid::build(fine).err(),
        Some(MultigridError::SingularDiagonal { level: 0, row: 1 })
    );
    // ...and the block-Jacobi solve of a healthy system stays finite and converges.
    a.add_diagonal(&[0.0; 36]);
    let b = vec![Vec3::X; 36];
    let (dv, s) = solve(&a, &[Filter::Free; 36], &b, &[Vec3::ZERO; 36], false, 1e-8);
    assert!(s.residual <= 1e-8 && dv.iter().all(|v| v.is_finite()));
}

/// The finest level refiltered where an active-set round changed it preconditions exactly as
/// a full refresh of the same matrix: same V-cycle output bit for bit, with its rows rewritten
/// in place (drags, holds) or moved (a vertex fixed, its couplings lumped).
#[test]
fn refiltered_finest_level_is_the_refreshed_one() {
    let mut a = cloth_system(32);
    let n = a.rows();
    let mut filt = held_every(n, 13, 5, Vec3::new(0.6, 0.0, 0.8));
    let mut fine = Csr::default();
    fine.filtered(&a, &filt);
    let mut mg = Multigrid::build(fine).expect("hierarchy");
    assert!(mg.has_parallel_halves());
    a.clear_edits();
    for round in 0..2 {
        if round == 0 {
            for i in [7u32, 511, 512, 900] {
                a.add(i, i, Mat3::IDENTITY * 1e-2);
            }
            filt[5] = Filter::Free;
            filt[600] = Filter::Direction(Vec3::Z);
        } else {
            filt[513] = Filter::Fixed;
        }
        let edited = a.edited_rows().expect("only adds").to_vec();
        let mut refreshed = mg.clone();
        let mut fine = Csr::default();
        fine.filtered(&a, &filt);
        refreshed.refresh_finest(fine).expect("refresh");
        assert_eq!(mg.refilter_finest(&a, &filt, &edited), Ok(true));
        a.clear_edits();
        assert_same_cycle(&mut mg, &mut refreshed, 23, &format!("round {round}"));
    }
}

/// A rebuild computes into the storage of the levels it replaces: what another matrix left
/// there (here a rotated cloth's, with other blocks lumped by a fixed row) does not leak into
/// the next rebuild, which preconditions exactly as one from a fresh build.
#[test]
fn rebuilds_in_reused_storage_are_fresh_ones() {
    let a = cloth_system(32);
    let n = a.rows();
    let free = vec![Filter::Free; n];
    let mut fixed = free.clone();
    fixed[100] = Filter::Fixed;
    let r = Mat3::from_rotation_y(0.7);
    let rotated = mapped(&a, |_, _, m| r * m * r.transpose());
    let filtered = |m: &BlockCsr, f: &[Filter]| {
        let mut c = Csr::default();
        c.filtered(m, f);
        c
    };
    let mut once = Multigrid::build(filtered(&a, &free)).expect("hierarchy");
    let mut twice = once.clone();
    once.rebuild(filtered(&a, &fixed)).expect("rebuild");
    twice.rebuild(filtered(&rotated, &free)).expect("rebuild");
    twice.rebuild(filtered(&a, &fixed)).expect("rebuild");
    assert_same_cycle(&mut once, &mut twice, 3, "reused storage");
}
