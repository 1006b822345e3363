//! ABB IRB 120 position measurements (L. Wu, X. Yang, K. Chen, H. Ren, "A minimal POE-based
//! model for robotic kinematic calibration with only position measurements", IEEE T-ASE
//! 12(2):758-763, 2015, §IV; data repository drliaowu/Minimal_Robot_Calibration_Using_Position,
//! each `.mat` variable converted to a CSV with a header line).
//!
//! # Layout
//! - `CaliJointAngles.csv`: 36 configurations × 6 joints, degrees;
//! - `CaliPosition.csv`: 108 × 3, millimetres, three rows per configuration in the order point 1,
//!   point 2, point 3 (the upstream `Experiment.m`: `CaliPosition=[point1_1;point2_1;point3_1;…]`);
//! - `TestJointAngles.csv` + `TestPosition.csv` (10 configurations, one point each) and
//!   `TestJointAngles2.csv` + `TestPosition2.csv` (30): held-out configurations. `Experiment.m`
//!   predicts them from "Test Point 1" and "Test Point 2" respectively: two points measured
//!   separately from the calibration points, 0.16 mm and 1.26 mm from point 1 at the zero
//!   configuration ([`TARGETS_AT_ZERO`]), so they are targets of their own here.
//!
//! Points are in the measurement device's frame.
//!
//! # Result
//! - joints `joint_1..joint_6`, radians;
//! - targets `point1`, `point2`, `point3` (calibration split, 108 samples), `test1`, `test2`
//!   (validation split, 10 + 30 samples; each test file pair is optional, but both files of a
//!   pair are needed);
//! - `config`: `cal-N`, `test1-N`, `test2-N` (N = 1-based configuration); no standard deviation;
//! - `Sample::line`: the line in the position file.

use nalgebra::Vector3;

use super::table::{read, Delimiter, Row};
use super::{in_file, numbered, Files};
use crate::csv::DataError;
use crate::data::{Measurements, Sample, Split};

/// Joint angles of the calibration configurations.
pub const CALIBRATION_JOINTS: &str = "CaliJointAngles.csv";
/// Positions of the three calibration points, three rows per configuration.
pub const CALIBRATION_POSITIONS: &str = "CaliPosition.csv";
/// Joint angles of the two test sets.
pub const TEST_JOINTS: [&str; 2] = ["TestJointAngles.csv", "TestJointAngles2.csv"];
/// Positions of the two test sets (test point 1, test point 2), one row per configuration.
pub const TEST_POSITIONS: [&str; 2] = ["TestPosition.csv", "TestPosition2.csv"];

/// Target names: the three calibration points, then the two test points.
pub const TARGETS: [&str; 5] = ["point1", "point2", "point3", "test1", "test2"];

/// Every target's position at the zero configuration, in the measurement frame, metres: the
/// constants `CaliPoint_Meas`, `TestPoint_Meas` and `TestPoint_Meas2` of the upstream
/// `Experiment.m` (given there in millimetres). The POE models of the paper use them as the
/// targets' nominal positions.
pub const TARGETS_AT_ZERO: [[f64; 3]; 5] = [
    [-0.082_401_255, 0.502_191_363, 0.652_794_976],
    [-0.069_225_085, 0.489_813_11, 0.653_858_786],
    [-0.060_642_945, 0.505_693_111, 0.653_060_532],
    [-0.082_538_708, 0.502_156_798, 0.652_749_355],
    [-0.082_389_469, 0.502_253_113, 0.654_004_118],
];

/// Parses the files (see the [module docs](self)).
pub(crate) fn parse(files: &Files<'_, '_>) -> Result<Measurements, DataError> {
    let joints = table(files.required(CALIBRATION_JOINTS)?, CALIBRATION_JOINTS, 6)?;
    let points = table(
        files.required(CALIBRATION_POSITIONS)?,
        CALIBRATION_POSITIONS,
        3,
    )?;
    if points.len() != 3 * joints.len() {
        return Err(DataError::Content {
            expected: format!(
                "3 rows in {CALIBRATION_POSITIONS} per configuration in {CALIBRATION_JOINTS} ({})",
                3 * joints.len()
            ),
            found: format!("{} rows", points.len()),
        });
    }
    let mut samples = Vec::with_capacity(points.len());
    for (i, (q, three)) in joints.iter().zip(points.chunks_exact(3)).enumerate() {
        for (target, row) in three.iter().enumerate() {
            samples.push(sample(
                q,
                row,
                target,
                format!("cal-{}", i + 1),
                Split::Calibration,
            ));
        }
    }
    for (k, (joints_file, points_file)) in TEST_JOINTS.into_iter().zip(TEST_POSITIONS).enumerate() {
        if files.optional(joints_file).is_none() && files.optional(points_file).is_none() {
            continue;
        }
        // One file of the pair without the other is an error naming the missing one.
        let (jt, pt) = (files.required(joints_file)?, files.required(points_file)?);
        let joints = table(jt, joints_file, 6)?;
        let points = table(pt, points_file, 3)?;
        if points.len() != joints.len() {
            return Err(DataError::Content {
                expected: format!(
                    "one row in {points_file} per configuration in {joints_file} ({})",
                    joints.len()
                ),
                found: format!("{} rows", points.len()),
            });
        }
        for (i, (q, row)) in joints.iter().zip(&points).enumerate() {
            let config = format!("test{}-{}", k + 1, i + 1);
            samples.push(sample(q, row, 3 + k, config, Split::Validation));
        }
    }
    Ok(Measurements {
        sessions: Vec::new(),
        joint_names: numbered("joint", 6),
        targets: TARGETS.map(String::from).to_vec(),
        samples,
    })
}

fn table(text: &str, name: &str, width: usize) -> Result<Vec<Row>, DataError> {
    read(text, Delimiter::Comma, width).map_err(|e| in_file(name, e))
}

fn sample(q: &Row, p: &Row, target: usize, config: String, split: Split) -> Sample {
    let v = &p.values;
    Sample {
        time: None,
        orientation: None,
        session: 0,
        q: q.values.iter().map(|d| d.to_radians()).collect(),
        target,
        point: Vector3::new(v[0], v[1], v[2]) / 1000.0,
        sigma: None,
        config: Some(config.into()),
        split,
        line: p.line,
        socket: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::import::{import, Layout, Source};

    fn src<'a>(name: &'a str, text: &'a str) -> Source<'a> {
        Source { name, text }
    }

    const JOINTS: &str =
        "q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg\n10,20,30,40,50,60\n0,0,0,0,0,90\n";
    const POINTS: &str = "x_mm,y_mm,z_mm\n1,2,3\n4,5,6\n7,8,9\n10,11,12\n13,14,15\n16,17,18\n";

    #[test]
    fn three_calibration_points_per_configuration_then_test_points() {
        let m = import(
            Layout::Liaowu,
            &[
                src(CALIBRATION_JOINTS, JOINTS),
                src(CALIBRATION_POSITIONS, POINTS),
                src(TEST_JOINTS[1], "a,b,c,d,e,f\n1,1,1,1,1,1\n"),
                src(TEST_POSITIONS[1], "x,y,z\n100,200,300\n"),
            ],
        )
        .unwrap();
        assert_eq!(m.samples.len(), 7);
        let s = &m.samples;
        assert_eq!((s[4].target, s[4].config.as_deref()), (1, Some("cal-2")));
        assert!((s[4].point - Vector3::new(0.013, 0.014, 0.015)).norm() < 1e-18);
        assert!((s[5].q[5] - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        assert_eq!(s[5].line, 7);
        let t = &s[6];
        assert_eq!((t.target, t.split), (4, Split::Validation));
        assert_eq!(m.targets[t.target], "test2");
        assert_eq!(t.config.as_deref(), Some("test2-1"));
    }

    #[test]
    fn row_counts_must_agree_and_pairs_be_complete() {
        let short = "x,y,z\n1,2,3\n";
        let e = import(
            Layout::Liaowu,
            &[
                src(CALIBRATION_JOINTS, JOINTS),
                src(CALIBRATION_POSITIONS, short),
            ],
        )
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "expected 3 rows in CaliPosition.csv per configuration in CaliJointAngles.csv (6), \
             found 1 rows"
        );
        let e = import(
            Layout::Liaowu,
            &[
                src(CALIBRATION_JOINTS, JOINTS),
                src(CALIBRATION_POSITIONS, POINTS),
                src(TEST_JOINTS[0], JOINTS),
            ],
        )
        .unwrap_err();
        assert!(
            e.to_string().contains("needs file 'TestPosition.csv'"),
            "{e}"
        );
        let e = import(
            Layout::Liaowu,
            &[
                src(CALIBRATION_JOINTS, "a\n1\n"),
                src(CALIBRATION_POSITIONS, POINTS),
            ],
        )
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "CaliJointAngles.csv: line 1: expected 6 fields, found 1"
        );
    }
}
