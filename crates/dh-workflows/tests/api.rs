//! The public API on the project's own fixtures: a vendor sheet read, written in every format
//! and read back, and `check`'s comparison naming the joint and parameter that differ.

use std::path::PathBuf;

use dh_core::Tolerance;
use dh_workflows::check::{CHECK_ANGULAR, CHECK_LINEAR};
use dh_workflows::read_back::read_back;
use dh_workflows::{compare, parse_doc, render_sheet, Format, Sheet, SheetDoc, SheetError};

fn fixture(path: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures")
        .join(path)
}

fn read(path: &str) -> String {
    std::fs::read_to_string(fixture(path)).unwrap()
}

/// The UR5's URDF chain, base link to flange.
fn ur5_chain() -> urdf_axes::Chain {
    let bytes = std::fs::read(fixture("robots/ur5/robot.urdf")).unwrap();
    urdf_axes::UrdfModel::from_bytes(&bytes)
        .unwrap()
        .chain(Some("base_link"), Some("tool0"))
        .unwrap()
}

fn tolerance() -> Tolerance {
    Tolerance::new(CHECK_LINEAR, CHECK_ANGULAR).unwrap()
}

#[test]
fn a_vendor_sheet_reads_in_si_units() {
    let sheet = Sheet::parse(&read("robots/ur5/vendor.yaml"), "vendor.yaml").unwrap();
    assert_eq!(sheet.table.rows.len(), 6);
    assert_eq!(sheet.table.rows[2].name, "elbow_joint");
    assert_eq!(sheet.table.rows[2].a, -0.39225);
    assert_eq!(sheet.table.rows[0].alpha, std::f64::consts::FRAC_PI_2);
    assert!(!sheet.has_base && !sheet.has_tool);
    assert!(sheet.warnings.is_empty(), "{:?}", sheet.warnings);
}

#[test]
fn every_fixture_sheet_is_written_and_read_back_equal() {
    for id in ["ur5", "puma560", "kuka_kr5_arc", "franka_panda"] {
        let sheet = Sheet::parse(&read(&format!("robots/{id}/vendor.yaml")), "vendor").unwrap();
        let doc = SheetDoc::from_table(&sheet.table, sheet.length_unit, sheet.angle_unit);
        // YAML and JSON: the document itself comes back.
        for format in [Format::Yaml, Format::Json] {
            let text = render_sheet(&doc, format).unwrap();
            assert_eq!(parse_doc(&text, "written").unwrap(), doc, "{id} {format:?}");
        }
        // CSV: the numbers it writes come back, and the table they make is the sheet's.
        let csv = render_sheet(&doc, Format::Csv).unwrap();
        let back = read_back(&csv, Format::Csv).unwrap();
        assert_eq!(back.joints, doc.joints, "{id} csv");
        let table = back.into_sheet("written.csv").unwrap().table;
        assert_eq!(table.convention, sheet.table.convention);
        for (b, s) in table.rows.iter().zip(&sheet.table.rows) {
            assert_eq!(b.name, s.name);
            for (x, y) in [
                (b.a, s.a),
                (b.d, s.d),
                (b.alpha, s.alpha),
                (b.theta, s.theta),
            ] {
                assert!((x - y).abs() < 1e-12, "{id} {}: {x} != {y}", b.name);
            }
        }
    }
}

#[test]
fn the_vendor_sheet_matches_its_urdf() {
    let chain = ur5_chain();
    let sheet = Sheet::parse(&read("robots/ur5/vendor.yaml"), "vendor.yaml").unwrap();
    let report = compare(&chain, &sheet, tolerance()).unwrap();
    assert!(report.matches, "{:?}", report.differences);
    assert!(report.differences.is_empty());
    assert!(report.max_position_error.unwrap() <= report.position_bound.unwrap());
}

#[test]
fn check_names_the_joint_and_parameter_that_differ() {
    let chain = ur5_chain();
    // Half a millimetre off in the elbow's link length.
    let text = read("robots/ur5/vendor.yaml").replace("a: -0.39225,", "a: -0.39175,");
    let sheet = Sheet::parse(&text, "vendor.yaml").unwrap();
    let report = compare(&chain, &sheet, tolerance()).unwrap();
    assert!(!report.matches);
    let named: Vec<(Option<&str>, &str)> = report
        .differences
        .iter()
        .map(|d| (d.joint.as_deref(), d.parameter.as_str()))
        .collect();
    let d = report
        .differences
        .iter()
        .find(|d| d.parameter == "a" && d.joint.as_deref() == Some("elbow_joint"))
        .unwrap_or_else(|| panic!("elbow_joint a not named: {named:?}"));
    assert!((d.difference.abs() - 5e-4).abs() < 1e-9, "{d:?}");
    assert!((d.urdf - d.sheet - d.difference).abs() < 1e-15);
}

#[test]
fn errors_name_the_file_joint_and_fault_and_hint_the_remedy() {
    let text = read("robots/ur5/vendor.yaml").replace("d: 0.10915,", "d: .nan,");
    let e = Sheet::parse(&text, "vendor.yaml").unwrap_err();
    assert!(matches!(&e, SheetError::BadJoint { joint, .. } if joint == "wrist_1_joint"));
    assert_eq!(
        e.to_string(),
        "vendor.yaml: joint 'wrist_1_joint': d must be a finite number, found NaN"
    );
    assert_eq!(e.hint(), None);
    let e = Sheet::parse("t,x,y,z\n0,1,2,3\n", "data.csv").unwrap_err();
    assert!(matches!(e, SheetError::NotASheet { line: 1, .. }), "{e}");
    assert!(e.hint().unwrap().contains("calibrate --data"));
}
