//! The user's own export, laid out by a column map: which columns hold the joint values, the
//! measured point, and optionally the target, the point's standard deviation, the pose
//! identifier, the calibration/validation split, the session and a 6-DoF device's orientation
//! ([`orientation`]); in which units; with which separator; with or without a header line.
//!
//! # Frames and units
//! Points are in the measuring device's frame, converted to metres with
//! [`ColumnMap::length_scale`]; joint values to radians with [`ColumnMap::angle_scale`] (joints
//! named in [`ColumnMap::prismatic`] to metres with the length scale). Orientations are the
//! target frame's rotation in the device frame, their angles in the angle unit (see
//! [`orientation`]). Lines starting with `#` are comments.
//!
//! # Columns
//! A [`ColumnRef`] is a 1-based column number or a header name. A decimal comma (`1,5`) is not
//! read: with `;` as separator, cells must use a decimal point.

use nalgebra::Vector3;

use crate::csv::{
    check_name, number, parse_split, DataError, Records, MAX_PLAUSIBLE_METRES as MAX_METRES,
    MAX_PLAUSIBLE_RADIANS as MAX_RADIANS, SIGMA_FLOOR,
};
use crate::data::{Measurements, Sample, Split};

pub mod orientation;
pub use orientation::{OrientationMap, RotationColumns};

/// A column by 1-based number or by header name.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ColumnRef {
    /// 1-based column number.
    Number(usize),
    /// A header name (needs a header line).
    Name(String),
}

impl ColumnRef {
    /// Parses a list of columns: names or 1-based numbers and ranges (`1-6`), separated by
    /// commas (`1-6`, `q1,q2,q3`, `7,8,9`).
    ///
    /// # Errors
    /// An empty item, a column 0 or a backwards range.
    pub fn parse_list(text: &str) -> Result<Vec<ColumnRef>, String> {
        let mut out = Vec::new();
        for item in text.split(',').map(str::trim) {
            if item.is_empty() {
                return Err(format!("expected column numbers or names, found '{text}'"));
            }
            let range = item.split_once('-').and_then(|(a, b)| {
                Some((
                    a.trim().parse::<usize>().ok()?,
                    b.trim().parse::<usize>().ok()?,
                ))
            });
            match (item.parse::<usize>(), range) {
                (Ok(0), _) | (_, Some((0, _))) => {
                    return Err(format!("expected columns numbered from 1, found '{item}'"))
                }
                (Ok(n), _) => out.push(ColumnRef::Number(n)),
                (_, Some((a, b))) if a <= b => out.extend((a..=b).map(ColumnRef::Number)),
                (_, Some(_)) => {
                    return Err(format!("expected a range low-high, found '{item}'"));
                }
                _ => out.push(ColumnRef::Name(item.to_string())),
            }
        }
        Ok(out)
    }
}

/// How the user's file is laid out (see the [module docs](self)).
#[derive(Clone, Debug, PartialEq)]
pub struct ColumnMap {
    /// The joint columns, in the model's joint order.
    pub joints: Vec<ColumnRef>,
    /// Joint names for the output, one per joint column; empty: the header's names (or
    /// `joint_1..n` without a header).
    pub joint_names: Vec<String>,
    /// The `x`, `y`, `z` columns of the measured point.
    pub point: [ColumnRef; 3],
    /// The target (reflector, marker) name column; without it every row measures target `t1`.
    pub target: Option<ColumnRef>,
    /// The isotropic standard deviation column.
    pub sigma: Option<ColumnRef>,
    /// The pose identifier column (repeats share it).
    pub config: Option<ColumnRef>,
    /// The split column (`calibration`/`train` or `validation`/`test`).
    pub set: Option<ColumnRef>,
    /// The measurement session column (a non-empty name per row; see [`crate::sessions`]):
    /// each session has its own device frame. Without it every row is in one session.
    pub session: Option<ColumnRef>,
    /// A 6-DoF device's orientation columns ([`orientation`]); `None`: points. Needs
    /// [`ColumnMap::sigma`] (the position sigma weighs the angle against the position).
    pub orientation: Option<OrientationMap>,
    /// Separator; `None` detects `,`, `;` or tab from the first data line.
    pub delimiter: Option<char>,
    /// Whether the first non-comment line is a header.
    pub header: bool,
    /// Metres per unit of the points, sigmas and prismatic joints (1e-3 for mm).
    pub length_scale: f64,
    /// Radians per unit of the revolute joints (π/180 for degrees).
    pub angle_scale: f64,
    /// Joints (by output name) that are prismatic.
    pub prismatic: Vec<String>,
}

/// The separator of `text`: the first of `,` `;` tab that occurs most on its first non-comment
/// line.
fn detect_delimiter(text: &str) -> char {
    let line = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))
        .unwrap_or("");
    [',', ';', '\t']
        .into_iter()
        .max_by_key(|d| (line.matches(*d).count(), usize::from(*d == ',')))
        .unwrap_or(',')
}

/// Reads `text` laid out as `map` says (see the [module docs](self)), with the warnings a
/// reader should see: standard deviations of 0 floored at [`SIGMA_FLOOR`], as the canonical
/// reader floors them.
///
/// # Errors
/// A [`DataError`] naming the line and column: no data rows, a column that is not there (by
/// number or name), a cell that is not a finite number, a negative standard deviation, values
/// that look like another unit, an unknown split, a name with control or bidi characters.
pub fn parse(text: &str, map: &ColumnMap) -> Result<(Measurements, Vec<String>), DataError> {
    let mut zero_sigmas: Vec<usize> = Vec::new();
    let delimiter = map.delimiter.unwrap_or_else(|| detect_delimiter(text));
    let mut rows = Records::new(text, delimiter, true).peekable();
    let header = if map.header {
        let h = rows.next().ok_or(DataError::Empty {
            found: "an empty file",
        })??;
        for (k, field) in h.fields.iter().enumerate() {
            check_name(field, h.line, &format!("{}", k + 1))?;
        }
        Some(h)
    } else {
        None
    };
    let width = match (&header, rows.peek()) {
        (Some(h), _) => h.fields.len(),
        (None, Some(Ok(r))) => r.fields.len(),
        _ => 0,
    };
    let header_line = header.as_ref().map_or(1, |h| h.line);
    let resolve = |c: &ColumnRef| -> Result<usize, DataError> {
        match c {
            ColumnRef::Number(n) if *n <= width => Ok(n - 1),
            ColumnRef::Number(n) => Err(DataError::Format {
                line: header_line,
                expected: format!("a column {n} (the file has {width})"),
                found: "none".into(),
            }),
            ColumnRef::Name(name) => header
                .as_ref()
                .and_then(|h| h.fields.iter().position(|f| f == name))
                .ok_or_else(|| DataError::Format {
                    line: header_line,
                    expected: format!("a column named '{name}'"),
                    found: match &header {
                        Some(h) => format!("the columns {}", h.fields.join(", ")),
                        None => "no header line (name columns by number)".into(),
                    },
                }),
        }
    };
    let joints: Vec<usize> = map.joints.iter().map(resolve).collect::<Result<_, _>>()?;
    if joints.is_empty() {
        return Err(DataError::Content {
            expected: "at least one joint column".into(),
            found: "none".into(),
        });
    }
    let point = [
        resolve(&map.point[0])?,
        resolve(&map.point[1])?,
        resolve(&map.point[2])?,
    ];
    let optional = |c: &Option<ColumnRef>| c.as_ref().map(resolve).transpose();
    let (target_col, sigma_col, config_col, set_col) = (
        optional(&map.target)?,
        optional(&map.sigma)?,
        optional(&map.config)?,
        optional(&map.set)?,
    );
    let session_col = optional(&map.session)?;
    let orientation_cols = match &map.orientation {
        None => None,
        Some(_) if sigma_col.is_none() => {
            return Err(DataError::Content {
                expected: "a sigma column with orientation columns (the position sigma weighs                            the angle against the position)"
                    .into(),
                found: "none".into(),
            })
        }
        Some(o) => Some(o.resolve(&resolve)?),
    };
    let joint_names: Vec<String> = if !map.joint_names.is_empty() {
        if map.joint_names.len() != joints.len() {
            return Err(DataError::Content {
                expected: format!("{} joint names, one per joint column", joints.len()),
                found: format!("{}", map.joint_names.len()),
            });
        }
        map.joint_names.clone()
    } else {
        joints
            .iter()
            .enumerate()
            .map(|(k, &c)| match &header {
                Some(h) => h.fields[c].clone(),
                None => format!("joint_{}", k + 1),
            })
            .collect()
    };
    let column_name = |c: usize| match &header {
        Some(h) => h.fields.get(c).cloned().unwrap_or_default(),
        None => format!("{}", c + 1),
    };
    let mut m = Measurements {
        sessions: Vec::new(),
        joint_names: joint_names.clone(),
        targets: Vec::new(),
        samples: Vec::new(),
    };
    for row in rows {
        let row = row?;
        let line = row.line;
        if row.fields.len() != width {
            return Err(DataError::Format {
                line,
                expected: format!("{width} fields"),
                found: format!("{}", row.fields.len()),
            });
        }
        let cell = |c: usize| row.fields[c].as_str();
        let mut q = Vec::with_capacity(joints.len());
        for (k, &c) in joints.iter().enumerate() {
            let v = number(cell(c), line, &column_name(c))?;
            let prismatic = map.prismatic.contains(&joint_names[k]);
            let (value, limit, unit) = if prismatic {
                (v * map.length_scale, MAX_METRES, "m")
            } else {
                (v * map.angle_scale, MAX_RADIANS, "rad")
            };
            if value.abs() > limit {
                return Err(DataError::Format {
                    line,
                    expected: format!(
                        "a joint value within {limit:.1} {unit} in column '{}' (is the angle unit right?)",
                        column_name(c)
                    ),
                    found: format!("'{}'", cell(c)),
                });
            }
            q.push(value);
        }
        let mut p = Vector3::zeros();
        for (k, &c) in point.iter().enumerate() {
            p[k] = number(cell(c), line, &column_name(c))? * map.length_scale;
            if p[k].abs() > MAX_METRES {
                return Err(DataError::Format {
                    line,
                    expected: format!(
                        "a coordinate within {MAX_METRES} m in column '{}' (is the length unit right?)",
                        column_name(c)
                    ),
                    found: format!("'{}'", cell(c)),
                });
            }
        }
        let target_name = match target_col {
            Some(c) => {
                check_name(cell(c), line, &column_name(c))?;
                cell(c).to_string()
            }
            None => "t1".to_string(),
        };
        let target = match m.targets.iter().position(|t| *t == target_name) {
            Some(k) => k,
            None => {
                m.targets.push(target_name);
                m.targets.len() - 1
            }
        };
        let sigma = match sigma_col {
            Some(c) if !cell(c).is_empty() => {
                let s = number(cell(c), line, &column_name(c))?;
                if s < 0.0 {
                    return Err(DataError::Format {
                        line,
                        expected: format!(
                            "a standard deviation >= 0 in column '{}'",
                            column_name(c)
                        ),
                        found: format!("'{}'", cell(c)),
                    });
                }
                let s = if s == 0.0 {
                    zero_sigmas.push(line);
                    SIGMA_FLOOR
                } else {
                    s * map.length_scale
                };
                Some(Vector3::repeat(s))
            }
            _ => None,
        };
        let config = match config_col {
            Some(c) if !cell(c).is_empty() => {
                check_name(cell(c), line, &column_name(c))?;
                Some(cell(c).into())
            }
            _ => None,
        };
        let split = match set_col {
            Some(c) if !cell(c).is_empty() => {
                parse_split(cell(c)).ok_or_else(|| DataError::Format {
                    line,
                    expected: format!(
                        "calibration, train, validation or test in column '{}'",
                        column_name(c)
                    ),
                    found: format!("'{}'", cell(c)),
                })?
            }
            _ => Split::Calibration,
        };
        let session = match session_col {
            None => 0,
            Some(c) if cell(c).is_empty() => {
                return Err(DataError::Format {
                    line,
                    expected: format!("a session name in column '{}'", column_name(c)),
                    found: "an empty cell".into(),
                })
            }
            Some(c) => {
                check_name(cell(c), line, &column_name(c))?;
                match m.sessions.iter().position(|s| s == cell(c)) {
                    Some(k) => k,
                    None => {
                        m.sessions.push(cell(c).to_string());
                        m.sessions.len() - 1
                    }
                }
            }
        };
        let orientation = match &orientation_cols {
            Some(o) => o.cells(line, &cell, &column_name, map.angle_scale)?,
            None => None,
        };
        if let (Some(_), None, Some(c)) = (&orientation, sigma, sigma_col) {
            return Err(DataError::Format {
                line,
                expected: format!(
                    "a standard deviation in column '{}' for a row with an orientation",
                    column_name(c)
                ),
                found: "an empty cell".into(),
            });
        }
        m.samples.push(Sample {
            orientation: orientation.map(Box::new),
            session,
            q: q.into(),
            target,
            point: p,
            sigma,
            config,
            split,
            line,
            socket: None,
        });
    }
    if m.samples.is_empty() {
        return Err(DataError::Empty {
            found: if map.header {
                "only a header"
            } else {
                "an empty file"
            },
        });
    }
    let notes = zero_sigmas
        .first()
        .map(|first| {
            format!(
                "{} sample(s) give a standard deviation of 0 (first at line {first}; a rounded export?): floored at {SIGMA_FLOOR:e} m",
                zero_sigmas.len()
            )
        })
        .into_iter()
        .collect();
    Ok((m, notes))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map() -> ColumnMap {
        ColumnMap {
            joints: ColumnRef::parse_list("1-2").unwrap(),
            joint_names: vec![],
            point: [
                ColumnRef::Number(3),
                ColumnRef::Number(4),
                ColumnRef::Number(5),
            ],
            target: None,
            sigma: None,
            config: None,
            set: None,
            session: None,
            orientation: None,
            delimiter: None,
            header: true,
            length_scale: 1e-3,
            angle_scale: std::f64::consts::PI / 180.0,
            prismatic: vec![],
        }
    }

    #[test]
    fn lists_of_columns() {
        assert_eq!(
            ColumnRef::parse_list("1-3,q7").unwrap(),
            vec![
                ColumnRef::Number(1),
                ColumnRef::Number(2),
                ColumnRef::Number(3),
                ColumnRef::Name("q7".into())
            ]
        );
        assert!(ColumnRef::parse_list("0").is_err());
        assert!(ColumnRef::parse_list("3-1").is_err());
        assert!(ColumnRef::parse_list("1,,2").is_err());
    }

    #[test]
    fn separators_units_and_header_names() {
        let text = "# export\nA1;A2;X;Y;Z\n90;-45;1000;2000;3000\n0;0;1;2;3\n";
        let (m, notes) = parse(text, &map()).unwrap();
        assert!(notes.is_empty());
        assert_eq!(m.joint_names, vec!["A1", "A2"]);
        assert!((m.samples[0].q[0] - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        assert!((m.samples[0].point - Vector3::new(1.0, 2.0, 3.0)).norm() < 1e-15);
        assert_eq!(m.samples[1].line, 4);
        let tabbed = text.replace(';', "\t");
        assert_eq!(parse(&tabbed, &map()).unwrap().0, m);
    }

    #[test]
    fn only_a_zero_sigma_is_floored_and_said() {
        let mut with_sigma = map();
        with_sigma.sigma = Some(ColumnRef::Number(6));
        let text = "a,b,x,y,z,s\n0,0,1,2,3,0.0005\n0,0,1,2,3,0\n";
        let (m, notes) = parse(text, &with_sigma).unwrap();
        // 0.5 µm is a sigma, not a rounding: it stays.
        assert!((m.samples[0].sigma.unwrap().x - 5e-7).abs() < 1e-18);
        assert_eq!(m.samples[1].sigma.unwrap().x, SIGMA_FLOOR);
        assert_eq!(notes.len(), 1);
        assert!(
            notes[0].contains("1 sample(s)") && notes[0].contains("line 3"),
            "{notes:?}"
        );
    }

    #[test]
    fn errors_name_the_line_and_column() {
        let e = parse("a,b,x,y,z\n1,2,3,4\n", &map()).unwrap_err();
        assert_eq!(e.to_string(), "line 2: expected 5 fields, found 4");
        let mut by_name = map();
        by_name.point[0] = ColumnRef::Name("px".into());
        let e = parse("a,b,x,y,z\n1,2,3,4,5\n", &by_name).unwrap_err();
        assert!(e.to_string().contains("a column named 'px'"), "{e}");
        let e = parse("a,b,x,y,z\n1,2,3,4,5e9\n", &map()).unwrap_err();
        assert!(e.to_string().contains("length unit"), "{e}");
        let mut radians = map();
        radians.angle_scale = 1.0;
        let e = parse("a,b,x,y,z\n90,0,3,4,5\n", &radians).unwrap_err();
        assert!(e.to_string().contains("angle unit"), "{e}");
    }

    #[test]
    fn a_session_column_names_each_rows_session() {
        let mut with = map();
        with.session = Some(ColumnRef::Name("day".into()));
        let text = "a,b,x,y,z,day\n0,0,1,2,3,mon\n1,0,1,2,3,tue\n2,0,1,2,3,mon\n";
        let (m, _) = parse(text, &with).unwrap();
        assert_eq!(m.sessions, ["mon", "tue"]);
        let s: Vec<usize> = m.samples.iter().map(|s| s.session).collect();
        assert_eq!(s, [0, 1, 0]);
        let e = parse("a,b,x,y,z,day\n0,0,1,2,3,\n", &with).unwrap_err();
        assert!(
            e.to_string().contains("line 2") && e.to_string().contains("session"),
            "{e}"
        );
    }
}
