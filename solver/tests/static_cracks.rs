//! Static stress intensity factors from the dynamic J-integral (`reference-solutions.md`,
//! "Static stress intensity factors"). A static state is reached by a slow load ramp plus
//! viscous damping; J and K are averaged over the last part of the hold.
#![allow(clippy::unwrap_used)]

mod common;
use common::*;
use fracture_solver::SolverConfig;
use fracture_solver::verification::{self, Settings};
use serde_json::json;

/// Run a scene to its end and average the crack-tip rows over the last `frac` of the run.
fn average_tips(s: &fracture_api::Scene, frac: f64) -> Vec<[f64; 4]> {
    verification::average_tips(s, frac, SolverConfig { threads: 0 })
        .unwrap()
        .tips
}

/// The centre-crack scene of `verification::center_crack` (strip 2b = 80 mm, 2a = 17 mm,
/// σ = 1 MPa ramped over 150 µs, viscous damping) and Tada's K_I.
fn center_crack_scene(h: f64, contour: u32) -> (fracture_api::Scene, f64) {
    let b = verification::center_crack(&Settings {
        j_contour: contour,
        ..Settings::at(h)
    })
    .unwrap();
    (b.scene, b.reference)
}

/// Centre crack in a long strip under remote tension: K_I = σ√(πa)·F(a/b) (Tada).
/// Resolution: 1 mm cells (a = 8.5 cells), 2×2 particles per cell, J contour half-size 2.
/// Tolerance: 3 % on K_I for both tips, |K_II| < 3 % of K_I.
#[test]
fn center_crack_mode_one() {
    let (s, k_ref) = center_crack_scene(0.001, 2);
    let tips = average_tips(&s, 0.2);
    assert_eq!(tips.len(), 2);
    for t in &tips {
        let err = (t[2] - k_ref) / k_ref;
        eprintln!(
            "J1 {:.4} J2 {:.4} KI {:.0} KII {:.0} (ref {k_ref:.0}, err {:.2} %)",
            t[0],
            t[1],
            t[2],
            t[3],
            100.0 * err
        );
        assert!(err.abs() < 0.03, "K_I {} vs {k_ref}", t[2]);
        assert!(t[3].abs() < 0.03 * k_ref, "K_II {}", t[3]);
    }
}

/// J path independence on a static problem: contours of half-size 2 and 3 cells agree within
/// 3 % (same centre-crack scene, averaged J1).
#[test]
fn center_crack_path_independence() {
    let (s2, _) = center_crack_scene(0.001, 2);
    let (s3, _) = center_crack_scene(0.001, 3);
    let j2 = average_tips(&s2, 0.2)[1][0];
    let j3 = average_tips(&s3, 0.2)[1][0];
    eprintln!("J1 contour 2: {j2:.4}, contour 3: {j3:.4}");
    assert!((j2 - j3).abs() / j2 < 0.03, "J1 {j2} vs {j3}");
}

/// Edge crack in a strip under remote tension: K_I = σ√(πa)·F(a/b) (Tada). Strip b = 40 mm,
/// half-height 48 mm, a = 12.5 mm (a/b = 0.3125), 1 mm cells, 2×2 particles per cell,
/// contour half-size 2. Tolerance: 5 %.
#[test]
fn edge_crack_mode_one() {
    let b = verification::edge_crack(&Settings::at(0.001)).unwrap();
    let (s, k_ref) = (b.scene, b.reference);
    let tips = average_tips(&s, 0.2);
    assert_eq!(tips.len(), 1, "the mouth is not a tip");
    let t = tips[0];
    let err = (t[2] - k_ref) / k_ref;
    eprintln!(
        "edge crack: KI {:.0} KII {:.0} ref {k_ref:.0} err {:.2} %",
        t[2],
        t[3],
        100.0 * err
    );
    assert!(err.abs() < 0.05, "K_I {} vs {k_ref}", t[2]);
}

/// Centre crack under remote shear τ: K_II = τ√(πa), K_I = 0 for a crack in an infinite plate.
/// The plate (104 mm square, crack 2a = 34 mm) is loaded on its four edges by the tractions of
/// the exact infinite-plate solution (Westergaard, piecewise constant over one-cell segments),
/// so the finite plate is a cut-out of the infinite one and the reference has no size factor.
/// Resolution: 1 mm cells, a = 17 cells, 2×2 particles per cell, J contour half-size 2; ramp
/// 250 µs, near-critical viscous damping, K averaged over the last 20 % of the run.
/// Tolerance: K_II within 5 %, |K_I| < 5 % of K_II (measured +4.0 % and 1.2 %).
///
/// The error falls slowly with resolution: +6.2 % at a = 8.5 cells, +4.0 % at 17 (observed
/// order about 0.6, against about 1 for mode I). The crack-sliding profile shows why: it is
/// elliptical with the exact amplitude away from the tip, but the last two cells behind each
/// tip slide 16–130 % more than the exact profile, a discretisation effect of the sliding faces
/// next to the tip (mode I, whose faces carry no σ_xx, shows no such excess). See
/// docs/verification.md.
#[test]
fn center_crack_mode_two() {
    let h = 0.001;
    let (w, a) = (0.104, 0.017);
    let m = 2.0 * h;
    let c = m + 0.5 * w + 0.5 * h;
    let tau = 1.0e6;
    let top = m + w + h;
    let ramp = 2.5e-4;
    let s = scene(json!({
        "name": "shear-crack",
        "grid": {"cell_size": h, "min": [0.0, 0.0], "max": [top + m, top + m]},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [m, m], "max": [top, top]}}}],
        "cracks": [{"points": [[c - a, c], [c + a, c]]}],
        "loads": exact_shear_loads(h, m, top, c, a, tau, ramp),
        "damping": {"kind": "viscous", "coefficient": 7.0e4},
        "time": {"end": 4.0e-4, "cfl": 0.5}
    }));
    let k_ref = tau * (std::f64::consts::PI * a).sqrt();
    let tips = average_tips(&s, 0.2);
    assert_eq!(tips.len(), 2);
    for t in &tips {
        eprintln!(
            "shear: J1 {:.4} KI {:.0} KII {:.0} ref {k_ref:.0} ({:+.2} %)",
            t[0],
            t[2],
            t[3],
            100.0 * (t[3].abs() / k_ref - 1.0)
        );
        assert!(
            (t[3].abs() - k_ref).abs() / k_ref < 0.05,
            "K_II {} vs {k_ref}",
            t[3]
        );
        assert!(
            t[2].abs() < 0.05 * t[3].abs(),
            "K_I {} with K_II {}",
            t[2],
            t[3]
        );
    }
}

/// Complex helpers (re, im).
type C = (f64, f64);
fn cmul(a: C, b: C) -> C {
    (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0)
}
fn cdiv(a: C, b: C) -> C {
    let d = b.0 * b.0 + b.1 * b.1;
    ((a.0 * b.0 + a.1 * b.1) / d, (a.1 * b.0 - a.0 * b.1) / d)
}
fn csqrt(a: C) -> C {
    let r = (a.0 * a.0 + a.1 * a.1).sqrt();
    let re = (0.5 * (r + a.0)).max(0.0).sqrt();
    let im = (0.5 * (r - a.0)).max(0.0).sqrt();
    (re, if a.1 < 0.0 { -im } else { im })
}

/// Westergaard stresses (σxx, σyy, σxy) of a crack (−a, a) on the x axis in an infinite plate
/// under remote shear τ, at (x, y) relative to the crack centre.
fn westergaard_shear(x: f64, y: f64, a: f64, tau: f64) -> [f64; 3] {
    let z = (x, y);
    let q = cmul(csqrt((x - a, y)), csqrt((x + a, y)));
    let zz = cdiv((tau * z.0, tau * z.1), q);
    let q3 = cmul(q, cmul(q, q));
    let zp = cdiv((-tau * a * a, 0.0), q3);
    [2.0 * zz.1 + y * zp.0, -y * zp.0, zz.0 - y * zp.1]
}

/// Tractions of the exact infinite-plate solution on the four edges, piecewise constant
/// over segments one cell long.
fn exact_shear_loads(
    h: f64,
    m: f64,
    top: f64,
    c: f64,
    a: f64,
    tau: f64,
    ramp: f64,
) -> serde_json::Value {
    let n = ((top - m) / h).round() as usize;
    let mut v = Vec::new();
    for k in 0..n {
        let (s0, s1) = (m + k as f64 * h, m + (k + 1) as f64 * h);
        let mid = 0.5 * (s0 + s1) - c;
        // top (normal +y): (σxy, σyy); bottom: −(σxy, σyy)
        let st = westergaard_shear(mid, top - c, a, tau);
        let sb = westergaard_shear(mid, m - c, a, tau);
        let (x0, x1) = (s0.max(m + 0.5 * h), s1.min(top - 0.5 * h));
        if x1 > x0 {
            v.push(json!({"region": {"rectangle": {"min": [x0, top - 0.5 * h], "max": [x1, top]}}, "traction": [st[2], st[1]], "ramp_time": ramp}));
            v.push(json!({"region": {"rectangle": {"min": [x0, m], "max": [x1, m + 0.5 * h]}}, "traction": [-sb[2], -sb[1]], "ramp_time": ramp}));
        }
        // right (normal +x): (σxx, σxy); left: −(σxx, σxy)
        let sr = westergaard_shear(top - c, mid, a, tau);
        let sl = westergaard_shear(m - c, mid, a, tau);
        v.push(json!({"region": {"rectangle": {"min": [top - 0.5 * h, s0], "max": [top, s1]}}, "traction": [sr[0], sr[2]], "ramp_time": ramp}));
        v.push(json!({"region": {"rectangle": {"min": [m, s0], "max": [m + 0.5 * h, s1]}}, "traction": [-sl[0], -sl[2]], "ramp_time": ramp}));
    }
    serde_json::Value::Array(v)
}

/// The reference field itself: remote shear far away, traction-free faces, and
/// √(2πr)·σ_xy → τ√(πa) ahead of the tip (to 0.1 % at r = 10⁻⁶ a).
#[test]
fn westergaard_shear_reference() {
    let (a, tau) = (0.017, 1.0e6);
    let far = westergaard_shear(1.0e3 * a, 7.0e2 * a, a, tau);
    assert!((far[2] - tau).abs() < 1e-5 * tau && far[0].abs() < 1e-5 * tau);
    for x in [-0.9 * a, -0.3 * a, 0.5 * a] {
        let f = westergaard_shear(x, 1e-12 * a, a, tau);
        assert!(
            f[1].abs() < 1e-3 * tau && f[2].abs() < 1e-3 * tau,
            "face {x}: {f:?}"
        );
    }
    let r = 1e-6 * a;
    let k = (2.0 * std::f64::consts::PI * r).sqrt() * westergaard_shear(a + r, 0.0, a, tau)[2];
    let k_ref = tau * (std::f64::consts::PI * a).sqrt();
    assert!((k - k_ref).abs() < 1e-3 * k_ref, "K {k} vs {k_ref}");
}
