//! MJCF (MuJoCo XML) input and `--format poe`, end to end, on the project's own fixtures
//! (`fixtures/mjcf`). Their kinematics against MuJoCo's: `crates/urdf-axes/tests/mjcf.rs` and
//! `tests/formats/mjcf_oracle.py`.

use crate::common::{exit_code, run};

const SCARA: &str = "fixtures/mjcf/scara.xml";
const CONSTRUCTS: &str = "fixtures/mjcf/constructs.xml";

#[test]
fn an_mjcf_file_extracts_by_its_root_element() {
    insta::assert_snapshot!(run(&["extract", SCARA], None));
    // The world holds one body on a free joint: the chain starts below it.
    insta::assert_snapshot!(run(&["extract", CONSTRUCTS, "--format", "yaml"], None));
}

#[test]
fn poe_is_written_and_proved() {
    insta::assert_snapshot!(run(&["extract", SCARA, "--format", "poe"], None));
}

#[test]
fn mjcf_errors_name_the_element_and_line() {
    let text = std::fs::read(crate::common::root().join(CONSTRUCTS)).expect("fixture");
    insta::assert_snapshot!("include_from_stdin", run(&["extract", "-"], Some(&text)));
    insta::assert_snapshot!(
        "ball_in_chain",
        run(
            &[
                "extract",
                CONSTRUCTS,
                "--base",
                "cart",
                "--tip",
                "camera_mount"
            ],
            None
        )
    );
    insta::assert_snapshot!(
        "free_in_chain",
        run(
            &["extract", CONSTRUCTS, "--base", "world", "--tip", "hand"],
            None
        )
    );
}

#[test]
fn check_reads_mjcf_against_its_own_sheet() {
    let dir = tempfile::tempdir().expect("a folder");
    let sheet = dir.path().join("scara.yaml");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_urdf-dh"))
        .args(["extract", SCARA, "--format", "yaml"])
        .current_dir(crate::common::root())
        .output()
        .expect("run");
    std::fs::write(&sheet, &out.stdout).expect("written");
    assert_eq!(
        exit_code(&["check", SCARA, "--sheet", sheet.to_str().expect("utf-8")]),
        0
    );
}
