//! The 3D example scenes of `scenes/` through the scene reader: each validates and runs; the
//! wave bar's front moves at c_L and its slices show the Rankine–Hugoniot stress; the impact
//! keeps its energy and momentum.

use fracture_api::results::Snapshot;
use fracture_api::scene::FieldKind;
use fracture_api::{AnyScene, ValidScene3, parse_any_scene};
use fracture_solver3d::Simulation3;

fn load(name: &str) -> ValidScene3 {
    let path = format!("{}/../scenes/{name}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).expect("scene file");
    match parse_any_scene(&text).expect("parses") {
        AnyScene::Three(s) => ValidScene3::new(s).expect("valid"),
        AnyScene::Two(_) => panic!("{name} is not a 3D scene"),
    }
}

#[test]
fn every_3d_scene_validates_and_steps() {
    let dir = format!("{}/../scenes", env!("CARGO_MANIFEST_DIR"));
    let mut n = 0;
    for e in std::fs::read_dir(dir).expect("scenes") {
        let name = e.expect("entry").file_name().to_string_lossy().into_owned();
        if !name.starts_with("3d-") {
            continue;
        }
        let valid = load(&name);
        let mut sim = Simulation3::new(&valid, 2).expect("build");
        for _ in 0..3 {
            sim.step().expect("step");
        }
        let snaps = sim.slice_snapshots(0, &[FieldKind::Stress, FieldKind::Velocity]);
        assert_eq!(snaps.len(), sim.slices().len(), "{name}");
        n += 1;
    }
    assert!(n >= 3, "only {n} 3D scenes");
}

/// Where σ_xx along the slice's mid row first falls to half of `plateau`.
fn front(s: &Snapshot, plateau: f64) -> f64 {
    let c = s.component("sxx").expect("sxx");
    let nx = s.nx as usize;
    let j = (s.ny / 2) as usize;
    let row: Vec<f64> = (0..nx).map(|i| f64::from(c.values[j * nx + i])).collect();
    let x = |i: usize| s.origin[0] + i as f64 * s.cell_size;
    // Start a few nodes in (the driven end).
    for i in 6..nx {
        let (a, b) = (row[i - 1] / plateau, row[i] / plateau);
        if a >= 0.5 && b < 0.5 {
            return x(i - 1) + (a - 0.5) / (a - b) * s.cell_size;
        }
    }
    f64::NAN
}

#[test]
fn wave_bar_front_runs_at_c_l() {
    let valid = load("3d-wave-bar.json");
    let mut sim = Simulation3::new(&valid, 2).expect("build");
    let m = &valid.scene().materials["steel"];
    let c_l = m
        .wave_speeds(fracture_api::scene::Analysis::PlaneStrain)
        .c_l;
    let plateau = -m.density() * c_l * 1.0;
    let mut fronts = Vec::new();
    for t in [4e-6, 9e-6] {
        while sim.time() < t - 0.5 * sim.time_step() {
            sim.step().expect("step");
        }
        let snaps = sim.slice_snapshots(0, &[FieldKind::Stress]);
        let z = &snaps[0];
        assert_eq!(z.slice.as_ref().map(|s| s.normal.as_str()), Some("z"));
        // Behind the front the slice shows −ρ c_L v within 2 % on average.
        let c = z.component("sxx").expect("sxx");
        let nx = z.nx as usize;
        // The mean over 1–13 mm (the plateau rings by ±10 % node to node behind the front:
        // the grid's dispersion, no damping).
        let j = z.ny as usize / 2;
        let mid = (4..17)
            .map(|i| f64::from(c.values[j * nx + i]))
            .sum::<f64>()
            / 13.0;
        assert!((mid / plateau - 1.0).abs() < 0.02, "{mid:e} vs {plateau:e}");
        fronts.push((sim.time(), front(z, plateau)));
    }
    let c = (fronts[1].1 - fronts[0].1) / (fronts[1].0 - fronts[0].0);
    eprintln!(
        "3d-wave-bar: front speed {c:.1} m/s, c_L {c_l:.1} m/s ({:+.2} %)",
        100.0 * (c / c_l - 1.0)
    );
    assert!((c / c_l - 1.0).abs() < 0.02, "{c} vs {c_l}");
}

#[test]
fn impact_scene_keeps_energy_and_momentum() {
    let valid = load("3d-impact.json");
    let mut sim = Simulation3::new(&valid, 2).expect("build");
    let e0 = sim.energy().kinetic;
    let p0 = sim.core().momentum();
    let mut worst: f64 = 0.0;
    while !sim.is_finished() {
        sim.step().expect("step");
        let e = sim.energy();
        worst = worst.max(((e.kinetic + e.strain) / e0 - 1.0).abs());
    }
    let p1 = sim.core().momentum();
    eprintln!("3d-impact: worst energy error {:.4} %", 100.0 * worst);
    assert!(worst < 0.005, "{worst}");
    assert!((p1[0] - p0[0]).abs() < 1e-12 * p0[0].abs());
}
