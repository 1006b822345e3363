//! Arrays read as the CSV reader reads the same cells.

use super::*;

fn arrays() -> SampleArrays {
    SampleArrays {
        time: None,
        joint_names: vec!["j1".into(), "j2".into()],
        q: vec![0.1, 0.2, 90.0, -45.0],
        points: vec![1000.0, 0.0, 500.0, 1.0, 2.0, 3.0],
        target: Some(vec!["A".into(), "B".into()]),
        sigma: Some(vec![f64::NAN, 0.0]),
        config: None,
        session: None,
        set: Some(vec!["train".into(), "test".into()]),
        quaternion: None,
        sigma_rot: None,
        sigma_axes: None,
    }
}

#[test]
fn converts_units_like_the_csv_reader() {
    let opts = CsvOptions {
        length_unit: LengthUnit::Millimetre,
        angle_unit: AngleUnit::Degree,
        prismatic: vec!["j2".into()],
    };
    let (m, notes) = Measurements::from_arrays(&arrays(), &opts).unwrap();
    let text = "j1,j2,x,y,z,target,sigma,set\n0.1,0.2,1000,0,500,A,,train\n90,-45,1,2,3,B,0,test\n";
    let (csv, _) = parse_measurements_noting(text, &m.joint_names, &opts).unwrap();
    assert_eq!(m.targets, csv.targets);
    for (a, c) in m.samples.iter().zip(&csv.samples) {
        assert_eq!(a.q, c.q);
        assert_eq!(a.point, c.point);
        assert_eq!(a.sigma, c.sigma);
        assert_eq!(a.split, c.split);
        assert_eq!(a.target, c.target);
    }
    assert_eq!(m.samples[1].line, csv.samples[1].line);
    assert_eq!(notes.len(), 1, "{notes:?}");
    assert!(notes[0].contains("first at row 1"), "{notes:?}");
}

/// Per-axis sigmas (`sx, sy, sz`) read as the CSV reader reads the same cells: millimetres
/// converted, a row of NaN for none, 0 floored with a note; refused beside `sigma`, with
/// one axis missing, or negative, naming the row and column.
#[test]
fn per_axis_sigmas_like_the_csv_reader() {
    let opts = CsvOptions {
        length_unit: LengthUnit::Millimetre,
        angle_unit: AngleUnit::Degree,
        prismatic: vec!["j2".into()],
    };
    let mut a = arrays();
    a.sigma = None;
    a.sigma_axes = Some(vec![f64::NAN, f64::NAN, f64::NAN, 0.01, 0.0, 0.03]);
    let (m, notes) = Measurements::from_arrays(&a, &opts).unwrap();
    let text = "j1,j2,x,y,z,target,sx,sy,sz,set\n0.1,0.2,1000,0,500,A,,,,train\n\
                90,-45,1,2,3,B,0.01,0,0.03,test\n";
    let (csv, csv_notes) = parse_measurements_noting(text, &m.joint_names, &opts).unwrap();
    for (a, c) in m.samples.iter().zip(&csv.samples) {
        assert_eq!(a.sigma, c.sigma);
    }
    let s = m.samples[1].sigma.unwrap();
    assert!(
        (s - Vector3::new(1e-5, SIGMA_FLOOR, 3e-5)).norm() < 1e-18,
        "{s}"
    );
    assert_eq!((notes.len(), csv_notes.len()), (1, 1), "{notes:?}");

    let mut both = a.clone();
    both.sigma = Some(vec![0.1, 0.1]);
    let e = Measurements::from_arrays(&both, &opts).unwrap_err();
    assert!(
        e.to_string().contains("either the isotropic 'sigma'"),
        "{e}"
    );
    let mut partial = a.clone();
    partial.sigma_axes = Some(vec![0.1, f64::NAN, 0.1, 0.1, 0.1, 0.1]);
    let e = Measurements::from_arrays(&partial, &opts).unwrap_err();
    assert!(
        e.to_string().starts_with("row 0, column 'sx, sy, sz': "),
        "{e}"
    );
    let mut negative = a.clone();
    negative.sigma_axes = Some(vec![0.1, 0.1, 0.1, 0.1, -0.1, 0.1]);
    let e = Measurements::from_arrays(&negative, &opts).unwrap_err();
    assert!(e.to_string().starts_with("row 1, column 'sy': "), "{e}");
    let mut short = a;
    short.sigma_axes = Some(vec![0.1; 5]);
    assert!(Measurements::from_arrays(&short, &opts).is_err());
}

/// [`arrays`] in metres and radians (plausible values in the default units).
fn si() -> SampleArrays {
    let mut a = arrays();
    a.points[0] = 1.0;
    a.points[2] = 0.5;
    a.q[2] = 1.0;
    a.q[3] = -0.5;
    a
}

#[test]
fn refuses_bad_cells_naming_row_and_column() {
    let opts = CsvOptions::default();
    assert!(Measurements::from_arrays(&si(), &opts).is_ok());
    let mut a = si();
    a.q[3] = f64::NAN;
    let e = Measurements::from_arrays(&a, &opts).unwrap_err();
    assert_eq!(
        e.to_string(),
        "row 1, column 'j2': expected a finite number, found NaN"
    );
    let mut a = si();
    a.q[2] = 90.0; // degrees read as radians
    let e = Measurements::from_arrays(&a, &opts).unwrap_err();
    assert!(e.to_string().starts_with("row 1, column 'j1': "), "{e}");
    let mut a = si();
    a.points[4] = f64::INFINITY;
    let e = Measurements::from_arrays(&a, &opts).unwrap_err();
    assert_eq!(
        e.to_string(),
        "row 1, column 'y': expected a finite number, found inf"
    );
    let mut a = si();
    a.points.pop();
    let e = Measurements::from_arrays(&a, &opts).unwrap_err();
    assert!(e.to_string().contains("points (rows x 3)"), "{e}");
    let mut a = si();
    a.set = Some(vec!["train".into(), "later".into()]);
    let e = Measurements::from_arrays(&a, &opts).unwrap_err();
    assert_eq!(
        e.to_string(),
        "row 1, column 'set': expected train, calibration, test or validation, found 'later'"
    );
    let mut a = si();
    a.sigma = Some(vec![-1.0, 0.1]);
    let e = Measurements::from_arrays(&a, &opts).unwrap_err();
    assert!(e.to_string().starts_with("row 0, column 'sigma': "), "{e}");
}

/// Orientation arrays read as the CSV reader reads the same cells: a 6-DoF row and a point
/// row (NaN), a `sigma_rot` of 0 floored with a note, and the refusals naming the row.
#[test]
fn orientations_read_as_the_csv_reader_reads_them() {
    let opts = CsvOptions::default();
    let mut a = si();
    a.quaternion = Some(vec![
        0.8,
        0.6,
        0.0,
        0.0,
        f64::NAN,
        f64::NAN,
        f64::NAN,
        f64::NAN,
    ]);
    a.sigma_rot = Some(vec![0.0, f64::NAN]);
    let (m, notes) = Measurements::from_arrays(&a, &opts).unwrap();
    let text = "j1,j2,x,y,z,target,sigma,set,qw,qx,qy,qz,sigma_rot\n\
                0.1,0.2,1,0,0.5,A,,train,0.8,0.6,0,0,0\n\
                1,-0.5,1,2,3,B,0,test,,,,,\n";
    let (csv, csv_notes) = parse_measurements_noting(text, &m.joint_names, &opts).unwrap();
    for (x, c) in m.samples.iter().zip(&csv.samples) {
        assert_eq!(x.orientation, c.orientation);
    }
    assert!(m.samples[0].orientation.as_ref().unwrap().sigma == SIGMA_ROT_FLOOR);
    assert!(
        notes
            .iter()
            .any(|n| n.contains("sigma_rot of 0 (first at row 0")),
        "{notes:?}"
    );
    assert_eq!(notes.len(), csv_notes.len());
    for (quaternion, sigma, expected) in [
        (
            [0.8, 0.6, f64::NAN, 0.0],
            1e-4,
            "row 0, column 'qy': expected all of qw, qx, qy, qz or none",
        ),
        (
            [0.9, 0.6, 0.0, 0.0],
            1e-4,
            "row 0, column 'qw': expected a unit quaternion",
        ),
        ([0.8, 0.6, 0.0, 0.0], -1.0, "row 0, column 'sigma_rot': "),
        (
            [0.8, 0.6, 0.0, 0.0],
            f64::NAN,
            "row 0, column 'sigma_rot': ",
        ),
    ] {
        let mut b = a.clone();
        b.quaternion.as_mut().unwrap()[..4].copy_from_slice(&quaternion);
        b.sigma_rot = Some(vec![sigma, f64::NAN]);
        let e = Measurements::from_arrays(&b, &opts)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with(expected), "{e}");
    }
    let mut b = a.clone();
    b.sigma_rot = None;
    let e = Measurements::from_arrays(&b, &opts)
        .unwrap_err()
        .to_string();
    assert!(e.contains("together"), "{e}");
}

/// A `time` array gives each sample and joint row its time (NaN: none, as an empty cell); a
/// wrong length or an infinite time is refused naming the column (and the row).
#[test]
fn times_are_read_like_the_time_column() {
    let opts = CsvOptions {
        length_unit: LengthUnit::Millimetre,
        angle_unit: AngleUnit::Degree,
        prismatic: vec!["j2".into()],
    };
    let timed = SampleArrays {
        time: Some(vec![1_700_000_000.5, f64::NAN]),
        ..arrays()
    };
    let (m, _) = Measurements::from_arrays(&timed, &opts).unwrap();
    let times: Vec<Option<f64>> = m.samples.iter().map(|s| s.time).collect();
    assert_eq!(times, vec![Some(1_700_000_000.5), None]);
    let joints = SampleArrays {
        points: Vec::new(),
        sigma: None,
        ..timed.clone()
    };
    let rows = crate::joints::joint_rows(&joints, &opts).unwrap();
    assert_eq!(rows[0].time, Some(1_700_000_000.5));
    assert_eq!(rows[1].time, None);
    let short = SampleArrays {
        time: Some(vec![1.0]),
        ..arrays()
    };
    let e = Measurements::from_arrays(&short, &opts)
        .unwrap_err()
        .to_string();
    assert!(e.contains("'time'"), "{e}");
    let infinite = SampleArrays {
        time: Some(vec![0.0, f64::INFINITY]),
        ..arrays()
    };
    let e = Measurements::from_arrays(&infinite, &opts)
        .unwrap_err()
        .to_string();
    assert!(e.contains("row 1") && e.contains("time"), "{e}");
}
