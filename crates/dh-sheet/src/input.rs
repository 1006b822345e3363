//! Reading robot files: a URDF or `.xacro` file (or standard input, `-`) as bytes within
//! [`urdf_axes::MAX_URDF_BYTES`], as UTF-8 text, and a URDF's chain ([`load_chain`]) with its
//! warnings ([`urdf_warnings`]). Errors name the file as [`display_name`] shows it (no
//! directories), with a hint where the user can do something ([`crate::error::Hinted`]).

use std::io::Read;
use std::path::Path;
use std::process::Command;

use anyhow::{Context, Result};
use urdf_axes::{Chain, UrdfModel};

use crate::error::hinted;

/// Reads `path`, or standard input when it is `-`, as bytes, refusing more than
/// [`urdf_axes::MAX_URDF_BYTES`] without reading further (so `- < /dev/zero` stops there).
///
/// # Errors
/// The file cannot be read; the message names it. Too long: [`urdf_axes::UrdfError::TooLarge`]
/// in the context "`NAME`: invalid URDF".
pub fn read_robot_bytes(path: &str) -> Result<Vec<u8>> {
    let limit = urdf_axes::MAX_URDF_BYTES;
    let mut buf = Vec::new();
    let mut size = None;
    let read = if path == "-" {
        std::io::stdin()
            .take(limit as u64 + 1)
            .read_to_end(&mut buf)
            .context("reading standard input")
    } else {
        std::fs::File::open(path)
            .and_then(|f| {
                size = f
                    .metadata()
                    .ok()
                    .and_then(|m| usize::try_from(m.len()).ok());
                f.take(limit as u64 + 1).read_to_end(&mut buf)
            })
            .with_context(|| format!("{path}: cannot read the file"))
    };
    read?;
    if buf.len() > limit {
        return Err(anyhow::Error::new(urdf_axes::UrdfError::TooLarge {
            size: size.filter(|&s| s > limit),
            limit,
        })
        .context(format!("{}: invalid URDF", display_name(path))));
    }
    Ok(buf)
}

/// Reads `path`, or standard input when it is `-`, as bytes.
///
/// # Errors
/// The file cannot be read; the message names it (an [`std::io::Error`] in the chain).
pub fn read_bytes(path: &str) -> Result<Vec<u8>> {
    if path == "-" {
        let mut buf = Vec::new();
        std::io::stdin()
            .read_to_end(&mut buf)
            .context("reading standard input")?;
        return Ok(buf);
    }
    read_file(path, PARALLEL_READ_BYTES).with_context(|| format!("{path}: cannot read the file"))
}

/// Files of at least this many bytes are read in as many parts as there are cores, each part
/// by its own thread (a 418 MB measurement file: the kernel's copy and the new pages' zeroing
/// took 0.6 s on one thread).
const PARALLEL_READ_BYTES: u64 = 64 << 20;

/// The bytes of the file `path`, as [`std::fs::read`] gives them; in parts on every core from
/// `parallel_from` bytes.
fn read_file(path: &str, parallel_from: u64) -> std::io::Result<Vec<u8>> {
    #[cfg(unix)]
    {
        use std::io::{Seek, SeekFrom};
        use std::os::unix::fs::FileExt;
        let mut file = std::fs::File::open(path)?;
        let meta = file.metadata()?;
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
        if let (true, Ok(len)) = (
            meta.is_file() && meta.len() >= parallel_from && threads > 1,
            usize::try_from(meta.len()),
        ) {
            let mut bytes = vec![0u8; len];
            let part = len.div_ceil(threads);
            let parts: Vec<std::io::Result<()>> = std::thread::scope(|scope| {
                let file = &file;
                let readers: Vec<_> = bytes
                    .chunks_mut(part)
                    .enumerate()
                    .map(|(k, piece)| {
                        scope.spawn(move || file.read_exact_at(piece, (k * part) as u64))
                    })
                    .collect();
                readers
                    .into_iter()
                    .map(|r| {
                        r.join()
                            .unwrap_or_else(|_| Err(std::io::Error::other("a reader failed")))
                    })
                    .collect()
            });
            match parts.into_iter().collect::<std::io::Result<Vec<()>>>() {
                Ok(_) => {
                    // What was appended after the length was taken, as `fs::read` reads it.
                    file.seek(SeekFrom::Start(len as u64))?;
                    file.read_to_end(&mut bytes)?;
                    return Ok(bytes);
                }
                // The file shrank while it was read: read it again as it is now.
                Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => {}
                Err(e) => return Err(e),
            }
        }
    }
    // Elsewhere (WebAssembly, Windows) the file is read in one part.
    #[cfg(not(unix))]
    let _ = parallel_from;
    std::fs::read(path)
}

/// Reads `path` (or `-`) as UTF-8 text, without the byte-order mark some editors put first
/// (the YAML parser would take it for part of the first key; URDF and JSON readers skip it).
///
/// # Errors
/// The file cannot be read or is not UTF-8 (the message gives the line of the first bad byte).
pub fn read_text(path: &str) -> Result<String> {
    utf8_text(path, read_bytes(path)?)
}

/// The bytes read from `path` as UTF-8 text.
///
/// # Errors
/// Not UTF-8 (the message gives the line of the first bad byte).
pub fn utf8_text(path: &str, mut bytes: Vec<u8>) -> Result<String> {
    if bytes.starts_with(b"\xEF\xBB\xBF") {
        bytes.drain(..3);
    }
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let line = e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count() + 1;
        hinted(
            format!(
                "{path}: line {line}: expected UTF-8 text, found a byte that is not (offset {at})"
            ),
            "convert the file to UTF-8, e.g. iconv -f latin1 -t utf-8 FILE > FILE.utf8",
        )
    })
}

/// Reads a robot description: a URDF, or a `.xacro` file expanded by the `xacro` command.
///
/// # Errors
/// The file cannot be read; a `.xacro` file when `xacro` is not on PATH or fails.
pub fn read_robot(path: &str) -> Result<Vec<u8>> {
    if !path.ends_with(".xacro") {
        return read_robot_bytes(path);
    }
    if !Path::new(path).is_file() {
        anyhow::bail!("{path}: cannot read the file: no such file");
    }
    let pipe = format!("xacro {path} | urdf-dh extract -");
    let out = match Command::new("xacro").arg(path).output() {
        Ok(out) => out,
        Err(_) => {
            return Err(hinted(
                format!("{path}: a .xacro file needs the 'xacro' command, which is not on PATH"),
                format!("install it with 'pip install xacro', or expand it yourself: {pipe}"),
            ))
        }
    };
    if !out.status.success() {
        let stderr = String::from_utf8_lossy(&out.stderr);
        return Err(hinted(
            format!("{path}: xacro failed: {}", stderr.trim()),
            format!("try it by hand: {pipe}"),
        ));
    }
    Ok(out.stdout)
}

/// A display name for a path argument (`<stdin>` for `-`), without directories so that outputs
/// stay the same wherever the file lives.
pub fn display_name(path: &str) -> String {
    if path == "-" {
        return "<stdin>".into();
    }
    Path::new(path)
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.to_string())
}

/// Loads the URDF and its chain.
///
/// # Errors
/// Unreadable file, invalid URDF, unknown or ambiguous base/tip.
pub fn load_chain(path: &str, base: Option<&str>, tip: Option<&str>) -> Result<(UrdfModel, Chain)> {
    let bytes = read_robot(path)?;
    load_chain_bytes(&bytes, &display_name(path), base, tip)
}

/// Loads the chain of a URDF given as bytes; `name` names it in error messages (a file name, or
/// `<string>` for XML text a library caller passed).
///
/// # Errors
/// Invalid URDF, unknown or ambiguous base/tip.
pub fn load_chain_bytes(
    bytes: &[u8],
    name: &str,
    base: Option<&str>,
    tip: Option<&str>,
) -> Result<(UrdfModel, Chain)> {
    let model = UrdfModel::from_bytes(bytes).with_context(|| format!("{name}: invalid URDF"))?;
    let chain = model.chain(base, tip).map_err(|e| chain_error(name, e))?;
    Ok((model, chain))
}

/// The error of choosing a chain of the file shown as `name`: a fault of a joint on the chain is
/// a fault of the file ("invalid URDF"), not of the choice ("cannot choose the chain").
pub fn chain_error(name: &str, e: urdf_axes::UrdfError) -> anyhow::Error {
    let what = if e.is_choice() {
        "cannot choose the chain"
    } else {
        "invalid URDF"
    };
    anyhow::Error::new(e).context(format!("{name}: {what}"))
}

/// The warnings of reading the URDF that concern `chain`, each prefixed with the file's name
/// (`name`), for `urdf-dh: warning:` lines.
pub fn urdf_warnings(name: &str, model: &UrdfModel, chain: &Chain) -> Vec<String> {
    model
        .warnings_for(chain)
        .iter()
        .map(|w| format!("{name}: {w}"))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file read in parts on every core is the file: parts of unequal length, a file just
    /// at the size where the parts start, and one below it.
    #[test]
    fn a_file_read_in_parts_is_the_file() {
        let dir = tempfile::tempdir().expect("a directory");
        let path = dir.path().join("rows.csv");
        let bytes: Vec<u8> = (0..1_000_003u32).map(|i| (i % 251) as u8).collect();
        std::fs::write(&path, &bytes).expect("written");
        let path = path.to_str().expect("a UTF-8 path");
        for from in [1, 1_000_003, 1_000_004] {
            assert_eq!(
                read_file(path, from).expect("read"),
                bytes,
                "from {from} bytes"
            );
        }
        let missing = dir.path().join("missing.csv");
        assert!(read_file(missing.to_str().expect("UTF-8"), 1).is_err());
    }
}
