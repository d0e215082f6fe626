//! Dynamic fracture checks: Freund's step-wave problem, dynamic path independence, and
//! propagation (`reference-solutions.md`).
#![allow(clippy::unwrap_used)]

mod common;
use common::*;
use fracture_solver::SolverConfig;
use fracture_verify::{self as verification, Settings};
use serde_json::json;

/// Freund's stationary crack under a plane step tensile wave:
/// K_I(t) = 2σ*·sqrt(c_L (t − t_c)(1 − 2ν)/π)/(1 − ν).
/// Geometry: a 40 mm wide strip with roller sides (x velocity fixed), an edge crack of 20 mm
/// at mid-height, a step traction σ* on the top edge, bottom edge free. The roller at the
/// mouth mirrors the crack, so the first scattered waves (from the mirror tip and the far
/// roller) reach the tip 2·20 mm/c_L = 15.7 µs after t_c. Resolution: 0.5 mm cells, 2×2
/// particles per cell, cfl 0.5, J contour half-size `contour` (`verification::freund`).
fn freund(contour: u32) -> Vec<(f64, f64, f64)> {
    let f = verification::freund(&Settings {
        j_contour: contour,
        ..Settings::at(0.0005)
    })
    .unwrap();
    verification::freund_series(&f, SolverConfig::all_cores())
        .unwrap()
        .rows
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
        eprintln!(
            "t-tc {:.2} us  K {k:.0}  Freund {k_ref:.0}  ({:+.2} %)",
            dt * 1e6,
            100.0 * (k - k_ref) / k_ref
        );
    }
    eprintln!("worst {:.2} % over {n} samples", 100.0 * worst);
    assert!(n > 50);
    assert!(worst < 0.05, "worst error {:.2} %", 100.0 * worst);
}

/// Stable growth against beam theory: a double cantilever beam (arms H = 5 mm thick, initial
/// crack 20 mm, Homalite, plane strain) opened slowly at its end (0.2 m/s per arm) grows
/// under displacement control by the equation of motion. Each arm is pulled by one column of
/// nodes at the end (a pin: the arm's end is free to rotate; a gripped strip several nodes
/// wide clamps the rotation and doubles J at a given opening). Beam theory with the root
/// rotation of the arms (Kanninen 1973: each arm a cantilever built in at an effective
/// a + χH, χ ≈ 0.64) gives G = 3E'H³Δ²/(16(a + χH)⁴) for a total opening Δ, so a crack that
/// grows at G = Γ has a = (3E'H³Δ²/(16Γ))^¼ − χH. Beam theory is quasi-static, and the arms'
/// first flexural period (~290 µs) is as long as the test, so the mass-proportional damping
/// (4·10⁴ /s) is near critical for that mode (ζ ≈ 0.9); with 10⁴ /s the crack ran in bursts
/// as J rode the vibration and the worst deviation swung between 6.6 and 14 % with the
/// filter time alone. Once it has grown 2h, the crack length (tip to load line) stays within
/// 8 % of beam theory at every sample and ends within 3 %, and the crack grows by more than 4h.
/// 0.5 mm cells (10 per arm), 2×2 particles per cell. Measured: worst +5.9 %, end +1.7 %;
/// the seed's `wave` rule ends +4.1 % and fails (`SPEED=wave`). With a throw-away switch, not
/// in the code (2026-12-03): default filter times of 2–6 cells gave worst 4.4–6.9 %, end
/// 0–2.2 %; the law before this one (relaxing on (G_f − Γ)/Γ) ended +5.0 % with a 6-cell
/// filter. The growth comes in 100–480 m/s bursts that stop (J's noise at a growing tip), so
/// the end error is partly a draw: the same scene as a `fracture run` with `filter_time`
/// 0.6–2.4 µs ends −1.8…+5.2 %, 2 of 12 past 3 % (`docs/rosakis-resolution.md`, 2026-12-03).
/// A change that moves it a few per cent may be noise; check it over several filter times.
#[test]
fn dcb_crack_length_follows_beam_theory() {
    let h = 0.0005;
    let m = 2.0 * h;
    let (len, arm, a0) = (0.060, 0.005, 0.020);
    let yc = m + arm + 0.5 * h;
    let top = m + 2.0 * arm + h;
    let gc = 10.0;
    let (vel, ramp) = (0.2, 2.0e-5);
    let s = scene(json!({
        "name": "dcb",
        "grid": {"cell_size": h, "min": [0.0, 0.0], "max": [len + 2.0 * m, top + m]},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [m, m], "max": [m + len, top]}}}],
        "cracks": [{"points": [[m - 0.5 * h, yc], [m + a0, yc]],
                    "j_integral": {"method": "domain", "radius": 6.0 * h},
                    "propagation": {"criterion": "energy_release", "toughness": gc, "direction": {"fixed": [1.0, 0.0]}, "speed": std::env::var("SPEED").unwrap_or("equation_of_motion".into())}}],
        "boundary_conditions": [
            {"region": {"rectangle": {"min": [m - 0.25 * h, yc + 2.0 * h], "max": [m + 0.25 * h, 1.0]}}, "velocity": {"y": vel}, "ramp_time": ramp},
            {"region": {"rectangle": {"min": [m - 0.25 * h, 0.0], "max": [m + 0.25 * h, yc - 2.0 * h]}}, "velocity": {"y": -vel}, "ramp_time": ramp}
        ],
        "damping": {"kind": "viscous", "coefficient": 4.0e4},
        "time": {"end": 5.0e-4, "cfl": 0.5}
    }));
    let mat = &s.materials["m"];
    let (e, nu) = (mat.youngs_modulus(), mat.poissons_ratio());
    let e_prime = e / (1.0 - nu * nu);
    // Load line: the pulled column of nodes, the body's end.
    let load_x = m;
    let chi = 0.64;
    let mut sim = sim(&s, 0);
    let mut worst: f64 = 0.0;
    let mut samples = 0;
    while !sim.is_finished() {
        sim.step().unwrap();
        let t = sim.time();
        let c = &sim.cracks().unwrap().cracks[0];
        if c.tips[1].advance < 2.0 * h || !sim.steps_taken().is_multiple_of(20) {
            continue;
        }
        let opening = 2.0 * vel * (t - 0.5 * ramp);
        let a = c.pts[c.pts.len() - 1].x[0] - load_x;
        let beam =
            (3.0 * e_prime * arm.powi(3) * opening * opening / (16.0 * gc)).powf(0.25) - chi * arm;
        worst = worst.max((a / beam - 1.0).abs());
        samples += 1;
    }
    let c = &sim.cracks().unwrap().cracks[0];
    let a = c.pts[c.pts.len() - 1].x[0] - load_x;
    let opening = 2.0 * vel * (sim.time() - 0.5 * ramp);
    let beam =
        (3.0 * e_prime * arm.powi(3) * opening * opening / (16.0 * gc)).powf(0.25) - chi * arm;
    eprintln!(
        "DCB grew {:.2} mm; at the end a = {:.2} mm vs beam theory {:.2} mm; worst deviation over {samples} samples {:.1} %",
        c.tips[1].advance * 1e3,
        a * 1e3,
        beam * 1e3,
        100.0 * worst
    );
    assert!(
        c.tips[1].advance > 4.0 * h,
        "the crack barely grew: {} m",
        c.tips[1].advance
    );
    assert!(
        worst < 0.08,
        "crack length off beam theory by {:.1} %",
        100.0 * worst
    );
    assert!(
        (a / beam - 1.0).abs() < 0.03,
        "final crack length {:.2} mm vs beam theory {:.2} mm",
        a * 1e3,
        beam * 1e3
    );
}

/// With a growing crack (fields, contact, J every step, propagation), 1 and 2 threads give
/// bitwise-identical energy and crack-tip rows.
#[test]
fn threads_give_identical_results_with_a_growing_crack() {
    // The edge-cracked plate of tests/common, for 30 µs.
    let mut v = edge_cracked_plate_json();
    v["time"]["end"] = json!(3.0e-5);
    let s = scene(v);
    let run = |threads| {
        let mut sim = sim(&s, threads);
        let mut rows = Vec::new();
        while !sim.is_finished() {
            sim.step().unwrap();
            rows.push(sim.energy().to_csv());
            for r in sim.crack_tips() {
                rows.push(r.to_csv());
            }
        }
        rows
    };
    let a = run(1);
    let b = run(2);
    assert!(
        a.iter().any(|r| r.split(',').nth(11) == Some("1")),
        "the crack never grew"
    );
    assert_eq!(a, b);
}

/// Fixed-direction growth follows the bond's material line (`docs/scene-extensions.md`,
/// "Propagation"): the reduced Rosakis scene (`scenes/rosakis-shear-mini.json`, an impact
/// that shears a bond at y = 27.5 mm, 1 mm cells) grows its crack about 22 mm along the bond
/// under the scene's growth law, the default equation of motion (about 40 mm under the seed's
/// wave rule, which the scene named before), while the struck lower half moves and shears the
/// bond line. At every 5 µs the tip must lie within h/10 of where the bond's material now is:
/// the initial bond y plus the mean y displacement of the particles within 1.5h of the tip.
/// It is 0.0025 mm (0.002 mm under the wave rule); growing straight in the current
/// configuration instead (the rule before) left the tip 0.19 mm off.
#[test]
fn fixed_direction_growth_follows_the_material_line() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenes/rosakis-shear-mini.json"
    );
    let text = std::fs::read_to_string(path).unwrap();
    let s: fracture_api::Scene = serde_json::from_str(&text).unwrap();
    let (h, bond_y) = (s.grid.cell_size, s.cracks[0].points[0][1]);
    let mut sim = common::sim(&s, 0);
    let mut worst: f64 = 0.0;
    let mut next_check = 5e-6;
    while !sim.is_finished() {
        sim.step().unwrap();
        if sim.time() < next_check {
            continue;
        }
        next_check += 5e-6;
        let c = &sim.cracks().unwrap().cracks[0];
        let tip = c.pts[c.pts.len() - 1].x;
        let p = sim.particles();
        let (mut n, mut uy) = (0.0, 0.0);
        for (k, cold) in p.kin.iter().zip(&p.cold) {
            let d = [k.x[0] - tip[0], k.x[1] - tip[1]];
            if d[0].hypot(d[1]) < 1.5 * h {
                n += 1.0;
                uy += k.x[1] - cold.x0[1];
            }
        }
        assert!(n > 0.0, "no material around the tip at {:e} s", sim.time());
        let off = tip[1] - (bond_y + uy / n);
        worst = worst.max(off.abs());
    }
    let c = &sim.cracks().unwrap().cracks[0];
    let grown = c.tips[1].advance;
    eprintln!(
        "grew {:.1} mm; largest distance of the tip from the bond's material line {:.4} mm",
        grown * 1e3,
        worst * 1e3
    );
    assert!(grown > 10.0 * h, "the crack grew only {grown} m");
    assert!(
        worst < 0.1 * h,
        "tip {worst} m off the bond's material line (tolerance h/10 = {} m)",
        0.1 * h
    );
}
