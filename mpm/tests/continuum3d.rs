//! The 3D continuum against physics it does not contain (small grids): the wave speed of a
//! laterally constrained bar, a vibrating bar's period, an impact's energy balance, a free
//! flight's momentum and energy, a plane-strain slab against its 2D twin; and determinism
//! (1 vs 2 threads, checkpoint resume).

use std::sync::Arc;

use fracture_api::scene::{Analysis, Damping, Material, ShapeFunction};
use fracture_mpm::particles::Particles;
use fracture_mpm::{BcSpec, Dim3, Elastic, Region, Simulation, Spec};

fn material(rho: f64, e: f64, nu: f64) -> Elastic {
    let m = Material::LinearElastic {
        density: rho,
        youngs_modulus: e,
        poissons_ratio: nu,
    };
    Elastic::new(&m, Analysis::PlaneStrain)
}

/// An empty 3D spec on the box [min, max] with cell h.
fn spec(min: [f64; 3], max: [f64; 3], h: f64, mats: Vec<Elastic>, dt_cfl: f64) -> Spec<Dim3> {
    let c = mats.iter().map(|m| m.c_l).fold(0.0, f64::max);
    Spec {
        min,
        max,
        h,
        shape: ShapeFunction::Gimp,
        materials: mats,
        particles: Particles::default(),
        bcs: Vec::new(),
        loads: Vec::new(),
        damping: Damping::None,
        dt: dt_cfl * h / c,
        total_steps: u64::MAX,
        threads: 2,
        scene_hash: "test".into(),
    }
}

/// Fill the box [lo, hi] (aligned to the lattice) with `ppc`³ particles per cell.
fn fill(
    s: &mut Spec<Dim3>,
    lo: [f64; 3],
    hi: [f64; 3],
    ppc: u32,
    mat: u32,
    v: [f64; 3],
    body: u32,
) {
    let sub = s.h / f64::from(ppc);
    let n: Vec<usize> = (0..3)
        .map(|d| ((hi[d] - lo[d]) / sub).round() as usize)
        .collect();
    for i in 0..n[0] {
        for j in 0..n[1] {
            for k in 0..n[2] {
                let x = [
                    lo[0] + (i as f64 + 0.5) * sub,
                    lo[1] + (j as f64 + 0.5) * sub,
                    lo[2] + (k as f64 + 0.5) * sub,
                ];
                s.add_particle(x, v, sub * sub * sub, ppc, mat, 0, body);
            }
        }
    }
}

fn everywhere(velocity: [Option<f64>; 3]) -> BcSpec<Dim3> {
    BcSpec {
        region: Region {
            contains: Arc::new(|_| true),
            lo: [-1e9; 3],
            hi: [1e9; 3],
        },
        velocity,
        ramp: 0.0,
        start: 0.0,
        end: f64::INFINITY,
        moving: false,
    }
}

fn slab_x(x0: f64, x1: f64, velocity: [Option<f64>; 3]) -> BcSpec<Dim3> {
    BcSpec {
        region: Region {
            contains: Arc::new(move |p| p[0] >= x0 && p[0] <= x1),
            lo: [x0, -1e9, -1e9],
            hi: [x1, 1e9, 1e9],
        },
        ..everywhere(velocity)
    }
}

/// Mean σ_xx of the particles in each x-slab of width `w` from `x0`.
fn profile(sim: &Simulation<Dim3>, x0: f64, w: f64, n: usize) -> Vec<f64> {
    let mut sum = vec![0.0; n];
    let mut cnt = vec![0.0f64; n];
    let p = sim.particles();
    for (k, s) in p.kin.iter().zip(&p.stress) {
        let i = ((k.x[0] - x0) / w).floor();
        if i >= 0.0 && (i as usize) < n {
            sum[i as usize] += s[0];
            cnt[i as usize] += 1.0;
        }
    }
    sum.iter().zip(&cnt).map(|(s, c)| s / c.max(1.0)).collect()
}

/// Where the profile first falls to half the plateau `p` (linear interpolation).
fn half_point(prof: &[f64], x0: f64, w: f64, p: f64) -> f64 {
    for i in 1..prof.len() {
        let (a, b) = (prof[i - 1] / p, prof[i] / p);
        if a >= 0.5 && b < 0.5 {
            let t = (a - 0.5) / (a - b);
            return x0 + (i as f64 - 0.5 + t) * w;
        }
    }
    f64::NAN
}

/// A bar held laterally on every node (uniaxial strain) driven at x = 0: its front moves at
/// c_L = √((λ+2μ)/ρ) and the stress behind it is −ρ c_L v (Rankine–Hugoniot).
#[test]
fn constrained_bar_wave_speed() {
    let m = material(7800.0, 200e9, 0.3);
    let h = 1e-3;
    let (len, wid) = (0.08, 0.004);
    let mut s = spec(
        [-3.0 * h, -3.0 * h, -3.0 * h],
        [len + 3.0 * h, wid + 3.0 * h, wid + 3.0 * h],
        h,
        vec![m],
        0.4,
    );
    fill(&mut s, [0.0; 3], [len, wid, wid], 2, 0, [0.0; 3], 0);
    let v0 = 1.0;
    s.bcs.push(everywhere([None, Some(0.0), Some(0.0)]));
    s.bcs.push(slab_x(-1.0, 0.0, [Some(v0), None, None]));
    let dt = s.dt;
    let mut sim = Simulation::new(s).expect("build");
    let plateau = -m.rho * m.c_l * v0;
    let w = h / 2.0;
    let n = (len / w) as usize;
    let mut fronts = Vec::new();
    for target in [4e-6, 9e-6] {
        while sim.time() < target - 0.5 * dt {
            sim.step().expect("step");
        }
        let prof = profile(&sim, 0.0, w, n);
        // The plateau behind the front (its first half).
        let behind: f64 = prof[4..n / 8].iter().sum::<f64>() / (n / 8 - 4) as f64;
        assert!(
            (behind / plateau - 1.0).abs() < 0.02,
            "plateau {behind:e} vs {plateau:e}"
        );
        fronts.push((sim.time(), half_point(&prof, 0.0, w, plateau)));
    }
    let c = (fronts[1].1 - fronts[0].1) / (fronts[1].0 - fronts[0].0);
    let err = c / m.c_l - 1.0;
    eprintln!(
        "constrained bar: c = {c:.1} m/s, c_L = {:.1}, error {:+.2} %",
        m.c_l,
        100.0 * err
    );
    assert!(err.abs() < 0.02, "c = {c} vs c_L = {}", m.c_l);
}

/// A free–free bar (ν = 0, so the 1D speed is √(E/ρ)) in its first mode: the end's
/// displacement u(t) = (v0/ω) sin ωt crosses zero again at T/2 = L/c.
#[test]
fn vibrating_bar_period() {
    let m = material(1000.0, 1e9, 0.0);
    let h = 1e-3;
    let (len, wid) = (0.04, 0.003);
    let mut s = spec(
        [-3.0 * h; 3],
        [len + 3.0 * h, wid + 3.0 * h, wid + 3.0 * h],
        h,
        vec![m],
        0.4,
    );
    fill(&mut s, [0.0; 3], [len, wid, wid], 2, 0, [0.0; 3], 0);
    let dt = s.dt;
    let mut sim = Simulation::new(s).expect("build");
    let v0 = 0.1;
    sim.set_velocities(|x| [v0 * (std::f64::consts::PI * x[0] / len).cos(), 0.0, 0.0]);
    let c = (m.e / m.rho).sqrt();
    let half = len / c;
    // Mean displacement of the particles within a cell of x = 0.
    let end_u = |sim: &Simulation<Dim3>| {
        let p = sim.particles();
        let (mut u, mut n) = (0.0, 0.0);
        for (k, cold) in p.kin.iter().zip(&p.cold) {
            if cold.x0[0] < h {
                u += k.x[0] - cold.x0[0];
                n += 1.0;
            }
        }
        u / n
    };
    let mut prev = (sim.time(), end_u(&sim));
    let mut crossing = f64::NAN;
    while sim.time() < 1.5 * half {
        sim.step().expect("step");
        let now = (sim.time(), end_u(&sim));
        if sim.time() > 0.5 * half && prev.1 > 0.0 && now.1 <= 0.0 {
            crossing = prev.0 + (now.0 - prev.0) * prev.1 / (prev.1 - now.1);
            break;
        }
        prev = now;
    }
    let err = crossing / half - 1.0;
    eprintln!(
        "vibrating bar: T/2 = {crossing:.4e} s, L/c = {half:.4e} s, error {:+.3} % (dt {dt:.2e})",
        100.0 * err
    );
    assert!(err.abs() < 0.01, "half period {crossing} vs {half}");
}

/// A cube strikes a block: no conditions, no damping, so kinetic + strain energy stays the
/// input (USAVG is not exactly conservative: within 0.5 %); momentum is exact.
#[test]
fn impact_energy_balance() {
    let m = material(2700.0, 70e9, 0.33);
    let h = 1e-3;
    let mut s = spec([-3.0 * h; 3], [0.03, 0.015, 0.015], h, vec![m], 0.4);
    fill(
        &mut s,
        [0.0, 0.0, 0.0],
        [0.012, 0.012, 0.012],
        2,
        0,
        [0.0; 3],
        0,
    );
    fill(
        &mut s,
        [0.013, 0.004, 0.004],
        [0.019, 0.008, 0.008],
        2,
        0,
        [-20.0, 0.0, 0.0],
        1,
    );
    let mut sim = Simulation::new(s).expect("build");
    let e0 = sim.ledger().kinetic;
    let p0 = sim.momentum();
    let mut worst: f64 = 0.0;
    let mut strained = 0.0_f64;
    for _ in 0..400 {
        sim.step().expect("step");
        let l = sim.ledger();
        worst = worst.max(((l.kinetic + l.strain) / e0 - 1.0).abs());
        strained = strained.max(l.strain / e0);
    }
    let p1 = sim.momentum();
    eprintln!(
        "impact: worst energy error {:.3} %, peak strain share {:.1} %",
        100.0 * worst,
        100.0 * strained
    );
    assert!(strained > 0.1, "the bodies must meet ({strained})");
    assert!(worst < 0.005, "energy error {worst}");
    assert!(
        (p1[0] - p0[0]).abs() < 1e-12 * p0[0].abs(),
        "{p0:?} → {p1:?}"
    );
}

/// A sphere of particles flying freely: momentum and energy to round-off.
#[test]
fn free_sphere_keeps_momentum_and_energy() {
    let m = material(7800.0, 200e9, 0.3);
    let h = 1e-3;
    let mut s = spec([-0.002; 3], [0.03, 0.02, 0.02], h, vec![m], 0.5);
    let (c, r) = ([0.008, 0.008, 0.008], 0.005);
    let mut full = Spec { ..s.clone() };
    fill(&mut full, [0.0; 3], [0.016; 3], 2, 0, [12.0, -5.0, 3.0], 0);
    for i in 0..full.particles.len() {
        let x = full.particles.kin[i].x;
        if (0..3).map(|d| (x[d] - c[d]).powi(2)).sum::<f64>() <= r * r {
            let k = full.particles.kin[i];
            s.add_particle(k.x, k.v, full.particles.mech[i].vol, 2, 0, 0, 0);
        }
    }
    let mut sim = Simulation::new(s).expect("build");
    let (e0, p0) = (sim.ledger().kinetic, sim.momentum());
    for _ in 0..200 {
        sim.step().expect("step");
    }
    let (l, p1) = (sim.ledger(), sim.momentum());
    for d in 0..3 {
        assert!(
            (p1[d] - p0[d]).abs() <= 1e-12 * p0[0].abs(),
            "momentum {p0:?} → {p1:?}"
        );
    }
    assert!(
        ((l.kinetic + l.strain) / e0 - 1.0).abs() < 1e-12,
        "energy {l:?} vs {e0}"
    );
    assert!(
        l.strain < 1e-12 * e0,
        "a rigid flight strains nothing: {l:?}"
    );
}

fn small_run(threads: usize) -> Simulation<Dim3> {
    let m = material(2700.0, 70e9, 0.33);
    let h = 1e-3;
    let mut s = spec([-3.0 * h; 3], [0.03, 0.015, 0.015], h, vec![m], 0.4);
    s.threads = threads;
    fill(&mut s, [0.0; 3], [0.02, 0.01, 0.01], 2, 0, [0.0; 3], 0);
    s.bcs.push(slab_x(-1.0, 0.0, [Some(5.0), None, None]));
    let mut sim = Simulation::new(s).expect("build");
    sim.set_velocities(|x| [0.0, 3.0 * (x[0] * 300.0).sin(), -2.0 * (x[2] * 400.0).cos()]);
    sim
}

fn bits(sim: &Simulation<Dim3>) -> Vec<u64> {
    let p = sim.particles();
    let mut out = Vec::new();
    for i in 0..p.len() {
        out.extend(
            p.kin[i]
                .x
                .iter()
                .chain(&p.kin[i].v)
                .chain(&p.stress[i])
                .map(|v| v.to_bits()),
        );
        out.push(p.wden[i].to_bits());
        out.push(u64::from(p.cold[i].id));
    }
    let l = sim.ledger();
    out.extend([l.kinetic, l.strain, l.external_work].map(f64::to_bits));
    out
}

#[test]
fn threads_and_checkpoints_are_bitwise() {
    let mut a = small_run(1);
    let mut b = small_run(2);
    for _ in 0..60 {
        a.step().expect("step");
        b.step().expect("step");
    }
    assert_eq!(bits(&a), bits(&b), "1 vs 2 threads");
    let ck = a.checkpoint();
    let mut c = small_run(2);
    c.restore(&ck).expect("restore");
    for _ in 0..40 {
        a.step().expect("step");
        c.step().expect("step");
    }
    assert_eq!(bits(&a), bits(&c), "resumed run");
    // Another scene's checkpoint is refused.
    let mut other = small_run(1);
    other.model.scene_hash = "other".into();
    assert!(other.restore(&ck).is_err());
}

/// The 2D impact bar scene (`scenes/impact-bar.json`, plane strain).
fn impact_bar() -> fracture_api::ValidScene {
    let text = std::fs::read_to_string(format!(
        "{}/../scenes/impact-bar.json",
        env!("CARGO_MANIFEST_DIR")
    ))
    .expect("scene");
    let scene = fracture_api::validate::parse_scene(&text).expect("scene");
    fracture_api::ValidScene::new(scene).expect("valid")
}

/// The impact bar (`scenes/impact-bar.json`, plane strain) as a slab two cells thick with
/// every node held in z: its energies per unit thickness are the 2D run's.
#[test]
fn plane_strain_slab_matches_its_2d_twin() {
    let valid = impact_bar();
    let s2 = fracture_mpm::scenes::spec_2d(&valid, 2);
    let h = s2.h;
    let layers = 2usize;
    let ppc = 2u32;
    let t = layers as f64 * h;
    let mut s3 = Spec::<Dim3> {
        min: [s2.min[0], s2.min[1], -3.0 * h],
        max: [s2.max[0], s2.max[1], t + 3.0 * h],
        h,
        shape: s2.shape,
        materials: s2.materials.clone(),
        particles: Particles::default(),
        bcs: Vec::new(),
        loads: Vec::new(),
        damping: s2.damping.clone(),
        dt: s2.dt,
        total_steps: s2.total_steps,
        threads: 2,
        scene_hash: "slab".into(),
    };
    let sub = h / f64::from(ppc);
    let p2 = &s2.particles;
    for i in 0..p2.len() {
        for k in 0..(layers * ppc as usize) {
            let x = p2.kin[i].x;
            let v = p2.kin[i].v;
            let z = (k as f64 + 0.5) * sub;
            s3.add_particle(
                [x[0], x[1], z],
                [v[0], v[1], 0.0],
                p2.mech[i].vol * sub,
                ppc,
                p2.mech[i].mat,
                0,
                p2.cold[i].body,
            );
        }
    }
    for bc in &s2.bcs {
        let c = Arc::clone(&bc.region.contains);
        s3.bcs.push(BcSpec {
            region: Region {
                contains: Arc::new(move |p: &[f64; 3]| c(&[p[0], p[1]])),
                lo: [bc.region.lo[0], bc.region.lo[1], -1e9],
                hi: [bc.region.hi[0], bc.region.hi[1], 1e9],
            },
            velocity: bc.velocity,
            ramp: bc.ramp,
            start: bc.start,
            end: bc.end,
            moving: bc.moving,
        });
    }
    s3.bcs.push(everywhere([None, None, Some(0.0)]));
    let mut a = Simulation::new(s2).expect("2D");
    let mut b = Simulation::new(s3).expect("3D");
    let mut worst: f64 = 0.0;
    for n in 0..300 {
        a.step().expect("2D step");
        b.step().expect("3D step");
        if n % 10 == 9 {
            let (la, lb) = (a.ledger(), b.ledger());
            let scale = la.external_work.abs().max(la.kinetic + la.strain);
            for (x, y) in [
                (la.kinetic, lb.kinetic / t),
                (la.strain, lb.strain / t),
                (la.external_work, lb.external_work / t),
            ] {
                worst = worst.max((y - x).abs() / scale);
            }
        }
    }
    eprintln!(
        "slab vs 2D twin: worst energy difference {:.2e} of the energy scale",
        worst
    );
    assert!(worst < 0.005, "{worst}");
}

/// A checkpoint names its dimension and format: a 2D checkpoint given to a 3D simulation,
/// and a 3D one of format 2 (before the envelope was shared with 2D), are refused with that
/// said, never read as a state.
#[test]
fn checkpoints_of_another_dimension_or_format_are_refused() {
    use fracture_mpm::CheckpointError;
    let valid = impact_bar();
    let mut two = Simulation::<fracture_mpm::Dim2>::new(fracture_mpm::scenes::spec_2d(&valid, 1))
        .expect("2D build");
    two.step().expect("step");
    let mut three = small_run(1);
    three.model.scene_hash = two.model.scene_hash.clone();
    match three.restore(&two.checkpoint()) {
        Err(CheckpointError::Mismatch(m)) => {
            assert!(m.contains("2D checkpoint") && m.contains("3D"), "{m}")
        }
        other => panic!("a 2D checkpoint in 3D: {other:?}"),
    }
    // The header of a format-2 3D checkpoint: its magic, format and version come first.
    let old = postcard::to_allocvec(&(*b"MPMCORE\0", 2u32, fracture_api::SOLVER_VERSION, 3u32))
        .expect("bytes");
    match three.restore(&old) {
        Err(
            e @ CheckpointError::Version {
                found_format: 2, ..
            },
        ) => {
            assert!(e.to_string().contains("format 2"), "{e}")
        }
        other => panic!("a format-2 checkpoint: {other:?}"),
    }
    // And this simulation's own checkpoint still resumes.
    let ck = three.checkpoint();
    let mut again = small_run(1);
    again.model.scene_hash = three.model.scene_hash.clone();
    again.restore(&ck).expect("own checkpoint");
}
