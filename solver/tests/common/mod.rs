//! Helpers shared by the physics tests.
#![allow(dead_code, clippy::unwrap_used)]

use fracture_api::Scene;
use fracture_solver::{Simulation, SolverConfig};

/// Parse a scene from a JSON value (panics on an invalid test scene).
pub fn scene(v: serde_json::Value) -> Scene {
    let s: Scene = serde_json::from_value(v).unwrap();
    if let Err(e) = fracture_api::validate::validate(&s) {
        panic!("test scene invalid: {e}");
    }
    s
}

/// Build a simulation with `threads` threads.
pub fn sim(s: &Scene, threads: usize) -> Simulation {
    Simulation::new(
        &fracture_api::ValidScene::new(s.clone()).unwrap(),
        SolverConfig {
            threads: fracture_solver::Parallelism::from_count(threads),
        },
    )
    .unwrap()
}

/// Homalite-100, dynamic constants (reference-solutions.md).
pub fn homalite() -> serde_json::Value {
    fracture_verify::homalite()
}

/// Total momentum Σ m v.
pub fn momentum(sim: &Simulation) -> [f64; 2] {
    let p = sim.particles();
    let mut m = [0.0; 2];
    for (k, me) in p.kin.iter().zip(&p.mech) {
        m[0] += me.m * k.v[0];
        m[1] += me.m * k.v[1];
    }
    m
}

/// The transfer tests' plate (1 mm cells, Homalite, 32 × 22 mm in a grid `width` m wide): held
/// at its foot (v_y = 0), pulled at its top by a ramped traction, kinetic damping 0.05, 20 µs.
/// A JSON scene for the tests to adjust before `scene`.
pub fn held_plate_json(width: f64) -> serde_json::Value {
    serde_json::json!({
        "grid": {"cell_size": 0.001, "min": [0.0, 0.0], "max": [width, 0.03]},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [0.004, 0.004], "max": [0.036, 0.026]}}}],
        "boundary_conditions": [{"region": {"rectangle": {"min": [0.0, 0.0], "max": [width, 0.0041]}},
                                 "velocity": {"y": 0.0}}],
        "loads": [{"region": {"rectangle": {"min": [0.0, 0.0255], "max": [1.0, 1.0]}},
                   "traction": [1.0e6, 2.0e6], "ramp_time": 2.0e-6}],
        "damping": {"kind": "kinetic", "coefficient": 0.05},
        "time": {"end": 2.0e-5}
    })
}

/// The transfer tests' edge-cracked plate (1 mm cells, 40 mm square in a 44 mm grid): a
/// 13 mm edge crack at mid-height with a 6-cell J ring and Γ = 5 J/m², opened by ramped
/// tractions of ±2 MPa on its top and bottom edges, 20 µs. A JSON scene to adjust.
pub fn edge_cracked_plate_json() -> serde_json::Value {
    let h = 0.001;
    let m = 2.0 * h;
    serde_json::json!({
        "grid": {"cell_size": h, "min": [0.0, 0.0], "max": [0.044, 0.044]},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [m, m], "max": [0.042, 0.042]}}}],
        "cracks": [{"points": [[m - 0.5 * h, 0.0225], [0.015, 0.0225]],
                    "j_integral": {"method": "domain", "radius": 6.0 * h},
                    "propagation": {"criterion": "energy_release", "toughness": 5.0}}],
        "loads": [
            {"region": {"rectangle": {"min": [0.0, 0.0415], "max": [1.0, 1.0]}}, "traction": [0.0, 2.0e6], "ramp_time": 5.0e-6},
            {"region": {"rectangle": {"min": [0.0, 0.0], "max": [1.0, 0.0025]}}, "traction": [0.0, -2.0e6], "ramp_time": 5.0e-6}
        ],
        "time": {"end": 2.0e-5}
    })
}
