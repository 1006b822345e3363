//! `.xacro` robots expanded natively (no Python, no `xacro` on PATH): the project's own
//! fixture, its errors, and the real xacro packages of ../shared/formats against Python's
//! `xacro` (PyPI) expansion of the same files.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::{root, settings, skip_without_shared};

/// Runs the binary in the repository root with PATH emptied (so that no `xacro` command can
/// be found) and `env` set; returns the snapshot text.
fn run_without_path(args: &[&str], env: &[(&str, &Path)]) -> (i32, String, String) {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_urdf-dh"));
    cmd.args(args)
        .current_dir(root())
        .env("PATH", "/nonexistent")
        .env_remove("ROS_PACKAGE_PATH")
        .env_remove("AMENT_PREFIX_PATH");
    for (k, v) in env {
        cmd.env(k, v);
    }
    let out = cmd.output().expect("run urdf-dh");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn snap(r: (i32, String, String)) -> String {
    format!("exit: {}\n--- stdout\n{}--- stderr\n{}", r.0, r.1, r.2)
}

const ARM: &str = "fixtures/xacro/demo_arm_description/urdf/arm.urdf.xacro";
const ARM_PKG: &str = "--package=demo_arm_description=fixtures/xacro/demo_arm_description";

/// The README's example: the fixture package with an argument, a package folder, an include,
/// a YAML file, block parameters and a conditional, without Python.
#[test]
fn xacro_fixture_expands_natively() {
    let _s = settings().bind_to_scope();
    insta::assert_snapshot!(snap(run_without_path(
        &[
            "extract",
            ARM,
            ARM_PKG,
            "--xacro-arg",
            "reach:=long",
            "--tip",
            "flange"
        ],
        &[]
    )));
}

/// The argument changes the table: the default reach is shorter.
#[test]
fn xacro_arguments_change_the_robot() {
    let long = run_without_path(
        &[
            "extract",
            ARM,
            ARM_PKG,
            "--xacro-arg",
            "reach:=long",
            "--format",
            "json",
        ],
        &[],
    );
    let short = run_without_path(&["extract", ARM, ARM_PKG, "--format", "json"], &[]);
    assert_eq!((long.0, short.0), (0, 0), "{}{}", long.2, short.2);
    let a2 = |text: &str| -> f64 {
        let v: serde_json::Value = serde_json::from_str(text).unwrap();
        v["joints"][1]["a"].as_f64().unwrap()
    };
    assert_eq!(a2(&long.1), 0.6);
    assert_eq!(a2(&short.1), 0.45);
}

/// The package found through ROS_PACKAGE_PATH instead of --package.
#[test]
fn xacro_packages_come_from_ros_package_path() {
    let (code, out, err) = run_without_path(
        &["extract", ARM, "--format", "json"],
        &[("ROS_PACKAGE_PATH", &root().join("fixtures/xacro"))],
    );
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("\"robot\": \"demo_arm\""), "{out}");
}

/// Errors exit 2 naming the file and line; malformed options are refused.
#[test]
fn xacro_errors_name_file_and_line() {
    let _s = settings().bind_to_scope();
    insta::assert_snapshot!(
        "xacro_missing_package",
        snap(run_without_path(&["extract", ARM], &[]))
    );
    insta::assert_snapshot!(
        "xacro_bad_argument",
        snap(run_without_path(
            &["extract", ARM, ARM_PKG, "--xacro-arg", "reach=long"],
            &[]
        ))
    );
}

/// A manifest entry of ../shared/formats for a xacro file.
struct Entry {
    id: String,
    file: PathBuf,
    base: String,
    tip: String,
    args: Vec<String>,
    ros_package_path: Vec<PathBuf>,
}

fn entries(formats: &Path) -> Vec<Entry> {
    let text = std::fs::read_to_string(formats.join("manifest.json")).unwrap();
    let manifest: serde_json::Value = serde_json::from_str(&text).unwrap();
    let strings = |v: &serde_json::Value| -> Vec<String> {
        v.as_array()
            .map(|a| {
                a.iter()
                    .filter_map(|s| s.as_str().map(String::from))
                    .collect()
            })
            .unwrap_or_default()
    };
    manifest["models"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| m["format"] == "xacro")
        .map(|m| Entry {
            id: m["id"].as_str().unwrap().to_string(),
            file: formats.join(m["file"].as_str().unwrap()),
            base: m["base"].as_str().unwrap().to_string(),
            tip: m["tip"].as_str().unwrap().to_string(),
            args: strings(&m["xacro_args"]),
            ros_package_path: strings(&m["ros_package_path"])
                .iter()
                .map(|p| formats.join(p))
                .collect(),
        })
        .collect()
}

/// `extract --format json` of `robot` (the entry's chain and xacro arguments).
fn extract_json(robot: &Path, e: &Entry) -> serde_json::Value {
    let mut args: Vec<String> = vec![
        "extract".into(),
        robot.display().to_string(),
        "--base".into(),
        e.base.clone(),
        "--tip".into(),
        e.tip.clone(),
        "--format".into(),
        "json".into(),
    ];
    for a in &e.args {
        args.push(format!("--xacro-arg={a}"));
    }
    let rpp = std::env::join_paths(&e.ros_package_path).unwrap();
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let (code, out, err) = run_without_path(&refs, &[("ROS_PACKAGE_PATH", Path::new(&rpp))]);
    assert_eq!(code, 0, "{}: {err}", e.id);
    serde_json::from_str(&out).unwrap()
}

/// Python's xacro command: $URDF_DH_XACRO, else `xacro` on PATH; `None` when neither runs.
fn python_xacro() -> Option<PathBuf> {
    let cmd = std::env::var_os("URDF_DH_XACRO")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("xacro"));
    let runs = Command::new(&cmd)
        .arg("--help")
        .output()
        .is_ok_and(|o| o.status.success());
    runs.then_some(cmd)
}

/// Two extractions' JSON equal: strings equal (warnings without the file name that starts
/// them), numbers equal to 1e-12 relative (the URDFs are the same text, so in practice they
/// are the same bits).
fn same(a: &serde_json::Value, b: &serde_json::Value, at: &str) -> Result<(), String> {
    use serde_json::Value as V;
    match (a, b) {
        (V::Number(x), V::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            if (x - y).abs() > 1e-12 * x.abs().max(y.abs()).max(1.0) {
                return Err(format!("{at}: {x} natively, {y} by Python's xacro"));
            }
            Ok(())
        }
        (V::Object(x), V::Object(y)) => {
            let keys = |o: &serde_json::Map<String, V>| o.keys().cloned().collect::<Vec<_>>();
            if keys(x) != keys(y) {
                return Err(format!("{at}: keys {:?} against {:?}", keys(x), keys(y)));
            }
            x.iter()
                .try_for_each(|(k, v)| same(v, &y[k], &format!("{at}.{k}")))
        }
        (V::Array(x), V::Array(y)) if x.len() == y.len() => x
            .iter()
            .zip(y)
            .enumerate()
            .try_for_each(|(i, (p, q))| same(p, q, &format!("{at}[{i}]"))),
        (V::String(x), V::String(y)) => {
            let tail = |s: &str| {
                s.split_once(": ")
                    .map_or(s.to_string(), |(_, t)| t.to_string())
            };
            if x != y && tail(x) != tail(y) {
                return Err(format!("{at}: '{x}' against '{y}'"));
            }
            Ok(())
        }
        _ if a == b => Ok(()),
        _ => Err(format!("{at}: {a} against {b}")),
    }
}

/// ../shared/formats: every real xacro top file expands natively (PATH without `xacro`) and
/// its DH table equals the table of Python's `xacro` expansion of the same file (PyPI xacro
/// with the ament shim of ../shared/formats/tools), when that command is installed.
#[test]
fn xacro_corpus_matches_python_xacro() {
    let Some(shared) = skip_without_shared("xacro corpus") else {
        return;
    };
    let formats = shared.join("formats");
    let list = entries(&formats);
    assert_eq!(list.len(), 18, "the manifest's xacro entries");
    let python = python_xacro();
    if python.is_none() {
        test_skips::skip(
            "Python's xacro is not installed (pip install xacro pyyaml, or set URDF_DH_XACRO): native expansions checked, the comparison with Python's not made",
        );
    }
    let dir = tempfile::tempdir().unwrap();
    let shim = formats.join("tools/ament_index_shim");
    let failures: Vec<String> = std::thread::scope(|s| {
        let handles: Vec<_> = list
            .chunks(list.len().div_ceil(3))
            .map(|chunk| {
                let (python, dir, shim) = (python.as_ref(), dir.path(), &shim);
                s.spawn(move || {
                    let mut failures = Vec::new();
                    for e in chunk {
                        let native = extract_json(&e.file, e);
                        let Some(py) = python else { continue };
                        let out = Command::new(py)
                            .arg(&e.file)
                            .args(&e.args)
                            .env(
                                "ROS_PACKAGE_PATH",
                                std::env::join_paths(&e.ros_package_path).unwrap(),
                            )
                            .env("PYTHONPATH", shim)
                            .output()
                            .unwrap();
                        assert!(
                            out.status.success(),
                            "{}: {}",
                            e.id,
                            String::from_utf8_lossy(&out.stderr)
                        );
                        let urdf = dir.join(format!("{}.urdf", e.id));
                        std::fs::write(&urdf, &out.stdout).unwrap();
                        if let Err(d) = same(&native, &extract_json(&urdf, e), &e.id) {
                            failures.push(d);
                        }
                    }
                    failures
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap())
            .collect()
    });
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A construct the native expansion refuses is handed to the `xacro` command when it is on
/// PATH, with a warning naming it; without one it is an error naming it.
#[test]
fn xacro_refused_construct_falls_back_to_python_xacro() {
    const FILE: &str = "fixtures/xacro/comprehension.urdf.xacro";
    let (code, out, err) = run_without_path(&["extract", FILE], &[]);
    assert_eq!(code, 2);
    assert!(out.is_empty());
    assert_eq!(
        err,
        "urdf-dh: error: comprehension.urdf.xacro: line 10: comprehensions are not supported by the native xacro expansion in '${[mm * 0.001 for mm in [400, 300]]}' (property 'lengths' of comprehension.urdf.xacro: line 5), and the 'xacro' command is not on PATH\nhint: install it with 'pip install xacro', or expand the file yourself: xacro fixtures/xacro/comprehension.urdf.xacro > robot.urdf\n"
    );
    // A stand-in `xacro` on PATH that prints the URDF Python's xacro gives.
    let dir = tempfile::tempdir().unwrap();
    let script = dir.path().join("xacro");
    std::fs::write(
        &script,
        "#!/bin/sh\n/bin/cat <<'X'\n<robot name=\"comprehension\"><link name=\"base\"/><link name=\"l1\"/><link name=\"tip\"/>\n<joint name=\"j1\" type=\"revolute\"><parent link=\"base\"/><child link=\"l1\"/><origin xyz=\"0 0 0\"/><axis xyz=\"0 0 1\"/><limit lower=\"-3\" upper=\"3\" effort=\"1\" velocity=\"1\"/></joint>\n<joint name=\"j2\" type=\"revolute\"><parent link=\"l1\"/><child link=\"tip\"/><origin xyz=\"0.4 0 0\"/><axis xyz=\"0 0 1\"/><limit lower=\"-3\" upper=\"3\" effort=\"1\" velocity=\"1\"/></joint></robot>\nX\n",
    )
    .unwrap();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&script, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    let out = Command::new(env!("CARGO_BIN_EXE_urdf-dh"))
        .args(["extract", FILE, "--format", "json"])
        .current_dir(root())
        .env("PATH", dir.path())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert_eq!(
        stderr,
        "urdf-dh: warning: comprehension.urdf.xacro: line 10: comprehensions are not supported by the native xacro expansion in '${[mm * 0.001 for mm in [400, 300]]}' (property 'lengths' of comprehension.urdf.xacro: line 5); expanded with Python's 'xacro' command instead\n"
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["joints"][0]["a"].as_f64(), Some(0.4));
}

/// `--xacro-arg` / `--package` reach the other commands that read a robot: `simulate --model`,
/// `check`, `batch` and `calibrate --model` on the fixture package.
#[test]
fn xacro_flags_reach_every_robot_reading_command() {
    let dir = tempfile::tempdir().unwrap();
    let (csv, truth, list) = (
        dir.path().join("m.csv"),
        dir.path().join("truth.yaml"),
        dir.path().join("chains.list"),
    );
    let (csv, truth) = (csv.to_str().unwrap(), truth.to_str().unwrap());
    let long = ["--xacro-arg", "reach:=long", ARM_PKG, "--tip", "flange"];
    let with = |args: &[&str]| -> Vec<String> {
        args.iter()
            .chain(long.iter())
            .map(|s| s.to_string())
            .collect()
    };
    let go = |args: Vec<String>| {
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, out, err) = run_without_path(&refs, &[]);
        assert_eq!(code, 0, "urdf-dh {}: {err}", args.join(" "));
        out
    };
    go(with(&[
        "simulate", "--model", ARM, "--poses", "20", "--noise", "1e-5", "--seed", "3", "--out",
        csv, "--truth", truth,
    ]));
    let report = go(with(&["check", ARM, "--sheet", truth]));
    assert!(report.contains("MATCH"), "{report}");
    let report = go(with(&["calibrate", "--model", ARM, "--data", csv]));
    assert!(report.contains("result: RMS"), "{report}");
    std::fs::write(&list, format!("{}\n", root().join(ARM).display())).unwrap();
    let lines = go(vec![
        "batch".into(),
        list.display().to_string(),
        "--xacro-arg".into(),
        "reach:=long".into(),
        ARM_PKG.into(),
    ]);
    let row: serde_json::Value = serde_json::from_str(lines.lines().next().unwrap()).unwrap();
    assert_eq!(row["sheet"]["robot"], "demo_arm", "{lines}");
    assert_eq!(
        row["sheet"]["joints"][1]["a"].as_f64(),
        Some(0.6),
        "{lines}"
    );
}
