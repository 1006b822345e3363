//! `calibrate --report` and `cpa --report`: one self-contained HTML page, well-formed (parsed
//! as XML), offline (no address, no script), with the sections, the text report's figures, the
//! outliers ringed and listed, the provenance (SHA-256 of the inputs), and every name escaped.
//! Serial points, a tree and contacts each get a page; so does a circle-point analysis.

use std::path::Path;

use crate::common::{exec, ok, simulate};

const UR5: &str = "fixtures/robots/ur5/vendor.yaml";

fn path(dir: &Path, name: &str) -> String {
    dir.join(name).to_string_lossy().into_owned()
}

/// The page at `file`, checked for what every page must be: no network address, no script,
/// no NaN or infinity, well-formed XML; returns the text and its sections' `data-testid`s.
fn page(file: &str) -> (String, Vec<String>) {
    let html = std::fs::read_to_string(file).unwrap();
    assert!(html.starts_with("<!DOCTYPE html>"), "{}", &html[..40]);
    for forbidden in ["http://", "https://", "<script", "<link", "@import", "url("] {
        assert!(!html.contains(forbidden), "the page holds {forbidden}");
    }
    for number in [">NaN", " NaN", ">inf", "-inf", " inf<"] {
        assert!(!html.contains(number), "the page prints {number:?}");
    }
    let options = roxmltree::ParsingOptions {
        allow_dtd: true,
        ..roxmltree::ParsingOptions::default()
    };
    let doc = roxmltree::Document::parse_with_options(&html, options)
        .unwrap_or_else(|e| panic!("{file} is not well-formed: {e}"));
    let sections = doc
        .descendants()
        .filter(|n| n.has_tag_name("section"))
        .filter_map(|n| n.attribute("data-testid").map(String::from))
        .collect();
    (html, sections)
}

/// Asserts that the page's `sections` (their ids) include every one of `wanted`.
fn has_sections(sections: &[String], wanted: &[&str]) {
    for s in wanted {
        assert!(
            sections.iter().any(|x| x == s),
            "no section {s}: {sections:?}"
        );
    }
}

/// The text of every cell of the rows of the tables of section `id`, row by row.
fn rows(html: &str, id: &str) -> Vec<Vec<String>> {
    let options = roxmltree::ParsingOptions {
        allow_dtd: true,
        ..roxmltree::ParsingOptions::default()
    };
    let doc = roxmltree::Document::parse_with_options(html, options).unwrap();
    let section = doc
        .descendants()
        .find(|n| n.attribute("data-testid") == Some(id))
        .unwrap_or_else(|| panic!("no section {id}"));
    section
        .descendants()
        .filter(|n| n.has_tag_name("tr"))
        .map(|tr| {
            tr.children()
                .filter(|c| c.has_tag_name("td"))
                .map(|td| {
                    td.descendants()
                        .filter(|d| d.is_text())
                        .filter_map(|d| d.text())
                        .collect::<String>()
                })
                .collect::<Vec<String>>()
        })
        .filter(|r| !r.is_empty())
        .collect()
}

/// A simulated UR5 set (60 poses, two targets, a quarter held out) with the `x` of two samples
/// moved by 4 mm: outliers at the file lines returned.
fn ur5_with_outliers(dir: &Path) -> (String, Vec<usize>) {
    let data = path(dir, "ur5.csv");
    simulate(
        UR5,
        "60",
        &data,
        &[
            "--noise",
            "5e-5",
            "--targets",
            "2",
            "--seed",
            "3",
            "--validation",
            "0.25",
            "--error",
            "elbow_joint.a=5e-4",
        ],
    );
    let text = std::fs::read_to_string(&data).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let header = lines
        .iter()
        .position(|l| l.starts_with("shoulder_pan_joint"))
        .unwrap();
    let x = lines[header].split(',').position(|c| c == "x").unwrap();
    let moved = vec![header + 12, header + 43];
    for &k in &moved {
        let mut cells: Vec<String> = lines[k].split(',').map(String::from).collect();
        cells[x] = (cells[x].parse::<f64>().unwrap() + 0.004).to_string();
        lines[k] = cells.join(",");
    }
    std::fs::write(&data, lines.join("\n") + "\n").unwrap();
    // 1-based file lines.
    (data, moved.iter().map(|k| k + 1).collect())
}

/// The numbers of the text report's step row `label` (metres).
fn step_row(text: &str, label: &str) -> Vec<f64> {
    let line = text
        .lines()
        .find(|l| l.split_whitespace().next() == Some(label))
        .unwrap_or_else(|| panic!("no step {label} in\n{text}"));
    line.split_whitespace()
        .skip(3)
        .map(|v| v.parse().unwrap())
        .collect()
}

#[test]
fn calibrate_report_has_the_text_reports_figures_outliers_and_provenance() {
    let dir = tempfile::tempdir().unwrap();
    let (data, moved) = ur5_with_outliers(dir.path());
    let report = path(dir.path(), "report.html");
    let text = ok(&[
        "calibrate",
        "--model",
        UR5,
        "--data",
        &data,
        "--effects",
        "auto",
        "--report",
        &report,
    ]);
    let (html, sections) = page(&report);
    has_sections(
        &sections,
        &[
            "summary",
            "steps",
            "residuals",
            "outliers",
            "diagnosis",
            "parameters",
            "correlations",
            "verdict",
            "settings",
            "provenance",
        ],
    );
    // The steps: RMS, mean, max and validation figures are the text report's, in mm.
    let steps = rows(&html, "steps");
    for label in ["nominal", "geometric"] {
        let text_row = step_row(&text, label);
        let row = steps.iter().find(|r| r[0] == label).unwrap();
        // Text: rms mean max val_rms val_mean val_max (m); page: rms mean max at 4..7 and
        // val_rms val_mean val_max at 8..11 (mm).
        let page: Vec<f64> = [4, 5, 6, 8, 9, 10]
            .iter()
            .map(|&k| row[k].parse().unwrap())
            .collect();
        for (p, t) in page.iter().zip(&text_row) {
            assert!((p - t * 1e3).abs() < 1e-9, "{label}: {p} mm against {t} m");
        }
    }
    // The outliers: both moved samples listed with their size in sigma, and ringed in every
    // residual plot (two pose-order plots and one per joint).
    let outliers = rows(&html, "outliers");
    let listed: Vec<usize> = outliers.iter().map(|r| r[0].parse().unwrap()).collect();
    assert_eq!(listed, moved, "{outliers:?}");
    for r in &outliers {
        let sigmas: f64 = r[5].parse().unwrap();
        assert!(sigmas > 50.0, "{r:?}");
        assert!(text.contains(&format!("line {}, ", r[0])), "{text}");
        assert!(text.contains(&format!("{} sigma", r[5])), "{text}");
    }
    let rings = html.matches("<circle cx=").count();
    assert!(rings >= 2 * (2 + 6), "{rings} outlier rings");
    assert!(html.contains("outlier(s) beyond the axis"));
    // The verdict and the condition number, as the text says them.
    assert!(text.contains("verdict: model complete"), "{text}");
    assert!(html.contains("<p class=\"big\">model complete</p>"));
    let condition = text
        .split("condition number ")
        .nth(1)
        .and_then(|t| t.split(',').next())
        .unwrap();
    let condition: f64 = condition.parse().unwrap();
    assert!(html.contains(&format!("{condition:.3e}")), "{condition}");
    // The most correlated pairs: largest first, each within [-1, 1], never two setup
    // parameters (device frame, targets).
    let pairs = rows(&html, "correlations");
    assert!(pairs.len() >= 5, "{pairs:?}");
    let r: Vec<f64> = pairs
        .iter()
        .map(|p| p[2].parse::<f64>().unwrap().abs())
        .collect();
    assert!(r.windows(2).all(|w| w[0] >= w[1]) && r[0] <= 1.0, "{r:?}");
    let setup = |n: &str| n.starts_with("device.") || n.starts_with("target.");
    assert!(
        pairs.iter().all(|p| !(setup(&p[0]) && setup(&p[1]))),
        "{pairs:?}"
    );
    // Provenance: the data's SHA-256 and size, the command line.
    let bytes = std::fs::read(&data).unwrap();
    let sha = dh_workflows::report_html::sha256_hex(&bytes);
    assert!(html.contains(&sha), "no {sha}");
    assert!(html.contains(&format!("<td class=\"n\">{}</td>", bytes.len())));
    assert!(html.contains("urdf-dh calibrate --model fixtures/robots/ur5/vendor.yaml"));
    assert!(html.contains(&format!("urdf-dh {}", env!("CARGO_PKG_VERSION"))));
}

#[test]
fn hostile_names_are_escaped_in_the_report() {
    let dir = tempfile::tempdir().unwrap();
    let hostile = "<img src=x onerror=alert(1)>&\"'";
    let sheet = std::fs::read_to_string(UR5)
        .unwrap()
        .replace("elbow_joint", "elbow<script>alert(1)</script>");
    let model = path(dir.path(), "m<b>&'\".yaml");
    std::fs::write(&model, sheet).unwrap();
    let data = path(dir.path(), "d<i>.csv");
    simulate(&model, "20", &data, &["--seed", "2", "--targets", "1"]);
    let text = std::fs::read_to_string(&data)
        .unwrap()
        .replace(",t1,", &format!(",{},", hostile.replace('"', "")));
    std::fs::write(&data, text).unwrap();
    let report = path(dir.path(), "r.html");
    ok(&[
        "calibrate",
        "--model",
        &model,
        "--data",
        &data,
        "--report",
        &report,
    ]);
    let (html, _) = page(&report);
    for raw in ["<script>alert", "<img src", "<b>&", "<i>.csv"] {
        assert!(!html.contains(raw), "unescaped {raw}");
    }
    assert!(html.contains("elbow&lt;script&gt;alert(1)&lt;/script&gt;"));
    assert!(html.contains("m&lt;b&gt;&amp;&#39;&quot;.yaml"));
    assert!(html.contains("&lt;img src=x onerror=alert(1)&gt;&amp;&#39;"));
}

#[test]
fn cpa_report_has_the_circles_the_points_left_out_and_the_table() {
    let dir = tempfile::tempdir().unwrap();
    let data = path(dir.path(), "cpa.csv");
    simulate(
        UR5,
        "8",
        &data,
        &["--cpa", "--noise", "2e-5", "--seed", "4"],
    );
    // One point of the second sweep moved by 3 mm: the screen leaves it out.
    let text = std::fs::read_to_string(&data).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let header = lines
        .iter()
        .position(|l| l.starts_with("shoulder_pan_joint"))
        .unwrap();
    let z = lines[header].split(',').position(|c| c == "z").unwrap();
    let k = header + 12;
    let mut cells: Vec<String> = lines[k].split(',').map(String::from).collect();
    cells[z] = (cells[z].parse::<f64>().unwrap() + 0.003).to_string();
    lines[k] = cells.join(",");
    std::fs::write(&data, lines.join("\n") + "\n").unwrap();
    let report = path(dir.path(), "cpa.html");
    let (code, out, err) = exec(&["cpa", &data, "--model", UR5, "--report", &report]);
    assert!(code == 0 || code == 1, "{err}");
    let (html, sections) = page(&report);
    has_sections(
        &sections,
        &[
            "summary",
            "sweeps",
            "joints",
            "residuals",
            "outliers",
            "table",
            "proof",
            "provenance",
        ],
    );
    let left_out = rows(&html, "outliers");
    assert_eq!(left_out.len(), 1, "{left_out:?}");
    assert_eq!(left_out[0][1], (k + 1).to_string());
    assert!(out.contains(&format!("line {}, target", k + 1)), "{out}");
    // The circle RMS of every joint as the text prints it (m, 6 decimals; the page: mm, 3).
    let joints = rows(&html, "joints");
    for j in ["shoulder_pan_joint", "elbow_joint", "wrist_3_joint"] {
        let line = out
            .lines()
            .find(|l| l.split_whitespace().next() == Some(j) && l.split_whitespace().count() == 8)
            .unwrap_or_else(|| panic!("{j} in\n{out}"));
        let circle: f64 = line.split_whitespace().nth(4).unwrap().parse().unwrap();
        let row = joints.iter().find(|r| r[0] == j).unwrap();
        let page: f64 = row[5].parse().unwrap();
        assert!(
            (page - circle * 1e3).abs() < 1e-9,
            "{j}: {page} against {circle}"
        );
    }
    // The table: six rows, the joints in order.
    let table = rows(&html, "table");
    assert_eq!(table[0][0], "shoulder_pan_joint");
    assert!(table.len() >= 6);
    // A plot per joint, the moved point ringed in one.
    assert!(html.matches("<svg ").count() >= 12);
    assert_eq!(html.matches("<circle cx=").count(), 1);
}

#[test]
fn contacts_and_trees_get_a_report() {
    let dir = tempfile::tempdir().unwrap();
    // Contacts.
    let data = path(dir.path(), "contacts.csv");
    crate::contacts::contacts(&data, 8, None, 5);
    let report = path(dir.path(), "contacts.html");
    ok(&[
        "calibrate",
        "--model",
        "fixtures/measured/mukca_panda/model.yaml",
        "--data",
        &data,
        "--report",
        &report,
    ]);
    let (html, sections) = page(&report);
    has_sections(
        &sections,
        &["summary", "steps", "residuals", "parameters", "provenance"],
    );
    assert!(html.contains("ball-in-socket"));
    // A tree.
    let nominal = path(dir.path(), "tree.yaml");
    std::fs::write(&nominal, crate::tree::tree_sheet(&[])).unwrap();
    let truth = dh_workflows::tree_sheet::TreeSheet::parse(
        &crate::tree::tree_sheet(&[("r2.a", 1e-3)]),
        "truth.yaml",
    )
    .unwrap();
    let data = path(dir.path(), "tree.csv");
    crate::tree::write_data(&truth, 30, 1, &data);
    let report = path(dir.path(), "tree.html");
    let text = ok(&[
        "calibrate",
        "--model",
        &nominal,
        "--data",
        &data,
        "--report",
        &report,
    ]);
    let (html, sections) = page(&report);
    has_sections(
        &sections,
        &[
            "summary",
            "steps",
            "tree",
            "parameters",
            "verdict",
            "provenance",
        ],
    );
    let steps = rows(&html, "steps");
    let geometric = steps.iter().find(|r| r[0] == "geometric").unwrap();
    let rms: f64 = geometric[4].parse().unwrap();
    let t = text
        .lines()
        .find(|l| l.trim_start().starts_with("geometric"))
        .unwrap();
    let text_rms: f64 = t.split_whitespace().nth(3).unwrap().parse().unwrap();
    assert!(
        (rms - text_rms * 1e3).abs() < 1e-9,
        "{rms} against {text_rms}\n{text}"
    );
    let tables = rows(&html, "tree");
    assert_eq!(
        tables.iter().map(|r| r[0].as_str()).collect::<Vec<_>>(),
        ["trunk", "r", "l"]
    );
}

#[test]
fn a_report_is_never_written_over_an_input_and_is_named_html() {
    let dir = tempfile::tempdir().unwrap();
    let (data, _) = ur5_with_outliers(dir.path());
    let before = std::fs::read(&data).unwrap();
    let (code, _, err) = exec(&[
        "calibrate",
        "--model",
        UR5,
        "--data",
        &data,
        "--report",
        &data,
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--report"), "{err}");
    assert_eq!(std::fs::read(&data).unwrap(), before);
    let (code, _, err) = exec(&[
        "calibrate",
        "--model",
        UR5,
        "--data",
        &data,
        "--report",
        &path(dir.path(), "r.svg"),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("an HTML page"), "{err}");
}

/// The provenance records the command line the run was given, not the process's own: a caller
/// that runs the command line in process (a test, the Python package's `run`) gets its command,
/// not the host program's arguments.
#[test]
fn the_provenance_records_the_command_given_in_process() {
    let dir = tempfile::tempdir().unwrap();
    let (data, _) = ur5_with_outliers(dir.path());
    let report = path(dir.path(), "in-process.html");
    let (code, _, err) = crate::common::cli(&[
        "calibrate",
        "--model",
        "fixtures/robots/ur5/vendor.yaml",
        "--data",
        &data,
        "--report",
        &report,
        "--quiet",
    ]);
    assert!(code == 0 || code == 1, "{err}");
    let (html, _) = page(&report);
    // The page's command line, exactly: a host argument that is also a word of the page (a test
    // filter such as `report`) must not make this test fail, as a search of the page for the
    // host's arguments did.
    let recorded = html
        .split_once("<p>command: <code>")
        .and_then(|(_, rest)| rest.split_once("</code></p>"))
        .map(|(c, _)| c.to_owned())
        .expect("a command line in the page");
    assert_eq!(
        recorded,
        format!(
            "urdf-dh calibrate --model fixtures/robots/ur5/vendor.yaml --data {data} --report \
             {report} --quiet"
        )
    );
}
