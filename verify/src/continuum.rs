//! Continuum problems: the fixed–free vibrating bar and the constrained-bar wave.

use std::f64::consts::PI;

use fracture_api::Scene;
use serde_json::json;

use fracture_solver::{Simulation, SolverConfig};

use crate::*;

/// Fixed–free bar (plane stress, L = 25, E = 100, ρ = 1, ν = 0, 1 unit thick), fixed at
/// x = 1, run to t = 100 (10 periods). The first-mode velocity v₀ sin(πx/2L) is set by
/// [`run_vibrating_bar`]. Reference: T = 4L/√(E/ρ) = 10.
pub fn vibrating_bar(s: &Settings) -> Result<Built, VerifyError> {
    let (l, x0) = (25.0, 1.0);
    let scene = to_scene(json!({
        "name": "vibrating-bar",
        "analysis": "plane_stress",
        "grid": {"cell_size": s.cell_size, "min": [0.0, 0.0], "max": [28.0, 3.0],
                 "shape_function": s.shape_name()},
        "materials": {"bar": {"model": "linear_elastic", "density": 1.0, "youngs_modulus": 100.0, "poissons_ratio": 0.0}},
        "bodies": [{"material": "bar", "region": {"rectangle": {"min": [x0, 1.0], "max": [x0 + l, 2.0]}},
                    "particles_per_cell": s.particles_per_cell}],
        "boundary_conditions": [{"region": {"rectangle": {"min": [0.9, 0.0], "max": [1.1, 3.0]}}, "velocity": {"x": 0.0}}],
        "time": {"end": 100.0, "cfl": s.cfl}
    }))?;
    Ok(Built {
        scene,
        reference: bar_period(l, 100.0, 1.0),
    })
}

/// The outcome of a vibrating-bar run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BarResult {
    /// Period fitted over all zero crossings of the momentum.
    pub period: f64,
    /// Zero crossings of the momentum (two per period).
    pub crossings: usize,
    /// (initial − final)/initial kinetic + strain energy.
    pub energy_loss: f64,
    /// Simulated time.
    pub time: f64,
    /// Particles.
    pub particles: usize,
    /// Steps taken.
    pub steps: u64,
}

/// Run the vibrating bar from v(x, 0) = v₀ sin(π(x − x₀)/2L), v₀ = 0.1, and fit the period
/// from the zero crossings of the total x momentum (every half period).
pub fn run_vibrating_bar(s: &Settings, config: SolverConfig) -> Result<BarResult, VerifyError> {
    let (l, x0) = (25.0, 1.0);
    let b = vibrating_bar(s)?;
    let mut sim = Simulation::new(&fracture_api::ValidScene::new(b.scene.clone())?, config)?;
    let beta = PI / (2.0 * l);
    sim.set_velocities(|x| [0.1 * (beta * (x[0] - x0)).sin(), 0.0]);
    let e0 = sim.energy();
    let total0 = e0.kinetic + e0.strain;
    let momentum = |sim: &Simulation| {
        let p = sim.particles();
        p.kin
            .iter()
            .zip(&p.mech)
            .map(|(k, m)| m.m * k.v[0])
            .sum::<f64>()
    };
    let mut prev = (sim.time(), momentum(&sim));
    let mut crossings = Vec::new();
    while !sim.is_finished() {
        sim.step()?;
        let now = (sim.time(), momentum(&sim));
        if prev.1.signum() != now.1.signum() && prev.1 != 0.0 {
            crossings.push(prev.0 + prev.1 / (prev.1 - now.1) * (now.0 - prev.0));
        }
        prev = now;
    }
    let n = crossings.len();
    let period = if n >= 2 {
        2.0 * (crossings[n - 1] - crossings[0]) / (n - 1) as f64
    } else {
        f64::NAN
    };
    let e1 = sim.energy();
    Ok(BarResult {
        period,
        crossings: n,
        energy_loss: (total0 - (e1.kinetic + e1.strain)) / total0,
        time: sim.time(),
        particles: sim.particle_count(),
        steps: sim.steps_taken(),
    })
}

/// The constrained-bar scene with its references.
#[derive(Debug, Clone)]
pub struct WaveScene {
    /// The scene.
    pub scene: Scene,
    /// Step traction (Pa).
    pub sigma: f64,
    /// Plane-strain c_L (m/s).
    pub c_l: f64,
    /// Particle velocity behind the front σ/(ρc_L) (m/s).
    pub v_expected: f64,
}

/// A 200 mm Homalite bar two cells thick, y velocity fixed everywhere (laterally
/// constrained: a 1D plane-strain wave), a step traction σ = 1 MPa on its left end, to 60 µs.
/// Reference: front speed c_L, particle velocity σ/(ρc_L).
pub fn wave_bar(s: &Settings) -> Result<WaveScene, VerifyError> {
    let h = s.cell_size;
    let lb = s.load_band();
    let m = 2.0 * h;
    let len = 0.200;
    let sigma = 1.0e6;
    let (gx, gy) = (len + 2.0 * m, 3.0 * m);
    let scene = to_scene(json!({
        "name": "wave",
        "grid": {"cell_size": h, "min": [0.0, 0.0], "max": [gx, gy], "shape_function": s.shape_name()},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [m, m], "max": [m + len, 2.0 * m]}},
                    "particles_per_cell": s.particles_per_cell}],
        "boundary_conditions": [{"region": {"rectangle": {"min": [0.0, 0.0], "max": [gx, gy]}},
                                 "velocity": {"y": 0.0}}],
        "loads": [{"region": {"rectangle": {"min": [m, m], "max": [m + lb, 2.0 * m]}},
                   "traction": [sigma, 0.0]}],
        "time": {"end": 6.0e-5, "cfl": s.cfl}
    }))?;
    let c_l = scene.materials["m"].wave_speeds(scene.analysis).c_l;
    Ok(WaveScene {
        scene,
        sigma,
        c_l,
        v_expected: sigma / (1230.0 * c_l),
    })
}

/// The outcome of a constrained-bar run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WaveResult {
    /// Front speed between t = 15 µs and 50 µs (m/s).
    pub speed: f64,
    /// Mean particle velocity between 20 % and 70 % of the way to the front (m/s).
    pub plateau: f64,
    /// c_L (m/s).
    pub c_l: f64,
    /// σ/(ρc_L) (m/s).
    pub v_expected: f64,
    /// Particles.
    pub particles: usize,
    /// Steps taken.
    pub steps: u64,
}

/// Run the constrained bar; the front is where the x-binned particle velocity last crosses
/// half of σ/(ρc_L), tracked from t = 15 µs to 50 µs.
pub fn run_wave_bar(s: &Settings, config: SolverConfig) -> Result<WaveResult, VerifyError> {
    let w = wave_bar(s)?;
    let m = 2.0 * s.cell_size;
    let mut sim = Simulation::new(&fracture_api::ValidScene::new(w.scene.clone())?, config)?;
    let v_expected = w.v_expected;
    let front = |sim: &Simulation| -> f64 {
        let p = sim.particles();
        let mut pts: Vec<(f64, f64)> = p.kin.iter().map(|k| (k.x[0], k.v[0])).collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        // Average the particles sharing an x (one column of particles).
        let mut bins: Vec<(f64, f64, usize)> = Vec::new();
        for (x, v) in pts {
            match bins.last_mut() {
                Some(b) if (b.0 - x).abs() < 1e-9 => {
                    b.1 += v;
                    b.2 += 1;
                }
                _ => bins.push((x, v, 1)),
            }
        }
        let prof: Vec<(f64, f64)> = bins.iter().map(|b| (b.0, b.1 / b.2 as f64)).collect();
        // Last crossing from above half to below half, scanning in +x.
        let half = 0.5 * v_expected;
        for w in prof.windows(2).rev() {
            if w[0].1 >= half && w[1].1 < half {
                return w[0].0 + (half - w[0].1) / (w[1].1 - w[0].1) * (w[1].0 - w[0].0);
            }
        }
        f64::NAN
    };
    let (t1, t2) = (1.5e-5, 5.0e-5);
    let mut x1 = f64::NAN;
    while !sim.is_finished() {
        sim.step()?;
        if x1.is_nan() && sim.time() >= t1 {
            x1 = front(&sim);
        }
        if sim.time() >= t2 {
            break;
        }
    }
    let x2 = front(&sim);
    let speed = (x2 - x1) / (sim.time() - t1);
    let p = sim.particles();
    let behind: Vec<f64> = p
        .kin
        .iter()
        .filter(|k| k.x[0] > m + 0.2 * (x2 - m) && k.x[0] < m + 0.7 * (x2 - m))
        .map(|k| k.v[0])
        .collect();
    let plateau = if behind.is_empty() {
        f64::NAN
    } else {
        behind.iter().sum::<f64>() / behind.len() as f64
    };
    Ok(WaveResult {
        speed,
        plateau,
        c_l: w.c_l,
        v_expected,
        particles: sim.particle_count(),
        steps: sim.steps_taken(),
    })
}
