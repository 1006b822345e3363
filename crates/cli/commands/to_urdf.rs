//! `urdf-dh to-urdf`: a URDF whose kinematics equal a DH sheet (the writer and its proof are
//! the `dh-workflows` library's, [`dh_workflows::urdf_writer`]).

use std::io::Write;

use anyhow::Result;
use dh_workflows::input::{display_name, read_text};
use dh_workflows::sheet::Sheet;
pub use dh_workflows::urdf_writer::{
    check_urdf, origin, prove_urdf, urdf_of, write_proved, UrdfProof,
};

use crate::error::Outcome;

/// Everything `to-urdf` needs.
#[derive(Clone, Debug)]
pub struct ToUrdfArgs {
    /// Sheet path or `-`.
    pub sheet: String,
    /// Robot name (default: the sheet's `robot`, else `robot`).
    pub name: Option<String>,
    /// Base link name.
    pub base_link: String,
    /// Tip link name.
    pub tip_link: String,
    /// Joint-value samples of the check of the written URDF.
    pub samples: usize,
    /// Seed of the sampler.
    pub seed: u64,
}

/// Runs `to-urdf`: writes the URDF, proved by extracting what was written ([`prove_urdf`]); the
/// proof is appended as a comment after the root element. Exit 1 if it fails.
///
/// # Errors
/// Unreadable or invalid sheet; a written URDF that does not read back.
pub fn to_urdf(args: &ToUrdfArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    let name = display_name(&args.sheet);
    let sheet = Sheet::parse(&read_text(&args.sheet)?, &name)?;
    for w in &sheet.warnings {
        writeln!(err, "urdf-dh: warning: {w}")?;
    }
    if let Some(w) = sheet.effects_warning(&name, "a URDF holds the DH kinematics alone") {
        writeln!(err, "urdf-dh: warning: {w}")?;
    }
    let (text, proof) = write_proved(
        &sheet,
        &name,
        args.name.as_deref(),
        &args.base_link,
        &args.tip_link,
        args.samples,
        args.seed,
    )?;
    out.write_all(text.as_bytes())?;
    if proof.passed {
        return Ok(Outcome::Pass);
    }
    writeln!(
        err,
        "urdf-dh: error: verification failed: the written URDF's kinematics stray {:.3e} m, {:.3e} rad from {name} (bound {:.3e} m, {:.3e} rad)",
        proof.deviation.0, proof.deviation.1, proof.bound.0, proof.bound.1
    )?;
    Ok(Outcome::Differs)
}
