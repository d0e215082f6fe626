//! Checkpoints (`solver/src/sim/checkpoint.rs`): a run interrupted after k steps, written to
//! bytes, restored into a fresh simulation and stepped to the end must be bitwise identical
//! to the uninterrupted run: every particle quantity, every crack point (line, surfaces,
//! reference position, zone and cohesive states), every tip state (growth, filters, speed
//! histories, cached J), the energy row and the crack-tip rows after every step, and the
//! work counters. This is what guards the completeness of the checkpoint: a persistent
//! field left out makes the restored run diverge. Reference: the uninterrupted run;
//! tolerance: none (`f64::to_bits` equality, or the exact `{:?}` text of f64s). Scenes: a
//! strip whose edge crack grows by the equation of motion with a process zone, the same
//! strip opening a cohesive interface, and a plain body under a traction load; 1 mm cells,
//! 2×2 particles per cell, a few hundred steps; 1 and 2 threads.
#![allow(clippy::unwrap_used)]

mod common;
use common::*;
use fracture_api::{Scene, ValidScene};
use fracture_solver::{CheckpointError, Simulation, SolverConfig};
use serde_json::json;

/// A strip 150 mm long and 21 mm high (1 mm cells), gripped top and bottom and pulled apart
/// over 40 µs, with an edge crack of 30 mm on its mid-plane; `growth` adds equation-of-motion
/// growth with a process zone (toughness well below the strip's G_∞), `cohesive` a cohesive
/// interface ahead of the crack.
fn strip(growth: bool, cohesive: bool, end: f64) -> Scene {
    let (h, len, b) = (0.001, 0.150, 0.010);
    let m = 2.0 * h;
    let (y0, y1) = (m, m + 2.0 * b);
    let cy = 0.5 * (y0 + y1) + 0.5 * h;
    let y1 = y1 + h;
    let (t_load, ramp) = (4.0e-5, 1.0e-5);
    let v = 2.0e-5 / (t_load - 0.5 * ramp);
    let mut crack = json!({"points": [[m - 0.5 * h, cy], [m + 0.030, cy]],
                           "j_integral": {"method": "domain", "radius": 6.0 * h}});
    if growth {
        crack["propagation"] = json!({"criterion": "energy_release", "toughness": 150.0,
                                      "direction": {"fixed": [1.0, 0.0]},
                                      "speed": "equation_of_motion"});
    }
    let mode = json!({"strength": 4.0e6, "toughness": 150.0});
    let interfaces = if cohesive {
        json!([{"points": [[m + 0.030, cy], [m + len + 0.5 * h, cy]],
                "cohesive": {"law": "linear", "normal": mode, "shear": mode}}])
    } else {
        json!([])
    };
    scene(json!({
        "grid": {"cell_size": h, "min": [0.0, 0.0], "max": [len + 2.0 * m, y1 + m]},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [m, y0], "max": [m + len, y1]}}}],
        "cracks": [crack],
        "interfaces": interfaces,
        "boundary_conditions": [
            {"region": {"rectangle": {"min": [0.0, y1 - 0.5 * h], "max": [1.0, 1.0]}},
             "velocity": {"x": 0.0, "y": v}, "ramp_time": ramp, "end": t_load},
            {"region": {"rectangle": {"min": [0.0, y1 - 0.5 * h], "max": [1.0, 1.0]}},
             "velocity": {"x": 0.0, "y": 0.0}, "start": t_load},
            {"region": {"rectangle": {"min": [0.0, 0.0], "max": [1.0, y0 + 0.5 * h]}},
             "velocity": {"x": 0.0, "y": -v}, "ramp_time": ramp, "end": t_load},
            {"region": {"rectangle": {"min": [0.0, 0.0], "max": [1.0, y0 + 0.5 * h]}},
             "velocity": {"x": 0.0, "y": 0.0}, "start": t_load}
        ],
        "output": {"speed_window": 2.0e-6},
        "time": {"end": end, "cfl": 0.5}
    }))
}

/// A plain block under a ramped traction with kinetic damping, fast enough that particles
/// leave their strips (re-sorts).
fn plain() -> Scene {
    scene(json!({
        "grid": {"cell_size": 0.001, "min": [0.0, 0.0], "max": [0.06, 0.03]},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [0.004, 0.004], "max": [0.036, 0.026]}},
                    "initial_velocity": [40.0, 0.0]}],
        "loads": [{"region": {"rectangle": {"min": [0.0, 0.0255], "max": [1.0, 1.0]}},
                   "traction": [1.0e6, 2.0e6], "ramp_time": 2.0e-6}],
        "damping": {"kind": "kinetic", "coefficient": 0.05},
        "time": {"end": 4.0e-5}
    }))
}

fn config(threads: usize) -> SolverConfig {
    SolverConfig::with_threads(threads)
}

/// Everything observable after a step, as exact text: energy and crack-tip rows (`{:?}` of
/// an f64 is its shortest round-trip text, so equal text is equal bits), particles as bits.
fn observe(sim: &mut Simulation) -> (String, Vec<u64>) {
    let mut text = format!("{:?}\n{:?}\n", sim.energy(), sim.crack_tips());
    if let Some(c) = sim.cracks() {
        text += &format!("{:?}\n{:?}\n", c.cracks, c.zone_work());
    }
    text += &format!(
        "{:?} {} {}",
        sim.work_counters(),
        sim.time(),
        sim.steps_taken()
    );
    let p = sim.particles();
    let mut bits = Vec::with_capacity(p.len() * 20);
    for i in 0..p.len() {
        let (k, me, c) = (p.kin[i], p.mech[i], p.cold[i]);
        bits.extend([k.x[0], k.x[1], k.v[0], k.v[1]].map(f64::to_bits));
        bits.extend(p.stress[i].map(f64::to_bits));
        bits.extend([me.m, me.vol, me.lh, p.wden[i], c.x0[0], c.x0[1]].map(f64::to_bits));
        bits.extend([me.mat, me.load, c.id, c.body].map(u64::from));
        if let Some(g) = p.grad_u.get(i) {
            bits.extend(g.map(f64::to_bits));
        }
        if let Some(f) = p.fmask.get(i) {
            bits.push(u64::from(*f));
        }
    }
    (text, bits)
}

/// The observations after every step from step `from` on, of a run of `s` on `threads`
/// threads that is checkpointed after `k` steps and restored (when `k` is Some).
fn run(s: &Scene, threads: usize, k: Option<u64>, from: u64) -> Vec<(String, Vec<u64>)> {
    let valid = ValidScene::new(s.clone()).unwrap();
    let mut sim = Simulation::new(&valid, config(threads)).unwrap();
    let mut out = Vec::new();
    while !sim.is_finished() {
        if Some(sim.steps_taken()) == k {
            let bytes = sim.checkpoint();
            // A fresh simulation (another thread count too) takes over.
            let other = if threads == 1 { 2 } else { 1 };
            sim = Simulation::restore(&valid, config(other), &bytes).unwrap();
            assert_eq!(sim.steps_taken(), k.unwrap());
        }
        sim.step().unwrap();
        if sim.steps_taken() >= from {
            out.push(observe(&mut sim));
        }
    }
    out
}

fn assert_resume_identical(name: &str, s: &Scene, k: u64) {
    for threads in [1, 2] {
        let a = run(s, threads, None, k + 1);
        let b = run(s, threads, Some(k), k + 1);
        assert_eq!(a.len(), b.len(), "{name}: steps");
        assert!(!a.is_empty(), "{name}: nothing after the checkpoint");
        for (i, (x, y)) in a.iter().zip(&b).enumerate() {
            let step = k + 1 + i as u64;
            if let Some((u, r)) = x.0.lines().zip(y.0.lines()).find(|(u, r)| u != r) {
                let at = u
                    .bytes()
                    .zip(r.bytes())
                    .position(|(a, b)| a != b)
                    .unwrap_or(0);
                let from = at.saturating_sub(200);
                panic!(
                    "{name}, {threads} threads: step {step} differs after a restore at step {k}:\n\
                     uninterrupted …{}\nrestored      …{}",
                    &u[from..(at + 100).min(u.len())],
                    &r[from..(at + 100).min(r.len())]
                );
            }
            assert_eq!(x.0, y.0, "{name}: step {step}");
            if let Some(w) = x.1.iter().zip(&y.1).position(|(p, q)| p != q) {
                panic!("{name}, {threads} threads: step {step}: particle word {w} differs");
            }
        }
    }
}

/// The growing crack: it must actually grow before and after the checkpoint, with zone
/// points behind its tip at the checkpoint.
#[test]
fn resume_is_bitwise_identical_on_a_growing_crack_with_a_process_zone() {
    let s = strip(true, false, 7.0e-5);
    let valid = ValidScene::new(s.clone()).unwrap();
    let mut sim = Simulation::new(&valid, config(2)).unwrap();
    let k = 230;
    for _ in 0..k {
        sim.step().unwrap();
    }
    let c = &sim.cracks().unwrap().cracks[0];
    let (adv, zone) = (
        c.tips[1].advance,
        c.pts.iter().filter(|p| p.zone.is_some()).count(),
    );
    assert!(
        adv > 0.0 && zone > 0,
        "not growing at the checkpoint: advance {adv}, zone points {zone}"
    );
    let n = c.pts.len();
    while !sim.is_finished() {
        sim.step().unwrap();
    }
    let c = &sim.cracks().unwrap().cracks[0];
    assert!(c.pts.len() > n, "no growth after the checkpoint");
    assert_resume_identical("growth", &s, k);
}

/// A cohesive interface opening ahead of the crack.
#[test]
fn resume_is_bitwise_identical_with_a_cohesive_interface() {
    let s = strip(false, true, 6.0e-5);
    assert_resume_identical("cohesive", &s, 190);
}

/// No cracks; re-sorts, a ramped load and damping.
#[test]
fn resume_is_bitwise_identical_on_a_plain_scene() {
    let s = plain();
    for k in [1, 37] {
        assert_resume_identical("plain", &s, k);
    }
}

/// Restoring before any step, and checkpoints of a restored simulation, are the same bytes.
#[test]
fn a_restored_simulation_checkpoints_to_the_same_bytes() {
    let s = strip(true, false, 1.0e-5);
    let valid = ValidScene::new(s).unwrap();
    let mut sim = Simulation::new(&valid, config(1)).unwrap();
    for _ in 0..5 {
        sim.step().unwrap();
    }
    let bytes = sim.checkpoint();
    let again = Simulation::restore(&valid, config(2), &bytes).unwrap();
    assert_eq!(again.checkpoint(), bytes);
    assert_eq!(fracture_solver::sim::checkpoint_steps(&bytes), Ok(5));
}

/// Another scene's checkpoint, a corrupted or truncated one, or garbage: refused with the
/// reason, never used.
#[test]
fn mismatched_or_corrupt_checkpoints_are_refused() {
    let s = strip(true, false, 1.0e-5);
    let valid = ValidScene::new(s.clone()).unwrap();
    let mut sim = Simulation::new(&valid, config(1)).unwrap();
    sim.step().unwrap();
    let bytes = sim.checkpoint();

    let other = ValidScene::new(strip(false, false, 1.0e-5)).unwrap();
    match Simulation::restore(&other, config(1), &bytes) {
        Err(CheckpointError::Scene { .. }) => {}
        r => panic!("another scene's checkpoint: {:?}", r.err()),
    }
    let mut flipped = bytes.clone();
    let last = flipped.len() - 9;
    flipped[last] ^= 0x10;
    match Simulation::restore(&valid, config(1), &flipped) {
        Err(CheckpointError::Corrupt(m)) => assert!(m.contains("digest"), "{m}"),
        r => panic!("a flipped bit: {:?}", r.err()),
    }
    for cut in [0, 5, bytes.len() / 2, bytes.len() - 1] {
        assert!(
            matches!(
                Simulation::restore(&valid, config(1), &bytes[..cut]),
                Err(CheckpointError::Corrupt(_))
            ),
            "truncated at {cut}"
        );
    }
    assert!(matches!(
        Simulation::restore(&valid, config(1), b"not a checkpoint at all"),
        Err(CheckpointError::Corrupt(_))
    ));
}

/// Size and time of a checkpoint and a restore of `scenes/rosakis-shear-mini.json` after 100
/// steps (a measurement for `docs/service.md`, not a check; `--ignored --nocapture`). With
/// `CHECKPOINT_OUT` set, the bytes are written there (to measure their compression).
#[test]
#[ignore]
fn measure_checkpoint_of_rosakis_shear_mini() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenes/rosakis-shear-mini.json"
    ))
    .unwrap();
    let s: Scene = serde_json::from_str(&text).unwrap();
    let valid = ValidScene::new(s).unwrap();
    let mut sim = Simulation::new(&valid, config(2)).unwrap();
    for _ in 0..100 {
        sim.step().unwrap();
    }
    let t0 = std::time::Instant::now();
    let bytes = sim.checkpoint();
    let t_write = t0.elapsed();
    let t0 = std::time::Instant::now();
    let back = Simulation::restore(&valid, config(2), &bytes).unwrap();
    let t_read = t0.elapsed();
    let t0 = std::time::Instant::now();
    let mut step_sim = back;
    step_sim.step().unwrap();
    eprintln!(
        "rosakis-shear-mini: {} particles, checkpoint {} bytes ({:.1} B/particle) in {:.1} ms, \
         restore {:.1} ms, one step {:.1} ms",
        sim.particle_count(),
        bytes.len(),
        bytes.len() as f64 / sim.particle_count() as f64,
        t_write.as_secs_f64() * 1e3,
        t_read.as_secs_f64() * 1e3,
        t0.elapsed().as_secs_f64() * 1e3
    );
    if let Some(p) = std::env::var_os("CHECKPOINT_OUT") {
        std::fs::write(p, &bytes).unwrap();
    }
}
