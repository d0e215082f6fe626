//! Propagation (`algorithm.md` §7): the growth criterion G ≥ toughness along the chosen
//! direction (the kink of maximum energy release or of maximum hoop stress from K_I, K_II,
//! or fixed along a material line with G = J1), the new tip point and
//! segment (segments stay at least h/2 long; a tip that runs out of material becomes a
//! mouth), and the tip histories behind the moving-box tip speed.

use fracture_api::scene::{GrowthDirection, Propagation};

use crate::tip_mechanics::{hoop_stress_angle, kinked_k, max_energy_release_angle};

use super::geometry::{dist, norm};
use super::j_integral::TipFrameJ;
use super::{CrackPoint, Cracks, TipState, View, mass_weighted_at};

/// The material displacement at x: the field-0 nodal displacement Σ S m (x_p − X_p) over the
/// mass, mass-weighted over x's cell.
fn displacement_at(v: &View<'_>, x: [f64; 2]) -> Option<[f64; 2]> {
    mass_weighted_at(
        v.geom,
        x,
        |ix, iy| Some(&v.nodes[v.geom.index(ix, iy)]),
        |n| n.u,
    )
}

impl Cracks {
    /// Moving-box tip speed over the speed window.
    pub(super) fn tip_speed(&self, tip: &TipState, time: f64) -> f64 {
        let Some(&(t0, a0)) = tip
            .history
            .iter()
            .find(|(t, _)| *t >= time - self.speed_window - 1e-15)
        else {
            return 0.0;
        };
        let span = time - t0;
        if span <= 0.0 {
            0.0
        } else {
            (tip.advance - a0) / span
        }
    }

    /// Check every growing tip (§7) and grow it; records the tip history. True if some tip
    /// advanced.
    pub fn propagate(&mut self, v: &View<'_>, time: f64) -> bool {
        let mut any = false;
        let step_len = self.cfl * self.h;
        for ci in 0..self.cracks.len() {
            for t in 0..2 {
                self.cracks[ci].tips[t].grew = false;
                let Propagation::EnergyRelease {
                    toughness,
                    direction,
                    ..
                } = self.cracks[ci].propagation.clone()
                else {
                    continue;
                };
                if !self.cracks[ci].tips[t].active {
                    continue;
                }
                let tf = self.tip_frame_j(ci, t, v, time);
                let TipFrameJ {
                    tip, e1, e2, j1, ..
                } = tf;
                let kink = |angle: fn(f64, f64) -> f64, k: [f64; 2]| -> (f64, [f64; 2]) {
                    // G of the kink: J1 (the energy measure) times the kinked crack's
                    // |k(θ)|²/|K|² (Hussain, Pu & Underwood), θ from the criterion. A negative
                    // K_I means faces pressed into contact: the tip is in mode II (K_I = 0).
                    let k = [k[0].max(0.0), k[1]];
                    let k2 = k[0] * k[0] + k[1] * k[1];
                    if !(k2.is_finite() && k2 > 0.0) {
                        return (j1, e1);
                    }
                    let th = angle(k[0], k[1]);
                    let (a, b) = kinked_k(k[0], k[1], th);
                    let (s, co) = th.sin_cos();
                    (
                        j1 * (a * a + b * b) / k2,
                        [co * e1[0] + s * e2[0], co * e1[1] + s * e2[1]],
                    )
                };
                let (g, dir) = match direction {
                    GrowthDirection::MaxEnergyRelease | GrowthDirection::MaxHoopStress => {
                        let speed = self.tip_speed(&self.cracks[ci].tips[t], time);
                        let k = self.tip_k(ci, t, &tf, speed);
                        if matches!(direction, GrowthDirection::MaxHoopStress) {
                            kink(hoop_stress_angle, k)
                        } else {
                            kink(|a, b| max_energy_release_angle(a, b).0, k)
                        }
                    }
                    GrowthDirection::Fixed(d) => {
                        let l = norm(d).max(1e-300);
                        let mut d = [d[0] / l, d[1] / l];
                        // The direction is a line: take the sense that points ahead.
                        if d[0] * e1[0] + d[1] * e1[1] < 0.0 {
                            d = [-d[0], -d[1]];
                        }
                        // G = J1 of the tip frame: the tip segment lies along the material
                        // line (the seed's rule J1 > J_Ic along the bond); the J2·sin θ of a
                        // slightly rotated bond is not energy released along it.
                        (j1, d)
                    }
                };
                if g < toughness || !g.is_finite() {
                    continue;
                }
                let (tip_i, prev_i) = {
                    let n = self.cracks[ci].pts.len();
                    if t == 0 { (0, 1) } else { (n - 1, n - 2) }
                };
                let tip0 = self.cracks[ci].pts[tip_i].x0;
                let ahead = [tip[0] + step_len * dir[0], tip[1] + step_len * dir[1]];
                let ahead0 = [tip0[0] + step_len * dir[0], tip0[1] + step_len * dir[1]];
                let new = match direction {
                    // A fixed direction is a line of the undeformed body (a bond, a weak
                    // plane): the new tip is where the material point a step ahead of the
                    // tip's material point along it is now, X + u(X), with u the nodal
                    // displacement field (two fixed-point passes from the straight guess).
                    // Growing straight in the current configuration instead lets the tip
                    // walk off a sheared bond by step × ∂u_n/∂s per growth step.
                    GrowthDirection::Fixed(_) => {
                        let mut x = ahead;
                        for _ in 0..2 {
                            if let Some(u) = displacement_at(v, x) {
                                x = [ahead0[0] + u[0], ahead0[1] + u[1]];
                            }
                        }
                        x
                    }
                    _ => ahead,
                };
                // Material ahead? If not, the crack has cut through: it becomes a mouth.
                let xi = v.geom.xi(new);
                let (ix, iy) = (xi[0].round(), xi[1].round());
                let has_material = ix >= 1.0
                    && iy >= 1.0
                    && (ix as usize) + 1 < v.geom.nx
                    && (iy as usize) + 1 < v.geom.ny
                    && v.nodes[v.geom.index(ix as usize, iy as usize)].m > 0.0;
                let c = &mut self.cracks[ci];
                if !has_material {
                    let e = 2.0 * self.h;
                    let out = [new[0] + e * dir[0], new[1] + e * dir[1]];
                    if t == 0 {
                        c.pts.insert(0, CrackPoint::at(out));
                    } else {
                        c.pts.push(CrackPoint::at(out));
                    }
                    c.ext[t] = e;
                    c.tips[t].active = false;
                    continue;
                }
                // Keep segments at least h/2: extend a short tip segment instead of adding.
                let short = dist(c.pts[tip_i].x, c.pts[prev_i].x) < 0.5 * self.h * (1.0 - 1e-9);
                let point = CrackPoint::grown(new, ahead0);
                if short {
                    c.pts[tip_i] = point;
                } else if t == 0 {
                    c.pts.insert(0, point);
                } else {
                    c.pts.push(point);
                }
                c.tips[t].advance += step_len;
                c.tips[t].released += g * step_len;
                c.tips[t].grew = true;
                c.tips[t].cached_j = None;
                any = true;
            }
        }
        // Tip histories for the moving-box speed.
        let keep = 2.0 * self.speed_window;
        for c in &mut self.cracks {
            for tip in &mut c.tips {
                tip.history.push_back((time, tip.advance));
                while tip.history.front().is_some_and(|(t0, _)| *t0 < time - keep) {
                    tip.history.pop_front();
                }
            }
        }
        any
    }
}
