//! What one run measures (`Measured`): the tip of the first crack, collected by the run's
//! sink (`Collect`), the speed measures taken from the tip's position along the bond, its x
//! (initiation, the mean to the end, window means, moving-box speeds, the slow-down), J1 of
//! the running tip, the fracture energy, the distance from the bond, the fringe snapshots.
//!
//! The speed is the tip's material coordinate along the bond, x(t), and not the crack
//! length: the length is measured along the crack's polyline, whose points move with the
//! deforming faces, so it changes after an arrest and runs ahead of the tip on a wavy crack.

use fracture_api::Scene;
use fracture_api::results::{
    CrackTipRow, EnergyRow, FractureEnergy, Progress, RunStatus, Snapshot, Summary,
};
use fracture_worker::{Control, RunOptions, RunSink, SinkError, run_scene};

/// Times (s after impact) of the fringe pictures.
pub(super) const FRINGE_TIMES: [f64; 2] = [4.0e-5, 6.0e-5];

/// What one run measured.
#[derive(Debug, Clone)]
pub(super) struct Measured {
    pub(super) status: RunStatus,
    pub(super) message: Option<String>,
    pub(super) wall: f64,
    pub(super) psps: f64,
    pub(super) steps: u64,
    pub(super) particles: u64,
    /// Tip samples: time (s), crack length along the polyline (m), tip x and y (m), the
    /// solver's tip speed (m/s, moving box of the polyline length over the scene's
    /// `output.speed_window`), whether the tip advanced in the sample's step, J1 (J/m²).
    pub(super) t: Vec<f64>,
    pub(super) len: Vec<f64>,
    pub(super) y: Vec<f64>,
    pub(super) x: Vec<f64>,
    pub(super) speed: Vec<f64>,
    pub(super) growing: Vec<bool>,
    pub(super) j1: Vec<f64>,
    /// J1 (J/m²) on the rings of half and twice the J radius (`crack_tips.csv` `j1_half`,
    /// `j1_double`).
    pub(super) j1_half: Vec<f64>,
    pub(super) j1_double: Vec<f64>,
    /// The run's fracture energy (summary), if a tip grew.
    pub(super) fracture: Option<FractureEnergy>,
    /// Fringe snapshots at `FRINGE_TIMES`.
    pub(super) fringes: Vec<Snapshot>,
    /// Largest distance (m) of the tip from the bond's material line: the tip's y against the
    /// initial bond y plus the material's y displacement at the tip, at every snapshot.
    pub(super) off_material: f64,
    /// The last energy row's `fracture` (J): tips' zones and cohesive traction work.
    pub(super) fracture_work: f64,
    /// Per sample of a cohesive interface's row: how far (m, along x) its farthest failed
    /// point lies ahead of its connected failure front, and its farthest softened point ahead
    /// of the end of its connected softened region (`crack_tips.csv` `connected_x`,
    /// `zone_connected_x`); NaN where not defined (crack tips).
    pub(super) apart: Vec<[f64; 2]>,
}

impl Measured {
    /// Time of the first growth (s): the first sample whose step advanced the tip.
    pub(super) fn initiation(&self) -> Option<f64> {
        self.t
            .iter()
            .zip(&self.growing)
            .find(|(_, g)| **g)
            .map(|(t, _)| *t)
    }
    /// The initiation time for tables: "12.3 µs", or "none".
    pub(super) fn initiation_label(&self) -> String {
        self.initiation()
            .map_or("none".to_string(), |t| format!("{:.1} µs", t * 1e6))
    }
    /// Mean tip speed from the first growing sample to the last sample (m/s), from x, if the
    /// crack grew.
    pub(super) fn mean_to_end(&self) -> Option<f64> {
        let i0 = self.growing.iter().position(|&g| g)?;
        let (t0, x0) = (self.t[i0], self.x[i0]);
        let (&t1, &x1) = (self.t.last()?, self.x.last()?);
        (t1 > t0).then(|| (x1 - x0) / (t1 - t0))
    }
    /// How far the tip moved along the bond (m): its last x less its first.
    pub(super) fn extension(&self) -> f64 {
        match (self.x.first(), self.x.last()) {
            (Some(a), Some(b)) => b - a,
            _ => 0.0,
        }
    }
    /// The tip's x at time `t` (linear interpolation, clamped).
    fn x_at(&self, t: f64) -> f64 {
        match self.t.iter().position(|&s| s >= t) {
            None => self.x.last().copied().unwrap_or(0.0),
            Some(0) => self.x.first().copied().unwrap_or(0.0),
            Some(i) => {
                let (t0, t1) = (self.t[i - 1], self.t[i]);
                let f = if t1 > t0 { (t - t0) / (t1 - t0) } else { 1.0 };
                self.x[i - 1] + f * (self.x[i] - self.x[i - 1])
            }
        }
    }
    /// Mean tip speed over [a, b] (s), from x.
    pub(super) fn mean_speed(&self, a: f64, b: f64) -> Option<f64> {
        let end = *self.t.last()?;
        (b <= end + 1e-12 && b > a).then(|| (self.x_at(b) - self.x_at(a)) / (b - a))
    }
    /// Moving-box speed from x over `w` (s) at every sample that has the whole box.
    pub(super) fn box_speed(&self, w: f64) -> Vec<[f64; 2]> {
        let Some(&end) = self.t.last() else {
            return Vec::new();
        };
        self.t
            .iter()
            .filter(|&&t| t - 0.5 * w >= 0.0 && t + 0.5 * w <= end)
            .map(|&t| [t, (self.x_at(t + 0.5 * w) - self.x_at(t - 0.5 * w)) / w])
            .collect()
    }
    /// [`box_speed`](Self::box_speed) with the time in µs, the unit of the speed figures'
    /// axis (`figures::speed_plot`).
    pub(super) fn box_speed_us(&self, w: f64) -> Vec<[f64; 2]> {
        self.box_speed(w)
            .iter()
            .map(|p| [p[0] * 1e6, p[1]])
            .collect()
    }
    /// Of the running samples (those whose step advanced the tip), how many have J1 below
    /// −`frac`·Γ, and how many there are.
    pub(super) fn negative_j(&self, gamma: f64, frac: f64) -> (usize, usize) {
        let running: Vec<f64> = self
            .growing
            .iter()
            .zip(&self.j1)
            .filter(|(g, _)| **g)
            .map(|(_, j)| *j)
            .collect();
        let low = running.iter().filter(|&&j| j < -frac * gamma).count();
        (low, running.len())
    }
    /// The running samples from `delay` (s) after initiation on: their J1 on the rings of
    /// half, once and twice the J radius.
    fn late_rings(&self, delay: f64) -> Vec<[f64; 3]> {
        let Some(t0) = self.initiation() else {
            return Vec::new();
        };
        (0..self.t.len())
            .filter(|&i| self.growing[i] && self.t[i] >= t0 + delay)
            .filter_map(|i| {
                let r = [
                    *self.j1_half.get(i)?,
                    *self.j1.get(i)?,
                    *self.j1_double.get(i)?,
                ];
                r.iter().all(|x| x.is_finite()).then_some(r)
            })
            .collect()
    }
    /// Mean J1 (J/m²) on the rings of half, once and twice the J radius over the running
    /// samples from `delay` (s) after initiation on, and how many samples that is.
    pub(super) fn ring_means(&self, delay: f64) -> ([f64; 3], usize) {
        let s = self.late_rings(delay);
        let n = s.len();
        let mut m = [0.0; 3];
        for r in &s {
            for k in 0..3 {
                m[k] += r[k] / n as f64;
            }
        }
        (if n > 0 { m } else { [f64::NAN; 3] }, n)
    }
    /// Of the running samples, how many have J1 below −`frac`·Γ on the rings of half, once
    /// and twice the J radius (a ring that does not fit reads NaN and is not counted).
    pub(super) fn negative_rings(&self, gamma: f64, frac: f64) -> [usize; 3] {
        let mut low = [0; 3];
        for i in (0..self.t.len()).filter(|&i| self.growing[i]) {
            for (k, col) in [&self.j1_half, &self.j1, &self.j1_double]
                .iter()
                .enumerate()
            {
                if col.get(i).is_some_and(|&j| j < -frac * gamma) {
                    low[k] += 1;
                }
            }
        }
        low
    }
    /// How many samples are running (the tip advanced in that step).
    pub(super) fn running(&self) -> usize {
        self.growing.iter().filter(|&&g| g).count()
    }
    /// Running samples at or above `v_min` (m/s, the solver's tip speed): how many, and how
    /// many of them have J1 below −`frac`·Γ.
    pub(super) fn fast_samples(&self, v_min: f64, gamma: f64, frac: f64) -> (usize, usize) {
        let fast: Vec<usize> = (0..self.t.len())
            .filter(|&i| self.growing[i] && self.speed.get(i).is_some_and(|&v| v >= v_min))
            .collect();
        let low = fast.iter().filter(|&&i| self.j1[i] < -frac * gamma).count();
        (fast.len(), low)
    }
    /// Largest distance of the tip from the initial bond line (m): the first tip sample is
    /// on the bond.
    pub(super) fn off_bond(&self) -> f64 {
        let y0 = self.y.first().copied().unwrap_or(0.0);
        self.y.iter().map(|y| (y - y0).abs()).fold(0.0, f64::max)
    }
}

/// Mean y displacement (m) of the material on the bond at the tip: the nodes within one cell
/// of (x_tip, y_bond) in x and 1.5 cells in y, both sides of the bond.
fn bond_displacement(snap: &Snapshot, x_tip: f64, y_bond: f64) -> Option<f64> {
    let uy = snap.component("uy")?;
    let h = snap.cell_size;
    let (nx, ny) = (snap.nx as usize, snap.ny as usize);
    let (mut sum, mut n) = (0.0, 0.0);
    for iy in 0..ny {
        let y = snap.origin[1] + iy as f64 * h;
        if (y - y_bond).abs() > 1.5 * h {
            continue;
        }
        for ix in 0..nx {
            let x = snap.origin[0] + ix as f64 * h;
            if (x - x_tip).abs() > h {
                continue;
            }
            let v = f64::from(*uy.values.get(iy * nx + ix)?);
            if v.is_finite() {
                sum += v;
                n += 1.0;
            }
        }
    }
    (n > 0.0).then(|| sum / n)
}

/// The sink of a study run: keeps one tip's rows (crack index, tip) and the fringe
/// snapshots.
struct Collect {
    m: Measured,
    target: (u32, u32),
}

impl RunSink for Collect {
    fn progress(&mut self, _p: &Progress) -> Result<Control, SinkError> {
        Ok(Control::Continue)
    }
    fn energy(&mut self, rows: &[EnergyRow]) -> Result<(), SinkError> {
        if let Some(r) = rows.last() {
            self.m.fracture_work = r.fracture;
        }
        Ok(())
    }
    fn crack_tips(&mut self, rows: &[CrackTipRow]) -> Result<(), SinkError> {
        // The notch runs from the struck edge (tip 0, the mouth) to its tip (tip 1); an
        // interface's row is its failure front (crack index past the scene's cracks, tip 1).
        let (crack, tip) = self.target;
        for r in rows.iter().filter(|r| r.crack == crack && r.tip == tip) {
            self.m.t.push(r.time);
            self.m.len.push(r.length);
            self.m.y.push(r.y);
            self.m.x.push(r.x);
            self.m.speed.push(r.speed);
            self.m.growing.push(r.growing);
            self.m.j1.push(r.j1);
            self.m.j1_half.push(r.j1_half);
            self.m.j1_double.push(r.j1_double);
            self.m
                .apart
                .push([r.x - r.connected_x, r.zone_x - r.zone_connected_x]);
        }
        Ok(())
    }
    fn snapshot(&mut self, snap: &Snapshot) -> Result<(), SinkError> {
        if let (Some(&y_tip), Some(&y0), Some(&x_tip)) =
            (self.m.y.last(), self.m.y.first(), self.m.x.last())
            && let Some(uy) = bond_displacement(snap, x_tip, y0)
        {
            self.m.off_material = self.m.off_material.max((y_tip - y0 - uy).abs());
        }
        if FRINGE_TIMES
            .iter()
            .any(|&t| (snap.time - t).abs() < 0.25e-6)
        {
            self.m.fringes.push(snap.clone());
        }
        Ok(())
    }
    fn finish(&mut self, s: &Summary) -> Result<(), SinkError> {
        self.m.status = s.status;
        self.m.message = s.message.clone();
        self.m.wall = s.wall_seconds;
        self.m.psps = s.particle_steps_per_second;
        self.m.steps = s.steps;
        self.m.particles = s.particles;
        self.m.fracture = s.fracture;
        Ok(())
    }
}

/// Run `scene` and measure the rows of `target` (crack index, tip).
pub(super) fn run_one(
    scene: &Scene,
    threads: fracture_solver::Parallelism,
    target: (u32, u32),
) -> Measured {
    let mut sink = Collect {
        target,
        m: Measured {
            status: RunStatus::Failed,
            message: None,
            wall: 0.0,
            psps: 0.0,
            steps: 0,
            particles: 0,
            t: Vec::new(),
            len: Vec::new(),
            y: Vec::new(),
            x: Vec::new(),
            speed: Vec::new(),
            growing: Vec::new(),
            j1: Vec::new(),
            j1_half: Vec::new(),
            j1_double: Vec::new(),
            fracture: None,
            fringes: Vec::new(),
            off_material: 0.0,
            fracture_work: 0.0,
            apart: Vec::new(),
        },
    };
    let opts = RunOptions {
        threads,
        ..RunOptions::default()
    };
    match fracture_api::ValidScene::new(scene.clone()) {
        Ok(valid) => {
            run_scene(&valid, &opts, &mut sink);
        }
        Err(e) => sink.m.message = Some(format!("invalid scene:\n{e}")),
    }
    sink.m
}

/// The first fall of the moving-box speed by at least 30 % from its running peak (after the
/// peak has reached 500 m/s): the time (s) and the relative drop.
pub(super) fn slow_down(m: &Measured, w: f64) -> (Option<f64>, f64) {
    let mut peak: f64 = 0.0;
    for p in m.box_speed(w) {
        peak = peak.max(p[1]);
        if peak > 500.0 && p[1] < 0.7 * peak {
            return (Some(p[0]), 1.0 - p[1] / peak);
        }
    }
    (None, 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run whose tip is at `x(t)`, grows where `x` rises, and whose polyline length is
    /// `len(t)`.
    fn measured(t: Vec<f64>, x: Vec<f64>, len: Vec<f64>) -> Measured {
        let n = t.len();
        let growing = (0..n).map(|i| i > 0 && x[i] > x[i - 1]).collect();
        Measured {
            status: RunStatus::Completed,
            message: None,
            wall: 0.0,
            psps: 0.0,
            steps: 0,
            particles: 0,
            t,
            len,
            y: vec![0.0; n],
            x,
            speed: vec![0.0; n],
            growing,
            j1: vec![100.0; n],
            j1_half: vec![100.0; n],
            j1_double: vec![100.0; n],
            fracture: None,
            fringes: Vec::new(),
            off_material: 0.0,
            fracture_work: 0.0,
            apart: Vec::new(),
        }
    }

    /// A tip at rest until 10 µs, then at 1000 m/s along x: initiation, mean and box speeds
    /// from x; the polyline length runs 1.5 times as fast (a wavy crack, faces moving) and
    /// does not enter the speeds.
    #[test]
    fn speeds_from_the_tip_position() {
        let t: Vec<f64> = (0..=400).map(|i| f64::from(i) * 1e-7).collect();
        let x: Vec<f64> = t
            .iter()
            .map(|&t| 0.017 + 1000.0 * (t - 1.0e-5).max(0.0))
            .collect();
        let len: Vec<f64> = t
            .iter()
            .map(|&t| 0.015 + 1500.0 * (t - 1.0e-5).max(0.0))
            .collect();
        let m = measured(t, x, len);
        let t0 = m.initiation().unwrap_or(0.0);
        assert!((t0 - 1.0e-5).abs() < 1.5e-7, "initiation {t0}");
        let v = m.mean_to_end().unwrap_or(0.0);
        assert!((v - 1000.0).abs() < 1e-6, "mean to end {v}");
        let v = m.mean_speed(2.0e-5, 3.0e-5).unwrap_or(0.0);
        assert!((v - 1000.0).abs() < 1e-6, "{v}");
        assert!(m.mean_speed(2.0e-5, 5.0e-5).is_none());
        assert!((m.extension() - 0.03).abs() < 1e-9, "{}", m.extension());
        let b = m.box_speed(2.0e-6);
        assert!(b.iter().all(|p| p[1] >= -1e-9 && p[1] <= 1000.0 + 1e-6));
        assert!(b.iter().any(|p| (p[1] - 1000.0).abs() < 1e-6));
        // The figures' samples span the run's 40 µs in µs (the cohesive page once drew every
        // curve at t = 0, its samples in s on an axis in µs).
        let bu = m.box_speed_us(2.0e-6);
        let span = bu.iter().map(|p| p[0]).fold(0.0, f64::max);
        assert!((38.0..=40.0).contains(&span), "last sample at {span} µs");
        assert_eq!(bu.len(), b.len());
        assert_eq!(slow_down(&m, 2.0e-6).0, None);
    }

    /// A tip that runs 10 mm and arrests while the polyline keeps changing length (its points
    /// move with the faces): the speed from x is 10 mm over the run, the length's would not be.
    #[test]
    fn arrest_is_read_from_x_not_the_length() {
        let t: Vec<f64> = (0..=300).map(|i| f64::from(i) * 1e-7).collect();
        let x: Vec<f64> = t
            .iter()
            .map(|&t| 0.017 + 1000.0 * (t.min(2.0e-5) - 1.0e-5).max(0.0))
            .collect();
        let len: Vec<f64> = t
            .iter()
            .zip(&x)
            .map(|(&t, &x)| x - 0.002 + 2.0e-3 * (t * 2.0e6).sin() * (t > 2.0e-5) as u8 as f64)
            .collect();
        let m = measured(t, x, len);
        let v = m.mean_to_end().unwrap_or(0.0);
        // 10 mm from 10.1 µs (the first growing sample) to 30 µs.
        assert!((v - 0.0099 / 1.99e-5).abs() < 1.0, "{v}");
        assert!(
            m.box_speed(2.0e-6)
                .iter()
                .filter(|p| p[0] > 2.2e-5)
                .all(|p| p[1].abs() < 1e-9)
        );
    }

    /// Ten samples 0.1 µs apart, the tip at rest for the first five and running after.
    fn starts_at_sample_five() -> Measured {
        let t: Vec<f64> = (0..10).map(|i| f64::from(i) * 1e-7).collect();
        let x: Vec<f64> = (0..10)
            .map(|i| if i < 5 { 0.0 } else { f64::from(i) * 1e-4 })
            .collect();
        measured(t, x, vec![0.0; 10])
    }

    /// J1 of the running samples only: a stationary tip's negative J does not count.
    #[test]
    fn negative_j_counts_running_samples() {
        let mut m = starts_at_sample_five();
        m.j1 = vec![
            -100.0, -100.0, 0.0, 0.0, 0.0, -30.0, -20.0, 50.0, 60.0, 70.0,
        ];
        assert_eq!(m.negative_j(250.0, 0.1), (1, 5));
    }

    /// The three rings: means over the running samples after the delay, negative counts per
    /// ring (a NaN ring counts nowhere), and the fast samples' share of the negative ones.
    #[test]
    fn rings_and_fast_samples() {
        let mut m = starts_at_sample_five();
        // Running from sample 5 (0.5 µs).
        m.j1 = vec![0.0, 0.0, 0.0, 0.0, 0.0, 10.0, 20.0, -30.0, 40.0, 50.0];
        m.j1_half = vec![0.0, 0.0, 0.0, 0.0, 0.0, 20.0, 30.0, 40.0, 50.0, 60.0];
        m.j1_double = vec![0.0, 0.0, 0.0, 0.0, 0.0, -40.0, -40.0, -40.0, f64::NAN, 0.0];
        m.speed = vec![0.0, 0.0, 0.0, 0.0, 0.0, 500.0, 900.0, 1200.0, 1200.0, 800.0];
        assert_eq!(m.negative_rings(100.0, 0.1), [0, 1, 3]);
        assert_eq!(m.fast_samples(1000.0, 100.0, 0.1), (2, 1));
        assert_eq!(m.running(), 5);
        // From 0.2 µs after initiation: samples 7 and 9 (8 has a NaN ring).
        let (means, n) = m.ring_means(0.2e-6);
        assert_eq!(n, 2);
        assert!((means[0] - 50.0).abs() < 1e-9 && (means[1] - 10.0).abs() < 1e-9);
        assert!((means[2] + 20.0).abs() < 1e-9);
    }

    /// A tip that runs, stops and runs: the slow-down is found where it stops.
    #[test]
    fn slow_down_is_found() {
        let t: Vec<f64> = (0..=600).map(|i| f64::from(i) * 1e-7).collect();
        let x: Vec<f64> = t
            .iter()
            .map(|&t| {
                let run1 = 1500.0 * (t.min(3.0e-5) - 1.0e-5).max(0.0);
                let run2 = 1500.0 * (t - 4.0e-5).max(0.0);
                0.025 + run1 + run2
            })
            .collect();
        let m = measured(t, x.clone(), x);
        let (at, drop) = slow_down(&m, 2.0e-6);
        let at = at.unwrap_or(0.0);
        assert!((at - 3.0e-5).abs() < 1.0e-6, "slow-down at {at}");
        assert!(drop >= 0.3);
    }
}
