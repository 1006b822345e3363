//! The bytes of one input, read once: a file or standard input (`-`) opened a single time and
//! read up to a size cap, whatever it is (a regular file, a FIFO, a device node, a pipe).
//!
//! Two rules, for files and standard input alike:
//! - **A cap.** Text inputs (sheets, lists, robots, models, inertials) stop at
//!   [`MAX_TEXT_BYTES`]; data inputs (measurements, joint values) at [`MAX_DATA_BYTES`]. Reading
//!   stops one byte past the cap, so `- < /dev/zero` costs the cap, not the machine's memory.
//! - **One open.** A FIFO or standard input can be read once only: opening a FIFO a second time
//!   waits for a new writer (a hang), and standard input is empty after its first reader. Inside
//!   [`reading_once`] (every command of the CLI and the Python package runs inside one), the
//!   bytes of every input that is not a regular file are kept, so a second read of the same input
//!   (a model read for its sheet and again for its inertials) gets the same bytes without a second
//!   open. Regular files are read again: they can be; and only text inputs are kept (data
//!   inputs, up to [`MAX_DATA_BYTES`], are read once by every command).

use std::cell::RefCell;
use std::collections::HashMap;
use std::io::Read;
use std::rc::Rc;

use anyhow::{Context, Result};

use crate::error::hinted;

/// Largest text input, in bytes (64 MiB, the URDF reader's cap [`urdf_axes::MAX_URDF_BYTES`]):
/// a sheet, a chain list, a robot or model file, an inertials file. Real ones are at most a few
/// megabytes.
pub const MAX_TEXT_BYTES: usize = urdf_axes::MAX_URDF_BYTES;

/// Largest data input, in bytes (1 GiB): a measurement or joint-value file. The largest real
/// run measured here, 2 000 000 rows, is a 418 MB file.
pub const MAX_DATA_BYTES: usize = 1 << 30;

/// What one input is, for the rule of one open: standard input, or a special file (FIFO, device
/// node) by device and inode.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
enum Key {
    Stdin,
    #[cfg(unix)]
    Special(u64, u64),
}

thread_local! {
    /// The bytes of the special inputs read in the current [`reading_once`] scope; `None`
    /// outside one.
    static KEPT: RefCell<Option<HashMap<Key, Rc<Vec<u8>>>>> = const { RefCell::new(None) };
}

/// Runs `f` with the rule of one open for standard input and special files (see the module's
/// documentation): each is opened and read once in `f`, later reads get the same bytes. Scopes
/// nest (the outer one keeps the bytes); the bytes are dropped when the outermost scope ends.
pub fn reading_once<T>(f: impl FnOnce() -> T) -> T {
    let outer = KEPT.with(|k| {
        let mut k = k.borrow_mut();
        let outer = k.is_some();
        if !outer {
            *k = Some(HashMap::new());
        }
        outer
    });
    // Dropped on return or unwind: the outermost scope clears what it kept.
    struct Clear(bool);
    impl Drop for Clear {
        fn drop(&mut self) {
            if !self.0 {
                KEPT.with(|k| *k.borrow_mut() = None);
            }
        }
    }
    let _clear = Clear(outer);
    f()
}

/// The key of `path` if it is an input read once only: standard input (`-`), or an existing
/// file that is not a regular file (looked at with `stat`, which does not open it).
fn key_of(path: &str) -> Option<Key> {
    if path == "-" {
        return Some(Key::Stdin);
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        let m = std::fs::metadata(path).ok()?;
        if !m.is_file() && !m.is_dir() {
            return Some(Key::Special(m.dev(), m.ino()));
        }
    }
    None
}

/// Why an input was refused for its size: what the caller names in its own error.
#[derive(Debug)]
pub struct TooLarge {
    /// The file's size where it is known (a regular file), else `None` (a pipe, a device).
    pub size: Option<usize>,
    /// The cap.
    pub limit: usize,
}

/// Reads `path` (`-`: standard input) once, to at most `limit` bytes: `Ok(Err(TooLarge))` when
/// there is more. Inside [`reading_once`], a second read of standard input or of the same
/// special file returns the bytes of the first.
///
/// # Errors
/// The file cannot be opened or read: the message names it (`standard input` for `-`).
pub fn read_capped(path: &str, limit: usize) -> Result<std::result::Result<Vec<u8>, TooLarge>> {
    let key = key_of(path);
    if let Some(key) = &key {
        let kept = KEPT.with(|k| k.borrow().as_ref().and_then(|m| m.get(key).cloned()));
        if let Some(bytes) = kept {
            return Ok(capped(bytes.as_ref().clone(), None, limit));
        }
    }
    let (bytes, size) = if path == "-" {
        let mut buf = Vec::new();
        std::io::stdin()
            .lock()
            .take(limit as u64 + 1)
            .read_to_end(&mut buf)
            .context("standard input: cannot read it")?;
        (buf, None)
    } else {
        // Quoted (escaped, cut): a path of 10^8 characters makes a message of a few hundred.
        read_opened(path, limit)
            .with_context(|| format!("{}: cannot read the file", crate::text::quote(path)))?
    };
    // Only text inputs are kept: they are the ones a command looks at twice (a model read for
    // its kind, then as a model). A data input is read once, and keeping a copy would double
    // the memory of a measurement file piped in.
    if let Some(key) = key.filter(|_| limit <= MAX_TEXT_BYTES) {
        KEPT.with(|k| {
            if let Some(m) = k.borrow_mut().as_mut() {
                m.insert(key, Rc::new(bytes.clone()));
            }
        });
    }
    Ok(capped(bytes, size, limit))
}

fn capped(
    bytes: Vec<u8>,
    size: Option<usize>,
    limit: usize,
) -> std::result::Result<Vec<u8>, TooLarge> {
    if bytes.len() > limit {
        Err(TooLarge {
            size: size.filter(|&s| s > limit),
            limit,
        })
    } else {
        Ok(bytes)
    }
}

/// Opens `path` once and reads at most `limit + 1` bytes of it (a regular file of at least
/// [`PARALLEL_READ_BYTES`] in parts on every core): the bytes and the file's size when it is a
/// regular file.
fn read_opened(path: &str, limit: usize) -> std::io::Result<(Vec<u8>, Option<usize>)> {
    let file = std::fs::File::open(path)?;
    let meta = file.metadata()?;
    if meta.is_dir() {
        return Err(std::io::Error::other("expected a file, found a directory"));
    }
    let size = meta
        .is_file()
        .then(|| usize::try_from(meta.len()).ok())
        .flatten();
    if let Some(len) = size.filter(|&l| l <= limit) {
        if let Some(bytes) = read_in_parts(&file, len, PARALLEL_READ_BYTES)? {
            return Ok((bytes, size));
        }
    }
    let mut buf = Vec::with_capacity(size.map_or(0, |s| s.min(limit) + 1));
    (&file).take(limit as u64 + 1).read_to_end(&mut buf)?;
    Ok((buf, size))
}

/// Files of at least this many bytes are read in as many parts as there are cores, each part
/// by its own thread (a 418 MB measurement file: the kernel's copy and the new pages' zeroing
/// took 0.6 s on one thread).
const PARALLEL_READ_BYTES: usize = 64 << 20;

/// The whole regular file `file` of `len` bytes read in parts on every core when `len` is at
/// least `parallel_from` (and the machine has more than one core); `None` otherwise, or when
/// the file shrank while it was read (the caller then reads it as it is now).
fn read_in_parts(
    file: &std::fs::File,
    len: usize,
    parallel_from: usize,
) -> std::io::Result<Option<Vec<u8>>> {
    #[cfg(unix)]
    {
        use std::io::{Seek, SeekFrom};
        use std::os::unix::fs::FileExt;
        // The size first: asking for the cores reads the cgroup files (a dozen system calls, a
        // third of a small extract's system time).
        if len < parallel_from {
            return Ok(None);
        }
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
        if threads < 2 {
            return Ok(None);
        }
        let mut bytes = vec![0u8; len];
        let part = len.div_ceil(threads);
        let parts: Vec<std::io::Result<()>> = std::thread::scope(|scope| {
            let readers: Vec<_> = bytes
                .chunks_mut(part)
                .enumerate()
                .map(|(k, piece)| scope.spawn(move || file.read_exact_at(piece, (k * part) as u64)))
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
                let mut f = file;
                f.seek(SeekFrom::Start(len as u64))?;
                f.read_to_end(&mut bytes)?;
                Ok(Some(bytes))
            }
            // The file shrank while it was read: read it again as it is now.
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => {
                let mut f = file;
                f.seek(SeekFrom::Start(0))?;
                Ok(None)
            }
            Err(e) => Err(e),
        }
    }
    #[cfg(not(unix))]
    {
        let _ = (file, len, parallel_from);
        Ok(None)
    }
}

/// [`read_capped`] with the cap's refusal as an error naming the input (`shown`) and what it was
/// read as (`what`: "a DH sheet", "measurements").
///
/// # Errors
/// As [`read_capped`]; more than `limit` bytes.
pub fn read_within(path: &str, shown: &str, limit: usize, what: &str) -> Result<Vec<u8>> {
    read_capped(path, limit)?.map_err(|t| too_large(shown, &t, what))
}

/// The error of an input beyond its cap.
pub fn too_large(shown: &str, t: &TooLarge, what: &str) -> anyhow::Error {
    let found = match t.size {
        Some(s) => format!("{s} bytes"),
        None => "more (reading stopped there)".to_string(),
    };
    hinted(
        format!(
            "{shown}: expected {what} of at most {} bytes ({} MiB), found {found}",
            t.limit,
            t.limit >> 20
        ),
        "is it the right file? /dev/zero, a disk image or a log given by mistake reads as an endless input",
    )
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
        for from in [1, 1_000_003, 1_000_004] {
            let file = std::fs::File::open(&path).expect("opened");
            let got = read_in_parts(&file, bytes.len(), from).expect("read");
            if from <= bytes.len()
                && std::thread::available_parallelism().map_or(1, |n| n.get()) > 1
            {
                assert_eq!(got.as_deref(), Some(bytes.as_slice()), "from {from} bytes");
            } else {
                assert!(got.is_none(), "from {from} bytes");
            }
        }
        let p = path.to_str().expect("UTF-8");
        assert_eq!(
            read_capped(p, 2_000_000).expect("read").expect("within"),
            bytes
        );
        let t = read_capped(p, 1000)
            .expect("read")
            .expect_err("beyond the cap");
        assert_eq!((t.size, t.limit), (Some(1_000_003), 1000));
        let missing = dir.path().join("missing.csv");
        assert!(read_capped(missing.to_str().expect("UTF-8"), 10).is_err());
        let e = read_capped(dir.path().to_str().expect("UTF-8"), 10).unwrap_err();
        assert!(format!("{e:#}").contains("found a directory"), "{e:#}");
    }

    /// A FIFO is opened once and read once in a scope: the second read gets the first's bytes
    /// (a second open would wait for a writer that never comes), and reading stops at the cap.
    #[cfg(unix)]
    #[test]
    fn a_fifo_is_opened_once_and_capped() {
        let dir = tempfile::tempdir().expect("a directory");
        let fifo = dir.path().join("sheet.fifo");
        let status = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .expect("mkfifo runs");
        assert!(status.success());
        let path = fifo.to_str().expect("UTF-8").to_string();
        let writer = {
            let fifo = fifo.clone();
            std::thread::spawn(move || std::fs::write(fifo, b"robot: x\n").expect("written"))
        };
        let (first, second) = reading_once(|| {
            let a = read_capped(&path, 100).expect("read").expect("within");
            let b = read_capped(&path, 100)
                .expect("read again")
                .expect("within");
            (a, b)
        });
        writer.join().expect("the writer ends");
        assert_eq!(first, b"robot: x\n");
        assert_eq!(second, first);
        // An endless writer: reading stops one byte past the cap.
        let writer = {
            let fifo = fifo.clone();
            std::thread::spawn(move || {
                use std::io::Write;
                let mut f = std::fs::OpenOptions::new()
                    .write(true)
                    .open(fifo)
                    .expect("opened");
                let chunk = [b'x'; 4096];
                // Ends when the reader closes its end (a broken pipe).
                while f.write_all(&chunk).is_ok() {}
            })
        };
        let t = read_capped(&path, 10_000)
            .expect("read")
            .expect_err("beyond the cap");
        assert_eq!((t.size, t.limit), (None, 10_000));
        writer.join().expect("the writer ends");
    }
}
