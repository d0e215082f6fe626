//! The per-tip results summary of a run (`summary.tips`) and its comparison with the scene's
//! reference values (`summary.references`).
//!
//! [`TipSummaryBuilder`] reads the crack-tip rows as they are produced (O(tips) memory plus
//! one speed window of samples per tip), so the run loop, a run folder's sink and the
//! service (from its stored rows) all build the same summary.

use std::collections::{BTreeMap, VecDeque};

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::results::CrackTipRow;
use crate::scene::{Reference, ReferenceAt, ReferenceQuantity, Scene};

/// The share of the run's end time over which [`ReferenceAt::LateMean`] averages: the last
/// 20 % (a damped static problem has settled there; the centre-crack tests average the same).
pub const LATE_FRACTION: f64 = 0.2;

/// The smallest window (s) over which the summary's peak speed is averaged. The rows' own
/// `speed` averages over `output.speed_window` (1 µs by default), which for a tip that
/// advances a cell at a time can be one cell per sample; 2 µs spans several advances at
/// any speed a tip reaches on the cell sizes the examples use.
pub const MIN_SPEED_WINDOW: f64 = 2.0e-6;

/// What one crack tip (or cohesive interface front) did over a run. Equality treats NaN (an
/// undefined value) as equal to NaN, so a summary equals its own copy.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema, utoipa::ToSchema)]
pub struct TipSummary {
    /// Index of the crack (scene cracks first, then interfaces), as `crack_tips.csv`.
    pub crack: u32,
    /// 0: the start of the crack's polyline, 1: its end.
    pub tip: u32,
    /// Number of samples of this tip.
    pub samples: u64,
    /// Final position x (m).
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub x: f64,
    /// Final position y (m).
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub y: f64,
    /// Time of the first sample at which the tip advanced (s); null when it never did.
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub initiation_time: f64,
    /// Crack growth at this tip (m): final length − first length.
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub growth: f64,
    /// J1 at the last sample where it was defined (J/m²).
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub j1_final: f64,
    /// Largest J1 of the run (J/m²).
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub j1_peak: f64,
    /// K_I at the last sample where it was defined (Pa·√m).
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub k1_final: f64,
    /// K_I of largest magnitude over the run, with its sign (Pa·√m).
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub k1_peak: f64,
    /// K_II at the last sample where it was defined (Pa·√m).
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub k2_final: f64,
    /// K_II of largest magnitude over the run, with its sign (Pa·√m).
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub k2_peak: f64,
    /// Mean of J1 over the last [`LATE_FRACTION`] of the scene's end time (J/m²); null when
    /// the run did not get there.
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub j1_late_mean: f64,
    /// Mean of K_I over the same window (Pa·√m).
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub k1_late_mean: f64,
    /// Mean of K_II over the same window (Pa·√m).
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub k2_late_mean: f64,
    /// Mean speed while running (m/s): the advance from the last sample at rest to the last
    /// sample at which the tip advanced, over that time; null when it did not run.
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub mean_speed: f64,
    /// Largest speed averaged over `speed_window` (m/s): the advance along the crack path
    /// over that window divided by it; null when the tip never advanced.
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub peak_speed: f64,
    /// The window of `peak_speed` (s): the scene's `output.speed_window` or
    /// [`MIN_SPEED_WINDOW`], whichever is longer.
    pub speed_window: f64,
}

/// A scene's reference value compared with the run (`summary.references`). Equality treats
/// NaN as equal to NaN, as [`TipSummary`]'s.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema, utoipa::ToSchema)]
pub struct ReferenceCheck {
    /// What was compared.
    pub quantity: ReferenceQuantity,
    /// Which value of the run.
    pub at: ReferenceAt,
    /// The crack (scene cracks first, then interfaces).
    pub crack: u32,
    /// The tip compared (the one named, or the crack's first tip with samples).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tip: Option<u32>,
    /// The reference value (SI units of the quantity).
    pub value: f64,
    /// The run's value; null when the run has none (no samples, never initiated …).
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub measured: f64,
    /// (measured − value) / |value|; null when either is undefined or the value is 0.
    #[serde(deserialize_with = "crate::nan::f64_or_nan")]
    #[schemars(with = "Option<f64>")]
    #[schema(value_type = Option<f64>)]
    pub relative_error: f64,
    /// Where the reference comes from.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub source: String,
    /// The relative tolerance the scene allows, when it gives one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<f64>,
    /// Whether |relative_error| ≤ tolerance; null without a tolerance or a measured value.
    #[serde(default)]
    pub within: Option<bool>,
}

/// Equal numbers, or both NaN.
fn same(a: f64, b: f64) -> bool {
    a == b || (a.is_nan() && b.is_nan())
}

impl TipSummary {
    /// The numbers of the summary, in field order.
    fn numbers(&self) -> [f64; 18] {
        [
            self.x,
            self.y,
            self.initiation_time,
            self.growth,
            self.j1_final,
            self.j1_peak,
            self.k1_final,
            self.k1_peak,
            self.k2_final,
            self.k2_peak,
            self.j1_late_mean,
            self.k1_late_mean,
            self.k2_late_mean,
            self.mean_speed,
            self.peak_speed,
            self.speed_window,
            f64::from(self.crack),
            f64::from(self.tip),
        ]
    }
}

impl PartialEq for TipSummary {
    fn eq(&self, o: &Self) -> bool {
        self.samples == o.samples
            && self
                .numbers()
                .iter()
                .zip(o.numbers())
                .all(|(&a, b)| same(a, b))
    }
}

impl PartialEq for ReferenceCheck {
    fn eq(&self, o: &Self) -> bool {
        (self.quantity, self.at, self.crack, self.tip) == (o.quantity, o.at, o.crack, o.tip)
            && (&self.source, self.tolerance, self.within) == (&o.source, o.tolerance, o.within)
            && same(self.value, o.value)
            && same(self.measured, o.measured)
            && same(self.relative_error, o.relative_error)
    }
}

/// Running statistics of one tip.
#[derive(Debug, Clone)]
struct Acc {
    samples: u64,
    last: CrackTipRow,
    first_length: f64,
    initiation: f64,
    last_growth_time: f64,
    /// Time of the last sample before initiation (at rest).
    rest_time: f64,
    length_at_initiation: f64,
    j1_final: f64,
    k1_final: f64,
    k2_final: f64,
    j1_peak: f64,
    k1_peak: f64,
    k2_peak: f64,
    late: [f64; 3],
    late_n: [u64; 3],
    /// (time, length) of the samples within the speed window.
    window: VecDeque<(f64, f64)>,
    peak_speed: f64,
}

/// Largest magnitude, keeping the sign; NaN never wins.
fn peak_abs(best: f64, x: f64) -> f64 {
    if x.is_finite() && (!best.is_finite() || x.abs() > best.abs()) {
        x
    } else {
        best
    }
}

impl Acc {
    fn new(row: &CrackTipRow) -> Acc {
        Acc {
            samples: 0,
            last: *row,
            first_length: row.length,
            initiation: f64::NAN,
            last_growth_time: f64::NAN,
            rest_time: f64::NAN,
            length_at_initiation: f64::NAN,
            j1_final: f64::NAN,
            k1_final: f64::NAN,
            k2_final: f64::NAN,
            j1_peak: f64::NAN,
            k1_peak: f64::NAN,
            k2_peak: f64::NAN,
            late: [0.0; 3],
            late_n: [0; 3],
            window: VecDeque::new(),
            peak_speed: f64::NAN,
        }
    }

    fn push(&mut self, row: &CrackTipRow, window: f64, late_from: f64) {
        if !self.first_length.is_finite() {
            self.first_length = row.length;
        }
        // The solver's own flag: a stationary crack's length still changes a little as the
        // body deforms its polyline, which is not growth.
        if row.growing {
            if self.initiation.is_nan() {
                self.initiation = row.time;
                // The tip was at rest at the previous sample: the run starts there.
                (self.rest_time, self.length_at_initiation) = if self.samples > 0 {
                    (self.last.time, self.last.length)
                } else {
                    (row.time, row.length)
                };
            }
            self.last_growth_time = row.time;
        }
        for (v, fin) in [
            (row.j1, &mut self.j1_final),
            (row.k1, &mut self.k1_final),
            (row.k2, &mut self.k2_final),
        ] {
            if v.is_finite() {
                *fin = v;
            }
        }
        if row.j1.is_finite() && (self.j1_peak.is_nan() || row.j1 > self.j1_peak) {
            self.j1_peak = row.j1;
        }
        self.k1_peak = peak_abs(self.k1_peak, row.k1);
        self.k2_peak = peak_abs(self.k2_peak, row.k2);
        if row.time >= late_from - 1e-9 * late_from.abs() {
            for (k, v) in [row.j1, row.k1, row.k2].into_iter().enumerate() {
                if v.is_finite() {
                    self.late[k] += v;
                    self.late_n[k] += 1;
                }
            }
        }
        // Peak speed: the advance over the trailing window (samples at least `window`
        // apart; the oldest kept sample is the latest one that far back).
        if row.length.is_finite() && row.time.is_finite() {
            self.window.push_back((row.time, row.length));
            while self.window.len() >= 2 && row.time - self.window[1].0 >= window {
                self.window.pop_front();
            }
            if let Some(&(t0, l0)) = self.window.front() {
                let dt = row.time - t0;
                if dt >= window * (1.0 - 1e-9) && dt > 0.0 && self.initiation.is_finite() {
                    let v = (row.length - l0) / dt;
                    if v.is_finite() && (self.peak_speed.is_nan() || v > self.peak_speed) {
                        self.peak_speed = v;
                    }
                }
            }
        }
        self.last = *row;
        self.samples += 1;
    }

    fn finish(&self, crack: u32, tip: u32, window: f64) -> TipSummary {
        let late = |k: usize| {
            if self.late_n[k] > 0 {
                self.late[k] / self.late_n[k] as f64
            } else {
                f64::NAN
            }
        };
        let growth = self.last.length - self.first_length;
        let running = self.last_growth_time - self.rest_time;
        let mean_speed = if running > 0.0 {
            (self.last.length - self.length_at_initiation) / running
        } else {
            f64::NAN
        };
        TipSummary {
            crack,
            tip,
            samples: self.samples,
            x: self.last.x,
            y: self.last.y,
            initiation_time: self.initiation,
            growth,
            j1_final: self.j1_final,
            j1_peak: self.j1_peak,
            k1_final: self.k1_final,
            k1_peak: self.k1_peak,
            k2_final: self.k2_final,
            k2_peak: self.k2_peak,
            j1_late_mean: late(0),
            k1_late_mean: late(1),
            k2_late_mean: late(2),
            mean_speed,
            peak_speed: self.peak_speed,
            speed_window: window,
        }
    }
}

/// Builds [`TipSummary`]s from crack-tip rows pushed in time order.
#[derive(Debug, Clone)]
pub struct TipSummaryBuilder {
    window: f64,
    late_from: f64,
    tips: BTreeMap<(u32, u32), Acc>,
}

impl TipSummaryBuilder {
    /// A builder for `scene`'s rows: its speed window and end time.
    pub fn new(scene: &Scene) -> TipSummaryBuilder {
        TipSummaryBuilder::with(scene.output.speed_window, scene.time.end)
    }

    /// A builder with the rows' `speed_window` (s) and the scene's end time (s).
    pub fn with(speed_window: f64, end_time: f64) -> TipSummaryBuilder {
        let window = if speed_window.is_finite() {
            speed_window.max(MIN_SPEED_WINDOW)
        } else {
            MIN_SPEED_WINDOW
        };
        TipSummaryBuilder {
            window,
            late_from: (1.0 - LATE_FRACTION) * end_time,
            tips: BTreeMap::new(),
        }
    }

    /// Add one row (rows of each tip in time order).
    pub fn push(&mut self, row: &CrackTipRow) {
        let (window, late_from) = (self.window, self.late_from);
        self.tips
            .entry((row.crack, row.tip))
            .or_insert_with(|| Acc::new(row))
            .push(row, window, late_from);
    }

    /// Add rows in time order.
    pub fn extend<'a>(&mut self, rows: impl IntoIterator<Item = &'a CrackTipRow>) {
        for r in rows {
            self.push(r);
        }
    }

    /// The summary of every tip seen, ordered by crack and tip.
    pub fn finish(&self) -> Vec<TipSummary> {
        self.tips
            .iter()
            .map(|(&(c, t), a)| a.finish(c, t, self.window))
            .collect()
    }
}

/// The value of `quantity` at `at` in a tip's summary.
fn measured(t: &TipSummary, quantity: ReferenceQuantity, at: ReferenceAt) -> f64 {
    use ReferenceAt as A;
    use ReferenceQuantity as Q;
    match (quantity, at) {
        (Q::J1, A::Final) => t.j1_final,
        (Q::J1, A::Peak) => t.j1_peak,
        (Q::J1, A::LateMean) => t.j1_late_mean,
        (Q::K1, A::Final) => t.k1_final,
        (Q::K1, A::Peak) => t.k1_peak,
        (Q::K1, A::LateMean) => t.k1_late_mean,
        (Q::K2, A::Final) => t.k2_final,
        (Q::K2, A::Peak) => t.k2_peak,
        (Q::K2, A::LateMean) => t.k2_late_mean,
        (Q::Growth, _) => t.growth,
        (Q::MeanSpeed, _) => t.mean_speed,
        (Q::PeakSpeed, _) => t.peak_speed,
        (Q::InitiationTime, _) => t.initiation_time,
    }
}

/// Compare each of `references` with the tips' summaries.
pub fn check_references(references: &[Reference], tips: &[TipSummary]) -> Vec<ReferenceCheck> {
    references
        .iter()
        .map(|r| {
            let tip = tips
                .iter()
                .find(|t| t.crack == r.crack && r.tip.is_none_or(|k| k == t.tip));
            let m = tip.map_or(f64::NAN, |t| measured(t, r.quantity, r.at));
            let relative_error = if m.is_finite() && r.value.is_finite() && r.value != 0.0 {
                (m - r.value) / r.value.abs()
            } else {
                f64::NAN
            };
            let within = match r.tolerance {
                Some(tol) if relative_error.is_finite() => Some(relative_error.abs() <= tol),
                _ => None,
            };
            ReferenceCheck {
                quantity: r.quantity,
                at: r.at,
                crack: r.crack,
                tip: tip.map(|t| t.tip).or(r.tip),
                value: r.value,
                measured: m,
                relative_error,
                source: r.source.clone(),
                tolerance: r.tolerance,
                within,
            }
        })
        .collect()
}

/// `summary.tips` and `summary.references` of `scene`'s run from its rows (time order).
pub fn summarize(scene: &Scene, rows: &[CrackTipRow]) -> (Vec<TipSummary>, Vec<ReferenceCheck>) {
    let mut b = TipSummaryBuilder::new(scene);
    b.extend(rows);
    let tips = b.finish();
    let refs = check_references(&scene.references, &tips);
    (tips, refs)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(time: f64, tip: u32, length: f64, growing: bool, k1: f64) -> CrackTipRow {
        CrackTipRow {
            time,
            crack: 0,
            tip,
            x: length,
            y: 0.0,
            length,
            speed: f64::NAN,
            j1: k1 * 1e-6,
            j2: 0.0,
            k1,
            k2: -0.5 * k1,
            growing,
            ..CrackTipRow::default()
        }
    }

    /// A tip at rest until 10 µs, then running at 500 m/s to 30 µs, sampled every 0.1 µs:
    /// initiation, growth, mean and windowed speed come out as the motion says.
    #[test]
    fn a_tip_running_at_constant_speed() {
        let mut b = TipSummaryBuilder::with(1e-6, 40e-6);
        let dt = 1e-7;
        for i in 0..=400 {
            let t = i as f64 * dt;
            let run = (t - 10e-6).clamp(0.0, 20e-6);
            let len = 0.01 + 500.0 * run;
            let growing = t > 10e-6 + 1e-12 && t <= 30e-6 + 1e-12;
            b.push(&row(t, 1, len, growing, 1e6 + 1e3 * i as f64));
        }
        let s = b.finish();
        assert_eq!(s.len(), 1);
        let t = &s[0];
        assert_eq!(t.samples, 401);
        assert!((t.initiation_time - 10.1e-6).abs() < 1e-12, "{t:?}");
        assert!((t.growth - 0.01).abs() < 1e-12, "{t:?}");
        assert!((t.mean_speed - 500.0).abs() < 1e-6, "{t:?}");
        assert!((t.peak_speed - 500.0).abs() < 1e-6, "{t:?}");
        assert_eq!(t.speed_window, MIN_SPEED_WINDOW);
        assert!((t.k1_final - 1.4e6).abs() < 1e-3);
        assert!((t.k1_peak - 1.4e6).abs() < 1e-3);
        assert!((t.k2_peak + 0.7e6).abs() < 1e-3, "sign kept: {}", t.k2_peak);
        // Samples at 32..=40 µs: K_I 1.32e6 … 1.4e6, mean 1.36e6.
        assert!((t.k1_late_mean - 1.36e6).abs() < 1e-3, "{}", t.k1_late_mean);
    }

    /// A tip that never moves has no initiation and no speeds; a reference to a crack
    /// without samples reads null, and a tolerance judges the error.
    #[test]
    fn references_compare_and_judge() {
        let mut b = TipSummaryBuilder::with(1e-6, 1e-5);
        for i in 0..=10 {
            b.push(&row(i as f64 * 1e-6, 0, 0.02, false, 0.99e6));
        }
        let tips = b.finish();
        assert!(tips[0].initiation_time.is_nan());
        assert!(tips[0].mean_speed.is_nan() && tips[0].peak_speed.is_nan());
        assert_eq!(tips[0].growth, 0.0);
        let r = |quantity, crack, tolerance| Reference {
            quantity,
            value: 1.0e6,
            crack,
            tip: None,
            at: ReferenceAt::Final,
            source: "test".into(),
            tolerance,
        };
        let checks = check_references(
            &[
                r(ReferenceQuantity::K1, 0, Some(0.02)),
                r(ReferenceQuantity::K1, 0, Some(0.005)),
                r(ReferenceQuantity::K1, 3, None),
                r(ReferenceQuantity::MeanSpeed, 0, Some(0.1)),
            ],
            &tips,
        );
        assert!((checks[0].relative_error + 0.01).abs() < 1e-12);
        assert_eq!(checks[0].within, Some(true));
        assert_eq!(checks[1].within, Some(false));
        assert!(checks[2].measured.is_nan());
        assert_eq!(checks[2].within, None);
        assert_eq!(checks[3].within, None, "no speed: not judged");
        let json = serde_json::to_value(&checks[2]).unwrap_or_default();
        assert!(json["measured"].is_null(), "{json}");
        // NaN reads back as NaN, and a summary equals its copy.
        let back: ReferenceCheck = serde_json::from_value(json).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(back, checks[2]);
        assert_eq!(tips, tips.clone());
        assert_ne!(checks[0], checks[1]);
    }
}
