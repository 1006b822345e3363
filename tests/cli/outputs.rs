//! Output files: never written over an input or over another output (however the path is
//! spelled), checked before any work so that a run writes all its files or none; and text
//! tables that survive names of any length.

use std::path::Path;

use crate::common::{exec, root};

const ARM: &str = "fixtures/invalid/urdf/valid_arm.urdf";
const CSV: &str = "fixtures/invalid/csv/valid_arm.csv";

/// Runs the binary in `dir`: (exit code, stdout, stderr).
fn exec_in(dir: &Path, args: &[&str]) -> (i32, String, String) {
    let (code, out, err) = exec_piped(dir, args, b"");
    (code, String::from_utf8_lossy(&out).into_owned(), err)
}

fn names(dir: &Path) -> Vec<String> {
    let mut n: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    n.sort();
    n
}

/// A scratch directory with the valid arm (`a.urdf`), its data (`d.csv`), a symbolic and a
/// hard link to the data, and a stale result (`r.yaml`).
fn scratch() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::copy(root().join(ARM), p.join("a.urdf")).unwrap();
    std::fs::copy(root().join(CSV), p.join("d.csv")).unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink("d.csv", p.join("link.csv")).unwrap();
    std::fs::hard_link(p.join("d.csv"), p.join("hard.csv")).unwrap();
    std::fs::write(p.join("r.yaml"), "previous result\n").unwrap();
    dir
}

#[test]
fn an_output_that_is_an_input_or_another_output_is_a_usage_error() {
    let dir = scratch();
    let p = dir.path();
    let data = std::fs::read(p.join("d.csv")).unwrap();
    let model = std::fs::read(p.join("a.urdf")).unwrap();
    let cal = |extra: &[&str]| {
        let mut args = vec!["calibrate", "--model", "a.urdf", "--data", "d.csv"];
        args.extend_from_slice(extra);
        exec_in(p, &args)
    };
    let mut runs = vec![
        ("--out ./d.csv", cal(&["--out", "./d.csv"])),
        ("--out hard link", cal(&["--out", "hard.csv"])),
        ("--out the model", cal(&["--out", "a.urdf"])),
        (
            "--plot = --out",
            cal(&["--out", "r.yaml", "--plot", "./r.yaml"]),
        ),
        (
            "--validate = --out",
            cal(&["--validate", "hard.csv", "--out", "d.csv"]),
        ),
        (
            "--svg = robot",
            exec_in(p, &["extract", "a.urdf", "--svg", "a.urdf"]),
        ),
        (
            "simulate --out = model",
            exec_in(p, &["simulate", "--model", "a.urdf", "--out", "a.urdf"]),
        ),
        (
            "simulate --truth = --out",
            exec_in(
                p,
                &[
                    "simulate", "--model", "a.urdf", "--out", "d.csv", "--truth", "d.csv",
                ],
            ),
        ),
        (
            "import F --out F",
            exec_in(
                p,
                &["import", "--layout", "innopolis", "d.csv", "--out", "d.csv"],
            ),
        ),
    ];
    #[cfg(unix)]
    runs.push(("--out symlink", cal(&["--out", "link.csv"])));
    for (what, (code, out, err)) in &runs {
        assert_eq!(*code, 2, "{what}: {err}");
        assert!(out.is_empty(), "{what}: {out}");
        // An output named with another format's extension (calibrate --out d.csv, --svg
        // a.urdf) is refused for its name first (guard::model_output and its siblings).
        assert!(
            err.starts_with("urdf-dh: error: ")
                && (err.contains("expected a file of its own")
                    || err.contains("expected a file name ending in")),
            "{what}: {err}"
        );
    }
    // The same clashes under names without an extension reach the check of clashes.
    std::fs::hard_link(p.join("d.csv"), p.join("hard")).unwrap();
    std::fs::hard_link(p.join("a.urdf"), p.join("arm")).unwrap();
    for (what, (code, out, err)) in [
        ("--out hard link, no extension", cal(&["--out", "hard"])),
        (
            "--plot = --out, no extension",
            cal(&["--out", "r", "--plot", "./r"]),
        ),
        (
            "--svg = robot, no extension",
            exec_in(p, &["extract", "arm", "--svg", "./arm"]),
        ),
    ] {
        assert_eq!(code, 2, "{what}: {err}");
        assert!(out.is_empty(), "{what}: {out}");
        assert!(err.contains("expected a file of its own"), "{what}: {err}");
    }
    std::fs::remove_file(p.join("hard")).unwrap();
    std::fs::remove_file(p.join("arm")).unwrap();
    // Nothing was touched, nothing was added.
    assert_eq!(std::fs::read(p.join("d.csv")).unwrap(), data);
    assert_eq!(std::fs::read(p.join("a.urdf")).unwrap(), model);
    assert_eq!(
        std::fs::read_to_string(p.join("r.yaml")).unwrap(),
        "previous result\n"
    );
    assert_eq!(
        names(p),
        ["a.urdf", "d.csv", "hard.csv", "link.csv", "r.yaml"]
    );
}

#[test]
fn a_run_with_an_unwritable_destination_writes_nothing() {
    let dir = scratch();
    let p = dir.path();
    std::fs::write(p.join("y.csv"), "old data\n").unwrap();
    let (code, out, err) = exec_in(
        p,
        &[
            "simulate",
            "--model",
            "a.urdf",
            "--out",
            "y.csv",
            "--truth",
            "missing/t.yaml",
        ],
    );
    assert_eq!(code, 2, "{err}");
    assert!(out.is_empty());
    assert!(
        err.contains("--truth missing/t.yaml") && err.contains("does not exist"),
        "{err}"
    );
    assert_eq!(
        std::fs::read_to_string(p.join("y.csv")).unwrap(),
        "old data\n"
    );

    let (code, out, err) = exec_in(
        p,
        &[
            "calibrate",
            "--model",
            "a.urdf",
            "--data",
            "d.csv",
            "--out",
            "r.yaml",
            "--plot",
            "missing/p.svg",
        ],
    );
    assert_eq!(code, 2, "{err}");
    assert!(
        out.is_empty(),
        "no report for a run that cannot write: {out}"
    );
    assert!(err.contains("--plot missing/p.svg"), "{err}");
    assert_eq!(
        std::fs::read_to_string(p.join("r.yaml")).unwrap(),
        "previous result\n"
    );
    // A directory as the output.
    std::fs::create_dir(p.join("sub")).unwrap();
    let (code, _, err) = exec_in(
        p,
        &[
            "calibrate",
            "--model",
            "a.urdf",
            "--data",
            "d.csv",
            "--plot",
            "sub",
        ],
    );
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("found a directory"), "{err}");
    assert_eq!(
        names(p),
        ["a.urdf", "d.csv", "hard.csv", "link.csv", "r.yaml", "sub", "y.csv"]
    );

    // And with every destination writable, both files are written.
    let (code, _, err) = exec_in(
        p,
        &[
            "simulate", "--model", "a.urdf", "--out", "y.csv", "--poses", "5",
        ],
    );
    assert_eq!(code, 0, "{err}");
    assert!(std::fs::read_to_string(p.join("y.csv"))
        .unwrap()
        .contains("joint_1"));
    assert!(p.join("y.truth.yaml").is_file());
}

/// A name of 70 000 characters (beyond `std::fmt`'s width limit of 65 535) in every text table:
/// a joint in `extract` and `convert`, a target in `calibrate`, a column in `cpa`.
#[test]
fn text_tables_take_names_of_any_length() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    let long = "j".repeat(70_000);
    let urdf = std::fs::read_to_string(root().join(ARM))
        .unwrap()
        .replace("joint_1", &long);
    std::fs::write(p.join("long.urdf"), &urdf).unwrap();
    let (code, out, err) = exec_in(p, &["extract", "long.urdf", "--samples", "20"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains(&long));

    let (code, sheet, err) = exec_in(p, &["extract", "long.urdf", "--format", "yaml"]);
    assert_eq!(code, 0, "{err}");
    std::fs::write(p.join("long.yaml"), &sheet).unwrap();
    let (code, out, err) = exec_in(
        p,
        &[
            "convert",
            "long.yaml",
            "--to",
            "modified",
            "--format",
            "text",
        ],
    );
    assert_eq!(code, 0, "{err}");
    assert!(out.contains(&long));
    let (code, _, err) = exec_in(p, &["check", "long.urdf", "--sheet", "long.yaml"]);
    assert_eq!(code, 0, "{err}");

    let data = std::fs::read_to_string(root().join(CSV))
        .unwrap()
        .replace(",t1,", &format!(",{long},"));
    std::fs::write(p.join("long.csv"), &data).unwrap();
    std::fs::copy(root().join(ARM), p.join("a.urdf")).unwrap();
    let (code, out, err) = exec_in(p, &["calibrate", "--model", "a.urdf", "--data", "long.csv"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("target"), "{out}");

    // cpa: a joint column of that name (a model with that joint names the column).
    let (code, _, err) = exec_in(
        p,
        &[
            "simulate",
            "--model",
            "long.urdf",
            "--cpa",
            "--poses",
            "8",
            "--out",
            "sweeps.csv",
        ],
    );
    assert_eq!(code, 0, "{err}");
    let (code, out, err) = exec_in(p, &["cpa", "sweeps.csv"]);
    assert!(code == 0 || code == 1, "{err}");
    assert!(out.contains(&long), "{out:.300}");
    for text in [&out, &err] {
        assert!(!text.contains("panicked"), "{text:.300}");
    }
    // The plain command line too.
    let (code, _, err) = exec(&["extract", ARM, "--tip", &long]);
    assert_eq!(code, 2);
    assert!(!err.contains("panicked"));
}

/// Runs the binary in `dir` with `stdin`: (exit code, stdout bytes, stderr).
fn exec_piped(dir: &Path, args: &[&str], stdin: &[u8]) -> (i32, Vec<u8>, String) {
    use std::io::Write;
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_urdf-dh"))
        .args(args)
        .current_dir(dir)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("run urdf-dh");
    child
        .stdin
        .take()
        .expect("stdin")
        .write_all(stdin)
        .expect("write stdin");
    let out = child.wait_with_output().expect("wait");
    (
        out.status.code().unwrap_or(-1),
        out.stdout,
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn a_dash_writes_the_artefact_to_stdout_and_the_report_to_stderr() {
    let dir = scratch();
    let p = dir.path();
    let before = names(p);

    // calibrate --out -: the calibrated sheet alone on stdout, readable by every command; the
    // report on stderr.
    let (code, sheet, err) = exec_piped(
        p,
        &[
            "calibrate",
            "--model",
            "a.urdf",
            "--data",
            "d.csv",
            "--out",
            "-",
        ],
        b"",
    );
    assert_eq!(code, 0, "{err}");
    let sheet_text = String::from_utf8(sheet.clone()).unwrap();
    assert!(sheet_text.contains("joints:"), "{sheet_text}");
    assert!(!sheet_text.contains("result: RMS"), "{sheet_text}");
    assert!(err.contains("result: RMS"), "{err}");
    let (code, converted, err) = exec_piped(p, &["convert", "-", "--to", "modified"], &sheet);
    assert_eq!(code, 0, "{err}");
    assert!(String::from_utf8_lossy(&converted).contains("passed: true"));

    // --plot -: the SVG on stdout; the report on stderr.
    let (code, svg, err) = exec_piped(
        p,
        &[
            "calibrate",
            "--model",
            "a.urdf",
            "--data",
            "d.csv",
            "--plot",
            "-",
        ],
        b"",
    );
    assert_eq!(code, 0, "{err}");
    assert!(svg.starts_with(b"<svg") || svg.starts_with(b"<?xml"));
    assert!(err.contains("result: RMS"), "{err}");

    // Two outputs on stdout: a usage error before any work.
    let (code, out, err) = exec_piped(
        p,
        &[
            "calibrate",
            "--model",
            "a.urdf",
            "--data",
            "d.csv",
            "--out",
            "-",
            "--plot",
            "-",
        ],
        b"",
    );
    assert_eq!(code, 2);
    assert!(out.is_empty());
    assert!(
        err.contains("--plot -: expected a file, found standard output already taken by --out -"),
        "{err}"
    );

    // extract --svg -: the picture on stdout, the table on stderr.
    let (code, svg, err) = exec_piped(p, &["extract", "a.urdf", "--svg", "-"], b"");
    assert_eq!(code, 0, "{err}");
    assert!(String::from_utf8_lossy(&svg).contains("</svg>"));
    assert!(err.contains("PASS"), "{err}");

    // simulate --out - needs --truth, and then pipes into calibrate --data -.
    let (code, _, err) = exec_piped(p, &["simulate", "--model", "a.urdf", "--out", "-"], b"");
    assert_eq!(code, 2);
    assert!(err.contains("expected --truth FILE"), "{err}");
    let (code, csv, err) = exec_piped(
        p,
        &[
            "simulate", "--model", "a.urdf", "--out", "-", "--truth", "t.yaml", "--poses", "40",
            "--noise", "1e-5", "--seed", "3",
        ],
        b"",
    );
    assert_eq!(code, 0, "{err}");
    assert!(p.join("t.yaml").is_file());
    let (code, report, err) =
        exec_piped(p, &["calibrate", "--model", "a.urdf", "--data", "-"], &csv);
    assert_eq!(code, 0, "{err}");
    assert!(String::from_utf8_lossy(&report).contains("result: RMS"));

    // No file named '-' anywhere.
    let mut expected = before;
    expected.push("t.yaml".into());
    expected.sort();
    assert_eq!(names(p), expected);
}
