//! The importers on the real published datasets in `shared/measured/` (outside the repository:
//! the data is never copied in). Each test skips, saying why, when its files are absent.
#![allow(clippy::print_stdout)]

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use dh_calib::data::{Measurements, Split};
use dh_calib::import::{import, Layout, Source};

const MEASURED: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/measured");

/// Reads `files` from the dataset directory `dir` and imports them; `None` (after printing the
/// reason) when a file is missing.
fn load(layout: Layout, dir: &str, files: &[&str]) -> Option<Measurements> {
    let dir: PathBuf = Path::new(MEASURED).join(dir);
    let mut texts = Vec::new();
    for name in files {
        match std::fs::read_to_string(dir.join(name)) {
            Ok(t) => texts.push((*name, t)),
            Err(e) => {
                test_skips::skip(&format!("{} not readable: {e}", dir.join(name).display()));
                return None;
            }
        }
    }
    let sources: Vec<Source<'_>> = texts
        .iter()
        .map(|(name, text)| Source { name, text })
        .collect();
    Some(import(layout, &sources).unwrap_or_else(|e| panic!("{layout}: {e}")))
}

fn configs(m: &Measurements) -> usize {
    m.samples
        .iter()
        .filter_map(|s| s.config.as_deref())
        .collect::<BTreeSet<_>>()
        .len()
}

fn count(m: &Measurements, split: Split) -> usize {
    m.samples.iter().filter(|s| s.split == split).count()
}

#[test]
fn innopolis_240_rows_3_markers_24_configurations() {
    let Some(m) = load(
        Layout::Innopolis,
        "innopolis_fanuc_r2000ic_165f_3markers",
        &["calibration_dataset.csv"],
    ) else {
        return;
    };
    assert_eq!(m.samples.len(), 720);
    assert_eq!(configs(&m), 24);
    assert_eq!(m.targets, ["A", "B", "C"]);
    // First row of the file: config 0, q1 = pi/4, marker A at (1.107234, 1.279674, 1.325723).
    let s = &m.samples[0];
    assert!((s.q[0] - std::f64::consts::FRAC_PI_4).abs() < 1e-10);
    assert_eq!(s.point.x, 1.107_234);
    assert_eq!(s.line, 2);
    // Ten repeats per configuration, each with three markers.
    assert!(m.samples[..30]
        .iter()
        .all(|s| s.config.as_deref() == Some("0")));
}

#[test]
fn boby_36_rows_3_smrs() {
    let Some(m) = load(
        Layout::Boby,
        "boby_klimchik_laser_tracker_cpa",
        &["N1N2N3Jval.csv"],
    ) else {
        return;
    };
    assert_eq!(m.samples.len(), 108);
    assert_eq!(configs(&m), 36);
    // Row 1: J1 = -9 deg, SMR1 at (702.604, -3165.984, 616.475) mm.
    let s = &m.samples[0];
    assert_eq!(s.q[0], (-9.0f64).to_radians());
    assert!((s.point.x - 0.702_604).abs() < 1e-15);
    // Rows 7-12 (samples 18..36): J2 swept with J3 = -J2.
    for s in &m.samples[18..36] {
        assert_eq!(s.q[2], -s.q[1]);
    }
}

#[test]
fn dlr_500_records_2_markers() {
    let Some(m) = load(Layout::Dlr, "dlr_agile_justin_vicon", &["measurements.csv"]) else {
        return;
    };
    assert_eq!(m.samples.len(), 1000);
    assert_eq!(configs(&m), 500);
    assert_eq!(m.joint_names.len(), 19);
    // Record 0: right marker (-1.8412635, 2.22621393, 1.58426529), lines 2-3.
    assert_eq!(m.samples[0].point.x, -1.841_263_5);
    assert_eq!(m.samples[1].point.z, 1.809_220_59);
    assert_eq!((m.samples[0].line, m.samples[2].line), (2, 4));
    // The head joints are zero throughout.
    assert!(m.samples.iter().all(|s| s.q[17] == 0.0 && s.q[18] == 0.0));
}

#[test]
fn liaowu_108_calibration_and_40_validation_points() {
    let Some(m) = load(
        Layout::Liaowu,
        "liaowu_abb_irb120_position",
        &[
            "CaliJointAngles.csv",
            "CaliPosition.csv",
            "TestJointAngles.csv",
            "TestPosition.csv",
            "TestJointAngles2.csv",
            "TestPosition2.csv",
        ],
    ) else {
        return;
    };
    assert_eq!(count(&m, Split::Calibration), 108);
    assert_eq!(count(&m, Split::Validation), 40);
    let per_target = |t: usize| m.samples.iter().filter(|s| s.target == t).count();
    assert_eq!(
        (0..5).map(per_target).collect::<Vec<_>>(),
        [36, 36, 36, 10, 30]
    );
    // The three calibration points of one configuration lie within a few centimetres.
    let s = &m.samples;
    assert!((s[0].point - s[1].point).norm() < 0.05);
}

#[test]
fn hilti_flat_444_waypoints() {
    let Some(m) = load(
        Layout::Hilti,
        "hilti_trailblazer_total_station",
        &["flat.yaml"],
    ) else {
        return;
    };
    assert_eq!(m.samples.len(), 444);
    assert_eq!(count(&m, Split::Calibration), 78);
    assert_eq!(count(&m, Split::Validation), 366);
    assert_eq!(m.joint_names[0], "column_prismatic_joint");
    assert_eq!(m.joint_names.len(), 7);
    // First waypoint, line 8 of the file.
    assert_eq!(m.samples[0].line, 8);
    assert_eq!(m.samples[0].point.x, 7.332_081_008_983_251);
}

#[test]
fn hilti_every_dataset_file_imports_every_waypoint() {
    let dir = Path::new(MEASURED).join("hilti_trailblazer_total_station");
    let Ok(entries) = std::fs::read_dir(&dir) else {
        test_skips::skip(&format!("{} not readable", dir.display()));
        return;
    };
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "yaml"))
        .collect();
    files.sort();
    assert_eq!(files.len(), 7, "{files:?}");
    for path in files {
        let text = std::fs::read_to_string(&path).unwrap();
        let name = path.file_name().unwrap().to_str().unwrap();
        let m = import(Layout::Hilti, &[Source { name, text: &text }])
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let entries = text
            .lines()
            .filter(|l| l.trim_start().starts_with("- id:"))
            .count();
        assert_eq!(m.samples.len(), entries, "{name}");
        assert!(m.samples.iter().all(|s| s.line > 0), "{name}");
        assert!(count(&m, Split::Calibration) > 0 && count(&m, Split::Validation) > 0);
    }
}

/// A dataset directory's other files (notes, the URDF) do not hide its one stationing file;
/// several stationing files are several sessions, and the error lists them.
#[test]
fn hilti_picks_its_one_yaml_among_other_files_and_lists_several() {
    let Some(m) = load(
        Layout::Hilti,
        "hilti_trailblazer_total_station",
        &["SOURCE.md", "flat.yaml", "trailblazer.urdf"],
    ) else {
        return;
    };
    assert_eq!(m.samples.len(), 444);
    let dir = Path::new(MEASURED).join("hilti_trailblazer_total_station");
    let texts: Vec<(&str, String)> = ["SOURCE.md", "flat.yaml", "pallet.yaml"]
        .iter()
        .map(|n| (*n, std::fs::read_to_string(dir.join(n)).unwrap()))
        .collect();
    let sources: Vec<Source<'_>> = texts
        .iter()
        .map(|(name, text)| Source { name, text })
        .collect();
    let e = import(Layout::Hilti, &sources).unwrap_err().to_string();
    assert!(
        e.contains("found 2: 'flat.yaml', 'pallet.yaml'; name the one to import"),
        "{e}"
    );
}
