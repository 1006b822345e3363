//! MATLAB `.mat` files (level 5, the format of MATLAB's `save` up to `-v7`), read as a table:
//! the numeric variables that share one number of rows become the columns of a CSV text that
//! the other readers take.
//!
//! # Columns
//! A variable of `N x 1` (or `1 x N`) values is the column named as the variable; one of `N x k`
//! gives the columns `name_1 .. name_k` (MATLAB's `name(:, 1) .. name(:, k)`). `N` is the
//! largest row count that more than one variable has (else the largest): variables of other
//! sizes (scalars, settings) are left out and named in the notes, as are variables that are not
//! real numeric arrays (text, cells, structures, complex or sparse arrays). Row `r` (1-based) of
//! the arrays is line `r + 1` of the text (line 1 is the header).
//!
//! # What is read
//! Numeric classes (double, single, 8- to 64-bit integers, logical), stored as any numeric
//! type, little- or big-endian, compressed (`-v7`, zlib) or not. HDF5-based `-v7.3` files are
//! refused with a hint to save with `-v7`. Compressed variables may expand to at most
//! [`MAX_EXPANDED_BYTES`] in all: a small file cannot take all memory.
//!
//! This reader is written here rather than taken from a crate: the one Rust crate for the
//! format prints to standard output on unsupported variables and panics on some inputs.

use std::io::Read;

use crate::csv::DataError;

/// Largest total size (bytes) of a file's variables after decompression: 64 MiB, eight million
/// doubles (nearly a million rows of nine columns).
pub const MAX_EXPANDED_BYTES: usize = 64 << 20;

/// Most values a variable may declare: as many doubles as [`MAX_EXPANDED_BYTES`] holds (a
/// variable of 1-byte integers could otherwise become eight times its size as doubles).
pub const MAX_VALUES: usize = MAX_EXPANDED_BYTES / 8;

/// The 116-character description a level-5 file starts with begins with this text.
const MAGIC: &[u8] = b"MATLAB 5.0 MAT-file";

/// Whether `bytes` look like a MATLAB level-5 `.mat` file (or a `-v7.3` one, which is refused
/// with a hint).
pub fn is_mat(bytes: &[u8]) -> bool {
    bytes.starts_with(MAGIC) || bytes.starts_with(b"MATLAB 7.3 MAT-file")
}

/// One real numeric variable, values row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct Variable {
    /// The variable's name.
    pub name: String,
    /// Rows.
    pub rows: usize,
    /// Columns.
    pub cols: usize,
    /// `rows x cols` values, row-major.
    pub values: Vec<f64>,
}

fn bad(expected: impl Into<String>, found: impl Into<String>) -> DataError {
    DataError::Content {
        expected: expected.into(),
        found: found.into(),
    }
}

/// Byte order of the file.
#[derive(Clone, Copy)]
struct Order {
    little: bool,
}

impl Order {
    fn u32(self, b: &[u8]) -> u32 {
        let a = [b[0], b[1], b[2], b[3]];
        if self.little {
            u32::from_le_bytes(a)
        } else {
            u32::from_be_bytes(a)
        }
    }

    /// The value of element `i` of a data type (`miINT8` .. `miUINT64`) as `f64`.
    fn value(self, kind: u32, b: &[u8], i: usize) -> Option<f64> {
        let size = type_size(kind)?;
        let s = b.get(i * size..(i + 1) * size)?;
        let mut a = [0u8; 8];
        if self.little {
            a[..size].copy_from_slice(s);
        } else {
            for (k, v) in s.iter().rev().enumerate() {
                a[k] = *v;
            }
        }
        Some(match kind {
            1 => f64::from(a[0] as i8),
            2 => f64::from(a[0]),
            3 => f64::from(i16::from_le_bytes([a[0], a[1]])),
            4 => f64::from(u16::from_le_bytes([a[0], a[1]])),
            5 => f64::from(i32::from_le_bytes([a[0], a[1], a[2], a[3]])),
            6 => f64::from(u32::from_le_bytes([a[0], a[1], a[2], a[3]])),
            7 => f64::from(f32::from_le_bytes([a[0], a[1], a[2], a[3]])),
            9 => f64::from_le_bytes(a),
            12 => i64::from_le_bytes(a) as f64,
            13 => u64::from_le_bytes(a) as f64,
            _ => return None,
        })
    }
}

/// Bytes per element of a numeric data type; `None` for the others.
fn type_size(kind: u32) -> Option<usize> {
    match kind {
        1 | 2 => Some(1),
        3 | 4 => Some(2),
        5..=7 => Some(4),
        9 | 12 | 13 => Some(8),
        _ => None,
    }
}

/// One data element: its type and its data (without padding); the rest after it.
fn element(order: Order, b: &[u8], top: bool) -> Result<(u32, &[u8], &[u8]), DataError> {
    if b.len() < 8 {
        return Err(bad(
            "a data element of 8 bytes or more",
            format!("{} bytes", b.len()),
        ));
    }
    let first = order.u32(&b[..4]);
    // The small format: type and size (at most 4) in the first word, the data in the second.
    if !top && first >> 16 != 0 {
        let (kind, size) = (first & 0xffff, (first >> 16) as usize);
        if size > 4 {
            return Err(bad(
                "a small data element of at most 4 bytes",
                format!("{size}"),
            ));
        }
        return Ok((kind, &b[4..4 + size], &b[8..]));
    }
    let size = order.u32(&b[4..8]) as usize;
    let data = size
        .checked_add(8)
        .and_then(|end| b.get(8..end))
        .ok_or_else(|| {
            bad(
                format!("{size} bytes of data after an element's tag"),
                format!("{} (the file is truncated)", b.len() - 8),
            )
        })?;
    // Compressed elements are not padded; every other one ends on an 8-byte boundary. The
    // data fit in the file, so these sums stay far below usize::MAX.
    let padded = if top && first == 15 {
        size
    } else {
        size.div_ceil(8).saturating_mul(8)
    };
    let rest = padded.checked_add(8).and_then(|start| b.get(start..));
    Ok((first, data, rest.unwrap_or(&[])))
}

/// Reads the numeric variables of a level-5 file (see the [module docs](self)); the notes name
/// what was left out.
///
/// # Errors
/// [`DataError::Content`] for a file that is not level 5 (a `-v7.3` file gets a hint), a
/// truncated or malformed element, or variables that expand beyond [`MAX_EXPANDED_BYTES`].
pub fn variables(bytes: &[u8]) -> Result<(Vec<Variable>, Vec<String>), DataError> {
    if bytes.starts_with(b"MATLAB 7.3 MAT-file") {
        return Err(bad(
            "a MATLAB level-5 file (save -v7 or -v6)",
            "a -v7.3 (HDF5) file; save it again with: save(FILE, '-v7')",
        ));
    }
    if !bytes.starts_with(MAGIC) || bytes.len() < 128 {
        return Err(bad("a MATLAB level-5 .mat file", "another kind of file"));
    }
    let order = match &bytes[126..128] {
        b"IM" => Order { little: true },
        b"MI" => Order { little: false },
        other => {
            return Err(bad(
                "the byte-order mark 'IM' or 'MI' at offset 126",
                format!("{other:?}"),
            ))
        }
    };
    let (mut out, mut notes, mut expanded, mut values) = (Vec::new(), Vec::new(), 0usize, 0usize);
    let mut rest = &bytes[128..];
    while rest.len() >= 8 {
        let (kind, data, next) = element(order, rest, true)?;
        rest = next;
        let inflated;
        let (kind, data) = if kind == 15 {
            let mut buf = Vec::new();
            let budget = (MAX_EXPANDED_BYTES - expanded) as u64;
            flate2::read::ZlibDecoder::new(data)
                .take(budget + 1)
                .read_to_end(&mut buf)
                .map_err(|e| bad("a zlib-compressed variable", format!("{e}")))?;
            expanded += buf.len();
            if expanded > MAX_EXPANDED_BYTES {
                return Err(bad(
                    format!("variables of at most {MAX_EXPANDED_BYTES} bytes in all"),
                    "more after decompression (export so large a set as CSV)",
                ));
            }
            inflated = buf;
            let (k, d, _) = element(order, &inflated, true)?;
            (k, d)
        } else {
            (kind, data)
        };
        if kind != 14 {
            continue; // not an array (miMATRIX)
        }
        match matrix(order, data)? {
            Ok(v) => {
                values += v.values.len();
                if values > MAX_VALUES {
                    return Err(bad(
                        format!("variables of at most {MAX_VALUES} values in all"),
                        "more (export so large a set as CSV)",
                    ));
                }
                out.push(v);
            }
            Err(note) => notes.push(note),
        }
    }
    Ok((out, notes))
}

/// A variable's name as MATLAB allows it: a letter, then letters, digits or `_` (at most 63
/// characters; `namelengthmax`). Names become CSV column names, so nothing else passes: a
/// comma or a quote would split or merge the header's columns, a control character would
/// reach the terminal.
///
/// # Errors
/// [`DataError::Content`] quoting the name, its unprintable characters as `\u{..}` and the
/// first character that is not allowed as U+XXXX.
fn variable_name(bytes: &[u8]) -> Result<String, DataError> {
    let name = String::from_utf8_lossy(bytes).into_owned();
    let allowed =
        |k: usize, c: char| c.is_ascii_alphabetic() || k > 0 && (c.is_ascii_digit() || c == '_');
    let wrong = name.chars().enumerate().find(|&(k, c)| !allowed(k, c));
    match wrong {
        None if !name.is_empty() && name.len() <= MAX_NAME => Ok(name),
        _ => {
            let shown: String = name
                .chars()
                .take(MAX_NAME)
                .flat_map(|c| {
                    if crate::csv::is_spoofing(c) {
                        format!("\\u{{{:x}}}", u32::from(c))
                            .chars()
                            .collect::<Vec<_>>()
                    } else {
                        vec![c]
                    }
                })
                .collect();
            let what = match wrong {
                Some((k, c)) => format!("U+{:04X} at character {}", u32::from(c), k + 1),
                None if name.is_empty() => "an empty name".into(),
                None => format!("{} characters", name.chars().count()),
            };
            Err(bad(
                format!(
                    "MATLAB variable names (a letter, then letters, digits or _, at most {MAX_NAME} characters)"
                ),
                format!("'{shown}' ({what})"),
            ))
        }
    }
}

/// Longest MATLAB variable name (`namelengthmax`).
const MAX_NAME: usize = 63;

/// One `miMATRIX` element: a real numeric 2-D variable, or a note saying why it is left out.
fn matrix(order: Order, b: &[u8]) -> Result<Result<Variable, String>, DataError> {
    let (_, flags, b) = element(order, b, false)?;
    if flags.len() < 8 {
        return Err(bad("array flags of 8 bytes", format!("{}", flags.len())));
    }
    let word = order.u32(&flags[..4]);
    let (class, complex) = (word & 0xff, word & 0x0800 != 0);
    let (_, dims, b) = element(order, b, false)?;
    let dims: Vec<usize> = dims
        .chunks_exact(4)
        .map(|c| order.u32(c) as usize)
        .collect();
    let (_, name, b) = element(order, b, false)?;
    let name = variable_name(name)?;
    let shape = dims
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join("x");
    if !(6..=15).contains(&class) {
        return Ok(Err(format!("'{name}' ({shape}) is not a numeric array")));
    }
    if complex {
        return Ok(Err(format!("'{name}' ({shape}) is complex")));
    }
    if dims.len() != 2 {
        return Ok(Err(format!("'{name}' ({shape}) is not 2-D")));
    }
    let (rows, cols) = (dims[0], dims[1]);
    let (kind, real, _) = element(order, b, false)?;
    let Some(size) = type_size(kind) else {
        return Err(bad(
            format!("numeric data in '{name}'"),
            format!("type {kind}"),
        ));
    };
    // Every declared size is checked before anything is allocated: a few bytes can declare
    // 2^31 x 2^30 values, whose byte count wraps around in unchecked arithmetic.
    let count = rows
        .checked_mul(cols)
        .filter(|&n| n <= MAX_VALUES)
        .ok_or_else(|| {
            bad(
                format!("a variable of at most {MAX_VALUES} values"),
                format!("'{name}' declared as {shape}"),
            )
        })?;
    if Some(real.len()) != count.checked_mul(size) {
        return Err(bad(
            format!("{count} values in '{name}' ({shape})"),
            format!("{} bytes of {size}", real.len()),
        ));
    }
    // Column-major in the file, row-major here.
    let mut values = vec![0.0; count];
    for c in 0..cols {
        for r in 0..rows {
            values[r * cols + c] = order.value(kind, real, c * rows + r).unwrap_or(f64::NAN);
        }
    }
    Ok(Ok(Variable {
        name,
        rows,
        cols,
        values,
    }))
}

/// The file as CSV text with a header (see the [module docs](self)) and the notes on what was
/// left out.
///
/// # Errors
/// As [`variables`]; no numeric variable.
pub fn to_csv(bytes: &[u8]) -> Result<(String, Vec<String>), DataError> {
    let (mut vars, mut notes) = variables(bytes)?;
    for v in &mut vars {
        if v.rows == 1 && v.cols > 1 {
            std::mem::swap(&mut v.rows, &mut v.cols); // a row vector is one column
        }
    }
    let count = |n: usize| vars.iter().filter(|v| v.rows == n).count();
    let rows = vars
        .iter()
        .map(|v| v.rows)
        .filter(|&n| n > 1)
        .max_by_key(|&n| (count(n) > 1, n))
        .ok_or_else(|| bad("a numeric variable with more than one row", "none"))?;
    let (used, left): (Vec<Variable>, Vec<Variable>) =
        vars.into_iter().partition(|v| v.rows == rows);
    for v in left {
        notes.push(format!(
            "'{}' ({}x{}) has not {rows} rows: left out",
            v.name, v.rows, v.cols
        ));
    }
    let mut header: Vec<String> = Vec::new();
    // Which variable each column comes from, to name both when two columns share a name.
    let mut origin: Vec<&str> = Vec::new();
    for v in &used {
        let names: Vec<String> = if v.cols == 1 {
            vec![v.name.clone()]
        } else {
            (1..=v.cols).map(|k| format!("{}_{k}", v.name)).collect()
        };
        for n in names {
            if let Some(k) = header.iter().position(|h| *h == n) {
                let found = if origin[k] == v.name {
                    format!("'{}' twice (a reader would take the first)", v.name)
                } else {
                    format!(
                        "a column '{n}' from both '{}' and '{}' (column k of a matrix M is M_k)",
                        origin[k], v.name
                    )
                };
                return Err(bad("variables whose columns have distinct names", found));
            }
            header.push(n);
            origin.push(&v.name);
        }
    }
    let mut text = header.join(",");
    text.push('\n');
    let mut cells = Vec::with_capacity(header.len());
    for r in 0..rows {
        cells.clear();
        for v in &used {
            cells.extend(v.values[r * v.cols..(r + 1) * v.cols].iter().map(|x| {
                // Shortest text that reads back to the same double; the readers refuse NaN.
                format!("{x:?}")
            }));
        }
        text.push_str(&cells.join(","));
        text.push('\n');
    }
    Ok((text, notes))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A level-5 file of the given top-level elements.
    fn file(little: bool, elements: &[Vec<u8>]) -> Vec<u8> {
        let mut b = b"MATLAB 5.0 MAT-file, test".to_vec();
        b.resize(124, b' ');
        b.extend([0x00, 0x01]);
        b.extend(if little { b"IM" } else { b"MI" });
        if !little {
            b[124..126].copy_from_slice(&[0x01, 0x00]);
        }
        for e in elements {
            b.extend(e);
        }
        b
    }

    fn word(little: bool, v: u32) -> [u8; 4] {
        if little {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        }
    }

    fn tagged(little: bool, kind: u32, data: &[u8]) -> Vec<u8> {
        let mut b = word(little, kind).to_vec();
        b.extend(word(little, data.len() as u32));
        b.extend(data);
        b.resize(b.len().div_ceil(8) * 8, 0);
        b
    }

    /// A double matrix (values column-major) named `name`.
    fn double(little: bool, name: &str, rows: u32, cols: u32, values: &[f64]) -> Vec<u8> {
        let mut flags = word(little, 6).to_vec();
        flags.extend([0; 4]);
        let mut dims = word(little, rows).to_vec();
        dims.extend(word(little, cols));
        let mut data = Vec::new();
        for v in values {
            data.extend(if little {
                v.to_le_bytes()
            } else {
                v.to_be_bytes()
            });
        }
        let mut m = tagged(little, 6, &flags);
        m.extend(tagged(little, 5, &dims));
        m.extend(tagged(little, 1, name.as_bytes()));
        m.extend(tagged(little, 9, &data));
        tagged(little, 14, &m)
    }

    #[test]
    fn columns_from_both_byte_orders() {
        for little in [true, false] {
            let q = double(little, "q", 3, 2, &[1.0, 2.0, 3.0, 10.0, 20.0, 30.0]);
            let t = double(little, "t", 1, 3, &[0.5, 0.25, 0.125]);
            let rate = double(little, "rate", 1, 1, &[100.0]);
            let (text, notes) = to_csv(&file(little, &[q, t, rate])).unwrap();
            assert_eq!(
                text,
                "q_1,q_2,t\n1.0,10.0,0.5\n2.0,20.0,0.25\n3.0,30.0,0.125\n"
            );
            assert_eq!(notes, ["'rate' (1x1) has not 3 rows: left out"]);
        }
    }

    #[test]
    fn compressed_variables_are_read_and_bounded() {
        use std::io::Write;
        let q = double(true, "q", 2, 1, &[1.5, -2.5]);
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(&q).unwrap();
        let packed = z.finish().unwrap();
        let mut element = 15u32.to_le_bytes().to_vec();
        element.extend((packed.len() as u32).to_le_bytes());
        element.extend(&packed);
        let (text, _) = to_csv(&file(true, &[element])).unwrap();
        assert_eq!(text, "q\n1.5\n-2.5\n");

        // 100 MB of zeros in a variable: refused after 64 MiB, whatever the file's size.
        let big = tagged(true, 14, &vec![0u8; 100 << 20]);
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
        z.write_all(&big).unwrap();
        let packed = z.finish().unwrap();
        assert!(packed.len() < 1 << 20);
        let mut element = 15u32.to_le_bytes().to_vec();
        element.extend((packed.len() as u32).to_le_bytes());
        element.extend(&packed);
        let e = to_csv(&file(true, &[element])).unwrap_err().to_string();
        assert!(e.contains("more after decompression"), "{e}");
    }

    #[test]
    fn bad_files_are_named_not_panicked_on() {
        let q = double(true, "q", 3, 2, &[1.0; 6]);
        let whole = file(true, &[q]);
        // Every truncation is an error or a smaller table, never a panic.
        for n in 0..whole.len() {
            let _ = to_csv(&whole[..n]);
        }
        let e = to_csv(b"MATLAB 7.3 MAT-file, Platform: GLNXA64").unwrap_err();
        assert!(e.to_string().contains("save(FILE, '-v7')"), "{e}");
        let e = to_csv(&file(true, &[])).unwrap_err();
        assert!(e.to_string().contains("a numeric variable"), "{e}");
        let e = to_csv(b"x,y\n1,2\n").unwrap_err();
        assert!(e.to_string().contains("another kind of file"), "{e}");
    }

    #[test]
    fn declared_sizes_are_checked_before_anything_is_allocated() {
        // 2^31 x 2^30 doubles declared in a few bytes: the byte count wraps to 0 unchecked.
        let m = double(true, "q", 1 << 31, 1 << 30, &[]);
        let e = to_csv(&file(true, &[m])).unwrap_err().to_string();
        assert!(
            e.contains("a variable of at most")
                && e.contains("'q' declared as 2147483648x1073741824"),
            "{e}"
        );
        // A tag declaring 4 GiB of data in a short file: truncated, not read past the end.
        let mut tag = 14u32.to_le_bytes().to_vec();
        tag.extend(u32::MAX.to_le_bytes());
        let e = to_csv(&file(true, &[tag])).unwrap_err().to_string();
        assert!(e.contains("the file is truncated"), "{e}");
    }

    #[test]
    fn names_that_are_not_matlab_names_or_repeat_are_refused() {
        let e = to_csv(&file(true, &[double(true, "A,x", 2, 1, &[1.0, 2.0])]))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("MATLAB variable names") && e.contains("'A,x' (U+002C at character 2)"),
            "{e}"
        );
        let e = to_csv(&file(true, &[double(true, "q\u{1b}", 2, 1, &[1.0, 2.0])]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("'q\\u{1b}' (U+001B at character 2)"), "{e}");
        let twice = [
            double(true, "q", 2, 1, &[1.0, 2.0]),
            double(true, "q", 2, 1, &[3.0, 4.0]),
        ];
        let e = to_csv(&file(true, &twice)).unwrap_err().to_string();
        assert!(e.contains("'q' twice"), "{e}");
        let clash = [
            double(true, "q", 2, 2, &[1.0, 2.0, 3.0, 4.0]),
            double(true, "q_1", 2, 1, &[3.0, 4.0]),
        ];
        let e = to_csv(&file(true, &clash)).unwrap_err().to_string();
        assert!(e.contains("a column 'q_1' from both 'q' and 'q_1'"), "{e}");
    }
}
