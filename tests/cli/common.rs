//! Helpers shared by the CLI tests.

use std::io::Write;
use std::path::PathBuf;
use std::process::{Command, Stdio};

/// The workspace root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// `../shared` beside the checkout, when it is there.
pub fn shared() -> Option<PathBuf> {
    let p = root().join("../shared");
    p.is_dir().then_some(p)
}

/// `../shared`, or `None` after recording the skip of the check `test` names
/// ([`test_skips::skip`]: shown past the harness's capture, listed by tests/run.sh).
pub fn skip_without_shared(test: &str) -> Option<PathBuf> {
    let s = shared();
    if s.is_none() {
        test_skips::skip(&format!(
            "{test}: ../shared (real URDFs and measurements written by others) is absent"
        ));
    }
    s
}

/// Runs the binary with `args` (and `stdin`), returning "exit: N", stdout and stderr as one
/// text for a snapshot.
pub fn run(args: &[&str], stdin: Option<&[u8]>) -> String {
    let mut child = Command::new(env!("CARGO_BIN_EXE_urdf-dh"))
        .args(args)
        .current_dir(root())
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn urdf-dh");
    {
        let mut pipe = child.stdin.take().expect("stdin");
        if let Some(bytes) = stdin {
            pipe.write_all(bytes).expect("write stdin");
        }
    }
    let out = child.wait_with_output().expect("wait");
    format!(
        "exit: {}\n--- stdout\n{}--- stderr\n{}",
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// The exit code alone.
pub fn exit_code(args: &[&str]) -> i32 {
    Command::new(env!("CARGO_BIN_EXE_urdf-dh"))
        .args(args)
        .current_dir(root())
        .stdin(Stdio::null())
        .output()
        .expect("run urdf-dh")
        .status
        .code()
        .unwrap_or(-1)
}

/// Fixture robot ids (folders of `fixtures/robots`).
pub fn fixture_robots() -> Vec<String> {
    let mut ids: Vec<String> = std::fs::read_dir(root().join("fixtures/robots"))
        .expect("fixtures/robots")
        .filter_map(|e| e.ok())
        .filter(|e| e.path().join("robot.urdf").is_file())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    ids.sort();
    ids
}

/// Snapshot settings: floating-point noise in verification figures (machine-dependent last
/// digits) is redacted; the tests assert those figures against their bounds separately.
pub fn settings() -> insta::Settings {
    let mut s = insta::Settings::clone_current();
    s.add_filter(
        r"(max_position_error|max_orientation_error)(\W+)[0-9.e+-]+",
        "$1$2[noise]",
    );
    s.add_filter(
        r"(max position error|max orientation error) [0-9.e+-]+",
        "$1 [noise]",
    );
    s
}

/// Runs the binary in the repository root; returns (exit code, stdout, stderr).
pub fn exec(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_urdf-dh"))
        .args(args)
        .current_dir(root())
        .output()
        .expect("run urdf-dh");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Runs the binary, asserts exit 0 (showing stderr otherwise) and returns stdout.
pub fn ok(args: &[&str]) -> String {
    let (code, out, err) = exec(args);
    assert_eq!(code, 0, "urdf-dh {}: exit {code}\n{err}", args.join(" "));
    out
}

/// The robot folders of `shared/<folder>` that hold a `robot.urdf`, sorted.
pub fn robot_dirs(shared: &std::path::Path, folder: &str) -> Vec<PathBuf> {
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(shared.join(folder))
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| p.join("robot.urdf").is_file())
        .collect();
    dirs.sort();
    dirs
}

/// One real chain: (label, URDF, base link, tip link).
pub type CorpusChain = (String, PathBuf, String, String);

/// Every real chain: `shared/robots` from the root link to every leaf with a moving joint on
/// the way, and the chains of `shared/robots-ext/manifest.json` (less the files it expects to be
/// refused).
pub fn corpus_chains(shared: &std::path::Path) -> Vec<CorpusChain> {
    let mut out = Vec::new();
    for dir in robot_dirs(shared, "robots") {
        let id = dir.file_name().unwrap().to_string_lossy().into_owned();
        let urdf = dir.join("robot.urdf");
        let model = urdf_axes::UrdfModel::from_bytes(&std::fs::read(&urdf).unwrap())
            .unwrap_or_else(|e| panic!("{id}: {e}"));
        let root = model.root_link().to_string();
        for leaf in model.leaves() {
            let moving = model
                .chain(Some(&root), Some(leaf))
                .map_or(0, |c| c.axes().len());
            if moving > 0 {
                let label = format!("robots/{id} -> {leaf}");
                out.push((label, urdf.clone(), root.clone(), leaf.to_string()));
            }
        }
    }
    let manifest: serde_json::Value =
        serde_json::from_slice(&std::fs::read(shared.join("robots-ext/manifest.json")).unwrap())
            .unwrap();
    for c in manifest["chains"].as_array().unwrap() {
        if c["expect"].as_str() == Some("refuse") {
            continue;
        }
        let field = |k: &str| c[k].as_str().unwrap().to_string();
        let urdf = shared
            .join("robots-ext")
            .join(field("robot"))
            .join("robot.urdf");
        out.push((
            format!("robots-ext/{}", field("id")),
            urdf,
            field("base"),
            field("tip"),
        ));
    }
    out
}

/// `(column name -> cell)` rows of CSV text written by the tool (its `#` comment lines left
/// out; names and cells without quoted commas).
pub fn csv_rows(text: &str) -> Vec<std::collections::HashMap<String, String>> {
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    lines
        .map(|l| {
            header
                .iter()
                .cloned()
                .zip(l.split(',').map(String::from))
                .collect()
        })
        .collect()
}

/// Asserts that the library's calibration ([`dh_workflows::calibration::run`]) of `model` against
/// `data` (with `validate`) gives the JSON report the command line printed (`json`) and, when
/// `out` names the file the command line wrote, the same calibrated model, byte for byte.
pub fn assert_library_calibrates_as_the_cli(
    model: &str,
    data: &str,
    validate: Option<&str>,
    out: Option<&str>,
    json: &str,
) {
    let mut request = dh_workflows::calibration::CalibrationRequest::new(Some(model.into()), data);
    request.validate = validate.map(Into::into);
    request.out = out.map(Into::into);
    let mut warnings = Vec::new();
    let mut calibrated = dh_workflows::calibration::run(&request, &mut warnings).unwrap();
    if let Some(path) = out {
        let written = calibrated
            .model_file(path, Some(model), &mut warnings)
            .unwrap()
            .expect("the model passes its proof");
        assert_eq!(written, std::fs::read_to_string(path).unwrap(), "{path}");
    }
    assert!(calibrated.proved());
    assert_eq!(calibrated.json().unwrap(), json);
}

/// Runs `urdf-dh simulate --model MODEL --poses POSES --out OUT` with `options` (noise,
/// targets, planted errors and effects, seed, truth file), asserting exit 0: the simulated sets
/// the calibration tests start from. Returns stdout.
pub fn simulate(model: &str, poses: &str, out: &str, options: &[&str]) -> String {
    let mut args = vec!["simulate", "--model", model, "--poses", poses, "--out", out];
    args.extend_from_slice(options);
    ok(&args)
}

/// Runs the CLI in process (no binary, no child process): (exit code, stdout, stderr).
pub fn cli(args: &[&str]) -> (i32, String, String) {
    let (mut out, mut err) = (Vec::new(), Vec::new());
    let mut argv = vec!["urdf-dh"];
    argv.extend_from_slice(args);
    let code = urdf_dh::cli::run(argv, &mut out, &mut err);
    (
        code,
        String::from_utf8_lossy(&out).into_owned(),
        String::from_utf8_lossy(&err).into_owned(),
    )
}
