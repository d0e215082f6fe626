//! `fracture bench throughput`: particle-steps per second on the seed's 500,000-particle
//! block (a) without a crack, (b) with one crack (contact, J at every history sample),
//! (c) with that crack propagating, each on 1 and 2 threads; the fraction of the machine's
//! memory bandwidth (a STREAM-like triad measured here) that a bytes-per-particle-step model
//! of the solver implies.

use std::path::Path;
use std::time::Instant;

use anyhow::Context;
use fracture_api::Scene;
use fracture_api::validate::scene_from_value;
use fracture_solver::grid::Node;
use fracture_solver::particles::{Cold, Kin, Mech};
use fracture_solver::shape::CachedW2;
use fracture_solver::{Simulation, SolverConfig};
use rayon::prelude::*;

use super::Machine;
use crate::report::{csv_line, markdown_table, sig, write_file};

/// A throughput case.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Case {
    /// The seed block, no crack.
    NoCrack,
    /// One 50 mm edge crack at mid-height (frictionless contact), J and K at every history
    /// sample.
    Crack,
    /// The same crack with energy-release propagation (G_c = 10 J/m²), the two halves of
    /// the block pulled apart at ±2 m/s so the tip grows within the timed steps.
    Propagation,
}

impl Case {
    /// All cases.
    pub const ALL: [Case; 3] = [Case::NoCrack, Case::Crack, Case::Propagation];
    /// Name in the tables.
    pub fn name(self) -> &'static str {
        match self {
            Case::NoCrack => "no crack",
            Case::Crack => "crack + contact + J per sample",
            Case::Propagation => "crack + propagation",
        }
    }
}

/// The seed block of `case` (`super::command::bench_block` plus the crack).
pub fn case_scene(case: Case, cell_size: f64, ppc: u32, steps: u64) -> anyhow::Result<Scene> {
    let base = super::command::bench_block(cell_size, ppc, steps)?;
    if case == Case::NoCrack {
        return Ok(base);
    }
    let h = cell_size;
    let m = 3.0 * h;
    let (w, l) = (0.125, 0.25);
    let mut v = serde_json::to_value(&base)?;
    // Mid-height, between two particle rows (mid-cell), from outside the left edge (a mouth)
    // to 50 mm in.
    let yc = m + 0.5 * l + 0.5 * h;
    let mut crack = serde_json::json!({"points": [[0.0, yc], [m + 0.05, yc]]});
    if case == Case::Propagation {
        crack["propagation"] =
            serde_json::json!({"criterion": "energy_release", "toughness": 10.0});
        // A ring of 6 cells, as the bench measured before issue 34, so the J window's cost per
        // particle-step is the same at every cell size (the default, 1/16 of the block's
        // 125 mm, spans under the 3 cells a growing ring needs at the CI's 5 mm cells). The
        // bench measures cost, not the crack's physics.
        crack["j_integral"] = serde_json::json!({"method": "domain", "radius": 6.0 * h});
        // Two bodies meeting at the crack line, moving apart: the crack opens at once.
        v["bodies"] = serde_json::json!([
            {"material": "homalite", "region": {"rectangle": {"min": [m, m], "max": [m + w, yc]}},
             "particles_per_cell": ppc, "initial_velocity": [0.0, -2.0]},
            {"material": "homalite", "region": {"rectangle": {"min": [m, yc], "max": [m + w, m + l]}},
             "particles_per_cell": ppc, "initial_velocity": [0.0, 2.0]}
        ]);
    }
    v["cracks"] = serde_json::json!([crack]);
    v["name"] = serde_json::json!(format!("bench-throughput-{}", case.name()));
    scene_from_value(v).map_err(|e| anyhow::anyhow!("{e}"))
}

/// One timed run.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Run {
    /// Case name.
    pub case: &'static str,
    /// Solver threads.
    pub threads: usize,
    /// Particles.
    pub particles: usize,
    /// Timed steps.
    pub steps: u64,
    /// Wall time of the timed steps (s).
    pub wall_seconds: f64,
    /// Particle-steps per second (all timed steps).
    pub particle_steps_per_second: f64,
    /// Particle-steps per second of the median step (robust to other load).
    pub median_particle_steps_per_second: f64,
    /// J evaluations during the timed steps.
    pub j_evaluations: u64,
    /// Timed steps in which a tip grew.
    pub growth_steps: u64,
    /// Model bytes per particle-step.
    pub bytes_per_particle_step: f64,
    /// Model traffic rate (GB/s) = bytes per particle-step × particle-steps/s.
    pub model_gb_per_s: f64,
    /// That over the triad bandwidth on the same thread count.
    pub fraction_of_bandwidth: f64,
    /// Instructions per particle-step of the case (cachegrind, one thread, 0.002 m cells or
    /// the matrix's if coarser, 20 steps; `--instructions`), where counted.
    pub instructions_per_particle_step: Option<f64>,
}

/// Options of the matrix.
#[derive(Debug, Clone)]
pub struct Options {
    /// Cell size (m).
    pub cell_size: f64,
    /// Particles per cell direction.
    pub ppc: u32,
    /// Timed steps.
    pub steps: u64,
    /// Warm-up steps.
    pub warmup: u64,
    /// Thread counts.
    pub threads: Vec<usize>,
    /// History sample (J and K of every tip) every this many steps.
    pub history_every: u64,
    /// Arithmetic of the particle passes.
    pub kernel: fracture_solver::kernel::Kernel,
    /// Count instructions per particle-step under cachegrind with this kernel argument
    /// (`--instructions`).
    pub instructions: Option<super::command::KernelArg>,
}

/// The bytes-per-particle-step model: bytes of the particle arrays each of the four passes
/// reads and writes (a written array counts twice: read for ownership, written back), plus
/// the grid traffic per particle. `cracks` adds the crack arrays (field mask, displacement
/// gradient, initial position).
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct BytesModel {
    /// Particle-array bytes per particle-step.
    pub particle: f64,
    /// Grid bytes per particle-step.
    pub grid: f64,
}

impl BytesModel {
    /// The model for `nodes_per_particle` active nodes per particle. Without a crack the
    /// solver fuses the last strain update with the next step's P2G (one sweep: the P2G's
    /// own reads of kin and mech drop out).
    pub fn new(cracks: bool, nodes_per_particle: f64) -> BytesModel {
        let kin = std::mem::size_of::<Kin>() as f64;
        let mech = std::mem::size_of::<Mech>() as f64;
        let stress = 32.0; // [f64; 4]
        let wden = 8.0; // strain energy density, f64
        let wts = std::mem::size_of::<CachedW2>() as f64;
        let cold = std::mem::size_of::<Cold>() as f64;
        let (mask, grad) = (2.0, 32.0);
        // P2G: write weights; read kin, mech (fused into the last strain update, which
        // reads mech anyway, it adds only kin).
        let mut b = 2.0 * wts + kin;
        if cracks {
            b += mech;
        }
        // Forces: read weights, mech; stress and strain energy density read + written.
        b += wts + mech + 2.0 * stress + 2.0 * wden;
        // Update: read weights, mech; kin read + written (v and x).
        b += wts + mech + 2.0 * kin;
        // Last strain update: read weights, mech; stress and strain energy density read +
        // written.
        b += wts + mech + 2.0 * stress + 2.0 * wden;
        if cracks {
            // Mask written in the field pass and read in the four passes; initial position
            // read in P2G; displacement gradient read + written in both stress updates.
            b += 2.0 * mask + 4.0 * mask + cold + 4.0 * grad;
        }
        // Grid: per active node and step, the reset writes it, the active-box count reads
        // it, the three nodal passes read and write it, and the four particle passes each
        // bring a node in and (scatter) write it back: 1 + 1 + 6 + 8 = 16 node transfers.
        let node = std::mem::size_of::<Node>() as f64;
        BytesModel {
            particle: b,
            grid: 16.0 * node * nodes_per_particle,
        }
    }
    /// Total bytes per particle-step.
    pub fn total(&self) -> f64 {
        self.particle + self.grid
    }
}

/// STREAM-like triad `a[i] = b[i] + s·c[i]` over three arrays of `n` f64 on `threads` threads:
/// the best of `reps` repetitions, in bytes per second (24 bytes per element, the STREAM
/// convention, which does not count the write-allocate read of a).
pub fn triad_bandwidth(n: usize, threads: usize, reps: usize) -> anyhow::Result<f64> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .context("triad thread pool")?;
    let mut a = vec![0.0f64; n];
    let b = vec![1.0f64; n];
    let c = vec![2.0f64; n];
    let s = 3.0;
    let chunk = n.div_ceil(threads.max(1) * 8).max(1024);
    let mut best = f64::INFINITY;
    for _ in 0..reps.max(1) {
        let start = Instant::now();
        pool.install(|| {
            a.par_chunks_mut(chunk)
                .zip(b.par_chunks(chunk).zip(c.par_chunks(chunk)))
                .for_each(|(a, (b, c))| {
                    for ((a, b), c) in a.iter_mut().zip(b).zip(c) {
                        *a = b + s * c;
                    }
                });
        });
        best = best.min(start.elapsed().as_secs_f64());
    }
    // Keep the result observable.
    if !a[n / 2].is_finite() {
        anyhow::bail!("triad produced a non-finite value");
    }
    Ok(24.0 * n as f64 / best)
}

fn time_case(case: Case, threads: usize, o: &Options) -> anyhow::Result<(Run, f64)> {
    let scene = case_scene(case, o.cell_size, o.ppc, o.warmup + o.steps)?;
    let mut sim = Simulation::new(
        &fracture_api::ValidScene::new(scene.clone())?,
        SolverConfig::with_threads(threads),
    )
    .with_context(|| format!("building the {} block", case.name()))?;
    sim.set_kernel(o.kernel);
    let every = o.history_every.max(1);
    let sample = |sim: &mut Simulation, k: u64| {
        if case != Case::NoCrack && k.is_multiple_of(every) {
            let _ = sim.crack_tips();
        }
    };
    for k in 0..o.warmup {
        sim.step()
            .map_err(|e| anyhow::anyhow!("{}: {e}", case.name()))?;
        sample(&mut sim, k + 1);
    }
    let c0 = sim.work_counters();
    let mut growth = 0;
    let mut active = 0.0;
    let mut times = Vec::with_capacity(o.steps as usize);
    let start = Instant::now();
    for k in 0..o.steps {
        let t0 = Instant::now();
        let st = sim
            .step()
            .map_err(|e| anyhow::anyhow!("{}: {e}", case.name()))?;
        growth += u64::from(st.grew);
        active += st.active_nodes as f64;
        sample(&mut sim, o.warmup + k + 1);
        times.push(t0.elapsed().as_secs_f64());
    }
    let wall = start.elapsed().as_secs_f64();
    let med = super::median(&times);
    let c1 = sim.work_counters();
    let particles = sim.particle_count();
    let nodes_per_particle = active / (o.steps.max(1) as f64) / particles.max(1) as f64;
    let model = BytesModel::new(case != Case::NoCrack, nodes_per_particle);
    let rate = if wall > 0.0 {
        (particles as f64 * o.steps as f64) / wall
    } else {
        0.0
    };
    Ok((
        Run {
            case: case.name(),
            threads: sim.threads(),
            particles,
            steps: o.steps,
            wall_seconds: wall,
            particle_steps_per_second: rate,
            median_particle_steps_per_second: particles as f64 / med,
            j_evaluations: c1.j_evaluations - c0.j_evaluations,
            growth_steps: growth,
            bytes_per_particle_step: model.total(),
            model_gb_per_s: model.total() * rate / 1e9,
            fraction_of_bandwidth: f64::NAN,
            instructions_per_particle_step: None,
        },
        nodes_per_particle,
    ))
}

/// The matrix's report.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Report {
    /// Where and when.
    pub machine: Machine,
    /// Cell size (m).
    pub cell_size: f64,
    /// History sample every this many steps.
    pub history_every: u64,
    /// Triad bandwidth (GB/s) per thread count.
    pub triad_gb_per_s: Vec<(usize, f64)>,
    /// The model without and with a crack (bytes per particle-step).
    pub model_no_crack: BytesModel,
    /// The model with a crack.
    pub model_crack: BytesModel,
    /// Arithmetic of the particle passes (`portable`, `fma`).
    pub kernel: &'static str,
    /// The runs.
    pub runs: Vec<Run>,
    /// Why instructions were asked for and not counted.
    pub instructions_note: Option<&'static str>,
    /// Cell size (m) of the instruction counts.
    pub instructions_cell: f64,
}

/// Cell size (m) of the instruction counts (31,250 particles: a cachegrind run of seconds).
pub const INSTRUCTIONS_CELL: f64 = 0.002;

/// Run the matrix; print the Markdown table; write `throughput.csv`, `throughput.json` and
/// `throughput.md` into `out` when given.
pub fn run(o: &Options, out: Option<&Path>) -> anyhow::Result<Report> {
    let machine = Machine::now();
    // 2^24 doubles per array: 3 × 128 MiB, far beyond any cache.
    let n = 1usize << 24;
    let mut triad = Vec::new();
    for &t in &o.threads {
        let t = if t == 0 { machine.cores } else { t };
        triad.push((t, triad_bandwidth(n, t, 5)? / 1e9));
    }
    let mut runs = Vec::new();
    let mut npp = 0.25;
    let mut instructions_note = None;
    // Cachegrind runs ~50x slower: a coarser matrix is counted at its own cell size.
    let instructions_cell = o.cell_size.max(INSTRUCTIONS_CELL);
    for case in Case::ALL {
        let instructions = match o.instructions {
            Some(k) => {
                let c = super::command::CaseArg::of(case);
                let n = super::ab::instructions_per_particle_step(c, instructions_cell, 20, k)?;
                if n.is_none() {
                    instructions_note = Some("valgrind is not installed: no instruction counts");
                }
                n
            }
            None => None,
        };
        for &t in &o.threads {
            let (mut r, nodes) = time_case(case, t, o)?;
            r.instructions_per_particle_step = instructions;
            npp = nodes;
            let bw = triad
                .iter()
                .find(|(tt, _)| *tt == r.threads)
                .map_or(f64::NAN, |x| x.1);
            r.fraction_of_bandwidth = r.model_gb_per_s / bw;
            eprintln!(
                "{} on {} threads: {:.4e} particle-steps/s",
                r.case, r.threads, r.particle_steps_per_second
            );
            runs.push(r);
        }
    }
    let report = Report {
        machine,
        cell_size: o.cell_size,
        history_every: o.history_every,
        triad_gb_per_s: triad,
        model_no_crack: BytesModel::new(false, npp),
        model_crack: BytesModel::new(true, npp),
        kernel: o.kernel.name(),
        runs,
        instructions_note,
        instructions_cell,
    };
    let md = markdown(&report);
    #[allow(clippy::print_stdout)]
    {
        println!("{md}");
    }
    if let Some(out) = out {
        write_file(out, "throughput.md", &md)?;
        write_file(
            out,
            "throughput.json",
            &serde_json::to_string_pretty(&report)?,
        )?;
        let mut csv = String::from(
            "case,threads,particles,steps,wall_seconds,particle_steps_per_second,median_particle_steps_per_second,j_evaluations,growth_steps,bytes_per_particle_step,model_gb_per_s,fraction_of_bandwidth,instructions_per_particle_step\n",
        );
        for r in &report.runs {
            csv.push_str(&csv_line(&[
                r.case.into(),
                r.threads.to_string(),
                r.particles.to_string(),
                r.steps.to_string(),
                format!("{:.5}", r.wall_seconds),
                format!("{:.6e}", r.particle_steps_per_second),
                format!("{:.6e}", r.median_particle_steps_per_second),
                r.j_evaluations.to_string(),
                r.growth_steps.to_string(),
                format!("{:.1}", r.bytes_per_particle_step),
                format!("{:.3}", r.model_gb_per_s),
                format!("{:.4}", r.fraction_of_bandwidth),
                r.instructions_per_particle_step
                    .map_or(String::new(), |n| format!("{n:.1}")),
            ]));
        }
        write_file(out, "throughput.csv", &csv)?;
    }
    Ok(report)
}

fn markdown(r: &Report) -> String {
    let mut s = format!(
        "# Throughput\n\n`fracture bench throughput`: the seed block at {} m cells ({} particles), \
         {} timed steps; history sample (J, K of every tip) every {} step(s); {} kernel; {}.\n\n",
        r.cell_size,
        r.runs.first().map_or(0, |x| x.particles),
        r.runs.first().map_or(0, |x| x.steps),
        r.history_every,
        r.kernel,
        r.machine.describe()
    );
    let rows: Vec<Vec<String>> = r
        .runs
        .iter()
        .map(|x| {
            vec![
                x.case.into(),
                x.threads.to_string(),
                format!("{:.3e}", x.wall_seconds / x.steps.max(1) as f64),
                format!("{:.2} M", x.particle_steps_per_second / 1e6),
                format!("{:.2} M", x.median_particle_steps_per_second / 1e6),
                x.j_evaluations.to_string(),
                x.growth_steps.to_string(),
                format!("{:.0}", x.bytes_per_particle_step),
                sig(x.model_gb_per_s, 3),
                format!("{:.0} %", 100.0 * x.fraction_of_bandwidth),
                x.instructions_per_particle_step
                    .map_or("–".into(), |n| format!("{n:.0}")),
            ]
        })
        .collect();
    s.push_str(&markdown_table(
        &[
            "case",
            "threads",
            "s/step",
            "particle-steps/s",
            "median step (particle-steps/s)",
            "J evaluations",
            "growth steps",
            "model B/particle-step",
            "model GB/s",
            "of triad bandwidth",
            "instructions/particle-step",
        ],
        &rows,
    ));
    s.push_str("\nTriad bandwidth (a = b + s·c, 3 × 128 MiB, best of 5, 24 B/element): ");
    s.push_str(
        &r.triad_gb_per_s
            .iter()
            .map(|(t, g)| format!("{g:.2} GB/s on {t} thread(s)"))
            .collect::<Vec<_>>()
            .join(", "),
    );
    s.push_str(&format!(
        ".\n\nBytes model per particle-step: particle arrays {:.0} B without a crack, {:.0} B \
         with one; grid {:.0} B (16 transfers of a {} B node × {:.3} active nodes per particle).\n",
        r.model_no_crack.particle,
        r.model_crack.particle,
        r.model_no_crack.grid,
        std::mem::size_of::<Node>(),
        r.model_no_crack.grid / (16.0 * std::mem::size_of::<Node>() as f64),
    ));
    if r.runs
        .iter()
        .any(|x| x.instructions_per_particle_step.is_some())
    {
        s.push_str(&format!(
            "\nInstructions per particle-step: valgrind's cachegrind on `fracture bench --case \
             <case> --threads 1` at {} m cells, 21 steps less 1 (set-up and the first step \
             subtracted); the same for every thread count.\n",
            r.instructions_cell
        ));
    }
    if let Some(n) = r.instructions_note {
        s.push_str(&format!("\n{n}.\n"));
    }
    s
}
