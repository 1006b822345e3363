//! `urdf-dh extract`: URDF -> DH table in either convention, proved by forward kinematics.

use anyhow::{Context, Result};
use dh_core::{Convention, Extraction, Tolerance};
use urdf_axes::{Chain, UrdfModel};

use crate::error::Outcome;
use crate::input::{display_name, read_robot};
// Loading a chain is `crate::input`'s; re-exported for the callers of `extract`'s API.
pub use crate::input::{chain_error, load_chain, load_chain_bytes, urdf_warnings};
use crate::readback::{failure_line, prove, Isometry3Pair, Source};
use crate::render::Format;
use crate::sheet::{PairDoc, SheetDoc, TolerancesDoc};
use crate::units::{AngleUnit, LengthUnit};

/// Everything `extract` needs.
#[derive(Clone, Debug)]
pub struct ExtractArgs {
    /// URDF path, `.xacro` path or `-`.
    pub path: String,
    /// Base link (default: the root link).
    pub base: Option<String>,
    /// Tip link (default: the end of the longest run of moving joints).
    pub tip: Option<String>,
    /// DH convention of the table.
    pub convention: Convention,
    /// Output format.
    pub format: Format,
    /// Length unit of the output.
    pub length_unit: LengthUnit,
    /// Angle unit of the output.
    pub angle_unit: AngleUnit,
    /// Tolerances for the axis classification.
    pub tolerance: Tolerance,
    /// Joint-value samples for the self-check ([`default_samples`] when not given).
    pub samples: Option<usize>,
    /// Seed of the sampler.
    pub seed: u64,
    /// Write a drawing of the DH frames here.
    pub svg: Option<String>,
    /// Joint values of the drawing (radians or metres; default all zero).
    pub q: Option<Vec<f64>>,
}

/// The result of an extraction and its verification, ready to print.
pub struct Extracted {
    /// The chain the table describes.
    pub chain: Chain,
    /// The extraction.
    pub extraction: Extraction,
    /// The sheet (table and facts, without the verification) in the requested units.
    pub sheet: SheetDoc,
    /// Warnings of reading the URDF that concern the chain (see [`urdf_warnings`]).
    pub urdf_warnings: Vec<String>,
}

/// Renders the sheet of `ex` in `format` and proves what was written: the text is read back at
/// its precision and compared with the URDF ([`crate::readback::prove`]); returns the text (with
/// the verification attached) and whether it passed.
///
/// # Errors
/// A writer bug (the text does not read back).
pub fn prove_extracted(
    ex: &mut Extracted,
    format: Format,
    samples: usize,
    seed: u64,
) -> Result<(String, bool)> {
    let table = &ex.extraction.table;
    let chain = &ex.chain;
    let free = Isometry3Pair {
        base: table.base,
        tool: table.tool,
    };
    prove(
        &mut ex.sheet,
        format,
        &free,
        Source {
            table,
            bound: ex.extraction.bound,
            oracle: |q: &[f64]| chain.fk(q),
            against: None,
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

/// Extracts; the caller proves what it writes ([`prove_extracted`]) and prints.
///
/// # Errors
/// As [`load_chain`], plus geometry errors (a chain without moving joints).
pub fn run_extract(args: &ExtractArgs) -> Result<Extracted> {
    let bytes = read_robot(&args.path)?;
    run_extract_bytes(&bytes, &display_name(&args.path), args)
}

/// [`run_extract`] on a URDF given as bytes (`args.path` is not read); `name` names it in
/// error messages.
///
/// # Errors
/// As [`load_chain_bytes`], plus geometry errors (a chain without moving joints).
pub fn run_extract_bytes(bytes: &[u8], name: &str, args: &ExtractArgs) -> Result<Extracted> {
    let (model, chain) = load_chain_bytes(bytes, name, args.base.as_deref(), args.tip.as_deref())?;
    extract_chain(&model, chain, name, &args.options())
}

/// What an extraction of one chain needs besides the chain.
#[derive(Clone, Copy, Debug)]
pub struct ExtractOptions {
    /// DH convention of the table.
    pub convention: Convention,
    /// Length unit of the output.
    pub length_unit: LengthUnit,
    /// Angle unit of the output.
    pub angle_unit: AngleUnit,
    /// Tolerances for the axis classification.
    pub tolerance: Tolerance,
}

impl ExtractArgs {
    /// The options of one chain's extraction.
    pub fn options(&self) -> ExtractOptions {
        ExtractOptions {
            convention: self.convention,
            length_unit: self.length_unit,
            angle_unit: self.angle_unit,
            tolerance: self.tolerance,
        }
    }
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
    let args = options;
    let extraction = dh_core::extract(
        chain.axes(),
        &chain.tip_pose(),
        args.tolerance,
        args.convention,
    )
    .with_context(|| format!("{name}: extraction failed"))?;
    let mut sheet = SheetDoc::from_table(&extraction.table, args.length_unit, args.angle_unit);
    sheet.robot = Some(model.robot_name().to_string()).filter(|n| !n.is_empty());
    sheet.base_link = Some(chain.base().to_string());
    sheet.tip_link = Some(chain.tip().to_string());
    let ex_rows = &extraction.table.rows;
    sheet.pairs = Some(
        extraction
            .pairs
            .iter()
            .map(|p| PairDoc {
                joints: [
                    ex_rows[p.first].name.clone(),
                    ex_rows[p.first + 1].name.clone(),
                ],
                relation: p.geometry.relation.to_string(),
                angle: args.angle_unit.from_si_unwrapped(p.geometry.angle),
                distance: args.length_unit.from_si(p.geometry.distance),
            })
            .collect(),
    );
    sheet.tolerances = Some(TolerancesDoc {
        linear: args.tolerance.linear,
        angular: args.tolerance.angular,
    });
    sheet.warnings = Some(extraction.warnings.iter().map(|w| w.to_string()).collect());
    let urdf_warnings = urdf_warnings(name, model, &chain);
    Ok(Extracted {
        chain,
        extraction,
        sheet,
        urdf_warnings,
    })
}

/// Runs `extract`, writing the table to `out` and warnings to `err`.
///
/// # Errors
/// As [`run_extract`], and failures to write.
pub fn extract(
    args: &ExtractArgs,
    out: &mut dyn std::io::Write,
    err: &mut dyn std::io::Write,
) -> Result<Outcome> {
    let mut ex = run_extract(args)?;
    for w in &ex.urdf_warnings {
        writeln!(err, "urdf-dh: warning: {w}")?;
    }
    for w in &ex.extraction.warnings {
        writeln!(err, "urdf-dh: warning: {w}")?;
    }
    let mut piped_svg = None;
    if let Some(path) = &args.svg {
        let n = ex.extraction.table.rows.len();
        let q = args.q.clone().unwrap_or_else(|| vec![0.0; n]);
        if q.len() != n {
            anyhow::bail!(
                "--q: expected {n} joint values (one per row: {}), found {}",
                ex.extraction
                    .table
                    .rows
                    .iter()
                    .map(|r| r.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
                q.len()
            );
        }
        let title = format!(
            "{} ({} -> {})",
            ex.sheet.robot.as_deref().unwrap_or("robot"),
            ex.chain.base(),
            ex.chain.tip()
        );
        let svg = crate::svg::frames_svg(&ex.extraction.table, &q, &title)
            .ok_or_else(|| anyhow::anyhow!("--q: the joint values do not fit the table"))?;
        if path == crate::output::STDIO {
            piped_svg = Some(svg);
        } else {
            crate::output::write_atomically(std::path::Path::new(path), svg.as_bytes())?;
        }
    }
    let samples = args
        .samples
        .unwrap_or_else(|| default_samples(ex.extraction.table.rows.len()));
    let (text, passed) = prove_extracted(&mut ex, args.format, samples, args.seed)?;
    // `--svg -`: the picture on standard output, the table on standard error.
    match piped_svg {
        Some(svg) => {
            out.write_all(svg.as_bytes())?;
            err.write_all(text.as_bytes())?;
        }
        None => out.write_all(text.as_bytes())?,
    }
    if passed {
        Ok(Outcome::Pass)
    } else {
        writeln!(
            err,
            "{}",
            failure_line("the table", "the URDF", ex.sheet.verification.as_ref())
        )?;
        Ok(Outcome::Differs)
    }
}
