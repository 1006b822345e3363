//! `urdf-dh check`: fixtures against their vendor sheets, representation freedoms that must not
//! alarm, planted errors that must be named, and the shared corpus against its notes.

use std::path::Path;

use dh_workflows::input::load_chain;
use dh_workflows::sheet::Sheet;
use serde_yaml::Value;
use urdf_dh::commands::check::{compare, CHECK_ANGULAR, CHECK_LINEAR};

use crate::common::{fixture_robots, root, run, settings, skip_without_shared};

fn tol() -> dh_core::Tolerance {
    dh_core::Tolerance::new(CHECK_LINEAR, CHECK_ANGULAR).unwrap()
}

/// (joint, parameter) pairs that `check` reports for `urdf` against sheet text.
fn differences(
    urdf: &str,
    base: Option<&str>,
    tip: Option<&str>,
    sheet: &str,
) -> (bool, Vec<(String, String, Vec<String>)>) {
    let (_, chain) = load_chain(urdf, base, tip).unwrap();
    let sheet = Sheet::parse(sheet, "sheet").unwrap();
    let r = compare(&chain, &sheet, tol()).unwrap();
    let d = r
        .differences
        .iter()
        .map(|d| {
            (
                d.joint.clone().unwrap_or_default(),
                d.parameter.clone(),
                d.aliases.clone(),
            )
        })
        .collect();
    (r.matches, d)
}

#[test]
fn every_fixture_robot_against_its_vendor_sheet() {
    let _s = settings().bind_to_scope();
    for id in fixture_robots() {
        let urdf = format!("fixtures/robots/{id}/robot.urdf");
        let sheet = format!("fixtures/robots/{id}/vendor.yaml");
        insta::with_settings!({snapshot_suffix => id.clone()}, {
            insta::assert_snapshot!("check", run(&["check", &urdf, "--sheet", &sheet], None));
        });
    }
}

#[test]
fn json_report_follows_the_contract() {
    let _s = settings().bind_to_scope();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_urdf-dh"))
        .args([
            "check",
            "fixtures/robots/kuka_kr5_arc/robot.urdf",
            "--sheet",
            "fixtures/robots/kuka_kr5_arc/vendor.yaml",
            "--format",
            "json",
        ])
        .current_dir(root())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for key in [
        "matches",
        "differences",
        "max_position_error",
        "max_orientation_error",
        "tolerances",
    ] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    let got: Vec<(String, String)> = v["differences"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| {
            (
                d["joint"].as_str().unwrap().to_string(),
                d["parameter"].as_str().unwrap().to_string(),
            )
        })
        .collect();
    // SOURCE.md of the fixture: KUKA's A1 turns about -z, and ARTE's zero pose differs on A2, A3.
    assert_eq!(
        got,
        [
            ("joint_a1", "direction"),
            ("joint_a2", "theta"),
            ("joint_a3", "theta")
        ]
        .map(|(a, b)| (a.to_string(), b.to_string()))
    );
    let d = &v["differences"][1];
    assert!((d["difference"].as_f64().unwrap() - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
}

/// The same kinematics written every other way must match: other convention, mm/deg, the
/// extracted table itself (other x signs, other common-normal places, base and tool given).
#[test]
fn representation_freedoms_never_alarm() {
    let bin = env!("CARGO_BIN_EXE_urdf-dh");
    for id in fixture_robots() {
        let urdf = format!("fixtures/robots/{id}/robot.urdf");
        let vendor = format!("fixtures/robots/{id}/vendor.yaml");
        let (vendor_match, _) = differences(
            &urdf,
            None,
            None,
            &std::fs::read_to_string(root().join(&vendor)).unwrap(),
        );
        let mut variants = Vec::new();
        for (to, lu, au) in [
            ("standard", "mm", "deg"),
            ("modified", "m", "rad"),
            ("modified", "mm", "deg"),
        ] {
            let out = std::process::Command::new(bin)
                .args([
                    "convert",
                    &vendor,
                    "--to",
                    to,
                    "--length-unit",
                    lu,
                    "--angle-unit",
                    au,
                ])
                .current_dir(root())
                .output()
                .unwrap();
            variants.push((
                format!("vendor as {to} {lu}/{au}"),
                String::from_utf8(out.stdout).unwrap(),
                vendor_match,
            ));
        }
        for convention in ["standard", "modified"] {
            let out = std::process::Command::new(bin)
                .args([
                    "extract",
                    &urdf,
                    "--format",
                    "yaml",
                    "--convention",
                    convention,
                    "--angle-unit",
                    "deg",
                ])
                .current_dir(root())
                .output()
                .unwrap();
            variants.push((
                format!("extracted {convention}"),
                String::from_utf8(out.stdout).unwrap(),
                true,
            ));
        }
        for (what, text, want) in variants {
            let (matches, diffs) = differences(&urdf, None, None, &text);
            assert_eq!(matches, want, "{id}: {what}: {diffs:?}");
        }
    }
}

fn mutate(sheet: &str, row: usize, key: &str, delta: f64) -> String {
    let mut v: Value = serde_yaml::from_str(sheet).unwrap();
    let j = &mut v["joints"][row][key];
    *j = Value::from(j.as_f64().unwrap() + delta);
    serde_yaml::to_string(&v).unwrap()
}

/// One planted change at a time, each must be named with its joint and parameter.
#[test]
fn planted_errors_are_named() {
    let mut planted = 0;
    for id in fixture_robots() {
        let urdf = format!("fixtures/robots/{id}/robot.urdf");
        let text =
            std::fs::read_to_string(root().join(format!("fixtures/robots/{id}/vendor.yaml")))
                .unwrap();
        let sheet = Sheet::parse(&text, "vendor").unwrap();
        let (_, base_diffs) = differences(&urdf, None, None, &text);
        let v: Value = serde_yaml::from_str(&text).unwrap();
        let mm = v["length_unit"].as_str() == Some("mm");
        let deg = v["angle_unit"].as_str() == Some("deg");
        let (len, ang) = (if mm { 0.5 } else { 5e-4 }, |d: f64| {
            if deg {
                d
            } else {
                d.to_radians()
            }
        });
        let n = sheet.table.rows.len();
        // Rows 2..n-1: row 1's theta and d hide in a free base, the last row's in a free tool.
        for row in 1..n - 1 {
            let name = sheet.table.rows[row].name.clone();
            let modified = sheet.table.convention == dh_core::Convention::Modified;
            let mut cases = vec![("theta", ang(0.5), "theta"), ("d", len, "d")];
            // a and alpha of a modified row describe the link before the joint: row >= 1 works.
            if !modified || row >= 1 {
                cases.push(("a", len, "a"));
                cases.push(("alpha", ang(0.05), "alpha"));
            }
            for (key, delta, param) in cases {
                let changed = mutate(&text, row, key, delta);
                let (matches, diffs) = differences(&urdf, None, None, &changed);
                // A change that a free base or tool absorbs entirely (d along a run of parallel
                // axes that ends at a free tool) changes no kinematics and must not be reported.
                let (_, chain) = load_chain(&urdf, None, None).unwrap();
                let literal =
                    compare(&chain, &Sheet::parse(&changed, "c").unwrap(), tol()).unwrap();
                let vendor_literal =
                    compare(&chain, &Sheet::parse(&text, "v").unwrap(), tol()).unwrap();
                if vendor_literal.max_position_error.unwrap() < 1e-9
                    && literal.max_position_error.unwrap() < 1e-9
                {
                    assert!(
                        matches,
                        "{id}: {key} of {name} +{delta} is unobservable yet reported: {diffs:?}"
                    );
                    continue;
                }
                assert!(!matches, "{id}: {key} of {name} +{delta} not found");
                let named = diffs
                    .iter()
                    .any(|(j, p, aliases)| p == param && (j == &name || aliases.contains(&name)));
                let new: Vec<_> = diffs.iter().filter(|d| !base_diffs.contains(d)).collect();
                assert!(named, "{id}: {key} of {name} +{delta}: reported {new:?}");
                planted += 1;
            }
        }
    }
    assert!(planted > 80, "only {planted} planted errors");
}

#[test]
fn a_reversed_joint_and_a_missing_joint_are_named() {
    // Reverse the UR5's elbow in the URDF: the axis of elbow_joint flips.
    let urdf = std::fs::read_to_string(root().join("fixtures/robots/ur5/robot.urdf")).unwrap();
    let at = urdf.find("name=\"elbow_joint\"").unwrap();
    let axis_at = at + urdf[at..].find("<axis xyz=\"").unwrap() + "<axis xyz=\"".len();
    let end = axis_at + urdf[axis_at..].find('"').unwrap();
    let flipped: Vec<String> = urdf[axis_at..end]
        .split_whitespace()
        .map(|c| {
            let v: f64 = c.parse().unwrap();
            format!("{}", -v)
        })
        .collect();
    let reversed = format!("{}{}{}", &urdf[..axis_at], flipped.join(" "), &urdf[end..]);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("reversed.urdf");
    std::fs::write(&path, reversed).unwrap();
    let sheet = std::fs::read_to_string(root().join("fixtures/robots/ur5/vendor.yaml")).unwrap();
    let (matches, diffs) = differences(path.to_str().unwrap(), None, None, &sheet);
    assert!(!matches);
    assert!(
        diffs
            .iter()
            .any(|(j, p, _)| j == "elbow_joint" && p == "direction"),
        "{diffs:?}"
    );

    let mut v: Value = serde_yaml::from_str(&sheet).unwrap();
    v["joints"].as_sequence_mut().unwrap().remove(3);
    let (matches, diffs) = differences(
        "fixtures/robots/ur5/robot.urdf",
        None,
        None,
        &serde_yaml::to_string(&v).unwrap(),
    );
    assert!(!matches);
    assert!(
        diffs
            .iter()
            .any(|(j, p, _)| j == "wrist_1_joint" && p == "joint_count"),
        "{diffs:?}"
    );
}

/// A base or tool the sheet gives is part of the comparison.
#[test]
fn a_wrong_given_tool_or_base_is_named() {
    let text =
        std::fs::read_to_string(root().join("fixtures/robots/franka_panda/vendor.yaml")).unwrap();
    assert!(differences("fixtures/robots/franka_panda/robot.urdf", None, None, &text).0);
    let mut v: Value = serde_yaml::from_str(&text).unwrap();
    v["tool"]["xyz"][2] = Value::from(0.1075);
    let (_, diffs) = differences(
        "fixtures/robots/franka_panda/robot.urdf",
        None,
        None,
        &serde_yaml::to_string(&v).unwrap(),
    );
    // A shift along the last axis is the last row's d or the tool's: either name is right.
    assert!(
        diffs
            .iter()
            .any(|(j, p, _)| p == "tool" || (j == "panda_joint7" && p == "d")),
        "{diffs:?}"
    );
    v["tool"]["xyz"][2] = Value::from(0.107);
    v["base"] = serde_yaml::from_str("{xyz: [0, 0, 0.001], rpy: [0, 0, 0]}").unwrap();
    let (_, diffs) = differences(
        "fixtures/robots/franka_panda/robot.urdf",
        None,
        None,
        &serde_yaml::to_string(&v).unwrap(),
    );
    assert!(
        diffs
            .iter()
            .any(|(j, p, _)| p == "d" && j == "panda_joint1" || p == "base"),
        "{diffs:?}"
    );
}

/// The chain of a shared robot as its NOTES.md gives it (`urdf_chain`), else the defaults with
/// `tool0` as the tip when there are several leaves.
fn chain_of(dir: &Path) -> (Option<String>, Option<String>) {
    let notes = std::fs::read_to_string(dir.join("NOTES.md")).unwrap_or_default();
    let field = |key: &str| {
        let start = notes.find("urdf_chain:")?;
        let line = notes[start..]
            .lines()
            .take(4)
            .find(|l| l.trim_start().starts_with(key))?;
        Some(line.split(':').nth(1)?.trim().trim_matches('"').to_string())
    };
    (
        field("base_link"),
        field("tip_link").or(Some("tool0".into())),
    )
}

/// ../shared/robots: `check` of every URDF against its dh.yaml agrees with the verdict its notes
/// give (README.md table): matches match; listed differences are named exactly; "geometry"
/// mismatches are mismatches with a real FK deviation.
#[test]
fn shared_corpus_agrees_with_its_notes() {
    let Some(shared) = skip_without_shared("check corpus") else {
        return;
    };
    let readme = std::fs::read_to_string(shared.join("robots/README.md")).unwrap();
    let mut checked = 0;
    let mut report = String::new();
    for line in readme
        .lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| robot") && !l.starts_with("|---"))
    {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        let (id, verdict) = (cells[1], cells[3]);
        let dir = shared.join("robots").join(id);
        if !dir.join("dh.yaml").is_file() {
            continue;
        }
        let (base, tip) = chain_of(&dir);
        let urdf = dir.join("robot.urdf");
        let sheet = std::fs::read_to_string(dir.join("dh.yaml")).unwrap();
        let (_, chain) =
            load_chain(urdf.to_str().unwrap(), base.as_deref(), tip.as_deref()).unwrap();
        let r = compare(&chain, &Sheet::parse(&sheet, "dh.yaml").unwrap(), tol()).unwrap();
        let got: Vec<String> = r
            .differences
            .iter()
            .map(|d| format!("{} {}", d.joint.clone().unwrap_or_default(), d.parameter))
            .collect();
        report += &format!(
            "{id:<44} {:<8} {}\n",
            if r.matches { "MATCH" } else { "MISMATCH" },
            got.join(", ")
        );
        if verdict == "match" {
            assert!(r.matches, "{id}: expected a match, got {got:?}");
        } else {
            assert!(!r.matches, "{id}: expected a mismatch ({verdict})");
            let listed = verdict
                .trim_start_matches("mismatch")
                .trim_start_matches(':')
                .trim();
            // The table truncates long lists; the full list is in NOTES.md.
            let notes = std::fs::read_to_string(dir.join("NOTES.md")).unwrap();
            let full = notes
                .lines()
                .find(|l| l.starts_with("MISMATCH expected, naming:"))
                .map(|l| {
                    l.trim_start_matches("MISMATCH expected, naming:")
                        .to_string()
                })
                .unwrap_or(listed.to_string());
            let full = full
                .split(". (")
                .next()
                .unwrap_or(&full)
                .trim()
                .trim_end_matches('.');
            let named: Vec<String> = full
                .split([',', ';'])
                .map(str::trim)
                .filter(|s| {
                    !s.starts_with("geometry") && !s.contains("deliberate") && !s.is_empty()
                })
                .map(|s| {
                    let mut w = s.split_whitespace();
                    format!("{} {}", w.next().unwrap_or(""), w.next().unwrap_or(""))
                })
                .collect();
            let named_in_got: Vec<&String> = got
                .iter()
                .filter(|g| !g.ends_with(" a") && !g.ends_with(" d") && !g.ends_with(" alpha"))
                .collect();
            if !named.is_empty() {
                assert_eq!(
                    named_in_got.iter().map(|s| s.as_str()).collect::<Vec<_>>(),
                    named.iter().map(|s| s.as_str()).collect::<Vec<_>>(),
                    "{id}"
                );
            }
            if full.contains("geometry") {
                assert!(
                    r.max_position_error.unwrap() > 1e-4,
                    "{id}: geometry mismatch but FK agrees"
                );
            }
        }
        checked += 1;
    }
    println!("{report}");
    assert!(checked >= 35, "checked {checked}");
}

/// Round trip: the URDF that `to-urdf` writes for a sheet matches the sheet.
#[test]
fn to_urdf_round_trips_every_fixture_sheet() {
    let bin = env!("CARGO_BIN_EXE_urdf-dh");
    let dir = tempfile::tempdir().unwrap();
    for id in fixture_robots() {
        let vendor = root().join(format!("fixtures/robots/{id}/vendor.yaml"));
        let out = std::process::Command::new(bin)
            .arg("to-urdf")
            .arg(&vendor)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(0));
        let path = dir.path().join(format!("{id}.urdf"));
        std::fs::write(&path, &out.stdout).unwrap();
        let code = std::process::Command::new(bin)
            .arg("check")
            .arg(&path)
            .arg("--sheet")
            .arg(&vendor)
            .output()
            .unwrap()
            .status
            .code();
        assert_eq!(code, Some(0), "{id}");
    }
}

mod round_trip {
    use dh_core::{Convention, DhRow, DhTable, Limits};
    use dh_workflows::sheet::{Sheet, SheetDoc};
    use dh_workflows::units::{AngleUnit, LengthUnit};
    use nalgebra::Isometry3;
    use proptest::prelude::*;
    use urdf_dh::commands::check::compare;
    use urdf_dh::commands::to_urdf::urdf_of;

    /// A row value: often exactly 0 or a multiple of 90 degrees (the degenerate cases vendor
    /// sheets are made of), else anything.
    fn angle() -> impl Strategy<Value = f64> {
        prop_oneof![
            Just(0.0),
            Just(std::f64::consts::FRAC_PI_2),
            Just(-std::f64::consts::FRAC_PI_2),
            Just(std::f64::consts::PI),
            -3.0..3.0f64
        ]
    }
    fn length() -> impl Strategy<Value = f64> {
        prop_oneof![Just(0.0), -0.8..0.8f64]
    }
    fn sheet() -> impl Strategy<Value = (DhTable, bool, bool)> {
        let row = (
            length(),
            angle(),
            length(),
            angle(),
            prop::bool::weighted(0.15),
        );
        (
            prop::collection::vec(row, 1..=8),
            prop::bool::ANY,
            prop::bool::ANY,
            prop::bool::ANY,
        )
            .prop_map(|(rows, modified, base, tool)| {
                let rows = rows
                    .into_iter()
                    .enumerate()
                    .map(|(i, (a, alpha, d, theta, prismatic))| {
                        let mut r = if prismatic {
                            DhRow::prismatic(&format!("j{i}"), a, alpha, d, theta)
                        } else {
                            DhRow::revolute(&format!("j{i}"), a, alpha, d, theta)
                        };
                        r.limits = Some(if prismatic {
                            Limits {
                                lower: -0.2,
                                upper: 0.3,
                            }
                        } else {
                            Limits {
                                lower: -3.0,
                                upper: 3.0,
                            }
                        });
                        r
                    })
                    .collect();
                let t = DhTable {
                    convention: if modified {
                        Convention::Modified
                    } else {
                        Convention::Standard
                    },
                    base: if base {
                        Isometry3::new(
                            nalgebra::Vector3::new(0.1, -0.2, 0.3),
                            nalgebra::Vector3::new(0.2, 0.1, -0.4),
                        )
                    } else {
                        Isometry3::identity()
                    },
                    tool: if tool {
                        Isometry3::new(
                            nalgebra::Vector3::new(0.0, 0.02, 0.1),
                            nalgebra::Vector3::new(0.0, 0.0, 0.7),
                        )
                    } else {
                        Isometry3::identity()
                    },
                    rows,
                };
                (t, base, tool)
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// `to-urdf` then `check` against the sheet matches, base and tool given or free.
        #[test]
        fn to_urdf_then_check_matches((table, base, tool) in sheet()) {
            let text = urdf_of(&table, "random", "base_link", "tool0");
            let model = urdf_axes::UrdfModel::parse(&text).unwrap();
            let chain = model.chain(None, None).unwrap();
            let mut doc = SheetDoc::from_table(&table, LengthUnit::M, AngleUnit::Rad);
            if !base { doc.base = None; }
            if !tool { doc.tool = None; }
            let sheet = Sheet::parse(&serde_yaml::to_string(&doc).unwrap(), "random").unwrap();
            let r = compare(&chain, &sheet, super::tol()).unwrap();
            prop_assert!(r.matches, "{:?}\n{text}", r.differences);
            prop_assert!(r.max_position_error.unwrap() < 1e-9, "{:?}", r.max_position_error);
        }
    }
}
