//! Reading the data rows of a large file in parallel chunks of lines ([`read_chunked`]): the
//! same samples, target and session numbers and notes as reading them in order.

use super::*;

/// Files shorter than this (bytes) are read row by row on one thread.
pub(super) const CHUNKED_MIN_BYTES: usize = 8 << 20;

/// About how many bytes of lines one chunk holds (it ends at a line break).
pub(super) const CHUNK_BYTES: usize = 1 << 20;

/// Chunks read at a time per thread: the samples of a wave are held apart before they join
/// the set, so a wave is kept small against the set itself.
const CHUNKS_PER_THREAD: usize = 4;

/// What a chunk's rows gave: their samples (lines counted from the chunk's first line as 1,
/// targets and sessions numbered in the chunk's own `seen`).
struct Chunk {
    samples: Vec<Sample>,
    seen: RowState,
}

/// The number of line breaks in `text`, counted 255 bytes at a time in bytes (which the
/// compiler counts a vector at a time).
fn line_breaks(text: &str) -> usize {
    text.as_bytes()
        .chunks(255)
        .map(|c| usize::from(c.iter().map(|&b| u8::from(b == b'\n')).sum::<u8>()))
        .sum()
}

/// Reads the data rows of `text` (a whole file whose header `reader` holds) into `m` in
/// chunks of about `chunk_bytes`, on up to `available_parallelism` threads; `seen` gets the
/// targets, sessions and zero-sigma lines. `None` when the file has a double quote (a quoted
/// cell may run over a line break) or a row is faulty: then `m` and `seen` are to be thrown
/// away and the file read row by row, whose error names the first faulty line as ever (a
/// unit's error reads the largest values of all rows before it).
pub(super) fn read_chunked(
    text: &str,
    reader: &RowReader<'_>,
    m: &mut Measurements,
    seen: &mut RowState,
    chunk_bytes: usize,
) -> Option<()> {
    // As `Records::new`: one byte-order mark dropped, lines split at '\n'.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    if text.contains('"') {
        return None;
    }
    // The rows start on the line after the header's (`header.line` is 1-based).
    let start = match reader.header.line {
        0 => return None,
        line => text.match_indices('\n').nth(line - 1)?.0 + 1,
    };
    let chunks = split_lines(&text[start..], chunk_bytes.max(1));
    // Each chunk's line breaks, counted on every core: the rows' bound for the set's list.
    let breaks = crate::fit::parallel_map(chunks.len(), |k| Ok(line_breaks(chunks[k]))).ok()?;
    m.samples.reserve_exact(breaks.iter().sum::<usize>() + 1);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let wave = (threads * CHUNKS_PER_THREAD).max(1);
    let columns = seen.largest.len();
    // 1-based line number of the chunk's first line, less one.
    let mut offset = reader.header.line;
    for (group, lines) in chunks.chunks(wave).zip(breaks.chunks(wave)) {
        let read =
            crate::fit::parallel_map(group.len(), |k| Ok(read_chunk(group[k], reader, columns)))
                .ok()?;
        for (chunk, lines) in read.into_iter().zip(lines) {
            let chunk = chunk?;
            join(chunk.samples, &chunk.seen, offset, m, seen);
            offset += lines;
        }
    }
    m.samples.shrink_to_fit();
    m.targets = std::mem::take(&mut seen.targets);
    m.sessions = std::mem::take(&mut seen.sessions);
    Some(())
}

/// `text` cut into pieces of about `size` bytes, each ending with a line break (the last with
/// the text).
fn split_lines(text: &str, size: usize) -> Vec<&str> {
    let mut out = Vec::new();
    let mut rest = text;
    while !rest.is_empty() {
        let end = match rest.get(size..).and_then(|tail| tail.find('\n')) {
            Some(k) => size + k + 1,
            None => rest.len(),
        };
        let (piece, tail) = rest.split_at(end);
        out.push(piece);
        rest = tail;
    }
    out
}

/// The rows of one chunk (a text without a double quote); `None` for a faulty row. Each line
/// is read as [`Records`] reads it (a line feed, then a carriage return, dropped; blank lines
/// and comments skipped; the cells between commas trimmed), its cells borrowed from `text`.
fn read_chunk(text: &str, reader: &RowReader<'_>, columns: usize) -> Option<Chunk> {
    let mut seen = RowState::new(columns);
    let mut samples = Vec::new();
    let mut cells: Vec<&str> = Vec::new();
    for (index, raw) in text.split('\n').enumerate() {
        let raw = raw.strip_suffix('\r').unwrap_or(raw);
        let trimmed = super::records::trim(raw);
        if trimmed.is_empty() || trimmed.starts_with('#') {
            continue;
        }
        cells.clear();
        // The cells between commas (as `raw.split(',')` gives them; the cells of a row are
        // short, where a byte loop beats a search for each comma).
        let mut start = 0;
        for (k, &b) in raw.as_bytes().iter().enumerate() {
            if b == b',' {
                cells.push(super::records::trim(&raw[start..k]));
                start = k + 1;
            }
        }
        cells.push(super::records::trim(&raw[start..]));
        samples.push(reader.sample(index + 1, &cells, &mut seen).ok()?);
    }
    Some(Chunk { samples, seen })
}

/// Appends a chunk's samples to `m`, their lines moved by `offset` and their targets and
/// sessions renumbered in `seen` (new names after those already there, in the chunk's order).
fn join(
    samples: Vec<Sample>,
    chunk: &RowState,
    offset: usize,
    m: &mut Measurements,
    seen: &mut RowState,
) {
    let number = |names: &[String], global: &mut Vec<String>| -> Vec<usize> {
        names
            .iter()
            .map(|n| match global.iter().position(|g| g == n) {
                Some(i) => i,
                None => {
                    global.push(n.clone());
                    global.len() - 1
                }
            })
            .collect()
    };
    let targets = number(&chunk.targets, &mut seen.targets);
    let sessions = number(&chunk.sessions, &mut seen.sessions);
    seen.zero_sigmas
        .extend(chunk.zero_sigmas.iter().map(|l| l + offset));
    seen.zero_sigmas_rot
        .extend(chunk.zero_sigmas_rot.iter().map(|l| l + offset));
    m.samples.extend(samples.into_iter().map(|mut s| {
        s.line += offset;
        s.target = targets.get(s.target).copied().unwrap_or(s.target);
        if !chunk.sessions.is_empty() {
            s.session = sessions.get(s.session).copied().unwrap_or(s.session);
        }
        s
    }));
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file of `rows` rows over three targets (the third first seen late), two sessions, a
    /// zero sigma now and then, CRLF line ends, spaces around cells, comments (some indented)
    /// and blank lines (some of spaces and a tab) between the rows.
    fn file(rows: usize) -> String {
        let mut text = String::from("\u{feff}# a comment\n\nj1, j2,x,y,z,target,session,sigma\n");
        for i in 0..rows {
            let target = match i {
                i if i > rows * 2 / 3 && i % 5 == 0 => "late",
                i if i % 2 == 0 => "a",
                _ => "b",
            };
            let sigma = if i % 97 == 0 { "0" } else { "1e-5" };
            let session = if i < rows / 2 { "s2" } else { "s1" };
            text.push_str(&format!(
                "{},{}, {},0.5,{},{target},{session},{sigma}\r\n",
                (i as f64 * 0.01).sin(),
                -(i as f64) * 1e-4,
                1.0 + i as f64 * 1e-3,
                (i % 7) as f64
            ));
            if i % 50 == 0 {
                text.push_str("# between rows\n\n");
            }
            if i % 70 == 0 {
                text.push_str("   # an indented comment\r\n \t \n");
            }
        }
        text
    }

    fn chunked(text: &str, chunk_bytes: usize) -> Option<(Measurements, Vec<usize>)> {
        let joints = vec!["j1".to_string(), "j2".to_string()];
        let opts = CsvOptions::default();
        let header = Records::new(text, ',', true).next()?.ok()?;
        let cols = header_columns(&header, &joints).ok()?;
        let reader = RowReader {
            header: &header,
            cols: &cols,
            revolute: vec![true, true],
            opts: &opts,
        };
        let mut m = Measurements {
            joint_names: joints.clone(),
            ..Measurements::default()
        };
        let mut seen = RowState::new(header.fields.len());
        read_chunked(text, &reader, &mut m, &mut seen, chunk_bytes)?;
        Some((m, seen.zero_sigmas))
    }

    #[test]
    fn chunks_read_what_the_rows_read_in_order() {
        let text = file(3000);
        let joints = vec!["j1".to_string(), "j2".to_string()];
        let (serial, notes) =
            parse_measurements_noting(&text, &joints, &CsvOptions::default()).expect("serial");
        assert_eq!(serial.targets, ["a", "b", "late"]);
        assert_eq!(serial.sessions, ["s2", "s1"]);
        for size in [1, 100, 4096, 1 << 20] {
            let (m, zeros) = chunked(&text, size).expect("chunked");
            assert_eq!(m, serial, "chunks of {size} bytes");
            assert_eq!(zeros.len(), 31);
            assert!(notes[0].contains(&format!("first at line {}", zeros[0])));
        }
    }

    /// Counted 255 bytes at a time, the line breaks are those counted one by one: runs of
    /// line breaks longer than a count's 255, and texts of every length around it.
    #[test]
    fn line_breaks_are_those_counted_one_by_one() {
        let mut texts = vec![
            String::new(),
            "\n".repeat(100_000),
            "a\r\nb,\n".repeat(1000),
        ];
        texts.extend((250..=520).map(|n| "\n".repeat(n)));
        texts.extend((250..=260).map(|n| "x".repeat(n) + "\n"));
        for text in &texts {
            let want = text.bytes().filter(|&b| b == b'\n').count();
            assert_eq!(line_breaks(text), want, "{} bytes", text.len());
        }
    }

    #[test]
    fn a_faulty_row_or_a_quote_leaves_the_rows_to_the_reader_in_order() {
        let text = file(500).replacen(",s1,", ",s1,x", 1);
        assert!(chunked(&text, 256).is_none());
        let text = file(500).replacen("late", "\"late\"", 1);
        assert!(chunked(&text, 256).is_none());
    }
}
