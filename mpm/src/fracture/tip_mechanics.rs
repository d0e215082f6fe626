//! Crack-tip mechanics that the J and K code and the growth laws share (`algorithm.md`
//! §6–§7): the moving-crack factors A_I(v), A_II(v) of Freund's G–K relation, the auxiliary
//! Williams fields of the interaction integral, and the kink criteria.
//!
//! Everything here is pure (no grid, no particles), in the tip frame: x1 ahead along the
//! crack, x2 to its left; θ measured from x1, positive towards x2.

use std::f64::consts::PI;

/// The elastic constants a tip needs, in the scene's 2D state.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TipMedium {
    /// Shear modulus μ (Pa).
    pub mu: f64,
    /// Kolosov constant κ: 3 − 4ν (plane strain), (3 − ν)/(1 + ν) (plane stress).
    pub kappa: f64,
    /// E' of G = K²/E': E/(1 − ν²) (plane strain), E (plane stress).
    pub e_prime: f64,
    /// The ν of Freund's A(v): ν (plane strain), ν/(1 + ν) (plane stress).
    pub nu_dyn: f64,
    /// Dilatational speed c_L of the 2D state (plane stress: √(E/(ρ(1 − ν²)))).
    pub c_l: f64,
    /// Shear speed c_S.
    pub c_s: f64,
    /// Rayleigh speed c_R.
    pub c_r: f64,
}

impl TipMedium {
    /// The constants of an isotropic material (E, ν, ρ) in plane strain or plane stress.
    pub fn new(e: f64, nu: f64, rho: f64, plane_stress: bool) -> TipMedium {
        let mu = e / (2.0 * (1.0 + nu));
        let c_s = (mu / rho).sqrt();
        let (kappa, e_prime, nu_dyn, c_l) = if plane_stress {
            (
                (3.0 - nu) / (1.0 + nu),
                e,
                nu / (1.0 + nu),
                (e / (rho * (1.0 - nu * nu))).sqrt(),
            )
        } else {
            (
                3.0 - 4.0 * nu,
                e / (1.0 - nu * nu),
                nu,
                (e * (1.0 - nu) / (rho * (1.0 + nu) * (1.0 - 2.0 * nu))).sqrt(),
            )
        };
        let c_r = fracture_api::scene::rayleigh_speed(c_l, c_s);
        TipMedium {
            mu,
            kappa,
            e_prime,
            nu_dyn,
            c_l,
            c_s,
            c_r,
        }
    }

    /// Freund's moving-crack factors (A_I(v), A_II(v)) of G = [A_I K_I² + A_II K_II²]/E'
    /// (Freund 1990, eq. 5.3.10; `reference-solutions.md`):
    /// A_I = v²α_d/((1 − ν)c_S²D), A_II = v²α_s/((1 − ν)c_S²D), α_d = √(1 − v²/c_L²),
    /// α_s = √(1 − v²/c_S²), D = 4α_dα_s − (1 + α_s²)², with the ν and c_L of the 2D state.
    /// Evaluated in a form without cancellation, so A → 1 smoothly as v → 0 (no cut-off);
    /// `None` at and above c_R, where D ≤ 0 and a K is not defined (an intersonic tip).
    pub fn moving_factors(&self, v: f64) -> Option<(f64, f64)> {
        let v = v.abs();
        if !v.is_finite() || v >= self.c_r {
            return None;
        }
        let d2 = (v / self.c_l).powi(2);
        let s2 = (v / self.c_s).powi(2);
        let beta = (self.c_s / self.c_l).powi(2);
        let (ad, as_) = ((1.0 - d2).sqrt(), (1.0 - s2).sqrt());
        // D/s² with 4α_dα_s − 4 = 4((α_dα_s)² − 1)/(α_dα_s + 1) and
        // (α_dα_s)² − 1 = s²(d²/s²·(s² − 1) − 1) + … written out: −d² − s² + d²s².
        let dn = 4.0 * (d2 - beta - 1.0) / (1.0 + ad * as_) + 4.0 - s2;
        if dn <= 0.0 {
            return None;
        }
        let k = 1.0 / ((1.0 - self.nu_dyn) * dn);
        Some((k * ad, k * as_))
    }
}

/// Which auxiliary field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Opening, K_I = 1.
    I,
    /// Sliding, K_II = 1.
    II,
}

/// The auxiliary Williams field of unit K at (r, θ) in the tip frame: displacement
/// (u1, u2) and stress (σ11, σ22, σ12) (Williams 1957; any fracture text, e.g. Anderson
/// table 2.1–2.2).
pub fn williams(mode: Mode, r: f64, th: f64, m: &TipMedium) -> ([f64; 2], [f64; 3]) {
    let (s2, c2) = (0.5 * th).sin_cos();
    let (s32, c32) = (1.5 * th).sin_cos();
    let ru = (r / (2.0 * PI)).sqrt() / (2.0 * m.mu);
    let rs = 1.0 / (2.0 * PI * r).sqrt();
    let k = m.kappa;
    match mode {
        Mode::I => (
            [
                ru * c2 * (k - 1.0 + 2.0 * s2 * s2),
                ru * s2 * (k + 1.0 - 2.0 * c2 * c2),
            ],
            [
                rs * c2 * (1.0 - s2 * s32),
                rs * c2 * (1.0 + s2 * s32),
                rs * s2 * c2 * c32,
            ],
        ),
        Mode::II => (
            [
                ru * s2 * (k + 1.0 + 2.0 * c2 * c2),
                -ru * c2 * (k - 1.0 - 2.0 * s2 * s2),
            ],
            [
                -rs * s2 * (2.0 + c2 * c32),
                rs * s2 * c2 * c32,
                rs * c2 * (1.0 - s2 * s32),
            ],
        ),
    }
}

/// ∂u^aux/∂x1 of [`williams`] at the tip-frame point (x1, x2): u ∝ √r, so
/// ∂u/∂r = u/(2r), and ∂u/∂θ by a central difference in θ (the field is smooth away from
/// the crack faces θ = ±π, where particles do not sit); ∂/∂x1 = cos θ ∂/∂r − sin θ/r ∂/∂θ.
pub fn williams_du_dx1(mode: Mode, x: [f64; 2], m: &TipMedium) -> [f64; 2] {
    let r = x[0].hypot(x[1]);
    let th = x[1].atan2(x[0]);
    let (u, _) = williams(mode, r, th, m);
    let e = 1e-6;
    let (up, _) = williams(mode, r, th + e, m);
    let (um, _) = williams(mode, r, th - e, m);
    let (s, c) = th.sin_cos();
    let mut d = [0.0; 2];
    for i in 0..2 {
        let du_dr = u[i] / (2.0 * r);
        let du_dth = (up[i] - um[i]) / (2.0 * e);
        d[i] = c * du_dr - s / r * du_dth;
    }
    d
}

/// Kink angle of the maximum hoop stress criterion (Erdogan & Sih 1963):
/// θ_c = 2·atan[(K_I − √(K_I² + 8K_II²))/(4K_II)]; 0 for K_II = 0, −70.53° for pure mode II
/// with K_II > 0. For K_I < 0 (closed faces) the formula still gives the angle at which
/// the hoop stress is largest.
pub fn hoop_stress_angle(k1: f64, k2: f64) -> f64 {
    if k2 == 0.0 || !(k1.is_finite() && k2.is_finite()) {
        return 0.0;
    }
    2.0 * ((k1 - (k1 * k1 + 8.0 * k2 * k2).sqrt()) / (4.0 * k2)).atan()
}

/// Stress intensity factors (k1, k2) at the tip of an infinitesimal kink at angle θ, from the
/// parent tip's (K_I, K_II): the kinked-crack solution of Hussain, Pu & Underwood (1974,
/// ASTM STP 560), in this module's sign convention (θ > 0 towards x2):
/// k1 = F(θ)(K_I cos θ − (3/2)K_II sin θ), k2 = F(θ)(K_II cos θ + (1/2)K_I sin θ),
/// F(θ) = 4/(3 + cos²θ) · ((1 − θ/π)/(1 + θ/π))^(θ/(2π)).
pub fn kinked_k(k1: f64, k2: f64, th: f64) -> (f64, f64) {
    let c = th.cos();
    let f = 4.0 / (3.0 + c * c) * ((1.0 - th / PI) / (1.0 + th / PI)).powf(th / (2.0 * PI));
    let s = th.sin();
    (f * (k1 * c - 1.5 * k2 * s), f * (k2 * c + 0.5 * k1 * s))
}

/// The kink angle of largest energy release G(θ) = (k1² + k2²)/E' of the kinked extension
/// ([`kinked_k`]) among the angles that open it (k1 ≥ 0), and G(θ)·E' there. Pure mode II
/// kinks at ∓75.2° (Hussain, Pu & Underwood), pure mode I at 0. A scan in 0.5° steps on
/// (−179°, 179°), refined by golden-section search.
pub fn max_energy_release_angle(k1: f64, k2: f64) -> (f64, f64) {
    let g = |th: f64| {
        let (a, b) = kinked_k(k1, k2, th);
        if a < 0.0 { -1.0 } else { a * a + b * b }
    };
    if !(k1.is_finite() && k2.is_finite()) {
        return (0.0, f64::NAN);
    }
    let step = 0.5_f64.to_radians();
    let lim = 179.0_f64.to_radians();
    let mut best = (g(0.0), 0.0);
    let n = (lim / step) as i64;
    for i in -n..=n {
        let th = i as f64 * step;
        let v = g(th);
        // Ties (pure mode I: symmetric) keep the angle nearest 0.
        if v > best.0 * (1.0 + 1e-12) {
            best = (v, th);
        }
    }
    if best.1 == 0.0 {
        return (0.0, best.0.max(0.0));
    }
    // Golden-section refinement inside the bracketing cell.
    let (mut a, mut b) = (best.1 - step, best.1 + step);
    let r = 0.5 * (5.0_f64.sqrt() - 1.0);
    let (mut c, mut d) = (b - r * (b - a), a + r * (b - a));
    for _ in 0..60 {
        if g(c) > g(d) {
            b = d;
        } else {
            a = c;
        }
        c = b - r * (b - a);
        d = a + r * (b - a);
    }
    let th = 0.5 * (a + b);
    (th, g(th).max(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn homalite(plane_stress: bool) -> TipMedium {
        TipMedium::new(5.2e9, 0.34, 1230.0, plane_stress)
    }

    /// The formula of `reference-solutions.md` evaluated directly (cancels at small v).
    fn freund_direct(m: &TipMedium, v: f64) -> (f64, f64) {
        let ad = (1.0 - (v / m.c_l).powi(2)).sqrt();
        let as_ = (1.0 - (v / m.c_s).powi(2)).sqrt();
        let d = 4.0 * ad * as_ - (1.0 + as_ * as_).powi(2);
        let k = v * v / ((1.0 - m.nu_dyn) * m.c_s * m.c_s * d);
        (k * ad, k * as_)
    }

    #[test]
    fn moving_factors_match_freund_in_both_states_and_are_continuous() {
        for ps in [false, true] {
            let m = homalite(ps);
            // Against the direct formula where it is well conditioned (rel. 1e-9).
            for f in [0.05, 0.2, 0.5, 0.8, 0.9, 0.95, 0.97, 0.99] {
                let v = f * m.c_r;
                let (a, b) = m.moving_factors(v).unwrap_or((f64::NAN, f64::NAN));
                let (ea, eb) = freund_direct(&m, v);
                assert!((a / ea - 1.0).abs() < 1e-9, "ps={ps} v={v}: {a} vs {ea}");
                assert!((b / eb - 1.0).abs() < 1e-9, "ps={ps} v={v}: {b} vs {eb}");
                assert!(a > 1.0 && b > 1.0, "A > 1 for a moving tip");
            }
            // A → 1 as v → 0 (both states: the plane-stress ν/(1+ν) and c_L make it so).
            let (a0, b0) = m.moving_factors(0.0).unwrap_or_default();
            assert!(
                (a0 - 1.0).abs() < 1e-12 && (b0 - 1.0).abs() < 1e-12,
                "{a0} {b0}"
            );
            // Continuous: no jump anywhere below c_R, in particular across the old cut-offs
            // (1e-3 c_S and 0.95 c_R). A diverges like 1/(c_R − v), so between speeds
            // Δv = 1e-4 c_R apart it may change by about Δv/(c_R − v), never more than 3×.
            let mut prev = m.moving_factors(0.0).unwrap_or_default();
            for i in 1..9990 {
                let v = i as f64 * 1e-4 * m.c_r;
                let cur = m.moving_factors(v).unwrap_or_default();
                let jump = (cur.0 / prev.0 - 1.0).abs();
                let allowed = 3.0 * 1e-4 * m.c_r / (m.c_r - v) + 1e-9;
                assert!(jump < allowed, "ps={ps}: A_I jumps {jump} at v = {v}");
                assert!(cur.0 >= prev.0, "A_I grows with v");
                prev = cur;
            }
            // Undefined at and above c_R.
            assert!(m.moving_factors(m.c_r).is_none());
            assert!(m.moving_factors(0.5 * (m.c_s + m.c_l)).is_none());
        }
        // Plane stress is not plane strain with its own c_L: the old code's (1 − ν) gave
        // A_I(0) = 1.13 in plane stress.
        let ps = homalite(true);
        let wrong = 1.0 / (2.0 * (1.0 - 0.34) * (1.0 - (ps.c_s / ps.c_l).powi(2)));
        assert!((wrong - 1.0).abs() > 0.1, "{wrong}");
    }

    #[test]
    fn williams_fields_are_the_k_fields() {
        let m = homalite(false);
        // Ahead of the tip (θ = 0): σ22 = σ11 = K/√(2πr), σ12 = 0 in mode I; σ12 = K/√(2πr)
        // in mode II.
        let r = 1e-3;
        let (_, s) = williams(Mode::I, r, 0.0, &m);
        let k = 1.0 / (2.0 * PI * r).sqrt();
        assert!((s[1] / k - 1.0).abs() < 1e-12 && (s[0] / k - 1.0).abs() < 1e-12);
        assert!(s[2].abs() < 1e-12 * k);
        let (_, s) = williams(Mode::II, r, 0.0, &m);
        assert!((s[2] / k - 1.0).abs() < 1e-12 && s[0].abs() < 1e-12 * k);
        // Crack opening of mode I: u2(π) − u2(−π) = (κ + 1)/μ √(r/2π) (COD of the K field).
        let (up, _) = williams(Mode::I, r, PI, &m);
        let (um, _) = williams(Mode::I, r, -PI, &m);
        let cod = (m.kappa + 1.0) / m.mu * (r / (2.0 * PI)).sqrt();
        assert!(((up[1] - um[1]) / cod - 1.0).abs() < 1e-12);
        // Mode II sliding: u1(π) − u1(−π) = (κ + 1)/μ √(r/2π).
        let (up, _) = williams(Mode::II, r, PI, &m);
        let (um, _) = williams(Mode::II, r, -PI, &m);
        assert!(((up[0] - um[0]) / cod - 1.0).abs() < 1e-12);
        // ∂u/∂x1 against a finite difference in x1, and the strain against Hooke's law.
        for mode in [Mode::I, Mode::II] {
            for &(x, y) in &[(0.7e-3, 0.4e-3), (-0.5e-3, 0.3e-3), (0.2e-3, -0.9e-3)] {
                let d = williams_du_dx1(mode, [x, y], &m);
                let e = 1e-9;
                let u = |x: f64, y: f64| williams(mode, x.hypot(y), y.atan2(x), &m).0;
                let (a, b) = (u(x + e, y), u(x - e, y));
                for i in 0..2 {
                    let fd = (a[i] - b[i]) / (2.0 * e);
                    assert!((d[i] - fd).abs() < 1e-6 * fd.abs().max(1e-3 * d[0].abs()));
                }
                // ε11 = ∂u1/∂x1 = (σ11 − ν'σ22)/E'' with the plane-strain compliance.
                let (_, s) = williams(mode, x.hypot(y), y.atan2(x), &m);
                let nu = 0.34;
                let e_mod = 2.0 * m.mu * (1.0 + nu);
                let e11 = ((1.0 - nu * nu) * s[0] - nu * (1.0 + nu) * s[1]) / e_mod;
                assert!(
                    (d[0] - e11).abs() < 1e-6 * e11.abs().max(1e-9),
                    "{} {e11}",
                    d[0]
                );
            }
        }
    }

    #[test]
    fn kink_angles() {
        let deg = |x: f64| x.to_degrees();
        // Erdogan–Sih: 0, −70.53° (pure mode II, K_II > 0), −53.13° (K_II = K_I).
        assert_eq!(hoop_stress_angle(1.0, 0.0), 0.0);
        assert!((deg(hoop_stress_angle(0.0, 1.0)) + 70.5288).abs() < 1e-3);
        assert!((deg(hoop_stress_angle(1.0, 1.0)) + 53.1301).abs() < 1e-3);
        assert!((deg(hoop_stress_angle(0.0, -1.0)) - 70.5288).abs() < 1e-3);
        // Maximum energy release of the kinked extension: ∓75.2° for pure mode II, 0 for
        // pure mode I, and the kinked k1 equals K_I at θ = 0 (F(0) = 1).
        let (th, g) = max_energy_release_angle(0.0, 1.0);
        assert!((deg(th) + 75.23).abs() < 0.05, "{}", deg(th));
        assert!(
            g > 1.0,
            "a kink releases more than the straight extension would: {g}"
        );
        let (th, _) = max_energy_release_angle(0.0, -1.0);
        assert!((deg(th) - 75.23).abs() < 0.05);
        assert_eq!(max_energy_release_angle(1.0, 0.0).0, 0.0);
        assert_eq!(kinked_k(2.0, 3.0, 0.0), (2.0, 3.0));
        // Mixed mode lies between: K_II = K_I gives a kink between 0 and the mode II angle.
        let (th, _) = max_energy_release_angle(1.0, 1.0);
        assert!(deg(th) < -40.0 && deg(th) > -75.0, "{}", deg(th));
    }
}
