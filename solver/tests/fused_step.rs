//! The fused step (`solver/src/sim/transfer.rs`: the last stress half-update of a step and the
//! next step's P2G in one particle sweep, where no re-sort and no crack falls between) against
//! the four-pass reference order of `algorithm.md` §2: the same scene stepped with fusion on
//! and off must give bitwise identical particle states and energy rows after every step.
//! Reference: the unfused step; tolerance: none (`f64::to_bits` equality). Resolution: 1 mm
//! cells, 2×2 particles per cell, tens of steps.
#![allow(clippy::unwrap_used)]

mod common;
use common::*;
use fracture_api::Scene;
use fracture_solver::Simulation;
use serde_json::json;

fn state_bits(sim: &Simulation) -> Vec<u64> {
    let p = sim.particles();
    let mut bits = Vec::new();
    for i in 0..p.len() {
        let (k, s) = (p.kin[i], p.stress[i]);
        bits.extend([k.x[0], k.x[1], k.v[0], k.v[1]].map(f64::to_bits));
        bits.extend(s.map(f64::to_bits));
        bits.push(p.wden[i].to_bits());
    }
    bits
}

/// Step `s` to its end with fusion on or off; the state and energy row after every step, and
/// after step `kick` the velocities replaced (which must drop a P2G done ahead).
fn run(s: &Scene, fused: bool, threads: usize, kick: Option<usize>) -> Vec<(String, Vec<u64>)> {
    let mut sim = sim(s, threads);
    sim.set_fused_step(fused);
    sim.set_velocities(|x| [8.0 * (300.0 * x[1]).sin(), -6.0 * (250.0 * x[0]).cos()]);
    let mut out = Vec::new();
    let mut n = 0;
    while !sim.is_finished() {
        sim.step().unwrap();
        n += 1;
        if Some(n) == kick {
            sim.set_velocities(|x| [30.0 + 5.0 * (200.0 * x[1]).cos(), 2.0]);
        }
        out.push((sim.energy().to_csv(), state_bits(&sim)));
    }
    out
}

fn assert_same(s: &Scene, threads: usize, kick: Option<usize>) {
    let a = run(s, true, threads, kick);
    let b = run(s, false, threads, kick);
    assert_eq!(a.len(), b.len());
    for (step, (x, y)) in a.iter().zip(&b).enumerate() {
        assert_eq!(x.0, y.0, "energy row of step {}", step + 1);
        if let Some(i) = x.1.iter().zip(&y.1).position(|(p, q)| p != q) {
            panic!(
                "step {}: state word {i} differs: fused {} vs unfused {}",
                step + 1,
                f64::from_bits(x.1[i]),
                f64::from_bits(y.1[i])
            );
        }
    }
}

/// A traction load, a velocity condition, kinetic damping; a body moving fast enough that
/// particles leave their strips (re-sorts between fused steps), on 1 and 2 threads.
#[test]
fn fused_step_matches_reference_order() {
    for shape in ["gimp", "linear"] {
        let s = scene(json!({
            "grid": {"cell_size": 0.001, "min": [0.0, 0.0], "max": [0.06, 0.03], "shape_function": shape},
            "materials": {"m": homalite()},
            "bodies": [{"material": "m", "region": {"rectangle": {"min": [0.004, 0.004], "max": [0.036, 0.026]}}}],
            "boundary_conditions": [{"region": {"rectangle": {"min": [0.0, 0.0], "max": [0.06, 0.0041]}},
                                     "velocity": {"y": 0.0}}],
            "loads": [{"region": {"rectangle": {"min": [0.0, 0.0255], "max": [1.0, 1.0]}},
                       "traction": [1.0e6, 2.0e6], "ramp_time": 2.0e-6}],
            "damping": {"kind": "kinetic", "coefficient": 0.05},
            "time": {"end": 2.0e-5}
        }));
        for threads in [1, 2] {
            assert_same(&s, threads, Some(7));
        }
    }
}
