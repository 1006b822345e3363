//! Every example of README.md and docs/guide/*.md, run and compared with the output the page
//! shows, so that no page can go stale.
//!
//! The convention (docs/guide/README.md, "Examples are tested"): a fenced block whose info string
//! is `console` holds commands, each on a line starting with `$ ` (a line ending in `\` goes on
//! the next), and after each the output it prints, stdout and stderr as a terminal shows them
//! (`2>&1`). Words after `console` in the info string:
//! - `exit=N`: every command of the block exits N (default 0);
//! - `shared`: the block reads `../shared`; without it the block is skipped and says so (a
//!   command that names `../shared` in a block without the word fails the test: the page must
//!   say so);
//! - `release`: too slow for a debug build; run only with `URDF_DH_DOCS_RELEASE=1` (with the
//!   binary of `URDF_DH_DOCS_BIN`, e.g. `target/release/urdf-dh`), skipped otherwise, saying so.
//!
//! Each page runs in a temporary directory of its own, its blocks in order (a later example may
//! read what an earlier one wrote), with `fixtures` a link to the repository's fixtures and
//! `../shared` a link to the shared data when it is there; commands run under `sh` with the
//! binary first on `PATH`, so pipes and redirections are the shell's. `cargo run --release --`
//! at the start of a command (the README's first command) stands for `urdf-dh`.
//!
//! Normalised, and only this: the temporary directory's path, printed as `[TMP]` (no example
//! should print it; none does today), and a last line without its newline given one (a page
//! cannot show the difference).
//!
//! `URDF_DH_BLESS=1 cargo test --test cli docs` writes what the commands print into the pages
//! (the shown outputs only; commands, prose and exit codes stay as they are).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use crate::common::{root, shared};

/// One command of a `console` block and the output the page shows after it.
struct Example {
    /// 1-based line of the `$ ` line in the page.
    line: usize,
    /// The command as the shell reads it (continuation lines kept).
    command: String,
    /// 0-based range of the page's lines that hold its output.
    output: std::ops::Range<usize>,
}

/// A `console` block: its words and its commands.
struct Block {
    /// 1-based line of the opening fence.
    line: usize,
    exit: i32,
    shared: bool,
    release: bool,
    examples: Vec<Example>,
}

/// The `console` blocks of a page, in order.
fn blocks(page: &str, name: &str) -> Vec<Block> {
    let lines: Vec<&str> = page.lines().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let fence = lines[i].trim_end();
        let Some(info) = fence.strip_prefix("```console") else {
            i += 1;
            continue;
        };
        let mut block = Block {
            line: i + 1,
            exit: 0,
            shared: false,
            release: false,
            examples: Vec::new(),
        };
        for word in info.split_whitespace() {
            match word {
                "shared" => block.shared = true,
                "release" => block.release = true,
                w if w.starts_with("exit=") => {
                    block.exit = w["exit=".len()..]
                        .parse()
                        .unwrap_or_else(|_| panic!("{name}:{}: bad word '{w}'", i + 1))
                }
                w => panic!("{name}:{}: unknown word '{w}' after ```console", i + 1),
            }
        }
        i += 1;
        while i < lines.len() && lines[i].trim_end() != "```" {
            let Some(first) = lines[i].strip_prefix("$ ") else {
                panic!(
                    "{name}:{}: a console block starts with a `$ ` command line",
                    i + 1
                );
            };
            let line = i + 1;
            let mut command = first.to_string();
            while command.ends_with('\\') && i + 1 < lines.len() {
                i += 1;
                command.push('\n');
                command.push_str(lines[i]);
            }
            i += 1;
            let start = i;
            while i < lines.len() && lines[i].trim_end() != "```" && !lines[i].starts_with("$ ") {
                i += 1;
            }
            block.examples.push(Example {
                line,
                command,
                output: start..i,
            });
        }
        assert!(i < lines.len(), "{name}:{}: unclosed block", block.line);
        i += 1;
        out.push(block);
    }
    out
}

/// The pages whose examples are tested: README.md and docs/guide/*.md.
fn pages() -> Vec<PathBuf> {
    let mut pages = vec![root().join("README.md")];
    let guide = root().join("docs/guide");
    let mut more: Vec<PathBuf> = std::fs::read_dir(&guide)
        .map(|d| {
            d.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "md"))
                .collect()
        })
        .unwrap_or_default();
    more.sort();
    pages.extend(more);
    pages
}

/// The binary the examples call: `URDF_DH_DOCS_BIN` (relative to the repository), else the
/// debug build cargo made for these tests.
fn binary() -> PathBuf {
    match std::env::var_os("URDF_DH_DOCS_BIN") {
        Some(b) => root().join(b),
        None => PathBuf::from(env!("CARGO_BIN_EXE_urdf-dh")),
    }
}

/// Runs one command in `dir` as the page's reader would, stdout and stderr together.
fn run(command: &str, dir: &Path, bin_dir: &Path) -> (i32, String) {
    let command = match command.strip_prefix("cargo run --release -- ") {
        Some(rest) => format!("urdf-dh {rest}"),
        None => command.to_string(),
    };
    let path = std::env::var_os("PATH").unwrap_or_default();
    let mut paths = vec![bin_dir.to_path_buf()];
    paths.extend(std::env::split_paths(&path));
    let out = Command::new("sh")
        .arg("-c")
        .arg(format!("{{ {command}\n}} 2>&1"))
        .current_dir(dir)
        .env("PATH", std::env::join_paths(paths).expect("PATH"))
        .env_remove("URDF_DH_XACRO")
        .stdin(Stdio::null())
        .stderr(Stdio::inherit())
        .output()
        .expect("spawn sh");
    let tmp = dir.parent().unwrap_or(dir).to_string_lossy().into_owned();
    let mut text = String::from_utf8_lossy(&out.stdout).replace(&tmp, "[TMP]");
    if !text.is_empty() && !text.ends_with('\n') {
        text.push('\n');
    }
    (out.status.code().unwrap_or(-1), text)
}

/// What one page's run found: failures (with diffs) and, in bless mode, the new outputs.
#[derive(Default)]
struct PageRun {
    failures: Vec<String>,
    /// Blocks not run, and why (listed by tests/run.sh through test_skips).
    skips: Vec<String>,
    notes: Vec<String>,
    blessed: BTreeMap<usize, (std::ops::Range<usize>, String)>,
}

/// Runs every example of one page in a fresh directory.
fn run_page(page: &Path, bless: bool, release: bool) -> PageRun {
    let name = page
        .strip_prefix(root())
        .unwrap_or(page)
        .display()
        .to_string();
    let text = std::fs::read_to_string(page).expect("read page");
    let lines: Vec<&str> = text.lines().collect();
    let mut result = PageRun::default();
    let tmp = tempfile::tempdir().expect("temp dir");
    let work = tmp.path().join("work");
    std::fs::create_dir(&work).expect("work dir");
    std::os::unix::fs::symlink(root().join("fixtures"), work.join("fixtures")).expect("link");
    if let Some(s) = shared() {
        std::os::unix::fs::symlink(s, tmp.path().join("shared")).expect("link shared");
    }
    let bin = binary();
    let bin_dir = bin.parent().expect("binary's folder").to_path_buf();
    for block in blocks(&text, &name) {
        let mentions_shared = block
            .examples
            .iter()
            .any(|e| e.command.contains("../shared"));
        if mentions_shared && !block.shared {
            result.failures.push(format!(
                "{name}:{}: an example reads ../shared: write ```console shared so that the page says so",
                block.line
            ));
            continue;
        }
        if block.shared && shared().is_none() {
            result.skips.push(format!(
                "{name}:{}: needs ../shared (real robots and measurements), absent",
                block.line
            ));
            continue;
        }
        if block.release && !release {
            result.skips.push(format!(
                "{name}:{}: a release example (URDF_DH_DOCS_RELEASE=1 URDF_DH_DOCS_BIN=target/release/urdf-dh runs it)",
                block.line
            ));
            continue;
        }
        for example in &block.examples {
            let started = Instant::now();
            let (code, actual) = run(&example.command, &work, &bin_dir);
            let seconds = started.elapsed().as_secs_f64();
            if seconds > 5.0 {
                result
                    .notes
                    .push(format!("{name}:{}: took {seconds:.1} s", example.line));
            }
            let shown: String = lines[example.output.clone()]
                .iter()
                .map(|l| format!("{l}\n"))
                .collect();
            if code != block.exit {
                result.failures.push(format!(
                    "{name}:{}: `{}` exited {code}, the page says {} (```console exit=N)\n{actual}",
                    example.line, example.command, block.exit
                ));
            }
            if shown != actual {
                if bless {
                    result
                        .blessed
                        .insert(example.line, (example.output.clone(), actual));
                } else {
                    let diff = similar::TextDiff::from_lines(&shown, &actual)
                        .unified_diff()
                        .context_radius(3)
                        .header(
                            &format!("{name}:{} (shown)", example.output.start + 1),
                            "printed",
                        )
                        .to_string();
                    result.failures.push(format!(
                        "{name}:{}: `{}` prints other output than the page shows:\n{diff}",
                        example.line, example.command
                    ));
                }
            }
        }
    }
    if !result.blessed.is_empty() {
        let mut new: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
        for (range, actual) in result.blessed.values().rev() {
            let replacement: Vec<String> = actual.lines().map(str::to_string).collect();
            new.splice(range.clone(), replacement);
        }
        let mut out = new.join("\n");
        out.push('\n');
        std::fs::write(page, out).expect("bless page");
        result.notes.push(format!(
            "{name}: blessed {} example output(s)",
            result.blessed.len()
        ));
    }
    result
}

#[test]
fn examples() {
    let bless = std::env::var_os("URDF_DH_BLESS").is_some_and(|v| v == "1");
    let release = std::env::var_os("URDF_DH_DOCS_RELEASE").is_some_and(|v| v == "1");
    let pages = pages();
    let runs: Vec<PageRun> = std::thread::scope(|s| {
        let handles: Vec<_> = pages
            .iter()
            .map(|p| s.spawn(move || run_page(p, bless, release)))
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("page thread"))
            .collect()
    });
    let mut report = String::new();
    for run in &runs {
        for skip in &run.skips {
            test_skips::skip(skip);
        }
        for note in &run.notes {
            // Past the harness's capture (as `println!` is not), so that a skip is seen.
            let _ = writeln!(std::io::stderr().lock(), "docs: {note}");
        }
        for failure in &run.failures {
            let _ = writeln!(report, "{failure}");
        }
    }
    assert!(report.is_empty(), "{report}");
}

#[test]
fn blocks_are_read_with_their_words_and_outputs() {
    let page =
        "text\n```console exit=1 shared\n$ urdf-dh a \\\n    b\nout 1\nout 2\n$ urdf-dh c\n```\n";
    let b = blocks(page, "page.md");
    assert_eq!(b.len(), 1);
    assert_eq!(
        (b[0].line, b[0].exit, b[0].shared, b[0].release),
        (2, 1, true, false)
    );
    assert_eq!(b[0].examples.len(), 2);
    assert_eq!(b[0].examples[0].command, "urdf-dh a \\\n    b");
    assert_eq!(b[0].examples[0].output, 4..6);
    assert_eq!(b[0].examples[1].line, 7);
    assert_eq!(b[0].examples[1].output, 7..7);
}

/// GitHub's anchor of a heading: lowercase, punctuation dropped, spaces to `-`.
fn anchor(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || *c == ' ' || *c == '-' || *c == '_')
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// The anchors of a Markdown page's headings (outside fenced blocks).
fn anchors(page: &str) -> Vec<String> {
    let mut fenced = false;
    let mut out = Vec::new();
    for line in page.lines() {
        if line.starts_with("```") {
            fenced = !fenced;
        } else if !fenced && line.starts_with('#') {
            out.push(anchor(line.trim_start_matches('#')));
        }
    }
    out
}

/// The targets of a page's inline links `[text](target)` (outside fenced blocks), with lines.
fn links(page: &str) -> Vec<(usize, String)> {
    let mut fenced = false;
    let mut out = Vec::new();
    for (i, line) in page.lines().enumerate() {
        if line.starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        let mut rest = line;
        while let Some(at) = rest.find("](") {
            let tail = &rest[at + 2..];
            let Some(end) = tail.find(')') else { break };
            out.push((i + 1, tail[..end].to_string()));
            rest = &tail[end..];
        }
    }
    out
}

/// Every relative link of README.md and the guide names a file that is there, and every
/// `#anchor` a heading of its page.
#[test]
fn links_resolve() {
    let mut dead = Vec::new();
    for page in pages() {
        let text = std::fs::read_to_string(&page).expect("read page");
        let name = page
            .strip_prefix(root())
            .unwrap_or(&page)
            .display()
            .to_string();
        for (line, target) in links(&text) {
            if target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            let (path, hash) = match target.split_once('#') {
                Some((p, h)) => (p, Some(h)),
                None => (target.as_str(), None),
            };
            let file = if path.is_empty() {
                page.clone()
            } else {
                page.parent().expect("page folder").join(path)
            };
            if !file.exists() {
                dead.push(format!(
                    "{name}:{line}: {target}: no file {}",
                    file.display()
                ));
                continue;
            }
            if let Some(hash) = hash {
                let linked = std::fs::read_to_string(&file).unwrap_or_default();
                if !anchors(&linked).iter().any(|a| a == hash) {
                    dead.push(format!(
                        "{name}:{line}: {target}: no heading with anchor #{hash}"
                    ));
                }
            }
        }
    }
    assert!(dead.is_empty(), "dead links:\n{}", dead.join("\n"));
}

#[test]
fn anchors_are_github_s() {
    assert_eq!(anchor(" Examples are tested"), "examples-are-tested");
    assert_eq!(
        anchor(" `--format poe`: product of exponentials"),
        "--format-poe-product-of-exponentials"
    );
    assert_eq!(
        links("see [a](b.md#c) and [d](e)"),
        vec![(1, "b.md#c".into()), (1, "e".into())]
    );
}
