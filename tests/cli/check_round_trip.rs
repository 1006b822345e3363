//! `extract --format yaml` then `check` of that output against the same URDF is a MATCH, for
//! every chain of ../shared/robots (root to each leaf) and ../shared/robots-ext (its
//! manifest), in both conventions. Runs the library in-process (what the binary runs) to stay
//! fast. Needs ../shared; skips with a reason without it.

use std::path::Path;

use dh_core::Convention;
use dh_workflows::render::{render_sheet, Format};
use dh_workflows::sheet::Sheet;
use dh_workflows::units::{AngleUnit, LengthUnit};
use urdf_dh::commands::check::{compare, CHECK_ANGULAR, CHECK_LINEAR};
use urdf_dh::commands::extract::{run_extract, ExtractArgs};

use crate::common::{corpus_chains, skip_without_shared};

/// Extracts `urdf` (`base` → `tip`) in `convention`, writes the YAML sheet, reads it back and
/// checks it against the same URDF. `None` for a match, else what went wrong.
fn round_trip(urdf: &Path, base: &str, tip: &str, convention: Convention) -> Option<String> {
    let args = ExtractArgs {
        path: urdf.to_string_lossy().into_owned(),
        base: Some(base.to_string()),
        tip: Some(tip.to_string()),
        convention,
        format: Format::Yaml,
        length_unit: LengthUnit::M,
        angle_unit: AngleUnit::Rad,
        tolerance: dh_core::Tolerance::default(),
        samples: Some(50),
        seed: 0,
        svg: None,
        q: None,
    };
    let ex = match run_extract(&args) {
        Ok(ex) => ex,
        Err(e) => return Some(format!("extract: {e:#}")),
    };
    let yaml = match render_sheet(&ex.sheet, Format::Yaml) {
        Ok(y) => y,
        Err(e) => return Some(format!("render: {e:#}")),
    };
    let sheet = match Sheet::parse(&yaml, "extracted.yaml") {
        Ok(s) => s,
        Err(e) => return Some(format!("sheet: {e:#}")),
    };
    let tol = dh_core::Tolerance::new(CHECK_LINEAR, CHECK_ANGULAR).ok()?;
    // Diagnosis only: does the YAML's xyz/rpy give back the base and tool extract computed?
    let written = |a: &nalgebra::Isometry3<f64>, b: &nalgebra::Isometry3<f64>, what: &str| {
        let (dp, dr) = dh_core::pose::pose_error(a, b);
        (dp > 1e-9 || dr > 1e-9).then(|| {
            format!(
                "; the YAML's {what} xyz/rpy is {dp:.1e} m, {dr:.1e} rad off the extracted {what}"
            )
        })
    };
    let lost = written(&ex.extraction.table.base, &sheet.table.base, "base")
        .into_iter()
        .chain(written(
            &ex.extraction.table.tool,
            &sheet.table.tool,
            "tool",
        ))
        .collect::<String>();
    match compare(&ex.chain, &sheet, tol) {
        Ok(r) if r.matches => None,
        Ok(r) => Some(format!(
            "MISMATCH {} (literal {:.2e} m {:.2e} rad){lost}",
            r.differences
                .iter()
                .map(|d| format!("{} {}", d.joint.as_deref().unwrap_or("-"), d.parameter))
                .collect::<Vec<_>>()
                .join(", "),
            r.max_position_error.unwrap_or(f64::NAN),
            r.max_orientation_error.unwrap_or(f64::NAN)
        )),
        Err(e) => Some(format!("check: {e:#}")),
    }
}

#[test]
fn extracted_sheets_check_as_a_match_across_the_corpus() {
    let Some(shared) = skip_without_shared("check round trip") else {
        return;
    };
    let chains = corpus_chains(&shared);
    assert!(
        chains.len() >= 300,
        "expected both corpora, found {} chains",
        chains.len()
    );
    let mut failures = Vec::new();
    for (label, urdf, base, tip) in &chains {
        for convention in [Convention::Standard, Convention::Modified] {
            if let Some(why) = round_trip(urdf, base, tip, convention) {
                failures.push(format!("{label} ({convention}): {why}"));
            }
        }
    }
    println!(
        "{} chains x 2 conventions, {} failures",
        chains.len(),
        failures.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
