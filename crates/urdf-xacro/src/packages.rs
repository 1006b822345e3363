//! `$(find PKG)`: the folder of a ROS package. Looked up, in order, in the `--package NAME=DIR`
//! pairs the caller gives, in the folders of `ROS_PACKAGE_PATH` (each walked recursively, the
//! first folder holding a `package.xml` whose `<name>` is PKG wins, and a package holds no
//! packages: rospack's rule), and in the `share/PKG` folders of `AMENT_PREFIX_PATH` (ROS 2's
//! install spaces). With an in-memory file tree ([`crate::Options::files`]) the environment is
//! not looked at: the tree's `package.xml` files are, then a folder of the tree named PKG.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use crate::files::Source;

/// Folders deeper than this below a `ROS_PACKAGE_PATH` entry are not searched.
const MAX_WALK_DEPTH: usize = 12;

/// Resolves package names, walking each `ROS_PACKAGE_PATH` folder at most once.
#[derive(Default)]
pub struct Packages {
    given: Vec<(String, PathBuf)>,
    walked: Option<HashMap<String, PathBuf>>,
    source: Source,
}

impl Packages {
    /// Resolution with the caller's `NAME=DIR` pairs first.
    pub fn new(given: &[(String, PathBuf)], source: Source) -> Packages {
        Packages {
            given: given.to_vec(),
            walked: None,
            source,
        }
    }

    /// The folder of package `name`.
    ///
    /// # Errors
    /// The package is found nowhere; the message says where it was looked for.
    pub fn find(&mut self, name: &str) -> Result<PathBuf, String> {
        if let Some((_, dir)) = self.given.iter().find(|(n, _)| n == name) {
            if let Source::Memory(_) = self.source {
                return Ok(dir.clone());
            }
            return Ok(absolute(dir));
        }
        if let Source::Memory(files) = &self.source {
            return in_memory(files, name).ok_or_else(|| {
                format!(
                    "package '{name}' not found (looked in the given package folders, the package.xml files and the folders of the files given)"
                )
            });
        }
        let ros = std::env::var_os("ROS_PACKAGE_PATH").unwrap_or_default();
        let walked = self.walked.get_or_insert_with(|| {
            let mut found = HashMap::new();
            for root in std::env::split_paths(&ros) {
                if !root.as_os_str().is_empty() {
                    walk(&root, 0, &mut found);
                }
            }
            found
        });
        if let Some(dir) = walked.get(name) {
            return Ok(absolute(dir));
        }
        let ament = std::env::var_os("AMENT_PREFIX_PATH").unwrap_or_default();
        for prefix in std::env::split_paths(&ament) {
            let share = prefix.join("share").join(name);
            if share.join("package.xml").is_file() {
                return Ok(absolute(&share));
            }
        }
        Err(format!(
            "package '{name}' not found (looked in the given package folders, ROS_PACKAGE_PATH and AMENT_PREFIX_PATH)"
        ))
    }
}

fn absolute(dir: &Path) -> PathBuf {
    std::path::absolute(dir).unwrap_or_else(|_| dir.to_path_buf())
}

/// The folder of package `name` in an in-memory tree: the folder of a `package.xml` naming it
/// (the shallowest), else the shallowest folder called `name`.
fn in_memory(files: &crate::files::MemoryFiles, name: &str) -> Option<PathBuf> {
    let shallowest = |dirs: Vec<PathBuf>| dirs.into_iter().min_by_key(|d| d.components().count());
    let manifests = files
        .iter()
        .filter(|(p, _)| p.file_name().is_some_and(|f| f == "package.xml"))
        .filter(|(_, text)| {
            std::str::from_utf8(text)
                .ok()
                .and_then(package_name)
                .is_some_and(|n| n == name)
        })
        .filter_map(|(p, _)| p.parent().map(Path::to_path_buf))
        .collect();
    if let Some(dir) = shallowest(manifests) {
        return Some(dir);
    }
    let named = files
        .keys()
        .filter_map(|p| {
            p.ancestors()
                .skip(1)
                .filter(|a| a.file_name().is_some_and(|f| f == name))
                .last()
                .map(Path::to_path_buf)
        })
        .collect();
    shallowest(named)
}

/// The `<name>` of a package.xml's text.
fn package_name(text: &str) -> Option<&str> {
    let start = text.find("<name>")? + "<name>".len();
    let end = start + text[start..].find("</name>")?;
    let name = text[start..end].trim();
    (!name.is_empty()).then_some(name)
}

fn walk(dir: &Path, depth: usize, found: &mut HashMap<String, PathBuf>) {
    let manifest = dir.join("package.xml");
    if manifest.is_file() {
        if let Some(name) = std::fs::read_to_string(&manifest)
            .ok()
            .as_deref()
            .and_then(package_name)
        {
            found
                .entry(name.to_string())
                .or_insert_with(|| dir.to_path_buf());
        }
        return;
    }
    if depth >= MAX_WALK_DEPTH {
        return;
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut subdirs: Vec<PathBuf> = entries
        .filter_map(Result::ok)
        .filter(|e| e.file_type().is_ok_and(|t| t.is_dir()))
        .filter(|e| !e.file_name().to_string_lossy().starts_with('.'))
        .map(|e| e.path())
        .collect();
    subdirs.sort();
    for sub in subdirs {
        walk(&sub, depth + 1, found);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_name_of_a_manifest() {
        assert_eq!(
            package_name("<package><name> my_pkg </name></package>"),
            Some("my_pkg")
        );
        assert_eq!(package_name("<package/>"), None);
    }

    #[test]
    fn given_packages_come_first() {
        let mut p = Packages::new(&[("arm".into(), PathBuf::from("/opt/arm"))], Source::Disk);
        assert_eq!(p.find("arm"), Ok(PathBuf::from("/opt/arm")));
    }

    #[test]
    fn finds_packages_in_memory_by_manifest_then_folder() {
        let mut files = crate::files::MemoryFiles::new();
        files.insert(
            "/drop/src/arm_pkg/package.xml".into(),
            b"<package><name>arm_description</name></package>".to_vec(),
        );
        files.insert("/drop/src/arm_pkg/urdf/arm.xacro".into(), Vec::new());
        files.insert("/drop/gripper/urdf/g.xacro".into(), Vec::new());
        let mut p = Packages::new(&[], Source::Memory(std::sync::Arc::new(files)));
        assert_eq!(
            p.find("arm_description"),
            Ok(PathBuf::from("/drop/src/arm_pkg"))
        );
        assert_eq!(p.find("gripper"), Ok(PathBuf::from("/drop/gripper")));
        let missing = p.find("base").unwrap_err();
        assert!(missing.contains("package 'base' not found"), "{missing}");
    }
}
