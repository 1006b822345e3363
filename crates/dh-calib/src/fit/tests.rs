//! Unit tests of the solver: the chunked QR, a circle fit, factors across chunks, aliases.

use nalgebra::{DMatrix, DVector};

use super::factor::Tsqr;
use super::*;

/// The chunked, structured QR gives the factor of the whole matrix: `RᵀR = AᵀA`, `R`
/// upper triangular, with several flushes, a rank-deficient column and a zero column.
#[test]
fn tsqr_factors_a_tall_matrix_in_chunks() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let cols = 6;
    let mut t = Tsqr::new(cols);
    // Three full chunks and a partial one.
    let rows = 3 * t.chunk + 37;
    let mut a = DMatrix::from_fn(rows, cols, |_, _| rng.random_range(-1.0..1.0));
    for i in 0..rows {
        a[(i, 3)] = 2.0 * a[(i, 0)] - a[(i, 1)];
        a[(i, 4)] = 0.0;
    }
    for i in 0..rows {
        let row: Vec<f64> = (0..cols).map(|k| a[(i, k)]).collect();
        t.push(&row);
    }
    let r = t.finish();
    for i in 0..cols {
        for k in 0..i {
            assert_eq!(r[(i, k)], 0.0);
        }
    }
    let (ata, rtr) = (a.transpose() * &a, r.transpose() * &r);
    assert!((ata - rtr).abs().max() < 1e-10 * rows as f64);
    assert!(r[(3, 3)].abs() < 1e-10 && r[(4, 4)] == 0.0);
}

/// Fit a circle's centre and radius to points: residual = |p − c| − r (1 per block).
struct Circle(Vec<(f64, f64)>);

impl Problem for Circle {
    fn parameter_count(&self) -> usize {
        3
    }
    fn block_count(&self) -> usize {
        self.0.len()
    }
    fn block_size(&self, _: usize) -> usize {
        1
    }
    fn residuals(&self, x: &[f64], b: usize, out: &mut [f64]) {
        let (px, py) = self.0[b];
        out[0] = ((px - x[0]).powi(2) + (py - x[1]).powi(2)).sqrt() - x[2];
    }
    fn jacobian(&self, x: &[f64], b: usize, cols: &[usize], r: &mut [f64], j: &mut [f64]) {
        self.residuals(x, b, r);
        let (px, py) = self.0[b];
        let d = ((px - x[0]).powi(2) + (py - x[1]).powi(2)).sqrt();
        for (k, &c) in cols.iter().enumerate() {
            j[k] = match c {
                0 => -(px - x[0]) / d,
                1 => -(py - x[1]) / d,
                _ => -1.0,
            };
        }
    }
}

#[test]
fn circle_fit_recovers_centre_and_radius() {
    let pts: Vec<_> = (0..40)
        .map(|i| {
            let t = i as f64 * 0.3;
            (1.0 + 2.0 * t.cos(), -0.5 + 2.0 * t.sin())
        })
        .collect();
    let p = Circle(pts);
    let out = solve(
        &p,
        &[0.2, 0.3, 1.0],
        &[0, 1, 2],
        &[1.0; 3],
        &Default::default(),
    )
    .unwrap();
    assert!((out.x[0] - 1.0).abs() < 1e-12, "{:?}", out.x);
    assert!((out.x[1] + 0.5).abs() < 1e-12);
    assert!((out.x[2] - 2.0).abs() < 1e-12);
    assert!(out.ssr < 1e-24);
    assert_eq!(out.rank, 3);
    // Holding the radius fixed leaves it at x0 and fits the centre only.
    let out = solve(
        &p,
        &[0.2, 0.3, 2.0],
        &[0, 1],
        &[1.0; 3],
        &Default::default(),
    )
    .unwrap();
    assert_eq!(out.x[2], 2.0);
    assert!(out.std_errors[2].is_none() && out.std_errors[0].is_some());
}

#[test]
fn the_pipelined_factor_is_the_serial_one_bit_for_bit() {
    // 2000 blocks: 32 messages from the Jacobian thread, several chunk flushes.
    let pts: Vec<_> = (0..2000)
        .map(|i| ((i as f64 * 0.013).sin() * 3.0, (i as f64 * 0.021).cos()))
        .collect();
    let p = Circle(pts);
    let (x, cols, scales) = ([0.1, 0.2, 1.5], [0, 1, 2], [1.0, 2.0, 3.0]);
    let serial = super::factor::factor_blocks(&p, &x, &cols, &scales, 0..2000, false).unwrap();
    let piped = super::factor::factor_blocks(&p, &x, &cols, &scales, 0..2000, true).unwrap();
    assert_eq!(serial, piped);
    // A block whose residual is not finite is named by either path.
    let mut bad = p.0.clone();
    bad[1500] = (f64::NAN, 0.0);
    let bad = Circle(bad);
    for pipelined in [false, true] {
        let e = super::factor::factor_blocks(&bad, &x, &cols, &scales, 0..2000, pipelined);
        assert!(
            matches!(&e, Err(CalibError::NonFinite { what }) if what == "residual block 1500"),
            "{e:?}"
        );
    }
}

#[test]
fn factor_matches_dense_qr_across_chunks() {
    // 700 rows forces several chunk flushes.
    let pts: Vec<_> = (0..700)
        .map(|i| ((i as f64 * 0.01).sin() * 3.0, (i as f64 * 0.017).cos()))
        .collect();
    let p = Circle(pts);
    let x = [0.1, 0.2, 1.5];
    let f = factor(&p, &x, &[0, 1, 2], &[1.0, 2.0, 3.0]).unwrap();
    let mut j = DMatrix::zeros(700, 3);
    let mut r = DVector::zeros(700);
    for b in 0..700 {
        let (mut rb, mut jb) = ([0.0], [0.0; 3]);
        p.jacobian(&x, b, &[0, 1, 2], &mut rb, &mut jb);
        r[b] = rb[0];
        for c in 0..3 {
            j[(b, c)] = jb[c] * [1.0, 2.0, 3.0][c];
        }
    }
    let gram = j.transpose() * &j;
    let gram_f = f.r.transpose() * &f.r;
    assert!((gram - gram_f).amax() < 1e-9);
    let jtr = j.transpose() * &r;
    assert!((jtr - f.r.transpose() * &f.qtr).amax() < 1e-9);
    assert!((f.ssr - r.norm_squared()).abs() < 1e-9);
}

#[test]
fn aliased_columns_are_found_with_their_partners() {
    // Columns: a, b = 2a (alias), c independent, d = 0 (no effect).
    let j = DMatrix::from_row_slice(
        4,
        4,
        &[
            1.0, 2.0, 0.0, 0.0, //
            0.5, 1.0, 1.0, 0.0, //
            -1.0, -2.0, 3.0, 0.0, //
            2.0, 4.0, 0.1, 0.0,
        ],
    );
    // Prefer fixing b (priority 0) over a (priority 1).
    let id = identifiability(&j, &[1.0; 4], &[1, 0, 1, 1], 1e-9).unwrap();
    assert_eq!(id.rank, 2);
    assert_eq!(id.free, vec![0, 2]);
    assert_eq!(id.fixed.len(), 2);
    let b = id.fixed.iter().find(|f| f.index == 1).unwrap();
    assert_eq!(b.aliases, vec![0]);
    // Moving b by t and a by −2t changes nothing.
    assert!((b.combination[0] + 2.0).abs() < 1e-9, "{:?}", b.combination);
    let d = id.fixed.iter().find(|f| f.index == 3).unwrap();
    assert!(d.aliases.is_empty());
    assert!(id.condition_number.is_finite());
}

/// [`Circle`] counting the blocks whose Jacobian it was asked for (a factor asks once per
/// block).
struct Counted {
    circle: Circle,
    jacobians: std::sync::atomic::AtomicUsize,
}

impl Problem for Counted {
    fn parameter_count(&self) -> usize {
        self.circle.parameter_count()
    }
    fn block_count(&self) -> usize {
        self.circle.block_count()
    }
    fn block_size(&self, b: usize) -> usize {
        self.circle.block_size(b)
    }
    fn residuals(&self, x: &[f64], b: usize, out: &mut [f64]) {
        self.circle.residuals(x, b, out);
    }
    fn jacobian(&self, x: &[f64], b: usize, cols: &[usize], r: &mut [f64], j: &mut [f64]) {
        self.jacobians
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        self.circle.jacobian(x, b, cols, r, j);
    }
}

/// A large fit's last step is checked by a sum of squares, not a factor: the same point and
/// sum of squares, bit for bit, one factor fewer, and the standard errors of the factor one
/// step before, which differ from the point's in the last digits. A small fit makes every
/// factor.
#[test]
fn a_large_fit_takes_its_last_step_without_a_factor() {
    use rand::{Rng, SeedableRng};
    use std::sync::atomic::Ordering;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let noisy = |n: usize, rng: &mut rand_chacha::ChaCha8Rng| {
        let circle = Circle(
            (0..n)
                .map(|i| {
                    let t = i as f64 * 0.001;
                    let r = 2.0 + rng.random_range(-0.01..0.01);
                    (1.0 + r * t.cos(), -0.5 + r * t.sin())
                })
                .collect(),
        );
        Counted {
            circle,
            jacobians: 0.into(),
        }
    };
    let (x0, free, scales) = ([1.0001, -0.4999, 1.9999], [0, 1, 2], [1.0; 3]);
    let options = FitOptions::default();
    let blocks = 3 * SEGMENT_BLOCKS;
    let p = noisy(blocks, &mut rng);
    let last = solve(&p, &x0, &free, &scales, &options).unwrap();
    let factors_last = p.jacobians.swap(0, Ordering::Relaxed) / blocks;
    let every = super::solve::solve_with_every_factor(&p, &x0, &free, &scales, &options).unwrap();
    let factors_every = p.jacobians.load(Ordering::Relaxed) / blocks;
    assert_eq!(factors_last + 1, factors_every);
    assert!(factors_last >= 2, "{factors_last} factors");
    assert_eq!(last.x, every.x);
    assert_eq!(last.ssr, every.ssr);
    assert_eq!(last.iterations, every.iterations);
    assert_eq!(last.termination, Termination::Converged);
    assert_eq!(last.rank, every.rank);
    for (a, b) in last.std_errors.iter().zip(&every.std_errors) {
        let (a, b) = (a.unwrap(), b.unwrap());
        assert!(a != b && ((a - b) / b).abs() < 1e-6, "{a} against {b}");
    }
    // At most SEGMENT_BLOCKS blocks: every point factored, as before.
    let p = noisy(SEGMENT_BLOCKS, &mut rng);
    let small = solve(&p, &x0, &free, &scales, &options).unwrap();
    let factors_small = p.jacobians.swap(0, Ordering::Relaxed) / SEGMENT_BLOCKS;
    let every = super::solve::solve_with_every_factor(&p, &x0, &free, &scales, &options).unwrap();
    assert_eq!(
        factors_small,
        p.jacobians.load(Ordering::Relaxed) / SEGMENT_BLOCKS
    );
    assert_eq!(small.std_errors, every.std_errors);
}
