//! The crate's floors stay one way: a module names only its own folder, the
//! folders below it (in the order the crate docs declare, `src/lib.rs`,
//! "Floors, bottom to top") and `crate::error`; no source file grows past
//! 800 lines. Read from the source tree, so a new `use` that climbs a floor
//! or a new top-level module outside the order fails here.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// Longest source file (lines): a longer one holds several concerns.
const MAX_LINES: usize = 800;

/// The marker of the line in `src/lib.rs` that declares the floors.
const MARKER: &str = "Floors, bottom to top:";

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("src is readable") {
        let path = entry.expect("directory entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The floors in the order `src/lib.rs` declares them (`a → b → …`).
fn floors() -> Vec<String> {
    let lib = std::fs::read_to_string(src().join("lib.rs")).expect("lib.rs");
    let mut text = String::new();
    let mut open = false;
    for line in lib.lines() {
        let line = line.trim_start_matches("//!").trim();
        if line.contains(MARKER) {
            open = true;
            text.push_str(line.split(MARKER).nth(1).unwrap_or(""));
        } else if open {
            if line.is_empty() {
                break;
            }
            text.push(' ');
            text.push_str(line);
        }
    }
    assert!(open, "src/lib.rs declares no \"{MARKER}\" line");
    text.trim_end_matches('.')
        .split('→')
        .map(|f| {
            f.trim()
                .trim_matches('`')
                .trim_end_matches('/')
                .trim_end_matches(".rs")
                .to_string()
        })
        .collect()
}

/// The code of a file without comments and without its test modules (from
/// the first `#[cfg(test)]` on: tests may check a floor against a higher
/// one, as the SIMD copies against the algorithms).
fn code(text: &str) -> String {
    let mut out = String::new();
    for line in text.lines() {
        let t = line.trim_start();
        if t.starts_with("#[cfg(test)]") || t.starts_with("#[cfg(all(test") {
            break;
        }
        if t.starts_with("//") {
            continue;
        }
        out.push_str(line.split(" //").next().unwrap_or(""));
        out.push('\n');
    }
    out
}

/// Every `crate::name` the code names (the first segment after `crate::`,
/// and each item of a `crate::{a, b::c}` group).
fn crate_paths(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(i) = rest.find("crate::") {
        rest = &rest[i + "crate::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let end = group.find('}').unwrap_or(group.len());
            for item in group[..end].split(',') {
                let head: String = item
                    .trim()
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if !head.is_empty() {
                    out.push(head);
                }
            }
        } else {
            out.push(
                rest.chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect(),
            );
        }
    }
    out
}

/// The floor a file belongs to: its folder under `src/`, or its own name
/// for a top-level file.
fn floor_of(path: &Path) -> String {
    let rel = path.strip_prefix(src()).expect("under src");
    let first = rel.components().next().expect("a file").as_os_str();
    first.to_string_lossy().trim_end_matches(".rs").to_string()
}

#[test]
fn imports_run_one_way_across_the_floors() {
    let floors = floors();
    assert!(floors.len() >= 5, "floors read from lib.rs: {floors:?}");
    let rank = |f: &str| floors.iter().position(|x| x == f);
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    let mut wrong = Vec::new();
    for path in &files {
        let here = floor_of(path);
        if here == "lib" || here == "error" {
            continue;
        }
        let Some(mine) = rank(&here) else {
            wrong.push(format!(
                "{}: module '{here}' is not among the floors {floors:?}",
                path.display()
            ));
            continue;
        };
        let text = std::fs::read_to_string(path).expect("readable source");
        for name in crate_paths(&code(&text)) {
            if name == "error" || name == here {
                continue;
            }
            match rank(&name) {
                Some(theirs) if theirs < mine => {}
                Some(_) => wrong.push(format!(
                    "{}: floor '{here}' names 'crate::{name}', a floor above it",
                    path.display()
                )),
                None => wrong.push(format!(
                    "{}: 'crate::{name}' is no floor (name the module path, not a re-export)",
                    path.display()
                )),
            }
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

#[test]
fn every_top_level_module_is_a_declared_floor() {
    let floors: BTreeSet<String> = floors().into_iter().collect();
    let lib = std::fs::read_to_string(src().join("lib.rs")).expect("lib.rs");
    let mods: BTreeSet<String> = lib
        .lines()
        .filter_map(|l| l.trim().strip_prefix("mod "))
        .map(|m| m.trim_end_matches(';').to_string())
        .filter(|m| m != "error")
        .collect();
    assert_eq!(
        mods, floors,
        "the modules of lib.rs and its declared floors"
    );
}

#[test]
fn no_source_file_is_longer_than_800_lines() {
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    let long: Vec<String> = files
        .iter()
        .filter_map(|p| {
            let n = std::fs::read_to_string(p).ok()?.lines().count();
            (n > MAX_LINES).then(|| format!("{}: {n} lines", p.display()))
        })
        .collect();
    assert!(long.is_empty(), "{}", long.join("\n"));
}

/// The checks themselves: a climbing import and a grouped one are found,
/// comments and test modules are not read.
#[test]
fn the_checker_reads_paths_groups_and_skips_comments_and_tests() {
    let text = "use crate::forces::Forces;\n\
                use crate::{model::Model, error::DynamicsError};\n\
                /// [`crate::analysis`] in a doc comment\n\
                let x = crate::kernels::chol::f(); // crate::dispatch\n\
                #[cfg(test)]\n\
                mod tests { use crate::analysis::x; }\n";
    assert_eq!(
        crate_paths(&code(text)),
        ["forces", "model", "error", "kernels"]
    );
}
