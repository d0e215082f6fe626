//! Steps the seed block at a chosen cell size, for profilers (callgrind, perf):
//! `cargo run --release -p fracture-solver --example profile_step -- 0.002 20 [crack] [fma]`.
#![allow(clippy::unwrap_used, clippy::print_stdout, missing_docs)]

use fracture_solver::{Simulation, SolverConfig};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let cell: f64 = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(0.002);
    let steps: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(20);
    let crack = args.iter().skip(3).any(|a| a == "crack");
    // `portable`: the portable kernel (bitwise the solver before the FMA dispatch).
    let portable = args.iter().skip(3).any(|a| a == "portable");
    // `fma`: the FMA kernel (what `fracture bench --kernel fma` runs), where the CPU has it.
    let fma = args.iter().skip(3).any(|a| a == "fma");
    let m = 4.0 * cell;
    let mut v = serde_json::json!({
        "grid": {"cell_size": cell, "min": [0.0, 0.0], "max": [0.125 + 2.0 * m, 0.25 + 2.0 * m]},
        "materials": {"h": {"model": "linear_elastic", "density": 1230.0, "youngs_modulus": 5.2e9, "poissons_ratio": 0.34}},
        "bodies": [{"material": "h", "region": {"rectangle": {"min": [m, m], "max": [m + 0.125, m + 0.25]}}}],
        "boundary_conditions": [{"region": {"rectangle": {"min": [0.0, m], "max": [m + 0.01 * cell, m + 0.125]}}, "velocity": {"x": 25.0}}],
        "time": {"end": 1.0}
    });
    if crack {
        v["cracks"] = serde_json::json!([{"points": [[0.0, m + 0.125 + 0.25 * cell], [m + 0.05, m + 0.125 + 0.25 * cell]]}]);
    }
    let scene: fracture_api::Scene = serde_json::from_value(v).unwrap();
    let mut sim = Simulation::new(
        &fracture_api::ValidScene::new(scene.clone()).unwrap(),
        SolverConfig::with_threads(1),
    )
    .unwrap();
    if portable {
        sim.set_kernel(fracture_solver::kernel::Kernel::Portable);
    }
    if fma {
        sim.set_kernel(fracture_solver::kernel::Kernel::Fma);
    }
    sim.step().unwrap();
    let t = std::time::Instant::now();
    let mut rows = 0usize;
    for _ in 0..steps {
        sim.step().unwrap();
        if crack {
            // J and K at every step, as with a history sample every step.
            rows += sim.crack_tips().len();
        }
    }
    let dt = t.elapsed().as_secs_f64();
    // A hash of every particle's state, to check that an optimisation is bitwise neutral.
    let p = sim.particles();
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    for i in 0..p.len() {
        let (k, s) = (p.kin[i], p.stress[i]);
        for v in [
            k.x[0], k.x[1], k.v[0], k.v[1], s[0], s[1], s[2], s[3], p.wden[i],
        ] {
            hash = (hash ^ v.to_bits()).wrapping_mul(0x0100_0000_01b3);
        }
    }
    println!(
        "{} particles, {steps} steps, {rows} tip rows: {:.3e} particle-steps/s (1 thread), state hash {hash:016x}",
        sim.particle_count(),
        (sim.particle_count() * steps) as f64 / dt
    );
}
