//! `batch`: many chains in one process, each table the one `extract --format json` proves.

use crate::common::{root, run};

#[test]
fn batch_writes_what_extract_writes_for_every_listed_chain() {
    let dir = tempfile::tempdir().unwrap();
    let robots = root().join("fixtures/robots");
    let list = dir.path().join("chains.list");
    std::fs::write(
        &list,
        format!(
            "# robot base tip\n{0}/ur5/robot.urdf\n{0}/franka_panda/robot.urdf base_link panda_link8  # trailing comment\n\n{0}/puma560/robot.urdf - -\n",
            robots.display()
        ),
    )
    .unwrap();
    let out = run(
        &["batch", list.to_str().unwrap(), "--convention", "both"],
        None,
    );
    assert!(out.starts_with("exit: 0\n"), "{out}");
    let stdout = out
        .split("--- stdout\n")
        .nth(1)
        .unwrap()
        .split("--- stderr\n")
        .next()
        .unwrap();
    let lines: Vec<serde_json::Value> = stdout
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 6, "three chains in two conventions");
    for line in &lines {
        let robot = line["robot"].as_str().unwrap();
        let convention = line["convention"].as_str().unwrap();
        let mut args = vec![
            "extract",
            robot,
            "--convention",
            convention,
            "--format",
            "json",
        ];
        for (key, flag) in [("base", "--base"), ("tip", "--tip")] {
            if let Some(v) = line[key].as_str() {
                args.extend([flag, v]);
            }
        }
        let single = run(&args, None);
        let json = single
            .split("--- stdout\n")
            .nth(1)
            .unwrap()
            .split("--- stderr\n")
            .next()
            .unwrap();
        let single: serde_json::Value = serde_json::from_str(json).unwrap();
        assert_eq!(line["sheet"], single, "{robot} {convention}");
        assert_eq!(line["sheet"]["verification"]["passed"], true);
    }
    assert!(
        out.contains("urdf-dh: batch: 6 tables: 6 proved, 0 failed their proof, 0 refused"),
        "{out}"
    );
}

#[test]
fn a_refused_chain_is_named_on_its_line_and_the_others_are_written() {
    let dir = tempfile::tempdir().unwrap();
    let list = dir.path().join("chains.list");
    std::fs::write(
        &list,
        format!(
            "{}/fixtures/robots/ur5/robot.urdf base_link nope\nmissing.urdf\n",
            root().display()
        ),
    )
    .unwrap();
    let out = run(&["batch", list.to_str().unwrap()], None);
    assert!(out.starts_with("exit: 2\n"), "{out}");
    assert!(out.contains("\"line\":1") && out.contains("nope"), "{out}");
    assert!(
        out.contains("\"line\":2") && out.contains("missing.urdf: cannot read the file"),
        "{out}"
    );
    assert!(
        out.contains("urdf-dh: error: 2 of 2 tables refused"),
        "{out}"
    );
    let empty = dir.path().join("empty.list");
    std::fs::write(&empty, "# nothing\n").unwrap();
    let out = run(&["batch", empty.to_str().unwrap()], None);
    assert!(
        out.starts_with("exit: 2\n") && out.contains("names no chain"),
        "{out}"
    );
}

#[test]
fn completions_and_the_manual_page_are_generated() {
    let bash = run(&["completions", "bash"], None);
    assert!(
        bash.starts_with("exit: 0\n") && bash.contains("urdf-dh") && bash.contains("batch"),
        "{bash}"
    );
    let man = run(&["man"], None);
    assert!(
        man.starts_with("exit: 0\n") && man.contains(".TH urdf-dh 1"),
        "{man}"
    );
    let help = run(&["extract", "--help"], None);
    assert!(
        help.contains("EXAMPLES:\n  urdf-dh extract robot.urdf"),
        "{help}"
    );
}

#[test]
fn random_errors_take_the_documented_length_comma_angle() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s.csv");
    let out = out.to_str().unwrap();
    let model = "fixtures/robots/ur5/vendor.yaml";
    let args = |errors: &'static str| {
        vec![
            "simulate",
            "--model",
            model,
            "--poses",
            "5",
            "--random-errors",
            errors,
            "--out",
            out,
        ]
    };
    let ok = run(&args("0.001,0.002"), None);
    assert!(ok.starts_with("exit: 0\n"), "{ok}");
    let four = run(&args("0.001,0.002,0.3,0.4"), None);
    assert!(
        four.starts_with("exit: 2\n") && four.contains("found 4 value(s)"),
        "{four}"
    );
}
