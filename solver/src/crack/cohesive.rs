//! Cohesive interfaces (`algorithm.md` §8): the state of one bonded point of an interface and
//! its traction–separation law on the effective separation
//! λ = sqrt((δ_n/δ_nc)² + (δ_t/δ_tc)²), with δ_c = G/(σ_c·∫T) per mode so that a pure mode
//! takes exactly its toughness. The traction is T(λ)·(σ_c δ_n/δ_nc, τ_c δ_t/δ_tc)/λ on the
//! loading envelope; below the largest λ reached past the peak it follows the secant to the
//! origin (damaged stiffness: closing and reopening create no energy). Compression is left to
//! the contact law (δ_n counts only opening).
//!
//! The tractions act at the force stage through the same node pairs and stick-capped ± impulses
//! as the process zone (`zone.rs`): an impulse never goes past the one that makes the two
//! fields move together, so the rigid linear law needs no time-step limit (a rigid bond, not
//! yet loaded to its strength, also ties the re-extrapolated momenta: `Cracks::bond_hold`).
//! The stiff elastic branches of the exponential and cubic laws are not made stable by that
//! cap on a double-cantilever beam above cfl 0.15, which validation enforces
//! (`MAX_CFL_ELASTIC_LAW`). The work is booked as the applied force times the separation that
//! opened under it.

use fracture_api::results::CrackTipRow;

pub use fracture_mpm::fracture::cohesive::Bond;

use super::geometry::dist;
use super::{Cracks, Fronts};

impl Cracks {
    /// Update every interface's fronts (`Fronts`) and its reported tip (tip 1: `advance` is
    /// the failure front's distance along the interface, `grew` whether it moved).
    pub(super) fn interface_fronts(&mut self) {
        for c in self.cracks.iter_mut().filter(|c| c.interface) {
            let mut f = Fronts::default();
            let mut arc = 0.0;
            // Whether every bonded point so far has failed / softened (the connected runs).
            let (mut all_failed, mut all_soft) = (true, true);
            for k in 0..c.pts.len() {
                if k > 0 {
                    arc += dist(c.pts[k - 1].x0, c.pts[k].x0);
                }
                let Some(b) = c.pts[k].bond else { continue };
                if b.failed {
                    f.failure = Some((arc, k));
                    f.failed_length += b.share;
                }
                all_failed &= b.failed;
                if all_failed {
                    f.connected_failure = Some((arc, k));
                }
                if b.softening() {
                    f.zone = Some((arc, k));
                }
                all_soft &= b.softening();
                if all_soft {
                    f.connected_zone = Some((arc, k));
                }
            }
            let front = f.failure.map_or(0.0, |(a, _)| a);
            let tip = &mut c.tips[1];
            tip.grew = front != tip.advance;
            tip.advance = front;
            c.fronts = f;
        }
    }

    /// One row per interface (`run-output.md`): crack = its index after the scene's cracks,
    /// tip 1, the failure front's position (the interface's first point before anything
    /// failed), the failed length, the front's moving-box speed; no J or K.
    pub(super) fn interface_rows(&self, time: f64) -> Vec<CrackTipRow> {
        let mut rows = Vec::new();
        for (ci, c) in self.cracks.iter().enumerate().filter(|(_, c)| c.interface) {
            let k = c.fronts.failure.map_or(0, |(_, k)| k);
            let x = c.pts[k].x;
            let nan = f64::NAN;
            let at = |f: Option<(f64, usize)>| f.map_or([nan, nan], |(_, k)| c.pts[k].x);
            let zone = at(c.fronts.zone);
            let connected = at(c.fronts.connected_failure);
            let zone_connected = at(c.fronts.connected_zone);
            rows.push(CrackTipRow {
                time,
                crack: ci as u32,
                tip: 1,
                x: x[0],
                y: x[1],
                length: c.fronts.failed_length,
                speed: self.tip_speed(&c.tips[1], time),
                j1: nan,
                j2: nan,
                k1: nan,
                k2: nan,
                growing: c.tips[1].grew,
                j1_half: nan,
                j2_half: nan,
                j1_double: nan,
                j2_double: nan,
                k1_cod: nan,
                k2_cod: nan,
                zone_x: zone[0],
                zone_y: zone[1],
                connected_x: connected[0],
                connected_y: connected[1],
                zone_connected_x: zone_connected[0],
                zone_connected_y: zone_connected[1],
            });
        }
        rows
    }
}

#[cfg(test)]
mod tests {
    use super::Bond;

    /// The connected fronts stop at the first point that has not failed (softened), while
    /// the farthest fronts jump ahead to a point that failed (softened) on its own: a daughter
    /// crack and the stragglers between (issue 35). States along the interface: failed ×3,
    /// softening, failed (the daughter), softening, rigid.
    #[test]
    fn connected_fronts_stop_at_the_first_straggler() {
        let (_, mut cracks) = super::super::test_cracks(
            1.0e-3,
            [0.03, 0.02],
            [[0.002, 0.002], [0.028, 0.018]],
            "interfaces",
            serde_json::json!([{"points": [[0.004, 0.0105], [0.026, 0.0105]],
                                "cohesive": {"law": "linear",
                                             "normal": {"strength": 1.0e6, "toughness": 10.0},
                                             "shear": {"strength": 1.0e6, "toughness": 10.0}}}]),
        );
        let c = cracks
            .cracks
            .iter_mut()
            .find(|c| c.interface)
            .expect("the interface");
        assert!(c.pts.len() > 8, "{} points", c.pts.len());
        // Failed, softening (past the peak, traction down by half) and rigid bonds.
        let states = ['F', 'F', 'F', 'S', 'F', 'S', 'R'];
        for (k, p) in c.pts.iter_mut().enumerate() {
            let Some(b) = p.bond.as_mut() else { continue };
            match states.get(k).copied().unwrap_or('R') {
                'F' => b.failed = true,
                'S' => b.lambda_max = 0.5 * (b.law.peak() + b.law.end()),
                _ => {}
            }
            let want = states.get(k).copied().unwrap_or('R');
            assert_eq!(b.softening(), want != 'R', "point {k} ({want})");
        }
        cracks.interface_fronts();
        let c = cracks
            .cracks
            .iter()
            .find(|c| c.interface)
            .expect("the interface");
        let f = &c.fronts;
        assert_eq!(f.failure.map(|x| x.1), Some(4), "farthest failed");
        assert_eq!(
            f.connected_failure.map(|x| x.1),
            Some(2),
            "connected failed"
        );
        assert_eq!(f.zone.map(|x| x.1), Some(5), "farthest softened");
        assert_eq!(f.connected_zone.map(|x| x.1), Some(5), "connected softened");
        let rows = cracks.interface_rows(0.0);
        let r = &rows[0];
        assert_eq!([r.x, r.connected_x], [c.pts[4].x[0], c.pts[2].x[0]]);
        assert_eq!(r.zone_connected_x, c.pts[5].x[0]);
    }
    use fracture_api::scene::{Cohesive, CohesiveLaw, CohesiveMode};

    /// A bond of `law`, engaged (the rigid linear law's loading to the strength is the
    /// solver's, tested on the strips).
    fn bond(law: CohesiveLaw) -> Bond {
        let mut b = Bond::new(&Cohesive {
            law,
            normal: CohesiveMode {
                strength: 2.0e6,
                toughness: 100.0,
            },
            shear: CohesiveMode {
                strength: 3.0e6,
                toughness: 400.0,
            },
        });
        b.engaged = true;
        b
    }

    /// Work of a path of separations, booked as the solver does (the traction at the start
    /// of each increment times the increment).
    fn work(b: &mut Bond, path: &[[f64; 2]]) -> f64 {
        let mut w = 0.0;
        for p in path.windows(2) {
            let t = b.traction(p[0][0], p[0][1]).unwrap_or([0.0; 2]);
            w += t[0] * (p[1][0] - p[0][0]) + t[1] * (p[1][1] - p[0][1]);
        }
        w
    }

    fn ramp(from: [f64; 2], to: [f64; 2], n: usize) -> Vec<[f64; 2]> {
        (0..=n)
            .map(|i| {
                let s = i as f64 / n as f64;
                [
                    from[0] + s * (to[0] - from[0]),
                    from[1] + s * (to[1] - from[1]),
                ]
            })
            .collect()
    }

    /// Each law takes its mode's toughness opening or sliding monotonically, fails, and its
    /// peak traction is the strength (the area under Xu–Needleman's e·λ·e^(−λ) and Needleman's
    /// (27/4)λ(1 − λ)², integrated here numerically, is independent of the closed forms the
    /// law's δ_c uses).
    #[test]
    fn each_law_takes_its_toughness_in_pure_modes() {
        for law in [
            CohesiveLaw::Linear,
            CohesiveLaw::Exponential,
            CohesiveLaw::Cubic,
        ] {
            for (mode, g, s) in [(0, 100.0, 2.0e6), (1, 400.0, 3.0e6)] {
                let mut b = bond(law);
                let end = 1.05 * law.end() * b.critical[mode];
                let mut to = [0.0; 2];
                to[mode] = end;
                let path = ramp([0.0; 2], to, 20_000);
                let mut peak: f64 = 0.0;
                let mut probe = bond(law);
                for p in &path {
                    let t = probe.traction(p[0], p[1]).unwrap_or([0.0; 2]);
                    peak = peak.max(t[mode]);
                }
                let w = work(&mut b, &path);
                assert!(b.failed, "{law:?} mode {mode} did not fail");
                assert!(
                    (w / g - 1.0).abs() < 2e-3,
                    "{law:?} mode {mode}: {w} vs {g}"
                );
                if law != CohesiveLaw::Linear {
                    assert!((peak / s - 1.0).abs() < 2e-3, "{law:?} peak {peak} vs {s}");
                }
            }
        }
    }

    /// Opening half-way past the peak, closing to zero and reopening to failure takes the
    /// same toughness as one monotonic opening: unloading follows the damaged secant, so it
    /// neither creates nor destroys energy.
    #[test]
    fn unloading_and_reloading_create_no_energy() {
        for law in [
            CohesiveLaw::Exponential,
            CohesiveLaw::Cubic,
            CohesiveLaw::Linear,
        ] {
            let mut b = bond(law);
            let dc = b.critical[0];
            let mid = 0.5 * (law.peak() + law.end().min(3.0)) * dc;
            let mut path = ramp([0.0; 2], [mid, 0.0], 10_000);
            path.extend(ramp([mid, 0.0], [0.0, 0.0], 10_000).into_iter().skip(1));
            path.extend(
                ramp([0.0; 2], [1.05 * law.end() * dc, 0.0], 40_000)
                    .into_iter()
                    .skip(1),
            );
            let w = work(&mut b, &path);
            assert!((w / 100.0 - 1.0).abs() < 3e-3, "{law:?}: {w} vs 100");
        }
    }

    /// The zone front's test: a drift far below δ_c under a rigid linear bond is not
    /// softening; 2 % of δ_c is (the traction has dropped by 2 %); the exponential law is in
    /// the zone only past its peak.
    #[test]
    fn softening_means_the_traction_has_dropped() {
        let mut b = bond(CohesiveLaw::Linear);
        let dc = b.critical[0];
        let _ = b.traction(1e-6 * dc, 0.0);
        assert!(!b.softening());
        let _ = b.traction(0.02 * dc, 0.0);
        assert!(b.softening());
        let mut e = bond(CohesiveLaw::Exponential);
        let dc = e.critical[0];
        let _ = e.traction(0.9 * dc, 0.0);
        assert!(!e.softening());
        let _ = e.traction(2.0 * dc, 0.0);
        assert!(e.softening());
    }
}
