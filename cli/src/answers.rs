//! What `fracture submit --wait` and `fracture sweep --wait` print when the work has ended:
//! a job's result summary (status, wall time, steps, the peak and mean speed of every crack
//! tip, the dashboard URL) and a sweep's table (one row per combination). Pure functions of
//! the API's documents, so they are tested without a server.

use std::collections::BTreeMap;

use fracture_api::jobs::JobInfo;
use fracture_api::results::{CrackTipRow, Summary};
use fracture_api::sweep::{SweepInfo, SweepJob, value_text};

/// The speed record of one crack tip over a run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TipStats {
    /// Index of the crack in the scene.
    pub crack: u32,
    /// 0: the start of the crack's polyline, 1: its end.
    pub tip: u32,
    /// Samples of this tip.
    pub samples: usize,
    /// Largest `speed` sample (m/s); NaN when no sample has a speed.
    pub peak_speed: f64,
    /// Time of the peak (s).
    pub peak_time: f64,
    /// Distance the tip moved (m): the sum of the steps between consecutive samples.
    pub travelled: f64,
    /// Mean speed (m/s): `travelled` over the time between the first and last samples; NaN
    /// with fewer than two samples.
    pub mean_speed: f64,
}

/// The speed record of every tip in `rows` (rows in time order, as the API returns them),
/// ordered by crack and tip.
pub fn tip_stats(rows: &[CrackTipRow]) -> Vec<TipStats> {
    let mut by_tip: BTreeMap<(u32, u32), Vec<&CrackTipRow>> = BTreeMap::new();
    for r in rows {
        by_tip.entry((r.crack, r.tip)).or_default().push(r);
    }
    by_tip
        .into_iter()
        .map(|((crack, tip), rows)| {
            let mut peak_speed = f64::NAN;
            let mut peak_time = f64::NAN;
            for r in &rows {
                if r.speed.is_finite() && (peak_speed.is_nan() || r.speed > peak_speed) {
                    peak_speed = r.speed;
                    peak_time = r.time;
                }
            }
            let travelled: f64 = rows
                .windows(2)
                .map(|w| (w[1].x - w[0].x).hypot(w[1].y - w[0].y))
                .filter(|d| d.is_finite())
                .sum();
            let span = match (rows.first(), rows.last()) {
                (Some(a), Some(b)) => b.time - a.time,
                _ => 0.0,
            };
            let mean_speed = if span > 0.0 {
                travelled / span
            } else {
                f64::NAN
            };
            TipStats {
                crack,
                tip,
                samples: rows.len(),
                peak_speed,
                peak_time,
                travelled,
                mean_speed,
            }
        })
        .collect()
}

/// A speed in m/s for a table, `–` when undefined.
fn speed(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.1} m/s")
    } else {
        "–".into()
    }
}

/// Seconds for a table, `–` when unknown.
fn seconds(v: Option<f64>) -> String {
    match v {
        Some(s) if s.is_finite() => format!("{s:.2} s"),
        _ => "–".into(),
    }
}

/// The dashboard page of a job on the server at `base`.
pub fn dashboard_url(base: &str, id: &str) -> String {
    format!("{}/#/runs/{id}", base.trim_end_matches('/'))
}

/// The dashboard page of a sweep on the server at `base`.
pub fn sweep_dashboard_url(base: &str, id: &str) -> String {
    format!("{}/#/sweeps/{id}", base.trim_end_matches('/'))
}

/// The result summary of an ended job, several lines ending in a newline.
pub fn job_summary(job: &JobInfo, tips: &[TipStats], dashboard: &str) -> String {
    let mut s = format!("job {}: {} ({})\n", job.id, job.status.as_str(), job.name);
    if let Some(m) = job.message.as_deref().filter(|m| !m.is_empty()) {
        s.push_str(&format!("  message: {m}\n"));
    }
    match &job.summary {
        Some(sum) => {
            s.push_str(&format!(
                "  wall time: {} ({} threads, {:.3e} particle-steps/s)\n",
                seconds(Some(sum.wall_seconds)),
                sum.threads,
                sum.particle_steps_per_second
            ));
            s.push_str(&format!(
                "  steps: {} (t = {:.4e} s, {} particles)\n",
                sum.steps, sum.sim_time, sum.particles
            ));
        }
        None => {
            let p = job.progress.unwrap_or_default();
            s.push_str("  wall time: – (no summary)\n");
            s.push_str(&format!(
                "  steps: {} (t = {:.4e} s, {:.0}% of the end time)\n",
                p.step,
                p.sim_time,
                100.0 * p.fraction
            ));
        }
    }
    // Rows past the scene's cracks are its interfaces' failure fronts (run-output.md).
    let n_cracks = job.scene.as_ref().map_or(usize::MAX, |sc| sc.crack_count());
    match &job.summary {
        Some(sum) if !sum.tips.is_empty() => s.push_str(&results_text(sum, n_cracks)),
        _ if tips.is_empty() => s.push_str("  crack tips: none recorded\n"),
        _ => {
            s.push_str("  crack tips (peak speed; mean = distance moved / time):\n");
            for t in tips {
                let at = if t.peak_time.is_finite() {
                    format!(" at t = {:.3e} s", t.peak_time)
                } else {
                    String::new()
                };
                s.push_str(&format!(
                    "    {}: peak {}{at}, mean {}, moved {:.3} mm ({} samples)\n",
                    tip_name(t.crack, t.tip, n_cracks),
                    speed(t.peak_speed),
                    speed(t.mean_speed),
                    1e3 * t.travelled,
                    t.samples
                ));
            }
        }
    }
    s.push_str(&format!("  dashboard: {dashboard}\n"));
    s
}

/// "crack C tip T", or "interface I front" for rows past the scene's `n_cracks` cracks.
fn tip_name(crack: u32, tip: u32, n_cracks: usize) -> String {
    match (crack as usize).checked_sub(n_cracks) {
        Some(i) => format!("interface {i} front"),
        None => format!("crack {crack} tip {tip}"),
    }
}

/// `v · scale` with four decimals, `–` when undefined.
fn num(v: f64, scale: f64) -> String {
    if v.is_finite() {
        format!("{:.4}", v * scale)
    } else {
        "–".into()
    }
}

/// The results of a run (`summary.tips` and `summary.references`), several indented lines
/// ending in a newline: per tip, K and J (final and peak), initiation, growth and speeds; then
/// each reference value against the run's. `n_cracks`: the scene's cracks (rows past them
/// are interface fronts).
pub fn results_text(sum: &Summary, n_cracks: usize) -> String {
    let mut s = String::new();
    let window = sum.tips.first().map_or(0.0, |t| t.speed_window);
    s.push_str(&format!(
        "  results (K in MPa·√m, J in J/m²; peak speeds averaged over {:.1} µs):\n",
        window * 1e6
    ));
    for t in &sum.tips {
        s.push_str(&format!(
            "    {}: K_I {} (peak {}), K_II {} (peak {}), J1 {} (peak {})\n",
            tip_name(t.crack, t.tip, n_cracks),
            num(t.k1_final, 1e-6),
            num(t.k1_peak, 1e-6),
            num(t.k2_final, 1e-6),
            num(t.k2_peak, 1e-6),
            num(t.j1_final, 1.0),
            num(t.j1_peak, 1.0),
        ));
        if t.initiation_time.is_finite() {
            s.push_str(&format!(
                "      initiated at {:.3} µs, grew {:.3} mm, mean {} while running, peak {}; ends at ({:.3}, {:.3}) mm\n",
                t.initiation_time * 1e6,
                t.growth * 1e3,
                speed(t.mean_speed),
                speed(t.peak_speed),
                t.x * 1e3,
                t.y * 1e3
            ));
        } else {
            s.push_str("      did not grow\n");
        }
    }
    if !sum.references.is_empty() {
        s.push_str("  reference values:\n");
        for r in &sum.references {
            let q = serde_json::to_value(r.quantity)
                .ok()
                .and_then(|v| v.as_str().map(String::from))
                .unwrap_or_default();
            let at = serde_json::to_value(r.at)
                .ok()
                .and_then(|v| v.as_str().map(String::from))
                .unwrap_or_default();
            let err = if r.relative_error.is_finite() {
                format!("{:+.2} %", 100.0 * r.relative_error)
            } else {
                "–".into()
            };
            let verdict = match (r.within, r.tolerance) {
                (Some(true), Some(t)) => format!(", within {:.3} %", 100.0 * t),
                (Some(false), Some(t)) => format!(", OUTSIDE {:.3} %", 100.0 * t),
                _ => String::new(),
            };
            let src = if r.source.is_empty() {
                String::new()
            } else {
                format!(" ({})", r.source)
            };
            let tip = r.tip.map_or(String::new(), |k| format!(" tip {k}"));
            s.push_str(&format!(
                "    {q} ({at}) of crack {}{tip}: {:.6e} against {:.6e}{src}: {err}{verdict}\n",
                r.crack, r.measured, r.value
            ));
        }
    }
    s
}

/// The peak speed over all tips of a run, NaN when none has one.
pub fn peak_speed(tips: &[TipStats]) -> f64 {
    tips.iter()
        .map(|t| t.peak_speed)
        .filter(|v| v.is_finite())
        .fold(f64::NAN, f64::max)
}

/// The table of an ended sweep: one row per combination (its parameter values, status, peak
/// tip speed, wall time, job id). `peaks` holds the peak speed of each job by id (see
/// [`peak_speed`]); a job missing there shows `–`.
pub fn sweep_table(s: &SweepInfo, peaks: &BTreeMap<String, f64>) -> String {
    let params: Vec<String> = s.parameters.iter().map(|p| p.path.clone()).collect();
    let mut header: Vec<String> = params.clone();
    header.extend(["status", "peak speed", "wall time", "job"].map(String::from));
    let mut rows = vec![header];
    let jobs: Vec<&SweepJob> = s.jobs.iter().flatten().collect();
    for j in jobs {
        let mut row: Vec<String> = params
            .iter()
            .map(|p| {
                j.values
                    .get(p)
                    .map(value_text)
                    .unwrap_or_else(|| "–".into())
            })
            .collect();
        row.push(j.status.as_str().to_string());
        row.push(speed(peaks.get(&j.id).copied().unwrap_or(f64::NAN)));
        row.push(seconds(j.summary.as_ref().map(|x| x.wall_seconds)));
        row.push(j.id.clone());
        rows.push(row);
    }
    let cols = rows.first().map(Vec::len).unwrap_or(0);
    let widths: Vec<usize> = (0..cols)
        .map(|c| {
            rows.iter()
                .map(|r| r.get(c).map(|x| x.chars().count()).unwrap_or(0))
                .max()
                .unwrap_or(0)
        })
        .collect();
    let mut out = String::new();
    for r in &rows {
        let cells: Vec<String> = r
            .iter()
            .zip(&widths)
            .map(|(c, w)| format!("{c:<w$}", w = *w))
            .collect();
        out.push_str(cells.join("  ").trim_end());
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(time: f64, tip: u32, x: f64, speed: f64) -> CrackTipRow {
        CrackTipRow {
            time,
            crack: 0,
            tip,
            x,
            y: 0.0,
            speed,
            ..CrackTipRow::default()
        }
    }

    #[test]
    fn tip_stats_take_the_peak_and_the_distance_over_time() {
        let rows = [
            row(0.0, 1, 0.010, 0.0),
            row(0.0, 0, 0.000, 0.0),
            row(1e-6, 1, 0.011, 800.0),
            row(2e-6, 1, 0.013, f64::NAN),
            row(3e-6, 1, 0.014, 600.0),
        ];
        let t = tip_stats(&rows);
        assert_eq!(t.len(), 2);
        assert_eq!((t[0].crack, t[0].tip, t[0].samples), (0, 0, 1));
        assert!(t[0].mean_speed.is_nan());
        assert_eq!((t[1].tip, t[1].samples), (1, 4));
        assert_eq!(t[1].peak_speed, 800.0);
        assert_eq!(t[1].peak_time, 1e-6);
        assert!((t[1].travelled - 0.004).abs() < 1e-12);
        assert!((t[1].mean_speed - 0.004 / 3e-6).abs() < 1e-6);
        assert_eq!(peak_speed(&t), 800.0);
        assert!(peak_speed(&[]).is_nan());
    }
}
