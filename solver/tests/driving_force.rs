//! The crack-tip driving force (`algorithm.md` §6–§7, `reference-solutions.md` "Growth:
//! direction, speed, energy"): domain J, the interaction integral's K_I and K_II, the kink
//! criteria and a dynamic kink. Resolutions and tolerances are stated in each test.
#![allow(clippy::unwrap_used)]

use fracture_api::ValidScene;
use fracture_api::results::CrackTipRow;
use fracture_api::scene::{JIntegral, Scene};
use fracture_solver::{Simulation, SolverConfig};
use fracture_verify::{self as verification, Settings};

/// Run `scene` to its end; the crack-tip rows of every step from `(1 − frac)·end` on.
fn rows_after(scene: &Scene, frac: f64) -> Vec<Vec<CrackTipRow>> {
    let mut sim = Simulation::new(
        &ValidScene::new(scene.clone()).unwrap(),
        SolverConfig::all_cores(),
    )
    .unwrap();
    let t0 = (1.0 - frac) * scene.time.end;
    let mut out = Vec::new();
    while !sim.is_finished() {
        sim.step().unwrap();
        if sim.time() >= t0 {
            out.push(sim.crack_tips());
        }
    }
    out
}

/// Mean of `f` over the samples, per tip.
fn mean(rows: &[Vec<CrackTipRow>], f: impl Fn(&CrackTipRow) -> f64) -> Vec<f64> {
    let n = rows.len() as f64;
    let tips = rows[0].len();
    (0..tips)
        .map(|t| rows.iter().map(|r| f(&r[t])).sum::<f64>() / n)
        .collect()
}

fn domain(mut s: Scene, radius: f64) -> Scene {
    for c in &mut s.cracks {
        c.j_contour = None;
        c.j_integral = Some(JIntegral::Domain { radius });
    }
    s
}

/// Static centre crack (Tada), 1 mm cells (a = 8.5 cells), domain radius 6 mm: K_I of the
/// interaction integral within 1 % at both tips, |K_II| < 1 % of it; domain J1 at 3, 6 and
/// 12 mm within 1 % of each other (path independence) and √(E'J1) within 2 % of K_I.
/// Measured: K_I −0.20 %, J1 4.781 / 4.817 / 4.806 J/m² (Tada's J 4.797). At R = 4 mm the
/// 2 mm ring gives +9 %: two particle rows across it are too few.
#[test]
fn center_crack_domain_j_and_interaction_k() {
    let b = verification::center_crack(&Settings::at(0.001)).unwrap();
    let rows = rows_after(&domain(b.scene, 0.006), 0.2);
    let (k1, k2) = (mean(&rows, |r| r.k1), mean(&rows, |r| r.k2));
    let (j, jh, jd) = (
        mean(&rows, |r| r.j1),
        mean(&rows, |r| r.j1_half),
        mean(&rows, |r| r.j1_double),
    );
    let e_prime = 5.2e9 / (1.0 - 0.34 * 0.34);
    for t in 0..2 {
        let err = k1[t] / b.reference - 1.0;
        eprintln!(
            "tip {t}: K_I {:.0} (Tada {:.0}, {:+.2} %), K_II {:.0}; J1 at 3/6/12 mm {:.4} {:.4} {:.4}; \
             K from J {:.0}",
            k1[t],
            b.reference,
            100.0 * err,
            k2[t],
            jh[t],
            j[t],
            jd[t],
            (e_prime * j[t]).sqrt()
        );
        assert!(err.abs() < 0.01, "K_I {} vs Tada {}", k1[t], b.reference);
        assert!(k2[t].abs() < 0.01 * b.reference, "K_II {}", k2[t]);
        for other in [jh[t], jd[t]] {
            assert!((other / j[t] - 1.0).abs() < 0.01, "J1 {} vs {other}", j[t]);
        }
        assert!(((e_prime * j[t]).sqrt() / k1[t] - 1.0).abs() < 0.02);
    }
}

/// The 30° inclined centre crack (a = 10 cells at 1 mm), domain radius 6 mm: K_II/K_I of the
/// interaction integral within 3 % of tan 30° at both tips.
#[test]
fn inclined_crack_mode_ratio() {
    let b = verification::inclined_crack(&Settings::at(0.001), 30.0).unwrap();
    let rows = rows_after(&domain(b.scene, 0.006), 0.2);
    let (k1, k2) = (mean(&rows, |r| r.k1), mean(&rows, |r| r.k2));
    let (c1, c2) = (mean(&rows, |r| r.k1_cod), mean(&rows, |r| r.k2_cod));
    for t in 0..2 {
        let ratio = (k2[t] / k1[t]).abs();
        eprintln!(
            "tip {t}: K_I {:.0} K_II {:.0}, |K_II/K_I| {ratio:.4} (tan 30° = {:.4}); COD ratio {:.4}",
            k1[t],
            k2[t],
            b.reference,
            (c2[t] / c1[t]).abs()
        );
        assert!(k1[t] > 0.0);
        assert!((ratio / b.reference - 1.0).abs() < 0.03, "ratio {ratio}");
    }
}

/// Pure mode II centre crack with exact edge tractions (a/h = 17, 1 mm cells), domain radius
/// 6 mm: K_II of the interaction integral within 2 % of τ√(πa), |K_I| < 1 % of it. Measured
/// +1.40 % and 0.18 % (the contour J with the crack-opening ratio gave +3.9 %).
#[test]
fn pure_mode_two_interaction_k() {
    let b = verification::shear_crack(&Settings::at(0.001)).unwrap();
    let rows = rows_after(&domain(b.scene, 0.006), 0.2);
    let (k1, k2) = (mean(&rows, |r| r.k1), mean(&rows, |r| r.k2));
    for t in 0..2 {
        let err = k2[t].abs() / b.reference - 1.0;
        eprintln!(
            "tip {t}: K_II {:.0} (ref {:.0}, {:+.2} %), K_I {:.0}",
            k2[t],
            b.reference,
            100.0 * err,
            k1[t]
        );
        assert!(err.abs() < 0.02, "K_II {}", k2[t]);
        assert!(k1[t].abs() < 0.01 * b.reference, "K_I {}", k1[t]);
    }
}

/// The first kink of the growing pure mode II crack, in each tip's own frame (e1 ahead, e2 to
/// its left): θ of the first grown segment (`verification::run_kink`), against the
/// criterion's pure mode II angle, ± 5°.
fn first_kink(direction: &str) -> (f64, Vec<f64>) {
    let b = verification::shear_kink(&Settings::at(0.001), direction).unwrap();
    let (angles, _, _) = verification::run_kink(&b.scene, true, SolverConfig::all_cores()).unwrap();
    assert_eq!(angles.len(), 2, "both tips grow");
    (b.reference, angles)
}

#[test]
fn pure_mode_two_kinks_by_the_hoop_stress_angle() {
    let (reference, angles) = first_kink("max_hoop_stress");
    eprintln!("max_hoop_stress: first kink {angles:?} (Erdogan–Sih {reference:.2}°)");
    for a in angles {
        assert!((a - reference).abs() < 5.0, "kink {a}° vs {reference}°");
    }
}

#[test]
fn pure_mode_two_kinks_by_the_max_energy_release_angle() {
    let (reference, angles) = first_kink("max_energy_release");
    eprintln!("max_energy_release: first kink {angles:?} (kink solution {reference:.2}°)");
    for a in angles {
        assert!((a - reference).abs() < 5.0, "kink {a}° vs {reference}°");
    }
}

/// Domain independence of a dynamic J: Freund's stationary crack under a step wave (0.5 mm
/// cells), domain radius 3 mm (6 cells): J1 at 3 and 6 mm within 3 % at every sample with
/// t − t_c in [3, 14] µs (the valid window), and K_I of the interaction integral within 5 %
/// of Freund's K_I(t) there. Measured: spread 1.97 % (1.73 % before the inertial term left
/// out the disk of 3h around the tip), K_I within 3.83 %. The inertial area
/// term matters here and this test sees it: with the term removed the spread is 48.9 %, with
/// its sign flipped 120 % (mutations run when the test was written).
#[test]
fn freund_domain_independence() {
    let f = verification::freund(&Settings::at(0.0005)).unwrap();
    let scene = domain(f.scene.clone(), 0.003);
    let mut sim = Simulation::new(
        &ValidScene::new(scene.clone()).unwrap(),
        SolverConfig::all_cores(),
    )
    .unwrap();
    let (mut worst_j, mut worst_k, mut n) = (0.0_f64, 0.0_f64, 0);
    while !sim.is_finished() {
        sim.step().unwrap();
        let dt = sim.time() - f.t_c;
        if !(3.0e-6..=14.0e-6).contains(&dt) {
            continue;
        }
        let r = sim.crack_tips()[0];
        let k_ref = verification::freund_k1(f.sigma, f.c_l, f.nu, dt);
        let ej = r.j1_double / r.j1 - 1.0;
        let ek = r.k1 / k_ref - 1.0;
        if n % 10 == 0 {
            eprintln!(
                "t-tc {:5.2} us  J1 3 mm {:.4}  6 mm {:.4} ({:+.2} %)  K_I {:.0} Freund {k_ref:.0} ({:+.2} %)",
                dt * 1e6,
                r.j1,
                r.j1_double,
                100.0 * ej,
                r.k1,
                100.0 * ek
            );
        }
        worst_j = worst_j.max(ej.abs());
        worst_k = worst_k.max(ek.abs());
        n += 1;
    }
    eprintln!(
        "worst J1 spread {:.2} %, worst K_I error {:.2} % over {n} samples",
        100.0 * worst_j,
        100.0 * worst_k
    );
    assert!(n > 50);
    assert!(worst_j < 0.03, "J1 spread {:.2} %", 100.0 * worst_j);
    assert!(worst_k < 0.05, "K_I error {:.2} %", 100.0 * worst_k);
}

/// Kalthoff–Winkler (`verification::kalthoff_winkler`: steel, 16.5 m/s, half model, 1 mm
/// cells, maximum hoop stress): the crack leaves the notch at 60–75° to the notch direction,
/// away from the impact (experiment ≈ 70°). The angle is that of the chord from the notch tip
/// to the tip once it has grown 5 mm.
#[test]
fn kalthoff_winkler_crack_angle() {
    let b = verification::kalthoff_winkler(&Settings::at(0.001)).unwrap();
    let (angles, _, _) =
        verification::run_kink(&b.scene, false, SolverConfig::all_cores()).unwrap();
    let angle = angles[0];
    eprintln!(
        "Kalthoff–Winkler: angle {angle:.1}° (experiment ≈ {}°)",
        b.reference
    );
    assert!((60.0..=75.0).contains(&angle), "crack angle {angle}°");
}

/// An edge crack closed by a pressure and sheared, with Coulomb friction μ = 0.3 on its faces
/// (60 mm block, 30 mm crack at mid-cell, 1 mm cells; pressure 1 MPa and shear 0.6 MPa on the
/// top row ramped over 100 µs, bottom fixed, viscous damping, 300 µs): the faces slide
/// against friction inside the J ring, so without the crack-face traction term J would
/// depend on the ring. With it, J1 at radii 6 and 12 mm within 2 % at the static end.
/// Measured: 7.118 / 7.246 / 7.308 J/m² at 3 / 6 / 12 mm (0.85 %); without the face term
/// 7.587 / 8.025 / 8.316 (3.6 %, the test fails — mutation run when it was written).
#[test]
fn friction_face_term_keeps_j_path_independent() {
    let h = 0.001;
    let m = 2.0 * h;
    let (w, yc) = (0.060, m + 0.030 + 0.5 * h);
    let top = m + 0.060 + h;
    let v = serde_json::json!({
        "name": "friction-edge-crack",
        "grid": {"cell_size": h, "min": [0.0, 0.0], "max": [w + 2.0 * m, top + m]},
        "materials": {"m": verification::homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [m, m], "max": [m + w, top]}}}],
        "cracks": [{"points": [[m - 0.5 * h, yc], [m + 0.030, yc]],
                    "contact": {"law": "coulomb", "friction": 0.3},
                    "j_integral": {"method": "domain", "radius": 0.006}}],
        "boundary_conditions": [{"region": {"rectangle": {"min": [0.0, 0.0], "max": [1.0, m + 0.1 * h]}},
                                 "velocity": {"x": 0.0, "y": 0.0}}],
        "loads": [{"region": {"rectangle": {"min": [0.0, top - 0.5 * h], "max": [1.0, 1.0]}},
                   "traction": [6.0e5, -1.0e6], "ramp_time": 1.0e-4}],
        "damping": {"kind": "viscous", "coefficient": 5.0e4},
        "time": {"end": 3.0e-4}
    });
    let scene: Scene = fracture_api::validate::scene_from_value(v).unwrap();
    let rows = rows_after(&scene, 0.1);
    let (j, jh, jd) = (
        mean(&rows, |r| r.j1)[0],
        mean(&rows, |r| r.j1_half)[0],
        mean(&rows, |r| r.j1_double)[0],
    );
    let k2 = mean(&rows, |r| r.k2)[0];
    eprintln!("friction: J1 at 3/6/12 mm {jh:.4} {j:.4} {jd:.4} J/m², K_II {k2:.0}");
    assert!(j > 0.0);
    assert!(
        (jd / j - 1.0).abs() < 0.02,
        "J1 {j} at 6 mm vs {jd} at 12 mm"
    );
}
