use super::*;
use crate::sheet::Sheet;

const CONF: &str = include_str!("../../../../fixtures/ur/calibration.conf");

#[test]
fn the_fixture_reads_with_its_metre_scale_cancelling_d() {
    let conf = CalibrationConf::parse(CONF, "calibration.conf").expect("conf");
    assert_eq!(conf.deltas.len(), 6);
    assert_eq!(conf.ignored, ["joint_checksum", "calibration_status"]);
    let d: Vec<f64> = (0..6).map(|k| conf.deltas.row(k)[2]).collect();
    assert_eq!(d[1], -3.225257106869156);
    assert_eq!(d[2], 9.378379227289445);
    // The run's d cancel to centimetres.
    assert!((d[1] + d[2] + d[3]).abs() < 0.01, "{d:?}");
    assert_eq!(conf.deltas.row(6), [0.0; 4]);
}

#[test]
fn faults_of_the_file_are_errors_naming_the_line_or_key() {
    let cases = [
        ("delta_theta = [0]", "expected a [mounting] section"),
        (
            "[mounting]\ndelta_theta = [0]\ndelta_a = [0]\ndelta_d = [0]",
            "expected 'delta_alpha",
        ),
        (
            "[mounting]\ndelta_theta = [0, x]",
            "line 2: delta_theta: expected finite numbers, found 'x'",
        ),
        (
            "[mounting]\ndelta_theta = [0]\ndelta_theta = [0]",
            "line 3: delta_theta: expected it once",
        ),
        (
            "[mounting]\ndelta_theta = [0, 1]\ndelta_a = [0]\ndelta_d = [0]\ndelta_alpha = [0]",
            "delta_a: expected as many numbers",
        ),
        ("[mounting]\ndelta_theta = [0,\n1", "expected ']'"),
        ("[mounting]\nnonsense", "line 2: expected 'key = value'"),
        ("[mounting]\ndelta_theta = 3", "expected an array"),
    ];
    for (text, what) in cases {
        let e = CalibrationConf::parse(text, "c.conf").expect_err(what);
        let m = format!("{e:#}");
        assert!(m.starts_with("c.conf: ") && m.contains(what), "{what}: {m}");
    }
    // Arrays over several lines and other sections are fine.
    let ok = "[other]\ndelta_d = [ 9 ]\n[mounting]\ndelta_theta = [ 1,\n 2 ]\ndelta_a = [0, 0]\ndelta_d = [0, 0]\ndelta_alpha = [0, 0]\n";
    let conf = CalibrationConf::parse(ok, "c.conf").expect("ok");
    assert_eq!(conf.deltas.row(1), [2.0, 0.0, 0.0, 0.0]);
}

#[test]
fn every_shipped_nominal_sheet_reads_as_a_six_joint_standard_table() {
    for s in NOMINAL {
        let sheet = Sheet::parse(s.text, s.name).unwrap_or_else(|e| panic!("{}: {e:#}", s.name));
        assert_eq!(sheet.table.rows.len(), 6, "{}", s.name);
        assert_eq!(sheet.table.convention, Convention::Standard);
        assert!(sheet
            .source
            .as_deref()
            .is_some_and(|t| t.contains("universal-robots.com")));
        // joints 2, 3 and 4 parallel; a2, a3 negative (UR's sign convention)
        let r = &sheet.table.rows;
        assert!(r[1].alpha == 0.0 && r[2].alpha == 0.0 && r[1].a < 0.0 && r[2].a < 0.0);
    }
    assert_eq!(nominal("UR5e").map(|s| s.name), Some("ur5e"));
    assert!(nominal("ur15").is_none());
    // UR5e as published: d1 0.1625, a2 -0.425, a3 -0.3922, d4 0.1333, d5 0.0997, d6 0.0996.
    let ur5e = Sheet::parse(nominal("ur5e").expect("ur5e").text, "ur5e").expect("sheet");
    let r = &ur5e.table.rows;
    assert_eq!(
        [r[0].d, r[1].a, r[2].a, r[3].d, r[4].d, r[5].d],
        [0.1625, -0.425, -0.3922, 0.1333, 0.0997, 0.0996]
    );
}

#[test]
fn the_calibrated_table_is_the_nominal_plus_the_deltas() {
    let nominal_sheet = Sheet::parse(nominal("ur3").expect("ur3").text, "ur3").expect("sheet");
    let conf = CalibrationConf::parse(CONF, "calibration.conf").expect("conf");
    let table = calibrated(&nominal_sheet.table, &conf.deltas).expect("calibrated");
    assert_eq!(table.rows[1].d, -3.225257106869156);
    assert_eq!(table.rows[0].d, 0.1519 + -2.1297045787682656e-05);
    let mut worst = 0.0f64;
    for k in 0..50 {
        let q: Vec<f64> = (0..6)
            .map(|j| ((k * 7 + j * 3) as f64 * 0.37).sin() * 3.0)
            .collect();
        let d = table.fk(&q).expect("fk").inverse()
            * calibrated_fk(&nominal_sheet.table, &conf.deltas, &q);
        worst = worst.max(d.translation.vector.norm());
    }
    // Metre-scale d cancel: a few ulps of 10 m.
    assert!(worst < 1e-13, "{worst}");
    // The calibrated arm is millimetres from the nominal one, not metres.
    let home = (nominal_sheet.table.fk(&[0.0; 6]).expect("fk").inverse()
        * table.fk(&[0.0; 6]).expect("fk"))
    .translation
    .vector
    .norm();
    assert!(home < 0.02, "{home}");
    let short = Deltas::new(vec![0.0], vec![0.0], vec![0.0], vec![0.0]).expect("deltas");
    assert!(calibrated(&nominal_sheet.table, &short).is_err());
}

/// The written URDF's joint origins: (joint, distance of its origin from its parent link's
/// frame, metres), read with the URDF reader.
fn origin_lengths(urdf: &str) -> Vec<(String, f64)> {
    let model = urdf_axes::UrdfModel::parse(urdf).expect("urdf");
    let mut out = Vec::new();
    for link in model.links() {
        if let Some((joint, _, origin)) = model.parent_joint(link) {
            out.push((joint.to_owned(), origin.translation.vector.norm()));
        }
    }
    out
}

/// `to-urdf`'s writer on the calibrated UR3: the naive DH frames sit metres out (the test
/// can fail), the written joint origins within twice the nominal arm's reach, and the written
/// URDF, extracted again, has the forward kinematics of nominal + deltas.
#[test]
fn the_written_urdf_keeps_joint_origins_on_the_arm_with_the_same_kinematics() {
    let conf = CalibrationConf::parse(CONF, "calibration.conf").expect("conf");
    for s in NOMINAL {
        let nominal_table = Sheet::parse(s.text, s.name).expect("sheet").table;
        let table = calibrated(&nominal_table, &conf.deltas).expect("calibrated");
        let reach = nominal_table.size();
        let naive = table.frames(&[0.0; 6]).expect("frames");
        let worst_naive = naive
            .iter()
            .map(|f| f.translation.vector.norm())
            .fold(0.0, f64::max);
        assert!(
            worst_naive > 2.0 * reach,
            "{}: the naive frames are on the arm already",
            s.name
        );
        let urdf = crate::urdf_writer::urdf_of(&table, s.name, "base_link", "tool0");
        for (joint, length) in origin_lengths(&urdf) {
            assert!(
                length <= 2.0 * reach,
                "{}: joint {joint} origin {length} m out (reach {reach} m)",
                s.name
            );
        }
        let proof = crate::urdf_writer::prove_urdf(&urdf, &table, "base_link", "tool0", 200, 1)
            .expect("proof");
        assert!(proof.passed, "{}: {proof:?}", s.name);
        let model = urdf_axes::UrdfModel::parse(&urdf).expect("urdf");
        let chain = model
            .chain(Some("base_link"), Some("tool0"))
            .expect("chain");
        for k in 0..50 {
            let q: Vec<f64> = (0..6)
                .map(|j| ((k * 11 + j * 5) as f64 * 0.29).cos() * 3.0)
                .collect();
            let d = chain.fk(&q).inverse() * calibrated_fk(&nominal_table, &conf.deltas, &q);
            assert!(
                d.translation.vector.norm() < 1e-9 && d.rotation.angle() < 1e-9,
                "{}: {d:?}",
                s.name
            );
        }
    }
}

/// The minimal-edit writer, given the robot's own URDF (the UR5 fixture): the calibrated
/// frames slide back onto the arm, and the edited URDF has the calibrated kinematics.
#[test]
fn the_minimal_edit_of_the_robots_urdf_keeps_joint_origins_on_the_arm() {
    let text = include_str!("../../../../fixtures/robots/ur5/robot.urdf");
    let model = urdf_axes::UrdfModel::parse(text).expect("urdf");
    let chain = model
        .chain(Some("base_link"), Some("tool0"))
        .expect("chain");
    let nominal_table = dh_core::extract(
        chain.axes(),
        &chain.tip_pose(),
        dh_core::Tolerance::default(),
        Convention::Standard,
    )
    .expect("extract")
    .table;
    let conf = CalibrationConf::parse(CONF, "calibration.conf").expect("conf");
    let table = calibrated(&nominal_table, &conf.deltas).expect("calibrated");
    let edited = crate::urdf_edit::minimal_edit(text, &nominal_table, &table, "base_link", "tool0")
        .expect("edit");
    let reach = nominal_table.size();
    for (joint, length) in origin_lengths(&edited) {
        assert!(
            length <= 2.0 * reach,
            "joint {joint} origin {length} m out (reach {reach} m)"
        );
    }
    let model = urdf_axes::UrdfModel::parse(&edited).expect("edited");
    let chain = model
        .chain(Some("base_link"), Some("tool0"))
        .expect("chain");
    for k in 0..50 {
        let q: Vec<f64> = (0..6)
            .map(|j| ((k * 13 + j * 7) as f64 * 0.31).sin() * 3.0)
            .collect();
        let d = chain.fk(&q).inverse() * table.fk(&q).expect("fk");
        assert!(
            d.translation.vector.norm() < 1e-9 && d.rotation.angle() < 1e-9,
            "{d:?}"
        );
    }
}
