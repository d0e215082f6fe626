//! Checks of the continuum solver against `reference-solutions.md` ("Checks of the continuum
//! solver"). Each test states its reference, resolution and tolerance.
#![allow(clippy::unwrap_used)]

mod common;
use common::*;
use fracture_solver::SolverConfig;
use fracture_verify::{self as verification, Settings};
use serde_json::json;

/// Rigid translation: a body in free flight keeps its momentum exactly (to round-off) and
/// develops no stress. Reference: rigid-body motion; tolerance: momentum 1e-12 relative,
/// |σ| < 1e-6 Pa (E = 5.2 GPa, so ~1e-15 relative).
#[test]
fn free_flight_keeps_momentum_and_no_stress() {
    let s = scene(json!({
        "name": "free-flight",
        "grid": {"cell_size": 0.001, "min": [0.0, 0.0], "max": [0.06, 0.03]},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"circle": {"center": [0.02, 0.015], "radius": 0.008}},
                    "initial_velocity": [12.0, -7.0]}],
        "time": {"end": 4.0e-4, "cfl": 0.5}
    }));
    let mut sim = sim(&s, 2);
    let p0 = momentum(&sim);
    while !sim.is_finished() {
        sim.step().unwrap();
    }
    let p1 = momentum(&sim);
    for k in 0..2 {
        assert!(
            (p1[k] - p0[k]).abs() <= 1e-12 * p0[k].abs(),
            "momentum {p0:?} -> {p1:?}"
        );
    }
    let smax = sim
        .particles()
        .stress
        .iter()
        .flat_map(|s| s.iter().copied())
        .fold(0.0f64, |a, b| a.max(b.abs()));
    assert!(smax < 1e-6, "free flight developed stress {smax} Pa");
    // It really flew: ~12 m/s × 0.4 ms = 4.8 mm.
    let x: f64 =
        sim.particles().kin.iter().map(|k| k.x[0]).sum::<f64>() / sim.particle_count() as f64;
    assert!(
        (x - (0.02 + 12.0 * sim.time())).abs() < 1e-9,
        "centre x = {x}"
    );
}

/// Laterally constrained bar under a step traction at one end: the front moves at the
/// plane-strain c_L, and the particle velocity behind it is σ/(ρ c_L).
/// Reference: 1D elastic wave; resolution: 1 mm cells, 2×2 particles per cell, cfl 0.5;
/// tolerance: speed 2 %, velocity 3 % (issue acceptance). Scene and front tracking:
/// `verification::wave_bar`, `verification::run_wave_bar`.
#[test]
fn constrained_bar_wave_speed_and_particle_velocity() {
    let r =
        verification::run_wave_bar(&Settings::at(0.001), SolverConfig::with_threads(2)).unwrap();
    let (c, c_l) = (r.speed, r.c_l);
    let (plateau, v_expected) = (r.plateau, r.v_expected);
    let c_err = (c - c_l).abs() / c_l;
    let v_err = (plateau - v_expected).abs() / v_expected;
    eprintln!(
        "front speed {c:.1} m/s vs c_L {c_l:.1} ({:.2} %), v {plateau:.5} vs {v_expected:.5} ({:.2} %)",
        100.0 * c_err,
        100.0 * v_err
    );
    assert!(c_err < 0.02, "front speed {c} vs c_L {c_l}");
    assert!(
        v_err < 0.03,
        "particle velocity {plateau} vs σ/(ρc) {v_expected}"
    );
}

/// Fixed–free vibrating bar (reference-solutions.md): L = 25, E = 100, ρ = 1, v₀ = 0.1,
/// v(x, 0) = v₀ sin(πx/2L): period 10.000. Resolution: 50 cells along the bar, 2×2
/// particles per cell, cfl 0.5, GIMP. Tolerance: period 0.5 %, energy kept within 1 % over
/// 10 periods (issue acceptance). Scene and period fit: `verification::run_vibrating_bar`.
#[test]
fn vibrating_bar_period_and_energy() {
    let r =
        verification::run_vibrating_bar(&Settings::at(0.5), SolverConfig::with_threads(2)).unwrap();
    // Crossings every half period: the period is fitted over all of them.
    let n = r.crossings;
    assert!(n >= 19, "only {n} zero crossings");
    let (period, loss) = (r.period, r.energy_loss);
    eprintln!(
        "period {period:.5} (10.000), energy change {:.3} % over {:.1} periods",
        100.0 * loss,
        r.time / 10.0
    );
    assert!((period - 10.0).abs() / 10.0 < 0.005, "period {period}");
    assert!(loss.abs() < 0.01, "energy changed by {:.3} %", 100.0 * loss);
}

/// Energy balance on an impact with no damping: kinetic + strain − external work stays
/// within 1 % of the energy put in (issue acceptance). A plane-strain Homalite block struck
/// on part of one edge by a prescribed velocity for 10 µs, then free; 1 mm cells.
#[test]
fn impact_energy_balance() {
    let s = scene(json!({
        "name": "impact",
        "grid": {"cell_size": 0.001, "min": [0.0, 0.0], "max": [0.064, 0.044]},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [0.002, 0.002], "max": [0.062, 0.042]}}}],
        "boundary_conditions": [{"region": {"rectangle": {"min": [0.0, 0.0], "max": [0.0021, 0.02]}},
                                 "velocity": {"x": 10.0}, "ramp_time": 1.0e-6, "end": 1.0e-5}],
        "time": {"end": 4.0e-5, "cfl": 0.5}
    }));
    let mut sim = sim(&s, 2);
    let mut worst: f64 = 0.0;
    while !sim.is_finished() {
        sim.step().unwrap();
        let e = sim.energy();
        worst = worst.max(e.total_error.abs());
    }
    let e = sim.energy();
    eprintln!("{e:?}; worst |error| {worst:e}");
    assert!(e.external_work > 0.0);
    assert!(
        worst < 0.01 * e.external_work,
        "energy error {worst:e} vs input {:e}",
        e.external_work
    );
}

/// 1 thread and 2 threads give bitwise-identical energies and particle states.
#[test]
fn threads_give_identical_results() {
    let s = scene(json!({
        "name": "determinism",
        "grid": {"cell_size": 0.001, "min": [0.0, 0.0], "max": [0.08, 0.03]},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [0.002, 0.002], "max": [0.078, 0.028]}},
                    "initial_velocity": [3.0, 0.0]}],
        "boundary_conditions": [{"region": {"rectangle": {"min": [0.0, 0.0], "max": [0.08, 0.0021]}},
                                 "velocity": {"y": 1.0}}],
        "time": {"end": 3.0e-5, "cfl": 0.7}
    }));
    let run = |threads| {
        let mut sim = sim(&s, threads);
        let mut rows = Vec::new();
        while !sim.is_finished() {
            sim.step().unwrap();
            rows.push(sim.energy().to_csv());
        }
        let state: Vec<u64> = sim
            .particles()
            .kin
            .iter()
            .flat_map(|k| [k.x[0].to_bits(), k.v[1].to_bits()])
            .collect();
        (rows, state)
    };
    let (a, sa) = run(1);
    let (b, sb) = run(2);
    assert_eq!(a, b);
    assert_eq!(sa, sb);
}
