//! `--help` wrapped to the terminal (at most 100 columns; exactly 100 when not a terminal) and a
//! manual page per command (`urdf-dh man [COMMAND]`, `urdf-dh man --dir DIR`).

use std::path::Path;
use std::process::{Command, Stdio};

use clap::CommandFactory;
use urdf_dh::cli::Cli;
use urdf_dh::manual::HELP_WIDTH;

use crate::common::root;

/// The command paths of urdf-dh: `[]`, `["extract"]`, ... (every level, from clap's command).
fn command_paths() -> Vec<Vec<String>> {
    fn walk(cmd: &clap::Command, path: Vec<String>, all: &mut Vec<Vec<String>>) {
        for sub in cmd.get_subcommands() {
            let mut p = path.clone();
            p.push(sub.get_name().to_owned());
            walk(sub, p, all);
        }
        all.push(path);
    }
    let mut all = Vec::new();
    walk(&Cli::command(), Vec::new(), &mut all);
    all
}

/// Runs the binary with stdout piped and `COLUMNS` set: (exit code, stdout, stderr).
fn piped(args: &[&str], columns: &str) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_urdf-dh"))
        .args(args)
        .current_dir(root())
        .env("COLUMNS", columns)
        .stdin(Stdio::null())
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
    )
}

/// The widest line of `text`, in characters.
fn widest(text: &str) -> usize {
    text.lines().map(|l| l.chars().count()).max().unwrap_or(0)
}

#[test]
fn every_help_fits_in_100_columns_whatever_columns_says() {
    let paths = command_paths();
    assert!(paths.len() >= 14, "{paths:?}");
    let mut widest_of_all = 0;
    for path in &paths {
        for flag in ["--help", "-h"] {
            let mut args: Vec<&str> = path.iter().map(String::as_str).collect();
            args.push(flag);
            let (code, help, err) = piped(&args, "40");
            assert_eq!((code, err.as_str()), (0, ""), "{args:?}");
            let w = widest(&help);
            assert!(w <= HELP_WIDTH, "{args:?}: a line of {w} columns\n{help}");
            widest_of_all = widest_of_all.max(w);
            // Not a terminal: the same text whatever the environment claims.
            let (_, wide, _) = piped(&args, "300");
            assert_eq!(help, wide, "{args:?}");
        }
    }
    // Wrapped at the width, not merely short (long lines of 471 columns were there before).
    assert!(widest_of_all > HELP_WIDTH - 5, "{widest_of_all}");
}

/// `urdf-dh ARGS` in a pseudo-terminal of `cols` columns (util-linux `script`), escape codes
/// and carriage returns removed.
fn in_terminal(args: &str, cols: usize) -> Option<String> {
    let bin = env!("CARGO_BIN_EXE_urdf-dh");
    let out = Command::new("script")
        .args([
            "-qec",
            &format!("stty rows 40 cols {cols}; '{bin}' {args}"),
            "/dev/null",
        ])
        .stdin(Stdio::null())
        .output()
        .ok()
        .filter(|o| o.status.success())?;
    let raw = String::from_utf8_lossy(&out.stdout);
    let mut text = String::new();
    let mut chars = raw.chars();
    while let Some(c) = chars.next() {
        match c {
            // CSI sequences: ESC [ parameters final-byte.
            '\u{1b}' => {
                for d in chars.by_ref() {
                    if d.is_ascii_alphabetic() {
                        break;
                    }
                }
            }
            '\r' => {}
            c => text.push(c),
        }
    }
    Some(text)
}

#[test]
fn help_follows_a_terminal_narrower_than_100_columns() {
    let Some(narrow) = in_terminal("calibrate --help", 60) else {
        test_skips::skip("no pseudo-terminal: util-linux `script` is absent or cannot run here");
        return;
    };
    assert!(narrow.contains("--effects"), "{narrow}");
    let w = widest(&narrow);
    assert!((50..=60).contains(&w), "a line of {w} columns\n{narrow}");
    let wide = in_terminal("calibrate --help", 200).unwrap();
    assert_eq!(widest(&wide), HELP_WIDTH, "{wide}");
}

/// The pages the top page names in its SUBCOMMANDS section: `urdf-dh-extract`, ...
fn named_pages(top: &str) -> Vec<String> {
    top.lines()
        .filter_map(|l| l.strip_suffix("(1)"))
        .map(|l| l.replace("\\-", "-"))
        .collect()
}

/// A minimal check of a roff page: a title line first, NAME and SYNOPSIS sections, every
/// unfilled block closed, no control line that is not one of the requests the pages use.
fn parses(page: &str) -> Result<(), String> {
    let body: Vec<&str> = page
        .lines()
        .filter(|l| !l.starts_with(".ie ") && !l.starts_with(".el "))
        .collect();
    if !body.first().is_some_and(|l| l.starts_with(".TH ")) {
        return Err("the first line is not .TH".into());
    }
    for section in [".SH NAME", ".SH SYNOPSIS"] {
        if !body.contains(&section) {
            return Err(format!("no {section}"));
        }
    }
    let mut unfilled = false;
    for line in &body {
        let Some(request) = line.strip_prefix('.') else {
            continue;
        };
        match request.split(' ').next().unwrap_or_default() {
            "nf" if !unfilled => unfilled = true,
            "fi" if unfilled => unfilled = false,
            "TH" | "SH" | "TP" | "IP" | "PP" | "RS" | "RE" | "br" => {}
            other => return Err(format!("unexpected request .{other}")),
        }
    }
    if unfilled {
        return Err(".nf without .fi".into());
    }
    Ok(())
}

/// groff's warnings for `file` (`-ww`, all of them), when groff is installed.
fn groff_warnings(file: &Path) -> Option<String> {
    let out = Command::new("groff")
        .args(["-man", "-Tutf8", "-ww", "-z"])
        .arg(file)
        .stdin(Stdio::null())
        .output()
        .ok()?;
    Some(format!(
        "exit {:?} {}",
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
    ))
}

#[test]
fn a_page_is_written_for_every_command_the_top_page_names() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_str().unwrap();
    let (code, out, err) = piped(&["man", "--dir", d], "80");
    assert_eq!((code, out.as_str(), err.as_str()), (0, "", ""));
    let mut written: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    written.sort();
    let top = std::fs::read_to_string(dir.path().join("urdf-dh.1")).unwrap();
    let named = named_pages(&top);
    let mut expected: Vec<String> = named.iter().map(|n| format!("{n}.1")).collect();
    expected.push("urdf-dh.1".into());
    expected.sort();
    assert_eq!(written, expected);
    // One page per command of clap's definition, and no `help` page.
    assert_eq!(named.len() + 1, command_paths().len(), "{named:?}");
    assert!(named.contains(&"urdf-dh-to-urdf".to_owned()), "{named:?}");
    let mut groff_absent = false;
    for file in &written {
        let path = dir.path().join(file);
        let page = std::fs::read_to_string(&path).unwrap();
        parses(&page).map_err(|e| format!("{file}: {e}")).unwrap();
        match groff_warnings(&path) {
            Some(w) => assert_eq!(w, "exit Some(0) ", "{file}"),
            None => groff_absent = true,
        }
        // `urdf-dh man COMMAND` prints the same page.
        let command = file.trim_end_matches(".1").strip_prefix("urdf-dh-");
        let args: Vec<&str> = std::iter::once("man").chain(command).collect();
        let (code, printed, _) = piped(&args, "80");
        assert_eq!((code, printed.as_str()), (0, page.as_str()), "{args:?}");
        if command.is_some() {
            assert!(
                page.contains("\n.SH \"SEE ALSO\"\nurdf\\-dh(1)\n"),
                "{file}"
            );
            assert!(page.contains("\n.SH EXAMPLES\n.nf\n"), "{file}");
        }
    }
    if groff_absent {
        test_skips::skip("groff is absent: the pages were parsed minimally, not rendered");
    }
}

#[test]
fn man_names_the_commands_when_one_is_unknown_and_writes_all_pages_or_none() {
    let (code, out, err) = piped(&["man", "extrakt"], "80");
    assert_eq!((code, out.as_str()), (2, ""));
    let cli = Cli::command();
    let commands: Vec<&str> = cli.get_subcommands().map(|c| c.get_name()).collect();
    assert!(commands.starts_with(&["extract", "batch"]), "{commands:?}");
    assert_eq!(
        err,
        format!(
            "urdf-dh: error: man: expected a command of urdf-dh, found 'extrakt'\n\
             hint: the commands with a page: {}\n",
            commands.join(", ")
        )
    );
    // A page that cannot be written (a directory in its place): no page is written.
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("urdf-dh-man.1")).unwrap();
    let d = dir.path().to_str().unwrap();
    let (code, out, err) = piped(&["man", "--dir", d], "80");
    assert_eq!((code, out.as_str()), (2, ""));
    assert!(
        err.contains("urdf-dh-man.1: cannot write the output: expected a file, found a directory"),
        "{err}"
    );
    let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(left.len(), 1, "{left:?}");
    // A directory that does not exist.
    let missing = dir.path().join("absent");
    let (code, _, err) = piped(&["man", "--dir", missing.to_str().unwrap()], "80");
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("does not exist"), "{err}");
}
