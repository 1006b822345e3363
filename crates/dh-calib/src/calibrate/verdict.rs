//! The verdict on a fitted session: its residual tested against the noise (chi-square with a
//! known per-axis sigma, or lack of fit against the pure error of repeated poses), and the
//! residual's remaining structure against each joint and the pose order (binned residuals, F
//! tests). The diagnosis ([`crate::diagnose`], steps 1 and 5) and the calibration's final
//! verdict both use these tests. Residuals and noise in metres.

use nalgebra::Vector3;

use super::{NoiseFloor, Prepared, Session};
use crate::findings::{NoiseTest, ResidualTest, Verdict};
use crate::fit::FitOutcome;
use crate::model::Observation;
use crate::stats;

mod structure_checks;
use structure_checks::structure_checks;

/// The verdict on the fit `fit` of `session` (final calibration RMS `rms`, noise floor
/// `floor`, effects `selected` estimated in it).
pub(crate) fn verdict(
    session: &Session<'_>,
    fit: &FitOutcome,
    alpha: f64,
    floor: Option<&NoiseFloor>,
    rms: f64,
    selected: &[String],
) -> Verdict {
    let res = session.position_residuals(&fit.x);
    verdict_with(session, fit, alpha, floor, rms, selected, &res)
}

/// [`verdict`] given the position residuals `res` of every calibration sample at `fit.x`
/// ([`Session::position_residuals`]): both tests read them, computed once.
pub(crate) fn verdict_with(
    session: &Session<'_>,
    fit: &FitOutcome,
    alpha: f64,
    floor: Option<&NoiseFloor>,
    rms: f64,
    selected: &[String],
    res: &[Vector3<f64>],
) -> Verdict {
    let test = residual_test_in(session, fit, alpha, Some(res));
    let structure = structure_checks(session, fit, alpha, res);
    // No ratio to a floor that is not a physical noise (a floor of 1e-17 m from identical
    // copies of one record gave "233348038164 x the floor").
    let position_ratio = floor
        .filter(|f| f.rms.is_finite() && f.rms >= crate::MIN_SIGMA)
        .map(|f| rms / f.rms)
        .filter(|r| r.is_finite());
    let angles = angle_ratio(session, fit, floor);
    let ratio = weighed_ratio(position_ratio, angles, session.prep.cal.len());
    let complete = (test.kind != NoiseTest::None).then_some(!test.significant);
    let parts = match (position_ratio, angles) {
        (Some(p), Some((a, _))) => format!(" (position {p:.2} x, orientation {a:.2} x)"),
        _ => String::new(),
    };
    let summary = match (complete, ratio) {
        (Some(true), _) => "model complete".to_string(),
        (Some(false), Some(r)) => format!("residual remains: {r:.2} x the floor{parts}"),
        (Some(false), None) => "residual remains".to_string(),
        (None, _) => "no test possible".to_string(),
    };
    let mut notes = Vec::new();
    let significant: Vec<&str> = structure
        .iter()
        .filter(|s| s.significant)
        .map(|s| s.variable.as_str())
        .collect();
    let shape = if significant.is_empty() {
        "no structure against the joints, the pose order, time or the gravity lever arms that \
         the tests resolve"
            .to_string()
    } else {
        format!(
            "structure against {} (see the bins)",
            significant.join(", ")
        )
    };
    match complete {
        None if test.summary.starts_with(IDENTICAL_REPEATS) => notes.push(
            "no test of the final model is possible: copies of one record are not repeated \
             measurements (give --sigma or a sigma column)"
                .into(),
        ),
        None if test.summary.starts_with(NOT_FINITE) => notes.push(format!(
            "no test of the final model is possible: {}",
            test.summary
        )),
        None => notes.push(
            "no test of the final model is possible: no known sigma and no repeated poses \
             (give --sigma or repeat poses under one config)"
                .into(),
        ),
        Some(false) => {
            if !selected.is_empty() {
                notes.push(format!(
                    "the residual is still above the noise with the selected effects ({}): they \
                     may stand in for something unmodelled rather than be its cause",
                    selected.join(", ")
                ));
            }
            notes.push(format!("the final residual has {shape}"));
        }
        Some(true) => {}
    }
    // A structure test can resolve what the residual test, spread over every degree of
    // freedom, does not (a warm-up of a few noise sigmas concentrated on a trend in time).
    if complete != Some(false) && !significant.is_empty() {
        notes.push(format!(
            "the final residual has {shape}{}",
            if complete == Some(true) {
                ", though its size is within the noise by the residual test"
            } else {
                ""
            }
        ));
    }
    Verdict {
        test,
        alpha,
        complete,
        ratio,
        position_ratio,
        angle_ratio: angles.map(|a| a.0),
        summary,
        structure,
        notes,
    }
}

/// The orientation part of a 6-DoF set's ratio to the floor: the calibration samples' angle
/// RMS per axis over its floor ([`NoiseFloor::angle_rms`]), with the number of samples that
/// measure an orientation; `None` without them or without a floor.
fn angle_ratio(
    session: &Session<'_>,
    fit: &FitOutcome,
    floor: Option<&NoiseFloor>,
) -> Option<(f64, usize)> {
    let angle_floor = floor
        .and_then(|f| f.angle_rms)
        .filter(|a| a.is_finite() && *a > 0.0)?;
    let cal = &session.prep.cal;
    let poses = cal
        .iter()
        .filter(|o| matches!(o.observation, Observation::TargetPose { .. }))
        .count();
    let angle = super::angle_rms(&session.model, &fit.x, cal)?;
    Some((angle / angle_floor, poses)).filter(|(r, _)| r.is_finite())
}

/// The ratio of a set's residual to its floor with position and orientation each over its
/// own noise: `sqrt((n p² + k a²) / (n + k))` for `n` samples of ratio `p` in position and `k`
/// of them of ratio `a` in orientation (3 rows each: the mean of the whitened squares over the
/// rows, the chi-square statistic over its degrees of freedom when every sigma is known); the
/// position's alone for points.
fn weighed_ratio(position: Option<f64>, angle: Option<(f64, usize)>, n: usize) -> Option<f64> {
    match (position, angle) {
        (Some(p), Some((a, k))) if n + k > 0 => {
            let (n, k) = (n as f64, k as f64);
            Some(((n * p * p + k * a * a) / (n + k)).sqrt())
        }
        (p, _) => p,
    }
}

/// How the summary of a residual test begins when the repeated poses are identical (a pure
/// error below [`crate::MIN_SIGMA`] per axis): no noise floor can be estimated from them.
const IDENTICAL_REPEATS: &str = "the repeated poses are identical";

/// How the summary of a residual test begins when its statistic is not a finite number.
const NOT_FINITE: &str = "the statistic is not a finite number";

/// The test that is not made: `summary` says why (held-out error decides).
fn no_test(summary: String) -> ResidualTest {
    ResidualTest {
        kind: NoiseTest::None,
        statistic: None,
        dof: (0.0, 0.0),
        p_value: None,
        noise_rms: None,
        significant: true,
        summary,
    }
}

/// Pure error of repeated points: `(sum of squares, degrees of freedom)`.
fn pure_error(prep: &Prepared) -> Option<(f64, usize)> {
    // Ordered by key: the sum is the same in every process (a hash map's order is not).
    let mut groups: std::collections::BTreeMap<(usize, usize), Vec<Vector3<f64>>> =
        std::collections::BTreeMap::new();
    for (o, key) in prep.cal.iter().zip(prep.repeat_keys()) {
        if let (Some(k), Observation::Point { point, .. }) = (key, &o.observation) {
            groups.entry(k).or_default().push(*point);
        }
    }
    let (mut ss, mut dof) = (0.0, 0usize);
    for pts in groups.values().filter(|v| v.len() > 1) {
        let mean = pts.iter().sum::<Vector3<f64>>() / pts.len() as f64;
        ss += pts.iter().map(|v| (v - mean).norm_squared()).sum::<f64>();
        dof += 3 * (pts.len() - 1);
    }
    (dof > 0).then_some((ss, dof))
}

/// Known per-axis noise (metres) of every calibration sample, when there is one: the
/// option's for all, or each sample's own.
#[derive(Clone, Copy)]
enum Known<'a> {
    Given(f64),
    Samples(&'a crate::prepare::Sigmas),
}

impl Known<'_> {
    /// The noise of calibration sample `i`.
    fn at(&self, i: usize) -> Vector3<f64> {
        match self {
            Known::Given(s) => Vector3::repeat(*s),
            Known::Samples(v) => v.get(i).unwrap_or_default(),
        }
    }
}

/// Known per-axis noise of every calibration sample, when there is one (no copy of the
/// samples' own: millions of them on a large set).
fn known_sigmas<'a>(session: &'a Session<'_>) -> Option<Known<'a>> {
    if let Some(s) = session.options.sigma {
        return Some(Known::Given(s));
    }
    let v = &session.prep.sigmas;
    v.iter()
        .all(|s| s.is_some_and(|s| s.iter().all(|x| *x > 0.0)))
        .then_some(Known::Samples(v))
}

pub(crate) fn residual_test(session: &Session<'_>, fit: &FitOutcome, alpha: f64) -> ResidualTest {
    residual_test_in(session, fit, alpha, None)
}

/// [`residual_test`], reading the position residuals at `fit.x` from `res` when given
/// ([`Session::position_residuals`]; a 6-DoF pose's angle residuals are computed again).
fn residual_test_in(
    session: &Session<'_>,
    fit: &FitOutcome,
    alpha: f64,
    res: Option<&[Vector3<f64>]>,
) -> ResidualTest {
    let m = fit.residual_count as f64;
    let p = fit.free.len() as f64;
    let dof = (m - p).max(1.0);
    let model = &session.model;
    if let Some(known) = known_sigmas(session) {
        let mut chi2 = 0.0;
        let mut r = [0.0; 6];
        for (i, o) in session.prep.cal.iter().enumerate() {
            let s = known.at(i);
            match res {
                Some(res) if !matches!(o.observation, Observation::TargetPose { .. }) => {
                    r[..3].copy_from_slice(res[i].as_slice());
                }
                _ => model.residuals(&fit.x, o, &mut r),
            }
            for a in 0..3 {
                chi2 += (r[a] / s[a]).powi(2);
            }
            // A 6-DoF pose's angle residuals are in metres of the position's RMS sigma
            // (`Observation::TargetPose`): 3 more degrees of freedom, counted in `m`.
            if matches!(o.observation, Observation::TargetPose { .. }) {
                let sp = (s.norm_squared() / 3.0).sqrt();
                for v in &r[3..] {
                    chi2 += (v / sp).powi(2);
                }
            }
        }
        let pv = stats::chi2_sf(chi2, dof);
        let n = session.prep.cal.len();
        let noise = ((0..n).map(|i| known.at(i).norm_squared()).sum::<f64>() / n as f64).sqrt();
        // No verdict from a statistic that is not a number: the readers hold every sigma to
        // at least MIN_SIGMA, so this is a guard, not a path input takes.
        if !(chi2.is_finite() && pv.is_finite()) {
            return no_test(format!(
                "{NOT_FINITE} (chi-square {chi2} against the known noise of {noise:e} m RMS): \
                 held-out error decides"
            ));
        }
        return ResidualTest {
            kind: NoiseTest::KnownSigma,
            statistic: Some(chi2),
            dof: (dof, 0.0),
            p_value: Some(pv),
            noise_rms: Some(noise),
            significant: pv < alpha,
            summary: format!(
                "chi-square {chi2:.1} on {dof:.0} degrees of freedom against the known noise, p = {pv:.2e}"
            ),
        };
    }
    if let Some((ss_pe, df_pe)) = pure_error(&session.prep) {
        let df_lof = dof - df_pe as f64;
        let ss_lof = (fit.ssr - ss_pe).max(0.0);
        let noise = (3.0 * ss_pe / df_pe as f64).sqrt();
        // Per-axis standard deviation of the repeats (`df_pe` counts 3 per repeat).
        let per_axis = (ss_pe / df_pe as f64).sqrt();
        if per_axis < crate::MIN_SIGMA {
            return no_test(format!(
                "{IDENTICAL_REPEATS} (pure error {per_axis:.1e} m per axis, below {:e} m): \
                 the noise floor cannot be estimated from them, held-out error decides",
                crate::MIN_SIGMA
            ));
        }
        if df_lof >= 1.0 {
            let f = (ss_lof / df_lof) / (ss_pe / df_pe as f64);
            let pv = stats::f_sf(f, df_lof, df_pe as f64);
            if !(f.is_finite() && pv.is_finite()) {
                return no_test(format!(
                    "{NOT_FINITE} (lack of fit F = {f} against the pure error of repeats): \
                     held-out error decides"
                ));
            }
            return ResidualTest {
                kind: NoiseTest::PureError,
                statistic: Some(f),
                dof: (df_lof, df_pe as f64),
                p_value: Some(pv),
                noise_rms: Some(noise),
                significant: pv < alpha,
                summary: format!(
                    "lack of fit F = {f:.1} on ({df_lof:.0}, {df_pe}) degrees of freedom against the pure error of repeats, p = {pv:.2e}"
                ),
            };
        }
    }
    no_test(
        "no independent noise estimate (no known sigma, no repeated poses): held-out error \
         decides"
            .into(),
    )
}
