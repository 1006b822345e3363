use super::*;

fn map() -> ColumnMap {
    ColumnMap {
        time: None,
        joints: ColumnRef::parse_list("1-2").unwrap(),
        joint_names: vec![],
        point: [
            ColumnRef::Number(3),
            ColumnRef::Number(4),
            ColumnRef::Number(5),
        ],
        target: None,
        sigma: None,
        sigma_axes: None,
        skip_incomplete: false,
        config: None,
        set: None,
        session: None,
        orientation: None,
        delimiter: None,
        header: true,
        length_scale: 1e-3,
        angle_scale: std::f64::consts::PI / 180.0,
        prismatic: vec![],
    }
}

#[test]
fn lists_of_columns() {
    assert_eq!(
        ColumnRef::parse_list("1-3,q7").unwrap(),
        vec![
            ColumnRef::Number(1),
            ColumnRef::Number(2),
            ColumnRef::Number(3),
            ColumnRef::Name("q7".into())
        ]
    );
    assert!(ColumnRef::parse_list("0").is_err());
    assert!(ColumnRef::parse_list("3-1").is_err());
    assert!(ColumnRef::parse_list("1,,2").is_err());
}

#[test]
fn separators_units_and_header_names() {
    let text = "# export\nA1;A2;X;Y;Z\n90;-45;1000;2000;3000\n0;0;1;2;3\n";
    let (m, notes) = parse(text, &map()).unwrap();
    assert!(notes.is_empty());
    assert_eq!(m.joint_names, vec!["A1", "A2"]);
    assert!((m.samples[0].q[0] - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    assert!((m.samples[0].point - Vector3::new(1.0, 2.0, 3.0)).norm() < 1e-15);
    assert_eq!(m.samples[1].line, 4);
    let tabbed = text.replace(';', "\t");
    assert_eq!(parse(&tabbed, &map()).unwrap().0, m);
}

#[test]
fn only_a_zero_sigma_is_floored_and_said() {
    let mut with_sigma = map();
    with_sigma.sigma = Some(ColumnRef::Number(6));
    let text = "a,b,x,y,z,s\n0,0,1,2,3,0.0005\n0,0,1,2,3,0\n";
    let (m, notes) = parse(text, &with_sigma).unwrap();
    // 0.5 µm is a sigma, not a rounding: it stays.
    assert!((m.samples[0].sigma.unwrap().x - 5e-7).abs() < 1e-18);
    assert_eq!(m.samples[1].sigma.unwrap().x, SIGMA_FLOOR);
    assert_eq!(notes.len(), 1);
    assert!(
        notes[0].contains("1 sample(s)") && notes[0].contains("line 3"),
        "{notes:?}"
    );
}

#[test]
fn errors_name_the_line_and_column() {
    let e = parse("a,b,x,y,z\n1,2,3,4\n", &map()).unwrap_err();
    assert_eq!(e.to_string(), "line 2: expected 5 fields, found 4");
    let mut by_name = map();
    by_name.point[0] = ColumnRef::Name("px".into());
    let e = parse("a,b,x,y,z\n1,2,3,4,5\n", &by_name).unwrap_err();
    assert!(e.to_string().contains("a column named 'px'"), "{e}");
    let e = parse("a,b,x,y,z\n1,2,3,4,5e9\n", &map()).unwrap_err();
    assert!(e.to_string().contains("length unit"), "{e}");
    let mut radians = map();
    radians.angle_scale = 1.0;
    let e = parse("a,b,x,y,z\n90,0,3,4,5\n", &radians).unwrap_err();
    assert!(e.to_string().contains("angle unit"), "{e}");
}

#[test]
fn a_session_column_names_each_rows_session() {
    let mut with = map();
    with.session = Some(ColumnRef::Name("day".into()));
    let text = "a,b,x,y,z,day\n0,0,1,2,3,mon\n1,0,1,2,3,tue\n2,0,1,2,3,mon\n";
    let (m, _) = parse(text, &with).unwrap();
    assert_eq!(m.sessions, ["mon", "tue"]);
    let s: Vec<usize> = m.samples.iter().map(|s| s.session).collect();
    assert_eq!(s, [0, 1, 0]);
    let e = parse("a,b,x,y,z,day\n0,0,1,2,3,\n", &with).unwrap_err();
    assert!(
        e.to_string().contains("line 2") && e.to_string().contains("session"),
        "{e}"
    );
}

#[test]
fn names_the_csv_cannot_hold_are_refused() {
    let text = "x,y,X,Y,Z\n0,0,1,2,3\n";
    // The header's names `x`, `y` would head the joint columns beside the point's `x, y`.
    let e = parse(text, &map()).unwrap_err().to_string();
    assert!(
        e.contains("'x', the name of a reserved column") && e.contains("header's names"),
        "{e}"
    );
    for (names, found) in [
        (["a", "a"], "'a' twice"),
        (["a", "e\u{1b}[2J"], "U+001B"),
        (["t\u{202e}1", "b"], "U+202E"),
        (["a", "sigma"], "'sigma', the name of a reserved column"),
    ] {
        let mut m = map();
        m.joint_names = names.iter().map(|n| n.to_string()).collect();
        let e = parse("a,b,X,Y,Z\n0,0,1,2,3\n", &m).unwrap_err().to_string();
        assert!(e.contains(found), "{names:?}: {e}");
    }
}

#[test]
fn a_column_in_two_roles_or_named_twice_is_refused() {
    let mut m = map();
    m.sigma = Some(ColumnRef::Number(5));
    let e = parse("a,b,X,Y,Z\n0,0,1,2,3\n", &m).unwrap_err().to_string();
    assert!(e.contains("column 5 ('Z') as point z and as sigma"), "{e}");
    let mut m = map();
    m.joints = vec![ColumnRef::Number(1), ColumnRef::Number(1)];
    m.joint_names = vec!["j1".into(), "j2".into()];
    let e = parse("a,b,X,Y,Z\n0,0,1,2,3\n", &m).unwrap_err().to_string();
    assert!(e.contains("as joint 1 and as joint 2"), "{e}");
    let mut m = map();
    m.point[0] = ColumnRef::Name("X".into());
    let e = parse("a,b,X,X,Z\n0,0,1,2,3\n", &m).unwrap_err().to_string();
    assert!(
        e.contains("one column named 'X'") && e.contains("columns 3 and 4"),
        "{e}"
    );
}

#[test]
fn a_prismatic_joint_must_be_a_joint() {
    let mut m = map();
    m.prismatic = vec!["A9".into()];
    let e = parse("A1,A2,X,Y,Z\n0,0,1,2,3\n", &m)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("prismatic joints among the joints 'A1', 'A2'") && e.contains("'A9'"),
        "{e}"
    );
}

#[test]
fn sigmas_are_held_to_the_sigma_options_range() {
    let mut m = map();
    m.sigma = Some(ColumnRef::Number(6));
    for bad in ["1e300", "1001", "1e-10", "-1"] {
        let text = format!("a,b,x,y,z,s\n0,0,1,2,3,{bad}\n").replace("x,y,z", "X,Y,Z");
        let e = parse(&text, &m).unwrap_err().to_string();
        assert!(
            e.contains("a standard deviation of 0 (floored) or in"),
            "{bad}: {e}"
        );
    }
    // 1000 mm (1 m) is the largest; in metres the canonical reader's 100 m is the cap.
    let (d, _) = parse("a,b,X,Y,Z,s\n0,0,1,2,3,1000\n", &m).unwrap();
    assert_eq!(d.samples[0].sigma.unwrap().x, 1.0);
    m.length_scale = 1.0;
    assert!(parse("a,b,X,Y,Z,s\n0,0,1,2,3,101\n", &m).is_err());
}

#[test]
fn per_axis_sigmas_incomplete_rows_and_copies() {
    let mut m = map();
    m.sigma_axes = Some([
        ColumnRef::Number(6),
        ColumnRef::Number(7),
        ColumnRef::Number(8),
    ]);
    m.config = Some(ColumnRef::Number(9));
    let text = "a,b,X,Y,Z,sx,sy,sz,id\n\
                0,0,1,2,3,0.01,0.02,0.03,p1\n\
                0,0,1,2,3,0.01,0.02,0.03,p1\n\
                1,0,NaN,NaN,NaN,NaN,NaN,NaN,p2\n\
                1,0,1,2,3,0.01,0.02,0.03,p2\n\
                1,0,1,2,3,0.01,0.02,0.03,p2\n\
                1,0,1,2,3.001,0.01,0.02,0.03,p2\n";
    let e = parse(text, &m).unwrap_err();
    assert!(matches!(e, DataError::Incomplete { line: 4, .. }), "{e}");
    assert_eq!(
        e.to_string(),
        "line 4, column 'X': expected a number, found 'NaN' (a value not logged)"
    );
    m.skip_incomplete = true;
    let (d, notes) = parse(text, &m).unwrap();
    let sigma = d.samples[0].sigma.unwrap();
    assert!(
        (sigma - Vector3::new(1e-5, 2e-5, 3e-5)).norm() < 1e-20,
        "{sigma}"
    );
    // Line 3 copies line 2 and line 6 copies line 5; line 7 differs by 1 µm: kept.
    let lines: Vec<usize> = d.samples.iter().map(|s| s.line).collect();
    assert_eq!(lines, [2, 5, 7]);
    assert_eq!(notes.len(), 2, "{notes:?}");
    assert!(
        notes[0].starts_with("1 incomplete row(s) left out")
            && notes[0].contains("line 4, column 'X'"),
        "{notes:?}"
    );
    assert!(
        notes[1].starts_with("2 row(s) are identical copies")
            && notes[1].contains("line 3, a copy of line 2"),
        "{notes:?}"
    );
    // The canonical CSV carries the per-axis sigmas as sx, sy, sz and reads back equal.
    let written = crate::csv::write_measurements(&d);
    assert!(written.contains(",sx,sy,sz"), "{written}");
    let back = crate::csv::parse_measurements(
        &written,
        &d.joint_names,
        &crate::csv::CsvOptions::default(),
    )
    .unwrap();
    for (a, b) in back.samples.iter().zip(&d.samples) {
        assert_eq!((&a.q, a.point, a.sigma), (&b.q, b.point, b.sigma));
    }
    let e = parse("a,b,X,Y,Z,sx,sy,sz,id\n0,0,NaN,1,1,1,1,1,p\n", &m).unwrap_err();
    assert!(e.to_string().contains("only incomplete rows"), "{e}");
}

#[test]
fn a_range_of_columns_is_bounded_before_it_is_allocated() {
    let e = ColumnRef::parse_list("1-100000000000").unwrap_err();
    assert!(e.contains("at most 65536 columns"), "{e}");
    let mut m = map();
    m.joints = ColumnRef::parse_list("1-60000").unwrap();
    let e = parse("a,b,X,Y,Z\n0,0,1,2,3\n", &m).unwrap_err().to_string();
    assert!(e.contains("a column 6 (the file has 5)"), "{e}");
}
