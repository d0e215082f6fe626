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
