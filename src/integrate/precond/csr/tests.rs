//! Unit tests of `csr.rs`, in their own file so that the test helpers they use
//! (which use `csr.rs` themselves) do not make an import cycle with it.

use super::super::dense::Dense;
use super::*;
use crate::linalg::PatternBuilder;
use crate::{Mat3, Vec3};

/// The two-halves filtering of a large matrix is the serial one, block for block.
#[test]
fn parallel_filtering_is_the_serial_one() {
    let n = PAR_FILTER_ROWS + 301;
    let mut p = PatternBuilder::new();
    for i in 0..n as u32 {
        for d in [1, 2, 50] {
            p.couple(i, (i + d) % n as u32);
        }
    }
    let mut a = p.build(n);
    for i in 0..n as u32 {
        for d in [1, 2, 50] {
            let j = (i + d) % n as u32;
            let t = f64::from(i) * 0.37 + f64::from(d);
            let dir = Vec3::new(t.sin(), t.cos(), 0.3).normalize();
            // Weak distance-2 couplings get lumped, the others stay.
            let k = if d == 2 { 1e-6 } else { 1.0 };
            let blk = Mat3::from_cols(dir * dir.x, dir * dir.y, dir * dir.z) * k;
            a.add(i, i, blk);
            a.add(j, j, blk);
            a.add(i, j, -blk);
            a.add(j, i, -blk);
        }
    }
    a.add_diagonal(&vec![1e-2; n]);
    let filter: Vec<Filter> = (0..n)
        .map(|i| match i % 7 {
            0 => Filter::Fixed,
            3 => Filter::Direction(Vec3::new(0.6, 0.0, 0.8)),
            _ => Filter::Free,
        })
        .collect();
    let mut par = Csr::default();
    par.filtered(&a, &filter);
    let mut dnorm = Vec::new();
    dnorm.extend((0..n).map(|i| frob2_f64(&a.diagonal(i)).sqrt().sqrt()));
    let (mut cols, mut vals, mut ends) = (Vec::new(), Vec::new(), vec![0]);
    filter_rows(&a, &filter, &dnorm, 0..n, &mut cols, &mut vals, &mut ends);
    assert_eq!(par.row_start, ends);
    assert_eq!(par.cols, cols);
    assert_eq!(par.vals, vals);
    assert!(par.cols.len() < a.nnz_blocks(), "some blocks lumped");
}

/// A product and a Galerkin factor large enough to be split in two halves by work are the
/// single-pass ones, block for block: each row's result does not depend on the split.
#[test]
fn split_products_are_the_serial_ones() {
    let n = 3000usize;
    let mut a = Csr {
        row_start: vec![0],
        ncols: n,
        ..Csr::default()
    };
    for i in 0..n {
        // Uneven rows, so that the split by work is not the split by rows.
        let width = 2 + (i * 7) % 11;
        for d in 0..width {
            let j = (i + d * 37) % n;
            let t = (i * 13 + d) as f32 * 0.1;
            a.cols.push(j as u32);
            a.vals.push(M3::from_cols(
                V3::new(t.sin(), 0.5, t.cos()),
                V3::new(0.25, t.cos(), 1.0),
                V3::new(t, -0.5, 0.75),
            ));
        }
        a.row_start.push(a.cols.len());
    }
    assert!(a.cols.len() >= PAR_BLOCKS, "large enough to be split");
    let x: Vec<V3> = (0..n)
        .map(|i| V3::new((i as f32).sin(), 1.0, (i % 5) as f32))
        .collect();
    let mut split = vec![V3::ZERO; n];
    a.mul(&x, &mut split);
    let serial: Vec<V3> = (0..n)
        // SAFETY: `x` has `n = ncols` entries.
        .map(|r| unsafe { a.row_times(r, &x) })
        .collect();
    assert_eq!(split, serial);
    let product = a.matmul(&a, n);
    let (mut part, mut cols, mut vals) = (Part::default(), Vec::new(), Vec::new());
    a.matmul_rows(&a, n, 0..n, &mut part, (&mut cols, &mut vals));
    let lens = part.lens;
    let ends: Vec<usize> = std::iter::once(0)
        .chain(lens.iter().scan(0, |e, l| {
            *e += l;
            Some(*e)
        }))
        .collect();
    assert_eq!(product.row_start, ends);
    assert_eq!(product.cols, cols);
    assert_eq!(product.vals, vals);
}

/// A chain 0-1-2 with stiff springs (negative blocks) and a weak positive distance-2 block
/// (bending-like), plus a weak negative one 0-3: only the weak positive block is lumped, the
/// matrix keeps its action on translations, and stays SPD (Cholesky of the dense copy).
#[test]
fn weak_positive_couplings_are_lumped_and_translations_kept() {
    let mut p = PatternBuilder::new();
    for (i, j) in [(0, 1), (1, 2), (0, 2), (0, 3)] {
        p.couple(i, j);
    }
    let mut a = p.build(4);
    let spring = |a: &mut BlockCsr, i: u32, j: u32, k: Mat3| {
        a.add(i, i, k);
        a.add(j, j, k);
        a.add(i, j, -k);
        a.add(j, i, -k);
    };
    let d = Vec3::new(1.0, 0.2, -0.1).normalize();
    let k = Mat3::from_cols(d * d.x, d * d.y, d * d.z) + Mat3::IDENTITY * 0.1;
    spring(&mut a, 0, 1, k);
    spring(&mut a, 1, 2, k);
    spring(&mut a, 0, 3, k * 1e-5);
    // Bending-like: energy c |x0 - 2 x1 + x2|^2 / 2 gives +c on the (0, 2) blocks.
    let c = 1e-5;
    let w = [1.0, -2.0, 1.0];
    for (ia, wa) in w.iter().enumerate() {
        for (ib, wb) in w.iter().enumerate() {
            a.add(ia as u32, ib as u32, Mat3::IDENTITY * (c * wa * wb));
        }
    }
    a.add_diagonal(&[1e-3; 4]);
    let mut f = Csr::default();
    f.filtered(&a, &[Filter::Free; 4]);
    let cols: Vec<Vec<u32>> = (0..4).map(|r| f.row(r).0.to_vec()).collect();
    assert_eq!(
        cols[0],
        vec![0, 1, 3],
        "(0, 2) lumped, weak spring (0, 3) kept"
    );
    assert_eq!(cols[2], vec![1, 2]);
    // Same product with every translation.
    for t in [Vec3::X, Vec3::Y, Vec3::new(0.3, -1.0, 2.0)] {
        let (mut y0, mut y1) = (vec![Vec3::ZERO; 4], vec![V3::ZERO; 4]);
        a.mul(&[t; 4], &mut y0);
        f.mul(&[t.as_vec3a(); 4], &mut y1);
        // Single precision: a few ulps of the O(1) blocks. Dropping the lumped coupling
        // instead would be off by c |t| >= 1e-5.
        for (u, v) in y0.iter().zip(&y1) {
            assert!((*u - v.as_dvec3()).length() <= 1e-6, "{u} vs {v}");
        }
    }
    assert!(Dense::factor(&f).is_ok());
}

/// Refiltering only the rows an active-set round changed gives the full pass's matrix, block
/// for block: after friction-drag-like diagonal changes and holds gained and released (the
/// rows keep their columns: rewritten in place), and after a vertex fixed (its couplings vanish
/// and are lumped: later rows move).
#[test]
fn refiltering_changed_rows_is_the_full_pass() {
    let mut a = crate::integrate::test_systems::cloth_system(24);
    let n = a.rows();
    let mut filter = crate::integrate::test_systems::held_every(n, 11, 4, Vec3::new(0.0, 0.6, 0.8));
    let mut inc = Csr::default();
    inc.filtered(&a, &filter);
    a.clear_edits();
    let mut rows = Vec::new();
    let check = |inc: &Csr, a: &BlockCsr, filter: &[Filter]| {
        let mut full = Csr::default();
        full.filtered(a, filter);
        assert_eq!(inc.row_start, full.row_start);
        assert_eq!(inc.cols, full.cols);
        assert_eq!(inc.vals, full.vals);
    };
    // A round: drags refitted on a few diagonals, one hold released and one gained.
    for i in [3u32, 200, 201, 575] {
        a.add(i, i, Mat3::IDENTITY * 0.3);
    }
    filter[4] = Filter::Free;
    filter[100] = Filter::Direction(Vec3::new(0.8, 0.0, 0.6));
    let edited = a
        .edited_rows()
        .expect("only adds since the last clear")
        .to_vec();
    assert_eq!(inc.refiltered(&a, &filter, &edited, &mut rows), Some(false));
    assert!(rows.len() < n / 10, "{} rows rewritten", rows.len());
    check(&inc, &a, &filter);
    a.clear_edits();
    // A vertex fixed: its couplings become zero blocks, lumped onto the diagonal.
    filter[300] = Filter::Fixed;
    assert_eq!(inc.refiltered(&a, &filter, &[], &mut rows), Some(true));
    check(&inc, &a, &filter);
    // Nothing changed: nothing to do.
    assert_eq!(inc.refiltered(&a, &filter, &[], &mut rows), Some(false));
    assert!(rows.is_empty());
    // Another pattern, or a bulk write (its edits are not listed): the full pass is needed.
    a.add_diagonal(&vec![0.0; n]);
    assert!(a.edited_rows().is_none());
    let other = crate::integrate::test_systems::cloth_system(24);
    assert_eq!(inc.refiltered(&other, &filter, &[], &mut rows), None);
}
