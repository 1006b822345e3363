//! Where a report came from: the input files (name as given, SHA-256, size), the command line,
//! the tool's version and the date ([`Provenance`]).
//!
//! The date is the time of the run in UTC, or `SOURCE_DATE_EPOCH` (seconds since 1970) when
//! that is set, so that a build or a test can make the page reproducible.

use std::fmt::Write as _;

use sha2::{Digest, Sha256};

use super::page::{esc, table};

/// One input of a run.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InputFile {
    /// What it is (`--model`, `--data`, ...).
    pub role: String,
    /// The path as given.
    pub path: String,
    /// Lowercase hex SHA-256 of its bytes; `None` when it could not be read again (standard
    /// input, a file gone since).
    pub sha256: Option<String>,
    /// Its size in bytes, when read.
    pub size: Option<u64>,
}

impl InputFile {
    /// `path` hashed as it is read, never held whole (`-`, standard input, is named but not
    /// hashed: it was read once).
    pub fn read(role: &str, path: &str) -> Self {
        let hashed = (path != "-")
            .then(|| {
                let mut file = std::fs::File::open(path).ok()?;
                let mut hasher = Sha256::new();
                let size = std::io::copy(&mut file, &mut hasher).ok()?;
                Some((hex(&hasher.finalize()), size))
            })
            .flatten();
        InputFile {
            role: role.into(),
            path: path.into(),
            sha256: hashed.as_ref().map(|h| h.0.clone()),
            size: hashed.map(|h| h.1),
        }
    }
}

/// Lowercase hex SHA-256 of `bytes`.
pub fn sha256_hex(bytes: &[u8]) -> String {
    hex(&Sha256::digest(bytes))
}

fn hex(digest: &[u8]) -> String {
    let mut s = String::with_capacity(2 * digest.len());
    for b in digest {
        let _ = write!(s, "{b:02x}");
    }
    s
}

/// What a report says about its run.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Provenance {
    /// The inputs, in the order of the command line.
    pub inputs: Vec<InputFile>,
    /// The command line, each argument as given.
    pub command: Vec<String>,
    /// The tool and its version (`urdf-dh 0.1.0`).
    pub tool: String,
    /// The date and time of the run, UTC (`2026-11-28 09:41:07 UTC`).
    pub date: String,
}

impl Provenance {
    /// The provenance of a run now: `inputs` as (role, path), each read and hashed; the tool
    /// named `tool` (its version is this crate's).
    pub fn now(tool: &str, command: Vec<String>, inputs: &[(&str, &str)]) -> Self {
        let seconds = std::env::var("SOURCE_DATE_EPOCH")
            .ok()
            .and_then(|s| s.trim().parse::<i64>().ok())
            .unwrap_or_else(|| {
                std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .map_or(0, |d| i64::try_from(d.as_secs()).unwrap_or(0))
            });
        Provenance {
            inputs: inputs
                .iter()
                .map(|(role, path)| InputFile::read(role, path))
                .collect(),
            command,
            tool: format!("{tool} {}", env!("CARGO_PKG_VERSION")),
            date: utc(seconds),
        }
    }

    /// The provenance section's markup.
    pub(super) fn html(&self) -> String {
        let rows: Vec<Vec<String>> = self
            .inputs
            .iter()
            .map(|f| {
                vec![
                    esc(&f.role),
                    format!("<code>{}</code>", esc(&f.path)),
                    f.size.map_or_else(|| "n/a".into(), |s| format!("{s}")),
                    f.sha256.as_deref().map_or_else(
                        || "n/a (standard input or not readable again)".into(),
                        |h| format!("<code>{h}</code>"),
                    ),
                ]
            })
            .collect();
        let mut s = table(&["input", "file", "#bytes", "SHA-256"], &rows);
        let command = self
            .command
            .iter()
            .map(|a| shell_quote(a))
            .collect::<Vec<_>>()
            .join(" ");
        let _ = write!(
            s,
            "<p>command: <code>{}</code></p>\n<p>tool: {} &#8212; run: {}</p>\n",
            esc(&command),
            esc(&self.tool),
            esc(&self.date)
        );
        s
    }
}

/// `arg` as a POSIX shell would need it quoted (single quotes when it holds anything but
/// letters, digits and `-_./,:=+@%`).
fn shell_quote(arg: &str) -> String {
    let plain = !arg.is_empty()
        && arg
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./,:=+@%".contains(c));
    if plain {
        arg.into()
    } else {
        format!("'{}'", arg.replace('\'', "'\\''"))
    }
}

/// `seconds` since 1970-01-01 as `YYYY-MM-DD HH:MM:SS UTC` (proleptic Gregorian calendar;
/// Howard Hinnant's `civil_from_days`).
pub fn utc(seconds: i64) -> String {
    let days = seconds.div_euclid(86_400);
    let rest = seconds.rem_euclid(86_400);
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02} {:02}:{:02}:{:02} UTC",
        rest / 3600,
        rest % 3600 / 60,
        rest % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_in_utc() {
        assert_eq!(utc(0), "1970-01-01 00:00:00 UTC");
        assert_eq!(utc(951_782_400), "2000-02-29 00:00:00 UTC");
        assert_eq!(utc(1_795_859_267), "2026-11-28 09:47:47 UTC");
        assert_eq!(utc(-1), "1969-12-31 23:59:59 UTC");
    }

    #[test]
    fn sha256_of_known_bytes() {
        assert_eq!(
            sha256_hex(b"abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }

    #[test]
    fn a_file_is_hashed_as_it_is_read() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("data.csv");
        std::fs::write(&file, b"abc").unwrap();
        let f = InputFile::read("--data", file.to_str().unwrap());
        assert_eq!(f.sha256.as_deref(), Some(sha256_hex(b"abc").as_str()));
        assert_eq!(f.size, Some(3));
        let stdin = InputFile::read("--data", "-");
        assert_eq!((stdin.sha256, stdin.size), (None, None));
        let gone = InputFile::read("--data", dir.path().join("gone").to_str().unwrap());
        assert_eq!(gone.sha256, None);
    }

    #[test]
    fn shell_quoting() {
        assert_eq!(shell_quote("--data"), "--data");
        assert_eq!(shell_quote("a b"), "'a b'");
        assert_eq!(shell_quote("it's"), "'it'\\''s'");
    }
}
