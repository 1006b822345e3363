//! Structure over time and gravity (issue 33 §2, §5), on simulated data: an arm warming up
//! (every link length growing along an exponential in time) is the library's
//! `thermal_growth`, fitted with its time constant from the samples' times (or their order);
//! a length change of another shape in time, and a wrist sagging along gravity in proportion to
//! its reach cubed, are named by the verdict's structure tests (time; the gravity lever arm of
//! a joint); with nothing planted, or a warm-up below detectability, nothing is selected or
//! named. Each run prints its figures (`--nocapture`).
#![allow(clippy::print_stdout)]
mod diagnose_support;

use dh_calib::calibrate::{CalibrationOptions, Report};
use dh_calib::data::{Measurements, Sample, Split};
use dh_calib::diagnose::{diagnose, DiagnoseOptions};
use dh_calib::model::{Block, Model, ModelOptions};
use dh_core::{Convention, DhTable, JointSampler};
use diagnose_support::{industrial, step_summaries, Arm};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

/// Poses of a set: every fifth pair of five is validation (interleaved in time).
const POSES: usize = 250;

/// The session's length (seconds): a 2 h warm-up.
const SESSION: f64 = 7200.0;

/// What a generated set planted and how big it is.
struct Planted {
    data: Measurements,
    /// RMS 3-D displacement of the calibration points by the planted structure (metres).
    displacement: f64,
}

fn random_pose(rng: &mut ChaCha8Rng, distance: f64) -> Isometry3<f64> {
    let mut g = || rng.sample::<f64, _>(StandardNormal);
    let rot = UnitQuaternion::from_quaternion(Quaternion::new(g(), g(), g(), g()));
    let dir = Vector3::new(g(), g(), g()).normalize();
    Isometry3::from_parts(Translation3::from(dir * distance), rot)
}

/// `POSES` random poses of `arm` in sequence, `t = k / (POSES − 1) · SESSION` seconds, with
/// ±1 mm / ±1 mrad geometric errors, a random device frame and target, noise `arm.sigma`
/// per axis, and `plant(k, t, q, p)`: a displacement (metres, robot base frame) of the target
/// at `p` (base frame) in pose `k` at time `t`. The samples carry no clock (their order is
/// their time) unless `clock`: then each carries `t` plus an origin of 1 h (seconds).
fn generate(
    arm: &Arm,
    seed: u64,
    plant: impl Fn(usize, f64, &[f64], Vector3<f64>) -> Vector3<f64>,
) -> Planted {
    generate_timed(arm, seed, false, plant)
}

fn generate_timed(
    arm: &Arm,
    seed: u64,
    clock: bool,
    plant: impl Fn(usize, f64, &[f64], Vector3<f64>) -> Vector3<f64>,
) -> Planted {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let table = &arm.table;
    let mut m = Model::new(table, &["t1".to_string()], &ModelOptions::default()).unwrap();
    let device = random_pose(&mut rng, 2.0 * table.size());
    m.set_device(&device);
    m.set_target(0, Vector3::from_fn(|_, _| rng.random_range(-0.1..0.1)));
    let mut x = vec![0.0; m.parameter_count()];
    for (c, p) in m.parameters().iter().enumerate() {
        if matches!(p.block, Block::Joint(_)) {
            x[c] = rng.random_range(-1.0..1.0) * 1e-3;
        }
    }
    let mut sampler = JointSampler::new(&table.rows, table.size(), rng.random());
    let mut samples = Vec::with_capacity(POSES);
    let mut moved = 0.0;
    let mut cal = 0usize;
    for k in 0..POSES {
        let mut q = Vec::new();
        sampler.next_into(&mut q);
        let t = k as f64 / (POSES - 1) as f64 * SESSION;
        let p = device
            .inverse_transform_point(&m.point(&x, &q, 0).into())
            .coords;
        let d = plant(k, t, &q, p);
        let noise = Vector3::from_fn(|_, _| rng.sample::<f64, _>(StandardNormal) * arm.sigma);
        let split = if k % 5 < 3 {
            Split::Calibration
        } else {
            Split::Validation
        };
        if split == Split::Calibration {
            moved += d.norm_squared();
            cal += 1;
        }
        samples.push(Sample {
            time: clock.then_some(3600.0 + t),
            orientation: None,
            session: 0,
            q: q.as_slice().into(),
            target: 0,
            point: device.transform_point(&(p + d).into()).coords + noise,
            sigma: Some(Vector3::repeat(arm.sigma)),
            config: Some(format!("p{k}").into()),
            split,
            line: 0,
            socket: None,
        });
    }
    Planted {
        data: Measurements {
            sessions: Vec::new(),
            joint_names: table.rows.iter().map(|r| r.name.clone()).collect(),
            targets: vec!["t1".into()],
            samples,
        },
        displacement: (moved / cal as f64).sqrt(),
    }
}

/// The gravity lever arm (metres) of the tip about joint `row`'s axis at `q`: `z · ((p − o) ×
/// ĝ)` with the axis through `o` along `z`, `p` the tip and `ĝ = −z` of the base frame.
fn lever(table: &DhTable, q: &[f64], row: usize) -> f64 {
    let frames = table.frames(q).unwrap();
    let axis = match table.convention {
        Convention::Standard => frames[row],
        Convention::Modified => frames[row + 1],
    };
    let tip = frames[table.rows.len()] * table.tool;
    let z = axis.rotation * Vector3::z();
    let arm = tip.translation.vector - axis.translation.vector;
    z.dot(&arm.cross(&-Vector3::z()))
}

fn run(arm: &Arm, data: &Measurements) -> Report {
    let diag = DiagnoseOptions {
        inertials: Some(arm.inertials.clone()),
        ..DiagnoseOptions::default()
    };
    diagnose(&arm.table, data, &CalibrationOptions::default(), &diag).unwrap()
}

fn describe(r: &Report) -> String {
    let structure: Vec<String> = r
        .verdict
        .structure
        .iter()
        .map(|s| {
            format!(
                "{} p {:.2e}{}",
                s.variable,
                s.p_value,
                if s.significant { " *" } else { "" }
            )
        })
        .collect();
    format!(
        "steps [{}]; selected {:?}; verdict {}; notes {:?}; structure [{}]; outliers {:?}",
        step_summaries(r).join(", "),
        r.selected_effects,
        r.verdict.summary,
        r.verdict.notes,
        structure.join(", "),
        r.outliers.as_ref().map(|o| o.outliers.len())
    )
}

/// Link lengths growing by `k (1 − exp(−t/τ))`: the target's base-frame position scales so.
fn warm_up(arm: &Arm, k: f64, tau: f64, seed: u64) -> Planted {
    warm_up_timed(arm, k, tau, seed, false)
}

/// [`warm_up`], its samples carrying their time when `clock`.
fn warm_up_timed(arm: &Arm, k: f64, tau: f64, seed: u64, clock: bool) -> Planted {
    generate_timed(arm, seed, clock, |_, t, _, p| {
        p * (k * (1.0 - (-t / tau).exp()))
    })
}

/// A tracker's noise (25 um per axis), where a 60 ppm warm-up leaves the geometric model
/// above the floor.
fn tracked() -> Arm {
    Arm {
        sigma: 25e-6,
        ..industrial()
    }
}

/// The estimate and standard error of parameter `name` in `r`.
fn estimate(r: &Report, name: &str) -> (f64, f64) {
    let p = r
        .parameters
        .iter()
        .find(|p| p.name == name)
        .unwrap_or_else(|| panic!("no parameter {name}"));
    (p.estimate, p.std_error.unwrap_or(f64::NAN))
}

/// A warm-up of 60 ppm with a time constant of 20 min over 2 h whose samples carry their time
/// (a `time` column): the library's `thermal_growth` is selected, its `k` and `tau` come back
/// within three standard errors (this set's `k` is 2.2 of them off: see the next test for the
/// bias over sets) and each well resolved, the model is complete and no pose is left out
/// (before it, the code ended "residual remains: 1.15 x the floor" with 4 clean poses left
/// out).
#[test]
fn a_timed_warm_up_is_fitted_as_thermal_growth() {
    let arm = tracked();
    let set = warm_up_timed(&arm, 60e-6, 1200.0, 3301, true);
    let r = run(&arm, &set.data);
    let (k, k_se) = estimate(&r, "thermal_growth.k");
    let (ln_tau, ln_tau_se) = estimate(&r, "thermal_growth.ln_tau");
    let info = format!(
        "planted {:.1} um: k {:.2} +- {:.2} ppm, tau {:.0} s (ln {ln_tau:.3} +- {ln_tau_se:.3}): {}",
        set.displacement * 1e6,
        k * 1e6,
        k_se * 1e6,
        ln_tau.exp(),
        describe(&r)
    );
    println!("{info}");
    assert_eq!(
        r.selected_effects,
        vec!["thermal_growth".to_string()],
        "{info}"
    );
    assert!((k - 60e-6).abs() < 3.0 * k_se && k_se < 6e-6, "{info}");
    assert!(
        (ln_tau - 1200f64.ln()).abs() < 3.0 * ln_tau_se && ln_tau_se < 0.25,
        "{info}"
    );
    assert_eq!(r.verdict.summary, "model complete", "{info}");
    assert_eq!(
        r.outliers.as_ref().map(|o| o.outliers.len()),
        Some(0),
        "{info}"
    );
    assert!(r.verdict.structure.iter().all(|s| !s.significant), "{info}");
    assert!(
        !r.notes.iter().any(|n| n.contains("no `time` column")),
        "{info}"
    );
}

/// Eight timed warm-ups (new seeds): each is selected and complete, and the estimates are
/// unbiased with honest standard errors: the mean of `(estimate − truth) / std_error` over the
/// eight is within two of its own standard errors (`1/√8`) of 0, each within 3.
#[test]
fn thermal_growth_estimates_are_unbiased_over_sets() {
    let arm = tracked();
    let (mut zk, mut zt) = (Vec::new(), Vec::new());
    for seed in 3310..3318 {
        let set = warm_up_timed(&arm, 60e-6, 1200.0, seed, true);
        let r = run(&arm, &set.data);
        assert_eq!(
            r.selected_effects,
            vec!["thermal_growth".to_string()],
            "seed {seed}"
        );
        assert_eq!(r.verdict.summary, "model complete", "seed {seed}");
        let (k, k_se) = estimate(&r, "thermal_growth.k");
        let (ln_tau, ln_tau_se) = estimate(&r, "thermal_growth.ln_tau");
        zk.push((k - 60e-6) / k_se);
        zt.push((ln_tau - 1200f64.ln()) / ln_tau_se);
    }
    println!("z of k {zk:.2?}; z of ln tau {zt:.2?}");
    for z in [&zk, &zt] {
        let mean = z.iter().sum::<f64>() / z.len() as f64;
        assert!(mean.abs() < 2.0 / (z.len() as f64).sqrt(), "{zk:?} {zt:?}");
        assert!(z.iter().all(|v| v.abs() < 3.0), "{zk:?} {zt:?}");
    }
}

/// The same warm-up without a clock: `t` is the pose order in `[0, 1]` (the poses are evenly
/// spaced in time here), so `tau` comes back as a fraction of the session (1/6) and a note
/// says what `t` was.
#[test]
fn an_untimed_warm_up_is_fitted_against_the_pose_order_and_says_so() {
    let arm = tracked();
    let set = warm_up_timed(&arm, 60e-6, 1200.0, 3301, false);
    let r = run(&arm, &set.data);
    let (k, k_se) = estimate(&r, "thermal_growth.k");
    let (ln_tau, ln_tau_se) = estimate(&r, "thermal_growth.ln_tau");
    let info = format!(
        "k {:.2} +- {:.2} ppm, tau {:.4} (ln {ln_tau:.3} +- {ln_tau_se:.3}): {}; notes {:?}",
        k * 1e6,
        k_se * 1e6,
        ln_tau.exp(),
        describe(&r),
        r.notes
    );
    println!("{info}");
    assert_eq!(
        r.selected_effects,
        vec!["thermal_growth".to_string()],
        "{info}"
    );
    assert!(
        (ln_tau - (1.0f64 / 6.0).ln()).abs() < 3.0 * ln_tau_se,
        "{info}"
    );
    assert!((k - 60e-6).abs() < 3.0 * k_se, "{info}");
    assert_eq!(r.verdict.summary, "model complete", "{info}");
    assert!(
        r.notes
            .iter()
            .any(|n| n.starts_with("thermal_growth: the samples carry no time")),
        "{info}"
    );
}

/// A robot length that grows and shrinks back over the session (half a sine in time, 60 ppm
/// at its peak): no library effect has that shape, so the verdict names the structure against
/// time.
#[test]
fn a_length_change_no_effect_has_shows_as_structure_against_time() {
    let arm = tracked();
    let set = generate(&arm, 3305, |_, t, _, p| {
        p * (60e-6 * (std::f64::consts::PI * t / SESSION).sin())
    });
    let r = run(&arm, &set.data);
    let info = format!("planted {:.1} um: {}", set.displacement * 1e6, describe(&r));
    println!("{info}");
    let time = r
        .verdict
        .structure
        .iter()
        .find(|s| s.variable == "time")
        .unwrap_or_else(|| panic!("no time test: {info}"));
    assert!(time.significant, "{info}");
    assert!(
        r.verdict
            .notes
            .iter()
            .any(|n| n.contains("structure against") && n.contains("time")),
        "{info}"
    );
}

/// A 60 ppm warm-up at 50 um of noise: the residual test finds the geometric model within the
/// noise, the time test still resolves the trend, and the verdict says so.
#[test]
fn a_warm_up_within_the_noise_is_still_named() {
    let arm = industrial();
    let set = warm_up(&arm, 60e-6, 1200.0, 3301);
    let r = run(&arm, &set.data);
    let info = format!("planted {:.1} um: {}", set.displacement * 1e6, describe(&r));
    println!("{info}");
    assert_eq!(r.verdict.summary, "model complete", "{info}");
    assert!(
        r.verdict.notes.iter().any(|n| n
            == "the final residual has structure against time (see the bins), though its size \
                is within the noise by the residual test"),
        "{info}"
    );
}

/// The same warm-up at 6 ppm, a tenth: below what the time test resolves at this noise, it
/// names nothing and nothing is added.
#[test]
fn a_warm_up_below_detectability_names_nothing() {
    let arm = tracked();
    let set = warm_up(&arm, 6e-6, 1200.0, 3304);
    let r = run(&arm, &set.data);
    let info = format!("planted {:.1} um: {}", set.displacement * 1e6, describe(&r));
    println!("{info}");
    assert!(r.selected_effects.is_empty(), "{info}");
    assert!(r.verdict.structure.iter().all(|s| !s.significant), "{info}");
}

/// A wrist moving along gravity by `c l³`, `l` the tip's gravity lever arm about joint a2
/// (signed: it rises on one side of the axis, which no sag does): the verdict must name
/// structure against a gravity variable (lever arm or torque) of a joint (today's code named
/// nothing and took stand-in effects). The library's `gravity_sag:a2` (`c |l|³`) takes the part
/// it explains; the odd part is left for the structure tests.
#[test]
fn a_sag_with_reach_cubed_is_named_against_gravity() {
    let arm = industrial();
    let table = arm.table.clone();
    // 40 um at a lever of 1 m, 0.1 mm at 1.35 m.
    let c = 4e-5;
    let set = generate(&arm, 3302, |_, _, q, _| {
        let l = lever(&table, q, 1);
        Vector3::new(0.0, 0.0, -c * l.powi(3))
    });
    let r = run(&arm, &set.data);
    let info = format!("planted {:.1} um: {}", set.displacement * 1e6, describe(&r));
    println!("{info}");
    assert!(
        r.verdict.structure.iter().any(|s| s.significant
            && (s.variable.starts_with("gravity lever at a")
                || s.variable.starts_with("gravity torque at a"))),
        "{info}"
    );
}

/// Nothing planted: none of the structure tests (joints, pose order, time, gravity levers)
/// fires.
#[test]
fn nothing_planted_names_no_structure() {
    let arm = industrial();
    let set = generate(&arm, 3303, |_, _, _, _| Vector3::zeros());
    let r = run(&arm, &set.data);
    let info = describe(&r);
    println!("{info}");
    assert!(r.selected_effects.is_empty(), "{info}");
    assert!(r.verdict.structure.iter().all(|s| !s.significant), "{info}");
    assert!(
        r.verdict.structure.iter().any(|s| s.variable == "time"),
        "{info}"
    );
    assert!(
        r.verdict
            .structure
            .iter()
            .any(|s| s.variable.starts_with("gravity lever at")),
        "{info}"
    );
}
