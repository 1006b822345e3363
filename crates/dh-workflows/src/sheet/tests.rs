//! Tests of reading and checking serial sheets.

use super::parse::duplicate_key_at;
use super::*;

#[test]
fn units_convert_on_read_and_write() {
    let text = "convention: standard\nlength_unit: mm\nangle_unit: deg\njoints:\n  - {name: j1, type: revolute, a: 180, alpha: -90, d: 400, theta: 0, lower: -155, upper: 155}\n";
    let s = Sheet::parse(text, "t.yaml").unwrap();
    let r = &s.table.rows[0];
    assert!((r.a - 0.18).abs() < 1e-15 && (r.alpha + std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    assert!(!s.has_base && !s.has_tool);
    let back = SheetDoc::from_table(&s.table, LengthUnit::Mm, AngleUnit::Deg);
    assert!((back.joints[0].a - 180.0).abs() < 1e-12);
    assert!((back.joints[0].upper.unwrap() - 155.0).abs() < 1e-12);
}

#[test]
fn mimics_of_no_row_warn_and_of_themselves_fail() {
    let sheet = |driver: &str| {
        format!("convention: standard\nlength_unit: m\nangle_unit: rad\njoints:\n  - {{name: a, type: revolute, a: 0, alpha: 0, d: 0, theta: 0}}\n  - {{name: b, type: revolute, a: 0, alpha: 0, d: 0, theta: 0, mimic: {{joint: {driver}}}}}\n")
    };
    assert!(Sheet::parse(&sheet("a"), "s.yaml")
        .unwrap()
        .warnings
        .is_empty());
    let s = Sheet::parse(&sheet("finger_1"), "s.yaml").unwrap();
    assert_eq!(s.warnings.len(), 1);
    assert!(
        s.warnings[0]
            .contains("follows 'finger_1', which is no joint of the sheet (joints: 'a', 'b')"),
        "{:?}",
        s.warnings
    );
    let e = Sheet::parse(&sheet("b"), "s.yaml").unwrap_err();
    assert!(
        e.to_string()
            .contains("joint 'b': mimic: expected another joint to follow, found itself"),
        "{e}"
    );
}

#[test]
fn magnitudes_beyond_any_robot_are_refused() {
    let e = Sheet::parse(
        "convention: standard\nlength_unit: m\nangle_unit: rad\njoints:\n  - {name: a, type: revolute, a: 0, alpha: 0, d: 1e306, theta: 0}\n",
        "s.yaml",
    )
    .unwrap_err();
    assert!(
        e.to_string().contains(
            "joint 'a': d: expected a magnitude of at most 1e30 (1e27 m or rad), found 1e306"
        ),
        "{e}"
    );
    // Found by fuzzing: extract writes ill-conditioned rows kilometres long, and they
    // must read back (here 7.9e9 mm, from a mutated KUKA URDF).
    assert!(Sheet::parse(
        "convention: standard\nlength_unit: mm\nangle_unit: deg\njoints:\n  - {name: a, type: revolute, a: 7.948966e9, alpha: 0, d: 0, theta: 0}\n",
        "s.yaml",
    )
    .is_ok());
}

#[test]
fn deep_nesting_is_refused_at_once() {
    // Found by fuzzing: libyaml scans unclosed flow collections in quadratic time.
    let text = format!("convention: standard\njoints: {}", "[".repeat(8000));
    let start = std::time::Instant::now();
    let e = Sheet::parse(&text, "s.yaml").unwrap_err();
    assert!(start.elapsed() < std::time::Duration::from_secs(1));
    assert!(
        e.to_string()
            .contains("s.yaml (line 2): expected lists and maps nested at most 64 deep"),
        "{e}"
    );
    // Brackets in quotes and comments do not count.
    let text = format!(
        "# {}\nconvention: standard\nlength_unit: m\nangle_unit: rad\nrobot: '{}'\njoints: [{{name: a, type: revolute, a: 0, alpha: 0, d: 0, theta: 0}}]\n",
        "[".repeat(100),
        "{".repeat(100)
    );
    assert!(Sheet::parse(&text, "s.yaml").is_ok());
}

#[test]
fn unknown_keys_and_bad_values_are_errors() {
    let e = Sheet::parse(
        "convention: standard\nlength_unit: m\nangle_unit: rad\njoints: []\nfoo: 1\n",
        "s.yaml",
    )
    .unwrap_err();
    assert!(e.to_string().contains("unknown field `foo`"), "{e}");
    let e = Sheet::parse(
        "convention: sideways\nlength_unit: m\nangle_unit: rad\njoints: []\n",
        "s.yaml",
    )
    .unwrap_err();
    assert!(e.to_string().contains("line 1"), "{e}");
}

#[test]
fn a_repeated_key_is_located_where_it_repeats() {
    let text =
        "convention: standard\nlength_unit: m\nangle_unit: deg\nangle_unit: rad\njoints: []\n";
    let e = parse_doc(text, "s.yaml").unwrap_err().to_string();
    assert!(e.contains("(line 4, column 1)"), "{e}");
    let flow = "joints:\n  - {name: j, d: 0, a: 0, d: 1}\n";
    assert_eq!(
        duplicate_key_at(flow, "joints[0]: duplicate field `d`", 10),
        Some((2, 27))
    );
    assert_eq!(duplicate_key_at(flow, "some other message", 0), None);
}

#[test]
fn a_bad_transform_says_which_in_one_message() {
    let e = Sheet::parse(
        "convention: standard\nlength_unit: m\nangle_unit: rad\nbase: {xyz: [0, 0, .inf], rpy: [0, 0, 0]}\njoints:\n  - {name: a, type: revolute, a: 0, alpha: 0, d: 0, theta: 0}\n",
        "s.yaml",
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        "reading the base transform: s.yaml: base: xyz and rpy must be finite numbers"
    );
}

/// A sheet of `n` revolute rows named `j1..jn`, row `i` carrying `extra(i)` (a mimic, ...).
fn rows_sheet(n: usize, unit: &str, theta: &str, extra: impl Fn(usize) -> String) -> String {
    let mut s = format!("convention: standard\nlength_unit: m\nangle_unit: {unit}\njoints:\n");
    for i in 1..=n {
        let t = if i == 1 { theta } else { "0" };
        s.push_str(&format!(
            "  - {{name: j{i}, type: revolute, a: 0.1, alpha: 0.5, d: 0, theta: {t}{}}}\n",
            extra(i)
        ));
    }
    s
}

#[test]
fn mimic_cycles_are_refused_naming_the_cycle() {
    // j1 -> j2 -> j3 -> j1; j4 follows the cycle from outside.
    let text = rows_sheet(4, "rad", "0", |i| match i {
        1 => ", mimic: {joint: j2}".into(),
        2 => ", mimic: {joint: j3}".into(),
        3 => ", mimic: {joint: j1}".into(),
        _ => ", mimic: {joint: j1}".into(),
    });
    let e = Sheet::parse(&text, "c.yaml").unwrap_err().to_string();
    assert!(
        e.contains("joint 'j1': mimic: expected drivers that end at a joint that mimics none, found a cycle j1 -> j2 -> j3 -> j1"),
        "{e}"
    );
    // A cycle reached from a row before it is named from its own first row.
    let text = rows_sheet(3, "rad", "0", |i| match i {
        1 => ", mimic: {joint: j2}".into(),
        2 => ", mimic: {joint: j3}".into(),
        _ => ", mimic: {joint: j2}".into(),
    });
    let e = Sheet::parse(&text, "c.yaml").unwrap_err().to_string();
    assert!(e.contains("found a cycle j2 -> j3 -> j2"), "{e}");
}

#[test]
fn a_long_reverse_mimic_chain_is_no_cycle_and_reads_in_one_pass() {
    // Each joint follows the next (the last moves on its own): 20 000 rows, a linear walk.
    let n = 20_000;
    let text = rows_sheet(n, "rad", "0", |i| {
        if i < n {
            format!(", mimic: {{joint: j{}}}", i + 1)
        } else {
            String::new()
        }
    });
    let s = Sheet::parse(&text, "chain.yaml").unwrap();
    assert_eq!(s.table.rows.len(), n);
    assert_eq!(s.table.rows[0].mimic.as_ref().unwrap().joint, "j2");
}

#[test]
fn angles_beyond_a_turn_are_wrapped_with_a_warning() {
    // 999999 rad: within 1e-15 rad of the exact wrap, -1.357564167085735044 rad (60-digit
    // arithmetic); its sine and cosine are those of 999999 (libm reduces exactly).
    let s = Sheet::parse(&rows_sheet(2, "rad", "999999", |_| String::new()), "w.yaml").unwrap();
    let t = s.table.rows[0].theta;
    assert!((t - -1.357_564_167_085_735).abs() < 1e-15, "{t}");
    assert!((t.sin() - 999_999f64.sin()).abs() < 1e-15);
    assert!((t.cos() - 999_999f64.cos()).abs() < 1e-15);
    let w = s.warnings.join("\n");
    assert!(
        w.contains(
            "joint 'j1': theta = 999999 rad is more than a turn: read as -1.357564167086 rad"
        ),
        "{w}"
    );
    // Negative, and in degrees (exact): -1e6 deg is -280 deg = 80 deg.
    let s = Sheet::parse(
        &rows_sheet(1, "rad", "-999999.5", |_| String::new()),
        "w.yaml",
    )
    .unwrap();
    assert!((s.table.rows[0].theta - 0.857_564_167_085_735).abs() < 1e-15);
    let s = Sheet::parse(
        &rows_sheet(1, "deg", "-1000000", |_| String::new()),
        "w.yaml",
    )
    .unwrap();
    assert!((s.table.rows[0].theta - 80f64.to_radians()).abs() < 1e-15);
    assert!(s
        .warnings
        .join("\n")
        .contains("read as 80.000000000000 deg"));
    // Within a turn: kept as written, no warning (270 deg stays 270 deg, -180 stays -180).
    for (unit, v, si) in [
        ("deg", "270", 270f64.to_radians()),
        ("deg", "-180", -std::f64::consts::PI),
        ("rad", "6.2", 6.2),
    ] {
        let s = Sheet::parse(&rows_sheet(1, unit, v, |_| String::new()), "w.yaml").unwrap();
        assert_eq!(s.table.rows[0].theta, si, "{unit} {v}");
        assert!(!s.warnings.iter().any(|w| w.contains("more than a turn")));
    }
    // Every wrapped angle lies in (-pi, pi] and is the same angle.
    for v in [
        7.0,
        -7.0,
        1e3,
        -1e3,
        123_456.789,
        999_999.999,
        -999_999.999,
        3.0 * std::f64::consts::PI,
    ] {
        let s = Sheet::parse(
            &rows_sheet(1, "rad", &format!("{v}"), |_| String::new()),
            "w.yaml",
        )
        .unwrap();
        let t = s.table.rows[0].theta;
        assert!(
            t > -std::f64::consts::PI && t <= std::f64::consts::PI,
            "{v}: {t}"
        );
        assert!(
            (t.sin() - v.sin()).abs() < 1e-12 && (t.cos() - v.cos()).abs() < 1e-12,
            "{v}: {t}"
        );
    }
}
