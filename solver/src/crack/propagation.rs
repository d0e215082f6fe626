//! Propagation (`algorithm.md` §7): the driving force G along the chosen direction (the kink
//! of maximum energy release or of maximum hoop stress from K_I, K_II, or fixed along a
//! material line with G = J1), how far the tip moves in this step, the new tip point and
//! segment (segments stay at least h/2 long; a tip that runs out of material becomes a
//! mouth), and the tip histories behind the moving-box tip speed.
//!
//! Two speed laws:
//! * `wave`, the seed's: while G ≥ Γ the tip jumps cfl·h = c_L·Δt in that step; the new
//!   faces are released at once (no fracture energy is dissipated: the summary reports it).
//! * `equation_of_motion`: G is filtered, G_f += (1 − e^{−Δt/τ})(G − G_f), so a one-step
//!   transient after an advance neither starts nor stops the tip; the speed relaxes over τ
//!   towards the speed at which Freund's g(v)·G* = Γ(v) would hold for G* = G_f/g(v)
//!   (`eom_speed`), so its steady state is G_f = Γ(v) below c_R; a resting tip starts once
//!   G_f ≥ Γ(0) and arrests when its target is rest; the tip moves v·Δt. Each point the tip
//!   leaves behind carries a process-zone traction (`zone.rs`) that dissipates Γ per unit area.

use fracture_api::scene::{GrowthDirection, GrowthSpeed, JIntegral, Propagation};

use crate::tip_mechanics::{hoop_stress_angle, kinked_k, max_energy_release_angle};

use super::geometry::{dist, norm};
use super::j_integral::TipFrameJ;
use super::zone::Zone;
use super::{CrackPoint, Cracks, TipState, View, mass_weighted_at};
pub(crate) use fracture_mpm::fracture::growth::{KINK_DEG, at_speed_wall, eom_speed, freund_g};

/// The material displacement at x: the field-0 nodal displacement Σ S m (x_p − X_p) over the
/// mass, mass-weighted over x's cell.
fn displacement_at(v: &View<'_>, x: [f64; 2]) -> Option<[f64; 2]> {
    mass_weighted_at(
        v.geom,
        x,
        |ix, iy| Some(&v.nodes[v.geom.at(ix, iy)]),
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

    /// The outer radius of crack `ci`'s J domain (the contour's half-size for a contour).
    pub(super) fn j_radius(&self, ci: usize) -> f64 {
        match self.cracks[ci].j_method {
            JIntegral::Domain { radius } => radius,
            JIntegral::Contour { cells } => f64::from(cells) * self.h,
        }
    }

    /// The energy the process zones of tip `t` take per unit advance where the J domain's
    /// weight q is below 1: Σ_k (1 − q(r_k))·(F_k/thickness)·∂δ/∂x1 over the zone points
    /// (F_k the force on the above face, δ the separation, x1 along the tip's direction e1).
    /// The domain integral without the zone tractions in its face term counts the zone at
    /// weight q, J_domain = J_tip + Σ q z_k; adding this makes it J_tip + Σ z_k, the energy
    /// release rate of the far field, whatever part of the zone the ring holds.
    pub(super) fn zone_outside_domain(
        &self,
        ci: usize,
        t: usize,
        e1: [f64; 2],
        radius: f64,
    ) -> f64 {
        let c = &self.cracks[ci];
        let n = c.pts.len();
        if n < 3 {
            return 0.0;
        }
        let tip = if t == 0 { c.pts[0].x } else { c.pts[n - 1].x };
        let sep = |k: usize| {
            let p = c.pts[k];
            [p.above[0] - p.below[0], p.above[1] - p.below[1]]
        };
        let x1 = |k: usize| (c.pts[k].x[0] - tip[0]) * e1[0] + (c.pts[k].x[1] - tip[1]) * e1[1];
        let mut sum = 0.0;
        for k in 1..n - 1 {
            let Some(z) = c.pts[k].zone else { continue };
            let Some((f, _)) = z.last else { continue };
            let r = dist(c.pts[k].x, tip);
            let w = 1.0 - super::domain::ring(r, radius).0;
            if w <= 0.0 {
                continue;
            }
            let dx = x1(k + 1) - x1(k - 1);
            if dx.abs() < 1e-12 * self.h {
                continue;
            }
            let (da, db) = (sep(k + 1), sep(k - 1));
            let dd = [(da[0] - db[0]) / dx, (da[1] - db[1]) / dx];
            sum += w * (f[0] * dd[0] + f[1] * dd[1]) / self.thickness;
        }
        sum
    }

    /// Check every growing tip (§7) and grow it; records the tip history. True if some tip
    /// advanced.
    pub fn propagate(&mut self, v: &View<'_>, time: f64) -> bool {
        let mut any = false;
        let dt = self.dt;
        for ci in 0..self.cracks.len() {
            for t in 0..2 {
                self.cracks[ci].tips[t].grew = false;
                let Propagation::EnergyRelease {
                    toughness,
                    direction,
                    speed,
                    filter_time,
                    process_zone,
                } = self.cracks[ci].propagation.clone()
                else {
                    continue;
                };
                let tip_state = &self.cracks[ci].tips[t];
                if !tip_state.active || tip_state.on_interface {
                    continue;
                }
                let tf = self.tip_frame_j(ci, t, v, time);
                // J1 of a tip with a process zone already counts the whole zone (J_tip + J_zone,
                // `tip_frame_j`).
                let TipFrameJ {
                    tip, e1, e2, j1, ..
                } = tf;
                let radius = self.j_radius(ci);
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
                // A kinked branch as long as the ring is driven by its own tip again.
                if let Some(at) = self.cracks[ci].tips[t].kink_at
                    && self.cracks[ci].tips[t].advance - at >= radius
                {
                    self.cracks[ci].tips[t].kink_at = None;
                }
                let (g, dir) = match (&direction, tf.kink) {
                    // A short kinked branch (pitfall 15): it keeps the criterion's angle from
                    // the parent's current K and the kinked-crack G there; for the equation of
                    // motion the tip's dynamic G, Freund's g(v) times it (the rate the law
                    // expects, as a running tip's domain J is).
                    (
                        GrowthDirection::MaxEnergyRelease | GrowthDirection::MaxHoopStress,
                        Some(kd),
                    ) => {
                        let [a, b] = kd.parent_k;
                        let th = if matches!(direction, GrowthDirection::MaxHoopStress) {
                            hoop_stress_angle(a, b)
                        } else {
                            max_energy_release_angle(a, b).0
                        };
                        let (s, co) = th.sin_cos();
                        let (p1, p2) = (kd.parent_e1, [-kd.parent_e1[1], kd.parent_e1[0]]);
                        let g_static = kd.at(th, tf.medium.e_prime).map_or(f64::NAN, |x| x.0);
                        let g = match speed {
                            GrowthSpeed::EquationOfMotion => {
                                g_static
                                    * freund_g(self.cracks[ci].tips[t].eom_speed, tf.medium.c_r)
                            }
                            GrowthSpeed::Wave => g_static,
                        };
                        (g, [co * p1[0] + s * p2[0], co * p1[1] + s * p2[1]])
                    }
                    (GrowthDirection::MaxEnergyRelease | GrowthDirection::MaxHoopStress, None) => {
                        let speed = self.tip_speed(&self.cracks[ci].tips[t], time);
                        let k = self.tip_k(ci, t, &tf, speed);
                        if matches!(direction, GrowthDirection::MaxHoopStress) {
                            kink(hoop_stress_angle, k)
                        } else {
                            kink(|a, b| max_energy_release_angle(a, b).0, k)
                        }
                    }
                    (&GrowthDirection::Fixed(d), _) => {
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
                let (step_len, gamma, zone_len) = match speed {
                    GrowthSpeed::Wave => {
                        if !(g.is_finite() && g >= toughness.at_rest()) {
                            continue;
                        }
                        (self.cfl * self.h, toughness.at_rest(), 0.0)
                    }
                    GrowthSpeed::EquationOfMotion => {
                        let tau = filter_time.unwrap_or(
                            Propagation::DEFAULT_FILTER_TRANSITS * radius / tf.medium.c_s,
                        );
                        let tip_state = &mut self.cracks[ci].tips[t];
                        if g.is_finite() {
                            // Until its first advance a tip follows G unfiltered: the J of a
                            // crack that has never moved is smooth in time, and the filter
                            // would start it τ late (Freund's step wave: 1.2–1.7 µs late with
                            // τ = 1.2–1.9 µs). After an arrest the filter stays: the waves the
                            // arrest sends out cross the ring (unfiltered restarts ran the
                            // damped DCB 8.5 % past beam theory).
                            if tip_state.g_filtered.is_finite() && tip_state.advance > 0.0 {
                                let a = 1.0 - (-dt / tau).exp();
                                tip_state.g_filtered += a * (g - tip_state.g_filtered);
                            } else {
                                tip_state.g_filtered = g;
                            }
                        }
                        let prescribed = self.cracks[ci].prescribed;
                        let tip_state = &mut self.cracks[ci].tips[t];
                        let speed = match prescribed {
                            Some([v, _]) => v,
                            None => eom_speed(
                                tip_state.g_filtered,
                                tip_state.eom_speed,
                                tf.medium.c_r,
                                &toughness,
                                dt,
                                tau,
                            ),
                        };
                        tip_state.eom_speed = speed;
                        if speed <= 0.0 {
                            continue;
                        }
                        let zone_len =
                            process_zone.unwrap_or(Propagation::DEFAULT_ZONE_FRACTION * radius);
                        // Γ(v), or at the wall that closes it near the speed limit, the
                        // energy that reaches the tip (`WALL_FRACTION`).
                        let gamma_v = prescribed.map_or_else(|| toughness.at(speed), |p| p[1]);
                        let gamma = if at_speed_wall(speed, tf.medium.c_r) {
                            gamma_v.max(tip_state.g_filtered)
                        } else {
                            gamma_v
                        };
                        tip_state.above_toughness += (gamma - gamma_v) * speed * dt;
                        (speed * dt, gamma, zone_len)
                    }
                };
                // A turn of more than KINK_DEG from the tip's direction starts a kinked
                // branch, unless the tip is already on a short one (whose direction comes
                // from the parent, not from its own still-straight chord).
                {
                    let tip_state = &mut self.cracks[ci].tips[t];
                    if tip_state.kink_at.is_none()
                        && dir[0] * e1[0] + dir[1] * e1[1] < KINK_DEG.to_radians().cos()
                    {
                        tip_state.kink_at = Some(tip_state.advance);
                    }
                }
                let new_zone =
                    (zone_len > 0.0).then(|| Zone::new(gamma, zone_len, tf.medium.e_prime));
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
                let xi = v.geom.xi(&new);
                let (ix, iy) = (xi[0].round(), xi[1].round());
                let has_material = ix >= 1.0
                    && iy >= 1.0
                    && (ix as usize) + 1 < v.geom.nx()
                    && (iy as usize) + 1 < v.geom.ny()
                    && v.nodes[v.geom.at(ix as usize, iy as usize)].m > 0.0;
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
                let mut point = CrackPoint::grown(new, ahead0);
                point.zone = new_zone;
                if short {
                    // The tip point moves on; a zone it carries is replaced by a fresh one
                    // (a tip point carries no traction, so nothing is lost).
                    if let Some(z) = c.pts[tip_i].zone.as_mut().zip(point.zone.as_mut()) {
                        z.1.side = z.0.side;
                    }
                    c.pts[tip_i] = point;
                } else {
                    // The old tip point becomes a face point: a scene point gets a zone over
                    // the half of the new segment it carries.
                    if let Some(z) = new_zone
                        && c.pts[tip_i].zone.is_none()
                    {
                        c.pts[tip_i].zone = Some(Zone {
                            side: if t == 0 { -1 } else { 1 },
                            ..z
                        });
                    }
                    if t == 0 {
                        c.pts.insert(0, point);
                    } else {
                        c.pts.push(point);
                    }
                }
                c.tips[t].advance += step_len;
                c.tips[t].required += gamma * step_len;
                c.tips[t].released += g * step_len;
                c.tips[t].grew = true;
                c.tips[t].cached_j = None;
                any = true;
            }
        }
        self.interface_fronts();
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
