//! `urdf-dh extract`: URDF -> DH table in either convention, proved by forward kinematics.

use anyhow::{Context, Result};
use dh_core::{Convention, Extraction, Tolerance};
use urdf_axes::{Chain, UrdfModel};

use crate::error::Outcome;
use crate::input::{display_name, read_robot};
use crate::readback::{prove, Isometry3Pair, Source};
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
    /// Tip link (default: the only leaf).
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
    /// Joint-value samples for the self-check.
    pub samples: usize,
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

/// Loads the URDF and its chain.
///
/// # Errors
/// Unreadable file, invalid URDF, unknown or ambiguous base/tip.
pub fn load_chain(path: &str, base: Option<&str>, tip: Option<&str>) -> Result<(UrdfModel, Chain)> {
    let bytes = read_robot(path)?;
    load_chain_bytes(&bytes, &display_name(path), base, tip)
}

/// Loads the chain of a URDF given as bytes; `name` names it in error messages (a file name, or
/// `<string>` for XML text a library caller passed).
///
/// # Errors
/// Invalid URDF, unknown or ambiguous base/tip.
pub fn load_chain_bytes(
    bytes: &[u8],
    name: &str,
    base: Option<&str>,
    tip: Option<&str>,
) -> Result<(UrdfModel, Chain)> {
    let model = UrdfModel::from_bytes(bytes).with_context(|| format!("{name}: invalid URDF"))?;
    let chain = model
        .chain(base, tip)
        .with_context(|| format!("{name}: cannot choose the chain"))?;
    Ok((model, chain))
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
    let extraction = dh_core::extract(
        chain.axes(),
        &chain.tip_pose(),
        args.tolerance,
        args.convention,
    )
    .with_context(|| format!("{name}: extraction failed"))?;
    let mut sheet = SheetDoc::from_table(&extraction.table, args.length_unit, args.angle_unit);
    sheet.robot = Some(model.robot_name().to_string());
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
    Ok(Extracted {
        chain,
        extraction,
        sheet,
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
    for w in &ex.extraction.warnings {
        writeln!(err, "urdf-dh: warning: {w}")?;
    }
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
        crate::output::write_atomically(std::path::Path::new(path), svg.as_bytes())?;
    }
    let (text, passed) = prove_extracted(&mut ex, args.format, args.samples, args.seed)?;
    out.write_all(text.as_bytes())?;
    if passed {
        Ok(Outcome::Pass)
    } else {
        let v = ex.sheet.verification.as_ref();
        writeln!(
            err,
            "urdf-dh: error: verification failed: forward kinematics of the table as written strays {:.3e} m, {:.3e} rad from the URDF (bound {:.3e} m, {:.3e} rad)",
            v.map_or(f64::INFINITY, |v| v.max_position_error),
            v.map_or(f64::INFINITY, |v| v.max_orientation_error),
            v.map_or(0.0, |v| v.position_bound),
            v.map_or(0.0, |v| v.orientation_bound)
        )?;
        Ok(Outcome::Differs)
    }
}
