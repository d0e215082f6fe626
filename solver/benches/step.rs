//! Throughput of the time step in particle-steps per second.
//!
//! `seed_block`: the seed's 125 mm × 250 mm Homalite block at 0.5 mm cells, 2×2 particles
//! per cell (500,000 particles), struck on part of one edge. Run with
//! `cargo bench -p fracture-solver --bench step`.
#![allow(missing_docs, clippy::unwrap_used)]

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use fracture_api::Scene;
use fracture_solver::{Simulation, SolverConfig};

fn seed_block(cell: f64, crack: bool) -> Scene {
    let m = 4.0 * cell;
    let mut v = serde_json::json!({
        "name": "seed-block",
        "grid": {"cell_size": cell, "min": [0.0, 0.0], "max": [0.125 + 2.0 * m, 0.25 + 2.0 * m]},
        "materials": {"homalite": {"model": "linear_elastic", "density": 1230.0,
                                   "youngs_modulus": 5.2e9, "poissons_ratio": 0.34}},
        "bodies": [{"material": "homalite",
                    "region": {"rectangle": {"min": [m, m], "max": [m + 0.125, m + 0.25]}}}],
        "boundary_conditions": [{"region": {"rectangle": {"min": [0.0, m], "max": [m + 0.01 * cell, m + 0.125]}},
                                 "velocity": {"x": 25.0}}],
        "time": {"end": 1.0e-3, "cfl": 0.5}
    });
    if crack {
        v["cracks"] = serde_json::json!([{"points": [[0.0, m + 0.125 + 0.25 * cell], [m + 0.05, m + 0.125 + 0.25 * cell]]}]);
    }
    serde_json::from_value(v).unwrap()
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("step");
    g.sample_size(10);
    for (name, crack) in [("seed_block_500k", false), ("seed_block_500k_crack", true)] {
        let scene = seed_block(0.0005, crack);
        let mut sim = Simulation::new(
            &fracture_api::ValidScene::new(scene.clone()).unwrap(),
            SolverConfig::all_cores(),
        )
        .unwrap();
        for _ in 0..3 {
            sim.step().unwrap();
        }
        g.throughput(Throughput::Elements(sim.particle_count() as u64));
        // With the crack, J and K are computed every step (a history sample every step).
        g.bench_function(name, |b| {
            b.iter(|| {
                sim.step().unwrap();
                if crack { sim.crack_tips().len() } else { 0 }
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
