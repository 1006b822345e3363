//! [`SheetError`]: every way a sheet, a tree sheet, an inertials file or a written table can be
//! refused, and the failures of `check`'s comparison.
//!
//! Each variant's message is complete on its own (`{}` prints the whole of it, the file named
//! first): no variant hides a cause in [`std::error::Error::source`]. Where the user can do
//! something specific, [`SheetError::hint`] says what.

use dh_core::CoreError;

/// Why a sheet or a comparison failed.
///
/// `origin` fields name the file as the caller gave it (with `(line N)` where known), so that a
/// message locates the fault without further context.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SheetError {
    /// The text holds nothing but whitespace.
    #[error(
        "{origin}: the sheet is empty; expected YAML or JSON with 'convention', 'length_unit', \
         'angle_unit' and 'joints'"
    )]
    Empty {
        /// The file.
        origin: String,
    },
    /// Flow collections nested deeper than `dh_calib::import::MAX_FLOW_DEPTH`.
    #[error(
        "{origin} (line {line}): expected lists and maps nested at most {max} deep, found deeper"
    )]
    TooDeep {
        /// The file.
        origin: String,
        /// 1-based line where the limit is passed.
        line: usize,
        /// The limit.
        max: usize,
    },
    /// The first line of content cannot start a sheet (a CSV table, XML, plain text).
    #[error(
        "{origin} (line {line}): expected a DH sheet (YAML or JSON with 'convention', \
         'length_unit', 'angle_unit' and 'joints'), found what looks like {looks}: '{found}'"
    )]
    NotASheet {
        /// The file.
        origin: String,
        /// 1-based line of the first content.
        line: usize,
        /// What the text looks like, e.g. "a CSV table (a measurement file?)".
        looks: &'static str,
        /// The line quoted (escaped, cut at 80 characters).
        found: String,
    },
    /// A YAML or JSON syntax error, an unknown, missing or repeated key, a value of the wrong
    /// type: the parser's message.
    #[error("{origin}{}: {message}", at(*.location))]
    Syntax {
        /// The file.
        origin: String,
        /// 1-based line and column, when the parser gave them.
        location: Option<(usize, usize)>,
        /// The parser's message (cut at 200 characters).
        message: String,
    },
    /// A sheet with `branches` given where one chain is expected.
    #[error(
        "{origin}: 'branches': a tree sheet (a trunk and {} branch(es): {}) describes no single \
         chain; only 'calibrate', and 'predict' and 'compensate' of its calibration, read trees",
        branches.len(),
        quoted_list(branches)
    )]
    TreeNotChain {
        /// The file.
        origin: String,
        /// The branches' names.
        branches: Vec<String>,
    },
    /// `inertials` in a sheet without `branches`.
    #[error("{origin}: 'inertials': only a tree sheet (with 'branches') carries its link masses")]
    InertialsNotTree {
        /// The file.
        origin: String,
    },
    /// A sheet without rows.
    #[error("{origin}: 'joints' is empty; expected at least one joint")]
    NoJoints {
        /// The file.
        origin: String,
    },
    /// Two rows of a serial sheet with one name.
    #[error("{origin}: joint '{joint}' appears twice")]
    DuplicateJoint {
        /// The file.
        origin: String,
        /// The repeated name.
        joint: String,
    },
    /// A bad row: blank or spoofing name, non-finite or huge value, limits out of order, bad
    /// mimic.
    #[error("{origin}: joint '{joint}': {problem}")]
    BadJoint {
        /// The file (and, in a tree sheet, the line and the branch).
        origin: String,
        /// The row's name (escaped where it holds control characters).
        joint: String,
        /// What is wrong, e.g. "d must be a finite number, found NaN".
        problem: String,
    },
    /// A bad `base`, `tool` or mount pose.
    #[error("{origin}: {what}: {problem}")]
    BadPose {
        /// The file.
        origin: String,
        /// Which pose, e.g. `base`, `branch 'r': tool`.
        what: String,
        /// What is wrong.
        problem: String,
    },
    /// A serial sheet's `base` or `tool` that does not read (the message of `error`, prefixed
    /// with the transform).
    #[error("reading the {which} transform: {error}")]
    Transform {
        /// `base` or `tool`.
        which: &'static str,
        /// What is wrong with it.
        error: Box<SheetError>,
    },
    /// A `robot`, `source`, `base_link` or `tip_link` holding a control or bidi character (see
    /// [`crate::text::label_problem`]): it would reach every table printed from the sheet.
    #[error("{origin}: {key}: {problem}")]
    BadLabel {
        /// The file.
        origin: String,
        /// The key.
        key: &'static str,
        /// What is wrong, quoting the text.
        problem: String,
    },
    /// A bad `effects` entry.
    #[error("{origin}: effects: {problem}")]
    BadEffects {
        /// The file.
        origin: String,
        /// What is wrong, naming the effect.
        problem: String,
    },
    /// A bad `coupled` entry.
    #[error("{origin}: coupled: {problem}")]
    BadCoupling {
        /// The file (and line).
        origin: String,
        /// What is wrong, naming the joint.
        problem: String,
    },
    /// A serial sheet given where a tree sheet is expected.
    #[error("{origin}: expected a tree sheet with 'branches', found a serial sheet")]
    NotATree {
        /// The file.
        origin: String,
    },
    /// `branches: []`.
    #[error("{origin}: 'branches' is empty; expected at least one branch")]
    NoBranches {
        /// The file.
        origin: String,
    },
    /// A bad branch: a blank or spoofing name, a `/` in it, no rows.
    #[error("{origin}: {branch}: {problem}")]
    BadBranch {
        /// The file and line.
        origin: String,
        /// `branch 'NAME'`, or `branch K` (from 1) when the name itself is bad.
        branch: String,
        /// What is wrong.
        problem: String,
        /// What to do about it, where there is something specific.
        hint: Option<&'static str>,
    },
    /// Two branches with one name.
    #[error("{origin}: branch '{branch}' appears twice; expected unique branch names")]
    DuplicateBranch {
        /// The file and line.
        origin: String,
        /// The repeated name.
        branch: String,
    },
    /// One joint name twice across a tree.
    #[error(
        "{origin}: {table}: joint '{joint}' appears twice in the tree (first in {first}); \
         expected unique joint names"
    )]
    DuplicateTreeJoint {
        /// The file and line.
        origin: String,
        /// `trunk` or `branch 'NAME'`, where it appears again.
        table: String,
        /// The repeated name.
        joint: String,
        /// Where it appears first.
        first: String,
    },
    /// The rows and branches make no tree (`dh_calib::tree::DhTree::new` refused them).
    #[error("{origin}: tree: {problem}")]
    BadTree {
        /// The file.
        origin: String,
        /// The tree builder's message.
        problem: String,
    },
    /// Bad link masses, payloads or gravity.
    #[error("{origin}: inertials: {problem}")]
    BadInertials {
        /// The file (and line).
        origin: String,
        /// What is wrong.
        problem: String,
        /// What to do about it (e.g. the tree's joint names), where known.
        hint: Option<String>,
    },
    /// Text that the writer of [`crate::render`] did not write: a bug when reading back the
    /// command's own output.
    #[error("{0}")]
    ReadBack(String),
    /// A format that is no DH sheet (`poe`) asked of a writer of sheets.
    #[error("--format {format}: expected a sheet format (text, yaml, json, csv, markdown), found {format}, which only extract writes (from a robot's chain)")]
    NotSheetFormat {
        /// The format.
        format: &'static str,
    },
    /// A sheet that cannot be written as YAML.
    #[error(transparent)]
    Yaml(#[from] serde_yaml::Error),
    /// A sheet that cannot be written as JSON.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// A step of `check`'s comparison failed (not expected for a valid chain and sheet).
    #[error("{step}: {error}")]
    Compare {
        /// The step, e.g. "extracting the URDF's own table".
        step: &'static str,
        /// The geometry's error.
        error: CoreError,
    },
    /// The sheet's own geometry failed (not expected for a sheet that read).
    #[error(transparent)]
    Geometry(#[from] CoreError),
}

impl SheetError {
    /// What the user can do about the error, where there is something specific to say (the
    /// CLI prints it as its `hint:` line).
    pub fn hint(&self) -> Option<String> {
        Some(match self {
            SheetError::NotASheet { .. } => {
                "measurements go to calibrate --data; a URDF goes to extract or check as the robot"
                    .into()
            }
            SheetError::TreeNotChain { .. } => {
                "calibrate the whole tree with: urdf-dh calibrate --model SHEET --data D.csv --out \
                 CAL.yaml (from a file, not standard input), then predict or compensate with \
                 --model CAL.yaml --branch NAME; for other commands give one chain as a serial \
                 sheet (the trunk's joints followed by one branch's)"
                    .into()
            }
            SheetError::InertialsNotTree { .. } => {
                "give a serial robot's link masses to calibrate with --inertials FILE".into()
            }
            SheetError::NotATree { .. } => {
                "a serial sheet is read as the model itself; a tree sheet adds 'branches: [{name, \
                 base, tool, joints}]'"
                    .into()
            }
            SheetError::NoBranches { .. } => "drop 'branches' for a serial robot".into(),
            SheetError::BadBranch { hint, .. } => return hint.map(String::from),
            SheetError::BadInertials { hint, .. } => return hint.clone(),
            SheetError::Transform { error, .. } => return error.hint(),
            _ => return None,
        })
    }
}

/// ` (line L, column C)`, or nothing.
fn at(location: Option<(usize, usize)>) -> String {
    match location {
        Some((line, column)) => format!(" (line {line}, column {column})"),
        None => String::new(),
    }
}

/// `'a', 'b'`.
fn quoted_list(names: &[String]) -> String {
    names
        .iter()
        .map(|n| format!("'{n}'"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// A result of this crate.
pub type Result<T, E = SheetError> = std::result::Result<T, E>;

/// An error with a `hint:` line telling the user what to do.
#[derive(Debug)]
pub struct Hinted {
    /// What is wrong.
    pub message: String,
    /// What to do about it.
    pub hint: String,
}

impl std::fmt::Display for Hinted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for Hinted {}

/// An error with a hint.
pub fn hinted(message: impl Into<String>, hint: impl Into<String>) -> anyhow::Error {
    anyhow::Error::new(Hinted {
        message: message.into(),
        hint: hint.into(),
    })
}

/// The `hint:` line for an error: a [`Hinted`] one's own, a [`SheetError`]'s own, else one for
/// the URDF reader's errors whose remedy is a command-line option of `urdf-dh` (`--tip`,
/// `--base`; the Python package's keyword arguments of the same names) or a tool.
pub fn hint_for(e: &anyhow::Error) -> Option<String> {
    if let Some(h) = e.chain().find_map(|c| c.downcast_ref::<Hinted>()) {
        return Some(h.hint.clone());
    }
    if let Some(h) = e
        .chain()
        .find_map(|c| c.downcast_ref::<SheetError>().and_then(SheetError::hint))
    {
        return Some(h);
    }
    let u = e
        .chain()
        .find_map(|c| c.downcast_ref::<urdf_axes::UrdfError>())?;
    Some(match u {
        urdf_axes::UrdfError::SeveralLeaves { leaves, .. } => format!(
            "choose the tip with --tip, e.g. --tip {}",
            leaves.first().map_or("LINK", String::as_str)
        ),
        urdf_axes::UrdfError::UnknownLink {
            role,
            link,
            candidates,
        } => match crate::text::normalisation_note(link, candidates.iter().map(String::as_str)) {
            // Two names that print alike: say how they differ, not what --tip takes.
            Some(note) => format!("{note}; give --{role} as the URDF spells it"),
            None => format!("--{role} takes the name of a <link> of the URDF (not of a joint)"),
        },
        urdf_axes::UrdfError::Disconnected {
            reversed: false,
            base,
            ..
        } => format!(
            "the tip must lie in the link tree below the base; '{base}' is not above it \
             (leave out --base to start at the root link)"
        ),
        urdf_axes::UrdfError::JointTypeInChain { joint, found, .. } => format!(
            "a {found} joint has no axis line: start the chain below '{joint}' \
             with --base (its child link), or end it above with --tip"
        ),
        urdf_axes::UrdfError::NoMovingJoint { .. } => "choose a --base and --tip with a revolute, \
             continuous or prismatic joint between them"
            .into(),
        urdf_axes::UrdfError::EntityDeclaration { .. } => {
            "expand the entities first (xacro, or by hand): urdf-dh reads plain URDF".into()
        }
        urdf_axes::UrdfError::TooLarge { .. } => "a robot description is a few megabytes at most (meshes live \
             in their own files): check what is being read"
            .into(),
        urdf_axes::UrdfError::NotUtf8 { .. } => {
            "convert the file to UTF-8, e.g. iconv -f latin1 -t utf-8 FILE > FILE.utf8".into()
        }
        urdf_axes::UrdfError::SeveralRoots { .. } => {
            "join every link to one tree with a joint (a fixed one will do), or remove the stray links"
                .into()
        }
        urdf_axes::UrdfError::Cycle { .. } | urdf_axes::UrdfError::NoRoot { .. } => {
            "a URDF is a tree of links: remove one joint of the cycle".into()
        }
        _ => return None,
    })
}
