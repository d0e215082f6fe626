//! Dynamic fracture checks: Freund's step-wave problem, dynamic path independence, and
//! propagation (`reference-solutions.md`).
#![allow(clippy::unwrap_used)]

mod common;
use common::*;
use serde_json::json;

/// Freund's stationary crack under a plane step tensile wave:
/// K_I(t) = 2σ*·sqrt(c_L (t − t_c)(1 − 2ν)/π)/(1 − ν).
/// Geometry: a 40 mm wide strip with roller sides (x velocity fixed), an edge crack of 20 mm
/// at mid-height, a step traction σ* on the top edge, bottom edge free. The roller at the
/// mouth mirrors the crack, so the first scattered waves (from the mirror tip and the far
/// roller) reach the tip 2·20 mm/c_L = 15.7 µs after t_c. Resolution: 0.5 mm cells, 2×2
/// particles per cell, cfl 0.5, J contour half-size `contour`.
fn freund(contour: u32) -> Vec<(f64, f64, f64)> {
    let h = 0.0005;
    let m = 2.0 * h;
    let (b, below, above) = (0.040, 0.040, 0.030);
    let yc = m + below + 0.5 * h;
    let top = yc + above - 0.5 * h;
    let sigma = 1.0e6;
    let s = scene(json!({
        "name": "freund",
        "grid": {"cell_size": h, "min": [0.0, 0.0], "max": [b + 2.0 * m, top + m]},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [m, m], "max": [m + b, top]}}}],
        "cracks": [{"points": [[m - 0.5 * h, yc], [m + 0.020, yc]], "j_contour": contour}],
        "boundary_conditions": [
            {"region": {"rectangle": {"min": [0.0, 0.0], "max": [m + 0.1 * h, 1.0]}}, "velocity": {"x": 0.0}},
            {"region": {"rectangle": {"min": [m + b - 0.1 * h, 0.0], "max": [1.0, 1.0]}}, "velocity": {"x": 0.0}}
        ],
        "loads": [{"region": {"rectangle": {"min": [0.0, top - 0.5 * h], "max": [1.0, 1.0]}},
                   "traction": [0.0, sigma]}],
        "time": {"end": 2.9e-5, "cfl": 0.5}
    }));
    let c_l = s.materials["m"].wave_speeds(s.analysis).c_l;
    let t_c = (top - yc) / c_l;
    let nu: f64 = 0.34;
    let mut sim = sim(&s, 0);
    let mut out = Vec::new();
    while !sim.is_finished() {
        sim.step().unwrap();
        let dt = sim.time() - t_c;
        if dt > 0.0 {
            let k_ref = 2.0 * sigma * (c_l * dt * (1.0 - 2.0 * nu) / std::f64::consts::PI).sqrt() / (1.0 - nu);
            let r = sim.crack_tips()[0];
            out.push((dt, r.k1, k_ref));
        }
    }
    out
}

/// K_I(t) within 5 % of Freund's formula over the valid window, after the first few cells of
/// rise (t − t_c from 3 µs, ~15 cells of wave travel, to 14 µs, before the scattered waves).
#[test]
fn freund_step_wave() {
    let rows = freund(2);
    let mut worst: f64 = 0.0;
    let mut n = 0;
    for &(dt, k, k_ref) in &rows {
        if (3.0e-6..=14.0e-6).contains(&dt) {
            let e = (k - k_ref) / k_ref;
            worst = worst.max(e.abs());
            n += 1;
        }
    }
    for &(dt, k, k_ref) in rows.iter().step_by(10) {
        eprintln!("t-tc {:.2} us  K {k:.0}  Freund {k_ref:.0}  ({:+.2} %)", dt * 1e6, 100.0 * (k - k_ref) / k_ref);
    }
    eprintln!("worst {:.2} % over {n} samples", 100.0 * worst);
    assert!(n > 50);
    assert!(worst < 0.05, "worst error {:.2} %", 100.0 * worst);
}

/// Dynamic path independence: with the area term, contours of half-size 2 and 3 agree within
/// 5 % over the valid window of the Freund problem.
#[test]
fn freund_path_independence() {
    let a = freund(2);
    let b = freund(3);
    let mut worst: f64 = 0.0;
    for (x, y) in a.iter().zip(&b) {
        if (3.0e-6..=14.0e-6).contains(&x.0) {
            // Compare J (∝ K²).
            let (ja, jb) = (x.1 * x.1, y.1 * y.1);
            worst = worst.max((ja - jb).abs() / ja);
        }
    }
    eprintln!("worst J difference between contours 2 and 3: {:.2} %", 100.0 * worst);
    assert!(worst < 0.05);
}
