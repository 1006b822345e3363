//! Outliers judged against the final model (`dh_calib::diagnose::diagnose_tree`): poses that
//! only an unmodelled effect puts far off the geometric fit are outliers of the geometric
//! step, not of the model with the effect. Planted: a gear-ratio error on the UR5's shoulder
//! lift (3e-3 rad/rad), 80 poses with that joint within ±40° and 6 poses near 180° (where the
//! error is five times larger), 30 µm of noise, and one true outlier 5 mm off.

mod fit_support;

use dh_calib::calibrate::{screen, CalibrationOptions, Report};
use dh_calib::data::{Measurements, Split};
use dh_calib::diagnose::{diagnose, DiagnoseOptions};
use dh_calib::simulate::{simulate, Errors, SimulationOptions};
use dh_core::pose::from_xyz_rpy;
use dh_core::{DhTable, Limits};
use nalgebra::Vector3;

const SIGMA: f64 = 3e-5;
const RATIO: f64 = 3e-3;

/// `poses` poses of the UR5 with its shoulder lift (`j2`) within `[lower, upper]` degrees, the
/// others anywhere, measured by one device on two fixed targets, with the effects `planted`;
/// configs prefixed by `tag`.
fn poses(
    poses: usize,
    lower: f64,
    upper: f64,
    seed: u64,
    tag: &str,
    planted: &[(&str, f64)],
) -> Measurements {
    let mut table: DhTable = fit_support::ur5();
    table.rows[1].limits = Some(Limits {
        lower: lower.to_radians(),
        upper: upper.to_radians(),
    });
    let (mut m, _) = simulate(
        &table,
        &SimulationOptions {
            seed,
            poses,
            sigma: SIGMA,
            targets: Some(vec![
                Vector3::new(0.03, 0.0, 0.05),
                Vector3::new(-0.02, 0.04, 0.03),
            ]),
            device: Some(from_xyz_rpy([1.2, -0.4, 0.3], [0.0, 0.0, 2.0])),
            effects: planted.iter().map(|(l, _)| l.to_string()).collect(),
            errors: Errors::Explicit(planted.iter().map(|(l, v)| (l.to_string(), *v)).collect()),
            validation_fraction: 0.0,
            ..Default::default()
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    for s in &mut m.samples {
        s.config = s.config.as_ref().map(|c| format!("{tag}{c}").into());
    }
    m
}

/// The narrow and the wide poses in one file (lines numbered), and the line of the true
/// outlier planted in the narrow ones.
fn data() -> (Measurements, Vec<usize>, usize) {
    data_with(&[("gear_ratio:j2", RATIO)])
}

/// [`data`] with these effects planted.
fn data_with(planted: &[(&str, f64)]) -> (Measurements, Vec<usize>, usize) {
    let mut m = poses(80, -40.0, 40.0, 11, "n", planted);
    let wide = poses(6, 160.0, 180.0, 12, "w", planted);
    let first_wide = m.samples.len();
    m.samples.extend(wide.samples);
    for (i, s) in m.samples.iter_mut().enumerate() {
        s.line = i + 2;
        assert_eq!(s.split, Split::Calibration);
    }
    let wide_lines = (first_wide..m.samples.len()).map(|i| i + 2).collect();
    m.samples[17].point += Vector3::new(3e-3, -4e-3, 0.0);
    let planted = m.samples[17].line;
    (m, wide_lines, planted)
}

/// The automatic diagnosis of `m` with the default options.
fn diagnose_auto(m: &Measurements) -> Report {
    diagnose(
        &fit_support::ur5(),
        m,
        &CalibrationOptions::default(),
        &DiagnoseOptions::default(),
    )
    .unwrap()
}

fn named(r: &Report) -> Vec<usize> {
    r.outliers
        .as_ref()
        .map(|o| o.outliers.iter().map(|p| p.line).collect())
        .unwrap_or_default()
}

#[test]
fn the_geometric_screen_alone_leaves_the_loaded_poses_out() {
    // The premise: against the geometry alone, the far poses are outliers.
    let (m, wide, _) = data();
    let table = fit_support::ur5();
    let s = screen(
        &dh_calib::tree::DhTree::serial(&table),
        &m,
        &CalibrationOptions::default(),
    )
    .unwrap();
    let flagged: Vec<usize> = s.outliers.iter().map(|o| o.line).collect();
    let wide_flagged = wide.iter().filter(|l| flagged.contains(l)).count();
    assert!(wide_flagged >= 6, "{flagged:?} of {wide:?}");
    assert!(s.effects.is_empty());
}

#[test]
fn the_diagnosis_judges_the_outliers_again_with_the_effect_it_found() {
    let (m, wide, planted) = data();
    let r = diagnose_auto(&m);
    assert_eq!(r.selected_effects, vec!["gear_ratio:j2".to_string()]);
    // Only the true outlier is left out; the loaded poses are back in the fit.
    assert_eq!(named(&r), vec![planted], "wide poses on lines {wide:?}");
    let scan = r.outliers.as_ref().unwrap();
    assert_eq!(scan.effects, vec!["gear_ratio:j2".to_string()]);
    assert!(
        r.notes.iter().any(|n| n.contains("outliers judged again")),
        "{:?}",
        r.notes
    );
    // With the far poses in, the ratio is estimated from the whole range: within 3 standard
    // errors of the planted value, and the fit is at the noise.
    let p = r
        .parameters
        .iter()
        .find(|p| p.name == "gear_ratio:j2")
        .unwrap();
    let se = p.std_error.unwrap();
    assert!(
        (p.estimate - RATIO).abs() < 3.0 * se,
        "{} ± {se}",
        p.estimate
    );
    assert!(r.rms_after < 1.2 * SIGMA * 3f64.sqrt(), "{}", r.rms_after);
}

#[test]
fn declared_effects_judge_the_outliers_from_the_start() {
    let (m, _, planted) = data();
    let table = fit_support::ur5();
    let r = diagnose(
        &table,
        &m,
        &CalibrationOptions::default(),
        &DiagnoseOptions {
            effects: dh_calib::diagnose::EffectSelection::Labels(vec!["gear_ratio:j2".into()]),
            ..DiagnoseOptions::default()
        },
    )
    .unwrap();
    assert_eq!(named(&r), vec![planted]);
    // No second pass was needed.
    assert!(
        !r.notes.iter().any(|n| n.contains("judged again")),
        "{:?}",
        r.notes
    );
}

/// With a second, smaller effect planted, the points left out are judged again as soon as the
/// first effect is in: the selection runs again from there, and the note names that effect
/// alone; the final model has both and leaves out only the true outlier.
#[test]
fn the_outliers_are_judged_again_as_soon_as_an_effect_is_in() {
    let (m, _, planted_line) = data_with(&[("gear_ratio:j2", RATIO), ("gear_ratio:j3", 5e-4)]);
    let r = diagnose_auto(&m);
    assert_eq!(
        r.selected_effects,
        vec!["gear_ratio:j2".to_string(), "gear_ratio:j3".to_string()]
    );
    assert_eq!(named(&r), vec![planted_line]);
    let note = r
        .notes
        .iter()
        .find(|n| n.contains("outliers judged again"))
        .unwrap_or_else(|| panic!("{:?}", r.notes));
    assert!(
        note.contains("against the geometry and gear_ratio:j2: 1 point(s) left out"),
        "{note}"
    );
    assert_eq!(
        r.outliers.as_ref().unwrap().effects,
        vec!["gear_ratio:j2".to_string()]
    );
    // The points given back were judged against a model of one effect: judged against the
    // final one of two, none of them is an outlier either, and a note says so.
    assert!(
        r.notes.iter().any(|n| n.starts_with("none of the ")
            && n.contains("point(s) given back is an outlier of the final model (the geometry and 2 effect(s)")),
        "{:?}",
        r.notes
    );
}
