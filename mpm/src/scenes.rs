//! Simulation specifications from scenes: [`spec_2d`] reads a validated 2D scene's continuum
//! (the lattice, masses, half-widths, load indices, conditions and time step); the 2D solver
//! builds its simulation from it and adds the crack layer (`fracture-solver`, `sim/build.rs`).

use std::sync::Arc;

use fracture_api::ValidScene;
use fracture_api::scene::{Analysis, Region as Region2};

use crate::dim::{Dim2, Elastic};
use crate::particles::Particles;
use crate::state::{BcSpec, LoadSpec, Region, Spec};

/// The core's region of a 2D scene region.
pub fn region_2d(r: &Region2) -> Region<Dim2> {
    let (lo, hi) = r.bounds();
    let r = r.clone();
    Region {
        contains: Arc::new(move |p: &[f64; 2]| r.contains(*p)),
        lo,
        hi,
    }
}

/// The specification of a validated 2D scene's continuum (its cracks and interfaces are
/// the 2D crack layer's and are not read here).
pub fn spec_2d(valid: &ValidScene, threads: usize) -> Spec<Dim2> {
    let (scene, size) = (valid.scene(), valid.size());
    let analysis = if scene.analysis == Analysis::PlaneStress {
        Analysis::PlaneStress
    } else {
        Analysis::PlaneStrain
    };
    let names: Vec<&String> = scene.materials.keys().collect();
    let materials: Vec<Elastic> = scene
        .materials
        .values()
        .map(|m| Elastic::new(m, analysis))
        .collect();
    let h = scene.grid.cell_size;
    let mut spec = Spec {
        min: scene.grid.min,
        max: scene.grid.max,
        h,
        shape: scene.grid.shape_function,
        materials,
        particles: Particles::default(),
        bcs: bc_specs_2d(scene),
        loads: scene
            .loads
            .iter()
            .map(|l| LoadSpec {
                traction: [
                    l.traction[0] * scene.thickness,
                    l.traction[1] * scene.thickness,
                ],
                ramp: l.ramp_time.unwrap_or(0.0),
            })
            .collect(),
        damping: scene.damping.clone(),
        dt: size.time_step,
        total_steps: size.steps,
        threads,
        scene_hash: scene.hash(),
    };
    fracture_api::lattice::for_each_seed(scene, |s| {
        let body = &scene.bodies[s.body as usize];
        let mat = names.iter().position(|n| **n == body.material).unwrap_or(0);
        let sub = h / s.ppc as f64;
        let vol = sub * sub * scene.thickness;
        let load = scene
            .loads
            .iter()
            .position(|l| l.region.contains(s.x))
            .map_or(0, |i| i as u32 + 1);
        spec.add_particle(
            s.x,
            body.initial_velocity,
            vol,
            s.ppc,
            mat as u32,
            load,
            s.body,
        );
    });
    spec
}

/// A 2D scene's velocity conditions as the core's specs (scene order).
pub fn bc_specs_2d(scene: &fracture_api::Scene) -> Vec<BcSpec<Dim2>> {
    scene
        .boundary_conditions
        .iter()
        .map(|bc| BcSpec {
            region: region_2d(&bc.region),
            velocity: [bc.velocity.x, bc.velocity.y, None],
            ramp: bc.ramp_time.unwrap_or(0.0),
            start: bc.start.unwrap_or(0.0),
            end: bc.end.unwrap_or(f64::INFINITY),
            moving: bc.moving,
        })
        .collect()
}
