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
//! l_j = z_j · ((p − o_j) × ĝ),   ĝ the unit gravity direction of the base link frame,
//! ```
//!
//! (`o_j`, `z_j` the axis' point and direction, `p` the tip's origin, all at the nominal
//! geometry in the base link frame; the torque of a unit weight at the tip; `ĝ` from
//! [`super::CalibrationOptions::gravity`], `--gravity`, else `−z`), is a variable: the
//! pose-mean residuals (per target, as the joints' tests) are regressed on `1, l, l², l³`
//! (`l` in units of the arm's size), per device axis, F test as the joints'. A joint whose
//! lever arm stays below [`MIN_LEVER`] of the arm's size over the poses (an axis along
//! gravity) has no test. Variable `gravity lever at <joint>`. With link masses (inertials),
//! the gravity torque `tau_j` about each joint's axis ([`crate::gravity`], N m, nominal
//! geometry) is a variable too, the same way (`tau` in units of its RMS over the poses): a
//! compliance or sag that follows the load rather than the tip's reach. A joint whose torque
//! stays below [`MIN_TORQUE`] of the largest joint's has no test. Variable `gravity torque at
//! <joint>`. Serial robots only (a tree's branches carry their own tips).

use dh_core::{Convention, DhTable, JointKind};
use nalgebra::{DMatrix, Vector3};

use super::{Prepared, Session};
use crate::findings::StructureCheck;
use crate::fit;
use crate::gravity::TorqueAxis;
use crate::model::Observation;
use crate::stats;

/// A joint whose gravity lever arm has an RMS over the poses below this fraction of the arm's
/// size gets no lever test (its axis is vertical or runs through the tip): the residual cannot
/// depend on a variable that does not vary.
pub(crate) const MIN_LEVER: f64 = 0.05;

/// A joint whose gravity torque has an RMS over the poses below this fraction of the largest
/// joint's gets no torque test (its axis is along gravity, or it carries no mass): as the
/// compliance candidates' bound ([`crate::effects::candidates`]).
pub(crate) const MIN_TORQUE: f64 = 1e-6;

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

/// A gravity structure variable of the verdict (see the module docs): its name, its value at
/// each picked unit, and the scale it is divided by before its powers are taken (the arm's
/// size for a lever arm, metres; the values' RMS for a torque, N m).
pub(super) struct GravityVariable {
    pub(super) variable: String,
    pub(super) values: Vec<f64>,
    pub(super) scale: f64,
}

/// The gravity structure variables of `session`'s robot: the lever arm (metres) of each
/// joint whose lever arm varies enough to be tested, then, when the calibration's gravity has
/// link masses ([`super::CalibrationOptions::gravity`]), the gravity torque (N m) of each
/// joint it loads, at each unit (the unit's first sample's joint values): `(picked, variables)`.
/// `units` are the first samples of the units (`None`: unit `u` is sample `u`). Empty for a
/// tree.
pub(super) fn gravity_variables(
    session: &Session<'_>,
    units: Option<&[usize]>,
    count: usize,
) -> (Vec<usize>, Vec<GravityVariable>) {
    let tree = session.model.tree();
    if !tree.branches().is_empty() || count == 0 {
        return (Vec::new(), Vec::new());
    }
    let table: &DhTable = tree.trunk();
    let rows = &table.rows;
    // The unit gravity direction in the base link frame.
    let down = session
        .options
        .gravity
        .as_ref()
        .map(|g| g.gravity())
        .filter(|g| g.norm() > 0.0 && g.iter().all(|v| v.is_finite()))
        .map_or(-Vector3::z(), |g| g / g.norm());
    let masses = session
        .options
        .gravity
        .as_ref()
        .filter(|g| g.tree().rows().len() == rows.len() && g.carried_mass(0) > 0.0);
    let step = count.div_ceil(UNITS_MAX).max(1);
    let picked: Vec<usize> = (0..count).step_by(step).collect();
    let mut levers: Vec<Vec<f64>> = vec![Vec::with_capacity(picked.len()); rows.len()];
    let mut torques: Vec<Vec<f64>> = match masses {
        Some(_) => vec![Vec::with_capacity(picked.len()); rows.len()],
        None => Vec::new(),
    };
    for &u in &picked {
        let i = units.map_or(u, |f| f[u]);
        let q = session.prep.cal.get(i).map(|o| &o.q[..]);
        if let (Some(g), Some(q)) = (masses, q) {
            for (j, t) in torques.iter_mut().enumerate() {
                t.push(g.torque(q, j, TorqueAxis::Joint));
            }
        } else {
            torques.iter_mut().for_each(|t| t.push(0.0));
        }
        // A sample whose joint values the table cannot take (none reach here: the model
        // checked them) has no lever arm: 0 keeps the lists aligned with `picked`.
        let frames = q.and_then(|q| table.frames(q).ok());
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
                z.dot(&arm.cross(&down))
            } else {
                0.0
            };
            levers[j].push(l);
        }
    }
    let size = table.size().max(f64::MIN_POSITIVE);
    let rms = |l: &[f64]| (l.iter().map(|v| v * v).sum::<f64>() / l.len().max(1) as f64).sqrt();
    let mut tested: Vec<GravityVariable> = levers
        .into_iter()
        .enumerate()
        .filter(|(j, l)| rows[*j].mimic.is_none() && !l.is_empty() && rms(l) >= MIN_LEVER * size)
        .map(|(j, values)| GravityVariable {
            variable: format!("gravity lever at {}", rows[j].name),
            values,
            scale: size,
        })
        .collect();
    // A torque test where the joint carries a torque above `MIN_TORQUE` of the largest one's
    // RMS (a joint whose axis is along gravity carries none).
    let biggest = torques.iter().map(|t| rms(t)).fold(0.0, f64::max);
    for (j, values) in torques.into_iter().enumerate() {
        let scale = rms(&values);
        if rows[j].mimic.is_none() && biggest > 0.0 && scale >= MIN_TORQUE * biggest {
            tested.push(GravityVariable {
                variable: format!("gravity torque at {}", rows[j].name),
                values,
                scale,
            });
        }
    }
    (picked, tested)
}

/// The test of the gravity variable `var` (see the module docs): the unit means `means` at
/// the units `picked` (indices into `means`) against `1, v, v², v³` (`v` the variable over
/// its scale), F test at `level`; the bins of the picked units' means against the variable.
pub(super) fn lever_check(
    var: &GravityVariable,
    picked: &[usize],
    means: &[Vector3<f64>],
    free: usize,
    level: f64,
    bins: impl Fn(&[f64], &[Vector3<f64>]) -> Vec<(f64, f64, f64)>,
) -> Option<StructureCheck> {
    let size = var.scale.max(f64::MIN_POSITIVE);
    let levers = &var.values;
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
        variable: var.variable.clone(),
        statistic: f,
        p_value: p,
        significant: p < level,
        bins: bins(levers, &picked_means),
    })
}
