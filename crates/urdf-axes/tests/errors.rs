//! One hand-written URDF per error: the variant, the names it carries, and its message (which
//! names the joint or link and the line).

mod common;

use common::{assert_message, lines, parse_err};
use urdf_axes::{UrdfError, UrdfModel};

/// Two links joined by joint `j` of the given type, with extra lines inside the joint; `j`
/// opens on line 4 and its extra lines start on line 6.
fn one_joint(version: &str, kind: &str, inner: &[&str]) -> String {
    let mut l = vec![
        match version {
            "" => "<robot name=\"r\">".to_owned(),
            v => format!("<robot name=\"r\" version=\"{v}\">"),
        },
        "  <link name=\"a\"/>".to_owned(),
        "  <link name=\"b\"/>".to_owned(),
        format!("  <joint name=\"j\" type=\"{kind}\">"),
        "    <parent link=\"a\"/><child link=\"b\"/>".to_owned(),
    ];
    l.extend(inner.iter().map(|s| format!("    {s}")));
    l.push("  </joint>".into());
    l.push("</robot>".into());
    l.join("\n")
}

const LIMIT: &str = "<limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/>";

#[test]
fn not_utf8_names_offset_and_line() {
    let e =
        UrdfModel::from_bytes(b"<robot name=\"r\">\n<link name=\"\xff\"/>\n</robot>").unwrap_err();
    assert_eq!(
        e,
        UrdfError::NotUtf8 {
            offset: 29,
            line: 2
        }
    );
    assert_message(&e, &["utf-8", "offset 29", "line 2"]);
}

#[test]
fn billion_laughs_is_refused_at_once() {
    let mut doc =
        String::from("<?xml version=\"1.0\"?>\n<!DOCTYPE robot [\n  <!ENTITY l0 \"lol\">\n");
    for i in 1..10 {
        let refs = format!("&l{};", i - 1).repeat(10);
        doc.push_str(&format!("  <!ENTITY l{i} \"{refs}\">\n"));
    }
    doc.push_str("]>\n<robot name=\"&l9;\"><link name=\"a\"/></robot>\n");
    // Refused at the first declaration, so nothing can be expanded.
    let e = parse_err(&doc);
    assert_eq!(e, UrdfError::EntityDeclaration { line: 3 });
    assert_message(&e, &["<!ENTITY", "line 3", "expected", "found"]);
}

fn parse_error(e: &UrdfError) -> (&str, Option<usize>) {
    match e {
        UrdfError::Parse { message, line } => (message, *line),
        other => panic!("expected a parse error, got {other:?}"),
    }
}

#[test]
fn xml_that_is_not_a_robot_is_a_parse_error() {
    for (text, line, piece) in [
        ("", None, "empty document"),
        ("hello world", Some(1), "'hello world'"),
        (
            "<robot name=\"r\">\n  <link name=\"a\"/>\n",
            Some(2),
            "found end of file",
        ),
        (
            "<robot name=\"r\">\n  <link name=\"a\">\n</robot>",
            Some(3),
            "</link>",
        ),
        ("<foo name=\"r\">\n</foo>", Some(1), "found <foo>"),
        (
            "<robot name=\"r\"/>\n<robot name=\"s\"/>",
            Some(2),
            "second",
        ),
        ("<robot name=\"&undefined;\">\n</robot>", Some(1), "entity"),
    ] {
        let e = parse_err(text);
        let (message, l) = parse_error(&e);
        assert_eq!(l, line, "{text:?}: {message}");
        assert!(message.contains(piece), "{text:?}: {message}");
        assert_message(&e, &[]);
    }
    // Nesting is bounded (a recursive reader would overflow its stack on 10,000 levels).
    let deep = format!(
        "<robot>{}{}</robot>",
        "<x>".repeat(10_000),
        "</x>".repeat(10_000)
    );
    assert!(parse_error(&parse_err(&deep)).0.contains("nested"));
    // Just below the limit, inside a joint, parsing works.
    let nested = one_joint(
        "",
        "continuous",
        &[&format!("{}{}", "<x>".repeat(97), "</x>".repeat(97))],
    );
    assert!(UrdfModel::parse(&nested).is_ok());
}

#[test]
fn missing_required_parts_are_located() {
    // A link without a name, on line 3.
    let e = parse_err(&lines(&[
        "<robot name=\"r\">",
        "  <link name=\"a\"/>",
        "  <link/>",
        "</robot>",
    ]));
    assert_eq!(parse_error(&e).1, Some(3));
    assert_message(&e, &["attribute 'name'", "line 3"]);
    // A limit without velocity, on line 6.
    let e = parse_err(&one_joint(
        "",
        "revolute",
        &["<limit lower=\"-1\" upper=\"1\" effort=\"1\"/>"],
    ));
    assert_eq!(parse_error(&e).1, Some(6));
    assert_message(&e, &["joint 'j'", "<limit>", "'velocity'", "line 6"]);
    // A joint without a parent, on line 4.
    let e = parse_err(&lines(&[
        "<robot name=\"r\">",
        "  <link name=\"a\"/>",
        "  <link name=\"b\"/>",
        "  <joint name=\"j\" type=\"fixed\">",
        "    <child link=\"b\"/>",
        "  </joint>",
        "</robot>",
    ]));
    assert_eq!(parse_error(&e).1, Some(4));
    assert_message(&e, &["joint 'j'", "<parent>", "line 4"]);
}

#[test]
fn malformed_numbers_are_located() {
    let e = parse_err(&one_joint(
        "",
        "revolute",
        &["<limit lower=\"abc\" upper=\"1\" effort=\"1\" velocity=\"1\"/>"],
    ));
    assert_eq!(parse_error(&e).1, Some(6));
    assert_message(&e, &["joint 'j'", "'lower'", "'abc'", "line 6"]);
    let e = parse_err(&one_joint("", "continuous", &["<axis xyz=\"1 0\"/>"]));
    assert_eq!(parse_error(&e).1, Some(6));
    assert_message(&e, &["joint 'j'", "expected 3 numbers", "'1 0'", "line 6"]);
    // Every token must be a number ("1 x 2 3" is not 1 2 3).
    let e = parse_err(&one_joint("", "continuous", &["<origin xyz=\"1 x 2 3\"/>"]));
    assert_eq!(parse_error(&e).1, Some(6));
    assert_message(
        &e,
        &["joint 'j'", "<origin>", "'xyz'", "'1 x 2 3'", "line 6"],
    );
}

#[test]
fn unsupported_joint_types() {
    for kind in ["ball", "spherical"] {
        let e = parse_err(&one_joint("", kind, &[]));
        assert_eq!(
            e,
            UrdfError::UnsupportedJointType {
                joint: "j".into(),
                found: kind.into(),
                line: Some(4)
            }
        );
        assert_message(&e, &["joint 'j'", "line 4", kind, "expected type revolute"]);
    }
}

#[test]
fn no_links() {
    let e = parse_err("<robot name=\"empty\"/>");
    assert_eq!(
        e,
        UrdfError::NoLinks {
            robot: "empty".into()
        }
    );
    assert_message(&e, &["'empty'", "<link>"]);
}

#[test]
fn duplicate_names() {
    let e = parse_err(&lines(&[
        "<robot name=\"r\">",
        "  <link name=\"a\"/>",
        "  <link name=\"a\"/>",
        "</robot>",
    ]));
    assert_eq!(
        e,
        UrdfError::DuplicateLink {
            link: "a".into(),
            line: Some(3),
            first_line: Some(2)
        }
    );
    assert_message(&e, &["link 'a'", "line 3", "line 2"]);
    let e = parse_err(&lines(&[
        "<robot name=\"r\">",
        "  <link name=\"a\"/><link name=\"b\"/><link name=\"c\"/>",
        "  <joint name=\"j\" type=\"fixed\"><parent link=\"a\"/><child link=\"b\"/></joint>",
        "  <joint name=\"j\" type=\"fixed\"><parent link=\"b\"/><child link=\"c\"/></joint>",
        "</robot>",
    ]));
    assert_eq!(
        e,
        UrdfError::DuplicateJoint {
            joint: "j".into(),
            line: Some(4),
            first_line: Some(3)
        }
    );
    assert_message(&e, &["joint 'j'", "line 4", "line 3"]);
}

#[test]
fn joint_naming_an_undefined_link() {
    let e = parse_err(&lines(&[
        "<robot name=\"r\">",
        "  <link name=\"a\"/>",
        "  <joint name=\"j\" type=\"fixed\">",
        "    <parent link=\"a\"/>",
        "    <child link=\"ghost\"/>",
        "  </joint>",
        "</robot>",
    ]));
    assert_eq!(
        e,
        UrdfError::MissingLink {
            joint: "j".into(),
            role: "child",
            link: "ghost".into(),
            line: Some(5)
        }
    );
    assert_message(&e, &["joint 'j'", "'ghost'", "child", "line 5"]);
}

#[test]
fn link_with_two_parents() {
    let e = parse_err(&lines(&[
        "<robot name=\"r\">",
        "  <link name=\"a\"/><link name=\"b\"/><link name=\"c\"/>",
        "  <joint name=\"j1\" type=\"fixed\"><parent link=\"a\"/><child link=\"c\"/></joint>",
        "  <joint name=\"j2\" type=\"fixed\"><parent link=\"b\"/><child link=\"c\"/></joint>",
        "</robot>",
    ]));
    assert_eq!(
        e,
        UrdfError::TwoParents {
            link: "c".into(),
            first: "j1".into(),
            second: "j2".into(),
            line: Some(4)
        }
    );
    assert_message(&e, &["link 'c'", "'j1'", "'j2'", "line 4"]);
}

#[test]
fn cycles_with_and_without_a_root() {
    // a is the root; b and c are each other's parent.
    let e = parse_err(&lines(&[
        "<robot name=\"r\">",
        "  <link name=\"a\"/><link name=\"b\"/><link name=\"c\"/>",
        "  <joint name=\"bc\" type=\"fixed\"><parent link=\"b\"/><child link=\"c\"/></joint>",
        "  <joint name=\"cb\" type=\"fixed\"><parent link=\"c\"/><child link=\"b\"/></joint>",
        "</robot>",
    ]));
    let UrdfError::Cycle { links, joint, line } = &e else {
        panic!("expected a cycle, got {e:?}")
    };
    assert_eq!(links.len(), 3);
    assert_eq!(links.first(), links.last());
    assert!(links.contains(&"b".to_owned()) && links.contains(&"c".to_owned()));
    let expected_line = if joint == "bc" { 3 } else { 4 };
    assert_eq!(*line, Some(expected_line));
    assert_message(
        &e,
        &[
            &format!("joint '{joint}'"),
            "cycle",
            "b -> c",
            &format!("line {expected_line}"),
        ],
    );
    // A joint from a link to itself is a cycle too.
    let e = parse_err(&lines(&[
        "<robot name=\"r\">",
        "  <link name=\"a\"/>",
        "  <joint name=\"self\" type=\"fixed\"><parent link=\"a\"/><child link=\"a\"/></joint>",
        "</robot>",
    ]));
    assert_eq!(
        e,
        UrdfError::NoRoot {
            links: vec!["a".into(), "a".into()]
        }
    );
    assert_message(&e, &["root", "a -> a"]);
}

#[test]
fn several_roots() {
    let e = parse_err(&lines(&[
        "<robot name=\"r\">",
        "  <link name=\"a\"/><link name=\"b\"/><link name=\"stray\"/>",
        "  <joint name=\"j\" type=\"fixed\"><parent link=\"a\"/><child link=\"b\"/></joint>",
        "</robot>",
    ]));
    assert_eq!(
        e,
        UrdfError::SeveralRoots {
            roots: vec!["a".into(), "stray".into()]
        }
    );
    assert_message(&e, &["found 2", "'a'", "'stray'"]);
}

#[test]
fn non_finite_numbers_anywhere() {
    let cases: [(&str, &[&str], &str, usize); 5] = [
        ("fixed", &["<origin xyz=\"nan 0 0\"/>"], "origin xyz", 6),
        ("fixed", &["<origin rpy=\"0 inf 0\"/>"], "origin rpy", 6),
        ("continuous", &["<axis xyz=\"0 0 -inf\"/>"], "axis xyz", 6),
        (
            "revolute",
            &["<limit lower=\"-inf\" upper=\"1\" effort=\"1\" velocity=\"1\"/>"],
            "limit lower",
            6,
        ),
        (
            "continuous",
            &["", "<mimic joint=\"j\" multiplier=\"nan\"/>"],
            "mimic multiplier",
            7,
        ),
    ];
    for (kind, inner, what, line) in cases {
        let e = parse_err(&one_joint("", kind, inner));
        let UrdfError::NonFinite {
            joint,
            what: w,
            line: l,
            ..
        } = &e
        else {
            panic!("expected NonFinite for {what}, got {e:?}")
        };
        assert_eq!((joint.as_str(), *w, *l), ("j", what, Some(line)));
        assert_message(&e, &["joint 'j'", what, "finite", &format!("line {line}")]);
    }
    // Under URDF 1.2 an omitted limit is infinite, but NaN is never "no limit".
    let e = parse_err(&one_joint(
        "1.2",
        "revolute",
        &["<limit lower=\"nan\" upper=\"1\" effort=\"1\" velocity=\"1\"/>"],
    ));
    assert_message(&e, &["joint 'j'", "limit lower", "NaN", "line 6"]);
}

#[test]
fn magnitudes_beyond_any_robot() {
    // Found by fuzzing: a finite origin of 1e306 m gave a table whose millimetres overflow.
    let e = parse_err(&one_joint(
        "",
        "continuous",
        &["<origin xyz=\"0 0 1e306\"/>"],
    ));
    assert_eq!(
        e,
        UrdfError::OutOfRange {
            joint: "j".into(),
            what: "origin xyz",
            value: 1e306,
            line: Some(6)
        }
    );
    assert_message(&e, &["joint 'j'", "origin xyz", "1e9", "1e306", "line 6"]);
    let e = parse_err(&one_joint(
        "",
        "prismatic",
        &["<limit lower=\"0\" upper=\"2e9\" effort=\"1\" velocity=\"1\"/>"],
    ));
    assert_message(&e, &["limit upper", "2e9", "line 6"]);
}

#[test]
fn zero_axis() {
    let e = parse_err(&one_joint(
        "",
        "prismatic",
        &["<axis xyz=\"0 0 0\"/>", LIMIT],
    ));
    assert_eq!(
        e,
        UrdfError::ZeroAxis {
            joint: "j".into(),
            axis: [0.0; 3],
            line: Some(6)
        }
    );
    assert_message(&e, &["joint 'j'", "non-zero", "line 6"]);
    // A fixed joint's axis is never used.
    assert!(UrdfModel::parse(&one_joint("", "fixed", &["<axis xyz=\"0 0 0\"/>"])).is_ok());
}

#[test]
fn reversed_limits() {
    let e = parse_err(&one_joint(
        "",
        "revolute",
        &["<limit lower=\"2\" upper=\"1\" effort=\"1\" velocity=\"1\"/>"],
    ));
    assert_eq!(
        e,
        UrdfError::LimitsReversed {
            joint: "j".into(),
            lower: 2.0,
            upper: 1.0,
            line: Some(6)
        }
    );
    assert_message(&e, &["joint 'j'", "lower <= upper", "line 6"]);
    // URDF 1.2 documents too (with the line of the <limit>).
    let e = parse_err(&one_joint(
        "1.2",
        "prismatic",
        &["<limit lower=\"2\" upper=\"1\" effort=\"1\" velocity=\"1\"/>"],
    ));
    assert_eq!(
        e,
        UrdfError::LimitsReversed {
            joint: "j".into(),
            lower: 2.0,
            upper: 1.0,
            line: Some(6)
        }
    );
}

#[test]
fn missing_limit() {
    for kind in ["revolute", "prismatic"] {
        let e = parse_err(&one_joint("", kind, &["<axis xyz=\"0 0 1\"/>"]));
        assert_eq!(
            e,
            UrdfError::MissingLimit {
                joint: "j".into(),
                kind,
                line: Some(4)
            }
        );
        assert_message(&e, &["joint 'j'", "<limit>", kind, "line 4"]);
    }
    assert!(UrdfModel::parse(&one_joint("", "continuous", &[])).is_ok());
}

#[test]
fn mimic_of_an_undefined_joint() {
    let e = parse_err(&one_joint("", "continuous", &["<mimic joint=\"nobody\"/>"]));
    assert_eq!(
        e,
        UrdfError::UnknownMimicJoint {
            joint: "j".into(),
            driver: "nobody".into(),
            line: Some(6)
        }
    );
    assert_message(&e, &["joint 'j'", "'nobody'", "mimic", "line 6"]);
    // Found by fuzzing: a joint following itself was accepted, and extract wrote a sheet that
    // the sheet reader refuses.
    let e = parse_err(&one_joint("", "continuous", &["<mimic joint=\"j\"/>"]));
    assert_eq!(
        e,
        UrdfError::MimicItself {
            joint: "j".into(),
            line: Some(6)
        }
    );
    assert_message(&e, &["joint 'j'", "itself", "line 6"]);
}
