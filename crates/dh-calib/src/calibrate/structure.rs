//! Structure tests of the residual against variables other than one joint's value (step 5 of
//! the verdict, beside the joints' and the pose order's in `verdict`): smooth trends in time
//! and the gravity lever arm of each joint. Residuals in metres.
//!
//! # Time
//! The samples carry no clock: the **pose order stands for time**, each pose group at
//! `s = 2 g / (G − 1) − 1` in `[−1, 1]` (`g` its number in order of first appearance, `G`
//! the groups; a session measured at a steady pace). The lag-1 test of `verdict` sees
//! residuals that resemble their neighbours; a warm-up does not show there, because its
//! residual `(g(t) − ḡ) · p` points where the target is, which changes from pose to pose.
//! This test regresses the pose-mean residuals `r̄_g` (3 rows per group) on a smooth trend
//! and on a length change growing smoothly in time:
//!
//! ```text
//! r̄_g ≈ Σ_{k=0..3} c_k P_k(s_g) + Σ_{k=1..3} λ_k P_k(s_g) (p_g − p̄)
//! ```
//!
//! `P_k` the Legendre polynomials (a cubic: a trend, an exponential's bend and its approach
//! to a plateau), `c_k` vectors (a drift of the device's translation), `λ_k` scalars (the
//! robot's or the device's lengths changing in time: a thermal growth), `p_g` the group's mean
//! measured position and `p̄` their mean (metres). F test of the explained part on its rank
//! against what is left, the degrees of freedom reduced by the parameters fitted, as the
//! joints' tests (N. R. Draper, H. Smith, *Applied Regression Analysis*, 3rd ed., 1998,
//! §6.1 for the polynomial, §2.1 for the F test). Variable `time`; its bins are over the
//! pose index.
//!
//! # Gravity lever arms
//! A link sagging under its own weight moves the tip along gravity by an amount that grows
//! with the load's lever arm (a cantilever's deflection goes as the cube of its length), a
//! function of several joints at once that no single joint's test resolves. For each revolute
//! joint `j` the lever arm of the tip about its axis under gravity (metres),
//!
//! ```text
//! l_j = z_j · ((p − o_j) × ĝ),   ĝ = −z of the robot's base link frame,
//! ```
//!
//! (`o_j`, `z_j` the axis' point and direction, `p` the tip's origin, all at the nominal
//! geometry in the base link frame; the torque of a unit weight at the tip), is a variable:
//! the pose-mean residuals (per target, as the joints' tests) are regressed on `1, l, l², l³`
//! (`l` in units of the arm's size), per device axis, F test as the joints'. A joint whose
//! lever arm stays below [`MIN_LEVER`] of the arm's size over the poses (a vertical axis)
//! has no test. Variable `gravity lever at <joint>`. Serial robots only (a tree's branches
//! carry their own tips).

use dh_core::{Convention, DhTable, JointKind};
use nalgebra::{DMatrix, Vector3};

use super::{Prepared, Session};
use crate::findings::StructureCheck;
use crate::fit;
use crate::model::Observation;
use crate::stats;

/// A joint whose gravity lever arm has an RMS over the poses below this fraction of the arm's
/// size gets no lever test (its axis is vertical or runs through the tip): the residual cannot
/// depend on a variable that does not vary.
pub(crate) const MIN_LEVER: f64 = 0.05;

/// Beyond this many units (pose means per target for the lever tests, pose groups for the
/// time test) the tests read an evenly spaced subset of them: a lever arm costs a forward
/// kinematics per unit and the time test a row of 16 columns per axis, and millions of poses
/// would add seconds to the verdict for a statistic that a fraction of them resolves (the
/// degrees of freedom of the parameters fitted are charged to the subset in proportion).
const UNITS_MAX: usize = 50_000;

/// The degree of the time trend's polynomial.
const TIME_DEGREE: usize = 3;

/// The measured position of a calibration observation (metres, device frame).
fn measured(o: &crate::model::Observed) -> Vector3<f64> {
    match &o.observation {
        Observation::Point { point, .. } => *point,
        Observation::Pose(p) => p.translation.vector,
        Observation::TargetPose { pose, .. } => pose.translation.vector,
    }
}

/// Legendre polynomials `P_0 .. P_3` at `s`.
fn legendre(s: f64) -> [f64; TIME_DEGREE + 1] {
    [
        1.0,
        s,
        0.5 * (3.0 * s * s - 1.0),
        0.5 * (5.0 * s * s * s - 3.0 * s),
    ]
}

/// The F test of `qr`'s factor of `[X | Y]` (`nb` basis columns, `ny` observation columns):
/// the part of `Y` that `X`'s resolved directions explain, over its rank, against the rest
/// (`ss_total` the sum of squares of `Y`, `rows` the scalar rows, `free` the parameters
/// fitted). Returns `(F, p)`, `None` without a resolved direction.
fn f_test(
    r: &DMatrix<f64>,
    nb: usize,
    ny: usize,
    ss_total: f64,
    rows: usize,
    free: usize,
    per_column: bool,
) -> Option<(f64, f64)> {
    let r11: DMatrix<f64> = r.view((0, 0), (nb, nb)).into_owned();
    let svd = r11.svd(true, false);
    let u = svd.u.as_ref()?;
    let smax = svd.singular_values.max();
    if smax <= 0.0 {
        return None;
    }
    let rank: Vec<usize> = (0..svd.singular_values.len())
        .filter(|&i| svd.singular_values[i] > 1e-9 * smax)
        .collect();
    let mut explained = 0.0;
    for a in 0..ny {
        let y = r.view((0, nb + a), (nb, 1));
        for &i in &rank {
            explained += u.column(i).dot(&y).powi(2);
        }
    }
    // With one basis per observation column (a device axis each), each column spends the
    // basis' rank.
    let d1 = (rank.len() * if per_column { ny } else { 1 }) as f64;
    let d2 = (rows as f64 - free as f64 - d1).max(1.0);
    let f = (explained / d1) / ((ss_total - explained).max(1e-300) / d2);
    Some((f, stats::f_sf(f, d1, d2)))
}

/// The time test (see the module docs) of the pose-group means `means` (group order) of the
/// residuals `res`, at `level`; `None` with fewer than 8 groups (no cubic trend to resolve
/// beside the geometry).
pub(super) fn time_check(
    prep: &Prepared,
    means: &[Vector3<f64>],
    free: usize,
    level: f64,
    bins: impl Fn(&[Vector3<f64>]) -> Vec<(f64, f64, f64)>,
) -> Option<StructureCheck> {
    let groups = means.len();
    if groups < 8 {
        return None;
    }
    // Every `step`-th group, and each picked group's mean measured position (as its mean
    // residual).
    let step = groups.div_ceil(UNITS_MAX).max(1);
    let picked = groups.div_ceil(step);
    let mut points = vec![Vector3::zeros(); picked];
    let mut counts = vec![0usize; picked];
    for (o, &g) in prep.cal.iter().zip(&prep.groups) {
        if g % step == 0 {
            if let Some(p) = points.get_mut(g / step) {
                *p += measured(o);
                counts[g / step] += 1;
            }
        }
    }
    for (p, &n) in points.iter_mut().zip(&counts) {
        *p /= n.max(1) as f64;
    }
    let centre = points.iter().sum::<Vector3<f64>>() / picked as f64;
    let nb = 3 * (TIME_DEGREE + 1) + TIME_DEGREE;
    let mut qr = fit::Tsqr::new(nb + 1);
    let mut row = vec![0.0; nb + 1];
    let mut ss = 0.0;
    for (k, p) in points.iter().enumerate() {
        let g = k * step;
        let mean = means[g];
        ss += mean.norm_squared();
        let s = 2.0 * g as f64 / (groups - 1) as f64 - 1.0;
        let poly = legendre(s);
        let d = p - centre;
        for a in 0..3 {
            row.iter_mut().for_each(|v| *v = 0.0);
            for (k, pk) in poly.iter().enumerate() {
                row[a * (TIME_DEGREE + 1) + k] = *pk;
            }
            for k in 1..=TIME_DEGREE {
                row[3 * (TIME_DEGREE + 1) + k - 1] = poly[k] * d[a];
            }
            row[nb] = mean[a];
            qr.push(&row);
        }
    }
    let r = qr.finish();
    let share = (free as f64 * picked as f64 / groups as f64).round() as usize;
    let (f, p) = f_test(&r, nb, 1, ss, 3 * picked, share, false)?;
    Some(StructureCheck {
        variable: "time".into(),
        statistic: f,
        p_value: p,
        significant: p < level,
        bins: bins(means),
    })
}

/// The joints of `session`'s robot whose gravity lever arm varies enough to be tested, with
/// each unit's lever arm (metres; the unit's first sample's joint values): `(row, levers)`.
/// `units` are the first samples of the units (`None`: unit `u` is sample `u`). Empty for a
/// tree.
pub(super) fn lever_arms(
    session: &Session<'_>,
    units: Option<&[usize]>,
    count: usize,
) -> (Vec<usize>, Vec<(usize, Vec<f64>)>) {
    let tree = session.model.tree();
    if !tree.branches().is_empty() || count == 0 {
        return (Vec::new(), Vec::new());
    }
    let table: &DhTable = tree.trunk();
    let rows = &table.rows;
    let step = count.div_ceil(UNITS_MAX).max(1);
    let picked: Vec<usize> = (0..count).step_by(step).collect();
    let mut levers: Vec<Vec<f64>> = vec![Vec::with_capacity(picked.len()); rows.len()];
    for &u in &picked {
        let i = units.map_or(u, |f| f[u]);
        // A sample whose joint values the table cannot take (none reach here: the model
        // checked them) has no lever arm: 0 keeps the lists aligned with `picked`.
        let frames = session
            .prep
            .cal
            .get(i)
            .and_then(|o| table.frames(&o.q).ok());
        let Some(frames) = frames else {
            levers.iter_mut().for_each(|l| l.push(0.0));
            continue;
        };
        let tip = frames[rows.len()] * table.tool;
        for (j, r) in rows.iter().enumerate() {
            let axis = match table.convention {
                Convention::Standard => frames[j],
                Convention::Modified => frames[j + 1],
            };
            let l = if r.kind == JointKind::Revolute {
                let z = axis.rotation * Vector3::z();
                let arm = tip.translation.vector - axis.translation.vector;
                z.dot(&arm.cross(&-Vector3::z()))
            } else {
                0.0
            };
            levers[j].push(l);
        }
    }
    let size = table.size().max(f64::MIN_POSITIVE);
    let tested = levers
        .into_iter()
        .enumerate()
        .filter(|(j, l)| {
            rows[*j].mimic.is_none()
                && !l.is_empty()
                && (l.iter().map(|v| v * v).sum::<f64>() / l.len() as f64).sqrt()
                    >= MIN_LEVER * size
        })
        .collect();
    (picked, tested)
}

/// The lever test of joint `row` (see the module docs): the unit means `means` at the units
/// `picked` (indices into `means`) against the lever arms `levers` (metres, one per picked
/// unit), F test at `level`; the bins of the picked units' means against the lever arm.
#[allow(clippy::too_many_arguments)]
pub(super) fn lever_check(
    session: &Session<'_>,
    row: usize,
    picked: &[usize],
    levers: &[f64],
    means: &[Vector3<f64>],
    free: usize,
    level: f64,
    bins: impl Fn(&[f64], &[Vector3<f64>]) -> Vec<(f64, f64, f64)>,
) -> Option<StructureCheck> {
    let size = session.model.tree().trunk().size().max(f64::MIN_POSITIVE);
    let nb = 4;
    let mut qr = fit::Tsqr::new(nb + 3);
    let mut x = [0.0; 7];
    let mut picked_means = Vec::with_capacity(picked.len());
    for (&u, &l) in picked.iter().zip(levers) {
        let m = means.get(u)?;
        let v = l / size;
        x[0] = 1.0;
        x[1] = v;
        x[2] = v * v;
        x[3] = v * v * v;
        x[4..7].copy_from_slice(m.as_slice());
        qr.push(&x);
        picked_means.push(*m);
    }
    let r = qr.finish();
    let ss: f64 = picked_means.iter().map(|v| v.norm_squared()).sum();
    // The parameters fitted are spread over all units; a subset carries its share.
    let share = (free as f64 * picked.len() as f64 / means.len().max(1) as f64).round() as usize;
    let (f, p) = f_test(&r, nb, 3, ss, 3 * picked.len(), share, true)?;
    Some(StructureCheck {
        variable: format!("gravity lever at {}", session.model.tree().rows()[row].name),
        statistic: f,
        p_value: p,
        significant: p < level,
        bins: bins(levers, &picked_means),
    })
}
