//! Measurements given as arrays rather than CSV text ([`SampleArrays`],
//! [`Measurements::from_arrays`]): what a numpy or DataFrame caller hands over, checked as the
//! CSV reader checks a file's cells, with errors naming the row and the column.

use super::*;

/// A measurement set as columns of equal length, one entry per sample, in the units of the
/// [`CsvOptions`] it is read with (as a CSV file's cells would be).
///
/// Frames: `points` are in the measuring device's frame. `q` and `points` are row-major: row
/// `i` of `q` is `q[i * joint_names.len()..(i + 1) * joint_names.len()]`, row `i` of `points`
/// is `points[3 * i..3 * i + 3]` (x, y, z).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SampleArrays {
    /// The joint columns, in the order of each row of `q`.
    pub joint_names: Vec<String>,
    /// Joint values, `rows × joint_names.len()`, row-major (radians or degrees; length unit for
    /// prismatic joints).
    pub q: Vec<f64>,
    /// Measured points, `rows × 3`, row-major (length unit).
    pub points: Vec<f64>,
    /// The `target` column (reflector names), or `None`: every sample measures
    /// [`DEFAULT_TARGET`].
    pub target: Option<Vec<String>>,
    /// The `sigma` column (isotropic standard deviation of each point, length unit; NaN for
    /// "not given", as an empty cell), or `None`.
    pub sigma: Option<Vec<f64>>,
    /// The `sx, sy, sz` columns (a standard deviation per device axis, length unit),
    /// `rows × 3`, row-major; a row of three NaN gives none (as three empty cells), or `None`.
    /// Not with `sigma`.
    pub sigma_axes: Option<Vec<f64>>,
    /// The `config` column (pose identifiers; empty for none), or `None`.
    pub config: Option<Vec<String>>,
    /// The `session` column (measurement sessions), or `None`.
    pub session: Option<Vec<String>>,
    /// The `set` column (`train`/`calibration`, `test`/`validation`, empty for calibration), or
    /// `None`.
    pub set: Option<Vec<String>>,
    /// The orientation columns `qw, qx, qy, qz` of a 6-DoF device (the measured rotation of the
    /// target frame in the device frame, a unit quaternion scalar first), `rows × 4`,
    /// row-major; a row of four NaN is a point. `None`: points only.
    pub quaternion: Option<Vec<f64>>,
    /// The `sigma_rot` column (radians, standard deviation per axis of the rotation), with
    /// `quaternion`; NaN in the rows of points.
    pub sigma_rot: Option<Vec<f64>>,
    /// The `time` column (seconds, any origin; NaN for a row without one, as an empty cell),
    /// or `None`: what effects of time (`thermal_growth`) read.
    pub time: Option<Vec<f64>>,
}

/// Row `row`'s time in `time` (NaN: none); an infinite time is an error naming the row.
pub(crate) fn time_at(time: &Option<Vec<f64>>, row: usize) -> Result<Option<f64>, DataError> {
    match time.as_ref().and_then(|t| t.get(row)).copied() {
        None => Ok(None),
        Some(t) if t.is_nan() => Ok(None),
        Some(t) if t.is_finite() => Ok(Some(t)),
        Some(t) => Err(array_error(
            row,
            "time",
            "a finite time in seconds",
            format!("{t}"),
        )),
    }
}

/// The error for row `row` (0-based, as numpy and pandas count), column `column`.
pub(crate) fn array_error(
    row: usize,
    column: &str,
    expected: impl Into<String>,
    found: impl Into<String>,
) -> DataError {
    DataError::Array {
        row,
        column: column.to_string(),
        expected: expected.into(),
        found: found.into(),
    }
}

impl SampleArrays {
    /// The same arrays with the joint columns `joints`, in that order (a DataFrame's columns
    /// may be in any order and include others).
    ///
    /// # Errors
    /// [`DataError::Content`] naming the joints without a column.
    pub fn with_joints(&self, joints: &[String]) -> Result<SampleArrays, DataError> {
        let missing: Vec<String> = joints
            .iter()
            .filter(|j| !self.joint_names.contains(j))
            .cloned()
            .collect();
        if !missing.is_empty() {
            return Err(DataError::Content {
                expected: format!("joint column(s) {}", list(&missing)),
                found: format!("the columns {}", list(&self.joint_names)),
            });
        }
        let width = self.joint_names.len();
        let n = self.q.len().checked_div(width).unwrap_or(0);
        let cols: Vec<usize> = joints
            .iter()
            .filter_map(|j| self.joint_names.iter().position(|n| n == j))
            .collect();
        let q = (0..n)
            .flat_map(|i| cols.iter().map(move |&c| i * width + c))
            .filter_map(|k| self.q.get(k).copied())
            .collect();
        Ok(SampleArrays {
            joint_names: joints.to_vec(),
            q,
            ..self.clone()
        })
    }

    /// Number of rows, after checking that every column has it; `points`: the set has points
    /// (else `points` must be empty and the joints give the count).
    pub(crate) fn rows(&self, points: bool) -> Result<usize, DataError> {
        let width = self.joint_names.len();
        let n = match (points, width) {
            (true, _) => self.points.len() / 3,
            (false, 0) => 0,
            (false, w) => self.q.len() / w,
        };
        let shape = |what: &str, len: usize, want: usize| {
            if len == want {
                Ok(())
            } else {
                Err(DataError::Content {
                    expected: format!("{want} values in {what} ({n} rows)"),
                    found: format!("{len}"),
                })
            }
        };
        shape(
            "points (rows x 3)",
            self.points.len(),
            if points { 3 * n } else { 0 },
        )?;
        shape(
            &format!("q (rows x {} joints)", self.joint_names.len()),
            self.q.len(),
            n * self.joint_names.len(),
        )?;
        shape(
            "qw, qx, qy, qz (rows x 4)",
            self.quaternion.as_ref().map_or(4 * n, Vec::len),
            4 * n,
        )?;
        shape(
            "sx, sy, sz (rows x 3)",
            self.sigma_axes.as_ref().map_or(3 * n, Vec::len),
            3 * n,
        )?;
        if self.sigma.is_some() && self.sigma_axes.is_some() {
            return Err(DataError::Content {
                expected: "either the isotropic 'sigma' or the per-axis 'sx, sy, sz'".into(),
                found: "both".into(),
            });
        }
        if self.quaternion.is_some() != self.sigma_rot.is_some() {
            return Err(DataError::Content {
                expected: "the orientation columns qw, qx, qy, qz and sigma_rot together".into(),
                found: "one without the other".into(),
            });
        }
        for (what, len) in [
            ("'sigma_rot'", self.sigma_rot.as_ref().map(Vec::len)),
            ("'target'", self.target.as_ref().map(Vec::len)),
            ("'sigma'", self.sigma.as_ref().map(Vec::len)),
            ("'config'", self.config.as_ref().map(Vec::len)),
            ("'session'", self.session.as_ref().map(Vec::len)),
            ("'set'", self.set.as_ref().map(Vec::len)),
            ("'time'", self.time.as_ref().map(Vec::len)),
        ] {
            if let Some(len) = len {
                shape(what, len, n)?;
            }
        }
        if n == 0 {
            return Err(DataError::Empty { found: "no rows" });
        }
        Ok(n)
    }
}

impl Measurements {
    /// The measurement set of `arrays`, read with the units of `opts` as
    /// [`parse_measurements_noting`] reads a file with the same columns: values converted to
    /// metres and radians, the same refusals (a value that is not finite, a revolute joint
    /// beyond 8π rad in radians, a coordinate beyond 100 m, a negative standard deviation, an
    /// unknown `set`, an empty session name, control characters in a name), standard
    /// deviations of 0 floored at [`SIGMA_FLOOR`] (the returned notes say how many).
    /// `Sample::line` is the line the row would have in the same CSV file (row `i` at line
    /// `i + 2`, the header being line 1), so that reports name samples as for the file.
    ///
    /// # Errors
    /// Columns of different lengths, no rows, a joint named as a reserved column or twice
    /// ([`DataError::Content`], [`DataError::ReservedJointName`],
    /// [`DataError::DuplicateColumn`]); a bad cell: [`DataError::Array`] naming the row (0-based,
    /// as numpy and pandas count) and the column.
    pub fn from_arrays(
        arrays: &SampleArrays,
        opts: &CsvOptions,
    ) -> Result<(Measurements, Vec<String>), DataError> {
        let n = arrays.rows(true)?;
        let names = &arrays.joint_names;
        for (k, j) in names.iter().enumerate() {
            check_name(j, 0, &format!("{}", k + 1))?;
            if RESERVED_COLUMNS.contains(&j.as_str()) {
                return Err(DataError::ReservedJointName {
                    line: 0,
                    joint: j.clone(),
                });
            }
            if names[..k].contains(j) {
                return Err(DataError::DuplicateColumn {
                    line: 0,
                    column: j.clone(),
                });
            }
        }
        let width = names.len();
        let revolute: Vec<bool> = names.iter().map(|j| !opts.prismatic.contains(j)).collect();
        let length = |v: f64| opts.length_unit.to_metres(v);
        let mut m = Measurements {
            joint_names: names.clone(),
            ..Measurements::default()
        };
        let mut zero_sigmas = Vec::new();
        let mut zero_sigmas_rot = Vec::new();
        for i in 0..n {
            let row = i;
            let mut q = Vec::with_capacity(width);
            for (k, name) in names.iter().enumerate() {
                let value = arrays.q[i * width + k];
                q.push(joint_value(value, revolute[k], row, name, opts)?);
            }
            let mut point = Vector3::zeros();
            for (k, axis) in ["x", "y", "z"].into_iter().enumerate() {
                let value = finite(arrays.points[3 * i + k], row, axis)?;
                if opts.length_unit == LengthUnit::Metre && value.abs() > MAX_PLAUSIBLE_METRES {
                    return Err(array_error(
                        row,
                        axis,
                        format!("a coordinate within {MAX_PLAUSIBLE_METRES} m"),
                        format!("{value} m: looks like millimetres; pass length_unit='mm'"),
                    ));
                }
                point[k] = length(value);
                if point[k].abs() > MAX_PLAUSIBLE_METRES {
                    return Err(array_error(
                        row,
                        axis,
                        format!("a coordinate within {MAX_PLAUSIBLE_METRES} m"),
                        format!("{value}"),
                    ));
                }
            }
            // One standard deviation as the CSV reader takes a cell: NaN for none, 0 floored.
            let mut one_sigma = |v: f64, column: &str| -> Result<Option<f64>, DataError> {
                match v {
                    v if v.is_nan() => Ok(None),
                    0.0 => {
                        if zero_sigmas.last() != Some(&row) {
                            zero_sigmas.push(row);
                        }
                        Ok(Some(SIGMA_FLOOR))
                    }
                    v if !(v > 0.0 && v.is_finite()) => Err(array_error(
                        row,
                        column,
                        "a standard deviation > 0",
                        format!("{v}"),
                    )),
                    v if length(v) < crate::MIN_SIGMA => Err(array_error(
                        row,
                        column,
                        format!(
                            "a standard deviation of 0 (floored) or at least {:e} m",
                            crate::MIN_SIGMA
                        ),
                        format!("{v}"),
                    )),
                    v if length(v) > MAX_PLAUSIBLE_METRES => Err(array_error(
                        row,
                        column,
                        format!("a standard deviation within {MAX_PLAUSIBLE_METRES} m"),
                        format!("{v}"),
                    )),
                    v => Ok(Some(length(v))),
                }
            };
            let sigma = match (&arrays.sigma, &arrays.sigma_axes) {
                (Some(s), _) => one_sigma(s[i], "sigma")?.map(Vector3::repeat),
                (None, Some(s)) => match (
                    one_sigma(s[3 * i], "sx")?,
                    one_sigma(s[3 * i + 1], "sy")?,
                    one_sigma(s[3 * i + 2], "sz")?,
                ) {
                    (Some(a), Some(b), Some(c)) => Some(Vector3::new(a, b, c)),
                    (None, None, None) => None,
                    _ => {
                        return Err(array_error(
                            row,
                            "sx, sy, sz",
                            "all of sx, sy, sz or none",
                            "some of them NaN",
                        ))
                    }
                },
                (None, None) => None,
            };
            let text =
                |col: &Option<Vec<String>>, name: &str| -> Result<Option<String>, DataError> {
                    match col {
                        None => Ok(None),
                        Some(c) => {
                            check_name(&c[i], row, name).map_err(|_| {
                                array_error(
                                    row,
                                    name,
                                    "a name without control characters",
                                    format!("{:?}", c[i]),
                                )
                            })?;
                            Ok(Some(c[i].clone()))
                        }
                    }
                };
            let target_name = text(&arrays.target, "target")?.unwrap_or(DEFAULT_TARGET.into());
            let target = index_of(&mut m.targets, &target_name);
            let config = text(&arrays.config, "config")?.filter(|c| !c.is_empty());
            let split = match text(&arrays.set, "set")?.as_deref() {
                None | Some("") => Split::Calibration,
                Some(s) => parse_split(s).ok_or_else(|| {
                    array_error(
                        row,
                        "set",
                        "train, calibration, test or validation",
                        format!("'{s}'"),
                    )
                })?,
            };
            let session = match text(&arrays.session, "session")? {
                None => 0,
                Some(s) if s.is_empty() => {
                    return Err(array_error(
                        row,
                        "session",
                        "a session name",
                        "an empty cell",
                    ))
                }
                Some(s) => index_of(&mut m.sessions, &s),
            };
            m.samples.push(Sample {
                time: time_at(&arrays.time, row)?,
                q: q.into(),
                target,
                point,
                sigma,
                config: config.map(Into::into),
                split,
                line: i + 2,
                socket: None,
                session,
                orientation: orientation_row(arrays, i, &mut zero_sigmas_rot)?.map(Box::new),
            });
        }
        let mut notes = Vec::new();
        if let Some(first) = zero_sigmas.first() {
            notes.push(format!(
                "{} sample(s) give a standard deviation of 0 (first at row {first}; a rounded export?): floored at {SIGMA_FLOOR:e} m",
                zero_sigmas.len()
            ));
        }
        if let Some(first) = zero_sigmas_rot.first() {
            notes.push(format!(
                "{} sample(s) give a sigma_rot of 0 (first at row {first}; a rounded export?): floored at {SIGMA_ROT_FLOOR:e} rad",
                zero_sigmas_rot.len()
            ));
        }
        Ok((m, notes))
    }
}

/// The orientation of row `i` of `arrays` (see [`SampleArrays::quaternion`]), checked as the
/// CSV reader checks the cells (all four or none, a unit quaternion, `sigma_rot` in
/// `[0, 1]` rad, 0 floored at [`SIGMA_ROT_FLOOR`] and its row pushed on `zero`).
fn orientation_row(
    arrays: &SampleArrays,
    i: usize,
    zero: &mut Vec<usize>,
) -> Result<Option<crate::data::Orientation>, DataError> {
    let (Some(q), Some(sigmas)) = (&arrays.quaternion, &arrays.sigma_rot) else {
        return Ok(None);
    };
    const NAMES: [&str; 4] = ["qw", "qx", "qy", "qz"];
    let v = [q[4 * i], q[4 * i + 1], q[4 * i + 2], q[4 * i + 3]];
    if v.iter().all(|x| x.is_nan()) {
        return Ok(None);
    }
    for (value, name) in v.iter().zip(NAMES) {
        if value.is_nan() {
            return Err(array_error(i, name, "all of qw, qx, qy, qz or none", "NaN"));
        }
        finite(*value, i, name)?;
    }
    let rotation = unit_quaternion(v, i, "qw, qx, qy, qz").map_err(|e| match e {
        DataError::Format {
            expected, found, ..
        } => array_error(i, "qw", expected, found),
        e => e,
    })?;
    let s = sigmas[i];
    let (sigma, floored) = super::orientation::floored_sigma_rot(s).ok_or_else(|| {
        array_error(
            i,
            "sigma_rot",
            super::orientation::sigma_rot_expected(s, "for an orientation"),
            format!("{s}"),
        )
    })?;
    if floored {
        zero.push(i);
    }
    Ok(Some(crate::data::Orientation { rotation, sigma }))
}

/// `value` if finite, else the error naming `row` and `column`.
pub(crate) fn finite(value: f64, row: usize, column: &str) -> Result<f64, DataError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(array_error(
            row,
            column,
            "a finite number",
            format!("{value}"),
        ))
    }
}

/// A joint value in metres or radians, refused as the CSV reader refuses its cell.
pub(crate) fn joint_value(
    value: f64,
    revolute: bool,
    row: usize,
    name: &str,
    opts: &CsvOptions,
) -> Result<f64, DataError> {
    let value = finite(value, row, name)?;
    if revolute && opts.angle_unit == AngleUnit::Radian && value.abs() > MAX_PLAUSIBLE_RADIANS {
        return Err(array_error(
            row,
            name,
            format!("a joint value within {MAX_PLAUSIBLE_RADIANS:.1} rad"),
            format!("{value} rad: looks like degrees; pass angle_unit='deg'"),
        ));
    }
    let (si, cap, unit) = if revolute {
        (
            opts.angle_unit.to_radians(value),
            MAX_PLAUSIBLE_RADIANS,
            "rad",
        )
    } else {
        (opts.length_unit.to_metres(value), MAX_PLAUSIBLE_METRES, "m")
    };
    if si.abs() > cap {
        return Err(array_error(
            row,
            name,
            format!("a joint value within {cap:.1} {unit}"),
            format!("{value}"),
        ));
    }
    Ok(si)
}

/// The index of `name` in `names`, appended when new.
fn index_of(names: &mut Vec<String>, name: &str) -> usize {
    match names.iter().position(|n| n == name) {
        Some(i) => i,
        None => {
            names.push(name.to_string());
            names.len() - 1
        }
    }
}

#[cfg(test)]
mod tests;
