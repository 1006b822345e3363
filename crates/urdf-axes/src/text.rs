//! Text-level helpers of the scan: line numbers, characters XML forbids, entity and character
//! references.

use std::borrow::Cow;

/// Byte offsets of line starts, for offset -> line lookups.
pub(crate) struct Lines {
    starts: Vec<usize>,
}

impl Lines {
    /// Indexes the line starts of `bytes`.
    pub fn new(bytes: &[u8]) -> Self {
        let mut starts = vec![0];
        starts.extend(
            bytes
                .iter()
                .enumerate()
                .filter(|(_, &b)| b == b'\n')
                .map(|(i, _)| i + 1),
        );
        Self { starts }
    }

    /// 1-based line of byte `offset`.
    pub fn line_of(&self, offset: usize) -> usize {
        self.starts.partition_point(|&s| s <= offset).max(1)
    }
}

/// Lines of offsets met in increasing order, counted as the scan goes (no index of the whole
/// text is built).
pub(crate) struct LineCounter<'t> {
    pub bytes: &'t [u8],
    pub offset: usize,
    pub line: usize,
}

impl LineCounter<'_> {
    /// 1-based line of byte `offset`.
    pub fn line_of(&mut self, offset: usize) -> usize {
        if offset < self.offset {
            self.offset = 0;
            self.line = 1;
        }
        let newlines = self
            .bytes
            .get(self.offset..offset)
            .map_or(0, |s| s.iter().filter(|&&c| c == b'\n').count());
        self.line += newlines;
        self.offset = offset;
        self.line
    }
}

/// The first character XML 1.0 forbids (a C0 control other than tab, line feed and carriage
/// return): its offset and code.
pub(crate) fn forbidden_character(b: &[u8]) -> Option<(usize, u8)> {
    b.iter()
        .position(|&c| c < 0x20 && !matches!(c, b'\t' | b'\n' | b'\r'))
        .and_then(|i| b.get(i).map(|&c| (i, c)))
}

/// 1-based column (in characters) of byte `offset` within its line.
pub(crate) fn column_of(text: &str, offset: usize) -> usize {
    let before = text.get(..offset).unwrap_or("");
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    before.get(start..).map_or(0, |s| s.chars().count()) + 1
}

/// The character a reference (`lt`, `#65`, `#x41`) stands for.
pub(crate) fn reference(name: &str) -> Option<char> {
    Some(match name {
        "lt" => '<',
        "gt" => '>',
        "amp" => '&',
        "quot" => '"',
        "apos" => '\'',
        _ => {
            let code = if let Some(hex) = name.strip_prefix("#x") {
                u32::from_str_radix(hex, 16).ok()?
            } else {
                name.strip_prefix('#')?.parse().ok()?
            };
            char::from_u32(code)?
        }
    })
}

/// The first `&...` of `raw` that is not a predefined entity or a character reference.
pub(crate) fn bad_reference(raw: &str) -> Option<String> {
    let mut rest = raw;
    while let Some(amp) = rest.find('&') {
        let tail = rest.get(amp..).unwrap_or("");
        let ok = tail
            .find(';')
            .and_then(|s| tail.get(1..s))
            .and_then(reference)
            .is_some();
        if !ok {
            return Some(excerpt(tail.split(';').next().unwrap_or(tail)));
        }
        rest = tail.get(1..).unwrap_or("");
    }
    None
}

/// Decodes the predefined entities and numeric character references (checked by
/// [`bad_reference`] when the tag was read).
pub(crate) fn decode(raw: &str) -> Cow<'_, str> {
    if !raw.contains('&') {
        return Cow::Borrowed(raw);
    }
    let mut out = String::with_capacity(raw.len());
    let mut rest = raw;
    while let Some(amp) = rest.find('&') {
        out.push_str(rest.get(..amp).unwrap_or(""));
        let tail = rest.get(amp..).unwrap_or("");
        let decoded = tail
            .find(';')
            .and_then(|s| Some((reference(tail.get(1..s)?)?, s)));
        match decoded {
            Some((c, s)) => {
                out.push(c);
                rest = tail.get(s + 1..).unwrap_or("");
            }
            None => {
                out.push('&');
                rest = tail.get(1..).unwrap_or("");
            }
        }
    }
    out.push_str(rest);
    Cow::Owned(out)
}

/// Shortens text quoted in a message.
pub(crate) fn excerpt(s: &str) -> String {
    let t = s.trim();
    // One line of a message: stop at the first line break.
    let first = t.lines().next().unwrap_or("");
    let short: String = first.chars().take(24).collect();
    if short.len() < t.len() {
        format!("{short}...")
    } else {
        short
    }
}
