//! Stability stress tests (issue: "stress-test numerical stability"). Each case either runs
//! stably (energy error bounded, stated per case) or stops with a clear `StepError`: never
//! NaN in the outputs, never a hang (every run is bounded in steps), never a panic.
//! The long variants run with `FRACTURE_LONG_TESTS=1`.
#![allow(clippy::unwrap_used)]

mod common;
use common::*;
use fracture_solver::{Simulation, SolverConfig, StepError};
use serde_json::json;

/// Outcome of a bounded run.
#[derive(Debug)]
struct Outcome {
    steps: u64,
    error: Option<StepError>,
    /// max over the run of |total_error|, divided by the largest energy scale reached
    /// (external work or initial energy).
    rel_energy_error: f64,
}

/// Step until the end, an error, or `max_steps`; check every energy row is finite.
fn run(scene: &fracture_api::Scene, max_steps: u64, velocity: Option<[f64; 2]>) -> Outcome {
    let mut sim = Simulation::new(
        &fracture_api::ValidScene::new(scene.clone()).unwrap(),
        SolverConfig::all_cores(),
    )
    .unwrap();
    if let Some(v) = velocity {
        sim.set_velocities(|_| v);
    }
    let e0 = sim.energy();
    let input0 = e0.kinetic + e0.strain;
    let mut worst: f64 = 0.0;
    let mut scale: f64 = input0.abs();
    let mut error = None;
    while !sim.is_finished() && sim.steps_taken() < max_steps {
        match sim.step() {
            Ok(_) => {}
            Err(e) => {
                error = Some(e);
                break;
            }
        }
        let e = sim.energy();
        // Outputs stay finite even on a failing step: the failure is caught first.
        for x in [
            e.kinetic,
            e.strain,
            e.external_work,
            e.dissipated,
            e.total_error,
        ] {
            assert!(x.is_finite(), "non-finite energy row {e:?}");
        }
        for r in sim.crack_tips() {
            for x in [r.x, r.y, r.speed, r.length] {
                assert!(x.is_finite(), "non-finite crack-tip row {r:?}");
            }
            // J and K are finite, or NaN (null) where they are not defined (a J ring that
            // leaves the material, `docs/solver.md`), never infinite.
            for x in [r.j1, r.j2, r.k1, r.k2] {
                assert!(!x.is_infinite(), "infinite J or K in {r:?}");
            }
        }
        scale = scale.max(e.external_work.abs());
        worst = worst.max(e.total_error.abs());
    }
    let worst = worst / scale.max(1e-300);
    Outcome {
        steps: sim.steps_taken(),
        error,
        rel_energy_error: worst,
    }
}

fn impact(shape: &str, cfl: f64, v: f64, e: f64, end: f64) -> fracture_api::Scene {
    scene(json!({
        "grid": {"cell_size": 0.001, "min": [0.0, 0.0], "max": [0.044, 0.024], "shape_function": shape},
        "materials": {"m": {"model": "linear_elastic", "density": 1230.0, "youngs_modulus": e, "poissons_ratio": 0.34}},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [0.002, 0.002], "max": [0.032, 0.022]}}}],
        "boundary_conditions": [{"region": {"rectangle": {"min": [0.0, 0.0], "max": [0.0021, 0.012]}},
                                 "velocity": {"x": v}, "end": end * 0.3}],
        "time": {"end": end, "cfl": cfl}
    }))
}

/// cfl from 0.1 to 1.0 for both shape functions on an impact: every run completes with
/// the energy error under 2 % of the work done (USAVG with FLIP is stable up to cfl = 1 on
/// this problem), or stops with a diagnosis. Prints the table for docs/stability.md.
#[test]
fn cfl_sweep_both_shape_functions() {
    for shape in ["gimp", "linear"] {
        for k in 1..=10 {
            let cfl = k as f64 / 10.0;
            let c_l = 2551.0;
            let end = 200.0 * cfl * 0.001 / c_l;
            let out = run(&impact(shape, cfl, 5.0, 5.2e9, end), 400, None);
            eprintln!(
                "{shape} cfl {cfl:.1}: steps {} error {:?} energy error {:.3} %",
                out.steps,
                out.error.as_ref().map(|e| e.to_string()),
                100.0 * out.rel_energy_error
            );
            match &out.error {
                None => assert!(
                    out.rel_energy_error < 0.02,
                    "{shape} cfl {cfl}: energy error {}",
                    out.rel_energy_error
                ),
                Some(e) => assert!(!e.to_string().is_empty()),
            }
        }
    }
}

/// Impact velocity from 1 m/s to 10 km/s (c_L = 2551 m/s): small-strain elasticity stops
/// making sense somewhere above ~100 m/s (strain ~ v/c_L). Up to 100 m/s the run is stable
/// (energy error < 2 %); beyond, it either completes or stops with a diagnosis — no panic,
/// no NaN.
#[test]
fn impact_velocity_sweep() {
    for v in [1.0, 10.0, 100.0, 1000.0, 10000.0] {
        let end = 200.0 * 0.5 * 0.001 / 2551.0;
        let out = run(&impact("gimp", 0.5, v, 5.2e9, end), 400, None);
        eprintln!(
            "v {v}: steps {} error {:?} energy error {:.3} %",
            out.steps,
            out.error.as_ref().map(|e| e.to_string()),
            100.0 * out.rel_energy_error
        );
        if v <= 100.0 {
            assert!(out.error.is_none(), "v {v}: {:?}", out.error);
            assert!(out.rel_energy_error < 0.02);
        }
    }
}

/// Very stiff (E = 10¹² Pa) and very soft (E = 10³ Pa) materials: the time step follows
/// c_L, runs are stable with the energy error under 2 %.
#[test]
fn stiff_and_soft_materials() {
    for e in [1.0e12, 1.0e3] {
        let c_l = fracture_api::scene::WaveSpeeds::new(
            e,
            0.34,
            1230.0,
            fracture_api::scene::Analysis::PlaneStrain,
        )
        .c_l;
        let end = 200.0 * 0.5 * 0.001 / c_l;
        // Impact speed a small fraction of c_L so the strain stays small.
        let out = run(&impact("gimp", 0.5, 1e-3 * c_l, e, end), 400, None);
        eprintln!(
            "E {e:e}: steps {} energy error {:.3} %",
            out.steps,
            100.0 * out.rel_energy_error
        );
        assert!(out.error.is_none(), "{:?}", out.error);
        assert!(out.rel_energy_error < 0.02);
    }
}

/// A one-particle scene and a one-cell body run; a body moving fast toward the grid edge
/// stops with a `LeftGrid` diagnosis naming the particle and where.
#[test]
fn tiny_scenes_and_the_grid_edge() {
    let one = scene(json!({
        "grid": {"cell_size": 0.001, "min": [0.0, 0.0], "max": [0.01, 0.01]},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [0.004, 0.004], "max": [0.005, 0.005]}}, "particles_per_cell": 1}],
        "time": {"end": 1.0e-6}
    }));
    let out = run(&one, 100, Some([1.0, 0.0]));
    assert!(out.error.is_none(), "{:?}", out.error);
    // Flying at 100 m/s toward the right edge 4 mm away: leaves within 40 µs.
    let fly = scene(json!({
        "grid": {"cell_size": 0.001, "min": [0.0, 0.0], "max": [0.012, 0.012]},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [0.002, 0.002], "max": [0.006, 0.006]}}, "initial_velocity": [100.0, 0.0]}],
        "time": {"end": 1.0e-4}
    }));
    let out = run(&fly, 1_000_000, None);
    let e = out.error.expect("must stop at the grid edge");
    eprintln!("{e}");
    assert!(matches!(e, StepError::LeftGrid { .. }), "{e}");
    assert!(e.to_string().contains("grid edge"));
}

/// A crack tip one cell from a free surface (the J ring reaches outside the material) and
/// a crack crossing a boundary condition: both run, J is flagged (null, never a silent 0)
/// where its ring leaves the material, energy error < 2 %.
#[test]
fn crack_near_free_surface_and_through_a_boundary_condition() {
    let s = scene(json!({
        "grid": {"cell_size": 0.001, "min": [0.0, 0.0], "max": [0.034, 0.024]},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [0.002, 0.002], "max": [0.032, 0.022]}}}],
        "cracks": [
            {"points": [[0.0015, 0.0125], [0.0305, 0.0125]]},
            {"points": [[0.010, 0.0055], [0.020, 0.0055]]}
        ],
        "boundary_conditions": [
            {"region": {"rectangle": {"min": [0.0, 0.0], "max": [1.0, 0.0021]}}, "velocity": {"y": 0.0}},
            {"region": {"rectangle": {"min": [0.014, 0.0], "max": [0.016, 1.0]}}, "velocity": {"x": 0.0}}
        ],
        "loads": [{"region": {"rectangle": {"min": [0.0, 0.0215], "max": [1.0, 1.0]}}, "traction": [0.0, 1.0e6], "ramp_time": 5.0e-6}],
        "time": {"end": 3.0e-5}
    }));
    let out = run(&s, 1000, None);
    eprintln!(
        "near surface: steps {} error {:?} energy error {:.3} %",
        out.steps,
        out.error,
        100.0 * out.rel_energy_error
    );
    assert!(out.error.is_none(), "{:?}", out.error);
    assert!(out.rel_energy_error < 0.02);
    // The tip 1.5 mm from the right edge: its 6 mm ring leaves the body, so J is null.
    let mut sim = Simulation::new(
        &fracture_api::ValidScene::new(s.clone()).unwrap(),
        SolverConfig::all_cores(),
    )
    .unwrap();
    sim.step().unwrap();
    let rows = sim.crack_tips();
    let near = rows.iter().find(|r| r.crack == 0 && r.tip == 1).unwrap();
    assert!(near.j1.is_nan() && near.k1.is_nan(), "{near:?}");
}

/// 10⁵ steps on a small scene (set FRACTURE_LONG_TESTS=1): a free vibration keeps its energy
/// within 1 % and never produces NaN.
#[test]
fn long_run_hundred_thousand_steps() {
    if std::env::var("FRACTURE_LONG_TESTS").is_err() {
        eprintln!("skipped: set FRACTURE_LONG_TESTS=1 for the 10^5-step run");
        return;
    }
    let s = scene(json!({
        "grid": {"cell_size": 0.001, "min": [0.0, 0.0], "max": [0.014, 0.008]},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [0.002, 0.002], "max": [0.012, 0.006]}}}],
        "time": {"end": 1.0}
    }));
    let mut sim = Simulation::new(
        &fracture_api::ValidScene::new(s.clone()).unwrap(),
        SolverConfig::with_threads(1),
    )
    .unwrap();
    // A full cosine wave along the body: no net momentum and no angular momentum, so the
    // free body vibrates in place (a half-wave would set it spinning into the grid edge).
    sim.set_velocities(|x| {
        [
            0.0,
            0.5 * ((x[0] - 0.002) / 0.010 * 2.0 * std::f64::consts::PI).cos(),
        ]
    });
    let e0 = sim.energy().kinetic;
    for _ in 0..100_000 {
        sim.step().unwrap();
    }
    let e = sim.energy();
    let drift = (e.kinetic + e.strain - e0).abs() / e0;
    eprintln!("10^5 steps: energy drift {:.4} %", 100.0 * drift);
    assert!(drift < 0.01);
}
