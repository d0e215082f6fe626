//! The energy flux the grid hands a tip of prescribed motion in Freund's step wave:
//! J1/(g(v)·G*(t)) over the second half of the window, per cell size and speed, for tips at
//! constant speed (`run_constant_speed`) and on the exact equation-of-motion histories
//! (`run_exact_history`). Prints the tables of `docs/running-tip.md`.
//!
//! `cargo run --release -p fracture-verify --example constant_speed -- [H_MM,...] [V/C_R,...] [R_MM [ZONE_MM [SCALE,...]]]`
//! (defaults: 1,0.5,0.25 and 0.3,0.6,0.85; R and the zone the solver's defaults; `-` keeps a
//! default). SCALE: the zone takes this many times LEFM's flux (default 1); with several,
//! only the constant-speed table is printed, one block per scale.
#![allow(clippy::print_stdout, missing_docs)]

use fracture_solver::SolverConfig;
use fracture_verify::{
    ConstantSpeedRun, Regularisation, Settings, VerifyError, run_constant_speed_taking,
    run_exact_history,
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
    let scales = list(args.next(), "1");
    let cfg = SolverConfig::with_threads(2);
    let header = || {
        println!(
            "| h (mm) | v/c_R | mean speed, 2nd half (c_R) | J1/(gG*), 2nd half | by quarter | s |"
        );
        println!("| --- | --- | --- | --- | --- | --- |");
    };
    for &scale in &scales {
        println!(
            "\nconstant speed v, J ring {}, zone taking {scale} × g(v)G*:\n",
            reg.label()
        );
        header();
        for &h in &hs {
            for &v in &vs {
                let t = std::time::Instant::now();
                let r = run_constant_speed_taking(&Settings::at(h * 1e-3), v, &reg, scale, cfg);
                row(h, v, r, t.elapsed().as_secs_f64());
            }
        }
    }
    if scales.len() > 1 {
        return;
    }
    println!("\nexact history to v, J ring {}:\n", reg.label());
    header();
    for &h in &hs {
        for &v in &vs {
            let t = std::time::Instant::now();
            let r = run_exact_history(&Settings::at(h * 1e-3), v, &reg, cfg);
            row(h, v, r, t.elapsed().as_secs_f64());
        }
    }
}
