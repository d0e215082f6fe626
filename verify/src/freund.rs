//! Freund's stationary crack under a step wave: the scene and its K_I(t) series.

use fracture_api::Scene;
use serde_json::json;

use fracture_solver::{Simulation, SolverConfig};

use crate::*;

/// The Freund scene with what its reference needs.
#[derive(Debug, Clone)]
pub struct FreundScene {
    /// The scene.
    pub scene: Scene,
    /// Step traction σ* (Pa).
    pub sigma: f64,
    /// Arrival time of the wave at the tip t_c = distance/c_L (s).
    pub t_c: f64,
    /// c_L (m/s).
    pub c_l: f64,
    /// Poisson's ratio.
    pub nu: f64,
}

/// Freund's problem: a 40 mm wide strip with roller sides (x velocity fixed), a 20 mm edge
/// crack at mid-height, a step traction σ* = 1 MPa on the top edge, bottom free, to 29 µs.
/// The roller at the mouth mirrors the crack, so the first scattered waves (from the mirror
/// tip and the far roller) reach the tip 2·20 mm/c_L = 15.7 µs after t_c.
pub fn freund(s: &Settings) -> Result<FreundScene, VerifyError> {
    let h = s.cell_size;
    let lb = s.load_band();
    let m = 2.0 * h;
    let (b, below, above) = (0.040, 0.040, 0.030);
    let yc = m + below + 0.5 * h;
    let top = yc + above - 0.5 * h;
    let sigma = 1.0e6;
    let scene = to_scene(json!({
        "name": "freund",
        "grid": {"cell_size": h, "min": [0.0, 0.0], "max": [b + 2.0 * m, top + m],
                 "shape_function": s.shape_name()},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [m, m], "max": [m + b, top]}},
                    "particles_per_cell": s.particles_per_cell}],
        "cracks": [{"points": [[m - 0.5 * h, yc], [m + 0.020, yc]], "j_contour": s.j_contour}],
        "boundary_conditions": [
            {"region": {"rectangle": {"min": [0.0, 0.0], "max": [m + 0.1 * h, 1.0]}}, "velocity": {"x": 0.0}},
            {"region": {"rectangle": {"min": [m + b - 0.1 * h, 0.0], "max": [1.0, 1.0]}}, "velocity": {"x": 0.0}}
        ],
        "loads": [{"region": {"rectangle": {"min": [0.0, top - lb], "max": [1.0, 1.0]}},
                   "traction": [0.0, sigma]}],
        "time": {"end": 2.9e-5, "cfl": s.cfl}
    }))?;
    let c_l = scene.materials["m"].wave_speeds(scene.analysis).c_l;
    Ok(FreundScene {
        t_c: (top - yc) / c_l,
        scene,
        sigma,
        c_l,
        nu: 0.34,
    })
}

/// The K_I history of a Freund run.
#[derive(Debug, Clone, PartialEq)]
pub struct FreundSeries {
    /// (t − t_c, K_I, Freund's K_I) at every step after the wave reached the tip.
    pub rows: Vec<(f64, f64, f64)>,
    /// Particles.
    pub particles: usize,
    /// Steps taken.
    pub steps: u64,
}

/// Run the Freund scene, sampling K_I at every step after t_c.
pub fn freund_series(f: &FreundScene, config: SolverConfig) -> Result<FreundSeries, VerifyError> {
    let mut sim = Simulation::new(&fracture_api::ValidScene::new(f.scene.clone())?, config)?;
    let mut rows = Vec::new();
    while !sim.is_finished() {
        sim.step()?;
        let dt = sim.time() - f.t_c;
        if dt > 0.0 {
            let k_ref = freund_k1(f.sigma, f.c_l, f.nu, dt);
            let Some(r) = sim.crack_tips().first().copied() else {
                return Err(VerifyError::NotMeasurable("no crack tip".into()));
            };
            rows.push((dt, r.k1, k_ref));
        }
    }
    Ok(FreundSeries {
        rows,
        particles: sim.particle_count(),
        steps: sim.steps_taken(),
    })
}
