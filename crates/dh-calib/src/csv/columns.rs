//! The header's columns: the joint columns and their name check ([`joint_name_problem`]), and
//! where each column sits (the reserved names are with the errors that quote them).

use super::*;

/// What is wrong with a list of joint names that a dataset gives itself, as the columns of the
/// canonical CSV would have them: an empty name, a repeated one, a reserved column's name
/// ([`RESERVED_COLUMNS`]) or a control character. `None` when the list is fine.
pub fn joint_name_problem(names: &[String]) -> Option<String> {
    for (i, name) in names.iter().enumerate() {
        if name.trim().is_empty() {
            return Some(format!("an empty name at position {}", i + 1));
        }
        if names[..i].contains(name) {
            return Some(format!("'{name}' twice"));
        }
        if RESERVED_COLUMNS.contains(&name.as_str()) {
            return Some(format!("'{name}', the name of a reserved column"));
        }
        if let Some(c) = name.chars().find(|c| is_spoofing(*c)) {
            return Some(format!(
                "'{}' with the control or bidi character U+{:04X}",
                name.escape_debug(),
                u32::from(c)
            ));
        }
    }
    None
}

/// Column indices of the canonical header.
pub(super) struct Columns {
    pub(super) joints: Vec<usize>,
    /// Absent only when there is a `socket` column.
    pub(super) xyz: Option<[usize; 3]>,
    pub(super) socket: Option<usize>,
    pub(super) partner: Option<[usize; 3]>,
    pub(super) target: Option<usize>,
    pub(super) config: Option<usize>,
    pub(super) sigma: Sigma,
    pub(super) set: Option<usize>,
    pub(super) session: Option<usize>,
    /// The `time` column (seconds, any origin), when the file has one.
    pub(super) time: Option<usize>,
    /// The quaternion columns `qw`, `qx`, `qy`, `qz` and `sigma_rot`, when the file has them.
    pub(super) orientation: Option<OrientationColumns>,
}

pub(super) enum Sigma {
    None,
    Isotropic(usize),
    PerAxis([usize; 3]),
}

pub(super) fn header_columns(
    header: &Record,
    joint_names: &[String],
) -> Result<Columns, DataError> {
    let line = header.line;
    let names = &header.fields;
    if let [only] = names.as_slice() {
        if let Some(found) = [';', '\t'].into_iter().find(|c| only.contains(*c)) {
            return Err(DataError::Separator { line, found });
        }
    }
    if let Some(joint) = joint_names
        .iter()
        .find(|j| RESERVED_COLUMNS.contains(&j.as_str()))
    {
        return Err(DataError::ReservedJointName {
            line,
            joint: joint.clone(),
        });
    }
    for (i, name) in names.iter().enumerate() {
        if names[..i].contains(name) {
            return Err(DataError::DuplicateColumn {
                line,
                column: name.clone(),
            });
        }
    }
    let find = |name: &str| names.iter().position(|n| n == name);
    let missing: Vec<String> = joint_names
        .iter()
        .filter(|j| find(j).is_none())
        .cloned()
        .collect();
    if !missing.is_empty() {
        return Err(DataError::MissingJoints {
            line,
            missing,
            found: names.clone(),
        });
    }
    let joints = joint_names.iter().filter_map(|j| find(j)).collect();
    let socket = find("socket");
    // A file of contacts only may leave out the point columns.
    let any_xyz = ["x", "y", "z"].iter().any(|c| find(c).is_some());
    let xyz = if socket.is_none() || any_xyz {
        let mut xyz = [0; 3];
        for (slot, column) in xyz.iter_mut().zip(["x", "y", "z"]) {
            *slot = find(column).ok_or_else(|| DataError::MissingCoordinate {
                line,
                column,
                found: names.clone(),
            })?;
        }
        Some(xyz)
    } else {
        None
    };
    let partner = match (socket, find("partner")) {
        (Some(_), Some(p)) => {
            let mut cols = [p, 0, 0];
            for (slot, column) in cols[1..].iter_mut().zip(["distance", "distance_sigma"]) {
                *slot = find(column).ok_or_else(|| DataError::MissingCoordinate {
                    line,
                    column,
                    found: names.clone(),
                })?;
            }
            Some(cols)
        }
        _ => None,
    };
    let per_axis = [find("sx"), find("sy"), find("sz")];
    let sigma = match (find("sigma"), per_axis) {
        (None, [None, None, None]) => Sigma::None,
        (Some(i), [None, None, None]) => Sigma::Isotropic(i),
        (None, [Some(a), Some(b), Some(c)]) => Sigma::PerAxis([a, b, c]),
        (Some(_), _) => {
            let other = ["sx", "sy", "sz"]
                .into_iter()
                .zip(per_axis)
                .find_map(|(n, i)| i.map(|_| n))
                .unwrap_or("sx");
            return Err(DataError::ConflictingColumns {
                line,
                first: "sigma".into(),
                second: other.into(),
            });
        }
        (None, _) => {
            let missing = ["sx", "sy", "sz"]
                .into_iter()
                .zip(per_axis)
                .find_map(|(n, i)| i.is_none().then_some(n))
                .unwrap_or("sx");
            return Err(DataError::MissingCoordinate {
                line,
                column: missing,
                found: names.clone(),
            });
        }
    };
    let orientation = orientation_columns(line, &find, names)?;
    Ok(Columns {
        orientation,
        joints,
        xyz,
        socket,
        partner,
        target: find("target"),
        config: find("config"),
        sigma,
        set: find("set"),
        session: find("session"),
        time: find("time"),
    })
}
