//! Local commands: `run`, `validate`, `schema`, `bench` (`api.md`, command line;
//! `run-output.md` for the run directory and exit status).
//!
//! Exit status: 0 success; 1 an output or system error (files, threads); 2 an invalid or
//! unreadable scene (every problem on stderr with its JSON path and value); 3 a run that
//! failed numerically (the message says at which step and where); 130 a run stopped with
//! Ctrl-C (status `cancelled` in its summary). A run keeps its partial outputs in every
//! case.

// A command-line tool prints its results on stdout.
#![allow(clippy::print_stdout)]

use std::io::IsTerminal;
use std::path::Path;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use fracture_api::results::{CrackTipRow, EnergyRow, Progress, RunStatus, Snapshot, Summary};
use fracture_api::{Scene, ValidScene};
use fracture_solver::Parallelism;
use fracture_worker::{Control, LocalOutput, RunOptions, RunSink, SinkError, run_scene};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Exit status of an output or system error.
const EXIT_ERROR: u8 = 1;
/// Exit status of an invalid scene.
const EXIT_INVALID: u8 = 2;
/// Exit status of a numerical failure.
const EXIT_FAILED: u8 = 3;
/// Exit status of a run stopped by Ctrl-C (128 + SIGINT, as shells report it).
const EXIT_INTERRUPTED: u8 = 130;

/// A scene that could not be loaded: what to print and the exit status.
struct LoadError {
    message: String,
    code: u8,
}

impl LoadError {
    fn report(self) -> ExitCode {
        eprintln!("{}", self.message);
        ExitCode::from(self.code)
    }
}

/// A valid scene of either dimension.
enum Loaded {
    Two(ValidScene),
    Three(fracture_api::ValidScene3),
}

/// Read, parse and validate a scene file of either dimension (`"analysis": "3d"` is 3D).
fn load_any_scene(path: &Path) -> Result<Loaded, LoadError> {
    let text = std::fs::read_to_string(path).map_err(|e| LoadError {
        message: format!("error: cannot read {}: {e}", path.display()),
        code: EXIT_INVALID,
    })?;
    let invalid = |errors: fracture_api::ValidationErrors| LoadError {
        message: format!(
            "error: {} is not a valid scene:\n{}",
            path.display(),
            errors
                .0
                .iter()
                .map(|e| format!("  {e}"))
                .collect::<Vec<_>>()
                .join("\n")
        ),
        code: EXIT_INVALID,
    };
    match fracture_api::parse_any_scene(&text).map_err(invalid)? {
        fracture_api::AnyScene::Two(scene) => {
            ValidScene::new(scene).map(Loaded::Two).map_err(invalid)
        }
        fracture_api::AnyScene::Three(scene) => fracture_api::ValidScene3::new(scene)
            .map(Loaded::Three)
            .map_err(invalid),
    }
}

/// The sink of `fracture run`: the run directory, plus a progress bar on a terminal.
struct CliSink {
    out: LocalOutput,
    bar: Option<ProgressBar>,
    /// Writing the results failed (as opposed to the physics).
    output_failed: bool,
    /// Set by Ctrl-C: cancel at the next progress report.
    interrupted: Arc<AtomicBool>,
}

impl CliSink {
    fn check<T>(&mut self, r: Result<T, SinkError>) -> Result<T, SinkError> {
        if r.is_err() {
            self.output_failed = true;
        }
        r
    }
}

impl RunSink for CliSink {
    fn progress(&mut self, p: &Progress) -> Result<Control, SinkError> {
        if let Some(bar) = &self.bar {
            bar.set_position(p.step);
            bar.set_message(format!("t = {:.3e} s", p.sim_time));
        }
        let r = self.out.progress(p);
        let control = self.check(r)?;
        if self.interrupted.load(Ordering::SeqCst) {
            return Ok(Control::Cancel);
        }
        Ok(control)
    }
    fn energy(&mut self, rows: &[EnergyRow]) -> Result<(), SinkError> {
        let r = self.out.energy(rows);
        self.check(r)
    }
    fn crack_tips(&mut self, rows: &[CrackTipRow]) -> Result<(), SinkError> {
        let r = self.out.crack_tips(rows);
        self.check(r)
    }
    fn snapshot(&mut self, snap: &Snapshot) -> Result<(), SinkError> {
        let r = self.out.snapshot(snap);
        self.check(r)
    }
    fn wants_volumes(&self) -> bool {
        self.out.wants_volumes()
    }
    fn volume(&mut self, volume: &fracture_api::results::Volume) -> Result<(), SinkError> {
        let r = self.out.volume(volume);
        self.check(r)
    }
    fn finish(&mut self, summary: &Summary) -> Result<(), SinkError> {
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
        let r = self.out.finish(summary);
        self.check(r)
    }
}

fn progress_bar(steps: u64) -> Option<ProgressBar> {
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = ProgressBar::with_draw_target(Some(steps), ProgressDrawTarget::stderr());
    let style = ProgressStyle::with_template(
        "{elapsed_precise} [{wide_bar}] {pos}/{len} steps, {msg}, ETA {eta}",
    )
    .unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style.progress_chars("=> "));
    Some(bar)
}

/// Folder of the VTK series under a run directory (`fracture run --vtk`).
pub const VTK_DIR: &str = "vtk";

/// `fracture run --vtk`: the run's snapshots (what `fields.mcap` holds, also of a failed or
/// cancelled run) as a VTK series in `OUT/vtk/`. Reports on stdout/stderr; false on failure.
fn export_vtk(out: &Path) -> bool {
    let mcap = out.join(fracture_worker::local::FIELDS_FILE);
    let dir = out.join(VTK_DIR);
    match fracture_results::vtk::export_mcap(&mcap, &dir) {
        Ok(series) => {
            println!(
                "VTK series in {} ({} files; open {} in ParaView)",
                dir.display(),
                series.files.len(),
                series.fields_pvd.display()
            );
            true
        }
        Err(e) => {
            eprintln!(
                "error: cannot write the VTK series to {}: {e}",
                dir.display()
            );
            false
        }
    }
}

/// Make `out` ready for a run: a missing or empty folder is used as it is; a non-empty one
/// is refused unless `force`, which removes the files a run writes there
/// ([`fracture_worker::local::RUN_FILES`]) and names any other file it leaves.
fn prepare_out(out: &Path, force: bool) -> Result<(), String> {
    let entries = match std::fs::read_dir(out) {
        Ok(d) => d,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) if out.is_file() => {
            return Err(format!(
                "--out {}: is a file, not a folder ({e})",
                out.display()
            ));
        }
        Err(e) => return Err(format!("--out {}: cannot read it: {e}", out.display())),
    };
    let mut names: Vec<String> = entries
        .filter_map(Result::ok)
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    if names.is_empty() {
        return Ok(());
    }
    if !force {
        let shown: Vec<&str> = names.iter().take(6).map(String::as_str).collect();
        let more = if names.len() > shown.len() {
            ", …"
        } else {
            ""
        };
        return Err(format!(
            "--out {}: the folder is not empty ({}{more}); choose a new folder, or add \
             --force to replace the previous run's files",
            out.display(),
            shown.join(", ")
        ));
    }
    let mut others = Vec::new();
    for name in names {
        let path = out.join(&name);
        if !fracture_worker::local::RUN_FILES.contains(&name.as_str()) {
            others.push(name);
            continue;
        }
        let removed = if path.is_dir() {
            std::fs::remove_dir_all(&path)
        } else {
            std::fs::remove_file(&path)
        };
        removed.map_err(|e| format!("--force: cannot remove {}: {e}", path.display()))?;
    }
    if !others.is_empty() {
        eprintln!(
            "warning: --out {} keeps files that are not a run's: {}",
            out.display(),
            others.join(", ")
        );
    }
    Ok(())
}

/// `fracture run`; with `vtk`, also the VTK series of its snapshots (`OUT/vtk/`); `force`
/// replaces a previous run's files in a non-empty `out`.
pub fn run(scene: &Path, out: &Path, threads: Parallelism, vtk: bool, force: bool) -> ExitCode {
    let loaded = match load_any_scene(scene) {
        Ok(s) => s,
        Err(e) => return e.report(),
    };
    if let Err(e) = prepare_out(out, force) {
        eprintln!("error: {e}");
        return ExitCode::from(EXIT_ERROR);
    }
    let mut output = match LocalOutput::create(out) {
        Ok(o) => o,
        Err(e) => {
            eprintln!("error: cannot write the run directory: {e}");
            return ExitCode::from(EXIT_ERROR);
        }
    };
    let written = match &loaded {
        Loaded::Two(scene) => output.write_scene(scene),
        Loaded::Three(scene) => output.write_scene3(scene.scene()),
    };
    if let Err(e) = written {
        eprintln!("error: cannot write the run directory: {e}");
        return ExitCode::from(EXIT_ERROR);
    }
    // A 3D run's `--vtk`: its whole grid at each snapshot time, written as it runs
    // (`OUT/vtk/volumes.pvd`); the 2D export below reads the snapshots back from the MCAP.
    let volumes = vtk && matches!(loaded, Loaded::Three(_));
    if volumes && let Err(e) = output.write_volumes(out.join("vtk")) {
        eprintln!("error: cannot write the VTK volumes: {e}");
        return ExitCode::from(EXIT_ERROR);
    }
    let steps = match &loaded {
        Loaded::Two(scene) => scene.size().steps,
        Loaded::Three(scene) => scene.size().steps,
    };
    let bar = progress_bar(steps);
    let opts = RunOptions {
        threads,
        flush_every: if bar.is_some() {
            Duration::from_millis(200)
        } else {
            RunOptions::default().flush_every
        },
    };
    // Ctrl-C stops the run cleanly (summary written, status cancelled); a second one
    // exits at once, keeping what was flushed.
    let interrupted = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&interrupted);
    if let Err(e) = ctrlc::set_handler(move || {
        if flag.swap(true, Ordering::SeqCst) {
            std::process::exit(i32::from(EXIT_INTERRUPTED));
        }
        eprintln!("\ninterrupted: stopping at the next report (Ctrl-C again to quit now)");
    }) {
        eprintln!("warning: Ctrl-C will not stop the run cleanly: {e}");
    }
    let mut sink = CliSink {
        out: output,
        bar,
        output_failed: false,
        interrupted,
    };
    let summary = match &loaded {
        Loaded::Two(scene) => run_scene(scene, &opts, &mut sink),
        Loaded::Three(scene) => fracture_worker::run_scene3(scene, &opts, &mut sink),
    };
    let cracks = match &loaded {
        Loaded::Two(scene) => scene.scene().cracks.len(),
        Loaded::Three(_) => 0,
    };
    let vtk_ok = !vtk || volumes || export_vtk(out);
    if volumes && summary.status == RunStatus::Completed {
        println!(
            "VTK volumes: {} (ParaView)",
            out.join("vtk").join("volumes.pvd").display()
        );
    }
    let message = summary.message.as_deref().unwrap_or("");
    match summary.status {
        RunStatus::Completed => {
            println!(
                "completed: {} steps to t = {:.4e} s, {} particles, {} threads, {:.2} s ({:.3e} particle-steps/s)",
                summary.steps,
                summary.sim_time,
                summary.particles,
                summary.threads,
                summary.wall_seconds,
                summary.particle_steps_per_second
            );
            if !summary.tips.is_empty() {
                print!("{}", crate::answers::results_text(&summary, cracks));
            }
            println!("results in {}", out.display());
            if !summary.tips.is_empty() {
                println!(
                    "crack paths: {}",
                    out.join(fracture_worker::local::PATH_FILE).display()
                );
            }
            if vtk_ok {
                ExitCode::SUCCESS
            } else {
                ExitCode::from(EXIT_ERROR)
            }
        }
        RunStatus::Failed if sink.output_failed => {
            eprintln!("error: {message}");
            eprintln!("partial results in {}", out.display());
            ExitCode::from(EXIT_ERROR)
        }
        RunStatus::Failed => {
            eprintln!(
                "error: the run failed after {} steps (t = {:.4e} s): {message}",
                summary.steps, summary.sim_time
            );
            eprintln!("partial results in {}", out.display());
            ExitCode::from(EXIT_FAILED)
        }
        RunStatus::Cancelled => {
            eprintln!("cancelled after {} steps: {message}", summary.steps);
            eprintln!("partial results in {}", out.display());
            ExitCode::from(EXIT_INTERRUPTED)
        }
    }
}

/// Write `text` to stdout; a reader that went away (`fracture validate x | head`) is not an
/// error worth a panic: the output is simply not wanted any more.
fn print_out(text: &str) -> ExitCode {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: cannot write the output: {e}");
            ExitCode::from(EXIT_ERROR)
        }
    }
}

/// `fracture validate`: a scene of either dimension (`"analysis": "3d"` is 3D); prints the
/// run's size and memory estimate.
pub fn validate(scene: &Path) -> ExitCode {
    let loaded = match load_any_scene(scene) {
        Ok(s) => s,
        Err(e) => return e.report(),
    };
    let (name, valid, size, est) = match &loaded {
        Loaded::Two(s) => (
            &s.scene().name,
            "valid",
            *s.size(),
            fracture_api::cost::memory_estimate(s.scene(), s.size().particles),
        ),
        Loaded::Three(s) => (
            &s.scene().name,
            "valid (3D)",
            *s.size(),
            fracture_api::cost::memory_estimate3(s.scene(), s.size().particles),
        ),
    };
    print_out(&format!(
        "{}: {valid}\nparticles: {}\ngrid nodes: {}\ntime step: {:e} s\nsteps: {}\n\
         particle-steps: {:e}\nmemory (estimate): {}\n",
        name,
        size.particles,
        size.grid_nodes,
        size.time_step,
        size.steps,
        fracture_api::cost::particle_steps(size.particles, size.steps) as f64,
        est
    ))
}

/// `fracture schema`: the 2D scene's JSON Schema, or with `three_d` (`--3d`) the 3D scene's.
pub fn schema(three_d: bool) -> ExitCode {
    let schema = if three_d {
        fracture_api::Scene3::json_schema()
    } else {
        Scene::json_schema()
    };
    match serde_json::to_string_pretty(&schema) {
        Ok(s) => print_out(&format!("{s}\n")),
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(EXIT_ERROR)
        }
    }
}
