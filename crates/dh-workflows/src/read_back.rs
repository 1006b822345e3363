//! The readers of the formats [`crate::render`] writes: the text and Markdown tables and the
//! CSV (YAML and JSON go through the sheet reader), for the proof on the artefact (`urdf-dh
//! extract` proves the table it wrote as read back at the precision it was written). Values stay
//! in the units the text gives.

use crate::error::SheetError;
use crate::render::Format;
use crate::sheet::{parse_doc, ConventionDoc, JointDoc, JointType, MimicDoc, PoseDoc, SheetDoc};
use crate::units::{AngleUnit, LengthUnit};

type Result<T> = std::result::Result<T, SheetError>;

/// A [`SheetError::ReadBack`] of the message.
fn unreadable(message: String) -> SheetError {
    SheetError::ReadBack(message)
}

/// Returns a [`SheetError::ReadBack`] of the formatted message.
macro_rules! bail {
    ($($arg:tt)*) => {
        return Err(unreadable(format!($($arg)*)))
    };
}

/// Returns a [`SheetError::ReadBack`] of the formatted message unless `cond` holds.
macro_rules! ensure {
    ($cond:expr, $($arg:tt)*) => {
        if !$cond {
            bail!($($arg)*);
        }
    };
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
        Format::Poe => Err(SheetError::NotSheetFormat { format: "poe" }),
    }
}

fn number(token: &str, what: &str) -> Result<f64> {
    token
        .parse::<f64>()
        .map_err(|_| unreadable(format!("{what}: expected a number, found '{token}'")))
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
        .ok_or_else(|| unreadable(format!("no '{label}' in '{line}'")))?;
    let rest = &line[at + label.len()..];
    let end = rest
        .find(']')
        .ok_or_else(|| unreadable(format!("no ']' after '{label}'")))?;
    Ok(&rest[..end])
}

/// Three numbers after the last `label [unit]` in `line`.
fn three_after(line: &str, label: &str) -> Result<[f64; 3]> {
    let at = line
        .rfind(label)
        .ok_or_else(|| unreadable(format!("no '{label}' in '{line}'")))?;
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
        .ok_or_else(|| unreadable(format!("no 'rpy [' in '{line}'")))?;
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
                .ok_or_else(|| unreadable("a limit without a value".into()))?;
            Ok(Some(number(v, "limit")?))
        }
        None => bail!("a row ends early"),
    }
}

fn read_text(text: &str) -> Result<SheetDoc> {
    let mut lines = text.lines();
    let header = lines
        .next()
        .ok_or_else(|| unreadable("empty output".into()))?;
    let columns = lines
        .next()
        .ok_or_else(|| unreadable("no column header".into()))?;
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
    Ok(SheetDoc::new(
        convention_of_header(header)?,
        length,
        angle,
        base,
        tool,
        joints,
    ))
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
    let header = lines
        .next()
        .ok_or_else(|| unreadable("empty output".into()))?;
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
    let (length, angle) = units.ok_or_else(|| unreadable("no table header".into()))?;
    let header = header.trim_matches('*');
    apply_tilts(text, &mut joints)?;
    Ok(SheetDoc::new(
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
    let header = lines
        .next()
        .ok_or_else(|| unreadable("empty output".into()))?;
    let convention = convention_of_header(header)?;
    let units = lines
        .next()
        .ok_or_else(|| unreadable("no units line".into()))?;
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
            .ok_or_else(|| unreadable(format!("no '{key}' in '{units}'")))
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
    Ok(SheetDoc::new(convention, length, angle, base, tool, joints))
}
