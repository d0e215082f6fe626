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
mod cohesive;
mod figures;
mod growth;
pub mod kinks;
mod measure;
mod report;
mod sweeps;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use anyhow::Context;
use fracture_api::validate::scene_from_value;
use serde_json::Value;

use measure::{Measured, run_one};
use report::Report;
use sweeps::{sweeps, variant_scene};

/// Arguments of `fracture study`.
#[derive(clap::Args, Debug)]
pub struct StudyArgs {
    /// Which study.
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
    #[arg(long, default_value = "1")]
    pub threads: fracture_solver::Parallelism,
    /// Runs at a time (`all`: one per core). One thread per run and one run per core uses a
    /// small machine best: most runs are too small to keep several threads busy.
    #[arg(long, default_value = "all")]
    pub jobs: fracture_solver::Parallelism,
    /// Also run the velocity and friction sweeps under the seed's `wave` rule (the toughness
    /// sweep always runs under both laws).
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    pub wave_all: bool,
    /// Run the convergence tables on the reduced scene (cell size, J domain radius).
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    pub convergence: bool,
    /// The smallest cell size (m) of the convergence tables; 1.25e-4 runs them all, 5e-4 is
    /// a quick check (the 0.125 mm runs are most of the study's time).
    #[arg(long, default_value_t = 1.25e-4)]
    pub min_cell: f64,
    /// Also run the cohesive part (the bond as a cohesive interface: impact, toughness and
    /// friction sweeps, cell-size check) and write `rosakis-cohesive.md`.
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    pub cohesive: bool,
    /// Run only the cohesive part.
    #[arg(long)]
    pub cohesive_only: bool,
    /// The base scene of the cohesive part.
    #[arg(long, default_value = "scenes/rosakis-shear-cohesive.json")]
    pub cohesive_scene: PathBuf,
    /// The smallest cell size (m) of the cohesive cell-size check (the scene's cells, double,
    /// half and a quarter of them; 2.5e-4 runs the first three for the 0.5 mm scene, the
    /// 0.25 mm run being most of the cohesive part's time; 1.25e-4 adds the 0.125 mm run,
    /// 8 million particles, about 15 min on 2 threads, `docs/scene-extensions.md`).
    #[arg(long, default_value_t = 2.5e-4)]
    pub cohesive_min_cell: f64,
    /// `growth`: J domain radius (m) of the regularisation held fixed in physical units.
    #[arg(long, default_value_t = 3.0e-3)]
    pub j_radius: f64,
    /// `growth`: process-zone length (m) of the fixed regularisation.
    #[arg(long, default_value_t = 1.0e-3)]
    pub zone: f64,
    /// `growth`: filter time (s) of the fixed regularisation.
    #[arg(long, default_value_t = 1.2e-6)]
    pub filter_time: f64,
}

/// The studies of `fracture study`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum StudyKind {
    /// The seed's Rosakis shear-crack sweeps (impact velocity, J_Ic, friction).
    Rosakis,
    /// Kinked crack paths under the default growth law (pure-shear plate, Kalthoff–Winkler):
    /// `kinks.md`.
    Kinks,
    /// Crack growth against known transients (Freund's step wave at constant Γ, the strip
    /// with fixed grips): `growth.md`.
    Growth,
}

/// `fracture study`.
pub fn study(a: StudyArgs) -> ExitCode {
    let done = match a.kind {
        StudyKind::Rosakis => rosakis(&a),
        StudyKind::Kinks => kinks::run(&a).map(|_| ()),
        StudyKind::Growth => growth::run(&a),
    };
    match done {
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

/// One run to make: its key, where it is listed, its scene and a cost estimate.
struct Job {
    key: String,
    label: String,
    scene: fracture_api::Scene,
    cost: f64,
}

/// Run `jobs` (the longest first, so that the last ones to finish are short), `--jobs` at a
/// time with `--threads` each, measuring the rows of `target` (crack index, tip); progress
/// lines start with `tag`. Returns what each run measured by its key, and the runs at a
/// time.
fn run_jobs(
    a: &StudyArgs,
    mut jobs: Vec<Job>,
    target: (u32, u32),
    tag: &str,
) -> anyhow::Result<(HashMap<String, Measured>, usize)> {
    jobs.sort_by(|x, y| y.cost.total_cmp(&x.cost));
    let total = jobs.len();
    let workers = a.jobs.resolve().clamp(1, total.max(1));
    println!(
        "{tag}{total} runs, {workers} at a time, {} solver thread(s) each",
        a.threads
    );
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let results: Mutex<HashMap<String, Measured>> = Mutex::new(HashMap::new());
    std::thread::scope(|s| {
        for _ in 0..workers {
            s.spawn(|| {
                while let Some(job) = jobs.get(next.fetch_add(1, Ordering::Relaxed)) {
                    let m = run_one(&job.scene, a.threads, target);
                    let n = done.fetch_add(1, Ordering::Relaxed) + 1;
                    println!(
                        "[{tag}{n}/{total}] {}: {:?}, {:.1} s, {:.2e} particle-steps/s, tip {:.1} mm further",
                        job.label,
                        m.status,
                        m.wall,
                        m.psps,
                        1e3 * m.extension()
                    );
                    if let Ok(mut r) = results.lock() {
                        r.insert(job.key.clone(), m);
                    }
                }
            });
        }
    });
    let results = results
        .into_inner()
        .map_err(|_| anyhow::anyhow!("a run panicked"))?;
    Ok((results, workers))
}

fn rosakis(a: &StudyArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        a.min_cell.is_finite() && a.min_cell > 0.0,
        "--min-cell must be a positive cell size in metres, got {}",
        a.min_cell
    );
    anyhow::ensure!(
        a.cohesive_min_cell.is_finite() && a.cohesive_min_cell > 0.0,
        "--cohesive-min-cell must be a positive cell size in metres, got {}",
        a.cohesive_min_cell
    );
    let figs = a.out.join("rosakis");
    std::fs::create_dir_all(&figs).with_context(|| format!("creating {}", figs.display()))?;
    if !a.cohesive_only {
        tip_law_study(a, &figs)?;
    }
    if a.cohesive || a.cohesive_only {
        let page = cohesive::run(&cohesive::Setup {
            a,
            scene: &a.cohesive_scene,
            out: &a.out,
            figs: &figs,
        })?;
        println!("wrote {}", page.display());
    }
    Ok(())
}

/// The seed's sweeps under both tip laws and the convergence tables: `rosakis.md`.
fn tip_law_study(a: &StudyArgs, figs: &Path) -> anyhow::Result<()> {
    let started = Instant::now();
    let sweeps = sweeps(a)?;
    let mut bases: HashMap<PathBuf, Value> = HashMap::new();
    let mut jobs: Vec<Job> = Vec::new();
    for sw in &sweeps {
        if !bases.contains_key(&sw.scene) {
            bases.insert(sw.scene.clone(), read_json(&sw.scene)?);
        }
        let base = &bases[&sw.scene];
        for v in &sw.runs {
            let key = v.key(&sw.scene.display().to_string());
            if jobs.iter().any(|j| j.key == key) {
                continue;
            }
            let end = sw.end.unwrap_or(a.end);
            let scene = variant_scene(base, v, end)
                .with_context(|| format!("sweep {} run {}", sw.id, v.label()))?;
            // Particles × steps: area / h² × end / h.
            let h = scene.grid.cell_size;
            let ext = [
                scene.grid.max[0] - scene.grid.min[0],
                scene.grid.max[1] - scene.grid.min[1],
            ];
            jobs.push(Job {
                key,
                label: format!("{} {}", sw.id, v.label()),
                scene,
                cost: ext[0] * ext[1] * end / (h * h * h),
            });
        }
    }
    let total = jobs.len();
    let (results, workers) = run_jobs(a, jobs, (0, 1), "")?;
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
        figs,
        load: std::fs::read_to_string("/proc/loadavg")
            .ok()
            .and_then(|l| l.split_whitespace().next().map(str::to_string)),
        wall: started.elapsed().as_secs_f64(),
        runs: total,
        workers,
    };
    report.write()
}
