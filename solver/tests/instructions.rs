//! The 2D instruction gate (issue 36: "2D instructions per particle-step within 2 %
//! (cachegrind)"). The 2D step now runs on the dimension-generic core; this test counts the
//! instructions one particle-step of the seed block costs (`examples/profile_step.rs`, 2 mm
//! cells, 31,250 particles, one thread, with and without a crack, portable and FMA kernels)
//! under valgrind's cachegrind, as the difference of 6 and 3 timed steps so that set-up is left
//! out, and compares them with the counts recorded at the commit before the move
//! (`tests/data/instructions.json`, the same example in the same test profile): at most 2 %
//! more.
//!
//! Instruction counts belong to a compiler: with another `rustc` than the recorded one the
//! comparison says nothing and the test says so and stops; without valgrind, or without the
//! example binary (`cargo test` builds the examples; a filtered `cargo test --test` does not),
//! likewise. CI installs valgrind (`.ci/run`) and runs it. `scripts/instructions-2d.sh` is the
//! same measurement on release builds, for the performance notes.
#![allow(clippy::unwrap_used, clippy::print_stderr)]

use std::path::PathBuf;
use std::process::Command;

use fracture_solver::kernel::Kernel;

/// Particles of the example's block at 2 mm cells.
const PARTICLES: u64 = 31_250;

fn example() -> Option<PathBuf> {
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../target"));
    let p = target.join("debug/examples/profile_step");
    p.exists().then_some(p)
}

/// Instructions of one run of the example (cachegrind's "I refs").
fn instructions(bin: &PathBuf, steps: u32, case: &[&str]) -> u64 {
    let out = Command::new("valgrind")
        .args([
            "--tool=cachegrind",
            "--cache-sim=no",
            "--cachegrind-out-file=/dev/null",
        ])
        .arg(bin)
        .args(["0.002", &steps.to_string()])
        .args(case)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    let line = err
        .lines()
        .find(|l| l.contains("I") && l.contains("refs"))
        .unwrap_or_else(|| panic!("no instruction count from cachegrind: {err}"));
    line.split_whitespace()
        .last()
        .unwrap()
        .replace(',', "")
        .parse()
        .unwrap()
}

#[test]
fn two_d_step_instructions_stay_within_two_percent_of_before_the_move() {
    let text = std::fs::read_to_string(format!(
        "{}/tests/data/instructions.json",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let rec: serde_json::Value = serde_json::from_str(&text).unwrap();
    let rustc = Command::new(std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into()))
        .arg("--version")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default();
    if rustc != rec["rustc"].as_str().unwrap() {
        eprintln!(
            "recorded with {}, this is {rustc}: counts not comparable",
            rec["rustc"]
        );
        return;
    }
    if Command::new("valgrind").arg("--version").output().is_err() {
        eprintln!("no valgrind: the instruction gate is not measured here");
        return;
    }
    let Some(bin) = example() else {
        eprintln!("no target/debug/examples/profile_step (run the whole `cargo test`)");
        return;
    };
    for case in ["portable", "fma", "crack portable", "crack fma"] {
        if case.contains("fma") && !Kernel::Fma.available() {
            eprintln!("{case}: this CPU has no AVX2/FMA");
            continue;
        }
        let args: Vec<&str> = case.split(' ').collect();
        let per = (instructions(&bin, 6, &args) - instructions(&bin, 3, &args)) / (3 * PARTICLES);
        let before = rec[case].as_u64().unwrap();
        let change = per as f64 / before as f64 - 1.0;
        eprintln!(
            "{case}: {per} instructions per particle-step, {before} before the move ({:+.1} %)",
            100.0 * change
        );
        assert!(
            change <= 0.02,
            "{case}: {per} vs {before} before the move ({:+.1} %)",
            100.0 * change
        );
    }
}
