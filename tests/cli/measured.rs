//! Measured data: `urdf-dh import` of every published set in `../shared/measured`, the `nominal`
//! and `geometric` steps of `calibrate` on each, and bad measurement files.

use crate::common::{exec, ok, simulate};
use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::common::{root, run, settings, skip_without_shared};

/// One published set: where it is, how to import it, which model and options to fit.
struct Set {
    /// Folder in `../shared/measured`.
    dir: &'static str,
    layout: &'static str,
    /// Files given to `import` (relative to the folder; empty: the folder itself).
    files: &'static [&'static str],
    samples: usize,
    /// The model: in this repository (`fixtures/...`) or in the set's folder (`shared:`).
    model: &'static str,
    /// Extra `calibrate` options.
    options: &'static [&'static str],
    /// Upper bound on the geometric step's calibration RMS (metres).
    geometric_below: f64,
}

const SETS: [Set; 5] = [
    Set {
        dir: "innopolis_fanuc_r2000ic_165f_3markers",
        layout: "innopolis",
        files: &["calibration_dataset.csv"],
        samples: 720,
        model: "fixtures/measured/innopolis_fanuc_r2000ic_165f/model.yaml",
        options: &[],
        geometric_below: 0.5e-3,
    },
    Set {
        dir: "boby_klimchik_laser_tracker_cpa",
        layout: "boby",
        files: &["N1N2N3Jval.csv"],
        samples: 108,
        model: "fixtures/measured/boby_klimchik_fanuc_r2000ic_165f/model.yaml",
        options: &[],
        geometric_below: 0.5e-3,
    },
    Set {
        dir: "liaowu_abb_irb120_position",
        layout: "liaowu",
        files: &[],
        samples: 148,
        model: "fixtures/measured/liaowu_abb_irb120/model.yaml",
        // The two test points are targets of their own, measured only in the test sets: their
        // positions cannot be fitted, so validation is by cross-validation on the three others.
        options: &["--targets", "point1,point2,point3"],
        geometric_below: 0.5e-3,
    },
    Set {
        dir: "dlr_agile_justin_vicon",
        layout: "dlr",
        files: &["measurements.csv"],
        samples: 1000,
        model: "fixtures/measured/dlr_agile_justin/right_arm.yaml",
        options: &["--targets", "right"],
        // Published (Tenhumberg & Baeuml 2021): mean 10.5 mm after the full DH step; the
        // elastic effects take it further.
        geometric_below: 15e-3,
    },
    Set {
        dir: "hilti_trailblazer_total_station",
        layout: "hilti",
        files: &["flat.yaml"],
        samples: 444,
        model: "shared:trailblazer.urdf",
        options: &["--tip", "prism"],
        geometric_below: 3e-3,
    },
];

/// The FANUC J2/J3 interaction of the Boby set, for a model that does not state it yet.
const FANUC_COUPLING: &str = "coupled:\n  joint_3: {joint_3: 1, joint_2: 1}\n";

fn model_path(set: &Set, folder: &Path, tmp: &Path) -> Option<PathBuf> {
    if let Some(name) = set.model.strip_prefix("shared:") {
        return Some(folder.join(name));
    }
    let p = root().join(set.model);
    if !p.is_file() {
        return None;
    }
    if set.layout == "boby" {
        let text = std::fs::read_to_string(&p).unwrap();
        if !text.contains("coupled:") {
            let copy = tmp.join("model.yaml");
            std::fs::write(&copy, text + FANUC_COUPLING).unwrap();
            return Some(copy);
        }
    }
    Some(p)
}

#[test]
fn every_published_set_imports_and_calibrates() {
    let Some(shared) = skip_without_shared("every_published_set_imports_and_calibrates") else {
        return;
    };
    let mut ran = 0;
    for set in &SETS {
        let folder = shared.join("measured").join(set.dir);
        if !folder.is_dir() {
            test_skips::skip(&format!(
                "{}: ../shared/measured/{} is absent",
                set.layout, set.dir
            ));
            continue;
        }
        let tmp = tempfile::tempdir().unwrap();
        let csv = tmp.path().join("data.csv").to_string_lossy().into_owned();
        let mut args = vec!["import".to_string(), "--layout".into(), set.layout.into()];
        if set.files.is_empty() {
            args.push(folder.to_string_lossy().into_owned());
        } else {
            args.extend(
                set.files
                    .iter()
                    .map(|f| folder.join(f).to_string_lossy().into_owned()),
            );
        }
        args.extend(["--out".into(), csv.clone()]);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, _, err) = exec(&args);
        assert_eq!(code, 0, "{}: {err}", set.layout);
        assert!(
            err.contains(&format!("data.csv: {} samples", set.samples)),
            "{}: {err}",
            set.layout
        );
        let Some(model) = model_path(set, &folder, tmp.path()) else {
            test_skips::skip(&format!(
                "{}: imported {} samples; calibration not checked: the nominal model {} is absent",
                set.layout, set.samples, set.model
            ));
            continue;
        };
        let model = model.to_string_lossy().into_owned();
        let mut args = vec![
            "calibrate",
            "--model",
            &model,
            "--data",
            &csv,
            "--format",
            "json",
        ];
        args.extend(set.options);
        let report: Value = serde_json::from_str(&ok(&args)).unwrap();
        let steps = report["steps"].as_array().unwrap();
        let labels: Vec<&str> = steps.iter().map(|s| s["label"].as_str().unwrap()).collect();
        assert_eq!(labels, ["nominal", "geometric"], "{}", set.layout);
        let (nominal, geometric) = (
            steps[0]["rms"].as_f64().unwrap(),
            steps[1]["rms"].as_f64().unwrap(),
        );
        let mm = |v: &Value| v.as_f64().map_or("-".into(), |v| format!("{:.3}", v * 1e3));
        println!(
            "{}: nominal RMS {} mm (validation {}), geometric {} mm (validation {}), mean {} mm",
            set.layout,
            mm(&steps[0]["rms"]),
            mm(&steps[0]["val_rms"]),
            mm(&steps[1]["rms"]),
            mm(&steps[1]["val_rms"]),
            mm(&steps[1]["mean"])
        );
        assert!(
            geometric < nominal,
            "{}: {geometric} >= {nominal}",
            set.layout
        );
        assert!(
            geometric < set.geometric_below,
            "{}: geometric RMS {geometric} m above {}",
            set.layout,
            set.geometric_below
        );
        ran += 1;
    }
    println!("{ran} published sets calibrated");
    let mukca = shared.join("measured/mukca_ball_socket_panda_iiwa");
    if mukca.is_dir() {
        println!(
            "mukca: not here: ball-in-socket contacts, not coordinate measurements (see contacts::mukca_panda_6_through_the_cli)"
        );
    }
}

#[test]
fn import_detects_the_layout_from_file_names_and_writes_canonical_csv() {
    let Some(shared) = skip_without_shared("import_detects_the_layout") else {
        return;
    };
    let folder = shared.join("measured/boby_klimchik_laser_tracker_cpa");
    if !folder.is_dir() {
        test_skips::skip(
            "the Boby set (../shared/measured/boby_klimchik_laser_tracker_cpa) is absent",
        );
        return;
    }
    let file = folder.join("N1N2N3Jval.csv").to_string_lossy().into_owned();
    let csv = ok(&["import", &file]);
    let mut lines = csv.lines().filter(|l| !l.starts_with('#'));
    assert_eq!(
        lines.next(),
        Some("joint_1,joint_2,joint_3,joint_4,joint_5,joint_6,x,y,z,target,config")
    );
    assert_eq!(lines.count(), 108);
    assert!(csv.starts_with("# imported by urdf-dh import --layout boby from N1N2N3Jval.csv\n"));
    // The canonical file feeds circle-point analysis directly.
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("boby.csv");
    std::fs::write(&path, &csv).unwrap();
    let text = ok(&["cpa", &path.to_string_lossy()]);
    assert!(
        text.contains("joint_2 with joint_3 x -1.0000: lines"),
        "{text}"
    );
}

#[test]
fn bad_dataset_files_exit_2_naming_the_file_and_line() {
    let _snap = settings().bind_to_scope();
    let dir = tempfile::tempdir().unwrap();
    let inno = dir.path().join("calibration_dataset.csv");
    std::fs::write(
        &inno,
        "config_id,q1_rad,q2_rad,q3_rad,q4_rad,q5_rad,q6_rad,mA_x_m,mA_y_m,mA_z_m,mB_x_m,mB_y_m,mB_z_m,mC_x_m,mC_y_m,mC_z_m\n0,0,0,0,0,0,0,1,2,3,1,2,3,1,2,3\n1,0,0,0,0,zero,0,1,2,3,1,2,3,1,2,3\n",
    )
    .unwrap();
    let inno = inno.to_string_lossy().into_owned();
    insta::assert_snapshot!(
        "bad_innopolis",
        run(&["import", "--layout", "innopolis", &inno], None)
    );
    insta::assert_snapshot!(
        "unknown_layout",
        run(&["import", "--layout", "fanuc", &inno], None)
    );
    let other = dir.path().join("points.csv");
    std::fs::write(&other, "a,b\n1,2\n").unwrap();
    insta::assert_snapshot!(
        "undetected_layout",
        run(&["import", &other.to_string_lossy()], None)
    );
    insta::assert_snapshot!(
        "missing_file",
        run(
            &["import", "--layout", "liaowu", &other.to_string_lossy()],
            None
        )
    );
}

#[test]
fn measurement_units_convert_on_reading() {
    // The same points in metres/radians and in millimetres/degrees give the same calibration.
    let dir = tempfile::tempdir().unwrap();
    let si = dir.path().join("si.csv").to_string_lossy().into_owned();
    simulate(
        "fixtures/robots/ur5/vendor.yaml",
        "40",
        &si,
        &[
            "--noise",
            "1e-5",
            "--seed",
            "3",
            "--error",
            "elbow_joint.a=0.001",
        ],
    );
    let text = std::fs::read_to_string(&si).unwrap();
    let mut mm = String::new();
    for (i, line) in text.lines().filter(|l| !l.starts_with('#')).enumerate() {
        if i == 0 {
            mm += line;
        } else {
            let cells: Vec<String> = line
                .split(',')
                .enumerate()
                .map(|(c, v)| match (c, v.parse::<f64>()) {
                    (0..=5, Ok(x)) => format!("{}", x.to_degrees()),
                    (6..=8 | 11, Ok(x)) => format!("{}", x * 1e3),
                    _ => v.to_string(),
                })
                .collect();
            mm += &cells.join(",");
        }
        mm += "\n";
    }
    let mm_path = dir.path().join("mm.csv").to_string_lossy().into_owned();
    std::fs::write(&mm_path, mm).unwrap();
    let a: Value = serde_json::from_str(&ok(&[
        "calibrate",
        "--model",
        "fixtures/robots/ur5/vendor.yaml",
        "--data",
        &si,
        "--format",
        "json",
    ]))
    .unwrap();
    let b: Value = serde_json::from_str(&ok(&[
        "calibrate",
        "--model",
        "fixtures/robots/ur5/vendor.yaml",
        "--data",
        &mm_path,
        "--length-unit",
        "mm",
        "--angle-unit",
        "deg",
        "--format",
        "json",
    ]))
    .unwrap();
    for key in ["rms_before", "rms_after", "noise_floor"] {
        let (x, y) = (a[key].as_f64().unwrap(), b[key].as_f64().unwrap());
        assert!((x - y).abs() < 1e-9, "{key}: {x} against {y}");
    }
}
