//! Effects of the measurement sequence: what depends on the order the poses were measured in
//! rather than on the joint values alone.
//!
//! # Labels
//! | label | change | parameters (unit) |
//! |---|---|---|
//! | `backlash_direction:J` | `theta_J += b · s_J` (`d_J` for a prismatic joint) | `backlash_direction:J` (rad; m) |
//! | `drift` | device positions `× (1 + c · t)` | `drift` (1) |
//! | `thermal_growth` | robot positions `× (1 + k (1 − exp(−t/tau)))` about the base origin, `t` the time (or the order) | `thermal_growth.k` (1), `.ln_tau` (see [`crate::effects_thermal`]) |
//!
//! # The sequence
//! The samples are taken in file order. A **pose** is a run of consecutive samples with one
//! `config` (or, without a config, the same joint values): the targets and repeats measured
//! there. Poses are numbered `k = 0 .. P-1` in order of appearance, calibration and validation
//! samples alike (the robot visited both); a pose visited again later is a new pose.
//! - `s_J` (dimensionless) is the sign of joint `J`'s last motion before pose `k`:
//!   `sign(q_J[k] − q_J[k−1])` over the poses, where a step smaller than
//!   [`MIN_DIRECTION_STEP`] keeps the previous sign (the joint did not move); `s_J = 0` at the
//!   first pose and until the joint first moves. A gear with backlash `2|b|` rests against one
//!   flank or the other after the motion: after a motion in `+q` the joint sits at `q + b`,
//!   after one in `−q` at `q − b` (rad, or m for a prismatic joint; an output that lags its
//!   encoder has `b < 0`). The mean of the two is the joint's offset, estimated as before.
//! - `t = k / (P − 1)` in `[0, 1]` (0 for a single pose) is the pose's place in time, and
//!   `drift` is the relative length change of the measured positions over the session: device
//!   positions are multiplied by `1 + c · t` about the device's origin, as a device scale that
//!   grows linearly from the first pose to the last (a laser tracker whose air compensation
//!   lags a temperature change). The first pose is the reference (`t = 0`). A linear growth is
//!   the first term of any smooth drift; an exponential `1 − exp(−t/tau)` would need a time
//!   constant the sample order cannot give (poses are not equally spaced in time): it is
//!   `thermal_growth` ([`crate::effects_thermal`]), which reads the samples' times.
//!
//! Outside a sequence (a prediction, a compensation, a synthetic sample) the context is
//! neutral ([`SampleContext::default`]: `s = 0`, `t = 0`): the model predicts the robot
//! midway in its backlash and in the state of the session's start.
//!
//! Thermal growth of the robot's own links scales positions about its base rather than about
//! the device; `drift` holds it only together with the device frame's translation, so it is
//! an effect of its own, `thermal_growth` ([`crate::effects_thermal`]).

use std::sync::Arc;

use dh_core::JointKind;

use crate::data::Measurements;
use crate::effect_label::{bad_label, expect_joint_names, EffectContext};
use crate::fit::CalibError;
use crate::model::{Effect, EffectField, SampleContext};

/// A joint step between consecutive poses smaller than this (radians, or metres for a
/// prismatic joint) is no motion: the joint keeps the direction of its last motion. Far below
/// a commanded move, above the jitter of an encoder reading of a joint held still.
pub const MIN_DIRECTION_STEP: f64 = 1e-6;

/// The kinds of label this module parses.
pub const KINDS: [&str; 3] = ["backlash_direction", "drift", "thermal_growth"];

/// The context of every sample of a sequence (see the module docs), from each sample's joint
/// values (one per row, in the order effects index them) and `config`, in sequence order.
pub fn sequence_contexts<'a, I>(samples: I) -> Vec<SampleContext>
where
    I: IntoIterator<Item = (&'a [f64], Option<&'a str>)>,
{
    let samples: Vec<(&[f64], Option<&str>)> = samples.into_iter().collect();
    // Pose index of each sample.
    let mut pose = Vec::with_capacity(samples.len());
    let mut firsts: Vec<usize> = Vec::new();
    for (i, &sample) in samples.iter().enumerate() {
        let same = i > 0 && same_pose(samples[i - 1], sample);
        if !same {
            firsts.push(i);
        }
        pose.push(firsts.len() - 1);
    }
    let count = firsts.len();
    let mut contexts: Vec<SampleContext> = Vec::with_capacity(count);
    let mut direction: Vec<f64> = Vec::new();
    for (k, &i) in firsts.iter().enumerate() {
        let q = samples[i].0;
        direction.resize(q.len(), 0.0);
        if k > 0 {
            let prev = samples[firsts[k - 1]].0;
            for (j, d) in direction.iter_mut().enumerate() {
                let step = q[j] - prev.get(j).copied().unwrap_or(q[j]);
                if step.abs() >= MIN_DIRECTION_STEP {
                    *d = step.signum();
                }
            }
        }
        contexts.push(SampleContext {
            time: None,
            direction: direction.clone(),
            order: if count > 1 {
                k as f64 / (count - 1) as f64
            } else {
                0.0
            },
        });
    }
    pose.iter().map(|&k| contexts[k].clone()).collect()
}

/// Whether two consecutive samples (joint values, config) are one pose: the same config, or
/// without configs the same joint values.
fn same_pose(a: (&[f64], Option<&str>), b: (&[f64], Option<&str>)) -> bool {
    match (a.1, b.1) {
        (Some(x), Some(y)) => x == y,
        (None, None) => a.0.len() == b.0.len() && a.0.iter().zip(b.0).all(|(x, y)| x == y),
        _ => false,
    }
}

/// [`sequence_contexts`] without the directions of motion: each context's `order` as there,
/// its `direction` empty (for fits whose effects read none; no vector per sample), as the
/// pose number of each sample and the number of poses ([`order_context`] makes each context
/// when it is needed: millions of them are not held beside the samples).
pub(crate) fn sequence_orders<'a, I>(samples: I) -> (Vec<usize>, usize)
where
    I: IntoIterator<Item = (&'a [f64], Option<&'a str>)>,
{
    let mut pose: Vec<usize> = Vec::new();
    let mut previous: Option<(&[f64], Option<&str>)> = None;
    let mut count = 0usize;
    for sample in samples {
        if !previous.is_some_and(|p| same_pose(p, sample)) {
            count += 1;
        }
        pose.push(count - 1);
        previous = Some(sample);
    }
    (pose, count)
}

/// The context of pose `k` of `count` in the sequence ([`sequence_orders`]): its order, no
/// directions.
pub(crate) fn order_context(k: usize, count: usize) -> SampleContext {
    SampleContext {
        time: None,
        direction: Vec::new(),
        order: if count > 1 {
            k as f64 / (count - 1) as f64
        } else {
            0.0
        },
    }
}

/// [`sequence_contexts`] of the samples of `data`, with each sample's values in row order
/// (one per table row, as effects index them) from `rows_q`, in sample order.
pub fn contexts_of<'a>(
    rows_q: impl IntoIterator<Item = &'a [f64]>,
    data: &'a Measurements,
) -> Vec<SampleContext> {
    let mut contexts = sequence_contexts(
        rows_q
            .into_iter()
            .zip(&data.samples)
            .map(|(q, s)| (q, s.config.as_deref())),
    );
    let times = elapsed(data);
    for (c, t) in contexts.iter_mut().zip(times) {
        c.time = t;
    }
    contexts
}

/// Each sample's time since the set's first timed sample (seconds; see
/// [`crate::data::Sample::time`]), `None` for a sample without one.
pub fn elapsed(data: &Measurements) -> impl Iterator<Item = Option<f64>> + '_ {
    let first = data.samples.iter().find_map(|s| s.time);
    data.samples
        .iter()
        .map(move |s| s.time.zip(first).map(|(t, f)| t - f))
}

/// Whether any sample of `data` carries a time.
pub fn has_times(data: &Measurements) -> bool {
    data.samples.iter().any(|s| s.time.is_some())
}

/// [`sequence_contexts`] of a measurement set whose columns are the rows effects index (a
/// serial robot without mimic joints, as the simulators write it).
pub fn measurement_contexts(data: &Measurements) -> Vec<SampleContext> {
    contexts_of(data.samples.iter().map(|s| &*s.q), data)
}

/// A joint whose direction of motion changes fewer times than this over the sequence takes
/// part in no direction backlash candidate: with a few reversals `s_J` is a step function of
/// the pose order, a few blocks of consecutive poses (in circle-point data, the joint's own
/// sweep against the rest), which a change of offset between parts of the session (a warm-up,
/// a re-seated target) fits as well.
pub const MIN_REVERSALS: usize = 4;

/// How many times row `row`'s direction of motion changes sign along `contexts` (in sequence
/// order; directions of 0, before the joint first moves, are skipped).
pub fn reversals<'a>(contexts: impl IntoIterator<Item = &'a SampleContext>, row: usize) -> usize {
    let mut last = 0.0;
    let mut count = 0;
    for c in contexts {
        let d = c.direction_of(row);
        if d != 0.0 {
            if last != 0.0 && d != last {
                count += 1;
            }
            last = d;
        }
    }
    count
}

/// Whether row `row` reverses at least [`MIN_REVERSALS`] times in `contexts`: only then can a
/// direction-dependent backlash show apart from an offset change.
pub fn reverses<'a>(contexts: impl IntoIterator<Item = &'a SampleContext>, row: usize) -> bool {
    reversals(contexts, row) >= MIN_REVERSALS
}

/// Parses a label of this module's [`KINDS`] (`kind` its part before the first `:`, `args`
/// the rest); `None` for any other kind.
pub(crate) fn parse(
    label: &str,
    kind: &str,
    args: &[&str],
    ctx: &EffectContext,
) -> Option<Result<Arc<dyn Effect>, CalibError>> {
    let count = |n: usize| expect_joint_names(label, kind, args, n);
    Some(match kind {
        "backlash_direction" => count(1).and_then(|()| {
            let row = ctx
                .tree
                .row_index(args[0])
                .ok_or_else(|| CalibError::MissingJoint {
                    joint: args[0].into(),
                })?;
            if ctx.tree.rows()[row].mimic.is_some() {
                return Err(bad_label(
                    label,
                    format!(
                        "expected a driven joint, found mimic joint '{}' (its driver's backlash covers it)",
                        args[0]
                    ),
                ));
            }
            Ok(Arc::new(BacklashDirection {
                joint: args[0].into(),
                row,
                prismatic: ctx.tree.rows()[row].kind == JointKind::Prismatic,
            }) as Arc<dyn Effect>)
        }),
        "drift" => count(0).map(|()| Arc::new(Drift) as Arc<dyn Effect>),
        crate::effects_thermal::LABEL => count(0).map(|()| {
            Arc::new(crate::effects_thermal::ThermalGrowth) as Arc<dyn Effect>
        }),
        _ => return None,
    })
}

/// A backlash that follows the direction of the last motion: `theta_J += b · s_J` (`d_J` for a
/// prismatic joint), named `backlash_direction:J` (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct BacklashDirection {
    joint: String,
    row: usize,
    prismatic: bool,
}

impl BacklashDirection {
    /// The row (tree joint order) whose direction drives it.
    pub fn row(&self) -> usize {
        self.row
    }
}

impl Effect for BacklashDirection {
    fn parameter_names(&self) -> Vec<String> {
        vec![format!("backlash_direction:{}", self.joint)]
    }
    fn joint(&self) -> &str {
        &self.joint
    }
    fn field(&self) -> EffectField {
        if self.prismatic {
            EffectField::D
        } else {
            EffectField::Theta
        }
    }
    /// Zero: the neutral context has no direction.
    fn delta(&self, _q: &[f64], _params: &[f64]) -> f64 {
        0.0
    }
    fn gradient(&self, _q: &[f64], _params: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|o| *o = 0.0);
    }
    fn uses_sequence(&self) -> bool {
        true
    }
    fn delta_in(&self, _q: &[f64], context: &SampleContext, params: &[f64]) -> f64 {
        params.first().copied().unwrap_or(0.0) * context.direction_of(self.row)
    }
    fn gradient_in(&self, _q: &[f64], context: &SampleContext, _params: &[f64], out: &mut [f64]) {
        if let Some(o) = out.first_mut() {
            *o = context.direction_of(self.row);
        }
    }
    fn scales(&self, length: f64) -> Vec<f64> {
        vec![if self.prismatic { 1.0 } else { length }]
    }
    fn units(&self) -> Vec<String> {
        vec![if self.prismatic { "m" } else { "rad" }.into()]
    }
}

/// A device scale growing linearly over the session: positions `× (1 + c · t)`, named
/// `drift` (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drift;

impl Effect for Drift {
    fn parameter_names(&self) -> Vec<String> {
        vec!["drift".into()]
    }
    fn joint(&self) -> &str {
        ""
    }
    fn field(&self) -> EffectField {
        EffectField::Scale
    }
    /// Zero: the neutral context is the session's start.
    fn delta(&self, _q: &[f64], _params: &[f64]) -> f64 {
        0.0
    }
    fn gradient(&self, _q: &[f64], _params: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|o| *o = 0.0);
    }
    fn uses_sequence(&self) -> bool {
        true
    }
    fn delta_in(&self, _q: &[f64], context: &SampleContext, params: &[f64]) -> f64 {
        params.first().copied().unwrap_or(0.0) * context.order
    }
    fn gradient_in(&self, _q: &[f64], context: &SampleContext, _params: &[f64], out: &mut [f64]) {
        if let Some(o) = out.first_mut() {
            *o = context.order;
        }
    }
    fn scales(&self, length: f64) -> Vec<f64> {
        vec![length]
    }
    fn units(&self) -> Vec<String> {
        vec!["1".into()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn poses_are_runs_of_one_config_and_still_joints_keep_their_direction() {
        let q = [
            vec![0.0, 1.0],
            vec![0.0, 1.0],
            vec![0.5, 1.0],
            vec![0.2, 1.0 + 1e-9],
            vec![0.2, 0.5],
        ];
        let cfg = [Some("a"), Some("a"), Some("b"), Some("c"), Some("d")];
        let c = sequence_contexts(q.iter().map(Vec::as_slice).zip(cfg));
        // Two samples of pose a: one pose, no motion yet.
        assert_eq!(c[0], c[1]);
        assert_eq!(c[0].direction, vec![0.0, 0.0]);
        assert_eq!(c[0].order, 0.0);
        assert_eq!(c[2].direction, vec![1.0, 0.0]);
        // A step below MIN_DIRECTION_STEP is no motion.
        assert_eq!(c[3].direction, vec![-1.0, 0.0]);
        assert_eq!(c[4].direction, vec![-1.0, -1.0]);
        assert_eq!((c[2].order, c[4].order), (1.0 / 3.0, 1.0));
        assert_eq!(reversals(&c, 0), 1);
        assert_eq!(reversals(&c, 1), 0);
        assert!(!reverses(&c, 0));
        let back_and_forth: Vec<SampleContext> = [1.0, -1.0, -1.0, 1.0, -1.0, 1.0]
            .iter()
            .map(|&d| SampleContext {
                time: None,
                direction: vec![d],
                order: 0.0,
            })
            .collect();
        assert_eq!(reversals(&back_and_forth, 0), 4);
        assert!(reverses(&back_and_forth, 0));
        // Without configs, equal joint values in a row are one pose.
        let c = sequence_contexts(q.iter().map(|v| (v.as_slice(), None)));
        assert_eq!(c[0], c[1]);
        assert_eq!(c[4].order, 1.0);
        assert!(sequence_contexts(std::iter::empty()).is_empty());
    }

    #[test]
    fn order_effects_read_the_context_and_are_neutral_without_one() {
        let b = BacklashDirection {
            joint: "j2".into(),
            row: 1,
            prismatic: false,
        };
        let ctx = SampleContext {
            time: None,
            direction: vec![1.0, -1.0],
            order: 0.25,
        };
        assert_eq!(b.delta_in(&[0.0, 0.0], &ctx, &[7e-5]), -7e-5);
        assert_eq!(b.delta(&[0.0, 0.0], &[7e-5]), 0.0);
        let mut g = [9.0];
        b.gradient_in(&[0.0; 2], &ctx, &[0.0], &mut g);
        assert_eq!(g, [-1.0]);
        assert_eq!(Drift.delta_in(&[], &ctx, &[2e-5]), 0.25 * 2e-5);
        assert_eq!(Drift.delta(&[], &[2e-5]), 0.0);
    }
}
