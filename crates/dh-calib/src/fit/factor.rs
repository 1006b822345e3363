//! The triangular factor of the column-scaled Jacobian, built block by block.
//!
//! A "tall skinny QR": blocks are stacked a few hundred rows at a time under the factor of
//! everything seen so far and re-factored by Householder reflections, so memory is `O(p²)`
//! and the accuracy that of a QR of the full Jacobian. The residual rides along as an extra
//! column (`Qᵀr` for free). Large problems are factored in segments on several threads and
//! the segments' factors stacked, deterministically in segment order, unless their Gram
//! matrix gives the factor (module `gram`).

use nalgebra::{DMatrix, DVector};

use super::gram::GramSum;
use super::{CalibError, Problem, MAX_BLOCK};

/// The triangular factor of the column-scaled Jacobian of some columns, with the residuals.
///
/// `[J·diag(s) | r] = Q [[r_factor, qtr], [0, ρ]]`, so `‖r + J·diag(s)·u‖² = ‖qtr + r_factor·u‖² + ρ²`.
#[derive(Clone, Debug, PartialEq)]
pub struct Factor {
    /// Upper triangular `p × p` factor of the scaled Jacobian.
    pub r: DMatrix<f64>,
    /// `Qᵀ r` restricted to the first `p` rows.
    pub qtr: DVector<f64>,
    /// Sum of squared residuals.
    pub ssr: f64,
    /// Number of residuals.
    pub rows: usize,
}

/// Size of [`Tsqr`]'s chunk of rows: 192 KiB, well within the L2 cache of one core.
const CHUNK_BYTES: usize = 192 * 1024;

/// Incremental QR of a tall matrix given a row at a time: the triangular factor `R` of the
/// rows so far, and a chunk of new rows `B` that is folded into it by Householder reflections
/// when full (the QR of `[R; B]`).
///
/// The reflections use the structure of `[R; B]`: the reflection of column `j` touches row `j`
/// of `R` and the chunk only (the rows of `R` below `j` are zero in that column), so a chunk
/// of `m` rows costs `2 m p²` operations, with no copy of the stack. Both are stored by
/// column, so every reflection runs over contiguous memory.
pub(crate) struct Tsqr {
    cols: usize,
    pub(super) chunk: usize,
    /// `R`, `cols × cols`, by column: element `(i, k)` at `k · cols + i`.
    r: Vec<f64>,
    /// The chunk, `chunk × cols`, by column: element `(i, k)` at `k · chunk + i`.
    b: Vec<f64>,
    filled: usize,
}

impl Tsqr {
    pub(crate) fn new(cols: usize) -> Self {
        // Each reflection sweeps the chunk's later columns: a chunk of CHUNK_BYTES stays in a
        // core's L2 cache across the sweeps (at least 64 rows, so that R's share of the work,
        // p² per chunk, stays small against 2 m p²).
        let chunk = (CHUNK_BYTES / (8 * cols.max(1))).max(64);
        Self {
            cols,
            chunk,
            r: vec![0.0; cols * cols],
            b: vec![0.0; chunk * cols],
            filled: 0,
        }
    }

    pub(crate) fn push(&mut self, row: &[f64]) {
        if self.filled == self.chunk {
            self.flush();
        }
        for (k, v) in row.iter().enumerate().take(self.cols) {
            self.b[k * self.chunk + self.filled] = *v;
        }
        self.filled += 1;
    }

    /// [`Tsqr::push`] of the row `[a₀·s₀, …, a_{p−1}·s_{p−1}, last]` (`p = cols − 1`: a
    /// scaled Jacobian row and its residual), written straight into the chunk; whether every
    /// value is finite.
    pub(crate) fn push_scaled(&mut self, a: &[f64], s: &[f64], last: f64) -> bool {
        if self.filled == self.chunk {
            self.flush();
        }
        let p = self.cols - 1;
        let mut finite = last.is_finite();
        for (k, (a, s)) in a.iter().zip(s).take(p).enumerate() {
            let v = a * s;
            finite &= v.is_finite();
            self.b[k * self.chunk + self.filled] = v;
        }
        self.b[p * self.chunk + self.filled] = last;
        self.filled += 1;
        finite
    }

    /// Folds the chunk into `R` (Golub & Van Loan, Matrix Computations, 4th ed., §5.1.2,
    /// Householder vectors with `v₀ = x₀ − α`, `α = −sign(x₀)‖x‖`).
    fn flush(&mut self) {
        let (p, n, m) = (self.cols, self.chunk, self.filled);
        if m == 0 {
            return;
        }
        for j in 0..p {
            let (before, rest) = self.b.split_at_mut((j + 1) * n);
            let bj = &before[j * n..j * n + m];
            let sigma = dot(bj, bj);
            if sigma == 0.0 {
                continue;
            }
            let x0 = self.r[j * p + j];
            let norm = (x0 * x0 + sigma).sqrt();
            let alpha = if x0 >= 0.0 { -norm } else { norm };
            let v0 = x0 - alpha;
            let beta = 2.0 / (v0 * v0 + sigma);
            // The later columns four at a time (one pass over `bj` for four dot products and
            // one for four updates), each with the same operations in the same order as alone.
            let mut columns = rest.chunks_exact_mut(n).map(|c| &mut c[..m]);
            let mut k = j + 1;
            while k + 4 <= p {
                let (Some(c0), Some(c1), Some(c2), Some(c3)) = (
                    columns.next(),
                    columns.next(),
                    columns.next(),
                    columns.next(),
                ) else {
                    break;
                };
                let d = dot4(bj, [&*c0, &*c1, &*c2, &*c3]);
                let mut w = [0.0; 4];
                for (l, wl) in w.iter_mut().enumerate() {
                    let rjk = self.r[(k + l) * p + j];
                    *wl = beta * (v0 * rjk + d[l]);
                    self.r[(k + l) * p + j] = rjk - *wl * v0;
                }
                let rows = bj.iter().zip(c0).zip(c1).zip(c2).zip(c3);
                for ((((x, y0), y1), y2), y3) in rows {
                    *y0 -= w[0] * x;
                    *y1 -= w[1] * x;
                    *y2 -= w[2] * x;
                    *y3 -= w[3] * x;
                }
                k += 4;
            }
            for (bk, k) in columns.zip(k..p) {
                let rjk = self.r[k * p + j];
                let w = beta * (v0 * rjk + dot(bj, bk));
                self.r[k * p + j] = rjk - w * v0;
                for (y, x) in bk.iter_mut().zip(bj) {
                    *y -= w * x;
                }
            }
            self.r[j * p + j] = alpha;
        }
        self.filled = 0;
    }

    pub(crate) fn finish(mut self) -> DMatrix<f64> {
        self.flush();
        DMatrix::from_column_slice(self.cols, self.cols, &self.r)
    }
}

/// `Σ aᵢ bᵢ` in four independent sums (which the compiler can keep in vector registers).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for l in 0..4 {
            acc[l] += x[l] * y[l];
        }
    }
    let tail: f64 = ra.iter().zip(rb).map(|(x, y)| x * y).sum();
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// [`dot`] of `a` with each of four columns in one pass over `a`: each sum the same as
/// [`dot`]'s, bit for bit (the same products added in the same order).
fn dot4(a: &[f64], b: [&[f64]; 4]) -> [f64; 4] {
    let mut acc = [[0.0; 4]; 4];
    let [b0, b1, b2, b3] = b.map(|c| c.chunks_exact(4));
    let quads = a.chunks_exact(4).zip(b0).zip(b1).zip(b2).zip(b3);
    for ((((x, y0), y1), y2), y3) in quads {
        for l in 0..4 {
            acc[0][l] += x[l] * y0[l];
            acc[1][l] += x[l] * y1[l];
            acc[2][l] += x[l] * y2[l];
            acc[3][l] += x[l] * y3[l];
        }
    }
    let body = a.len() - a.len() % 4;
    std::array::from_fn(|c| {
        let tail: f64 = a[body..]
            .iter()
            .zip(&b[c][body..])
            .map(|(x, y)| x * y)
            .sum();
        let acc = &acc[c];
        (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
    })
}

pub(super) fn check_columns(n: usize, columns: &[usize], scales: &[f64]) -> Result<(), CalibError> {
    if scales.len() != n {
        return Err(CalibError::Length {
            what: "scales".into(),
            expected: n,
            found: scales.len(),
        });
    }
    for &c in columns {
        if c >= n {
            return Err(CalibError::BadParameter {
                index: c,
                reason: format!("expected an index below {n}"),
            });
        }
        let s = scales[c];
        if !(s.is_finite() && s > 0.0) {
            return Err(CalibError::BadParameter {
                index: c,
                reason: format!("expected a positive finite scale, found {s}"),
            });
        }
    }
    Ok(())
}

/// Factors the column-scaled Jacobian of `columns` at `x` (see [`Factor`]); the columns of
/// `r` are in the order of `columns`. A problem of more than [`SEGMENT_BLOCKS`] blocks is
/// factored from its Gram matrix when the Jacobian's condition number allows it
/// ([`super::GRAM_MAX_CONDITION`]), else by the QR in a second pass over the blocks.
///
/// # Errors
/// [`CalibError::NonFinite`] when a residual or derivative is not finite;
/// [`CalibError::BadParameter`] / [`CalibError::Length`] for bad `columns` or `scales`.
pub fn factor<P: Problem + ?Sized>(
    problem: &P,
    x: &[f64],
    columns: &[usize],
    scales: &[f64],
) -> Result<Factor, CalibError> {
    let n = problem.parameter_count();
    check_columns(n, columns, scales)?;
    let p = columns.len();
    let blocks = problem.block_count();
    if blocks <= SEGMENT_BLOCKS {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        let pipelined = blocks >= PIPELINE_BLOCKS && cores > 1;
        let (full, ssr, rows) = factor_blocks(problem, x, columns, scales, 0..blocks, pipelined)?;
        return Ok(split_factor(&full, p, ssr, rows));
    }
    // The Gram matrix of each segment in parallel, summed in segment order (the same result
    // whatever the number of threads), when it is well enough conditioned (see `gram`).
    let parts = segments(blocks, |range| {
        GramSum::over(problem, x, columns, scales, range)
    })?;
    let mut sum = GramSum::empty(p + 1);
    for part in parts {
        sum.add(part);
    }
    match sum.factor() {
        Some(f) => Ok(f),
        None => qr_segments(problem, x, columns, scales),
    }
}

/// [`factor`] by the QR whatever the problem's size (never from the Gram matrix): for a
/// caller that looks for the directions the data do not determine, where the Gram matrix
/// would be refused after a pass over every block ([`super::GRAM_MAX_CONDITION`]).
///
/// # Errors
/// As [`factor`].
pub fn factor_by_qr<P: Problem + ?Sized>(
    problem: &P,
    x: &[f64],
    columns: &[usize],
    scales: &[f64],
) -> Result<Factor, CalibError> {
    if problem.block_count() <= SEGMENT_BLOCKS {
        return factor(problem, x, columns, scales);
    }
    check_columns(problem.parameter_count(), columns, scales)?;
    qr_segments(problem, x, columns, scales)
}

/// The QR factor of a problem of more than [`SEGMENT_BLOCKS`] blocks: the segments' factors in
/// parallel, stacked in segment order.
fn qr_segments<P: Problem + ?Sized>(
    problem: &P,
    x: &[f64],
    columns: &[usize],
    scales: &[f64],
) -> Result<Factor, CalibError> {
    let (p, blocks) = (columns.len(), problem.block_count());
    let parts = segments(blocks, |range| {
        factor_blocks(problem, x, columns, scales, range, false)
    })?;
    let mut tsqr = Tsqr::new(p + 1);
    let (mut ssr, mut rows) = (0.0, 0);
    let mut row = vec![0.0; p + 1];
    for (r, s, m) in parts {
        for i in 0..r.nrows() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = r[(i, j)];
            }
            tsqr.push(&row);
        }
        ssr += s;
        rows += m;
    }
    Ok(split_factor(&tsqr.finish(), p, ssr, rows))
}

/// Blocks per segment of a problem factored (or summed) in parallel: problems of at most this
/// many blocks take the serial path, bit for bit as before threads were used.
pub const SEGMENT_BLOCKS: usize = 16_384;

/// Runs `work` on consecutive ranges of [`SEGMENT_BLOCKS`] blocks on up to
/// `available_parallelism` threads; returns the results in range order (the first error in
/// that order, if any).
fn segments<T: Send>(
    blocks: usize,
    work: impl Fn(std::ops::Range<usize>) -> Result<T, CalibError> + Sync,
) -> Result<Vec<T>, CalibError> {
    parallel_map(blocks.div_ceil(SEGMENT_BLOCKS), |k| {
        work(k * SEGMENT_BLOCKS..((k + 1) * SEGMENT_BLOCKS).min(blocks))
    })
}

/// `work(0..count)` on up to `available_parallelism` threads, results in index order (the
/// first error in that order, if any): [`dh_core::parallel::try_map`].
pub(crate) fn parallel_map<T: Send>(
    count: usize,
    work: impl Fn(usize) -> Result<T, CalibError> + Sync,
) -> Result<Vec<T>, CalibError> {
    dh_core::parallel::try_map(count, work, || CalibError::NonFinite {
        what: "a worker thread lost its result".into(),
    })
}

/// `one` of every item, in parallel segments of [`SEGMENT_BLOCKS`] items for long lists (each
/// value the same as on one thread), in order.
pub(crate) fn in_segments<T: Sync, R: Send>(items: &[T], one: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let parts: Vec<&[T]> = items.chunks(SEGMENT_BLOCKS).collect();
    if parts.len() <= 1 {
        return items.iter().map(&one).collect();
    }
    match parallel_map(parts.len(), |k| {
        Ok(parts[k].iter().map(&one).collect::<Vec<R>>())
    }) {
        Ok(r) => r.into_iter().flatten().collect(),
        // Only a lost result gets here (a worker's panic reaches the caller): compute on this
        // thread instead.
        Err(_) => items.iter().map(one).collect(),
    }
}

/// `(r_factor, qtr)` out of the `(p + 1) × (p + 1)` factor of `[J | r]`.
fn split_factor(full: &DMatrix<f64>, p: usize, ssr: f64, rows: usize) -> Factor {
    Factor {
        r: full.view((0, 0), (p, p)).clone_owned(),
        qtr: full.view((0, p), (p, 1)).column(0).clone_owned(),
        ssr,
        rows,
    }
}

/// Problems of at least this many blocks (and at most [`SEGMENT_BLOCKS`], on a machine of more
/// than one core) have their Jacobian made on a second thread while the calling one factors it:
/// the same rows pushed in the same order, so the same factor bit for bit.
const PIPELINE_BLOCKS: usize = 512;

/// Blocks per message from the Jacobian thread.
const MESSAGE_BLOCKS: usize = 64;

/// The triangular factor of `[J·diag(s) | r]` over `range` of blocks, its sum of squared
/// residuals and its number of rows; `pipelined`: the Jacobian made on a second thread.
pub(super) fn factor_blocks<P: Problem + ?Sized>(
    problem: &P,
    x: &[f64],
    columns: &[usize],
    scales: &[f64],
    range: std::ops::Range<usize>,
    pipelined: bool,
) -> Result<(DMatrix<f64>, f64, usize), CalibError> {
    let tsqr = Tsqr::new(columns.len() + 1);
    let (tsqr, ssr, rows) = accumulate(problem, x, columns, scales, range, pipelined, tsqr)?;
    Ok((tsqr.finish(), ssr, rows))
}

/// Where the rows `[a₀·s₀, …, a_{p−1}·s_{p−1}, r]` of a scaled Jacobian and its residuals go,
/// one at a time in block order: a [`Tsqr`] or the Gram matrix of a [`GramSum`].
pub(super) trait RowSink: Send {
    /// Adds the row `[a₀·s₀, …, a_{p−1}·s_{p−1}, last]`; whether every value is finite.
    fn push_scaled(&mut self, a: &[f64], s: &[f64], last: f64) -> bool;
}

impl RowSink for Tsqr {
    fn push_scaled(&mut self, a: &[f64], s: &[f64], last: f64) -> bool {
        Tsqr::push_scaled(self, a, s, last)
    }
}

/// The rows of `[J·diag(s) | r]` over `range` of blocks pushed into `sink` in block order, with
/// their sum of squared residuals and their number; `pipelined`: the Jacobian made on a second
/// thread.
pub(super) fn accumulate<P: Problem + ?Sized, S: RowSink>(
    problem: &P,
    x: &[f64],
    columns: &[usize],
    scales: &[f64],
    range: std::ops::Range<usize>,
    pipelined: bool,
    sink: S,
) -> Result<(S, f64, usize), CalibError> {
    let p = columns.len();
    let column_scales: Vec<f64> = columns.iter().map(|&c| scales[c]).collect();
    let mut into = Rows {
        sink,
        column_scales,
        ssr: 0.0,
        rows: 0,
    };
    if !pipelined {
        let mut res = [0.0; MAX_BLOCK];
        let mut jac = vec![0.0; MAX_BLOCK * p];
        for b in range {
            let m = problem.block_size(b).min(MAX_BLOCK);
            problem.jacobian(x, b, columns, &mut res[..m], &mut jac[..m * p]);
            into.push(b, &res[..m], &jac[..m * p])?;
        }
    } else {
        // (first block, row counts, residuals, Jacobian rows) of consecutive blocks.
        type Message = (usize, Vec<usize>, Vec<f64>, Vec<f64>);
        let produce = |send: &mut dyn FnMut(Message) -> bool| {
            for first in range.clone().step_by(MESSAGE_BLOCKS) {
                let blocks = first..(first + MESSAGE_BLOCKS).min(range.end);
                let sizes: Vec<usize> = blocks
                    .clone()
                    .map(|b| problem.block_size(b).min(MAX_BLOCK))
                    .collect();
                let total: usize = sizes.iter().sum();
                let (mut res, mut jac) = (vec![0.0; total], vec![0.0; total * p]);
                let mut at = 0;
                for (b, &m) in blocks.zip(&sizes) {
                    let (r, j) = (&mut res[at..at + m], &mut jac[at * p..(at + m) * p]);
                    problem.jacobian(x, b, columns, r, j);
                    at += m;
                }
                if !send((first, sizes, res, jac)) {
                    return;
                }
            }
        };
        dh_core::parallel::pipeline(4, produce, |items| -> Result<(), CalibError> {
            for (first, sizes, res, jac) in items {
                let mut at = 0;
                for (k, &m) in sizes.iter().enumerate() {
                    into.push(first + k, &res[at..at + m], &jac[at * p..(at + m) * p])?;
                    at += m;
                }
            }
            Ok(())
        })?;
    }
    Ok((into.sink, into.ssr, into.rows))
}

/// What [`accumulate`] accumulates, block after block.
struct Rows<S> {
    sink: S,
    column_scales: Vec<f64>,
    ssr: f64,
    rows: usize,
}

impl<S: RowSink> Rows<S> {
    /// Adds block `b`'s residuals `res` and Jacobian rows `jac` (row-major, unscaled).
    fn push(&mut self, b: usize, res: &[f64], jac: &[f64]) -> Result<(), CalibError> {
        let p = self.column_scales.len();
        for (i, &r) in res.iter().enumerate() {
            // The scaled Jacobian row, then the residual; the factor is thrown away on a
            // value that is not finite.
            if !self
                .sink
                .push_scaled(&jac[i * p..(i + 1) * p], &self.column_scales, r)
            {
                return Err(CalibError::NonFinite {
                    what: format!("residual block {b}"),
                });
            }
            self.ssr += r * r;
        }
        self.rows += res.len();
        Ok(())
    }
}

/// Sum of squared residuals at `x`, or `None` when one is not finite.
pub fn sum_of_squares<P: Problem + ?Sized>(problem: &P, x: &[f64]) -> Option<f64> {
    let blocks = problem.block_count();
    let ssr = if blocks <= SEGMENT_BLOCKS {
        sum_blocks(problem, x, 0..blocks)
    } else {
        segments(blocks, |range| Ok(sum_blocks(problem, x, range)))
            .ok()?
            .into_iter()
            .sum()
    };
    ssr.is_finite().then_some(ssr)
}

fn sum_blocks<P: Problem + ?Sized>(problem: &P, x: &[f64], range: std::ops::Range<usize>) -> f64 {
    let mut res = [0.0; MAX_BLOCK];
    let mut ssr = 0.0;
    for b in range {
        let m = problem.block_size(b).min(MAX_BLOCK);
        problem.residuals(x, b, &mut res[..m]);
        for v in &res[..m] {
            ssr += v * v;
        }
    }
    ssr
}
