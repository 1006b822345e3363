//! The part of a chain that does not depend on the sample, computed once per parameter vector.
//!
//! Most ops of a chain (the device, base and tool blocks, every DH value but the joint's own)
//! depend on the parameters `x` alone. At one `x` the ops between two sample-dependent ops
//! (a joint's `theta` or `d`, an op moved by an effect) multiply into one constant frame, so a
//! sample costs one elementary transform per joint and one frame product per run of constant
//! ops, instead of every elementary transform. For the Jacobian, the frame before each
//! constant op is the frame at the start of its run (per sample) times the constant frame of
//! the run's ops before it (per `x`): its axis and origin expressed in the run's start frame
//! are computed once.
//!
//! The prepared chains of the last parameter vector are kept per thread, keyed by the model's
//! revision (a number every change of a model's ops, effects or sessions renews) and the bits
//! of `x`.

use std::cell::RefCell;
use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};

use nalgebra::{Matrix3, Vector3};

use super::ops::{Frame, OpKind, DEVICE_OPS};
use super::{Model, SampleContext};

/// The session key of a chain measured in the `device` block's frame whatever the sample's
/// session ([`Model::session_ops`] of a session that has no block of its own).
pub(super) const DEVICE_BLOCK: usize = usize::MAX;

/// A revision number no model has had yet (see [`Model`]'s `revision`).
pub(super) fn next_revision() -> u64 {
    static NEXT: AtomicU64 = AtomicU64::new(1);
    NEXT.fetch_add(1, Ordering::Relaxed)
}

/// One step of a prepared chain.
#[derive(Clone, Debug)]
enum Step {
    /// The product of consecutive ops that depend on `x` alone (device frame units: metres).
    Const(Frame),
    /// An op whose value depends on the sample (joint value, effect moving it at this `x`): its
    /// index in the model's ops and the range of [`PreparedChain::effects`] holding the effect
    /// slots that move it.
    Var { op: usize, effects: Range<usize> },
}

/// Where an op of the chain acts: its step, and the frame just before it expressed in the
/// frame at the start of that step (`axis`: the op's axis, a unit vector, zero for a fixed
/// frame; `origin`: metres).
#[derive(Clone, Copy, Debug)]
pub(super) struct Place {
    pub(super) step: usize,
    pub(super) axis: Vector3<f64>,
    pub(super) origin: Vector3<f64>,
    /// Whether the op is in the chain's device block, before the base link frame: its motion
    /// carries the shift effects' translation with the rest ([`super::EffectField::Shift`]),
    /// which the ops after it do not turn.
    pub(super) device: bool,
}

/// One chain (an op list) prepared at one `x`.
#[derive(Clone, Debug)]
pub(super) struct PreparedChain {
    steps: Vec<Step>,
    effects: Vec<usize>,
    /// Per model op: where it acts on this chain (`None` off the chain).
    places: Vec<Option<Place>>,
    /// The rotation of the chain's device block at `x` (the base link frame's axes in the
    /// device frame): what turns a shift into the device frame.
    device_rotation: Matrix3<f64>,
}

impl PreparedChain {
    /// Prepares the ops `ops` (in order) of `model` at `x`.
    fn new(model: &Model, x: &[f64], ops: &[usize]) -> Self {
        let mut steps = Vec::new();
        let mut effects = Vec::new();
        let mut places = vec![None; model.ops.len()];
        // The run of constant ops being multiplied, if any.
        let mut run: Option<Frame> = None;
        let mut device = Frame::IDENTITY;
        for (k, &i) in ops.iter().enumerate() {
            let in_device = k < DEVICE_OPS;
            if in_device {
                let o = &model.ops[i];
                let v = o.value + o.param.and_then(|p| x.get(p)).copied().unwrap_or(0.0);
                device.apply(o.kind, v, &o.fixed);
            }
            let o = &model.ops[i];
            // The effects that move the op at this `x`: an effect whose parameters are all
            // zero moves nothing (`Effect::delta_in` of zeros), so an op moved by such effects
            // alone is constant here and joins its run.
            let moved: Vec<usize> = (0..model.effects.len())
                .filter(|&s| {
                    let slot = &model.effects[s];
                    slot.op == Some(i)
                        && x.get(slot.params.clone())
                            .unwrap_or(&[])
                            .iter()
                            .any(|p| *p != 0.0)
                })
                .collect();
            let axis = match o.kind {
                OpKind::Trans(a) | OpKind::Rot(a) => Vector3::ith(a as usize, 1.0),
                OpKind::Fixed => Vector3::zeros(),
            };
            if o.joint.is_some() || !moved.is_empty() {
                if let Some(f) = run.take() {
                    steps.push(Step::Const(f));
                }
                let start = effects.len();
                effects.extend(moved);
                places[i] = Some(Place {
                    step: steps.len(),
                    axis,
                    origin: Vector3::zeros(),
                    device: in_device,
                });
                steps.push(Step::Var {
                    op: i,
                    effects: start..effects.len(),
                });
            } else {
                let f = run.get_or_insert(Frame::IDENTITY);
                places[i] = Some(Place {
                    step: steps.len(),
                    axis: f.r * axis,
                    origin: f.t,
                    device: in_device,
                });
                // As `Model::op_values` computes it for an op without joint or effect.
                let v = o.value + o.param.and_then(|p| x.get(p)).copied().unwrap_or(0.0);
                f.apply(o.kind, v, &o.fixed);
            }
        }
        if let Some(f) = run {
            steps.push(Step::Const(f));
        }
        Self {
            steps,
            effects,
            places,
            device_rotation: device.r,
        }
    }

    /// The rotation of the chain's device block (see the field).
    pub(super) fn device_rotation(&self) -> &Matrix3<f64> {
        &self.device_rotation
    }

    /// Where op `op` acts on this chain (`None` off the chain).
    pub(super) fn place(&self, op: usize) -> Option<&Place> {
        self.places.get(op).and_then(Option::as_ref)
    }

    /// The frame at the end of the chain for joint values `q` in context `ctx` (the same as
    /// [`Model::chain`] of [`Model::op_values`] up to rounding); `starts`, when given,
    /// receives the frame at the start of each step.
    pub(super) fn frame(
        &self,
        model: &Model,
        x: &[f64],
        q: &[f64],
        ctx: &SampleContext,
        mut starts: Option<&mut Vec<Frame>>,
    ) -> Frame {
        if let Some(s) = starts.as_mut() {
            s.clear();
        }
        let mut f = Frame::IDENTITY;
        for step in &self.steps {
            if let Some(s) = starts.as_mut() {
                s.push(f);
            }
            match step {
                Step::Const(c) => {
                    f.t += f.r * c.t;
                    f.r *= c.r;
                }
                Step::Var { op, effects } => {
                    let o = &model.ops[*op];
                    // As `Model::op_values` computes it, in the same order.
                    let mut v = o.value
                        + o.param.and_then(|p| x.get(p)).copied().unwrap_or(0.0)
                        + o.joint.and_then(|j| q.get(j)).copied().unwrap_or(0.0);
                    // The effects that move the op at this `x` (see `PreparedChain::new`).
                    for &e in &self.effects[effects.clone()] {
                        let slot = &model.effects[e];
                        let params = x.get(slot.params.clone()).unwrap_or(&[]);
                        v += slot.effect.delta_in(q, ctx, params);
                    }
                    f.apply(o.kind, v, &o.fixed);
                }
            }
        }
        if model.has_shift() {
            f.t += self.device_rotation * model.shift_at(x, q, ctx);
        }
        f
    }
}

/// Chains prepared at one `x` of one model revision.
struct Entry {
    revision: u64,
    x: Vec<u64>,
    /// `((chain, session), prepared)`, in the order first asked for.
    chains: Vec<((usize, usize), PreparedChain)>,
}

/// Entries a thread keeps, most recent first: two, for callers that alternate between two
/// parameter vectors.
const ENTRIES: usize = 2;

thread_local! {
    static CACHE: RefCell<Vec<Entry>> = const { RefCell::new(Vec::new()) };
}

impl Model {
    /// Runs `work` on chain `chain` of session `session` prepared at `x` (from this thread's
    /// cache when the model and `x` are those of a recent call).
    pub(super) fn with_prepared<T>(
        &self,
        x: &[f64],
        chain: usize,
        session: usize,
        work: impl FnOnce(&PreparedChain) -> T,
    ) -> T {
        CACHE.with(|cache| {
            let mut cache = cache.borrow_mut();
            // Every element compared (no early exit): the compiler compares them a vector at
            // a time, and this runs once per sample and pass.
            let hit = cache.iter().position(|e| {
                e.revision == self.revision
                    && e.x.len() == x.len()
                    && e.x
                        .iter()
                        .zip(x)
                        .fold(true, |same, (a, b)| same & (*a == b.to_bits()))
            });
            match hit {
                Some(0) => {}
                Some(k) => cache.swap(0, k),
                None => {
                    if cache.len() == ENTRIES {
                        cache.pop();
                    }
                    cache.insert(
                        0,
                        Entry {
                            revision: self.revision,
                            x: x.iter().map(|v| v.to_bits()).collect(),
                            chains: Vec::new(),
                        },
                    );
                }
            }
            let entry = &mut cache[0];
            let key = (chain, session);
            let k = match entry.chains.iter().position(|(c, _)| *c == key) {
                Some(k) => k,
                None => {
                    let p = PreparedChain::new(self, x, self.session_ops(chain, session));
                    entry.chains.push((key, p));
                    entry.chains.len() - 1
                }
            };
            work(&entry.chains[k].1)
        })
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use nalgebra::{Isometry3, Vector3};

    use super::super::{GearRatio, Model, ModelOptions, Observation, Observed, SampleContext};
    use super::DEVICE_BLOCK;
    use crate::test_robots::ur5;

    /// A UR5 model with a gear ratio on `j2` and a second session with its own device block,
    /// and a parameter vector with every entry away from zero.
    fn model() -> (Model, Vec<f64>) {
        let table = ur5();
        let mut m = Model::new(&table, &["t".into()], &ModelOptions::default()).unwrap();
        m.add_effect(Arc::new(GearRatio::new(&table, "j2").unwrap()))
            .unwrap();
        m.add_session(1, "moved", &Isometry3::translation(0.5, -0.2, 0.1));
        let x = (0..m.parameter_count())
            .map(|i| 1e-3 * ((i as f64 * 0.7).sin() + 0.1))
            .collect();
        (m, x)
    }

    #[test]
    fn prepared_chains_agree_with_op_by_op_chains() {
        let (m, x) = model();
        let ctx = SampleContext::default();
        for k in 0..20 {
            let q: Vec<f64> = (0..6)
                .map(|j| ((k * 6 + j) as f64 * 1.3).sin() * 2.5)
                .collect();
            for session in [0, 1, DEVICE_BLOCK] {
                let ops = if session == DEVICE_BLOCK {
                    m.chain_ops(0)
                } else {
                    m.session_ops(0, session)
                };
                let mut v = Vec::new();
                m.op_values(&x, &q, &ctx, &mut v);
                let want = m.chain(&v, None, ops);
                let got = m.with_prepared(&x, 0, session, |p| p.frame(&m, &x, &q, &ctx, None));
                assert!((got.t - want.t).norm() < 1e-12, "{session}");
                assert!((got.r - want.r).norm() < 1e-12, "{session}");
            }
        }
    }

    /// A twist of `j2`'s row by `q₂` times the parameter: an effect on an op with no joint.
    #[derive(Debug)]
    struct Twist;

    impl crate::model::Effect for Twist {
        fn parameter_names(&self) -> Vec<String> {
            vec!["twist".into()]
        }
        fn joint(&self) -> &str {
            "j2"
        }
        fn field(&self) -> crate::model::EffectField {
            crate::model::EffectField::Alpha
        }
        fn delta(&self, q: &[f64], params: &[f64]) -> f64 {
            q[1] * params[0]
        }
        fn gradient(&self, q: &[f64], _params: &[f64], out: &mut [f64]) {
            out[0] = q[1];
        }
        fn scales(&self, _length: f64) -> Vec<f64> {
            vec![1.0]
        }
    }

    /// An op moved only by an effect whose parameters are zero is constant at that `x`: it
    /// joins its run (one step fewer), the frame is the op-by-op chain's, and the Jacobian
    /// column of the effect's parameter there is still its derivative (central differences).
    #[test]
    fn an_op_moved_only_by_an_effect_at_zero_joins_its_run() {
        let table = ur5();
        let mut m = Model::new(&table, &["t".into()], &ModelOptions::default()).unwrap();
        m.add_effect(Arc::new(Twist)).unwrap();
        let c = m.effects()[0].1.start;
        let mut x: Vec<f64> = (0..m.parameter_count())
            .map(|i| 1e-3 * ((i as f64 * 0.7).sin() + 0.1))
            .collect();
        x[c] = 0.0;
        let mut tilted = x.clone();
        tilted[c] = 2e-3;
        let steps = |x: &[f64]| m.with_prepared(x, 0, 0, |p| p.steps.len());
        assert_eq!(
            steps(&x) + 2,
            steps(&tilted),
            "the twist op and the run it splits"
        );
        let ctx = SampleContext::default();
        let q = [0.3, -1.2, 0.8, 0.1, 1.5, -0.4];
        for x in [&x, &tilted] {
            let mut v = Vec::new();
            m.op_values(x, &q, &ctx, &mut v);
            let want = m.chain(&v, None, m.session_ops(0, 0));
            let got = m.with_prepared(x, 0, 0, |p| p.frame(&m, x, &q, &ctx, None));
            assert!((got.t - want.t).norm() < 1e-12);
            assert!((got.r - want.r).norm() < 1e-12);
        }
        let obs = Observed::new(
            q.to_vec(),
            Observation::Point {
                target: 0,
                point: Vector3::new(0.1, 0.2, 0.3),
            },
        );
        let (mut r, mut jac) = ([0.0; 3], [0.0; 3]);
        m.jacobian(&x, &obs, &[c], &mut r, &mut jac);
        let h = 1e-6;
        let at = |d: f64| {
            let mut y = x.clone();
            y[c] = d;
            let mut r = [0.0; 3];
            m.residuals(&y, &obs, &mut r);
            r
        };
        let (plus, minus) = (at(h), at(-h));
        for k in 0..3 {
            let fd = (plus[k] - minus[k]) / (2.0 * h);
            assert!((jac[k] - fd).abs() < 1e-8, "{k}: {} {fd}", jac[k]);
        }
        assert!(jac.iter().any(|j| j.abs() > 1e-3), "{jac:?}");
    }

    #[test]
    fn a_changed_model_is_prepared_again() {
        let (mut m, x) = model();
        let q = [0.3, -1.2, 0.8, 0.1, 1.5, -0.4];
        let obs = Observed::new(
            q.to_vec(),
            Observation::Point {
                target: 0,
                point: Vector3::new(0.1, 0.2, 0.3),
            },
        );
        let mut before = [0.0; 3];
        m.residuals(&x, &obs, &mut before);
        // The same `x` after moving the device: the cached chains must not be used.
        let moved = Isometry3::translation(1.0, 0.0, 0.0);
        m.set_device(&moved);
        let mut after = [0.0; 3];
        m.residuals(&x, &obs, &mut after);
        let mut fresh = model().0;
        fresh.set_device(&moved);
        let mut want = [0.0; 3];
        fresh.residuals(&x, &obs, &mut want);
        assert!((after[0] - before[0] - 1.0).abs() < 1e-9);
        assert_eq!(after, want);
    }
}
