//! Time the core's step on a block: `cargo run --release -p fracture-mpm --example block --
//! 3 50 2 20 [fma]` (dimension, cells per side, threads, steps, the FMA kernel). Prints particle-steps/s and the
//! per-pass shares.

use fracture_api::scene::{Analysis, Damping, Material, ShapeFunction};
use fracture_mpm::particles::Particles;
use fracture_mpm::{Dim, Dim2, Dim3, Elastic, Simulation, Spec};

fn run<D: Dim>(cells: usize, threads: usize, steps: usize, fma: bool) {
    let m = Elastic::new(
        &Material::LinearElastic {
            density: 7800.0,
            youngs_modulus: 200e9,
            poissons_ratio: 0.3,
        },
        Analysis::PlaneStrain,
    );
    let h = 1e-3;
    let mut min = D::V::default();
    let mut max = D::V::default();
    for d in 0..D::N {
        min.as_mut()[d] = -4.0 * h;
        max.as_mut()[d] = (cells as f64 + 4.0) * h;
    }
    let mut s = Spec::<D> {
        min,
        max,
        h,
        shape: ShapeFunction::Gimp,
        materials: vec![m],
        particles: Particles::default(),
        bcs: Vec::new(),
        loads: Vec::new(),
        damping: Damping::None,
        dt: 0.4 * h / m.c_l,
        total_steps: u64::MAX,
        threads,
        scene_hash: String::new(),
    };
    let per = 2 * cells;
    let total = per.pow(D::N as u32);
    let sub = h / 2.0;
    let vol = sub.powi(D::N as i32);
    for i in 0..total {
        let mut x = D::V::default();
        let mut r = i;
        for d in (0..D::N).rev() {
            x.as_mut()[d] = ((r % per) as f64 + 0.5) * sub;
            r /= per;
        }
        s.add_particle(x, D::V::default(), vol, 2, 0, 0, 0);
    }
    let mut sim = Simulation::new(s).expect("build");
    if fma {
        sim.set_kernel(fracture_mpm::Kernel::Fma);
    }
    sim.set_velocities(|x| {
        let mut v = D::V::default();
        v.as_mut()[0] = (x.as_ref()[0] * 200.0).sin();
        v
    });
    sim.step().expect("step");
    let t = std::time::Instant::now();
    for _ in 0..steps {
        sim.step().expect("step");
    }
    let secs = t.elapsed().as_secs_f64();
    let rate = (total * steps) as f64 / secs;
    let pt = sim.pass_times();
    let tot = pt.total();
    eprintln!(
        "{} block: {total} particles, {threads} threads: {:.2} M particle-steps/s; shares p2g {:.0} % forces {:.0} % update {:.0} % strain {:.0} % grid {:.0} % sort {:.0} %",
        D::NAME,
        rate / 1e6,
        100.0 * pt.p2g / tot,
        100.0 * pt.forces / tot,
        100.0 * pt.update / tot,
        100.0 * pt.strain / tot,
        100.0 * pt.grid / tot,
        100.0 * pt.sort / tot
    );
}

fn main() {
    let a: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|s| s.parse().ok())
        .collect();
    let (dim, cells, threads, steps) = (
        a.first().copied().unwrap_or(3),
        a.get(1).copied().unwrap_or(50),
        a.get(2).copied().unwrap_or(2),
        a.get(3).copied().unwrap_or(20),
    );
    let fma = std::env::args().any(|a| a == "fma");
    if dim == 2 {
        run::<Dim2>(cells, threads, steps, fma);
    } else {
        run::<Dim3>(cells, threads, steps, fma);
    }
}
