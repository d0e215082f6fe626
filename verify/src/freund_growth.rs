//! Crack growth against known transients (issue 34): Freund's exact universal function g(v)
//! of a mode I crack in plane strain, Freund's step wave with a crack growing at constant Γ
//! (the scene, its exact and approximate references, a runner), and the strip with fixed
//! grips whose steady speed solves Γ(v*) = G_∞.
//!
//! Sources: Freund, *Dynamic Fracture Mechanics* (1990), ch. 5–7: the factorisation of the
//! Rayleigh function into S_±, the universal function k(v) of the stress intensity factor of a
//! tip moving at v, and the energy release rate G = (1 − ν²)/E·A_I(v)·K_I² of a moving tip
//! (`reference-solutions.md`, "Dynamic stress intensity factor (Freund)"). The book was not at
//! hand here, so its equation numbers are not quoted; each formula is stated in full and
//! pinned by the checks of this module's tests: the factorisation identity, k(0) = 1,
//! k(c_R) = 0, g(0) = 1, g(c_R) = 0, g decreasing.

use std::f64::consts::PI;

use fracture_api::Scene;
use fracture_api::scene::{Analysis, WaveSpeeds};
use serde_json::{Value, json};

use fracture_solver::{Simulation, SolverConfig};

use crate::*;

// ---------------------------------------------------------------------------------------
// Freund's universal functions.
// ---------------------------------------------------------------------------------------

/// Adaptive Simpson quadrature of `f` over [lo, hi] to an absolute tolerance `tol`
/// (Richardson-corrected, at most 2^40 panels along any branch).
fn adaptive_simpson(f: &dyn Fn(f64) -> f64, lo: f64, hi: f64, tol: f64) -> f64 {
    fn panel(a: f64, b: f64, fa: f64, fm: f64, fb: f64) -> f64 {
        (b - a) / 6.0 * (fa + 4.0 * fm + fb)
    }
    #[allow(clippy::too_many_arguments)]
    fn split(
        f: &dyn Fn(f64) -> f64,
        a: f64,
        b: f64,
        fa: f64,
        fm: f64,
        fb: f64,
        whole: f64,
        tol: f64,
        depth: u32,
    ) -> f64 {
        let m = 0.5 * (a + b);
        let (lm, rm) = (0.5 * (a + m), 0.5 * (m + b));
        let (flm, frm) = (f(lm), f(rm));
        let left = panel(a, m, fa, flm, fm);
        let right = panel(m, b, fm, frm, fb);
        let delta = left + right - whole;
        if depth == 0 || delta.abs() <= 15.0 * tol {
            return left + right + delta / 15.0;
        }
        split(f, a, m, fa, flm, fm, left, 0.5 * tol, depth - 1)
            + split(f, m, b, fm, frm, fb, right, 0.5 * tol, depth - 1)
    }
    let (fa, fm, fb) = (f(lo), f(0.5 * (lo + hi)), f(hi));
    split(f, lo, hi, fa, fm, fb, panel(lo, hi, fa, fm, fb), tol, 40)
}

/// Freund's S_+(ζ) for slownesses a = 1/c_L < b = 1/c_S (ζ in s/m, any real ζ > −a):
/// S_+(ζ) = exp{−(1/π) ∫_a^b θ(η) dη/(η + ζ)}, θ(η) = arg[(b² − 2η²)² + i·4η²√(η² − a²)√(b² − η²)],
/// the phase of the Rayleigh function on its branch cut, continuous in [0, π/2] (π/2 where
/// b² = 2η²). With S_−(ζ) = S_+(−ζ) it factorises the Rayleigh function,
/// R(ζ) = (b² − 2ζ²)² + 4ζ²√(a² − ζ²)√(b² − ζ²) = 2(b² − a²)(c² − ζ²)·S_+(ζ)·S_−(ζ), c = 1/c_R,
/// and S_± → 1 as |ζ| → ∞ (checked in the tests for |ζ| < a).
pub fn rayleigh_s_plus(zeta: f64, c_l: f64, c_s: f64) -> f64 {
    let (a, b) = (1.0 / c_l, 1.0 / c_s);
    let theta = |eta: f64| {
        let num = 4.0
            * eta
            * eta
            * (eta * eta - a * a).max(0.0).sqrt()
            * (b * b - eta * eta).max(0.0).sqrt();
        let den = (b * b - 2.0 * eta * eta).powi(2);
        num.atan2(den)
    };
    // η = m − d·cos φ takes the square-root ends of θ away: dη = d·sin φ dφ.
    let (m, d) = (0.5 * (a + b), 0.5 * (b - a));
    let integrand = |phi: f64| {
        let eta = m - d * phi.cos();
        theta(eta) * d * phi.sin() / (eta + zeta)
    };
    (-adaptive_simpson(&integrand, 0.0, PI, 1e-13) / PI).exp()
}

/// Freund's universal function of a mode I tip moving at v in plane strain: the stress
/// intensity factor is K_I(t) = k(v)·K_I*(t), K_I* that of the stationary crack with the same
/// length and load, and k(v) = (1 − v/c_R) / (√(1 − v/c_L)·S_+(1/v)) ([`rayleigh_s_plus`]).
/// k(0) = 1, k(c_R) = 0; 1 for v ≤ 0 and 0 for v ≥ c_R.
pub fn freund_k(v: f64, c_l: f64, c_s: f64, c_r: f64) -> f64 {
    if v <= 0.0 {
        return 1.0;
    }
    if v >= c_r {
        return 0.0;
    }
    (1.0 - v / c_r) / ((1.0 - v / c_l).sqrt() * rayleigh_s_plus(1.0 / v, c_l, c_s))
}

/// A_I(v) of the moving-crack energy release rate G = (1 − ν²)/E·A_I(v)·K_I² (plane strain,
/// `reference-solutions.md`): A_I = v²α_d/((1 − ν)c_S²D), α_d = √(1 − v²/c_L²),
/// α_s = √(1 − v²/c_S²), D = 4α_dα_s − (1 + α_s²)². Written without the cancellation of D at
/// small v: with s = v/c_S, κ = c_S²/c_L²,
/// D = s²[16(1 − κ) − (24 − 16κ)s² + 8s⁴ − s⁶]/[4α_dα_s + (2 − s²)²], and 1 − ν = 1/(2(1 − κ)).
/// A_I(0) = 1; it grows without bound towards c_R (D = 0 there).
pub fn freund_a1(v: f64, c_l: f64, c_s: f64) -> f64 {
    let s2 = (v / c_s).powi(2);
    let kappa = (c_s / c_l).powi(2);
    let alpha_d = (1.0 - v * v / (c_l * c_l)).max(0.0).sqrt();
    let alpha_s = (1.0 - s2).max(0.0).sqrt();
    let one_minus_nu = 0.5 / (1.0 - kappa);
    let poly = 16.0 * (1.0 - kappa) - (24.0 - 16.0 * kappa) * s2 + 8.0 * s2 * s2 - s2 * s2 * s2;
    alpha_d * (4.0 * alpha_d * alpha_s + (2.0 - s2).powi(2)) / (one_minus_nu * poly)
}

/// Freund's exact g(v) = A_I(v)·k(v)² ([`freund_a1`], [`freund_k`]): the dynamic energy
/// release rate of a mode I tip moving at v over the static one of the same crack and load,
/// G = g(v)·G*. g(0) = 1, g(c_R) = 0, decreasing; below the approximation 1 − v/c_R by
/// 3.5 % at 0.2 c_R, 10 % at 0.5 c_R and 23 % at 0.8 c_R for Homalite (ν = 0.34).
pub fn freund_g_exact(v: f64, c_l: f64, c_s: f64, c_r: f64) -> f64 {
    if v <= 0.0 {
        return 1.0;
    }
    if v >= c_r {
        return 0.0;
    }
    let k = freund_k(v, c_l, c_s, c_r);
    freund_a1(v, c_l, c_s) * k * k
}

/// The approximation of g used by the solver's equation of motion, 1 − v/c_R (0 past c_R).
pub fn freund_g_linear(v: f64, c_r: f64) -> f64 {
    (1.0 - v / c_r).clamp(0.0, 1.0)
}

// ---------------------------------------------------------------------------------------
// Growth at constant Γ under G*(t) ∝ t: the reference.
// ---------------------------------------------------------------------------------------

/// The motion of a tip at constant Γ driven by a static energy release rate that grows as
/// G*(t) = G*₁·t (Freund's step wave, t from the wave's arrival): initiation at t_f with
/// G*(t_f) = Γ, then g(v)·G*(t) = Γ, i.e. g(v(t)) = t_f/t, and l(t) = ∫ v dt.
///
/// With the exact g this is solved on a table of v (2,000 rows up to 0.995 c_R):
/// l = ∫_{t_f}^t v dt′ = t_f·[v/g(v) − ∫_0^v du/g(u)] (by parts with t = t_f/g(v)). With
/// g = 1 − v/c_R in closed form: v = c_R(1 − t_f/t), l = c_R[t − t_f − t_f ln(t/t_f)].
#[derive(Debug, Clone)]
pub struct GrowthReference {
    /// Initiation time t_f (s after the wave's arrival).
    pub t_f: f64,
    /// c_R (m/s).
    pub c_r: f64,
    /// Rows (v, g(v), ∫_0^v du/g(u)), ascending in v.
    table: Vec<[f64; 3]>,
}

impl GrowthReference {
    /// The reference for initiation at `t_f` in a material of wave speeds c_L, c_S, c_R.
    pub fn new(t_f: f64, c_l: f64, c_s: f64, c_r: f64) -> GrowthReference {
        const ROWS: usize = 2000;
        let v_max = 0.995 * c_r;
        let mut table = Vec::with_capacity(ROWS + 1);
        let mut integral = 0.0;
        let mut prev: Option<[f64; 2]> = None;
        for i in 0..=ROWS {
            let v = v_max * i as f64 / ROWS as f64;
            let g = freund_g_exact(v, c_l, c_s, c_r);
            if let Some([v0, g0]) = prev {
                // Trapezoid on 1/g (smooth below 0.995 c_R).
                integral += 0.5 * (v - v0) * (1.0 / g0 + 1.0 / g);
            }
            table.push([v, g, integral]);
            prev = Some([v, g]);
        }
        GrowthReference { t_f, c_r, table }
    }

    /// Exact g(v) from the table (linear between rows; the last row past it).
    pub fn g(&self, v: f64) -> f64 {
        self.row_at_speed(v)[1]
    }

    fn row_at_speed(&self, v: f64) -> [f64; 3] {
        let n = self.table.len();
        let i = self.table.partition_point(|r| r[0] < v);
        if i == 0 {
            return self.table[0];
        }
        if i >= n {
            return self.table[n - 1];
        }
        let (r0, r1) = (self.table[i - 1], self.table[i]);
        let w = (v - r0[0]) / (r1[0] - r0[0]);
        [v, r0[1] + w * (r1[1] - r0[1]), r0[2] + w * (r1[2] - r0[2])]
    }

    /// The row where g(v) = `g` (g falls with v), interpolated.
    fn row_at_g(&self, g: f64) -> [f64; 3] {
        let n = self.table.len();
        let i = self.table.partition_point(|r| r[1] > g);
        if i == 0 {
            return self.table[0];
        }
        if i >= n {
            return self.table[n - 1];
        }
        let (r0, r1) = (self.table[i - 1], self.table[i]);
        let w = (r0[1] - g) / (r0[1] - r1[1]);
        [r0[0] + w * (r1[0] - r0[0]), g, r0[2] + w * (r1[2] - r0[2])]
    }

    /// Tip speed at time t (exact g): 0 before t_f, else the v with g(v) = t_f/t.
    pub fn speed(&self, t: f64) -> f64 {
        if t <= self.t_f {
            return 0.0;
        }
        self.row_at_g(self.t_f / t)[0]
    }

    /// Advance at time t (exact g): t_f·[v/g(v) − ∫_0^v du/g] = v·t − t_f·∫_0^v du/g.
    pub fn advance(&self, t: f64) -> f64 {
        if t <= self.t_f {
            return 0.0;
        }
        let r = self.row_at_g(self.t_f / t);
        (r[0] * t - self.t_f * r[2]).max(0.0)
    }

    /// Tip speed with g = 1 − v/c_R: c_R(1 − t_f/t).
    pub fn speed_linear(&self, t: f64) -> f64 {
        if t <= self.t_f {
            return 0.0;
        }
        self.c_r * (1.0 - self.t_f / t)
    }

    /// Advance with g = 1 − v/c_R: c_R[t − t_f − t_f ln(t/t_f)].
    pub fn advance_linear(&self, t: f64) -> f64 {
        if t <= self.t_f {
            return 0.0;
        }
        self.c_r * (t - self.t_f - self.t_f * (t / self.t_f).ln())
    }
}

/// Slope G*₁ of Freund's static energy release rate under a step wave σ*, G*(t) = G*₁·t:
/// G* = K*²(1 − ν²)/E with K*(t) = 2σ*√(c_L t(1 − 2ν)/π)/(1 − ν) ([`freund_k1`]), so
/// G*₁ = 4σ*²c_L(1 − 2ν)(1 + ν)/(π(1 − ν)E) (plane strain).
pub fn freund_g_star_rate(sigma: f64, c_l: f64, nu: f64, youngs: f64) -> f64 {
    4.0 * sigma * sigma * c_l * (1.0 - 2.0 * nu) * (1.0 + nu) / (PI * (1.0 - nu) * youngs)
}

// ---------------------------------------------------------------------------------------
// Regularisation overrides shared by the scenes.
// ---------------------------------------------------------------------------------------

/// Explicit regularisation of the growth law, so that a study can hold it fixed in metres
/// and seconds while h changes (`algorithm.md`, pitfall 13). `None`: the solver's default.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Regularisation {
    /// Outer radius of the J domain (m): `j_integral: {"method": "domain", "radius": r}`.
    pub j_radius: Option<f64>,
    /// Process-zone length behind the tip (m): `propagation.process_zone`.
    pub process_zone: Option<f64>,
    /// Filter time of J and of the speed's relaxation (s): `propagation.filter_time`.
    pub filter_time: Option<f64>,
}

impl Regularisation {
    /// Every value given.
    pub fn physical(j_radius: f64, process_zone: f64, filter_time: f64) -> Regularisation {
        Regularisation {
            j_radius: Some(j_radius),
            process_zone: Some(process_zone),
            filter_time: Some(filter_time),
        }
    }
    /// Whether every value is the solver's default.
    pub fn is_default(&self) -> bool {
        *self == Regularisation::default()
    }
    /// A short label: "defaults", or "r 3 mm, zone 1 mm, τ 1.2 µs" of the values given.
    pub fn label(&self) -> String {
        if self.is_default() {
            return "defaults".into();
        }
        let mut parts = Vec::new();
        if let Some(r) = self.j_radius {
            parts.push(format!("r {} mm", 1e3 * r));
        }
        if let Some(z) = self.process_zone {
            parts.push(format!("zone {} mm", 1e3 * z));
        }
        if let Some(f) = self.filter_time {
            parts.push(format!("τ {} µs", 1e6 * f));
        }
        parts.join(", ")
    }
    /// Write the values given into a crack of a scene document.
    fn apply(&self, crack: &mut Value) {
        if let Some(r) = self.j_radius {
            crack["j_integral"] = json!({"method": "domain", "radius": r});
        }
        if let Some(z) = self.process_zone {
            crack["propagation"]["process_zone"] = json!(z);
        }
        if let Some(f) = self.filter_time {
            crack["propagation"]["filter_time"] = json!(f);
        }
    }
}

/// Homalite-100 (dynamic constants) in plane strain: c_L, c_S, c_R.
fn homalite_speeds() -> WaveSpeeds {
    WaveSpeeds::new(5.2e9, 0.34, 1230.0, Analysis::PlaneStrain)
}

// ---------------------------------------------------------------------------------------
// Freund's step wave with a growing crack.
// ---------------------------------------------------------------------------------------

/// Geometry of the growing-crack step-wave scene (m).
const FG_WIDTH: f64 = 0.060;
const FG_CRACK: f64 = 0.020;
const FG_ABOVE: f64 = 0.035;
const FG_BELOW: f64 = 0.035;
const FG_SIGMA: f64 = 1.0e6;

/// The scene of Freund's step wave on a crack growing at constant Γ, with its reference.
#[derive(Debug, Clone)]
pub struct FreundGrowthScene {
    /// The scene (ends at t_c + window).
    pub scene: Scene,
    /// The speed the exact reference reaches at the end of the window, over c_R.
    pub target: f64,
    /// Toughness Γ (J/m²).
    pub gamma: f64,
    /// Step traction σ* (Pa).
    pub sigma: f64,
    /// Arrival of the wave at the crack plane t_c (s).
    pub t_c: f64,
    /// The valid window after t_c (s): until the first scattered wave reaches the moving tip
    /// ([`freund_growth_window`]).
    pub window: f64,
    /// Slope of G*(t) = G*₁·(t − t_c) (J/m²/s).
    pub g_star_rate: f64,
    /// Wave speeds (plane strain).
    pub speeds: WaveSpeeds,
    /// The exact and 1 − v/c_R references (times after t_c).
    pub reference: GrowthReference,
    /// The regularisation written into the scene.
    pub regularisation: Regularisation,
}

/// The valid window of the growing-crack step wave (s after the wave reaches the crack
/// plane) for a tip that advances `advance(τ)`: the first τ at which a wave scattered by
/// another feature reaches the moving tip. Paths (c_L τ against): the diffraction from the
/// mirror tip across the mouth's roller, 2a + l(τ); from the tip to the far roller and back,
/// 2(W − a) − l(τ); the faces' reflection from the top edge, 2·above; the transmitted wave's
/// reflection from the free bottom, 2·below.
pub fn freund_growth_window(
    c_l: f64,
    [width, crack, above, below]: [f64; 4],
    advance: &dyn Fn(f64) -> f64,
) -> f64 {
    let reached = |tau: f64| {
        let l = advance(tau);
        let first = (2.0 * crack + l)
            .min(2.0 * (width - crack) - l)
            .min(2.0 * above)
            .min(2.0 * below);
        c_l * tau >= first
    };
    let hi = 2.0 * width.max(above).max(below) / c_l;
    // The first path length grows slower than c_L τ, so `reached` switches once.
    fracture_api::scene::bisect(0.0, hi, 60, |tau| !reached(tau)).1
}

/// Freund's step wave (Homalite-100, plane strain, σ* = 1 MPa on the top edge, bottom free,
/// roller sides) on a 60 mm wide strip with a 20 mm edge crack at mid-cell, 35 mm of material
/// above and below, grown along its line by the equation of motion at a constant Γ chosen so
/// that the exact reference (g = A_I k²) runs at `target`·c_R at the end of the window.
/// The window (≈ 15.7 µs + l/c_L, the mirror tip's diffraction first) and Γ are found
/// together: t_f = g(target·c_R)·τ_w, Γ = G*₁·t_f. `reg` overrides the J radius, zone and
/// filter time; the scene ends at t_c + τ_w.
pub fn freund_growth(
    s: &Settings,
    target: f64,
    reg: &Regularisation,
) -> Result<FreundGrowthScene, VerifyError> {
    if !(target > 0.0 && target < 0.99) {
        return Err(VerifyError::Scene(format!(
            "target speed {target} c_R outside (0, 0.99)"
        )));
    }
    let sp = homalite_speeds();
    let nu = 0.34;
    let g_rate = freund_g_star_rate(FG_SIGMA, sp.c_l, nu, 5.2e9);
    let g_end = freund_g_exact(target * sp.c_r, sp.c_l, sp.c_s, sp.c_r);
    let dims = [FG_WIDTH, FG_CRACK, FG_ABOVE, FG_BELOW];
    // Fixed point of τ_w → t_f = g·τ_w → l(τ) → τ_w (l ≪ 2a: converges in a few rounds).
    let mut window = 2.0 * FG_CRACK / sp.c_l;
    let mut reference = GrowthReference::new(g_end * window, sp.c_l, sp.c_s, sp.c_r);
    for _ in 0..30 {
        let next = freund_growth_window(sp.c_l, dims, &|tau| reference.advance(tau));
        let done = (next - window).abs() < 1e-12;
        window = next;
        reference.t_f = g_end * window;
        if done {
            break;
        }
    }
    let gamma = g_rate * reference.t_f;

    let h = s.cell_size;
    let lb = s.load_band();
    let m = 2.0 * h;
    let yc = m + FG_BELOW + 0.5 * h;
    let top = yc + FG_ABOVE - 0.5 * h;
    let t_c = (top - yc) / sp.c_l;
    let mut crack = json!({
        "points": [[m - 0.5 * h, yc], [m + FG_CRACK, yc]],
        "propagation": {"criterion": "energy_release", "toughness": gamma,
                        "direction": {"fixed": [1.0, 0.0]}, "speed": "equation_of_motion"}
    });
    reg.apply(&mut crack);
    let scene = to_scene(json!({
        "name": "freund-growth",
        "grid": {"cell_size": h, "min": [0.0, 0.0], "max": [FG_WIDTH + 2.0 * m, top + m],
                 "shape_function": s.shape_name()},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [m, m], "max": [m + FG_WIDTH, top]}},
                    "particles_per_cell": s.particles_per_cell}],
        "cracks": [crack],
        "boundary_conditions": [
            {"region": {"rectangle": {"min": [0.0, 0.0], "max": [m + 0.1 * h, 1.0]}}, "velocity": {"x": 0.0}},
            {"region": {"rectangle": {"min": [m + FG_WIDTH - 0.1 * h, 0.0], "max": [1.0, 1.0]}}, "velocity": {"x": 0.0}}
        ],
        "loads": [{"region": {"rectangle": {"min": [0.0, top - lb], "max": [1.0, 1.0]}},
                   "traction": [0.0, FG_SIGMA]}],
        "time": {"end": t_c + window, "cfl": s.cfl}
    }))?;
    Ok(FreundGrowthScene {
        scene,
        target,
        gamma,
        sigma: FG_SIGMA,
        t_c,
        window,
        g_star_rate: g_rate,
        speeds: sp,
        reference,
        regularisation: *reg,
    })
}

/// One step of a growth run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GrowthSample {
    /// Time (s): after t_c for Freund's problem, simulated time for the strip.
    pub t: f64,
    /// The tip's advance (m).
    pub advance: f64,
    /// The equation of motion's speed in this step (m/s).
    pub speed: f64,
    /// J1 of the tip frame (J/m²).
    pub j1: f64,
    /// The filtered driving force the law decides on (J/m²).
    pub g_filtered: f64,
}

/// What a growing-crack step-wave run measured, with the references over the same times.
#[derive(Debug, Clone, PartialEq)]
pub struct FreundGrowthRun {
    /// Every step after t_c.
    pub samples: Vec<GrowthSample>,
    /// First time (after t_c) with advance > 0 (NaN if the tip never moved).
    pub initiation: f64,
    /// The reference initiation t_f.
    pub initiation_exact: f64,
    /// The interval of the mean speed: the last third of [t_f, window] (s after t_c).
    pub interval: [f64; 2],
    /// Measured Δadvance/Δt over `interval` (m/s).
    pub mean_speed: f64,
    /// The exact-g reference's Δl/Δt over `interval` (m/s).
    pub mean_speed_exact: f64,
    /// The 1 − v/c_R reference's Δl/Δt over `interval` (m/s).
    pub mean_speed_linear: f64,
    /// Advance at the end of the window: measured, exact g, 1 − v/c_R (m).
    pub final_advance: [f64; 3],
    /// Median over the running samples (speed > 0) of J1/(g(v)·G*(t)), exact g at the tip's
    /// speed: 1 where the grid delivers LEFM's energy flux to the moving tip.
    pub j1_over_g_gstar: f64,
    /// Median over the running samples of J1/Γ (1 where the law's balance holds on J1).
    pub j1_over_gamma: f64,
    /// The tip's energy taken above Γ(v) at the speed limit (J/m), and all it took (J/m).
    pub above_toughness: [f64; 2],
    /// Particles.
    pub particles: usize,
    /// Steps taken.
    pub steps: u64,
}

/// Linear interpolation of the advance at time t in samples ordered in time.
fn advance_at(samples: &[GrowthSample], t: f64) -> f64 {
    let i = samples.partition_point(|s| s.t < t);
    if i == 0 {
        return samples.first().map_or(f64::NAN, |s| s.advance);
    }
    if i >= samples.len() {
        return samples.last().map_or(f64::NAN, |s| s.advance);
    }
    let (a, b) = (samples[i - 1], samples[i]);
    let w = if b.t > a.t {
        (t - a.t) / (b.t - a.t)
    } else {
        1.0
    };
    a.advance + w * (b.advance - a.advance)
}

/// Median of finite values (NaN without any).
pub fn median(values: impl IntoIterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = values.into_iter().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// The growing tip's state and J1 after a step (crack 0, tip 1).
fn tip_sample(sim: &mut Simulation, t: f64) -> Result<(GrowthSample, [f64; 2]), VerifyError> {
    let j1 = sim
        .crack_tips()
        .iter()
        .find(|r| r.crack == 0 && r.tip == 1)
        .map_or(f64::NAN, |r| r.j1);
    let tip = sim
        .cracks()
        .and_then(|c| c.cracks.first())
        .map(|c| c.tips[1].clone())
        .ok_or_else(|| VerifyError::NotMeasurable("no crack".into()))?;
    Ok((
        GrowthSample {
            t,
            advance: tip.advance,
            speed: tip.eom_speed,
            j1,
            g_filtered: tip.g_filtered,
        },
        [tip.above_toughness, tip.required],
    ))
}

/// Run the growing-crack step wave to the end of its window, sampling the tip every step
/// after t_c, and measure it against the references.
pub fn run_freund_growth(
    f: &FreundGrowthScene,
    config: SolverConfig,
) -> Result<FreundGrowthRun, VerifyError> {
    let mut sim = Simulation::new(&fracture_api::ValidScene::new(f.scene.clone())?, config)?;
    let mut samples = Vec::new();
    let mut energy = [0.0; 2];
    while !sim.is_finished() {
        sim.step()?;
        let t = sim.time() - f.t_c;
        if t > 0.0 {
            let (s, e) = tip_sample(&mut sim, t)?;
            samples.push(s);
            energy = e;
        }
    }
    if samples.len() < 3 {
        return Err(VerifyError::NotMeasurable(format!(
            "{} samples after the wave's arrival",
            samples.len()
        )));
    }
    let r = &f.reference;
    let end = f.window;
    let interval = [r.t_f + 2.0 * (end - r.t_f) / 3.0, end];
    let dt = interval[1] - interval[0];
    let mean = |adv: &dyn Fn(f64) -> f64| (adv(interval[1]) - adv(interval[0])) / dt;
    let initiation = samples
        .iter()
        .find(|s| s.advance > 0.0)
        .map_or(f64::NAN, |s| s.t);
    let (c_l, c_s, c_r) = (f.speeds.c_l, f.speeds.c_s, f.speeds.c_r);
    let running = samples.iter().filter(|s| s.speed > 0.0);
    let j1_over_g_gstar = median(
        running
            .clone()
            .map(|s| s.j1 / (freund_g_exact(s.speed, c_l, c_s, c_r) * f.g_star_rate * s.t)),
    );
    let j1_over_gamma = median(running.map(|s| s.j1 / f.gamma));
    Ok(FreundGrowthRun {
        initiation,
        initiation_exact: r.t_f,
        interval,
        mean_speed: mean(&|t| advance_at(&samples, t)),
        mean_speed_exact: mean(&|t| r.advance(t)),
        mean_speed_linear: mean(&|t| r.advance_linear(t)),
        final_advance: [
            advance_at(&samples, end),
            r.advance(end),
            r.advance_linear(end),
        ],
        j1_over_g_gstar,
        j1_over_gamma,
        above_toughness: energy,
        particles: sim.particle_count(),
        steps: sim.steps_taken(),
        samples,
    })
}

// ---------------------------------------------------------------------------------------
// Freund's step wave with a tip at a prescribed constant speed.
// ---------------------------------------------------------------------------------------

/// A tip driven at a prescribed speed through Freund's step wave: the energy flux the grid
/// delivers to a tip of known speed, without the equation of motion's feedback.
#[derive(Debug, Clone, PartialEq)]
pub struct ConstantSpeedRun {
    /// The prescribed speed at the end of the window (m/s).
    pub speed: f64,
    /// c_R (m/s).
    pub c_r: f64,
    /// Every step after t_c.
    pub samples: Vec<GrowthSample>,
    /// The valid window after t_c (s).
    pub window: f64,
    /// Median over the second half of the window of J1/(g(v)·G*(t)) (exact g at the tip's
    /// speed in that step): 1 where the grid delivers LEFM's energy flux.
    pub ratio: f64,
    /// Medians over the window's four quarters.
    pub ratio_quarters: [f64; 4],
    /// Mean speed over the second half (m/s).
    pub mean_speed: f64,
}

/// Freund's growing-crack step-wave scene (`freund_growth`) with the tip driven at
/// `fraction`·c_R from the wave's arrival ([`run_prescribed_speed`]); the window is the step
/// wave's for a tip advancing v·t.
pub fn run_constant_speed(
    s: &Settings,
    fraction: f64,
    reg: &Regularisation,
    config: SolverConfig,
) -> Result<ConstantSpeedRun, VerifyError> {
    run_constant_speed_taking(s, fraction, reg, 1.0, config)
}

/// [`run_constant_speed`] with the zone taking `zone_scale` times LEFM's flux.
pub fn run_constant_speed_taking(
    s: &Settings,
    fraction: f64,
    reg: &Regularisation,
    zone_scale: f64,
    config: SolverConfig,
) -> Result<ConstantSpeedRun, VerifyError> {
    let f = freund_growth(s, 0.5, reg)?;
    let v = fraction * f.speeds.c_r;
    let dims = [FG_WIDTH, FG_CRACK, FG_ABOVE, FG_BELOW];
    let window = freund_growth_window(f.speeds.c_l, dims, &|tau| v * tau);
    run_prescribed_speed(f, window, &|_| v, zone_scale, config)
}

/// The growing-crack step-wave scene `f` (`freund_growth`, target `target`) with its tip
/// driven along the exact equation-of-motion history v(t) of the reference: the energy flux
/// the grid hands a tip that moves exactly as LEFM says it should.
pub fn run_exact_history(
    s: &Settings,
    target: f64,
    reg: &Regularisation,
    config: SolverConfig,
) -> Result<ConstantSpeedRun, VerifyError> {
    let f = freund_growth(s, target, reg)?;
    let window = f.window;
    let r = f.reference.clone();
    run_prescribed_speed(f, window, &move |t| r.speed(t), 1.0, config)
}

/// Run `f` to `window` after t_c with the tip's speed prescribed as `speed(t)` (t after t_c)
/// and its process zone taking, per unit new area, `zone_scale` times the energy LEFM says
/// reaches a tip so moving: Γ(t) = zone_scale·g(v)·G*₁·t (`Simulation::set_prescribed_motion`;
/// 1 in [`run_constant_speed`] and [`run_exact_history`]). For any speed history of
/// this problem G(t) = g(v)·G*(t), G* = G*₁·t (Freund 1990, §7.4), so J1/(g(v)G*₁t) is 1
/// where the grid hands the moving tip LEFM's flux, and the zone then takes what arrives.
pub fn run_prescribed_speed(
    mut f: FreundGrowthScene,
    window: f64,
    speed: &dyn Fn(f64) -> f64,
    zone_scale: f64,
    config: SolverConfig,
) -> Result<ConstantSpeedRun, VerifyError> {
    let sp = f.speeds;
    let (c_l, c_s, c_r) = (sp.c_l, sp.c_s, sp.c_r);
    f.scene.time.end = f.t_c + window;
    let mut sim = Simulation::new(&fracture_api::ValidScene::new(f.scene.clone())?, config)?;
    let mut samples = Vec::new();
    let dt = sim.time_step();
    while !sim.is_finished() {
        let t_next = sim.time() + dt - f.t_c;
        let v = speed(t_next).max(0.0);
        let flux = zone_scale * freund_g_exact(v, c_l, c_s, c_r) * f.g_star_rate * t_next.max(0.0);
        sim.set_prescribed_motion(0, Some((v, flux)));
        sim.step()?;
        let t = sim.time() - f.t_c;
        if t > 0.0 {
            samples.push(tip_sample(&mut sim, t)?.0);
        }
    }
    let ratio_in = |a: f64, b: f64| {
        median(
            samples
                .iter()
                .filter(|x| x.t >= a * window && x.t < b * window && x.speed > 0.0)
                .map(|x| x.j1 / (freund_g_exact(x.speed, c_l, c_s, c_r) * f.g_star_rate * x.t)),
        )
    };
    let half = 0.5 * window;
    let mean_speed = (advance_at(&samples, window) - advance_at(&samples, half)) / half;
    Ok(ConstantSpeedRun {
        speed: speed(window),
        c_r,
        window,
        ratio: ratio_in(0.5, 1.01),
        ratio_quarters: [
            ratio_in(0.0, 0.25),
            ratio_in(0.25, 0.5),
            ratio_in(0.5, 0.75),
            ratio_in(0.75, 1.01),
        ],
        mean_speed,
        samples,
    })
}

// ---------------------------------------------------------------------------------------
// The strip with fixed grips.
// ---------------------------------------------------------------------------------------

/// Strip geometry (m) and loading, as `solver/tests/growth_law.rs`.
const STRIP_LENGTH: f64 = 0.150;
const STRIP_HALF: f64 = 0.010;
const STRIP_CRACK: f64 = 0.030;
const STRIP_DELTA: f64 = 2.0e-5;
const STRIP_LOAD: f64 = 4.0e-5;
const STRIP_RAMP: f64 = 1.0e-5;
/// The run stops once the tip is this close to the far end (m).
const STRIP_STOP: f64 = 0.020;

/// The strip with fixed grips and its steady-state reference.
#[derive(Debug, Clone)]
pub struct StripScene {
    /// The scene.
    pub scene: Scene,
    /// G_∞ = Mδ²/b (J/m²), M = ρc_L² = E(1 − ν)/((1 + ν)(1 − 2ν)).
    pub g_inf: f64,
    /// The steady speed v* with Γ(v*) = G_∞ (m/s).
    pub v_star: f64,
    /// c_R (m/s).
    pub c_r: f64,
    /// End of the grips' motion (s).
    pub t_load: f64,
    /// The advance at which the run stops (m).
    pub stop_advance: f64,
    /// The regularisation written into the scene.
    pub regularisation: Regularisation,
}

/// A Homalite strip of height 2b = 20 mm + h (cells of h), 150 mm long, with a 30 mm edge
/// crack along its mid-plane (mid-cell), its top and bottom edges gripped (x fixed, y moved
/// ±δ = 20 µm over 40 µs with a 10 µs ramp, then held), grown along the mid-plane by the
/// equation of motion with the toughness Γ(v) = G_∞·(1 + (v − v*)/c_R) (rows at 0 and c_R),
/// v* = `target`·c_R, to 150 µs: the energy released per unit growth far from the ends is
/// G_∞ = Mδ²/b at any speed, so the steady speed is v* (`reference-solutions.md`, "Strip with
/// fixed grips"). The geometry of `strip()` in `solver/tests/growth_law.rs`.
pub fn strip_fixed_grips(
    s: &Settings,
    target: f64,
    reg: &Regularisation,
) -> Result<StripScene, VerifyError> {
    if !(target > 0.0 && target < 1.0) {
        return Err(VerifyError::Scene(format!(
            "target speed {target} c_R outside (0, 1)"
        )));
    }
    let h = s.cell_size;
    let m = 2.0 * h;
    let (y0, y1) = (m, m + 2.0 * STRIP_HALF);
    let cy = 0.5 * (y0 + y1) + 0.5 * h;
    let y1 = y1 + h; // one cell more, so the mid-plane lies at mid-cell
    let v_grip = STRIP_DELTA / (STRIP_LOAD - 0.5 * STRIP_RAMP);
    let (e, nu) = (5.2e9, 0.34);
    let big_m = e * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let sp = homalite_speeds();
    let b_eff = 0.5 * (y1 - y0);
    let g_inf = big_m * STRIP_DELTA * STRIP_DELTA / b_eff;
    let v_star = target * sp.c_r;
    let table = json!([
        [0.0, g_inf * (1.0 - target)],
        [sp.c_r, g_inf * (2.0 - target)]
    ]);
    let mut crack = json!({
        "points": [[m - 0.5 * h, cy], [m + STRIP_CRACK, cy]],
        "propagation": {"criterion": "energy_release", "toughness": table,
                        "direction": {"fixed": [1.0, 0.0]}, "speed": "equation_of_motion"}
    });
    reg.apply(&mut crack);
    let scene = to_scene(json!({
        "name": "strip-fixed-grips",
        "grid": {"cell_size": h, "min": [0.0, 0.0], "max": [STRIP_LENGTH + 2.0 * m, y1 + m],
                 "shape_function": s.shape_name()},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [m, y0], "max": [m + STRIP_LENGTH, y1]}},
                    "particles_per_cell": s.particles_per_cell}],
        "cracks": [crack],
        "boundary_conditions": [
            {"region": {"rectangle": {"min": [0.0, y1 - 0.5 * h], "max": [1.0, 1.0]}},
             "velocity": {"x": 0.0, "y": v_grip}, "ramp_time": STRIP_RAMP, "end": STRIP_LOAD},
            {"region": {"rectangle": {"min": [0.0, y1 - 0.5 * h], "max": [1.0, 1.0]}},
             "velocity": {"x": 0.0, "y": 0.0}, "start": STRIP_LOAD},
            {"region": {"rectangle": {"min": [0.0, 0.0], "max": [1.0, y0 + 0.5 * h]}},
             "velocity": {"x": 0.0, "y": -v_grip}, "ramp_time": STRIP_RAMP, "end": STRIP_LOAD},
            {"region": {"rectangle": {"min": [0.0, 0.0], "max": [1.0, y0 + 0.5 * h]}},
             "velocity": {"x": 0.0, "y": 0.0}, "start": STRIP_LOAD}
        ],
        "output": {"speed_window": 2.0e-6},
        "time": {"end": 1.5e-4, "cfl": s.cfl}
    }))?;
    Ok(StripScene {
        scene,
        g_inf,
        v_star,
        c_r: sp.c_r,
        t_load: STRIP_LOAD,
        stop_advance: STRIP_LENGTH - STRIP_CRACK - STRIP_STOP,
        regularisation: *reg,
    })
}

/// What a strip run measured.
#[derive(Debug, Clone, PartialEq)]
pub struct StripRun {
    /// Every step (t is the simulated time).
    pub samples: Vec<GrowthSample>,
    /// First time with advance > 0 (s; NaN if the tip never moved).
    pub initiation: f64,
    /// The interval of the steady speed: the last third of [initiation, stop], not before
    /// the grips stop (s).
    pub interval: [f64; 2],
    /// Least-squares slope of advance against time over `interval` (m/s).
    pub steady_speed: f64,
    /// Median of J1/G_∞ over the running samples in `interval` (1 at LEFM's steady state).
    pub j1_over_g_inf: f64,
    /// Median of J1/Γ(v) over the running samples in `interval`, v the tip's speed.
    pub j1_over_gamma: f64,
    /// Fraction of the running samples with J1 < 0.
    pub negative_j1: f64,
    /// The tip's energy taken above Γ(v) at the speed limit (J/m), and all it took (J/m).
    pub above_toughness: [f64; 2],
    /// Particles.
    pub particles: usize,
    /// Steps taken.
    pub steps: u64,
}

/// Least-squares slope of advance against time over samples in [t0, t1] (NaN with fewer
/// than 3).
fn slope(samples: &[GrowthSample], [t0, t1]: [f64; 2]) -> f64 {
    let pts: Vec<[f64; 2]> = samples
        .iter()
        .filter(|s| s.t >= t0 && s.t <= t1)
        .map(|s| [s.t, s.advance])
        .collect();
    if pts.len() < 3 {
        return f64::NAN;
    }
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p[0]).sum::<f64>() / n;
    let my = pts.iter().map(|p| p[1]).sum::<f64>() / n;
    let sxy: f64 = pts.iter().map(|p| (p[0] - mx) * (p[1] - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p[0] - mx) * (p[0] - mx)).sum();
    sxy / sxx
}

/// Run the strip until the tip is 20 mm from the far end (or the scene's end), sampling the
/// tip every step, and measure its steady speed and J1 while it runs.
pub fn run_strip(st: &StripScene, config: SolverConfig) -> Result<StripRun, VerifyError> {
    let mut sim = Simulation::new(&fracture_api::ValidScene::new(st.scene.clone())?, config)?;
    let mut samples = Vec::new();
    let mut energy = [0.0; 2];
    while !sim.is_finished() {
        sim.step()?;
        let t = sim.time();
        let (s, e) = tip_sample(&mut sim, t)?;
        samples.push(s);
        energy = e;
        if s.advance >= st.stop_advance {
            break;
        }
    }
    let initiation = samples
        .iter()
        .find(|s| s.advance > 0.0)
        .map_or(f64::NAN, |s| s.t);
    let stop = samples.last().map_or(f64::NAN, |s| s.t);
    if !initiation.is_finite() {
        return Err(VerifyError::NotMeasurable("the crack did not grow".into()));
    }
    let interval = [
        (initiation + 2.0 * (stop - initiation) / 3.0).max(st.t_load),
        stop,
    ];
    let toughness = |v: f64| st.g_inf * (1.0 + (v - st.v_star) / st.c_r);
    let steady: Vec<&GrowthSample> = samples
        .iter()
        .filter(|s| s.speed > 0.0 && s.t >= interval[0])
        .collect();
    let running = samples.iter().filter(|s| s.speed > 0.0).count().max(1);
    let negative = samples
        .iter()
        .filter(|s| s.speed > 0.0 && s.j1 < 0.0)
        .count();
    Ok(StripRun {
        initiation,
        interval,
        steady_speed: slope(&samples, interval),
        j1_over_g_inf: median(steady.iter().map(|s| s.j1 / st.g_inf)),
        j1_over_gamma: median(steady.iter().map(|s| s.j1 / toughness(s.speed))),
        negative_j1: negative as f64 / running as f64,
        above_toughness: energy,
        particles: sim.particle_count(),
        steps: sim.steps_taken(),
        samples,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The factorisation R(ζ) = 2(b² − a²)(c² − ζ²)S_+(ζ)S_+(−ζ) on |ζ| < a, to 1e-9.
    #[test]
    fn s_plus_factorises_the_rayleigh_function() {
        let sp = homalite_speeds();
        let (a, b, c) = (1.0 / sp.c_l, 1.0 / sp.c_s, 1.0 / sp.c_r);
        for f in [-0.9, -0.5, 0.0, 0.3, 0.95] {
            let z = f * a;
            let r = (b * b - 2.0 * z * z).powi(2)
                + 4.0 * z * z * (a * a - z * z).sqrt() * (b * b - z * z).sqrt();
            let fact = 2.0
                * (b * b - a * a)
                * (c * c - z * z)
                * rayleigh_s_plus(z, sp.c_l, sp.c_s)
                * rayleigh_s_plus(-z, sp.c_l, sp.c_s);
            assert!((fact / r - 1.0).abs() < 1e-9, "ζ = {f} a: {fact} vs {r}");
        }
    }

    /// The cancellation-free A_I equals the formula of `reference-solutions.md` where that
    /// one is well conditioned.
    #[test]
    fn a1_matches_the_direct_formula() {
        let sp = homalite_speeds();
        let nu = 0.34;
        for f in [0.2, 0.5, 0.8, 0.95] {
            let v = f * sp.c_r;
            let ad = (1.0 - (v / sp.c_l).powi(2)).sqrt();
            let as_ = (1.0 - (v / sp.c_s).powi(2)).sqrt();
            let d = 4.0 * ad * as_ - (1.0 + as_ * as_).powi(2);
            let direct = v * v * ad / ((1.0 - nu) * sp.c_s * sp.c_s * d);
            let a1 = freund_a1(v, sp.c_l, sp.c_s);
            assert!((a1 / direct - 1.0).abs() < 1e-6, "{f}: {a1} vs {direct}");
        }
    }

    /// The exact reference is consistent with itself: its advance is the integral of its
    /// speed (central differences, 1e-3), g(v(t)) = t_f/t, and the closed form's likewise.
    #[test]
    fn reference_advance_integrates_its_speed() {
        let sp = homalite_speeds();
        let r = GrowthReference::new(3.0e-6, sp.c_l, sp.c_s, sp.c_r);
        for t in [4.0e-6, 8.0e-6, 15.0e-6] {
            let dt = 1e-9;
            let v = (r.advance(t + dt) - r.advance(t - dt)) / (2.0 * dt);
            assert!(
                (v / r.speed(t) - 1.0).abs() < 1e-3,
                "t {t}: {v} vs {}",
                r.speed(t)
            );
            let vl = (r.advance_linear(t + dt) - r.advance_linear(t - dt)) / (2.0 * dt);
            assert!((vl / r.speed_linear(t) - 1.0).abs() < 1e-6);
            // g(v(t)) = t_f/t.
            assert!((r.g(r.speed(t)) * t / r.t_f - 1.0).abs() < 1e-4);
        }
    }
}
