//! Unit tests of the measurement CSV reader and writer.

use super::*;

fn names(n: &[&str]) -> Vec<String> {
    n.iter().map(|s| s.to_string()).collect()
}

/// Fuzzing find: a model joint named `socket` was read from the socket column and the file
/// written back had that column twice.
#[test]
fn a_joint_named_like_a_reserved_column_is_refused() {
    for joint in RESERVED_COLUMNS {
        let text = format!("{joint},x,y,z\n0.0,1,2,3\n");
        let err =
            parse_measurements(&text, &names(&[joint]), &CsvOptions::default()).expect_err(joint);
        assert!(
            matches!(&err, DataError::ReservedJointName { line: 1, joint: j } if j == joint),
            "{err}"
        );
        assert!(err.to_string().contains("rename the joint"), "{err}");
    }
}

#[test]
fn reads_all_optional_columns() {
    let text = "\
# a comment
j1, j2 ,x,y,z,target,config,sigma,set

0.1,0.2,1,2,3,A,c1,1e-5,train
0.1,0.2,1.5,2,3,B,c1,,test
  # indented comment
0.3,0.4,1,2,3.5,A,,2e-5,
";
    let m = parse_measurements(text, &names(&["j1", "j2"]), &CsvOptions::default()).unwrap();
    assert_eq!(m.targets, names(&["A", "B"]));
    assert_eq!(m.samples.len(), 3);
    let s = &m.samples;
    assert_eq!(s[0].q[..], [0.1, 0.2]);
    assert_eq!(s[0].point, Vector3::new(1.0, 2.0, 3.0));
    assert_eq!(s[0].sigma, Some(Vector3::new(1e-5, 1e-5, 1e-5)));
    assert_eq!(s[0].config.as_deref(), Some("c1"));
    assert_eq!(s[0].line, 4);
    assert_eq!(
        (s[1].target, s[1].split, s[1].sigma),
        (1, Split::Validation, None)
    );
    assert_eq!(
        (s[2].config.clone(), s[2].split, s[2].line),
        (None, Split::Calibration, 7)
    );
}

#[test]
fn joint_columns_follow_the_models_order_not_the_files() {
    let text = "z,y,x,b,a\n3,2,1,20,10\n";
    let m = parse_measurements(text, &names(&["a", "b"]), &CsvOptions::default()).unwrap();
    assert_eq!(m.samples[0].q[..], [10.0, 20.0]);
    assert_eq!(m.samples[0].point, Vector3::new(1.0, 2.0, 3.0));
    assert_eq!(m.targets, vec![DEFAULT_TARGET.to_string()]);
}

#[test]
fn converts_units_and_keeps_prismatic_joints_as_lengths() {
    let text = "rot,slide,x,y,z,sx,sy,sz\n90,250,1000,-2000,500,0.01,0.02,0.03\n";
    let opts = CsvOptions {
        length_unit: LengthUnit::Millimetre,
        angle_unit: AngleUnit::Degree,
        prismatic: names(&["slide"]),
    };
    let m = parse_measurements(text, &names(&["rot", "slide"]), &opts).unwrap();
    let s = &m.samples[0];
    assert!((s.q[0] - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    assert!((s.q[1] - 0.25).abs() < 1e-15);
    assert!((s.point - Vector3::new(1.0, -2.0, 0.5)).norm() < 1e-15);
    assert!((s.sigma.unwrap() - Vector3::new(1e-5, 2e-5, 3e-5)).norm() < 1e-18);
}

#[test]
fn quoted_cells_keep_commas() {
    let text = "j,x,y,z,target\n0,1,2,3,\"left, upper\"\n";
    let m = parse_measurements(text, &names(&["j"]), &CsvOptions::default()).unwrap();
    assert_eq!(m.targets, names(&["left, upper"]));
}

fn err(text: &str, joints: &[&str]) -> String {
    parse_measurements(text, &names(joints), &CsvOptions::default())
        .unwrap_err()
        .to_string()
}

#[test]
fn error_messages_name_line_column_and_text() {
    assert_eq!(
        err("", &["j"]),
        "expected a header line and at least one data row, found an empty file"
    );
    assert_eq!(
        err("# only comments\n\nj,x,y,z\n", &["j"]),
        "expected a header line and at least one data row, found only a header"
    );
    assert_eq!(
        err("j1,x,y,z\n0,0,0,0\n", &["j1", "j2", "j3"]),
        "line 1: missing joint column(s) 'j2', 'j3'; the header has 'j1', 'x', 'y', 'z'"
    );
    assert_eq!(
        err("j,x,z\n0,0,0\n", &["j"]),
        "line 1: missing point column 'y'; the header has 'j', 'x', 'z'"
    );
    assert_eq!(
        err("j,x,y,z,x\n0,0,0,0,0\n", &["j"]),
        "line 1: duplicate column 'x'"
    );
    assert_eq!(
        err("j,x,y,z\n0,0,0,0\n0,0,0\n", &["j"]),
        "line 3: expected 4 fields, found 3"
    );
    assert_eq!(
        err("j,x,y,z\n0,0,abc,0\n", &["j"]),
        "line 2, column 'y': expected a number, found 'abc'"
    );
    assert_eq!(
        err("j,x,y,z\nNaN,0,0,0\n", &["j"]),
        "line 2, column 'j': expected a finite number, found 'NaN'"
    );
    assert_eq!(
        err("j,x,y,z\n0,inf,0,0\n", &["j"]),
        "line 2, column 'x': expected a finite number, found 'inf'"
    );
    assert_eq!(
        err("j,x,y,z,set\n0,0,0,0,holdout\n", &["j"]),
        "line 2, column 'set': expected train, calibration, test or validation, found 'holdout'"
    );
    assert_eq!(
        err("j,x,y,z,sigma,sy\n0,0,0,0,1,1\n", &["j"]),
        "line 1: columns 'sigma' and 'sy' conflict; give one of them"
    );
    assert_eq!(
        err("j,x,y,z,sigma\n0,0,0,0,-1\n", &["j"]),
        "line 2, column 'sigma': expected a standard deviation > 0, found '-1'"
    );
    assert_eq!(
        err("j,x,y,z,target\n0,0,0,0,\"open\n", &["j"]),
        "line 2: unterminated quoted field"
    );
}

#[test]
fn suspicious_units_say_what_to_pass() {
    assert_eq!(
        err("j,x,y,z\n90,0,0,0\n", &["j"]),
        "line 2, column 'j': 90 rad looks like degrees; pass --angle-unit deg"
    );
    assert_eq!(
        err("j,x,y,z\n0,0,1250.5,0\n", &["j"]),
        "line 2, column 'y': 1250.5 m looks like millimetres; pass --length-unit mm"
    );
    // Prismatic columns are lengths: 90 (m!) is not an angle, and is not checked as one.
    let opts = CsvOptions {
        prismatic: names(&["j"]),
        ..CsvOptions::default()
    };
    assert!(parse_measurements("j,x,y,z\n90,0,0,0\n", &names(&["j"]), &opts).is_ok());
    // Rows in one unit, then rows in the other: the file mixes units.
    assert_eq!(
        err("j,x,y,z\n0,0,0.8,0\n0,0,1.2,0\n0,0,1250.5,0\n", &["j"]),
        "line 4, column 'y': 1250.5 m looks like millimetres, but the rows above look like \
             metres: the file mixes units"
    );
    assert_eq!(
        err("j,x,y,z\n1.5,0,0,0\n90,0,0,0\n", &["j"]),
        "line 3, column 'j': 90 rad looks like degrees, but the rows above look like \
             radians: the file mixes units"
    );
    // A home pose of zeros first says nothing about the unit.
    assert_eq!(
        err("j,x,y,z\n0,0,0,0\n90,0,0,0\n", &["j"]),
        "line 3, column 'j': 90 rad looks like degrees; pass --angle-unit deg"
    );
}

#[test]
fn writing_round_trips_exactly() {
    let mk = |q: Vec<f64>, target, point, sigma, config: Option<&str>, split| Sample {
        time: None,
        orientation: None,
        session: 0,
        q: q.into(),
        target,
        point,
        sigma,
        config: config.map(Into::into),
        split,
        line: 0,
        socket: None,
    };
    let m = Measurements {
        sessions: Vec::new(),
        joint_names: names(&["joint 1", "a,b"]),
        targets: names(&["SMR1", "with \"quote\""]),
        samples: vec![
            mk(
                vec![0.1 + 0.2, -1e-300],
                0,
                Vector3::new(1.0 / 3.0, -2.5e-7, 12.345_678_901_234_568),
                Some(Vector3::new(1e-5, 2e-5, 3e-5)),
                Some("pose 1"),
                Split::Calibration,
            ),
            mk(
                vec![std::f64::consts::PI, 0.0],
                1,
                Vector3::new(-0.0, 5e-324, 99.999_999_999_999_99),
                None,
                None,
                Split::Validation,
            ),
        ],
    };
    let text = write_measurements(&m);
    let back = parse_measurements(&text, &m.joint_names, &CsvOptions::default()).unwrap();
    let strip = |m: &Measurements| {
        let mut m = m.clone();
        m.samples.iter_mut().for_each(|s| s.line = 0);
        m
    };
    assert_eq!(strip(&back), m);
    for (a, b) in back.samples.iter().zip(&m.samples) {
        for (x, y) in a.point.iter().zip(b.point.iter()) {
            assert_eq!(x.to_bits(), y.to_bits());
        }
    }
    assert_eq!(back.samples[1].line, 4);
}

/// The `time` column (seconds, any origin): read as written, an empty cell is no time, the
/// writer adds the column only when a sample has one, and a non-number names line and column.
#[test]
fn time_column_round_trips_and_bad_times_are_named() {
    let text = "j1,x,y,z,time\n0.1,1,2,3,1700000000.25\n0.2,1,2,3,\n0.3,1,2,3,-5e-3\n";
    let m = parse_measurements(text, &names(&["j1"]), &CsvOptions::default()).unwrap();
    let times: Vec<Option<f64>> = m.samples.iter().map(|s| s.time).collect();
    assert_eq!(times, vec![Some(1_700_000_000.25), None, Some(-5e-3)]);
    let written = write_measurements(&m);
    assert!(
        written.lines().nth(1) == Some("j1,x,y,z,target,time"),
        "{written}"
    );
    let back = parse_measurements(&written, &m.joint_names, &CsvOptions::default()).unwrap();
    let back_times: Vec<Option<f64>> = back.samples.iter().map(|s| s.time).collect();
    assert_eq!(back_times, times);
    let untimed = m.filtered(|i, _| i == 1);
    assert!(!write_measurements(&untimed).contains("time"));
    let e = err("j1,x,y,z,time\n0.1,1,2,3,noon\n", &["j1"]);
    assert!(
        e.contains("line 2") && e.contains("time") && e.contains("noon"),
        "{e}"
    );
}

#[test]
fn reads_orientation_columns_and_writes_them_back() {
    let text = "\
j1,x,y,z,sigma,qw,qx,qy,qz,sigma_rot
0.1,1,2,3,2e-5,0.7071068,0,0.7071068,0,5e-5
0.2,1,2,3,2e-5,,,,,
";
    let m = parse_measurements(text, &names(&["j1"]), &CsvOptions::default()).unwrap();
    let o = m.samples[0].orientation.as_ref().unwrap();
    assert_eq!(o.sigma, 5e-5);
    // Rounded to 7 digits, normalised: a quarter turn about y.
    let expected =
        nalgebra::UnitQuaternion::from_euler_angles(0.0, std::f64::consts::FRAC_PI_2, 0.0);
    assert!(o.rotation.angle_to(&expected) < 1e-7);
    assert!((o.rotation.quaternion().norm() - 1.0).abs() < 1e-15);
    assert_eq!(m.samples[1].orientation, None);
    let back = parse_measurements(
        &write_measurements(&m),
        &names(&["j1"]),
        &CsvOptions::default(),
    )
    .unwrap();
    for (a, b) in m.samples.iter().zip(&back.samples) {
        assert_eq!(a.orientation, b.orientation);
    }
}

/// A `sigma_rot` of 0 (a device that rounds its angles) is floored with a note naming how many
/// and the first line, as a position sigma of 0 is.
#[test]
fn zero_orientation_sigmas_are_floored_with_a_note() {
    let text = "j1,x,y,z,sigma,qw,qx,qy,qz,sigma_rot\n\
                0.1,1,2,3,1e-5,1,0,0,0,5e-5\n\
                0.2,1,2,3,1e-5,1,0,0,0,0\n\
                0.3,1,2,3,1e-5,1,0,0,0,0\n";
    let (m, notes) =
        parse_measurements_noting(text, &["j1".to_string()], &CsvOptions::default()).unwrap();
    let sigmas: Vec<f64> = m
        .samples
        .iter()
        .map(|s| s.orientation.as_ref().unwrap().sigma)
        .collect();
    assert_eq!(sigmas, [5e-5, SIGMA_ROT_FLOOR, SIGMA_ROT_FLOOR]);
    assert_eq!(notes.len(), 1, "{notes:?}");
    assert!(
        notes[0].starts_with("2 sample(s) give a sigma_rot of 0 (first at line 3;"),
        "{notes:?}"
    );
}

#[test]
fn bad_orientations_name_line_and_column() {
    let head = "j1,x,y,z,qw,qx,qy,qz,sigma_rot\n";
    for (row, expected) in [
        (
            "0.1,1,2,3,1.2,0,0,0,5e-5",
            "line 2: expected a unit quaternion in columns qw, qx, qy, qz (norm within 0.001 of 1), found norm 1.2",
        ),
        ("0.1,1,2,3,1,NaN,0,0,5e-5", "line 2"),
        ("0.1,1,2,3,1,0,,0,5e-5", "line 2: expected all of qw, qx, qy, qz or none, found an empty 'qy'"),
        ("0.1,1,2,3,1,0,0,0,", "line 2: expected a standard deviation in column 'sigma_rot'"),
        ("0.1,1,2,3,1,0,0,0,-1", "line 2: expected a standard deviation >= 0 and <= 1 rad in column 'sigma_rot', found '-1'"),
    ] {
        let e = err(&format!("{head}{row}\n"), &["j1"]);
        assert!(e.starts_with(expected), "{e}");
    }
    let nan = err(&format!("{head}0.1,1,2,3,1,NaN,0,0,5e-5\n"), &["j1"]);
    assert!(nan.contains("qx"), "{nan}");
    let e = err("j1,x,y,z,qw,qx,qy,qz\n0.1,1,2,3,1,0,0,0\n", &["j1"]);
    assert!(e.contains("missing point column 'sigma_rot'"), "{e}");
    let e = err("j1,x,y,z,qw,qx,qy\n0.1,1,2,3,1,0,0\n", &["j1"]);
    assert!(e.contains("missing point column 'qz'"), "{e}");
}

/// The cells' trim is `str::trim`: the same text for every mix of ASCII and Unicode whitespace
/// (the vertical tab, NEL, no-break and em spaces), letters and multi-byte characters at
/// either end.
#[test]
fn the_cells_trim_is_str_trim() {
    let parts = [
        "", " ", "\t", "\u{b}", "\u{c}", "\r", "\n", "\u{85}", "\u{a0}", "\u{2003}", "a", "1.5",
        "é", "#", "~", "\u{7f}", "\u{1}",
    ];
    for a in parts {
        for b in parts {
            for c in parts {
                let text = format!("{a}{b}{c}");
                assert_eq!(records::trim(&text), text.trim(), "{text:?}");
            }
        }
    }
}

/// UTF-16 without a byte-order mark is valid UTF-8 (a zero byte beside each ASCII character):
/// it is named with the command that converts it, not reported as a control character U+0000.
/// CR-only line ends (old Mac OS) make the file one line: named the same way.
#[test]
fn utf16_and_cr_only_texts_are_named_with_their_conversion() {
    let csv = "joint_1,x,y,z\n0.1,1,2,3\n";
    let joints = names(&["joint_1"]);
    let le: String = csv.chars().flat_map(|c| [c, '\0']).collect();
    let be: String = csv.chars().flat_map(|c| ['\0', c]).collect();
    for (text, order) in [(le, "le"), (be, "be")] {
        let e = parse_measurements(&text, &joints, &CsvOptions::default()).unwrap_err();
        let e = e.to_string();
        assert!(
            e.contains(&format!("found UTF-16{}", order.to_uppercase()))
                && e.contains(&format!("iconv -f utf-16{order} -t utf-8")),
            "{e}"
        );
    }
    let cr = csv.replace('\n', "\r");
    let e = parse_measurements(&cr, &joints, &CsvOptions::default()).unwrap_err();
    assert!(
        e.to_string().contains("CR alone (old Mac OS line ends)")
            && e.to_string().contains("tr '\\r' '\\n'"),
        "{e}"
    );
    // CRLF and a last line without an end read as before.
    let crlf = csv.replace('\n', "\r\n");
    assert_eq!(
        parse_measurements(&crlf, &joints, &CsvOptions::default())
            .unwrap()
            .samples
            .len(),
        1
    );
    assert!(parse_measurements(
        "joint_1,x,y,z\r\n0.1,1,2,3",
        &joints,
        &CsvOptions::default()
    )
    .is_ok());
}

/// A `;`-separated export given as a measurement file is pointed to `import --layout columns`.
#[test]
fn a_semicolon_export_is_pointed_to_the_columns_import() {
    let text = "joint_1;x;y;z\n0.1;1;2;3\n";
    let e = parse_measurements(text, &names(&["joint_1"]), &CsvOptions::default()).unwrap_err();
    assert_eq!(
        e.to_string(),
        "line 1: expected columns separated by ',', found ';' (the header is one column); an \
         export with its own separator, units and column names reads with urdf-dh import \
         --layout columns"
    );
}
