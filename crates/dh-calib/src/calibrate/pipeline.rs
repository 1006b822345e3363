//! The entry points: [`calibrate`] and [`calibrate_tree`] run the session's steps in order
//! and attach the outlier screen; the diagnosis reuses the fitted session.

use super::*;

/// Runs the calibration of `nominal` against `data` (see the module docs).
///
/// Joint values are matched to rows by name; a mimic row without its own column follows its
/// driver. The report's contract (names, units, layout) is described on [`Report`] and
/// [`crate::model`].
///
/// # Errors
/// [`CalibError::MissingJoint`] when a row has no column, [`CalibError::BadTarget`] /
/// [`CalibError::Length`] / [`CalibError::NonFinite`] for bad samples,
/// [`CalibError::TooFewSamples`] with fewer than 3 calibration samples,
/// [`CalibError::Degenerate`] when the measured points are collinear, and any error of
/// [`Model::new`] or [`fit::solve`].
pub fn calibrate(
    nominal: &DhTable,
    data: &Measurements,
    options: &CalibrationOptions,
) -> Result<Report, CalibError> {
    calibrate_tree(&DhTree::serial(nominal), data, options)
}

/// [`calibrate`] for a tree: the targets ride on the branches named by
/// [`CalibrationOptions::target_branches`] (or their own names), the joint values are matched
/// to the tree's rows by name, and the report's `tree` holds the calibrated tree.
///
/// # Errors
/// As [`calibrate`], and [`CalibError::BadOption`] for a target on no branch.
pub fn calibrate_tree(
    tree: &DhTree,
    data: &Measurements,
    options: &CalibrationOptions,
) -> Result<Report, CalibError> {
    let Fitted {
        session,
        geo:
            Geometric {
                mut steps,
                last,
                mut fixed,
                ..
            },
        scan,
    } = fitted_session(
        tree,
        data,
        options,
        &options.effects,
        (&options.effects, None),
        None,
        Folds::Refit,
    )?;
    let mut last = last.outcome;
    if !options.effects.is_empty() {
        let all: Vec<usize> = (0..session.model.parameter_count()).collect();
        // Effects with a shape (a time constant) start from a grid over it.
        let start = shape_start(&session, &last.x, &all)?;
        let (free, fixed2) = session.identify(&start, &all)?;
        fixed = fixed2;
        let mut step = session.step("effects", &start, &free, steps.last())?;
        step.report.fixed = session.named_geometric(&fixed);
        last = step.outcome;
        steps.push(step.report);
    }
    let mut report = session.report(&last, steps, fixed, &[]);
    report.selected_effects = options
        .effects
        .iter()
        .map(|e| crate::effects::label_of(e.as_ref()))
        .collect();
    attach_outliers(&mut report, scan);
    Ok(report)
}

/// A session of the data with `effects` whose geometric step has run, after the outlier screen
/// of `options.outliers` ([`crate::calibrate::screen`]) when it is on.
pub(crate) struct Fitted<'a> {
    pub(crate) session: Session<'a>,
    pub(crate) geo: Geometric,
    pub(crate) scan: Option<crate::outliers::OutlierReport>,
}

/// Builds the session of `data` with `effects` and runs its geometric step. The screen judges
/// the points against the geometry and `judged_with` (declared effects, or those a diagnosis
/// selected), flagging only samples the judgement `before` left out when given; without them its first round is
/// that fit (the same calibration samples, the
/// geometric parameters fitted without effects), so data without outliers are fitted once. When the screen leaves samples out
/// (and they are not kept), the session is built anew from the samples kept, placed in the
/// whole file's sequence: a dropped pose was still visited, so the direction of the next
/// one's motion and the time are the file's. `screened`: the findings of that screen, made
/// before (by [`screen_from`] with no first round, the same `judged_with` and `before`), used
/// instead of screening again. The geometric step's cross-validation folds are fitted as
/// `folds` says.
pub(crate) fn fitted_session<'a>(
    tree: &DhTree,
    data: &Measurements,
    options: &'a CalibrationOptions,
    effects: &[Arc<dyn Effect>],
    (judged_with, before): (&[Arc<dyn Effect>], Option<&crate::outliers::OutlierReport>),
    screened: Option<crate::outliers::OutlierReport>,
    folds: Folds,
) -> Result<Fitted<'a>, CalibError> {
    if options.outliers.screen {
        check_level(options)?;
    }
    // A screen made before that leaves points out needs no fit of all of `data`.
    if let Some(scan) = screened
        .as_ref()
        .filter(|s| options.outliers.screen && !s.kept && !s.outliers.is_empty())
    {
        let (session, geo) = without_outliers(tree, data, options, effects, scan, folds)?;
        return Ok(Fitted {
            session,
            geo,
            scan: screened,
        });
    }
    let mut session = Session::new(tree, data, options, effects, None)?;
    if !options.outliers.screen {
        let geo = session.geometric_with(folds)?;
        return Ok(Fitted {
            session,
            geo,
            scan: None,
        });
    }
    // The fit of all of `data` is the screen's first round; its geometric step's folds are
    // refitted only when the screen keeps the points.
    let mut geo = session.geometric_with(Folds::Later)?;
    let scan = match screened {
        Some(scan) => scan,
        None => screen_from(
            tree,
            data,
            options,
            Some((&session, &geo)),
            judged_with,
            before,
        )?,
    };
    if scan.kept || scan.outliers.is_empty() {
        session.finish_geometric(&mut geo, folds)?;
        return Ok(Fitted {
            session,
            geo,
            scan: Some(scan),
        });
    }
    // The first session's samples are not needed any more: free them before the second.
    drop(session);
    let (session, geo) = without_outliers(tree, data, options, effects, &scan, folds)?;
    Ok(Fitted {
        session,
        geo,
        scan: Some(scan),
    })
}

/// The session of the samples of `data` that `scan` keeps, placed in the whole file's
/// sequence, with `effects`, and its geometric step (its folds fitted as `folds` says).
fn without_outliers<'a>(
    tree: &DhTree,
    data: &Measurements,
    options: &'a CalibrationOptions,
    effects: &[Arc<dyn Effect>],
    scan: &crate::outliers::OutlierReport,
    folds: Folds,
) -> Result<(Session<'a>, Geometric), CalibError> {
    let dropped: std::collections::BTreeSet<usize> =
        scan.outliers.iter().map(|o| o.sample).collect();
    let sequence =
        crate::prepare::kept_sequence(&sequence_of(&rows_of(tree, data)?, data), data, |i, _| {
            !dropped.contains(&i)
        });
    let cleaned = scan.without(data);
    let mut session = Session::new(tree, &cleaned, options, effects, Some(&sequence))?;
    let geo = session.geometric_with(folds)?;
    Ok((session, geo))
}

/// Stores the screen's findings in `report`.
pub(crate) fn attach_outliers(report: &mut Report, scan: Option<crate::outliers::OutlierReport>) {
    report.outliers = scan;
}

/// The geometric fit of `data` measured on the serial robot `table` (no effects, every fold
/// refitted): the session and step the unit tests of the fits' parts start from.
#[cfg(test)]
pub(crate) fn fitted_for_tests<'a>(
    table: &dh_core::DhTable,
    data: &Measurements,
    options: &'a CalibrationOptions,
) -> Fitted<'a> {
    fitted_session(
        &DhTree::serial(table),
        data,
        options,
        &[],
        (&[], None),
        None,
        Folds::Refit,
    )
    .expect("a fit")
}
