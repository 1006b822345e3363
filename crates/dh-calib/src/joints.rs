//! Joint-value files and the map from a controller's joint columns to a table's rows.
//!
//! `predict` and `compensate` read joint values only: one header line naming the columns, one
//! pose per line, `#` comment lines. Each of the model's measured joints needs a column
//! (radians, metres for prismatic joints, or the units of [`CsvOptions`]); an optional `config`
//! column names the pose, and every other column is ignored, so a measurement file (with its
//! `x,y,z`) is a joint-value file too.
//!
//! A table row's joint value is not always a column of its own: a mimic row follows its
//! driver (`multiplier · driver + offset`) and a coupled row is a sum of columns (FANUC's J3
//! measured from the horizontal). [`JointMap`] is that linear map, `q_rows = A · q_columns + b`.

use dh_core::DhTable;
use nalgebra::DMatrix;

use crate::csv::{
    array_error, check_name, joint_value, number, AngleUnit, CsvOptions, DataError, Records,
    SampleArrays, MAX_PLAUSIBLE_METRES, MAX_PLAUSIBLE_RADIANS,
};

/// The linear map from measured joint columns to a table's row values (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct JointMap {
    /// The measured columns, in the table's row order of first use.
    pub columns: Vec<String>,
    /// `rows × columns`.
    pub matrix: DMatrix<f64>,
    /// Per row.
    pub offset: Vec<f64>,
}

impl JointMap {
    /// The map of `table` with its `coupled` joints (`(joint, [(driver, coefficient)])`, as a
    /// sheet gives them): plain rows read their own column, mimic rows their driver's, coupled
    /// rows the sum over their drivers' columns.
    pub fn new(table: &DhTable, coupled: &[(String, Vec<(String, f64)>)]) -> JointMap {
        let mut columns: Vec<String> = Vec::new();
        let mut terms: Vec<(Vec<(usize, f64)>, f64)> = Vec::with_capacity(table.rows.len());
        let mut column = |name: &str| match columns.iter().position(|c| c == name) {
            Some(i) => i,
            None => {
                columns.push(name.to_string());
                columns.len() - 1
            }
        };
        for r in &table.rows {
            let coupled = coupled.iter().find(|(j, _)| j == &r.name);
            terms.push(match (&r.mimic, coupled) {
                (Some(m), _) => (vec![(column(&m.joint), m.multiplier)], m.offset),
                (None, Some((_, t))) => (t.iter().map(|(d, c)| (column(d), *c)).collect(), 0.0),
                (None, None) => (vec![(column(&r.name), 1.0)], 0.0),
            });
        }
        let mut matrix = DMatrix::zeros(table.rows.len(), columns.len());
        let mut offset = Vec::with_capacity(table.rows.len());
        for (r, (t, b)) in terms.into_iter().enumerate() {
            for (c, k) in t {
                matrix[(r, c)] += k;
            }
            offset.push(b);
        }
        JointMap {
            columns,
            matrix,
            offset,
        }
    }

    /// Row values (one per table row) of column values `q` (one per [`JointMap::columns`]).
    pub fn rows(&self, q: &[f64]) -> Vec<f64> {
        (0..self.matrix.nrows())
            .map(|r| {
                self.offset[r]
                    + (0..self.matrix.ncols())
                        .map(|c| self.matrix[(r, c)] * q.get(c).copied().unwrap_or(0.0))
                        .sum::<f64>()
            })
            .collect()
    }
}

/// One pose of a joint-value file.
#[derive(Clone, Debug, PartialEq)]
pub struct JointRow {
    /// Its line in the file (1-based).
    pub line: usize,
    /// The `config` cell, when the file has that column and the cell is not empty.
    pub config: Option<String>,
    /// The `target` cell, when the file has that column (a measurement file) and the cell is
    /// not empty.
    pub target: Option<String>,
    /// The `session` cell, when the file has that column (a measurement file of several
    /// measurement sessions) and the cell is not empty.
    pub session: Option<String>,
    /// Values in metres and radians, one per requested column, in the requested order.
    pub q: Vec<f64>,
    /// The `time` cell (seconds, any origin), when the file has that column and the cell is
    /// not empty: what effects of time (`thermal_growth`) read.
    pub time: Option<f64>,
}

/// Reads a joint-value file (see the module docs): the columns `joints`, in that order,
/// converted to metres and radians with `opts` (its `prismatic` names the length columns).
///
/// # Errors
/// As the measurement reader ([`crate::csv::parse_measurements`]) for the same faults: an
/// empty file, a missing or duplicate column, a wrong cell count, a cell that is not a finite
/// number, a value that looks like the other unit or is beyond four turns or 100 m, control
/// characters in a name. Each names the line and the column.
pub fn parse_joint_values(
    text: &str,
    joints: &[String],
    opts: &CsvOptions,
) -> Result<Vec<JointRow>, DataError> {
    let mut records = Records::new(text, ',', true).peekable();
    let header = records.next().ok_or(DataError::Empty {
        found: "an empty file",
    })??;
    if records.peek().is_none() {
        return Err(DataError::Empty {
            found: "only a header",
        });
    }
    for (k, field) in header.fields.iter().enumerate() {
        check_name(field, header.line, &format!("{}", k + 1))?;
        if header.fields[..k].contains(field) {
            return Err(DataError::DuplicateColumn {
                line: header.line,
                column: field.clone(),
            });
        }
    }
    let find = |name: &str| header.fields.iter().position(|n| n == name);
    let missing: Vec<String> = joints
        .iter()
        .filter(|j| find(j).is_none())
        .cloned()
        .collect();
    if !missing.is_empty() {
        return Err(DataError::MissingJoints {
            line: header.line,
            missing,
            found: header.fields.clone(),
        });
    }
    let cols: Vec<usize> = joints.iter().filter_map(|j| find(j)).collect();
    let config = find("config");
    let target = find("target");
    let session = find("session");
    let time = find("time");
    let mut out = Vec::new();
    for record in records {
        let record = record?;
        let line = record.line;
        if record.fields.len() != header.fields.len() {
            return Err(DataError::FieldCount {
                line,
                expected: header.fields.len(),
                found: record.fields.len(),
            });
        }
        let mut q = Vec::with_capacity(cols.len());
        for (&c, name) in cols.iter().zip(joints) {
            let value = number(&record.fields[c], line, name)?;
            let prismatic = opts.prismatic.contains(name);
            if !prismatic
                && opts.angle_unit == AngleUnit::Radian
                && value.abs() > MAX_PLAUSIBLE_RADIANS
            {
                return Err(DataError::SuspiciousUnit {
                    line,
                    column: name.clone(),
                    value,
                    unit: "rad",
                    hint: "looks like degrees; pass --angle-unit deg",
                });
            }
            let si = if prismatic {
                opts.length_unit.to_metres(value)
            } else {
                opts.angle_unit.to_radians(value)
            };
            let cap = if prismatic {
                MAX_PLAUSIBLE_METRES
            } else {
                MAX_PLAUSIBLE_RADIANS
            };
            if si.abs() > cap {
                return Err(DataError::SuspiciousUnit {
                    line,
                    column: name.clone(),
                    value,
                    unit: if prismatic { "m" } else { "rad" },
                    hint: "is beyond four turns or 100 m: no pose of an arm",
                });
            }
            q.push(si);
        }
        let name = |column: Option<usize>, what: &str| -> Result<Option<String>, DataError> {
            match column.map(|c| record.fields[c].clone()) {
                Some(c) if !c.is_empty() => {
                    check_name(&c, line, what)?;
                    Ok(Some(c))
                }
                _ => Ok(None),
            }
        };
        let config = name(config, "config")?;
        let target = name(target, "target")?;
        let session = name(session, "session")?;
        let time = match time.map(|c| record.fields[c].as_str()) {
            None | Some("") => None,
            Some(text) => Some(number(text, line, "time")?),
        };
        out.push(JointRow {
            line,
            config,
            target,
            session,
            q,
            time,
        });
    }
    Ok(out)
}

/// The joint-value rows of `arrays` (their joint columns, in order, and the optional `config`,
/// `target` and `session` columns; no points), converted to metres and radians with `opts` as
/// [`parse_joint_values`] converts a file's cells. `JointRow::line` is the line the row would
/// have in the same CSV file (row `i` at line `i + 2`); empty names are `None`.
///
/// # Errors
/// Columns of different lengths, no rows, points given ([`DataError::Content`],
/// [`DataError::Empty`]); a value that is not finite or beyond four turns (8π rad) or 100 m, a
/// name with control characters: [`DataError::Array`] naming the row (0-based) and the column.
pub fn joint_rows(arrays: &SampleArrays, opts: &CsvOptions) -> Result<Vec<JointRow>, DataError> {
    let n = arrays.rows(false)?;
    let width = arrays.joint_names.len();
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let row = i;
        let mut q = Vec::with_capacity(width);
        for (k, name) in arrays.joint_names.iter().enumerate() {
            let revolute = !opts.prismatic.contains(name);
            q.push(joint_value(
                arrays.q[i * width + k],
                revolute,
                row,
                name,
                opts,
            )?);
        }
        let name = |col: &Option<Vec<String>>, what: &str| -> Result<Option<String>, DataError> {
            match col.as_ref().map(|c| c[i].clone()) {
                Some(c) if !c.is_empty() => {
                    check_name(&c, row, what).map_err(|_| {
                        array_error(
                            row,
                            what,
                            "a name without control characters",
                            format!("{c:?}"),
                        )
                    })?;
                    Ok(Some(c))
                }
                _ => Ok(None),
            }
        };
        out.push(JointRow {
            line: i + 2,
            config: name(&arrays.config, "config")?,
            target: name(&arrays.target, "target")?,
            session: name(&arrays.session, "session")?,
            q,
            time: crate::csv::time_at(&arrays.time, row)?,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use dh_core::{Convention, DhRow, Mimic};
    use nalgebra::Isometry3;

    fn table() -> DhTable {
        let row = |name: &str| DhRow::revolute(name, 0.1, 0.0, 0.0, 0.0);
        let mut f = row("f");
        f.mimic = Some(Mimic {
            joint: "j1".into(),
            multiplier: 2.0,
            offset: 0.5,
        });
        DhTable {
            convention: Convention::Standard,
            base: Isometry3::identity(),
            tool: Isometry3::identity(),
            rows: vec![row("j1"), row("j2"), row("j3"), f],
        }
    }

    #[test]
    fn mimic_and_coupled_rows_follow_their_columns() {
        let coupled = vec![(
            "j3".to_string(),
            vec![("j3".to_string(), 1.0), ("j2".to_string(), 1.0)],
        )];
        let map = JointMap::new(&table(), &coupled);
        assert_eq!(map.columns, ["j1", "j2", "j3"]);
        let rows = map.rows(&[0.1, 0.2, 0.3]);
        let want = [0.1, 0.2, 0.5, 0.7];
        for (a, b) in rows.iter().zip(want) {
            assert!((a - b).abs() < 1e-15, "{rows:?}");
        }
    }

    #[test]
    fn joint_files_read_in_the_requested_order_and_name_bad_cells() {
        let joints = vec!["b".to_string(), "a".to_string()];
        let opts = CsvOptions {
            angle_unit: AngleUnit::Degree,
            ..CsvOptions::default()
        };
        let rows =
            parse_joint_values("# c\na,b,x,config\n90,180,1,p1\n0,0,,\n", &joints, &opts).unwrap();
        assert_eq!(rows.len(), 2);
        assert_eq!(rows[0].config.as_deref(), Some("p1"));
        assert!((rows[0].q[0] - std::f64::consts::PI).abs() < 1e-15);
        assert_eq!(rows[1].config, None);
        assert_eq!(rows[1].line, 4);
        let e = parse_joint_values("a,b\n1,x\n", &joints, &CsvOptions::default()).unwrap_err();
        assert!(e.to_string().contains("line 2, column 'b'"), "{e}");
        let e = parse_joint_values("a\n1\n", &joints, &CsvOptions::default()).unwrap_err();
        assert!(e.to_string().contains("missing joint column(s) 'b'"), "{e}");
        let e = parse_joint_values("a,b\n90,0\n", &joints, &CsvOptions::default()).unwrap_err();
        assert!(e.to_string().contains("--angle-unit deg"), "{e}");
        assert!(parse_joint_values("a,b\n", &joints, &CsvOptions::default()).is_err());
    }

    #[test]
    fn joint_rows_read_arrays_as_the_file_reader_reads_cells() {
        let arrays = SampleArrays {
            joint_names: vec!["j2".into(), "j1".into()],
            q: vec![90.0, 1.0, -45.0, 2.0],
            config: Some(vec!["p1".into(), String::new()]),
            ..SampleArrays::default()
        };
        let opts = CsvOptions {
            angle_unit: AngleUnit::Degree,
            ..CsvOptions::default()
        };
        let joints = vec!["j1".to_string(), "j2".to_string()];
        let rows = joint_rows(&arrays.with_joints(&joints).unwrap(), &opts).unwrap();
        let text = "j1,j2,config\n1,90,p1\n2,-45,\n";
        let file = parse_joint_values(text, &joints, &opts).unwrap();
        assert_eq!(rows.len(), 2);
        for (a, f) in rows.iter().zip(&file) {
            assert_eq!(a.q, f.q);
            assert_eq!(a.config, f.config);
            assert_eq!(a.line, f.line);
        }
        let mut bad = arrays.clone();
        bad.q[3] = f64::NAN;
        let e = joint_rows(&bad, &opts).unwrap_err();
        assert_eq!(
            e.to_string(),
            "row 1, column 'j1': expected a finite number, found NaN"
        );
        let e = arrays.with_joints(&["j3".to_string()]).unwrap_err();
        assert!(e.to_string().contains("'j3'"), "{e}");
        bad.q.pop();
        assert!(joint_rows(&bad, &opts).is_err());
    }
}
