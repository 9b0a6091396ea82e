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
    let s = pcg.iterate(&a, &filt, None, 1e-9, 10_000, &mut split);
    let mut whole = vec![Vec3::ZERO; n];
    let w = Pcg::default().solve(&a, &filt, &b, &z, None, 1e-9, 10_000, &mut whole, None);
    assert!(s.iterations > 0 && s.iterations == w.iterations);
    assert_eq!(split, whole);
}
