//! Static stress intensity factors from the dynamic J-integral (`reference-solutions.md`,
//! "Static stress intensity factors"). A static state is reached by a slow load ramp plus
//! viscous damping; J and K are averaged over the last part of the hold.
#![allow(clippy::unwrap_used)]

use fracture_solver::SolverConfig;
use fracture_verify::{self as verification, Settings};

/// Run a scene to its end and average the crack-tip rows over the last `frac` of the run.
fn average_tips(s: &fracture_api::Scene, frac: f64) -> Vec<[f64; 4]> {
    verification::average_tips(s, frac, SolverConfig::all_cores())
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
    let b = verification::shear_crack(&Settings::at(0.001)).unwrap();
    let (s, k_ref) = (b.scene, b.reference);
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
