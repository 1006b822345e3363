//! The residuals and Jacobian rows of every calibration sample at one point, made once for the
//! cross-validation folds: each fold's refit starts at the fit of all samples, so its first
//! factor is of its training samples' rows there, the same rows in every fold.

use super::*;
use crate::fit::Problem;

/// Most values (residuals and Jacobian entries) kept: 32 MiB. Larger sets make each fold's
/// first factor from the model, as the other iterations do.
const MAX_VALUES: usize = 1 << 22;

/// The residuals and Jacobian (columns `columns`, unscaled) of every sample of `obs` at `x`,
/// as [`Model::jacobian`] writes them.
pub(super) struct RowsAt<'a> {
    model: &'a Model,
    obs: &'a [Observed],
    x: &'a [f64],
    columns: &'a [usize],
    /// Where each sample's residuals start in `residuals` (its Jacobian at `columns.len()`
    /// times that in `jacobian`); one more entry than samples.
    start: Vec<usize>,
    residuals: Vec<f64>,
    jacobian: Vec<f64>,
}

impl<'a> RowsAt<'a> {
    /// The rows of `obs` at `x`, or `None` when they would hold more than [`MAX_VALUES`].
    pub(super) fn new(
        model: &'a Model,
        obs: &'a [Observed],
        x: &'a [f64],
        columns: &'a [usize],
    ) -> Option<Self> {
        let p = columns.len();
        let mut start = Vec::with_capacity(obs.len() + 1);
        let mut total = 0;
        start.push(0);
        for o in obs {
            total += o.observation.residual_count();
            start.push(total);
        }
        if total.saturating_mul(p + 1) > MAX_VALUES {
            return None;
        }
        let mut residuals = Vec::with_capacity(total);
        let mut jacobian = Vec::with_capacity(total * p);
        sample_rows(model, obs, x, columns, &start, |_, r, j| {
            residuals.extend_from_slice(r);
            jacobian.extend_from_slice(j);
        })?;
        Some(Self {
            model,
            obs,
            x,
            columns,
            start,
            residuals,
            jacobian,
        })
    }

    /// The residuals and Jacobian (row-major, residual count × columns) of sample `i`.
    pub(super) fn sample(&self, i: usize) -> (&[f64], &[f64]) {
        let (a, b) = (self.start[i], self.start[i + 1]);
        let p = self.columns.len();
        (&self.residuals[a..b], &self.jacobian[a * p..b * p])
    }

    /// The samples `subset` (indices into the samples) as a problem whose Jacobian at the
    /// point and columns of these rows is read from them (and made by the model elsewhere).
    pub(super) fn subset<'s>(&'s self, subset: &'s [usize]) -> RowsSubset<'s> {
        RowsSubset { rows: self, subset }
    }
}

/// Samples per piece of work of [`sample_rows`].
const PIECE: usize = 128;

/// Pieces made at once by [`sample_rows`] (what is held besides its output).
const PIECES_AT_ONCE: usize = 64;

/// The residuals and Jacobian (columns `columns`, unscaled, row-major) of every sample of `obs`
/// at `x`, as [`Model::jacobian`] writes them, handed to `sink` in sample order a piece at a
/// time: `sink(first, residuals, jacobian)` for the samples from `first` on, whose residuals
/// start at `start[first]` (`start` has one more entry than `obs`). Each sample's rows are its
/// own computation, so [`PIECES_AT_ONCE`] pieces of [`PIECE`] samples are made at a time on
/// the machine's cores: the same bits whatever their number, and at most those pieces held
/// besides what `sink` keeps. `None` only when a worker thread lost its result.
pub(crate) fn sample_rows(
    model: &Model,
    obs: &[Observed],
    x: &[f64],
    columns: &[usize],
    start: &[usize],
    mut sink: impl FnMut(usize, &[f64], &[f64]),
) -> Option<()> {
    let p = columns.len();
    let pieces = obs.len().div_ceil(PIECE);
    for group in (0..pieces).step_by(PIECES_AT_ONCE) {
        let count = PIECES_AT_ONCE.min(pieces - group);
        let made = dh_core::parallel::map(count, |k| {
            let k = group + k;
            let (first, last) = (k * PIECE, ((k + 1) * PIECE).min(obs.len()));
            let (base, end) = (start[first], start[last]);
            let mut residuals = vec![0.0; end - base];
            let mut jacobian = vec![0.0; (end - base) * p];
            for (i, o) in obs.iter().enumerate().take(last).skip(first) {
                let (a, b) = (start[i] - base, start[i + 1] - base);
                model.jacobian(
                    x,
                    o,
                    columns,
                    &mut residuals[a..b],
                    &mut jacobian[a * p..b * p],
                );
            }
            (first, residuals, jacobian)
        })?;
        for (first, r, j) in made {
            sink(first, &r, &j);
        }
    }
    Some(())
}

/// Some samples of [`RowsAt`] as a [`Problem`] (the [`SubsetProblem`] of the same samples,
/// with its Jacobian at the rows' point read from them).
pub(super) struct RowsSubset<'s> {
    rows: &'s RowsAt<'s>,
    subset: &'s [usize],
}

impl Problem for RowsSubset<'_> {
    fn parameter_count(&self) -> usize {
        self.rows.model.parameter_count()
    }
    fn block_count(&self) -> usize {
        self.subset.len()
    }
    fn block_size(&self, block: usize) -> usize {
        let i = self.subset[block];
        self.rows.start[i + 1] - self.rows.start[i]
    }
    fn residuals(&self, x: &[f64], block: usize, out: &mut [f64]) {
        let o = &self.rows.obs[self.subset[block]];
        self.rows.model.residuals(x, o, out);
    }
    fn jacobian(
        &self,
        x: &[f64],
        block: usize,
        columns: &[usize],
        residuals: &mut [f64],
        jacobian: &mut [f64],
    ) {
        let rows = self.rows;
        let i = self.subset[block];
        if x != rows.x || columns != rows.columns {
            rows.model
                .jacobian(x, &rows.obs[i], columns, residuals, jacobian);
            return;
        }
        let (a, b) = (rows.start[i], rows.start[i + 1]);
        let p = columns.len();
        residuals[..b - a].copy_from_slice(&rows.residuals[a..b]);
        jacobian[..(b - a) * p].copy_from_slice(&rows.jacobian[a * p..b * p]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simulate::{simulate, SimulationOptions};

    /// The rows made in pieces on the cores are each sample's own rows, in sample order.
    #[test]
    fn the_rows_made_in_pieces_are_each_samples_own() {
        let table = crate::test_robots::ur5();
        // 2800 poses of 3 targets: 8400 samples, 66 pieces in two groups, the last one short.
        let (data, _) = simulate(
            &table,
            &SimulationOptions {
                poses: 2800,
                target_count: 3,
                validation_fraction: 0.0,
                ..SimulationOptions::default()
            },
        )
        .expect("a simulated set");
        let options = CalibrationOptions::default();
        let fitted = super::super::fitted_for_tests(&table, &data, &options);
        let (session, geo) = (fitted.session, fitted.geo);
        let (model, cal, x) = (&session.model, &session.prep.cal, &geo.last.outcome.x);
        let columns = &geo.free;
        let p = columns.len();
        let rows = RowsAt::new(model, cal, x, columns).expect("rows that fit in memory");
        assert_eq!(cal.len(), 8400);
        for (i, o) in cal.iter().enumerate() {
            let m = o.observation.residual_count();
            let (mut res, mut jac) = (vec![0.0; m], vec![0.0; m * p]);
            model.jacobian(x, o, columns, &mut res, &mut jac);
            assert_eq!(rows.sample(i), (&res[..], &jac[..]), "sample {i}");
        }
    }
}
