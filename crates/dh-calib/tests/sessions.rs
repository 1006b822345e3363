//! Measurement sessions (the device moved between days): each session's device frame is
//! estimated, the geometry shared; an unseen validation session's frame is fitted on its own
//! samples with the robot fixed.
mod fit_support;

use dh_calib::calibrate::{calibrate, CalibrationOptions, Report};
use dh_calib::csv::{parse_measurements, write_measurements, CsvOptions};
use dh_calib::simulate::{simulate, Errors, SimulationOptions, Truth};

const SIGMA: f64 = 20e-6;

/// 0.5 mm and 0.03 degree errors on parameters a UR5 calibration identifies.
fn planted() -> Vec<(String, f64)> {
    let deg = 0.03_f64.to_radians();
    vec![
        ("j2.a".into(), 5e-4),
        ("j3.a".into(), -5e-4),
        ("j5.d".into(), 5e-4),
        ("j4.alpha".into(), deg),
        ("j5.alpha".into(), -deg),
    ]
}

/// Three sessions of 60 poses each; the third is the validation split.
fn three_sessions() -> (dh_calib::data::Measurements, Truth) {
    simulate(
        &fit_support::ur5(),
        &SimulationOptions {
            seed: 7,
            poses: 180,
            sessions: 3,
            validation_fraction: 1.0 / 3.0,
            sigma: SIGMA,
            target_count: 3,
            errors: Errors::Explicit(planted()),
            ..Default::default()
        },
    )
    .unwrap()
}

fn estimate(r: &Report, name: &str) -> (f64, Option<f64>) {
    let p = r.parameters.iter().find(|p| p.name == name).unwrap();
    (p.estimate - p.nominal, p.std_error)
}

#[test]
fn sessions_recover_planted_errors_and_validate_an_unseen_session_at_the_noise_level() {
    let (data, truth) = three_sessions();
    assert_eq!(data.sessions, ["s1", "s2", "s3"]);
    // The CSV keeps the sessions.
    let names = data.joint_names.clone();
    let back = parse_measurements(&write_measurements(&data), &names, &CsvOptions::default());
    let back = back.unwrap();
    assert_eq!(back.sessions, data.sessions);
    assert!(back
        .samples
        .iter()
        .zip(&data.samples)
        .all(|(a, b)| a.session == b.session));

    let r = calibrate(&fit_support::ur5(), &data, &CalibrationOptions::default()).unwrap();
    for (name, truth) in planted() {
        let (err, se) = estimate(&r, &name);
        let se = se.unwrap_or_else(|| panic!("{name} is not estimated"));
        let z = (err - truth) / se;
        assert!(
            z.abs() < 3.0,
            "{name}: planted {truth:e}, found {err:e} ± {se:e}"
        );
    }
    let floor = r.noise_floor.as_ref().unwrap().rms;
    let ratio = r.rms_after / floor;
    assert!(
        (ratio - 1.0).abs() < 0.05,
        "rms {} vs floor {floor}",
        r.rms_after
    );
    assert_eq!(r.verdict.complete, Some(true), "{}", r.verdict.summary);
    // Every session's frame, the unseen third one fitted on its validation samples.
    assert_eq!(r.sessions.len(), 3);
    for (s, t) in r.sessions.iter().zip(&truth.sessions) {
        let d = s.device.inverse() * t;
        assert!(
            d.translation.vector.norm() < 1e-4 && d.rotation.angle() < 1e-4,
            "session {}: frame off by {} m, {} rad",
            s.name,
            d.translation.vector.norm(),
            d.rotation.angle()
        );
    }
    assert!(!r.sessions[0].fitted_on_validation && !r.sessions[1].fitted_on_validation);
    assert!(r.sessions[2].fitted_on_validation);
    assert!(r.notes.iter().any(|n| n.contains("session 's3'")));
    // Validation at the noise level: the 3-D noise RMS is sqrt(3) sigma.
    let val = r.val_rms_after.unwrap();
    let noise = 3f64.sqrt() * SIGMA;
    assert!(val < 1.15 * noise, "validation RMS {val} vs noise {noise}");
    for s in &r.sessions {
        let rms = s.rms.or(s.val_rms).unwrap();
        assert!(rms < 1.15 * noise, "session {}: {rms}", s.name);
    }
}

#[test]
fn one_frame_for_several_sessions_leaves_the_residual() {
    let (mut data, _) = three_sessions();
    data.sessions.clear();
    for s in &mut data.samples {
        s.session = 0;
    }
    let r = calibrate(&fit_support::ur5(), &data, &CalibrationOptions::default()).unwrap();
    let floor = r.noise_floor.as_ref().unwrap().rms;
    assert!(
        r.rms_after > 100.0 * floor,
        "rms {} floor {floor}",
        r.rms_after
    );
    assert_eq!(r.verdict.complete, Some(false));
    assert!(
        r.verdict.summary.contains("residual remains"),
        "{}",
        r.verdict.summary
    );
    assert_eq!(r.sessions.len(), 1);
}

#[test]
fn a_session_with_too_few_poses_is_refused_with_its_name_and_line() {
    let (mut data, _) = three_sessions();
    data.sessions.push("tiny".into());
    // The first two calibration poses (3 targets each) go to session 'tiny'.
    for (i, s) in data.samples.iter_mut().enumerate() {
        s.line = i + 2;
        if i < 6 {
            s.session = 3;
        }
    }
    let e = calibrate(&fit_support::ur5(), &data, &CalibrationOptions::default()).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("session 'tiny'") && msg.contains("line 2"),
        "{msg}"
    );
    assert!(msg.contains("at least 3 poses"), "{msg}");

    let text = "j1,j2,j3,j4,j5,j6,x,y,z,session\n0,0,0,0,0,0,1,1,1,\n";
    let names: Vec<String> = (1..=6).map(|k| format!("j{k}")).collect();
    let e = parse_measurements(text, &names, &CsvOptions::default()).unwrap_err();
    assert!(
        e.to_string().contains("line 2") && e.to_string().contains("session"),
        "{e}"
    );
}
