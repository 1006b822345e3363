//! Fanuc R-2000iC/165F with three markers, Innopolis University robotics course data
//! (`calibration_dataset.csv`, converted from the course's `calibration_dataset.mat`).
//!
//! # Layout
//! A CSV with header `config_id, q1_rad..q6_rad, mA_x_m, mA_y_m, mA_z_m, mB_…, mC_…`: one row
//! per measurement, ten consecutive rows repeating each of 24 configurations. Columns are found
//! by name, so their order does not matter. The course's own `calibration_dataset.mat` (variables
//! `q`, `mA`, `mB`, `mC`) reads too, through [`super::mat`]: its columns `q_1..q_6`,
//! `mA_1..mA_3` (x, y, z), ... stand for the CSV's, and without `config_id` a run of consecutive
//! rows with the same joint values is one configuration (`0`, `1`, ..., as the CSV's `config_id`).
//!
//! # Result
//! - joints `joint_1..joint_6` = `q1..q6`, radians, the controller's values as recorded (the
//!   upstream code applies joint directions `[1, 1, -1, -1, -1, -1]` and offsets
//!   `[0, -pi/2, pi/2, 0, 0, 0]` in its model; the values here are untouched);
//! - targets `A`, `B`, `C` (markers `mA`, `mB`, `mC`): three samples per row, metres, in the
//!   measurement frame;
//! - `config` = `config_id`, so the ten repeats of a pose share an id (pure error);
//! - every sample is for calibration; no standard deviation is given.

use std::sync::Arc;

use nalgebra::Vector3;

use super::numbered;
use crate::csv::{number, records, DataError};
use crate::data::{Measurements, Sample, Split};

/// The dataset's file name.
pub const FILE: &str = "calibration_dataset.csv";

/// Target names, one per marker.
pub const TARGETS: [&str; 3] = ["A", "B", "C"];

/// Parses `calibration_dataset.csv` (see the [module docs](self)).
///
/// # Errors
/// A [`DataError`] for a missing column (naming the columns found), a row with the wrong number
/// of fields, or a cell that is not a finite number.
pub fn parse(text: &str) -> Result<Measurements, DataError> {
    let recs = records(text, ',', true)?;
    let (header, rows) = recs.split_first().ok_or(DataError::Empty {
        found: "an empty file",
    })?;
    if rows.is_empty() {
        return Err(DataError::Empty {
            found: "only a header",
        });
    }
    // A column by its CSV name, or by its name in the .mat export.
    let find = |name: &str, mat: &str| {
        let at = |n: &str| header.fields.iter().position(|f| f == n);
        at(name)
            .or_else(|| at(mat))
            .ok_or_else(|| DataError::Format {
                line: header.line,
                expected: format!("a column '{name}'"),
                found: format!("columns {}", header.fields.join(", ")),
            })
    };
    let config_col = find("config_id", "config_id").ok();
    let joint_cols = (1..=6)
        .map(|i| find(&format!("q{i}_rad"), &format!("q_{i}")))
        .collect::<Result<Vec<_>, _>>()?;
    let mut marker_cols = Vec::new();
    for marker in ["mA", "mB", "mC"] {
        let mut xyz = [0; 3];
        for ((slot, axis), k) in xyz.iter_mut().zip(["x", "y", "z"]).zip(1..) {
            *slot = find(&format!("{marker}_{axis}_m"), &format!("{marker}_{k}"))?;
        }
        marker_cols.push(xyz);
    }
    if config_col.is_none() && !header.fields.iter().any(|f| f == "q_1") {
        // The CSV layout needs its config_id; only the .mat export goes without.
        find("config_id", "config_id")?;
    }
    let mut previous: Option<Vec<f64>> = None;
    let mut runs = 0usize;

    let mut samples = Vec::with_capacity(3 * rows.len());
    for row in rows {
        let line = row.line;
        if row.fields.len() != header.fields.len() {
            return Err(DataError::FieldCount {
                line,
                expected: header.fields.len(),
                found: row.fields.len(),
            });
        }
        let cell = |i: usize| number(&row.fields[i], line, &header.fields[i]);
        let q = joint_cols
            .iter()
            .map(|&i| cell(i))
            .collect::<Result<Vec<_>, _>>()?;
        let config = match config_col {
            Some(c) => row.fields[c].clone(),
            None => {
                if previous.as_ref() != Some(&q) {
                    runs += 1;
                    previous = Some(q.clone());
                }
                (runs - 1).to_string()
            }
        };
        let q: Arc<[f64]> = q.into();
        for (target, xyz) in marker_cols.iter().enumerate() {
            let point = Vector3::new(cell(xyz[0])?, cell(xyz[1])?, cell(xyz[2])?);
            samples.push(Sample {
                time: None,
                orientation: None,
                session: 0,
                q: Arc::clone(&q),
                target,
                point,
                sigma: None,
                config: Some(config.as_str().into()),
                split: Split::Calibration,
                line,
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

    /// Two rows in the layout (made-up values), columns shuffled.
    const EXCERPT: &str = "\
q1_rad,config_id,q2_rad,q3_rad,q4_rad,q5_rad,q6_rad,mA_x_m,mA_y_m,mA_z_m,mB_x_m,mB_y_m,mB_z_m,mC_x_m,mC_y_m,mC_z_m
0.5,0,0.1,0.2,-1,0.3,2,1.1,1.2,1.3,2.1,2.2,2.3,3.1,3.2,3.3
0.5,0,0.1,0.2,-1,0.3,2,1.1001,1.2,1.3,2.1,2.2,2.3,3.1,3.2,3.3
";

    #[test]
    fn three_samples_per_row() {
        let m = parse(EXCERPT).unwrap();
        assert_eq!(m.samples.len(), 6);
        assert_eq!(m.joint_names[5], "joint_6");
        let s = &m.samples[4];
        assert_eq!(s.q[..], [0.5, 0.1, 0.2, -1.0, 0.3, 2.0]);
        assert_eq!((s.target, s.line), (1, 3));
        assert_eq!(s.point, Vector3::new(2.1, 2.2, 2.3));
        assert_eq!(m.samples[3].point.x, 1.1001);
        assert!(m.samples.iter().all(|s| s.config.as_deref() == Some("0")));
    }

    #[test]
    fn the_mat_export_reads_with_configurations_from_runs() {
        let text = "q_1,q_2,q_3,q_4,q_5,q_6,mA_1,mA_2,mA_3,mB_1,mB_2,mB_3,mC_1,mC_2,mC_3
0.5,0.1,0.2,-1,0.3,2,1.1,1.2,1.3,2.1,2.2,2.3,3.1,3.2,3.3
0.5,0.1,0.2,-1,0.3,2,1.1001,1.2,1.3,2.1,2.2,2.3,3.1,3.2,3.3
0.6,0.1,0.2,-1,0.3,2,1.1,1.2,1.3,2.1,2.2,2.3,3.1,3.2,3.3
";
        let m = parse(text).unwrap();
        let configs: Vec<&str> = m
            .samples
            .iter()
            .map(|s| s.config.as_deref().unwrap())
            .collect();
        assert_eq!(configs, ["0", "0", "0", "0", "0", "0", "1", "1", "1"]);
        assert_eq!(m.samples[8].point, Vector3::new(3.1, 3.2, 3.3));
    }

    #[test]
    fn missing_column_is_named() {
        let text = EXCERPT.replacen("q3_rad", "q3", 1);
        let e = parse(&text).unwrap_err().to_string();
        assert!(
            e.starts_with("line 1: expected a column 'q3_rad', found columns q1_rad,"),
            "{e}"
        );
    }
}
