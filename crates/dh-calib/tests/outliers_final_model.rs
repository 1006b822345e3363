//! Outliers judged against the final model, validation points included (issue 33 §4): a
//! clean held-out pose that only an unmodelled effect puts far off the geometric fit must be
//! given back once the model has the effect, and the report must say so with both figures.
//!
//! Planted: a direction backlash of 70 µrad on the UR5's shoulder lift (`j2`), in a sequence
//! that sweeps `j2` upward and reverses it at every fourth pose only, so the backlash offset
//! is absorbed by the geometric fit except at the 25 reversed poses, which it puts off by
//! up to about 100 µm; 20 µm of tracker noise per axis; 100 poses, the two reversed poses
//! farthest off and every fifth of the others held out for validation (17 samples). Of those
//! two, the geometric screen leaves one out (5.2 sigma against a validation threshold of
//! 4.2); the diagnosis finds the backlash, with which the pose is 1.9 sigma off. A real
//! lost-beam point (3 mm, calibration) must stay named, and no other.

mod fit_support;

use dh_calib::calibrate::{screen, CalibrationOptions, Report, Validation};
use dh_calib::data::{Measurements, Split};
use dh_calib::diagnose::{diagnose, DiagnoseOptions};
use dh_calib::effects::parse_label;
use dh_calib::model::ModelOptions;
use dh_calib::simulate::{plant_effects, simulate, Errors, SimulationOptions};
use dh_calib::tree::DhTree;
use dh_core::pose::from_xyz_rpy;
use nalgebra::Vector3;

/// Tracker noise per axis (metres).
const SIGMA: f64 = 2e-5;
/// The planted direction backlash of `j2` (radians).
const BACKLASH: f64 = 7e-5;
/// Every this many poses of the upward sweep, the joint's direction is reversed once.
const REVERSE_EVERY: usize = 4;

/// The set (lines numbered from 2), whether each sample's pose was reached moving `j2`
/// downward, and the line of the lost-beam point.
fn data() -> (Measurements, Vec<bool>, usize) {
    let table = fit_support::ur5();
    let (mut m, truth) = simulate(
        &table,
        &SimulationOptions {
            seed: 3,
            poses: 100,
            sigma: SIGMA,
            errors: Errors::Random {
                length: 5e-4,
                angle: 1e-3,
            },
            device: Some(from_xyz_rpy([1.5, -0.5, 0.4], [0.0, 0.0, 2.5])),
            validation_fraction: 0.0,
            ..Default::default()
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    // The sweep: j2 upward, swapping neighbours every few poses (the second of each swapped
    // pair is approached downward).
    m.samples.sort_by(|a, b| a.q[1].total_cmp(&b.q[1]));
    let mut reversed = vec![false; m.samples.len()];
    let mut k = REVERSE_EVERY / 2;
    while k + 1 < m.samples.len() {
        m.samples.swap(k, k + 1);
        reversed[k + 1] = true;
        k += REVERSE_EVERY;
    }
    for (i, s) in m.samples.iter_mut().enumerate() {
        s.line = i + 2;
        s.config = Some(format!("p{i}").into());
    }
    let clean = m.clone();
    plant_effects(
        &table,
        &mut m,
        &truth,
        &[(
            parse_label("backlash_direction:j2", &table).unwrap_or_else(|e| panic!("{e}")),
            vec![BACKLASH],
        )],
        &ModelOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    // Held out: the two reversed poses the backlash moves most, and every fifth other pose.
    let mut moved: Vec<(f64, usize)> = (0..m.samples.len())
        .filter(|&i| reversed[i])
        .map(|i| ((m.samples[i].point - clean.samples[i].point).norm(), i))
        .collect();
    moved.sort_by(|a, b| b.0.total_cmp(&a.0));
    for &(_, i) in moved.iter().take(2) {
        m.samples[i].split = Split::Validation;
    }
    for (i, s) in m.samples.iter_mut().enumerate() {
        if !reversed[i] && i % 5 == 3 {
            s.split = Split::Validation;
        }
    }
    // A lost beam on a calibration pose approached upward.
    let lost = 20;
    assert_eq!(m.samples[lost].split, Split::Calibration);
    assert!(!reversed[lost]);
    m.samples[lost].point += Vector3::new(3e-3, -1e-3, 0.0);
    let line = m.samples[lost].line;
    (m, reversed, line)
}

fn named(r: &Report) -> Vec<usize> {
    r.outliers
        .as_ref()
        .map(|o| o.outliers.iter().map(|p| p.line).collect())
        .unwrap_or_default()
}

#[test]
fn the_geometric_screen_leaves_a_clean_reversed_validation_pose_out() {
    // The premise: against the geometry alone, one reversed held-out pose is beyond the
    // validation threshold, besides the lost beam.
    let (m, reversed, lost) = data();
    let s = screen(
        &DhTree::serial(&fit_support::ur5()),
        &m,
        &CalibrationOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let clean: Vec<_> = s.outliers.iter().filter(|o| o.line != lost).collect();
    assert_eq!(clean.len(), 1, "{:?}", s.outliers);
    let o = clean[0];
    assert!(o.validation && reversed[o.line - 2], "{o:?}");
    assert!(o.sigmas > s.validation_threshold, "{o:?}");
    assert!(s.outliers.iter().any(|o| o.line == lost && !o.validation));
}

#[test]
fn a_clean_validation_pose_is_given_back_by_the_final_model() {
    let (m, reversed, lost) = data();
    let r = diagnose(
        &fit_support::ur5(),
        &m,
        &CalibrationOptions::default(),
        &DiagnoseOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        r.selected_effects,
        vec!["backlash_direction:j2".to_string()]
    );
    // Only the lost beam stays out: no false outlier, no missed one.
    assert_eq!(named(&r), vec![lost], "{:?}", r.outliers);
    let o = r.outliers.as_ref().unwrap_or_else(|| panic!("no screen"));
    // The reversed pose is given back, with its figures against both models.
    assert_eq!(o.given_back.len(), 1, "{:?}", o.given_back);
    let g = &o.given_back[0];
    assert!(g.validation && reversed[g.line - 2], "{g:?}");
    assert!(g.before.effects.is_empty(), "{g:?}");
    assert!(g.before.sigmas > g.before.threshold, "{g:?}");
    assert_eq!(g.after.effects, vec!["backlash_direction:j2".to_string()]);
    assert!(g.after.sigmas < 0.5 * g.after.threshold, "{g:?}");
    let reason = g.reason();
    assert!(
        reason.contains("sigma against the geometric model, ")
            && reason.ends_with("sigma against the geometry and backlash_direction:j2"),
        "{reason}"
    );
    // The held-out figures include it: every held-out sample.
    let held_out = m
        .samples
        .iter()
        .filter(|s| s.split == Split::Validation)
        .count();
    assert_eq!(held_out, 17);
    assert_eq!(r.validation, Validation::Split { samples: held_out });
    assert!(
        r.notes.iter().any(|n| n.contains("outliers judged again")),
        "{:?}",
        r.notes
    );
    // The backlash estimate covers the truth, and the model is complete.
    let p = r
        .parameters
        .iter()
        .find(|p| p.name == "backlash_direction:j2")
        .unwrap_or_else(|| panic!("{:?}", r.parameters));
    let se = p.std_error.unwrap_or(f64::INFINITY);
    assert!(
        (p.estimate - BACKLASH).abs() < 3.0 * se,
        "{} ± {se}",
        p.estimate
    );
    assert_eq!(r.verdict.summary, "model complete");
}
