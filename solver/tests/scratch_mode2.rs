#![allow(clippy::unwrap_used, missing_docs)]
mod common;
use common::*;
use serde_json::json;

#[test]
#[ignore]
fn scratch() {
    let h: f64 = std::env::var("H").map(|v| v.parse().unwrap()).unwrap_or(0.001);
    let contour: u32 = std::env::var("C").map(|v| v.parse().unwrap()).unwrap_or(2);
    let damp: f64 = std::env::var("D").map(|v| v.parse().unwrap()).unwrap_or(5e4);
    let ramp: f64 = std::env::var("RAMP").map(|v| v.parse().unwrap()).unwrap_or(1.2e-4);
    let end: f64 = std::env::var("END").map(|v| v.parse().unwrap()).unwrap_or(2.4e-4);
    let law = std::env::var("LAW").unwrap_or("frictionless".into());
    let w: f64 = std::env::var("W").map(|v| v.parse().unwrap()).unwrap_or(0.12); let a = 0.0085;
    let m = 2.0 * h;
    let c = m + 0.5 * w + 0.5 * h;
    let tau = 1.0e6;
    let top = m + w + h;
    let s = scene(json!({
        "name": "shear-crack",
        "grid": {"cell_size": h, "min": [0.0, 0.0], "max": [top + m, top + m]},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [m, m], "max": [top, top]}}}],
        "cracks": [{"points": [[c - a, c], [c + a, c]], "j_contour": contour, "contact": {"law": law}}],
        "loads": [
            {"region": {"rectangle": {"min": [m + 0.5 * h, top - 0.5 * h], "max": [top - 0.5 * h, top]}},
             "traction": [tau, 0.0], "ramp_time": ramp},
            {"region": {"rectangle": {"min": [m + 0.5 * h, m], "max": [top - 0.5 * h, m + 0.5 * h]}},
             "traction": [-tau, 0.0], "ramp_time": ramp},
            {"region": {"rectangle": {"min": [top - 0.5 * h, m], "max": [top, top]}},
             "traction": [0.0, tau], "ramp_time": ramp},
            {"region": {"rectangle": {"min": [m, m], "max": [m + 0.5 * h, top]}},
             "traction": [0.0, -tau], "ramp_time": ramp}
        ],
        "damping": {"kind": "viscous", "coefficient": damp},
        "time": {"end": end, "cfl": 0.5}
    }));
    let mut sim = sim(&s, 0);
    while !sim.is_finished() {
        sim.step().unwrap();
        if sim.steps_taken() % 200 == 0 || sim.is_finished() {
            for r in sim.crack_tips() {
                eprintln!("t={:.1}us tip{} J1 {:.3} J2 {:.3} KI {:.0} KII {:.0}", r.time*1e6, r.tip, r.j1, r.j2, r.k1, r.k2);
            }
        }
    }
    // stress sample far from crack
    let p = sim.particles();
    let mut sxy = 0.0; let mut n = 0.0;
    for (k, s) in p.kin.iter().zip(&p.stress) { if (k.x[0]-m-0.02).abs() < 0.01 && (k.x[1]-c).abs() < 0.01 { sxy += s[2]; n += 1.0; } }
    eprintln!("sxy near left side {:.0}; ref K {:.0}, J {:.3}", sxy/n, tau*(std::f64::consts::PI*a).sqrt(), (tau*(std::f64::consts::PI*a).sqrt()).powi(2)/(5.2e9/(1.0-0.34f64.powi(2))));
}
