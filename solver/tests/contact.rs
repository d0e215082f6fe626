//! Crack-face contact (`algorithm.md` §4).
#![allow(clippy::unwrap_used)]

mod common;
use common::*;
use fracture_solver::crack::{Cracks, SlotInfo};
use fracture_solver::grid::{GridGeom, Node};
use fracture_solver::sim::Stage;
use proptest::prelude::*;
use serde_json::json;

fn cracks_with(law: serde_json::Value) -> Cracks {
    let s = scene(json!({
        "grid": {"cell_size": 1.0, "min": [0.0, 0.0], "max": [16.0, 16.0]},
        "materials": {"m": {"model": "linear_elastic", "density": 1.0, "youngs_modulus": 1.0, "poissons_ratio": 0.3}},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [1.0, 1.0], "max": [15.0, 15.0]}}}],
        "cracks": [{"points": [[2.0, 5.5], [9.0, 5.5]], "contact": law}],
        "time": {"end": 1.0}
    }));
    let geom = GridGeom::new([0.0, 0.0], [16.0, 16.0], 1.0);
    Cracks::new(&s, &geom, &[], 1e-7)
}

fn node(v: &[f64]) -> Node {
    Node {
        m: v[0],
        p: [v[1], v[2]],
        f: [v[3], v[4]],
        q: [v[5], v[6]],
        u: [v[7], v[8]],
        ..Node::default()
    }
}

proptest! {
    /// Each law conserves the total momentum of the two fields to round-off at every stage
    /// (Δp is applied as +Δp to one field and −Δp to the other). Tolerance: 1e-12 of the
    /// momentum scale.
    #[test]
    fn every_law_conserves_momentum(
        a in proptest::collection::vec(-1.0f64..1.0, 9),
        b in proptest::collection::vec(-1.0f64..1.0, 9),
        angle in 0.0f64..6.3,
        above in any::<bool>(),
    ) {
        let dt = 0.01;
        for law in [json!({"law": "frictionless"}), json!({"law": "coulomb", "friction": 0.3}), json!({"law": "stick"})] {
            for stage in [Stage::Extrapolated, Stage::Forces, Stage::Reextrapolated] {
                let mut c = cracks_with(law.clone());
                c.slots = vec![SlotInfo { above_is_f1: above, normal: [angle.cos(), angle.sin()], crack: 0 }];
                let mut n0 = node(&a);
                n0.m = a[0].abs() + 0.1;
                let mut n1 = node(&b);
                n1.m = b[0].abs() + 0.1;
                let mom = |n: &Node| match stage {
                    Stage::Extrapolated => n.p,
                    Stage::Forces => [n.p[0] + dt * n.f[0], n.p[1] + dt * n.f[1]],
                    Stage::Reextrapolated => n.q,
                };
                let mut nodes = vec![n0];
                let mut f1 = vec![n1];
                let before = [mom(&nodes[0])[0] + mom(&f1[0])[0], mom(&nodes[0])[1] + mom(&f1[0])[1]];
                let w = c.contact(stage, &mut nodes, &mut f1, &[0], 0.0, dt);
                let after = [mom(&nodes[0])[0] + mom(&f1[0])[0], mom(&nodes[0])[1] + mom(&f1[0])[1]];
                prop_assert!((before[0] - after[0]).abs() < 1e-12 && (before[1] - after[1]).abs() < 1e-12,
                    "{law} {stage:?}: {before:?} -> {after:?}");
                prop_assert!(w >= 0.0);
            }
        }
    }
}

/// A block cut by a crack from edge to edge and compressed across it: no particle crosses the
/// crack, and the energy balance holds within 2 % of the work done (frictionless contact).
/// 40 mm × 41 mm Homalite, 1 mm cells, top pushed down at up to 2 m/s, bottom fixed.
#[test]
fn compression_across_a_crack_does_not_interpenetrate() {
    let h = 0.001;
    let m = 2.0 * h;
    let (w, hh) = (0.040, 0.041);
    let yc = m + 0.5 * hh;
    let s = scene(json!({
        "grid": {"cell_size": h, "min": [0.0, 0.0], "max": [w + 2.0 * m, hh + 2.0 * m]},
        "materials": {"m": homalite()},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [m, m], "max": [m + w, m + hh]}}}],
        "cracks": [{"points": [[m - 0.5 * h, yc], [m + w + 0.5 * h, yc]]}],
        "boundary_conditions": [
            {"region": {"rectangle": {"min": [0.0, 0.0], "max": [1.0, m + 0.1 * h]}}, "velocity": {"x": 0.0, "y": 0.0}},
            {"region": {"rectangle": {"min": [0.0, m + hh - 0.1 * h], "max": [1.0, 1.0]}}, "velocity": {"y": -2.0}, "ramp_time": 5.0e-6}
        ],
        "time": {"end": 4.0e-5}
    }));
    let mut sim = sim(&s, 0);
    let side0: Vec<(u32, bool)> = sim
        .particles()
        .kin
        .iter()
        .zip(&sim.particles().cold)
        .map(|(k, c)| (c.id, k.x[1] > yc))
        .collect();
    let mut side0 = side0;
    side0.sort();
    let mut worst: f64 = 0.0;
    while !sim.is_finished() {
        sim.step().unwrap();
        worst = worst.max(sim.energy().total_error.abs());
    }
    let line = &sim.cracks().unwrap().lines()[0];
    let y_at = |x: f64| {
        for wv in line.windows(2) {
            let (a, b) = (wv[0], wv[1]);
            if (a[0] <= x && x <= b[0]) || (b[0] <= x && x <= a[0]) {
                let t = if b[0] != a[0] {
                    (x - a[0]) / (b[0] - a[0])
                } else {
                    0.0
                };
                return a[1] + t * (b[1] - a[1]);
            }
        }
        yc
    };
    let p = sim.particles();
    let mut crossed = 0;
    for (k, c) in p.kin.iter().zip(&p.cold) {
        let was_above = side0.binary_search(&(c.id, true)).is_ok();
        if was_above != (k.x[1] > y_at(k.x[0])) {
            crossed += 1;
        }
    }
    let e = sim.energy();
    eprintln!("crossed {crossed}; {e:?}; worst |error| {worst:e}");
    assert!(e.external_work > 0.0);
    assert_eq!(crossed, 0, "{crossed} particles crossed the crack");
    assert!(
        worst < 0.02 * e.external_work,
        "energy error {worst:e} vs work {:e}",
        e.external_work
    );
}

/// Coulomb friction: with a normal pressure p and a shear τ on the upper half of a block cut
/// by a crack, the halves slide only when |τ| > μ p. μ = 0.3, p = 1 MPa; τ = 0.5 μp sticks,
/// τ = 1.5 μp slides. Measured by the growth of the tangential crack opening at the centre of the crack over the
/// second half of the run, once the load is fully applied (tolerance: the stick case slips
/// less than 2 % of the sliding case).
#[test]
fn coulomb_sliding_starts_only_past_the_friction_limit() {
    let run = |tau: f64, law: serde_json::Value| {
        let h = 0.001;
        let m = 2.0 * h;
        let (w, hh) = (0.040, 0.041);
        let yc = m + 0.5 * hh;
        let top = m + hh;
        let s = scene(json!({
            "grid": {"cell_size": h, "min": [0.0, 0.0], "max": [w + 2.0 * m, hh + 2.0 * m]},
            "materials": {"m": homalite()},
            "bodies": [{"material": "m", "region": {"rectangle": {"min": [m, m], "max": [m + w, top]}}}],
            "cracks": [{"points": [[m - 0.5 * h, yc], [m + w + 0.5 * h, yc]], "contact": law.clone()}],
            "boundary_conditions": [
                {"region": {"rectangle": {"min": [0.0, 0.0], "max": [1.0, m + 0.1 * h]}}, "velocity": {"x": 0.0, "y": 0.0}}
            ],
            "loads": [{"region": {"rectangle": {"min": [0.0, top - 0.5 * h], "max": [1.0, 1.0]}},
                       "traction": [tau, -1.0e6], "ramp_time": 2.0e-5}],
            "damping": {"kind": "viscous", "coefficient": 5.0e4},
            "time": {"end": 2.0e-4}
        }));
        let mut sim = sim(&s, 0);
        // Slip: mean x displacement of the particles within 2h above the crack minus that of
        // the particles within 2h below it.
        let slip = |sim: &fracture_solver::Simulation| {
            let p = sim.particles();
            let (mut up, mut nu, mut lo, mut nl) = (0.0, 0.0, 0.0, 0.0);
            for (k, c) in p.kin.iter().zip(&p.cold) {
                let d = c.x0[1] - yc;
                if d > 0.0 && d < 2.0 * h {
                    up += k.x[0] - c.x0[0];
                    nu += 1.0;
                } else if d < 0.0 && d > -2.0 * h {
                    lo += k.x[0] - c.x0[0];
                    nl += 1.0;
                }
            }
            up / nu - lo / nl
        };
        let mut half = None;
        while !sim.is_finished() {
            sim.step().unwrap();
            if half.is_none() && sim.time() >= 1.0e-4 {
                half = Some(slip(&sim));
            }
        }
        // Slip accumulated once the load is fully applied (second half of the run).
        let growth = slip(&sim) - half.unwrap();
        let e = sim.energy();
        eprintln!(
            "tau {tau:.0}: slip growth {growth:e} m, friction+damping {:e} J",
            e.dissipated
        );
        growth
    };
    let bonded = run(0.5 * 0.3e6, json!({"law": "stick"}));
    let stick = run(0.5 * 0.3e6, json!({"law": "coulomb", "friction": 0.3}));
    let slide = run(1.5 * 0.3e6, json!({"law": "coulomb", "friction": 0.3}));
    assert!(slide > 1.0e-6, "no sliding past the limit: {slide:e}");
    assert!(
        stick.abs() < 0.02 * slide,
        "sliding below the limit: {stick:e} vs {slide:e}"
    );
    // Below the limit the faces behave like bonded faces (only elastic motion).
    assert!(
        stick.abs() <= 1.2 * bonded.abs() + 1e-9,
        "{stick:e} vs bonded {bonded:e}"
    );
}
