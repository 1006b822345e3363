//! Preparing measurements for a fit: the joint rows of each sample in the tree's order, the
//! sample contexts (sequence, config) and the calibration/validation split ([`Prepared`]).

use std::collections::HashMap;
use std::sync::Arc;

use nalgebra::{Isometry3, Translation3};

use crate::data::{CompactString, Measurements, Sample, Split};
use crate::fit::CalibError;
use crate::model::{Observation, Observed, SampleContext};
use crate::tree::DhTree;

mod groups;
mod sigmas;

use groups::{pose_groups, PoseKey};

pub(crate) use sigmas::Sigmas;

/// Calibration samples, validation samples and the pose group of each calibration sample.
pub(crate) struct Prepared {
    pub(crate) cal: Vec<Observed>,
    pub(crate) val: Vec<Observed>,
    /// The pose group of each calibration sample, numbered from 0 in order of first
    /// appearance (so group `g + 1` first appears after group `g`).
    pub(crate) groups: Vec<usize>,
    pub(crate) group_count: usize,
    /// Whether each calibration sample names its pose (`config`): its repeat key is then its
    /// pose group and target ([`Prepared::repeat_keys`]).
    pub(crate) named: Vec<bool>,
    /// The known per-axis noise of each calibration sample (metres), held once when all are
    /// the same.
    pub(crate) sigmas: Sigmas,
    /// `sigma_rot` of the calibration samples that measure an orientation, in order (radians;
    /// none for point samples, which are most of a large set).
    pub(crate) sigmas_rot: Vec<f64>,
    /// Pose group of each validation sample (numbered apart from the calibration groups).
    pub(crate) val_groups: Vec<usize>,
}

impl Prepared {
    /// The repeat key of each calibration sample, in order: `(pose group, target)` for a
    /// sample that names its pose, `None` for one that does not (its repeats are not known).
    pub(crate) fn repeat_keys(&self) -> impl Iterator<Item = Option<(usize, usize)>> + '_ {
        self.cal
            .iter()
            .zip(&self.groups)
            .zip(&self.named)
            .map(|((o, &g), &named)| {
                let target = match o.observation {
                    Observation::Point { target, .. } | Observation::TargetPose { target, .. } => {
                        target
                    }
                    // `prepare` makes none; the tip has no target.
                    Observation::Pose(_) => usize::MAX,
                };
                named.then_some((g, target))
            })
    }
}

/// Each sample's joint values per row of `tree` (mimic rows from their driver's column).
///
/// # Errors
/// [`CalibError::MissingJoint`] for a row without a column; [`CalibError::Length`] for a
/// sample with the wrong number of values; [`CalibError::NonFinite`] for a non-finite value.
///
/// When the rows are the set's columns in order (no mimic row, no column left out), each
/// sample's values are shared ([`Arc`]), not copied.
pub(crate) fn rows_of(tree: &DhTree, data: &Measurements) -> Result<Vec<Arc<[f64]>>, CalibError> {
    enum Source {
        Column(usize),
        Mimic(usize, f64, f64),
    }
    let column = |name: &str| data.joint_names.iter().position(|n| n == name);
    let mut sources = Vec::with_capacity(tree.rows().len());
    for r in tree.rows() {
        let s = match (column(&r.name), &r.mimic) {
            (Some(c), _) => Source::Column(c),
            (None, Some(m)) => match column(&m.joint) {
                Some(c) => Source::Mimic(c, m.multiplier, m.offset),
                None => {
                    return Err(CalibError::MissingJoint {
                        joint: r.name.clone(),
                    })
                }
            },
            (None, None) => {
                return Err(CalibError::MissingJoint {
                    joint: r.name.clone(),
                })
            }
        };
        sources.push(s);
    }
    let same_columns = sources.len() == data.joint_names.len()
        && sources
            .iter()
            .enumerate()
            .all(|(k, s)| matches!(s, Source::Column(c) if *c == k));
    let mut rows_q: Vec<Arc<[f64]>> = Vec::with_capacity(data.samples.len());
    for s in &data.samples {
        if s.q.len() != data.joint_names.len() {
            return Err(CalibError::Length {
                what: format!("joint values at line {}", s.line),
                expected: data.joint_names.len(),
                found: s.q.len(),
            });
        }
        if s.q.iter().any(|v| !v.is_finite()) {
            return Err(CalibError::NonFinite {
                what: format!("sample at line {}", s.line),
            });
        }
        rows_q.push(if same_columns {
            Arc::clone(&s.q)
        } else {
            sources
                .iter()
                .map(|src| match *src {
                    Source::Column(c) => s.q[c],
                    Source::Mimic(c, m, o) => m * s.q[c] + o,
                })
                .collect()
        });
    }
    Ok(rows_q)
}

/// The place of each sample of `data` in its sequence, from its row values `rows_q`.
pub(super) fn sequence_of(rows_q: &[Arc<[f64]>], data: &Measurements) -> Vec<SampleContext> {
    crate::effects_order::contexts_of(rows_q.iter().map(|q| &**q), data)
}

/// [`sequence_of`] without the directions of motion (each context's `direction` empty), one
/// at a time.
fn orders_of<'a>(
    rows_q: &[Arc<[f64]>],
    data: &'a Measurements,
) -> impl Iterator<Item = SampleContext> + 'a {
    let (pose, count) = crate::effects_order::sequence_orders(
        rows_q
            .iter()
            .map(|q| &**q)
            .zip(data.samples.iter().map(|s| s.config.as_deref())),
    );
    pose.into_iter()
        .zip(crate::effects_order::elapsed(data))
        .map(move |(k, time)| SampleContext {
            time,
            ..crate::effects_order::order_context(k, count)
        })
}

/// The places in `data`'s whole sequence `full` ([`sequence_of`]) of the samples `keep`
/// keeps, in order: the sequence of `data.filtered(keep)`, whose left-out samples were still
/// visited.
pub(crate) fn kept_sequence(
    full: &[SampleContext],
    data: &Measurements,
    keep: impl Fn(usize, &crate::data::Sample) -> bool,
) -> Vec<SampleContext> {
    full.iter()
        .zip(&data.samples)
        .enumerate()
        .filter(|(i, (_, s))| keep(*i, s))
        .map(|(_, (c, _))| c.clone())
        .collect()
}

/// What sample `s` measured: a point, or with an orientation a target pose whose angle is
/// weighed by `σ_position / σ_rotation` (metres per radian, `σ_position` the RMS of the
/// sample's per-axis sigma; see [`Observation::TargetPose`]).
///
/// # Errors
/// [`CalibError::BadOption`] for an orientation without a position sigma.
fn observation_of(s: &Sample) -> Result<Observation, CalibError> {
    let Some(o) = &s.orientation else {
        return Ok(Observation::Point {
            target: s.target,
            point: s.point,
        });
    };
    let sigma = s.sigma.map(|v| (v.norm_squared() / 3.0).sqrt());
    match sigma {
        Some(sp) if sp > 0.0 && o.sigma > 0.0 => Ok(Observation::TargetPose {
            target: s.target,
            pose: Box::new(Isometry3::from_parts(
                Translation3::from(s.point),
                o.rotation,
            )),
            weight: sp / o.sigma,
        }),
        _ => Err(CalibError::BadOption {
            what: format!("sample at line {}", s.line),
            reason: "expected a position sigma (sigma or sx, sy, sz) with an orientation, \
                     found none: it weighs the angle against the position"
                .into(),
        }),
    }
}

/// A prepared sample (or why it cannot be) and the hash of its pose key ([`PoseKey`]; 0 for a
/// validation sample).
type Batched = (Result<Observed, CalibError>, u64);

/// Samples per batch handed from the thread that prepares them to the one that files them.
const PREPARE_BATCH: usize = 4096;

/// From this many samples on, [`prepare`] makes the prepared samples on a second thread.
const PREPARE_PARALLEL_MIN: usize = 65_536;

/// Prepares `data` for `tree`; `sequence` is each sample's place in the measurement sequence
/// when `data` is part of a longer one (the samples an outlier screen kept, placed in the
/// whole file: [`fitted_session`]), `None` to take `data`'s own order; without `directions`
/// (no effect of the fit reads the direction of motion) the contexts' `direction` is left
/// empty when taken from `data`'s own order.
pub(crate) fn prepare(
    tree: &DhTree,
    data: &Measurements,
    sequence: Option<&[SampleContext]>,
    directions: bool,
) -> Result<Prepared, CalibError> {
    let rows_q = rows_of(tree, data)?;
    // The place of every sample in the sequence, calibration and validation alike (the robot
    // visited both, in file order).
    // Read one at a time: a list of them would be held beside the samples (64 MB on
    // 2 000 000 samples).
    let contexts: Box<dyn Iterator<Item = SampleContext> + Send + '_> = match sequence {
        Some(c) if c.len() == data.samples.len() => Box::new(c.iter().cloned()),
        _ if directions => Box::new(sequence_of(&rows_q, data).into_iter()),
        _ => Box::new(orders_of(&rows_q, data)),
    };
    // Each list reserved at its final length: grown by doubling, the list of 2 000 000
    // prepared samples would be held twice while it moves (0.45 GB at once).
    let n_val = data
        .samples
        .iter()
        .filter(|s| s.split == Split::Validation)
        .count();
    let n_cal = data.samples.len() - n_val;
    let mut out = Prepared {
        cal: Vec::with_capacity(n_cal),
        val: Vec::with_capacity(n_val),
        groups: Vec::new(),
        group_count: 0,
        named: Vec::with_capacity(n_cal),
        sigmas: Sigmas::default(),
        sigmas_rot: vec![],
        val_groups: Vec::with_capacity(n_val),
    };
    let mut val_ids: HashMap<String, usize> = HashMap::new();
    // The pose keys' hashes are made beside the samples, on the second thread below (SipHash
    // with random keys, as a map's own); the calibration samples' config names (`None`: the
    // joint values are the key) and hashes are kept for `pose_groups`.
    let key_hasher = std::collections::hash_map::RandomState::new();
    let mut names: Vec<Option<&CompactString>> = Vec::with_capacity(n_cal);
    let mut hashes: Vec<u64> = Vec::with_capacity(n_cal);
    for s in &data.samples {
        if s.target >= data.targets.len() {
            return Err(CalibError::BadTarget {
                line: s.line,
                target: s.target,
                count: data.targets.len(),
            });
        }
        if s.point.iter().any(|v| !v.is_finite()) {
            return Err(CalibError::NonFinite {
                what: format!("sample at line {}", s.line),
            });
        }
    }
    // The prepared samples are made in order on a second thread (their joint values, what
    // they measure, their contexts, their pose keys' hashes), a batch at a time, while this
    // one files them.
    let produce = |send: &mut dyn FnMut(Vec<Batched>) -> bool| {
        let mut batch = Vec::with_capacity(PREPARE_BATCH);
        for ((s, q), context) in data.samples.iter().zip(rows_q).zip(contexts) {
            let hash = match (&s.config, s.split) {
                (_, Split::Validation) => 0,
                (Some(c), _) => PoseKey::Named(c).hash_by(&key_hasher),
                (None, _) => PoseKey::Unnamed(&q).hash_by(&key_hasher),
            };
            let obs = observation_of(s).map(|observation| Observed {
                session: s.session,
                q,
                observation,
                context,
            });
            batch.push((obs, hash));
            if batch.len() == PREPARE_BATCH
                && !send(std::mem::replace(
                    &mut batch,
                    Vec::with_capacity(PREPARE_BATCH),
                ))
            {
                return;
            }
        }
        if !batch.is_empty() {
            send(batch);
        }
    };
    let mut consume = |batches: &mut dyn Iterator<Item = Vec<Batched>>| {
        for (s, (obs, hash)) in data.samples.iter().zip(batches.flatten()) {
            let obs = obs?;
            match s.split {
                Split::Validation => {
                    let key = match &s.config {
                        Some(c) => c.to_string(),
                        None => format!("{:?}", obs.q),
                    };
                    let next = val_ids.len();
                    out.val_groups.push(*val_ids.entry(key).or_insert(next));
                    out.val.push(obs);
                }
                Split::Calibration => {
                    names.push(s.config.as_ref());
                    hashes.push(hash);
                    out.named.push(s.config.is_some());
                    out.sigmas.push(s.sigma);
                    if let Some(o) = &s.orientation {
                        out.sigmas_rot.push(o.sigma);
                    }
                    out.cal.push(obs);
                }
            }
        }
        Ok::<(), CalibError>(())
    };
    if data.samples.len() >= PREPARE_PARALLEL_MIN {
        dh_core::parallel::pipeline(4, produce, |mut items| consume(&mut items))?;
    } else {
        let mut batches = Vec::new();
        produce(&mut |b| {
            batches.push(b);
            true
        });
        consume(&mut batches.into_iter())?;
    }
    let cal = &out.cal;
    let key = |i: usize| match names[i] {
        Some(c) => PoseKey::Named(c),
        None => PoseKey::Unnamed(&cal[i].q),
    };
    let (groups, count) = pose_groups(&key, &hashes);
    drop((names, hashes));
    out.groups = groups;
    out.group_count = count;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    /// Pose groups are numbered in order of first appearance, named or not, and the sigmas
    /// come back as given.
    #[test]
    fn groups_are_numbered_in_order_of_first_appearance() {
        let tree = DhTree::serial(&crate::test_robots::ur5());
        let joint_names: Vec<String> = (1..=6).map(|j| format!("j{j}")).collect();
        let sample = |q0: f64, config: Option<&str>, split: Split, line: usize| Sample {
            sigma: (!line.is_multiple_of(3)).then(|| Vector3::repeat(1e-5 * line as f64)),
            config: config.map(Into::into),
            split,
            ..Sample::test_point(
                &[q0, 0.1, 0.2, 0.3, 0.4, 0.5],
                Vector3::new(0.1 * line as f64, 0.2, 0.3),
                line,
            )
        };
        let cal = Split::Calibration;
        let data = Measurements {
            joint_names,
            targets: vec!["t".into()],
            samples: vec![
                sample(0.0, Some("b"), cal, 1),
                sample(0.0, Some("a"), cal, 2),
                sample(0.5, None, Split::Validation, 3),
                sample(0.0, Some("b"), cal, 4),
                sample(0.7, None, cal, 5),
                sample(0.0, Some("c"), cal, 6),
                sample(0.7, None, cal, 7),
                sample(0.0, Some("a"), cal, 8),
                sample(0.9, None, cal, 9),
            ],
            sessions: vec![],
        };
        let prep = prepare(&tree, &data, None, false).unwrap();
        assert_eq!(prep.groups, vec![0, 1, 0, 2, 3, 2, 1, 4]);
        assert_eq!(prep.group_count, 5);
        let mut seen = 0;
        for &g in &prep.groups {
            assert!(g <= seen);
            seen = seen.max(g + 1);
        }
        let sigmas: Vec<_> = data
            .samples
            .iter()
            .filter(|s| s.split == cal)
            .map(|s| s.sigma)
            .collect();
        assert_eq!(prep.sigmas.iter().collect::<Vec<_>>(), sigmas);
    }

    /// A set large enough for the second thread gives the same groups, contexts and joint
    /// values as numbered here one sample at a time.
    #[test]
    fn a_large_set_is_prepared_as_a_small_one_would_be() {
        let tree = DhTree::serial(&crate::test_robots::ur5());
        let n = PREPARE_PARALLEL_MIN + PREPARE_BATCH + 17;
        let samples: Vec<Sample> = (0..n)
            .map(|i| Sample {
                // Names repeat out of order; every 7th sample is unnamed.
                config: (i % 7 != 3).then(|| format!("c{}", (i * 7919) % 1000).into()),
                split: if i % 11 == 5 {
                    Split::Validation
                } else {
                    Split::Calibration
                },
                ..Sample::test_point(
                    &[i as f64 * 1e-5, 0.1, 0.2, 0.3, 0.4, 0.5],
                    Vector3::new(0.1, 0.2, 0.3),
                    i + 2,
                )
            })
            .collect();
        let data = Measurements::test_ur5(samples);
        let prep = prepare(&tree, &data, None, false).unwrap();
        let mut ids: HashMap<String, usize> = HashMap::new();
        let mut expected = vec![];
        for s in data
            .samples
            .iter()
            .filter(|s| s.split == Split::Calibration)
        {
            let key = match &s.config {
                Some(c) => c.to_string(),
                None => format!("{:?}", s.q),
            };
            let next = ids.len();
            expected.push(*ids.entry(key).or_insert(next));
        }
        assert_eq!(prep.groups, expected);
        assert_eq!(prep.group_count, ids.len());
        let cal: Vec<&Sample> = data
            .samples
            .iter()
            .filter(|s| s.split == Split::Calibration)
            .collect();
        assert_eq!(prep.cal.len(), cal.len());
        // The rows are the set's columns in order: the values are shared, not copied.
        assert!(prep
            .cal
            .iter()
            .zip(&cal)
            .all(|(o, s)| Arc::ptr_eq(&o.q, &s.q)));
        assert_eq!(prep.val.len(), n - cal.len());
        let orders: Vec<f64> = prep.cal.iter().map(|o| o.context.order).collect();
        assert!(orders.windows(2).all(|w| w[0] < w[1]));
    }

    /// Columns in another order than the rows (or fewer rows than columns) give each
    /// prepared sample its own values in row order.
    #[test]
    fn columns_out_of_row_order_are_copied_into_row_order() {
        let tree = DhTree::serial(&crate::test_robots::ur5());
        let q = [0.6, 0.5, 0.4, 0.3, 0.2, 0.1, 9.0];
        let sample = Sample::test_point(&q, Vector3::new(0.1, 0.2, 0.3), 2);
        let mut data = Measurements {
            joint_names: ["j6", "j5", "j4", "j3", "j2", "j1", "extra"]
                .map(String::from)
                .to_vec(),
            targets: vec!["t".into()],
            samples: vec![sample],
            sessions: vec![],
        };
        let prep = prepare(&tree, &data, None, false).unwrap();
        assert_eq!(prep.cal[0].q[..], [0.1, 0.2, 0.3, 0.4, 0.5, 0.6]);
        // The same values in row order, but one column more than rows: still a copy.
        data.joint_names = ["j1", "j2", "j3", "j4", "j5", "j6", "extra"]
            .map(String::from)
            .to_vec();
        let prep = prepare(&tree, &data, None, false).unwrap();
        assert_eq!(prep.cal[0].q[..], q[..6]);
        assert!(!Arc::ptr_eq(&prep.cal[0].q, &data.samples[0].q));
    }
}
