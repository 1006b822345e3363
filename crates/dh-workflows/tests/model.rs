//! The model loader of the measured-data commands (`dh_workflows::model::load_model`) on the UR5
//! fixture: the URDF chain extracted and verified, and the vendor sheet, give the same joints and
//! the same forward kinematics; the refusals keep the command line's words and hints.

use std::path::PathBuf;

use dh_core::Convention;
use dh_workflows::error::Hinted;
use dh_workflows::model::load_model;
use dh_workflows::{AngleUnit, LengthUnit};

fn fixture(path: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures")
        .join(path)
        .to_string_lossy()
        .into_owned()
}

const JOINTS: [&str; 6] = [
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
];

#[test]
fn a_urdf_and_its_vendor_sheet_load_as_the_same_robot() {
    let urdf = load_model(
        &fixture("robots/ur5/robot.urdf"),
        None,
        Some("tool0"),
        Convention::Standard,
    )
    .unwrap();
    let sheet = load_model(
        &fixture("robots/ur5/vendor.yaml"),
        None,
        None,
        Convention::Standard,
    )
    .unwrap();
    assert_eq!(urdf.origin, "robot.urdf");
    assert_eq!(urdf.links, ("base_link".to_string(), "tool0".to_string()));
    assert_eq!(urdf.units, (LengthUnit::M, AngleUnit::Rad));
    assert_eq!(urdf.measured_joints(), JOINTS);
    assert_eq!(sheet.measured_joints(), JOINTS);
    assert!(urdf.prismatic().is_empty());
    // The URDF's table is its chain's verified extraction: the same tip pose as the URDF's own
    // forward kinematics; the sheet's is the vendor's numbers as read.
    let (_, chain) =
        dh_workflows::input::load_chain(&fixture("robots/ur5/robot.urdf"), None, Some("tool0"))
            .unwrap();
    let q = [0.3, -1.1, 0.9, -0.4, 1.2, 0.5];
    let a = urdf.table.fk(&q).unwrap();
    let b = chain.fk(&q);
    let gap = (a.translation.vector - b.translation.vector).norm();
    assert!(gap < 1e-9, "{gap}");
    let text = std::fs::read_to_string(fixture("robots/ur5/vendor.yaml")).unwrap();
    let read = dh_workflows::Sheet::parse(&text, "vendor.yaml").unwrap();
    assert_eq!(sheet.table, read.table);
}

#[test]
fn refusals_keep_the_command_lines_words() {
    let e = load_model(
        &fixture("robots/ur5/vendor.yaml"),
        Some("base_link"),
        None,
        Convention::Standard,
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        "vendor.yaml: --base and --tip choose a chain of a URDF, but the model is a DH sheet"
    );
    let hint = e.downcast_ref::<Hinted>().unwrap();
    assert_eq!(hint.hint, "drop --base/--tip, or give the URDF as --model");
    let e = load_model(
        &fixture("robots/ur5/robot.urdf"),
        None,
        Some("no_such_link"),
        Convention::Standard,
    )
    .unwrap_err();
    assert!(
        format!("{e:#}").starts_with("robot.urdf: cannot choose the chain"),
        "{e:#}"
    );
    let e = load_model("/nonexistent/r.urdf", None, None, Convention::Standard).unwrap_err();
    assert!(
        e.to_string().contains("r.urdf: cannot read the file"),
        "{e}"
    );
}
