//! `fracture study kinks`: kinked crack paths under the default growth law (issue 34,
//! `algorithm.md` pitfall 15). The pure-shear plate and Kalthoff–Winkler
//! (`fracture_verify::shear_kink_path`, `kalthoff_winkler_path`) run at 1 mm and 0.5 mm cells
//! with the solver's default J domain, process zone and filter; each tip's path is measured
//! by `fracture_verify::run_path` (growth, chord angle over its first 2 and 10 mm, point
//! symmetry, J1 and K over time). Writes `kinks.md` with its tables and verdicts against the
//! acceptance bounds (`fracture_verify::bounds`), and `kinks/` with an SVG of the paths and
//! one of the driving force per scene and the CSVs behind them.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use anyhow::Context;
use fracture_api::Scene;
use fracture_solver::SolverConfig;
use fracture_verify::{
    PathOverrides, PathProblem, PathReport, Settings, TipPathReport, bounds, kalthoff_winkler_path,
    run_path, shear_kink_path,
};

use super::StudyArgs;
use crate::report::svg::{Frame, Marker, PALETTE, Scale, Stroke, Svg, TickStyle, legend_entry};
use crate::report::svg::{text, vertical_text};
use crate::report::{csv_line, markdown_table, sig, write_file};

/// The cell sizes of the study (m).
const CELLS: [f64; 2] = [0.001, 0.0005];

/// The two problems.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Problem {
    Shear,
    Kalthoff,
}

impl Problem {
    const ALL: [Problem; 2] = [Problem::Shear, Problem::Kalthoff];
    fn name(self) -> &'static str {
        match self {
            Problem::Shear => "shear-plate",
            Problem::Kalthoff => "kalthoff-winkler",
        }
    }
    fn title(self) -> &'static str {
        match self {
            Problem::Shear => "Pure-shear plate",
            Problem::Kalthoff => "Kalthoff–Winkler",
        }
    }
    fn build(self, h: f64) -> anyhow::Result<PathProblem> {
        let o = PathOverrides::default();
        let s = Settings::at(h);
        Ok(match self {
            Problem::Shear => shear_kink_path(&s, &o)?,
            Problem::Kalthoff => kalthoff_winkler_path(&s, &o)?,
        })
    }
}

/// One finished run.
struct Run {
    problem: Problem,
    h: f64,
    scene: Scene,
    /// Expected path angle in the tip frame (degrees).
    angle: f64,
    report: PathReport,
    /// Rayleigh speed of the scene's material (m/s).
    c_r: f64,
    /// Γ at rest (J/m²).
    toughness: f64,
}

/// The initiation toughness of crack 0 (NaN if it does not grow).
fn toughness_of(scene: &Scene) -> f64 {
    match scene.cracks.first().map(|c| &c.propagation) {
        Some(fracture_api::scene::Propagation::EnergyRelease { toughness, .. }) => {
            toughness.at_rest()
        }
        _ => f64::NAN,
    }
}

/// Run the four scenes (`--jobs` at a time, `--threads` each, the 0.5 mm runs first) and
/// write the page; returns its path.
pub fn run(a: &StudyArgs) -> anyhow::Result<PathBuf> {
    let started = Instant::now();
    let mut jobs: Vec<(Problem, f64, PathProblem)> = Vec::new();
    for &h in CELLS.iter().rev() {
        for p in Problem::ALL {
            jobs.push((p, h, p.build(h).with_context(|| p.name())?));
        }
    }
    let total = jobs.len();
    let workers = a.jobs.resolve().clamp(1, total);
    println!(
        "kinks: {total} runs, {workers} at a time, {} solver thread(s) each",
        a.threads
    );
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let runs: Mutex<Vec<Run>> = Mutex::new(Vec::new());
    let errors: Mutex<Vec<String>> = Mutex::new(Vec::new());
    let config = SolverConfig { threads: a.threads };
    std::thread::scope(|s| {
        for _ in 0..workers {
            s.spawn(|| {
                while let Some((problem, h, p)) = jobs.get(next.fetch_add(1, Ordering::Relaxed)) {
                    let label = format!("{} {} mm", problem.name(), 1e3 * h);
                    let n = done.fetch_add(1, Ordering::Relaxed) + 1;
                    match run_path(&p.scene, config) {
                        Ok(report) => {
                            println!(
                                "[kinks {n}/{total}] {label}: {:.1} s, growth {} mm",
                                report.wall,
                                report
                                    .tips
                                    .iter()
                                    .map(|t| format!("{:.2}", 1e3 * t.growth))
                                    .collect::<Vec<_>>()
                                    .join(" / ")
                            );
                            let c_r = p
                                .scene
                                .materials
                                .values()
                                .next()
                                .map_or(f64::NAN, |m| m.wave_speeds(p.scene.analysis).c_r);
                            if let Ok(mut r) = runs.lock() {
                                r.push(Run {
                                    problem: *problem,
                                    h: *h,
                                    toughness: toughness_of(&p.scene),
                                    scene: p.scene.clone(),
                                    angle: p.angle,
                                    report,
                                    c_r,
                                });
                            }
                        }
                        Err(e) => {
                            println!("[kinks {n}/{total}] {label}: failed: {e}");
                            if let Ok(mut r) = errors.lock() {
                                r.push(format!("{label}: {e}"));
                            }
                        }
                    }
                }
            });
        }
    });
    let mut runs = runs
        .into_inner()
        .map_err(|_| anyhow::anyhow!("a run panicked"))?;
    let errors = errors
        .into_inner()
        .map_err(|_| anyhow::anyhow!("a run panicked"))?;
    runs.sort_by(|x, y| {
        (x.problem as u8)
            .cmp(&(y.problem as u8))
            .then(y.h.total_cmp(&x.h))
    });
    let page = Page {
        a,
        runs: &runs,
        errors: &errors,
        workers,
        wall: started.elapsed().as_secs_f64(),
    };
    page.write()
}

/// One acceptance bound checked.
struct Verdict {
    bound: String,
    measured: String,
    pass: bool,
}

struct Page<'a> {
    a: &'a StudyArgs,
    runs: &'a [Run],
    errors: &'a [String],
    workers: usize,
    wall: f64,
}

/// Degrees to one decimal, or "–".
fn deg(a: Option<f64>) -> String {
    a.map_or("–".into(), |a| format!("{a:.1}°"))
}

/// Metres as millimetres to two decimals.
fn mm(x: f64) -> String {
    if x.is_finite() {
        format!("{:.2}", 1e3 * x)
    } else {
        "–".into()
    }
}

fn cell_label(h: f64) -> String {
    format!("{} mm", sig(1e3 * h, 2))
}

/// The tip's J1 just before it started, and the mean and least J1 over the 10 µs after.
fn drive(t: &TipPathReport) -> (f64, f64, f64) {
    let Some(t0) = t.initiation else {
        return (f64::NAN, f64::NAN, f64::NAN);
    };
    let before = t
        .samples
        .iter()
        .rev()
        .find(|s| s.time < t0)
        .map_or(f64::NAN, |s| s.j1);
    let (mean, min) = t.j1_over(t0, t0 + 1.0e-5);
    (before, mean, min)
}

impl Page<'_> {
    fn run(&self, p: Problem, h: f64) -> Option<&Run> {
        self.runs.iter().find(|r| r.problem == p && r.h == h)
    }

    fn verdicts(&self) -> Vec<Verdict> {
        let mut v = Vec::new();
        for &h in &CELLS {
            let cell = cell_label(h);
            let run = self.run(Problem::Shear, h);
            let tips = run.map(|r| r.report.tips.as_slice()).unwrap_or(&[]);
            let growth: Vec<String> = tips.iter().map(|t| mm(t.growth)).collect();
            v.push(Verdict {
                bound: format!(
                    "pure-shear plate, {cell}: both tips grow ≥ {} mm",
                    mm(bounds::SHEAR_GROWTH)
                ),
                measured: format!("{} mm", growth.join(" / ")),
                pass: tips.len() == 2 && tips.iter().all(|t| t.growth >= bounds::SHEAR_GROWTH),
            });
            let (lo, hi) = bounds::SHEAR_ANGLE_2MM;
            v.push(Verdict {
                bound: format!(
                    "pure-shear plate, {cell}: path angle over the first 2 mm in {lo}° … {hi}° (tip frame) at both tips"
                ),
                measured: tips
                    .iter()
                    .map(|t| deg(t.angle_2mm))
                    .collect::<Vec<_>>()
                    .join(" / "),
                pass: tips.len() == 2
                    && tips
                        .iter()
                        .all(|t| t.angle_2mm.is_some_and(|a| (lo..=hi).contains(&a))),
            });
            let sym = run.and_then(|r| r.report.symmetry);
            let common = run.map_or(0.0, |r| r.report.symmetry_length);
            v.push(Verdict {
                bound: format!(
                    "pure-shear plate, {cell}: point-symmetric paths, error ≤ {} mm over ≥ {} mm of common path",
                    mm(bounds::SHEAR_SYMMETRY),
                    mm(bounds::SHEAR_GROWTH)
                ),
                measured: format!(
                    "{} mm over {} mm",
                    sym.map_or("–".into(), mm),
                    mm(common)
                ),
                pass: sym.is_some_and(|e| e <= bounds::SHEAR_SYMMETRY)
                    && common >= bounds::SHEAR_GROWTH,
            });
        }
        let kw = |h: f64| self.run(Problem::Kalthoff, h).and_then(|r| r.report.tip(1));
        for &h in &CELLS {
            let cell = cell_label(h);
            let t = kw(h);
            v.push(Verdict {
                bound: format!(
                    "Kalthoff–Winkler, {cell}: grows ≥ {} mm",
                    mm(bounds::KALTHOFF_GROWTH)
                ),
                measured: format!("{} mm", t.map_or("–".into(), |t| mm(t.growth))),
                pass: t.is_some_and(|t| t.growth >= bounds::KALTHOFF_GROWTH),
            });
            let (lo, hi) = bounds::KALTHOFF_ANGLE_10MM;
            v.push(Verdict {
                bound: format!(
                    "Kalthoff–Winkler, {cell}: path angle over the first 10 mm in {lo}° … {hi}°"
                ),
                measured: deg(t.and_then(|t| t.angle_10mm)),
                pass: t
                    .and_then(|t| t.angle_10mm)
                    .is_some_and(|a| (lo..=hi).contains(&a)),
            });
        }
        let (a1, a2) = (
            kw(CELLS[0]).and_then(|t| t.angle_10mm),
            kw(CELLS[1]).and_then(|t| t.angle_10mm),
        );
        let spread = a1.zip(a2).map(|(x, y)| (x - y).abs());
        v.push(Verdict {
            bound: format!(
                "Kalthoff–Winkler: 10 mm angle at 1 mm and 0.5 mm within {}°",
                bounds::KALTHOFF_CELL_SPREAD
            ),
            measured: format!("{} vs {}: {}", deg(a1), deg(a2), deg(spread)),
            pass: spread.is_some_and(|d| d <= bounds::KALTHOFF_CELL_SPREAD),
        });
        v
    }

    fn write(&self) -> anyhow::Result<PathBuf> {
        let figs = self.a.out.join("kinks");
        let verdicts = self.verdicts();
        let mut md = String::new();
        let _ = writeln!(
            md,
            "# Kinked crack paths under the default growth law\n\n\
             This page is written by `fracture study kinks`; do not edit it by hand. Regenerate:\n\n\
             ```sh\ncargo run --release -- study kinks --out {} --jobs {} --threads {}\n```\n",
            self.a.out.display(),
            self.a.jobs,
            self.a.threads
        );
        let _ = writeln!(
            md,
            "A kinked crack is judged by the path it grows over several millimetres, not by the \
             angle at which it leaves (`algorithm.md` pitfall 15: right after a kink the J domain \
             still holds the parent crack's field and the kinked tip can stall). Both scenes grow \
             by maximum hoop stress with the default `equation_of_motion` speed and the solver's \
             default J domain (1/16 of the shortest body side: 6.5 mm and 6.25 mm), process zone (a third of it) and filter time (R/(2c_S)), all fixed in metres and seconds, at 1 mm and 0.5 mm cells. \
             Built by `fracture_verify::shear_kink_path` and `kalthoff_winkler_path`, measured by \
             `fracture_verify::run_path`; `verify/tests/kinked_paths.rs` checks the same bounds at \
             1 mm.\n\n\
             - **Pure-shear plate**: a = 17 mm centre crack in a 104 mm Homalite plate under the \
             exact tractions of remote shear τ, ramped to 1 MPa over 250 µs and held to 300 µs, \
             Γ = 4 J/m². Expected: both tips kink at −70.5° in their own frames (Erdogan–Sih), a Z \
             point-symmetric about the crack centre, and keep growing (the kink's G reaches \
             about 3Γ at full load and rises as the branches lengthen).\n\
             - **Kalthoff–Winkler**: steel half model, 50 mm notch struck below at 16.5 m/s, \
             Γ = 22 kJ/m², to 90 µs. Expected: about 70° to the notch (experiment; simulations \
             60–70°), the crack running for tens of millimetres.\n\n\
             Path angles are chord angles from the initial tip to the point of the path at that \
             path length, in the tip's initial frame (e1 along the crack outwards, e2 to its left); \
             growth is the length of the path (crack points at the end of the run). The symmetry \
             error is the largest distance between tip 0's path turned by 180° about the crack \
             centre and tip 1's path, at equal path lengths over their common length.\n"
        );
        let _ = writeln!(md, "## Verdicts\n");
        let rows: Vec<Vec<String>> = verdicts
            .iter()
            .map(|v| {
                vec![
                    v.bound.clone(),
                    v.measured.clone(),
                    if v.pass {
                        "pass".into()
                    } else {
                        "**FAIL**".into()
                    },
                ]
            })
            .collect();
        md.push_str(&markdown_table(&["bound", "measured", "verdict"], &rows));
        for v in &verdicts {
            println!(
                "{}: {}: {}",
                if v.pass { "pass" } else { "FAIL" },
                v.bound,
                v.measured
            );
        }
        if !self.errors.is_empty() {
            let _ = writeln!(md, "\nRuns that gave no answer:\n");
            for e in self.errors {
                let _ = writeln!(md, "- {e}");
            }
        }
        self.tip_table(&mut md);
        self.cell_table(&mut md);
        self.symmetry_table(&mut md);
        let _ = writeln!(md, "\n## Paths and driving force\n");
        for p in Problem::ALL {
            let path_svg = format!("{}-paths.svg", p.name());
            let drive_svg = format!("{}-drive.svg", p.name());
            write_file(&figs, &path_svg, self.path_figure(p))?;
            write_file(&figs, &drive_svg, self.drive_figure(p))?;
            let _ = writeln!(
                md,
                "![{} paths](kinks/{path_svg})\n\n![{} J1 and growth](kinks/{drive_svg})\n",
                p.title(),
                p.title()
            );
        }
        let _ = writeln!(
            md,
            "Tables behind the figures: `kinks/paths.csv` (each tip's path), `kinks/tips.csv` \
             (each tip's crack-tip rows: growth, speed, J1, J2, K_I, K_II, filtered G).\n"
        );
        let _ = writeln!(md, "## Runs\n");
        let rows: Vec<Vec<String>> = self
            .runs
            .iter()
            .map(|r| {
                vec![
                    r.problem.title().into(),
                    cell_label(r.h),
                    r.report.particles.to_string(),
                    r.report.steps.to_string(),
                    format!("{:.0}", 1e6 * r.report.end),
                    format!("{:.1}", r.report.wall),
                ]
            })
            .collect();
        md.push_str(&markdown_table(
            &[
                "scene",
                "cells",
                "particles",
                "steps",
                "end (µs)",
                "wall (s)",
            ],
            &rows,
        ));
        let _ = writeln!(
            md,
            "\n{} runs, {} at a time with {} solver thread(s) each, {:.0} s in all.",
            self.runs.len(),
            self.workers,
            self.a.threads,
            self.wall
        );
        write_file(&figs, "paths.csv", self.paths_csv())?;
        write_file(&figs, "tips.csv", self.tips_csv())?;
        write_file(&self.a.out, "kinks.md", &md)?;
        let page = self.a.out.join("kinks.md");
        println!("wrote {} and {}", page.display(), figs.display());
        Ok(page)
    }

    fn tip_table(&self, md: &mut String) {
        let _ = writeln!(md, "\n## Growth and angle per tip\n");
        let _ = writeln!(
            md,
            "J1 before: the tip's J1 at the last sample before it started; after: mean and least \
             J1 over the 10 µs after it started, all over Γ. Angle, whole path: the chord from \
             the initial tip to the final one, for paths shorter than 2 mm. A kinked tip whose J1 falls \
             well below Γ (or below 0) after the kink stalls there. Peak speed: the largest \
             crack-tip speed of the rows over c_R (a tip at the law's cap, ≥ 0.99 c_R, would \
             meet any speed bound by the cap: `algorithm.md` pitfall 14).\n"
        );
        let mut rows = Vec::new();
        for r in self.runs {
            for t in &r.report.tips {
                let (before, mean, min) = drive(t);
                let peak = t
                    .samples
                    .iter()
                    .map(|s| s.speed)
                    .filter(|v| v.is_finite())
                    .fold(f64::NAN, f64::max);
                rows.push(vec![
                    r.problem.title().into(),
                    cell_label(r.h),
                    t.tip.to_string(),
                    t.initiation
                        .map_or("–".into(), |s| format!("{:.1}", 1e6 * s)),
                    mm(t.growth),
                    mm(t.advance),
                    deg(t.angle_2mm),
                    deg(t.angle_10mm),
                    deg(t.angle_end),
                    format!("{:.1}°", r.angle),
                    sig(before / r.toughness, 3),
                    format!(
                        "{} / {}",
                        sig(mean / r.toughness, 3),
                        sig(min / r.toughness, 3)
                    ),
                    sig(peak / r.c_r, 2),
                    if t.active_at_end { "yes" } else { "no" }.into(),
                ]);
            }
        }
        md.push_str(&markdown_table(
            &[
                "scene",
                "cells",
                "tip",
                "start (µs)",
                "growth (mm)",
                "advance (mm)",
                "angle, 2 mm",
                "angle, 10 mm",
                "angle, whole path",
                "expected",
                "J1/Γ before",
                "J1/Γ after: mean / least",
                "peak v/c_R",
                "tip at end",
            ],
            &rows,
        ));
    }

    fn cell_table(&self, md: &mut String) {
        let _ = writeln!(md, "\n## 1 mm against 0.5 mm cells\n");
        let mut rows = Vec::new();
        for p in Problem::ALL {
            let (Some(r1), Some(r2)) = (self.run(p, CELLS[0]), self.run(p, CELLS[1])) else {
                continue;
            };
            for t1 in &r1.report.tips {
                let Some(t2) = r2.report.tip(t1.tip) else {
                    continue;
                };
                let diff = |a: Option<f64>, b: Option<f64>| deg(a.zip(b).map(|(x, y)| x - y));
                rows.push(vec![
                    p.title().into(),
                    t1.tip.to_string(),
                    format!("{} / {}", mm(t1.growth), mm(t2.growth)),
                    format!("{} / {}", deg(t1.angle_2mm), deg(t2.angle_2mm)),
                    diff(t1.angle_2mm, t2.angle_2mm),
                    format!("{} / {}", deg(t1.angle_10mm), deg(t2.angle_10mm)),
                    diff(t1.angle_10mm, t2.angle_10mm),
                ]);
            }
        }
        md.push_str(&markdown_table(
            &[
                "scene",
                "tip",
                "growth 1 / 0.5 mm (mm)",
                "angle 2 mm, 1 / 0.5 mm",
                "difference",
                "angle 10 mm, 1 / 0.5 mm",
                "difference",
            ],
            &rows,
        ));
    }

    fn symmetry_table(&self, md: &mut String) {
        let _ = writeln!(md, "\n## Point symmetry of the pure-shear plate\n");
        let rows: Vec<Vec<String>> = CELLS
            .iter()
            .filter_map(|&h| self.run(Problem::Shear, h))
            .map(|r| {
                let g: Vec<f64> = r.report.tips.iter().map(|t| t.growth).collect();
                vec![
                    cell_label(r.h),
                    r.report.symmetry.map_or("–".into(), mm),
                    mm(r.report.symmetry_length),
                    if g.len() == 2 {
                        mm((g[0] - g[1]).abs())
                    } else {
                        "–".into()
                    },
                ]
            })
            .collect();
        md.push_str(&markdown_table(
            &[
                "cells",
                "symmetry error (mm)",
                "over common path (mm)",
                "growth difference (mm)",
            ],
            &rows,
        ));
    }

    fn paths_csv(&self) -> String {
        let mut s = csv_line(&["scene", "cell_mm", "tip", "k", "x_mm", "y_mm"]);
        for r in self.runs {
            for t in &r.report.tips {
                for (k, p) in t.path.iter().enumerate() {
                    s.push_str(&csv_line(&[
                        r.problem.name().to_string(),
                        format!("{}", 1e3 * r.h),
                        t.tip.to_string(),
                        k.to_string(),
                        format!("{:.5}", 1e3 * p[0]),
                        format!("{:.5}", 1e3 * p[1]),
                    ]));
                }
            }
        }
        s
    }

    fn tips_csv(&self) -> String {
        let mut s = csv_line(&[
            "scene",
            "cell_mm",
            "tip",
            "time_us",
            "advance_mm",
            "speed_m_s",
            "j1",
            "j2",
            "k1",
            "k2",
            "g_filtered",
        ]);
        let f = |x: f64| {
            if x.is_finite() {
                format!("{x:.6e}")
            } else {
                String::new()
            }
        };
        for r in self.runs {
            for t in &r.report.tips {
                for q in &t.samples {
                    s.push_str(&csv_line(&[
                        r.problem.name().to_string(),
                        format!("{}", 1e3 * r.h),
                        t.tip.to_string(),
                        format!("{:.4}", 1e6 * q.time),
                        format!("{:.5}", 1e3 * q.advance),
                        f(q.speed),
                        f(q.j1),
                        f(q.j2),
                        f(q.k1),
                        f(q.k2),
                        f(q.g_filtered),
                    ]));
                }
            }
        }
        s
    }

    /// The paths of one scene at both cell sizes over the initial crack, with the expected
    /// direction from each tip (20 mm, dashed), in millimetres at equal scales. Each run is
    /// moved so that its initial crack's last point lies on the first run's (the scenes put
    /// the crack at mid-cell and the body two cells in, so their coordinates differ by
    /// fractions of a millimetre).
    fn path_figure(&self, p: Problem) -> String {
        let runs: Vec<&Run> = self.runs.iter().filter(|r| r.problem == p).collect();
        let last_point = |r: &Run| {
            r.scene
                .cracks
                .first()
                .and_then(|c| c.points.last())
                .map_or([0.0; 2], |q| [q[0], q[1]])
        };
        let anchor = runs.first().map_or([0.0; 2], |r| last_point(r));
        let shift = |r: &Run, q: [f64; 2]| {
            let o = last_point(r);
            [q[0] + anchor[0] - o[0], q[1] + anchor[1] - o[1]]
        };
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        let mut grow = |q: [f64; 2]| {
            for k in 0..2 {
                if q[k].is_finite() {
                    lo[k] = lo[k].min(1e3 * q[k]);
                    hi[k] = hi[k].max(1e3 * q[k]);
                }
            }
        };
        let mut cracks: Vec<Vec<[f64; 2]>> = Vec::new();
        let mut rays: Vec<[[f64; 2]; 2]> = Vec::new();
        if let Some(r) = runs.first() {
            if let Some(c) = r.scene.cracks.first() {
                let line: Vec<[f64; 2]> = c.points.iter().map(|q| [q[0], q[1]]).collect();
                line.iter().for_each(|&q| grow(q));
                cracks.push(line);
            }
            for t in &r.report.tips {
                let (Some(&o), e1) = (t.path.first(), t.direction) else {
                    continue;
                };
                let (s, c) = r.angle.to_radians().sin_cos();
                let e2 = [-e1[1], e1[0]];
                let d = [c * e1[0] + s * e2[0], c * e1[1] + s * e2[1]];
                let end = [o[0] + 0.02 * d[0], o[1] + 0.02 * d[1]];
                grow(end);
                rays.push([o, end]);
            }
        }
        for r in &runs {
            for t in &r.report.tips {
                t.path.iter().for_each(|&q| grow(shift(r, q)));
            }
        }
        if !(lo[0].is_finite() && lo[1].is_finite()) {
            lo = [0.0, 0.0];
            hi = [10.0, 10.0];
        }
        // Whole ticks (5 or 10 mm) around the view, padded by 2 mm.
        let step = if (hi[0] - lo[0]).max(hi[1] - lo[1]) > 50.0 {
            10.0
        } else {
            5.0
        };
        let lo = [
            ((lo[0] - 2.0) / step).floor() * step,
            ((lo[1] - 2.0) / step).floor() * step,
        ];
        let hi = [
            ((hi[0] + 2.0) / step).ceil() * step,
            ((hi[1] + 2.0) / step).ceil() * step,
        ];
        let (span_x, span_y) = (hi[0] - lo[0], hi[1] - lo[1]);
        let px_per_mm = (560.0 / span_x).min(560.0 / span_y);
        let (w, h) = (span_x * px_per_mm, span_y * px_per_mm);
        let frame = Frame {
            left: 60.0,
            top: 40.0,
            width: w,
            height: h,
            x: Scale::linear(lo[0], hi[0]),
            y: Scale::linear(lo[1], hi[1]),
        };
        let mut svg = Svg::new(w + 260.0, h + 90.0, 12);
        svg.add(
            text(
                60.0,
                24.0,
                &format!("{}: crack paths (default law)", p.title()),
            )
            .bold(),
        );
        let tick = TickStyle::Grid("#eee");
        frame.x_ticks(&mut svg, step, tick, 16.0, |v| format!("{v:.0}"));
        frame.y_ticks(&mut svg, step, tick, 6.0, |v| format!("{v:.0}"));
        svg.add(frame.outline("#999"));
        svg.add(text(frame.left + 0.5 * w, frame.bottom() + 34.0, "x (mm)").middle());
        svg.add(vertical_text(20.0, frame.top + 0.5 * h, "y (mm)"));
        let to_mm = |pts: &[[f64; 2]]| -> Vec<[f64; 2]> {
            pts.iter().map(|q| [1e3 * q[0], 1e3 * q[1]]).collect()
        };
        for c in &cracks {
            svg.add(frame.polyline(&to_mm(c), Stroke::new("#000").width(2.0)));
        }
        for ray in &rays {
            svg.add(frame.polyline(&to_mm(ray), Stroke::new("#888").dashed()));
        }
        let colours = [PALETTE[0], PALETTE[1]];
        for (i, r) in runs.iter().enumerate() {
            let colour = colours[i % 2];
            for t in &r.report.tips {
                let moved: Vec<[f64; 2]> = t.path.iter().map(|&q| shift(r, q)).collect();
                let pts = to_mm(&moved);
                svg.add(frame.polyline(&pts, Stroke::new(colour).width(1.5)));
                if let Some(&end) = pts.last() {
                    svg.add(frame.marker(end, Marker::Dot { r: 2.5, colour }, None));
                }
            }
        }
        let lx = frame.right() + 20.0;
        svg.add(legend_entry(
            lx,
            frame.top + 10.0,
            Stroke::new("#000").width(2.0),
            None,
            "initial crack",
        ));
        svg.add(legend_entry(
            lx,
            frame.top + 30.0,
            Stroke::new("#888").dashed(),
            None,
            &format!(
                "expected ({:.1}°)",
                runs.first().map_or(f64::NAN, |r| r.angle)
            ),
        ));
        for (i, r) in runs.iter().enumerate() {
            let colour = colours[i % 2];
            svg.add(legend_entry(
                lx,
                frame.top + 50.0 + 20.0 * i as f64,
                Stroke::new(colour).width(1.5),
                Some(Marker::Dot { r: 2.5, colour }),
                &format!("{} cells", cell_label(r.h)),
            ));
        }
        svg.finish()
    }

    /// J1/Γ (top) and growth (bottom) against time of every tip of one scene at both cell
    /// sizes.
    fn drive_figure(&self, p: Problem) -> String {
        let runs: Vec<&Run> = self.runs.iter().filter(|r| r.problem == p).collect();
        let t_end = runs
            .iter()
            .map(|r| 1e6 * r.report.end)
            .fold(0.0f64, f64::max)
            .max(1.0);
        let g_max = runs
            .iter()
            .flat_map(|r| r.report.tips.iter().map(|t| 1e3 * t.growth))
            .fold(1.0f64, f64::max);
        let g_top = (g_max / 5.0).ceil() * 5.0;
        let (w, h) = (620.0, 220.0);
        let x = Scale::linear(0.0, (t_end / 10.0).ceil() * 10.0);
        let top = Frame {
            left: 70.0,
            top: 40.0,
            width: w,
            height: h,
            x,
            y: Scale::linear(-1.0, 4.0).clamped(),
        };
        let bottom = Frame {
            top: top.bottom() + 40.0,
            y: Scale::linear(0.0, g_top),
            ..top
        };
        let mut svg = Svg::new(w + 280.0, bottom.bottom() + 60.0, 12);
        svg.add(
            text(
                70.0,
                24.0,
                &format!("{}: J1/Γ and growth against time", p.title()),
            )
            .bold(),
        );
        let t_step = if t_end > 150.0 { 50.0 } else { 10.0 };
        for f in [&top, &bottom] {
            f.x_ticks(&mut svg, t_step, TickStyle::Grid("#eee"), 16.0, |v| {
                format!("{v:.0}")
            });
            svg.add(f.outline("#999"));
        }
        top.y_ticks(&mut svg, 1.0, TickStyle::Grid("#eee"), 6.0, |v| {
            format!("{v:.0}")
        });
        bottom.y_ticks(&mut svg, g_top / 5.0, TickStyle::Grid("#eee"), 6.0, |v| {
            sig(v, 2)
        });
        svg.add(top.y_reference(1.0, Stroke::new("#888").dashed(), "Γ", -4.0));
        svg.add(top.y_reference(0.0, Stroke::new("#bbb"), "", 0.0));
        svg.add(vertical_text(
            24.0,
            top.top + 0.5 * h,
            "J1 / Γ (clipped to −1 … 4)",
        ));
        svg.add(vertical_text(24.0, bottom.top + 0.5 * h, "growth (mm)"));
        svg.add(text(bottom.left + 0.5 * w, bottom.bottom() + 34.0, "time (µs)").middle());
        let mut legend = 0.0;
        for (i, r) in runs.iter().enumerate() {
            for t in &r.report.tips {
                let colour = PALETTE[(2 * i + t.tip) % PALETTE.len()];
                let j: Vec<[f64; 2]> = t
                    .samples
                    .iter()
                    .filter(|s| s.j1.is_finite())
                    .map(|s| [1e6 * s.time, s.j1 / r.toughness])
                    .collect();
                let g: Vec<[f64; 2]> = t
                    .samples
                    .iter()
                    .map(|s| [1e6 * s.time, 1e3 * s.advance])
                    .collect();
                if let Some(e) = top.path(&j, Stroke::new(colour)) {
                    svg.add(e);
                }
                if let Some(e) = bottom.path(&g, Stroke::new(colour).width(1.5)) {
                    svg.add(e);
                }
                svg.add(legend_entry(
                    top.right() + 20.0,
                    top.top + 10.0 + legend,
                    Stroke::new(colour).width(1.5),
                    None,
                    &format!("{} cells, tip {}", cell_label(r.h), t.tip),
                ));
                legend += 20.0;
            }
        }
        svg.finish()
    }
}
