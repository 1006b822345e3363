//! The tree section of a tree calibration's report ([`TreeCalibrationDoc`]): which
//! parameters, targets and mount belong to the trunk and to each branch (see [`crate::tree`];
//! mounts in the branch point frame, metres and radians).

use serde::{Deserialize, Serialize};

use super::doc::{CalibrationDoc, PoseSi};
use crate::tree::DhTree;

/// Which table a parameter of a tree belongs to: `None` for the trunk, `Some(b)` for branch
/// `b`; the device frame belongs to none (`Err(())`).
fn table_of(name: &str, tree: &DhTree, targets: &[(String, usize)]) -> Result<Option<usize>, ()> {
    if name.starts_with("device.") {
        return Err(());
    }
    if name.starts_with("base.") {
        return Ok(None);
    }
    if let Some(rest) = name.strip_prefix("target.") {
        // `target.<name>.<x|y|z>`: target names may hold dots, the coordinate may not.
        let target = rest.rsplit_once('.').map_or(rest, |(t, _)| t);
        return targets
            .iter()
            .find(|(t, _)| t == target)
            .map(|(_, b)| Some(*b))
            .ok_or(());
    }
    // Effects: `<kind>:<joint>[:<joint>]`, on the first joint's table; `scale` on none.
    let joint = match name.split_once(':') {
        Some((_, joints)) => joints.split(':').next().unwrap_or_default(),
        None => name.rsplit_once('.').map_or(name, |(j, _)| j),
    };
    if let Some(b) = joint
        .strip_suffix(".base")
        .and_then(|b| tree.branch_index(b))
    {
        return Ok(Some(b));
    }
    match tree.row_index(joint) {
        Some(r) => Ok(tree.place(r).0),
        None => Err(()),
    }
}

/// One table of the tree in the report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TableDoc {
    /// `trunk`, or the branch's name.
    pub name: String,
    /// Its joints, in order.
    pub joints: Vec<String>,
    /// The targets riding on it (a branch), none for the trunk.
    pub targets: Vec<String>,
    /// Estimated parameters of its rows, base or mount, targets and effects.
    pub free: Vec<String>,
    /// Parameters of it held at nominal.
    pub fixed: Vec<String>,
    /// The calibrated mount in the branch point frame (branches; metres, radians).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mount: Option<PoseSi>,
}

/// The JSON report of a tree: the serial report's keys and `tree`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TreeCalibrationDoc {
    /// Everything a serial calibration reports.
    #[serde(flatten)]
    pub report: CalibrationDoc,
    /// The trunk and each branch.
    pub tree: Vec<TableDoc>,
}

/// The tree section of the report.
pub fn tables(
    tree: &DhTree,
    calibrated: &DhTree,
    doc: &CalibrationDoc,
    targets: &[(String, usize)],
) -> Vec<TableDoc> {
    let mut out = Vec::with_capacity(tree.branches().len() + 1);
    let names = |rows: &[dh_core::DhRow]| rows.iter().map(|r| r.name.clone()).collect();
    let params = |b: Option<usize>, free: bool| -> Vec<String> {
        doc.parameters
            .iter()
            .filter(|p| p.free == free && table_of(&p.name, tree, targets) == Ok(b))
            .map(|p| p.name.clone())
            .collect()
    };
    out.push(TableDoc {
        name: "trunk".into(),
        joints: names(&tree.trunk().rows),
        targets: Vec::new(),
        free: params(None, true),
        fixed: params(None, false),
        mount: None,
    });
    for (b, br) in tree.branches().iter().enumerate() {
        out.push(TableDoc {
            name: br.name.clone(),
            joints: names(&br.table.rows),
            targets: targets
                .iter()
                .filter(|(_, c)| *c == b)
                .map(|(t, _)| t.clone())
                .collect(),
            free: params(Some(b), true),
            fixed: params(Some(b), false),
            mount: calibrated
                .branches()
                .get(b)
                .map(|c| PoseSi::of(&c.table.base)),
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use dh_core::{Convention, DhRow, DhTable};
    use nalgebra::Isometry3;

    use super::*;
    use crate::tree::Branch;

    fn table(rows: Vec<DhRow>) -> DhTable {
        DhTable {
            convention: Convention::Modified,
            base: Isometry3::identity(),
            tool: Isometry3::identity(),
            rows,
        }
    }

    #[test]
    fn parameters_belong_to_their_table() {
        let branch = |name: &str, joint: &str| Branch {
            name: name.into(),
            table: table(vec![DhRow::revolute(joint, 0.3, 0.0, 0.0, 0.0)]),
        };
        let t = &DhTree::new(
            table(vec![DhRow::revolute("t1", 0.0, 0.0, 0.2, 0.0)]),
            vec![branch("r", "r1"), branch("l", "l1")],
        )
        .unwrap();
        let targets = [("r".to_string(), 0), ("l/m.1".to_string(), 1)];
        assert_eq!(table_of("device.x", t, &targets), Err(()));
        assert_eq!(table_of("base.rz", t, &targets), Ok(None));
        assert_eq!(table_of("t1.theta", t, &targets), Ok(None));
        assert_eq!(table_of("r1.a", t, &targets), Ok(Some(0)));
        assert_eq!(table_of("l.base.x", t, &targets), Ok(Some(1)));
        assert_eq!(table_of("target.l/m.1.z", t, &targets), Ok(Some(1)));
        assert_eq!(table_of("compliance:l1", t, &targets), Ok(Some(1)));
        assert_eq!(table_of("coupling:r1:t1", t, &targets), Ok(Some(0)));
        assert_eq!(table_of("scale", t, &targets), Err(()));
    }
}
