//! `fracture study growth`: crack growth against known transients (issue 34). Freund's step
//! wave on a crack growing at constant Γ (three toughnesses, the exact reference reaching
//! 0.3, 0.6 and 0.85 c_R at the end of the valid window) and the strip with fixed grips
//! (v* = 0.3, 0.6, 0.8 c_R), at 0.5 and 0.25 mm cells (0.125 mm for the fastest Freund case
//! with `--min-cell 1.25e-4`), each under the solver's default regularisation and under one
//! held fixed in metres and seconds (`--j-radius`, `--zone`, `--filter-time`). Writes
//! `growth.md` with its tables and, in `growth/`, the SVG figures of advance and speed against
//! time with both references (exact g = A_I k² and 1 − v/c_R).

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use fracture_solver::SolverConfig;
use fracture_verify::{
    FreundGrowthRun, FreundGrowthScene, GrowthSample, Regularisation, Settings, StripRun,
    StripScene, freund_g_exact, freund_growth, freund_growth_window, run_freund_growth, run_strip,
    strip_fixed_grips,
};

use super::StudyArgs;
use crate::report::svg::{
    Frame, PALETTE, Scale, Stroke, Svg, TickStyle, legend_entry, text, vertical_text,
};
use crate::report::{markdown_table, write_file};

/// The time axis of the Freund figures.
const ARRIVAL: &str = "time after the wave's arrival (µs)";
/// Target speeds (over c_R) of the Freund cases at the end of the window.
const FREUND_TARGETS: [f64; 3] = [0.3, 0.6, 0.85];
/// Steady speeds (over c_R) of the strips.
const STRIP_TARGETS: [f64; 3] = [0.3, 0.6, 0.8];
/// Cell sizes of every case (m).
const CELLS: [f64; 2] = [5.0e-4, 2.5e-4];
/// The extra cell size of the fastest Freund case (m), run when `--min-cell` allows it.
const FINE_CELL: f64 = 1.25e-4;
/// The Freund cases and cell size (m) of the parameter table: each regularisation parameter
/// of the fixed set halved and doubled (the J radius by 2/3 and 3/2) with the others held.
const SENS_TARGETS: [f64; 2] = [0.6, 0.85];
const SENS_CELL: f64 = 2.5e-4;

/// The variants of the parameter table around the fixed regularisation (r, zone, τ): a
/// label and the set.
fn sensitivity(r: f64, zone: f64, tau: f64) -> Vec<(String, Regularisation)> {
    vec![
        ("as fixed".into(), Regularisation::physical(r, zone, tau)),
        (
            format!("r × 2/3 ({:.1} mm)", 2.0e3 * r / 3.0),
            Regularisation::physical(2.0 * r / 3.0, zone, tau),
        ),
        (
            format!("r × 3/2 ({:.1} mm)", 1.5e3 * r),
            Regularisation::physical(1.5 * r, zone, tau),
        ),
        (
            format!("zone × 1/2 ({:.2} mm)", 0.5e3 * zone),
            Regularisation::physical(r, 0.5 * zone, tau),
        ),
        (
            format!("zone × 2 ({:.2} mm)", 2.0e3 * zone),
            Regularisation::physical(r, 2.0 * zone, tau),
        ),
        (
            format!("τ × 1/2 ({:.2} µs)", 0.5e6 * tau),
            Regularisation::physical(r, zone, 0.5 * tau),
        ),
        (
            format!("τ × 2 ({:.2} µs)", 2.0e6 * tau),
            Regularisation::physical(r, zone, 2.0 * tau),
        ),
    ]
}

/// Which problem a run is.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Case {
    Freund(f64),
    Strip(f64),
}

impl Case {
    fn name(self) -> String {
        match self {
            Case::Freund(r) => format!("freund-{r}"),
            Case::Strip(r) => format!("strip-{r}"),
        }
    }
}

/// One run to make.
struct Job {
    case: Case,
    h: f64,
    reg: Regularisation,
    /// Rough cost (particles × steps), for ordering.
    cost: f64,
}

impl Job {
    fn key(&self) -> String {
        key(self.case, self.h, &self.reg)
    }
    fn label(&self) -> String {
        format!(
            "{} h {} mm, {}",
            self.case.name(),
            1e3 * self.h,
            self.reg.label()
        )
    }
}

fn key(case: Case, h: f64, reg: &Regularisation) -> String {
    format!("{}|{h}|{}", case.name(), reg.label())
}

/// What one run gave.
enum Outcome {
    Freund(Box<FreundGrowthScene>, FreundGrowthRun),
    Strip(Box<StripScene>, StripRun),
    Failed(String),
}

fn run_job(job: &Job, config: SolverConfig) -> Outcome {
    let s = Settings::at(job.h);
    match job.case {
        Case::Freund(r) => match freund_growth(&s, r, &job.reg) {
            Ok(f) => match run_freund_growth(&f, config) {
                Ok(m) => Outcome::Freund(Box::new(f), m),
                Err(e) => Outcome::Failed(one_line(&e.to_string())),
            },
            Err(e) => Outcome::Failed(one_line(&e.to_string())),
        },
        Case::Strip(r) => match strip_fixed_grips(&s, r, &job.reg) {
            Ok(st) => match run_strip(&st, config) {
                Ok(m) => Outcome::Strip(Box::new(st), m),
                Err(e) => Outcome::Failed(one_line(&e.to_string())),
            },
            Err(e) => Outcome::Failed(one_line(&e.to_string())),
        },
    }
}

/// A table row for a run that failed: its labels, the error, and empty cells to `width`.
fn failed_row(mut labels: Vec<String>, e: &str, width: usize) -> Vec<String> {
    labels.push(format!("failed: {e}"));
    labels.resize(width, String::new());
    labels
}

/// A message on one line, runs of white space as one space (a table cell).
fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The study: every run, then the page.
pub(super) fn run(a: &StudyArgs) -> anyhow::Result<()> {
    for (name, v) in [
        ("--j-radius", a.j_radius),
        ("--zone", a.zone),
        ("--filter-time", a.filter_time),
        ("--min-cell", a.min_cell),
    ] {
        anyhow::ensure!(
            v.is_finite() && v > 0.0,
            "{name} must be a positive number (SI units), got {v}"
        );
    }
    let started = Instant::now();
    let fixed = Regularisation::physical(a.j_radius, a.zone, a.filter_time);
    let regs = [Regularisation::default(), fixed];
    let mut jobs = Vec::new();
    for reg in regs {
        for r in FREUND_TARGETS {
            let mut cells = CELLS.to_vec();
            if r == 0.85 && a.min_cell <= FINE_CELL * 1.0001 {
                cells.push(FINE_CELL);
            }
            for h in cells {
                // 60 × 70 mm, ≈ 32 µs.
                let cost = 0.060 * 0.070 * 4.0 / (h * h) * 3.2e-5 / (0.5 * h / 2551.0);
                jobs.push(Job {
                    case: Case::Freund(r),
                    h,
                    reg,
                    cost,
                });
            }
        }
        for r in STRIP_TARGETS {
            for h in CELLS {
                // 150 × 20 mm, 150 µs.
                let cost = 0.150 * 0.020 * 4.0 / (h * h) * 1.5e-4 / (0.5 * h / 2551.0);
                jobs.push(Job {
                    case: Case::Strip(r),
                    h,
                    reg,
                    cost,
                });
            }
        }
    }
    if a.min_cell <= SENS_CELL * 1.0001 {
        for r in SENS_TARGETS {
            // The first variant is the fixed set, already run.
            for (_, reg) in sensitivity(a.j_radius, a.zone, a.filter_time)
                .into_iter()
                .skip(1)
            {
                let h = SENS_CELL;
                let cost = 0.060 * 0.070 * 4.0 / (h * h) * 3.2e-5 / (0.5 * h / 2551.0);
                jobs.push(Job {
                    case: Case::Freund(r),
                    h,
                    reg,
                    cost,
                });
            }
        }
    }
    jobs.sort_by(|x, y| y.cost.total_cmp(&x.cost));
    let total = jobs.len();
    let workers = a.jobs.resolve().clamp(1, total.max(1));
    println!(
        "growth: {total} runs, {workers} at a time, {} solver thread(s) each",
        a.threads
    );
    let config = SolverConfig { threads: a.threads };
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let results: Mutex<HashMap<String, Outcome>> = Mutex::new(HashMap::new());
    std::thread::scope(|s| {
        for _ in 0..workers {
            s.spawn(|| {
                while let Some(job) = jobs.get(next.fetch_add(1, Ordering::Relaxed)) {
                    let t0 = Instant::now();
                    let out = run_job(job, config);
                    let n = done.fetch_add(1, Ordering::Relaxed) + 1;
                    let what = match &out {
                        Outcome::Freund(_, m) => format!(
                            "mean speed {:.0} m/s vs {:.0} (exact g)",
                            m.mean_speed, m.mean_speed_exact
                        ),
                        Outcome::Strip(st, m) => format!(
                            "steady speed {:.0} m/s vs v* {:.0}",
                            m.steady_speed, st.v_star
                        ),
                        Outcome::Failed(e) => format!("failed: {e}"),
                    };
                    println!(
                        "[growth {n}/{total}] {}: {what}, {:.1} s",
                        job.label(),
                        t0.elapsed().as_secs_f64()
                    );
                    if let Ok(mut r) = results.lock() {
                        r.insert(job.key(), out);
                    }
                }
            });
        }
    });
    let results = results
        .into_inner()
        .map_err(|_| anyhow::anyhow!("a run panicked"))?;
    let page = Page {
        a,
        regs,
        results: &results,
        figs: &a.out.join("growth"),
        wall: started.elapsed().as_secs_f64(),
        runs: total,
        workers,
    };
    let path = page.write()?;
    println!("wrote {}", path.display());
    Ok(())
}

/// The page and what it is made from.
struct Page<'a> {
    a: &'a StudyArgs,
    regs: [Regularisation; 2],
    results: &'a HashMap<String, Outcome>,
    figs: &'a Path,
    wall: f64,
    runs: usize,
    workers: usize,
}

/// Percentage with a sign, or "–".
fn pct(x: f64) -> String {
    if x.is_finite() {
        format!("{:+.1} %", 100.0 * x)
    } else {
        "–".into()
    }
}

/// A number to `d` decimals, or "–".
fn num(x: f64, d: usize) -> String {
    if x.is_finite() {
        format!("{x:.d$}")
    } else {
        "–".into()
    }
}

/// The commit the study ran on, and whether the solver or scene code had uncommitted
/// changes (then the "defaults" columns are those of the working tree).
fn source_state() -> String {
    let git = |args: &[&str]| {
        std::process::Command::new("git")
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    match git(&["rev-parse", "--short", "HEAD"]) {
        Some(head) => {
            let dirty = git(&["status", "--porcelain", "--", "solver", "api", "verify"])
                .is_some_and(|s| !s.is_empty());
            if dirty {
                format!("commit {head} with uncommitted changes in solver/, api/ or verify/")
            } else {
                format!("commit {head}")
            }
        }
        None => "an unknown commit".into(),
    }
}

impl Page<'_> {
    fn get(&self, case: Case, h: f64, reg: &Regularisation) -> Option<&Outcome> {
        self.results.get(&key(case, h, reg))
    }

    fn freund(&self, case: Case, h: f64, reg: &Regularisation) -> Option<&FreundGrowthRun> {
        match self.get(case, h, reg) {
            Some(Outcome::Freund(_, m)) => Some(m),
            _ => None,
        }
    }

    fn strip(&self, case: Case, h: f64, reg: &Regularisation) -> Option<&StripRun> {
        match self.get(case, h, reg) {
            Some(Outcome::Strip(_, m)) => Some(m),
            _ => None,
        }
    }

    fn command(&self) -> String {
        let a = self.a;
        format!(
            "cargo run --release -- study growth --min-cell {} --j-radius {} --zone {} --filter-time {} \
             --jobs {} --threads {} --out {}",
            a.min_cell,
            a.j_radius,
            a.zone,
            a.filter_time,
            a.jobs,
            a.threads,
            a.out.display()
        )
    }

    fn write(&self) -> anyhow::Result<std::path::PathBuf> {
        let mut md = String::new();
        let _ = writeln!(md, "# Crack growth against known transients\n");
        let _ = writeln!(
            md,
            "Regenerate with `{}` ({} runs, {} at a time, {:.0} s on \
             this machine; {}).\n",
            self.command(),
            self.runs,
            self.workers,
            self.wall,
            source_state()
        );
        md.push_str(INTRO);
        self.g_table(&mut md);
        self.freund_tables(&mut md)?;
        self.sensitivity_table(&mut md);
        self.strip_tables(&mut md)?;
        md.push_str(MODEL_NOTE);
        let path = self.a.out.join("growth.md");
        write_file(&self.a.out, "growth.md", md)?;
        Ok(path)
    }

    /// Exact g against 1 − v/c_R.
    fn g_table(&self, md: &mut String) {
        let sp = fracture_api::scene::WaveSpeeds::new(
            5.2e9,
            0.34,
            1230.0,
            fracture_api::scene::Analysis::PlaneStrain,
        );
        let mut rows = Vec::new();
        for f in [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.85, 0.9, 0.95] {
            let g = freund_g_exact(f * sp.c_r, sp.c_l, sp.c_s, sp.c_r);
            rows.push(vec![
                format!("{f}"),
                format!("{g:.4}"),
                format!("{:.4}", 1.0 - f),
                pct(g / (1.0 - f) - 1.0),
            ]);
        }
        let _ = writeln!(
            md,
            "## Freund's g(v)\n\nExact g(v) = A_I(v)·k(v)² for Homalite-100 in plane strain \
             (c_L {:.0}, c_S {:.0}, c_R {:.1} m/s; `fracture_verify::freund_g_exact`), against \
             the solver's 1 − v/c_R:\n",
            sp.c_l, sp.c_s, sp.c_r
        );
        md.push_str(&markdown_table(
            &["v/c_R", "g exact", "1 − v/c_R", "exact vs 1 − v/c_R"],
            &rows,
        ));
        md.push('\n');
    }

    /// How the fastest and middle Freund cases depend on each parameter of the fixed
    /// regularisation at [`SENS_CELL`]: each halved and doubled (the radius by 2/3 and 3/2)
    /// with the others held.
    fn sensitivity_table(&self, md: &mut String) {
        let a = self.a;
        let variants = sensitivity(a.j_radius, a.zone, a.filter_time);
        let mut rows = Vec::new();
        for r in SENS_TARGETS {
            let base = self
                .freund(Case::Freund(r), SENS_CELL, &variants[0].1)
                .map(|m| m.mean_speed);
            for (label, reg) in &variants {
                let row = match self.get(Case::Freund(r), SENS_CELL, reg) {
                    Some(Outcome::Freund(_, m)) => vec![
                        format!("{r}"),
                        label.clone(),
                        format!("{:.2}", 1e6 * m.initiation),
                        format!("{:.0}", m.mean_speed),
                        pct(m.mean_speed / m.mean_speed_exact - 1.0),
                        base.map_or("–".into(), |b| pct(m.mean_speed / b - 1.0)),
                        num(m.j1_over_g_gstar, 2),
                    ],
                    Some(Outcome::Failed(e)) => {
                        failed_row(vec![format!("{r}"), label.clone()], e, 7)
                    }
                    _ => continue,
                };
                rows.push(row);
            }
        }
        if rows.is_empty() {
            return;
        }
        let _ = writeln!(
            md,
            "\n## How the answer depends on each parameter\n\n\
             The 0.6 and 0.85 c_R Freund cases at {} mm, each parameter of the fixed set (r {} mm, zone {} mm, \
             τ {} µs) changed with the others held: the J radius by 2/3 and 3/2, the zone and the filter time \
             halved and doubled. Speed over the last third of the window as above; \"vs fixed\" against the fixed \
             set's run.\n",
            1e3 * SENS_CELL,
            1e3 * a.j_radius,
            1e3 * a.zone,
            1e6 * a.filter_time
        );
        md.push_str(&markdown_table(
            &[
                "case",
                "regularisation",
                "initiation (µs)",
                "speed, last third (m/s)",
                "vs exact g",
                "vs fixed",
                "J1/(g G*)",
            ],
            &rows,
        ));
    }

    fn freund_tables(&self, md: &mut String) -> anyhow::Result<()> {
        let _ = writeln!(md, "## Freund's step wave on a growing crack\n");
        md.push_str(FREUND_SETUP);
        // The cases: Γ, t_f, window (any run's scene: they do not depend on h or the law).
        let mut rows = Vec::new();
        for r in FREUND_TARGETS {
            let scene = self.results.values().find_map(|o| match o {
                Outcome::Freund(f, _) if f.target == r => Some(f),
                _ => None,
            });
            if let Some(f) = scene {
                let c_r = f.speeds.c_r;
                let w = f.window;
                let lin_end = f.reference.speed_linear(w) / c_r;
                let window_lin =
                    freund_growth_window(f.speeds.c_l, [0.060, 0.020, 0.035, 0.035], &|t| {
                        f.reference.advance_linear(t)
                    });
                rows.push(vec![
                    format!("{r}"),
                    format!("{:.4}", f.gamma),
                    format!("{:.2}", 1e6 * f.reference.t_f),
                    format!("{:.2}", 1e6 * w),
                    format!("{:.2}", 1e3 * f.reference.advance(w)),
                    format!("{lin_end:.3}"),
                    format!("{:.2}", 1e3 * f.reference.advance_linear(w)),
                    format!("{:.2}", 1e6 * window_lin),
                ]);
            }
        }
        md.push_str(&markdown_table(
            &[
                "v(end)/c_R, exact g",
                "Γ (J/m²)",
                "t_f (µs)",
                "window (µs)",
                "l(end) exact g (mm)",
                "v(end)/c_R, 1 − v/c_R",
                "l(end), 1 − v/c_R (mm)",
                "window with 1 − v/c_R's l (µs)",
            ],
            &rows,
        ));
        md.push_str(FREUND_COLUMNS);
        let mut rows = Vec::new();
        for r in FREUND_TARGETS {
            for reg in &self.regs {
                let mut cells = CELLS.to_vec();
                cells.push(FINE_CELL);
                for h in cells {
                    let Some(o) = self.get(Case::Freund(r), h, reg) else {
                        continue;
                    };
                    let (f, m) = match o {
                        Outcome::Freund(f, m) => (f, m),
                        Outcome::Failed(e) => {
                            rows.push(failed_row(
                                vec![format!("{r}"), reg.label(), format!("{}", 1e3 * h)],
                                e,
                                14,
                            ));
                            continue;
                        }
                        Outcome::Strip(..) => continue,
                    };
                    // 0.25 mm against 0.5 mm (and 0.125 against 0.25) of the same case and law.
                    let coarser = self
                        .freund(Case::Freund(r), 2.0 * h, reg)
                        .map_or(f64::NAN, |c| m.mean_speed / c.mean_speed - 1.0);
                    let [above, required] = m.above_toughness;
                    rows.push(vec![
                        format!("{r}"),
                        reg.label(),
                        format!("{}", 1e3 * h),
                        format!(
                            "{} / {:.2}",
                            num(1e6 * m.initiation, 2),
                            1e6 * m.initiation_exact
                        ),
                        format!("{:.0}", m.mean_speed),
                        format!("{:.0}", m.mean_speed_exact),
                        pct(m.mean_speed / m.mean_speed_exact - 1.0),
                        format!("{:.0}", m.mean_speed_linear),
                        pct(m.mean_speed / m.mean_speed_linear - 1.0),
                        format!(
                            "{:.2} / {:.2}",
                            1e3 * m.final_advance[0],
                            1e3 * m.final_advance[1]
                        ),
                        format!(
                            "{:.0} / {:.0}",
                            m.samples.last().map_or(f64::NAN, |s| s.speed),
                            f.reference.speed(f.window)
                        ),
                        pct(coarser),
                        format!(
                            "{} / {}",
                            num(m.j1_over_g_gstar, 2),
                            num(m.j1_over_gamma, 2)
                        ),
                        if required > 0.0 {
                            format!("{:.2e} ({:.0} %)", above, 100.0 * above / required)
                        } else {
                            format!("{above:.2e}")
                        },
                    ]);
                }
            }
        }
        md.push_str(&markdown_table(
            &[
                "case",
                "regularisation",
                "h (mm)",
                "initiation / t_f (µs)",
                "speed, last third (m/s)",
                "exact g",
                "vs exact g",
                "1 − v/c_R",
                "vs 1 − v/c_R",
                "l(end) / exact (mm)",
                "v(end) / exact (m/s)",
                "vs 2h",
                "J1/(g G*) / J1/Γ",
                "above Γ (J/m)",
            ],
            &rows,
        ));
        md.push('\n');
        for r in FREUND_TARGETS {
            self.freund_figures(md, r)?;
        }
        Ok(())
    }

    /// The two figures of a Freund case: advance and speed against time, every run with both
    /// references.
    fn freund_figures(&self, md: &mut String, r: f64) -> anyhow::Result<()> {
        let Some(f) = self.results.values().find_map(|o| match o {
            Outcome::Freund(f, _) if f.target == r => Some(f),
            _ => None,
        }) else {
            return Ok(());
        };
        let mut runs: Vec<(String, &[GrowthSample])> = Vec::new();
        for reg in &self.regs {
            for h in [CELLS[0], CELLS[1], FINE_CELL] {
                if let Some(m) = self.freund(Case::Freund(r), h, reg) {
                    runs.push((legend(h, reg), &m.samples));
                }
            }
        }
        let w = f.window;
        let n = 200;
        let times: Vec<f64> = (0..=n).map(|i| w * i as f64 / n as f64).collect();
        let refs = |fun: &dyn Fn(f64) -> f64, scale: f64| -> Vec<[f64; 2]> {
            times.iter().map(|&t| [1e6 * t, scale * fun(t)]).collect()
        };
        let name = format!("freund-{r}");
        let title = format!(
            "Freund step wave, Γ = {:.3} J/m² (exact g: {r} c_R at the end of the window)",
            f.gamma
        );
        let adv_refs = [
            ("exact g", refs(&|t| f.reference.advance(t), 1e3)),
            ("1 − v/c_R", refs(&|t| f.reference.advance_linear(t), 1e3)),
        ];
        let svg = plot(
            &format!("{title}: advance"),
            ARRIVAL,
            "crack advance l (mm)",
            &runs,
            &|s| 1e3 * s.advance,
            &adv_refs,
            1e6 * w,
        );
        write_file(self.figs, &format!("{name}-advance.svg"), svg)?;
        let v_refs = [
            ("exact g", refs(&|t| f.reference.speed(t), 1.0)),
            ("1 − v/c_R", refs(&|t| f.reference.speed_linear(t), 1.0)),
        ];
        let svg = plot(
            &format!("{title}: speed"),
            ARRIVAL,
            "tip speed v (m/s, the law's)",
            &runs,
            &|s| s.speed,
            &v_refs,
            1e6 * w,
        );
        write_file(self.figs, &format!("{name}-speed.svg"), svg)?;
        let _ = writeln!(
            md,
            "![advance, {r}](growth/{name}-advance.svg)\n![speed, {r}](growth/{name}-speed.svg)\n\n\
             *Case {r}: advance and the law's speed against time, with exact g (black dashed) and \
             1 − v/c_R (grey dashed); \"fixed\" is {}.*\n",
            self.regs[1].label()
        );
        Ok(())
    }

    fn strip_tables(&self, md: &mut String) -> anyhow::Result<()> {
        let _ = writeln!(md, "## The strip with fixed grips\n");
        md.push_str(STRIP_SETUP);
        let mut rows = Vec::new();
        for r in STRIP_TARGETS {
            for reg in &self.regs {
                for h in CELLS {
                    let Some(o) = self.get(Case::Strip(r), h, reg) else {
                        continue;
                    };
                    let (st, m) = match o {
                        Outcome::Strip(st, m) => (st, m),
                        Outcome::Failed(e) => {
                            rows.push(failed_row(
                                vec![format!("{r}"), reg.label(), format!("{}", 1e3 * h)],
                                e,
                                12,
                            ));
                            continue;
                        }
                        Outcome::Freund(..) => continue,
                    };
                    let coarser = self
                        .strip(Case::Strip(r), 2.0 * h, reg)
                        .map_or(f64::NAN, |c| m.steady_speed / c.steady_speed - 1.0);
                    let [above, required] = m.above_toughness;
                    rows.push(vec![
                        format!("{r}"),
                        reg.label(),
                        format!("{}", 1e3 * h),
                        format!("{:.1}", 1e6 * m.initiation),
                        format!("{:.0}–{:.0}", 1e6 * m.interval[0], 1e6 * m.interval[1]),
                        format!("{:.0}", m.steady_speed),
                        spread(&m.samples, m.interval),
                        format!("{:.0}", st.v_star),
                        pct(m.steady_speed / st.v_star - 1.0),
                        pct(coarser),
                        format!(
                            "{} / {} / {:.1} %",
                            num(m.j1_over_g_inf, 2),
                            num(m.j1_over_gamma, 2),
                            100.0 * m.negative_j1
                        ),
                        if required > 0.0 {
                            format!("{:.2e} ({:.0} %)", above, 100.0 * above / required)
                        } else {
                            format!("{above:.2e}")
                        },
                    ]);
                }
            }
        }
        md.push_str(&markdown_table(
            &[
                "v*/c_R",
                "regularisation",
                "h (mm)",
                "initiation (µs)",
                "steady interval (µs)",
                "steady speed (m/s)",
                "law's speed, mean ± sd (m/s)",
                "v* (m/s)",
                "vs v*",
                "vs 2h",
                "J1/G_∞ / J1/Γ(v) / J1 < 0",
                "above Γ (J/m)",
            ],
            &rows,
        ));
        md.push('\n');
        for r in STRIP_TARGETS {
            let mut runs: Vec<(String, &[GrowthSample])> = Vec::new();
            let mut v_star = f64::NAN;
            for reg in &self.regs {
                for h in CELLS {
                    if let Some(Outcome::Strip(st, m)) = self.get(Case::Strip(r), h, reg) {
                        v_star = st.v_star;
                        runs.push((legend(h, reg), &m.samples));
                    }
                }
            }
            if runs.is_empty() {
                continue;
            }
            let line = vec![[0.0, v_star], [150.0, v_star]];
            let svg = plot(
                &format!("Strip with fixed grips, v* = {r} c_R = {v_star:.0} m/s: speed"),
                "time (µs)",
                "tip speed v (m/s, the law's)",
                &runs,
                &|s| s.speed,
                &[("v*", line)],
                150.0,
            );
            let name = format!("strip-{r}-speed.svg");
            write_file(self.figs, &name, svg)?;
            let _ = writeln!(
                md,
                "![strip {r}](growth/{name})\n\n*Strip, v* = {r} c_R: the law's speed against \
                 time; \"fixed\" is {}.*\n",
                self.regs[1].label()
            );
        }
        Ok(())
    }
}

/// Mean ± standard deviation of the law's speed over samples in [t0, t1]: how steady the
/// "steady" interval is.
fn spread(samples: &[GrowthSample], [t0, t1]: [f64; 2]) -> String {
    let v: Vec<f64> = samples
        .iter()
        .filter(|s| s.t >= t0 && s.t <= t1)
        .map(|s| s.speed)
        .collect();
    if v.is_empty() {
        return "–".into();
    }
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let sd = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n).sqrt();
    format!("{mean:.0} ± {sd:.0}")
}

/// The legend of a run: its cell size and "defaults" or "fixed" (the regularisation of the
/// tables).
fn legend(h: f64, reg: &Regularisation) -> String {
    let which = if reg.is_default() {
        "defaults"
    } else {
        "fixed"
    };
    format!("{} mm, {which}", 1e3 * h)
}

/// Values of a series against time (µs), thinned to at most 400 points.
fn series(samples: &[GrowthSample], value: &dyn Fn(&GrowthSample) -> f64) -> Vec<[f64; 2]> {
    let stride = samples.len().div_ceil(400).max(1);
    samples
        .iter()
        .step_by(stride)
        .map(|s| [1e6 * s.t, value(s)])
        .filter(|p| p[1].is_finite())
        .collect()
}

/// One figure: runs as solid lines, references dashed, the legend on the right.
fn plot(
    title: &str,
    x_label: &str,
    y_label: &str,
    runs: &[(String, &[GrowthSample])],
    value: &dyn Fn(&GrowthSample) -> f64,
    references: &[(&str, Vec<[f64; 2]>)],
    t_end_us: f64,
) -> String {
    const W: f64 = 760.0;
    const H: f64 = 420.0;
    const L: f64 = 64.0;
    const R: f64 = 210.0;
    const T: f64 = 36.0;
    const B: f64 = 48.0;
    let curves: Vec<(String, Vec<[f64; 2]>)> = runs
        .iter()
        .map(|(n, s)| (n.clone(), series(s, value)))
        .collect();
    let y_max = curves
        .iter()
        .flat_map(|c| c.1.iter())
        .chain(references.iter().flat_map(|r| r.1.iter()))
        .map(|p| p[1])
        .filter(|y| y.is_finite())
        .fold(0.0_f64, f64::max)
        .max(1e-9)
        * 1.08;
    let frame = Frame {
        left: L,
        top: T,
        width: W - L - R,
        height: H - T - B,
        x: Scale::linear(0.0, t_end_us).clamped(),
        y: Scale::linear(0.0, y_max).clamped(),
    };
    let mut svg = Svg::new(W, H, 12);
    svg.add(text(W / 2.0, 20.0, title).middle().size(12));
    svg.add(frame.axes("#333"));
    let mark = TickStyle::Mark {
        len: 5.0,
        colour: "#333",
    };
    frame.x_ticks(&mut svg, nice_step(t_end_us), mark, 18.0, |t| {
        format!("{t:.0}")
    });
    let ys = nice_step(y_max);
    frame.y_ticks(&mut svg, ys, mark, 8.0, |v| {
        if ys < 1.0 {
            format!("{v:.1}")
        } else {
            format!("{v:.0}")
        }
    });
    svg.add(text((L + W - R) / 2.0, H - 10.0, x_label).middle());
    svg.add(vertical_text(16.0, (T + H - B) / 2.0, y_label));
    let mut row = 0.0;
    for (i, (name, pts)) in references.iter().enumerate() {
        let stroke = Stroke::new(if i == 0 { "#000" } else { "#888" })
            .width(1.4)
            .dashed();
        if let Some(p) = frame.path(pts, stroke) {
            svg.add(p);
        }
        svg.add(legend_entry(
            W - R + 10.0,
            T + 14.0 + 18.0 * row,
            stroke,
            None,
            name,
        ));
        row += 1.0;
    }
    for (i, (name, pts)) in curves.iter().enumerate() {
        let c = PALETTE[i % PALETTE.len()];
        if let Some(p) = frame.path(pts, Stroke::new(c).width(1.4)) {
            svg.add(p);
        }
        svg.add(legend_entry(
            W - R + 10.0,
            T + 14.0 + 18.0 * row,
            Stroke::new(c).width(2.0),
            None,
            name,
        ));
        row += 1.0;
    }
    svg.finish()
}

/// A tick step of 1, 2 or 5 × 10ⁿ giving 4–10 ticks over [0, span].
fn nice_step(span: f64) -> f64 {
    let raw = span / 6.0;
    let mag = 10f64.powf(raw.log10().floor());
    let f = raw / mag;
    let m = if f < 1.5 {
        1.0
    } else if f < 3.5 {
        2.0
    } else if f < 7.5 {
        5.0
    } else {
        10.0
    };
    m * mag
}

const INTRO: &str = "\
What the equation of motion does against two transients whose answers are known without the \
solver (`reference-solutions.md`, \"Growth: direction, speed, energy\"): Freund's step wave on a \
crack growing at a constant toughness, where the static energy release rate G*(t) grows in \
proportion to time and the tip must satisfy g(v)·G*(t) = Γ, and the strip with fixed grips, \
where the steady speed v* solves Γ(v*) = G_∞. Every case runs at two cell sizes under the \
solver's default regularisation (J domain radius, process-zone length, filter time: whatever \
the solver chooses for the scene) and under one held fixed in metres and seconds, so that \
refining h refines only the discretisation (`algorithm.md`, pitfall 13). \
`fracture_verify::freund_growth`, `strip_fixed_grips` and their runners build and measure the \
scenes; `verify/tests/growth_transients.rs` holds the acceptance checks.\n\n";

const FREUND_SETUP: &str = "\
Homalite-100 (E = 5.2 GPa, ν = 0.34, ρ = 1230 kg/m³, plane strain), a strip 60 mm wide with \
roller sides, a 20 mm edge crack at mid-cell from the left roller, 35 mm of material above and \
below it, a step traction σ* = 1 MPa on the top edge and the bottom free; the crack grows along \
its line by the equation of motion at constant Γ. G*(t) = K*(t)²(1 − ν²)/E with \
K*(t) = 2σ*√(c_L t(1 − 2ν)/π)/(1 − ν), t after the wave reaches the crack plane, whatever the \
tip's position. Reference: initiation at t_f with G*(t_f) = Γ, then g(v)·G*(t) = Γ with the \
exact g (l by integrating v) or with g = 1 − v/c_R (v = c_R(1 − t_f/t), \
l = c_R[t − t_f − t_f ln(t/t_f)]). The window ends when the first scattered wave reaches the \
moving tip: the diffraction from the mirror tip across the mouth's roller (2a + l), before the \
far roller (2(W − a) − l) and the top and bottom edges (2 × 35 mm); Γ is chosen with the window \
so that the exact reference runs at 0.3, 0.6 and 0.85 c_R at its end:\n\n";

const FREUND_COLUMNS: &str = "\n\
Columns: initiation is the first step with advance > 0 against t_f; the speed is Δadvance/Δt \
over the last third of [t_f, window] against both references' Δl/Δt over the same interval; \
\"vs 2h\" compares that speed with the same case and regularisation at twice the cell size; \
J1/(g G*) is the median over the running steps of J1 at the tip over LEFM's energy flux into a \
tip at the law's speed (exact g), and J1/Γ the median of J1 over the toughness (the law's \
balance holds on its filtered J1, so this is 1 unless the filter lags); \"above Γ\" is the \
energy the tip took beyond Γ(v) at the law's speed wall, and its share of all it took.\n\n";

const STRIP_SETUP: &str = "\
The strip of `solver/tests/growth_law.rs`: 150 mm × (20 mm + h), a 30 mm edge crack along its \
mid-plane, the grips moved ±20 µm over 40 µs and then held, so G_∞ = Mδ²/b (M = ρc_L²) far \
ahead; toughness Γ(v) = G_∞(1 + (v − v*)/c_R). The run stops when the tip is 20 mm from the far \
end or at 150 µs; the steady speed is the least-squares slope of the advance over the last \
third of [initiation, stop] (not before the grips stop); J1 ratios are medians over the running \
steps in that interval.\n\n";

const MODEL_NOTE: &str = "\
## Which numbers rest on a model parameter\n\n\
The references (g(v), t_f, the windows, v(t), l(t), G_∞, v*) rest on none: they follow from \
the elastic constants, the load and Γ. Every measured number rests on the tip law's \
regularisation, which is a model, not a discretisation: the J domain radius (J of a moving tip \
is averaged over it), the process-zone length (the cohesive traction behind the tip that \
dissipates Γ) and the filter time (the speed relaxes over it, so an accelerating tip lags the \
speed its J asks for by about τ·dv/dt; a tip starts on its unfiltered J, so initiation does not \
wait for the filter). The solver's defaults are lengths and times of the scene (R = 1/16 of the \
bodies' shortest side, zone R/3, τ = R/(2 c_S)), so the rows under the defaults, like those under \
the fixed set, change with h only through the discretisation: the 0.25 / 0.5 mm difference of a \
row is the discretisation error. The parameter table above shows the regularisation's own \
effect; `--j-radius`, `--zone` and `--filter-time` move the fixed set.\n";

#[cfg(test)]
mod tests {
    use super::nice_step;

    #[test]
    fn tick_steps_are_round() {
        assert_eq!(nice_step(21.7), 5.0);
        assert_eq!(nice_step(1100.0), 200.0);
        assert!((nice_step(15.0) - 2.0).abs() < 1e-12);
    }
}
