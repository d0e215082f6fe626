//! Observing a simulation: read-only views (scene, time, particles, grid), energies
//! (`algorithm.md` §2), crack-tip rows with J and K computed on demand (§6), work counters of
//! the optional phases, and field snapshots (mass-weighted nodal averages of particle values).

use fracture_api::Scene;
use fracture_api::results::{
    CrackTipRow, EnergyRow, FieldComponent, ParticleSnapshot, Snapshot, field_components,
};
use fracture_api::scene::FieldKind;

use super::{PassTimes, Simulation, WorkCounters};
use crate::crack::Cracks;
use crate::grid::GridGeom;
use crate::particles::Particles;
use crate::shape::Weights2;

/// Read-only views.
impl Simulation {
    /// The scene.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }
    /// Simulated time (s).
    pub fn time(&self) -> f64 {
        self.core.state.time
    }
    /// Steps taken.
    pub fn steps_taken(&self) -> u64 {
        self.core.state.steps
    }
    /// Δt (s).
    pub fn time_step(&self) -> f64 {
        self.core.model.dt
    }
    /// End time (s).
    pub fn end_time(&self) -> f64 {
        self.scene.time.end
    }
    /// Steps to reach the end time.
    pub fn total_steps(&self) -> u64 {
        self.core.model.total_steps
    }
    /// Whether the end time is reached.
    pub fn is_finished(&self) -> bool {
        self.core.is_finished()
    }
    /// Number of particles.
    pub fn particle_count(&self) -> usize {
        self.core.state.parts.len()
    }
    /// Nodes of the grid box.
    pub fn grid_node_count(&self) -> usize {
        self.grid().nx() * self.grid().ny()
    }
    /// Nodes (and extra crack fields) touched by particles in the last step.
    pub fn active_node_count(&self) -> usize {
        self.core.scratch.active_nodes
    }
    /// Threads in use.
    pub fn threads(&self) -> usize {
        self.core.model.threads
    }
    /// Grid geometry.
    pub fn grid(&self) -> &GridGeom {
        &self.core.model.geom
    }
    /// The particles (sorted by cell; `cold[i].id` is the creation index).
    pub fn particles(&self) -> &Particles {
        &self.core.state.parts
    }
    /// Wall time of each pass so far (s): the core's counters of the step's sort, four
    /// passes and grid work (crack phases included in the grid's).
    pub fn pass_times(&self) -> PassTimes {
        self.core.pass_times()
    }

    /// Energies now (J per the scene's thickness).
    pub fn energy(&self) -> EnergyRow {
        let l = self.core.ledger();
        EnergyRow {
            time: self.time(),
            kinetic: l.kinetic,
            strain: l.strain,
            external_work: l.external_work,
            dissipated: l.dissipated,
            total_error: l.balance(),
            fracture: self.cracks().map_or(0.0, |c| c.zone_work()),
        }
    }

    /// The fracture-energy report of the growing tips (None when no crack can grow): what
    /// the new surface takes (Σ Γ(v)·Δa·thickness), what the process zones dissipated, and the
    /// rest, which stayed in the body.
    pub fn fracture_energy(&self) -> Option<fracture_api::results::FractureEnergy> {
        let c = self.cracks().filter(|c| c.can_grow())?;
        let (required, above_toughness, new_area) = c.fracture_required();
        let dissipated = c.zone_work();
        Some(fracture_api::results::FractureEnergy {
            required,
            dissipated,
            not_dissipated: required - dissipated,
            new_area,
            at_speed_limit: above_toughness,
        })
    }

    /// One row per crack tip now (J and K computed here, on demand).
    pub fn crack_tips(&mut self) -> Vec<CrackTipRow> {
        let time = self.time();
        let c = &mut self.core;
        let v = super::layer::view(&c.model, &c.state.parts, &c.state.strip_bounds, &c.scratch);
        match c.state.layer.0.as_mut() {
            Some(cr) => cr.tip_rows(&v, time),
            None => Vec::new(),
        }
    }

    /// The cracks, if the scene has any.
    pub fn cracks(&self) -> Option<&Cracks> {
        self.core.state.layer.0.as_deref()
    }

    /// Prescribe crack `crack`'s growth between steps: its growing tips run at `speed` (m/s)
    /// and their process zones take `toughness` (J/m²) per unit new area, whatever the
    /// equation of motion would say (`None`: the law again). Verification drives a tip along
    /// a known motion with the energy LEFM says reaches it this way; not for users, not in
    /// checkpoints. False when there is no such crack.
    #[doc(hidden)]
    pub fn set_prescribed_motion(&mut self, crack: usize, motion: Option<(f64, f64)>) -> bool {
        let c = self.core.state.layer.0.as_deref_mut();
        match c.and_then(|c| c.cracks.get_mut(crack)) {
            Some(c) => {
                c.prescribed = motion.map(|(v, g)| [v, g]);
                true
            }
            None => false,
        }
    }

    /// How often the optional (crack) phases have run so far.
    pub fn work_counters(&self) -> WorkCounters {
        WorkCounters {
            steps: self.steps_taken(),
            j_evaluations: self.cracks().map_or(0, |c| c.j_evaluations()),
            ..self.core.state.counters
        }
    }

    /// Fields sampled at the grid nodes now: mass-weighted averages of particle values
    /// (NaN where no particle reaches a node).
    pub fn snapshot(&self, index: u32, fields: &[FieldKind]) -> Snapshot {
        let g = *self.grid();
        let shape = self.core.model.shape;
        let mats = &self.core.model.mats;
        let mut names: Vec<&'static str> = Vec::new();
        for f in fields {
            for c in field_components(*f) {
                if !names.contains(c) {
                    names.push(c);
                }
            }
        }
        let nn = g.nx() * g.ny();
        let nc = names.len();
        let mut mass = vec![0.0f64; nn];
        let mut acc = vec![0.0f64; nn * nc];
        let thickness = self.scene.thickness;
        let fringe_c = self.scene.output.fringe_constant.unwrap_or(f64::NAN);
        let p = self.particles();
        let mut vals = vec![0.0f64; nc];
        // Per-particle values too, when the scene asks for them (`output.particles`).
        let mut cloud = self.scene.output.particles.then(|| ParticleSnapshot {
            x: Vec::with_capacity(p.len()),
            y: Vec::with_capacity(p.len()),
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
            let s = p.stress[i];
            // Small strain from the stress through the compliance (exact for linear
            // elasticity): ε = [σ − ν(tr σ − σ)]/E per axis, γ = σxy/μ.
            let mt = &mats[p.mech[i].mat as usize];
            let e = [
                (s[0] - mt.nu * (s[1] + s[3])) / mt.e,
                (s[1] - mt.nu * (s[0] + s[3])) / mt.e,
                s[2] / mt.mu,
            ];
            for (c, name) in names.iter().enumerate() {
                vals[c] = match *name {
                    "sxx" => s[0],
                    "syy" => s[1],
                    "sxy" => s[2],
                    "exx" => e[0],
                    "eyy" => e[1],
                    "exy" => 0.5 * e[2],
                    "vx" => k.v[0],
                    "vy" => k.v[1],
                    "speed" => k.v[0].hypot(k.v[1]),
                    "ux" => k.x[0] - p.cold[i].x0[0],
                    "uy" => k.x[1] - p.cold[i].x0[1],
                    // N = h(σ1 − σ2)/f_σ, σ1 − σ2 = 2·sqrt(((σxx − σyy)/2)² + σxy²).
                    "fringe" => thickness * 2.0 * (0.5 * (s[0] - s[1])).hypot(s[2]) / fringe_c,
                    "material" => p.mech[i].mat as f64,
                    _ => 0.0,
                };
            }
            if let Some(c) = cloud.as_mut() {
                c.x.push(k.x[0] as f32);
                c.y.push(k.x[1] as f32);
                for (comp, v) in c.components.iter_mut().zip(&vals) {
                    comp.values.push(*v as f32);
                }
            }
            let w = Weights2::new(shape, g.xi(&k.x), p.mech[i].lh);
            for a in 0..3 {
                for b in 0..3 {
                    let sh = w.s(a, b);
                    if sh == 0.0 {
                        continue;
                    }
                    let ix = (w.x.base + a as i32) as usize;
                    let iy = (w.y.base + b as i32) as usize;
                    if ix >= g.nx() || iy >= g.ny() {
                        continue;
                    }
                    let n = iy * g.nx() + ix;
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
        Snapshot {
            index,
            time: self.time(),
            nx: g.nx() as u32,
            ny: g.ny() as u32,
            origin: g.origin,
            cell_size: g.h,
            fields: fields.iter().map(|f| f.name().to_string()).collect(),
            components,
            cracks: self.cracks().map(|c| c.lines()).unwrap_or_default(),
            particles: cloud,
            slice: None,
        }
    }
}
