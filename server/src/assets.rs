//! Files embedded in the binary at build time: the dashboard (`web/`) and the example
//! scenes (`scenes/*.json`).

use fracture_api::jobs::SceneEntry;
use rust_embed::RustEmbed;

/// The dashboard.
#[derive(RustEmbed)]
#[folder = "../web/"]
pub struct Web;

/// The example scenes.
#[derive(RustEmbed)]
#[folder = "../scenes/"]
pub struct Scenes;

/// Every embedded example scene, sorted by name (files that are not JSON objects skipped).
pub fn scenes() -> Vec<SceneEntry> {
    let mut names: Vec<String> = Scenes::iter()
        .map(|n| n.to_string())
        .filter(|n| n.ends_with(".json"))
        .collect();
    names.sort();
    names
        .into_iter()
        .filter_map(|n| {
            let f = Scenes::get(&n)?;
            let scene: serde_json::Value = serde_json::from_slice(&f.data).ok()?;
            let description = scene
                .get("description")
                .and_then(|d| d.as_str())
                .unwrap_or_default()
                .to_string();
            let name = n
                .rsplit('/')
                .next()
                .unwrap_or(&n)
                .trim_end_matches(".json")
                .to_string();
            Some(SceneEntry {
                name,
                description,
                scene,
                particles: 0,
                steps: 0,
                particle_steps: 0,
                estimated_wall_seconds: None,
                estimate_particle_steps_per_second: None,
                estimate_basis: None,
            })
        })
        .collect()
}

/// Content type from a file name.
pub fn mime(path: &str) -> &'static str {
    let ext = path.rsplit('.').next().unwrap_or_default();
    match ext {
        "html" => "text/html; charset=utf-8",
        "js" | "mjs" => "text/javascript; charset=utf-8",
        "css" => "text/css; charset=utf-8",
        "json" => "application/json",
        "svg" => "image/svg+xml",
        "png" => "image/png",
        "ico" => "image/x-icon",
        "woff2" => "font/woff2",
        "txt" => "text/plain; charset=utf-8",
        "md" => "text/markdown; charset=utf-8",
        _ => "application/octet-stream",
    }
}

/// The repository's guides (`docs/*.md`), embedded at build time by `build.rs` (the figures
/// in `docs/`'s folders are left out).
mod docs {
    include!(concat!(env!("OUT_DIR"), "/docs.rs"));
}

/// The text of the guide `docs/{name}.md`, if there is one.
pub fn doc(name: &str) -> Option<&'static str> {
    docs::DOCS
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, text)| *text)
}

/// The names of the embedded guides (without `.md`), sorted.
pub fn doc_names() -> Vec<&'static str> {
    docs::DOCS.iter().map(|(n, _)| *n).collect()
}
