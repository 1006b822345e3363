//! Where an expansion reads its files: the disk, or an in-memory tree the caller gives
//! ([`crate::Options::files`]: the files a person dropped on the web page, where there is no
//! disk). In memory, paths are compared after lexical normalisation (`a/./b/../c` is `a/c`),
//! since there is no file system to canonicalise them.

use std::collections::BTreeMap;
use std::path::{Component, Path, PathBuf};
use std::sync::Arc;

/// Files by path, their contents as bytes: an in-memory folder tree.
pub type MemoryFiles = BTreeMap<PathBuf, Vec<u8>>;

/// The files an expansion reads.
#[derive(Clone, Debug, Default)]
pub enum Source {
    /// The file system.
    #[default]
    Disk,
    /// Only the given files; nothing is read from the disk or the environment.
    Memory(Arc<MemoryFiles>),
}

/// `path` with `.` dropped and `..` applied to the component before it.
pub fn normalize(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                if !out.pop() {
                    out.push("..");
                }
            }
            other => out.push(other.as_os_str()),
        }
    }
    out
}

impl Source {
    /// The bytes of the file at `path`.
    ///
    /// # Errors
    /// The file cannot be read (in memory: it was not given).
    pub fn read(&self, path: &Path, limit: usize) -> Result<Vec<u8>, String> {
        match self {
            Source::Disk => {
                use std::io::Read;
                let f = std::fs::File::open(path).map_err(|e| e.to_string())?;
                let mut bytes = Vec::new();
                f.take(limit as u64 + 1)
                    .read_to_end(&mut bytes)
                    .map_err(|e| e.to_string())?;
                Ok(bytes)
            }
            Source::Memory(files) => files
                .get(&normalize(path))
                .cloned()
                .ok_or_else(|| "no such file among the files given".to_string()),
        }
    }

    /// Whether `path` is a file.
    pub fn is_file(&self, path: &Path) -> bool {
        match self {
            Source::Disk => path.is_file(),
            Source::Memory(files) => files.contains_key(&normalize(path)),
        }
    }

    /// The path that names `path`'s file alone (for include cycles).
    pub fn canonical(&self, path: &Path) -> PathBuf {
        match self {
            Source::Disk => std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf()),
            Source::Memory(_) => normalize(path),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalizes_lexically() {
        assert_eq!(normalize(Path::new("/a/./b/../c")), PathBuf::from("/a/c"));
        assert_eq!(normalize(Path::new("a/../../b")), PathBuf::from("../b"));
    }

    #[test]
    fn reads_only_the_given_files() {
        let mut files = MemoryFiles::new();
        files.insert(PathBuf::from("/p/urdf/a.xacro"), b"<robot/>".to_vec());
        let s = Source::Memory(Arc::new(files));
        assert_eq!(
            s.read(Path::new("/p/x/../urdf/a.xacro"), 100),
            Ok(b"<robot/>".to_vec())
        );
        assert!(s.is_file(Path::new("/p/urdf/./a.xacro")));
        assert!(s.read(Path::new("/p/urdf/b.xacro"), 100).is_err());
    }
}
