//! DLR Agile Justin humanoid upper body under a Vicon camera system (J. Tenhumberg, B. Bäuml,
//! "Calibration of an Elastic Humanoid Upper Body and Efficient Compensation for Motion
//! Planning", IEEE Humanoids 2021; data from the dlr-alr/dlr-elastic-calibration site).
//!
//! # Layout
//! `measurements.csv`, written by pandas: header `,joints,markers`, then one record per
//! configuration, `index,[numpy vector],"[[numpy 2×3 array]]"`. The marker array's rows are on
//! two text lines inside one quoted field, so 500 records take 1000 lines.
//! - `joints`: 19 commanded joint values, radians: torso (3), right arm (7), left arm (7),
//!   head (2, zero throughout the published file);
//! - `markers`: `[[right x y z], [left x y z]]`, metres, in the camera system's frame.
//!
//! # Result
//! - joints, in the file's order: `torso_1..torso_3`, `right_1..right_7`, `left_1..left_7`,
//!   `head_1`, `head_2` (names chosen here: the dataset gives none). Justin's torso is
//!   mechanically coupled, so it has more joints than the three values recorded; a model for
//!   this set has to express the coupling through these three values;
//! - targets `right` and `left` (the marker on each hand): two samples per record;
//! - `config` = the record's index; all samples for calibration; no standard deviation.

use std::sync::Arc;

use nalgebra::Vector3;

use super::numbered;
use crate::csv::{number, records, DataError};
use crate::data::{Measurements, Sample, Split};

/// The dataset's file name.
pub const FILE: &str = "measurements.csv";

/// Target names: the marker on the right hand, then the left.
pub const TARGETS: [&str; 2] = ["right", "left"];

/// Joint values per record.
const JOINTS: usize = 19;

/// The joint names, in the file's order (see the [module docs](self)).
pub fn joint_names() -> Vec<String> {
    let mut names = numbered("torso", 3);
    names.extend(numbered("right", 7));
    names.extend(numbered("left", 7));
    names.extend(numbered("head", 2));
    names
}

/// Parses `measurements.csv` (see the [module docs](self)).
///
/// # Errors
/// A [`DataError`] for a header other than `,joints,markers`, a record without three fields,
/// a joint vector without 19 numbers, a marker array without 2×3 numbers, or a value that is
/// not a finite number.
pub fn parse(text: &str) -> Result<Measurements, DataError> {
    let recs = records(text, ',', false)?;
    let (header, rows) = recs.split_first().ok_or(DataError::Empty {
        found: "an empty file",
    })?;
    if header.fields != ["", "joints", "markers"] {
        return Err(DataError::Format {
            line: header.line,
            expected: "the header ',joints,markers'".into(),
            found: format!("'{}'", header.fields.join(",")),
        });
    }
    if rows.is_empty() {
        return Err(DataError::Empty {
            found: "only a header",
        });
    }
    let mut samples = Vec::with_capacity(2 * rows.len());
    for row in rows {
        let line = row.line;
        let [index, joints, markers] = row.fields.as_slice() else {
            return Err(DataError::FieldCount {
                line,
                expected: 3,
                found: row.fields.len(),
            });
        };
        let q = numpy_numbers(joints, line, "joints")?;
        if q.len() != JOINTS {
            return Err(DataError::Format {
                line,
                expected: format!("{JOINTS} joint values"),
                found: q.len().to_string(),
            });
        }
        let xyz = numpy_numbers(markers, line, "markers")?;
        if xyz.len() != 6 || !markers.trim_start().starts_with("[[") {
            return Err(DataError::Format {
                line,
                expected: "a 2x3 marker array [[right x y z] [left x y z]]".into(),
                found: format!("'{}'", markers.replace('\n', " ")),
            });
        }
        let q: Arc<[f64]> = q.into();
        for (target, p) in xyz.chunks_exact(3).enumerate() {
            samples.push(Sample {
                time: None,
                orientation: None,
                session: 0,
                q: Arc::clone(&q),
                target,
                point: Vector3::new(p[0], p[1], p[2]),
                sigma: None,
                config: Some(index.as_str().into()),
                split: Split::Calibration,
                line,
                socket: None,
            });
        }
    }
    Ok(Measurements {
        sessions: Vec::new(),
        joint_names: joint_names(),
        targets: TARGETS.map(String::from).to_vec(),
        samples,
    })
}

/// The numbers of a numpy-printed array: brackets and line breaks are separators.
fn numpy_numbers(text: &str, line: usize, column: &str) -> Result<Vec<f64>, DataError> {
    text.split(|c: char| c == '[' || c == ']' || c.is_whitespace())
        .filter(|t| !t.is_empty())
        .map(|t| number(t, line, column))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two records in the layout (made-up values): numpy's padding, `0.` and exponent forms; the
    /// first joint vector wraps onto a second line, which pandas quotes.
    const EXCERPT: &str = ",joints,markers
0,\"[ 1.0e-01 -2.0e-01  3.0e-01  1. 2. 3. 4. 5. 6. 7.
  -1. -2. -3. -4. -5. -6. -7.  0.          0.        ]\",\"[[-1.5   2.25  1.0]
 [-3.0   1.5   1.75]]\"
1,[0.1 0.2 0.3 1 2 3 4 5 6 7 -1 -2 -3 -4 -5 -6 -7 0 0],\"[[1 2 3]
 [4 5 6]]\"
";

    #[test]
    fn two_samples_per_record_right_then_left() {
        let m = parse(EXCERPT).unwrap();
        assert_eq!(m.samples.len(), 4);
        assert_eq!(m.joint_names.len(), 19);
        assert_eq!(m.joint_names[3], "right_1");
        assert_eq!(m.joint_names[18], "head_2");
        let (r, l) = (&m.samples[0], &m.samples[1]);
        assert_eq!((r.target, l.target), (0, 1));
        assert_eq!(r.point, Vector3::new(-1.5, 2.25, 1.0));
        assert_eq!(l.point, Vector3::new(-3.0, 1.5, 1.75));
        assert_eq!(r.q[0], 0.1);
        assert_eq!(r.q[10], -1.0);
        assert_eq!((r.line, m.samples[2].line), (2, 5));
        assert_eq!(m.samples[3].config.as_deref(), Some("1"));
    }

    #[test]
    fn wrong_sizes_are_named() {
        let text = ",joints,markers\n0,[1 2 3],\"[[1 2 3]\n [4 5 6]]\"\n";
        assert_eq!(
            parse(text).unwrap_err().to_string(),
            "line 2: expected 19 joint values, found 3"
        );
        let e = parse("a,b\n").unwrap_err().to_string();
        assert_eq!(
            e,
            "line 1: expected the header ',joints,markers', found 'a,b'"
        );
    }
}
