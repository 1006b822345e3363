//! Hilti construction-robot stationing datasets: a lifting column and a Doosan arm measured by
//! a total station (Hilti-Research/construction_robot_stationing_datasets; CC BY-NC-SA 3.0).
//!
//! # Layout
//! One YAML file per dataset (`flat.yaml`, `pallet.yaml`, …):
//!
//! ```yaml
//! joint_names: [column_prismatic_joint, dsr_joint1, …, dsr_joint6]
//! column_heights:
//!   1.98:
//!     solution_spaces:
//!       0:
//!         stationing_measurements:
//!         - {id: 0, joint_states: [1.98, 1.47, …], prism_position: [7.33, 5.83, 1.17], …}
//!         evaluation_measurements: […]
//! ```
//!
//! `joint_states`: the column in metres, then the arm in radians; `prism_position`: the prism on
//! the tool in the total station's frame, metres. Fields other than these (time, commanded
//! position, `upside_down`, accelerometers) are not imported.
//!
//! # Result
//! - joints: the file's `joint_names` (the URDF's names: `column_prismatic_joint` is prismatic,
//!   metres; the column's two real segments follow it as URDF mimic joints);
//! - one target, `prism`;
//! - stationing measurements → calibration split, evaluation measurements → validation split;
//! - `config`: `h<column height>/s<solution space>/<id>`;
//! - `sigma`: 0.75 mm per axis, the total station's datasheet value the dataset's README gives;
//! - `Sample::line`: the line of the measurement's `- id:` entry.
//!
//! Undeclared effects are present by design (column deflection, backlash, base tilt in some files,
//! temperature in `outdoor.yaml`).

use nalgebra::Vector3;
use serde_yaml::Value;

use crate::csv::DataError;
use crate::data::{Measurements, Sample, Split};

/// Target name: the total-station prism on the tool.
pub const TARGET: &str = "prism";

/// Standard deviation of a total-station point per axis (metres): Hilti PLT 300 datasheet value
/// from the dataset's README.
pub const SIGMA: f64 = 0.75e-3;

/// Parses one stationing YAML file (see the [module docs](self)).
///
/// # Errors
/// [`DataError::Format`] for invalid YAML, [`DataError::Content`] for a missing or malformed
/// field or a NaN or infinite value (naming the field and the station), [`DataError::Empty`] for a
/// file without measurements.
pub fn parse(text: &str) -> Result<Measurements, DataError> {
    if let Some(line) = super::too_deep_at(text) {
        return Err(DataError::Format {
            line,
            expected: format!(
                "lists and maps nested at most {} deep",
                super::MAX_FLOW_DEPTH
            ),
            found: "deeper".into(),
        });
    }
    let root: Value = serde_yaml::from_str(text).map_err(|e| match e.location() {
        Some(at) => DataError::Format {
            line: at.line(),
            expected: "a YAML document".into(),
            found: e.to_string(),
        },
        None => format("a YAML document", &e.to_string()),
    })?;
    let names_line = text
        .lines()
        .position(|l| l.trim_start().starts_with("joint_names"))
        .map_or(1, |i| i + 1);
    let names_error = |found: String| DataError::Format {
        line: names_line,
        expected: "a list of distinct joint names in 'joint_names'".into(),
        found,
    };
    let joint_names: Vec<String> = match field(&root, "joint_names", "the file")?.as_sequence() {
        Some(list) => list
            .iter()
            .map(|v| {
                v.as_str()
                    .map(String::from)
                    .ok_or_else(|| names_error(format!("{v:?}, which is not a name")))
            })
            .collect::<Result<_, _>>()?,
        None => Vec::new(),
    };
    if joint_names.is_empty() {
        return Err(names_error("no names".into()));
    }
    // The names become the columns of the canonical CSV (found by fuzzing: a repeated name was
    // accepted and written as two columns of one name).
    if let Some(problem) = crate::csv::joint_name_problem(&joint_names) {
        return Err(names_error(problem));
    }
    // Measurements in document order, matched with the lines of their `- id:` entries.
    let id_lines: Vec<usize> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| l.trim_start().starts_with("- id:"))
        .map(|(i, _)| i + 1)
        .collect();
    let mut samples = Vec::new();
    let heights = mapping(
        field(&root, "column_heights", "the file")?,
        "column_heights",
    )?;
    for (height, station) in heights {
        let height = key(height);
        let spaces = mapping(
            field(station, "solution_spaces", &format!("height {height}"))?,
            "solution_spaces",
        )?;
        for (space, lists) in spaces {
            let space = key(space);
            let here = format!("height {height}, solution space {space}");
            for (name, list) in mapping(lists, &here)? {
                let split = match name.as_str() {
                    Some("stationing_measurements") => Split::Calibration,
                    Some("evaluation_measurements") => Split::Validation,
                    _ => continue,
                };
                let Some(list) = list.as_sequence() else {
                    return Err(format(
                        &format!("a list of measurements at {here}"),
                        "another value",
                    ));
                };
                for entry in list {
                    let id = field(entry, "id", &here).map(key)?;
                    let at = format!("{here}, id {id}");
                    let q = numbers(field(entry, "joint_states", &at)?, joint_names.len(), &at)?;
                    let p = numbers(field(entry, "prism_position", &at)?, 3, &at)?;
                    samples.push(Sample {
                        time: None,
                        orientation: None,
                        session: 0,
                        q: q.into(),
                        target: 0,
                        point: Vector3::new(p[0], p[1], p[2]),
                        sigma: Some(Vector3::repeat(SIGMA)),
                        config: Some(compact_str::format_compact!("h{height}/s{space}/{id}")),
                        split,
                        line: 0,
                        socket: None,
                    });
                }
            }
        }
    }
    if samples.is_empty() {
        return Err(DataError::Empty {
            found: "no measurements",
        });
    }
    if id_lines.len() == samples.len() {
        for (s, line) in samples.iter_mut().zip(id_lines) {
            s.line = line;
        }
    }
    Ok(Measurements {
        sessions: Vec::new(),
        joint_names,
        targets: vec![TARGET.into()],
        samples,
    })
}

fn format(expected: &str, found: &str) -> DataError {
    DataError::Content {
        expected: expected.into(),
        found: found.into(),
    }
}

fn field<'v>(v: &'v Value, name: &str, at: &str) -> Result<&'v Value, DataError> {
    v.get(name)
        .ok_or_else(|| format(&format!("a field '{name}' at {at}"), "none"))
}

fn mapping<'v>(v: &'v Value, what: &str) -> Result<&'v serde_yaml::Mapping, DataError> {
    v.as_mapping()
        .ok_or_else(|| format(&format!("a mapping in {what}"), "another value"))
}

/// A mapping key or id as text.
fn key(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        Value::Number(n) => n.to_string(),
        Value::Bool(b) => b.to_string(),
        _ => "?".into(),
    }
}

/// A value as flow-style text: `[1, 2]`.
fn show(v: &Value) -> String {
    match v.as_sequence() {
        Some(items) => format!("[{}]", items.iter().map(key).collect::<Vec<_>>().join(", ")),
        None => key(v),
    }
}

fn numbers(v: &Value, n: usize, at: &str) -> Result<Vec<f64>, DataError> {
    let values: Option<Vec<f64>> = v
        .as_sequence()
        .and_then(|s| s.iter().map(Value::as_f64).collect());
    match values {
        Some(values) if values.len() == n => {
            if let Some(bad) = values.iter().find(|x| !x.is_finite()) {
                return Err(format(&format!("finite numbers at {at}"), &bad.to_string()));
            }
            Ok(values)
        }
        _ => Err(format(&format!("a list of {n} numbers at {at}"), &show(v))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A made-up file in the layout: two stations, one with evaluation points.
    const EXCERPT: &str = "\
joint_names: [column_prismatic_joint, a1, a2]
column_heights:
  1.98:
    solution_spaces:
      0:
        stationing_measurements:
        - id: 0
          time: 1.0
          joint_states: [1.5, 0.1,
            -0.2]
          prism_position: [7.0, 5.5, 1.25]
        evaluation_measurements:
        - id: 1
          joint_states: [1.5, 0.3, 0.4]
          prism_position: [7.5, 5.0, 1.0]
  2.72:
    solution_spaces:
      3:
        stationing_measurements: []
        evaluation_measurements:
        - id: 7
          joint_states: [2.7, 0.0, 0.0]
          prism_position: [1, 2, 3]
";

    #[test]
    fn stationing_is_calibration_and_evaluation_is_validation() {
        let m = parse(EXCERPT).unwrap();
        assert_eq!(m.joint_names, vec!["column_prismatic_joint", "a1", "a2"]);
        assert_eq!(m.samples.len(), 3);
        let s = &m.samples;
        assert_eq!(s[0].q[..], [1.5, 0.1, -0.2]);
        assert_eq!(s[0].point, Vector3::new(7.0, 5.5, 1.25));
        assert_eq!(s[0].split, Split::Calibration);
        assert_eq!(s[0].sigma, Some(Vector3::repeat(0.75e-3)));
        assert_eq!((s[1].split, s[1].line), (Split::Validation, 13));
        assert_eq!(s[2].config.as_deref(), Some("h2.72/s3/7"));
        assert_eq!(s[2].point, Vector3::new(1.0, 2.0, 3.0));
    }

    /// Fuzzing find: a repeated joint name was accepted and written as two CSV columns of one
    /// name, which the CSV reader refuses.
    #[test]
    fn joint_names_must_be_distinct_unreserved_names() {
        for (names, found) in [
            ("[column_prismatic_joint, a1, a1]", "'a1' twice"),
            (
                "[column_prismatic_joint, x, a2]",
                "'x', the name of a reserved column",
            ),
            ("[column_prismatic_joint, 7, a2]", "which is not a name"),
            ("[]", "no names"),
        ] {
            let text = EXCERPT.replace("[column_prismatic_joint, a1, a2]", names);
            let err = parse(&text).unwrap_err().to_string();
            assert!(
                err.starts_with("line 1: expected a list of distinct joint names")
                    && err.contains(found),
                "{names}: {err}"
            );
        }
    }

    #[test]
    fn malformed_fields_are_named() {
        let text = EXCERPT.replace("prism_position: [1, 2, 3]", "prism_position: [1, 2]");
        assert_eq!(
            parse(&text).unwrap_err().to_string(),
            "expected a list of 3 numbers at height 2.72, solution space 3, id 7, found [1, 2]"
        );
    }
}
