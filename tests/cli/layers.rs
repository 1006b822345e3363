//! The faces (the command line `crates/cli`, the Python package `crates/python`, the web page's
//! bindings `crates/wasm`) call one library layer, `dh-workflows` (issue 32 §5): none names
//! `dh_core`, `dh_calib`, `urdf_axes` or `urdf_xacro` in its code, and none has those crates
//! among its `[dependencies]` (dev-dependencies of the end-to-end tests may). A type a face
//! needs is re-exported by `dh_workflows` (`geometry`, `fit`, beside its workflow); a domain
//! function belongs in `dh_workflows`. Each failure names the file and line.

use std::path::{Path, PathBuf};

/// The crates below the faces' layer, as Rust paths and as package names.
const BELOW: [(&str, &str); 4] = [
    ("dh_core", "dh-core"),
    ("dh_calib", "dh-calib"),
    ("urdf_axes", "urdf-axes"),
    ("urdf_xacro", "urdf-xacro"),
];

/// The Rust sources of the faces (relative to the workspace root) and their manifests.
const FACE_SOURCES: [&str; 3] = ["crates/cli", "crates/python/src", "crates/wasm/src"];
const FACE_MANIFESTS: [&str; 3] = [
    "Cargo.toml",
    "crates/python/Cargo.toml",
    "crates/wasm/Cargo.toml",
];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every `.rs` file under `dir`, sorted.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

/// Whether `word` occurs in `code` as a whole identifier.
fn has_identifier(code: &str, word: &str) -> bool {
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    code.match_indices(word).any(|(i, _)| {
        let before = code[..i].chars().next_back();
        let after = code[i + word.len()..].chars().next();
        !before.is_some_and(ident) && !after.is_some_and(ident)
    })
}

/// The (line number, crate) of each direct use in a Rust source: the crate's name as an
/// identifier in code (comments, doc comments included, are not code).
fn direct_uses(text: &str) -> Vec<(usize, &'static str)> {
    let mut found = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let trimmed = line.trim_start();
        if trimmed.starts_with("//") {
            continue;
        }
        // A trailing comment (code, then ` // ...`).
        let code = line.split(" //").next().unwrap_or(line);
        for (krate, _) in BELOW {
            if has_identifier(code, krate) {
                found.push((k + 1, krate));
            }
        }
    }
    found
}

/// The (line number, package) of each dependency on a crate below the layer in a manifest's
/// `[dependencies]` (and target-specific dependencies), dev- and build-dependencies aside.
fn manifest_dependencies(text: &str) -> Vec<(usize, &'static str)> {
    let mut found = Vec::new();
    let mut in_dependencies = false;
    for (k, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.starts_with('[') {
            let header = line.trim_matches(|c| c == '[' || c == ']');
            // `[dependencies]`, `[target.'cfg(...)'.dependencies]`, `[dependencies.dh-core]`.
            let last = header.rsplit('.').next().unwrap_or("");
            // (`[workspace.dependencies]` only declares versions: not a dependency.)
            let dependencies = header == "dependencies"
                || (header.starts_with("target.") && header.ends_with(".dependencies"))
                || header.starts_with("dependencies.");
            in_dependencies = dependencies;
            if header.starts_with("dependencies.") {
                for (_, package) in BELOW {
                    if last == package {
                        found.push((k + 1, package));
                    }
                }
            }
            continue;
        }
        if !in_dependencies {
            continue;
        }
        let key = line.split(['=', '.']).next().unwrap_or("").trim();
        for (_, package) in BELOW {
            if key == package {
                found.push((k + 1, package));
            }
        }
    }
    found
}

#[test]
fn faces_call_only_dh_workflows() {
    let root = root();
    let mut problems = Vec::new();
    for dir in FACE_SOURCES {
        let files = rust_files(&root.join(dir));
        assert!(!files.is_empty(), "{dir}: no Rust sources found");
        for file in files {
            let text = std::fs::read_to_string(&file).unwrap();
            let shown = file.strip_prefix(&root).unwrap_or(&file).display();
            for (line, krate) in direct_uses(&text) {
                problems.push(format!(
                    "{shown}:{line}: names {krate} (use dh_workflows: its geometry, fit, or the workflow's module)"
                ));
            }
        }
    }
    for manifest in FACE_MANIFESTS {
        let text = std::fs::read_to_string(root.join(manifest)).unwrap();
        for (line, package) in manifest_dependencies(&text) {
            problems.push(format!(
                "{manifest}:{line}: depends on {package} (a face depends on dh-workflows only)"
            ));
        }
    }
    assert!(
        problems.is_empty(),
        "the faces reach past dh-workflows:\n{}",
        problems.join("\n")
    );
}

/// The scanners see what they must and only that, so the test above can fail.
#[test]
fn the_scanners_find_direct_uses_and_skip_comments() {
    let code = "//! see `dh_core::DhTable`\nuse dh_core::Tolerance;\nlet t = dh_calib::csv::X; // dh_core::y\nuse my_dh_core::Z;\nfn f(x: urdf_axes::Chain) {}\n";
    assert_eq!(
        direct_uses(code),
        vec![(2, "dh_core"), (3, "dh_calib"), (5, "urdf_axes")]
    );
    let manifest = "[workspace.dependencies]\ndh-core = \"1\"\n[dependencies]\ndh-workflows = { path = \"a\" }\ndh-core = { path = \"b\" }\nurdf-axes.workspace = true\n\n[dev-dependencies]\ndh-calib.workspace = true\n\n[dependencies.urdf-xacro]\npath = \"c\"\n";
    assert_eq!(
        manifest_dependencies(manifest),
        vec![(5, "dh-core"), (6, "urdf-axes"), (11, "urdf-xacro")]
    );
}
