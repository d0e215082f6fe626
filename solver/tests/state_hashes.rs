//! The 2D refactor gate (issue 36: "every 2D output bitwise identical to the commit before the
//! refactor"). The 2D solver is being moved onto the dimension-generic core (`fracture-mpm`)
//! in steps; each step must leave every 2D output unchanged to the bit. This test steps the
//! product's own 2D scenes (a growing crack with contact, the cohesive Rosakis scene, the
//! re-sorting projectile impact, Coulomb friction on a closed crack, Kalthoff–Winkler's
//! kinking crack), with both arithmetic kernels and on 1 and 2 threads, and hashes what a run
//! writes: every step's energy row, the crack-tip rows every 10 steps, and at the end every
//! particle array and a snapshot of all fields.
//!
//! The hashes are compared with `tests/data/state_hashes.json`, recorded by this same test at
//! the commit named in the file, before the move began (`FRACTURE_RECORD_STATE_HASHES=1 cargo
//! test -p fracture-solver --release --test state_hashes` writes it). It is a regression gate
//! on the refactor, not a physics check: the physics tests (`tests/*.rs`, `verify`) say whether
//! those bits are right. A deliberate change of 2D results must re-record the file and say so
//! in its commit. The FMA entries are checked only where the CPU has AVX2/FMA.
#![allow(clippy::unwrap_used, clippy::print_stderr)]

mod common;
use std::collections::BTreeMap;
use std::fmt::Write as _;

use common::*;
use fracture_api::Scene;
use fracture_api::scene::FieldKind;
use fracture_solver::kernel::Kernel;
use serde_json::json;
use sha2::{Digest, Sha256};

/// A product scene from `scenes/`, cut to `steps` steps' worth of time (at least).
fn product_scene(name: &str) -> Scene {
    let path = format!("{}/../scenes/{name}.json", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap();
    scene(serde_json::from_str(&text).unwrap())
}

/// The gate's scenes: name, scene, steps, whether a crack must grow within them.
fn cases() -> Vec<(&'static str, Scene, u64, bool)> {
    let mut kw = product_scene("kalthoff-winkler");
    kw.time.end = 4.0e-5;
    // Fast enough to cross strips: the particles re-sort during the run.
    let mut ff = product_scene("free-flight");
    ff.bodies[0].initial_velocity = [300.0, 120.0];
    vec![
        ("free-flight-fast", ff, 120, false),
        ("moving-cracked-plate", moving_cracked_plate(), 150, true),
        (
            "rosakis-shear-mini",
            product_scene("rosakis-shear-mini"),
            140,
            true,
        ),
        (
            "rosakis-shear-cohesive-mini",
            product_scene("rosakis-shear-cohesive-mini"),
            140,
            true,
        ),
        (
            "rosakis-shear-cohesive-projectile-mini",
            product_scene("rosakis-shear-cohesive-projectile-mini"),
            140,
            false,
        ),
        ("coulomb-crack", product_scene("coulomb-crack"), 120, false),
        ("kalthoff-winkler", kw, 200, true),
        ("damped-held-plate", damped_held_plate(), 100, false),
        (
            "viscous-held-cracked-plate",
            viscous_held_cracked_plate(),
            150,
            true,
        ),
    ]
}

/// The edge-cracked plate pulled apart and flying at 150 m/s in a wider grid, for 40 µs:
/// growth, contact and re-sorts in one run.
fn moving_cracked_plate() -> Scene {
    let mut v = edge_cracked_plate_json();
    v["grid"]["max"] = json!([0.064, 0.044]);
    v["bodies"][0]["initial_velocity"] = json!([150.0, 0.0]);
    v["time"]["end"] = json!(4.0e-5);
    scene(v)
}

/// The plate held at its foot, pulled at its top, with kinetic damping (conditions, loads
/// and damping on the grid).
fn damped_held_plate() -> Scene {
    scene(held_plate_json(0.06))
}

/// The edge-cracked plate held along the cracked edge (conditions on nodes with two
/// fields), with viscous damping, for 40 µs.
fn viscous_held_cracked_plate() -> Scene {
    let mut v = edge_cracked_plate_json();
    v["boundary_conditions"] = json!([{"region": {"rectangle": {"min": [0.0, 0.0], "max": [0.0026, 0.044]}},
                                        "velocity": {"x": 0.0}}]);
    v["damping"] = json!({"kind": "viscous", "coefficient": 2000.0});
    v["time"]["end"] = json!(4.0e-5);
    scene(v)
}

fn bits(h: &mut Sha256, xs: &[f64]) {
    for x in xs {
        h.update(x.to_bits().to_le_bytes());
    }
}

/// Run `s` for `steps` steps with `kernel` on `threads` threads: the hash of its outputs and
/// the growth (m) of its longest crack and whether the particles were re-sorted.
fn run_hash(s: &Scene, steps: u64, kernel: Kernel, threads: usize) -> (String, f64, bool) {
    let mut sim = sim(s, threads);
    assert_eq!(sim.set_kernel(kernel), kernel);
    let mut h = Sha256::new();
    let first = sim.crack_tips();
    let mut ids0: Vec<u32> = Vec::new();
    let mut rows = String::new();
    for k in 0..steps {
        if sim.is_finished() {
            break;
        }
        sim.step().unwrap();
        if k == 0 {
            // The order after the first step's sort: a later change is a re-sort.
            ids0 = sim.particles().cold.iter().map(|c| c.id).collect();
        }
        rows.clear();
        writeln!(rows, "{}", sim.energy().to_csv()).unwrap();
        if k % 10 == 9 {
            for t in sim.crack_tips() {
                writeln!(rows, "{t:?}").unwrap();
            }
        }
        h.update(rows.as_bytes());
    }
    let p = sim.particles();
    for i in 0..p.len() {
        let (k, m, c) = (p.kin[i], p.mech[i], p.cold[i]);
        bits(&mut h, &[k.x[0], k.x[1], k.v[0], k.v[1], m.m, m.vol, m.lh]);
        bits(&mut h, &p.stress[i]);
        bits(&mut h, &[p.wden[i], c.x0[0], c.x0[1]]);
        h.update(c.id.to_le_bytes());
        if let Some(g) = p.grad_u.get(i) {
            bits(&mut h, g);
        }
        if let Some(f) = p.fmask.get(i) {
            h.update(f.to_le_bytes());
        }
    }
    let snap = sim.snapshot(0, &FieldKind::ALL);
    h.update(serde_json::to_vec(&snap).unwrap());
    // The checkpoint's bytes: a checkpoint written before the move resumes after it.
    h.update(sim.checkpoint());
    let grown = sim
        .crack_tips()
        .iter()
        .zip(&first)
        .map(|(a, b)| a.length - b.length)
        .fold(0.0, f64::max);
    let resorted = sim.particles().cold.iter().map(|c| c.id).ne(ids0);
    (format!("{:x}", h.finalize()), grown, resorted)
}

fn record_path() -> String {
    format!(
        "{}/tests/data/state_hashes.json",
        env!("CARGO_MANIFEST_DIR")
    )
}

#[test]
fn two_d_outputs_are_bitwise_those_recorded_before_the_move() {
    let recording = std::env::var_os("FRACTURE_RECORD_STATE_HASHES").is_some();
    let recorded: BTreeMap<String, String> = if recording {
        BTreeMap::new()
    } else {
        let text = std::fs::read_to_string(record_path()).unwrap();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        serde_json::from_value(v["hashes"].clone()).unwrap()
    };
    let mut now = BTreeMap::new();
    for (name, s, steps, grows) in cases() {
        for kernel in [Kernel::Portable, Kernel::Fma] {
            if !kernel.available() {
                eprintln!("{name}: this CPU has no AVX2/FMA; the FMA hash is not checked");
                continue;
            }
            let (one, grown, resorted) = run_hash(&s, steps, kernel, 1);
            let (two, _, _) = run_hash(&s, steps, kernel, 2);
            assert_eq!(
                one,
                two,
                "{name} ({}): 1 and 2 threads differ",
                kernel.name()
            );
            eprintln!(
                "{name} ({}): {one}, crack grew {:.2} mm, re-sorted: {resorted}",
                kernel.name(),
                grown * 1e3
            );
            if name.starts_with("free-flight") || name.starts_with("moving") {
                assert!(resorted, "{name}: the gate needs a run that re-sorts");
            }
            if grows {
                assert!(
                    grown > 1e-3,
                    "{name}: the gate needs a growing crack (grew {grown} m)"
                );
            }
            now.insert(format!("{name}/{}", kernel.name()), one);
        }
    }
    if recording {
        let commit = std::env::var("FRACTURE_RECORD_COMMIT").unwrap_or_default();
        let v = serde_json::json!({
            "what": "SHA-256 of a 2D run's outputs (tests/state_hashes.rs); recorded before the 2D solver's move onto the core",
            "commit": commit,
            "hashes": now,
        });
        std::fs::create_dir_all(format!("{}/tests/data", env!("CARGO_MANIFEST_DIR"))).unwrap();
        std::fs::write(
            record_path(),
            serde_json::to_string_pretty(&v).unwrap() + "\n",
        )
        .unwrap();
        return;
    }
    for (k, h) in &now {
        let want = recorded
            .get(k)
            .unwrap_or_else(|| panic!("{k}: no recorded hash"));
        assert_eq!(h, want, "{k}: 2D outputs changed since the recorded commit");
    }
}
