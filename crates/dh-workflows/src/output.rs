//! Writing output files so that a failed run never leaves one half-written, never replaces a
//! device node or a FIFO, and never lands on an input.
//!
//! The rules, for every command:
//! - **Regular files are staged.** A new file or an existing regular file is written in full to
//!   a temporary file beside it, synced, and only then renamed over it: a run that fails before
//!   that (bad input, a full disk, a killed process) leaves the previous file, or none, never a
//!   truncated one.
//! - **Special files are written in place.** A destination that exists and is not a regular
//!   file (`/dev/null`, a terminal, a FIFO a reader waits on) is opened and written as it is,
//!   never replaced by a regular file; a socket or a directory is refused.
//! - **Every write error is an error** (a full device, a closed pipe), naming the destination.
//! - **All or nothing, standard output included.** A run's files are committed (renamed) only
//!   after standard output has been written and flushed and every special file written: a run
//!   whose standard output fails leaves none of its files.
//! - **Never over an input** ([`check_destinations`]), however spelled, standard input included
//!   (the file the shell redirected into it).

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use crate::error::hinted;
use crate::text::escape;

/// Writes `bytes` to `path` by the module's rules: a regular file atomically (a temporary file
/// in the target's own directory, synced, renamed over `path`), a special file in place.
///
/// A new file gets the usual permissions (`0666` less the umask on Unix); an existing file keeps
/// its own. A symbolic link is followed, so the file it points to is replaced, not the link.
/// On any error the temporary file is removed and `path` is untouched.
///
/// # Errors
/// The directory does not exist or is not writable, the disk is full, `path` is a directory or
/// a socket; the message names `path`.
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

/// [`write_all`], with a path of `-` written to `stdout`: the files are staged, `stdout` is
/// written and flushed, the special files written, and only then are the files renamed into
/// place, so a failure of standard output leaves every file as it was.
///
/// # Errors
/// As [`write_all`], and a failed write or flush of `stdout` (named "standard output").
pub fn write_all_or_stdout(files: &[(&Path, &[u8])], stdout: &mut dyn Write) -> Result<()> {
    commit(files, Some(stdout))
}

/// Writes several files as one: every regular file is staged (written in full and synced to a
/// temporary beside its target) and every special file written before the first rename, so a
/// failure while writing (a full disk, a vanished directory, a full device) leaves every
/// regular target as it was. Only a failure of a rename itself (which moves no data) can leave
/// the earlier targets replaced. A path of `-` is a file of that name here; see
/// [`write_all_or_stdout`] for standard output.
///
/// # Errors
/// As [`write_atomically`], for the first file that fails.
pub fn write_all(files: &[(&Path, &[u8])]) -> Result<()> {
    commit(files, None)
}

/// Flushes `stdout` (the report a command wrote there), then writes `files` as [`write_all`]
/// does: for a command whose files must not land when its standard output failed.
///
/// # Errors
/// A failed flush of `stdout`, then as [`write_all`].
pub fn write_all_after(stdout: &mut dyn Write, files: &[(&Path, &[u8])]) -> Result<()> {
    stdout.flush().map_err(named_stdout)?;
    write_all(files)
}

/// What a destination is when it is written.
enum Destination {
    /// A new or regular file: staged, then renamed.
    Regular,
    /// An existing file that is not a regular file: written in place.
    Special,
}

/// The kind of the destination `target` (symbolic links resolved), refusing what cannot be
/// written: a directory, a socket.
fn destination(target: &Path, shown: &str) -> Result<Destination> {
    let Ok(m) = std::fs::metadata(target) else {
        return Ok(Destination::Regular);
    };
    if m.is_file() {
        return Ok(Destination::Regular);
    }
    if m.is_dir() {
        anyhow::bail!("{shown}: cannot write the output: expected a file, found a directory");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if m.file_type().is_socket() {
            anyhow::bail!("{shown}: cannot write the output: expected a file, found a socket");
        }
    }
    Ok(Destination::Special)
}

fn commit(files: &[(&Path, &[u8])], stdout: Option<&mut dyn Write>) -> Result<()> {
    let mut staged = Vec::with_capacity(files.len());
    let mut special = Vec::new();
    let mut piped = Vec::new();
    for (path, bytes) in files {
        if stdout.is_some() && path.as_os_str() == STDIO {
            piped.push(*bytes);
            continue;
        }
        let target = resolve_symlink(path);
        let shown = escape(&path.to_string_lossy()).into_owned();
        match destination(&target, &shown)? {
            Destination::Regular => staged.push(stage(&target, &shown, bytes)?),
            Destination::Special => special.push((target, shown, *bytes)),
        }
    }
    if let Some(out) = stdout {
        let written = (|| -> std::io::Result<()> {
            for bytes in &piped {
                out.write_all(bytes)?;
            }
            out.flush()
        })();
        written.map_err(named_stdout)?;
    }
    for (target, shown, bytes) in special {
        write_in_place(&target, bytes)
            .with_context(|| format!("{shown}: cannot write the output"))?;
    }
    for (tmp, target, shown) in staged {
        tmp.persist(&target)
            .map_err(|e| e.error)
            .with_context(|| format!("{shown}: cannot write the output"))?;
    }
    Ok(())
}

/// An error of standard output whose message already names it ("standard output: ..."): what
/// a writer that stands for the process's standard output returns (the CLI's does), so that a
/// message names it once.
#[derive(Debug)]
pub struct StdoutError(pub String);

impl std::fmt::Display for StdoutError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for StdoutError {}

/// A failed write to standard output as an error that names it once.
fn named_stdout(e: std::io::Error) -> anyhow::Error {
    if e.get_ref().is_some_and(|inner| inner.is::<StdoutError>()) {
        anyhow::Error::new(e)
    } else {
        anyhow::Error::new(e).context("standard output: cannot write the output")
    }
}

/// Writes `bytes` to the existing special file `target` as it is (no truncation, no rename):
/// a device node, or a FIFO (which waits for its reader, as a shell's `>` does).
fn write_in_place(target: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut f = std::fs::OpenOptions::new().write(true).open(target)?;
    f.write_all(bytes)?;
    f.flush()
}

/// Writes `bytes` to a synced temporary file beside `target`: (the temporary, the target, the
/// destination as shown in messages).
fn stage(
    target: &Path,
    shown: &str,
    bytes: &[u8],
) -> Result<(tempfile::NamedTempFile, PathBuf, String)> {
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let existing = std::fs::metadata(target).ok();
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
    Ok((tmp, target.to_path_buf(), shown.to_string()))
}

/// What makes two spellings of a path the same file: the device and inode of an existing file
/// (so hard links and symbolic links match), else the canonical directory and the file name.
#[derive(Debug, PartialEq, Eq)]
enum Identity {
    #[cfg(unix)]
    Inode(u64, u64),
    Path(PathBuf),
}

/// The identity of an input (`-`: what standard input is, when it is a regular file: `cmd - <
/// a.urdf` reads `a.urdf`) or of an output (`-`: none, standard output is never a file here).
fn identity(path: &str, input: bool) -> Option<Identity> {
    if path == STDIO {
        return if input { stdin_identity() } else { None };
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

/// The regular file standard input reads, by device and inode (`fstat` of descriptor 0): a
/// pipe, a terminal or a device is nothing an output could overwrite.
fn stdin_identity() -> Option<Identity> {
    #[cfg(unix)]
    {
        use std::os::fd::AsFd;
        use std::os::unix::fs::MetadataExt;
        let fd = std::io::stdin().as_fd().try_clone_to_owned().ok()?;
        let m = std::fs::File::from(fd).metadata().ok()?;
        m.is_file().then(|| Identity::Inode(m.dev(), m.ino()))
    }
    #[cfg(not(unix))]
    {
        None
    }
}

/// Checks a run's output files before it reads or computes anything: each output must be a
/// new file or a plain file, in a directory that exists and can be written, and no output may
/// be one of the inputs or another output, however spelled (`./d.csv`, a symbolic or hard
/// link). `inputs` and `outputs` are `(option, path)`. An input `-` is standard input, which
/// clashes with an output that is the regular file redirected into it (`< a.urdf`); an output
/// `-` is standard output, and at most one output may be `-`. An existing output that is not a
/// regular file (a device node, a FIFO) is written in place later and needs no probe here; a
/// directory or a socket is refused.
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
        .map(|(_, p)| identity(p, true))
        .chain(outputs.iter().map(|(_, p)| identity(p, false)))
        .collect();
    for (k, (option, path)) in outputs.iter().enumerate() {
        let at = inputs.len() + k;
        let shown = escape(path);
        let target = (*path != STDIO).then(|| resolve_symlink(Path::new(path)));
        let kind = match &target {
            Some(t) => Some(destination(t, &format!("{option} {shown}"))?),
            None => None,
        };
        // Two outputs to one device (`--out /dev/null --plot /dev/null`) lose nothing.
        let special = matches!(kind, Some(Destination::Special));
        if let Some(id) = &ids[at] {
            let clash = ids[..at]
                .iter()
                .enumerate()
                .position(|(j, o)| o.as_ref() == Some(id) && (j < inputs.len() || !special));
            if let Some(j) = clash {
                let (other, kind) = if j < inputs.len() {
                    (inputs[j], "input")
                } else {
                    (outputs[j - inputs.len()], "output")
                };
                let found = if other.1 == STDIO {
                    format!("the file standard input reads ({} -)", other.0)
                } else {
                    format!("the {kind} {} {}", other.0, escape(other.1))
                };
                return Err(hinted(
                    format!("{option} {shown}: expected a file of its own, found {found}"),
                    "write each output to a new file: urdf-dh never writes over its inputs or one output over another",
                ));
            }
        }
        let (Some(target), Some(Destination::Regular)) = (target, kind) else {
            continue;
        };
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

    /// A standard output that fails: nothing of the run lands.
    struct FullOut;
    impl Write for FullOut {
        fn write(&mut self, _: &[u8]) -> std::io::Result<usize> {
            Err(std::io::Error::from_raw_os_error(28))
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn a_failed_standard_output_commits_no_file() {
        let dir = tempfile::tempdir().unwrap();
        let truth = dir.path().join("truth.yaml");
        let e = write_all_or_stdout(
            &[
                (Path::new(STDIO), b"data".as_slice()),
                (&truth, b"truth".as_slice()),
            ],
            &mut FullOut,
        )
        .unwrap_err();
        assert!(format!("{e:#}").starts_with("standard output: "), "{e:#}");
        assert!(entries(dir.path()).is_empty(), "{:?}", entries(dir.path()));
        // The report a command wrote before its files: flushed first, and its failure keeps
        // the files out.
        let mut buffered = std::io::BufWriter::new(FullOut);
        buffered.write_all(b"report").unwrap();
        let e = write_all_after(&mut buffered, &[(&truth, b"t".as_slice())]).unwrap_err();
        assert!(format!("{e:#}").starts_with("standard output: "), "{e:#}");
        assert!(entries(dir.path()).is_empty(), "{:?}", entries(dir.path()));
    }

    /// A FIFO and a private device node are written where they are, never replaced by a
    /// regular file; a socket is refused; a full device is an error naming it.
    #[cfg(unix)]
    #[test]
    fn special_files_are_written_in_place() {
        use std::os::unix::fs::FileTypeExt;
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("out.fifo");
        assert!(std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success());
        let reader = {
            let fifo = fifo.clone();
            std::thread::spawn(move || std::fs::read(fifo).unwrap())
        };
        write_all(&[(&fifo, b"through the pipe".as_slice())]).unwrap();
        assert_eq!(reader.join().unwrap(), b"through the pipe");
        assert!(std::fs::symlink_metadata(&fifo)
            .unwrap()
            .file_type()
            .is_fifo());
        check_destinations(&[], &[("--out", fifo.to_str().unwrap())]).unwrap();

        let socket = dir.path().join("s.sock");
        let _listener = std::os::unix::net::UnixListener::bind(&socket).unwrap();
        let e = write_all(&[(&socket, b"x".as_slice())]).unwrap_err();
        assert!(format!("{e:#}").contains("found a socket"), "{e:#}");
        let e = check_destinations(&[], &[("--out", socket.to_str().unwrap())]).unwrap_err();
        assert!(format!("{e:#}").contains("--out"), "{e:#}");

        // Device nodes need root (CAP_MKNOD): private ones, never the system's.
        let node = |name: &str, minor: &str| {
            let p = dir.path().join(name);
            std::process::Command::new("mknod")
                .arg(&p)
                .args(["c", "1", minor])
                .stderr(std::process::Stdio::null())
                .status()
                .is_ok_and(|s| s.success())
                .then_some(p)
        };
        let (Some(null), Some(full)) = (node("null", "3"), node("full", "7")) else {
            test_skips::skip("device nodes: mknod is not allowed here (not root)");
            return;
        };
        write_all(&[(&null, b"gone".as_slice())]).unwrap();
        assert!(std::fs::symlink_metadata(&null)
            .unwrap()
            .file_type()
            .is_char_device());
        // Two outputs on one device lose nothing; an input and an output on it still clash.
        let n = null.to_str().unwrap();
        check_destinations(&[], &[("--out", n), ("--plot", n)]).unwrap();
        assert!(check_destinations(&[("--data", n)], &[("--out", n)]).is_err());
        let plain = dir.path().join("plain.yaml");
        let e = write_all(&[(&plain, b"x".as_slice()), (&full, b"y".as_slice())]).unwrap_err();
        assert!(
            format!("{e:#}").contains("full: cannot write the output"),
            "{e:#}"
        );
        assert!(
            !plain.exists(),
            "a regular file landed though the device failed"
        );
        assert!(std::fs::symlink_metadata(&full)
            .unwrap()
            .file_type()
            .is_char_device());
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
