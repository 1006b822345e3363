//! Points left out as evidence (issue 33 §4): when the outlier screen, judging against a model
//! without some effect, leaves out the very poses that show it (every pose a direction
//! backlash reverses), the selection sees no trace of the effect and may call the model
//! complete while naming its evidence as outliers. So at the end of a selection run, the
//! calibration points still left out are judged against each remaining candidate: first
//! linearised (is there one value of the candidate's parameters that brings several of them,
//! from at least [`MIN_POSES`] poses, within the screen's threshold?), then, for the
//! [`MAX_EXACT`] candidates that explain most of them, exactly, as the screen judges
//! ([`rejudge`] against the selected effects and the candidate, every parameter fitted). When
//! that judgement gives back points of [`MIN_POSES`] poses or more, the selection runs again
//! with them, and its own tests (F, BIC, held-out) decide whether the candidate is added.
//!
//! The linearised step costs one Jacobian of the left-out points and a small least-squares
//! fit per candidate; the exact one a fit with the candidate, only for a candidate that the
//! linearised step finds explaining points of several poses.

use std::collections::BTreeSet;

use nalgebra::{DMatrix, DVector};

use super::rejudge::Rejudged;
use super::*;
use crate::calibrate::LeftOut;

/// Fewest poses whose left-out points a candidate must explain: a structure the points
/// share (one lost pose is no structure).
pub const MIN_POSES: usize = 2;

/// Most candidates judged exactly against the left-out points per selection run.
pub const MAX_EXACT: usize = 2;

/// Most candidates (the best of the linearised step) whose explanation the kept points are
/// asked to agree with ([`Kept::agree`]).
pub const MAX_CHECKED: usize = 4;

/// Most rounds of the linearised fit-and-judge of one candidate.
const MAX_ROUNDS: usize = 10;

/// One candidate's linearised explanation of the left-out calibration points.
struct Explains {
    /// Index into the pool.
    effect: usize,
    /// The left-out calibration points (indices into [`LeftOut::prep`]'s `cal`) it brings
    /// within the screen's threshold.
    points: BTreeSet<usize>,
    /// Distinct poses of those points.
    poses: usize,
    /// Its parameter count.
    parameters: usize,
}

/// The remaining candidates (`remaining`, indices into the pool and the model's effects) that
/// explain left-out calibration points of at least [`MIN_POSES`] poses at the fit `x`
/// (linearised: the candidate's columns alone, the geometry as fitted), best first: most
/// points, then fewest parameters; with the points each explains.
///
/// # Errors
/// Those of [`dense`].
fn explaining(
    session: &Session<'_>,
    x: &[f64],
    remaining: &[usize],
    left: &LeftOut,
) -> Result<Vec<(usize, BTreeSet<usize>)>, CalibError> {
    let obs = &left.prep.cal;
    if obs.is_empty() {
        return Ok(Vec::new());
    }
    let effects = session.model.effects();
    let columns: Vec<usize> = remaining
        .iter()
        .filter_map(|&e| effects.get(e).map(|(_, r)| r.clone()))
        .flatten()
        .collect();
    let (j, r, starts) = dense(&session.model, obs, x, &columns, &session.scales)?;
    if j.iter().chain(r.iter()).any(|v| !v.is_finite()) {
        return Ok(Vec::new());
    }
    // Position rows standardised by each point's scale, as the screen judges them.
    let n = obs.len();
    let mut rs = DVector::<f64>::zeros(3 * n);
    let mut js = DMatrix::zeros(3 * n, columns.len());
    for (i, s) in left.cal_scales.iter().enumerate() {
        for a in 0..3 {
            rs[3 * i + a] = r[starts[i] + a] / s[a];
            for c in 0..columns.len() {
                js[(3 * i + a, c)] = j[(starts[i] + a, c)] / s[a];
            }
        }
    }
    let norm = |v: &DVector<f64>, i: usize| v.rows(3 * i, 3).norm();
    let t0: Vec<f64> = (0..n).map(|i| norm(&rs, i)).collect();
    // A gross outlier (a lost beam a hundred sigma off) would pull the first fit: it starts
    // from the points within three times the median's distance.
    let mut sorted = t0.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[n / 2];
    let start: BTreeSet<usize> = (0..n).filter(|&i| t0[i] <= 3.0 * median).collect();
    let mut found = Vec::new();
    let mut at = 0;
    for &e in remaining {
        let k = effects.get(e).map_or(0, |(_, r)| r.len());
        let c = js.columns(at, k).into_owned();
        at += k;
        let mut set = start.clone();
        // Whether the points brought within the threshold settled.
        let mut settled = false;
        for _ in 0..MAX_ROUNDS {
            let rows: Vec<usize> = set.iter().flat_map(|&i| 3 * i..3 * i + 3).collect();
            if rows.len() <= k {
                break;
            }
            let a = c.select_rows(rows.iter());
            let b = DVector::from_iterator(rows.len(), rows.iter().map(|&q| -rs[q]));
            // Normal equations: a column these points do not move leaves no solution.
            let Some(dc) = a.tr_mul(&a).cholesky().map(|f| f.solve(&a.tr_mul(&b))) else {
                break;
            };
            let pred = &rs + &c * &dc;
            let now: BTreeSet<usize> = (0..n)
                .filter(|&i| norm(&pred, i) <= left.threshold)
                .collect();
            if now == set {
                settled = true;
                break;
            }
            set = now;
        }
        let poses: BTreeSet<usize> = set.iter().map(|&i| left.cal_poses[i]).collect();
        let explained_now = set.iter().all(|&i| t0[i] > left.threshold);
        if settled && poses.len() >= MIN_POSES && explained_now && set.len() * 3 > k {
            found.push(Explains {
                effect: e,
                poses: poses.len(),
                points: set,
                parameters: k,
            });
        }
    }
    found.sort_by(|a, b| {
        b.points
            .len()
            .cmp(&a.points.len())
            .then(b.poses.cmp(&a.poses))
            .then(a.parameters.cmp(&b.parameters))
    });
    Ok(found.into_iter().map(|f| (f.effect, f.points)).collect())
}

/// The judgement that gives back the left-out points a candidate explains, when one does
/// (see the module docs): the effects judged against (the `selected` ones and the
/// candidate), the judgement before (`scan`) and the new one; `None` when no candidate gives
/// back points of at least [`MIN_POSES`] poses.
///
/// # Errors
/// Those of [`dense`] and of the screen.
#[allow(clippy::too_many_arguments)]
pub(super) fn left_out_evidence(
    tree: &DhTree,
    data: &Measurements,
    options: &CalibrationOptions,
    session: &Session<'_>,
    x: &[f64],
    pool: &[Arc<dyn Effect>],
    (selected, free): (&[usize], &[usize]),
    scan: Option<&crate::outliers::OutlierReport>,
    alpha: f64,
) -> Result<Option<Rejudged>, CalibError> {
    let (Some(left), Some(scan)) = (&session.left_out, scan) else {
        return Ok(None);
    };
    let remaining: Vec<usize> = (0..pool.len()).filter(|e| !selected.contains(e)).collect();
    let found: Vec<(usize, BTreeSet<usize>)> = explaining(session, x, &remaining, left)?
        .into_iter()
        .take(MAX_CHECKED)
        .collect();
    if found.is_empty() {
        return Ok(None);
    }
    let effects = session.model.effects();
    let ranges: Vec<std::ops::Range<usize>> = found
        .iter()
        .map(|(e, _)| effects.get(*e).map_or(0..0, |(_, r)| r.clone()))
        .collect();
    let Some(kept) = Kept::new(session, x, free, &ranges, left)? else {
        return Ok(None);
    };
    let mut exact = 0;
    for (c, ((e, points), range)) in found.iter().zip(&ranges).enumerate() {
        if exact == MAX_EXACT {
            break;
        }
        if !kept.agree((c, range.len()), points, left, alpha) {
            continue;
        }
        let e = *e;
        exact += 1;
        let with: Vec<Arc<dyn Effect>> = selected
            .iter()
            .chain(std::iter::once(&e))
            .map(|&i| pool[i].clone())
            .collect();
        let again = crate::calibrate::screen_from(tree, data, options, None, &with, Some(scan))?;
        let back: Vec<usize> = scan
            .left_out()
            .difference(&again.left_out())
            .copied()
            .collect();
        let poses: BTreeSet<&str> = back
            .iter()
            .map(|&i| data.samples[i].config.as_deref().unwrap_or(""))
            .collect();
        let posed = back.iter().all(|&i| data.samples[i].config.is_some());
        if (posed && poses.len() >= MIN_POSES) || (!posed && back.len() >= MIN_POSES) {
            return Ok(Some((with, scan.clone(), again)));
        }
    }
    Ok(None)
}

/// The linearised fit at `x` of the kept calibration points and of the left-out ones (the
/// `free` parameters and the columns of a few candidates), for [`Kept::agree`].
struct Kept {
    /// The kept points' residuals less what the free parameters explain (metres).
    r_perp: DVector<f64>,
    /// The candidates' columns (all of `columns`) on the kept points, less what the free
    /// parameters explain.
    c_perp: DMatrix<f64>,
    /// The residual's sigma per coordinate of the kept points (metres).
    sigma: f64,
    /// The left-out points' residuals (metres) and first rows.
    rl: DVector<f64>,
    starts: Vec<usize>,
    /// The candidates' columns on the left-out points, the free parameters following
    /// (`C_L − J_{L,F} R⁻¹ Qᵀ C`).
    cl: DMatrix<f64>,
    /// First column of each candidate's columns in `c_perp` and `cl` (in `ranges`' order).
    offsets: Vec<usize>,
}

impl Kept {
    /// One pass over the kept points for the columns of every candidate (`ranges`, model
    /// columns); `None` when the residual's sigma is zero or a factor fails.
    ///
    /// # Errors
    /// Those of [`dense`].
    fn new(
        session: &Session<'_>,
        x: &[f64],
        free: &[usize],
        ranges: &[std::ops::Range<usize>],
        left: &LeftOut,
    ) -> Result<Option<Kept>, CalibError> {
        let cols: Vec<usize> = ranges.iter().flat_map(|r| r.clone()).collect();
        let offsets: Vec<usize> = ranges
            .iter()
            .scan(0, |at, r| {
                *at += r.len();
                Some(*at - r.len())
            })
            .collect();
        let model = &session.model;
        let (jf, r, _) = dense(model, &session.prep.cal, x, free, &session.scales)?;
        let (jc, _, _) = dense(model, &session.prep.cal, x, &cols, &session.scales)?;
        let all: Vec<usize> = (0..r.len()).collect();
        let projected = Projector::new(&jf, &r, all);
        let qtc = projected.q.tr_mul(&jc);
        let c_perp = &jc - &projected.q * &qtc;
        // How the free parameters follow the candidates': `δ_F = −R⁻¹ Qᵀ C δ_C`.
        let follow = if projected.r.nrows() == 0 {
            DMatrix::zeros(0, cols.len())
        } else {
            match projected.r.solve_upper_triangular(&qtc) {
                Some(b) => b,
                None => return Ok(None),
            }
        };
        let dof = (r.len() as f64 - free.len() as f64).max(1.0);
        let sigma = (projected.r_perp.norm_squared() / dof).sqrt();
        if !(sigma > 0.0 && sigma.is_finite()) {
            return Ok(None);
        }
        let obs = &left.prep.cal;
        let (jlf, rl, starts) = dense(model, obs, x, free, &session.scales)?;
        let (jlc, _, _) = dense(model, obs, x, &cols, &session.scales)?;
        let cl = &jlc - &jlf * &follow;
        Ok(Some(Kept {
            r_perp: projected.r_perp,
            c_perp,
            sigma,
            rl,
            starts,
            cl,
            offsets,
        }))
    }

    /// Whether candidate `candidate` (its place in [`Kept::new`]'s list; `k` parameters) explains the left-out calibration
    /// points `points` (indices into [`LeftOut::prep`]'s `cal`) with the points kept
    /// agreeing: one linearised fit of its parameters, the free ones following, to the kept
    /// points (each coordinate over the residual's sigma) and those left-out points (each
    /// over its screen scale), those brought within the screen's threshold kept in it until
    /// they settle; it must explain points of [`MIN_POSES`] poses or more, none explained
    /// already, while the kept points' sum of squares grows by no more than the
    /// `1 − alpha` quantile of `χ²_k` times the residual variance (`k` its parameters). An
    /// effect that the left-out points alone call for and the kept points reject (a harmonic
    /// as large as a few far-off poses need) is not their explanation.
    fn agree(
        &self,
        (candidate, k): (usize, usize),
        points: &BTreeSet<usize>,
        left: &LeftOut,
        alpha: f64,
    ) -> bool {
        if k == 0 {
            return false;
        }
        let at = self.offsets[candidate];
        let c_perp = self.c_perp.columns(at, k);
        let cl = self.cl.columns(at, k);
        let (rl, sigma) = (&self.rl, self.sigma);
        let row = |i: usize, a: usize| self.starts[i] + a;
        let standardised = |d: &DVector<f64>, i: usize| {
            Vector3::new(
                d[row(i, 0)] / left.cal_scales[i][0],
                d[row(i, 1)] / left.cal_scales[i][1],
                d[row(i, 2)] / left.cal_scales[i][2],
            )
            .norm()
        };
        // Normal equations: the kept points' part once, each left-out point's added.
        let kept_n = c_perp.tr_mul(&c_perp) / (sigma * sigma);
        let kept_g = -(c_perp.tr_mul(&self.r_perp)) / (sigma * sigma);
        let mut set = points.clone();
        let mut value = DVector::zeros(k);
        let mut settled = false;
        for _ in 0..MAX_ROUNDS {
            let mut normal = kept_n.clone();
            let mut g = kept_g.clone();
            for &i in &set {
                for ax in 0..3 {
                    let s2 = left.cal_scales[i][ax].powi(2);
                    let row = cl.row(row(i, ax));
                    normal += row.transpose() * row / s2;
                    g -= row.transpose() * (rl[self.starts[i] + ax] / s2);
                }
            }
            let Some(dc) = normal.cholesky().map(|f| f.solve(&g)) else {
                return false;
            };
            let pred = rl + cl * &dc;
            value = dc;
            let now: BTreeSet<usize> = (0..left.prep.cal.len())
                .filter(|&i| standardised(&pred, i) <= left.threshold)
                .collect();
            if now == set {
                settled = true;
                break;
            }
            set = now;
        }
        let poses: BTreeSet<usize> = set.iter().map(|&i| left.cal_poses[i]).collect();
        let fresh = set.iter().all(|&i| standardised(rl, i) > left.threshold);
        let before = self.r_perp.norm_squared();
        let after = (&self.r_perp + c_perp * &value).norm_squared();
        let bound = crate::outliers::threshold_in(1, alpha, k as f64).powi(2);
        settled
            && poses.len() >= MIN_POSES
            && fresh
            && after.is_finite()
            && after - before <= bound * sigma * sigma
    }
}
