//! The READMEs' non-Rust code blocks run as pasted: every TOML block is
//! TOML, every scene among them reads without error and without warning and
//! builds a model, the Cargo dependency line names the facade, and every
//! repository path a shell block names exists. (The Rust blocks are
//! doctests: `src/lib.rs` includes the top-level README, each crate its own;
//! the Python blocks run in `crates/softrod-py/tests/test_readme.py`.)

use std::path::{Path, PathBuf};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Every README a user reads: the repository's and each crate's.
fn readmes() -> Vec<PathBuf> {
    let mut files = vec![repo().join("README.md")];
    let mut crates: Vec<_> = std::fs::read_dir(repo().join("crates"))
        .unwrap()
        .map(|e| e.unwrap().path().join("README.md"))
        .filter(|p| p.exists())
        .collect();
    crates.sort();
    files.extend(crates);
    files
}

/// The fenced blocks of `text` whose info string starts with `lang`, with
/// their first line number.
fn blocks(text: &str, lang: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut current: Option<(usize, String)> = None;
    for (i, line) in text.lines().enumerate() {
        if let Some(info) = line.strip_prefix("```") {
            match current.take() {
                Some(block) => out.push(block),
                None if info.split(',').next() == Some(lang) => {
                    current = Some((i + 2, String::new()))
                }
                None => current = Some((0, String::new())), // another language: skipped
            }
        } else if let Some((_, body)) = current.as_mut() {
            body.push_str(line);
            body.push('\n');
        }
    }
    out.into_iter().filter(|(line, _)| *line > 0).collect()
}

#[test]
fn toml_blocks_are_toml_and_scenes_build_without_warnings() {
    let mut scenes = 0;
    let mut cargo = 0;
    for file in readmes() {
        let text = std::fs::read_to_string(&file).unwrap();
        for (line, block) in blocks(&text, "toml") {
            let at = format!("{}:{line}", file.display());
            let value: toml::Table = toml::from_str(&block).unwrap_or_else(|e| panic!("{at}: {e}"));
            if value.contains_key("rod") {
                let (scene, warnings) = softrod_scene::Scene::from_str(&block, &at)
                    .unwrap_or_else(|e| panic!("{at}: {e}"));
                assert!(warnings.is_empty(), "{at}: {warnings:?}");
                scene.build().unwrap_or_else(|e| panic!("{at}: {e}"));
                scenes += 1;
            } else {
                let dep = &value["dependencies"]["softrod"];
                assert!(
                    dep.get("git").is_some() || dep.get("path").is_some(),
                    "{at}"
                );
                cargo += 1;
            }
        }
    }
    // The README's scene in one minute, the CLI README's arm.toml; the
    // README's dependency line.
    assert!(
        scenes >= 2 && cargo >= 1,
        "{scenes} scenes, {cargo} Cargo blocks"
    );
}

#[test]
fn paths_in_shell_blocks_exist() {
    for file in readmes() {
        let text = std::fs::read_to_string(&file).unwrap();
        for (line, block) in blocks(&text, "sh") {
            for word in block.split_whitespace() {
                let word = word.trim_matches(|c: char| "`'\"(),;".contains(c));
                let named = ["examples/", "scripts/", "crates/"]
                    .iter()
                    .any(|p| word.starts_with(p));
                if named && !word.contains('*') {
                    assert!(
                        repo().join(word).exists(),
                        "{}:{line}: {word} does not exist",
                        file.display()
                    );
                }
            }
        }
    }
}
