//! The bad-input corpus of `fixtures/invalid/` (see its README.md): every case is one run of
//! the binary, snapshotted as exit code + stdout + stderr. Errors exit 2 with nothing on stdout
//! and one `urdf-dh: error:` line naming the file, line or joint (and a `hint:` line where one
//! helps); suspicious but readable input is a `urdf-dh: warning:`. Nothing panics.

mod cases;

use std::collections::BTreeSet;

use crate::common::{root, run, settings};
use cases::CASES;

#[test]
fn every_bad_input_gets_a_clear_error() {
    let _snap = settings().bind_to_scope();
    let mut names = BTreeSet::new();
    for c in CASES {
        assert!(names.insert(c.name), "case {} twice", c.name);
        let out = run(c.args, None);
        insta::assert_snapshot!(c.name, out);
        let code: i32 = out
            .lines()
            .next()
            .and_then(|l| l.strip_prefix("exit: "))
            .and_then(|n| n.parse().ok())
            .unwrap_or(-1);
        assert_eq!(code, c.exit, "{}: {out}", c.name);
        let (stdout, stderr) = out
            .split_once("--- stderr\n")
            .map(|(o, e)| (o.split_once("--- stdout\n").map_or("", |(_, o)| o), e))
            .unwrap_or(("", ""));
        assert!(!stderr.contains("panicked"), "{}: {stderr}", c.name);
        if c.exit == 2 {
            assert!(
                stdout.is_empty(),
                "{}: an error writes nothing to stdout",
                c.name
            );
            assert!(
                stderr.starts_with("urdf-dh: error: "),
                "{}: {stderr}",
                c.name
            );
            // Usage errors are clap's, with its possible values, tips and usage line.
            let usage = stderr.contains("For more information, try '--help'.");
            let lines: Vec<&str> = stderr.lines().collect();
            assert!(
                usage || lines.len() == 1 || lines.len() == 2 && lines[1].starts_with("hint: "),
                "{}: one error line and at most a hint: {stderr}",
                c.name
            );
        }
    }
}

/// Every file of the corpus is some case's input (no untested case, no stale file).
#[test]
fn every_corpus_file_is_a_case() {
    let used: BTreeSet<String> = CASES
        .iter()
        .flat_map(|c| c.args.iter())
        .filter(|a| a.starts_with("fixtures/invalid/"))
        .map(|a| a.to_string())
        .collect();
    let mut files = Vec::new();
    for dir in ["urdf", "sheet", "csv", "xacro"] {
        for e in std::fs::read_dir(root().join("fixtures/invalid").join(dir)).unwrap() {
            let name = e.unwrap().file_name().to_string_lossy().into_owned();
            files.push(format!("fixtures/invalid/{dir}/{name}"));
        }
    }
    files.sort();
    let unused: Vec<&String> = files.iter().filter(|f| !used.contains(*f)).collect();
    assert!(unused.is_empty(), "corpus files no case reads: {unused:?}");
    assert!(CASES.len() >= 40, "{} cases", CASES.len());
}
