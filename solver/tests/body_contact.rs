//! Body-to-body contact (`Body::contact`, `docs/scene-extensions.md`) against one-dimensional
//! wave theory (`reference-solutions.md`, two-body impact). Bars in uniaxial strain (rollers on
//! their long edges), a striker of length L_s at v meeting a longer target at rest:
//! - equal bars: a stress ρc_L·v/2 runs into both; after one transit of the striker,
//!   2L_s/c_L, the striker is at rest and the target carries all the momentum. Bonded bars
//!   (no contact law, one shared field) instead hold together and move on at v/2: the
//!   contact law is what lets the striker go;
//! - steel onto Homalite: the struck face moves at v·Z_s/(Z_s + Z_h) (impedance matching,
//!   Z = ρc_L), so the target's stress is Z_h·v·Z_s/(Z_s + Z_h);
//! - total x momentum is exact at every step (±Δp at each node), the energy balance closes
//!   within 2 %, and the results are bitwise the same on 1 and 2 threads;
//! - Coulomb friction: a block pressed on a held plate by a traction p and sliding at v₀
//!   slows by Coulomb's law, at about μp/(ρH_b); frictionless, it slides on.
//!
//! 0.5 mm cells, 2×2 particles per cell; tolerances as stated at each assertion.
#![allow(clippy::unwrap_used)]

mod common;
use common::*;
use fracture_api::Scene;
use fracture_solver::Simulation;
use serde_json::json;

/// Bar geometry (m).
const H: f64 = 0.0005;
const STRIKER: f64 = 0.020;
const TARGET: f64 = 0.030;
const HEIGHT: f64 = 0.004;
const V: f64 = 10.0;

fn steel() -> serde_json::Value {
    json!({"model": "linear_elastic", "density": 8000.0, "youngs_modulus": 190.0e9,
           "poissons_ratio": 0.3})
}

/// Uniaxial-strain (plane strain, rollers) wave speed and impedance of (E, ν, ρ).
fn wave(e: f64, nu: f64, rho: f64) -> (f64, f64) {
    let c = (e * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu)) / rho).sqrt();
    (c, rho * c)
}

/// A striker (body 1, `striker` material) at +V touching a target (body 0, Homalite) at
/// rest; `contact` gives the striker a frictionless contact law. Ends at `end`.
fn bars(striker_material: serde_json::Value, contact: bool, end: f64) -> Scene {
    let m = 2.0 * H;
    let x_face = m + STRIKER;
    let (y0, y1) = (m, m + HEIGHT);
    let e = 0.01 * H;
    let mut striker = json!({"material": "s",
        "region": {"rectangle": {"min": [m, y0], "max": [x_face, y1]}},
        "initial_velocity": [V, 0.0]});
    if contact {
        striker["contact"] = json!({"law": "frictionless"});
    }
    scene(json!({
        "name": "two-body-impact",
        "grid": {"cell_size": H, "min": [0.0, 0.0], "max": [x_face + TARGET + m, y1 + m]},
        "materials": {"t": homalite(), "s": striker_material},
        "bodies": [
            {"material": "t", "region": {"rectangle": {"min": [x_face, y0], "max": [x_face + TARGET, y1]}}},
            striker
        ],
        "boundary_conditions": [
            {"region": {"rectangle": {"min": [0.0, 0.0], "max": [1.0, y0 + e]}}, "velocity": {"y": 0.0}},
            {"region": {"rectangle": {"min": [0.0, y1 - e], "max": [1.0, 1.0]}}, "velocity": {"y": 0.0}}
        ],
        "time": {"end": end, "cfl": 0.5}
    }))
}

/// Per body (0 target, 1 striker): momentum Σ m v_x, mass, and the mean σ_xx of the
/// particles whose x lies in `band` (m), with their count.
fn per_body(sim: &Simulation, band: [[f64; 2]; 2]) -> [(f64, f64, f64, f64); 2] {
    let p = sim.particles();
    let mut out = [(0.0, 0.0, 0.0, 0.0); 2];
    for ((k, me), (c, s)) in p.kin.iter().zip(&p.mech).zip(p.cold.iter().zip(&p.stress)) {
        let b = c.body as usize;
        out[b].0 += me.m * k.v[0];
        out[b].1 += me.m;
        if k.x[0] > band[b][0] && k.x[0] < band[b][1] {
            out[b].2 += s[0];
            out[b].3 += 1.0;
        }
    }
    for o in &mut out {
        if o.3 > 0.0 {
            o.2 /= o.3;
        }
    }
    out
}

/// Run to the end, checking total x momentum at every step; returns the simulation and the
/// stresses of both bars at t_mid, sampled in the bands the front has swept (2 mm clear of
/// the face and of the front).
fn run(s: &Scene, c_t: f64, c_s: f64, t_mid: f64) -> (Simulation, [f64; 2]) {
    let mut sim = sim(s, 0);
    let p0 = momentum(&sim)[0];
    let e0 = sim.energy().kinetic;
    let x_face = 2.0 * H + STRIKER;
    let mut mid = [f64::NAN; 2];
    while !sim.is_finished() {
        sim.step().unwrap();
        let p = momentum(&sim)[0];
        assert!(
            ((p - p0) / p0).abs() < 1e-12,
            "x momentum {p} against {p0} at t = {:.3e} s",
            sim.time()
        );
        if mid[0].is_nan() && sim.time() >= t_mid {
            let t = sim.time();
            let band = [
                [x_face + 0.002, x_face + c_t * t - 0.002],
                [x_face - c_s * t + 0.002, x_face - 0.002],
            ];
            let b = per_body(&sim, band);
            mid = [b[0].2, b[1].2];
        }
    }
    // Energy balance within 2 % of the initial kinetic energy (measured 0.003–1.04 %, the
    // largest after the bars part).
    let e = sim.energy();
    let total = e.kinetic + e.strain + e.dissipated - e.external_work;
    eprintln!(
        "energy at {:.1} µs: kinetic + strain + dissipated − work = {:.5} of the initial",
        sim.time() * 1e6,
        total / e0
    );
    assert!(
        (total / e0 - 1.0).abs() < 0.02,
        "energy {} of the initial",
        total / e0
    );
    (sim, mid)
}

/// Equal bars: ρc_L·v/2 in both within 3 % at half a transit (measured +0.6 / +0.7 %), the
/// striker at rest after one transit (|v̄| < 3 % of v; measured −1.0 %) and the target with over
/// 97 % of the momentum. The target (30 mm) sends its pulse back as tension; it reaches the
/// face at 2L_t/c_L and the contact lets the bodies part: one striker transit later the
/// striker is still at rest within 5 % of v (measured −3.7 % at 0.5 mm, about as much at 0.25 mm:
/// the grid's overshoot behind the unloading front, which the one-sided contact passes into
/// the target when it pushes and leaves in the striker when it would pull; it does not fall
/// with h, like the overshoot). Bonded bars (no contact law, one shared field) pass the tension
/// into the striker, which is pulled forward (v̄ > v/5): the contact law is what lets go.
#[test]
fn equal_bars_exchange_their_momentum_in_one_transit() {
    let (c, z) = wave(5.2e9, 0.34, 1230.0);
    let transit = 2.0 * STRIKER / c;
    let sigma = -0.5 * z * V;
    let x_face = 2.0 * H + STRIKER;
    let (sim, mid) = run(
        &bars(homalite(), true, transit + 1.5e-6),
        c,
        c,
        0.5 * transit,
    );
    let b = per_body(&sim, [[x_face, x_face]; 2]);
    let p0 = b[0].0 + b[1].0;
    let v_striker = b[1].0 / b[1].1;
    eprintln!(
        "contact: σ_xx target {:.4} striker {:.4} of −ρc_L v/2; striker v̄ {v_striker:.4} m/s; \
         target momentum {:.4} of the total",
        mid[0] / sigma,
        mid[1] / sigma,
        b[0].0 / p0
    );
    for (name, s) in [("target", mid[0]), ("striker", mid[1])] {
        assert!(
            (s / sigma - 1.0).abs() < 0.03,
            "{name} σ_xx {s} against {sigma}"
        );
    }
    assert!(v_striker.abs() < 0.03 * V, "striker v̄ {v_striker} m/s");
    assert!(b[0].0 / p0 > 0.97, "target momentum share {}", b[0].0 / p0);

    // After the target's tension has come back to the face and one striker transit more.
    let late = 2.0 * TARGET / c + transit;
    let mut v_late = [0.0; 2];
    for (k, contact) in [true, false].into_iter().enumerate() {
        let (sim, _) = run(&bars(homalite(), contact, late), c, c, late);
        let b = per_body(&sim, [[x_face, x_face]; 2]);
        v_late[k] = b[1].0 / b[1].1;
    }
    eprintln!(
        "at {:.1} µs: striker v̄ {:.4} m/s with contact, {:.4} m/s bonded",
        late * 1e6,
        v_late[0],
        v_late[1]
    );
    assert!(
        v_late[0].abs() < 0.05 * V,
        "contact: striker v̄ {} m/s",
        v_late[0]
    );
    assert!(v_late[1] > 0.2 * V, "bonded: striker v̄ {} m/s", v_late[1]);
}

/// Steel onto Homalite: the target's stress is Z_h·v·Z_s/(Z_s + Z_h) within 3 % (measured
/// +1.3 %), sampled before the steel striker's own transit (7 µs) ends: the struck face moves at ≈ 0.94 v, the impedance match of the Rosakis
/// experiment's projectile (`reference-solutions.md`).
#[test]
fn steel_striker_loads_homalite_by_impedance_matching() {
    let (c_h, z_h) = wave(5.2e9, 0.34, 1230.0);
    let (c_s, z_s) = wave(190.0e9, 0.3, 8000.0);
    let t_mid = 6.0e-6;
    let (_, mid) = run(&bars(steel(), true, t_mid + 1e-7), c_h, c_s, t_mid);
    let sigma = -z_h * V * z_s / (z_s + z_h);
    eprintln!(
        "steel → Homalite: σ_xx target {:.4} of −Z_h v Z_s/(Z_s + Z_h) = {:.3} MPa",
        mid[0] / sigma,
        sigma * 1e-6
    );
    assert!(
        (mid[0] / sigma - 1.0).abs() < 0.03,
        "target σ_xx {} against {sigma}",
        mid[0]
    );
}

/// The contact field's results do not depend on the thread count (bitwise).
#[test]
fn contact_is_bitwise_independent_of_threads() {
    let s = bars(homalite(), true, 8.0e-6);
    let mut runs = Vec::new();
    for threads in [1, 2] {
        let mut sim = sim(&s, threads);
        while !sim.is_finished() {
            sim.step().unwrap();
        }
        let p = sim.particles();
        let bits: Vec<u64> = p
            .kin
            .iter()
            .flat_map(|k| [k.x[0], k.x[1], k.v[0], k.v[1]])
            .chain(p.stress.iter().flat_map(|s| *s))
            .map(f64::to_bits)
            .collect();
        runs.push(bits);
    }
    assert!(runs[0] == runs[1], "1 and 2 threads differ");
}

/// A Homalite block (10 × 4 mm, body 1, `contact`) sliding at `v0` on a Homalite plate
/// (40 × 4 mm, body 0) held at its bottom edge, pressed by a traction `p` on its top.
fn sliding_block(contact: serde_json::Value, p: f64, v0: f64, end: f64) -> Scene {
    let m = 2.0 * H;
    let (plate_w, plate_h, block_w, block_h) = (0.040, 0.004, 0.010, 0.004);
    let y_face = m + plate_h;
    let (bx0, bx1) = (m + 0.005, m + 0.005 + block_w);
    let top = y_face + block_h;
    let e = 0.01 * H;
    scene(json!({
        "name": "sliding-block",
        "grid": {"cell_size": H, "min": [0.0, 0.0], "max": [plate_w + 2.0 * m, top + m]},
        "materials": {"m": homalite()},
        "bodies": [
            {"material": "m", "region": {"rectangle": {"min": [m, m], "max": [m + plate_w, y_face]}}},
            {"material": "m", "region": {"rectangle": {"min": [bx0, y_face], "max": [bx1, top]}},
             "initial_velocity": [v0, 0.0], "contact": contact}
        ],
        "boundary_conditions": [
            {"region": {"rectangle": {"min": [0.0, 0.0], "max": [1.0, m + e]}},
             "velocity": {"x": 0.0, "y": 0.0}}
        ],
        "loads": [{"region": {"rectangle": {"min": [bx0 - H, top - 0.5 * H], "max": [bx1 + H, 1.0]}},
                   "traction": [0.0, -p]}],
        "time": {"end": end, "cfl": 0.5}
    }))
}

/// The block's mean x and y velocity, sampled every step.
fn block_velocity(s: &Scene) -> (Vec<(f64, f64, f64)>, Simulation) {
    let mut sim = sim(s, 0);
    let mut out = Vec::new();
    while !sim.is_finished() {
        sim.step().unwrap();
        let p = sim.particles();
        let (mut mv, mut mw, mut m) = (0.0, 0.0, 0.0);
        for ((k, me), c) in p.kin.iter().zip(&p.mech).zip(&p.cold) {
            if c.body == 1 {
                mv += me.m * k.v[0];
                mw += me.m * k.v[1];
                m += me.m;
            }
        }
        out.push((sim.time(), mv / m, mw / m));
    }
    (out, sim)
}

/// Coulomb friction μ = 0.3 under p = 1 MPa, the block at 2 m/s:
/// - Coulomb's law on the block: its x impulse over μ∫N dt within 2 % (measured 1.0000),
///   with ∫N dt from the block's own vertical momentum balance;
/// - its deceleration between 4 and 20 µs within 15 % of μp/(ρH_b) = 61 km/s² (measured
///   +10.1 %: the normal force rings about p·A as the pressure wave runs between the loaded
///   top and the held bottom, and over this interval it averages 10 % above p·A);
/// - frictionless, the block keeps its speed within 0.5 % (measured 100.00 %): no normal
///   impulse takes x momentum at its front corner (`Cracks::body_normals`).
///
/// The energy balance is not closed by the booked frictional work: 1.05 ½mv₀² booked while
/// the block lost 0.98 and the bodies gained 0.15 in elastic shear, so the sum is 23 % of
/// ½mv₀² over (printed; asserted below 30 % so that a worse ledger fails). The booking is the
/// crack faces' (`contact.rs`): a known gap, `docs/solver.md`.
#[test]
fn coulomb_friction_stops_a_pressed_block_at_the_rate_of_its_normal_force() {
    let (mu, p, v0, rho, hb) = (0.3, 1.0e6, 2.0, 1230.0, 0.004);
    let decel = mu * p / (rho * hb);
    let (hist, _) = block_velocity(&sliding_block(
        json!({"law": "frictionless"}),
        p,
        v0,
        20.0e-6,
    ));
    let v_end = hist.last().map_or(f64::NAN, |h| h.1);
    eprintln!("frictionless: v at 20 µs {v_end:.4} m/s");
    assert!(
        v_end > 0.995 * v0,
        "frictionless block slowed to {v_end} m/s"
    );
    let (hist, sim) = block_velocity(&sliding_block(
        json!({"law": "coulomb", "friction": mu}),
        p,
        v0,
        30.0e-6,
    ));
    let at = |t: f64| hist.iter().find(|h| h.0 >= t).map_or(f64::NAN, |h| h.1);
    let measured = (at(4.0e-6) - at(20.0e-6)) / 16.0e-6;
    // Coulomb's law itself: ΔP_x = −μ∫N dt with ∫N dt = ΔP_y + pA·Δt (the block's own
    // vertical momentum balance), over the sliding interval.
    let (t1, t2) = (4.0e-6, 20.0e-6);
    let py = |t: f64| hist.iter().find(|h| h.0 >= t).map_or(f64::NAN, |h| h.2);
    let mass = rho * 0.010 * hb * sim.scene().thickness;
    let normal_impulse = mass * (py(t2) - py(t1)) + p * 0.010 * sim.scene().thickness * (t2 - t1);
    let ratio = mass * (at(t1) - at(t2)) / (mu * normal_impulse);
    eprintln!("friction impulse over μ∫N dt: {ratio:.4}");
    let e = sim.energy();
    let e0 = 0.5 * rho * 0.010 * hb * sim.scene().thickness * v0 * v0;
    let balance = (e.kinetic + e.strain + e.dissipated - e.external_work - e0) / e0;
    eprintln!(
        "Coulomb: deceleration {:.4} of μp/(ρH_b) = {decel:.0} m/s²; v at 30 µs {:.4} m/s; \
         friction work {:.4} of ½mv₀², balance {balance:.4}",
        measured / decel,
        at(29.9e-6),
        e.dissipated / e0
    );
    assert!(
        (ratio - 1.0).abs() < 0.02,
        "friction impulse {ratio} of μ∫N dt"
    );
    assert!(
        (measured / decel - 1.0).abs() < 0.15,
        "deceleration {measured} m/s²"
    );
    assert!(balance.abs() < 0.3, "energy balance {balance} of ½mv₀²");
}
