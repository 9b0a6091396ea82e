//! Unit tests of `cycle.rs`, in their own file so that the test helpers they use
//! (which use `cycle.rs` themselves) do not make an import cycle with it.

use super::super::csr::Csr;
use super::super::hierarchy::Multigrid;
use crate::integrate::test_systems::*;
use crate::linalg::Filter;
use crate::Vec3;

#[test]
fn multigrid_matches_block_jacobi_on_random_spd_system() {
    check_agreement(&random_system(600, 7), 11);
}

#[test]
fn multigrid_matches_block_jacobi_on_constrained_cloth() {
    check_agreement(&cloth_system(24), 5);
}

#[test]
fn vcycle_is_symmetric_positive_definite() {
    let a = cloth_system(20);
    let n = a.rows();
    let mut rng = Rng(3);
    let (filt, _) = constraints(n, &mut rng);
    let mut fine = Csr::default();
    fine.filtered(&a, &filt);
    let mut mg = Multigrid::build(fine).expect("hierarchy");
    assert!(mg.level_sizes().len() >= 2, "{:?}", mg.level_sizes());
    for _ in 0..5 {
        let u: Vec<Vec3> = (0..n).map(|_| rng.vec3()).collect();
        let v: Vec<Vec3> = (0..n).map(|_| rng.vec3()).collect();
        let (mut mu, mut mv) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
        mg.apply(&u, &mut mu);
        mg.apply(&v, &mut mv);
        let (vmu, umv) = (dot(&v, &mu), dot(&u, &mv));
        // Symmetric in exact arithmetic; the hierarchy is single precision, so up to
        // ~100 f32 ulps (1.2e-5). A one-sided smoother is off by ~1e-1.
        assert!(
            (vmu - umv).abs() <= 1e-5 * vmu.abs().max(umv.abs()),
            "{vmu} vs {umv}"
        );
        assert!(dot(&u, &mu) > 0.0);
    }
}

/// Large levels smooth two halves in parallel; the V-cycle must stay symmetric positive
/// definite (48 x 48 = 2304 rows, above the parallel-sweep threshold).
#[test]
fn vcycle_with_parallel_halves_is_symmetric_positive_definite() {
    let a = cloth_system(48);
    let n = a.rows();
    let mut rng = Rng(9);
    let (filt, _) = constraints(n, &mut rng);
    let mut fine = Csr::default();
    fine.filtered(&a, &filt);
    let mut mg = Multigrid::build(fine).expect("hierarchy");
    assert!(mg.has_parallel_halves());
    for _ in 0..3 {
        let u: Vec<Vec3> = (0..n).map(|_| rng.vec3()).collect();
        let v: Vec<Vec3> = (0..n).map(|_| rng.vec3()).collect();
        let (mut mu, mut mv) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
        mg.apply(&u, &mut mu);
        mg.apply(&v, &mut mv);
        let (vmu, umv) = (dot(&v, &mu), dot(&u, &mv));
        // Symmetric in exact arithmetic; the hierarchy is single precision, so up to
        // ~100 f32 ulps (1.2e-5). A one-sided smoother is off by ~1e-1.
        assert!(
            (vmu - umv).abs() <= 1e-5 * vmu.abs().max(umv.abs()),
            "{vmu} vs {umv}"
        );
        assert!(dot(&u, &mu) > 0.0);
    }
}

#[test]
fn iterations_do_not_grow_with_resolution() {
    let mut its = Vec::new();
    for res in [16, 32, 64] {
        let a = cloth_system(res);
        let n = a.rows();
        let filt: Vec<Filter> = (0..n)
            .map(|i| {
                if i == 0 || i == res - 1 {
                    Filter::Fixed
                } else {
                    Filter::Free
                }
            })
            .collect();
        let b = vec![Vec3::new(0.0, 0.0, -9.81 * 5e-5 / 60.0); n];
        let (_, s) = solve(&a, &filt, &b, &vec![Vec3::ZERO; n], true, 1e-5);
        its.push(s.iterations);
    }
    // Multigrid's count stays flat with the resolution (block Jacobi's grows like res).
    assert!(its.iter().all(|&k| k <= 20), "{its:?}");
}
