//! What a file that is not what a command reads looks like instead: a DH sheet or a
//! measurement CSV given to `extract`, an image, a MATLAB file or another binary file, so that
//! the refusal can point at the command that reads it.
//!
//! Only the file's first bytes are looked at ([`LOOKED_AT`]); each test is a signature the
//! formats define (PNG's, PDF's, ZIP's, MATLAB level 5's header text) or the keys and columns
//! urdf-dh's own formats start with.

/// Bytes looked at from the start of a file.
pub const LOOKED_AT: usize = 8192;

/// What a file looks like and which command reads it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Sniffed {
    /// What the file looks like, as a message says it ("a DH sheet (YAML or JSON)").
    pub what: &'static str,
    /// What to do with it (a command line, or what to give instead).
    pub hint: &'static str,
}

/// What `bytes` (a file given as a robot description) look like, when it is something urdf-dh
/// recognises as another kind of file; `None` for what may be a (broken) URDF or unknown text.
pub fn not_a_robot(bytes: &[u8]) -> Option<Sniffed> {
    let head = &bytes[..bytes.len().min(LOOKED_AT)];
    let binary = |what| Sniffed {
        what,
        hint: "give the robot's URDF (XML text with a <robot> element), or - to read it from \
               standard input",
    };
    if head.starts_with(b"\x89PNG\r\n\x1a\n") {
        return Some(binary("a PNG image"));
    }
    if head.starts_with(b"\xff\xd8\xff") {
        return Some(binary("a JPEG image"));
    }
    if head.starts_with(b"%PDF-") {
        return Some(binary("a PDF document"));
    }
    if head.starts_with(b"PK\x03\x04") {
        return Some(binary("a ZIP archive (or an office document)"));
    }
    if head.starts_with(b"MATLAB 5.0 MAT-file") {
        return Some(Sniffed {
            what: "a MATLAB .mat file",
            hint: "urdf-dh import reads measurements from .mat files: urdf-dh import FILE --out \
                   measured.csv",
        });
    }
    // NUL bytes: binary, unless they fill every other byte (UTF-16 text, which the reader's
    // own message names).
    let zeros_at = |k: usize| head.iter().skip(k).step_by(2).filter(|&&b| b == 0).count();
    let half = head.len() / 2;
    let utf16 = head.starts_with(b"\xff\xfe")
        || head.starts_with(b"\xfe\xff")
        || (half > 0 && (zeros_at(0) * 10 >= half * 9 || zeros_at(1) * 10 >= half * 9));
    if head.contains(&0) && !utf16 {
        return Some(binary("a binary file"));
    }
    let text = match std::str::from_utf8(head) {
        Ok(text) => text,
        // A character cut at the end of the head is not a fault of the file.
        Err(e) if head.len() == LOOKED_AT && head.len() - e.valid_up_to() < 4 => {
            std::str::from_utf8(&head[..e.valid_up_to()]).unwrap_or_default()
        }
        // Latin-1, UTF-16: the reader's own message says what to do.
        Err(_) => return None,
    };
    if text.trim_start().starts_with('<') {
        return None;
    }
    if looks_like_sheet(text) {
        return Some(Sniffed {
            what: "a DH sheet (YAML or JSON)",
            hint: "a sheet is read by check (against a URDF: urdf-dh check ROBOT.urdf --sheet \
                   FILE), convert (urdf-dh convert FILE --to modified) and to-urdf (urdf-dh \
                   to-urdf FILE > robot.urdf)",
        });
    }
    if looks_like_measurements(text) {
        return Some(Sniffed {
            what: "a measurement CSV",
            hint: "measurements are read by calibrate (urdf-dh calibrate --model MODEL --data \
                   FILE) and cpa (urdf-dh cpa FILE)",
        });
    }
    None
}

/// A YAML or JSON document with the keys a DH sheet starts with.
fn looks_like_sheet(text: &str) -> bool {
    let key = |k: &str| {
        text.lines().any(|l| {
            let l = l.trim_start().trim_start_matches('{').trim_start();
            l.starts_with(&format!("{k}:")) || l.starts_with(&format!("\"{k}\":"))
        })
    };
    key("joints") && (key("convention") || key("length_unit") || key("branches"))
}

/// A CSV whose header (the first line that is not a `#` comment) has a `target` column or the
/// point columns `x,y,z`.
fn looks_like_measurements(text: &str) -> bool {
    let Some(header) = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))
    else {
        return false;
    };
    let cells: Vec<String> = header
        .split([',', ';', '\t'])
        .map(|c| c.trim().trim_matches('"').to_ascii_lowercase())
        .collect();
    let has = |name: &str| cells.iter().any(|c| c == name);
    cells.len() >= 3 && (has("target") || (has("x") && has("y") && has("z")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_of_other_kinds_are_named() {
        assert_eq!(
            not_a_robot(b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR").unwrap().what,
            "a PNG image"
        );
        assert_eq!(
            not_a_robot(b"MATLAB 5.0 MAT-file, Platform: GLNXA64")
                .unwrap()
                .what,
            "a MATLAB .mat file"
        );
        assert_eq!(
            not_a_robot(&[0u8, 1, 0, 2, 0, 0, 7, 0]).unwrap().what,
            "a binary file"
        );
        let sheet =
            "# UR5\nrobot: ur5\nconvention: standard\nlength_unit: m\njoints:\n  - {name: a}\n";
        let s = not_a_robot(sheet.as_bytes()).unwrap();
        assert_eq!(s.what, "a DH sheet (YAML or JSON)");
        assert!(
            s.hint.contains("urdf-dh check ROBOT.urdf --sheet FILE"),
            "{}",
            s.hint
        );
        let json = "{\n  \"convention\": \"standard\",\n  \"joints\": []\n}\n";
        assert_eq!(
            not_a_robot(json.as_bytes()).unwrap().what,
            "a DH sheet (YAML or JSON)"
        );
        let csv = "# simulated\nj1,j2,x,y,z,target\n0,0,1,2,3,t1\n";
        let s = not_a_robot(csv.as_bytes()).unwrap();
        assert_eq!(s.what, "a measurement CSV");
        assert!(s.hint.contains("calibrate"), "{}", s.hint);
    }

    #[test]
    fn urdfs_and_unknown_text_are_not_named() {
        assert_eq!(
            not_a_robot(b"<?xml version=\"1.0\"?>\n<robot name=\"r\"/>"),
            None
        );
        assert_eq!(not_a_robot(b"  <robot name=\"r\">"), None);
        assert_eq!(not_a_robot(b"hello world\n"), None);
        assert_eq!(not_a_robot(b""), None);
        // UTF-16 text is left to the reader's own message.
        assert_eq!(not_a_robot(b"\xff\xfe<\0r\0o\0"), None);
        assert_eq!(not_a_robot(b"<\0r\0o\0b\0o\0t\0"), None);
        // Latin-1 text is not binary.
        assert_eq!(not_a_robot(b"<robot name=\"gel\xe4nk\">"), None);
    }
}
