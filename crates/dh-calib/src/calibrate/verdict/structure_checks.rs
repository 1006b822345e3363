//! The residual's remaining structure after a fit (step 5 of the verdict, [`super::verdict`]):
//! the pose-mean residuals against each joint (an F test of a low-order basis in the joint's
//! value), the pose order, time and each gravity lever arm, at a Bonferroni level, with the
//! binned residuals the report draws. Residuals in metres.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use dh_core::JointKind;
use nalgebra::{DMatrix, Vector3};

use super::super::{Prepared, Session};
use crate::findings::StructureCheck;
use crate::fit::{self, FitOutcome};
use crate::model::Observation;
use crate::stats;

/// The residual's structure at `fit` (step 5 of the verdict), given the position residuals
/// `res` of every calibration sample at `fit.x` ([`Session::position_residuals`]).
pub(super) fn structure_checks(
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
    let (picked, levers) = super::super::structure::gravity_variables(session, firsts, means.len());
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
        out.extend(super::super::structure::lever_check(
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
    out.extend(super::super::structure::time_check(
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
