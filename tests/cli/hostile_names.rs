//! Hostile names and usage mistakes (issue 30, classes 7, 8 and 10): no control or bidi
//! character reaches the terminal or a JSON document raw, whatever command prints the name and
//! wherever it comes from (URDF, sheet, list, argument); long names and paths are cut in
//! messages; names that differ only in Unicode normalisation are told apart; usage mistakes
//! (`--q` without `--svg`, an output extension of another format, a negative number, a typo,
//! a sheet given as a robot) get a word.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use crate::common::root;

/// A run's exit code, standard output and standard error.
struct Run {
    code: i32,
    stdout: String,
    stderr: String,
}

/// Runs the binary in `dir` with `args`, standard input empty.
fn run_in(dir: &Path, args: &[&str]) -> Run {
    let out = Command::new(env!("CARGO_BIN_EXE_urdf-dh"))
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .output()
        .expect("run urdf-dh");
    Run {
        code: out.status.code().unwrap_or(-1),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// A character that can drive a terminal or reorder what it shows: a control character other
/// than the line feed, or a bidi formatting character (the set the readers refuse).
fn spoofing(c: char) -> bool {
    (c.is_control() && c != '\n')
        || matches!(c, '\u{061C}' | '\u{200E}' | '\u{200F}' | '\u{202A}'..='\u{202E}' | '\u{2066}'..='\u{2069}')
}

/// Asserts that neither stream of `r` (the run of `what`) holds a [`spoofing`] character.
fn assert_clean(what: &str, r: &Run) {
    for (stream, text) in [("stdout", &r.stdout), ("stderr", &r.stderr)] {
        if let Some((at, c)) = text.char_indices().find(|&(_, c)| spoofing(c)) {
            panic!(
                "{what}: raw U+{:04X} on {stream} at byte {at}:\n{}",
                u32::from(c),
                text.escape_debug()
            );
        }
    }
}

fn ur5() -> PathBuf {
    root().join("fixtures/robots/ur5")
}

/// The hostile text: ESC [2J (clear the screen), a right-to-left override, a C1 CSI.
const HOSTILE: &str = "\u{1b}[2Jx\u{202e}y\u{9b}1m";

/// A folder with the UR5's URDF and sheet, each also with a hostile robot name, a sheet with a
/// hostile effect, source and tip link, and a small measurement set.
fn hostile_folder() -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let urdf = std::fs::read_to_string(ur5().join("robot.urdf")).unwrap();
    std::fs::write(d.join("robot.urdf"), &urdf).unwrap();
    let start = urdf.find("<robot name=\"").unwrap() + "<robot name=\"".len();
    let end = start + urdf[start..].find('"').unwrap();
    let hostile_urdf = format!(
        "{}&#27;[2Jx&#x202E;y&#x9b;1m{}",
        &urdf[..start],
        &urdf[end..]
    );
    std::fs::write(d.join("esc.urdf"), hostile_urdf).unwrap();
    let sheet = std::fs::read_to_string(ur5().join("vendor.yaml")).unwrap();
    std::fs::write(d.join("vendor.yaml"), &sheet).unwrap();
    // As YAML escapes: a YAML reader refuses some of these characters raw.
    let yaml_text = r#""\u001b[2Jx\u202ey\u009b1m""#;
    let with = |key: &str| -> String {
        sheet
            .lines()
            .map(|l| {
                if l.starts_with(&format!("{key}:")) {
                    format!("{key}: {yaml_text}")
                } else {
                    l.to_string()
                }
            })
            .collect::<Vec<_>>()
            .join("\n")
            + "\n"
    };
    std::fs::write(d.join("robot.yaml"), with("robot")).unwrap();
    std::fs::write(d.join("source.yaml"), with("source")).unwrap();
    std::fs::write(
        d.join("tip.yaml"),
        format!(
            "{}tip_link: {yaml_text}\nbase_link: base_link\n",
            with("none")
        ),
    )
    .unwrap();
    std::fs::write(
        d.join("effect.yaml"),
        format!(
            "{}effects:\n  - {{name: {yaml_text}, value: 1, unit: m}}\n",
            with("none")
        ),
    )
    .unwrap();
    let r = run_in(
        d,
        &[
            "simulate",
            "--model",
            "vendor.yaml",
            "--poses",
            "30",
            "--out",
            "d.csv",
        ],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    std::fs::write(
        d.join("list.txt"),
        format!("robot.urdf base_link tool0{HOSTILE}\nesc.urdf\n"),
    )
    .unwrap();
    dir
}

#[test]
fn no_hostile_name_reaches_the_terminal_raw() {
    let dir = hostile_folder();
    let d = dir.path();
    let tip = format!("tool0{HOSTILE}");
    let name = format!("arm{HOSTILE}");
    let runs: Vec<Vec<&str>> = vec![
        vec!["extract", "esc.urdf"],
        vec!["extract", "esc.urdf", "--format", "json"],
        vec!["extract", "robot.urdf", "--tip", &tip],
        vec!["extract", "robot.urdf", "--base", &tip, "--format", "yaml"],
        vec!["check", "esc.urdf", "--sheet", "vendor.yaml"],
        vec![
            "check",
            "robot.urdf",
            "--sheet",
            "robot.yaml",
            "--format",
            "json",
        ],
        vec![
            "check",
            "robot.urdf",
            "--sheet",
            "vendor.yaml",
            "--tip",
            &tip,
        ],
        vec![
            "convert",
            "robot.yaml",
            "--to",
            "modified",
            "--format",
            "text",
        ],
        vec![
            "convert",
            "source.yaml",
            "--to",
            "modified",
            "--format",
            "json",
        ],
        vec![
            "convert", "tip.yaml", "--to", "modified", "--format", "markdown",
        ],
        vec![
            "convert",
            "effect.yaml",
            "--to",
            "modified",
            "--format",
            "csv",
        ],
        vec!["to-urdf", "robot.yaml"],
        vec!["to-urdf", "vendor.yaml", "--name", &name, "--samples", "10"],
        vec![
            "to-urdf",
            "vendor.yaml",
            "--tip-link",
            &tip,
            "--samples",
            "10",
        ],
        vec!["batch", "list.txt", "--samples", "10"],
        vec!["calibrate", "--model", "robot.yaml", "--data", "d.csv"],
        vec![
            "calibrate",
            "--model",
            "effect.yaml",
            "--data",
            "d.csv",
            "--format",
            "json",
        ],
        vec!["calibrate", "--model", "esc.urdf", "--data", "d.csv"],
        vec![
            "calibrate",
            "--model",
            "robot.urdf",
            "--tip",
            &tip,
            "--data",
            "d.csv",
        ],
        vec!["simulate", "--model", "robot.yaml", "--out", "s.csv"],
        vec!["simulate", "--model", "esc.urdf", "--out", "s.csv"],
        vec!["cpa", "d.csv", "--model", "robot.yaml"],
        vec!["predict", "--model", "robot.yaml", "--joints", "d.csv"],
        vec![
            "compensate",
            "--nominal",
            "robot.yaml",
            "--model",
            "vendor.yaml",
            "--joints",
            "d.csv",
        ],
        vec!["import", "d.csv", "--joint-names", &name],
    ];
    for args in &runs {
        let r = run_in(d, args);
        assert_clean(&args.join(" "), &r);
    }
}

#[test]
fn hostile_robot_names_are_refused_where_they_are_read() {
    let dir = hostile_folder();
    let d = dir.path();
    let r = run_in(d, &["extract", "esc.urdf"]);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(
        r.stderr
            .contains("esc.urdf: invalid URDF: robot '\\u{1b}[2Jx\\u{202e}y\\u{9b}1m'")
            && r.stderr.contains("found U+001B at character 1"),
        "{}",
        r.stderr
    );
    assert_eq!(r.stdout, "");
    for (file, key) in [
        ("robot.yaml", "robot"),
        ("source.yaml", "source"),
        ("tip.yaml", "tip_link"),
    ] {
        let r = run_in(d, &["convert", file, "--to", "modified"]);
        assert_eq!(r.code, 2, "{file}: {}", r.stderr);
        assert!(
            r.stderr.contains(&format!(
                "{file}: {key}: '\\u{{1b}}[2Jx\\u{{202e}}y\\u{{9b}}1m': expected text without control or bidi characters, found U+001B at character 1"
            )),
            "{}",
            r.stderr
        );
    }
    let r = run_in(d, &["convert", "effect.yaml", "--to", "modified"]);
    assert_eq!(r.code, 2);
    assert!(
        r.stderr
            .contains("effect.yaml: effects: expected a printable effect name, found '\\u{1b}[2Jx\\u{202e}y\\u{9b}1m'"),
        "{}",
        r.stderr
    );
}

#[test]
fn batch_json_carries_a_hostile_tip_as_escapes_that_read_back() {
    let dir = hostile_folder();
    let r = run_in(dir.path(), &["batch", "list.txt", "--samples", "10"]);
    assert_clean("batch", &r);
    let first = r.stdout.lines().next().expect("a line per chain");
    assert!(
        first.contains("\\u202e") && first.contains("\\u001b") && first.contains("\\u009b"),
        "{first}"
    );
    let v: serde_json::Value = serde_json::from_str(first).unwrap();
    assert_eq!(v["tip"], format!("tool0{HOSTILE}"));
    // The hostile URDF's line is refused, its error escaped in the JSON too.
    let second: serde_json::Value = serde_json::from_str(r.stdout.lines().nth(1).unwrap()).unwrap();
    assert!(
        second["error"].as_str().unwrap().contains("robot '"),
        "{second}"
    );
}

#[test]
fn a_model_file_name_with_a_line_feed_is_simulated_and_reads_back() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::copy(ur5().join("vendor.yaml"), d.join("a\nb.yaml")).unwrap();
    let r = run_in(
        d,
        &[
            "simulate",
            "--model",
            "a\nb.yaml",
            "--poses",
            "20",
            "--out",
            "x\u{202e}.csv",
        ],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert_clean("simulate", &r);
    let csv = std::fs::read_to_string(d.join("x\u{202e}.csv")).unwrap();
    let first = csv.lines().next().unwrap();
    assert!(
        first.starts_with("# simulated by urdf-dh simulate from a\\u{a}b.yaml (seed 1, 20 poses"),
        "{first}"
    );
    let header = csv.lines().find(|l| !l.starts_with('#')).unwrap();
    assert!(header.starts_with("shoulder_pan_joint,"), "{csv}");
    // Both files read back: the data by calibrate, the truth as a sheet.
    let r = run_in(
        d,
        &[
            "calibrate",
            "--model",
            "x\u{202e}.truth.yaml",
            "--data",
            "x\u{202e}.csv",
        ],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert_clean("calibrate", &r);
}

#[test]
fn long_tips_and_paths_are_cut_in_messages() {
    let tip = format!("a{}z", "t".repeat(100_000));
    let robot = ur5().join("robot.urdf");
    let r = run_in(
        &root(),
        &["extract", robot.to_str().unwrap(), "--tip", &tip],
    );
    assert_eq!(r.code, 2);
    assert!(r.stderr.len() < 2_000, "{} bytes", r.stderr.len());
    assert!(
        r.stderr.contains("tip link 'atttt") && r.stderr.contains("tttz'"),
        "{}",
        r.stderr
    );
    // The quote that opens the name is part of the word cut: 100 002 characters less 157 kept.
    assert!(
        r.stderr.contains("…(99845 characters cut)…"),
        "{}",
        r.stderr
    );
    let path = format!("{}.urdf", "p".repeat(100_000));
    for args in [
        vec!["extract", path.as_str()],
        vec!["convert", path.as_str(), "--to", "modified"],
        vec![
            "calibrate",
            "--model",
            path.as_str(),
            "--data",
            path.as_str(),
        ],
    ] {
        let r = run_in(&root(), &args);
        assert_eq!(r.code, 2, "{}", r.stderr);
        assert!(
            r.stderr.len() < 2_000,
            "{}: {} bytes",
            args[0],
            r.stderr.len()
        );
        assert!(r.stderr.contains("characters cut)…pppp"), "{}", r.stderr);
    }
}

#[test]
fn names_differing_only_in_normalisation_are_told_apart() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = std::fs::read_to_string(ur5().join("robot.urdf"))
        .unwrap()
        .replace("\"tool0\"", "\"caf\u{e9}\"");
    std::fs::write(dir.path().join("r.urdf"), urdf).unwrap();
    let r = run_in(dir.path(), &["extract", "r.urdf", "--tip", "cafe\u{301}"]);
    assert_eq!(r.code, 2);
    assert!(
        r.stderr.contains("differ only in Unicode normalisation: the given name is NFD (U+0063 U+0061 U+0066 U+0065 U+0301), the file's is NFC (U+0063 U+0061 U+0066 U+00E9); give --tip as the URDF spells it"),
        "{}",
        r.stderr
    );
}

#[test]
fn usage_mistakes_get_a_word() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let robot = ur5().join("robot.urdf");
    let robot = robot.to_str().unwrap();
    let sheet = ur5().join("vendor.yaml");
    let sheet = sheet.to_str().unwrap();

    // --q draws nothing without --svg.
    let r = run_in(d, &["extract", robot, "--q", "0,0,0,0,0,0"]);
    assert_eq!(r.code, 2);
    assert!(r.stderr.contains("--svg"), "{}", r.stderr);

    // --arc shapes only the sweeps of --cpa.
    let r = run_in(
        d,
        &[
            "simulate", "--model", sheet, "--out", "d.csv", "--arc", "0.5",
        ],
    );
    assert_eq!(r.code, 2);
    assert!(r.stderr.contains("--cpa"), "{}", r.stderr);

    // An output's extension names another format.
    let r = run_in(d, &["extract", robot, "--svg", "frames.png"]);
    assert_eq!(r.code, 2);
    assert!(
        r.stderr.contains("expected a file name ending in .svg (this option writes an SVG drawing), found '.png', which names a PNG image: name it e.g. frames.svg"),
        "{}",
        r.stderr
    );
    assert!(!d.join("frames.png").exists());
    let r = run_in(
        d,
        &[
            "calibrate",
            "--model",
            sheet,
            "--data",
            "d.csv",
            "--out",
            "m.txt",
        ],
    );
    assert_eq!(r.code, 2);
    assert!(
        r.stderr.contains("found '.txt', which names plain text"),
        "{}",
        r.stderr
    );
    let r = run_in(d, &["simulate", "--model", sheet, "--out", "d.yaml"]);
    assert_eq!(r.code, 2);
    assert!(
        r.stderr.contains("this option writes a CSV table"),
        "{}",
        r.stderr
    );

    // A negative number meets the option's range, not clap's "unexpected argument".
    let r = run_in(
        d,
        &[
            "simulate", "--model", sheet, "--out", "d.csv", "--noise", "-1",
        ],
    );
    assert_eq!(r.code, 2);
    assert!(!r.stderr.contains("unexpected argument"), "{}", r.stderr);
    assert!(
        r.stderr.contains("'--noise <SIGMA>'") && r.stderr.contains("found -1"),
        "{}",
        r.stderr
    );

    // A typo gets the option meant.
    let r = run_in(d, &["extract", robot, "--tp", "tool0"]);
    assert_eq!(r.code, 2);
    assert!(
        r.stderr.contains("hint: did you mean '--tip'?"),
        "{}",
        r.stderr
    );
    assert!(
        !r.stderr.contains("to pass '--tp' as a value"),
        "{}",
        r.stderr
    );

    // Standard output is named as such.
    let r = run_in(
        d,
        &[
            "simulate", "--model", sheet, "--poses", "5", "--out", "-", "--truth", "t.yaml",
        ],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stderr.starts_with("urdf-dh: <stdout>: "), "{}", r.stderr);
    assert!(!r.stderr.contains("<stdin>"), "{}", r.stderr);
    let truth = std::fs::read_to_string(d.join("t.yaml")).unwrap();
    assert!(truth.contains("truth of <stdout>"), "{truth}");
    std::fs::write(d.join("d.csv"), r.stdout.as_bytes()).unwrap();

    // Files that are not robots are named, with the command that reads them.
    let r = run_in(d, &["extract", sheet]);
    assert_eq!(r.code, 2);
    assert!(
        r.stderr.contains("the file is a DH sheet (YAML or JSON)"),
        "{}",
        r.stderr
    );
    assert!(
        r.stderr.contains("hint: a sheet is read by check"),
        "{}",
        r.stderr
    );
    let r = run_in(d, &["extract", "d.csv"]);
    assert_eq!(r.code, 2);
    assert!(
        r.stderr.contains("the file is a measurement CSV"),
        "{}",
        r.stderr
    );
    assert!(
        r.stderr
            .contains("urdf-dh calibrate --model MODEL --data FILE"),
        "{}",
        r.stderr
    );
    std::fs::write(d.join("p.png"), b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR\0\0").unwrap();
    let r = run_in(d, &["extract", "p.png"]);
    assert_eq!(r.code, 2);
    assert!(r.stderr.contains("the file is a PNG image"), "{}", r.stderr);
    assert!(!r.stderr.contains("iconv"), "{}", r.stderr);
}
