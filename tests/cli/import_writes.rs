//! What `import --layout columns` writes, its reader reads back equal (the idea of
//! `tests/cli/writers.rs`, for `import`): random joint and target names (plain ones and the
//! ones that clash with the CSV's own columns or hold control, bidi, separator and quote
//! characters), random values, separators and file names, through `import`, into the canonical
//! CSV, read back by `dh_calib::csv::parse_measurements`. `import` may refuse (exit 2, one error
//! line), never write what its reader refuses or reads differently.

use proptest::prelude::*;

use crate::common::cli;

/// A name a user's export may hold.
fn name() -> impl Strategy<Value = String> {
    prop_oneof![
        12 => "[a-z][a-z0-9_]{0,6}",
        1 => Just("x".to_string()),
        1 => Just("sigma".to_string()),
        1 => Just("target".to_string()),
        1 => Just("a,b".to_string()),
        1 => Just("q \"1\"".to_string()),
        1 => Just("#j".to_string()),
        1 => Just(" j ".to_string()),
        1 => Just("e\u{1b}[31m".to_string()),
        1 => Just("t\u{202e}1".to_string()),
        1 => Just("l\nm".to_string()),
        1 => Just("gelenk_ä".to_string()),
    ]
}

/// One row: joint values (degrees), a point (mm), a sigma (mm), a target name.
type Row = (Vec<f64>, [f64; 3], f64, String);

#[derive(Debug, Clone)]
struct Export {
    joint_names: Vec<String>,
    /// Given with `--joint-names` (else the header's names are written).
    given: bool,
    delimiter: (char, &'static str),
    rows: Vec<Row>,
    file_name: String,
}

fn export() -> impl Strategy<Value = Export> {
    (1usize..=4).prop_flat_map(|n| {
        let row = (
            prop::collection::vec(-720.0..720.0f64, n),
            [-5000.0..5000.0f64, -5000.0..5000.0f64, -5000.0..5000.0f64],
            prop_oneof![Just(0.0), 1e-5..10.0f64],
            prop_oneof![3 => Just("t1".to_string()), 1 => name()],
        );
        (
            prop::collection::vec(name(), n),
            prop::bool::ANY,
            prop_oneof![
                Just((',', "comma")),
                Just((';', "semicolon")),
                Just(('\t', "tab"))
            ],
            prop::collection::vec(row, 1..6),
            prop_oneof![
                3 => Just("export.csv".to_string()),
                1 => Just("ex\nport.csv".to_string()),
                1 => Just("ex\u{1b}port\u{202e}.csv".to_string()),
            ],
        )
            .prop_map(|(joint_names, given, delimiter, rows, file_name)| Export {
                joint_names,
                given,
                delimiter,
                rows,
                file_name,
            })
    })
}

/// A cell of the export, quoted when it holds the separator, a quote, a line break or spaces.
fn cell(text: &str, delimiter: char) -> String {
    if text.contains([delimiter, '"', '\n', '\r']) || text.trim() != text || text.starts_with('#') {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

impl Export {
    fn text(&self) -> String {
        let d = self.delimiter.0;
        let mut header: Vec<String> = self.joint_names.iter().map(|n| cell(n, d)).collect();
        header.extend(["X", "Y", "Z", "S", "T"].map(String::from));
        let mut text = header.join(&d.to_string()) + "\n";
        for (q, p, s, t) in &self.rows {
            let mut cells: Vec<String> = q.iter().map(|v| format!("{v:?}")).collect();
            cells.extend(p.iter().map(|v| format!("{v:?}")));
            cells.push(format!("{s:?}"));
            cells.push(cell(t, d));
            text += &(cells.join(&d.to_string()) + "\n");
        }
        text
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn what_import_writes_its_reader_reads_back_equal(e in export()) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(&e.file_name);
        std::fs::write(&path, e.text()).unwrap();
        let n = e.joint_names.len();
        let joints = format!("1-{n}");
        let points = format!("{}-{}", n + 1, n + 3);
        let (sigma, target) = (format!("{}", n + 4), format!("{}", n + 5));
        let names = e.joint_names.join(",");
        let mut args = vec![
            "import", "--layout", "columns", "--joints", &joints, "--points", &points,
            "--sigma", &sigma, "--target", &target, "--delimiter", e.delimiter.1,
            "--length-unit", "mm", "--angle-unit", "deg",
        ];
        // A name holding a comma cannot be given in the comma-separated --joint-names.
        let given = e.given && !e.joint_names.iter().any(|n| n.contains(','));
        if given {
            args.extend(["--joint-names", &names]);
        }
        let file = path.to_string_lossy().into_owned();
        args.push(&file);
        let (code, out, err) = cli(&args);
        if code != 0 {
            prop_assert_eq!(code, 2, "{}", err);
            prop_assert!(out.is_empty());
            prop_assert_eq!(err.lines().filter(|l| l.starts_with("urdf-dh: error: ")).count(), 1, "{}", err);
            prop_assert!(!err.contains("panicked"));
            // Plain names are never refused.
            let plain = |s: &str| !s.is_empty() && s.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_');
            let reserved = |s: &str| dh_calib::csv::RESERVED_COLUMNS.contains(&s);
            let mut distinct = e.joint_names.clone();
            distinct.sort();
            distinct.dedup();
            prop_assert!(
                !(e.joint_names.iter().all(|n| plain(n) && !reserved(n))
                    && distinct.len() == n
                    && e.rows.iter().all(|r| plain(&r.3))),
                "refused plain names: {}\n{}", err, e.text()
            );
            return Ok(());
        }
        // The header comment stays comments: every line up to the header starts with '#'.
        let header = out.lines().position(|l| !l.starts_with('#')).unwrap();
        prop_assert!(out.lines().nth(header).unwrap().contains(",x,y,z,target"), "{}", out);
        let back = dh_calib::csv::parse_measurements(
            &out,
            &e.joint_names,
            &dh_calib::csv::CsvOptions::default(),
        );
        prop_assert!(back.is_ok(), "the reader refused what import wrote: {:?}\n{}", back.err(), out);
        let back = back.unwrap();
        // Identical rows are counted once: compare with the distinct rows in order.
        let mut rows: Vec<&Row> = Vec::new();
        for r in &e.rows {
            if !rows.contains(&r) {
                rows.push(r);
            }
        }
        prop_assert_eq!(back.samples.len(), rows.len());
        for (s, (q, p, sigma, t)) in back.samples.iter().zip(rows) {
            for (a, b) in s.q.iter().zip(q) {
                prop_assert!((a - b.to_radians()).abs() <= 1e-12 * b.to_radians().abs().max(1.0), "{} vs {}", a, b);
            }
            for (a, b) in s.point.iter().zip(p) {
                prop_assert!((a - b / 1e3).abs() <= 1e-15 * (b / 1e3).abs().max(1.0), "{} vs {}", a, b);
            }
            let expected = if *sigma == 0.0 { dh_calib::csv::SIGMA_FLOOR } else { sigma / 1e3 };
            prop_assert!((s.sigma.unwrap().x - expected).abs() <= 1e-15 * expected);
            prop_assert_eq!(&back.targets[s.target], t);
        }
    }
}
