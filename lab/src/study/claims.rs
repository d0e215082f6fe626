//! The claims section of the page: each claim of the seed against the measurements, with the
//! rule of its verdict, per scene; and the convergence table in the cell size.

use std::fmt::Write as _;

use super::measure::slow_down;
use super::report::{Report, speed_cell};
use super::sweeps::{Sweep, cells_label, scale_suffix};
use crate::report::{markdown_header, markdown_row, markdown_table};

impl Report<'_> {
    /// The claims section: one table per scene, then the convergence table.
    pub(super) fn claims(&self, md: &mut String) {
        let _ = writeln!(
            md,
            "## The seed's claims against this project's measurements\n\n\
             Speeds are mean crack-tip speeds from the crack length; \"early\" is the mean over the first 10 µs \
             after initiation, \"late\" the largest {:.0} µs moving-box speed after that. Verdicts are computed \
             from the numbers by the rule stated in each row.\n",
            self.a.window * 1e6
        );
        let _ = writeln!(md, "### {} (all four sweeps)\n", self.a.scene.display());
        self.claims_for(md, "");
        if let Some(fine) = &self.a.fine {
            let _ = writeln!(md, "\n### {} (all four sweeps)\n", fine.display());
            self.claims_for(md, "-fine");
        }
        if let Some(finest) = &self.a.finest {
            let _ = writeln!(
                md,
                "\n### {} (J_Ic = 25 and 250 J/m² only)\n",
                finest.display()
            );
            self.claims_for(md, "-finest");
        }
        self.convergence(md);
    }

    /// The claims table of the sweeps run on one scene (`suffix`: see `scale_suffix`).
    fn claims_for(&self, md: &mut String, suffix: &str) {
        let s = &self.speeds;
        let mut rows: Vec<Vec<String>> = Vec::new();
        // 1. Speed rises with impact velocity and saturates near 1600 m/s.
        if let Some(sw) = self.sweep(&format!("velocity{suffix}")) {
            let pts: Vec<(f64, Option<f64>)> = sw
                .runs
                .iter()
                .filter_map(|v| {
                    self.get(sw, v)
                        .map(|m| (v.v, self.mean_after_init(m, 2.0e-5)))
                })
                .collect();
            let vals: Vec<f64> = pts.iter().filter_map(|p| p.1).collect();
            let rises = vals.len() == pts.len()
                && vals.len() >= 2
                && vals.windows(2).all(|w| w[1] >= 0.97 * w[0]);
            let top = vals.last().copied().unwrap_or(0.0);
            let before = vals
                .len()
                .checked_sub(2)
                .and_then(|i| vals.get(i))
                .copied()
                .unwrap_or(0.0);
            let saturates = top > 0.0 && (top - before) / top < 0.1;
            let near = (1400.0..=1800.0).contains(&top);
            rows.push(claim(
                "Speed rises with impact velocity and saturates near 1600 m/s (J_Ic = 25, frictionless)",
                "mean speed over 20 µs after initiation: each within 3 % or above the previous; the last two within 10 %; the fastest in 1400–1800 m/s",
                pts.iter()
                    .map(|(v, s)| format!(
                        "{v} m/s: {}",
                        s.map_or("no growth".into(), |s| format!("{s:.0}"))
                    ))
                    .collect::<Vec<_>>()
                    .join("; "),
                verdict(
                    rises && saturates && near,
                    &[
                        (rises, "rises"),
                        (saturates, "saturates"),
                        (near, "near 1600 m/s"),
                    ],
                ),
            ));
            // 2. Slow-down near 20 µs.
            if let Some(m) = sw
                .runs
                .iter()
                .find(|v| v.v == 25.0)
                .and_then(|v| self.get(sw, v))
            {
                let (t_dip, drop) = slow_down(m, self.a.window);
                let init = m.initiation().unwrap_or(0.0);
                let ok = t_dip.is_some_and(|t| {
                    (t - init - 2.0e-5).abs() < 7.0e-6 || (t - 2.0e-5).abs() < 7.0e-6
                });
                rows.push(claim(
                    "\"Break-point\" slow-down or arrest near t = 20 µs (J_Ic = 25, 25 m/s)",
                    "first fall of the moving-box speed by ≥ 30 % from its running peak; agrees if within 7 µs of 20 µs after impact or after initiation",
                    t_dip.map_or("no such fall".into(), |t| format!(
                        "speed falls {:.0} % at {:.1} µs after impact ({:.1} µs after initiation at {:.1} µs)",
                        drop * 100.0,
                        t * 1e6,
                        (t - init) * 1e6,
                        init * 1e6
                    )),
                    if ok {
                        "agrees"
                    } else if t_dip.is_some() {
                        "differs: at another time"
                    } else {
                        "differs: no slow-down"
                    },
                ));
            }
        }
        // 3. Higher J_Ic is slower; 4. J_Ic = 250: ~1000 then ~1800 m/s.
        if let Some(sw) = self.sweep(&format!("toughness{suffix}")) {
            let pts: Vec<(f64, Option<f64>)> = sw
                .runs
                .iter()
                .filter_map(|v| {
                    self.get(sw, v)
                        .map(|m| (v.j_ic, self.mean_after_init(m, 3.0e-5)))
                })
                .collect();
            let vals: Vec<f64> = pts.iter().filter_map(|p| p.1).collect();
            let falls =
                vals.len() == pts.len() && vals.len() >= 2 && vals.windows(2).all(|w| w[1] < w[0]);
            rows.push(claim(
                "Higher J_Ic is slower (25 m/s, frictionless)",
                "mean speed over 30 µs after initiation falls strictly with J_Ic",
                pts.iter()
                    .map(|(j, s)| {
                        format!(
                            "J_Ic {j}: {}",
                            s.map_or("no growth".into(), |s| format!("{s:.0}"))
                        )
                    })
                    .collect::<Vec<_>>()
                    .join("; "),
                if falls { "agrees" } else { "differs" },
            ));
            if let Some(m) = sw
                .runs
                .iter()
                .find(|v| v.j_ic == 250.0)
                .and_then(|v| self.get(sw, v))
            {
                let (early, late) = self.early_late(m);
                let e_ok = early.is_some_and(|e| (800.0..=1250.0).contains(&e));
                let l_ok = late.is_some_and(|l| (1600.0..=2000.0).contains(&l));
                rows.push(claim(
                    "J_Ic = 250: first ~1000 m/s, later ~1800 m/s (the \"transition case\")",
                    "early speed in 800–1250 m/s, late speed in 1600–2000 m/s",
                    format!(
                        "early {}, late {}",
                        speed_cell(early, s),
                        speed_cell(late, s)
                    ),
                    verdict(e_ok && l_ok, &[(e_ok, "early ~1000"), (l_ok, "late ~1800")]),
                ));
            }
        }
        // 5. Friction delays and slows the crack, mostly at low impact speed.
        let fr = |id: &str| -> Option<Vec<FrictionRow>> {
            let sw = self.sweep(id)?;
            Some(
                sw.runs
                    .iter()
                    .filter_map(|v| {
                        self.get(sw, v)
                            .map(|m| (v.mu, m.initiation(), self.mean_after_init(m, 3.0e-5)))
                    })
                    .collect(),
            )
        };
        if let (Some(fast), Some(slow)) = (
            fr(&format!("friction{suffix}")),
            fr(&format!("friction-slow{suffix}")),
        ) {
            let effect = |rows: &[FrictionRow]| -> (f64, f64) {
                // Delay (s) and relative slow-down of μ = 0.3 against μ = 0.
                let (Some(a), Some(b)) = (rows.first(), rows.last()) else {
                    return (0.0, 0.0);
                };
                let delay = match (a.1, b.1) {
                    (Some(x), Some(y)) => y - x,
                    (Some(_), None) => f64::INFINITY,
                    _ => 0.0,
                };
                let slow = match (a.2, b.2) {
                    (Some(x), Some(y)) if x > 0.0 => 1.0 - y / x,
                    (Some(_), None) => 1.0,
                    _ => 0.0,
                };
                (delay, slow)
            };
            let (d_fast, s_fast) = effect(&fast);
            let (d_slow, s_slow) = effect(&slow);
            let delays = d_fast > 0.0 || d_slow > 0.0;
            let slows = s_fast > 0.0 || s_slow > 0.0;
            let mostly_low = d_slow >= d_fast && s_slow >= s_fast;
            let show = |rows: &[FrictionRow]| {
                rows.iter()
                    .map(|(mu, t, s)| {
                        format!(
                            "μ {mu}: {} / {}",
                            t.map_or("no growth".into(), |t| format!("{:.1} µs", t * 1e6)),
                            s.map_or("–".into(), |s| format!("{s:.0} m/s"))
                        )
                    })
                    .collect::<Vec<_>>()
                    .join("; ")
            };
            rows.push(claim(
                "Friction delays and slows the crack, mostly at low impact speed (J_Ic = 250)",
                "μ = 0.3 against μ = 0: later initiation and lower mean speed over 30 µs after initiation; both effects larger at 15 m/s than at 25 m/s",
                format!("25 m/s: {}; 15 m/s: {}", show(&fast), show(&slow)),
                verdict(
                    delays && slows && mostly_low,
                    &[
                        (delays, "delays"),
                        (slows, "slows"),
                        (mostly_low, "mostly at low speed"),
                    ],
                ),
            ));
        }
        // Never faster than c_L, always on the bond.
        let mut fastest: f64 = 0.0;
        let mut off: f64 = 0.0;
        let mut raw: f64 = 0.0;
        for sw in self
            .sweeps
            .iter()
            .filter(|sw| scale_suffix(sw.id) == suffix && sw.end.is_none())
        {
            for v in &sw.runs {
                if let Some(m) = self.get(sw, v) {
                    fastest = m.speed.iter().copied().fold(fastest, f64::max);
                    off = off.max(m.off_material);
                    raw = raw.max(m.off_bond());
                }
            }
        }
        rows.push(claim(
            "(method) the tip never outruns c_L; the crack runs along the bond",
            "largest tip speed of the solver (1 µs moving box, `crack_tips.csv` `speed`) ≤ 1.02 c_L (a growing tip advances c_L·Δt per step and also moves with the material); tip within 0.5 mm of the bond's material line (the crack line moves with the material, so the tip's y is compared with the initial bond y plus the material's y displacement at the tip, every 5 µs); the largest distance from the initial bond line is shown too",
            format!(
                "{:.0} m/s ({:.3} c_L); {:.3} mm from the material line ({:.3} mm from the initial line)",
                fastest,
                fastest / s.c_l,
                off * 1e3,
                raw * 1e3
            ),
            if fastest <= 1.02 * s.c_l && off < 0.5e-3 {
                "holds"
            } else {
                "fails"
            },
        ));
        md.push_str(&markdown_table(
            &["seed's claim", "rule", "measured", "verdict"],
            &rows,
        ));
    }

    /// The cell-size table: the toughness sweep's J_Ic = 25 and 250 runs on every scene that
    /// ran them, side by side, with the change between the two finest cell sizes.
    fn convergence(&self, md: &mut String) {
        let scales: Vec<(&Sweep, String)> = ["toughness", "toughness-fine", "toughness-finest"]
            .iter()
            .filter_map(|id| self.sweep(id))
            .map(|sw| {
                let cells =
                    cells_label(&sw.scene).unwrap_or_else(|_| sw.scene.display().to_string());
                (sw, cells)
            })
            .collect();
        if scales.len() < 2 {
            return;
        }
        let _ = writeln!(
            md,
            "\n### Convergence in the cell size (25 m/s, frictionless)\n\n\
             The same runs at each cell size. *Early*: mean speed over the first 10 µs after initiation; \
             *to end*: mean from initiation to the end of the run; *late*: the largest {:.0} µs moving-box \
             speed after the first 10 µs; *off line*: largest distance of the tip from the bond's material line.\n",
            self.a.window * 1e6
        );
        md.push_str(&markdown_header(&[
            "J_Ic",
            "cells",
            "initiation",
            "early",
            "to end",
            "late",
            "off line",
        ]));
        for j_ic in [25.0, 250.0] {
            // (cells, mean to end) of each scale that has this run, coarse to fine.
            let mut to_ends: Vec<(String, f64)> = Vec::new();
            for (sw, cells) in &scales {
                let Some(v) = sw.runs.iter().find(|v| v.j_ic == j_ic) else {
                    continue;
                };
                let Some(m) = self.get(sw, v) else { continue };
                let (early, late) = self.early_late(m);
                let to_end = m.mean_to_end();
                if let Some(e) = to_end {
                    to_ends.push((cells.clone(), e));
                }
                let f = |x: Option<f64>| speed_cell(x, &self.speeds);
                md.push_str(&markdown_row(&[
                    format!("{j_ic} J/m²"),
                    cells.clone(),
                    m.initiation_label(),
                    f(early),
                    f(to_end),
                    f(late),
                    format!("{:.3} mm", m.off_material * 1e3),
                ]));
            }
            // The change between the two finest sizes, its empty cells written `| |` as on the
            // committed page (`markdown_row` writes them `|  |`).
            if let [.., (c1, a), (c2, b)] = to_ends.as_slice() {
                let _ = writeln!(
                    md,
                    "| | {c1} → {c2} | | | {:+.1} % | | |",
                    100.0 * (b - a) / a
                );
            }
        }
    }
}

/// A row of the claims table: the seed's claim, the rule of the verdict, what was measured,
/// the verdict.
fn claim(claim: &str, rule: &str, measured: String, verdict: impl Into<String>) -> Vec<String> {
    vec![claim.into(), rule.into(), measured, verdict.into()]
}

/// One run of a friction sweep: μ, initiation time (s), mean speed after initiation (m/s).
type FrictionRow = (f64, Option<f64>, Option<f64>);

/// "agrees", or "differs: …" listing the parts that failed.
fn verdict(all: bool, parts: &[(bool, &str)]) -> String {
    if all {
        "agrees".into()
    } else {
        let held: Vec<&str> = parts.iter().filter(|p| p.0).map(|p| p.1).collect();
        let failed: Vec<&str> = parts.iter().filter(|p| !p.0).map(|p| p.1).collect();
        if held.is_empty() {
            format!("differs (not {})", failed.join(", not "))
        } else {
            format!(
                "partly: {} hold; not {}",
                held.join(", "),
                failed.join(", not ")
            )
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn verdict_names_what_failed() {
        assert_eq!(verdict(true, &[(true, "a")]), "agrees");
        assert_eq!(
            verdict(false, &[(true, "rises"), (false, "saturates")]),
            "partly: rises hold; not saturates"
        );
    }
}
