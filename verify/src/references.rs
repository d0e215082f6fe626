//! Analytic reference answers (`reference-solutions.md`): the material, Tada's factors, the
//! mode II plate, Freund's K_I(t), the bar period.

use std::f64::consts::PI;

use serde_json::{Value, json};

/// Homalite-100 with its dynamic constants (E = 5.2 GPa, ν = 0.34, ρ = 1230 kg/m³), as a
/// scene material.
pub fn homalite() -> Value {
    json!({"model": "linear_elastic", "density": 1230.0,
        "youngs_modulus": 5.2e9, "poissons_ratio": 0.34})
}

/// Tada's centre-crack factor F(a/b) for a strip of width 2b under remote tension:
/// F = (1 − 0.025(a/b)² + 0.06(a/b)⁴)·sqrt(sec(πa/2b)); K_I = σ√(πa)·F.
pub fn tada_center(ab: f64) -> f64 {
    let s = (PI * ab / 2.0).cos().recip().sqrt();
    (1.0 - 0.025 * ab * ab + 0.06 * ab.powi(4)) * s
}

/// Tada's single-edge-crack factor F(a/b) for a strip of width b under remote tension:
/// F = sqrt((2b/πa) tan(πa/2b))·(0.752 + 2.02 a/b + 0.37(1 − sin(πa/2b))³)/cos(πa/2b).
pub fn tada_edge(ab: f64) -> f64 {
    let x = PI * ab / 2.0;
    ((2.0 / (PI * ab)) * x.tan()).sqrt() * (0.752 + 2.02 * ab + 0.37 * (1.0 - x.sin()).powi(3))
        / x.cos()
}

/// Mode II centre crack in a large plate under remote shear τ: K_II = τ√(πa).
pub fn mode_two_k(tau: f64, a: f64) -> f64 {
    tau * (PI * a).sqrt()
}

/// Freund's semi-infinite crack struck by a plane step tensile wave σ*, a time `t` after the
/// wave reaches the tip: K_I(t) = 2σ*·sqrt(c_L t (1 − 2ν)/π)/(1 − ν) (0 for t ≤ 0).
pub fn freund_k1(sigma: f64, c_l: f64, nu: f64, t: f64) -> f64 {
    if t <= 0.0 {
        return 0.0;
    }
    2.0 * sigma * (c_l * t * (1.0 - 2.0 * nu) / PI).sqrt() / (1.0 - nu)
}

/// First-mode period of a fixed–free bar of length L: T = 4L/c with c = sqrt(E/ρ) (ν = 0).
pub fn bar_period(length: f64, youngs: f64, density: f64) -> f64 {
    4.0 * length / (youngs / density).sqrt()
}
