//! Reading a written sheet back, in every output format, and proving what was written.
//!
//! The self-check of `extract` and `convert` is on the artefact: the text the command writes
//! (YAML, JSON, CSV, the aligned text table, Markdown) is read back here at the precision it
//! was written, and that table, not the one in memory, is compared with the source by forward
//! kinematics ([`dh_core::compare_written`]), within the source's bound plus what the written
//! precision allows ([`dh_core::written_bound`]).

use anyhow::{anyhow, bail, ensure, Context, Result};
use dh_core::{Bound, DhTable, Precision};
use nalgebra::Isometry3;

use crate::render::{render_sheet_at, Format};
use crate::sheet::VerificationDoc;
use crate::sheet::{parse_doc, ConventionDoc, JointDoc, JointType, MimicDoc, PoseDoc, SheetDoc};
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
        Format::Yaml | Format::Json | Format::Csv => Precision::rounded(l, a),
        Format::Text | Format::Markdown => {
            let step = |decimals: usize| 0.5 * 10f64.powi(-((decimals + extra) as i32));
            Precision::rounded(
                l + step(crate::render::decimals(length.symbol())) * length.metres(),
                a + step(crate::render::decimals(angle.symbol())) * angle.radians(),
            )
        }
    }
}

/// Reads text that [`crate::render::render_sheet`] wrote in `format` back into a sheet document (units,
/// convention, base, tool, rows and couplings; the facts around them are not read back).
///
/// # Errors
/// Text that is not what the writer writes (a bug, reported as such by the caller).
pub fn read_back(text: &str, format: Format) -> Result<SheetDoc> {
    match format {
        Format::Yaml | Format::Json => parse_doc(text, "written output"),
        Format::Csv => read_csv(text),
        Format::Text => read_text(text),
        Format::Markdown => read_markdown(text),
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
/// renders again with the verification attached; returns the final text and whether it passed.
/// A base or tool the document leaves out (free) is taken from `free` when comparing.
///
/// # Errors
/// A written text that does not read back as the same table twice (a writer bug), or rows that
/// differ from the source's in number.
pub fn prove<F>(
    doc: &mut SheetDoc,
    format: Format,
    free: &Isometry3Pair,
    source: Source<'_, F>,
) -> Result<(String, bool)>
where
    F: FnMut(&[f64]) -> Isometry3<f64>,
{
    let size = source.table.size();
    if size > MAX_PROVABLE_SIZE {
        bail!(
            "the chain spans {size:.3e} m (lengths, offsets and prismatic travel): beyond {MAX_PROVABLE_SIZE:e} m \
             no table can be proved to {} m in double precision",
            Bound::MAX_POSITION
        );
    }
    doc.verification = None;
    let extra = extra_decimals(source.table, format, doc.length_unit, doc.angle_unit);
    let first = render_sheet_at(doc, format, extra)?;
    let written = table_of(&first, format, free)?;
    let mut problems = Vec::new();
    for (w, s) in written.rows.iter().zip(&source.table.rows) {
        if w.kind != s.kind {
            problems.push(format!(
                "joint '{}' is written as {:?}, not {:?}",
                w.name, w.kind, s.kind
            ));
        }
    }
    let dev = dh_core::compare_written(
        &written,
        source.table,
        source.oracle,
        source.samples,
        source.seed,
    )
    .map_err(|e| anyhow!("the written table does not read back with the source's rows: {e}"))?;
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
    let last = render_sheet_at(doc, format, extra)?;
    // What was proved must be what is written: the verification is attached after the table.
    ensure!(
        table_of(&last, format, free)? == written,
        "internal error: the {format:?} output reads back differently once verified"
    );
    Ok((last, passed))
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
    (0..9)
        .find(|&k| {
            let b = dh_core::written_bound(table, precision_at(format, l, a, k));
            b.position <= TEXT_TARGET && b.orientation <= TEXT_TARGET
        })
        .unwrap_or(9)
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

fn number(token: &str, what: &str) -> Result<f64> {
    token
        .parse::<f64>()
        .map_err(|_| anyhow!("{what}: expected a number, found '{token}'"))
}

fn length_unit(symbol: &str) -> Result<LengthUnit> {
    match symbol {
        "m" => Ok(LengthUnit::M),
        "mm" => Ok(LengthUnit::Mm),
        _ => bail!("expected a length unit, found '{symbol}'"),
    }
}

fn angle_unit(symbol: &str) -> Result<AngleUnit> {
    match symbol {
        "rad" => Ok(AngleUnit::Rad),
        "deg" => Ok(AngleUnit::Deg),
        _ => bail!("expected an angle unit, found '{symbol}'"),
    }
}

fn convention_of_header(line: &str) -> Result<ConventionDoc> {
    if line.contains(", standard DH: A_i") {
        Ok(ConventionDoc::Standard)
    } else if line.contains(", modified DH (Craig): A_i") {
        Ok(ConventionDoc::Modified)
    } else {
        bail!("no convention in the header line '{line}'")
    }
}

/// The unit between `[` and `]` after `label` in `line`.
fn bracket_after<'a>(line: &'a str, label: &str) -> Result<&'a str> {
    let at = line
        .find(label)
        .ok_or_else(|| anyhow!("no '{label}' in '{line}'"))?;
    let rest = &line[at + label.len()..];
    let end = rest
        .find(']')
        .ok_or_else(|| anyhow!("no ']' after '{label}'"))?;
    Ok(&rest[..end])
}

/// Three numbers after the last `label [unit]` in `line`.
fn three_after(line: &str, label: &str) -> Result<[f64; 3]> {
    let at = line
        .rfind(label)
        .ok_or_else(|| anyhow!("no '{label}' in '{line}'"))?;
    let rest = &line[at + label.len()..];
    let rest = &rest[rest.find(']').map_or(0, |k| k + 1)..];
    let v: Vec<f64> = rest
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|t| !t.is_empty())
        .take(3)
        .map(|t| number(t, label))
        .collect::<Result<_>>()?;
    ensure!(
        v.len() == 3,
        "expected 3 numbers after '{label}' in '{line}'"
    );
    Ok([v[0], v[1], v[2]])
}

fn pose_of_line(line: &str) -> Result<Option<PoseDoc>> {
    if line.trim_end().ends_with("not given") {
        return Ok(None);
    }
    // The rpy comes last; the xyz is the last one before it (a link name may hold either word).
    let rpy_at = line
        .rfind("rpy [")
        .ok_or_else(|| anyhow!("no 'rpy [' in '{line}'"))?;
    Ok(Some(PoseDoc {
        xyz: three_after(&line[..rpy_at], "xyz [")?,
        rpy: three_after(&line[rpy_at..], "rpy [")?,
    }))
}

fn kind_of(token: &str) -> Result<JointType> {
    match token {
        "revolute" => Ok(JointType::Revolute),
        "prismatic" => Ok(JointType::Prismatic),
        _ => bail!("expected a joint type, found '{token}'"),
    }
}

/// A coupling cell `= m * joint + offset` (or `- offset`).
fn coupling_of(tokens: &[&str]) -> Result<MimicDoc> {
    ensure!(
        tokens.len() >= 6 && tokens[0] == "=" && tokens[2] == "*",
        "expected '= multiplier * joint +|- offset', found '{}'",
        tokens.join(" ")
    );
    let n = tokens.len();
    let sign = match tokens[n - 2] {
        "+" => 1.0,
        "-" => -1.0,
        s => bail!("expected '+' or '-' in a coupling, found '{s}'"),
    };
    Ok(MimicDoc {
        joint: tokens[3..n - 2].join(" "),
        multiplier: number(tokens[1], "coupling multiplier")?,
        offset: sign * number(tokens[n - 1], "coupling offset")?,
    })
}

/// A limit cell read from the right end of `tokens`: `-` or `value unit`.
fn pop_limit(tokens: &mut Vec<&str>) -> Result<Option<f64>> {
    match tokens.pop() {
        Some("-") => Ok(None),
        Some(_unit) => {
            let v = tokens
                .pop()
                .ok_or_else(|| anyhow!("a limit without a value"))?;
            Ok(Some(number(v, "limit")?))
        }
        None => bail!("a row ends early"),
    }
}

fn read_text(text: &str) -> Result<SheetDoc> {
    let mut lines = text.lines();
    let header = lines.next().ok_or_else(|| anyhow!("empty output"))?;
    let columns = lines.next().ok_or_else(|| anyhow!("no column header"))?;
    let (angle, length) = (
        angle_unit(bracket_after(columns, "theta [")?)?,
        length_unit(bracket_after(columns, "d [")?)?,
    );
    let mut joints = Vec::new();
    let (mut base, mut tool) = (None, None);
    for line in lines {
        if line.starts_with("base ") {
            base = pose_of_line(line)?;
            continue;
        }
        if line.starts_with("tool ") {
            tool = pose_of_line(line)?;
            break;
        }
        if line.starts_with(crate::render::TILTS_LINE) || line.starts_with("effect ") {
            continue;
        }
        let mut tokens: Vec<&str> = line.split_whitespace().collect();
        let mimic = match tokens.iter().rposition(|t| *t == "=") {
            Some(k) => {
                let m = coupling_of(&tokens[k..])?;
                tokens.truncate(k);
                Some(m)
            }
            None => None,
        };
        let upper = pop_limit(&mut tokens)?;
        let lower = pop_limit(&mut tokens)?;
        ensure!(tokens.len() >= 7, "a row too short: '{line}'");
        let n = tokens.len();
        let v = |i: usize, what: &str| number(tokens[i], what);
        joints.push(JointDoc {
            name: tokens[1..n - 5].join(" "),
            kind: kind_of(tokens[n - 5])?,
            theta: v(n - 4, "theta")?,
            d: v(n - 3, "d")?,
            a: v(n - 2, "a")?,
            alpha: v(n - 1, "alpha")?,
            lower,
            upper,
            mimic,
            beta: None,
        });
    }
    apply_tilts(text, &mut joints)?;
    Ok(doc_of(
        convention_of_header(header)?,
        length,
        angle,
        base,
        tool,
        joints,
    ))
}

fn doc_of(
    convention: ConventionDoc,
    length_unit: LengthUnit,
    angle_unit: AngleUnit,
    base: Option<PoseDoc>,
    tool: Option<PoseDoc>,
    joints: Vec<JointDoc>,
) -> SheetDoc {
    SheetDoc {
        robot: None,
        source: None,
        base_link: None,
        tip_link: None,
        convention,
        length_unit,
        angle_unit,
        base,
        tool,
        joints,
        coupled: None,
        branches: None,
        inertials: None,
        pairs: None,
        tolerances: None,
        warnings: None,
        verification: None,
        cpa: None,
        calibration: None,
        truth: None,
        effects: None,
    }
}

/// Reads the tilts line ([`crate::render::TILTS_LINE`], after an optional `# `) of `text` into
/// the rows it names: entries `NAME VALUE UNIT` separated by `, `, in row order.
fn apply_tilts(text: &str, joints: &mut [JointDoc]) -> Result<()> {
    let Some(line) = text.lines().find_map(|l| {
        l.trim_start_matches("# ")
            .strip_prefix(crate::render::TILTS_LINE)
    }) else {
        return Ok(());
    };
    let mut rest = line.trim_end();
    for j in joints.iter_mut() {
        let Some(after) = rest
            .strip_prefix(j.name.as_str())
            .and_then(|r| r.strip_prefix(' '))
        else {
            continue;
        };
        let mut parts = after.splitn(3, ' ');
        let (Some(value), Some(unit)) = (parts.next(), parts.next()) else {
            continue;
        };
        let unit = unit.trim_end_matches(',');
        if angle_unit(unit).is_err() {
            continue;
        }
        j.beta = Some(number(value, "beta")?);
        rest = parts.next().unwrap_or("").trim_start_matches(", ");
    }
    ensure!(rest.is_empty(), "a tilt names no row in order: '{rest}'");
    Ok(())
}

/// Cells of a Markdown table row, `\|` unescaped.
fn markdown_cells(line: &str) -> Vec<String> {
    let inner = line.trim().trim_start_matches('|');
    let inner = inner.strip_suffix('|').unwrap_or(inner);
    let mut cells = vec![String::new()];
    let mut chars = inner.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\\' if chars.peek() == Some(&'|') => {
                if let Some(s) = cells.last_mut() {
                    s.push('|');
                }
                chars.next();
            }
            '|' => cells.push(String::new()),
            c => {
                if let Some(s) = cells.last_mut() {
                    s.push(c);
                }
            }
        }
    }
    cells.into_iter().map(|c| c.trim().to_string()).collect()
}

fn limit_cell(cell: &str) -> Result<Option<f64>> {
    if cell == "-" {
        return Ok(None);
    }
    let v = cell.split_whitespace().next().unwrap_or("");
    Ok(Some(number(v, "limit")?))
}

fn read_markdown(text: &str) -> Result<SheetDoc> {
    let mut lines = text.lines();
    let header = lines.next().ok_or_else(|| anyhow!("empty output"))?;
    let mut units = None;
    let mut joints = Vec::new();
    let (mut base, mut tool) = (None, None);
    for line in lines {
        if line.starts_with("| # |") {
            units = Some((
                length_unit(bracket_after(line, "d [")?)?,
                angle_unit(bracket_after(line, "theta [")?)?,
            ));
        } else if line.starts_with("|---") || line.trim().is_empty() {
        } else if line.starts_with('|') {
            let c = markdown_cells(line);
            ensure!(
                c.len() == 10,
                "expected 10 cells in a row, found {}: '{line}'",
                c.len()
            );
            let tokens: Vec<&str> = c[9].split_whitespace().collect();
            joints.push(JointDoc {
                name: c[1].clone(),
                kind: kind_of(&c[2])?,
                theta: number(&c[3], "theta")?,
                d: number(&c[4], "d")?,
                a: number(&c[5], "a")?,
                alpha: number(&c[6], "alpha")?,
                lower: limit_cell(&c[7])?,
                upper: limit_cell(&c[8])?,
                mimic: if tokens.is_empty() {
                    None
                } else {
                    Some(coupling_of(&tokens)?)
                },
                beta: None,
            });
        } else if line.starts_with("base: ") {
            base = pose_of_line(line)?;
        } else if line.starts_with("tool: ") {
            tool = pose_of_line(line)?;
        }
    }
    let (length, angle) = units.ok_or_else(|| anyhow!("no table header"))?;
    let header = header.trim_matches('*');
    apply_tilts(text, &mut joints)?;
    Ok(doc_of(
        convention_of_header(header)?,
        length,
        angle,
        base,
        tool,
        joints,
    ))
}

/// Fields of one CSV record (RFC 4180 quoting).
fn csv_fields(line: &str) -> Vec<String> {
    let mut fields = vec![String::new()];
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                if let Some(s) = fields.last_mut() {
                    s.push('"');
                }
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => fields.push(String::new()),
            (c, _) => {
                if let Some(s) = fields.last_mut() {
                    s.push(c);
                }
            }
        }
    }
    fields
}

/// `xyz X Y Z rpy R P Y` of a CSV comment line.
fn csv_pose(rest: &str) -> Result<PoseDoc> {
    let t: Vec<&str> = rest.split_whitespace().collect();
    ensure!(
        t.len() == 8 && t[0] == "xyz" && t[4] == "rpy",
        "expected 'xyz X Y Z rpy R P Y', found '{rest}'"
    );
    let v = |i: usize| number(t[i], "pose");
    Ok(PoseDoc {
        xyz: [v(1)?, v(2)?, v(3)?],
        rpy: [v(5)?, v(6)?, v(7)?],
    })
}

fn read_csv(text: &str) -> Result<SheetDoc> {
    let mut lines = text.lines();
    let header = lines.next().ok_or_else(|| anyhow!("empty output"))?;
    let convention = convention_of_header(header)?;
    let units = lines.next().ok_or_else(|| anyhow!("no units line"))?;
    let words: Vec<&str> = units
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|w| !w.is_empty())
        .collect();
    let after = |key: &str| {
        words
            .iter()
            .position(|w| *w == key)
            .and_then(|k| words.get(k + 1))
            .copied()
            .ok_or_else(|| anyhow!("no '{key}' in '{units}'"))
    };
    let (length, angle) = (
        length_unit(after("length_unit")?)?,
        angle_unit(after("angle_unit")?)?,
    );
    let (mut base, mut tool) = (None, None);
    let mut joints = Vec::new();
    for line in lines {
        if let Some(rest) = line.strip_prefix("# base ") {
            base = Some(csv_pose(rest)?);
        } else if let Some(rest) = line.strip_prefix("# tool ") {
            tool = Some(csv_pose(rest)?);
        } else if line.starts_with("joint,type,") || line.starts_with('#') {
        } else {
            let f = csv_fields(line);
            ensure!(
                f.len() == 11,
                "expected 11 fields, found {}: '{line}'",
                f.len()
            );
            let opt = |s: &str, what: &str| -> Result<Option<f64>> {
                if s.is_empty() {
                    Ok(None)
                } else {
                    number(s, what).map(Some)
                }
            };
            joints.push(JointDoc {
                name: f[0].clone(),
                kind: kind_of(&f[1])?,
                a: number(&f[2], "a")?,
                alpha: number(&f[3], "alpha")?,
                d: number(&f[4], "d")?,
                theta: number(&f[5], "theta")?,
                lower: opt(&f[6], "lower")?,
                upper: opt(&f[7], "upper")?,
                mimic: if f[8].is_empty() {
                    None
                } else {
                    Some(MimicDoc {
                        joint: f[8].clone(),
                        multiplier: number(&f[9], "mimic multiplier")?,
                        offset: number(&f[10], "mimic offset")?,
                    })
                },
                beta: None,
            });
        }
    }
    apply_tilts(text, &mut joints)?;
    Ok(doc_of(convention, length, angle, base, tool, joints))
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
