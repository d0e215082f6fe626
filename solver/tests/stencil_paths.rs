//! The field-0 fast path of the particle passes against the generic multi-field path
//! (`solver/src/sim/stencil.rs`): the same scene stepped with the normal per-particle choice
//! and with every particle forced through the generic path must give bitwise identical
//! particle states, energies and crack-tip rows. Reference: the generic path; tolerance: none
//! (`f64::to_bits` equality). Resolution: 1 mm cells, 2×2 particles per cell, tens of steps.
#![allow(clippy::unwrap_used)]

mod common;
use common::*;
use fracture_api::Scene;
use fracture_solver::Simulation;
use serde_json::json;

/// Every particle's state as bits: position, velocity, stress, strain energy density and (with
/// cracks) displacement gradient.
fn state_bits(sim: &Simulation) -> Vec<u64> {
    let p = sim.particles();
    let mut bits = Vec::new();
    for i in 0..p.len() {
        let (k, s) = (p.kin[i], p.stress[i]);
        bits.extend([k.x[0], k.x[1], k.v[0], k.v[1]].map(f64::to_bits));
        bits.extend(s.map(f64::to_bits));
        bits.push(p.wden[i].to_bits());
        if let Some(g) = p.grad_u.get(i) {
            bits.extend(g.map(f64::to_bits));
        }
    }
    bits
}

/// Step `s` to its end (fast path allowed or not), recording energy and tip rows every step
/// (the tips exercise J and K on the grid the passes wrote).
fn run(s: &Scene, generic: bool, vibrate: bool) -> (Vec<String>, Vec<u64>) {
    let mut sim = sim(s, 2);
    sim.force_generic_stencil(generic);
    if vibrate {
        // A non-uniform initial velocity, so that particles leave the lattice positions and
        // visit stencils with two and three nodes per direction.
        sim.set_velocities(|x| [8.0 * (300.0 * x[1]).sin(), -6.0 * (250.0 * x[0]).cos()]);
    }
    let mut rows = Vec::new();
    while !sim.is_finished() {
        sim.step().unwrap();
        rows.push(sim.energy().to_csv());
        for r in sim.crack_tips() {
            rows.push(r.to_csv());
        }
    }
    (rows, state_bits(&sim))
}

/// The fast-path run's rows, after checking that the generic-path run gives the same bits.
fn assert_paths_agree(s: &Scene, vibrate: bool) -> Vec<String> {
    let (rows_fast, fast) = run(s, false, vibrate);
    let (rows_generic, generic) = run(s, true, vibrate);
    assert_eq!(fast.len(), generic.len());
    if let Some(i) = fast.iter().zip(&generic).position(|(a, b)| a != b) {
        panic!(
            "state word {i} differs: fast {} vs generic {}",
            f64::from_bits(fast[i]),
            f64::from_bits(generic[i])
        );
    }
    assert_eq!(rows_fast, rows_generic);
    rows_fast
}

/// No crack: every particle takes the fast path normally. A velocity condition, a traction
/// load (the loaded force scatter) and kinetic damping, with a non-uniform initial velocity.
#[test]
fn fast_path_matches_generic_path_without_a_crack() {
    let s = scene(json!({
        "grid": {"cell_size": 0.001, "min": [0.0, 0.0], "max": [0.04, 0.03]},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [0.004, 0.004], "max": [0.036, 0.026]}}}],
        "boundary_conditions": [{"region": {"rectangle": {"min": [0.0, 0.0], "max": [0.04, 0.0041]}},
                                 "velocity": {"y": 0.0}}],
        "loads": [{"region": {"rectangle": {"min": [0.0, 0.0255], "max": [1.0, 1.0]}},
                   "traction": [1.0e6, 2.0e6], "ramp_time": 2.0e-6}],
        "damping": {"kind": "kinetic", "coefficient": 0.05},
        "time": {"end": 1.5e-5}
    }));
    assert_paths_agree(&s, true);
}

/// A growing crack under tension (fields, contact, J every step, propagation): the particles
/// near the crack take the generic path anyway, the others the fast path normally.
#[test]
fn fast_path_matches_generic_path_with_a_growing_crack() {
    // The edge-cracked plate of tests/common, for 30 µs.
    let mut v = edge_cracked_plate_json();
    v["time"]["end"] = json!(3.0e-5);
    let s = scene(v);
    let rows = assert_paths_agree(&s, false);
    assert!(
        rows.iter().any(|r| r.split(',').nth(11) == Some("1")),
        "the crack never grew"
    );
}
