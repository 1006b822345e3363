//! `import --layout columns`: a user's own export (its separators, units, names and column
//! order) read into the canonical measurement CSV, checked against the set it was laid out from.

use crate::common::{exec, root};

const EXPORT: &str = "fixtures/import/export_semicolon_mm_deg.csv";
const ORIGINAL: &str = "fixtures/invalid/csv/valid_arm.csv";
const ARM: &str = "fixtures/invalid/urdf/valid_arm.urdf";

/// The data rows of a canonical measurement CSV as (numbers, texts).
fn rows(text: &str) -> Vec<(Vec<f64>, Vec<String>)> {
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .map(|l| {
            let (mut nums, mut texts) = (Vec::new(), Vec::new());
            for cell in l.split(',') {
                match cell.parse::<f64>() {
                    Ok(v) => nums.push(v),
                    Err(_) => texts.push(cell.to_string()),
                }
            }
            (nums, texts)
        })
        .collect()
}

const MAP: &[&str] = &[
    "--layout",
    "columns",
    "--joints",
    "5-6",
    "--joint-names",
    "joint_1,joint_2",
    "--points",
    "2-4",
    "--target",
    "7",
    "--config",
    "Pose",
    "--sigma",
    "Sigma [mm]",
    "--length-unit",
    "mm",
    "--angle-unit",
    "deg",
];

#[test]
fn a_relaid_export_reads_back_as_the_set_it_came_from() {
    let mut args = vec!["import"];
    args.extend_from_slice(MAP);
    args.push(EXPORT);
    let (code, imported, err) = exec(&args);
    assert_eq!(code, 0, "{err}");
    let original = std::fs::read_to_string(root().join(ORIGINAL)).unwrap();
    let (a, b) = (rows(&imported), rows(&original));
    assert_eq!(a.len(), 8);
    assert_eq!(a.len(), b.len());
    for ((na, ta), (nb, tb)) in a.iter().zip(&b) {
        assert_eq!(ta, tb);
        assert_eq!(na.len(), nb.len());
        for (x, y) in na.iter().zip(nb) {
            assert!((x - y).abs() <= 1e-12 * y.abs().max(1e-3), "{x} vs {y}");
        }
    }
    // The import calibrates as the original does.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("imported.csv");
    std::fs::write(&path, &imported).unwrap();
    let report = |data: &str| {
        let (code, out, err) = exec(&["calibrate", "--model", ARM, "--data", data]);
        assert_eq!(code, 0, "{err}");
        out.lines()
            .filter(|l| l.starts_with("result:") || l.starts_with("geometric"))
            .map(String::from)
            .collect::<Vec<_>>()
    };
    assert_eq!(report(path.to_str().unwrap()), report(ORIGINAL));
}

#[test]
fn column_maps_that_do_not_fit_are_usage_errors() {
    let cases: &[(&[&str], &str)] = &[
        (
            &["import", "--layout", "columns", "--points", "2-4", EXPORT],
            "--layout columns: expected --joints, found none",
        ),
        (
            &[
                "import", "--layout", "columns", "--joints", "5-6", "--points", "2-3", EXPORT,
            ],
            "--points: expected 3 columns (x, y, z), found 2",
        ),
        (
            &["import", "--joints", "5-6", "--points", "2-4", EXPORT],
            "expected --layout columns",
        ),
        (
            &[
                "import", "--layout", "columns", "--joints", "5-6", "--points", "2-4,Q", EXPORT,
            ],
            "--points: expected 3 columns",
        ),
        (
            &[
                "import", "--layout", "columns", "--joints", "5-6", "--points", "2-4", "--target",
                "X", EXPORT,
            ],
            "expected a column named 'X'",
        ),
        (
            // Degrees read as radians: 89 "rad" is beyond four turns.
            &[
                "import",
                "--layout",
                "columns",
                "--joints",
                "5-6",
                "--points",
                "2-4",
                "--length-unit",
                "mm",
                EXPORT,
            ],
            "is the angle unit right?",
        ),
        (
            // Millimetres read as metres: 1933 m is beyond 100 m.
            &[
                "import",
                "--layout",
                "columns",
                "--joints",
                "5-6",
                "--points",
                "2-4",
                "--angle-unit",
                "deg",
                EXPORT,
            ],
            "is the length unit right?",
        ),
    ];
    for (args, expected) in cases {
        let (code, out, err) = exec(args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(out.is_empty(), "{args:?}: {out}");
        assert!(err.contains(expected), "{args:?}: {err}");
        assert_eq!(
            err.lines()
                .filter(|l| l.starts_with("urdf-dh: error:"))
                .count(),
            1,
            "{err}"
        );
    }
}

/// The same export saved by MATLAB-compatible `save` (`-v7`, compressed; scipy's `savemat`):
/// variables `A` (8x2, degrees), `P` (8x3, mm), `sigma` (8x1, mm), and `rate` (1x1) and
/// `operator` (text), which are not columns.
const MAT_EXPORT: &str = "fixtures/import/export_mm_deg.mat";

#[test]
fn a_mat_export_reads_as_its_csv_export() {
    let (code, from_mat, err) = exec(&[
        "import",
        "--layout",
        "columns",
        "--joints",
        "A_1,A_2",
        "--joint-names",
        "joint_1,joint_2",
        "--points",
        "P_1,P_2,P_3",
        "--sigma",
        "sigma",
        "--length-unit",
        "mm",
        "--angle-unit",
        "deg",
        MAT_EXPORT,
    ]);
    assert_eq!(code, 0, "{err}");
    // What is not a column is named, not silently dropped.
    assert!(
        err.contains("'rate' (1x1) has not 8 rows: left out"),
        "{err}"
    );
    assert!(
        err.contains("'operator' (1x12) is not a numeric array"),
        "{err}"
    );
    let original = std::fs::read_to_string(root().join(ORIGINAL)).unwrap();
    let (a, b) = (rows(&from_mat), rows(&original));
    assert_eq!(a.len(), 8);
    for ((na, _), (nb, _)) in a.iter().zip(&b) {
        assert_eq!(na.len(), nb.len());
        for (x, y) in na.iter().zip(nb) {
            assert!((x - y).abs() <= 1e-12 * y.abs().max(1e-3), "{x} vs {y}");
        }
    }
    // A column that is not there is named with the columns the file has.
    let (code, _, err) = exec(&[
        "import",
        "--layout",
        "columns",
        "--joints",
        "q_1",
        "--points",
        "P_1,P_2,P_3",
        MAT_EXPORT,
    ]);
    assert_eq!(code, 2);
    assert!(err.contains("'q_1'") && err.contains("A_1"), "{err}");
}

/// The Innopolis course's own `calibration_dataset.mat` (github.com/Sarrasor/RoboticManipulators,
/// `data/calibration_dataset.mat`) imports as the CSV converted from it in `../shared`. The file
/// is not in the repository (nothing fetched is committed): the test runs where
/// `URDF_DH_INNOPOLIS_MAT` names a copy and says so when it skips.
#[test]
fn the_innopolis_mat_file_imports_as_its_csv() {
    let Ok(mat) = std::env::var("URDF_DH_INNOPOLIS_MAT") else {
        test_skips::skip("URDF_DH_INNOPOLIS_MAT does not name a copy of calibration_dataset.mat");
        return;
    };
    let Some(shared) =
        crate::common::skip_without_shared("the_innopolis_mat_file_imports_as_its_csv")
    else {
        return;
    };
    let csv = shared.join("measured/innopolis_fanuc_r2000ic_165f_3markers/calibration_dataset.csv");
    let (code, from_mat, err) = exec(&["import", &mat]);
    assert_eq!(code, 0, "{err}");
    let (code, from_csv, err) = exec(&["import", csv.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let (a, b) = (rows(&from_mat), rows(&from_csv));
    assert_eq!(a.len(), 720);
    // The same targets and configurations (runs of equal joint values in the .mat, config_id in
    // the CSV) and the same numbers up to the CSV's rounding (joint values to 10 digits).
    assert_eq!(a.len(), b.len());
    for (k, ((na, ta), (nb, tb))) in a.iter().zip(&b).enumerate() {
        assert_eq!(ta, tb, "row {k}");
        assert_eq!(na.len(), nb.len(), "row {k}");
        for (x, y) in na.iter().zip(nb) {
            assert!((x - y).abs() <= 1e-9, "row {k}: {x} vs {y}");
        }
    }
}

/// A 6-DoF export: the rows of a simulated 6-DoF set laid out as a user's tool might write
/// them (`;`, millimetres, degrees, the quaternion's scalar last or roll-pitch-yaw), imported
/// with `--quaternion`/`--rpy` and `--sigma-rot`: the canonical reader gets the simulated
/// values back, and the import calibrates as the simulated set does.
#[test]
fn a_six_dof_export_imports_as_the_set_it_came_from() {
    const UR5: &str = "fixtures/robots/ur5/vendor.yaml";
    let dir = tempfile::tempdir().unwrap();
    let sim = dir.path().join("sim.csv").to_string_lossy().into_owned();
    let (code, _, err) = exec(&[
        "simulate",
        "--model",
        UR5,
        "--poses",
        "40",
        "--noise",
        "20e-6",
        "--orientation-noise",
        "50e-6",
        "--random-errors",
        "0.0005,0.0003",
        "--seed",
        "5",
        "--out",
        &sim,
    ]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(&sim).unwrap();
    let header: Vec<&str> = text
        .lines()
        .find(|l| !l.starts_with('#'))
        .unwrap()
        .split(',')
        .collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let original = rows(&text);
    // Numbers of a simulated row: 6 joints, x, y, z, sigma, qw, qx, qy, qz, sigma_rot.
    assert_eq!(original[0].0.len(), 15);
    assert_eq!((col("x"), col("qw")), (6, 12));
    let deg = 180.0 / std::f64::consts::PI;
    let mut quaternion = String::from("pose;J1;J2;J3;J4;J5;J6;X;Y;Z;S;QX;QY;QZ;QW;SR\n");
    let mut rpy = String::from("pose;J1;J2;J3;J4;J5;J6;X;Y;Z;S;R;P;YW;SR\n");
    for (i, (n, _)) in original.iter().enumerate() {
        let joints: Vec<String> = n[..6].iter().map(|v| format!("{}", v * deg)).collect();
        let mm: Vec<String> = n[6..10].iter().map(|v| format!("{}", v * 1e3)).collect();
        let (w, x, y, z) = (n[10], n[11], n[12], n[13]);
        let sr = n[14] * deg;
        let common = format!("p{i};{};{}", joints.join(";"), mm.join(";"));
        quaternion.push_str(&format!("{common};{x};{y};{z};{w};{sr}\n"));
        // URDF roll-pitch-yaw of the same rotation.
        let roll = (2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y));
        let pitch = (2.0 * (w * y - z * x)).clamp(-1.0, 1.0).asin();
        let yaw = (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z));
        rpy.push_str(&format!(
            "{common};{};{};{};{sr}\n",
            roll * deg,
            pitch * deg,
            yaw * deg
        ));
    }
    let report = |data: &str| {
        let (code, out, err) = exec(&["calibrate", "--model", UR5, "--data", data]);
        assert_eq!(code, 0, "{err}");
        out.lines()
            .filter(|l| l.starts_with("result:") || l.starts_with("angle:"))
            .map(String::from)
            .collect::<Vec<_>>()
    };
    let expected = report(&sim);
    assert_eq!(expected.len(), 2, "{expected:?}");
    for (name, export, rotation) in [
        (
            "quaternion.csv",
            quaternion,
            ["--quaternion", "QW,QX,QY,QZ"],
        ),
        ("rpy.csv", rpy, ["--rpy", "R,P,YW"]),
    ] {
        let path = dir.path().join(name);
        std::fs::write(&path, export).unwrap();
        let out = dir.path().join(format!("imported-{name}"));
        let (code, _, err) = exec(&[
            "import",
            "--layout",
            "columns",
            "--joints",
            "J1,J2,J3,J4,J5,J6",
            "--joint-names",
            &header[..6].join(","),
            "--points",
            "X,Y,Z",
            "--sigma",
            "S",
            rotation[0],
            rotation[1],
            "--sigma-rot",
            "SR",
            "--config",
            "pose",
            "--length-unit",
            "mm",
            "--angle-unit",
            "deg",
            &path.to_string_lossy(),
            "--out",
            &out.to_string_lossy(),
        ]);
        assert_eq!(code, 0, "{name}: {err}");
        let imported = std::fs::read_to_string(&out).unwrap();
        let back = rows(&imported);
        assert_eq!(back.len(), original.len());
        for ((a, _), (b, _)) in back.iter().zip(&original) {
            assert_eq!(a.len(), b.len(), "{name}");
            // A quaternion and its negative are one rotation: compare up to the sign.
            let sign = if a[10] * b[10] + a[11] * b[11] + a[12] * b[12] + a[13] * b[13] < 0.0 {
                -1.0
            } else {
                1.0
            };
            for (k, (x, y)) in a.iter().zip(b).enumerate() {
                let y = if (10..14).contains(&k) { sign * y } else { *y };
                assert!(
                    (x - y).abs() <= 1e-9 * y.abs().max(1e-3),
                    "{name}: column {k}: {x} vs {y}"
                );
            }
        }
        assert_eq!(report(&out.to_string_lossy()), expected, "{name}");
    }
    // Orientation options that do not fit: usage errors, exit 2.
    let path = dir
        .path()
        .join("quaternion.csv")
        .to_string_lossy()
        .into_owned();
    for (extra, expected) in [
        (
            &[
                "--quaternion",
                "QW,QX,QY",
                "--sigma-rot",
                "SR",
                "--sigma",
                "S",
            ][..],
            "--quaternion: expected 4 columns (qw, qx, qy, qz), found 3",
        ),
        (
            &["--quaternion", "QW,QX,QY,QZ", "--sigma", "S"][..],
            "expected --sigma-rot",
        ),
        (
            &["--quaternion", "QW,QX,QY,QZ", "--sigma-rot", "SR"][..],
            "expected --sigma as well",
        ),
        (
            &[
                "--quaternion",
                "QW,QX,QY,QZ",
                "--sigma-rot",
                "SQ",
                "--sigma",
                "S",
            ][..],
            "expected a column named 'SQ'",
        ),
        (
            // Degrees read as radians (line 2 is the zero pose).
            &[
                "--rpy",
                "J1,J2,J3",
                "--sigma-rot",
                "SR",
                "--sigma",
                "S",
                "--angle-unit",
                "rad",
            ][..],
            "quaternion.csv: line 3: expected an angle within a turn in column 'J",
        ),
    ] {
        let mut args = vec![
            "import",
            "--layout",
            "columns",
            "--joints",
            "QX,QY",
            "--points",
            "X,Y,Z",
            "--length-unit",
            "mm",
        ];
        args.extend_from_slice(extra);
        args.push(&path);
        let (code, out, err) = exec(&args);
        assert_eq!(code, 2, "{extra:?}: {err}");
        assert!(out.is_empty());
        assert!(err.contains(expected), "{extra:?}: {err}");
    }
}

/// `--time COL` writes the export's time column (seconds) as the canonical `time` column, an
/// empty cell a row without a time; a cell that is no number names its line and column, and
/// `--time` without `--layout columns` is refused.
#[test]
fn a_time_column_is_imported_as_the_time_of_each_row() {
    let dir = tempfile::tempdir().unwrap();
    let export = dir.path().join("timed.csv");
    std::fs::write(
        &export,
        "q1,q2,X,Y,Z,stamp\n0.1,0.2,1,2,3,1700000000.5\n0.3,0.4,1,2,4,\n0.5,0.6,1,2,5,1700000060\n",
    )
    .unwrap();
    let export = export.to_str().unwrap();
    let map = [
        "import", "--layout", "columns", "--joints", "1-2", "--points", "3-5", "--time", "stamp",
    ];
    let mut args = map.to_vec();
    args.push(export);
    let (code, out, err) = exec(&args);
    assert_eq!(code, 0, "{err}");
    let lines: Vec<&str> = out.lines().filter(|l| !l.starts_with('#')).collect();
    assert_eq!(lines[0], "q1,q2,x,y,z,target,time", "{out}");
    let times: Vec<&str> = lines[1..]
        .iter()
        .map(|l| l.rsplit(',').next().unwrap())
        .collect();
    assert_eq!(times, ["1700000000.5", "", "1700000060.0"], "{out}");

    let bad = dir.path().join("bad.csv");
    std::fs::write(&bad, "q1,q2,X,Y,Z,stamp\n0.1,0.2,1,2,3,noon\n").unwrap();
    let mut args = map.to_vec();
    args.push(bad.to_str().unwrap());
    let (code, _, err) = exec(&args);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("line 2") && err.contains("'stamp'") && err.contains("'noon'"),
        "{err}"
    );
    let (code, _, err) = exec(&["import", "--time", "stamp", export]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--time: expected --layout columns"), "{err}");
}
