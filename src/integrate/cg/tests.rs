//! Unit tests of `cg.rs`, in their own file so that the test helpers they use
//! (which use `cg.rs` themselves) do not make an import cycle with it.

use super::*;
use crate::integrate::test_systems::*;
/// The start from the span of two directions: exact (no iteration) when the solution lies
/// in it, while the first direction alone needs iterations; a useless second direction
/// (parallel to the first, or not finite) falls back to the first alone.
#[test]
fn start_directions_span_the_solution() {
    let mut rng = Rng(21);
    let (a, filt, z, b, x) = solved_cloth(&mut rng);
    let n = a.rows();
    let e: Vec<Vec3> = (0..n).map(|_| rng.vec3() * 0.1).collect();
    // x = (g - h) / 0.3 on the free components.
    let g: Vec<Vec3> = x.iter().zip(&e).map(|(x, e)| *x * 0.3 + *e).collect();
    let run = |second: Option<&[Vec3]>| {
        let mut dv = g.clone();
        let s = Pcg::default().solve(&a, &filt, &b, &z, None, 1e-9, 10_000, &mut dv, second);
        (dv, s)
    };
    let (dv, two) = run(Some(&e));
    assert_eq!(two.iterations, 0, "{two:?}");
    let scale = x.iter().map(|v| v.length()).fold(0.0, f64::max);
    for i in 0..n {
        assert!((dv[i] - x[i]).length() <= 1e-6 * scale, "vertex {i}");
    }
    let (_, one) = run(None);
    assert!(one.iterations > 5, "{one:?}");
    let parallel: Vec<Vec3> = g.iter().map(|v| *v * 2.0).collect();
    let mut bad = e.clone();
    bad[3] = Vec3::NAN;
    for second in [&parallel, &bad] {
        let (dv, s) = run(Some(second));
        assert_eq!(s.iterations, one.iterations, "{s:?} vs {one:?}");
        assert!(s.residual <= 1e-9 && dv.iter().all(|v| v.is_finite()));
    }
}

/// `start` answers alone exactly when its start meets the tolerance: from the solution it
/// returns it unchanged with no iteration, from zero it leaves the iterations to `iterate`,
/// and the two together are `solve`, bit for bit.
#[test]
fn a_start_that_meets_the_tolerance_needs_no_iteration() {
    let (a, filt, z, b, x) = solved_cloth(&mut Rng(5));
    let n = a.rows();
    let mut pcg = Pcg::default();
    let mut dv = x.clone();
    let done = pcg.start(&a, &filt, &b, &z, 1e-9, &mut dv, None);
    let done = done.expect("the solution meets the tolerance");
    assert_eq!(done.iterations, 0);
    assert!(done.residual <= 1e-9, "{done:?}");
    for i in 0..n {
        assert!(
            (dv[i] - x[i]).length() <= 1e-9 * (1.0 + x[i].length()),
            "vertex {i}"
        );
    }
    let mut split = vec![Vec3::ZERO; n];
    assert!(pcg
        .start(&a, &filt, &b, &z, 1e-9, &mut split, None)
        .is_none());
    let s = pcg.iterate(&a, &filt, Precond::BlockJacobi, 1e-9, 10_000, &mut split);
    let mut whole = vec![Vec3::ZERO; n];
    let w = Pcg::default().solve(&a, &filt, &b, &z, None, 1e-9, 10_000, &mut whole, None);
    assert!(s.iterations > 0 && s.iterations == w.iterations);
    assert_eq!(split, whole);
}

/// The Cholesky factor of the filtered matrix as the preconditioner: on the cloth system with
/// pins, contact directions and targets it solves in one iteration, and its answer agrees with
/// the multigrid-preconditioned one and the reference to the solve tolerance. With pair springs
/// outside the pattern (`OffPattern`: the factor holds only their lumped diagonal) it still
/// reaches the tolerance, in a few iterations, at the answer block Jacobi finds.
#[test]
fn cholesky_preconditioner_agrees_with_multigrid() {
    use crate::integrate::contact::ContactSpring;
    let mut rng = Rng(5);
    let (mut a, filt, z, b, x) = solved_cloth(&mut rng);
    let n = a.rows();
    let tol = 1e-10;
    let direct = |a: &BlockCsr, pcg: &mut Pcg| {
        let mut chol = FilteredCholesky::default();
        chol.factorise(a, &filt).expect("positive definite");
        let mut dv = vec![Vec3::ZERO; n];
        assert!(pcg.start(a, &filt, &b, &z, tol, &mut dv, None).is_none());
        let s = pcg.iterate(a, &filt, Precond::Cholesky(&mut chol), tol, 100, &mut dv);
        (dv, s)
    };
    let (dv, s) = direct(&a, &mut Pcg::default());
    assert!(s.residual <= tol && s.iterations == 1, "{s:?}");
    let (mg, ms) = solve(&a, &filt, &b, &z, true, tol);
    assert!(ms.residual <= tol);
    let scale = x.iter().map(|v| v.length()).fold(0.0, f64::max);
    for i in 0..n {
        assert!((dv[i] - x[i]).length() <= 1e-7 * scale, "row {i}");
        assert!((dv[i] - mg[i]).length() <= 1e-7 * scale, "row {i}");
    }
    // Pair springs between vertices the pattern does not couple (a layer under another).
    let mut pcg = Pcg::default();
    for k in 0..6u32 {
        let (p, q, r) = (
            k * 13 % n as u32,
            (k * 29 + 70) % n as u32,
            (k * 29 + 71) % n as u32,
        );
        let c = ContactSpring {
            verts: [p, q, r, r],
            weights: [1.0, -0.5, -0.5, 0.0],
            normal: rng.vec3().normalize(),
            point: Vec3::ZERO,
            gap: 0.0,
            stiffness: 4e3,
            friction: 0.0,
        };
        c.add_jacobian(&mut a, 1e-3);
        pcg.extra.push(&c, &a, 1e-3);
    }
    let (dv, s) = direct(&a, &mut pcg);
    assert!(
        s.residual <= tol && (2..30).contains(&s.iterations),
        "{s:?}"
    );
    let mut reference = vec![Vec3::ZERO; n];
    let r = pcg.solve(&a, &filt, &b, &z, None, 1e-13, 10_000, &mut reference, None);
    assert!(r.residual <= 1e-13);
    let scale = reference.iter().map(|v| v.length()).fold(0.0, f64::max);
    for i in 0..n {
        assert!((dv[i] - reference[i]).length() <= 1e-7 * scale, "row {i}");
    }
}
