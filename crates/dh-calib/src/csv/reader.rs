//! Reading a measurement CSV into [`Measurements`] ([`parse_measurements`],
//! [`parse_measurements_noting`]): units converted to metres and radians, per-axis sigmas
//! floored at [`SIGMA_FLOOR`], samples, sockets and the split.

use super::*;

/// Reads a measurement set in the canonical CSV layout (see the [module docs](crate::csv)).
///
/// `joint_names` are the model's joints: each needs a column, and every sample's `q` follows
/// their order. Values are converted to metres and radians with `opts`. Frames: points are in
/// the measuring device's frame. `Sample::line` is the row's 1-based line in `text`.
///
/// # Errors
/// A [`DataError`] naming the line and column for: no header or no data rows, a missing joint
/// or point column, duplicate or conflicting columns, a row with the wrong number of fields, a
/// cell that is not a finite number, a standard deviation < 0 (0 is floored at [`SIGMA_FLOOR`]), an unknown `set` value, and
/// values that look like another unit (a revolute joint beyond 8π rad, a coordinate beyond
/// 100 m).
pub fn parse_measurements(
    text: &str,
    joint_names: &[String],
    opts: &CsvOptions,
) -> Result<Measurements, DataError> {
    parse_measurements_noting(text, joint_names, opts).map(|(m, _)| m)
}

/// Standard deviation (metres) given to a point whose `sigma` cell is 0: trackers export
/// coordinates rounded to 1 µm, and some write a 0 for "exact". A zero would weight the point
/// infinitely; 1 µm is the rounding step, a conservative bound on the rounding error (whose
/// standard deviation is the step over √12).
pub const SIGMA_FLOOR: f64 = 1e-6;

/// [`parse_measurements`], with the warnings a reader should see: standard deviations of 0
/// floored at [`SIGMA_FLOOR`] (how many, and the first line).
///
/// # Errors
/// As [`parse_measurements`].
pub fn parse_measurements_noting(
    text: &str,
    joint_names: &[String],
    opts: &CsvOptions,
) -> Result<(Measurements, Vec<String>), DataError> {
    // Row by row: the rows' cells are never all held at once.
    let mut rows = Records::new(text, ',', true).peekable();
    let header = rows.next().ok_or(DataError::Empty {
        found: "an empty file",
    })??;
    let header = &header;
    if rows.peek().is_none() {
        return Err(DataError::Empty {
            found: "only a header",
        });
    }
    for (k, field) in header.fields.iter().enumerate() {
        check_name(field, header.line, &format!("{}", k + 1))?;
    }
    let cols = header_columns(header, joint_names)?;
    let reader = RowReader {
        header,
        cols: &cols,
        revolute: joint_names
            .iter()
            .map(|j| !opts.prismatic.contains(j))
            .collect(),
        opts,
    };
    let mut m = Measurements {
        sessions: Vec::new(),
        joint_names: joint_names.to_vec(),
        targets: Vec::new(),
        samples: Vec::new(),
    };
    let mut seen = RowState::new(header.fields.len());
    // A large file without quotes in parallel chunks of lines (the same samples, names and
    // notes; on any fault, the rows again in order for the exact error).
    let chunked = (text.len() >= CHUNKED_MIN_BYTES)
        .then(|| read_chunked(text, &reader, &mut m, &mut seen, CHUNK_BYTES))
        .flatten();
    if chunked.is_none() {
        m.targets.clear();
        m.sessions.clear();
        m.samples = Vec::new();
        seen = RowState::new(header.fields.len());
        for row in rows {
            let row = row?;
            let sample = reader.sample(row.line, &row.fields, &mut seen)?;
            m.samples.push(sample);
        }
        m.targets = std::mem::take(&mut seen.targets);
        m.sessions = std::mem::take(&mut seen.sessions);
    }
    let zero_sigmas = seen.zero_sigmas;
    let mut notes = Vec::new();
    if let Some(first) = zero_sigmas.first() {
        notes.push(format!(
            "{} sample(s) give a standard deviation of 0 (first at line {first}; a rounded export?): floored at {SIGMA_FLOOR:e} m",
            zero_sigmas.len()
        ));
    }
    if let Some(first) = seen.zero_sigmas_rot.first() {
        notes.push(format!(
            "{} sample(s) give a sigma_rot of 0 (first at line {first}; a rounded export?): floored at {:e} rad",
            seen.zero_sigmas_rot.len(),
            super::orientation::SIGMA_ROT_FLOOR
        ));
    }
    Ok((m, notes))
}

/// The fixed part of reading a data row: the header, its columns and the units.
pub(super) struct RowReader<'a> {
    pub(super) header: &'a Record,
    pub(super) cols: &'a Columns,
    /// Per joint column: revolute (else prismatic).
    pub(super) revolute: Vec<bool>,
    pub(super) opts: &'a CsvOptions,
}

/// What the rows read so far have named and seen.
pub(super) struct RowState {
    /// Target names in order of first appearance.
    pub(super) targets: Vec<String>,
    /// Session names in order of first appearance.
    pub(super) sessions: Vec<String>,
    /// Largest magnitude accepted so far per column: a value far beyond it that is also beyond
    /// the unit's plausible range means the file mixes units (an earlier row in the other one).
    pub(super) largest: Vec<f64>,
    /// Lines with a standard deviation of 0 (each once, in order).
    pub(super) zero_sigmas: Vec<usize>,
    /// Lines with a `sigma_rot` of 0, in order.
    pub(super) zero_sigmas_rot: Vec<usize>,
    /// The row's joint values as they are read (one list for every row; each sample gets
    /// its own copy, allocated once).
    joints: Vec<f64>,
}

impl RowState {
    /// Nothing seen yet, for a header of `columns` columns.
    pub(super) fn new(columns: usize) -> Self {
        RowState {
            targets: Vec::new(),
            sessions: Vec::new(),
            largest: vec![0.0; columns],
            zero_sigmas: Vec::new(),
            zero_sigmas_rot: Vec::new(),
            joints: Vec::new(),
        }
    }
}

impl RowReader<'_> {
    /// The sample of the data row on line `line` whose cells (unquoted, trimmed) are
    /// `fields`, after the rows `seen` summarises (its targets and sessions numbered there).
    ///
    /// # Errors
    /// As [`parse_measurements`], for this row.
    pub(super) fn sample<C: AsRef<str>>(
        &self,
        line: usize,
        fields: &[C],
        seen: &mut RowState,
    ) -> Result<Sample, DataError> {
        let (header, cols, opts) = (self.header, self.cols, self.opts);
        let revolute_columns = &self.revolute;
        let length = |v: f64| opts.length_unit.to_metres(v);
        let expected = header.fields.len();
        let mixed = |largest: &[f64], col: usize, value: f64, ratio: f64| {
            largest
                .get(col)
                .is_some_and(|&m| m > 0.0 && value.abs() > ratio * m)
        };
        let largest = &mut seen.largest;
        let zero_sigmas = &mut seen.zero_sigmas;
        if fields.len() != expected {
            return Err(DataError::FieldCount {
                line,
                expected,
                found: fields.len(),
            });
        }
        let cell = |i: usize| fields[i].as_ref();
        let name = |i: usize| header.fields[i].as_str();

        let q = &mut seen.joints;
        q.clear();
        for (&col, &revolute) in cols.joints.iter().zip(revolute_columns) {
            let value = number(cell(col), line, name(col))?;
            if revolute
                && opts.angle_unit == AngleUnit::Radian
                && value.abs() > MAX_PLAUSIBLE_RADIANS
            {
                return Err(DataError::SuspiciousUnit {
                    line,
                    column: name(col).into(),
                    value,
                    unit: "rad",
                    // Degrees are 57 times radians.
                    hint: if mixed(largest, col, value, 20.0) {
                        "looks like degrees, but the rows above look like radians: the file \
                         mixes units"
                    } else {
                        "looks like degrees; pass --angle-unit deg"
                    },
                });
            }
            if let Some(m) = largest.get_mut(col) {
                *m = m.max(value.abs());
            }
            let si = if revolute {
                opts.angle_unit.to_radians(value)
            } else {
                length(value)
            };
            // Whatever the unit: a joint value past four turns or 100 m is no pose (and a
            // huge one would lose every digit in the trigonometry).
            let cap = if revolute {
                MAX_PLAUSIBLE_RADIANS
            } else {
                MAX_PLAUSIBLE_METRES
            };
            if si.abs() > cap {
                return Err(DataError::Format {
                    line,
                    expected: format!(
                        "a joint value within {cap:.1} {} in column '{}'",
                        if revolute { "rad" } else { "m" },
                        name(col)
                    ),
                    found: format!("'{}'", cell(col)),
                });
            }
            q.push(si);
        }

        let socket = match cols.socket.map(cell).filter(|c| !c.is_empty()) {
            None => None,
            Some(socket) => {
                let partner = match cols.partner {
                    Some([p, d, ds]) if !cell(p).is_empty() => {
                        let distance = length(number(cell(d), line, name(d))?);
                        let sigma = length(number(cell(ds), line, name(ds))?);
                        if !(distance > 0.0 && sigma > 0.0) {
                            return Err(DataError::Format {
                                line,
                                expected: "a distance and its standard deviation > 0".into(),
                                found: format!("{} and {}", cell(d), cell(ds)),
                            });
                        }
                        Some(SocketDistance {
                            socket: cell(p).to_string(),
                            distance,
                            sigma,
                        })
                    }
                    _ => None,
                };
                Some(Socket {
                    name: socket.to_string(),
                    partner,
                })
            }
        };
        let mut point = Vector3::zeros();
        let xyz_cols: &[usize] = match (&cols.xyz, &socket) {
            (Some(c), None) => c,
            (Some(c), Some(_)) => {
                if let Some(&col) = c.iter().find(|&&col| !cell(col).is_empty()) {
                    return Err(DataError::Format {
                        line,
                        expected: format!(
                            "an empty '{}' in a contact row (socket given)",
                            name(col)
                        ),
                        found: format!("'{}'", cell(col)),
                    });
                }
                &[]
            }
            (None, None) => {
                return Err(DataError::Format {
                    line,
                    expected: "a socket name (the file has no x, y, z columns)".into(),
                    found: "an empty 'socket' cell".into(),
                })
            }
            (None, Some(_)) => &[],
        };
        for (k, &col) in xyz_cols.iter().enumerate() {
            let value = number(cell(col), line, name(col))?;
            if opts.length_unit == LengthUnit::Metre && value.abs() > MAX_PLAUSIBLE_METRES {
                return Err(DataError::SuspiciousUnit {
                    line,
                    column: name(col).into(),
                    value,
                    unit: "m",
                    hint: if mixed(largest, col, value, 100.0) {
                        "looks like millimetres, but the rows above look like metres: the file \
                         mixes units"
                    } else {
                        "looks like millimetres; pass --length-unit mm"
                    },
                });
            }
            if let Some(m) = largest.get_mut(col) {
                *m = m.max(value.abs());
            }
            point[k] = length(value);
            if point[k].abs() > MAX_PLAUSIBLE_METRES {
                return Err(DataError::Format {
                    line,
                    expected: format!(
                        "a coordinate within {MAX_PLAUSIBLE_METRES} m in column '{}'",
                        name(col)
                    ),
                    found: format!("'{}'", cell(col)),
                });
            }
        }

        let mut sigma_cell = |col: usize| -> Result<Option<f64>, DataError> {
            let text = cell(col);
            if text.is_empty() {
                return Ok(None);
            }
            let value = number(text, line, name(col))?;
            if value == 0.0 {
                if zero_sigmas.last() != Some(&line) {
                    zero_sigmas.push(line);
                }
                return Ok(Some(SIGMA_FLOOR));
            }
            if value < 0.0 {
                return Err(DataError::BadSigma {
                    line,
                    column: name(col).into(),
                    text: text.into(),
                });
            }
            if length(value) < crate::MIN_SIGMA {
                return Err(DataError::Format {
                    line,
                    expected: format!(
                        "a standard deviation of 0 (floored) or at least {:e} m in column '{}'",
                        crate::MIN_SIGMA,
                        name(col)
                    ),
                    found: format!("'{text}'"),
                });
            }
            if length(value) > MAX_PLAUSIBLE_METRES {
                return Err(DataError::Format {
                    line,
                    expected: format!(
                        "a standard deviation within {MAX_PLAUSIBLE_METRES} m in column '{}'",
                        name(col)
                    ),
                    found: format!("'{text}'"),
                });
            }
            Ok(Some(length(value)))
        };
        let sigma = match cols.sigma {
            Sigma::None => None,
            Sigma::Isotropic(col) => sigma_cell(col)?.map(|s| Vector3::new(s, s, s)),
            Sigma::PerAxis(c) => match (sigma_cell(c[0])?, sigma_cell(c[1])?, sigma_cell(c[2])?) {
                (Some(a), Some(b), Some(c)) => Some(Vector3::new(a, b, c)),
                (None, None, None) => None,
                _ => {
                    return Err(DataError::Format {
                        line,
                        expected: "all of sx, sy, sz or none".into(),
                        found: "some of them empty".into(),
                    })
                }
            },
        };

        for col in [cols.target, cols.config, cols.socket, cols.session]
            .into_iter()
            .flatten()
        {
            check_name(cell(col), line, name(col))?;
        }
        if let Some([p, _, _]) = cols.partner {
            check_name(cell(p), line, name(p))?;
        }
        let target_name = cols.target.map_or(DEFAULT_TARGET, cell);
        let target = match seen.targets.iter().position(|t| t == target_name) {
            Some(i) => i,
            None => {
                seen.targets.push(target_name.to_string());
                seen.targets.len() - 1
            }
        };
        let config = cols
            .config
            .map(cell)
            .filter(|c| !c.is_empty())
            .map(CompactString::from);
        let split = match cols.set.map(cell) {
            None | Some("") => Split::Calibration,
            Some(text) => parse_split(text).ok_or_else(|| DataError::UnknownSet {
                line,
                text: text.into(),
            })?,
        };
        let session = match cols.session {
            None => 0,
            Some(col) if cell(col).is_empty() => {
                return Err(DataError::Format {
                    line,
                    expected: "a session name in column 'session'".into(),
                    found: "an empty cell".into(),
                })
            }
            Some(col) => match seen.sessions.iter().position(|t| t == cell(col)) {
                Some(i) => i,
                None => {
                    seen.sessions.push(cell(col).to_string());
                    seen.sessions.len() - 1
                }
            },
        };
        let orientation = match &cols.orientation {
            Some(o) => orientation_cells(o, line, &cell, &name)?.map(|(o, floored)| {
                if floored {
                    seen.zero_sigmas_rot.push(line);
                }
                o
            }),
            None => None,
        };
        let time = match cols.time.map(cell) {
            None | Some("") => None,
            Some(text) => Some(number(text, line, "time")?),
        };
        Ok(Sample {
            time,
            orientation: orientation.map(Box::new),
            session,
            q: q.as_slice().into(),
            target,
            point,
            sigma,
            config,
            split,
            line,
            socket: socket.map(Box::new),
        })
    }
}

pub(crate) fn parse_split(text: &str) -> Option<Split> {
    match text.to_ascii_lowercase().as_str() {
        "train" | "calibration" => Some(Split::Calibration),
        "test" | "validation" => Some(Split::Validation),
        _ => None,
    }
}

#[cfg(test)]
mod sigma_tests {
    use super::*;

    /// Sigma cells of 1e-300 or a subnormal are refused naming line and column (their
    /// chi-square was infinite and the verdict "model complete"); 1e-9 m is read, and so is
    /// 2e-6 mm (2e-9 m), while 5e-7 mm (5e-10 m) is not.
    #[test]
    fn sigmas_below_a_nanometre_are_refused() {
        let names = vec!["j1".to_string()];
        let read = |sigma: &str, unit: LengthUnit| {
            let text = format!("j1,x,y,z,target,sx,sy,sz\n0.1,1,2,3,t,1e-5,{sigma},1e-5\n");
            let opts = CsvOptions {
                length_unit: unit,
                angle_unit: AngleUnit::Radian,
                prismatic: Vec::new(),
            };
            parse_measurements(&text, &names, &opts)
        };
        for tiny in ["1e-300", "5e-324", "9e-10"] {
            let e = read(tiny, LengthUnit::Metre).unwrap_err().to_string();
            assert!(
                e.contains("line 2")
                    && e.contains("at least 1e-9 m in column 'sy'")
                    && e.contains(&format!("'{tiny}'")),
                "{e}"
            );
        }
        let m = read("1e-9", LengthUnit::Metre).unwrap();
        assert_eq!(m.samples[0].sigma.unwrap().y, 1e-9);
        assert!(read("2e-6", LengthUnit::Millimetre).is_ok());
        assert!(read("5e-7", LengthUnit::Millimetre).is_err());
    }
}
