//! Before/after pictures of a run's isochromatic fringes (issue 20): the picture the
//! dashboard served before (the nodal fringe order at one pixel per cell) and the one it
//! serves now (the fringe order computed per pixel from the interpolated stresses, the
//! default resolution of at least 4 px per cell), for the snapshot nearest a time.
//!
//! `cargo run --release -p fracture-results --example fringe_before_after -- RUN/fields.mcap
//! TIME_S FRINGES_PER_PA OUT_PREFIX` writes OUT_PREFIX-before.png and OUT_PREFIX-after.png
//! and prints the aliasing report of each.
#![allow(clippy::print_stdout)]

use std::process::ExitCode;

use fracture_results::mcapfile::read_snapshots;
use fracture_results::render::{RenderOptions, render_png_with};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().collect();
    let [_, mcap, time, per_pa, out] = args.as_slice() else {
        eprintln!("usage: fringe_before_after RUN/fields.mcap TIME_S FRINGES_PER_PA OUT_PREFIX");
        return ExitCode::from(2);
    };
    let (Ok(time), Ok(per_pa)) = (time.parse::<f64>(), per_pa.parse::<f64>()) else {
        eprintln!("TIME_S and FRINGES_PER_PA must be numbers");
        return ExitCode::from(2);
    };
    let snaps = match read_snapshots(mcap) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{mcap}: {e}");
            return ExitCode::FAILURE;
        }
    };
    let Some(snap) = snaps
        .iter()
        .min_by(|a, b| (a.time - time).abs().total_cmp(&(b.time - time).abs()))
    else {
        eprintln!("{mcap}: no snapshots");
        return ExitCode::FAILURE;
    };
    let before = RenderOptions {
        px_per_cell: Some(1.0),
        ..RenderOptions::default()
    };
    let after = RenderOptions {
        fringe_per_pa: Some(per_pa),
        ..RenderOptions::default()
    };
    for (name, opts) in [("before", before), ("after", after)] {
        match render_png_with(snap, "fringe", &opts) {
            Ok(r) => {
                let path = format!("{out}-{name}.png");
                if let Err(e) = std::fs::write(&path, &r.png) {
                    eprintln!("{path}: {e}");
                    return ExitCode::FAILURE;
                }
                println!(
                    "{path}: t = {:.1} µs, {}×{} px, {:.1} px/cell, max {:.2} fringes/px, aliased {} ({} pairs)",
                    snap.time * 1e6,
                    r.report.width,
                    r.report.height,
                    r.report.px_per_cell,
                    r.report.max_fringes_per_pixel.unwrap_or(f64::NAN),
                    r.report.aliased,
                    r.report.aliased_pairs
                );
            }
            Err(e) => {
                eprintln!("render {name}: {e}");
                return ExitCode::FAILURE;
            }
        }
    }
    ExitCode::SUCCESS
}
