//! `fracture bench` as a command: its arguments, the one-line throughput run of the README,
//! and the dispatch to the matrix, skip and accuracy benchmarks.

use std::process::ExitCode;
use std::time::Instant;

use anyhow::Context;
use fracture_api::Scene;
use fracture_api::validate::{scene_from_value, validate as validate_scene};
use fracture_solver::kernel::Kernel;
use fracture_solver::{Simulation, SolverConfig};

/// Exit status of an output or system error.
const EXIT_ERROR: u8 = 1;
/// Exit status of an invalid argument.
const EXIT_INVALID: u8 = 2;
/// Exit status of a numerical failure.
const EXIT_FAILED: u8 = 3;

/// Arguments of `fracture bench`.
#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    /// Which benchmark. Without one: a single throughput run of the seed block (the
    /// one-line figure of the README).
    #[arg(value_enum)]
    pub kind: Option<BenchKind>,
    /// Timed steps (throughput, skip).
    #[arg(long, default_value_t = 50)]
    pub steps: u64,
    /// Untimed warm-up steps before them.
    #[arg(long, default_value_t = 5)]
    pub warmup: u64,
    /// Solver threads (`all`: one per core); the throughput matrix uses --thread-counts.
    #[arg(long, default_value = "all")]
    pub threads: fracture_solver::Parallelism,
    /// Thread counts of the throughput matrix.
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    pub thread_counts: Vec<usize>,
    /// Cell size (m) of the block's grid; 0.0005 gives the seed's 500,000 particles,
    /// 0.002 about 31,000 (a CI-sized run).
    #[arg(long, default_value_t = 0.0005)]
    pub cell_size: f64,
    /// Particles per cell direction.
    #[arg(long, default_value_t = 2)]
    pub particles_per_cell: u32,
    /// History sample (J and K of every crack tip) every this many steps (throughput).
    #[arg(long, default_value_t = 1)]
    pub history_every: u64,
    /// Accuracy ladder.
    #[arg(long, value_enum, default_value_t = crate::bench::accuracy::Ladder::Full)]
    pub ladder: crate::bench::accuracy::Ladder,
    /// Cost axis of the accuracy plot and Pareto front (cpu: robust to other load).
    #[arg(long, value_enum, default_value_t = crate::bench::accuracy::Cost::Wall)]
    pub cost: crate::bench::accuracy::Cost,
    /// Accuracy: run only these setting families (default: all).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub families: Vec<crate::bench::accuracy::Family>,
    /// Shorthand for `--ladder quick`.
    #[arg(long)]
    pub quick: bool,
    /// Output folder (accuracy: default `out/accuracy`; throughput and skip: files only
    /// when given).
    #[arg(long)]
    pub out: Option<std::path::PathBuf>,
    /// Print the result as JSON (single throughput run).
    #[arg(long)]
    pub json: bool,
    /// Arithmetic of the particle passes (throughput): `auto` (FMA where the CPU has it),
    /// `portable` or `fma`.
    #[arg(long, value_enum, default_value_t = KernelArg::Auto)]
    pub kernel: KernelArg,
    /// The case of the single throughput run (what `--instructions` and `ab` run).
    #[arg(long, value_enum, default_value_t = CaseArg::NoCrack)]
    pub case: CaseArg,
    /// Throughput matrix: also count instructions per particle-step of each case under
    /// valgrind's cachegrind (one thread, 0.002 m cells or --cell-size if coarser; skipped
    /// with a note where valgrind is not installed).
    #[arg(long)]
    pub instructions: bool,
    /// `ab`: the baseline `fracture` binary (built from the stated baseline commit).
    #[arg(long)]
    pub baseline: Option<std::path::PathBuf>,
    /// `ab`: interleaved pairs (baseline, this binary); `throughput3d`: interleaved
    /// repetitions of each case.
    #[arg(long, default_value_t = 7)]
    pub pairs: usize,
    /// The single throughput run: `2` (the seed block) or `3` (the 3D block of
    /// `throughput3d`, `--cells` per side).
    #[arg(long, default_value_t = 2)]
    pub dim: u32,
    /// Cells per side of the 3D block (`--dim 3`, `throughput3d`): 50 with the default two
    /// particles per cell direction gives 1,000,000 particles.
    #[arg(long, default_value_t = 50)]
    pub cells: usize,
}

impl BenchArgs {
    /// The single run that `bench throughput --instructions` counts: `case` on one thread,
    /// one warm-up step, `steps` steps, JSON output.
    pub fn for_instructions(case: CaseArg, cell_size: f64, steps: u64, kernel: KernelArg) -> Self {
        BenchArgs {
            kind: None,
            steps,
            warmup: 1,
            threads: fracture_solver::Parallelism::threads(1),
            thread_counts: vec![1],
            cell_size,
            particles_per_cell: 2,
            history_every: 1,
            ladder: crate::bench::accuracy::Ladder::Full,
            cost: crate::bench::accuracy::Cost::Wall,
            families: Vec::new(),
            quick: false,
            out: None,
            json: true,
            kernel,
            case,
            instructions: false,
            baseline: None,
            pairs: 1,
            dim: 2,
            cells: 50,
        }
    }
}

/// `--case`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum CaseArg {
    /// The seed block without a crack.
    NoCrack,
    /// With a 50 mm edge crack, J and K of its tip at every history sample.
    Crack,
    /// With that crack propagating.
    Propagation,
}

impl CaseArg {
    /// The throughput matrix's case.
    pub fn case(self) -> crate::bench::throughput::Case {
        use crate::bench::throughput::Case;
        match self {
            CaseArg::NoCrack => Case::NoCrack,
            CaseArg::Crack => Case::Crack,
            CaseArg::Propagation => Case::Propagation,
        }
    }
    /// The argument of the matrix's case `c`.
    pub fn of(c: crate::bench::throughput::Case) -> CaseArg {
        use crate::bench::throughput::Case;
        match c {
            Case::NoCrack => CaseArg::NoCrack,
            Case::Crack => CaseArg::Crack,
            Case::Propagation => CaseArg::Propagation,
        }
    }
}

/// `--kernel`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum KernelArg {
    /// The fastest kernel this CPU runs.
    Auto,
    /// Plain multiply and add (the same bits on every CPU).
    Portable,
    /// Fused multiply-add (AVX2 and FMA; refused on a CPU without them).
    Fma,
}

impl KernelArg {
    /// The solver's kernel, or an error where this CPU lacks it.
    pub fn kernel(self) -> anyhow::Result<Kernel> {
        let k = match self {
            KernelArg::Auto => Kernel::detect(),
            KernelArg::Portable => Kernel::Portable,
            KernelArg::Fma => Kernel::Fma,
        };
        if !k.available() {
            anyhow::bail!("--kernel {}: this CPU lacks AVX2 or FMA", k.name());
        }
        Ok(k)
    }
}

/// The benchmarks of `fracture bench`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum BenchKind {
    /// Particle-steps per second on the seed's impacted Homalite block (125 mm × 250 mm,
    /// plane strain, GIMP): no crack, a crack with J at every history sample, a propagating
    /// crack, on each of --thread-counts; with the memory-bandwidth model.
    Throughput,
    /// The verification problems on a ladder of resolutions and settings: error against
    /// the analytic answer and wall time, convergence orders, Pareto front.
    Accuracy,
    /// What a scene does not pay for: crack code, J between samples, inactive grid,
    /// unrequested snapshot fields.
    Skip,
    /// Interleaved A/B runs of the single throughput run (`--case`, `--threads`, `--kernel`)
    /// against a baseline binary (`--baseline`), `--pairs` pairs: medians, ratio of the
    /// medians and median of the pair ratios.
    Ab,
    /// The 3D block (Homalite, `--cells` per side, struck at 20 m/s on part of a face) on
    /// the dimension-generic core against the 2D solver's seed block, interleaved, on each
    /// of --thread-counts: particle-steps/s, the bytes model and (with --instructions)
    /// instructions per particle-step.
    Throughput3d,
    /// All three, into `<out>/throughput`, `<out>/skip` and `<out>/accuracy` (default
    /// `out/bench`): the one command that regenerates every figure of `docs/performance.md`
    /// and `docs/accuracy.md`.
    All,
}

/// The seed's benchmark block: 125 mm × 250 mm Homalite (E = 5.2 GPa, ν = 0.34,
/// ρ = 1230 kg/m³), plane strain, `ppc`² particles per cell, a grid box three cells larger
/// on each side, struck at 20 m/s over the lower quarter of its left edge. The end time
/// leaves room for `steps` steps.
pub fn bench_block(cell_size: f64, ppc: u32, steps: u64) -> anyhow::Result<Scene> {
    let h = cell_size;
    let m = 3.0 * h;
    let (w, l) = (0.125, 0.25);
    let rho = 1230.0_f64;
    let (e, nu) = (5.2e9_f64, 0.34_f64);
    let cfl = 0.5;
    let value = serde_json::json!({
        "name": "bench-throughput-block",
        "description": "The seed's impacted Homalite block (fracture bench throughput).",
        "analysis": "plane_strain",
        "thickness": 0.01,
        "grid": {"cell_size": h, "min": [0.0, 0.0], "max": [w + 2.0 * m, l + 2.0 * m],
                 "shape_function": "gimp"},
        "materials": {"homalite": {"model": "linear_elastic", "density": rho,
                                    "youngs_modulus": e, "poissons_ratio": nu}},
        "bodies": [{"material": "homalite",
                    "region": {"rectangle": {"min": [m, m], "max": [m + w, m + l]}},
                    "particles_per_cell": ppc}],
        "boundary_conditions": [{
            "region": {"rectangle": {"min": [0.0, 0.0], "max": [m, m + 0.25 * l]}},
            "velocity": {"x": 20.0}
        }],
        "time": {"end": 1.0, "cfl": cfl}
    });
    let mut scene = scene_from_value(value).map_err(|e| anyhow::anyhow!("{e}"))?;
    let dt = scene
        .time_step()
        .ok_or_else(|| anyhow::anyhow!("the benchmark block has no valid material"))?;
    scene.time.end = (steps as f64 + 0.5) * dt;
    Ok(scene)
}

/// Result of the throughput benchmark.
#[derive(Debug, serde::Serialize)]
struct Throughput {
    benchmark: &'static str,
    case: &'static str,
    particles: usize,
    grid_nodes: usize,
    cell_size: f64,
    particles_per_cell: u32,
    threads: usize,
    warmup_steps: u64,
    steps: u64,
    wall_seconds: f64,
    seconds_per_step: f64,
    particle_steps_per_second: f64,
    kernel: &'static str,
    solver_version: &'static str,
}

fn throughput(a: &BenchArgs) -> anyhow::Result<Result<Throughput, String>> {
    if a.dim == 3 {
        return throughput_3d(a);
    }
    let case = a.case.case();
    let scene = crate::bench::throughput::case_scene(
        case,
        a.cell_size,
        a.particles_per_cell,
        a.warmup + a.steps,
    )?;
    if let Err(e) = validate_scene(&scene) {
        anyhow::bail!("the benchmark block is not a valid scene:\n{e}");
    }
    let mut sim = Simulation::new(
        &fracture_api::ValidScene::new(scene.clone())?,
        SolverConfig { threads: a.threads },
    )
    .context("building the benchmark block")?;
    let mut start = Instant::now();
    sim.set_kernel(a.kernel.kernel()?);
    // With a crack, J and K of every tip at every `--history-every`-th step, as the matrix.
    let every = a.history_every.max(1);
    let sampled = case != crate::bench::throughput::Case::NoCrack;
    for k in 1..=(a.warmup + a.steps) {
        if k == a.warmup + 1 {
            start = Instant::now();
        }
        if let Err(e) = sim.step() {
            return Ok(Err(e.to_string()));
        }
        if sampled && k.is_multiple_of(every) {
            let _ = sim.crack_tips();
        }
    }
    let wall = if a.steps > 0 {
        start.elapsed().as_secs_f64()
    } else {
        0.0
    };
    let particles = sim.particle_count();
    let rate = |n: f64| if wall > 0.0 { n / wall } else { 0.0 };
    Ok(Ok(Throughput {
        benchmark: "throughput",
        case: case.name(),
        particles,
        grid_nodes: sim.grid_node_count(),
        cell_size: a.cell_size,
        particles_per_cell: a.particles_per_cell,
        threads: sim.threads(),
        warmup_steps: a.warmup,
        steps: a.steps,
        wall_seconds: wall,
        seconds_per_step: if a.steps > 0 {
            wall / a.steps as f64
        } else {
            0.0
        },
        particle_steps_per_second: rate(particles as f64 * a.steps as f64),
        kernel: sim.kernel().name(),
        solver_version: fracture_api::SOLVER_VERSION,
    }))
}

/// The single run of the 3D block (`--dim 3`).
fn throughput_3d(a: &BenchArgs) -> anyhow::Result<Result<Throughput, String>> {
    let threads = a.threads.resolve();
    let kernel = a.kernel.kernel()?;
    let r = crate::bench::block3d::time_block(
        a.cells,
        a.particles_per_cell,
        threads,
        a.warmup,
        a.steps,
        kernel,
    )?;
    let r = match r {
        Ok(r) => r,
        Err(e) => return Ok(Err(e)),
    };
    Ok(Ok(Throughput {
        benchmark: "throughput",
        case: "3d block",
        particles: r.particles,
        grid_nodes: r.grid_nodes,
        cell_size: crate::bench::block3d::CELL,
        particles_per_cell: a.particles_per_cell,
        threads,
        warmup_steps: a.warmup,
        steps: a.steps,
        wall_seconds: r.wall_seconds,
        seconds_per_step: if a.steps > 0 {
            r.wall_seconds / a.steps as f64
        } else {
            0.0
        },
        particle_steps_per_second: r.particle_steps_per_second,
        kernel: r.kernel,
        solver_version: fracture_api::SOLVER_VERSION,
    }))
}

/// `fracture bench`. Its result is its standard output.
#[allow(clippy::print_stdout)]
pub fn bench(a: BenchArgs) -> ExitCode {
    if !(a.cell_size.is_finite() && a.cell_size > 0.0) {
        eprintln!(
            "error: --cell-size {} must be a positive length (m)",
            a.cell_size
        );
        return ExitCode::from(EXIT_INVALID);
    }
    let result = match a.kind {
        None => throughput(&a),
        Some(kind) => return bench_kind(kind, &a),
    };
    match result {
        Ok(Ok(t)) => {
            if a.json {
                match serde_json::to_string_pretty(&t) {
                    Ok(s) => println!("{s}"),
                    Err(e) => {
                        eprintln!("error: {e}");
                        return ExitCode::from(EXIT_ERROR);
                    }
                }
            } else {
                println!(
                    "throughput: {} particles ({} grid nodes), {} threads, {} steps after {} warm-up: \
                     {:.3} s, {:.3e} s/step, {:.4e} particle-steps/s ({} kernel)",
                    t.particles,
                    t.grid_nodes,
                    t.threads,
                    t.steps,
                    t.warmup_steps,
                    t.wall_seconds,
                    t.seconds_per_step,
                    t.particle_steps_per_second,
                    t.kernel
                );
            }
            ExitCode::SUCCESS
        }
        Ok(Err(step_error)) => {
            eprintln!("error: the benchmark run failed: {step_error}");
            ExitCode::from(EXIT_FAILED)
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(EXIT_ERROR)
        }
    }
}

/// `fracture bench accuracy | throughput | skip | all`.
fn bench_kind(kind: BenchKind, a: &BenchArgs) -> ExitCode {
    if kind == BenchKind::Throughput && a.thread_counts.is_empty() {
        eprintln!("error: --thread-counts is empty");
        return ExitCode::from(EXIT_INVALID);
    }
    let result = if kind == BenchKind::All {
        let root = a
            .out
            .clone()
            .unwrap_or_else(|| std::path::PathBuf::from("out/bench"));
        [BenchKind::Throughput, BenchKind::Skip, BenchKind::Accuracy]
            .into_iter()
            .try_for_each(|k| {
                let name = match k {
                    BenchKind::Throughput => "throughput",
                    BenchKind::Throughput3d => "throughput3d",
                    BenchKind::Ab => "ab",
                    BenchKind::Skip => "skip",
                    _ => "accuracy",
                };
                bench_one(k, a, Some(root.join(name)))
            })
    } else {
        bench_one(kind, a, a.out.clone())
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(EXIT_ERROR)
        }
    }
}

fn bench_one(
    kind: BenchKind,
    a: &BenchArgs,
    out: Option<std::path::PathBuf>,
) -> anyhow::Result<()> {
    use super::{accuracy, skip, throughput};
    match kind {
        BenchKind::Accuracy => {
            let ladder = if a.quick {
                accuracy::Ladder::Quick
            } else {
                a.ladder
            };
            let out = out.unwrap_or_else(|| std::path::PathBuf::from("out/accuracy"));
            accuracy::run(
                ladder,
                &fracture_verify::Problem::ALL,
                &a.families,
                a.threads,
                a.cost,
                &out,
            )
            .map(|_| ())
        }
        BenchKind::Throughput => throughput::run(
            &throughput::Options {
                cell_size: a.cell_size,
                ppc: a.particles_per_cell,
                steps: a.steps,
                warmup: a.warmup,
                threads: a.thread_counts.clone(),
                history_every: a.history_every,
                kernel: a.kernel.kernel()?,
                instructions: a.instructions.then_some(a.kernel),
            },
            out.as_deref(),
        )
        .map(|_| ()),
        BenchKind::Ab => {
            let Some(base) = a.baseline.as_deref() else {
                anyhow::bail!(
                    "bench ab needs --baseline PATH (a fracture binary of the baseline commit)"
                );
            };
            super::ab::run(base, a, out.as_deref()).map(|_| ())
        }
        BenchKind::Skip => skip::run(
            &skip::Options {
                cell_size: a.cell_size,
                steps: a.steps,
                warmup: a.warmup,
                threads: a.threads,
            },
            out.as_deref(),
        )
        .map(|_| ()),
        BenchKind::Throughput3d => super::block3d::run(a, out.as_deref()).map(|_| ()),
        BenchKind::All => anyhow::bail!("bench all runs the others"),
    }
}
