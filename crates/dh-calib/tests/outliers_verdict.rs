//! Outliers and the verdict on the final model, on simulated sets with the fault planted:
//! 1 % of the points 2-5 mm off, one point a metre off, an effect outside the library.

mod fit_support;

use dh_calib::calibrate::{calibrate, CalibrationOptions, Report};
use dh_calib::data::Measurements;
use dh_calib::diagnose::{diagnose, DiagnoseOptions};
use dh_calib::findings::NoiseTest;
use dh_calib::outliers::{threshold, OutlierOptions, DEFAULT_LEVEL};
use dh_calib::simulate::{simulate, Errors, SimulationOptions};
use fit_support::ur5;
use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const SIGMA: f64 = 1e-4;

fn clean(seed: u64, poses: usize, repeats: usize) -> Measurements {
    let (mut m, _) = simulate(
        &ur5(),
        &SimulationOptions {
            seed,
            poses,
            sigma: SIGMA,
            errors: Errors::Random {
                length: 1e-3,
                angle: 2e-3,
            },
            validation_fraction: 0.2,
            repeats,
            ..Default::default()
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    // As if read from a file: the line names the sample.
    for (i, s) in m.samples.iter_mut().enumerate() {
        s.line = i + 2;
    }
    m
}

/// Moves `count` calibration samples (chosen at random) by `lo..hi` metres in a random
/// direction; returns their file lines, sorted.
fn plant(m: &mut Measurements, seed: u64, count: usize, lo: f64, hi: f64) -> Vec<usize> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let cal: Vec<usize> = (0..m.samples.len())
        .filter(|&i| m.samples[i].split == dh_calib::data::Split::Calibration)
        .collect();
    let mut lines = Vec::new();
    while lines.len() < count {
        let i = cal[rng.random_range(0..cal.len())];
        if lines.contains(&m.samples[i].line) {
            continue;
        }
        let d = Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        if d.norm() < 0.1 {
            continue;
        }
        m.samples[i].point += d.normalize() * rng.random_range(lo..hi);
        lines.push(m.samples[i].line);
    }
    lines.sort_unstable();
    lines
}

fn without_sigma(m: &mut Measurements) {
    for s in &mut m.samples {
        s.sigma = None;
    }
}

fn named(r: &Report) -> Vec<usize> {
    let mut v: Vec<usize> = r
        .outliers
        .as_ref()
        .map(|o| o.outliers.iter().map(|p| p.line).collect())
        .unwrap_or_default();
    v.sort_unstable();
    v
}

fn floor(r: &Report) -> f64 {
    r.noise_floor.as_ref().map_or(f64::NAN, |f| f.rms)
}

#[test]
fn clean_sets_name_nothing() {
    for seed in 1..=3 {
        for known in [true, false] {
            let mut m = clean(seed, 400, 1);
            if !known {
                without_sigma(&mut m);
            }
            let r = calibrate(&ur5(), &m, &CalibrationOptions::default()).unwrap();
            assert_eq!(named(&r), Vec::<usize>::new(), "seed {seed} known {known}");
            if known {
                assert_eq!(r.verdict.summary, "model complete", "seed {seed}");
                assert_eq!(r.verdict.complete, Some(true));
            } else {
                assert_eq!(r.verdict.summary, "no test possible", "seed {seed}");
                assert_eq!(r.verdict.complete, None);
                assert!(r.verdict.notes[0].contains("no test"));
            }
        }
    }
}

#[test]
fn one_percent_millimetres_off_are_named_and_left_out() {
    for seed in 1..=2 {
        for known in [true, false] {
            let mut m = clean(seed, 400, 1);
            if !known {
                without_sigma(&mut m);
            }
            let planted = plant(&mut m, seed, 3, 2e-3, 5e-3);
            let r = calibrate(&ur5(), &m, &CalibrationOptions::default()).unwrap();
            assert_eq!(named(&r), planted, "seed {seed} known {known}");
            let o = r.outliers.as_ref().unwrap();
            assert!(o.rms_with > 1.8 * o.rms_without, "{o:?}");
            for p in &o.outliers {
                assert!(p.residual > 1.5e-3 && p.sigmas > o.threshold, "{p:?}");
                assert!(p.config.is_some() && p.target == "t1");
            }
            // Without them the fit sits on the noise.
            let clean_floor = (3.0f64).sqrt() * SIGMA;
            assert!(
                r.rms_after < 1.1 * clean_floor,
                "seed {seed}: {}",
                r.rms_after
            );
            if known {
                assert_eq!(r.verdict.summary, "model complete", "seed {seed}");
            }
            // Kept: still named, and the verdict says the residual is not noise.
            let keep = CalibrationOptions {
                outliers: OutlierOptions {
                    keep: true,
                    ..Default::default()
                },
                ..Default::default()
            };
            let k = calibrate(&ur5(), &m, &keep).unwrap();
            assert_eq!(named(&k), planted);
            assert!(k.outliers.as_ref().unwrap().kept);
            assert!(k.rms_after > 1.8 * r.rms_after);
            if known {
                assert_eq!(k.verdict.complete, Some(false));
                assert!(k.verdict.summary.starts_with("residual remains: "));
            }
        }
    }
}

#[test]
fn a_point_a_metre_off_spoils_nothing() {
    for seed in 1..=3 {
        let reference = calibrate(&ur5(), &clean(seed, 300, 1), &Default::default()).unwrap();
        let mut m = clean(seed, 300, 1);
        let planted = plant(&mut m, seed + 10, 1, 1.0, 1.0 + 1e-9);
        let r = calibrate(&ur5(), &m, &CalibrationOptions::default()).unwrap();
        assert_eq!(named(&r), planted, "seed {seed}");
        let o = r.outliers.as_ref().unwrap();
        assert!((o.outliers[0].residual - 1.0).abs() < 0.01, "{o:?}");
        assert!(o.rms_with > 0.02, "{o:?}");
        assert!((r.rms_after - reference.rms_after).abs() < 0.05 * reference.rms_after);
        let (a, b) = (r.val_rms_after.unwrap(), reference.val_rms_after.unwrap());
        assert!((a - b).abs() < 0.05 * b, "validation {a} vs {b}");
        assert_eq!(r.verdict.summary, "model complete");
    }
}

#[test]
fn a_far_validation_point_is_named_and_left_out_of_the_figures() {
    let mut m = clean(4, 300, 1);
    let i = m
        .samples
        .iter()
        .position(|s| s.split == dh_calib::data::Split::Validation)
        .unwrap();
    m.samples[i].point.x += 0.01;
    let r = calibrate(&ur5(), &m, &CalibrationOptions::default()).unwrap();
    let o = r.outliers.as_ref().unwrap();
    assert_eq!(o.outliers.len(), 1);
    assert!(o.outliers[0].validation && o.outliers[0].line == m.samples[i].line);
    assert!(r.val_rms_after.unwrap() < 1.2 * floor(&r));
}

/// A periodic error of the measured points no library effect models (a device-side ripple
/// with the base joint): the final model must not pass.
#[test]
fn an_effect_outside_the_library_leaves_residual_remains() {
    for seed in 1..=2 {
        let mut m = clean(seed, 300, 1);
        for s in &mut m.samples {
            s.point.x += 5e-4 * (3.0 * s.q[0] + 0.4).sin();
            s.point.z += 4e-4 * (2.0 * s.q[3]).cos();
        }
        let r = diagnose(
            &ur5(),
            &m,
            &CalibrationOptions::default(),
            &DiagnoseOptions::default(),
        )
        .unwrap();
        assert_eq!(r.verdict.complete, Some(false), "seed {seed}");
        assert_eq!(r.verdict.test.kind, NoiseTest::KnownSigma);
        let ratio = r.verdict.ratio.unwrap();
        assert!(ratio > 1.5, "seed {seed}: {ratio}");
        assert_eq!(
            r.verdict.summary,
            format!("residual remains: {ratio:.2} x the floor")
        );
        assert!(
            r.verdict.structure.iter().any(|s| s.significant),
            "seed {seed}: {:?}",
            r.verdict.structure
        );
        if !r.selected_effects.is_empty() {
            assert!(r.verdict.notes.iter().any(|n| n.contains("stand in")));
        }
        // A ripple is not a handful of far points: nothing is named.
        assert!(named(&r).len() <= 2, "seed {seed}: {:?}", named(&r));
    }
}

#[test]
fn repeated_poses_give_the_pure_error_test() {
    let mut m = clean(5, 120, 3);
    without_sigma(&mut m);
    let r = calibrate(&ur5(), &m, &CalibrationOptions::default()).unwrap();
    assert_eq!(r.verdict.test.kind, NoiseTest::PureError);
    assert_eq!(r.verdict.complete, Some(true), "{:?}", r.verdict.test);
    for s in &mut m.samples {
        s.point.y += 6e-4 * (2.0 * s.q[1]).sin();
    }
    let r = calibrate(&ur5(), &m, &CalibrationOptions::default()).unwrap();
    assert_eq!(r.verdict.test.kind, NoiseTest::PureError);
    assert_eq!(r.verdict.complete, Some(false), "{:?}", r.verdict.test);
}

#[test]
fn the_threshold_is_a_bonferroni_bound() {
    // 5.1 sigma at 1000 points, growing slowly with N.
    let t = threshold(1000, DEFAULT_LEVEL);
    assert!((t - 5.09).abs() < 0.02, "{t}");
    assert!(threshold(100_000, DEFAULT_LEVEL) < 6.0);
}
