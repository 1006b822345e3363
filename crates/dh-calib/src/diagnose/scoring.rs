//! Scoring and judging candidates (module docs, steps 2 to 4): the candidates' columns
//! projected off the estimated parameters' column space (aliasing, first-order SSR
//! reduction), the F-to-enter test, BIC `m ln(SSR/m) + p ln m`, and the one-sided paired
//! Wilcoxon signed-rank test of held-out squared errors (metres squared; a 6-DoF sample's
//! orientation error weighed in as in the fit, `sigma / sigma_rot` metres per radian).

use super::*;
use crate::calibrate::HeldOut;

/// The scaled Jacobian, the residuals and the first row of each observation.
pub(crate) type Dense = (DMatrix<f64>, DVector<f64>, Vec<usize>);

/// Stacks the scaled Jacobian of `columns` and the residuals of `obs` at `x`; returns them
/// with the first row of each observation (the rows made on the machine's cores,
/// [`crate::calibrate::sample_rows`]).
///
/// # Errors
/// [`CalibError::NonFinite`] when a worker thread lost its result.
pub(crate) fn dense(
    model: &Model,
    obs: &[Observed],
    x: &[f64],
    columns: &[usize],
    scales: &[f64],
) -> Result<Dense, CalibError> {
    let mut starts = Vec::with_capacity(obs.len() + 1);
    starts.push(0);
    for o in obs {
        starts.push(starts[starts.len() - 1] + o.observation.residual_count());
    }
    let m = starts[obs.len()];
    let n = columns.len();
    let mut j = DMatrix::zeros(m, n);
    let mut r = DVector::zeros(m);
    let column_scales: Vec<f64> = columns.iter().map(|&c| scales[c]).collect();
    let filled =
        crate::calibrate::sample_rows(model, obs, x, columns, &starts, |first, res, jac| {
            let row = starts[first];
            for (i, &v) in res.iter().enumerate() {
                r[row + i] = v;
                for (k, &s) in column_scales.iter().enumerate() {
                    j[(row + i, k)] = jac[i * n + k] * s;
                }
            }
        });
    filled.ok_or_else(|| CalibError::NonFinite {
        what: "a worker thread lost its result".into(),
    })?;
    starts.pop();
    Ok((j, r, starts))
}

/// Least squares of `r + J_F δ_F + C δ_C` on a subset of rows, through the QR of `J_F`.
pub(crate) struct Projector {
    pub(super) q: DMatrix<f64>,
    pub(super) r: DMatrix<f64>,
    pub(super) qtr: DVector<f64>,
    /// The residuals of the rows, less what `J_F` explains.
    pub(super) r_perp: DVector<f64>,
    pub(super) rows: Vec<usize>,
    /// All rows, in order (no selection needed).
    pub(super) all: bool,
}

impl Projector {
    pub(crate) fn new(jf: &DMatrix<f64>, res: &DVector<f64>, rows: Vec<usize>) -> Projector {
        let sub = jf.select_rows(rows.iter());
        let rr = res.select_rows(rows.iter());
        let (q, r) = if sub.ncols() == 0 {
            (DMatrix::zeros(rows.len(), 0), DMatrix::zeros(0, 0))
        } else {
            let qr = sub.qr();
            (qr.q(), qr.r())
        };
        let qtr = q.tr_mul(&rr);
        let r_perp = &rr - &q * &qtr;
        let all = rows.iter().enumerate().all(|(i, &r)| i == r) && rows.len() == res.len();
        Projector {
            q,
            r,
            qtr,
            r_perp,
            rows,
            all,
        }
    }

    /// `(δ_F, δ_C, reduction, independence)` for candidate columns `c` (all rows);
    /// independence is NaN when the columns are zero.
    pub(crate) fn solve(&self, c: &DMatrix<f64>) -> (DVector<f64>, DVector<f64>, f64, f64) {
        let selected;
        let cs = if self.all {
            c
        } else {
            selected = c.select_rows(self.rows.iter());
            &selected
        };
        let qtc = self.q.tr_mul(cs);
        let c_perp = cs - &self.q * &qtc;
        let r_perp = &self.r_perp;
        let k = c.ncols();
        let mut dc = DVector::zeros(k);
        let mut reduction = 0.0;
        let mut independence = 1.0;
        if k > 0 {
            let big = (0..k).map(|j| cs.column(j).norm()).fold(0.0, f64::max);
            let svd = c_perp.clone().svd(true, true);
            let smin = svd.singular_values.min();
            independence = if big > 0.0 { smin / big } else { f64::NAN };
            if let (Some(u), Some(vt)) = (&svd.u, &svd.v_t) {
                let smax = svd.singular_values.max();
                for i in 0..svd.singular_values.len() {
                    let s = svd.singular_values[i];
                    if s > 1e-12 * smax.max(1e-300) && s > 0.0 {
                        let coef = u.column(i).dot(r_perp);
                        reduction += coef * coef;
                        dc -= vt.row(i).transpose() * (coef / s);
                    }
                }
            }
        }
        let rhs = -(&self.qtr + &qtc * &dc);
        let df = if self.r.nrows() == 0 {
            DVector::zeros(0)
        } else {
            self.r
                .solve_upper_triangular(&rhs)
                .unwrap_or_else(|| DVector::zeros(rhs.len()))
        };
        (df, dc, reduction, independence)
    }
}

/// A judged refit and, when it ran, its step with the free and held parameters.
pub(super) type Attempt = (
    Trial,
    Option<(
        crate::calibrate::StepResult,
        Vec<usize>,
        Vec<crate::fit::Fixed>,
    )>,
);

pub(super) struct Scored {
    pub(super) candidates: Vec<(usize, CandidateReport)>,
    pub(super) baseline_val: Option<f64>,
    pub(super) residuals: usize,
}

pub(super) fn distances_of(res: &DVector<f64>, starts: &[usize], idx: &[usize]) -> Vec<f64> {
    idx.iter()
        .map(|&i| {
            let s = starts[i];
            Vector3::new(res[s], res[s + 1], res[s + 2]).norm()
        })
        .collect()
}

pub(super) fn rms(d: &[f64]) -> Option<f64> {
    (!d.is_empty()).then(|| (d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64).sqrt())
}

/// Scores every candidate in `remaining` at `x` with `free` estimated (see the module docs).
pub(super) fn score(
    session: &Session<'_>,
    x: &[f64],
    free: &[usize],
    remaining: &[usize],
) -> Result<Scored, CalibError> {
    let model = &session.model;
    let effects = model.effects();
    let p = free.len();
    let prep = &session.prep;
    let non_finite = || CalibError::NonFinite {
        what: "candidate scoring".into(),
    };
    let (jf, r, starts) = dense(model, &prep.cal, x, free, &session.scales)?;
    if jf.iter().chain(r.iter()).any(|v| !v.is_finite()) {
        return Err(non_finite());
    }
    let all_rows: Vec<usize> = (0..r.len()).collect();
    let full = Projector::new(&jf, &r, all_rows);
    // A candidate with a shape grid (a time constant) is scored by its amplitude's column at
    // the grid's best shape, set in `at` (its amplitude is 0 there, so nothing else moves);
    // it still counts all its parameters.
    let span = crate::calibrate::sequence_span(&prep.cal);
    let mut at = x.to_vec();
    let mut columns = free.to_vec();
    let mut spans = Vec::with_capacity(remaining.len());
    for &e in remaining {
        let start = columns.len();
        if let Some((effect, range)) = effects.get(e) {
            let grid = effect.shape_grid(span);
            if grid.is_empty() || range.len() < 2 {
                columns.extend(range.clone());
            } else {
                let solve = |c: &DMatrix<f64>| {
                    let (_, dc, reduction, _) = full.solve(c);
                    (dc.get(0).copied().unwrap_or(0.0), reduction)
                };
                let best = crate::calibrate::best_shape(
                    (model, effect.as_ref()),
                    &prep.cal,
                    x,
                    range,
                    (&grid, &session.scales),
                    &solve,
                )?;
                if let Some(b) = best {
                    at[range.start + 1] = b.shape;
                }
                columns.push(range.start);
            }
        }
        spans.push(start..columns.len());
    }
    let x = &at[..];
    let (jc, _, _) = dense(model, &prep.cal, x, &columns[p..], &session.scales)?;
    if jc.iter().any(|v| !v.is_finite()) {
        return Err(non_finite());
    }
    let mut j = DMatrix::zeros(r.len(), columns.len());
    j.columns_mut(0, p).copy_from(&jf);
    j.columns_mut(p, columns.len() - p).copy_from(&jc);
    // Held-out predictions, linearised.
    enum Held {
        Split {
            jv: DMatrix<f64>,
            rv: DVector<f64>,
            starts: Vec<usize>,
            locate: Vec<(Vec<usize>, Vec<nalgebra::Matrix3<f64>>)>,
        },
        Folds(FoldNormals),
        None,
    }
    // Rows of each sample, by its first row.
    let mut size_by_start = vec![0usize; r.len()];
    for (i, &s) in starts.iter().enumerate() {
        size_by_start[s] = starts.get(i + 1).copied().unwrap_or(r.len()) - s;
    }
    let size_at = |s: usize| size_by_start[s];
    let held = match &session.validation {
        Validation::Split { .. } => {
            let val = crate::sessions::val_for_linearisation(model, x, prep);
            let (jv, rv, sv) = dense(model, &val, x, &columns, &session.scales)?;
            let locate = crate::calibrate::validation_locations(model, x, prep);
            Held::Split {
                jv,
                rv,
                starts: sv,
                locate,
            }
        }
        Validation::CrossValidation { folds, .. } => {
            let mut of_fold = vec![Vec::new(); *folds];
            for (i, g) in prep.groups.iter().enumerate() {
                of_fold[g % folds].push(starts[i]);
            }
            Held::Folds(FoldNormals::new(&jf, &r, &of_fold, size_at))
        }
        Validation::None => Held::None,
    };
    let predict = |c_span: Option<std::ops::Range<usize>>,
                   c: &DMatrix<f64>,
                   fit: &(DVector<f64>, DVector<f64>, f64, f64)|
     -> Option<f64> {
        match &held {
            Held::Split {
                jv,
                rv,
                starts,
                locate,
            } => {
                let (df, dc) = (&fit.0, &fit.1);
                let mut pred = rv + jv.columns(0, p) * df;
                if let Some(s) = &c_span {
                    pred += jv.columns(s.start, s.len()) * dc;
                }
                // Targets only the validation measured: located from their own samples first.
                for (samples, rotations) in locate {
                    let mut sum = Vector3::zeros();
                    for (&i, rot) in samples.iter().zip(rotations) {
                        sum += rot.transpose() * pred.fixed_rows::<3>(starts[i]);
                    }
                    let offset = sum / samples.len() as f64;
                    for (&i, rot) in samples.iter().zip(rotations) {
                        let mut row = pred.fixed_rows_mut::<3>(starts[i]);
                        row -= rot * offset;
                    }
                }
                let idx: Vec<usize> = (0..starts.len()).collect();
                rms(&distances_of(&pred, starts, &idx))
            }
            Held::Folds(normals) => rms(&normals.distances(c, size_at)),
            Held::None => None,
        }
    };
    let empty = DMatrix::zeros(r.len(), 0);
    let baseline_val = predict(None, &empty, &full.solve(&empty));
    // How far each row's joint moved in the calibration data (radians or metres).
    let rows = model.tree().rows();
    let mut travel = vec![(f64::INFINITY, f64::NEG_INFINITY); rows.len()];
    for o in &prep.cal {
        for (t, &q) in travel.iter_mut().zip(o.q.iter()) {
            *t = (t.0.min(q), t.1.max(q));
        }
    }
    let still = |name: &str| {
        rows.iter()
            .position(|r| r.name == name)
            .and_then(|k| travel.get(k))
            .is_some_and(|(lo, hi)| hi - lo < MIN_JOINT_MOTION)
    };
    // Each candidate is judged on its own, so the candidates are spread over the cores; the
    // table is in `remaining`'s order whatever the number of threads.
    let out = crate::fit::parallel_map(remaining.len(), |i| {
        let (e, span) = (remaining[i], &spans[i]);
        let c = j.columns(span.start, span.len()).into_owned();
        let fit = full.solve(&c);
        let (reduction, independence) = (fit.2, fit.3);
        // A coupling between joints of which one hardly moves is no coupling these data can
        // show (a torso held still would "couple" with whatever stands in for its deflection).
        let static_coupling = effects.get(e).is_some_and(|(eff, _)| {
            eff.label()
                .strip_prefix("coupling:")
                .and_then(|rest| rest.split_once(':'))
                .is_some_and(|(joint, driver)| still(joint) || still(driver))
        });
        // A direction backlash of a joint that hardly reverses is an offset change between
        // blocks of poses (see `effects_order::MIN_REVERSALS`).
        let one_way = effects.get(e).is_some_and(|(eff, _)| {
            eff.label()
                .strip_prefix("backlash_direction:")
                .and_then(|name| rows.iter().position(|r| r.name == name))
                .is_some_and(|k| {
                    !crate::effects_order::reverses(prep.cal.iter().map(|o| &o.context), k)
                })
        });
        let inert = independence.is_nan() || static_coupling || one_way;
        let aliased = !inert && independence < ALIAS_SINE;
        let val_rms = if aliased || inert {
            None
        } else {
            predict(Some(span.clone()), &c, &fit)
        };
        let label = effects
            .get(e)
            .map(|(eff, _)| eff.label())
            .unwrap_or_default();
        Ok((
            e,
            CandidateReport {
                label,
                parameters: effects
                    .get(e)
                    .map_or(span.len(), |(eff, _)| eff.parameter_names().len()),
                score: if aliased || inert { 0.0 } else { reduction },
                independence: if inert { 0.0 } else { independence },
                val_rms,
                reason: None,
                status: if inert {
                    CandidateStatus::Inert
                } else if aliased {
                    CandidateStatus::Aliased
                } else {
                    CandidateStatus::NotSelected
                },
            },
        ))
    })?;
    Ok(Scored {
        candidates: out,
        baseline_val,
        residuals: r.len(),
    })
}

/// BIC of a least-squares fit: `m ln(SSR/m) + p ln m` (`m` residuals, `p` parameters).
pub(crate) fn bic(ssr: f64, m: f64, p: f64) -> f64 {
    m * (ssr.max(1e-300) / m).ln() + p * m.ln()
}

/// The tests of the rule for one refit (see the module docs).
#[allow(clippy::too_many_arguments)]
pub(super) fn judge(
    session: &Session<'_>,
    before: &FitOutcome,
    held_before: &HeldOut,
    after: &FitOutcome,
    held_after: &HeldOut,
    k: usize,
    k_count: usize,
    alpha: f64,
    forced: bool,
    label: String,
    step: &StepReport,
) -> Trial {
    let m = after.residual_count as f64;
    let (p0, p1) = (before.free.len() as f64, after.free.len() as f64);
    let dof = (m - p1).max(1.0);
    let f = ((before.ssr - after.ssr) / k as f64) / (after.ssr / dof).max(1e-300);
    let f_p = stats::f_sf(f, k as f64, dof);
    let f_threshold = alpha / k_count as f64;
    let bic = (bic(before.ssr, m, p0), bic(after.ssr, m, p1));
    let groups = match session.validation {
        Validation::Split { .. } => Some(&session.prep.val_groups),
        Validation::CrossValidation { .. } => Some(&session.prep.groups),
        Validation::None => None,
    };
    // A 6-DoF sample's error weighs its orientation in, as the fit does (each part over its
    // own sigma): an effect the angles show and the positions hardly do must pass here too.
    // With a validation split, the left-out validation points that either fit explains are
    // compared too, over the same points for both (see [`crate::calibrate::LeftOut`]): a
    // held-out pose that only this candidate's effect explains is its best evidence.
    let held_out = groups.and_then(|g| {
        let (mut b, mut a) = (held_before.weighed(), held_after.weighed());
        let left = match (&session.validation, &session.left_out) {
            (Validation::Split { .. }, Some(left)) => {
                left.explained_validation(&session.model, &before.x, &after.x)
            }
            _ => Default::default(),
        };
        if left.2.is_empty() {
            return paired_wilcoxon(&b, &a, g);
        }
        b.extend(left.0);
        a.extend(left.1);
        let groups: Vec<usize> = g.iter().copied().chain(left.2).collect();
        paired_wilcoxon(&b, &a, &groups)
    });
    let mut reasons = Vec::new();
    if !forced {
        if f_p.is_nan() || f_p >= f_threshold {
            reasons.push(format!("F-to-enter p = {f_p:.2e} >= {f_threshold:.2e}"));
        }
        if bic.1.is_nan() || bic.1 >= bic.0 {
            reasons.push("BIC does not decrease".to_string());
        }
        match held_out {
            Some((_, p)) if p < alpha => {}
            Some((_, p)) => reasons.push(format!("held-out improvement p = {p:.2e} >= {alpha}")),
            None if groups.is_some() => {
                reasons.push("held-out improvement cannot be tested".to_string())
            }
            None => {}
        }
    }
    Trial {
        label,
        rms: step.rms,
        val_rms: step.val_rms,
        f,
        f_p,
        f_threshold,
        bic,
        held_out,
        accepted: reasons.is_empty(),
        reason: reasons.join("; "),
    }
}

/// One-sided Wilcoxon signed-rank test that `after` is smaller than `before`, paired over the
/// groups of the samples (per group `Σ d_before² − d_after²`; zero differences dropped, ties
/// given mid-ranks, normal approximation with the tie correction; F. Wilcoxon, "Individual
/// comparisons by ranking methods", Biometrics Bulletin 1(6), 1945). Returns `(z, p)`;
/// `None` with fewer than 6 non-zero differences. Ranks rather than a t test because a few
/// poses that an effect fixes dominate the squared errors and make a t statistic erratic.
pub(crate) fn paired_wilcoxon(
    before: &[f64],
    after: &[f64],
    groups: &[usize],
) -> Option<(f64, f64)> {
    if before.len() != after.len() || before.len() != groups.len() || before.is_empty() {
        return None;
    }
    let mut sums: HashMap<usize, f64> = HashMap::new();
    for ((b, a), g) in before.iter().zip(after).zip(groups) {
        *sums.entry(*g).or_insert(0.0) += b * b - a * a;
    }
    let scale = sums.values().map(|v| v.abs()).fold(0.0, f64::max);
    let mut d: Vec<f64> = sums
        .into_values()
        .filter(|v| v.abs() > 1e-12 * scale)
        .collect();
    let n = d.len();
    if n < 6 {
        return None;
    }
    d.sort_by(|x, y| x.abs().total_cmp(&y.abs()));
    let (mut w_plus, mut ties) = (0.0, 0.0);
    let mut i = 0;
    while i < n {
        let mut k = i;
        while k + 1 < n && d[k + 1].abs() == d[i].abs() {
            k += 1;
        }
        let rank = (i + k) as f64 / 2.0 + 1.0;
        let t = (k - i + 1) as f64;
        ties += t * t * t - t;
        for v in &d[i..=k] {
            if *v > 0.0 {
                w_plus += rank;
            }
        }
        i = k + 1;
    }
    let nf = n as f64;
    let mean = nf * (nf + 1.0) / 4.0;
    let var = nf * (nf + 1.0) * (2.0 * nf + 1.0) / 24.0 - ties / 48.0;
    if var <= 0.0 {
        return None;
    }
    let z = (w_plus - mean) / var.sqrt();
    Some((z, stats::normal_sf(z)))
}
