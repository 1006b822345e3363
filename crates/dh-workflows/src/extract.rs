//! Extraction with its proof: a URDF chain's DH table (`dh_core::extract`, the paper's
//! line-geometry method) as a sheet with the extraction's facts (axis pairs, tolerances,
//! warnings), and the proof of that sheet as written ([`prove_extracted`]): the text is read
//! back at its precision and compared with the URDF by forward kinematics.
//!
//! Frames and units: the table is in metres and radians, `base` is DH frame 0 in the base link
//! frame and `tool` the tip link frame in the last DH frame; the sheet is in the units asked for.
//!
//! ```
//! use dh_workflows::extract::{extract_bytes, prove_extracted, ExtractOptions};
//! use dh_workflows::Format;
//!
//! let urdf = br#"<robot name="r"><link name="base"/><link name="l1"/><link name="l2"/>
//!   <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
//!     <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
//!   <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
//!     <origin xyz="0.3 0 0"/><axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
//! </robot>"#;
//! let mut ex = extract_bytes(urdf, "r.urdf", None, None, &ExtractOptions::default())?;
//! let (yaml, passed) = prove_extracted(&mut ex, Format::Yaml, 200, 1)?;
//! assert!(passed && yaml.contains("j2"));
//! # Ok::<(), anyhow::Error>(())
//! ```

use anyhow::{Context, Result};
use dh_core::{Convention, Extraction, Tolerance};
use urdf_axes::{Chain, UrdfModel};

use crate::input::{load_chain_in, urdf_warnings};
use crate::prove::{prove, Isometry3Pair, Source};
use crate::render::Format;
use crate::sheet::{PairDoc, SheetDoc, TolerancesDoc};
use crate::units::{AngleUnit, LengthUnit};

/// The result of an extraction, ready to prove ([`prove_extracted`]) and print.
pub struct Extracted {
    /// The chain the table describes.
    pub chain: Chain,
    /// The extraction.
    pub extraction: Extraction,
    /// The sheet (table and facts, without the verification) in the requested units.
    pub sheet: SheetDoc,
    /// Warnings of reading the URDF that concern the chain (see [`urdf_warnings`]).
    pub urdf_warnings: Vec<String>,
    /// What the table is proved against when the robot file is not a URDF (`the MJCF`), for
    /// the verification line; `None` for a URDF.
    pub against: Option<String>,
}

/// What an extraction of one chain needs besides the chain.
#[derive(Clone, Copy, Debug)]
pub struct ExtractOptions {
    /// DH convention of the table.
    pub convention: Convention,
    /// Length unit of the sheet.
    pub length_unit: LengthUnit,
    /// Angle unit of the sheet.
    pub angle_unit: AngleUnit,
    /// Tolerances for the axis classification.
    pub tolerance: Tolerance,
}

impl Default for ExtractOptions {
    /// Standard DH, metres and radians, the default tolerances.
    fn default() -> Self {
        ExtractOptions {
            convention: Convention::Standard,
            length_unit: LengthUnit::M,
            angle_unit: AngleUnit::Rad,
            tolerance: Tolerance::default(),
        }
    }
}

/// Renders the sheet of `ex` in `format` and proves what was written: the text is read back at
/// its precision and compared with the URDF ([`crate::prove::prove`], `samples` joint-value
/// samples drawn with `seed`); returns the text (with the verification attached) and whether it
/// passed.
///
/// # Errors
/// A writer bug (the text does not read back), a chain too large to prove.
pub fn prove_extracted(
    ex: &mut Extracted,
    format: Format,
    samples: usize,
    seed: u64,
) -> Result<(String, bool)> {
    prove_extracted_with(ex, format, samples, seed, |chain, q| chain.fk(q))
}

/// [`prove_extracted`] with the URDF's tip pose at joint values `q` given by
/// `oracle(&ex.chain, q)`, which must be what `ex.chain.fk(q)` gives: a caller proving several
/// tables of one chain may keep the poses it has computed (`urdf-dh batch` does for its
/// second convention).
///
/// # Errors
/// As [`prove_extracted`].
pub fn prove_extracted_with<F>(
    ex: &mut Extracted,
    format: Format,
    samples: usize,
    seed: u64,
    mut oracle: F,
) -> Result<(String, bool)>
where
    F: FnMut(&Chain, &[f64]) -> nalgebra::Isometry3<f64> + Send,
{
    let Extracted {
        chain,
        extraction,
        sheet,
        against,
        ..
    } = ex;
    let table = &extraction.table;
    if format == Format::Poe {
        let (text, verification, passed) = crate::poe::prove_poe(
            chain,
            table,
            (sheet.robot.clone(), against.clone()),
            samples,
            seed,
            |q| oracle(chain, q),
        )?;
        sheet.verification = Some(verification);
        return Ok((text, passed));
    }
    let free = Isometry3Pair {
        base: table.base,
        tool: table.tool,
    };
    prove(
        sheet,
        format,
        &free,
        Source {
            table,
            bound: extraction.bound,
            oracle: |q: &[f64]| oracle(chain, q),
            against: against.clone(),
            samples,
            seed,
        },
    )
}

/// Joint-value samples of the self-check when none are asked for: 1000, fewer for chains beyond
/// 10 000 joints so that the check costs at most 1e7 joint evaluations (a 100 000-joint chain: 100
/// samples, each still moving every joint), and never fewer than 10.
pub fn default_samples(joints: usize) -> usize {
    (10_000_000 / joints.max(1)).clamp(10, 1000)
}

/// Extracts the chain `base` -> `tip` (defaults as [`crate::input::load_chain_bytes`]) of the URDF `bytes`,
/// named `name` in messages; the caller proves it ([`prove_extracted`]).
///
/// # Errors
/// As [`crate::input::load_chain_bytes`], plus geometry errors (a chain without moving joints).
pub fn extract_bytes(
    bytes: &[u8],
    name: &str,
    base: Option<&str>,
    tip: Option<&str>,
    options: &ExtractOptions,
) -> Result<Extracted> {
    extract_bytes_in(bytes, name, None, base, tip, options)
}

/// [`extract_bytes`] of a robot file read from folder `dir` (where an MJCF `<include>` is
/// resolved; `None` when it was not read from a file).
///
/// # Errors
/// As [`load_chain_in`], plus geometry errors (a chain without moving joints).
pub fn extract_bytes_in(
    bytes: &[u8],
    name: &str,
    dir: Option<&std::path::Path>,
    base: Option<&str>,
    tip: Option<&str>,
    options: &ExtractOptions,
) -> Result<Extracted> {
    let (model, chain) = load_chain_in(bytes, name, dir, base, tip)?;
    extract_chain(&model, chain, name, options)
}

/// [`extract_bytes`] of a robot file held in memory with the files beside it
/// ([`crate::input::RobotFiles`]: a `.xacro` file expanded from them, an MJCF's includes read
/// from them); the expansion's warnings come first in [`Extracted::urdf_warnings`].
///
/// # Errors
/// As [`crate::input::RobotFiles::load_chain`], plus geometry errors.
pub fn extract_files(
    robot: &crate::input::RobotFiles,
    base: Option<&str>,
    tip: Option<&str>,
    options: &ExtractOptions,
) -> Result<Extracted> {
    let (model, chain, mut warnings) = robot.load_chain(base, tip)?;
    let mut ex = extract_chain(&model, chain, &robot.name(), options)?;
    warnings.append(&mut ex.urdf_warnings);
    ex.urdf_warnings = warnings;
    Ok(ex)
}

/// Extracts the table of `chain` (of `model`, read from the file shown as `name`) and its sheet
/// with the extraction's facts; the caller proves it ([`prove_extracted`]).
///
/// # Errors
/// Geometry errors (non-finite values).
pub fn extract_chain(
    model: &UrdfModel,
    chain: Chain,
    name: &str,
    options: &ExtractOptions,
) -> Result<Extracted> {
    let extraction = dh_core::extract(
        chain.axes(),
        &chain.tip_pose(),
        options.tolerance,
        options.convention,
    )
    .with_context(|| format!("{name}: extraction failed"))?;
    let (length, angle) = (options.length_unit, options.angle_unit);
    let mut sheet = SheetDoc::from_table(&extraction.table, length, angle);
    sheet.robot = Some(model.robot_name().to_string()).filter(|n| !n.is_empty());
    sheet.base_link = Some(chain.base().to_string());
    sheet.tip_link = Some(chain.tip().to_string());
    let rows = &extraction.table.rows;
    sheet.pairs = Some(
        extraction
            .pairs
            .iter()
            .map(|p| PairDoc {
                joints: [rows[p.first].name.clone(), rows[p.first + 1].name.clone()],
                relation: p.geometry.relation.to_string(),
                angle: angle.from_si_unwrapped(p.geometry.angle),
                distance: length.from_si(p.geometry.distance),
            })
            .collect(),
    );
    sheet.tolerances = Some(TolerancesDoc {
        linear: options.tolerance.linear,
        angular: options.tolerance.angular,
    });
    sheet.warnings = Some(extraction.warnings.iter().map(|w| w.to_string()).collect());
    let urdf_warnings = urdf_warnings(name, model, &chain);
    let against = (model.format_name() != "URDF").then(|| format!("the {}", model.format_name()));
    Ok(Extracted {
        chain,
        extraction,
        sheet,
        urdf_warnings,
        against,
    })
}
