//! `fracture bench skip`: measured figures of the work a scene does not pay for
//! (`docs/performance.md`): crack code in a scene without cracks, J-integrals between
//! history samples, inactive grid regions, and snapshot fields nobody asked for.

use std::path::Path;
use std::time::Instant;

use anyhow::Context;
use fracture_api::Scene;
use fracture_api::scene::FieldKind;
use fracture_api::validate::scene_from_value;
use fracture_solver::{Simulation, SolverConfig, WorkCounters};

use super::Machine;
use super::throughput::{Case, case_scene};
use crate::report::{markdown_table, write_file};

/// Options of `fracture bench skip`.
#[derive(Debug, Clone)]
pub struct Options {
    /// Cell size of the seed block (m).
    pub cell_size: f64,
    /// Timed steps per measurement.
    pub steps: u64,
    /// Warm-up steps.
    pub warmup: u64,
    /// Solver threads (`all`: one per core).
    pub threads: fracture_solver::Parallelism,
}

/// One measurement.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Figure {
    /// Which claim.
    pub claim: &'static str,
    /// The configuration.
    pub config: String,
    /// Particles.
    pub particles: usize,
    /// Timed steps.
    pub steps: u64,
    /// Seconds per step (or per snapshot).
    pub seconds_per_step: f64,
    /// Crack field passes, contact passes, surface moves, propagation checks, J evaluations
    /// over the timed steps.
    pub counters: [u64; 5],
    /// A note (ratio, sizes).
    pub note: String,
}

fn delta(a: WorkCounters, b: WorkCounters) -> [u64; 5] {
    [
        b.crack_field_passes - a.crack_field_passes,
        b.contact_passes - a.contact_passes,
        b.surface_moves - a.surface_moves,
        b.propagation_checks - a.propagation_checks,
        b.j_evaluations - a.j_evaluations,
    ]
}

/// Time `steps` steps after `warmup`, sampling crack tips every `every` steps (0: never).
fn time_steps(
    scene: &Scene,
    o: &Options,
    every: u64,
) -> anyhow::Result<(Simulation, f64, [u64; 5])> {
    let mut sim = Simulation::new(
        &fracture_api::ValidScene::new(scene.clone())?,
        SolverConfig { threads: o.threads },
    )
    .with_context(|| format!("building {}", scene.name))?;
    for _ in 0..o.warmup {
        sim.step().map_err(|e| anyhow::anyhow!("{e}"))?;
    }
    let c0 = sim.work_counters();
    let mut times = Vec::with_capacity(o.steps as usize);
    for k in 1..=o.steps {
        let start = Instant::now();
        sim.step().map_err(|e| anyhow::anyhow!("{e}"))?;
        if every > 0 && k.is_multiple_of(every) {
            let _ = sim.crack_tips();
        }
        times.push(start.elapsed().as_secs_f64());
    }
    // The median step: robust to other load. With sampling every k steps, the sampled
    // steps are 1/k of them, so the median hides them for k > 2: report the mean then.
    let per = if every > 2 {
        times.iter().sum::<f64>() / times.len().max(1) as f64
    } else {
        super::median(&times)
    };
    let c = delta(c0, sim.work_counters());
    Ok((sim, per, c))
}

/// A square Homalite body of side `side` (m) at the corner of a grid of side `grid` (m),
/// 2×2 particles per cell, pushed at 5 m/s on its left edge.
fn body_in_grid(h: f64, side: f64, grid: f64, steps: u64) -> anyhow::Result<Scene> {
    let m = 3.0 * h;
    let v = serde_json::json!({
        "name": format!("body {side} m in grid {grid} m"),
        "grid": {"cell_size": h, "min": [0.0, 0.0], "max": [grid, grid]},
        "materials": {"m": fracture_verify::homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [m, m], "max": [m + side, m + side]}}}],
        "boundary_conditions": [{"region": {"rectangle": {"min": [0.0, 0.0], "max": [m, m + side]}},
                                 "velocity": {"x": 5.0}}],
        "time": {"end": 1.0, "cfl": 0.5}
    });
    let mut s = scene_from_value(v).map_err(|e| anyhow::anyhow!("{e}"))?;
    let dt = s
        .time_step()
        .ok_or_else(|| anyhow::anyhow!("no time step"))?;
    s.time.end = (steps as f64 + 0.5) * dt;
    Ok(s)
}

/// Produce the figures; print the Markdown report; write `skip.md` and `skip.json` into
/// `out` when given.
pub fn run(o: &Options, out: Option<&Path>) -> anyhow::Result<Vec<Figure>> {
    let machine = Machine::now();
    let total = o.warmup + o.steps;
    let mut figs = Vec::new();
    let h = o.cell_size;

    // 1. No crack: no crack code runs, and the crack arrays are never allocated.
    let plain = case_scene(Case::NoCrack, h, 2, total)?;
    let (sim, t_plain, c_plain) = time_steps(&plain, o, 1)?;
    let n = sim.particle_count();
    figs.push(Figure {
        claim: "no crack → no crack code",
        config: "seed block, no crack (crack_tips() called every step anyway)".into(),
        particles: n,
        steps: o.steps,
        seconds_per_step: t_plain,
        counters: c_plain,
        note: format!(
            "crack arrays: fmask {} entries, grad_u {} entries",
            sim.particles().fmask.len(),
            sim.particles().grad_u.len()
        ),
    });
    drop(sim);
    let cracked = case_scene(Case::Crack, h, 2, total)?;
    let (_, t_crack, c_crack) = time_steps(&cracked, o, 0)?;
    figs.push(Figure {
        claim: "no crack → no crack code",
        config: "same block with one crack, no history sample".into(),
        particles: n,
        steps: o.steps,
        seconds_per_step: t_crack,
        counters: c_crack,
        note: format!("{:.2}× the step time without the crack", t_crack / t_plain),
    });

    // 2. J only when sampled or needed for growth.
    for every in [1u64, 10] {
        let (_, t, c) = time_steps(&cracked, o, every)?;
        figs.push(Figure {
            claim: "J only when sampled or needed for growth",
            config: format!("one crack, history sample every {every} step(s)"),
            particles: n,
            steps: o.steps,
            seconds_per_step: t,
            counters: c,
            note: format!(
                "{} J evaluations in {} steps; {:.2}× the unsampled crack step",
                c[4],
                o.steps,
                t / t_crack
            ),
        });
    }
    let growing = case_scene(Case::Propagation, h, 2, total)?;
    let (_, t, c) = time_steps(&growing, o, 10)?;
    figs.push(Figure {
        claim: "J only when sampled or needed for growth",
        config: "propagating crack, history sample every 10 steps".into(),
        particles: n,
        steps: o.steps,
        seconds_per_step: t,
        counters: c,
        note: format!(
            "{} J evaluations in {} steps: the growth check needs J every step, the samples reuse it",
            c[4], o.steps
        ),
    });

    // 3. Inactive grid regions: a 50 mm body in a tight grid and in a 500 mm grid (same
    // cell size as the block: 10,000 cells and 40,000 particles at 0.5 mm).
    let side = 0.05;
    let hb = h;
    let tight = body_in_grid(hb, side, side + 6.0 * hb, total)?;
    let large = body_in_grid(hb, side, 0.5, total)?;
    let (st, t_tight, _) = time_steps(&tight, o, 0)?;
    let (nt, gt) = (st.particle_count(), st.grid_node_count());
    drop(st);
    let (sl, t_large, _) = time_steps(&large, o, 0)?;
    let gl = sl.grid_node_count();
    drop(sl);
    figs.push(Figure {
        claim: "inactive grid regions cost nothing",
        config: format!("50 mm body, tight grid ({gt} nodes)"),
        particles: nt,
        steps: o.steps,
        seconds_per_step: t_tight,
        counters: [0; 5],
        note: String::new(),
    });
    figs.push(Figure {
        claim: "inactive grid regions cost nothing",
        config: format!("same body, 500 mm grid ({gl} nodes)"),
        particles: nt,
        steps: o.steps,
        seconds_per_step: t_large,
        counters: [0; 5],
        note: format!(
            "{:.2}× the tight grid's step time with {:.0}× the nodes",
            t_large / t_tight,
            gl as f64 / gt as f64
        ),
    });

    // 4. Snapshots: one field against all of them, against a step.
    let sim = Simulation::new(
        &fracture_api::ValidScene::new(plain.clone())?,
        SolverConfig { threads: o.threads },
    )?;
    let reps = 5;
    let time_snap = |fields: &[FieldKind]| {
        let mut comps = 0;
        let mut times = Vec::new();
        for i in 0..reps {
            let start = Instant::now();
            comps = sim.snapshot(i, fields).components.len();
            times.push(start.elapsed().as_secs_f64());
        }
        (super::median(&times), comps)
    };
    let (t1, c1) = time_snap(&[FieldKind::Stress]);
    let (ta, ca) = time_snap(&FieldKind::ALL);
    figs.push(Figure {
        claim: "snapshot fields nobody asked for are not computed",
        config: format!("seed block, snapshot of stress ({c1} components)"),
        particles: n,
        steps: 1,
        seconds_per_step: t1,
        counters: [0; 5],
        note: format!("{:.2} steps' time", t1 / t_plain),
    });
    figs.push(Figure {
        claim: "snapshot fields nobody asked for are not computed",
        config: format!("seed block, snapshot of all fields ({ca} components)"),
        particles: n,
        steps: 1,
        seconds_per_step: ta,
        counters: [0; 5],
        note: format!(
            "{:.2}× the one-field snapshot; {:.2} steps' time",
            ta / t1,
            ta / t_plain
        ),
    });

    let md = markdown(&figs, &machine, o);
    #[allow(clippy::print_stdout)]
    {
        println!("{md}");
    }
    if let Some(out) = out {
        write_file(out, "skip.md", &md)?;
        write_file(
            out,
            "skip.json",
            &serde_json::to_string_pretty(
                &serde_json::json!({"machine": machine, "figures": figs}),
            )?,
        )?;
    }
    Ok(figs)
}

fn markdown(figs: &[Figure], machine: &Machine, o: &Options) -> String {
    let mut s = format!(
        "# What a scene does not pay for\n\n`fracture bench skip --cell-size {} --steps {} --warmup {} --threads {}`; {}.\n\
         Time per step: the median step (the mean where a sample falls every 10 steps); \
         snapshots: the median of 5. Counters over the timed steps: crack field passes / \
         contact passes / surface moves / propagation checks / J evaluations.\n\n",
        o.cell_size,
        o.steps,
        o.warmup,
        o.threads,
        machine.describe()
    );
    let rows: Vec<Vec<String>> = figs
        .iter()
        .map(|f| {
            vec![
                f.claim.into(),
                f.config.clone(),
                f.particles.to_string(),
                f.steps.to_string(),
                format!("{:.3e}", f.seconds_per_step),
                f.counters
                    .iter()
                    .map(u64::to_string)
                    .collect::<Vec<_>>()
                    .join(" / "),
                f.note.clone(),
            ]
        })
        .collect();
    s.push_str(&markdown_table(
        &[
            "claim",
            "configuration",
            "particles",
            "steps",
            "s per step (or snapshot)",
            "counters",
            "figure",
        ],
        &rows,
    ));
    s
}
