//! `fracture bench throughput3d`: the 3D block on the dimension-generic core (`fracture-mpm`)
//! against the 2D solver's seed block (no crack), interleaved on each thread count:
//! particle-steps per second (from the median step), a bytes-per-particle-step model of the
//! core's passes and, with `--instructions`, instructions per particle-step counted by
//! cachegrind (one thread, a 16-cell 3D block and the 2D block at 2 mm cells).
//!
//! The 3D block: Homalite (E = 5.2 GPa, ν = 0.34, ρ = 1230 kg/m³), `--cells` cells of 1 mm
//! per side (50 cells × 2³ particles per cell = 1,000,000 particles), struck at 20 m/s over
//! the lower quarter of its x = 0 face, GIMP.

use std::path::Path;
use std::process::Command;
use std::time::Instant;

use anyhow::Context;
use fracture_api::{AnyScene, ValidScene3, parse_any_scene};
use fracture_mpm::Kernel;
use fracture_solver3d::Simulation3;

use super::Machine;
use super::command::{BenchArgs, CaseArg, KernelArg};
use crate::report::{markdown_table, sig, write_file};

/// Cell size of the 3D block (m).
pub const CELL: f64 = 0.001;

/// The 3D block with `cells` cells per side, `ppc` particles per cell direction, an end
/// time that leaves room for `steps` steps.
pub fn block_scene(cells: usize, ppc: u32, steps: u64) -> anyhow::Result<ValidScene3> {
    let h = CELL;
    let side = cells as f64 * h;
    let m = 3.0 * h;
    let rho = 1230.0_f64;
    let (e, nu) = (5.2e9_f64, 0.34_f64);
    let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let mu = e / (2.0 * (1.0 + nu));
    let c_l = ((lambda + 2.0 * mu) / rho).sqrt();
    let cfl = 0.5;
    let end = (steps as f64 + 0.5) * cfl * h / c_l;
    let doc = serde_json::json!({
        "name": "bench-throughput-block-3d",
        "description": "The 3D throughput block (fracture bench throughput3d).",
        "analysis": "3d",
        "grid": {"cell_size": h, "min": [-m, -m, -m], "max": [side + m, side + m, side + m]},
        "materials": {"homalite": {"model": "linear_elastic", "density": rho,
                                    "youngs_modulus": e, "poissons_ratio": nu}},
        "bodies": [{"material": "homalite",
                    "region": {"box": {"min": [0.0, 0.0, 0.0], "max": [side, side, side]}},
                    "particles_per_cell": ppc}],
        "boundary_conditions": [{
            "region": {"box": {"min": [-m, -m, -m], "max": [0.0, side + m, 0.25 * side]}},
            "velocity": {"x": 20.0}
        }],
        "time": {"end": end, "cfl": cfl}
    });
    let text = doc.to_string();
    match parse_any_scene(&text).map_err(|e| anyhow::anyhow!("{e}"))? {
        AnyScene::Three(s) => ValidScene3::new(s).map_err(|e| anyhow::anyhow!("{e}")),
        AnyScene::Two(_) => anyhow::bail!("the 3D block parsed as a 2D scene"),
    }
}

/// One timed run.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Timed {
    /// Particles.
    pub particles: usize,
    /// Grid nodes.
    pub grid_nodes: usize,
    /// Wall time of the timed steps (s).
    pub wall_seconds: f64,
    /// Particle-steps per second over the timed steps.
    pub particle_steps_per_second: f64,
    /// Particle-steps per second from the median step.
    pub median_particle_steps_per_second: f64,
    /// Active nodes per particle (mean over the timed steps).
    pub nodes_per_particle: f64,
    /// Kernel.
    pub kernel: &'static str,
    /// Share of the step's wall time per pass: sort, p2g, forces, update, strain, grid.
    pub pass_shares: [f64; 6],
}

/// Time the 3D block: `warmup` untimed steps, then `steps` timed ones.
pub fn time_block(
    cells: usize,
    ppc: u32,
    threads: usize,
    warmup: u64,
    steps: u64,
    kernel: Kernel,
) -> anyhow::Result<Result<Timed, String>> {
    let valid = block_scene(cells, ppc, warmup + steps)?;
    let mut sim = Simulation3::new(&valid, threads).context("building the 3D block")?;
    let kernel = sim.set_kernel(kernel);
    for _ in 0..warmup {
        if let Err(e) = sim.step() {
            return Ok(Err(e.to_string()));
        }
    }
    let p0 = sim.pass_times();
    let mut times = Vec::with_capacity(steps as usize);
    let mut active = 0.0;
    let start = Instant::now();
    for _ in 0..steps {
        let t = Instant::now();
        match sim.step() {
            Ok(s) => active += s.active_nodes as f64,
            Err(e) => return Ok(Err(e.to_string())),
        }
        times.push(t.elapsed().as_secs_f64());
    }
    let wall = start.elapsed().as_secs_f64();
    let p1 = sim.pass_times();
    let d = [
        p1.sort - p0.sort,
        p1.p2g - p0.p2g,
        p1.forces - p0.forces,
        p1.update - p0.update,
        p1.strain - p0.strain,
        p1.grid - p0.grid,
    ];
    let total: f64 = d.iter().sum();
    let n = sim.particle_count();
    let med = super::median(&times);
    Ok(Ok(Timed {
        particles: n,
        grid_nodes: sim.grid_node_count(),
        wall_seconds: wall,
        particle_steps_per_second: if wall > 0.0 {
            (n as f64 * steps as f64) / wall
        } else {
            0.0
        },
        median_particle_steps_per_second: n as f64 / med,
        nodes_per_particle: active / steps.max(1) as f64 / n.max(1) as f64,
        kernel: kernel.name(),
        pass_shares: d.map(|x| if total > 0.0 { x / total } else { f64::NAN }),
    }))
}

/// Bytes moved per particle-step by the core's passes (no fusion): particle arrays read and
/// written by each pass, and 16 node transfers per active node (zeroing, the active count,
/// three nodal passes read + write, four particle passes bring each node in and the
/// scatters write it back), for dimension `dims` (2 or 3).
pub fn bytes_model(dims: usize, nodes_per_particle: f64) -> f64 {
    let f = 8.0;
    let d = dims as f64;
    let kin = 2.0 * d * f;
    let mech = 40.0;
    let stress = if dims == 3 { 6.0 * f } else { 4.0 * f };
    let wden = f;
    let wts = 20.0 * d;
    // The node as laid out (mass, p, f, q, u, v, a): size_of, so the model follows the layout.
    let node = if dims == 3 {
        std::mem::size_of::<fracture_mpm::grid::Node<fracture_mpm::Dim3>>()
    } else {
        std::mem::size_of::<fracture_mpm::grid::Node<fracture_mpm::Dim2>>()
    } as f64;
    let particle = (2.0 * wts + kin + mech) // P2G: weights written, kin and mech read
        + (wts + mech + 2.0 * stress + 2.0 * wden) // forces
        + (wts + mech + 2.0 * kin) // update
        + (wts + mech + 2.0 * stress + 2.0 * wden); // strain
    particle + 16.0 * node * nodes_per_particle
}

/// A row of the report.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Row {
    /// Case.
    pub case: String,
    /// Threads.
    pub threads: usize,
    /// Particles.
    pub particles: usize,
    /// Median over the repetitions of the median-step particle-steps/s.
    pub particle_steps_per_second: f64,
    /// Bytes per particle-step by the model.
    pub bytes_per_particle_step: f64,
    /// Instructions per particle-step (cachegrind), when counted.
    pub instructions_per_particle_step: Option<f64>,
    /// Pass shares (3D: sort, p2g, forces, update, strain, grid).
    pub pass_shares: Option<[f64; 6]>,
}

/// The report.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Report {
    /// Where and when.
    pub machine: Machine,
    /// Rows.
    pub rows: Vec<Row>,
}

/// Instructions per particle-step of the 3D block with `cells` per side under cachegrind:
/// two child runs (`bench --dim 3`, one thread, one warm-up step) with and without `steps`
/// timed steps. `Ok(None)` without valgrind.
pub fn instructions_3d(cells: usize, steps: u64, kernel: KernelArg) -> anyhow::Result<Option<f64>> {
    if Command::new("valgrind").arg("--version").output().is_err() {
        return Ok(None);
    }
    let me = std::env::current_exe().context("the path of this fracture binary")?;
    let kernel = match kernel {
        KernelArg::Auto => "auto",
        KernelArg::Portable => "portable",
        KernelArg::Fma => "fma",
    };
    let count = |n: u64| -> anyhow::Result<(f64, f64)> {
        let o = Command::new("valgrind")
            .args([
                "--tool=cachegrind",
                "--cache-sim=no",
                "--cachegrind-out-file=/dev/null",
            ])
            .arg(&me)
            .args([
                "bench",
                "--json",
                "--dim",
                "3",
                "--threads",
                "1",
                "--warmup",
                "1",
            ])
            .args(["--cells", &cells.to_string(), "--steps", &n.to_string()])
            .args(["--kernel", kernel])
            .output()
            .context("running valgrind")?;
        let err = String::from_utf8_lossy(&o.stderr);
        if !o.status.success() {
            anyhow::bail!("valgrind failed ({}): {}", o.status, err.trim());
        }
        let refs = super::ab::parse_i_refs(&err)
            .ok_or_else(|| anyhow::anyhow!("no `I refs` line in valgrind's output"))?;
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).context("bench --json")?;
        Ok((refs, v["particles"].as_f64().unwrap_or(f64::NAN)))
    };
    let (with, particles) = count(steps)?;
    let (without, _) = count(0)?;
    Ok(Some((with - without) / (particles * steps.max(1) as f64)))
}

/// Run the comparison: for each thread count, `pairs` interleaved repetitions of the 3D
/// block and of the 2D solver's seed block (0.5 mm cells, no crack).
pub fn run(a: &BenchArgs, out: Option<&Path>) -> anyhow::Result<Report> {
    let machine = Machine::now();
    let kernel = a.kernel.kernel()?;
    let reps = a.pairs.max(1);
    let mut rows = Vec::new();
    for &threads in &a.thread_counts {
        let mut r3 = Vec::new();
        let mut r2 = Vec::new();
        let mut last3 = None;
        let mut p2 = 0;
        for _ in 0..reps {
            match time_block(
                a.cells,
                a.particles_per_cell,
                threads,
                a.warmup,
                a.steps,
                kernel,
            )? {
                Ok(t) => {
                    r3.push(t.median_particle_steps_per_second);
                    last3 = Some(t);
                }
                Err(e) => anyhow::bail!("3D block: {e}"),
            }
            let (rate, n) = time_2d(threads, a.warmup, a.steps, kernel)?;
            r2.push(rate);
            p2 = n;
        }
        let t3 = last3.ok_or_else(|| anyhow::anyhow!("no 3D run"))?;
        rows.push(Row {
            case: format!("3D block ({} cells/side)", a.cells),
            threads,
            particles: t3.particles,
            particle_steps_per_second: super::median(&r3),
            bytes_per_particle_step: bytes_model(3, t3.nodes_per_particle),
            instructions_per_particle_step: None,
            pass_shares: Some(t3.pass_shares),
        });
        rows.push(Row {
            case: "2D seed block, 2D solver (no crack)".into(),
            threads,
            particles: p2,
            particle_steps_per_second: super::median(&r2),
            bytes_per_particle_step: f64::NAN,
            instructions_per_particle_step: None,
            pass_shares: None,
        });
    }
    if a.instructions {
        let i3 = instructions_3d(16, 4, a.kernel)?;
        let i2 = super::ab::instructions_per_particle_step(CaseArg::NoCrack, 0.002, 4, a.kernel)?;
        for r in &mut rows {
            r.instructions_per_particle_step = if r.case.starts_with("3D") { i3 } else { i2 };
        }
    }
    let report = Report { machine, rows };
    let md = markdown(&report, kernel);
    #[allow(clippy::print_stdout)]
    {
        println!("{md}");
    }
    if let Some(dir) = out {
        write_file(dir, "throughput3d.md", &md)?;
        write_file(
            dir,
            "throughput3d.json",
            serde_json::to_string_pretty(&report)?,
        )?;
    }
    Ok(report)
}

/// The 2D solver's seed block (no crack, 0.5 mm): median-step particle-steps/s and the
/// particle count.
fn time_2d(
    threads: usize,
    warmup: u64,
    steps: u64,
    kernel: Kernel,
) -> anyhow::Result<(f64, usize)> {
    use fracture_solver::{Simulation, SolverConfig};
    let scene =
        super::throughput::case_scene(super::throughput::Case::NoCrack, 0.0005, 2, warmup + steps)?;
    let mut sim = Simulation::new(
        &fracture_api::ValidScene::new(scene)?,
        SolverConfig::with_threads(threads),
    )
    .context("building the 2D block")?;
    sim.set_kernel(match kernel {
        Kernel::Portable => fracture_solver::kernel::Kernel::Portable,
        Kernel::Fma => fracture_solver::kernel::Kernel::Fma,
    });
    for _ in 0..warmup {
        sim.step().map_err(|e| anyhow::anyhow!("2D block: {e}"))?;
    }
    let mut times = Vec::new();
    for _ in 0..steps {
        let t = Instant::now();
        sim.step().map_err(|e| anyhow::anyhow!("2D block: {e}"))?;
        times.push(t.elapsed().as_secs_f64());
    }
    let n = sim.particle_count();
    Ok((n as f64 / super::median(&times), n))
}

fn markdown(r: &Report, kernel: Kernel) -> String {
    let rows: Vec<Vec<String>> = r
        .rows
        .iter()
        .map(|row| {
            vec![
                row.case.clone(),
                row.threads.to_string(),
                row.particles.to_string(),
                format!("{:.2} M", row.particle_steps_per_second / 1e6),
                sig(row.bytes_per_particle_step, 4),
                row.instructions_per_particle_step
                    .map_or_else(|| "–".into(), |i| format!("{i:.0}")),
                row.pass_shares.map_or_else(
                    || "–".into(),
                    |s| {
                        format!(
                            "p2g {:.0} %, forces {:.0} %, update {:.0} %, strain {:.0} %, grid {:.0} %, sort {:.0} %",
                            100.0 * s[1],
                            100.0 * s[2],
                            100.0 * s[3],
                            100.0 * s[4],
                            100.0 * s[5],
                            100.0 * s[0]
                        )
                    },
                ),
            ]
        })
        .collect();
    format!(
        "{}\n{} kernel; {}\n",
        markdown_table(
            &[
                "case",
                "threads",
                "particles",
                "particle-steps/s",
                "model B/particle-step",
                "instructions/particle-step",
                "pass shares",
            ],
            &rows
        ),
        kernel.name(),
        r.machine.describe()
    )
}
