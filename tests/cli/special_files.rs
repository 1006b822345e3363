//! Standard input, standard output and special files as first-class citizens (issue 30): an
//! input read from standard input is never overwritten; a destination that is a device node or
//! a FIFO is written in place, never replaced; a full device or a closed standard output is exit
//! 2 naming it; a run whose standard output fails leaves none of its files; an input is opened
//! once (a FIFO does not hang) and capped (standard input on an endless device stops at the
//! cap). Every special file here is a private one, made in a temporary folder (`mknod`,
//! `mkfifo`, a socket bound there): the system's /dev is never written.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::common::root;

const ARM: &str = "fixtures/invalid/urdf/valid_arm.urdf";
const SHEET: &str = "fixtures/invalid/sheet/valid_arm.yaml";
const CSV: &str = "fixtures/invalid/csv/valid_arm.csv";

/// The binary with `args` in `dir`.
fn cmd(dir: &Path, args: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_urdf-dh"));
    c.args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    c
}

/// Runs `c` to its end, killing it after 60 s (a hang is a failure, not a stuck suite):
/// (exit code, stdout, stderr).
fn finish(mut c: Command) -> (i32, Vec<u8>, String) {
    let mut child = c.spawn().expect("run urdf-dh");
    let start = Instant::now();
    loop {
        if child.try_wait().expect("wait").is_some() {
            break;
        }
        if start.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            panic!("urdf-dh hung for 60 s: {c:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().expect("output");
    (
        out.status.code().unwrap_or(-1),
        out.stdout,
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A scratch folder with the arm (`a.urdf`), its sheet (`a.yaml`) and its data (`d.csv`).
fn scratch() -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("a folder");
    let p = dir.path();
    std::fs::copy(root().join(ARM), p.join("a.urdf")).expect("copied");
    std::fs::copy(root().join(SHEET), p.join("a.yaml")).expect("copied");
    std::fs::copy(root().join(CSV), p.join("d.csv")).expect("copied");
    dir
}

/// A private character device `name` in `dir` with the numbers of /dev/null (1, 3) or
/// /dev/full (1, 7); `None` (saying so) where this user may not make device nodes.
fn device(dir: &Path, name: &str, minor: u32) -> Option<PathBuf> {
    let path = dir.join(name);
    let made = Command::new("mknod")
        .arg(&path)
        .args(["c", "1", &minor.to_string()])
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !made {
        test_skips::skip(&format!(
            "device nodes: mknod {} c 1 {minor} is not allowed here (not root)",
            path.display()
        ));
    }
    made.then_some(path)
}

fn is_char_device(p: &Path) -> bool {
    use std::os::unix::fs::FileTypeExt;
    std::fs::symlink_metadata(p).is_ok_and(|m| m.file_type().is_char_device())
}

fn fifo(dir: &Path, name: &str) -> PathBuf {
    let path = dir.join(name);
    let made = Command::new("mkfifo").arg(&path).status().expect("mkfifo");
    assert!(made.success());
    path
}

#[test]
fn an_input_read_from_standard_input_is_never_overwritten() {
    let dir = scratch();
    let p = dir.path();
    // Each output has the extension its option writes; standard input reads that very file.
    for f in ["s.svg", "m.yaml", "p.svg", "o.csv", "j.csv"] {
        std::fs::copy(p.join("d.csv"), p.join(f)).expect("copied");
    }
    let cases: [(&str, &[&str]); 6] = [
        ("s.svg", &["extract", "-", "--svg", "s.svg"]),
        (
            "m.yaml",
            &[
                "calibrate",
                "--model",
                "a.urdf",
                "--data",
                "-",
                "--out",
                "m.yaml",
            ],
        ),
        ("p.svg", &["cpa", "-", "--plot", "./p.svg"]),
        ("o.csv", &["simulate", "--model", "-", "--out", "o.csv"]),
        (
            "j.csv",
            &[
                "predict", "--model", "a.yaml", "--joints", "-", "--out", "j.csv",
            ],
        ),
        (
            "j.csv",
            &[
                "compensate",
                "--nominal",
                "a.yaml",
                "--model",
                "a.yaml",
                "--joints",
                "-",
                "--out",
                "j.csv",
            ],
        ),
    ];
    for (file, args) in cases {
        let before = std::fs::read(p.join(file)).expect("read");
        let mut c = cmd(p, args);
        c.stdin(std::fs::File::open(p.join(file)).expect("opened"));
        let (code, _, err) = finish(c);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(
            err.contains("found the file standard input reads"),
            "{args:?}: {err}"
        );
        assert_eq!(
            std::fs::read(p.join(file)).expect("read"),
            before,
            "{args:?}"
        );
    }
    // Standard input from another file: the run goes on.
    let mut c = cmd(p, &["extract", "-", "--svg", "frames.svg"]);
    c.stdin(std::fs::File::open(p.join("a.urdf")).expect("opened"));
    let (code, _, err) = finish(c);
    assert_eq!(code, 0, "{err}");
    assert!(std::fs::read_to_string(p.join("frames.svg"))
        .expect("drawn")
        .contains("<svg"));
}

#[test]
fn a_device_node_is_written_in_place_and_a_full_one_is_an_error() {
    let dir = scratch();
    let p = dir.path();
    let Some(null) = device(p, "null", 3) else {
        return;
    };
    let null_s = null.to_str().expect("UTF-8");
    for args in [
        vec!["extract", "a.urdf", "--svg", null_s],
        vec![
            "simulate", "--model", "a.yaml", "--poses", "5", "--out", null_s, "--truth", "t.yaml",
        ],
        vec![
            "calibrate",
            "--model",
            "a.urdf",
            "--data",
            "d.csv",
            "--out",
            null_s,
            "--plot",
            null_s,
        ],
        vec!["convert", "a.yaml", "--to", "modified", "--samples", "10"],
    ] {
        let (code, _, err) = finish(cmd(p, &args));
        assert_eq!(code, 0, "{args:?}: {err}");
        assert!(is_char_device(&null), "{args:?} replaced the device node");
    }
    let Some(full) = device(p, "full", 7) else {
        return;
    };
    let full_s = full.to_str().expect("UTF-8");
    let (code, _, err) = finish(cmd(p, &["extract", "a.urdf", "--svg", full_s]));
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("full: cannot write the output"), "{err}");
    assert!(is_char_device(&full));
    // Standard output on a full device: exit 2 naming it, and no file of the run lands.
    let on_full = |args: &[&str]| {
        let mut c = cmd(p, args);
        c.stdout(
            std::fs::OpenOptions::new()
                .write(true)
                .open(&full)
                .expect("opened"),
        );
        finish(c)
    };
    let (code, _, err) = on_full(&[
        "simulate", "--model", "a.yaml", "--poses", "5", "--out", "-", "--truth", "t2.yaml",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("standard output"), "{err}");
    assert!(
        !p.join("t2.yaml").exists(),
        "the truth landed though the data did not"
    );
    let (code, _, err) = on_full(&[
        "calibrate",
        "--model",
        "a.urdf",
        "--data",
        "d.csv",
        "--out",
        "-",
        "--plot",
        "p.svg",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        !p.join("p.svg").exists(),
        "the chart landed though the model did not"
    );
    let (code, _, err) = on_full(&["extract", "a.urdf", "--svg", "f.svg"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        !p.join("f.svg").exists(),
        "the drawing landed though the table did not"
    );
    for args in [
        &["completions", "bash"][..],
        &["man"],
        &["convert", "a.yaml", "--to", "modified"],
    ] {
        let (code, _, err) = on_full(args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(
            err.contains("standard output") && !err.contains("panicked"),
            "{args:?}: {err}"
        );
    }
}

#[test]
fn a_fifo_destination_is_written_in_place_and_a_socket_is_refused() {
    let dir = scratch();
    let p = dir.path();
    let pipe = fifo(p, "frames.fifo");
    let reader = {
        let pipe = pipe.clone();
        std::thread::spawn(move || std::fs::read_to_string(pipe).expect("read the FIFO"))
    };
    let (code, _, err) = finish(cmd(p, &["extract", "a.urdf", "--svg", "frames.fifo"]));
    assert_eq!(code, 0, "{err}");
    assert!(reader.join().expect("reader").contains("<svg"));
    use std::os::unix::fs::FileTypeExt;
    assert!(std::fs::symlink_metadata(&pipe)
        .expect("there")
        .file_type()
        .is_fifo());
    let _socket = std::os::unix::net::UnixListener::bind(p.join("s.sock")).expect("bound");
    let (code, _, err) = finish(cmd(p, &["extract", "a.urdf", "--svg", "s.sock"]));
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("found a socket"), "{err}");
}

#[test]
fn a_fifo_input_is_opened_once() {
    let dir = scratch();
    let p = dir.path();
    // `calibrate` reads its model twice (is it a tree sheet? then the sheet itself): a second
    // open of a FIFO would wait for a writer that never comes.
    for (args, feed) in [
        (
            vec!["calibrate", "--model", "m.fifo", "--data", "d.csv"],
            "a.yaml",
        ),
        (vec!["convert", "m.fifo", "--to", "modified"], "a.yaml"),
        (vec!["extract", "m.fifo"], "a.urdf"),
    ] {
        let pipe = fifo(p, "m.fifo");
        let writer = {
            let (pipe, bytes) = (pipe.clone(), std::fs::read(p.join(feed)).expect("read"));
            std::thread::spawn(move || {
                // Written once; a reader that opens again finds no writer.
                let _ = std::fs::write(pipe, bytes);
            })
        };
        let (code, _, err) = finish(cmd(p, &args));
        assert_eq!(code, 0, "{args:?}: {err}");
        writer.join().expect("writer");
        std::fs::remove_file(&pipe).expect("removed");
    }
}

#[test]
fn a_closed_standard_output_is_an_error_not_a_lost_result() {
    let dir = scratch();
    let p = dir.path();
    let bin = env!("CARGO_BIN_EXE_urdf-dh");
    let run = |redirect: &str| {
        let mut c = Command::new("sh");
        c.arg("-c")
            .arg(format!("exec \"$0\" extract a.urdf {redirect}"))
            .arg(bin)
            .current_dir(p)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        finish(c)
    };
    let (code, _, err) = run(">&-");
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("standard output is closed"), "{err}");
    // A shell's `> /dev/null` is a choice to throw the output away: it is not refused.
    let (code, _, err) = run(">/dev/null");
    assert_eq!(code, 0, "{err}");
}

#[test]
fn standard_input_is_capped_like_a_file() {
    let dir = scratch();
    let p = dir.path();
    // An endless input: a private /dev/zero where device nodes can be made, else a FIFO fed
    // without end.
    for args in [
        &["convert", "-", "--to", "modified"][..],
        &["check", "a.urdf", "--sheet", "-"],
        &["to-urdf", "-"],
        &["batch", "-"],
        &["extract", "-"],
    ] {
        let mut c = cmd(p, args);
        let zero = p.join("zero");
        let feeder = if zero.exists() || device(p, "zero", 5).is_some() {
            c.stdin(std::fs::File::open(&zero).expect("opened"));
            None
        } else {
            let pipe = fifo(p, "endless.fifo");
            let feeder = std::thread::spawn({
                let pipe = pipe.clone();
                move || {
                    use std::io::Write;
                    let mut f = std::fs::OpenOptions::new()
                        .write(true)
                        .open(pipe)
                        .expect("opened");
                    while f.write_all(&[b' '; 65536]).is_ok() {}
                }
            });
            c.stdin(std::fs::File::open(&pipe).expect("opened"));
            Some((feeder, pipe))
        };
        let (code, _, err) = finish(c);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains("at most 67108864 bytes"), "{args:?}: {err}");
        if let Some((feeder, pipe)) = feeder {
            feeder.join().expect("feeder");
            std::fs::remove_file(pipe).expect("removed");
        }
    }
}
