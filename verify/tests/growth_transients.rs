//! Crack growth against known transients (issue 34, item 4): Freund's exact g(v) and its
//! properties, Freund's step wave on a crack growing at constant Γ (the fastest case, 0.85 c_R
//! at the end of the window) under the solver's defaults and under a regularisation held at
//! J ring 3 mm, zone 1 mm, filter 1.2 µs, and the strip with fixed grips at v* = 0.6 c_R, all at
//! 0.5 mm cells. References: `reference-solutions.md`, "Dynamic stress intensity factor
//! (Freund)" and "Growth: direction, speed, energy"; scenes and runners in
//! `fracture_verify::freund_growth`; the study over cell sizes is `fracture study growth`
//! (`docs/growth.md`). The growth checks are acceptance tests of issue 34: those the solver
//! does not meet yet are ignored with the measured number.
#![allow(clippy::unwrap_used, clippy::print_stderr)]

use fracture_api::scene::{Analysis, WaveSpeeds};
use fracture_solver::{Parallelism, SolverConfig};
use fracture_verify::*;

fn homalite() -> WaveSpeeds {
    WaveSpeeds::new(5.2e9, 0.34, 1230.0, Analysis::PlaneStrain)
}

/// The regularisation held fixed in physical units: J ring 3 mm, zone 1 mm, filter 1.2 µs.
fn physical() -> Regularisation {
    Regularisation::physical(3.0e-3, 1.0e-3, 1.2e-6)
}

fn config() -> SolverConfig {
    SolverConfig {
        threads: Parallelism::threads(1),
    }
}

/// Freund's g(v) = A_I(v)·k(v)² (Homalite, plane strain): k(0) = g(0) = 1, k(c_R) = g(c_R) = 0,
/// g strictly decreasing on [0, c_R], below 1 − v/c_R everywhere inside and by 2–25 % between
/// 0.2 and 0.8 c_R (measured: 3.5 % at 0.2, 10.2 % at 0.5, 23.4 % at 0.8 c_R), and the
/// factorisation of the Rayleigh function that defines S_+ holds on |ζ| < 1/c_L (1e-9).
#[test]
fn exact_g_has_freunds_properties() {
    let s = homalite();
    let (c_l, c_s, c_r) = (s.c_l, s.c_s, s.c_r);
    assert_eq!(freund_k(0.0, c_l, c_s, c_r), 1.0);
    assert_eq!(freund_g_exact(0.0, c_l, c_s, c_r), 1.0);
    assert_eq!(freund_k(c_r, c_l, c_s, c_r), 0.0);
    assert!((freund_k(1e-6 * c_r, c_l, c_s, c_r) - 1.0).abs() < 1e-5);
    assert!(freund_g_exact(0.9999 * c_r, c_l, c_s, c_r) < 1e-3);
    let mut prev = 1.0;
    for i in 1..200 {
        let f = i as f64 / 200.0;
        let g = freund_g_exact(f * c_r, c_l, c_s, c_r);
        assert!(g < prev, "g not decreasing at {f} c_R: {g} after {prev}");
        assert!(g < 1.0 - f, "g above 1 − v/c_R at {f} c_R: {g}");
        prev = g;
    }
    for (f, below) in [(0.2, 0.035), (0.5, 0.102), (0.8, 0.234)] {
        let g = freund_g_exact(f * c_r, c_l, c_s, c_r);
        let gap = 1.0 - g / (1.0 - f);
        eprintln!("g({f} c_R) = {g:.4}: {:.1} % below 1 − v/c_R", 100.0 * gap);
        assert!((gap - below).abs() < 0.002, "{f} c_R: {gap}");
    }
    let (a, b, c) = (1.0 / c_l, 1.0 / c_s, 1.0 / c_r);
    for f in [-0.99, -0.6, 0.0, 0.4, 0.99] {
        let z = f * a;
        let r = (b * b - 2.0 * z * z).powi(2)
            + 4.0 * z * z * (a * a - z * z).sqrt() * (b * b - z * z).sqrt();
        let fact = 2.0
            * (b * b - a * a)
            * (c * c - z * z)
            * rayleigh_s_plus(z, c_l, c_s)
            * rayleigh_s_plus(-z, c_l, c_s);
        assert!((fact / r - 1.0).abs() < 1e-9, "ζ = {f}/c_L: {fact} vs {r}");
    }
}

/// Issue 34's initiation clause: the first advance within 0.5 µs of t_f, where the exact
/// G*(t) of the stationary crack reaches Γ.
fn assert_starts_at_t_f(r: &FreundGrowthRun) {
    assert!(
        (r.initiation - r.initiation_exact).abs() < 0.5e-6,
        "initiation {} vs t_f {}",
        r.initiation,
        r.initiation_exact
    );
}

/// Freund's step wave on a crack growing at constant Γ, the exact reference reaching
/// 0.85 c_R at the end of the window, at 0.5 mm cells under `reg`: the measured initiation
/// within 0.5 µs of t_f (G*(t_f) = Γ) and the mean speed over the last third of [t_f, window]
/// within 7 % of the exact-g reference's.
fn freund_fastest(reg: &Regularisation) {
    let f = freund_growth(&Settings::at(0.0005), 0.85, reg).unwrap();
    let r = run_freund_growth(&f, config()).unwrap();
    let err = r.mean_speed / r.mean_speed_exact - 1.0;
    eprintln!(
        "freund growth 0.85 c_R, 0.5 mm, {}: Γ {:.3} J/m², window {:.2} µs; initiation {:.2} µs \
         vs t_f {:.2}; mean speed over [{:.2}, {:.2}] µs {:.0} m/s vs exact g {:.0} ({:+.1} %), \
         1 − v/c_R {:.0}; advance {:.2} mm vs {:.2} / {:.2}; J1/(gG*) {:.3}, J1/Γ {:.3}; above Γ \
         {:.3e} of {:.3e} J/m",
        reg.label(),
        f.gamma,
        1e6 * f.window,
        1e6 * r.initiation,
        1e6 * r.initiation_exact,
        1e6 * r.interval[0],
        1e6 * r.interval[1],
        r.mean_speed,
        r.mean_speed_exact,
        100.0 * err,
        r.mean_speed_linear,
        1e3 * r.final_advance[0],
        1e3 * r.final_advance[1],
        1e3 * r.final_advance[2],
        r.j1_over_g_gstar,
        r.j1_over_gamma,
        r.above_toughness[0],
        r.above_toughness[1],
    );
    assert_starts_at_t_f(&r);
    assert!(
        err.abs() < 0.07,
        "mean speed {} vs {}",
        r.mean_speed,
        r.mean_speed_exact
    );
}

/// Freund's step wave at the three toughnesses (the exact reference reaching 0.3, 0.6 and
/// 0.85 c_R at the end of the window), 0.5 mm cells, the solver's defaults: the crack starts
/// within 0.5 µs of t_f, where the exact G*(t) of the stationary crack reaches Γ. What is
/// tested is the stationary J under a transient (the wave crossing the ring) and the law's
/// start on its unfiltered J (89d05f5; before, the filter delayed the slow case by 1.6 µs).
/// Measured at b80f3c3: 10.98 / 6.08 / 2.65 µs against 10.66 / 6.16 / 2.37.
#[test]
fn freund_growth_starts_at_t_f_at_three_toughnesses() {
    for target in [0.3, 0.6, 0.85] {
        let f = freund_growth(&Settings::at(0.0005), target, &Regularisation::default()).unwrap();
        let r = run_freund_growth(&f, config()).unwrap();
        eprintln!(
            "freund growth {target} c_R, 0.5 mm, defaults: Γ {:.3} J/m², initiation {:.2} µs vs t_f {:.2}",
            f.gamma,
            1e6 * r.initiation,
            1e6 * r.initiation_exact
        );
        assert_starts_at_t_f(&r);
    }
}

/// [`freund_fastest`] under the solver's default regularisation.
#[test]
#[ignore = "issue 34: initiation 2.65 µs vs t_f 2.37 (passes), last-third speed 1082 m/s vs exact g 969 (+11.6 %), J1/(gG*) 2.31; at 56306de initiation 4.02 µs, +12.3 %"]
fn freund_growth_fastest_case_follows_the_exact_reference() {
    freund_fastest(&Regularisation::default());
}

/// [`freund_fastest`] with the regularisation held at J ring 3 mm, zone 1 mm, filter 1.2 µs.
#[test]
#[ignore = "issue 34: initiation 2.65 µs vs t_f 2.37 (passes), last-third speed 1107 m/s vs exact g 969 (+14.2 %), J1/(gG*) 3.17; at 56306de initiation 3.82 µs, +14.6 %"]
fn freund_growth_fastest_case_with_fixed_regularisation() {
    freund_fastest(&physical());
}

/// The strip with fixed grips, Γ(v) = G_∞(1 + (v − v*)/c_R), v* = 0.6 c_R, at 0.5 mm cells with
/// the regularisation held at J ring 3 mm, zone 1 mm, filter 1.2 µs (the default ring, 1/16 of
/// the 20.5 mm strip height, spans under 3 cells at 0.5 mm and validation refuses it): the
/// steady speed (slope of the advance over the last third of the run) within 7 % of v*.
#[test]
#[ignore = "issue 34: steady speed 572 m/s vs v* 703 (-18.7 %); at 56306de 528 m/s (-24.9 %), the law's speed there 582 ± 128 m/s"]
fn strip_runs_at_the_speed_where_toughness_meets_g_infinity() {
    let st = strip_fixed_grips(&Settings::at(0.0005), 0.6, &physical()).unwrap();
    let r = run_strip(&st, config()).unwrap();
    let err = r.steady_speed / st.v_star - 1.0;
    eprintln!(
        "strip 0.6 c_R, 0.5 mm: G_inf {:.1} J/m²; initiation {:.1} µs; steady speed over \
         [{:.1}, {:.1}] µs {:.0} m/s vs v* {:.0} ({:+.1} %); J1/G_inf {:.3}, J1/Γ(v) {:.3}, \
         {:.1} % of running samples J1 < 0; above Γ {:.3e} of {:.3e} J/m",
        st.g_inf,
        1e6 * r.initiation,
        1e6 * r.interval[0],
        1e6 * r.interval[1],
        r.steady_speed,
        st.v_star,
        100.0 * err,
        r.j1_over_g_inf,
        r.j1_over_gamma,
        100.0 * r.negative_j1,
        r.above_toughness[0],
        r.above_toughness[1],
    );
    assert!(
        err.abs() < 0.07,
        "steady speed {} vs {}",
        r.steady_speed,
        st.v_star
    );
}

/// J1/(g(v)·G*(t)) over the second half of the window of Freund's step wave with the tip
/// driven at a prescribed speed and its zone taking LEFM's flux (`run_constant_speed`,
/// `run_exact_history`): 1 where the grid hands a tip of known motion LEFM's energy flux. No
/// equation of motion, no filter: the running tip's driving force alone.
fn flux_ratio(run: Result<ConstantSpeedRun, VerifyError>, label: &str) -> f64 {
    let r = run.unwrap();
    eprintln!(
        "{label}: J1/(gG*) {:.3} over the second half (quarters {:.3} {:.3} {:.3} {:.3}), mean speed {:.3} c_R",
        r.ratio,
        r.ratio_quarters[0],
        r.ratio_quarters[1],
        r.ratio_quarters[2],
        r.ratio_quarters[3],
        r.mean_speed / r.c_r
    );
    r.ratio
}

/// A tip that barely moves (0.02 c_R) receives the stationary crack's G*(t) = G*₁·t within
/// 3 % (measured 0.984 at 0.5 mm, 1.000 at 0.25 mm): the prescribed-motion runner and the
/// reference agree where the running-tip terms of J vanish, so the running cases below
/// measure the running tip, not the harness.
#[test]
fn a_tip_held_near_rest_receives_the_stationary_flux() {
    let st = Settings::at(0.0005);
    let ratio = flux_ratio(
        run_constant_speed(&st, 0.02, &Regularisation::default(), config()),
        "0.02 c_R",
    );
    assert!((ratio - 1.0).abs() < 0.03, "J1/(gG*) {ratio}");
}

/// Tips driven at 0.3, 0.6 and 0.85 c_R receive g(v)·G* within 7 % at 0.5 mm.
#[test]
#[ignore = "issue 34: J1/(gG*) 1.07 / 1.19 / 1.21 at 0.5 mm (1.05 / 1.19 / 1.05 at 0.25 mm; 1.16-1.21 at 0.6 c_R whatever the ring and zone): docs/running-tip.md"]
fn tips_at_constant_speed_receive_freunds_flux() {
    receive_freunds_flux(run_constant_speed, "constant speed");
}

/// Tips driven along the exact equation-of-motion histories of the three toughnesses receive
/// g(v)·G* within 7 % at 0.5 mm.
#[test]
#[ignore = "issue 34: J1/(gG*) 1.09 / 1.29 / 1.43 at 0.5 mm, 1.03 / 1.25 / 1.21 at 0.25 mm (docs/running-tip.md)"]
fn tips_on_the_exact_histories_receive_freunds_flux() {
    receive_freunds_flux(run_exact_history, "exact history to");
}

/// The prescribed-motion runner `run` at 0.3, 0.6 and 0.85 c_R, 0.5 mm: J1/(gG*) within 7 %.
fn receive_freunds_flux(
    run: fn(&Settings, f64, &Regularisation, SolverConfig) -> Result<ConstantSpeedRun, VerifyError>,
    label: &str,
) {
    let st = Settings::at(0.0005);
    for v in [0.3, 0.6, 0.85] {
        let ratio = flux_ratio(
            run(&st, v, &Regularisation::default(), config()),
            &format!("{label} {v} c_R"),
        );
        assert!(
            (ratio - 1.0).abs() < 0.07,
            "{label} {v} c_R: J1/(gG*) {ratio}"
        );
    }
}
