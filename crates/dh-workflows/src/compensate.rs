//! Using a calibration on the robot: for each commanded joint row (what the nominal model uses
//! to reach its targets), the joint values with which the calibrated robot puts its tool where
//! the nominal model puts it ([`dh_calib::compensate::compensate`], numerical inverse kinematics
//! seeded by the commanded values), with the error before and after, as `urdf-dh compensate`
//! writes them and the Python package returns them.
//!
//! Frames and units: the tool's errors are in the base link frame, positions in metres and
//! angles in radians; joint values in metres and radians ([`JointInput`]).

use anyhow::Result;
use dh_calib::compensate::{compensate as solve, Compensated};
/// The inverse kinematics' options, and the default largest change of a joint value from the
/// commanded one (radians or metres).
pub use dh_calib::compensate::{CompensateOptions, DEFAULT_MAX_CHANGE};
use dh_calib::tree::DhTree;
use dh_core::DhTable;
use nalgebra::Isometry3;

use crate::calibrated::CalibratedModel;
use crate::error::hinted;
use crate::predict::JointInput;
use crate::text::escape;
use crate::units::{AngleUnit, LengthUnit};

/// Why a pose was not compensated.
#[derive(Clone, Debug, PartialEq)]
pub enum Failure {
    /// The solution needs a larger change than [`CompensateOptions::max_change`] of these
    /// columns (a singular pose?).
    MaxChange {
        /// The columns at the bound.
        columns: Vec<String>,
    },
    /// The goal is beyond the calibrated robot's reach from the commanded values: the nearest
    /// pose is what remains.
    Unreachable,
    /// No convergence after this many iterations (a singular pose?).
    NoConvergence {
        /// Iterations taken.
        iterations: usize,
    },
    /// The corrected values leave these joints' limits.
    BeyondLimits {
        /// The joints (table rows).
        joints: Vec<String>,
    },
}

/// One commanded row, compensated.
#[derive(Clone, Debug, PartialEq)]
pub struct CompensatedRow {
    /// The row's pose name: its `config`, else `line<N>`.
    pub config: String,
    /// Its line in the joint file (1-based; the row for arrays).
    pub line: usize,
    /// The solver's result: corrected values in the model's measured columns, errors before
    /// and after.
    pub result: Compensated,
    /// Why the row was not compensated, `None` when it was.
    pub failure: Option<Failure>,
}

/// The `status` cell of a row that was compensated ([`CompensatedRow::status`]).
pub const COMPENSATED: &str = "compensated";

impl CompensatedRow {
    /// The row's `status` as the written file gives it: [`COMPENSATED`], or the failure's
    /// word ([`Failure::status`]), so that a program reading the file can keep the rows that
    /// were corrected.
    pub fn status(&self) -> &'static str {
        self.failure.as_ref().map_or(COMPENSATED, Failure::status)
    }
}

impl Failure {
    /// One word for the failure, the `status` cell of its row: `max_change`, `unreachable`,
    /// `no_convergence`, `beyond_limits`.
    pub fn status(&self) -> &'static str {
        match self {
            Failure::MaxChange { .. } => "max_change",
            Failure::Unreachable => "unreachable",
            Failure::NoConvergence { .. } => "no_convergence",
            Failure::BeyondLimits { .. } => "beyond_limits",
        }
    }

    /// The failure of `c`, a pose of the measured columns `columns`, or `None`.
    fn of(c: &Compensated, columns: &[String]) -> Option<Failure> {
        if !c.converged && !c.at_max_change.is_empty() {
            Some(Failure::MaxChange {
                columns: c
                    .at_max_change
                    .iter()
                    .filter_map(|&i| columns.get(i).cloned())
                    .collect(),
            })
        } else if c.stalled {
            Some(Failure::Unreachable)
        } else if !c.converged {
            Some(Failure::NoConvergence {
                iterations: c.iterations,
            })
        } else if !c.beyond_limits.is_empty() {
            Some(Failure::BeyondLimits {
                joints: c.beyond_limits.clone(),
            })
        } else {
            None
        }
    }

    /// The failure in words, with the errors of `c` in units `lu`, `au` (`max_change`: the
    /// option's value, in rad or m).
    pub fn describe(
        &self,
        c: &Compensated,
        max_change: f64,
        lu: LengthUnit,
        au: AngleUnit,
    ) -> String {
        let quoted = |names: &[String]| {
            names
                .iter()
                .map(|n| format!("'{}'", escape(n)))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let (p, r) = (
            c.position_error / lu.metres(),
            c.orientation_error / au.radians(),
        );
        let (l, a) = (lu.symbol(), au.symbol());
        match self {
            Failure::MaxChange { columns } => format!(
                "needs more than --max-change {max_change} (rad or m) of {} (a singular pose?): {p:.3e} {l} and {r:.3e} {a} remain at that bound",
                quoted(columns)
            ),
            Failure::Unreachable => format!(
                "beyond the calibrated robot's reach from the commanded values: the nearest pose leaves {p:.3e} {l} and {r:.3e} {a}"
            ),
            Failure::NoConvergence { iterations } => format!(
                "no convergence after {iterations} iterations (a singular pose?), {p:.3e} {l} and {r:.3e} {a} remain"
            ),
            Failure::BeyondLimits { joints } => format!("beyond the limits of {}", quoted(joints)),
        }
    }
}

/// Poses not compensated, repeats of one pose (a measurement file's targets and repeats, in
/// consecutive rows with the same failure) as one entry.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FailedPose {
    /// The pose's name ([`CompensatedRow::config`]).
    pub config: String,
    /// The lines of its rows.
    pub lines: Vec<usize>,
    /// Why, in words ([`Failure::describe`]).
    pub why: String,
}

impl std::fmt::Display for FailedPose {
    /// `config (line N): why`, or `config (K rows, lines A-B): why`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let at = match self.lines.as_slice() {
            [one] => format!("line {one}"),
            [first, .., last] => format!("{} rows, lines {first}-{last}", self.lines.len()),
            [] => String::new(),
        };
        write!(f, "{} ({at}): {}", escape(&self.config), self.why)
    }
}

/// The poses of `rows` that were not compensated ([`FailedPose`]), their errors in units `lu`,
/// `au`; `max_change` is the option's value (rad or m).
pub fn failed_poses(
    rows: &[CompensatedRow],
    max_change: f64,
    lu: LengthUnit,
    au: AngleUnit,
) -> Vec<FailedPose> {
    let mut failed: Vec<FailedPose> = Vec::new();
    for row in rows {
        let Some(f) = &row.failure else { continue };
        let why = f.describe(&row.result, max_change, lu, au);
        match failed.last_mut() {
            Some(p) if p.config == row.config && p.why == why => p.lines.push(row.line),
            _ => failed.push(FailedPose {
                config: row.config.clone(),
                lines: vec![row.line],
                why,
            }),
        }
    }
    failed
}

/// Refuses a calibrated model whose joints are not the nominal model's (`origins`: the two
/// files' names, nominal first).
///
/// # Errors
/// The joints differ, naming both lists.
pub fn same_joints(
    nominal: &DhTable,
    calibrated: &CalibratedModel,
    origins: (&str, &str),
) -> Result<()> {
    let a: Vec<&str> = nominal.rows.iter().map(|r| r.name.as_str()).collect();
    let b: Vec<&str> = calibrated
        .loaded
        .table
        .rows
        .iter()
        .map(|r| r.name.as_str())
        .collect();
    if a != b {
        let list = |names: &[&str]| {
            names
                .iter()
                .map(|n| format!("'{}'", escape(n)))
                .collect::<Vec<_>>()
                .join(", ")
        };
        return Err(hinted(
            format!(
                "{} and {} have different joints: {} against {}",
                origins.0,
                origins.1,
                list(&a),
                list(&b)
            ),
            "give the model the calibration started from as --nominal (with --base/--tip for a URDF)",
        ));
    }
    Ok(())
}

/// Compensates every row of `input`: the goal is the tool pose of `nominal` (the model the
/// robot's controller uses) at the commanded values, reached by `model` (the calibrated robot,
/// with the same joints: [`same_joints`]).
///
/// # Errors
/// A nominal model whose forward kinematics fail at a row (non-finite values); an effect of
/// time without the rows' times ([`crate::predict::timed_contexts`]).
pub fn compensate(
    nominal: &DhTable,
    model: &CalibratedModel,
    input: &JointInput,
    options: &CompensateOptions,
) -> Result<Vec<CompensatedRow>> {
    compensate_to(model, input, options, &|q| Ok(nominal.fk(q)?))
}

/// [`compensate`] for a calibrated tree: the goal is the tip of branch
/// [`CompensateOptions::chain`] of the nominal tree `nominal` at the commanded values, and
/// only the joints of that branch's chain move (see [`dh_calib::compensate`]): the trunk's
/// joints, shared by every branch, move the other branches' tools with them.
///
/// # Errors
/// As [`compensate`]; a nominal tree without that branch.
pub fn compensate_tree(
    nominal: &DhTree,
    model: &CalibratedModel,
    input: &JointInput,
    options: &CompensateOptions,
) -> Result<Vec<CompensatedRow>> {
    let chain = options.chain;
    compensate_to(model, input, options, &|q| {
        nominal
            .frames(q)?
            .tips
            .get(chain)
            .copied()
            .ok_or_else(|| anyhow::anyhow!("the nominal tree has no branch {chain}"))
    })
}

/// The nominal model of `compensate`: the chain the robot program was computed with, or for a
/// calibrated tree the nominal tree sheet (whose chosen branch's tool is the goal).
#[derive(Clone, Debug)]
pub enum NominalModel {
    /// A serial model's table (metres, radians).
    Chain(DhTable),
    /// A tree sheet's tree.
    Tree(DhTree),
}

impl NominalModel {
    /// Reads the nominal model at `path` for the calibrated `model`: a tree sheet when `model`
    /// is a tree, else a URDF chain (`base`, `tip`) or a sheet.
    ///
    /// # Errors
    /// As [`crate::model::load_model`]; for a tree, a file that is no tree sheet (naming it,
    /// with a hint).
    pub fn load(
        path: &str,
        base: Option<&str>,
        tip: Option<&str>,
        model: &CalibratedModel,
    ) -> Result<NominalModel> {
        if !model.is_tree() {
            let loaded = crate::model::load_model(path, base, tip, dh_core::Convention::Standard)?;
            return Ok(NominalModel::Chain(loaded.table));
        }
        let origin = crate::input::display_name(path);
        let text = crate::input::read_text(path)?;
        let doc = crate::sheet::parse_doc(&text, &origin)?;
        if doc.branches.is_none() {
            return Err(hinted(
                format!(
                    "{origin}: expected the nominal tree sheet (with 'branches') of the calibrated tree {}, found a model of one chain",
                    model.loaded.origin
                ),
                "give the tree sheet the calibration started from as --nominal",
            ));
        }
        Ok(NominalModel::Tree(
            crate::tree_sheet::TreeSheet::from_doc(doc, &text, &origin)?.tree,
        ))
    }

    /// Every row in joint order (a tree's joint table), for [`same_joints`].
    pub fn rows(&self) -> DhTable {
        match self {
            NominalModel::Chain(t) => t.clone(),
            NominalModel::Tree(t) => t.joint_table(),
        }
    }

    /// [`compensate`] or [`compensate_tree`], as the model is.
    ///
    /// # Errors
    /// As those.
    pub fn compensate(
        &self,
        model: &CalibratedModel,
        input: &JointInput,
        options: &CompensateOptions,
    ) -> Result<Vec<CompensatedRow>> {
        match self {
            NominalModel::Chain(t) => compensate(t, model, input, options),
            NominalModel::Tree(t) => compensate_tree(t, model, input, options),
        }
    }
}

/// Compensates every row of `input` towards `goal(row values)` (base link frame).
fn compensate_to(
    model: &CalibratedModel,
    input: &JointInput,
    options: &CompensateOptions,
    goal: &dyn Fn(&[f64]) -> Result<Isometry3<f64>>,
) -> Result<Vec<CompensatedRow>> {
    let columns = &model.joints.columns;
    // Rows in a sequence are compensated on their joints' flanks ([`JointInput::contexts`]),
    // and at their times for an effect of time.
    let contexts = crate::predict::timed_contexts(model, input)?;
    let mut sequenced = (!contexts.is_empty()).then(|| model.calibrated.clone());
    input
        .rows
        .iter()
        .enumerate()
        .map(|(i, row)| {
            let goal = goal(&model.joints.rows(&row.q))?;
            let calibrated = match (sequenced.as_mut(), contexts.get(i)) {
                (Some(c), Some(ctx)) => {
                    c.set_context(ctx.clone());
                    &*c
                }
                _ => &model.calibrated,
            };
            let result = solve(calibrated, &model.joints, &goal, &row.q, options);
            Ok(CompensatedRow {
                config: row
                    .config
                    .clone()
                    .unwrap_or_else(|| format!("line{}", row.line)),
                line: row.line,
                failure: Failure::of(&result, columns),
                result,
            })
        })
        .collect()
}
