//! Builders shared by the integration tests.
#![allow(dead_code)]

use std::fmt::Write;

use urdf_axes::{UrdfError, UrdfModel};

/// Joins lines with '\n', so that `lines[i]` sits on source line `i + 1`.
pub fn lines(lines: &[&str]) -> String {
    lines.join("\n")
}

/// The error of parsing `text` and choosing its default chain (a joint's own faults are
/// errors only on the chosen chain).
pub fn parse_err(text: &str) -> UrdfError {
    match UrdfModel::parse(text).and_then(|m| m.chain(None, None)) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e,
    }
}

/// Asserts that the message of `e` contains every piece and starts lowercase.
pub fn assert_message(e: &UrdfError, pieces: &[&str]) {
    let m = e.to_string();
    for p in pieces {
        assert!(m.contains(p), "message {m:?} lacks {p:?}");
    }
    assert!(
        m.chars().next().is_some_and(|c| !c.is_uppercase()),
        "message {m:?} starts uppercase"
    );
    assert!(!m.ends_with('.'), "message {m:?} ends with a period");
}

/// One joint of a generated serial chain.
#[derive(Clone, Debug)]
pub struct JointSpec {
    /// `revolute`, `continuous`, `prismatic` or `fixed`.
    pub kind: &'static str,
    pub xyz: [f64; 3],
    pub rpy: [f64; 3],
    /// `None`: no `<axis>` element (URDF default 1 0 0).
    pub axis: Option<[f64; 3]>,
}

/// A URDF serial chain `l0 -> l1 -> ... -> ln` with joints `j1 .. jn`.
pub fn serial_urdf(joints: &[JointSpec]) -> String {
    let mut s = String::from("<robot name=\"serial\">\n");
    for i in 0..=joints.len() {
        let _ = writeln!(s, "  <link name=\"l{i}\"/>");
    }
    for (i, j) in joints.iter().enumerate() {
        let _ = writeln!(s, "  <joint name=\"j{}\" type=\"{}\">", i + 1, j.kind);
        let _ = writeln!(s, "    <parent link=\"l{i}\"/><child link=\"l{}\"/>", i + 1);
        let _ = writeln!(
            s,
            "    <origin xyz=\"{:e} {:e} {:e}\" rpy=\"{:e} {:e} {:e}\"/>",
            j.xyz[0], j.xyz[1], j.xyz[2], j.rpy[0], j.rpy[1], j.rpy[2]
        );
        if let Some(a) = j.axis {
            let _ = writeln!(s, "    <axis xyz=\"{:e} {:e} {:e}\"/>", a[0], a[1], a[2]);
        }
        if matches!(j.kind, "revolute" | "prismatic") {
            s.push_str("    <limit lower=\"-3\" upper=\"3\" effort=\"1\" velocity=\"1\"/>\n");
        }
        s.push_str("  </joint>\n");
    }
    s.push_str("</robot>\n");
    s
}
