//! `urdf-dh calibrate` of tree sheets: a simulated two-branch tree whose planted errors come
//! back through the CLI, and the DLR Agile Justin set (`../shared`) as one tree against the
//! figures of docs/results.md.

use crate::common::{exec, ok};
use std::path::Path;

use dh_workflows::tree_sheet::TreeSheet;
use nalgebra::{Isometry3, Point3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::Value;

use crate::common::skip_without_shared;

fn path(dir: &Path, name: &str) -> String {
    dir.join(name).to_string_lossy().into_owned()
}

/// A torso of two joints carrying two arms of three; `{..}` placeholders take planted errors.
pub(crate) fn tree_sheet(e: &[(&str, f64)]) -> String {
    let v = |name: &str, nominal: f64| {
        nominal
            + e.iter()
                .filter(|(n, _)| *n == name)
                .map(|(_, d)| d)
                .sum::<f64>()
    };
    // Lengths in metres, angles in degrees (planted angle errors are given in radians).
    let deg = |name: &str, nominal: f64| nominal + (v(name, nominal) - nominal).to_degrees();
    format!(
        "robot: two-arm test tree\n\
         convention: modified\nlength_unit: m\nangle_unit: deg\n\
         base: {{xyz: [0, 0, 0.4], rpy: [0, 0, 0]}}\n\
         tool: {{xyz: [0, 0, 0.15], rpy: [0, 0, 0]}}\n\
         joints:\n\
         \x20 - {{name: t1, type: revolute, a: 0, alpha: 0, d: 0.1, theta: 0}}\n\
         \x20 - {{name: t2, type: revolute, a: {}, alpha: {}, d: 0, theta: 0}}\n\
         branches:\n\
         \x20 - name: r\n\
         \x20   base: {{xyz: [0.1, -0.2, 0], rpy: [90, 0, 0]}}\n\
         \x20   tool: {{xyz: [0, 0, 0.08], rpy: [0, 0, 0]}}\n\
         \x20   joints:\n\
         \x20     - {{name: r1, type: revolute, a: 0, alpha: 0, d: 0, theta: 0}}\n\
         \x20     - {{name: r2, type: revolute, a: {}, alpha: {}, d: 0, theta: {}}}\n\
         \x20     - {{name: r3, type: revolute, a: {}, alpha: 0, d: 0.02, theta: 0}}\n\
         \x20 - name: l\n\
         \x20   base: {{xyz: [0.1, 0.2, 0], rpy: [-90, 0, 0]}}\n\
         \x20   tool: {{xyz: [0, 0, 0.08], rpy: [0, 0, 0]}}\n\
         \x20   joints:\n\
         \x20     - {{name: l1, type: revolute, a: 0, alpha: 0, d: 0, theta: 0}}\n\
         \x20     - {{name: l2, type: revolute, a: {}, alpha: {}, d: 0, theta: 0}}\n\
         \x20     - {{name: l3, type: revolute, a: 0.3, alpha: 0, d: 0, theta: {}}}\n",
        v("t2.a", 0.05),
        deg("t2.alpha", 90.0),
        v("r2.a", 0.05),
        deg("r2.alpha", -90.0),
        deg("r2.theta", 0.0),
        v("r3.a", 0.3),
        v("l2.a", 0.05),
        deg("l2.alpha", 90.0),
        deg("l3.theta", 0.0),
    )
}

/// Errors planted in the truth (metres, radians), each identifiable from both hands' points.
pub(crate) const PLANTED: [(&str, f64); 8] = [
    ("t2.a", 2e-3),
    ("t2.alpha", 3e-3),
    ("r2.a", -1.5e-3),
    ("r2.alpha", 2e-3),
    ("r2.theta", -2.5e-3),
    ("r3.a", 1e-3),
    ("l2.a", 1.2e-3),
    ("l2.alpha", -2e-3),
];

/// Measurement noise per axis (metres).
pub(crate) const NOISE: f64 = 2e-5;

/// The measuring device's frame of the simulated data, `T_device_base`.
pub(crate) fn device() -> Isometry3<f64> {
    Isometry3::new(Vector3::new(1.2, -0.3, 0.2), Vector3::new(0.02, -0.01, 0.4))
}

/// The targets of the simulated data, one per branch (`r`, then `l`), and their positions in
/// their branch's tip frame (metres).
pub(crate) const TARGETS: [&str; 2] = ["r", "l/hand"];

/// See [`TARGETS`].
pub(crate) const OFFSETS: [Vector3<f64>; 2] = [
    Vector3::new(0.01, 0.02, 0.03),
    Vector3::new(-0.02, 0.01, 0.04),
];

/// Writes `poses` poses of both hands of `truth` in the measurement CSV: target `r` on branch
/// `r` and `l/hand` on branch `l` (the `BRANCH/NAME` rule), with Gaussian-like noise.
pub(crate) fn write_data(truth: &TreeSheet, poses: usize, seed: u64, file: &str) {
    write_data_with(truth, poses, seed, file, &|_| {});
}

/// [`write_data`] with the points at joint values `moved` changes (the file keeps the
/// commanded ones): how a planted effect on the joint values shows.
pub(crate) fn write_data_with(
    truth: &TreeSheet,
    poses: usize,
    seed: u64,
    file: &str,
    moved: &dyn Fn(&mut Vec<f64>),
) {
    let tree = &truth.tree;
    let (device, offsets, names) = (device(), OFFSETS, TARGETS);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut text = String::from("t1,t2,r1,r2,r3,l1,l2,l3,x,y,z,target,config,sigma\n");
    for p in 0..poses {
        let q: Vec<f64> = (0..tree.rows().len())
            .map(|_| rng.random_range(-1.5..1.5))
            .collect();
        let mut actual = q.clone();
        moved(&mut actual);
        let frames = tree.frames(&actual).unwrap();
        for b in 0..2 {
            let point = device * frames.tips[b] * Point3::from(offsets[b]);
            // Sum of uniforms: near Gaussian with standard deviation NOISE.
            let mut noise = || (0..12).map(|_| rng.random_range(-0.5..0.5)).sum::<f64>() * NOISE;
            let (x, y, z) = (point.x + noise(), point.y + noise(), point.z + noise());
            let qs: Vec<String> = q.iter().map(|v| format!("{v:.17}")).collect();
            text += &format!(
                "{},{x:.17},{y:.17},{z:.17},{},p{p},{NOISE}\n",
                qs.join(","),
                names[b]
            );
        }
    }
    std::fs::write(file, text).unwrap();
}

#[test]
fn a_simulated_tree_comes_back_through_the_cli() {
    let dir = tempfile::tempdir().unwrap();
    let nominal = path(dir.path(), "tree.yaml");
    std::fs::write(&nominal, tree_sheet(&[])).unwrap();
    let truth = TreeSheet::parse(&tree_sheet(&PLANTED), "truth.yaml").unwrap();
    let (data, validation) = (path(dir.path(), "d.csv"), path(dir.path(), "v.csv"));
    write_data(&truth, 60, 1, &data);
    write_data(&truth, 20, 2, &validation);
    let out = path(dir.path(), "calibrated.yaml");
    let json = ok(&[
        "calibrate",
        "--model",
        &nominal,
        "--data",
        &data,
        "--validate",
        &validation,
        "--format",
        "json",
        "--out",
        &out,
    ]);
    crate::common::assert_library_calibrates_as_the_cli(
        &nominal,
        &data,
        Some(&validation),
        Some(&out),
        &json,
    );
    let report: Value = serde_json::from_str(&json).unwrap();
    assert_eq!(report["validation"]["method"], "split");
    // The nominal model misses by millimetres; the geometric step reaches the noise (3-D RMS
    // of noise NOISE per axis: about 1.7 NOISE) on both sets.
    let steps = report["steps"].as_array().unwrap();
    assert!(steps[0]["rms"].as_f64().unwrap() > 1e-3, "{}", steps[0]);
    let geometric = &steps[1];
    for key in ["rms", "val_rms"] {
        let v = geometric[key].as_f64().unwrap();
        assert!(v < 2.5 * NOISE, "geometric {key} {v}");
    }
    // Every planted error is estimated, within 4 standard errors.
    for (name, planted) in PLANTED {
        let p = report["parameters"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| p["name"] == name)
            .unwrap_or_else(|| panic!("no parameter {name}"));
        assert_eq!(p["free"], true, "{name} held: {p}");
        let change = p["estimate"].as_f64().unwrap() - p["nominal"].as_f64().unwrap();
        let se = p["std_error"].as_f64().unwrap();
        assert!(
            (change - planted).abs() < 4.0 * se && se < planted.abs() / 5.0,
            "{name}: change {change:e}, planted {planted:e}, standard error {se:e}"
        );
    }
    // The tree section: which table each parameter and target belongs to.
    let tree = report["tree"].as_array().unwrap();
    let names: Vec<&str> = tree.iter().map(|t| t["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["trunk", "r", "l"]);
    assert_eq!(tree[2]["targets"], serde_json::json!(["l/hand"]));
    assert_eq!(tree[1]["joints"], serde_json::json!(["r1", "r2", "r3"]));
    let free = |t: &Value, n: &str| t["free"].as_array().unwrap().iter().any(|p| p == n);
    assert!(free(&tree[0], "t2.a") && free(&tree[1], "r2.a") && free(&tree[2], "l2.alpha"));
    assert!(free(&tree[2], "target.l/hand.x") && !free(&tree[1], "target.l/hand.x"));
    // The calibrated tree sheet reads back with the estimates.
    let back =
        TreeSheet::parse(&std::fs::read_to_string(&out).unwrap(), "calibrated.yaml").unwrap();
    let r2 = back.tree.branches()[0].table.rows[1].a;
    let estimate = report["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == "r2.a")
        .and_then(|p| p["estimate"].as_f64())
        .unwrap();
    assert!((r2 - estimate).abs() < 1e-9, "{r2} against {estimate}");
    // The text report names the tables.
    let text = ok(&["calibrate", "--model", &nominal, "--data", &data]);
    assert!(text.contains("tree: trunk and 2 branch(es)"), "{text}");
    assert!(text.contains("  branch l: joints l1, l2, l3;"), "{text}");
    assert!(text.contains("targets l/hand"), "{text}");
    assert!(
        text.contains("5-fold cross-validation over 60 poses"),
        "{text}"
    );
}

#[test]
fn an_effect_on_a_branch_joint_comes_back_and_inertials_come_from_the_sheet() {
    let dir = tempfile::tempdir().unwrap();
    // The sheet carries its masses; compliance labels then load without --inertials.
    let nominal = path(dir.path(), "tree.yaml");
    std::fs::write(
        &nominal,
        tree_sheet(&[])
            + "inertials:\n  com_frame: dh\n  links:\n    - {joint: r2, mass: 3.0, com: [0.15, 0, 0]}\n    - {joint: l2, mass: 3.0, com: [0.15, 0, 0]}\n  payloads:\n    - {branch: r, mass: 1.0, com: [0, 0, 0.05]}\n",
    )
    .unwrap();
    let truth = TreeSheet::parse(&tree_sheet(&PLANTED), "truth.yaml").unwrap();
    let data = path(dir.path(), "d.csv");
    // gear_ratio:r2 (theta += eps q): the arm turns (1 + eps) times the commanded r2.
    const EPS: f64 = 3e-3;
    let r2 = truth.tree.row_index("r2").unwrap();
    write_data_with(&truth, 60, 4, &data, &|q| q[r2] *= 1.0 + EPS);
    let json = ok(&[
        "calibrate",
        "--model",
        &nominal,
        "--data",
        &data,
        "--effects",
        "gear_ratio:r2,compliance:l2",
        "--format",
        "json",
    ]);
    let report: Value = serde_json::from_str(&json).unwrap();
    let p = report["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == "gear_ratio:r2")
        .unwrap();
    let (e, se) = (
        p["estimate"].as_f64().unwrap(),
        p["std_error"].as_f64().unwrap(),
    );
    assert!(
        (e - EPS).abs() < 4.0 * se && se < EPS / 5.0,
        "{e:e} +- {se:e}"
    );
    let last = report["steps"].as_array().unwrap().last().unwrap().clone();
    assert_eq!(last["label"], "effects");
    assert!(last["rms"].as_f64().unwrap() < 2.5 * NOISE, "{last}");
    let tree = report["tree"].as_array().unwrap();
    let free = |t: &Value, n: &str| t["free"].as_array().unwrap().iter().any(|p| p == n);
    assert!(free(&tree[1], "gear_ratio:r2") && free(&tree[2], "compliance:l2"));
    // Without masses, compliance is refused with the tree's joints in the hint.
    let bare = path(dir.path(), "bare.yaml");
    std::fs::write(&bare, tree_sheet(&[])).unwrap();
    let (code, _, err) = exec(&[
        "calibrate",
        "--model",
        &bare,
        "--data",
        &data,
        "--effects",
        "compliance:l2",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("hint: effects are named") && err.contains("l1, l2, l3"),
        "{err}"
    );
}

/// `--plot` of a tree: two panels a branch (before, after), each with the samples of that
/// branch's target at every pose and the RMS line of its calibration samples; the after panels
/// sit at the noise, the before ones at the planted errors.
#[test]
fn a_tree_is_plotted_per_branch() {
    let dir = tempfile::tempdir().unwrap();
    let nominal = path(dir.path(), "tree.yaml");
    std::fs::write(
        &nominal,
        tree_sheet(&[])
            + "inertials:\n  com_frame: dh\n  links:\n    - {joint: r2, mass: 3.0, com: [0.15, 0, 0]}\n    - {joint: l2, mass: 3.0, com: [0.15, 0, 0]}\n",
    )
    .unwrap();
    let truth = TreeSheet::parse(&tree_sheet(&PLANTED), "truth.yaml").unwrap();
    let data = path(dir.path(), "d.csv");
    let r2 = truth.tree.row_index("r2").unwrap();
    write_data_with(&truth, 40, 5, &data, &|q| q[r2] *= 1.0 + 3e-3);
    let (svg, out) = (path(dir.path(), "r.svg"), path(dir.path(), "cal.yaml"));
    let (code, _, err) = exec(&[
        "calibrate",
        "--model",
        &nominal,
        "--data",
        &data,
        "--effects",
        "gear_ratio:r2,compliance:l2",
        "--plot",
        &svg,
        "--out",
        &out,
    ]);
    assert_eq!(code, 0, "{err}");
    // A written tree is predicted and compensated like a serial sheet: no warning.
    assert!(!err.contains("take one chain"), "{err}");
    let text = std::fs::read_to_string(&svg).unwrap();
    let panels: Vec<&str> = text
        .split("<g>")
        .skip(1)
        .map(|g| g.split("</g>").next().unwrap())
        .collect();
    assert_eq!(panels.len(), 4, "{text}");
    let rms = |panel: &str| -> f64 {
        let at = panel.find(">RMS ").expect("an RMS line") + 5;
        panel[at..].split(' ').next().unwrap().parse().unwrap()
    };
    for (panel, label) in panels.iter().zip([
        "branch r, before: nominal tree",
        "branch r, after: effects",
        "branch l, before: nominal tree",
        "branch l, after: effects",
    ]) {
        assert!(panel.contains(label), "{label}: {panel}");
        assert_eq!(panel.matches("<circle").count(), 40, "{label}");
    }
    // Millimetres: the planted errors move the hands by millimetres, the noise is 0.02 mm per
    // axis (0.035 mm in 3-D).
    for b in [0, 2] {
        let (before, after) = (rms(panels[b]), rms(panels[b + 1]));
        assert!(
            before > 0.5 && after < 0.06,
            "before {before} mm, after {after} mm"
        );
    }
}

#[test]
fn options_that_need_one_chain_are_refused_for_a_tree() {
    let dir = tempfile::tempdir().unwrap();
    let nominal = path(dir.path(), "tree.yaml");
    std::fs::write(&nominal, tree_sheet(&[])).unwrap();
    let data = path(dir.path(), "d.csv");
    write_data(
        &TreeSheet::parse(&tree_sheet(&[]), "t.yaml").unwrap(),
        8,
        3,
        &data,
    );
    for (extra, says) in [
        (
            vec!["--payload", "1,0,0,0"],
            "--payload: tree.yaml is a tree with one tip per branch",
        ),
        (
            vec!["--out", "t.urdf"],
            "a tree is written as a tree sheet, not a URDF",
        ),
        (vec!["--tip", "tool0"], "the model is a tree sheet"),
        (vec!["--effects", "compliance:r2"], "r2"),
    ] {
        let mut args = vec!["calibrate", "--model", &nominal, "--data", &data];
        args.extend(extra.iter().copied());
        let (code, out, err) = exec(&args);
        assert_eq!(code, 2, "{extra:?}: {err}");
        assert!(out.is_empty() && err.contains(says), "{extra:?}: {err}");
    }
}

/// The DLR Agile Justin set as one tree: the nominal and geometric figures of
/// docs/results.md (10-fold cross-validation), to the printed digit.
#[test]
fn the_dlr_tree_calibrates_through_the_cli() {
    let Some(shared) = skip_without_shared("the_dlr_tree_calibrates_through_the_cli") else {
        return;
    };
    let file = shared.join("measured/dlr_agile_justin_vicon/measurements.csv");
    if !file.is_file() {
        test_skips::skip(&format!("{} is absent", file.display()));
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let csv = path(dir.path(), "dlr.csv");
    ok(&[
        "import",
        "--layout",
        "dlr",
        &file.to_string_lossy(),
        "--out",
        &csv,
    ]);
    let json = ok(&[
        "calibrate",
        "--model",
        "fixtures/measured/dlr_agile_justin/model.yaml",
        "--data",
        &csv,
        "--folds",
        "10",
        "--format",
        "json",
    ]);
    let report: Value = serde_json::from_str(&json).unwrap();
    let steps = report["steps"].as_array().unwrap();
    let mm = |s: &Value, k: &str| (s[k].as_f64().unwrap() * 1e5).round() / 1e2;
    // docs/results.md: with the three outliers of the geometric residual left out (lines
    // 226, 693, 996 at 5.2-5.7 sigma; all points: geometric 11.362 mm), nominal 21.954 RMS /
    // 19.966 mean / 22.051 10-fold; geometric 11.235 / 10.010 / 11.537 (mm), with 12 and 76
    // free parameters.
    assert_eq!(steps[0]["free"], 12);
    assert_eq!(steps[1]["free"], 76);
    let lines: Vec<u64> = report["outliers"]["points"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["line"].as_u64().unwrap())
        .collect();
    assert_eq!(lines, [226, 693, 996]);
    assert_eq!(
        (report["outliers"]["rms_with"].as_f64().unwrap() * 1e5).round() / 1e2,
        11.36
    );
    for (s, rms, mean, val) in [
        (&steps[0], 21.95, 19.97, 22.05),
        (&steps[1], 11.24, 10.01, 11.54),
    ] {
        assert_eq!(
            (mm(s, "rms"), mm(s, "mean"), mm(s, "val_rms")),
            (rms, mean, val),
            "{}",
            s["label"]
        );
    }
    let tree = report["tree"].as_array().unwrap();
    assert_eq!(tree[1]["targets"], serde_json::json!(["right"]));
    assert_eq!(tree[2]["targets"], serde_json::json!(["left"]));
}

/// A tree calibration with `thermal_growth` records in its calibrated sheet what the effect's
/// `t` was, as a serial one does: `calibration.time_unit: pose_order` for data without times,
/// `s` for the same rows with a `time` column.
#[test]
fn a_tree_sheet_records_the_time_unit_of_its_warm_up() {
    let dir = tempfile::tempdir().unwrap();
    let nominal = path(dir.path(), "tree.yaml");
    std::fs::write(&nominal, tree_sheet(&[])).unwrap();
    let truth = TreeSheet::parse(&tree_sheet(&PLANTED), "truth.yaml").unwrap();
    let untimed = path(dir.path(), "d.csv");
    write_data(&truth, 40, 3, &untimed);
    // The same rows with their times, poses 30 s apart.
    let timed_text: String = std::fs::read_to_string(&untimed)
        .unwrap()
        .lines()
        .enumerate()
        .map(|(i, l)| match i {
            0 => format!("{l},time\n"),
            _ => format!("{l},{}\n", ((i - 1) / 2) as f64 * 30.0),
        })
        .collect();
    let timed = path(dir.path(), "t.csv");
    std::fs::write(&timed, timed_text).unwrap();
    for (data, word) in [(&untimed, "pose_order"), (&timed, "s")] {
        let out = path(dir.path(), "calibrated.yaml");
        let (code, _, err) = exec(&[
            "calibrate",
            "--model",
            &nominal,
            "--data",
            data,
            "--effects",
            "thermal_growth",
            "--out",
            &out,
        ]);
        assert!(code == 0 || code == 1, "{err}");
        let sheet = std::fs::read_to_string(&out).unwrap();
        let keys: Vec<&str> = sheet
            .lines()
            .filter(|l| l.trim_start().starts_with("time_unit:"))
            .collect();
        assert_eq!(keys, [format!("  time_unit: {word}")], "{sheet}");
        // The sheet still reads as a tree sheet.
        TreeSheet::parse(&sheet, "calibrated.yaml").unwrap();
    }
}
