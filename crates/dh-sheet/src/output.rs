//! Writing output files so that a failed run never leaves one half-written.
//!
//! Every command that writes a file (rather than standard output) goes through
//! [`write_atomically`]: the bytes go to a temporary file beside the target, are flushed to disk,
//! and only then renamed over the target. A run that fails before that point (bad input, a full
//! disk, a killed process) leaves the previous file, or no file, but never a truncated one.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use crate::error::hinted;
use crate::text::escape;

/// Writes `bytes` to `path` atomically: into a temporary file in the target's own directory
/// (a rename is atomic only within one file system), synced to disk, then renamed over `path`.
///
/// A new file gets the usual permissions (`0666` less the umask on Unix); an existing file keeps
/// its own. A symbolic link is followed, so the file it points to is replaced, not the link.
/// On any error the temporary file is removed and `path` is untouched.
///
/// # Errors
/// The directory does not exist or is not writable, the disk is full, or `path` is a directory;
/// the message names `path`.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    write_all(&[(path, bytes)])
}

/// The path that means standard output (or input): `-`.
pub const STDIO: &str = "-";

/// Whether any of `paths` is [`STDIO`]: the artefact then goes to standard output, and the
/// report that would go there goes to standard error instead (so a pipe carries the artefact
/// alone).
pub fn any_stdout<'a>(paths: impl IntoIterator<Item = Option<&'a str>>) -> bool {
    paths.into_iter().flatten().any(|p| p == STDIO)
}

/// [`write_all`], with a path of `-` written to `stdout` once every file is in place.
///
/// # Errors
/// As [`write_all`], and a failed write to `stdout`.
pub fn write_all_or_stdout(files: &[(&Path, &[u8])], stdout: &mut dyn Write) -> Result<()> {
    let (piped, real): (Vec<_>, Vec<_>) = files
        .iter()
        .copied()
        .partition(|(p, _)| p.as_os_str() == STDIO);
    write_all(&real)?;
    for (_, bytes) in piped {
        stdout.write_all(bytes)?;
    }
    Ok(())
}

/// Writes several files as one: every file is staged (written in full and synced to a
/// temporary beside its target) before the first rename, so a failure while writing (a full
/// disk, a vanished directory) leaves every target as it was. Only a failure of a rename itself
/// (which moves no data) can leave the earlier targets replaced.
///
/// # Errors
/// As [`write_atomically`], for the first file that fails.
pub fn write_all(files: &[(&Path, &[u8])]) -> Result<()> {
    let mut staged = Vec::with_capacity(files.len());
    for (path, bytes) in files {
        staged.push(stage(path, bytes)?);
    }
    for (tmp, target, shown) in staged {
        tmp.persist(&target)
            .map_err(|e| e.error)
            .with_context(|| format!("{shown}: cannot write the output"))?;
    }
    Ok(())
}

/// Writes `bytes` to a synced temporary file beside `path`'s target: (the temporary, the
/// target, `path` as shown in messages).
fn stage(path: &Path, bytes: &[u8]) -> Result<(tempfile::NamedTempFile, PathBuf, String)> {
    let target = resolve_symlink(path);
    let shown = path.display().to_string();
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let existing = std::fs::metadata(&target).ok();
    if existing.as_ref().is_some_and(|m| m.is_dir()) {
        anyhow::bail!("{shown}: cannot write the output: expected a file, found a directory");
    }
    let mut builder = tempfile::Builder::new();
    builder.prefix(".urdf-dh-").suffix(".tmp");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        // tempfile's default is 0600; 0666 lets the umask decide, as for any new file.
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let mut tmp = builder
        .tempfile_in(dir)
        .with_context(|| format!("{shown}: cannot write the output"))?;
    let written = (|| -> std::io::Result<()> {
        tmp.write_all(bytes)?;
        if let Some(m) = &existing {
            tmp.as_file().set_permissions(m.permissions())?;
        }
        tmp.as_file().sync_all()
    })();
    written.with_context(|| format!("{shown}: cannot write the output"))?;
    Ok((tmp, target, shown))
}

/// What makes two spellings of a path the same file: the device and inode of an existing file
/// (so hard links and symbolic links match), else the canonical directory and the file name.
#[derive(Debug, PartialEq, Eq)]
enum Identity {
    #[cfg(unix)]
    Inode(u64, u64),
    Path(PathBuf),
}

fn identity(path: &str) -> Option<Identity> {
    if path == "-" {
        return None;
    }
    let p = Path::new(path);
    if let Ok(m) = std::fs::metadata(p) {
        #[cfg(unix)]
        {
            use std::os::unix::fs::MetadataExt;
            let _ = &m;
            return Some(Identity::Inode(m.dev(), m.ino()));
        }
        #[cfg(not(unix))]
        {
            let _ = m;
            return std::fs::canonicalize(p).ok().map(Identity::Path);
        }
    }
    let dir = match p.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let dir = std::fs::canonicalize(dir).ok()?;
    Some(Identity::Path(dir.join(p.file_name()?)))
}

/// Checks a run's output files before it reads or computes anything: each output must be a
/// new file or a plain file, in a directory that exists and can be written, and no output may
/// be one of the inputs or another output, however spelled (`./d.csv`, a symbolic or hard
/// link). `inputs` and `outputs` are `(option, path)`; `-` (standard input or output) is never
/// a clash with a file, but at most one output may be `-` (standard output).
///
/// # Errors
/// A usage error naming both options and the file, or the output that cannot be written.
pub fn check_destinations(inputs: &[(&str, &str)], outputs: &[(&str, &str)]) -> Result<()> {
    let piped: Vec<&str> = outputs
        .iter()
        .filter(|(_, p)| *p == STDIO)
        .map(|(o, _)| *o)
        .collect();
    if let [first, second, ..] = piped.as_slice() {
        return Err(hinted(
            format!(
                "{second} -: expected a file, found standard output already taken by {first} -"
            ),
            "at most one output can go to standard output; give the others file names",
        ));
    }
    let ids: Vec<Option<Identity>> = inputs
        .iter()
        .chain(outputs)
        .map(|(_, p)| identity(p))
        .collect();
    for (k, (option, path)) in outputs.iter().enumerate() {
        let at = inputs.len() + k;
        let shown = escape(path);
        if let Some(id) = &ids[at] {
            if let Some(j) = ids[..at].iter().position(|o| o.as_ref() == Some(id)) {
                let (other, kind) = if j < inputs.len() {
                    (inputs[j], "input")
                } else {
                    (outputs[j - inputs.len()], "output")
                };
                return Err(hinted(
                    format!(
                        "{option} {shown}: expected a file of its own, found the {kind} {} {}",
                        other.0,
                        escape(other.1)
                    ),
                    "write each output to a new file: urdf-dh never writes over its inputs or one output over another",
                ));
            }
        }
        if *path == "-" {
            continue;
        }
        let p = Path::new(path);
        if p.is_dir() {
            anyhow::bail!(
                "{option} {shown}: cannot write the output: expected a file, found a directory"
            );
        }
        let target = resolve_symlink(p);
        let dir = match target.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        if !dir.is_dir() {
            anyhow::bail!(
                "{option} {shown}: cannot write the output: the directory {} does not exist",
                escape(&dir.to_string_lossy())
            );
        }
        // Writable: the same probe the write itself makes (a temporary beside the target).
        tempfile::Builder::new()
            .prefix(".urdf-dh-")
            .suffix(".tmp")
            .tempfile_in(dir)
            .with_context(|| format!("{option} {shown}: cannot write the output"))?;
    }
    Ok(())
}

/// The file a symbolic link points to (links of links followed); `path` itself otherwise.
fn resolve_symlink(path: &Path) -> PathBuf {
    let is_link = std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink());
    if is_link {
        if let Ok(real) = std::fs::canonicalize(path) {
            return real;
        }
    }
    path.to_path_buf()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn writes_a_new_file_and_replaces_an_old_one_leaving_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.yaml");
        write_atomically(&path, b"first\n").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"first\n");
        write_atomically(&path, b"second, longer\n").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"second, longer\n");
        assert_eq!(entries(dir.path()), ["out.yaml"]);
    }

    #[test]
    fn a_failed_write_leaves_the_old_file_and_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        // The target is a directory: refused before anything is written.
        let sub = dir.path().join("sub");
        std::fs::create_dir(&sub).unwrap();
        let e = write_atomically(&sub, b"x").unwrap_err();
        assert!(format!("{e:#}").contains("found a directory"), "{e:#}");
        // The directory does not exist.
        let e = write_atomically(&dir.path().join("nope/out.csv"), b"x").unwrap_err();
        assert!(format!("{e:#}").contains("out.csv"), "{e:#}");
        assert_eq!(entries(dir.path()), ["sub"]);
        assert!(entries(&sub).is_empty());
    }

    #[test]
    fn a_set_of_files_is_written_whole_or_not_at_all() {
        let dir = tempfile::tempdir().unwrap();
        let first = dir.path().join("model.yaml");
        std::fs::write(&first, b"old model").unwrap();
        // The second destination's directory is missing: staging fails before any rename.
        let e = write_all(&[
            (&first, b"new model".as_slice()),
            (&dir.path().join("missing/plot.svg"), b"<svg/>".as_slice()),
        ])
        .unwrap_err();
        assert!(format!("{e:#}").contains("plot.svg"), "{e:#}");
        assert_eq!(std::fs::read(&first).unwrap(), b"old model");
        assert_eq!(entries(dir.path()), ["model.yaml"]);
        let second = dir.path().join("plot.svg");
        write_all(&[
            (&first, b"new model".as_slice()),
            (&second, b"<svg/>".as_slice()),
        ])
        .unwrap();
        assert_eq!(std::fs::read(&first).unwrap(), b"new model");
        assert_eq!(entries(dir.path()), ["model.yaml", "plot.svg"]);
    }

    #[test]
    fn outputs_are_compared_with_inputs_and_each_other() {
        let dir = tempfile::tempdir().unwrap();
        let data = dir.path().join("d.csv");
        std::fs::write(&data, b"x").unwrap();
        let d = data.to_string_lossy().into_owned();
        let dotted = dir
            .path()
            .join(".")
            .join("d.csv")
            .to_string_lossy()
            .into_owned();
        let e = check_destinations(&[("--data", &d)], &[("--out", &dotted)]).unwrap_err();
        assert!(e.to_string().contains("found the input --data"), "{e}");
        // Two new files of one name.
        let a = dir.path().join("r.yaml").to_string_lossy().into_owned();
        let b = dir.path().join("sub/../r.yaml");
        std::fs::create_dir(dir.path().join("sub")).unwrap();
        let b = b.to_string_lossy().into_owned();
        let e = check_destinations(&[], &[("--out", &a), ("--plot", &b)]).unwrap_err();
        assert!(e.to_string().contains("found the output --out"), "{e}");
        check_destinations(&[("--data", &d)], &[("--out", &a)]).unwrap();
        check_destinations(&[("--data", "-")], &[("--out", &a)]).unwrap();
        assert_eq!(
            entries(dir.path()),
            ["d.csv", "sub"],
            "the probe leaves nothing"
        );
    }

    #[cfg(unix)]
    #[test]
    fn keeps_permissions_and_follows_links() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let real = dir.path().join("real.urdf");
        std::fs::write(&real, b"old").unwrap();
        std::fs::set_permissions(&real, std::fs::Permissions::from_mode(0o640)).unwrap();
        let link = dir.path().join("link.urdf");
        std::os::unix::fs::symlink(&real, &link).unwrap();
        write_atomically(&link, b"new").unwrap();
        assert!(std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(std::fs::read(&real).unwrap(), b"new");
        let mode = std::fs::metadata(&real).unwrap().permissions().mode();
        assert_eq!(mode & 0o777, 0o640);
        // A new file gets what any new file gets (not the temporary's private 0600).
        let fresh = dir.path().join("fresh.csv");
        write_atomically(&fresh, b"x").unwrap();
        let plain = dir.path().join("plain.csv");
        std::fs::write(&plain, b"x").unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&fresh), mode(&plain));
    }
}
