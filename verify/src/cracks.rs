//! Static crack problems: the centre, edge and mode II (exact Westergaard edge tractions)
//! cracks, and the averaging runner of a ramp-and-hold problem.

use std::f64::consts::PI;

use fracture_api::Scene;
use serde_json::{Value, json};

use fracture_solver::{Simulation, SolverConfig};

use crate::*;

/// Tension 1 MPa on the top and bottom particle rows of a body from y = `bottom` to `top`,
/// each a band `lb` deep ([`Settings::load_band`]), ramped over `ramp`.
pub(crate) fn end_tension(top: f64, bottom: f64, lb: f64, ramp: f64) -> Value {
    json!([
        {"region": {"rectangle": {"min": [0.0, top - lb], "max": [1.0, 1.0]}},
         "traction": [0.0, 1.0e6], "ramp_time": ramp},
        {"region": {"rectangle": {"min": [0.0, 0.0], "max": [1.0, bottom + lb]}},
         "traction": [0.0, -1.0e6], "ramp_time": ramp}
    ])
}

/// Centre crack 2a = 17 mm in a strip 2b = 80 mm wide and 120 mm tall (a/b = 0.2125), crack
/// at mid-cell, tension σ = 1 MPa on both ends ramped over 150 µs, viscous damping 4·10⁴ 1/s,
/// to 300 µs. Reference: K_I = σ√(πa)·F(a/b) (Tada).
pub fn center_crack(s: &Settings) -> Result<Built, VerifyError> {
    let h = s.cell_size;
    let lb = s.load_band();
    let (b, half_h, a) = (0.040, 0.060, 0.0085);
    let m = 2.0 * h;
    let cx = m + b;
    let cy = m + half_h + 0.5 * h;
    let v = json!({
        "name": "center-crack",
        "grid": {"cell_size": h, "min": [0.0, 0.0], "max": [2.0 * b + 2.0 * m, 2.0 * half_h + 2.0 * m + h],
                 "shape_function": s.shape_name()},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [m, m], "max": [m + 2.0 * b, m + 2.0 * half_h + h]}},
                    "particles_per_cell": s.particles_per_cell}],
        "cracks": [{"points": [[cx - a, cy], [cx + a, cy]], "j_contour": s.j_contour}],
        "loads": end_tension(2.0 * half_h + m + h, m, lb, 1.5e-4),
        "damping": {"kind": "viscous", "coefficient": 4.0e4},
        "time": {"end": 3.0e-4, "cfl": s.cfl}
    });
    Ok(Built {
        scene: to_scene(v)?,
        reference: 1.0e6 * (PI * a).sqrt() * tada_center(a / b),
    })
}

/// Edge crack a = 12.5 mm in a strip b = 40 mm wide, half-height 48 mm (a/b = 0.3125),
/// tension 1 MPa ramped over 120 µs, viscous damping 5·10⁴ 1/s, to 240 µs.
/// Reference: K_I = σ√(πa)·F(a/b) (Tada).
pub fn edge_crack(s: &Settings) -> Result<Built, VerifyError> {
    let h = s.cell_size;
    let lb = s.load_band();
    let (b, half_h, a) = (0.040, 0.048, 0.0125);
    let m = 2.0 * h;
    let cy = m + half_h + 0.5 * h;
    let v = json!({
        "name": "edge-crack",
        "grid": {"cell_size": h, "min": [0.0, 0.0], "max": [b + 2.0 * m, 2.0 * half_h + 2.0 * m + h],
                 "shape_function": s.shape_name()},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [m, m], "max": [m + b, m + 2.0 * half_h + h]}},
                    "particles_per_cell": s.particles_per_cell}],
        "cracks": [{"points": [[m - 0.5 * h, cy], [m + a, cy]], "j_contour": s.j_contour}],
        "loads": end_tension(2.0 * half_h + m + h, m, lb, 1.2e-4),
        "damping": {"kind": "viscous", "coefficient": 5.0e4},
        "time": {"end": 2.4e-4, "cfl": s.cfl}
    });
    Ok(Built {
        scene: to_scene(v)?,
        reference: 1.0e6 * (PI * a).sqrt() * tada_edge(a / b),
    })
}

/// Centre crack 2a = 34 mm (a = 17 mm, mid-cell) in a 104 mm square under remote shear
/// τ = 1 MPa, loaded on its four edges by the tractions of the exact infinite-plate solution
/// ([`westergaard_shear`], constant over one-cell edge segments), so the plate is a cut-out of
/// the infinite one and the reference needs no finite-size factor. Ramped over 250 µs, viscous
/// damping 7·10⁴ 1/s, to 400 µs (the scene of `shear-crack.json`). Reference: K_II = τ√(πa).
pub fn shear_crack(s: &Settings) -> Result<Built, VerifyError> {
    let h = s.cell_size;
    let (w, a) = (0.104, 0.017);
    let m = 2.0 * h;
    let c = m + 0.5 * w + 0.5 * h;
    let tau = 1.0e6;
    let top = m + w + h;
    let v = json!({
        "name": "shear-crack",
        "grid": {"cell_size": h, "min": [0.0, 0.0], "max": [top + m, top + m],
                 "shape_function": s.shape_name()},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [m, m], "max": [top, top]}},
                    "particles_per_cell": s.particles_per_cell}],
        "cracks": [{"points": [[c - a, c], [c + a, c]], "j_contour": s.j_contour}],
        "loads": exact_shear_loads(s, [m, top], c, a, tau, 2.5e-4),
        "damping": {"kind": "viscous", "coefficient": 7.0e4},
        "time": {"end": 4.0e-4, "cfl": s.cfl}
    });
    Ok(Built {
        scene: to_scene(v)?,
        reference: mode_two_k(tau, a),
    })
}

/// Complex numbers as (re, im), for the Westergaard function.
type Complex = (f64, f64);

fn c_mul(a: Complex, b: Complex) -> Complex {
    (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0)
}

fn c_div(a: Complex, b: Complex) -> Complex {
    let d = b.0 * b.0 + b.1 * b.1;
    ((a.0 * b.0 + a.1 * b.1) / d, (a.1 * b.0 - a.0 * b.1) / d)
}

/// Principal square root (branch cut along the negative real axis).
fn c_sqrt(a: Complex) -> Complex {
    let r = a.0.hypot(a.1);
    let re = (0.5 * (r + a.0)).max(0.0).sqrt();
    let im = (0.5 * (r - a.0)).max(0.0).sqrt();
    (re, if a.1 < 0.0 { -im } else { im })
}

/// Stresses (σ_xx, σ_yy, σ_xy) of a crack (−a, a) on the x axis of an infinite plate under
/// remote shear τ, at (x, y) from the crack centre (Westergaard, mode II):
/// Z = τz/√(z² − a²), Z' = −τa²/(z² − a²)^{3/2}, σ_xx = 2 Im Z + y Re Z', σ_yy = −y Re Z',
/// σ_xy = Re Z − y Im Z'. √(z² − a²) is taken as √(z − a)·√(z + a), which is ≈ z far away
/// and has its cut on the crack.
pub fn westergaard_shear(x: f64, y: f64, a: f64, tau: f64) -> [f64; 3] {
    let q = c_mul(c_sqrt((x - a, y)), c_sqrt((x + a, y)));
    let z = c_div((tau * x, tau * y), q);
    let zp = c_div((-tau * a * a, 0.0), c_mul(q, c_mul(q, q)));
    [2.0 * z.1 + y * zp.0, -y * zp.0, z.0 - y * zp.1]
}

/// Loads of the square `[lo, hi]²` (crack centre at (c, c)) carrying the tractions of
/// [`westergaard_shear`] on its edges (t = σ·n), evaluated at the middle of each one-cell edge
/// segment and held constant over it, on the outermost particle row ([`Settings::load_band`]).
fn exact_shear_loads(
    s: &Settings,
    [lo, hi]: [f64; 2],
    c: f64,
    a: f64,
    tau: f64,
    ramp: f64,
) -> Value {
    let h = s.cell_size;
    let lb = s.load_band();
    let n = ((hi - lo) / h).round() as usize;
    let mut loads = Vec::with_capacity(4 * n);
    let load = |min: [f64; 2], max: [f64; 2], t: [f64; 2]| json!({"region": {"rectangle": {"min": min, "max": max}}, "traction": t, "ramp_time": ramp});
    for k in 0..n {
        let (s0, s1) = (lo + k as f64 * h, lo + (k + 1) as f64 * h);
        let mid = 0.5 * (s0 + s1) - c;
        // Top and bottom rows without the corner particles (those belong to the sides).
        let (x0, x1) = (s0.max(lo + lb), s1.min(hi - lb));
        if x1 > x0 {
            let top = westergaard_shear(mid, hi - c, a, tau);
            let bottom = westergaard_shear(mid, lo - c, a, tau);
            loads.push(load([x0, hi - lb], [x1, hi], [top[2], top[1]]));
            loads.push(load([x0, lo], [x1, lo + lb], [-bottom[2], -bottom[1]]));
        }
        let right = westergaard_shear(hi - c, mid, a, tau);
        let left = westergaard_shear(lo - c, mid, a, tau);
        loads.push(load([hi - lb, s0], [hi, s1], [right[0], right[2]]));
        loads.push(load([lo, s0], [lo + lb, s1], [-left[0], -left[2]]));
    }
    Value::Array(loads)
}

/// Crack-tip values averaged over the end of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct AveragedTips {
    /// Per tip: mean J1, J2, K_I, K_II.
    pub tips: Vec<[f64; 4]>,
    /// Particles.
    pub particles: usize,
    /// Steps taken.
    pub steps: u64,
}

/// Run `scene` to its end and average the crack-tip rows (J1, J2, K_I, K_II) over the last
/// `frac` of the run (the hold of a ramp-and-hold static problem).
pub fn average_tips(
    scene: &Scene,
    frac: f64,
    config: SolverConfig,
) -> Result<AveragedTips, VerifyError> {
    let mut sim = Simulation::new(&fracture_api::ValidScene::new(scene.clone())?, config)?;
    let t_avg = (1.0 - frac) * scene.time.end;
    let mut sums: Vec<[f64; 4]> = Vec::new();
    let mut n = 0.0;
    while !sim.is_finished() {
        sim.step()?;
        if sim.time() >= t_avg {
            let rows = sim.crack_tips();
            if sums.is_empty() {
                sums = vec![[0.0; 4]; rows.len()];
            }
            for (s, r) in sums.iter_mut().zip(&rows) {
                s[0] += r.j1;
                s[1] += r.j2;
                s[2] += r.k1;
                s[3] += r.k2;
            }
            n += 1.0;
        }
    }
    Ok(AveragedTips {
        tips: sums
            .iter()
            .map(|s| [s[0] / n, s[1] / n, s[2] / n, s[3] / n])
            .collect(),
        particles: sim.particle_count(),
        steps: sim.steps_taken(),
    })
}
