//! `convert NOMINAL --deltas calibration.conf` (a UR controller's factory calibration) and
//! `to-urdf` of what it writes, on the project's own simulated UR3 calibration
//! (fixtures/ur/calibration.conf, metre-scale cancelling d like a real UR3's).

use dh_workflows::sheet::Sheet;
use dh_workflows::ur;

use crate::common::{root, run};

const CONF: &str = "fixtures/ur/calibration.conf";

/// The stdout of a run.
fn stdout(out: &str) -> &str {
    out.split_once("--- stdout\n")
        .and_then(|(_, rest)| rest.split_once("--- stderr\n"))
        .map_or("", |(s, _)| s)
}

#[test]
fn convert_with_deltas_writes_the_calibrated_sheet_and_to_urdf_keeps_it_on_the_arm() {
    let out = run(&["convert", "ur3", "--deltas", CONF], None);
    assert!(out.starts_with("exit: 0"), "{out}");
    let written = stdout(&out).to_owned();
    assert!(
        written.contains("passed: true")
            && written.contains("against: ur3.yaml + the deltas of calibration.conf"),
        "{written}"
    );
    // FK: the written sheet (read back at its precision) against nominal + deltas.
    let nominal = Sheet::parse(ur::nominal("ur3").unwrap().text, "ur3")
        .unwrap()
        .table;
    let conf =
        ur::CalibrationConf::parse(&std::fs::read_to_string(root().join(CONF)).unwrap(), "c")
            .unwrap();
    let sheet = Sheet::parse(&written, "written").unwrap();
    let mut worst = 0.0f64;
    for k in 0..100 {
        let q: Vec<f64> = (0..6)
            .map(|j| ((k * 17 + j * 3) as f64 * 0.41).sin() * 3.0)
            .collect();
        let d =
            sheet.table.fk(&q).unwrap().inverse() * ur::calibrated_fk(&nominal, &conf.deltas, &q);
        worst = worst.max(d.translation.vector.norm());
    }
    println!("written sheet vs nominal + deltas: {worst:.1e} m");
    assert!(worst < 1e-9, "{worst}");
    // to-urdf of it: proved, every joint origin within twice the nominal reach.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ur3-calibrated.yaml");
    std::fs::write(&path, &written).unwrap();
    let out = run(&["to-urdf", path.to_str().unwrap()], None);
    assert!(
        out.starts_with("exit: 0") && out.contains(": PASS -->"),
        "{out}"
    );
    let reach = nominal.size();
    let doc = roxmltree::Document::parse(stdout(&out)).unwrap();
    let mut joints = 0;
    for o in doc.descendants().filter(|n| n.has_tag_name("origin")) {
        let xyz: Vec<f64> = o
            .attribute("xyz")
            .unwrap()
            .split_whitespace()
            .map(|t| t.parse().unwrap())
            .collect();
        let length = xyz.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!(
            length <= 2.0 * reach,
            "origin {xyz:?}: {length} m, reach {reach} m"
        );
        joints += 1;
    }
    assert_eq!(joints, 7);
}

#[test]
fn convert_with_deltas_refuses_what_it_cannot_read() {
    let out = run(&["convert", "ur15", "--deltas", CONF], None);
    assert!(
        out.starts_with("exit: 2")
            && out.contains("no shipped nominal table")
            && out.contains("ur3, ur5, ur10"),
        "{out}"
    );
    let out = run(
        &[
            "convert",
            "ur5e",
            "--deltas",
            "fixtures/robots/ur5/robot.urdf",
        ],
        None,
    );
    assert!(
        out.starts_with("exit: 2") && out.contains("robot.urdf: line 2: expected 'key = value'"),
        "{out}"
    );
    let out = run(&["convert", "ur5e"], None);
    assert!(out.starts_with("exit: 2") && out.contains("--to"), "{out}");
    // A nominal name works without deltas too.
    let out = run(&["convert", "ur5e", "--to", "modified"], None);
    assert!(
        out.starts_with("exit: 0") && out.contains("passed: true"),
        "{out}"
    );
}
