//! Round trips over every real chain of `../shared/robots` and `../shared/robots-ext`, both
//! conventions, through the CLI in process: every output format of `extract` proves itself
//! (exit 0: the table as written was read back and verified); `extract` -> `to-urdf` ->
//! `extract` gives the same table; `convert` to the other convention and back is the identity.
//! Needs ../shared; skips with a reason without it.

use crate::common::{cli, corpus_chains, robot_dirs, skip_without_shared};

/// Joint-value samples per check: enough to catch a wrong table, few enough for 558 tables.
const SAMPLES: &str = "100";
/// Two tables are the same when every length agrees to this (metres)...
const SAME_LENGTH: f64 = 1e-9;
/// ... and every angle to this (radians).
const SAME_ANGLE: f64 = 1e-9;

/// `t` with the pair of DH values that a change of convention moves into a transform folded
/// into it: a standard table's last `a`, `alpha` into the tool; a modified table's first `alpha`,
/// `a` into the base. Converting there and back keeps everything else, and this, exactly.
fn folded(t: &dh_core::DhTable) -> dh_core::DhTable {
    use dh_core::pose::{rot_x, trans_x};
    let mut t = t.clone();
    match t.convention {
        dh_core::Convention::Standard => {
            if let Some(last) = t.rows.last_mut() {
                t.tool = trans_x(last.a) * rot_x(last.alpha) * t.tool;
                (last.a, last.alpha) = (0.0, 0.0);
            }
        }
        dh_core::Convention::Modified => {
            if let Some(first) = t.rows.first_mut() {
                t.base = t.base * rot_x(first.alpha) * trans_x(first.a);
                (first.a, first.alpha) = (0.0, 0.0);
            }
        }
    }
    t
}

fn table(yaml: &str) -> dh_core::DhTable {
    dh_workflows::sheet::Sheet::parse(yaml, "output")
        .unwrap()
        .table
}

/// Where two tables differ beyond [`SAME_LENGTH`] / [`SAME_ANGLE`], if anywhere.
fn differs(a: &dh_core::DhTable, b: &dh_core::DhTable) -> Option<String> {
    let angle = |x: f64, y: f64| {
        let d = (x - y).rem_euclid(std::f64::consts::TAU);
        d.min(std::f64::consts::TAU - d)
    };
    if a.rows.len() != b.rows.len() {
        return Some(format!("{} rows vs {}", a.rows.len(), b.rows.len()));
    }
    for (r, s) in a.rows.iter().zip(&b.rows) {
        let worst_len = (r.a - s.a).abs().max((r.d - s.d).abs());
        let worst_ang = angle(r.alpha, s.alpha).max(angle(r.theta, s.theta));
        if r.name != s.name || r.kind != s.kind || worst_len > SAME_LENGTH || worst_ang > SAME_ANGLE
        {
            return Some(format!("row {}: {r:?} vs {s:?}", r.name));
        }
    }
    for (what, p, q) in [("base", &a.base, &b.base), ("tool", &a.tool, &b.tool)] {
        let (dp, dr) = dh_core::pose::pose_error(p, q);
        if dp > SAME_LENGTH || dr > SAME_ANGLE {
            return Some(format!("{what} differs by {dp:.1e} m, {dr:.1e} rad"));
        }
    }
    None
}

#[test]
fn every_real_chain_round_trips_in_every_format() {
    let Some(shared) = skip_without_shared("round trips") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let mut all = corpus_chains(&shared);
    // The reproductions of defects: rounded URDF angles with a tool near pitch ±90°,
    // antiparallel and coincident axes (chain base -> tip).
    let repro = robot_dirs(&shared, "repro");
    assert!(
        repro.len() >= 4,
        "expected the repro cases, found {}",
        repro.len()
    );
    for dir in repro {
        let id = format!("repro/{}", dir.file_name().unwrap().to_string_lossy());
        all.push((id, dir.join("robot.urdf"), "base".into(), "tip".into()));
    }
    assert!(
        all.len() >= 300,
        "expected both corpora, found {} chains",
        all.len()
    );
    let mut failures = Vec::new();
    let mut tables = 0;
    for (id, urdf, base, tip) in &all {
        let urdf = urdf.to_str().unwrap();
        for convention in ["standard", "modified"] {
            let id = format!("{id} ({convention})");
            let common = [
                "extract",
                urdf,
                "--base",
                base,
                "--tip",
                tip,
                "--convention",
                convention,
                "--samples",
                SAMPLES,
            ];
            // Every format proves the table it writes.
            for (format, units) in [
                ("yaml", ["m", "rad"]),
                ("json", ["mm", "deg"]),
                ("csv", ["m", "deg"]),
                ("text", ["m", "rad"]),
                ("text", ["mm", "deg"]),
                ("markdown", ["mm", "deg"]),
            ] {
                let mut args = common.to_vec();
                args.extend([
                    "--format",
                    format,
                    "--length-unit",
                    units[0],
                    "--angle-unit",
                    units[1],
                ]);
                let (code, out, err) = cli(&args);
                if code != 0
                    || !(out.contains("passed: true")
                        || out.contains("\"passed\": true")
                        || out.contains(": PASS")
                        || format == "csv")
                {
                    failures.push(format!(
                        "{id} {format} {units:?}: exit {code}: {}",
                        err.lines().last().unwrap_or("")
                    ));
                }
            }
            let mut args = common.to_vec();
            args.extend(["--format", "yaml"]);
            let (code, yaml, err) = cli(&args);
            if code != 0 {
                failures.push(format!("{id}: extract exit {code}: {err}"));
                continue;
            }
            tables += 1;
            let sheet = dir.path().join("sheet.yaml");
            std::fs::write(&sheet, &yaml).unwrap();
            let sheet = sheet.to_str().unwrap();
            let extracted = table(&yaml);

            // extract -> to-urdf -> extract: the same table.
            let (code, written, err) = cli(&[
                "to-urdf",
                sheet,
                "--base-link",
                "rt_base",
                "--tip-link",
                "rt_tip",
                "--samples",
                SAMPLES,
            ]);
            if code != 0 {
                failures.push(format!("{id}: to-urdf exit {code}: {err}"));
            } else {
                let path = dir.path().join("written.urdf");
                std::fs::write(&path, written).unwrap();
                let (code, again, err) = cli(&[
                    "extract",
                    path.to_str().unwrap(),
                    "--base",
                    "rt_base",
                    "--tip",
                    "rt_tip",
                    "--convention",
                    convention,
                    "--format",
                    "yaml",
                    "--samples",
                    SAMPLES,
                ]);
                if code != 0 {
                    failures.push(format!(
                        "{id}: extract of to-urdf's URDF exit {code}: {err}"
                    ));
                } else if let Some(d) = differs(&extracted, &table(&again)) {
                    failures.push(format!("{id}: extract -> to-urdf -> extract: {d}"));
                }
            }

            // convert there and back: the identity.
            let other = if convention == "standard" {
                "modified"
            } else {
                "standard"
            };
            let (code, there, err) = cli(&["convert", sheet, "--to", other, "--samples", SAMPLES]);
            if code != 0 {
                failures.push(format!("{id}: convert exit {code}: {err}"));
                continue;
            }
            let there_path = dir.path().join("there.yaml");
            std::fs::write(&there_path, there).unwrap();
            let (code, back, err) = cli(&[
                "convert",
                there_path.to_str().unwrap(),
                "--to",
                convention,
                "--samples",
                SAMPLES,
            ]);
            if code != 0 {
                failures.push(format!("{id}: convert back exit {code}: {err}"));
            } else if let Some(d) = differs(&folded(&extracted), &folded(&table(&back))) {
                failures.push(format!("{id}: convert there and back: {d}"));
            }
        }
    }
    println!(
        "round trips: {tables} tables extracted, {} failures",
        failures.len()
    );
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
