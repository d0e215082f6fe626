//! Cohesive interfaces (`algorithm.md` §8), tested against physics the traction law does not
//! contain: a strip with fixed grips whose mid-plane is a bonded interface ahead of an edge
//! crack, opened (mode I) or sheared (mode II) until the bond unzips. The energy the failed
//! points took per unit failed area must be the mode's toughness (the law's area, reached only
//! if the grid delivers the separations the law expects), the global energy balance must close
//! with the traction work as the dissipation, and the failure front must run along the bond.
#![allow(clippy::unwrap_used)]

mod common;
use common::*;
use fracture_api::Scene;
use serde_json::json;

/// A strip 150 mm long, 2b = 20 mm + h high (cells of h), an edge crack of 30 mm along the
/// mid-plane (mid-cell), the rest of the mid-plane a cohesive interface with `law`, its
/// normal and shear strengths `strength` (Pa) and toughnesses `toughness` (J/m²); the grips
/// (top and bottom rows) move ±δ over 40 µs, then hold: along y (`shear` false: mode I, G_∞ =
/// M δ²/b with M the uniaxial-strain modulus) or along x (mode II, G_∞ = μ δ²/b). Returns the
/// scene and G_∞.
fn strip(h: f64, law: &str, strength: f64, toughness: f64, shear: bool) -> (Scene, f64) {
    let (len, b) = (0.150, 0.010);
    let m = 2.0 * h;
    let (y0, y1) = (m, m + 2.0 * b + h);
    let cy = 0.5 * (y0 + y1);
    let delta = 2.0e-5;
    let (t_load, ramp) = (4.0e-5, 1.0e-5);
    let v = delta / (t_load - 0.5 * ramp);
    let g_inf = g_infinity(h, shear);
    let vel = |s: f64| {
        if shear {
            json!({"x": s * v, "y": 0.0})
        } else {
            json!({"x": 0.0, "y": s * v})
        }
    };
    let mode = json!({"strength": strength, "toughness": toughness});
    // The elastic laws run at the validation's limit (`MAX_CFL_ELASTIC_LAW`).
    let cfl = if law == "linear" {
        0.5
    } else {
        fracture_api::validate::MAX_CFL_ELASTIC_LAW
    };
    let s = scene(json!({
        "name": "cohesive-strip",
        "grid": {"cell_size": h, "min": [0.0, 0.0], "max": [len + 2.0 * m, y1 + m]},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [m, y0], "max": [m + len, y1]}}}],
        "cracks": [{"points": [[m - 0.5 * h, cy], [m + 0.030, cy]]}],
        "interfaces": [{"points": [[m + 0.030, cy], [m + len + 0.5 * h, cy]],
                        "cohesive": {"law": law, "normal": mode, "shear": mode}}],
        "boundary_conditions": [
            {"region": {"rectangle": {"min": [0.0, y1 - 0.5 * h], "max": [1.0, 1.0]}},
             "velocity": vel(1.0), "ramp_time": ramp, "end": t_load},
            {"region": {"rectangle": {"min": [0.0, y1 - 0.5 * h], "max": [1.0, 1.0]}},
             "velocity": vel(0.0), "start": t_load},
            {"region": {"rectangle": {"min": [0.0, 0.0], "max": [1.0, y0 + 0.5 * h]}},
             "velocity": vel(-1.0), "ramp_time": ramp, "end": t_load},
            {"region": {"rectangle": {"min": [0.0, 0.0], "max": [1.0, y0 + 0.5 * h]}},
             "velocity": vel(0.0), "start": t_load}
        ],
        "output": {"speed_window": 2.0e-6},
        "time": {"end": 1.2e-4, "cfl": cfl}
    }));
    (s, g_inf)
}

/// G_∞ of `strip`: M δ²/b (mode I, M the uniaxial-strain modulus) or μ δ²/b (mode II), with
/// δ = 20 µm per grip and b half the strip's height 20 mm + h.
fn g_infinity(h: f64, shear: bool) -> f64 {
    let (e, nu) = (5.2e9, 0.34);
    let big_m = e * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let mu = e / (2.0 * (1.0 + nu));
    let (delta, b_eff) = (2.0e-5, 0.5 * (0.020 + h));
    let modulus = if shear { mu } else { big_m };
    modulus * delta * delta / b_eff
}

/// What the strip run measured.
struct Outcome {
    /// Traction work of the failed points over their area (J/m²).
    per_area: f64,
    /// Failed area (m²).
    area: f64,
    /// |Δ total_error| from the start over the work done.
    balance: f64,
    /// Work done by the grips (J).
    work: f64,
    /// Failure front positions (x, m) at the history samples.
    fronts: Vec<f64>,
    /// Largest |y − mid-plane| of a failure front (m).
    off_line: f64,
}

/// The traction work of the interface's (crack 1's) failed points (J) and their area (m²).
fn failed_work_and_area(sim: &fracture_solver::Simulation, s: &Scene) -> (f64, f64) {
    let c = &sim.cracks().unwrap().cracks[1];
    let (mut work, mut area) = (0.0, 0.0);
    for p in &c.pts {
        if let Some(b) = p.bond
            && b.failed
        {
            work += b.work;
            area += b.share * s.thickness;
        }
    }
    (work, area)
}

fn run(s: &Scene) -> Outcome {
    let mut sim = sim(s, 0);
    let cy = s.interfaces[0].points[0][1];
    let mut fronts = Vec::new();
    let mut off_line: f64 = 0.0;
    let mut next = 0.0;
    while !sim.is_finished() {
        sim.step().unwrap();
        if sim.time() >= next {
            next += 1.0e-6;
            let rows = sim.crack_tips();
            // The interface's row: crack index 1 (after the scene's one crack), tip 1.
            let r = rows.iter().find(|r| r.crack == 1).unwrap();
            if r.length > 0.0 {
                off_line = off_line.max((r.y - cy).abs());
            }
            fronts.push(r.x);
        }
    }
    let e = sim.energy();
    let (work, area) = failed_work_and_area(&sim, s);
    Outcome {
        per_area: work / area,
        area,
        balance: e.total_error.abs() / e.external_work,
        work: e.external_work,
        fronts,
        off_line,
    }
}

/// The strip of `strip` with G = G_∞/2 and the strength that makes the cohesive zone 5 mm
/// long (E'G/σ_c² in mode I, μG/τ_c² in mode II: 5 cells at 1 mm, 10 at 0.5 mm), run and
/// printed. Returns the outcome and the toughness.
fn case(h: f64, law: &str, shear: bool) -> (Outcome, f64, f64) {
    let g_inf = g_infinity(h, shear);
    let g = 0.5 * g_inf;
    let (e, nu) = (5.2e9, 0.34);
    let modulus = if shear {
        e / (2.0 * (1.0 + nu))
    } else {
        e / (1.0 - nu * nu)
    };
    let strength = (modulus * g / 0.005).sqrt();
    let (s, _) = strip(h, law, strength, g, shear);
    let o = run(&s);
    eprintln!(
        "{law} mode {}, h {} mm: σ_c {:.2} MPa, per failed area {:.2} vs G {g:.2} J/m² ({:+.2} %), \
         failed {:.1} mm, balance {:.3} % of work {:.3e} J, front at end {:.1} mm, off line {:.3} mm",
        if shear { "II" } else { "I" },
        h * 1e3,
        strength * 1e-6,
        o.per_area,
        100.0 * (o.per_area / g - 1.0),
        o.area / s.thickness * 1e3,
        100.0 * o.balance,
        o.work,
        o.fronts.last().unwrap() * 1e3,
        o.off_line * 1e3
    );
    // The front unzips the bond from the crack tip (x = 32 mm) to the far end, on the bond.
    assert!(o.area / s.thickness > 0.1, "too little failed: {}", o.area);
    assert!(
        o.fronts.windows(2).all(|w| w[1] >= w[0] - 0.1 * h),
        "front went back"
    );
    assert!(o.off_line < 0.5 * h);
    (o, g, s.thickness)
}

/// Mode I, linear softening: the failed points took G_Ic per unit area within 5 % at 0.5 mm
/// cells, and the energy balance (the traction work as the dissipation) converges with the
/// cell size: the error at 0.5 mm is at most 0.65 of that at 1 mm (first order, measured
/// 2.2 % → 1.2 % of the work done), as is the shortfall of energy per area (−6.5 % → −3.5 %).
#[test]
fn mode_one_interface_dissipates_its_toughness_and_the_balance_converges() {
    let (coarse, g1, _) = case(0.001, "linear", false);
    let (fine, g2, _) = case(0.0005, "linear", false);
    let (e1, e2) = (coarse.per_area / g1 - 1.0, fine.per_area / g2 - 1.0);
    assert!(e2.abs() < 0.05, "{} vs {g2}", fine.per_area);
    assert!(e2.abs() <= 0.65 * e1.abs(), "energy error {e1} → {e2}");
    assert!(
        fine.balance <= 0.65 * coarse.balance,
        "balance {} → {}",
        coarse.balance,
        fine.balance
    );
    assert!(fine.balance < 0.015, "balance {}", fine.balance);
}

/// Mode II, linear softening, a sheared strip: the failed points took G_IIc per unit area
/// within 5 % and the balance closes within 1 % of the work done (0.5 mm cells).
#[test]
fn mode_two_interface_dissipates_its_toughness() {
    let (o, g, _) = case(0.0005, "linear", true);
    assert!((o.per_area / g - 1.0).abs() < 0.05, "{} vs {g}", o.per_area);
    assert!(o.balance < 0.01, "balance {}", o.balance);
}

/// Xu–Needleman's exponential and Needleman's cubic law, whose stiff initial branches limit
/// the explicit step: at the validation's largest cfl (0.15) the run stays stable and each law
/// takes its toughness per unit area within 5 % at 1 mm cells.
#[test]
fn stiff_laws_are_stable_and_take_their_toughness() {
    for law in ["exponential", "cubic"] {
        let (o, g, _) = case(0.001, law, false);
        assert!(
            (o.per_area / g - 1.0).abs() < 0.05,
            "{law}: {} vs {g}",
            o.per_area
        );
        assert!(o.balance < 0.05, "{law}: balance {}", o.balance);
    }
}

/// A double-cantilever beam (Homalite, 60 mm long, two 5 mm arms, cells of h) whose
/// mid-plane is a 20 mm crack continued to the far end by a linear-law interface (G_Ic = 10
/// J/m², σ_c from a 5 mm zone E'G/σ_c²); the first 2 mm of the arms are pulled apart at
/// ±0.2 m/s (ramped over 20 µs) for 500 µs, no damping: the bond unzips stably from the
/// crack tip while the arms bend (the bonded region ahead is in compression, then tension,
/// as the arms vibrate — what made the rigid law's drift blow up before `Bond::engaged`).
fn dcb(h: f64) -> Scene {
    let (len, t, g) = (0.060, 0.005, 10.0);
    let (x0, y0) = (2.0 * h, 2.0 * h);
    let yc = y0 + t + 0.5 * h;
    let e_prime = 5.2e9 / (1.0 - 0.34 * 0.34);
    let strength = (e_prime * g / 0.005_f64).sqrt();
    let tip = x0 + 0.020;
    let mode = json!({"strength": strength, "toughness": g});
    scene(json!({
        "name": "cohesive-dcb",
        "grid": {"cell_size": h, "min": [0.0, 0.0], "max": [x0 + len + 2.0 * h, yc + t + 2.5 * h]},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [x0, y0], "max": [x0 + len, y0 + 2.0 * t + h]}}}],
        "cracks": [{"points": [[x0 - 0.5 * h, yc], [tip, yc]]}],
        "interfaces": [{"points": [[tip, yc], [x0 + len + 0.5 * h, yc]],
                        "cohesive": {"law": "linear", "normal": mode, "shear": mode}}],
        "boundary_conditions": [
            {"region": {"rectangle": {"min": [0.0, yc + 2.0 * h], "max": [x0 + 0.002, 1.0]}},
             "velocity": {"y": 0.2}, "ramp_time": 2.0e-5},
            {"region": {"rectangle": {"min": [0.0, 0.0], "max": [x0 + 0.002, yc - 2.0 * h]}},
             "velocity": {"y": -0.2}, "ramp_time": 2.0e-5}
        ],
        "time": {"end": 5.0e-4, "cfl": 0.5}
    }))
}

/// What the DCB run measured.
struct DcbOutcome {
    /// Traction work of the failed points over their area (J/m²) and that area (m²).
    per_area: f64,
    area: f64,
    /// Total error of the energy balance over the work done (signed).
    balance: f64,
    /// For each point at the step it failed: the opening of the material across the bond,
    /// the mean y-displacement of the particles in the row just above minus that of the row
    /// just below, within half a cell of the point along x (m).
    openings: Vec<f64>,
}

fn run_dcb(s: &Scene) -> DcbOutcome {
    let mut sim = sim(s, 0);
    let h = s.grid.cell_size;
    let yc = s.interfaces[0].points[0][1];
    let mut was_failed: Vec<bool> = Vec::new();
    let mut openings = Vec::new();
    while !sim.is_finished() {
        sim.step().unwrap();
        let c = &sim.cracks().unwrap().cracks[1];
        was_failed.resize(c.pts.len(), false);
        for (k, pt) in c.pts.iter().enumerate() {
            let Some(b) = pt.bond else { continue };
            if b.failed && !was_failed[k] {
                was_failed[k] = true;
                let p = sim.particles();
                let (mut up, mut dn) = ((0.0, 0), (0.0, 0));
                for (kin, cold) in p.kin.iter().zip(&p.cold) {
                    let x0 = cold.x0;
                    if (x0[0] - pt.x0[0]).abs() >= 0.5 * h {
                        continue;
                    }
                    let u = kin.x[1] - x0[1];
                    if x0[1] > yc && x0[1] < yc + 0.5 * h {
                        up = (up.0 + u, up.1 + 1);
                    } else if x0[1] < yc && x0[1] > yc - 0.5 * h {
                        dn = (dn.0 + u, dn.1 + 1);
                    }
                }
                if up.1 > 0 && dn.1 > 0 {
                    openings.push(up.0 / f64::from(up.1) - dn.0 / f64::from(dn.1));
                }
            }
        }
    }
    let e = sim.energy();
    let (work, area) = failed_work_and_area(&sim, s);
    DcbOutcome {
        per_area: work / area,
        area,
        balance: e.total_error / e.external_work,
        openings,
    }
}

/// Mode I on a double-cantilever beam, loaded only at the crack mouth (acceptance of the
/// cohesive issue): the run stays stable at cfl 0.5, the failed points took G_Ic per unit
/// area within 5 %, the energy balance (traction work as the dissipation) closes within 1 %
/// of the work done at 1 and 0.5 mm cells, and the material opened by δ_c = 2G/σ_c (the
/// law's end) where each point failed: the particles' displacement jump across the bond,
/// which the law does not see (it reads the crack surfaces), within 10 %. Measured (this
/// test, `--nocapture`): per area −2.6 % / −0.7 %, balance −0.6 % / −0.1 % at 1 / 0.5 mm.
#[test]
fn mode_one_dcb_dissipates_its_toughness_and_the_balance_closes() {
    for h in [0.001, 0.0005] {
        let s = dcb(h);
        let mode = s.interfaces[0].cohesive.normal;
        let g = mode.toughness;
        let delta_c = 2.0 * g / mode.strength;
        let o = run_dcb(&s);
        let mean_opening = o.openings.iter().sum::<f64>() / o.openings.len().max(1) as f64;
        let worst = o
            .openings
            .iter()
            .map(|d| (d / delta_c - 1.0).abs())
            .fold(0.0, f64::max);
        eprintln!(
            "DCB h {} mm: failed {:.1} mm, per failed area {:.3} vs G {g} J/m² ({:+.2} %), \
             balance {:+.3} % of the work, opening at failure mean {:.3} µm vs δ_c {:.3} µm \
             (worst {:.1} % off, {} points)",
            h * 1e3,
            o.area / s.thickness * 1e3,
            o.per_area,
            100.0 * (o.per_area / g - 1.0),
            100.0 * o.balance,
            mean_opening * 1e6,
            delta_c * 1e6,
            100.0 * worst,
            o.openings.len()
        );
        assert!(
            o.area / s.thickness > 0.005,
            "too little failed: {}",
            o.area
        );
        assert!((o.per_area / g - 1.0).abs() < 0.05, "{} vs {g}", o.per_area);
        assert!(o.balance.abs() < 0.01, "balance {}", o.balance);
        assert!(o.openings.len() >= 5, "{} openings", o.openings.len());
        assert!(
            worst < 0.10,
            "opening at failure {:?} vs δ_c {delta_c}",
            o.openings
        );
    }
}
