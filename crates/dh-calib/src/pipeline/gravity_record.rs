//! The gravity model of a calibration as a calibrated model file holds it (the `calibration`
//! section's `gravity_model`, or a simulated truth's): what `compliance:J`,
//! `lateral_compliance:J` and `backlash:J` need to be evaluated again from joint values alone.
//!
//! The gravity torques of these effects are computed at the **nominal** geometry the
//! calibration started from ([`crate::effects`]), not at the calibrated one, so the record
//! holds that geometry beside the masses: read back, the torques are the fit's to the last bit
//! and a prediction is the fitted model's (the written proof checks it to 1 nm). Units: kg,
//! metres, radians, m/s²; each centre of mass in its row's DH frame of that geometry (frame
//! `i`, after the row's transform), a payload's in the tip frame; `gravity` in the robot's
//! base link frame.

use dh_core::pose::{from_xyz_rpy, to_xyz_rpy};
use dh_core::DhTable;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use super::PoseRecord;
use crate::fit::CalibError;
use crate::gravity::{GravityModel, Inertial, Inertials};
use crate::tree::DhTree;

/// A body's mass and centre as the record holds it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MassRecord {
    /// The joint that moves the body (a link), absent for a payload.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint: Option<String>,
    /// Mass (kg).
    pub mass: f64,
    /// Centre of mass (m): in the joint row's DH frame, or a payload's in the tip frame.
    pub com: [f64; 3],
    /// A tree's payload: the branch whose tip carries it (absent for a serial robot).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub branch: Option<String>,
}

/// One row of the nominal geometry (metres, radians).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RowGeometry {
    /// The row's joint.
    pub joint: String,
    /// Link length (m).
    pub a: f64,
    /// Link twist (rad).
    pub alpha: f64,
    /// Link offset (m).
    pub d: f64,
    /// Joint angle offset (rad).
    pub theta: f64,
    /// Hayati-Mirmirani tilt (rad), absent when zero.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub beta: f64,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

/// The gravity model of a serial calibration (see the module docs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GravityRecord {
    /// Gravity in the base link frame (m/s²).
    pub gravity: [f64; 3],
    /// Link masses, by joint.
    pub links: Vec<MassRecord>,
    /// Payloads on the tip.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub payloads: Vec<MassRecord>,
    /// The nominal DH frame 0 in the base link frame.
    pub base: PoseRecord,
    /// The nominal tip link frame in the last DH frame.
    pub tool: PoseRecord,
    /// The nominal rows, in table order (a tree's in its joint order: the trunk's, then each
    /// branch's).
    pub rows: Vec<RowGeometry>,
    /// A tree's branches (absent for a serial robot, whose `tool` is its tip): `base` and
    /// `tool` above are then the trunk's.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub branches: Vec<BranchGeometry>,
}

/// A branch of a tree's nominal geometry: its mount and tip (metres, radians) and how many of
/// the record's rows are its own.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BranchGeometry {
    /// The branch's name.
    pub name: String,
    /// Its DH frame 0 in the trunk's branch point frame.
    pub base: PoseRecord,
    /// Its tip in its last DH frame.
    pub tool: PoseRecord,
    /// Its rows (after the trunk's and the earlier branches').
    pub joints: usize,
}

/// What keeps a gravity record from making a gravity model of a table.
fn bad(reason: String) -> CalibError {
    CalibError::BadOption {
        what: "calibration.gravity_model".into(),
        reason,
    }
}

impl GravityRecord {
    /// The record of a robot's gravity model `g`: a serial robot's, or a tree's with its
    /// branches and each payload's branch. Always `Some` since trees are recorded too.
    pub fn of(g: &GravityModel) -> Option<Self> {
        let tree = g.tree();
        let table = tree.trunk();
        let pose = |p| {
            let (xyz, rpy) = to_xyz_rpy(p);
            PoseRecord { xyz, rpy }
        };
        let inertials = g.inertials();
        let branch_name = |chain: usize| {
            tree.branches()
                .get(chain)
                .map(|b| b.name.clone())
                .filter(|_| !tree.branches().is_empty())
        };
        Some(GravityRecord {
            gravity: g.gravity().into(),
            links: inertials
                .links
                .iter()
                .map(|(joint, i)| MassRecord {
                    joint: Some(joint.clone()),
                    mass: i.mass,
                    com: i.com.into(),
                    branch: None,
                })
                .collect(),
            payloads: inertials
                .payloads
                .iter()
                .map(|(chain, i)| MassRecord {
                    joint: None,
                    mass: i.mass,
                    com: i.com.into(),
                    branch: branch_name(*chain),
                })
                .collect(),
            base: pose(&table.base),
            tool: pose(&table.tool),
            rows: tree
                .rows()
                .iter()
                .map(|r| RowGeometry {
                    joint: r.name.clone(),
                    a: r.a,
                    alpha: r.alpha,
                    d: r.d,
                    theta: r.theta,
                    beta: r.beta,
                })
                .collect(),
            branches: tree
                .branches()
                .iter()
                .map(|b| BranchGeometry {
                    name: b.name.clone(),
                    base: pose(&b.table.base),
                    tool: pose(&b.table.tool),
                    joints: b.table.rows.len(),
                })
                .collect(),
        })
    }

    /// The gravity model it records, for the calibrated `tree` (a serial robot's trunk alone,
    /// see [`GravityRecord::model`]), whose joints, kinds, limits and convention the nominal
    /// geometry shares.
    ///
    /// # Errors
    /// As [`GravityRecord::model`]; branches that are not the tree's (names and joint counts,
    /// in order); a payload on no branch of the tree.
    pub fn model_of(&self, tree: &DhTree) -> Result<GravityModel, CalibError> {
        if tree.branches().is_empty() && self.branches.is_empty() {
            return self.model(tree.trunk());
        }
        let names = |v: Vec<(&str, usize)>| format!("{v:?}");
        let want: Vec<(&str, usize)> = tree
            .branches()
            .iter()
            .map(|b| (b.name.as_str(), b.table.rows.len()))
            .collect();
        let found: Vec<(&str, usize)> = self
            .branches
            .iter()
            .map(|b| (b.name.as_str(), b.joints))
            .collect();
        if want != found {
            return Err(bad(format!(
                "expected the branches (name, joints) {}, found {}",
                names(want),
                names(found)
            )));
        }
        check_rows(&self.rows, tree.rows())?;
        let mut rows = self.rows.iter();
        let mut trunk = tree.trunk().clone();
        set_rows(&mut trunk, rows.by_ref(), &self.base, &self.tool, "")?;
        let mut branches = Vec::with_capacity(self.branches.len());
        for (b, g) in tree.branches().iter().zip(&self.branches) {
            let mut table = b.table.clone();
            let what = format!("branch '{}': ", g.name);
            set_rows(&mut table, rows.by_ref(), &g.base, &g.tool, &what)?;
            branches.push(crate::tree::Branch {
                name: b.name.clone(),
                table,
            });
        }
        let nominal = DhTree::new(trunk, branches)?;
        let payloads = self
            .payloads
            .iter()
            .map(|m| {
                let chain = m
                    .branch
                    .as_deref()
                    .and_then(|b| tree.branch_index(b))
                    .ok_or_else(|| {
                        bad(format!(
                            "a payload on {:?}: expected a branch of the tree",
                            m.branch
                        ))
                    })?;
                Ok((chain, inertial(m)))
            })
            .collect::<Result<Vec<_>, CalibError>>()?;
        let inertials = Inertials {
            links: self.links()?,
            payloads,
        };
        GravityModel::new(&nominal, &inertials, Vector3::from(self.gravity))
    }

    /// The link masses by joint.
    fn links(&self) -> Result<Vec<(String, Inertial)>, CalibError> {
        self.links
            .iter()
            .map(|m| {
                let joint = m
                    .joint
                    .clone()
                    .ok_or_else(|| bad("a link without 'joint'".into()))?;
                Ok((joint, inertial(m)))
            })
            .collect()
    }

    /// The gravity model it records, for the calibrated `table` (whose joints, kinds, limits
    /// and convention the nominal geometry shares).
    ///
    /// # Errors
    /// [`CalibError::BadOption`] naming `calibration.gravity_model` when its rows are not the
    /// table's joints in order, a link names no joint, or a value is not finite; as
    /// [`GravityModel::new`].
    pub fn model(&self, table: &DhTable) -> Result<GravityModel, CalibError> {
        check_rows(&self.rows, &table.rows)?;
        let mut nominal = table.clone();
        set_rows(&mut nominal, self.rows.iter(), &self.base, &self.tool, "")?;
        let inertials = Inertials {
            links: self.links()?,
            payloads: self.payloads.iter().map(|m| (0, inertial(m))).collect(),
        };
        GravityModel::new(
            &DhTree::serial(&nominal),
            &inertials,
            Vector3::from(self.gravity),
        )
    }
}

/// A mass record's body.
fn inertial(m: &MassRecord) -> Inertial {
    Inertial {
        mass: m.mass,
        com: Vector3::from(m.com),
    }
}

/// Refuses recorded rows that are not `rows`' joints in order.
fn check_rows(records: &[RowGeometry], rows: &[dh_core::DhRow]) -> Result<(), CalibError> {
    if records.len() != rows.len() || records.iter().zip(rows).any(|(g, r)| g.joint != r.name) {
        return Err(bad(format!(
            "expected the rows of the model's joints {:?}, found {:?}",
            rows.iter().map(|r| r.name.as_str()).collect::<Vec<_>>(),
            records.iter().map(|r| r.joint.as_str()).collect::<Vec<_>>()
        )));
    }
    Ok(())
}

/// Gives `table`'s rows the next recorded geometries of `records` (one per row), and its base
/// and tool the recorded poses (`what` prefixes the poses' names in errors: empty for the
/// trunk, `branch 'NAME': ` for a branch).
fn set_rows<'a>(
    table: &mut DhTable,
    mut records: impl Iterator<Item = &'a RowGeometry>,
    base: &PoseRecord,
    tool: &PoseRecord,
    what: &str,
) -> Result<(), CalibError> {
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
    for r in table.rows.iter_mut() {
        let g = records
            .next()
            .ok_or_else(|| bad(format!("expected a row of joint '{}'", r.name)))?;
        if !finite(&[g.a, g.alpha, g.d, g.theta, g.beta]) {
            return Err(bad(format!(
                "row '{}': expected finite a, alpha, d, theta, beta",
                g.joint
            )));
        }
        (r.a, r.alpha, r.d, r.theta, r.beta) = (g.a, g.alpha, g.d, g.theta, g.beta);
    }
    for (part, p) in [("base", base), ("tool", tool)] {
        if !finite(&p.xyz) || !finite(&p.rpy) {
            return Err(bad(format!("{what}{part}: expected a finite pose")));
        }
    }
    table.base = from_xyz_rpy(base.xyz, base.rpy);
    table.tool = from_xyz_rpy(tool.xyz, tool.rpy);
    Ok(())
}

/// The effect kinds whose values need the gravity model (see [`crate::effects`]): link masses
/// and nominal geometry, or for `gravity_sag` the gravity and nominal geometry alone (its
/// record's `links` are then empty).
pub const GRAVITY_EFFECTS: [&str; 4] = [
    "compliance",
    "lateral_compliance",
    "backlash",
    "gravity_sag",
];

/// Whether the effect parameter `name` belongs to a gravity effect ([`GRAVITY_EFFECTS`]).
pub fn needs_gravity(name: &str) -> bool {
    name.split(':')
        .next()
        .is_some_and(|k| GRAVITY_EFFECTS.contains(&k))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gravity::TorqueAxis;
    use dh_core::DhRow;

    fn arm() -> DhTable {
        DhTable {
            convention: dh_core::Convention::Standard,
            base: from_xyz_rpy([0.0, 0.0, 0.3], [0.0, 0.0, 0.2]),
            tool: from_xyz_rpy([0.0, 0.0, 0.1], [0.0, 0.0, 0.0]),
            rows: vec![
                DhRow::revolute("j1", 0.0, std::f64::consts::FRAC_PI_2, 0.3, 0.0),
                DhRow::revolute("j2", 0.5, 0.0, 0.0, 0.1),
                DhRow::revolute("j3", 0.4, 0.0, 0.0, 0.0),
            ],
        }
    }

    #[test]
    fn a_record_rebuilds_the_torques_of_the_nominal_geometry_exactly() {
        let nominal = arm();
        let inertials = Inertials {
            links: vec![
                (
                    "j2".into(),
                    Inertial {
                        mass: 4.0,
                        com: Vector3::new(-0.25, 0.0, 0.01),
                    },
                ),
                (
                    "j3".into(),
                    Inertial {
                        mass: 2.5,
                        com: Vector3::new(-0.2, 0.01, 0.0),
                    },
                ),
            ],
            payloads: vec![(
                0,
                Inertial {
                    mass: 1.0,
                    com: Vector3::new(0.0, 0.0, 0.05),
                },
            )],
        };
        let g = GravityModel::serial(&nominal, &inertials, GravityModel::default_gravity())
            .expect("a valid model");
        let record = GravityRecord::of(&g).expect("serial");
        let text = serde_yaml::to_string(&record).expect("serialises");
        let back: GravityRecord = serde_yaml::from_str(&text).expect("reads back");
        // Read with a calibrated table 2 mm and 1 mrad off: the torques are the nominal's.
        let mut calibrated = nominal.clone();
        calibrated.rows[1].a += 0.002;
        calibrated.rows[2].alpha += 0.001;
        let rebuilt = back.model(&calibrated).expect("rebuilds");
        for q in [[0.1, 0.7, -1.2], [2.0, -0.3, 0.4]] {
            for row in 0..3 {
                for axis in [TorqueAxis::Joint, TorqueAxis::Lateral] {
                    let (a, b) = (g.torque(&q, row, axis), rebuilt.torque(&q, row, axis));
                    assert!((a - b).abs() <= 1e-12 * a.abs().max(1.0), "{a} vs {b}");
                    let (a, b) = (g.torque_scale(row, axis), rebuilt.torque_scale(row, axis));
                    assert!((a - b).abs() <= 1e-12 * a, "{a} vs {b}");
                }
            }
        }
        // Rows of another robot are refused, naming the section.
        let mut other = calibrated.clone();
        other.rows[2].name = "elbow".into();
        let e = back.model(&other).expect_err("other joints");
        assert!(e.to_string().contains("calibration.gravity_model"), "{e}");
    }

    /// A tree's record keeps its branches and the payload's branch: read back against a
    /// calibrated tree, the torques are those of the nominal tree; another tree is refused.
    #[test]
    fn a_tree_record_rebuilds_the_torques_of_the_nominal_tree() {
        use crate::tree::Branch;
        let branch = |name: &str, y: f64| Branch {
            name: name.into(),
            table: DhTable {
                base: from_xyz_rpy([0.1, y, 0.0], [1.2, 0.0, 0.0]),
                rows: vec![
                    DhRow::revolute(&format!("{name}1"), 0.0, 0.3, 0.0, 0.0),
                    DhRow::revolute(&format!("{name}2"), 0.3, 0.0, 0.0, 0.0),
                ],
                ..arm()
            },
        };
        let nominal = DhTree::new(
            DhTable {
                rows: vec![DhRow::revolute("t1", 0.0, 0.0, 0.4, 0.0)],
                ..arm()
            },
            vec![branch("r", -0.2), branch("l", 0.2)],
        )
        .expect("a tree");
        let inertials = Inertials {
            links: vec![
                (
                    "r2".into(),
                    Inertial {
                        mass: 3.0,
                        com: Vector3::new(-0.15, 0.0, 0.0),
                    },
                ),
                (
                    "l2".into(),
                    Inertial {
                        mass: 2.0,
                        com: Vector3::new(-0.1, 0.0, 0.01),
                    },
                ),
            ],
            payloads: vec![(
                1,
                Inertial {
                    mass: 1.0,
                    com: Vector3::new(0.0, 0.0, 0.05),
                },
            )],
        };
        let g = GravityModel::new(&nominal, &inertials, GravityModel::default_gravity())
            .expect("a valid model");
        let record = GravityRecord::of(&g).expect("a record");
        assert_eq!(record.branches.len(), 2);
        assert_eq!(record.payloads[0].branch.as_deref(), Some("l"));
        let text = serde_yaml::to_string(&record).expect("serialises");
        let back: GravityRecord = serde_yaml::from_str(&text).expect("reads back");
        let mut calibrated = nominal.clone();
        calibrated = DhTree::new(
            {
                let mut t = calibrated.trunk().clone();
                t.rows[0].d += 0.002;
                t
            },
            calibrated.branches().to_vec(),
        )
        .expect("a tree");
        let rebuilt = back.model_of(&calibrated).expect("rebuilds");
        let q = [0.3, -0.7, 1.1, 0.2, -0.4];
        for row in 0..5 {
            let (a, b) = (
                g.torque(&q, row, TorqueAxis::Joint),
                rebuilt.torque(&q, row, TorqueAxis::Joint),
            );
            assert!(
                (a - b).abs() <= 1e-12 * a.abs().max(1.0),
                "row {row}: {a} vs {b}"
            );
        }
        let e = back
            .model_of(
                &DhTree::new(nominal.trunk().clone(), vec![branch("r", -0.2)]).expect("a tree"),
            )
            .expect_err("another tree");
        assert!(e.to_string().contains("branches"), "{e}");
    }
}
