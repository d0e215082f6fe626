//! The energy flux the grid hands a tip of prescribed motion in Freund's step wave:
//! J1/(g(v)·G*(t)) over the second half of the window, per cell size and speed, for tips at
//! constant speed (`run_constant_speed`) and on the exact equation-of-motion histories
//! (`run_exact_history`). Prints the tables of `docs/running-tip.md`.
//!
//! `cargo run --release -p fracture-verify --example constant_speed -- [H_MM,...] [V/C_R,...] [R_MM [ZONE_MM]]`
//! (defaults: 1,0.5,0.25 and 0.3,0.6,0.85; R and the zone the solver's defaults; `-` keeps a
//! default).
#![allow(clippy::print_stdout, missing_docs)]

use fracture_solver::SolverConfig;
use fracture_verify::{
    ConstantSpeedRun, Regularisation, Settings, VerifyError, run_constant_speed, run_exact_history,
};

fn list(a: Option<String>, d: &str) -> Vec<f64> {
    a.unwrap_or_else(|| d.into())
        .split(',')
        .filter_map(|x| x.parse().ok())
        .collect()
}

fn row(h: f64, v: f64, r: Result<ConstantSpeedRun, VerifyError>, secs: f64) {
    match r {
        Ok(r) => {
            let q = r.ratio_quarters.map(|x| format!("{x:.2}"));
            println!(
                "| {h} | {v} | {:.3} | **{:.3}** | {} | {secs:.0} |",
                r.mean_speed / r.c_r,
                r.ratio,
                q.join(" / ")
            );
        }
        Err(e) => println!("| {h} | {v} | – | error: {e} | – | {secs:.0} |"),
    }
}

fn main() {
    let mut args = std::env::args().skip(1);
    let hs = list(args.next(), "1,0.5,0.25");
    let vs = list(args.next(), "0.3,0.6,0.85");
    let mm = |a: Option<String>| a.and_then(|x| x.parse::<f64>().ok()).map(|r| r * 1e-3);
    let reg = Regularisation {
        j_radius: mm(args.next()),
        process_zone: mm(args.next()),
        filter_time: None,
    };
    let cfg = SolverConfig::with_threads(2);
    for (title, exact) in [("constant speed v", false), ("exact history to v", true)] {
        println!("\n{title}, J ring {}:\n", reg.label());
        println!(
            "| h (mm) | v/c_R | mean speed, 2nd half (c_R) | J1/(gG*), 2nd half | by quarter | s |"
        );
        println!("| --- | --- | --- | --- | --- | --- |");
        for &h in &hs {
            for &v in &vs {
                let st = Settings::at(h * 1e-3);
                let t = std::time::Instant::now();
                let r = if exact {
                    run_exact_history(&st, v, &reg, cfg)
                } else {
                    run_constant_speed(&st, v, &reg, cfg)
                };
                row(h, v, r, t.elapsed().as_secs_f64());
            }
        }
    }
}
