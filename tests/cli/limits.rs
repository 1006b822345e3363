//! Limits on size and time: an endless input is cut at the size limit, long chains (thousands
//! of joints, chains of mimics) extract and verify in linear time, and a failed run leaves the
//! output it was asked to write untouched.

use crate::common::run;

const VALID_ARM: &str = "fixtures/invalid/urdf/valid_arm.urdf";

/// A serial chain of `n` revolute joints turning about z, y, x in turn, 1 mm apart.
fn long_chain(n: usize) -> String {
    let mut s = String::from("<robot name=\"long\">\n<link name=\"l0\"/>\n");
    for i in 1..=n {
        s.push_str(&format!("<link name=\"l{i}\"/>\n"));
    }
    let axes = ["0 0 1", "0 1 0", "1 0 0"];
    for i in 1..=n {
        s.push_str(&format!(
            "<joint name=\"j{i}\" type=\"revolute\"><parent link=\"l{}\"/><child link=\"l{i}\"/>\
             <origin xyz=\"0 0 0.001\" rpy=\"0 0 0\"/><axis xyz=\"{}\"/>\
             <limit lower=\"-0.001\" upper=\"0.001\" effort=\"1\" velocity=\"1\"/></joint>\n",
            i - 1,
            axes[i % 3]
        ));
    }
    s.push_str("</robot>\n");
    s
}

/// `extract` of a URDF given on stdin, as a csv table verified at 10 samples.
fn extract_csv(urdf: &str) -> String {
    run(
        &["extract", "-", "--format", "csv", "--samples", "10"],
        Some(urdf.as_bytes()),
    )
}

/// An endless input (`extract - < /dev/zero`) is cut at the size limit with a clear error, not
/// read until memory runs out.
#[test]
fn input_beyond_the_size_limit_is_refused() {
    let bytes = vec![0u8; urdf_axes::MAX_URDF_BYTES + 1];
    let out = run(&["extract", "-"], Some(&bytes));
    assert_eq!(
        out,
        format!(
            "exit: 2\n--- stdout\n--- stderr\nurdf-dh: error: <stdin>: invalid robot file: expected \
             a robot description of at most {} bytes, found more\nhint: a robot description is a few megabytes \
             at most (meshes live in their own files): check what is being read\n",
            urdf_axes::MAX_URDF_BYTES
        )
    );
}

/// An oversized MJCF or SDFormat file is not called a URDF: its format is not known before it
/// is read, so the error names a robot file.
#[test]
fn an_oversized_mjcf_or_sdformat_file_is_named_a_robot_file() {
    let dir = tempfile::tempdir().expect("tempdir");
    for (name, head) in [
        ("big.xml", "<mujoco model='m'>"),
        ("big.sdf", "<sdf version='1.7'>"),
    ] {
        let path = dir.path().join(name);
        let mut bytes = head.as_bytes().to_vec();
        bytes.resize(urdf_axes::MAX_URDF_BYTES + 1, b' ');
        std::fs::write(&path, bytes).expect("written");
        let out = run(&["extract", path.to_str().expect("utf-8")], None);
        assert!(
            out.contains(&format!(
                "{name}: invalid robot file: expected a robot description of at most {} bytes",
                urdf_axes::MAX_URDF_BYTES
            )) && !out.contains("URDF"),
            "{out}"
        );
    }
}

/// A 4000-joint chain in which each joint mimics the next (drivers after their followers)
/// extracts and verifies; the csv names each row's driver.
#[test]
fn a_long_chain_of_mimics_extracts() {
    let n = 4000;
    let urdf: String = long_chain(n)
        .lines()
        .map(|l| {
            let joint = l
                .strip_prefix("<joint name=\"j")
                .and_then(|r| r.split('"').next())
                .and_then(|k| k.parse::<usize>().ok())
                .filter(|&k| k < n);
            let line = match joint {
                Some(k) => l.replacen(
                    "<parent",
                    &format!("<mimic joint=\"j{}\" multiplier=\"0.5\"/><parent", k + 1),
                    1,
                ),
                None => l.to_owned(),
            };
            line + "\n"
        })
        .collect();
    let out = extract_csv(&urdf);
    assert!(
        out.starts_with("exit: 0\n"),
        "{}",
        &out[..out.len().min(2000)]
    );
    for i in [1, 2, n / 2, n - 1] {
        let row = out
            .lines()
            .find(|l| l.starts_with(&format!("j{i},")))
            .unwrap_or_else(|| panic!("row j{i}"));
        assert!(row.contains(&format!(",j{},0.5,0", i + 1)), "{row}");
    }
}

/// 10 000 joints extract and verify, one row each. The time's growth with the chain's length
/// is measured by `cargo bench -p urdf-axes --bench parse` (chains of 1 000 to 10 000 joints) and
/// `benches/scale.sh` (100 000 joints), not timed
/// here.
#[test]
fn a_ten_thousand_joint_chain_extracts_and_verifies() {
    let out = extract_csv(&long_chain(10_000));
    assert!(
        out.starts_with("exit: 0\n"),
        "{}",
        &out[..out.len().min(2000)]
    );
    let rows = out
        .lines()
        .filter(|l| l.starts_with('j') && l.contains(",revolute,"))
        .count();
    assert_eq!(rows, 10_000, "one csv row per joint");
    assert!(out.contains("j10000"));
}

/// A run that fails leaves the output file it was asked to write as it was (written through a
/// temporary file and a rename), and no temporary beside it.
#[test]
fn a_failed_run_leaves_its_output_file_untouched() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("calibrated.yaml");
    std::fs::write(&out, "previous result\n").unwrap();
    let out_arg = out.to_string_lossy().into_owned();
    for data in [
        "fixtures/invalid/csv/mixed_units.csv",
        "fixtures/invalid/csv/too_few_poses.csv",
    ] {
        let r = run(
            &[
                "calibrate",
                "--model",
                VALID_ARM,
                "--data",
                data,
                "--out",
                &out_arg,
            ],
            None,
        );
        assert!(r.starts_with("exit: 2\n"), "{r}");
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "previous result\n");
    }
    // A successful run replaces it whole.
    let r = run(
        &[
            "calibrate",
            "--model",
            VALID_ARM,
            "--data",
            "fixtures/invalid/csv/valid_arm.csv",
            "--out",
            &out_arg,
        ],
        None,
    );
    assert!(r.starts_with("exit: 0\n"), "{r}");
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.contains("joints:"), "{text}");
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, ["calibrated.yaml"]);
}
