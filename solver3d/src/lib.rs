//! `fracture-solver3d`: 3D runs on the dimension-generic core (`fracture-mpm`).
//!
//! [`Simulation3`] is built from a validated 3D scene ([`ValidScene3`]): particles on the
//! scene's lattice (`fracture_api::lattice3`), the bodies' materials, velocity conditions
//! resolved to nodes, traction loads, the time step; it steps on the core's
//! [`Simulation<Dim3>`](fracture_mpm::Simulation) and is observed through the energy ledger
//! and field slices (planes of the grid sampled like 2D snapshots, `output.slices`).
//! Crack surfaces, fronts and J along them are the next layer (`three-d.md`).

#![allow(clippy::needless_range_loop)]

use std::sync::Arc;

use fracture_api::ValidScene3;
use fracture_api::results::{
    EnergyRow, FieldComponent, ParticleCloud, ParticleSnapshot, Snapshot, SnapshotSlice, Volume,
};
use fracture_api::scene::{Analysis, FieldKind};
use fracture_api::scene3::{Axis, Region3, Scene3, Slice};
use fracture_mpm::particles::Particles;
use fracture_mpm::{
    BcSpec, BuildError, CheckpointError, Dim3, Elastic, Kernel, LoadSpec, PassTimes, Region,
    Simulation, Spec, StepError, StepStats,
};

/// The core's region of a scene region.
pub fn region(r: &Region3) -> Region<Dim3> {
    let (lo, hi) = r.bounds();
    let r = r.clone();
    Region {
        contains: Arc::new(move |p: &[f64; 3]| r.contains(*p)),
        lo,
        hi,
    }
}

/// The specification of a validated 3D scene.
pub fn spec_3d(valid: &ValidScene3, threads: usize) -> Spec<Dim3> {
    let (scene, size) = (valid.scene(), valid.size());
    let names: Vec<&String> = scene.materials.keys().collect();
    let materials: Vec<Elastic> = scene
        .materials
        .values()
        .map(|m| Elastic::new(m, Analysis::PlaneStrain))
        .collect();
    let h = scene.grid.cell_size;
    let mut spec = Spec {
        min: scene.grid.min,
        max: scene.grid.max,
        h,
        shape: scene.grid.shape_function,
        materials,
        particles: Particles::default(),
        bcs: scene
            .boundary_conditions
            .iter()
            .map(|bc| BcSpec {
                region: region(&bc.region),
                velocity: bc.velocity.components(),
                ramp: bc.ramp_time.unwrap_or(0.0),
                start: bc.start.unwrap_or(0.0),
                end: bc.end.unwrap_or(f64::INFINITY),
                moving: bc.moving,
            })
            .collect(),
        loads: scene
            .loads
            .iter()
            .map(|l| LoadSpec {
                traction: l.traction,
                ramp: l.ramp_time.unwrap_or(0.0),
            })
            .collect(),
        damping: scene.damping.clone(),
        dt: size.time_step,
        total_steps: size.steps,
        threads,
        scene_hash: scene.hash(),
    };
    let mat_of: Vec<u32> = scene
        .bodies
        .iter()
        .map(|b| names.iter().position(|n| **n == b.material).unwrap_or(0) as u32)
        .collect();
    fracture_api::lattice3::for_each_seed3(scene, |s| {
        let body = &scene.bodies[s.body as usize];
        let sub = h / f64::from(s.ppc);
        let load = scene
            .loads
            .iter()
            .position(|l| l.region.contains(s.x))
            .map_or(0, |i| i as u32 + 1);
        spec.add_particle(
            s.x,
            body.initial_velocity,
            sub * sub * sub,
            s.ppc,
            mat_of[s.body as usize],
            load,
            s.body,
        );
    });
    spec
}

/// A 3D run: the core's simulation and the scene it came from.
pub struct Simulation3 {
    sim: Simulation<Dim3>,
    scene: Scene3,
    slices: Vec<Slice>,
    /// Nodes lighter than this are left empty (NaN) in slices.
    m_snapshot: f64,
}

impl Simulation3 {
    /// Build from a validated scene with `threads` threads (results do not depend on it).
    pub fn new(valid: &ValidScene3, threads: usize) -> Result<Simulation3, BuildError> {
        let spec = spec_3d(valid, threads);
        let m_min = spec
            .particles
            .mech
            .iter()
            .map(|m| m.m)
            .fold(f64::INFINITY, f64::min);
        let scene = valid.scene().clone();
        let slices = scene.output.slices_or_default(&scene.grid);
        Ok(Simulation3 {
            sim: Simulation::new(spec)?,
            scene,
            slices,
            m_snapshot: 1e-9 * m_min,
        })
    }

    /// Advance one step.
    pub fn step(&mut self) -> Result<StepStats, StepError> {
        self.sim.step()
    }
    /// The scene.
    pub fn scene(&self) -> &Scene3 {
        &self.scene
    }
    /// The core simulation (particles, grid, ledger).
    pub fn core(&self) -> &Simulation<Dim3> {
        &self.sim
    }
    /// The core simulation, mutable (initial conditions, kernel).
    pub fn core_mut(&mut self) -> &mut Simulation<Dim3> {
        &mut self.sim
    }
    /// Simulated time (s).
    pub fn time(&self) -> f64 {
        self.sim.time()
    }
    /// Time step (s).
    pub fn time_step(&self) -> f64 {
        self.sim.time_step()
    }
    /// End time (s).
    pub fn end_time(&self) -> f64 {
        self.scene.time.end
    }
    /// Steps taken.
    pub fn steps_taken(&self) -> u64 {
        self.sim.steps_taken()
    }
    /// Steps to the end.
    pub fn total_steps(&self) -> u64 {
        self.sim.model.total_steps
    }
    /// Whether the end time is reached.
    pub fn is_finished(&self) -> bool {
        self.sim.is_finished()
    }
    /// Number of particles.
    pub fn particle_count(&self) -> usize {
        self.sim.particles().len()
    }
    /// Number of grid nodes.
    pub fn grid_node_count(&self) -> usize {
        self.sim.grid().node_count()
    }
    /// Threads.
    pub fn threads(&self) -> usize {
        self.sim.model.threads
    }
    /// The arithmetic of the particle passes.
    pub fn set_kernel(&mut self, k: Kernel) -> Kernel {
        self.sim.set_kernel(k)
    }
    /// Wall time per pass so far.
    pub fn pass_times(&self) -> PassTimes {
        self.sim.pass_times()
    }
    /// The energy row now (J).
    pub fn energy(&self) -> EnergyRow {
        let l = self.sim.ledger();
        EnergyRow {
            time: self.sim.time(),
            kinetic: l.kinetic,
            strain: l.strain,
            external_work: l.external_work,
            dissipated: l.dissipated,
            total_error: l.balance(),
            fracture: 0.0,
        }
    }
    /// The state as bytes.
    pub fn checkpoint(&self) -> Vec<u8> {
        self.sim.checkpoint()
    }
    /// Continue from a checkpoint of this scene.
    pub fn restore(&mut self, bytes: &[u8]) -> Result<(), CheckpointError> {
        self.sim.restore(bytes)
    }
    /// The slices this run writes.
    pub fn slices(&self) -> &[Slice] {
        &self.slices
    }

    /// One snapshot per slice, indices `first`, `first + 1`, …: mass-weighted averages of
    /// particle values at the nodes of the grid plane nearest each slice (NaN where no
    /// particle reaches a node), as 2D snapshots are.
    pub fn slice_snapshots(&self, first: u32, fields: &[FieldKind]) -> Vec<Snapshot> {
        self.slices
            .iter()
            .enumerate()
            .map(|(k, s)| self.slice_snapshot(first + k as u32, *s, fields))
            .collect()
    }

    /// The fields on the whole grid (the `--vtk` volumes): mass-weighted averages of particle
    /// values at every node, x fastest; with the particles when the scene records them.
    pub fn volume(&self, index: u32, fields: &[FieldKind]) -> Volume {
        let g = *self.sim.grid();
        let [nx, ny, nz] = g.n;
        let names = component_names(fields);
        let nc = names.len();
        let nn = nx * ny * nz;
        let mut mass = vec![0.0f64; nn];
        let mut acc = vec![0.0f64; nn * nc];
        let p = self.sim.particles();
        let mats = &self.sim.model.mats;
        let mut vals = vec![0.0f64; nc];
        let mut cloud = self.scene.output.particles.then(|| ParticleCloud {
            x: Vec::with_capacity(p.len()),
            y: Vec::with_capacity(p.len()),
            z: Vec::with_capacity(p.len()),
            components: names
                .iter()
                .map(|n| FieldComponent {
                    name: (*n).to_string(),
                    values: Vec::with_capacity(p.len()),
                })
                .collect(),
        });
        for i in 0..p.len() {
            let k = p.kin[i];
            let lh = p.mech[i].lh;
            let m = &mats[p.mech[i].mat as usize];
            particle_values(
                &names,
                &k.x,
                &k.v,
                &p.cold[i].x0,
                &p.stress[i],
                m,
                p.mech[i].mat,
                &mut vals,
            );
            if let Some(c) = cloud.as_mut() {
                c.x.push(k.x[0] as f32);
                c.y.push(k.x[1] as f32);
                c.z.push(k.x[2] as f32);
                for (comp, v) in c.components.iter_mut().zip(&vals) {
                    comp.values.push(*v as f32);
                }
            }
            let w = fracture_mpm::dim::weights::<Dim3>(
                self.sim.model.shape,
                &g.xi(&k.x),
                lh,
                0.25 / lh,
            );
            for a in 0..3 {
                for b in 0..3 {
                    for c in 0..3 {
                        let sh = w[0].s[a] * w[1].s[b] * w[2].s[c];
                        if sh == 0.0 {
                            continue;
                        }
                        let ix = (w[0].base + a as i32) as usize;
                        let iy = (w[1].base + b as i32) as usize;
                        let iz = (w[2].base + c as i32) as usize;
                        if ix >= nx || iy >= ny || iz >= nz {
                            continue;
                        }
                        let n = (iz * ny + iy) * nx + ix;
                        let sm = sh * p.mech[i].m;
                        mass[n] += sm;
                        for q in 0..nc {
                            acc[n * nc + q] += sm * vals[q];
                        }
                    }
                }
            }
        }
        let components = names
            .iter()
            .enumerate()
            .map(|(q, name)| FieldComponent {
                name: (*name).to_string(),
                values: (0..nn)
                    .map(|n| {
                        if mass[n] > self.m_snapshot {
                            (acc[n * nc + q] / mass[n]) as f32
                        } else {
                            f32::NAN
                        }
                    })
                    .collect(),
            })
            .collect();
        Volume {
            index,
            time: self.sim.time(),
            n: [nx as u32, ny as u32, nz as u32],
            origin: g.origin,
            cell_size: g.h,
            fields: fields.iter().map(|f| f.name().to_string()).collect(),
            components,
            particles: cloud,
        }
    }

    fn slice_snapshot(&self, index: u32, slice: Slice, fields: &[FieldKind]) -> Snapshot {
        let g = *self.sim.grid();
        let nrm = slice.normal.index();
        let (ua, ub) = match slice.normal {
            Axis::X => (1, 2),
            Axis::Y => (0, 2),
            Axis::Z => (0, 1),
        };
        let plane =
            (((slice.at - g.origin[nrm]) / g.h).round().max(0.0) as usize).min(g.n[nrm] - 1);
        let (na, nb) = (g.n[ua], g.n[ub]);
        let names = component_names(fields);
        let nc = names.len();
        let nn = na * nb;
        let mut mass = vec![0.0f64; nn];
        let mut acc = vec![0.0f64; nn * nc];
        let p = self.sim.particles();
        let mats = &self.sim.model.mats;
        let mut vals = vec![0.0f64; nc];
        let node_at = g.origin[nrm] + plane as f64 * g.h;
        let mut cloud = self.scene.output.particles.then(|| ParticleSnapshot {
            x: Vec::new(),
            y: Vec::new(),
            components: names
                .iter()
                .map(|n| FieldComponent {
                    name: (*n).to_string(),
                    values: Vec::new(),
                })
                .collect(),
        });
        for i in 0..p.len() {
            let k = p.kin[i];
            let lh = p.mech[i].lh;
            let xi = g.xi(&k.x);
            let w = fracture_mpm::dim::weights::<Dim3>(self.sim.model.shape, &xi, lh, 0.25 / lh);
            let off = plane as i64 - i64::from(w[nrm].base);
            if !(0..3).contains(&off) || w[nrm].s[off as usize] == 0.0 {
                continue;
            }
            let sn = w[nrm].s[off as usize];
            particle_values(
                &names,
                &k.x,
                &k.v,
                &p.cold[i].x0,
                &p.stress[i],
                &mats[p.mech[i].mat as usize],
                p.mech[i].mat,
                &mut vals,
            );
            if let Some(c) = cloud.as_mut()
                && (k.x[nrm] - node_at).abs() <= 0.5 * g.h
            {
                c.x.push(k.x[ua] as f32);
                c.y.push(k.x[ub] as f32);
                for (comp, v) in c.components.iter_mut().zip(&vals) {
                    comp.values.push(*v as f32);
                }
            }
            for a in 0..3 {
                for b in 0..3 {
                    let sh = sn * w[ua].s[a] * w[ub].s[b];
                    if sh == 0.0 {
                        continue;
                    }
                    let ia = (w[ua].base + a as i32) as usize;
                    let ib = (w[ub].base + b as i32) as usize;
                    if ia >= na || ib >= nb {
                        continue;
                    }
                    let n = ib * na + ia;
                    let sm = sh * p.mech[i].m;
                    mass[n] += sm;
                    for c in 0..nc {
                        acc[n * nc + c] += sm * vals[c];
                    }
                }
            }
        }
        let components = names
            .iter()
            .enumerate()
            .map(|(c, name)| FieldComponent {
                name: (*name).to_string(),
                values: (0..nn)
                    .map(|n| {
                        if mass[n] > self.m_snapshot {
                            (acc[n * nc + c] / mass[n]) as f32
                        } else {
                            f32::NAN
                        }
                    })
                    .collect(),
            })
            .collect();
        let axis = |i: usize| ["x", "y", "z"][i].to_string();
        Snapshot {
            index,
            time: self.sim.time(),
            nx: na as u32,
            ny: nb as u32,
            origin: [g.origin[ua], g.origin[ub]],
            cell_size: g.h,
            fields: fields.iter().map(|f| f.name().to_string()).collect(),
            components,
            cracks: Vec::new(),
            particles: cloud,
            slice: Some(SnapshotSlice {
                normal: slice.normal.name().to_string(),
                at: slice.at,
                node_at,
                axes: [axis(ua), axis(ub)],
            }),
        }
    }
}

/// The components each field kind produces in 3D, in order.
pub fn field_components3(kind: FieldKind) -> &'static [&'static str] {
    match kind {
        FieldKind::Stress => &["sxx", "syy", "szz", "syz", "sxz", "sxy"],
        FieldKind::Strain => &["exx", "eyy", "ezz", "eyz", "exz", "exy"],
        FieldKind::Velocity => &["vx", "vy", "vz", "speed"],
        FieldKind::Displacement => &["ux", "uy", "uz"],
        // Refused by validation in 3D.
        FieldKind::Fringe => &[],
        FieldKind::Material => &["material"],
    }
}

fn component_names(fields: &[FieldKind]) -> Vec<&'static str> {
    let mut names: Vec<&'static str> = Vec::new();
    for f in fields {
        for c in field_components3(*f) {
            if !names.contains(c) {
                names.push(c);
            }
        }
    }
    names
}

/// The values of one particle for `names`: stress (xx, yy, zz, yz, xz, xy), the small
/// strain through the compliance (exact for linear elasticity: ε = [(1+ν)σ − ν tr σ I]/E,
/// tensor shear components), velocity, displacement, material.
#[allow(clippy::too_many_arguments)]
fn particle_values(
    names: &[&str],
    x: &[f64; 3],
    v: &[f64; 3],
    x0: &[f64; 3],
    s: &[f64; 6],
    m: &Elastic,
    mat: u32,
    out: &mut [f64],
) {
    let tr = s[0] + s[1] + s[2];
    let normal = |k: usize| ((1.0 + m.nu) * s[k] - m.nu * tr) / m.e;
    let shear = |k: usize| (1.0 + m.nu) * s[k] / m.e;
    for (c, name) in names.iter().enumerate() {
        out[c] = match *name {
            "sxx" => s[0],
            "syy" => s[1],
            "szz" => s[2],
            "syz" => s[3],
            "sxz" => s[4],
            "sxy" => s[5],
            "exx" => normal(0),
            "eyy" => normal(1),
            "ezz" => normal(2),
            "eyz" => shear(3),
            "exz" => shear(4),
            "exy" => shear(5),
            "vx" => v[0],
            "vy" => v[1],
            "vz" => v[2],
            "speed" => (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt(),
            "ux" => x[0] - x0[0],
            "uy" => x[1] - x0[1],
            "uz" => x[2] - x0[2],
            "material" => f64::from(mat),
            _ => 0.0,
        };
    }
}
