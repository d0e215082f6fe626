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
//!   transient after an advance neither starts nor stops the tip; the speed relaxes on the
//!   balance of the measured dynamic energy release rate and the toughness,
//!   dv/dt = (c_R/τ)(G_f − Γ(v))/Γ(v) (`eom_speed`), whose steady state is Freund's
//!   g(v)·G* = Γ(v) below c_R; a resting tip starts once G_f ≥ Γ(0) and arrests when v
//!   falls to 0; the tip moves v·Δt. Each point the tip leaves behind carries a
//!   process-zone traction (`zone.rs`) that dissipates Γ per unit area.

use fracture_api::scene::{GrowthDirection, GrowthSpeed, JIntegral, Propagation, Toughness};

use crate::tip_mechanics::{hoop_stress_angle, kinked_k, max_energy_release_angle};

use super::geometry::{dist, norm};
use super::j_integral::TipFrameJ;
use super::zone::Zone;
use super::{CrackPoint, Cracks, TipState, View, mass_weighted_at};

/// The equation of motion's speed after a step Δt: v relaxes on the measured balance,
/// dv/dt = (c_R/τ)·(G_f − Γ(v))/Γ(v), from rest only once G_f ≥ Γ(0), kept in [0, c_R).
///
/// G_f is the dynamic energy release rate measured at the running tip, Freund's g(v)·G*,
/// so the steady state is his equation of motion g(v)·G* = Γ(v), and it is stable: a faster
/// tip measures a smaller G (g′ < 0). Inverting G* = G_f/g(v) with the current v instead
/// (this law before) is not: G_f reaches the ring a wave travel time late, and the map
/// v ← c_R·(1 − Γ·g(v)/G_f) has only rest and c_R as attractors, so a double cantilever
/// beam under slow opening ran 4 mm past beam theory in one burst.
pub(crate) fn eom_speed(
    g_filtered: f64,
    v_prev: f64,
    c_r: f64,
    toughness: &Toughness,
    dt: f64,
    tau: f64,
) -> f64 {
    let v_max = (1.0 - 1e-3) * c_r;
    if !(g_filtered.is_finite() && c_r.is_finite() && c_r > 0.0 && tau > 0.0) {
        return 0.0;
    }
    let v = v_prev.clamp(0.0, v_max);
    if v <= 0.0 && g_filtered < toughness.at_rest() {
        return 0.0;
    }
    let gamma = toughness.at(v);
    if !(gamma.is_finite() && gamma > 0.0) {
        return 0.0;
    }
    (v + dt / tau * c_r * (g_filtered - gamma) / gamma).clamp(0.0, v_max)
}

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

    /// The outer radius of crack `ci`'s J domain (the contour's half-size for a contour).
    fn j_radius(&self, ci: usize) -> f64 {
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
    fn zone_outside_domain(&self, ci: usize, t: usize, e1: [f64; 2], radius: f64) -> f64 {
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
                let TipFrameJ {
                    tip,
                    e1,
                    e2,
                    mut j1,
                    ..
                } = tf;
                let radius = self.j_radius(ci);
                if matches!(speed, GrowthSpeed::EquationOfMotion) {
                    j1 += self.zone_outside_domain(ci, t, e1, radius);
                }
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
                let (step_len, gamma, zone_len) = match speed {
                    GrowthSpeed::Wave => {
                        if !(g.is_finite() && g >= toughness.at_rest()) {
                            continue;
                        }
                        (self.cfl * self.h, toughness.at_rest(), 0.0)
                    }
                    GrowthSpeed::EquationOfMotion => {
                        let tau = filter_time
                            .unwrap_or(Propagation::DEFAULT_FILTER_RADII * radius / tf.medium.c_s);
                        let tip_state = &mut self.cracks[ci].tips[t];
                        if g.is_finite() {
                            if tip_state.g_filtered.is_finite() {
                                let a = 1.0 - (-dt / tau).exp();
                                tip_state.g_filtered += a * (g - tip_state.g_filtered);
                            } else {
                                tip_state.g_filtered = g;
                            }
                        }
                        let speed = eom_speed(
                            tip_state.g_filtered,
                            tip_state.eom_speed,
                            tf.medium.c_r,
                            &toughness,
                            dt,
                            tau,
                        );
                        tip_state.eom_speed = speed;
                        if speed <= 0.0 {
                            continue;
                        }
                        let zone_len =
                            process_zone.unwrap_or(Propagation::DEFAULT_ZONE_FRACTION * radius);
                        (speed * dt, toughness.at(speed), zone_len)
                    }
                };
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
