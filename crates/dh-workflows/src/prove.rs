//! Proving what was written: a sheet rendered in any output format, read back and compared with
//! its source.
//!
//! The self-check of `extract` and `convert` is on the artefact: the text the command writes
//! (YAML, JSON, CSV, the aligned text table, Markdown) is read back here at the precision it
//! was written, and that table, not the one in memory, is compared with the source by forward
//! kinematics ([`dh_core::compare_while_writing`]: the source's side already runs while the
//! text is written and read back), within the source's bound plus what the written precision
//! allows ([`dh_core::written_bound`]).

use anyhow::{anyhow, bail, ensure, Context, Result};
use dh_core::{Bound, DhTable, Precision};
use nalgebra::Isometry3;

use crate::read_back::read_back;
use crate::render::{render_sheet_at, Format};
use crate::sheet::{SheetDoc, VerificationDoc};
use crate::units::{AngleUnit, LengthUnit, PRINT_NOISE};

/// The precision at which `format` writes values in these units: the fixed decimals of the text
/// and Markdown tables ([`crate::render`]), or the picometre / 1e-12 rad rounding (with the snap
/// to multiples of 45° within 1e-12 rad) of the sheet's numbers in YAML, JSON and CSV
/// ([`LengthUnit::from_si`], [`AngleUnit::from_si`]), plus the float noise printed as 0.
pub fn precision_of(format: Format, length: LengthUnit, angle: AngleUnit) -> Precision {
    precision_at(format, length, angle, 0)
}

/// [`precision_of`] for text and Markdown tables written with `extra` more decimals.
pub fn precision_at(
    format: Format,
    length: LengthUnit,
    angle: AngleUnit,
    extra: usize,
) -> Precision {
    let sheet_length = 0.5 * 10f64.powi(-(length.decimals() as i32)) * length.metres();
    let sheet_angle =
        (0.5 * 10f64.powi(-(angle.decimals() as i32)) * angle.radians()).max(10.0 * PRINT_NOISE);
    let (l, a) = (sheet_length + PRINT_NOISE, sheet_angle + PRINT_NOISE);
    match format {
        // PoE is proved by `crate::poe`, at its own precision; as JSON here.
        Format::Yaml | Format::Json | Format::Csv | Format::Poe => Precision::rounded(l, a),
        Format::Text | Format::Markdown => {
            let step = |decimals: usize| 0.5 * 10f64.powi(-((decimals + extra) as i32));
            Precision::rounded(
                l + step(crate::render::decimals(length.symbol())) * length.metres(),
                a + step(crate::render::decimals(angle.symbol())) * angle.radians(),
            )
        }
    }
}

/// What [`prove`] compares the written table with.
pub struct Source<'a, F> {
    /// The table the output was written from (SI units).
    pub table: &'a DhTable,
    /// The source's own bound (snapping, float arithmetic).
    pub bound: Bound,
    /// The tip pose the source gives at joint values `q` (one per row).
    pub oracle: F,
    /// What the source is, for the report ("the URDF", "the input sheet").
    pub against: Option<String>,
    /// Joint-value samples.
    pub samples: usize,
    /// Seed of the sampler.
    pub seed: u64,
}

/// Renders `doc` in `format`, reads the text back, compares that table with the source and
/// attaches the verification: appended to the proved text when it comes last (text, YAML, JSON;
/// see `verification_after`), else by rendering again and checking that the new text reads back
/// as the same table. Returns the final text and whether it passed.
/// A base or tool the document leaves out (free) is taken from `free` when comparing.
///
/// # Errors
/// A sample count outside [`crate::ranges::check_samples`]'s range (zero samples prove
/// nothing), a written text that does not read back as the same table twice (a writer bug), or
/// rows that differ from the source's in number.
pub fn prove<F>(
    doc: &mut SheetDoc,
    format: Format,
    free: &Isometry3Pair,
    source: Source<'_, F>,
) -> Result<(String, bool)>
where
    F: FnMut(&[f64]) -> Isometry3<f64> + Send,
{
    crate::ranges::check_samples(source.samples, source.table.rows.len())
        .map_err(|e| anyhow!("samples: {e}"))?;
    let size = source.table.size();
    // A size that is NaN (a table with a non-finite value) is no provable size either.
    if size.is_nan() || size > MAX_PROVABLE_SIZE {
        bail!(
            "the chain spans {size:.3e} m (lengths, offsets and prismatic travel): beyond {MAX_PROVABLE_SIZE:e} m \
             no table can be proved to {} m in double precision",
            Bound::MAX_POSITION
        );
    }
    doc.verification = None;
    let extra = extra_decimals(source.table, format, doc.length_unit, doc.angle_unit);
    // The oracle runs on a second thread while this one renders and reads back (a long chain).
    let mut first = String::new();
    let (written, dev) = dh_core::compare_while_writing(
        source.table,
        source.oracle,
        source.samples,
        source.seed,
        || -> Result<DhTable, Unproved> {
            first = render_sheet_at(doc, format, extra).map_err(|e| Unproved::Written(e.into()))?;
            table_of(&first, format, free).map_err(Unproved::Written)
        },
    )
    .map_err(|e| match e {
        Unproved::Written(e) => e,
        Unproved::Rows(e) => {
            anyhow!("the written table does not read back with the source's rows: {e}")
        }
    })?;
    let mut problems = Vec::new();
    for (w, s) in written.rows.iter().zip(&source.table.rows) {
        if w.kind != s.kind {
            problems.push(format!(
                "joint '{}' is written as {:?}, not {:?}",
                w.name, w.kind, s.kind
            ));
        }
    }
    let rounding = dh_core::written_bound(
        &written,
        precision_of(format, doc.length_unit, doc.angle_unit),
    );
    // Capped as the extraction bound is: a written table more than 1 mm / 1 mrad off its
    // source never verifies, whatever its precision allows.
    let bound = Bound {
        position: (source.bound.position + rounding.position).min(Bound::MAX_POSITION),
        orientation: (source.bound.orientation + rounding.orientation).min(Bound::MAX_ORIENTATION),
    };
    let passed = problems.is_empty()
        && dev.max_position_error <= bound.position
        && dev.max_orientation_error <= bound.orientation;
    doc.verification = Some(VerificationDoc {
        samples: dev.samples,
        seed: source.seed,
        max_position_error: dev.max_position_error,
        max_orientation_error: dev.max_orientation_error,
        position_bound: crate::units::bound_for_print(bound.position),
        orientation_bound: crate::units::bound_for_print(bound.orientation),
        passed,
        against: source.against,
    });
    let last = match verification_after(doc, format, &first)? {
        // The text proved, then its verification: the bytes read back above, and a last line
        // (text) or top-level key (YAML, JSON) that adds nothing to the table.
        Some(tail) => tail,
        None => {
            let last = render_sheet_at(doc, format, extra)?;
            // What was proved must be what is written.
            ensure!(
                table_of(&last, format, free)? == written,
                "internal error: the {format:?} output reads back differently once verified"
            );
            last
        }
    };
    Ok((last, passed))
}

/// The rendering of `doc` (with its verification) made from `first`, its rendering without
/// the verification, when the verification is all it adds at the end: the text table's last
/// line, or the YAML or JSON sheet's last top-level key (no key follows it). `None` for the
/// other formats and documents.
fn verification_after(doc: &SheetDoc, format: Format, first: &str) -> Result<Option<String>> {
    #[derive(serde::Serialize)]
    struct Tail<'a> {
        verification: &'a VerificationDoc,
    }
    let Some(v) = &doc.verification else {
        return Ok(None);
    };
    let last_key = doc.cpa.is_none() && doc.calibration.is_none() && doc.truth.is_none();
    Ok(match format {
        Format::Text => Some(first.to_owned() + &crate::render::verification_line(v)),
        Format::Yaml if last_key => {
            Some(first.to_owned() + &serde_yaml::to_string(&Tail { verification: v })?)
        }
        Format::Json if last_key => {
            // `{ ... "warnings": [] }` and `{ "verification": { ... } }`, pretty-printed alike:
            // the key's lines go before the closing brace.
            let tail = crate::text::json_pretty(&Tail { verification: v })?;
            match (first.strip_suffix("\n}\n"), tail.strip_prefix("{\n")) {
                (Some(head), Some(key)) => Some(format!("{head},\n{key}\n")),
                _ => None,
            }
        }
        _ => None,
    })
}

/// Why [`prove`] found no figures: the writing or reading back failed, or the table read back
/// has other rows than the source.
enum Unproved {
    Written(anyhow::Error),
    Rows(dh_core::CoreError),
}

impl From<dh_core::CoreError> for Unproved {
    fn from(e: dh_core::CoreError) -> Self {
        Unproved::Rows(e)
    }
}

/// The largest chain (metres, [`DhTable::size`]) whose written table can be proved: float
/// arithmetic alone moves the tip of a larger one by more than [`Bound::MAX_POSITION`] (a
/// double holds about 16 digits; 1e10 m to 1 mm takes 13 of them, with the rest for rounding
/// over the chain).
pub const MAX_PROVABLE_SIZE: f64 = 1e10;

/// The text and Markdown tables' usual decimals (1e-6 m, 1e-6 rad or 1e-4°) bound a written
/// arm's error by some 1e-5 m; a chain of kilometres (a mobile base's prismatic joints with
/// limits of ±1e6 m) needs more to stay within a tenth of [`Bound::MAX_POSITION`]: the fewest
/// extra decimals that do (at most 9).
pub const TEXT_TARGET: f64 = 0.1 * Bound::MAX_POSITION;

fn extra_decimals(table: &DhTable, format: Format, l: LengthUnit, a: AngleUnit) -> usize {
    if !matches!(format, Format::Text | Format::Markdown) {
        return 0;
    }
    let fits = |k: usize| {
        let b = dh_core::written_bound(table, precision_at(format, l, a, k));
        b.position <= TEXT_TARGET && b.orientation <= TEXT_TARGET
    };
    // The bound falls as decimals are added: the usual arm fits at once, and a long chain is
    // searched by halves (each try is a pass over the table).
    if fits(0) {
        return 0;
    }
    let tries: Vec<usize> = (1..9).collect();
    1 + tries.partition_point(|&k| !fits(k))
}

/// The error line of a written table that failed its proof: what (`table`) strayed how far from
/// what (`source`), against which bound.
pub fn failure_line(table: &str, source: &str, v: Option<&VerificationDoc>) -> String {
    format!(
        "urdf-dh: error: verification failed: forward kinematics of {table} as written strays {:.3e} m, {:.3e} rad from {source} (bound {:.3e} m, {:.3e} rad)",
        v.map_or(f64::INFINITY, |v| v.max_position_error),
        v.map_or(f64::INFINITY, |v| v.max_orientation_error),
        v.map_or(0.0, |v| v.position_bound),
        v.map_or(0.0, |v| v.orientation_bound)
    )
}

/// The base and tool to use where a written sheet leaves them out (free transforms).
pub struct Isometry3Pair {
    /// Base (DH frame 0 in the base link frame).
    pub base: Isometry3<f64>,
    /// Tool (tip link frame in the last DH frame).
    pub tool: Isometry3<f64>,
}

fn table_of(text: &str, format: Format, free: &Isometry3Pair) -> Result<DhTable> {
    let doc =
        read_back(text, format).with_context(|| format!("reading the {format:?} output back"))?;
    let (has_base, has_tool) = (doc.base.is_some(), doc.tool.is_some());
    let mut table = doc.into_sheet("written output")?.table;
    if !has_base {
        table.base = free.base;
    }
    if !has_tool {
        table.tool = free.tool;
    }
    Ok(table)
}

#[cfg(test)]
mod tests {
    use super::*;
    use dh_core::pose::from_xyz_rpy;
    use dh_core::{Convention, DhRow, Limits, Mimic};

    /// A table with awkward names (spaces, `|`, `,`, quotes), a mimic row, a prismatic row and a
    /// base at pitch -pi/2.
    fn table() -> DhTable {
        let mut rows = vec![
            DhRow::revolute("j 1|a", 0.1, std::f64::consts::FRAC_PI_2, 0.4, 0.2),
            DhRow::revolute("j,2\"", 0.7, 0.0, 0.0, -1.1),
            DhRow::prismatic("j3", 0.05, -std::f64::consts::FRAC_PI_2, 0.3, 0.0),
            DhRow::revolute("j4", 0.0, 0.9, 0.25, 0.4),
        ];
        rows[0].limits = Some(Limits {
            lower: -3.0,
            upper: 3.0,
        });
        rows[2].limits = Some(Limits {
            lower: -0.2,
            upper: 0.5,
        });
        // A Hayati tilt on a row with spaces in its neighbour's name, written on its own line.
        rows[1].beta = 3.1e-4;
        rows[3].beta = -2e-3;
        rows[3].mimic = Some(Mimic {
            joint: "j,2\"".into(),
            multiplier: -1.5,
            offset: 0.3,
        });
        DhTable {
            convention: Convention::Modified,
            base: from_xyz_rpy([0.1, -0.2, 0.3], [0.4, -std::f64::consts::FRAC_PI_2, -2.0]),
            tool: from_xyz_rpy([0.0, 0.05, 0.12], [3.0, -0.3, 1.0]),
            rows,
        }
    }

    fn free(t: &DhTable) -> Isometry3Pair {
        Isometry3Pair {
            base: t.base,
            tool: t.tool,
        }
    }

    #[test]
    fn every_format_reads_back_and_proves_itself() {
        let t = table();
        let fk = t.prepare();
        for format in [
            Format::Yaml,
            Format::Json,
            Format::Csv,
            Format::Text,
            Format::Markdown,
        ] {
            for (l, a) in [
                (LengthUnit::M, AngleUnit::Rad),
                (LengthUnit::Mm, AngleUnit::Deg),
            ] {
                let mut doc = SheetDoc::from_table(&t, l, a);
                let (text, passed) = prove(
                    &mut doc,
                    format,
                    &free(&t),
                    Source {
                        table: &t,
                        bound: Bound {
                            position: 0.0,
                            orientation: 0.0,
                        },
                        oracle: |q: &[f64]| fk.fk(q).unwrap_or_default(),
                        against: None,
                        samples: 200,
                        seed: 1,
                    },
                )
                .unwrap_or_else(|e| panic!("{format:?} {l:?} {a:?}: {e:#}"));
                assert!(passed, "{format:?} {l:?} {a:?}:\n{text}");
                // A verification appended to the proved text is what the writer writes.
                let extra = extra_decimals(&t, format, l, a);
                let whole =
                    render_sheet_at(&doc, format, extra).unwrap_or_else(|e| panic!("{e:#}"));
                assert_eq!(text, whole, "{format:?} {l:?} {a:?}");
                let mut bare = doc.clone();
                bare.verification = None;
                let first =
                    render_sheet_at(&bare, format, extra).unwrap_or_else(|e| panic!("{e:#}"));
                let appended =
                    verification_after(&doc, format, &first).unwrap_or_else(|e| panic!("{e:#}"));
                assert_eq!(
                    appended.is_some(),
                    matches!(format, Format::Text | Format::Yaml | Format::Json),
                    "{format:?}"
                );
                if let Some(appended) = appended {
                    assert_eq!(appended, text, "{format:?}");
                }
                let read = |text: &str| {
                    table_of(text, format, &free(&t)).unwrap_or_else(|e| panic!("{e:#}"))
                };
                assert_eq!(
                    read(&text),
                    read(&first),
                    "{format:?}: the verification is read"
                );
                let back = read_back(&text, format).unwrap_or_else(|e| panic!("{e:#}"));
                assert_eq!(back.joints.len(), 4);
                assert_eq!(back.joints[0].name, "j 1|a", "{format:?}");
                assert!(
                    back.joints[1].beta.is_some() && back.joints[3].beta.is_some(),
                    "{format:?}"
                );
                assert_eq!(
                    back.joints[3].mimic.as_ref().map(|m| m.joint.as_str()),
                    Some(back.joints[1].name.as_str()),
                    "{format:?}"
                );
            }
        }
    }

    #[test]
    fn a_wrong_source_fails_the_proof() {
        let t = table();
        let mut other = t.clone();
        other.rows[1].a += 1e-4;
        let fk = other.prepare();
        for format in [Format::Yaml, Format::Text] {
            let mut doc = SheetDoc::from_table(&t, LengthUnit::M, AngleUnit::Rad);
            let (text, passed) = prove(
                &mut doc,
                format,
                &free(&t),
                Source {
                    table: &t,
                    bound: Bound {
                        position: 0.0,
                        orientation: 0.0,
                    },
                    oracle: |q: &[f64]| fk.fk(q).unwrap_or_default(),
                    against: None,
                    samples: 50,
                    seed: 1,
                },
            )
            .unwrap_or_else(|e| panic!("{e:#}"));
            assert!(!passed, "{format:?}: {text}");
            assert!(doc.verification.as_ref().is_some_and(|v| !v.passed));
        }
    }

    #[test]
    fn the_extra_decimals_are_the_fewest_that_bound_the_table() {
        // Chains from a metre to a million kilometres (the prismatic row's travel): every
        // count of extra decimals from 0 to 9 is reached, and the search by halves agrees
        // with trying each count in turn.
        let mut seen = std::collections::BTreeSet::new();
        for e in 0..24 {
            let mut t = table();
            t.rows[2].limits = Some(Limits {
                lower: 0.0,
                upper: 10f64.powf(e as f64 / 2.0),
            });
            for (format, l, a) in [
                (Format::Text, LengthUnit::M, AngleUnit::Rad),
                (Format::Markdown, LengthUnit::Mm, AngleUnit::Deg),
            ] {
                let linear = (0..9)
                    .find(|&k| {
                        let b = dh_core::written_bound(&t, precision_at(format, l, a, k));
                        b.position <= TEXT_TARGET && b.orientation <= TEXT_TARGET
                    })
                    .unwrap_or(9);
                assert_eq!(extra_decimals(&t, format, l, a), linear, "10^{e}/2 m");
                seen.insert(linear);
            }
            assert_eq!(
                extra_decimals(&t, Format::Yaml, LengthUnit::M, AngleUnit::Rad),
                0
            );
        }
        assert!(seen.len() >= 5, "{seen:?}");
    }

    #[test]
    fn the_text_precision_is_its_last_decimal() {
        let p = precision_of(Format::Text, LengthUnit::Mm, AngleUnit::Deg);
        assert!((p.length - 0.5e-6).abs() < 1e-11, "{p:?}");
        assert!(
            (p.angle - 0.5e-4 * std::f64::consts::PI / 180.0).abs() < 1e-11,
            "{p:?}"
        );
        let p = precision_of(Format::Yaml, LengthUnit::M, AngleUnit::Rad);
        assert!(p.length < 1e-11 && p.angle < 1e-11, "{p:?}");
    }
}
