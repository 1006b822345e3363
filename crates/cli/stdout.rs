//! Standard output as an output like any other: its write errors name it, and a standard output
//! the shell closed (`>&-`) is an error, not a place where results vanish.
//!
//! Rust's runtime reopens a closed descriptor 0, 1 or 2 on `/dev/null` before `main` (so that
//! no file the program opens lands on it); every write would then "succeed". [`was_closed`]
//! tells that case from a shell's `> /dev/null`: the runtime opens `/dev/null` read-write, a
//! shell's redirection opens it write-only.

use std::io::Write;

use dh_workflows::output::StdoutError;

/// The process's standard output, for [`crate::cli::run`]: write errors carry the words
/// "standard output" (their kind kept, so a closed pipe still ends the run quietly), and a
/// standard output that was closed refuses every write.
pub struct Stdout<W> {
    inner: W,
    closed: bool,
}

impl<W: Write> Stdout<W> {
    /// Wraps `inner`, refusing writes when `closed` (see [`was_closed`]).
    pub fn new(inner: W, closed: bool) -> Self {
        Stdout { inner, closed }
    }

    fn refuse(&self) -> std::io::Error {
        std::io::Error::other(StdoutError(
            "standard output is closed (the shell's >&-), so the output would be lost; redirect it to a file or /dev/null".to_string(),
        ))
    }
}

fn named(e: std::io::Error) -> std::io::Error {
    std::io::Error::new(e.kind(), StdoutError(format!("standard output: {e}")))
}

impl<W: Write> Write for Stdout<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if self.closed && !buf.is_empty() {
            return Err(self.refuse());
        }
        self.inner.write(buf).map_err(named)
    }

    fn write_all(&mut self, buf: &[u8]) -> std::io::Result<()> {
        if self.closed && !buf.is_empty() {
            return Err(self.refuse());
        }
        self.inner.write_all(buf).map_err(named)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush().map_err(named)
    }
}

/// Whether this process's standard output was closed when it started (Linux: descriptor 1 is
/// `/dev/null` opened read-write, as only Rust's runtime opens it; elsewhere `false`).
pub fn was_closed() -> bool {
    #[cfg(target_os = "linux")]
    {
        use std::os::fd::AsFd;
        use std::os::unix::fs::{FileTypeExt, MetadataExt};
        /// /dev/null's device number, makedev(1, 3), fixed by Linux's devices.txt.
        const DEV_NULL: u64 = (1 << 8) | 3;
        // One fstat for every run; /proc is read only when standard output is /dev/null.
        let Ok(fd) = std::io::stdout().as_fd().try_clone_to_owned() else {
            return true;
        };
        let Ok(out) = std::fs::File::from(fd).metadata() else {
            return false;
        };
        if !out.file_type().is_char_device() || out.rdev() != DEV_NULL {
            return false;
        }
        let Ok(info) = std::fs::read_to_string("/proc/self/fdinfo/1") else {
            return false;
        };
        let flags = info
            .lines()
            .find_map(|l| l.strip_prefix("flags:"))
            .and_then(|f| u32::from_str_radix(f.trim(), 8).ok());
        // O_ACCMODE = 3, O_RDWR = 2.
        flags.is_some_and(|f| f & 3 == 2)
    }
    #[cfg(not(target_os = "linux"))]
    {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Full;
    impl Write for Full {
        fn write(&mut self, _: &[u8]) -> std::io::Result<usize> {
            Err(std::io::Error::from_raw_os_error(28))
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn errors_name_standard_output_and_keep_their_kind() {
        let mut out = Stdout::new(Full, false);
        let e = out.write_all(b"x").unwrap_err();
        assert!(e.to_string().starts_with("standard output: "), "{e}");
        assert_eq!(e.kind(), std::io::ErrorKind::StorageFull);
        let mut closed = Stdout::new(Vec::new(), true);
        assert!(
            closed.write_all(b"").is_ok(),
            "nothing written, nothing lost"
        );
        let e = closed.write_all(b"table").unwrap_err();
        assert!(e.to_string().contains(">&-"), "{e}");
    }
}
