//! The verdict on a fitted session: its residual tested against the noise (chi-square with a
//! known per-axis sigma, or lack of fit against the pure error of repeated poses), and the
//! residual's remaining structure against each joint and the pose order (binned residuals, F
//! tests). The diagnosis ([`crate::diagnose`], steps 1 and 5) and the calibration's final
//! verdict both use these tests. Residuals and noise in metres.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use dh_core::JointKind;
use nalgebra::{DMatrix, Vector3};

use super::{NoiseFloor, Prepared, Session};
use crate::findings::{NoiseTest, ResidualTest, StructureCheck, Verdict};
use crate::fit::{self, FitOutcome};
use crate::model::Observation;
use crate::stats;

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

/// The residual's structure at `fit` (step 5 of the verdict), given the position residuals
/// `res` of every calibration sample at `fit.x` ([`Session::position_residuals`]).
fn structure_checks(
    session: &Session<'_>,
    fit: &FitOutcome,
    alpha: f64,
    res: &[Vector3<f64>],
) -> Vec<StructureCheck> {
    let model = &session.model;
    let prep = &session.prep;
    let rows = model.tree().rows();
    // One unit per pose and target: repeats are averaged, so that the test asks whether the
    // joint explains the lack of fit, not whether there is one (that is the residual test).
    // When every pose group holds one sample (distinct poses, as in most large sets), each
    // unit is that sample and its mean its residual, bit for bit (`(0 + r) / 1` is `r` for
    // every `r` but `-0.0`): the residuals are read as they are, no list of means is made
    // (48 MB and 16 MB of first samples on 2 000 000 poses).
    let singles = prep.group_count == prep.cal.len()
        && res
            .iter()
            .all(|r| r.iter().all(|v| v.to_bits() != (-0.0f64).to_bits()));
    let units = (!singles).then(|| unit_means(prep, res));
    let (means, firsts): (&[Vector3<f64>], Option<&[usize]>) = match &units {
        Some((m, f)) => (m, Some(f)),
        None => (res, None),
    };
    let joints: Vec<usize> = (0..rows.len())
        .filter(|&j| rows[j].mimic.is_none())
        .collect();
    // The gravity lever arms of the joints that have one (see `structure`), read first: their
    // count is part of the Bonferroni level of every test.
    let (picked, levers) = super::structure::gravity_variables(session, firsts, means.len());
    // Each joint, the pose order, time, and each gravity lever arm.
    let k_tests = (joints.len() + 2 + levers.len()) as f64;
    let level = alpha / k_tests;
    // The joints' tests are independent: run on every core, gathered in joint order.
    let check = |j: usize| joint_check(session, fit, j, means, firsts, res, level);
    let mut out: Vec<StructureCheck> =
        match fit::parallel_map(joints.len(), |k| Ok(check(joints[k]))) {
            Ok(c) => c.into_iter().flatten().collect(),
            // Only a lost result gets here (a worker's panic reaches the caller): compute on
            // this thread instead.
            Err(_) => joints.iter().filter_map(|&j| check(j)).collect(),
        };
    for var in &levers {
        let bin = |v: &[f64], m: &[Vector3<f64>]| bins(|| v.iter().copied(), m, 8);
        out.extend(super::structure::lever_check(
            var,
            &picked,
            means,
            fit.free.len(),
            level,
            bin,
        ));
    }
    drop(units);
    // Pose order: pose-mean residuals in order of first appearance, which is the order of
    // the group numbers (`Prepared::groups`); with a sample per group, its residuals.
    let groups = (!singles).then(|| group_means(prep, res));
    let means: &[Vector3<f64>] = groups.as_deref().unwrap_or(res);
    if means.len() >= 4 {
        let a: Vec<f64> = means.windows(2).map(|w| w[0].dot(&w[1])).collect();
        let num: f64 = a.iter().sum();
        let den = a.iter().map(|v| v * v).sum::<f64>().sqrt();
        let z = if den > 0.0 { num / den } else { 0.0 };
        let p = 2.0 * stats::normal_sf(z.abs());
        out.push(StructureCheck {
            variable: "pose order".into(),
            statistic: z,
            p_value: p,
            significant: p < level,
            bins: bins(|| (0..means.len()).map(|i| i as f64), means, 8),
        });
    }
    let bin = |m: &[Vector3<f64>]| bins(|| (0..m.len()).map(|i| i as f64), m, 8);
    out.extend(super::structure::time_check(
        prep,
        means,
        fit.free.len(),
        level,
        bin,
    ));
    out
}

/// The mean residual of each unit of [`structure_checks`] (a pose group's samples of one
/// target, in order of first appearance) and the unit's first sample.
///
/// The unit of each group's first target sits in a slot per group (groups are numbered from
/// 0), other targets of a group in a map: a map entry per unit cost 100 MB on 2 000 000
/// poses. Each unit's sum, count and first sample are lists of their own (40 bytes a unit in
/// one list of tuples); the sums become the means in place.
fn unit_means(prep: &Prepared, res: &[Vector3<f64>]) -> (Vec<Vector3<f64>>, Vec<usize>) {
    let target_of = |o: &crate::model::Observed| match o.observation {
        Observation::Point { target, .. } | Observation::TargetPose { target, .. } => target,
        Observation::Pose(_) => usize::MAX,
    };
    let mut first_unit: Vec<usize> = vec![usize::MAX; prep.group_count];
    let mut unit_of: IndexMap<(usize, usize), usize> = IndexMap::default();
    let mut means: Vec<Vector3<f64>> = Vec::with_capacity(prep.group_count);
    let mut counts: Vec<usize> = Vec::with_capacity(prep.group_count);
    let mut firsts: Vec<usize> = Vec::with_capacity(prep.group_count);
    for (i, o) in prep.cal.iter().enumerate() {
        let t = target_of(o);
        let next = means.len();
        let g = prep.groups[i];
        let u = match first_unit.get_mut(g) {
            Some(slot) if *slot == usize::MAX => {
                *slot = next;
                next
            }
            Some(u) if target_of(&prep.cal[firsts[*u]]) == t => *u,
            _ => *unit_of.entry((g, t)).or_insert(next),
        };
        if u == next {
            means.push(Vector3::zeros());
            counts.push(0);
            firsts.push(i);
        }
        means[u] += res[i];
        counts[u] += 1;
    }
    drop((first_unit, unit_of));
    for (m, &n) in means.iter_mut().zip(&counts) {
        *m /= n as f64;
    }
    (means, firsts)
}

/// The mean residual of each pose group, in group order (metres).
fn group_means(prep: &Prepared, res: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    // A slot per group number (a hash map of millions of groups held 170 MB), the sums
    // becoming the means in place.
    let slots = prep.groups.iter().max().map_or(0, |g| g + 1);
    let mut means: Vec<Vector3<f64>> = vec![Vector3::zeros(); slots];
    let mut counts: Vec<usize> = vec![0; slots];
    for (i, &g) in prep.groups.iter().enumerate() {
        means[g] += res[i];
        counts[g] += 1;
    }
    for (m, &n) in means.iter_mut().zip(&counts) {
        *m /= n.max(1) as f64;
    }
    means
}

/// The test of joint `j` of [`structure_checks`]: whether the pose-mean residuals `means` (of
/// the units whose first samples are `firsts`; unit `u` is sample `u` when `None`) depend on the joint's value, through the
/// basis `1, sin q, cos q, sin 2q, cos 2q` (`1, q, q²` for a prismatic joint), by an F test
/// at `level`; the bins of every sample's residual `res` against the joint.
///
/// The basis and the means are folded a chunk of units at a time into the triangular factor
/// `R = [[R₁₁, R₁₂], [0, R₂₂]]` of `[X | Y]` (`X` the basis, `Y` the means; [`fit::Tsqr`]):
/// `X = Q₁R₁₁` and `Q₁ᵀY = R₁₂`, so the singular values of `X` are those of `R₁₁`, its left
/// singular vectors `Q₁U` (`R₁₁ = U S Vᵀ`), and the part of `Y` they explain
/// `Σ‖uᵢᵀR₁₂‖²` over the resolved ones: the same figures as the singular value decomposition
/// of the whole basis, to rounding, in memory of the factor instead of two matrices the size
/// of the basis.
fn joint_check(
    session: &Session<'_>,
    fit: &FitOutcome,
    j: usize,
    means: &[Vector3<f64>],
    firsts: Option<&[usize]>,
    res: &[Vector3<f64>],
    level: f64,
) -> Option<StructureCheck> {
    let prep = &session.prep;
    let row = &session.model.tree().rows()[j];
    let prismatic = row.kind == JointKind::Prismatic;
    let nb = if prismatic { 3 } else { 5 };
    // The joint's value of every sample, read once (each sample's values sit apart, a
    // cache miss per read of millions of samples): the basis and the bins read them here.
    let values: Vec<f64> = prep
        .cal
        .iter()
        .map(|o| o.q.get(j).copied().unwrap_or(0.0))
        .collect();
    let mut qr = fit::Tsqr::new(nb + 3);
    let mut x = [0.0; 8];
    for (u, mean) in means.iter().enumerate() {
        let v = values[firsts.map_or(u, |f| f[u])];
        x[0] = 1.0;
        if prismatic {
            x[1] = v;
            x[2] = v * v;
        } else {
            x[1] = v.sin();
            x[2] = v.cos();
            x[3] = (2.0 * v).sin();
            x[4] = (2.0 * v).cos();
        }
        x[nb..nb + 3].copy_from_slice(mean.as_slice());
        qr.push(&x[..nb + 3]);
    }
    let r = qr.finish();
    let r11: DMatrix<f64> = r.view((0, 0), (nb, nb)).into_owned();
    let svd = r11.svd(true, false);
    let u = svd.u.as_ref()?;
    let smax = svd.singular_values.max();
    let rank: Vec<usize> = (0..svd.singular_values.len())
        .filter(|&i| svd.singular_values[i] > 1e-9 * smax)
        .collect();
    let mut explained = 0.0;
    for a in 0..3 {
        let y = r.view((0, nb + a), (nb, 1));
        for &i in &rank {
            explained += u.column(i).dot(&y).powi(2);
        }
    }
    let ssr0: f64 = means.iter().map(|v| v.norm_squared()).sum();
    let d1 = (3 * rank.len()) as f64;
    let d2 = (3.0 * means.len() as f64 - fit.free.len() as f64 - d1).max(1.0);
    let f = (explained / d1) / ((ssr0 - explained).max(1e-300) / d2);
    let p = stats::f_sf(f, d1, d2);
    Some(StructureCheck {
        variable: row.name.clone(),
        statistic: f,
        p_value: p,
        significant: p < level,
        bins: bins(|| values.iter().copied(), res, 8),
    })
}

/// A hasher for the integer keys of the pose maps above (rustc's Fx: a rotate, xor and
/// multiply per word): they hold an entry per pose of millions of samples, where SipHash
/// cost a tenth of the checks. Neither map is iterated: the results do not depend on it.
#[derive(Clone, Copy, Default)]
struct IndexHasher(u64);

impl Hasher for IndexHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.add(u64::from(*b));
        }
    }
    fn write_usize(&mut self, n: usize) {
        self.add(n as u64);
    }
}

impl IndexHasher {
    fn add(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(5) ^ v).wrapping_mul(0x517c_c1b7_2722_0a95);
    }
}

type IndexMap<K, V> = HashMap<K, V, BuildHasherDefault<IndexHasher>>;

/// `(centre, RMS, |mean|)` of `res` in `n` equal bins of the values `v()` lists (one per
/// residual, in order; listed twice, not held: millions of them on a large set).
fn bins<I: Iterator<Item = f64>>(
    v: impl Fn() -> I,
    res: &[Vector3<f64>],
    n: usize,
) -> Vec<(f64, f64, f64)> {
    let lo = v().fold(f64::INFINITY, f64::min);
    let hi = v().fold(f64::NEG_INFINITY, f64::max);
    if !(lo.is_finite() && hi.is_finite()) {
        return vec![];
    }
    let w = ((hi - lo) / n as f64).max(1e-12);
    let mut acc = vec![(Vector3::zeros(), 0.0, 0usize); n];
    for (x, r) in v().zip(res) {
        let b = (((x - lo) / w) as usize).min(n - 1);
        acc[b].0 += r;
        acc[b].1 += r.norm_squared();
        acc[b].2 += 1;
    }
    acc.into_iter()
        .enumerate()
        .filter(|(_, a)| a.2 > 0)
        .map(|(b, (s, ss, c))| {
            (
                lo + (b as f64 + 0.5) * w,
                (ss / c as f64).sqrt(),
                (s / c as f64).norm(),
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::{Measurements, Sample};
    use crate::tree::DhTree;

    /// With a sample per pose group, the unit and group means are the residuals bit for bit,
    /// which `structure_checks` then reads as they are; with repeats they are averages.
    #[test]
    fn single_sample_groups_have_their_residuals_as_means() {
        let tree = DhTree::serial(&crate::test_robots::ur5());
        let data = |configs: &[&str]| {
            Measurements::test_ur5(
                configs
                    .iter()
                    .enumerate()
                    .map(|(i, c)| Sample {
                        config: Some((*c).into()),
                        ..Sample::test_point(
                            &[0.1 * i as f64, 0.1, 0.2, 0.3, 0.4, 0.5],
                            Vector3::new(0.1, 0.2, 0.3),
                            i + 2,
                        )
                    })
                    .collect(),
            )
        };
        let res: Vec<Vector3<f64>> = (0..5)
            .map(|i| Vector3::new(1e-4 / (i as f64 + 3.0), -7e-5 * (i as f64 + 1.0), 0.1 / 3.0))
            .collect();
        let bits = |v: &[Vector3<f64>]| -> Vec<u64> {
            v.iter()
                .flat_map(|r| r.iter().map(|x| x.to_bits()).collect::<Vec<_>>())
                .collect()
        };
        let prep =
            crate::prepare::prepare(&tree, &data(&["a", "b", "c", "d", "e"]), None, false).unwrap();
        assert_eq!(prep.group_count, prep.cal.len());
        let (means, firsts) = unit_means(&prep, &res);
        assert_eq!(bits(&means), bits(&res));
        assert_eq!(firsts, vec![0, 1, 2, 3, 4]);
        assert_eq!(bits(&group_means(&prep, &res)), bits(&res));
        // The one exception, which `structure_checks` looks for: a mean of -0.0 is 0.0.
        let mut signed = res.clone();
        signed[1].y = -0.0;
        assert_eq!(
            unit_means(&prep, &signed).0[1].y.to_bits(),
            0.0f64.to_bits()
        );
        // Repeats: "a" twice, "b" twice, "c" once.
        let prep =
            crate::prepare::prepare(&tree, &data(&["a", "b", "a", "c", "b"]), None, false).unwrap();
        let (means, firsts) = unit_means(&prep, &res);
        assert_eq!(firsts, vec![0, 1, 3]);
        assert_eq!(means[0], (res[0] + res[2]) / 2.0);
        assert_eq!(means[1], (res[1] + res[4]) / 2.0);
        assert_eq!(means[2], res[3]);
        assert_eq!(group_means(&prep, &res), means);
    }
}
