//! Unit tests of `measured`.

use super::*;
use crate::model::{is_urdf, LoadedModel};
use crate::tree_sheet::TreeSheet;
use dh_core::Convention;

#[test]
fn header_cells_are_split_unquoted_and_trimmed() {
    assert_eq!(
        split_header(" j1 ,\"j,2\", x,y,z,\"a\"\"b\""),
        ["j1", "j,2", "x", "y", "z", "a\"b"]
    );
}

#[test]
fn urdf_or_sheet_by_extension_then_content() {
    assert!(is_urdf("r.urdf", "convention: standard"));
    assert!(!is_urdf("r.yaml", "<robot/>"));
    assert!(is_urdf("r.txt", "  <?xml version='1.0'?><robot/>"));
    assert!(!is_urdf("-", "convention: standard"));
}

#[test]
fn effect_labels() {
    let table = DhTable {
        convention: Convention::Standard,
        base: nalgebra::Isometry3::identity(),
        tool: nalgebra::Isometry3::identity(),
        rows: vec![dh_core::DhRow::revolute("j1", 0.3, 0.0, 0.0, 0.0)],
    };
    assert_eq!(
        parse_effect("gear_ratio:j1", &table)
            .unwrap()
            .parameter_names(),
        ["gear_ratio:j1"]
    );
    for (label, says) in [
        ("gear_ratio", "found 0 arguments"),
        ("gear_ratio:j9", "j9"),
        ("wobble:j1", "found 'wobble'"),
    ] {
        let e = parse_effect(label, &table).err().unwrap();
        assert!(e.to_string().contains(says), "{e}");
    }
}

#[test]
fn a_tree_measures_its_rows_and_couples_a_branch_joint_to_a_trunk_driver() {
    let tree = "\
convention: modified
length_unit: m
angle_unit: deg
joints:
  - {name: t1, type: revolute, a: 0, alpha: 0, d: 0.2, theta: 0}
  - {name: t2, type: revolute, a: 0.3, alpha: 90, d: 0, theta: 0}
branches:
  - name: r
    joints:
      - {name: r1, type: revolute, a: 0, alpha: 0, d: 0, theta: 0}
      - {name: r2, type: revolute, a: 0.25, alpha: -90, d: 0, theta: 0}
  - name: l
    joints:
      - {name: l1, type: revolute, a: 0, alpha: 0, d: 0, theta: 0}
      - {name: l2, type: revolute, a: 0.25, alpha: 90, d: 0, theta: 0}
";
    let s = TreeSheet::parse(tree, "tree.yaml").unwrap();
    assert_eq!(
        LoadedModel::of_tree(&s, "tree.yaml").measured_joints(),
        ["t1", "t2", "r1", "r2", "l1", "l2"]
    );
    // The coupled joint's value is a sum over measured columns, wherever they sit.
    let text = format!("{tree}coupled:\n  l2: {{t2: -1, r2: 0.5}}\n");
    let s = TreeSheet::parse(&text, "tree.yaml").unwrap();
    let model = LoadedModel::of_tree(&s, "tree.yaml");
    assert_eq!(model.measured_joints(), ["t1", "t2", "r1", "r2", "l1"]);
    let mut data = dh_calib::data::Measurements {
        sessions: Vec::new(),
        joint_names: vec![
            "t1".into(),
            "t2".into(),
            "r1".into(),
            "r2".into(),
            "l1".into(),
        ],
        targets: vec!["l".into()],
        samples: vec![dh_calib::data::Sample {
            time: None,
            orientation: None,
            session: 0,
            q: vec![0.1, 0.2, 0.3, 0.4, 0.5].into(),
            target: 0,
            point: nalgebra::Vector3::zeros(),
            sigma: None,
            config: None,
            split: dh_calib::data::Split::Calibration,
            line: 2,
            socket: None,
        }],
    };
    model.couple(&mut data).unwrap();
    assert_eq!(data.joint_names.last().map(String::as_str), Some("l2"));
    assert!((data.samples[0].q[5] - (-0.2 + 0.5 * 0.4)).abs() < 1e-15);
}
