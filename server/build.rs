//! Build facts for `GET /api/v1/version`: the git commit (`FRACTURE_GIT_COMMIT` if the
//! builder sets it, else `git rev-parse HEAD` when the sources are a git checkout) and the
//! Cargo profile. Nothing fails when git is missing: the commit is then unknown.
//!
//! Also the list of the repository's guides (`docs/*.md`, not the figures under `docs/`'s
//! folders) that `GET /docs/{name}.md` serves: `$OUT_DIR/docs.rs`, one `include_str!` each.

include!("../build-support/build_facts.rs");

fn main() {
    emit_build_facts();
    embed_docs();
}

/// Writes `$OUT_DIR/docs.rs`: `pub static DOCS: &[(&str, &str)]`, (file name without
/// `.md`, text) sorted by name. A missing `docs/` gives an empty list.
fn embed_docs() {
    use std::fmt::Write as _;
    let manifest = std::env::var("CARGO_MANIFEST_DIR").unwrap_or_else(|_| ".".into());
    let dir = std::path::Path::new(&manifest).join("../docs");
    // a directory: cargo reruns this script when any file in it changes or is added
    println!("cargo:rerun-if-changed={}", dir.display());
    let mut names: Vec<(String, std::path::PathBuf)> = std::fs::read_dir(&dir)
        .map(|rd| {
            rd.filter_map(Result::ok)
                .map(|e| e.path())
                .filter(|p| p.is_file() && p.extension().is_some_and(|x| x == "md"))
                .filter_map(|p| {
                    let stem = p.file_stem()?.to_str()?.to_string();
                    let ok = stem
                        .chars()
                        .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
                    ok.then_some((stem, p.canonicalize().ok()?))
                })
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    let mut out = String::from("/// The guides of `docs/`: (name without `.md`, text).\n");
    out.push_str("pub static DOCS: &[(&str, &str)] = &[\n");
    for (name, path) in &names {
        let _ = writeln!(
            out,
            "    ({name:?}, include_str!({:?})),",
            path.display().to_string()
        );
    }
    out.push_str("];\n");
    let out_dir = std::env::var("OUT_DIR").unwrap_or_else(|_| ".".into());
    let _ = std::fs::write(std::path::Path::new(&out_dir).join("docs.rs"), out);
}
