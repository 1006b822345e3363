//! The warm-up of the robot's links: `thermal_growth`, every length of the robot growing along
//! an exponential in time.
//!
//! # Model
//! | label | change | parameters (unit) |
//! |---|---|---|
//! | `thermal_growth` | robot positions `× (1 + k (1 − exp(−t/tau)))` about the base origin | `thermal_growth.k` (1), `thermal_growth.ln_tau` (`ln tau`, tau in s) |
//!
//! A link of steel lengthens by about 12 ppm per kelvin; a robot that warms up from its
//! motors lengthens every link together, and a first-order heat balance makes the growth
//! `k (1 − exp(−t/tau))`, `k` the relative growth at equilibrium and `tau` the time constant
//! (tens of minutes for an industrial arm). Every `a` and `d` of the table, the base and tool
//! offsets and the targets' offsets scale by the same factor: in the base link frame, every
//! position is multiplied by it ([`crate::model::EffectField::Growth`]), about the base's
//! origin, while the device frame stays. That is what sets it apart from `drift`, a device
//! scale about the device's origin, and from `scale`, a constant one.
//!
//! `t` is the sample's time since the set's first timed sample, in seconds
//! ([`crate::data::Sample::time`], the measurement file's `time` column). Without times it
//! is the pose order `t` in `[0, 1]` of [`crate::effects_order`] (the first pose 0, the last
//! 1), and `tau` is then in that unit (a fraction of the session), which assumes evenly
//! spaced poses; the diagnosis says so in a note.
//!
//! `tau` is fitted as `ln tau` (so it stays positive) with `tau` in seconds (or in session
//! units without times), 0 meaning `tau = 1`. The growth is not linear in it, and at `k = 0`
//! it does not act at all: a fit that starts from `k = 0` first fits `k` linearly at each
//! `tau` of [`Effect::shape_grid`] and starts the joint fit from the best
//! (`crate::calibrate::shape_start`).
//!
//! Outside a sequence (a prediction without times or order) `t = 0`: the robot as it was at
//! the set's first sample.

use crate::model::{Effect, EffectField, SampleContext};

/// The label of the effect.
pub const LABEL: &str = "thermal_growth";

/// Growth whose `ln tau` column is scaled as that amplitude's ([`Effect::scales`]): 1e-4
/// (100 ppm, about 8 K of steel), a typical warm-up. Scaling only: the fit's steps and the
/// identifiability test see the `ln tau` column at about the size of the `k` column.
pub const TYPICAL_GROWTH: f64 = 1e-4;

/// Number of time constants of the start grid ([`Effect::shape_grid`]).
pub const GRID_POINTS: usize = 24;

/// The grid's time constants run from this fraction of the sequence's span...
pub const GRID_SHORTEST: f64 = 1.0 / 30.0;

/// ...to this multiple of it (log-spaced): a `tau` longer than a few spans is a linear growth
/// over the set, a shorter one than a few poses a step at its start.
pub const GRID_LONGEST: f64 = 3.0;

/// `x = t / tau` beyond which `exp(−x)` is 0 in double precision (and `x exp(−x)` too).
const EXP_UNDERFLOW: f64 = 745.0;

/// The robot's lengths growing along an exponential in time, named `thermal_growth` (see
/// the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThermalGrowth;

/// `(1 − exp(−t/tau), (t/tau) exp(−t/tau))` at `t` and `ln tau`: the shape and minus its
/// derivative by `ln tau`. Both 0 at `t <= 0` and for a NaN.
fn shape(t: f64, ln_tau: f64) -> (f64, f64) {
    let x = t * (-ln_tau).exp();
    if x.is_nan() || x <= 0.0 {
        return (0.0, 0.0);
    }
    // Beyond it (a tau of 0 included) the growth is complete.
    if x > EXP_UNDERFLOW {
        return (1.0, 0.0);
    }
    let e = (-x).exp();
    (-(-x).exp_m1(), x * e)
}

/// What the `t` of a calibration's effects of time was: a calibrated sheet's
/// `calibration.time_unit` (YAML `s` or `pose_order`), so that a prediction reads its rows'
/// times in the same unit (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum TimeUnit {
    /// Seconds since the set's first timed sample: the data had a `time` column.
    #[serde(rename = "s")]
    Seconds,
    /// The pose order in `[0, 1]` (the first pose 0, the last 1): the data had no times, and
    /// `tau` is a fraction of the session.
    #[serde(rename = "pose_order")]
    PoseOrder,
}

impl TimeUnit {
    /// The unit of `t` in a calibration of `data` whose estimated effect parameters are
    /// `names` (see [`crate::model`]): `None` when none is `thermal_growth`'s (no effect of
    /// time), else seconds when a sample of `data` has a time, the pose order otherwise.
    pub fn of_calibration<'a>(
        names: impl IntoIterator<Item = &'a str>,
        data: &crate::data::Measurements,
    ) -> Option<TimeUnit> {
        let prefix = format!("{LABEL}.");
        names.into_iter().any(|n| n.starts_with(&prefix)).then(|| {
            if crate::effects_order::has_times(data) {
                TimeUnit::Seconds
            } else {
                TimeUnit::PoseOrder
            }
        })
    }

    /// The YAML word (`s`, `pose_order`).
    pub fn word(self) -> &'static str {
        match self {
            TimeUnit::Seconds => "s",
            TimeUnit::PoseOrder => "pose_order",
        }
    }
}

/// The time `t` an effect of time reads in `context`: its time in seconds when the samples
/// carry one, else its place in the pose order.
pub fn time_of(context: &SampleContext) -> f64 {
    context.time.unwrap_or(context.order)
}

impl Effect for ThermalGrowth {
    fn parameter_names(&self) -> Vec<String> {
        vec![format!("{LABEL}.k"), format!("{LABEL}.ln_tau")]
    }
    fn label(&self) -> String {
        LABEL.into()
    }
    fn joint(&self) -> &str {
        ""
    }
    fn field(&self) -> EffectField {
        EffectField::Growth
    }
    /// Zero: the neutral context is the set's first sample (`t = 0`).
    fn delta(&self, _q: &[f64], _params: &[f64]) -> f64 {
        0.0
    }
    fn gradient(&self, _q: &[f64], _params: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|o| *o = 0.0);
    }
    fn uses_sequence(&self) -> bool {
        true
    }
    fn uses_time(&self) -> bool {
        true
    }
    fn delta_in(&self, _q: &[f64], context: &SampleContext, params: &[f64]) -> f64 {
        let k = params.first().copied().unwrap_or(0.0);
        // No growth at `k = 0` whatever tau (the shape is finite and not negative, so this is
        // `k · shape` to the bit): the candidate is in every evaluation of the diagnosis, at
        // `k = 0` with its start's tau until it is selected, and the exponential is skipped.
        if k == 0.0 {
            return k;
        }
        let ln_tau = params.get(1).copied().unwrap_or(0.0);
        k * shape(time_of(context), ln_tau).0
    }
    fn gradient_in(&self, _q: &[f64], context: &SampleContext, params: &[f64], out: &mut [f64]) {
        let k = params.first().copied().unwrap_or(0.0);
        let ln_tau = params.get(1).copied().unwrap_or(0.0);
        let (f, g) = shape(time_of(context), ln_tau);
        if let [dk, dtau, ..] = out {
            *dk = f;
            *dtau = -k * g;
        }
    }
    fn scales(&self, length: f64) -> Vec<f64> {
        // `x e^{-x}` peaks at 1/e: the most a unit of `ln tau` moves a point per unit of `k`.
        vec![
            length,
            length * TYPICAL_GROWTH.recip() * std::f64::consts::E.recip(),
        ]
    }
    fn units(&self) -> Vec<String> {
        vec!["1".into(), "ln s".into()]
    }
    /// `ln tau` for [`GRID_POINTS`] time constants log-spaced from [`GRID_SHORTEST`] to
    /// [`GRID_LONGEST`] times `span`.
    fn shape_grid(&self, span: f64) -> Vec<f64> {
        if !(span.is_finite() && span > 0.0) {
            return Vec::new();
        }
        let (lo, hi) = ((span * GRID_SHORTEST).ln(), (span * GRID_LONGEST).ln());
        (0..GRID_POINTS)
            .map(|i| lo + (hi - lo) * i as f64 / (GRID_POINTS - 1) as f64)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(t: f64) -> SampleContext {
        SampleContext {
            time: Some(t),
            ..SampleContext::default()
        }
    }

    #[test]
    fn growth_follows_the_exponential_and_its_gradient_the_difference_quotient() {
        let e = ThermalGrowth;
        let p = [60e-6, 1200f64.ln()];
        // One time constant in: 1 − 1/e of the equilibrium growth.
        let d = e.delta_in(&[], &at(1200.0), &p);
        assert!((d - 60e-6 * (1.0 - (-1.0f64).exp())).abs() < 1e-18, "{d}");
        assert_eq!(e.delta_in(&[], &at(0.0), &p), 0.0);
        assert_eq!(e.delta(&[], &p), 0.0);
        // Without a time, the pose order is `t`.
        let ordered = SampleContext {
            order: 0.5,
            ..SampleContext::default()
        };
        let q = [1e-4, 0.25f64.ln()];
        assert!((e.delta_in(&[], &ordered, &q) - 1e-4 * (1.0 - (-2.0f64).exp())).abs() < 1e-18);
        for t in [0.0, 300.0, 1200.0, 7200.0] {
            let mut g = [0.0; 2];
            e.gradient_in(&[], &at(t), &p, &mut g);
            for (i, h) in [(0, 1e-9), (1, 1e-6)] {
                let mut a = p;
                let mut b = p;
                a[i] += h;
                b[i] -= h;
                let fd = (e.delta_in(&[], &at(t), &a) - e.delta_in(&[], &at(t), &b)) / (2.0 * h);
                assert!(
                    (g[i] - fd).abs() <= 1e-7 * fd.abs().max(1e-12),
                    "t {t} {i}: {g:?} {fd}"
                );
            }
        }
        // Far time constants give finite values: a step, and no growth.
        let mut g = [0.0; 2];
        e.gradient_in(&[], &at(7200.0), &[1e-4, -800.0], &mut g);
        assert_eq!(g, [1.0, 0.0]);
        e.gradient_in(&[], &at(7200.0), &[1e-4, 800.0], &mut g);
        assert_eq!(g, [0.0, 0.0]);
    }

    /// A calibration records its effects of time's unit only with one; the YAML words are
    /// `s` and `pose_order`.
    #[test]
    fn time_units_are_recorded_with_an_effect_of_time() {
        let untimed = crate::data::Measurements::default();
        let names = ["thermal_growth.k", "thermal_growth.ln_tau"];
        assert_eq!(
            TimeUnit::of_calibration(names, &untimed),
            Some(TimeUnit::PoseOrder)
        );
        assert_eq!(TimeUnit::of_calibration(["drift", "scale"], &untimed), None);
        for u in [TimeUnit::Seconds, TimeUnit::PoseOrder] {
            let yaml = serde_yaml::to_string(&u).unwrap_or_default();
            assert_eq!(yaml.trim(), u.word());
            assert_eq!(serde_yaml::from_str::<TimeUnit>(u.word()).ok(), Some(u));
        }
    }

    #[test]
    fn the_start_grid_spans_the_sequence() {
        let g = ThermalGrowth.shape_grid(7200.0);
        assert_eq!(g.len(), GRID_POINTS);
        assert!((g[0].exp() - 240.0).abs() < 1e-9);
        assert!((g[GRID_POINTS - 1].exp() - 21600.0).abs() < 1e-6);
        assert!(ThermalGrowth.shape_grid(0.0).is_empty());
        assert!(ThermalGrowth.shape_grid(f64::NAN).is_empty());
    }
}
