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
