//! `fracture bench accuracy`: the verification problems of
//! [`fracture_verify`] at a ladder of resolutions and settings, each run's
//! error against the analytic answer and its wall time, the observed convergence orders and
//! the Pareto front of error against cost.

use std::path::Path;
use std::time::Instant;

use fracture_verify::{Problem, Settings, ShapeFunction};

use super::Machine;
use crate::report::{csv_line, markdown_table, sig, write_file};

/// Which ladder to run.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ladder {
    /// One coarse run per problem (seconds; the CI smoke test of the command).
    Tiny,
    /// The two coarsest resolutions and one rung of each other family (a couple of minutes).
    Quick,
    /// The whole ladder of `docs/accuracy.md` (tens of minutes on 2 cores).
    Full,
}

/// The cost axis of the plot and the Pareto front.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cost {
    /// Wall-clock seconds (the figure on an idle machine).
    Wall,
    /// CPU seconds of the process (robust to other load; with `--threads 1` the work).
    Cpu,
}

impl Cost {
    /// The cost of a row.
    pub fn of(self, r: &Row) -> f64 {
        match self {
            Cost::Wall => r.wall_seconds,
            Cost::Cpu => r.cpu_seconds,
        }
    }
    /// Axis label.
    pub fn label(self) -> &'static str {
        match self {
            Cost::Wall => "wall time",
            Cost::Cpu => "CPU time",
        }
    }
}

/// A setting family: one curve of the plot.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Family {
    /// Cell size (GIMP, 2×2 particles per cell, cfl 0.5, contour 2).
    Resolution,
    /// Cell size with linear shape functions.
    Linear,
    /// Particles per cell direction at the problem's base cell size.
    Ppc,
    /// Courant number at the base cell size.
    Cfl,
    /// J contour half-size at the base cell size.
    Contour,
}

impl Family {
    /// All families in plot order.
    pub const ALL: [Family; 5] = [
        Family::Resolution,
        Family::Linear,
        Family::Ppc,
        Family::Cfl,
        Family::Contour,
    ];
    /// Name in the CSV and legend.
    pub fn name(self) -> &'static str {
        match self {
            Family::Resolution => "resolution",
            Family::Linear => "linear",
            Family::Ppc => "ppc",
            Family::Cfl => "cfl",
            Family::Contour => "contour",
        }
    }
}

/// One run of the ladder.
#[derive(Debug, Clone, Copy)]
pub struct Rung {
    /// Problem.
    pub problem: Problem,
    /// Family.
    pub family: Family,
    /// Settings.
    pub settings: Settings,
}

/// Cell sizes of the resolution family, coarsest first, and the base cell size of the other
/// families (chosen so that a full ladder stays within tens of minutes on 2 cores).
fn resolutions(p: Problem) -> (Vec<f64>, f64) {
    match p {
        Problem::CenterCrack | Problem::EdgeCrack => (vec![0.004, 0.002, 0.001, 0.0005], 0.001),
        Problem::ShearCrack => (vec![0.004, 0.002, 0.001], 0.002),
        Problem::Freund => (vec![0.002, 0.001, 0.0005], 0.001),
        Problem::VibratingBar => (vec![1.0, 0.5, 0.25], 0.5),
        Problem::WaveSpeed => (vec![0.002, 0.001, 0.0005], 0.001),
        Problem::InclinedCrack => (vec![0.004, 0.002, 0.001], 0.002),
        Problem::ShearKink => (vec![0.004, 0.002, 0.001], 0.002),
        Problem::KalthoffWinkler => (vec![0.002, 0.001, 0.0005], 0.001),
    }
}

/// The runs of a ladder, in execution order.
pub fn rungs(ladder: Ladder, problems: &[Problem]) -> Vec<Rung> {
    let mut out = Vec::new();
    for &p in problems {
        let (hs, base) = resolutions(p);
        let coarse = hs[0];
        let mut push = |family, settings| {
            out.push(Rung {
                problem: p,
                family,
                settings,
            })
        };
        let with = |h: f64, f: &dyn Fn(&mut Settings)| {
            let mut s = Settings::at(h);
            f(&mut s);
            s
        };
        match ladder {
            Ladder::Tiny => {
                push(Family::Resolution, Settings::at(coarse));
                if p == Problem::VibratingBar {
                    // Two points: the convergence fit runs too.
                    push(Family::Resolution, Settings::at(hs[1]));
                }
            }
            Ladder::Quick => {
                for &h in &hs[..2] {
                    push(Family::Resolution, Settings::at(h));
                }
                push(
                    Family::Linear,
                    with(coarse, &|s| s.shape = ShapeFunction::Linear),
                );
                push(Family::Ppc, with(coarse, &|s| s.particles_per_cell = 1));
                push(Family::Cfl, with(coarse, &|s| s.cfl = 0.9));
                if p.has_crack() {
                    push(Family::Contour, with(coarse, &|s| s.j_contour = 3));
                }
            }
            Ladder::Full => {
                for &h in &hs {
                    push(Family::Resolution, Settings::at(h));
                }
                // Linear shape functions on all but the finest (most expensive) rung.
                for &h in &hs[..hs.len() - 1] {
                    push(
                        Family::Linear,
                        with(h, &|s| s.shape = ShapeFunction::Linear),
                    );
                }
                for ppc in [1, 3] {
                    push(Family::Ppc, with(base, &|s| s.particles_per_cell = ppc));
                }
                for cfl in [0.25, 0.9] {
                    push(Family::Cfl, with(base, &|s| s.cfl = cfl));
                }
                if p.has_crack() {
                    for c in [1, 3, 4] {
                        push(Family::Contour, with(base, &|s| s.j_contour = c));
                    }
                }
            }
        }
    }
    out
}

/// The outcome of one rung.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Row {
    /// Problem name.
    pub problem: &'static str,
    /// Family name.
    pub family: &'static str,
    /// Cell size h.
    pub cell_size: f64,
    /// Characteristic length over h (cells across the crack a/h; cells along the bar).
    pub cells_across: f64,
    /// Particles per cell direction.
    pub ppc: u32,
    /// Courant number.
    pub cfl: f64,
    /// Shape functions.
    pub shape: &'static str,
    /// J contour half-size (crack problems).
    pub contour: u32,
    /// Particles.
    pub particles: usize,
    /// Steps.
    pub steps: u64,
    /// Wall time of the run (s), building the simulation included.
    pub wall_seconds: f64,
    /// CPU time of the process during the run (s): the cost measure under load.
    pub cpu_seconds: f64,
    /// Solver value.
    pub value: f64,
    /// Analytic value.
    pub reference: f64,
    /// Signed relative error.
    pub error: f64,
    /// Worst relative error over the time window (Freund).
    pub worst: f64,
    /// Why there is no value ("" when there is).
    pub failure: String,
}

fn shape_name(s: ShapeFunction) -> &'static str {
    match s {
        ShapeFunction::Gimp => "gimp",
        ShapeFunction::Linear => "linear",
    }
}

/// Run one rung.
pub fn run_rung(r: &Rung, threads: fracture_solver::Parallelism) -> Row {
    let s = r.settings;
    let (start, cpu0) = (Instant::now(), super::process_cpu_seconds());
    let m = r.problem.measure(&s, threads);
    let wall = start.elapsed().as_secs_f64();
    let cpu = super::process_cpu_seconds() - cpu0;
    let mut row = Row {
        problem: r.problem.name(),
        family: r.family.name(),
        cell_size: s.cell_size,
        cells_across: r.problem.length_scale() / s.cell_size,
        ppc: s.particles_per_cell,
        cfl: s.cfl,
        shape: shape_name(s.shape),
        contour: if r.problem.has_crack() {
            s.j_contour
        } else {
            0
        },
        particles: 0,
        steps: 0,
        wall_seconds: wall,
        cpu_seconds: cpu,
        value: f64::NAN,
        reference: f64::NAN,
        error: f64::NAN,
        worst: f64::NAN,
        failure: String::new(),
    };
    match m {
        Ok(m) => {
            row.particles = m.particles;
            row.steps = m.steps;
            row.value = m.value;
            row.reference = m.reference;
            row.error = m.error;
            row.worst = m.worst.unwrap_or(f64::NAN);
        }
        Err(e) => row.failure = e.to_string().replace([',', '\n'], ";"),
    }
    row
}

/// Least-squares slope of ln|error| against ln h over the rows of one problem and family
/// (the observed convergence order: |e| ∝ h^p); `None` with fewer than two usable points.
pub fn convergence_order(rows: &[&Row]) -> Option<f64> {
    let pts: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.error.is_finite() && r.error != 0.0)
        .map(|r| (r.cell_size.ln(), r.error.abs().ln()))
        .collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// Indices (into `rows`) of the Pareto front of (cost, |error|): the runs that no
/// cheaper-or-equal run beats on error, cheapest first.
pub fn pareto(rows: &[&Row], cost: Cost) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..rows.len())
        .filter(|&i| rows[i].error.is_finite() && cost.of(rows[i]).is_finite())
        .collect();
    idx.sort_by(|&a, &b| {
        cost.of(rows[a])
            .total_cmp(&cost.of(rows[b]))
            .then(rows[a].error.abs().total_cmp(&rows[b].error.abs()))
    });
    let mut best = f64::INFINITY;
    let mut front = Vec::new();
    for i in idx {
        let e = rows[i].error.abs();
        if e < best {
            best = e;
            front.push(i);
        }
    }
    front
}

const CSV_HEADER: &str = "problem,family,cell_size,cells_across,ppc,cfl,shape,contour,particles,steps,wall_seconds,cpu_seconds,value,reference,error,worst,failure\n";

fn csv(rows: &[Row]) -> String {
    let mut s = String::from(CSV_HEADER);
    for r in rows {
        s.push_str(&csv_line(&[
            r.problem.into(),
            r.family.into(),
            format!("{:e}", r.cell_size),
            format!("{:.3}", r.cells_across),
            r.ppc.to_string(),
            r.cfl.to_string(),
            r.shape.into(),
            r.contour.to_string(),
            r.particles.to_string(),
            r.steps.to_string(),
            format!("{:.4}", r.wall_seconds),
            format!("{:.2}", r.cpu_seconds),
            format!("{:.8e}", r.value),
            format!("{:.8e}", r.reference),
            format!("{:.6e}", r.error),
            format!("{:.6e}", r.worst),
            r.failure.clone(),
        ]));
    }
    s
}

/// The settings columns of a run (problem, family, h, a/h, ppc, cfl, shape, contour).
fn settings_cells(r: &Row) -> Vec<String> {
    vec![
        r.problem.into(),
        r.family.into(),
        format!("{:e}", r.cell_size),
        sig(r.cells_across, 3),
        r.ppc.to_string(),
        r.cfl.to_string(),
        r.shape.into(),
        r.contour.to_string(),
    ]
}

fn pct(x: f64) -> String {
    if x.is_finite() {
        format!("{:+.2} %", 100.0 * x)
    } else {
        "–".into()
    }
}

fn markdown(
    rows: &[Row],
    machine: &Machine,
    ladder: Ladder,
    threads: fracture_solver::Parallelism,
    cost: Cost,
) -> String {
    let mut s = format!(
        "# Accuracy ladder\n\n`fracture bench accuracy --ladder {}` with {} solver threads; {}.\n\
         Error = (solver − analytic)/analytic; Freund: mean |error| over t − t_c ∈ [3, 14] µs \
         (sign of the mean error), worst in the last column. Wall time includes building the \
         simulation.\n\n",
        match ladder {
            Ladder::Tiny => "tiny",
            Ladder::Quick => "quick",
            Ladder::Full => "full",
        },
        match threads {
            fracture_solver::Parallelism::AllCores => "one per core".to_string(),
            fracture_solver::Parallelism::Threads(n) => n.to_string(),
        },
        machine.describe()
    );
    s.push_str("## Observed convergence orders\n\nLeast-squares slope p of ln|error| against ln h (|error| ∝ h^p) over the cell-size ladder.\n\n");
    let mut conv = Vec::new();
    for p in Problem::ALL {
        for fam in [Family::Resolution, Family::Linear] {
            let rs: Vec<&Row> = rows
                .iter()
                .filter(|r| r.problem == p.name() && r.family == fam.name())
                .collect();
            if rs.is_empty() {
                continue;
            }
            let errs = rs
                .iter()
                .map(|r| format!("{}: {}", sig(r.cells_across, 3), pct(r.error)))
                .collect::<Vec<_>>()
                .join(", ");
            conv.push(vec![
                p.name().to_string(),
                p.reference_name().to_string(),
                fam.name().to_string(),
                errs,
                convergence_order(&rs).map_or("–".into(), |o| format!("{o:.2}")),
            ]);
        }
    }
    s.push_str(&markdown_table(
        &[
            "problem",
            "reference",
            "family",
            "error by cells across (a/h or L/h)",
            "order p",
        ],
        &conv,
    ));
    s.push_str(&format!(
        "\n## Pareto front (error against {})\n\n",
        cost.label()
    ));
    let mut front_rows = Vec::new();
    for p in Problem::ALL {
        let rs: Vec<&Row> = rows.iter().filter(|r| r.problem == p.name()).collect();
        for i in pareto(&rs, cost) {
            let r = rs[i];
            let mut row = settings_cells(r);
            row.extend([
                format!("{:.2}", r.wall_seconds),
                format!("{:.2}", r.cpu_seconds),
                pct(r.error),
            ]);
            front_rows.push(row);
        }
    }
    s.push_str(&markdown_table(
        &[
            "problem", "family", "h (m)", "a/h", "ppc", "cfl", "shape", "contour", "wall s",
            "CPU s", "error",
        ],
        &front_rows,
    ));
    s.push_str("\n## All runs\n\n");
    let all: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            let mut row = settings_cells(r);
            row.extend([
                r.particles.to_string(),
                r.steps.to_string(),
                format!("{:.2}", r.wall_seconds),
                format!("{:.2}", r.cpu_seconds),
                sig(r.value, 6),
                sig(r.reference, 6),
                pct(r.error),
                pct(r.worst),
                r.failure.clone(),
            ]);
            row
        })
        .collect();
    s.push_str(&markdown_table(
        &[
            "problem",
            "family",
            "h (m)",
            "a/h",
            "ppc",
            "cfl",
            "shape",
            "contour",
            "particles",
            "steps",
            "wall s",
            "CPU s",
            "value",
            "reference",
            "error",
            "worst",
            "failure",
        ],
        &all,
    ));
    s
}

/// Run the ladder, print progress on stderr and the Markdown report on stdout, and write
/// `accuracy.csv`, `accuracy.md` and `accuracy.svg` into `out`.
pub fn run(
    ladder: Ladder,
    problems: &[Problem],
    families: &[Family],
    threads: fracture_solver::Parallelism,
    cost: Cost,
    out: &Path,
) -> anyhow::Result<Vec<Row>> {
    let machine = Machine::now();
    let rungs: Vec<Rung> = rungs(ladder, problems)
        .into_iter()
        .filter(|r| families.is_empty() || families.contains(&r.family))
        .collect();
    let mut rows = Vec::new();
    for (k, r) in rungs.iter().enumerate() {
        let row = run_rung(r, threads);
        eprintln!(
            "[{}/{}] {} {} h={:e} ppc={} cfl={} {} contour={}: {:.2} s, error {}{}",
            k + 1,
            rungs.len(),
            row.problem,
            row.family,
            row.cell_size,
            row.ppc,
            row.cfl,
            row.shape,
            row.contour,
            row.wall_seconds,
            pct(row.error),
            if row.failure.is_empty() {
                String::new()
            } else {
                format!(" ({})", row.failure)
            }
        );
        rows.push(row);
        // Keep what is done on disk: a long ladder interrupted still leaves its report.
        write_reports(out, &rows, &machine, ladder, threads, cost)?;
    }
    let md = markdown(&rows, &machine, ladder, threads, cost);
    #[allow(clippy::print_stdout)]
    {
        println!("{md}");
    }
    Ok(rows)
}

fn write_reports(
    out: &Path,
    rows: &[Row],
    machine: &Machine,
    ladder: Ladder,
    threads: fracture_solver::Parallelism,
    cost: Cost,
) -> anyhow::Result<()> {
    write_file(out, "accuracy.csv", csv(rows))?;
    write_file(
        out,
        "accuracy.md",
        markdown(rows, machine, ladder, threads, cost),
    )?;
    write_file(
        out,
        "accuracy.svg",
        super::accuracy_plot::accuracy_plot(rows, cost),
    )?;
    write_file(
        out,
        "accuracy.json",
        serde_json::to_string_pretty(&serde_json::json!({"machine": machine, "runs": rows}))?,
    )
}
