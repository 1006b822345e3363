//! `urdf-dh extract`: URDF -> DH table in either convention, proved by forward kinematics.
//! The extraction and its proof are the `dh-workflows` library's ([`dh_workflows::extract`]); this
//! command reads the file, draws the frames (`--svg`) and prints.

use std::path::Path;

use anyhow::Result;
pub use dh_workflows::extract::{
    default_samples, extract_bytes, extract_bytes_in, extract_chain, prove_extracted,
    prove_extracted_with, ExtractOptions, Extracted,
};
use dh_workflows::geometry::{Convention, Tolerance};
use dh_workflows::input::{display_name, read_robot};
use dh_workflows::prove::failure_line;
use dh_workflows::render::Format;
use dh_workflows::units::{AngleUnit, LengthUnit};

use crate::error::Outcome;

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

/// Extracts; the caller proves what it writes ([`prove_extracted`]) and prints.
///
/// # Errors
/// As [`dh_workflows::input::load_chain`], plus geometry errors (a chain without moving joints).
pub fn run_extract(args: &ExtractArgs) -> Result<Extracted> {
    let bytes = read_robot(&args.path)?;
    extract_bytes_in(
        &bytes,
        &display_name(&args.path),
        dh_workflows::input::folder_of(&args.path).as_deref(),
        args.base.as_deref(),
        args.tip.as_deref(),
        &args.options(),
    )
}

/// [`run_extract`] on a URDF given as bytes (`args.path` is not read); `name` names it in
/// error messages.
///
/// # Errors
/// As [`dh_workflows::input::load_chain_bytes`], plus geometry errors (a chain without moving joints).
pub fn run_extract_bytes(bytes: &[u8], name: &str, args: &ExtractArgs) -> Result<Extracted> {
    extract_bytes(
        bytes,
        name,
        args.base.as_deref(),
        args.tip.as_deref(),
        &args.options(),
    )
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
    let mut drawing = None;
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
        drawing = Some((path, svg));
    }
    let samples = args
        .samples
        .unwrap_or_else(|| default_samples(ex.extraction.table.rows.len()));
    let (text, passed) = prove_extracted(&mut ex, args.format, samples, args.seed)?;
    // `--svg -`: the picture on standard output, the table on standard error. A drawing in a
    // file lands only once the table has reached standard output.
    match drawing {
        Some((path, svg)) if path == dh_workflows::output::STDIO => {
            dh_workflows::output::write_all_or_stdout(&[(Path::new(path), svg.as_bytes())], out)?;
            err.write_all(text.as_bytes())?;
        }
        Some((path, svg)) => {
            out.write_all(text.as_bytes())?;
            dh_workflows::output::write_all_after(out, &[(Path::new(path), svg.as_bytes())])?;
        }
        None => out.write_all(text.as_bytes())?,
    }
    if passed {
        Ok(Outcome::Pass)
    } else {
        writeln!(
            err,
            "{}",
            failure_line(
                "the table",
                ex.against.as_deref().unwrap_or("the URDF"),
                ex.sheet.verification.as_ref()
            )
        )?;
        Ok(Outcome::Differs)
    }
}
