//! The one place the lab formats what it writes: Markdown and CSV tables ([`table`]), SVG
//! line and scatter plots ([`svg`]), and the files they go to ([`write_file`]). `bench` and
//! `study` build their figures and pages from these.

pub mod svg;
pub mod table;

use std::path::Path;

pub use table::{csv_line, markdown_header, markdown_row, markdown_table, sig};

/// Create `dir` and write `name` into it.
pub fn write_file(dir: &Path, name: &str, contents: impl AsRef<[u8]>) -> anyhow::Result<()> {
    use anyhow::Context;
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let path = dir.join(name);
    std::fs::write(&path, contents).with_context(|| format!("cannot write {}", path.display()))
}
