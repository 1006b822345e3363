//! `urdf-dh calibrate` on contact data (ball-in-socket, a `socket` column): the report on a
//! small simulated set, the calibrated model written and read back, effects declared and
//! selected, the chart; and the MUKCa `panda_6` set when `../shared` is there.

use crate::common::{ok, simulate};
use std::path::Path;

use dh_calib::csv::write_measurements;
use dh_calib::data::{Measurements, Sample, Socket, SocketDistance, Split};
use dh_calib::effects::parse_label;
use dh_calib::model::{Model, ModelOptions};
use dh_core::pose::from_xyz_rpy;
use dh_core::{Convention, DhRow, DhTable};
use nalgebra::{DMatrix, DVector, Isometry3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::Value;

use crate::common::{run, settings, skip_without_shared};

/// The nominal model of the simulated contacts: the same table as `PANDA` below.
const PANDA: &str = "fixtures/measured/mukca_panda/model.yaml";

/// Contact noise per axis of the simulated contacts (metres): a tenth of a millimetre, as a
/// hand-placed ball.
const CONTACT_SIGMA: f64 = 1e-4;

fn path(dir: &Path, name: &str) -> String {
    dir.join(name).to_string_lossy().into_owned()
}

/// Franka's modified DH with the tool to the ball centre, as `fixtures/measured/mukca_panda`.
fn panda() -> DhTable {
    let h = std::f64::consts::FRAC_PI_2;
    let r = |i: usize, a: f64, alpha: f64, d: f64| {
        DhRow::revolute(&format!("joint_{i}"), a, alpha, d, 0.0)
    };
    DhTable {
        convention: Convention::Modified,
        base: Isometry3::identity(),
        tool: from_xyz_rpy(
            [0.000025170947, -0.000084766225, 0.240528297908],
            [0.0, 0.0, -std::f64::consts::FRAC_PI_4],
        ),
        rows: vec![
            r(1, 0.0, 0.0, 0.333),
            r(2, 0.0, -h, 0.0),
            r(3, 0.0, h, 0.316),
            r(4, 0.0825, h, 0.0),
            r(5, -0.0825, -h, 0.384),
            r(6, 0.0, h, 0.0),
            r(7, 0.088, h, 0.0),
        ],
    }
}

/// Joint values that put the ball at `goal` under `model` at `x` (damped Gauss-Newton from a
/// random start near a reaching pose); `None` when it does not converge.
fn touch(model: &Model, x: &[f64], goal: Vector3<f64>, rng: &mut ChaCha8Rng) -> Option<Vec<f64>> {
    let mut q: Vec<f64> = [0.0, 0.3, 0.0, -2.0, 0.0, 2.2, 0.8]
        .iter()
        .map(|v| v + rng.random_range(-0.7..0.7))
        .collect();
    for _ in 0..100 {
        let p = model.point(x, &q, 0);
        let e = p - goal;
        if e.norm() < 1e-12 {
            // Joint values as a controller reports them, within ±π.
            return Some(
                q.iter()
                    .map(|v| {
                        (v + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                            - std::f64::consts::PI
                    })
                    .collect(),
            );
        }
        let mut j = DMatrix::zeros(3, 7);
        for k in 0..7 {
            let mut qp = q.clone();
            qp[k] += 1e-7;
            j.set_column(k, &((model.point(x, &qp, 0) - p) / 1e-7));
        }
        let jjt = &j * j.transpose() + DMatrix::identity(3, 3) * 1e-6;
        let step = j.transpose() * jjt.lu().solve(&DVector::from_column_slice(e.as_slice()))?;
        for k in 0..7 {
            q[k] -= step[k];
        }
    }
    None
}

/// Simulated contacts of a Panda with planted geometric errors (and `effect` at its value):
/// three placements of a two-socket tool (50 mm ± 0.1 mm), `per_socket` contacts per socket;
/// placements `p0` and `p1` calibrate, `p2` validates. Written as the measurement CSV.
pub(crate) fn contacts(file: &str, per_socket: usize, effect: Option<(&str, f64)>, seed: u64) {
    let table = panda();
    let mut model = Model::new(&table, &["ball".into()], &ModelOptions::default()).unwrap();
    let range = effect.map(|(label, _)| {
        model
            .add_effect(parse_label(label, &table).unwrap())
            .unwrap()
    });
    let mut x = vec![0.0; model.parameter_count()];
    for (name, v) in [
        ("joint_2.alpha", 1e-3),
        ("joint_3.d", -8e-4),
        ("joint_4.a", 1e-3),
        ("joint_5.theta", -1.2e-3),
        ("joint_6.alpha", 8e-4),
        ("target.ball.x", 6e-4),
    ] {
        x[model.index_of(name).unwrap()] = v;
    }
    if let (Some(r), Some((_, v))) = (range, effect) {
        x[r.start] = v;
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut samples = Vec::new();
    let placements = [
        Vector3::new(0.45, -0.15, 0.05),
        Vector3::new(0.5, 0.1, 0.15),
        Vector3::new(0.35, 0.3, 0.0),
    ];
    let offsets = [Vector3::new(0.0, 0.05, 0.0), Vector3::new(0.03, 0.0, 0.04)];
    for (p, centre) in placements.iter().enumerate() {
        let pair = [*centre, centre + offsets[p % 2]];
        for (hole, goal) in pair.iter().enumerate() {
            let mut n = 0;
            while n < per_socket {
                let noise = Vector3::from_fn(|_, _| {
                    rng.random_range(-1.0..1.0) * CONTACT_SIGMA * 3f64.sqrt()
                });
                let Some(q) = touch(&model, &x, goal + noise, &mut rng) else {
                    continue;
                };
                samples.push(Sample {
                    time: None,
                    orientation: None,
                    session: 0,
                    q: q.into(),
                    target: 0,
                    point: Vector3::zeros(),
                    sigma: None,
                    config: None,
                    split: if p < 2 {
                        Split::Calibration
                    } else {
                        Split::Validation
                    },
                    line: 0,
                    socket: Some(Box::new(Socket {
                        name: format!("p{p}/{hole}"),
                        partner: Some(SocketDistance {
                            socket: format!("p{p}/{}", 1 - hole),
                            distance: 0.05,
                            sigma: 1e-4,
                        }),
                    })),
                });
                n += 1;
            }
        }
    }
    let data = Measurements {
        sessions: Vec::new(),
        joint_names: table.rows.iter().map(|r| r.name.clone()).collect(),
        targets: vec!["ball".into()],
        samples,
    };
    std::fs::write(file, write_measurements(&data)).unwrap();
}

/// The consistency of a step of the JSON report (metres): train, test.
fn consistency(report: &Value, step: usize) -> (f64, f64) {
    let s = &report["steps"][step];
    (
        s["train"]["mean_abs"].as_f64().unwrap(),
        s["test"]["mean_abs"].as_f64().unwrap(),
    )
}

fn last_step(report: &Value) -> usize {
    report["steps"].as_array().unwrap().len() - 1
}

fn regex_escape(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '/' || c == '_' {
                c.to_string()
            } else {
                format!("\\{c}")
            }
        })
        .collect()
}

#[test]
fn the_contact_report_on_simulated_contacts() {
    let dir = tempfile::tempdir().unwrap();
    let data = path(dir.path(), "contacts.csv");
    contacts(&data, 12, None, 5);
    let mut s = settings();
    s.add_filter(
        regex_escape(&dir.path().to_string_lossy()).as_str(),
        "[tmp]",
    );
    s.bind(|| {
        insta::assert_snapshot!(run(&["calibrate", "--model", PANDA, "--data", &data], None));
    });
}

#[test]
fn the_calibrated_model_of_contacts_reads_back_with_the_calibrated_consistency() {
    let dir = tempfile::tempdir().unwrap();
    let data = path(dir.path(), "contacts.csv");
    contacts(&data, 12, None, 7);
    let (sheet, urdf, svg) = (
        path(dir.path(), "cal.yaml"),
        path(dir.path(), "cal.urdf"),
        path(dir.path(), "cal.svg"),
    );
    let json = ok(&[
        "calibrate",
        "--model",
        PANDA,
        "--data",
        &data,
        "--format",
        "json",
        "--out",
        &sheet,
        "--plot",
        &svg,
    ]);
    crate::common::assert_library_calibrates_as_the_cli(PANDA, &data, None, Some(&sheet), &json);
    let report: Value = serde_json::from_str(&json).unwrap();
    ok(&[
        "calibrate",
        "--model",
        PANDA,
        "--data",
        &data,
        "--out",
        &urdf,
    ]);
    let (train, test) = consistency(&report, last_step(&report));
    let (given, _) = consistency(&report, 0);
    // From several times the contact noise to about it (mean distance of a 3-D point from its
    // mean: 1.6 sigma for a Gaussian, 1.5 sigma for this uniform noise).
    assert!(given > 5.0 * CONTACT_SIGMA, "as given {given}");
    assert!(train < 2.0 * CONTACT_SIGMA, "train {train}");
    assert!(test < 2.5 * CONTACT_SIGMA, "test {test}");

    // The written sheet, as the model, predicts the contacts as the calibration left them:
    // its `as given` consistency is the calibrated one (the ball is in its tool).
    let again: Value = serde_json::from_str(&ok(&[
        "calibrate",
        "--model",
        &sheet,
        "--data",
        &data,
        "--format",
        "json",
    ]))
    .unwrap();
    let (train2, test2) = consistency(&again, 0);
    // The sheet's numbers are written to 1e-12 m and rad.
    assert!((train2 - train).abs() < 1e-9, "{train2} against {train}");
    assert!((test2 - test).abs() < 1e-9, "{test2} against {test}");
    let written: serde_yaml::Value =
        serde_yaml::from_str(&std::fs::read_to_string(&sheet).unwrap()).unwrap();
    let cal = &written["calibration"];
    assert_eq!(cal["kind"].as_str(), Some("contacts"));
    assert!((cal["consistency_after"].as_f64().unwrap() - train).abs() < 1e-15);
    assert_eq!(cal["sockets"].as_sequence().unwrap().len(), 4);
    // The URDF and the sheet are the same kinematics.
    ok(&["check", &urdf, "--sheet", &sheet]);

    // The chart: a dot per contact in each of the two panels, and the legend's two.
    let svg = std::fs::read_to_string(&svg).unwrap();
    let doc = roxmltree::Document::parse(&svg).expect("well-formed XML");
    let dots = doc
        .descendants()
        .filter(|n| n.has_tag_name("circle"))
        .count();
    assert_eq!(dots, 2 * 72 + 2);
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["cal.svg", "cal.urdf", "cal.yaml", "contacts.csv"]);
}

#[test]
fn a_planted_gear_harmonic_in_contacts_is_selected_and_a_declared_one_estimated() {
    let dir = tempfile::tempdir().unwrap();
    let data = path(dir.path(), "harmonic.csv");
    // A once-per-turn error of joint 1 of 3 mrad (sine term): 1.5 mm at the ball.
    let planted = 3e-3;
    contacts(&data, 15, Some(("gear_harmonic:joint_1", planted)), 9);
    let auto: Value = serde_json::from_str(&ok(&[
        "calibrate",
        "--model",
        PANDA,
        "--data",
        &data,
        "--format",
        "json",
        "--effects",
        "auto",
    ]))
    .unwrap();
    assert_eq!(
        auto["selected_effects"],
        serde_json::json!(["gear_harmonic:joint_1"])
    );
    let labels: Vec<&str> = auto["steps"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["label"].as_str().unwrap())
        .collect();
    assert_eq!(
        labels,
        ["as given", "nominal", "geometric", "+gear_harmonic:joint_1"]
    );
    let (geo_train, geo_test) = consistency(&auto, 2);
    let (train, test) = consistency(&auto, 3);
    assert!(train < geo_train && test < geo_test, "{train} {test}");
    let parameter = |r: &Value, name: &str| -> (f64, f64) {
        let p = r["parameters"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| p["name"] == name)
            .unwrap_or_else(|| panic!("no {name}"))
            .clone();
        (
            p["estimate"].as_f64().unwrap(),
            p["std_error"].as_f64().unwrap(),
        )
    };
    let (v, se) = parameter(&auto, "gear_harmonic:joint_1.sin");
    assert!((v - planted).abs() < 4.0 * se, "{v} ± {se}");
    // Candidates never selected are no parameters of the result.
    assert!(!auto["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .any(|p| p["name"] == "gear_ratio:joint_2"));
    assert!(auto["candidates"].as_array().unwrap().len() > 10);

    let declared: Value = serde_json::from_str(&ok(&[
        "calibrate",
        "--model",
        PANDA,
        "--data",
        &data,
        "--format",
        "json",
        "--effects",
        "gear_harmonic:joint_1",
    ]))
    .unwrap();
    assert_eq!(declared["steps"][3]["label"], "effects");
    let (train_d, _) = consistency(&declared, 3);
    assert!((train_d - train).abs() < 1e-6, "{train_d} against {train}");
    assert!((parameter(&declared, "gear_harmonic:joint_1.sin").0 - v).abs() < 1e-9);
    assert!(declared["candidates"].as_array().unwrap().is_empty());
}

/// `thermal_growth` cannot be selected on contacts (`auto` does not search it: contact data
/// carries no sample order) and naming it is refused, exit 2 naming the effect, so that no
/// contact calibration carries it (and none lacks its derived tau).
#[test]
fn thermal_growth_is_refused_on_contacts() {
    let dir = tempfile::tempdir().unwrap();
    let data = path(dir.path(), "contacts.csv");
    contacts(&data, 12, None, 5);
    let (code, _, err) = crate::common::exec(&[
        "calibrate",
        "--model",
        PANDA,
        "--data",
        &data,
        "--effects",
        "thermal_growth",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("effect 'thermal_growth'")
            && err.contains("expected an effect of the joint values, found one of the sample order, which contact data does not carry"),
        "{err}"
    );
}

#[test]
fn effects_auto_on_simulated_points_shows_the_candidates_and_the_planted_effect() {
    let dir = tempfile::tempdir().unwrap();
    let data = path(dir.path(), "gear.csv");
    simulate(
        "fixtures/robots/ur5/vendor.yaml",
        "80",
        &data,
        &[
            "--noise",
            "3e-5",
            "--targets",
            "2",
            "--effect",
            "gear_ratio:elbow_joint=0.002",
            "--validation",
            "0.3",
            "--seed",
            "3",
        ],
    );
    let mut s = settings();
    s.add_filter(
        regex_escape(&dir.path().to_string_lossy()).as_str(),
        "[tmp]",
    );
    s.bind(|| {
        insta::assert_snapshot!(run(
            &[
                "calibrate",
                "--model",
                "fixtures/robots/ur5/vendor.yaml",
                "--data",
                &data,
                "--effects",
                "auto"
            ],
            None
        ));
    });
}

#[test]
fn alpha_sets_the_level_of_every_test_of_the_selection_and_is_echoed() {
    let dir = tempfile::tempdir().unwrap();
    let data = path(dir.path(), "gear.csv");
    simulate(
        "fixtures/robots/ur5/vendor.yaml",
        "60",
        &data,
        &[
            "--noise",
            "3e-5",
            "--targets",
            "2",
            "--effect",
            "gear_ratio:elbow_joint=0.002",
            "--seed",
            "5",
        ],
    );
    let base = [
        "calibrate",
        "--model",
        "fixtures/robots/ur5/vendor.yaml",
        "--data",
        &data,
        "--effects",
        "auto",
        "--sigma",
        "3e-5",
    ];
    for (alpha, level) in [(None, 0.01), (Some("0.05"), 0.05), (Some("1e-6"), 1e-6)] {
        let mut args = base.to_vec();
        if let Some(a) = alpha {
            args.extend(["--alpha", a]);
        }
        let text = ok(&args);
        assert!(
            text.contains(&format!("tests at level {level};")),
            "{alpha:?}: {text}"
        );
        args.extend(["--format", "json"]);
        let doc: serde_json::Value = serde_json::from_str(&ok(&args)).unwrap();
        assert_eq!(doc["diagnosis"]["alpha"].as_f64(), Some(level), "{alpha:?}");
        assert_eq!(doc["verdict"]["alpha"].as_f64(), Some(level), "{alpha:?}");
        // The planted ratio (2e-3 rad/rad, hundreds of sigmas) passes at every level.
        let selected = doc["selected_effects"].as_array().unwrap();
        assert!(
            selected.iter().any(|e| e == "gear_ratio:elbow_joint"),
            "{alpha:?}: {selected:?}"
        );
    }
}

#[test]
fn mukca_panda_6_through_the_cli() {
    let Some(shared) = skip_without_shared("mukca_panda_6_through_the_cli") else {
        return;
    };
    let set = shared.join("measured/mukca_ball_socket_panda_iiwa/data/panda_6");
    if !set.is_dir() {
        test_skips::skip(&format!("{} is absent", set.display()));
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (train, test, sheet) = (
        path(dir.path(), "train.csv"),
        path(dir.path(), "test.csv"),
        path(dir.path(), "cal.yaml"),
    );
    let p = |s: &str| set.join(s).to_string_lossy().into_owned();
    ok(&["import", &p("front"), "--out", &train]);
    ok(&["import", &p("left"), &p("right"), "--out", &test]);
    let report: Value = serde_json::from_str(&ok(&[
        "calibrate",
        "--model",
        PANDA,
        "--data",
        &train,
        "--validate",
        &test,
        "--format",
        "json",
        "--effects",
        "auto",
        "--out",
        &sheet,
    ]))
    .unwrap();
    let mm = |v: f64| v * 1e3;
    let (given_train, given_test) = consistency(&report, 0);
    let (geo_train, geo_test) = consistency(&report, 2);
    let (train_c, test_c) = consistency(&report, last_step(&report));
    println!(
        "panda_6: consistency as given {:.3} / {:.3} mm, geometric {:.3} / {:.3} mm, with {:?} {:.3} / {:.3} mm (train / test; published 8.28 -> 0.168 / 7.79 -> 0.347)",
        mm(given_train),
        mm(given_test),
        mm(geo_train),
        mm(geo_test),
        report["selected_effects"],
        mm(train_c),
        mm(test_c)
    );
    // docs/results.md: 8.787 / 10.591 as given, 0.177 / 0.250 geometric.
    assert!((mm(given_train) - 8.787).abs() < 0.01, "{given_train}");
    assert!((mm(geo_train) - 0.177).abs() < 0.01, "{geo_train}");
    assert!((mm(geo_test) - 0.250).abs() < 0.01, "{geo_test}");
    // Whatever the selection adds must not make the held-out placements worse.
    assert!(test_c <= geo_test + 1e-9, "{test_c} against {geo_test}");
    let again: Value = serde_json::from_str(&ok(&[
        "calibrate",
        "--model",
        &sheet,
        "--data",
        &train,
        "--validate",
        &test,
        "--format",
        "json",
    ]))
    .unwrap();
    // Without effects the written sheet reproduces the calibrated figures as given; with
    // effects (which a sheet does not apply) at least the geometric ones.
    let (train2, _) = consistency(&again, 0);
    if report["selected_effects"].as_array().unwrap().is_empty() {
        assert!(
            (train2 - train_c).abs() < 1e-9,
            "{train2} against {train_c}"
        );
    } else {
        assert!(train2 < 2.0 * geo_train, "{train2} against {geo_train}");
    }
}
