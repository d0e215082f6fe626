//! `fracture study rosakis`: the seed's parameter study of the Rosakis intersonic shear-crack
//! experiment, end to end in one command. It runs the three sweeps of the seed (impact
//! velocity at J_Ic = 25 J/m² without friction; J_Ic at 25 m/s; crack-face friction μ at
//! J_Ic = 250 J/m², at 25 m/s and at a low impact speed) on a Rosakis scene, measures the
//! crack-tip speed (moving box) of every run, checks each claim of the seed against the
//! measurements, and writes `rosakis.md` with its figures (speed against time per sweep as
//! SVG, isochromatic fringe pictures as PNG) and tables (CSV beside them).
//!
//! Here: the arguments and the run of every sweep. `sweeps`: what is run; `measure`:
//! what a run measures; `report` and `claims`: the page and its verdicts; `figures`:
//! its plots and fringe pictures.

// A command-line tool prints its progress on stdout.
#![allow(clippy::print_stdout)]

mod claims;
mod figures;
mod measure;
mod report;
mod sweeps;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context;
use fracture_api::validate::scene_from_value;
use serde_json::Value;

use measure::{Measured, run_one};
use report::Report;
use sweeps::{sweeps, variant_scene};

/// Arguments of `fracture study`.
#[derive(clap::Args, Debug)]
pub struct StudyArgs {
    /// Which study (only `rosakis` so far).
    #[arg(value_enum, default_value_t = StudyKind::Rosakis)]
    pub kind: StudyKind,
    /// The base scene of the sweeps.
    #[arg(long, default_value = "scenes/rosakis-shear-coarse.json")]
    pub scene: PathBuf,
    /// Also run the four sweeps on this (finer) scene, e.g. scenes/rosakis-shear.json.
    #[arg(long)]
    pub fine: Option<PathBuf>,
    /// Also run the toughness sweep's J_Ic = 25 and 250 J/m² runs on this (finest) scene,
    /// e.g. scenes/rosakis-shear-finest.json, for the cell-size convergence table.
    #[arg(long)]
    pub finest: Option<PathBuf>,
    /// The reduced scene of the acceptance test, swept over J_Ic at its own end time.
    #[arg(long, default_value = "scenes/rosakis-shear-mini.json")]
    pub mini: PathBuf,
    /// Folder for `rosakis.md`; figures and tables go to its `rosakis/` subfolder.
    #[arg(long, default_value = "docs")]
    pub out: PathBuf,
    /// Simulated time of every run (s).
    #[arg(long, default_value_t = 8.0e-5)]
    pub end: f64,
    /// Width of the moving box of the plotted tip speed (s). The seed used 1 µs at 0.5 mm
    /// cells; at 1 mm cells a growth step is 0.5 mm, so a 1 µs box moves in steps of about
    /// 500 m/s and a wider box shows the trend.
    #[arg(long, default_value_t = 4.0e-6)]
    pub window: f64,
    /// Solver threads per run (`all`: one per core).
    #[arg(long, default_value = "all")]
    pub threads: fracture_solver::Parallelism,
}

/// The studies of `fracture study`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum StudyKind {
    /// The seed's Rosakis shear-crack sweeps (impact velocity, J_Ic, friction).
    Rosakis,
}

/// `fracture study`.
pub fn study(a: StudyArgs) -> ExitCode {
    match rosakis(&a) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn read_json(p: &Path) -> anyhow::Result<Value> {
    let text = std::fs::read_to_string(p).with_context(|| format!("reading {}", p.display()))?;
    serde_json::from_str(&text).with_context(|| format!("parsing {}", p.display()))
}

fn rosakis(a: &StudyArgs) -> anyhow::Result<()> {
    let figs = a.out.join("rosakis");
    std::fs::create_dir_all(&figs).with_context(|| format!("creating {}", figs.display()))?;
    let sweeps = sweeps(a)?;
    let mut bases: HashMap<PathBuf, Value> = HashMap::new();
    let mut results: HashMap<String, Measured> = HashMap::new();
    let total: usize = sweeps.iter().map(|s| s.runs.len()).sum();
    let mut done = 0;
    for sw in &sweeps {
        if !bases.contains_key(&sw.scene) {
            bases.insert(sw.scene.clone(), read_json(&sw.scene)?);
        }
        let base = &bases[&sw.scene];
        for v in &sw.runs {
            done += 1;
            let key = v.key(&sw.scene.display().to_string());
            if results.contains_key(&key) {
                println!(
                    "[{done}/{total}] {} {}: same run as before",
                    sw.id,
                    v.label()
                );
                continue;
            }
            let scene = variant_scene(base, v, sw.end.unwrap_or(a.end))
                .with_context(|| format!("sweep {} run {}", sw.id, v.label()))?;
            let m = run_one(&scene, a.threads);
            println!(
                "[{done}/{total}] {} {}: {:?}, {:.1} s, {:.2e} particle-steps/s, crack {:.1} mm longer",
                sw.id,
                v.label(),
                m.status,
                m.wall,
                m.psps,
                1e3 * (m.len.last().unwrap_or(&0.0) - m.len.first().unwrap_or(&0.0))
            );
            results.insert(key, m);
        }
    }
    let base = &bases[&a.scene];
    let scene0 = scene_from_value(base.clone()).map_err(|e| anyhow::anyhow!("{e}"))?;
    let speeds = scene0
        .materials
        .values()
        .next()
        .map(|m| m.wave_speeds(scene0.analysis))
        .context("the base scene has no material")?;
    let report = Report {
        a,
        sweeps: &sweeps,
        results: &results,
        speeds,
        figs: &figs,
        load: std::fs::read_to_string("/proc/loadavg")
            .ok()
            .and_then(|l| l.split_whitespace().next().map(str::to_string)),
    };
    report.write()
}
