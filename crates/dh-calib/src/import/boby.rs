//! Laser-tracker circle-point data of an industrial 6R robot (R. A. Boby, A. Klimchik,
//! "Combination of Geometric and Parametric Approaches for Kinematic Identification of an
//! Industrial Robot", RCIM; data repository RABKKK/LaserTrackerPoseData4KinIdent).
//!
//! # Layout
//! `N1N2N3Jval.csv`: whitespace separated, no header, 21 numbers per row:
//! - columns 1-9: x, y, z of SMR1, SMR2, SMR3 (three reflectors on one end-effector nest), in
//!   the laser tracker's frame, millimetres;
//! - columns 10-15: unused (zero in the published file; not checked);
//! - columns 16-21: joints J1..J6 from the controller, degrees.
//!
//! (The upstream README says "the last 9 columns" hold the joints; the file has 12 trailing
//! columns, the first six of which are zero.) The 36 rows sweep one joint at a time, six poses per
//! joint; the J2 block moves J3 = −J2 with it (see [`crate::cpa`] for what that means).
//!
//! # Result
//! Joints `joint_1..joint_6` in radians, targets `SMR1`, `SMR2`, `SMR3` in metres: three samples
//! per row, all for calibration, `config` = the row number (1-based, counting data rows).

use std::sync::Arc;

use nalgebra::Vector3;

use super::numbered;
use super::table::{read, Delimiter};
use crate::csv::DataError;
use crate::data::{Measurements, Sample, Split};

/// The dataset's file name.
pub const FILE: &str = "N1N2N3Jval.csv";

/// Target names, one per spherically mounted retroreflector.
pub const TARGETS: [&str; 3] = ["SMR1", "SMR2", "SMR3"];

/// Numbers per row.
const WIDTH: usize = 21;
/// First joint column (0-based).
const FIRST_JOINT: usize = 15;

/// Parses `N1N2N3Jval.csv` (see the [module docs](self)).
///
/// # Errors
/// A [`DataError`] for a row without 21 numbers or a cell that is not a finite number.
pub fn parse(text: &str) -> Result<Measurements, DataError> {
    let rows = read(text, Delimiter::Whitespace, WIDTH)?;
    let mut samples = Vec::with_capacity(3 * rows.len());
    for (index, row) in rows.iter().enumerate() {
        let v = &row.values;
        let q: Arc<[f64]> = v[FIRST_JOINT..FIRST_JOINT + 6]
            .iter()
            .map(|deg| deg.to_radians())
            .collect();
        for target in 0..3 {
            let p = &v[3 * target..3 * target + 3];
            samples.push(Sample {
                time: None,
                orientation: None,
                session: 0,
                q: Arc::clone(&q),
                target,
                point: Vector3::new(p[0], p[1], p[2]) / 1000.0,
                sigma: None,
                config: Some(compact_str::format_compact!("{}", index + 1)),
                split: Split::Calibration,
                line: row.line,
                socket: None,
            });
        }
    }
    Ok(Measurements {
        sessions: Vec::new(),
        joint_names: numbered("joint", 6),
        targets: TARGETS.map(String::from).to_vec(),
        samples,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn millimetres_and_degrees_become_metres_and_radians() {
        // One made-up row in the layout: SMRs, six zeros, J1..J6.
        let text = "1.0e+03 -2.0e+03 5.0e+02 1 2 3 4 5 6 0 0 0 0 0 0 \
                    9.0e+01 -4.5e+01 4.5e+01 0 0 3.6e+02\n";
        let m = parse(text).unwrap();
        assert_eq!(m.samples.len(), 3);
        assert_eq!(m.targets, vec!["SMR1", "SMR2", "SMR3"]);
        let s = &m.samples[0];
        assert_eq!(s.point, Vector3::new(1.0, -2.0, 0.5));
        assert_eq!(m.samples[2].point, Vector3::new(0.004, 0.005, 0.006));
        let want = [90.0, -45.0, 45.0, 0.0, 0.0, 360.0].map(f64::to_radians);
        assert_eq!(s.q[..], want[..]);
        assert_eq!((s.line, s.config.as_deref()), (1, Some("1")));
    }

    #[test]
    fn short_rows_are_rejected() {
        let e = parse("1 2 3\n").unwrap_err();
        assert_eq!(e.to_string(), "line 1: expected 21 fields, found 3");
    }
}
