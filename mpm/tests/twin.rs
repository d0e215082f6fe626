//! The core's `Dim2` run is the 2D solver's run, bit for bit: every particle's position,
//! velocity, stress and strain energy density and the energy ledger after some steps, on the
//! project's uncracked scenes and variants of them (linear shape functions, kinetic and
//! viscous damping, plane stress, a moving condition, a ramped load), with 1 and 2 threads
//! and both kernels. Since the 2D solver's `Simulation` became the core's
//! `Simulation<Dim2, CrackLayer>`, this checks that its crack layer, absent, adds nothing to
//! the step (`solver/tests/state_hashes.rs` is the gate against the solver before the move).

use fracture_api::validate::parse_scene;
use fracture_api::{Scene, ValidScene};
use fracture_mpm::scenes::spec_2d;
use fracture_mpm::{Dim2, Kernel, Simulation};
use fracture_solver::{Parallelism, SolverConfig};

fn scene(name: &str) -> Scene {
    let path = format!("{}/../scenes/{name}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).expect("scene file");
    parse_scene(&text).expect("valid scene")
}

/// Run both for `steps` steps and compare everything bitwise.
fn twin(label: &str, scene: Scene, steps: usize, threads: usize, kernel: Kernel) {
    let valid = ValidScene::new(scene).expect("valid");
    let mut a = fracture_solver::Simulation::new(
        &valid,
        SolverConfig {
            threads: Parallelism::threads(threads),
        },
    )
    .expect("2D solver");
    let mut b = Simulation::<Dim2>::new(spec_2d(&valid, threads)).expect("core");
    let ka = a.set_kernel(match kernel {
        Kernel::Portable => fracture_solver::kernel::Kernel::Portable,
        Kernel::Fma => fracture_solver::kernel::Kernel::Fma,
    });
    let kb = b.set_kernel(kernel);
    // The vibrating bar starts at rest: give both the same velocity field.
    if label.contains("vibrating") || label.contains("viscous") {
        let mode = |x: [f64; 2]| [0.3 * (x[0] * 41.0).sin(), 0.1 * (x[1] * 29.0).cos()];
        a.set_velocities(mode);
        b.set_velocities(|x| mode(*x));
    }
    assert_eq!(ka.name(), kb.name(), "{label}: kernels");
    for _ in 0..steps {
        a.step().expect("2D step");
        b.step().expect("core step");
    }
    let (pa, pb) = (a.particles(), b.particles());
    assert_eq!(pa.len(), pb.len(), "{label}: particle count");
    for i in 0..pa.len() {
        let (ka, kb) = (pa.kin[i], pb.kin[i]);
        assert_eq!(pa.cold[i].id, pb.cold[i].id, "{label}: order at {i}");
        for d in 0..2 {
            assert_eq!(ka.x[d].to_bits(), kb.x[d].to_bits(), "{label}: x of {i}");
            assert_eq!(ka.v[d].to_bits(), kb.v[d].to_bits(), "{label}: v of {i}");
        }
        for c in 0..4 {
            assert_eq!(
                pa.stress[i][c].to_bits(),
                pb.stress[i][c].to_bits(),
                "{label}: stress {c} of {i}"
            );
        }
        assert_eq!(
            pa.wden[i].to_bits(),
            pb.wden[i].to_bits(),
            "{label}: W of {i}"
        );
    }
    let (ea, lb) = (a.energy(), b.ledger());
    assert_eq!(
        ea.kinetic.to_bits(),
        lb.kinetic.to_bits(),
        "{label}: kinetic"
    );
    assert_eq!(ea.strain.to_bits(), lb.strain.to_bits(), "{label}: strain");
    assert_eq!(
        ea.external_work.to_bits(),
        lb.external_work.to_bits(),
        "{label}: external work"
    );
    assert_eq!(
        ea.dissipated.to_bits(),
        lb.dissipated.to_bits(),
        "{label}: dissipated"
    );
    assert!(
        b.ledger().kinetic > 0.0 || b.ledger().strain > 0.0,
        "{label}: nothing moved"
    );
}

#[test]
fn uncracked_scenes_are_bitwise_the_2d_solver() {
    for name in [
        "wave-bar.json",
        "vibrating-bar.json",
        "impact-bar.json",
        "free-flight.json",
    ] {
        for threads in [1, 2] {
            twin(name, scene(name), 60, threads, Kernel::Portable);
        }
    }
}

#[test]
fn variants_are_bitwise_the_2d_solver() {
    let base = scene("impact-bar.json");
    let mut linear = base.clone();
    linear.grid.shape_function = fracture_api::scene::ShapeFunction::Linear;
    twin("linear", linear, 40, 2, Kernel::Portable);

    let mut stress = base.clone();
    stress.analysis = fracture_api::scene::Analysis::PlaneStress;
    twin("plane stress", stress, 40, 2, Kernel::Portable);

    let mut kinetic = scene("wave-bar.json");
    kinetic.damping = fracture_api::scene::Damping::Kinetic { coefficient: 0.2 };
    twin("kinetic damping", kinetic, 40, 2, Kernel::Portable);

    let mut viscous = scene("vibrating-bar.json");
    viscous.damping = fracture_api::scene::Damping::Viscous { coefficient: 50.0 };
    twin("viscous damping", viscous, 40, 1, Kernel::Portable);

    let mut moving = base.clone();
    for bc in &mut moving.boundary_conditions {
        bc.moving = true;
    }
    twin("moving conditions", moving, 40, 2, Kernel::Portable);

    let mut ramped = scene("wave-bar.json");
    for l in &mut ramped.loads {
        l.ramp_time = Some(2e-6);
    }
    twin("ramped load", ramped, 40, 2, Kernel::Portable);

    if Kernel::Fma.available() {
        twin("fma", scene("impact-bar.json"), 40, 2, Kernel::Fma);
    }
}
