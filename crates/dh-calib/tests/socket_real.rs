//! The MUKCa ball-in-socket contacts (`shared/measured/mukca_ball_socket_panda_iiwa`, outside
//! the repository: the data is never copied in): import of every robot, and the calibration of
//! `panda_6` trained on its `front` placement and tested on `left` and `right`, as the upstream
//! result `calibrated_urdf/panda_6` was (its `config.yaml`). Skips, saying why, when the data is
//! absent.
#![allow(clippy::print_stdout)]

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4};
use std::path::{Path, PathBuf};

use dh_calib::calibrate::CalibrationOptions;
use dh_calib::data::{Measurements, Split};
use dh_calib::import::{import, Layout, Source};
use dh_calib::socket::calibrate_sockets;
use dh_calib::tree::DhTree;
use dh_core::pose::from_xyz_rpy;
use dh_core::{Convention, DhRow, DhTable};

const DATA: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../../shared/measured/mukca_ball_socket_panda_iiwa/data"
);

/// The placements of `robot`, imported; `None` (after printing why) when absent.
fn load(robot: &str, placements: &[&str], split: Split) -> Option<Measurements> {
    let dir: PathBuf = Path::new(DATA).join(robot);
    let mut texts = Vec::new();
    for p in placements {
        for f in ["hole_0.csv", "hole_1.csv"] {
            match std::fs::read_to_string(dir.join(p).join(f)) {
                Ok(t) => texts.push((format!("{p}/{f}"), t)),
                Err(e) => {
                    test_skips::skip(&format!(
                        "needs ../shared: {} not readable: {e}",
                        dir.join(p).join(f).display()
                    ));
                    return None;
                }
            }
        }
    }
    let sources: Vec<Source<'_>> = texts
        .iter()
        .map(|(name, text)| Source { name, text })
        .collect();
    let mut m = import(Layout::Mukca, &sources).unwrap_or_else(|e| panic!("{robot}: {e}"));
    for s in &mut m.samples {
        s.split = split;
    }
    Some(m)
}

fn sockets(m: &Measurements) -> usize {
    let mut names: Vec<&str> = m
        .samples
        .iter()
        .filter_map(|s| s.socket.as_ref().map(|c| c.name.as_str()))
        .collect();
    names.sort_unstable();
    names.dedup();
    names.len()
}

#[test]
fn every_robot_imports_with_the_row_counts_of_source_md() {
    for (robot, placements, rows, joints) in [
        ("panda_6", &["front", "left", "right"][..], 199, 7),
        (
            "kuka_14",
            &["front", "left_back", "raised_left"][..],
            180,
            7,
        ),
        (
            "dinova_1",
            &["front", "left", "lower_left", "raised_back"][..],
            137,
            6,
        ),
    ] {
        let Some(m) = load(robot, placements, Split::Calibration) else {
            return;
        };
        assert_eq!(m.samples.len(), rows, "{robot}");
        assert_eq!(m.joint_names.len(), joints, "{robot}");
        assert_eq!(sockets(&m), 2 * placements.len(), "{robot}");
        assert!(m.samples.iter().all(|s| s.q.iter().all(|v| v.abs() < 7.0)));
    }
}

/// `fixtures/measured/mukca_panda/model.yaml`.
fn panda() -> DhTable {
    let r = |i: usize, a: f64, alpha: f64, d: f64| {
        DhRow::revolute(&format!("joint_{i}"), a, alpha, d, 0.0)
    };
    DhTable {
        convention: Convention::Modified,
        base: nalgebra::Isometry3::identity(),
        tool: from_xyz_rpy(
            [0.000025170947, -0.000084766225, 0.240528297908],
            [0.0, 0.0, -FRAC_PI_4],
        ),
        rows: vec![
            r(1, 0.0, 0.0, 0.333),
            r(2, 0.0, -FRAC_PI_2, 0.0),
            r(3, 0.0, FRAC_PI_2, 0.316),
            r(4, 0.0825, FRAC_PI_2, 0.0),
            r(5, -0.0825, -FRAC_PI_2, 0.384),
            r(6, 0.0, FRAC_PI_2, 0.0),
            r(7, 0.088, FRAC_PI_2, 0.0),
        ],
    }
}

/// Published (upstream README): mean absolute consistency error 8.28 -> 0.168 mm on train,
/// 7.79 -> 0.347 mm on test. Ours, same split and definition: 8.79 -> 0.177 (train), 10.59 ->
/// 0.250 (test). The "before" figures differ from the published ones (upstream drops outliers
/// first and may average other robots); the test figure after calibration beats the published
/// one. Bands of about ±5 % around our figures.
#[test]
fn panda_6_trained_on_front_is_consistent_on_left_and_right() {
    let Some(mut data) = load("panda_6", &["front"], Split::Calibration) else {
        return;
    };
    let Some(test) = load("panda_6", &["left", "right"], Split::Validation) else {
        return;
    };
    data.samples.extend(test.samples);
    let r = calibrate_sockets(
        &DhTree::serial(&panda()),
        &data,
        &CalibrationOptions::default(),
    )
    .unwrap();
    let given = &r.consistency[0];
    let last = r.consistency.last().unwrap();
    assert_eq!(last.label, "geometric");
    let test_given = given.test.unwrap();
    let test_last = last.test.unwrap();
    println!(
        "train {:.3} -> {:.3} mm, test {:.3} -> {:.3} mm",
        given.train.mean_abs * 1e3,
        last.train.mean_abs * 1e3,
        test_given.mean_abs * 1e3,
        test_last.mean_abs * 1e3
    );
    assert!(
        (8.4e-3..9.2e-3).contains(&given.train.mean_abs),
        "{given:?}"
    );
    assert!(
        (10.1e-3..11.1e-3).contains(&test_given.mean_abs),
        "{given:?}"
    );
    assert!(
        (0.165e-3..0.186e-3).contains(&last.train.mean_abs),
        "{last:?}"
    );
    assert!(
        (0.235e-3..0.265e-3).contains(&test_last.mean_abs),
        "{last:?}"
    );
    // The published test figure is the floor to beat.
    assert!(test_last.mean_abs < 0.347e-3);
    // The 50 mm between the sockets is kept on the held-out placements to a tenth of a mm.
    assert!(test_last.distance_error.unwrap() < 0.15e-3, "{last:?}");
    assert!(r.fixed.iter().any(|f| f.name == "device.x"));
}
