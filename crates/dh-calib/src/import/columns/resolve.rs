//! A [`ColumnMap`] checked against a file's header: every column found (by number or by a
//! header name that only one column has), each column in one role only, the joint names
//! written fit the measurement CSV, and the prismatic joints are among them.

use super::{orientation, ColumnMap, ColumnRef};
use crate::csv::{joint_name_problem, DataError, Record};

/// The map's columns as 0-based indices into the file's rows.
pub(super) struct Columns {
    pub(super) joints: Vec<usize>,
    pub(super) point: [usize; 3],
    pub(super) target: Option<usize>,
    pub(super) sigma: Sigma,
    pub(super) config: Option<usize>,
    pub(super) set: Option<usize>,
    pub(super) session: Option<usize>,
    pub(super) time: Option<usize>,
    pub(super) orientation: Option<orientation::Resolved>,
    /// The names the joints are written under, one per joint column.
    pub(super) joint_names: Vec<String>,
    /// Per joint column: prismatic (a length), else revolute.
    pub(super) prismatic: Vec<bool>,
}

/// The standard deviation's columns.
#[derive(Clone, Copy)]
pub(super) enum Sigma {
    None,
    Isotropic(usize),
    /// `sx`, `sy`, `sz`: the device's per-axis standard deviations.
    PerAxis([usize; 3]),
}

impl Sigma {
    /// The columns, in order.
    pub(super) fn columns(self) -> Vec<usize> {
        match self {
            Sigma::None => vec![],
            Sigma::Isotropic(c) => vec![c],
            Sigma::PerAxis(c) => c.to_vec(),
        }
    }
}

/// The file's header (when it has one) and width, to find columns in.
pub(super) struct Header<'a> {
    pub(super) record: Option<&'a Record>,
    pub(super) width: usize,
    pub(super) line: usize,
}

impl Header<'_> {
    /// The 0-based index of column `c`.
    ///
    /// # Errors
    /// A number beyond the file's width, a name no column has, or a name two columns have
    /// (the first would be taken, silently).
    pub(super) fn find(&self, c: &ColumnRef) -> Result<usize, DataError> {
        let (line, width) = (self.line, self.width);
        match c {
            ColumnRef::Number(n) if *n <= width => Ok(n - 1),
            ColumnRef::Number(n) => Err(DataError::Format {
                line,
                expected: format!("a column {n} (the file has {width})"),
                found: "none".into(),
            }),
            ColumnRef::Name(name) => {
                let Some(h) = self.record else {
                    return Err(DataError::Format {
                        line,
                        expected: format!("a column named '{name}'"),
                        found: "no header line (name columns by number)".into(),
                    });
                };
                let mut at = h.fields.iter().enumerate().filter(|(_, f)| *f == name);
                match (at.next(), at.next()) {
                    (Some((k, _)), None) => Ok(k),
                    (Some((a, _)), Some((b, _))) => Err(DataError::Format {
                        line,
                        expected: format!("one column named '{name}'"),
                        found: format!(
                            "columns {} and {} both named so (name the one you mean by number)",
                            a + 1,
                            b + 1
                        ),
                    }),
                    (None, _) => Err(DataError::Format {
                        line,
                        expected: format!("a column named '{name}'"),
                        found: format!("the columns {}", h.fields.join(", ")),
                    }),
                }
            }
        }
    }

    /// A column's name in messages: its header name, else its number.
    pub(super) fn name(&self, c: usize) -> String {
        match self.record {
            Some(h) => h.fields.get(c).cloned().unwrap_or_default(),
            None => format!("{}", c + 1),
        }
    }
}

impl ColumnMap {
    /// The map's columns in the file with `header` (see the [module docs](self)).
    ///
    /// # Errors
    /// As [`Header::find`]; no joint column; orientation columns without a sigma column; a
    /// column in two roles; joint names the measurement CSV cannot hold (see
    /// [`joint_name_problem`]); a prismatic joint that is not among the joints.
    pub(super) fn resolve(&self, header: &Header<'_>) -> Result<Columns, DataError> {
        let find = |c: &ColumnRef| header.find(c);
        let joints: Vec<usize> = self.joints.iter().map(find).collect::<Result<_, _>>()?;
        if joints.is_empty() {
            return Err(DataError::Content {
                expected: "at least one joint column".into(),
                found: "none".into(),
            });
        }
        let point = [
            find(&self.point[0])?,
            find(&self.point[1])?,
            find(&self.point[2])?,
        ];
        let optional = |c: &Option<ColumnRef>| c.as_ref().map(find).transpose();
        let sigma = match (&self.sigma, &self.sigma_axes) {
            (Some(_), Some(_)) => {
                return Err(DataError::Content {
                    expected: "one sigma column or three per-axis ones".into(),
                    found: "both".into(),
                })
            }
            (Some(c), None) => Sigma::Isotropic(find(c)?),
            (None, Some([a, b, c])) => Sigma::PerAxis([find(a)?, find(b)?, find(c)?]),
            (None, None) => Sigma::None,
        };
        let orientation = match &self.orientation {
            None => None,
            Some(_) if matches!(sigma, Sigma::None) => {
                return Err(DataError::Content {
                    expected: "a sigma column with orientation columns (the position sigma \
                               weighs the angle against the position)"
                        .into(),
                    found: "none".into(),
                })
            }
            Some(o) => Some(o.resolve(&find)?),
        };
        let columns = Columns {
            joints,
            point,
            target: optional(&self.target)?,
            sigma,
            config: optional(&self.config)?,
            set: optional(&self.set)?,
            session: optional(&self.session)?,
            time: optional(&self.time)?,
            orientation,
            joint_names: Vec::new(),
            prismatic: Vec::new(),
        };
        columns.one_role_each(header)?;
        let joint_names = self.joint_names(&columns.joints, header)?;
        if let Some(p) = self.prismatic.iter().find(|p| !joint_names.contains(p)) {
            return Err(DataError::Content {
                expected: format!("prismatic joints among the joints {}", quoted(&joint_names)),
                found: format!("'{}'", p.escape_debug()),
            });
        }
        let prismatic = joint_names
            .iter()
            .map(|n| self.prismatic.contains(n))
            .collect();
        Ok(Columns {
            joint_names,
            prismatic,
            ..columns
        })
    }

    /// The names the joints are written under: the map's, else the header's names of the
    /// joint columns, else `joint_1..n`.
    ///
    /// # Errors
    /// A count that does not match the joint columns; names the measurement CSV cannot hold.
    fn joint_names(&self, joints: &[usize], header: &Header<'_>) -> Result<Vec<String>, DataError> {
        let names: Vec<String> = if !self.joint_names.is_empty() {
            if self.joint_names.len() != joints.len() {
                return Err(DataError::Content {
                    expected: format!("{} joint names, one per joint column", joints.len()),
                    found: format!("{}", self.joint_names.len()),
                });
            }
            self.joint_names.clone()
        } else {
            joints
                .iter()
                .enumerate()
                .map(|(k, &c)| match header.record {
                    Some(h) => h.fields[c].clone(),
                    None => format!("joint_{}", k + 1),
                })
                .collect()
        };
        if let Some(problem) = joint_name_problem(&names) {
            let source = if self.joint_names.is_empty() {
                "the header's names of the joint columns"
            } else {
                "the joint names given"
            };
            return Err(DataError::Content {
                expected: format!(
                    "joint names that can head the measurement CSV's columns ({source}; \
                     name the joints with joint names of your own)"
                ),
                found: problem,
            });
        }
        Ok(names)
    }
}

impl Columns {
    /// Every column in one role: a column read as a joint and as a coordinate (or twice as a
    /// joint) would give a set that says what the file does not.
    fn one_role_each(&self, header: &Header<'_>) -> Result<(), DataError> {
        let mut roles: Vec<(usize, String)> = Vec::new();
        for (k, &c) in self.joints.iter().enumerate() {
            roles.push((c, format!("joint {}", k + 1)));
        }
        for (c, axis) in self.point.iter().zip(["x", "y", "z"]) {
            roles.push((*c, format!("point {axis}")));
        }
        match self.sigma {
            Sigma::None => {}
            Sigma::Isotropic(c) => roles.push((c, "sigma".into())),
            Sigma::PerAxis(c) => {
                for (c, axis) in c.iter().zip(["x", "y", "z"]) {
                    roles.push((*c, format!("sigma {axis}")));
                }
            }
        }
        for (c, role) in [
            (self.target, "target"),
            (self.config, "config"),
            (self.set, "set"),
            (self.session, "session"),
            (self.time, "time"),
        ] {
            if let Some(c) = c {
                roles.push((c, role.into()));
            }
        }
        if let Some(o) = &self.orientation {
            roles.extend(o.roles());
        }
        for (i, (c, role)) in roles.iter().enumerate() {
            if let Some((_, first)) = roles[..i].iter().find(|(d, _)| d == c) {
                return Err(DataError::Content {
                    expected: "each column in one role".into(),
                    found: format!(
                        "column {} ('{}') as {first} and as {role}",
                        c + 1,
                        header.name(*c).escape_debug()
                    ),
                });
            }
        }
        Ok(())
    }
}

/// `'a', 'b'` (names escaped).
fn quoted(names: &[String]) -> String {
    names
        .iter()
        .map(|n| format!("'{}'", n.escape_debug()))
        .collect::<Vec<_>>()
        .join(", ")
}
