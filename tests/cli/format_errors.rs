//! An error in a robot file names the format that was read (MJCF, SDFormat, URDF), both when
//! the file does not read and when a joint on the chosen chain is at fault: never "invalid URDF"
//! for an MJCF or SDFormat input.

use crate::common::run;

/// The `urdf-dh: error:` line of `extract -` on `text`, after checking the exit code (2).
fn error_of(text: &str) -> String {
    let out = run(&["extract", "-"], Some(text.as_bytes()));
    assert!(out.starts_with("exit: 2\n"), "{out}");
    out.lines()
        .find(|l| l.starts_with("urdf-dh: error:"))
        .unwrap_or_else(|| panic!("no error line: {out}"))
        .to_string()
}

#[test]
fn an_sdformat_error_says_sdformat() {
    // Does not read: the joint's child is no link.
    let unread = r#"<sdf version="1.6"><model name="m"><link name="a"/><link name="b"/>
        <joint name="j" type="revolute"><parent>a</parent><child>c</child>
        <axis><xyz>0 0 1</xyz></axis></joint></model></sdf>"#;
    let e = error_of(unread);
    assert!(
        e.starts_with("urdf-dh: error: <stdin>: invalid SDFormat: "),
        "{e}"
    );
    // Reads, but the chain's joint has no direction.
    let zero_axis = r#"<sdf version="1.6"><model name="m"><link name="a"/><link name="b"/>
        <joint name="j" type="revolute"><parent>a</parent><child>b</child>
        <axis><xyz>0 0 0</xyz></axis></joint></model></sdf>"#;
    let e = error_of(zero_axis);
    assert!(
        e.starts_with("urdf-dh: error: <stdin>: invalid SDFormat: joint 'j'"),
        "{e}"
    );
}

#[test]
fn an_mjcf_error_says_mjcf_and_a_urdf_error_still_says_urdf() {
    let mjcf = r#"<mujoco model="m"><worldbody><body name="b">
        <joint name="j" axis="0 0 0"/></body></worldbody></mujoco>"#;
    let e = error_of(mjcf);
    assert!(
        e.starts_with("urdf-dh: error: <stdin>: invalid MJCF: joint 'j'"),
        "{e}"
    );
    let urdf = r#"<robot name="r"><link name="a"/><link name="b"/>
        <joint name="j" type="revolute"><parent link="a"/><child link="b"/>
        <axis xyz="0 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>"#;
    let e = error_of(urdf);
    assert!(
        e.starts_with("urdf-dh: error: <stdin>: invalid URDF: joint 'j'"),
        "{e}"
    );
}
