//! The fused last pass (second stress update + next step's P2G into the spare grid) gives
//! the bits of the unfused step, in 2D and 3D, through re-sorts, a checkpoint and a change
//! of velocities between steps.

use fracture_api::ValidScene;
use fracture_api::validate::parse_scene;
use fracture_mpm::scenes::spec_2d;
use fracture_mpm::{Dim, Dim2, Simulation};

fn bits<D: Dim>(sim: &Simulation<D>) -> Vec<u64> {
    let p = sim.particles();
    let mut out = Vec::new();
    for i in 0..p.len() {
        out.extend(
            p.kin[i]
                .x
                .as_ref()
                .iter()
                .chain(p.kin[i].v.as_ref())
                .map(|v| v.to_bits()),
        );
        out.extend(p.stress[i].as_ref().iter().map(|v| v.to_bits()));
        out.push(p.wden[i].to_bits());
    }
    let l = sim.ledger();
    out.extend([l.kinetic, l.strain, l.external_work].map(f64::to_bits));
    out
}

fn impact_bar(threads: usize) -> Simulation<Dim2> {
    let text = std::fs::read_to_string(format!(
        "{}/../scenes/impact-bar.json",
        env!("CARGO_MANIFEST_DIR")
    ))
    .expect("scene");
    let valid = ValidScene::new(parse_scene(&text).expect("parse")).expect("valid");
    Simulation::new(spec_2d(&valid, threads)).expect("build")
}

#[test]
fn fused_step_is_bitwise_the_unfused_step_2d() {
    let mut a = impact_bar(2);
    let mut b = impact_bar(1);
    b.set_fused_step(false);
    for k in 0..120 {
        a.step().expect("a");
        b.step().expect("b");
        if k == 50 {
            // Between steps: a new velocity field drops the P2G done ahead.
            a.set_velocities(|x| [x[0].sin(), 0.5]);
            b.set_velocities(|x| [x[0].sin(), 0.5]);
        }
        if k == 80 {
            let ck = a.checkpoint();
            let mut c = impact_bar(2);
            c.restore(&ck).expect("restore");
            a = c;
        }
    }
    assert_eq!(bits(&a), bits(&b));
}

#[test]
fn fused_step_is_bitwise_the_unfused_step_3d() {
    use fracture_api::scene::{Analysis, Damping, Material, ShapeFunction};
    use fracture_mpm::particles::Particles;
    use fracture_mpm::{Dim3, Elastic, Spec};
    let m = Elastic::new(
        &Material::LinearElastic {
            density: 2700.0,
            youngs_modulus: 70e9,
            poissons_ratio: 0.33,
        },
        Analysis::PlaneStrain,
    );
    let build = |fuse: bool| {
        let h = 1e-3;
        let mut s = Spec::<Dim3> {
            min: [-0.003; 3],
            max: [0.03, 0.012, 0.012],
            h,
            shape: ShapeFunction::Gimp,
            materials: vec![m],
            particles: Particles::default(),
            bcs: Vec::new(),
            loads: Vec::new(),
            damping: Damping::None,
            dt: 0.4 * h / m.c_l,
            total_steps: u64::MAX,
            threads: 2,
            scene_hash: "fused".into(),
        };
        let sub = h / 2.0;
        for i in 0..24 {
            for j in 0..12 {
                for k in 0..12 {
                    let x = [
                        (i as f64 + 0.5) * sub,
                        (j as f64 + 0.5) * sub,
                        (k as f64 + 0.5) * sub,
                    ];
                    // Fast enough to cross strips (re-sorts) within the run.
                    s.add_particle(x, [400.0, 30.0, -20.0], sub * sub * sub, 2, 0, 0, 0);
                }
            }
        }
        let mut sim = Simulation::new(s).expect("build");
        sim.set_fused_step(fuse);
        sim
    };
    let (mut a, mut b) = (build(true), build(false));
    for _ in 0..150 {
        a.step().expect("a");
        b.step().expect("b");
    }
    assert_eq!(bits(&a), bits(&b));
}
