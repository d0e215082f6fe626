//! Writes the benchmark scenes of the driving-force checks into `scenes/` from their
//! builders (`cargo run -p fracture-verify --example benchmark_scenes`), so the shipped files
//! are the tested scenes (`cli/tests/scenes.rs` compares them).
#![allow(clippy::print_stdout, clippy::unwrap_used)]

use fracture_verify::{Settings, benchmark_scenes};

fn main() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    for (name, scene) in benchmark_scenes(&Settings::at(0.001)).unwrap() {
        let path = dir.join(format!("{name}.json"));
        let text = serde_json::to_string_pretty(&scene).unwrap() + "\n";
        std::fs::write(&path, text).unwrap();
        println!("wrote {}", path.display());
    }
}
