//! The documentation a newcomer reads first stays true to the code and the repository:
//!
//! * every property of the scene's JSON Schema (`fracture schema`, walked through its
//!   definitions and variants) and every name of its enumerations is documented in
//!   `docs/scenes.md`;
//! * no tracked file points at the design folder that lives outside the repository (a
//!   clone does not have it): the in-repository pages replace it;
//! * the README's first screen (80 lines) holds the two commands and a picture that exists.
//!
//! This test lives in `fracture-api`, the lightest crate that owns the schema, so running it
//! builds no solver, server or browser driver.
#![allow(clippy::unwrap_used, missing_docs)]

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use fracture_api::Scene;
use serde_json::Value;

/// The repository root. `DOCS_TEST_ROOT` points the checks at another checkout, e.g. a
/// worktree of an older commit, to see what they report there.
fn repo() -> PathBuf {
    if let Some(root) = std::env::var_os("DOCS_TEST_ROOT") {
        return PathBuf::from(root);
    }
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf()
}

fn read(rel: &str) -> String {
    let path = repo().join(rel);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Walks a schema: the keys of every `properties` object go to `props`, every string of an
/// `enum` and every `const` to `names`.
fn walk(v: &Value, props: &mut BTreeSet<String>, names: &mut BTreeSet<String>) {
    match v {
        Value::Object(map) => {
            if let Some(Value::Object(p)) = map.get("properties") {
                props.extend(p.keys().cloned());
            }
            if let Some(Value::Array(e)) = map.get("enum") {
                names.extend(e.iter().filter_map(|s| s.as_str().map(str::to_string)));
            }
            if let Some(Value::String(c)) = map.get("const") {
                names.insert(c.clone());
            }
            for child in map.values() {
                walk(child, props, names);
            }
        }
        Value::Array(items) => {
            for child in items {
                walk(child, props, names);
            }
        }
        _ => {}
    }
}

/// Whether `doc` names `name` in code: `` `name` `` or the end of a path, `` `a.b.name` ``
/// (also `` `a[].name` ``), or a quoted JSON value, `` `"name"` ``.
fn documented(doc: &str, name: &str) -> bool {
    doc.contains(&format!("`{name}`"))
        || doc.contains(&format!(".{name}`"))
        || doc.contains(&format!("`\"{name}\"`"))
}

#[test]
fn every_scene_field_is_documented_in_the_scene_guide() {
    let schema = Scene::json_schema();
    let (mut props, mut names) = (BTreeSet::new(), BTreeSet::new());
    walk(&schema, &mut props, &mut names);
    // The walk itself: fields from the top, a definition, a tagged and an untagged variant.
    for known in [
        "grid",
        "cell_size",
        "toughness",
        "friction",
        "radius",
        "coefficient",
    ] {
        assert!(props.contains(known), "the schema walk missed `{known}`");
    }
    assert!(names.contains("plane_strain") && names.contains("equation_of_motion"));

    let doc = read("docs/scenes.md");
    let missing: Vec<String> = props
        .iter()
        .filter(|p| !documented(&doc, p))
        .map(|p| format!("property `{p}`"))
        .chain(
            names
                .iter()
                .filter(|n| !documented(&doc, n))
                .map(|n| format!("value \"{n}\"")),
        )
        .collect();
    assert!(
        missing.is_empty(),
        "docs/scenes.md does not document these scene schema names (write each as `name`, \
         `path.name` or `\"value\"`):\n  {}",
        missing.join("\n  ")
    );
}

/// The files the repository tracks (`git ls-files`), or every file outside `target/` and
/// `.git/` where git is not available.
fn tracked_files() -> Vec<PathBuf> {
    let root = repo();
    if let Ok(out) = std::process::Command::new("git")
        .arg("ls-files")
        .current_dir(&root)
        .output()
        && out.status.success()
    {
        return String::from_utf8_lossy(&out.stdout)
            .lines()
            .map(|l| root.join(l))
            .collect();
    }
    let mut files = Vec::new();
    let mut stack = vec![root.clone()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap().flatten() {
            let path = entry.path();
            let name = entry.file_name();
            if path.is_dir() {
                if name != "target" && name != ".git" && name != "node_modules" {
                    stack.push(path);
                }
            } else {
                files.push(path);
            }
        }
    }
    files
}

/// Text files a reader or a build sees: sources, pages, manifests, CI and scripts.
fn is_text_source(rel: &str) -> bool {
    const EXT: [&str; 11] = [
        "md", "rs", "js", "mjs", "html", "css", "toml", "py", "sh", "json", "yml",
    ];
    let ext = Path::new(rel).extension().and_then(|e| e.to_str());
    ext.is_some_and(|e| EXT.contains(&e))
        || rel == ".ci/run"
        || rel.starts_with("scripts/")
        || rel.starts_with(".ci/")
}

#[test]
fn no_file_points_at_the_design_folder_outside_the_repository() {
    // Built at run time, so this file does not match itself.
    let folder = ["sha", "red"].concat();
    let needles = [format!("../{folder}"), format!("{folder}/design")];
    let root = repo();
    let mut hits = Vec::new();
    for path in tracked_files() {
        let rel = path
            .strip_prefix(&root)
            .unwrap_or(&path)
            .to_string_lossy()
            .replace('\\', "/");
        if !is_text_source(&rel) {
            continue;
        }
        let Ok(text) = std::fs::read_to_string(&path) else {
            continue; // deleted in the work tree, or not UTF-8
        };
        for (n, line) in text.lines().enumerate() {
            if needles.iter().any(|s| line.contains(s.as_str())) {
                hits.push(format!("{rel}:{}: {}", n + 1, line.trim()));
            }
        }
    }
    assert!(
        hits.is_empty(),
        "these lines point at a folder a clone does not have; point them at the pages in \
         docs/ instead (docs/architecture.md, docs/scenes.md, docs/solver.md, \
         docs/run-output.md):\n  {}",
        hits.join("\n  ")
    );
}

#[test]
fn the_readme_first_screen_has_the_two_commands_and_a_picture() {
    let readme = read("README.md");
    let first: Vec<&str> = readme.lines().take(80).collect();
    for command in ["cargo run --release", "cargo test --workspace"] {
        let found = first.iter().any(|l| {
            l.trim_start()
                .strip_prefix(command)
                .is_some_and(|rest| rest.is_empty() || rest.starts_with(char::is_whitespace))
                && !l.contains("--release --") // `cargo run --release -- run …` is another one
        });
        assert!(
            found,
            "README.md: the first 80 lines should hold the command `{command}` on a line of \
             its own"
        );
    }
    // Markdown images `![alt](path)` and HTML `<img src="path">` in the first screen.
    let mut images = Vec::new();
    for line in &first {
        let mut rest = *line;
        while let Some(i) = rest.find("![") {
            rest = &rest[i + 2..];
            if let Some(j) = rest.find("](")
                && let Some(k) = rest[j + 2..].find(')')
            {
                let target = &rest[j + 2..j + 2 + k];
                images.push(target.split_whitespace().next().unwrap_or("").to_string());
            }
        }
        if let Some(i) = line.find("<img")
            && let Some(j) = line[i..].find("src=\"")
        {
            let target = &line[i + j + 5..];
            if let Some(k) = target.find('"') {
                images.push(target[..k].to_string());
            }
        }
    }
    let local: Vec<&String> = images
        .iter()
        .filter(|p| !p.contains("://") && !p.is_empty())
        .collect();
    assert!(
        !local.is_empty(),
        "README.md: the first 80 lines should show a picture the project makes (found: {images:?})"
    );
    for p in &local {
        assert!(
            repo().join(p).is_file(),
            "README.md shows {p}, which is not a file in the repository"
        );
    }
}
