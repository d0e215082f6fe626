//! The page `rosakis.md`: its prose (header, scenes, regeneration, footer), one section per
//! sweep with its speed figure and table, and the CSVs beside it (`runs.csv`, `speeds.csv`).
//! The claims and convergence sections are in `super::claims`, the figures in
//! `super::figures`.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

use fracture_api::results::RunStatus;
use fracture_api::scene::WaveSpeeds;

use crate::report::{csv_line, markdown_table, write_file};

use super::StudyArgs;
use super::figures::speed_plot;
use super::measure::Measured;
use super::sweeps::{
    P_CELL, P_CONTACT, P_J_INTEGRAL, P_SPEED, P_TOUGHNESS, P_VELOCITY, Sweep, Variant,
};

/// Speed windows of the tables (µs after impact).
const WINDOWS: [(f64, f64); 7] = [
    (10.0, 20.0),
    (20.0, 30.0),
    (30.0, 40.0),
    (40.0, 50.0),
    (50.0, 60.0),
    (60.0, 70.0),
    (70.0, 80.0),
];

/// Columns of `runs.csv`: one row per run.
const RUNS_CSV_HEADER: [&str; 29] = [
    "sweep",
    "v_m_s",
    "j_ic",
    "mu",
    "law",
    "cell_mm",
    "j_radius_mm",
    "status",
    "initiation_us",
    "mean_speed_10_20us",
    "mean_speed_20_30us",
    "mean_speed_30_40us",
    "mean_speed_40_50us",
    "mean_speed_50_60us",
    "mean_speed_60_70us",
    "mean_speed_70_80us",
    "mean_speed_to_end",
    "tip_advance_mm",
    "crack_length_growth_mm",
    "running_samples",
    "running_samples_j1_below_minus_0.1_jic",
    "fracture_required_j",
    "fracture_dissipated_j",
    "max_off_bond_mm",
    "max_off_material_line_mm",
    "wall_s",
    "particle_steps_per_s",
    "steps",
    "particles",
];

/// The last columns of a sweep's table (after the run, its initiation and its windows).
const SWEEP_TABLE_TAIL: [&str; 7] = [
    "initiation to end",
    "max box speed",
    "tip advance",
    "J1 < −0.1 J_Ic",
    "fracture energy required / dissipated",
    "wall",
    "particle-steps/s",
];

/// Everything the report needs.
pub(super) struct Report<'a> {
    pub(super) a: &'a StudyArgs,
    pub(super) sweeps: &'a [Sweep],
    pub(super) results: &'a HashMap<String, Measured>,
    pub(super) speeds: WaveSpeeds,
    pub(super) figs: &'a Path,
    /// 1-minute load average when the runs had finished (Linux), for the timings' context.
    pub(super) load: Option<String>,
    /// Wall time of the whole study (s), its number of distinct runs and runs at a time.
    pub(super) wall: f64,
    pub(super) runs: usize,
    pub(super) workers: usize,
}

/// Speed in m/s with v/c_S and v/c_R.
pub(super) fn speed_cell(v: Option<f64>, s: &WaveSpeeds) -> String {
    match v {
        Some(v) => format!("{:.0} ({:.2} c_S, {:.2} c_R)", v, v / s.c_s, v / s.c_r),
        None => "–".into(),
    }
}

/// A length in mm for the CSVs, empty if the scene's own.
fn opt_mm(x: Option<f64>) -> String {
    x.map_or(String::new(), |x| format!("{}", (x * 1e7).round() / 1e4))
}

/// "412 of 1,250 (33 %)": the running samples with J1 < −0.1 J_Ic.
pub(super) fn negative_j_cell(m: &Measured, j_ic: f64) -> String {
    let (low, n) = m.negative_j(j_ic, 0.1);
    if n == 0 {
        "–".into()
    } else {
        format!("{low} of {n} ({:.1} %)", 100.0 * low as f64 / n as f64)
    }
}

/// "4.63 / 4.71 mJ": the fracture energy required and dissipated.
pub(super) fn energy_cell(m: &Measured) -> String {
    m.fracture.map_or("–".into(), |f| {
        format!("{:.2} / {:.2} mJ", f.required * 1e3, f.dissipated * 1e3)
    })
}

impl Report<'_> {
    /// What run `v` of sweep `sw` measured (runs shared by two sweeps ran once).
    pub(super) fn get(&self, sw: &Sweep, v: &Variant) -> Option<&Measured> {
        self.results.get(&v.key(&sw.scene.display().to_string()))
    }
    /// Mean speed over 10 µs after initiation, and the whole run's mean after initiation.
    pub(super) fn early_late(&self, m: &Measured) -> (Option<f64>, Option<f64>) {
        let end = m.t.last().copied().unwrap_or(0.0);
        match m.initiation() {
            Some(t0) => (
                m.mean_speed(t0, t0 + 1.0e-5),
                m.box_speed(self.a.window)
                    .iter()
                    .filter(|p| p[0] > t0 + 1.0e-5)
                    .map(|p| p[1])
                    .fold(None, |acc: Option<f64>, v| {
                        Some(acc.map_or(v, |a| a.max(v)))
                    })
                    .filter(|_| end > t0 + 1.0e-5),
            ),
            None => (None, None),
        }
    }

    /// Write the page, its figures and its CSVs.
    pub(super) fn write(&self) -> anyhow::Result<()> {
        let mut md = String::new();
        let mut runs_csv = csv_line(&RUNS_CSV_HEADER);
        let mut series_csv = csv_line(&[
            "sweep",
            "v_m_s",
            "j_ic",
            "mu",
            "law",
            "cell_mm",
            "j_radius_mm",
            "time_us",
            "box_speed_m_s",
        ]);
        self.header(&mut md);
        self.claims(&mut md);
        self.convergence(&mut md);
        self.free_tip(&mut md);
        let _ = writeln!(md, "\n## The sweeps, run by run");
        for sw in self.sweeps {
            self.section(&mut md, &mut runs_csv, &mut series_csv, sw)?;
        }
        self.footer(&mut md);
        write_file(self.figs, "runs.csv", &runs_csv)?;
        write_file(self.figs, "speeds.csv", &series_csv)?;
        write_file(&self.a.out, "rosakis.md", &md)?;
        println!(
            "wrote {} and {}",
            self.a.out.join("rosakis.md").display(),
            self.figs.display()
        );
        Ok(())
    }

    /// The section of one sweep: its speed figure, its table, its fringe pictures; its rows of
    /// `runs.csv` and `speeds.csv`.
    fn section(
        &self,
        md: &mut String,
        runs_csv: &mut String,
        series_csv: &mut String,
        sw: &Sweep,
    ) -> anyhow::Result<()> {
        let _ = writeln!(md, "\n## {}\n", sw.title);
        let svg_name = format!("speed-{}.svg", sw.id);
        let mut series = Vec::new();
        for v in &sw.runs {
            if let Some(m) = self.get(sw, v) {
                let pts = m.box_speed_us(self.a.window);
                for p in &pts {
                    series_csv.push_str(&csv_line(&[
                        sw.id.to_string(),
                        v.v.to_string(),
                        v.j_ic.to_string(),
                        v.mu.to_string(),
                        v.law.json().to_string(),
                        opt_mm(v.h),
                        opt_mm(v.radius),
                        format!("{:.2}", p[0]),
                        format!("{:.1}", p[1]),
                    ]));
                }
                series.push(((sw.legend)(v), pts));
            }
        }
        let end = sw.end.unwrap_or(self.a.end);
        let svg = speed_plot(&sw.title, &series, &self.speeds, end * 1e6);
        write_file(self.figs, &svg_name, &svg)?;
        let _ = writeln!(
            md,
            "![tip speed against time, {}](rosakis/{svg_name})\n\nSpeed = the tip's advance along the bond (its x) over a {:.0} µs moving box. Reference lines: c_R, c_S, √2·c_S, c_L.\n",
            sw.title,
            self.a.window * 1e6
        );
        let windows: Vec<(f64, f64)> = WINDOWS
            .iter()
            .copied()
            .filter(|(_, b)| b * 1e-6 <= end + 1e-12)
            .collect();
        let mut header: Vec<String> = vec!["run".into(), "initiation".into()];
        header.extend(windows.iter().map(|(a, b)| format!("{a:.0}–{b:.0} µs")));
        header.extend(SWEEP_TABLE_TAIL.iter().map(|s| s.to_string()));
        let mut rows = Vec::new();
        for v in &sw.runs {
            let Some(m) = self.get(sw, v) else { continue };
            let window_means: Vec<Option<f64>> = windows
                .iter()
                .map(|(a, b)| m.mean_speed(a * 1e-6, b * 1e-6))
                .collect();
            let status = if m.status == RunStatus::Completed {
                String::new()
            } else {
                format!(
                    " ({:?}: {})",
                    m.status,
                    m.message.clone().unwrap_or_default()
                )
            };
            let vmax = m
                .box_speed(self.a.window)
                .iter()
                .map(|p| p[1])
                .fold(0.0, f64::max);
            let mut row = vec![format!("{}{status}", (sw.legend)(v)), m.initiation_label()];
            row.extend(
                window_means
                    .iter()
                    .map(|s| s.map_or("–".to_string(), |s| format!("{s:.0}"))),
            );
            row.extend([
                speed_cell(m.mean_to_end(), &self.speeds),
                format!("{vmax:.0}"),
                format!("{:.1} mm", m.extension() * 1e3),
                negative_j_cell(m, v.j_ic),
                energy_cell(m),
                format!("{:.0} s", m.wall),
                format!("{:.2e}", m.psps),
            ]);
            rows.push(row);
            runs_csv.push_str(&csv_line(&self.csv_fields(sw, v, m)));
        }
        let header: Vec<&str> = header.iter().map(String::as_str).collect();
        md.push_str(&markdown_table(&header, &rows));
        let _ = writeln!(
            md,
            "\nMean speeds in m/s of the tip's x over 10 µs windows after impact (v/c_S = speed/{:.0}, v/c_R = speed/{:.0}); *initiation to end*: mean speed of x from the first growing sample to the end of the run; *max box speed*: the largest {:.0} µs moving-box speed of x; *tip advance*: the tip's last x less its first; *J1 < −0.1 J_Ic*: running samples (the tip advanced in that step) whose J1 is below −0.1 J_Ic; fracture energy Γ·Δa·thickness that the new surface requires and that the growth law dissipated (`summary.fracture`).",
            self.speeds.c_s,
            self.speeds.c_r,
            self.a.window * 1e6
        );
        self.fringes(md, sw)
    }

    /// The row of `runs.csv` of run `v` of sweep `sw`.
    fn csv_fields(&self, sw: &Sweep, v: &Variant, m: &Measured) -> Vec<String> {
        let opt = |x: Option<f64>| x.map_or(String::new(), |s| format!("{s:.1}"));
        let mut fields = vec![
            sw.id.to_string(),
            v.v.to_string(),
            v.j_ic.to_string(),
            v.mu.to_string(),
            v.law.json().to_string(),
            opt_mm(v.h),
            opt_mm(v.radius),
            format!("{:?}", m.status),
            m.initiation()
                .map_or(String::new(), |t| format!("{:.2}", t * 1e6)),
        ];
        fields.extend(
            WINDOWS
                .iter()
                .map(|(a, b)| opt(m.mean_speed(a * 1e-6, b * 1e-6))),
        );
        let (low, n) = m.negative_j(v.j_ic, 0.1);
        let growth = m.len.last().unwrap_or(&0.0) - m.len.first().unwrap_or(&0.0);
        fields.extend([
            opt(m.mean_to_end()),
            format!("{:.3}", m.extension() * 1e3),
            format!("{:.3}", growth * 1e3),
            n.to_string(),
            low.to_string(),
            m.fracture
                .map_or(String::new(), |f| format!("{:.6e}", f.required)),
            m.fracture
                .map_or(String::new(), |f| format!("{:.6e}", f.dissipated)),
            format!("{:.3}", m.off_bond() * 1e3),
            format!("{:.3}", m.off_material * 1e3),
            format!("{:.2}", m.wall),
            format!("{:.3}", m.psps),
            m.steps.to_string(),
            m.particles.to_string(),
        ]);
        fields
    }

    /// The command line that regenerates this page (the defaults are spelled out).
    pub(super) fn command(&self) -> String {
        let a = self.a;
        let mut c = format!(
            "cargo run --release -- study rosakis --scene {} --mini {} --out {} --end {:e} --window {:e} --jobs {} --threads {} --min-cell {:e}",
            a.scene.display(),
            a.mini.display(),
            a.out.display(),
            a.end,
            a.window,
            a.jobs,
            a.threads,
            a.min_cell
        );
        if !a.wave_all {
            c.push_str(" --wave-all false");
        }
        if !a.convergence {
            c.push_str(" --convergence false");
        }
        for (k, p) in [("fine", &a.fine), ("finest", &a.finest)] {
            if let Some(p) = p {
                let _ = write!(c, " --{k} {}", p.display());
            }
        }
        c
    }

    /// Whether the study ran with its default arguments.
    fn defaults(&self) -> bool {
        let a = self.a;
        a.scene == Path::new("scenes/rosakis-shear-coarse.json")
            && a.mini == Path::new("scenes/rosakis-shear-mini.json")
            && a.out == Path::new("docs")
            && a.end == 8.0e-5
            && a.window == 4.0e-6
            && a.jobs == fracture_solver::Parallelism::AllCores
            && a.threads == fracture_solver::Parallelism::threads(1)
            && a.min_cell == 1.25e-4
            && a.wave_all
            && a.convergence
            && a.fine.is_none()
            && a.finest.is_none()
    }

    /// "23.4 min (1,404 s)": the study's wall time.
    pub(super) fn wall_label(&self) -> String {
        format!("{:.1} min ({:.0} s)", self.wall / 60.0, self.wall)
    }

    /// The title, the wave speeds, the growth laws, how to regenerate the page and the
    /// scenes' modelling.
    fn header(&self, md: &mut String) {
        let s = &self.speeds;
        let _ = writeln!(
            md,
            "# The Rosakis shear-crack experiment: the seed's study, redone with the crack-tip equation of motion\n\n\
             This page is written by `fracture study rosakis` (see *Regenerate* below); do not edit it by hand.\n\n\
             The seed (Bardenhagen 2010) reproduces the Rosakis et al. (1999) experiment: two Homalite-100 plates \
             bonded along a weak plane, a notch along the bond from the struck edge, a steel projectile hitting that \
             edge below the notch at about 25 m/s. A compressive wave runs in the lower half only and shears the bond; \
             in the experiment the crack runs along the bond, sub-Rayleigh and then intersonic. The seed varies the impact velocity, \
             the toughness J_Ic (25, 100, 250 J/m²) and the crack-face friction μ (0, 0.1, 0.3), and plots the \
             crack-tip speed (1 µs moving box) against time.\n\n\
             Wave speeds (Homalite-100, dynamic constants, plane strain): c_L = {:.0} m/s, c_S = {:.0} m/s, \
             c_R = {:.0} m/s, √2·c_S = {:.0} m/s.\n",
            s.c_l,
            s.c_s,
            s.c_r,
            2f64.sqrt() * s.c_s
        );
        let _ = writeln!(
            md,
            "## Two growth laws\n\n\
             - **Equation of motion** (`\"speed\": \"equation_of_motion\"`, the product's default): the tip moves \
             v·Δt per step, the speed relaxing over `filter_time` (default R/(2 c_S) for the J ring's radius R; a tip starts on its unfiltered J) towards the speed at which \
             Freund's g(v)·G* = Γ(v) would hold for the measured dynamic energy release rate (the J1 of the domain \
             integral filtered over `filter_time`, G* = J1/g(v)), so that in steady state J1 = Γ(v); a process zone behind the tip dissipates the \
             fracture energy Γ per unit new area (`docs/scene-extensions.md`). For a tip-only law g(v) → 0 as v → c_R, \
             so its cracks run below c_R.\n\
             - **The seed's wave rule** (`\"speed\": \"wave\"`): while J ≥ J_Ic a tip jumps c_L·Δt per step; its speed is c_L \
             times the fraction of growing steps, and it dissipates no fracture energy (`summary.fracture.not_dissipated`). \
             It runs here only to compare with the seed and with the earlier version of this page.\n\n\
             Every sweep of the seed runs under the equation of motion; the seed's rule runs the {} on the 1 mm scene \
             and the toughness sweep and cell-size table on the reduced scene.\n",
            if self.a.wave_all {
                "same four sweeps"
            } else {
                "toughness sweep"
            }
        );
        let _ = writeln!(
            md,
            "## Regenerate\n\n```sh\n{}\n```\n\n\
             {}The study made {} distinct runs, \
             {} at a time with {} solver thread(s) each, in **{}** on this machine ({} cores; 1-minute load \
             average {} when the last run had finished, other work included).\n\n\
             Each run is the base scene with the parameters set by JSON path, exactly as \
             `fracture sweep` or `POST /api/v1/sweeps` would set them: `{P_VELOCITY}` = 0.93·v (the struck edge \
             moves at 0.93 v, impedance matching steel on Homalite), `{P_TOUGHNESS}` = J_Ic, `{P_CONTACT}` = \
             frictionless or Coulomb with μ, `{P_SPEED}` = the law; for the convergence runs `{P_CELL}` (and both \
             crack points' y moved to mid-cell of the new grid) and `{P_J_INTEGRAL}` = \
             `{{\"method\": \"domain\", \"radius\": r}}`. The seed's sweeps run {:.0} µs, the reduced scene its own 30 µs; \
             crack tips are sampled every 0.1 µs and fringe snapshots taken every 5 µs (none for the convergence runs). \
             Figures and tables go to `rosakis/` beside this page (`runs.csv`: one row per run; `speeds.csv`: the \
             plotted speed curves).\n\n\
             **Speed** everywhere on this page is measured from the tip's position along the bond, its x (the \
             bond is the line y = const, so x less the notch's x is the distance along the bond): the mean from the \
             first growing sample to the end, window means and the moving-box curves, all from x(t). The earlier \
             version of this page took them from the crack's polyline length, whose points move with the deforming \
             faces (it kept changing after an arrest).\n",
            self.command(),
            if self.defaults() {
                "(`cargo run --release -- study rosakis` with no arguments runs the same.) "
            } else {
                "(Not the defaults: `cargo run --release -- study rosakis` runs the full study.) "
            },
            self.runs,
            self.workers,
            self.a.threads,
            self.wall_label(),
            std::thread::available_parallelism().map_or(1, |n| n.get()),
            self.load.as_deref().unwrap_or("unknown"),
            self.a.end * 1e6
        );
        let _ = writeln!(
            md,
            "## The scenes and their modelling choices\n\n\
             - `scenes/rosakis-shear-coarse.json`: 1 mm cells, 2×2 particles per cell, 125,000 particles, the bond \
             at mid-cell (y = 65.5 mm). `scenes/rosakis-shear-mini.json`: the reduced scene (100 mm × 50 mm, \
             15 mm notch, bond at y = 27.5 mm mid-cell, 30 µs, 20,000 particles at 1 mm), on which the convergence \
             tables run at 1, 0.5, 0.25 and 0.125 mm with the bond moved to mid-cell of each grid (27.75, 27.625, \
             27.5625 mm) and 2×2 particles per cell.\n\
             - Block 250 mm along the bond × 125 mm across (the seed's 125 mm × 250 mm block; the bond runs along \
             the long side so the crack has room to run), one Homalite-100 body with the bond as the crack's path: \
             growth is constrained along the bond (fixed direction [1, 0]), which is how the seed models the weak \
             plane.\n\
             - Homalite-100 dynamic constants E = 5.2 GPa, ν = 0.34, ρ = 1230 kg/m³ (Samudrala & Rosakis 2003), \
             plane strain as in the seed.\n\
             - Notch: 25 mm along the bond from the struck (left) edge.\n\
             - Impact: a prescribed x velocity 0.93·v on the 25 mm patch of the left edge just below the notch, \
             ramped over 1 µs, for the projectile's pulse 2L_p/c_steel ≈ 30 µs (75 mm steel projectile); \
             after that the patch is free. The seed does not state how it loads the edge; a prescribed velocity \
             over the pulse is the impedance-matching idealisation of `reference-solutions.md`.\n\
             - Propagation: J1 of the domain integral against J_Ic, under the law the run names. The ring is the \
             default for a crack growing by the equation of motion, 1/16 of the block's shorter side (7.8 mm), the \
             process zone a third of it and the filter time R/(2 c_S) (3.1 µs), the same in metres and seconds at \
             every cell size (issue 34).\n\
             - Crack faces: frictionless or Coulomb friction μ, as the sweep says.\n\
             - Fringes: plate thickness 9.5 mm and f_σ = 23 kN/m (one fringe ≈ 2.4 MPa).\n"
        );
    }

    /// Mean speed over `span` (s) after initiation.
    pub(super) fn mean_after_init(&self, m: &Measured, span: f64) -> Option<f64> {
        let t0 = m.initiation()?;
        m.mean_speed(t0, t0 + span)
    }

    /// Run cost and why results can differ from the seed.
    fn footer(&self, md: &mut String) {
        let _ = writeln!(
            md,
            "\n## Run cost\n\n\
             The whole study: {} ({} runs, {} at a time). Wall time and particle-steps/s of every run are in the \
             tables above and in `rosakis/runs.csv` (runs that share the machine slow each other). \
             The seed's longest runs took up to 3 hours serial (its conclusions slide); the cohesive-zone AMR runs it \
             compares with, about 48 hours.\n\n\
             ## Why results can differ from the seed\n\n\
             - Time origin: this project's t = 0 is the first contact of the projectile; the wave needs about \
             10 µs to cross the 25 mm of the notch, so times here are about 10 µs later than times measured from \
             initiation. The seed's figures do not state their origin; both are given where it matters.\n\
             - The impact is idealised as a prescribed edge velocity over the pulse; the experiment's projectile \
             and the seed's loading may differ in the pulse shape and in what the edge does after the pulse.\n\
             - Growth law: the seed's rule moves a growing tip at c_L and relies on the box average, so its speed \
             is the fraction of growing steps times c_L, set by the J contour and the grid. The equation of motion \
             sets the speed from the balance G = Γ(v) of the measured dynamic G. Neither models the experiment's intersonic transition, which runs \
             through a daughter crack nucleated ahead of the tip on the bond (the Burridge–Andrews mechanism): that \
             needs a cohesive interface along the bond (issue 17), not a tip law.\n",
            self.wall_label(),
            self.runs,
            self.workers
        );
    }
}

#[cfg(test)]
mod tests {
    use super::super::StudyKind;
    use super::super::sweeps::{Law, sweeps};
    use super::*;

    /// A run that starts at 10–20 µs (later for tougher bonds), runs, pauses at 40–46 µs and
    /// runs faster.
    fn synthetic(v: &Variant) -> Measured {
        let t: Vec<f64> = (0..=800).map(|i| f64::from(i) * 1e-7).collect();
        let t0 = 1.0e-5 + v.j_ic * 2.0e-8 + v.mu * 1.0e-5;
        // Cell-size dependence: slight under the equation of motion, strong under the wave
        // rule, so that the two laws get different verdicts.
        let k = if v.law == Law::Wave { 1e6 } else { 1e5 };
        let s1 = 700.0 + 30.0 * v.v - v.j_ic + v.h.map_or(0.0, |h| k * h);
        let len: Vec<f64> = t
            .iter()
            .map(|&t| 0.025 + s1 * (t.min(4.0e-5) - t0).max(0.0) + 1.3 * s1 * (t - 4.6e-5).max(0.0))
            .collect();
        let n = t.len();
        Measured {
            status: RunStatus::Completed,
            message: None,
            wall: 12.0,
            psps: 1.0e6,
            steps: 4000,
            particles: 125_000,
            t,
            y: vec![0.0; n],
            speed: vec![1000.0; n],
            growing: (0..n).map(|i| i > 0 && len[i] > len[i - 1]).collect(),
            j1: vec![v.j_ic; n],
            j1_half: vec![v.j_ic; n],
            j1_double: vec![v.j_ic; n],
            fracture: None,
            x: len.clone(),
            len,
            fringes: Vec::new(),
            off_material: 1e-4,
            fracture_work: 0.0,
            apart: Vec::new(),
        }
    }

    /// The page for synthetic runs of every sweep: a section and a figure per sweep, a row of
    /// `runs.csv` per run, and every Markdown table rectangular.
    #[test]
    fn page_for_synthetic_runs() {
        let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
        let out = std::env::temp_dir().join(format!("fracture-lab-study-{}", std::process::id()));
        let a = StudyArgs {
            kind: StudyKind::Rosakis,
            scene: scenes.join("rosakis-shear-coarse.json"),
            fine: Some(scenes.join("rosakis-shear.json")),
            finest: None,
            mini: scenes.join("rosakis-shear-mini.json"),
            out: out.clone(),
            end: 8.0e-5,
            window: 4.0e-6,
            threads: fracture_solver::Parallelism::AllCores,
            jobs: fracture_solver::Parallelism::AllCores,
            wave_all: true,
            convergence: true,
            min_cell: 1.25e-4,
            cohesive: false,
            cohesive_only: false,
            cohesive_scene: scenes.join("rosakis-shear-cohesive.json"),
            cohesive_min_cell: 2.5e-4,
            j_radius: 3.0e-3,
            zone: 1.0e-3,
            filter_time: 1.2e-6,
        };
        let sweeps = sweeps(&a).expect("the scenes are readable");
        let mut results = HashMap::new();
        for sw in &sweeps {
            for v in &sw.runs {
                results.insert(v.key(&sw.scene.display().to_string()), synthetic(v));
            }
        }
        let figs = out.join("rosakis");
        let report = Report {
            a: &a,
            sweeps: &sweeps,
            results: &results,
            speeds: WaveSpeeds {
                c_l: 2540.0,
                c_s: 1310.0,
                c_r: 1210.0,
            },
            figs: &figs,
            load: None,
            wall: 600.0,
            runs: 40,
            workers: 2,
        };
        report.write().expect("the page is written");
        let read = |p: &Path| std::fs::read_to_string(p).expect("written");
        let md = read(&out.join("rosakis.md"));
        for sw in &sweeps {
            assert!(md.contains(&format!("\n## {}\n", sw.title)), "{}", sw.title);
            let svg = read(&figs.join(format!("speed-{}.svg", sw.id)));
            assert_eq!(svg.matches("<path d=\"M").count(), sw.runs.len() + 1);
        }
        let runs: usize = sweeps.iter().map(|s| s.runs.len()).sum();
        assert_eq!(read(&figs.join("runs.csv")).lines().count(), 1 + runs);
        // The convergence tables and their verdicts are on the page.
        assert!(md.contains("### Crack speed against the cell size"));
        assert!(md.contains("### Crack speed against the J domain radius"));
        assert!(md.contains("10.0 min (600 s)"));
        assert!(!md.contains("Stale"));
        let verdict_of = |law: &str| -> Vec<String> {
            md.lines()
                .filter(|l| {
                    ["25", "250"]
                        .iter()
                        .any(|j| l.starts_with(&format!("| {j} J/m² | {law} |")))
                })
                .filter_map(|l| {
                    l.trim_end_matches(" |")
                        .rsplit(" | ")
                        .next()
                        .map(String::from)
                })
                .collect()
        };
        assert_eq!(verdict_of("equation of motion"), ["met", "met"]);
        assert_eq!(verdict_of("seed's wave rule"), ["not met", "not met"]);
        let mut columns = None;
        for line in md.lines() {
            if line.starts_with('|') {
                let n = line.matches('|').count();
                assert_eq!(*columns.get_or_insert(n), n, "{line}");
            } else {
                columns = None;
            }
        }
        let _ = std::fs::remove_dir_all(&out);
    }
}
