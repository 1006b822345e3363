//! Skips that are seen. A test that cannot make a check here (the real robots and measurements
//! of `../shared` are absent, an optional tool such as Python's xacro is not installed) calls
//! [`skip`] with the reason and returns (or goes on with what it can check).
//!
//! `cargo test` captures what a passing test prints, so a skip reported with `println!` ends as
//! a plain `ok`. [`skip`] writes past the capture, to the process's standard error, and appends
//! the same line to the file named by [`LOG_VAR`]: the README's test command, `bash
//! tests/run.sh`, sets it and lists every skip, with its reason and a count, at its end.

use std::io::Write;
use std::path::Path;

/// The environment variable naming the file to which every skip appends its line.
pub const LOG_VAR: &str = "URDF_DH_SKIP_LOG";

/// Records that the running test skipped its check, or a part of it, because of `reason`
/// (say what is missing and how to get it): the line `SKIPPED: BINARY TEST: REASON` goes to
/// standard error and, when [`LOG_VAR`] names a file, is appended to that file.
///
/// The test's name is the name of the thread it runs on (the test harness names it so);
/// `BINARY` is the test executable's name without cargo's hash.
pub fn skip(reason: &str) {
    let log = std::env::var_os(LOG_VAR).filter(|p| !p.is_empty());
    // Not `eprint!`: the test harness captures that and shows it only for a failed test.
    record(
        reason,
        log.as_deref().map(Path::new),
        &mut std::io::stderr().lock(),
    );
}

/// [`skip`]'s work, with the log file and standard error given.
fn record(reason: &str, log: Option<&Path>, stderr: &mut dyn Write) {
    let line = format!("SKIPPED: {}: {}\n", who(), reason.trim_end());
    let _ = stderr.write_all(line.as_bytes());
    if let Some(path) = log {
        let file = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(path);
        // One write per line: lines of tests running in parallel do not interleave.
        let written = file.and_then(|mut f| f.write_all(line.as_bytes()));
        if let Err(e) = written {
            let note = format!(
                "test-skips: cannot append to {} ({LOG_VAR}): {e}\n",
                path.display()
            );
            let _ = stderr.write_all(note.as_bytes());
        }
    }
}

/// `BINARY TEST` of the running test: `cli corpus::corpus_extracts`.
fn who() -> String {
    let binary = std::env::current_exe()
        .ok()
        .and_then(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .map(|stem| match stem.rsplit_once('-') {
            // cargo names test executables NAME-HASH (16 hexadecimal digits).
            Some((name, hash))
                if hash.len() == 16 && hash.bytes().all(|b| b.is_ascii_hexdigit()) =>
            {
                name.to_owned()
            }
            _ => stem,
        })
        .unwrap_or_else(|| "?".to_owned());
    let thread = std::thread::current();
    let test = thread.name().unwrap_or("?");
    format!("{binary} {test}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_skip_is_shown_and_appended_with_the_test_and_the_reason() {
        let dir = std::env::temp_dir().join(format!("test-skips-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let log = dir.join("skips.txt");
        let _ = std::fs::remove_file(&log);
        let shown = std::thread::Builder::new()
            .name("module::some_test".into())
            .spawn({
                let log = log.clone();
                move || {
                    let mut shown = Vec::new();
                    record("../shared is absent", Some(&log), &mut shown);
                    record("python's xacro is not installed\n", Some(&log), &mut shown);
                    shown
                }
            })
            .unwrap()
            .join()
            .unwrap();
        let expected = "SKIPPED: test_skips module::some_test: ../shared is absent\n\
                        SKIPPED: test_skips module::some_test: python's xacro is not installed\n";
        assert_eq!(String::from_utf8(shown).unwrap(), expected);
        assert_eq!(std::fs::read_to_string(&log).unwrap(), expected);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_log_that_cannot_be_written_is_named() {
        let mut shown = Vec::new();
        let dir = std::env::temp_dir();
        record("no tool", Some(&dir), &mut shown);
        let shown = String::from_utf8(shown).unwrap();
        assert!(
            shown.contains(": no tool\ntest-skips: cannot append to "),
            "{shown}"
        );
    }

    #[test]
    fn the_binary_is_named_without_cargo_hash() {
        let who = who();
        assert!(who.starts_with("test_skips "), "{who}");
    }
}
