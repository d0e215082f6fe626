//! The growth law of a tip that moves by the equation of motion (`algorithm.md` §7): Freund's
//! g(v), the speed that balances the measured dynamic energy release rate against Γ(v), the
//! relaxation of the speed towards it, the wall near c_R. Dimension-free: a 2D tip and a
//! point of a 3D front take the same law.

use fracture_api::scene::{Toughness, bisect};

/// Freund's universal function of the dynamic energy release rate, g(v) ≈ 1 − v/c_R
/// (Freund 1990, §6.4; exact at v = 0 and v = c_R for both modes). It only sets how fast
/// [`eom_speed`] approaches its steady state, never where that state is.
pub fn freund_g(v: f64, c_r: f64) -> f64 {
    (1.0 - v / c_r).max(0.0)
}

/// The speed at which a tip whose measured dynamic energy release rate is G_f at speed v
/// would balance its toughness: Freund's equation of motion g(v_t)·G* = Γ(v_t) with the
/// static-equivalent G* = G_f/g(v). The root is found by bisection on [0, v_max] (the first
/// sign change of g·G* − Γ, which falls with v for any non-decreasing Γ(v)); 0 when the tip
/// would not run even from rest.
pub fn target_speed(g_filtered: f64, v: f64, c_r: f64, v_max: f64, toughness: &Toughness) -> f64 {
    let gv = freund_g(v, c_r);
    if !(g_filtered > 0.0 && gv > 0.0) {
        return 0.0;
    }
    let g_star = g_filtered / gv;
    let excess = |u: f64| freund_g(u, c_r) * g_star - toughness.at(u);
    let at_rest = excess(0.0);
    if at_rest.is_nan() || at_rest <= 0.0 {
        return 0.0;
    }
    if excess(v_max) >= 0.0 {
        return v_max;
    }
    bisect(0.0, v_max, 48, |u| excess(u) > 0.0).0
}

/// The equation of motion's speed limit, as a fraction of c_R: Freund's g(v) vanishes at
/// c_R, so no finite G* drives a tip there.
pub const SPEED_LIMIT: f64 = 1.0 - 1e-3;

/// Where the toughness curve is closed by a wall: from 99 % of the speed limit up, the new
/// surface takes the energy that reaches the tip, max(Γ(v), G_f) (`propagate`), so any
/// G_f ≥ Γ(v) balances there. The grid does not deliver Freund's fall of G_f towards c_R
/// (g(v) → 0): on the reduced Rosakis bond a tip held near c_R keeps G_f ≈ 400–1,000 J/m²
/// against Γ = 25 or 250. Taking only Γ(v) there left the difference in the body next to the
/// new faces, and J1 then depended on the ring (0.5 mm cells, J_Ic = 25: 680 / 458 / 44 J/m²
/// on 3 / 6 / 12 mm rings, 5.3 % of the 6 mm ring's samples below −0.1 Γ; with the wall 0 %).
pub const WALL_FRACTION: f64 = 0.99;

/// A growth direction this far (degrees) from the tip's direction starts a kinked branch,
/// driven from the parent crack's field until it is as long as the J ring
/// (`j_integral.rs`, `algorithm.md` pitfall 15).
pub const KINK_DEG: f64 = 10.0;

/// Whether a tip running at v is at the wall that closes Γ(v) ([`WALL_FRACTION`]).
pub fn at_speed_wall(v: f64, c_r: f64) -> bool {
    v >= WALL_FRACTION * SPEED_LIMIT * c_r
}

/// The equation of motion's speed after a step Δt: v relaxes over τ towards the speed v_t at
/// which the measured balance would hold, dv/dt = (v_t − v)/τ, with g(v_t)·G* = Γ(v_t) and
/// G* = G_f/g(v) ([`target_speed`]); from rest only once G_f ≥ Γ(0); a tip whose target is
/// rest arrests at once (G_f is already filtered over τ). Kept in [0, [`SPEED_LIMIT`]·c_R].
///
/// G_f is the dynamic energy release rate measured at the running tip, Freund's g(v)·G*, so
/// v_t = v exactly where G_f = Γ(v): the steady state is his equation of motion whatever g
/// is. Linearised about it, δv′ = −δv(t − d)/τ with d the delay of the measurement (the
/// wave transit to the ring and the filter): a delayed feedback of unit gain, stable for any
/// G*/Γ. Relaxing on the raw balance, dv/dt = (c_R/τ)(G_f − Γ)/Γ (this law before), has the
/// gain G*/Γ instead — 20 to 300 on the Rosakis bond — and oscillated between 470 m/s and
/// c_R once the grid resolved the fall of G_f with speed; jumping to v_t at once (the law
/// before that) ran away to c_R or rest. Measured again on Freund's step wave with growth
/// (issue 34, 0.5 mm cells, ring 3.75 mm, τ = R/(2c_S) = 1.5 µs, J without the inertial disk of
/// `domain::INERTIA_EXCLUSION_CELLS`, `fracture run`): relaxing over
/// 0.3τ or jumping at once ran the fastest case at 0.97–1.0 c_R with J1 5–380 times Freund's
/// (1 − v/c_R)G*; with the process zone off, jumping at once did not run away (−6 % of the
/// 1 − v/c_R reference) — the zone's J1 rises with the tip's speed, and τ is what holds it.
pub fn eom_speed(
    g_filtered: f64,
    v_prev: f64,
    c_r: f64,
    toughness: &Toughness,
    dt: f64,
    tau: f64,
) -> f64 {
    let v_max = SPEED_LIMIT * c_r;
    if !(g_filtered.is_finite() && c_r.is_finite() && c_r > 0.0 && tau > 0.0) {
        return 0.0;
    }
    let v = v_prev.clamp(0.0, v_max);
    let rest = toughness.at_rest();
    if v <= 0.0 && (rest.is_nan() || g_filtered < rest) {
        return 0.0;
    }
    let v_t = target_speed(g_filtered, v, c_r, v_max, toughness);
    // Arrest at once (Freund 1990, ch. 7: the tip has no inertia; it stops when G* < Γ(0)).
    // G_f is already filtered over τ, so a one-step transient cannot stop the tip.
    if v_t <= 0.0 {
        return 0.0;
    }
    let next = v + (1.0 - (-dt / tau).exp()) * (v_t - v);
    next.clamp(0.0, v_max)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A plant that is not the law's model: the tip's measured G is the exact-shaped
    /// g(v) = (1 − v/c_R)/√(1 − v/c_L) (c_L = 2c_R) times G*, seen one filter time late and
    /// filtered as the solver does. Returns the speed after 400 τ, and the largest distance
    /// of v from `v_star` after `settle`.
    fn drive(g_star: f64, toughness: &Toughness, v_star: f64, settle: f64) -> (f64, f64) {
        let (c_r, tau) = (1000.0_f64, 1.0e-6_f64);
        let dt = tau / 50.0;
        let g_true = |v: f64| (1.0 - v / c_r) / (1.0 - v / (2.0 * c_r)).sqrt();
        let delay = 50; // steps: one τ
        let mut past = vec![0.0_f64; delay];
        let (mut v, mut g_f) = (0.0_f64, 0.0_f64);
        let mut worst: f64 = 0.0;
        for n in 0..20_000_u32 {
            let seen = past[n as usize % delay];
            past[n as usize % delay] = v;
            g_f += (1.0 - (-dt / tau).exp()) * (g_true(seen) * g_star - g_f);
            v = eom_speed(g_f, v, c_r, toughness, dt, tau);
            if f64::from(n) * dt >= settle {
                worst = worst.max((v - v_star).abs());
            }
        }
        (v, worst)
    }

    /// Bisection root of g_true(v)·G* = Γ(v).
    fn freund_root(g_star: f64, toughness: &Toughness) -> f64 {
        let c_r = 1000.0;
        let f =
            |v: f64| (1.0 - v / c_r) / (1.0 - v / (2.0 * c_r)).sqrt() * g_star - toughness.at(v);
        bisect(0.0, c_r, 60, |v| f(v) > 0.0).0
    }

    /// The steady speed is Freund's root for the true g (the law only knows 1 − v/c_R), and
    /// the tip settles on it without a limit cycle for G*/Γ from 1.5 to 200 — the range that
    /// made the earlier law (gain G*/Γ) oscillate — and for a toughness rising with speed.
    #[test]
    fn speed_settles_on_freunds_root_for_any_driving_ratio() {
        let cases = [
            (1.5, Toughness::Constant(1.0)),
            (20.0, Toughness::Constant(1.0)),
            (200.0, Toughness::Constant(1.0)),
            (
                20.0,
                Toughness::Table(vec![[0.0, 1.0], [500.0, 4.0], [900.0, 15.0]]),
            ),
        ];
        for (g_star, t) in cases {
            let v_star = freund_root(g_star, &t);
            let (v, worst) = drive(g_star, &t, v_star, 100.0e-6);
            assert!(
                (v - v_star).abs() < 0.005 * 1000.0 && worst < 0.01 * 1000.0,
                "G*/Γ0 {g_star}: v {v:.1} vs Freund's {v_star:.1} m/s, settled band ±{worst:.1}"
            );
        }
    }

    /// Below Γ(0) a resting tip does not start. A running tip arrests on Freund's criterion,
    /// the static-equivalent G* = G_f/g(v) below Γ(0), in the step it falls there; with
    /// G_f < Γ(0) but G* above it (a body with G* = 1.2 Γ measured at 500 m/s, g = 1/2: G_f =
    /// 0.6 Γ) it only slows, to the root of (1 − v/c_R)·1.2 = 1, c_R/6.
    #[test]
    fn rest_below_toughness_and_arrest() {
        let t = Toughness::Constant(1.0);
        let (c_r, dt, tau) = (1000.0, 1e-8, 1e-6);
        assert_eq!(eom_speed(0.99, 0.0, c_r, &t, dt, tau), 0.0);
        assert_eq!(eom_speed(0.45, 500.0, c_r, &t, dt, tau), 0.0);
        let mut v = 500.0;
        for _ in 0..3_000 {
            let g_f = (1.0 - v / c_r) * 1.2;
            v = eom_speed(g_f, v, c_r, &t, dt, tau);
            assert!(v > 0.0, "arrested with G* above Γ(0)");
        }
        // 3,000 steps = 30 τ: the relaxation towards 166.7 m/s has settled.
        assert!((v - c_r / 6.0).abs() < 1.0, "{v} m/s, not c_R/6");
    }
}
