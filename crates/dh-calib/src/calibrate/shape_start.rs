//! Starts of the effects that are not linear in a shape parameter ([`Effect::shape_grid`]:
//! `thermal_growth`'s time constant), in two stages: a grid over the shape with the amplitude
//! fitted linearly at each value (one Gauss-Newton step with the other estimated parameters),
//! then the joint fit from the best. At amplitude 0 such a shape does not act, so a fit that
//! started there would hold it (not identifiable) and fit the amplitude at a wrong shape.
//!
//! Units: as the effect's parameters; the span of the sequence in the unit the effects read
//! ([`crate::effects_thermal::time_of`]: seconds, or the pose order).

use std::ops::Range;

use super::*;
use crate::diagnose::{dense, Projector};

/// The extent of the sequence of `observations` in the unit time effects read: the largest
/// time since the set's first (seconds), or 1 for the pose order (0 with one pose).
pub(crate) fn sequence_span(observations: &[Observed]) -> f64 {
    observations
        .iter()
        .map(|o| crate::effects_thermal::time_of(&o.context))
        .fold(0.0, f64::max)
}

/// A shape fitted on the grid: the amplitude (parameter units), the shape value and the
/// reduction of the sum of squares it gives to first order (m²).
pub(crate) struct ShapeFit {
    pub(crate) amplitude: f64,
    pub(crate) shape: f64,
    pub(crate) reduction: f64,
}

/// The best value of `grid` for the shape parameter (`range.start + 1`) of `effect`, whose
/// parameters are `range`, its amplitude (`range.start`) 0 at `x`: at each value, the
/// amplitude's column on `observations`, fitted by `solve` (scaled columns in, the scaled
/// amplitude step and the reduction out: a projection off the other estimated columns).
/// `None` when no value reduces anything.
///
/// The effect is the amplitude times a shape of the sample (its `delta_in` at amplitude 1),
/// so the amplitude's column at one shape is the column at another with each sample's rows
/// rescaled by the ratio of the shapes: the model is evaluated once, at the grid's last value
/// (for a time constant, the longest, whose shape is 0 only where every shape is: `t = 0`).
///
/// # Errors
/// Those of [`dense`].
pub(crate) fn best_shape(
    (model, effect): (&Model, &dyn Effect),
    observations: &[Observed],
    x: &[f64],
    range: &Range<usize>,
    (grid, scales): (&[f64], &[f64]),
    solve: &dyn Fn(&DMatrix<f64>) -> (f64, f64),
) -> Result<Option<ShapeFit>, CalibError> {
    let amplitude = range.start;
    let shape = amplitude + 1;
    let Some(&reference) = grid.last() else {
        return Ok(None);
    };
    let mut at = x.to_vec();
    at[shape] = reference;
    let (column, _, starts) = dense(model, observations, &at, &[amplitude], scales)?;
    let shape_of = |o: &Observed, g: f64| effect.delta_in(&o.q, &o.context, &[1.0, g]);
    let base: Vec<f64> = observations
        .iter()
        .map(|o| shape_of(o, reference))
        .collect();
    let mut best: Option<ShapeFit> = None;
    let mut c = column.clone();
    for &g in grid {
        for (i, o) in observations.iter().enumerate() {
            let ratio = if base[i] == 0.0 {
                0.0
            } else {
                shape_of(o, g) / base[i]
            };
            let end = starts.get(i + 1).copied().unwrap_or(column.nrows());
            for row in starts[i]..end {
                c[(row, 0)] = column[(row, 0)] * ratio;
            }
        }
        let (step, reduction) = solve(&c);
        let better = best.as_ref().is_none_or(|b| reduction > b.reduction);
        if reduction.is_finite() && reduction > 0.0 && better {
            best = Some(ShapeFit {
                amplitude: step * scales[amplitude],
                shape: g,
                reduction,
            });
        }
    }
    Ok(best)
}

/// `x` with a start for every effect of `session`'s model among `columns` that has a shape
/// grid and amplitude 0 at `x` ([`best_shape`] on the calibration samples, the other
/// `columns` estimated with it); `x` itself for the rest.
///
/// # Errors
/// Those of [`dense`].
pub(crate) fn shape_start(
    session: &Session<'_>,
    x: &[f64],
    columns: &[usize],
) -> Result<Vec<f64>, CalibError> {
    let mut out = x.to_vec();
    let cal = &session.prep.cal;
    let span = sequence_span(cal);
    for (effect, range) in session.model.effects() {
        let grid = effect.shape_grid(span);
        if grid.is_empty()
            || range.len() < 2
            || !columns.contains(&range.start)
            || out.get(range.start) != Some(&0.0)
        {
            continue;
        }
        let others: Vec<usize> = columns
            .iter()
            .copied()
            .filter(|c| !range.contains(c))
            .collect();
        let (jf, r, _) = dense(&session.model, cal, &out, &others, &session.scales)?;
        let projector = Projector::new(&jf, &r, (0..r.len()).collect());
        let solve = |c: &DMatrix<f64>| {
            let (_, dc, reduction, _) = projector.solve(c);
            (dc.get(0).copied().unwrap_or(0.0), reduction)
        };
        let fit = best_shape(
            (&session.model, effect.as_ref()),
            cal,
            &out,
            &range,
            (&grid, &session.scales),
            &solve,
        )?;
        if let Some(f) = fit {
            out[range.start] = f.amplitude;
            out[range.start + 1] = f.shape;
        }
    }
    Ok(out)
}
