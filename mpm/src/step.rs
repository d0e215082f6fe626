//! The simulation and its one step sequence (`algorithm.md` §2, USAVG):
//! 1. P2G (mass, momentum), velocity conditions on the momenta, nodal velocities;
//! 2. velocity gradient, first stress half-update, forces; damping, condition force fix,
//!    nodal accelerations;
//! 3. particle update and re-extrapolation; conditions on the new momenta, nodal velocities;
//! 4. velocity gradient from the re-extrapolated momenta, second stress half-update.
//!
//! The particle passes run on a [`Backend`]; the grid work between them (zeroing the active
//! box, nodal values, conditions, damping) is here, on the host grid.

use std::time::Instant;

use crate::backend::{Backend, Cpu};
use crate::dim::Dim;
use crate::grid::{GridGeom, Node};
use crate::gridops::{self, Stage};
use crate::layer::{Hook, Layer, NoLayer};
use crate::math::Kernel;
use crate::particles::Particles;
use crate::passes::{Acc, FAIL_GRID, FAIL_POSITION, FAIL_VELOCITY, Grid, PassCx};
use crate::sort::{SortScratch, sort_by_cell};
use crate::state::{BcNodes, Ledger, Model, PassTimes, Scratch, Spec, State, WorkCounters};

/// Why a simulation could not be built.
#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    /// The thread pool could not be created.
    #[error("thread pool: {0}")]
    Threads(String),
    /// The specification is inconsistent.
    #[error("{0}")]
    Spec(String),
}

fn fmt_pos(p: &[f64; 3], n: usize) -> String {
    let parts: Vec<String> = p[..n].iter().map(|v| format!("{v:.6e}")).collect();
    format!("({})", parts.join(", "))
}

/// Why a step failed, with its diagnosis.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StepError {
    /// A particle quantity became NaN or infinite.
    #[error("step {step}: {quantity} of particle {particle} at {} m is not finite", fmt_pos(.position, *.dims))]
    NonFinite {
        /// Step number.
        step: u64,
        /// Original particle index.
        particle: usize,
        /// Which quantity.
        quantity: &'static str,
        /// Particle position (start of the step; unused components 0).
        position: [f64; 3],
        /// Number of spatial dimensions.
        dims: usize,
    },
    /// Total energy grew far beyond the energy put in.
    #[error(
        "step {step}: energy blow-up: kinetic + strain = {energy:.6e} J against {reference:.6e} J put in (initial energy + external work); reduce time.cfl or check the loads"
    )]
    EnergyBlowUp {
        /// Step number.
        step: u64,
        /// Kinetic + strain energy.
        energy: f64,
        /// Initial energy plus external work.
        reference: f64,
    },
    /// A particle reached the grid edge.
    #[error("step {step}: particle {particle} reached the grid edge at {} m; enlarge grid.min/grid.max", fmt_pos(.position, *.dims))]
    LeftGrid {
        /// Step number.
        step: u64,
        /// Original particle index.
        particle: usize,
        /// Position.
        position: [f64; 3],
        /// Number of spatial dimensions.
        dims: usize,
    },
    /// A grid node needs more velocity fields than supported.
    #[error(
        "step {step}: node at {} m needs {fields} velocity fields; at most {max} are supported (two cracks within a cell of each other?)",
        fmt_pos(.position, *.dims)
    )]
    TooManyFields {
        /// Step number.
        step: u64,
        /// Node position (unused components 0).
        position: [f64; 3],
        /// Number of spatial dimensions.
        dims: usize,
        /// Fields needed.
        fields: u32,
        /// Fields supported.
        max: u32,
    },
}

/// What happened in one step.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepStats {
    /// The layer grew something (a crack tip advanced) in this step.
    pub grew: bool,
    /// Active grid nodes (field-1 nodes included) in this step.
    pub active_nodes: usize,
}

/// A running simulation of dimension `D` with the layer `L` on its step ([`NoLayer`]: the
/// plain continuum).
pub struct Simulation<D: Dim, L: Layer<D> = NoLayer> {
    /// What persists (the checkpoint).
    pub state: State<D, L>,
    /// What the scene gives.
    pub model: Model<D>,
    /// The step's working memory.
    pub scratch: Scratch<D>,
    backend: Box<dyn Backend<D>>,
}

impl<D: Dim> Simulation<D, NoLayer> {
    /// Build a simulation (CPU backend, portable arithmetic).
    pub fn new(spec: Spec<D>) -> Result<Simulation<D>, BuildError> {
        Self::with_backend(spec, Box::new(Cpu))
    }

    /// Build a simulation on the given backend.
    pub fn with_backend(
        spec: Spec<D>,
        backend: Box<dyn Backend<D>>,
    ) -> Result<Simulation<D>, BuildError> {
        Simulation::with_layer(spec, NoLayer, backend)
    }
}

impl<D: Dim, L: Layer<D>> Simulation<D, L> {
    /// Build a simulation with a layer on its step, on the given backend.
    pub fn with_layer(
        spec: Spec<D>,
        layer: L,
        backend: Box<dyn Backend<D>>,
    ) -> Result<Simulation<D, L>, BuildError> {
        if spec.particles.is_empty() {
            return Err(BuildError::Spec("no particles".into()));
        }
        if !(spec.dt > 0.0 && spec.h > 0.0) {
            return Err(BuildError::Spec(format!(
                "time step {} and cell size {} must be > 0",
                spec.dt, spec.h
            )));
        }
        let threads = spec.threads.max(1);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| BuildError::Threads(e.to_string()))?;
        let geom = GridGeom::<D>::new(spec.min, spec.max, spec.h);
        let bcs = spec
            .bcs
            .iter()
            .map(|b| BcNodes::new(b.clone(), &geom))
            .collect();
        let c_max = spec.materials.iter().map(|m| m.c_l).fold(0.0, f64::max);
        let mass_total: f64 = spec.particles.mech.iter().map(|m| m.m).sum();
        let model = Model {
            geom,
            shape: spec.shape,
            mats: spec.materials,
            bcs,
            loads: spec.loads.clone(),
            damping: spec.damping,
            dt: spec.dt,
            total_steps: spec.total_steps,
            // Gathers must use every node with mass: skipping light nodes breaks Σ∇S = 0.
            m_tiny: f64::MIN_POSITIVE,
            energy_scale: 1e-12 * mass_total * c_max * c_max,
            kernel: Kernel::Portable,
            generic_stencil: false,
            threads,
            pool: std::sync::Arc::new(pool),
            scene_hash: spec.scene_hash,
        };
        let multi = layer.multi_field();
        let scratch = Scratch {
            nodes: vec![Node::default(); geom.storage_len()],
            f1: Vec::new(),
            f1_index: Vec::new(),
            slot_of: if multi {
                vec![u32::MAX; geom.storage_len()]
            } else {
                Vec::new()
            },
            active: None,
            active_nodes: 0,
            load_now: vec![D::V::default(); spec.loads.len()],
            sorter: SortScratch::default(),
            plane_sums: vec![0.0; geom.cols],
            times: PassTimes::default(),
            nodes_alt: Vec::new(),
            alt_box: None,
            prefetched: None,
            fuse: true,
        };
        let mut parts = spec.particles;
        if multi {
            let n = parts.len();
            parts.fmask = vec![Default::default(); n];
            parts.grad_u = vec![Default::default(); n];
        }
        let mut state = State {
            parts,
            layer,
            needs_sort: true,
            strip_bounds: vec![0; geom.strips + 1],
            time: 0.0,
            steps: 0,
            ledger: Ledger::default(),
            counters: WorkCounters::default(),
        };
        state.ledger.kinetic = kinetic_energy(&state.parts);
        state.ledger.initial_total = state.ledger.kinetic;
        Ok(Simulation {
            state,
            model,
            scratch,
            backend,
        })
    }

    /// The arithmetic of the particle passes (portable by default; FMA where the CPU has it).
    pub fn set_kernel(&mut self, kernel: Kernel) -> Kernel {
        self.model.kernel = if kernel.available() {
            kernel
        } else {
            Kernel::Portable
        };
        // A P2G done ahead by the last fused step used the other arithmetic.
        self.scratch.prefetched = None;
        self.model.kernel
    }

    /// The backend's name.
    pub fn backend_name(&self) -> &'static str {
        self.backend.name()
    }

    /// Replace every particle's velocity by `f(x0)` of its initial position (initial
    /// conditions richer than a uniform velocity, e.g. a vibration mode).
    pub fn set_velocities(&mut self, f: impl Fn(&D::V) -> D::V) {
        let p = &mut self.state.parts;
        for (k, c) in p.kin.iter_mut().zip(&p.cold) {
            k.v = f(&c.x0);
        }
        // A P2G done ahead by the last fused step used the old velocities.
        self.scratch.prefetched = None;
        let l = &mut self.state.ledger;
        l.kinetic = kinetic_energy(&self.state.parts);
        l.initial_total = l.kinetic + l.strain + l.dissipated - l.external_work;
    }

    /// Simulated time (s).
    pub fn time(&self) -> f64 {
        self.state.time
    }
    /// Steps taken.
    pub fn steps_taken(&self) -> u64 {
        self.state.steps
    }
    /// Time step (s).
    pub fn time_step(&self) -> f64 {
        self.model.dt
    }
    /// Whether the end time is reached.
    pub fn is_finished(&self) -> bool {
        self.state.steps >= self.model.total_steps
    }
    /// The energy ledger.
    pub fn ledger(&self) -> Ledger {
        self.state.ledger
    }
    /// The particles.
    pub fn particles(&self) -> &Particles<D> {
        &self.state.parts
    }
    /// The grid geometry.
    pub fn grid(&self) -> &GridGeom<D> {
        &self.model.geom
    }
    /// Wall time of each pass so far.
    pub fn pass_times(&self) -> PassTimes {
        self.scratch.times
    }
    /// Total momentum Σ m v of the particles.
    pub fn momentum(&self) -> [f64; 3] {
        let p = &self.state.parts;
        let mut out = [0.0; 3];
        for (k, m) in p.kin.iter().zip(&p.mech) {
            for d in 0..D::N {
                out[d] += m.m * k.v.as_ref()[d];
            }
        }
        out
    }

    /// Advance one time step.
    pub fn step(&mut self) -> Result<StepStats, StepError> {
        let pool = std::sync::Arc::clone(&self.model.pool);
        pool.install(|| self.step_inner())
    }

    /// Fuse the last stress half-update with the next step's P2G where no re-sort falls
    /// between (on by default; bitwise identical either way: `tests/fused.rs`).
    pub fn set_fused_step(&mut self, on: bool) {
        self.scratch.fuse = on;
        self.scratch.prefetched = None;
    }

    fn step_inner(&mut self) -> Result<StepStats, StepError> {
        let t = Instant::now();
        // This step's P2G, when the last step's fused pass 4 did it.
        let prefetched = self.take_prefetched();
        if prefetched.is_none() && self.state.needs_sort {
            self.sort()?;
        }
        let mut mark = Instant::now();
        self.scratch.times.sort += (mark - t).as_secs_f64();
        let mut lap = |slot: fn(&mut PassTimes) -> &mut f64, sc: &mut Scratch<D>| {
            let now = Instant::now();
            *slot(&mut sc.times) += (now - mark).as_secs_f64();
            mark = now;
        };
        let dt = self.model.dt;
        let t0 = self.state.time;
        let t1 = t0 + dt;
        if prefetched.is_none() {
            self.reset_grid();
            let (layer, cx) = self.hook();
            layer.fields(cx)?;
            self.index_f1();
        }
        self.ramp_loads(t0);
        lap(|t| &mut t.grid, &mut self.scratch);

        // Pass 1: P2G; conditions and the layer on the momenta.
        let acc = match prefetched {
            Some(acc) => acc,
            None => self.pass(|b, cx, p, g| b.p2g(cx, p, g)),
        };
        lap(|t| &mut t.p2g, &mut self.scratch);
        self.check(&acc)?;
        self.set_active(&acc);
        self.apply_bc_momentum(t0, false);
        self.layer_stage(Stage::Extrapolated);
        self.nodal(Stage::Extrapolated);
        lap(|t| &mut t.grid, &mut self.scratch);

        // Pass 2: first stress half-update and forces; damping, condition force fix, layer.
        let acc = self.pass(|b, cx, p, g| b.forces(cx, p, g));
        lap(|t| &mut t.forces, &mut self.scratch);
        self.check(&acc)?;
        self.damp_forces();
        self.bc_force_fix(t1);
        self.layer_stage(Stage::Forces);
        self.nodal(Stage::Forces);
        lap(|t| &mut t.grid, &mut self.scratch);

        // Pass 3: particle update and re-extrapolation; conditions and layer on the new momenta.
        let acc = self.pass(|b, cx, p, g| b.update(cx, p, g));
        lap(|t| &mut t.update, &mut self.scratch);
        self.check(&acc)?;
        let l = &mut self.state.ledger;
        l.kinetic = acc.e;
        l.external_work += acc.w;
        l.work_abs += acc.w.abs();
        self.state.needs_sort |= acc.resort;
        self.apply_bc_momentum(t1, true);
        self.layer_stage(Stage::Reextrapolated);
        self.nodal(Stage::Reextrapolated);
        let (layer, cx) = self.hook();
        layer.surfaces(cx);
        lap(|t| &mut t.grid, &mut self.scratch);

        // Pass 4: second stress half-update, fused with the next P2G where nothing can fall
        // between (no re-sort due; no multi-field layer, whose next fields depend on the
        // committed positions and the surfaces' motion).
        let fuse = self.scratch.fuse && !self.state.needs_sort && !self.state.layer.multi_field();
        let acc = if fuse {
            self.zero_alt();
            let (m, st, sc) = (&self.model, &mut self.state, &mut self.scratch);
            let cx = pass_cx(m, &st.strip_bounds, &sc.load_now, &sc.slot_of, false);
            let grid = &mut Grid::single(&mut sc.nodes);
            let (acc, next) = self
                .backend
                .strain_p2g(&cx, &mut st.parts, grid, &mut sc.nodes_alt);
            self.scratch.alt_box = self.box_of(&next);
            self.scratch.prefetched = Some(next);
            acc
        } else {
            self.pass(|b, cx, p, g| b.strain(cx, p, g))
        };
        lap(|t| &mut t.strain, &mut self.scratch);
        self.check(&acc)?;
        self.state.ledger.strain = acc.e;
        self.state.time = t1;
        self.state.steps += 1;

        // The layer after the step (growth).
        let (layer, cx) = self.hook();
        let grew = layer.after_step(cx)?;

        // Energy blow-up: kinetic + strain far above everything ever put in.
        let l = self.state.ledger;
        let energy = l.kinetic + l.strain;
        let reference = l.initial_total.abs() + l.work_abs + l.dissipated;
        if !energy.is_finite() || energy > 10.0 * reference + self.model.energy_scale {
            return Err(StepError::EnergyBlowUp {
                step: self.state.steps,
                energy,
                reference,
            });
        }
        Ok(StepStats {
            grew,
            active_nodes: self.scratch.active_nodes,
        })
    }

    /// One particle pass on the backend, over both fields of the grid.
    fn pass(
        &mut self,
        run: impl FnOnce(
            &mut dyn Backend<D>,
            &PassCx<'_, D>,
            &mut Particles<D>,
            &mut Grid<'_, D>,
        ) -> Acc,
    ) -> Acc {
        let (m, st, sc) = (&self.model, &mut self.state, &mut self.scratch);
        let multi = st.layer.multi_field();
        let cx = pass_cx(m, &st.strip_bounds, &sc.load_now, &sc.slot_of, multi);
        let mut grid = Grid {
            nodes: &mut sc.nodes,
            f1: &mut sc.f1,
            f1_index: &sc.f1_index,
        };
        run(self.backend.as_mut(), &cx, &mut st.parts, &mut grid)
    }

    /// The layer and what its hooks see (split borrows of the simulation).
    fn hook(&mut self) -> (&mut L, Hook<'_, D>) {
        let st = &mut self.state;
        let cx = Hook {
            model: &self.model,
            parts: &mut st.parts,
            strip_bounds: &st.strip_bounds,
            ledger: &mut st.ledger,
            counters: &mut st.counters,
            scratch: &mut self.scratch,
            time: st.time,
            steps: st.steps,
        };
        (&mut st.layer, cx)
    }

    /// The layer at a momentum stage.
    fn layer_stage(&mut self, stage: Stage) {
        let (layer, cx) = self.hook();
        layer.stage(stage, cx);
    }

    /// The slot map of the field-1 table the layer just built.
    fn index_f1(&mut self) {
        let sc = &mut self.scratch;
        sc.f1.resize(sc.f1_index.len(), Node::default());
        for (slot, &i) in sc.f1_index.iter().enumerate() {
            sc.slot_of[i as usize] = slot as u32;
        }
    }

    fn position3(&self, i: usize) -> [f64; 3] {
        let mut p = [0.0; 3];
        p[..D::N].copy_from_slice(self.state.parts.kin[i].x.as_ref());
        p
    }

    /// The step error of a pass's first failure, if any.
    fn check(&self, acc: &Acc) -> Result<(), StepError> {
        let Some((i, kind)) = acc.fail else {
            return Ok(());
        };
        let particle = self.state.parts.cold[i].id as usize;
        let step = self.state.steps + 1;
        let position = self.position3(i);
        Err(match kind {
            FAIL_GRID => StepError::LeftGrid {
                step,
                particle,
                position,
                dims: D::N,
            },
            _ => StepError::NonFinite {
                step,
                particle,
                quantity: match kind {
                    FAIL_VELOCITY => "velocity",
                    FAIL_POSITION => "position",
                    _ => "stress",
                },
                position,
                dims: D::N,
            },
        })
    }

    /// Counting sort of the particles by cell (x-plane major), and the strip bounds.
    fn sort(&mut self) -> Result<(), StepError> {
        let st = &mut self.state;
        let sorted = sort_by_cell(
            &self.model.geom,
            &mut st.parts,
            &mut st.strip_bounds,
            &mut self.scratch.sorter,
        );
        if let Err(i) = sorted {
            let k = st.parts.kin[i];
            let mut position = [0.0; 3];
            position[..D::N].copy_from_slice(k.x.as_ref());
            return Err(StepError::LeftGrid {
                step: st.steps,
                particle: st.parts.cold[i].id as usize,
                position,
                dims: D::N,
            });
        }
        st.needs_sort = false;
        Ok(())
    }

    /// At the start of a step: when the last step's fused pass 4 did this step's P2G, swap
    /// its grid in (the old one becomes the spare, dirty in its active box) and return the
    /// P2G's reduction.
    fn take_prefetched(&mut self) -> Option<Acc> {
        let acc = self.scratch.prefetched.take()?;
        let sc = &mut self.scratch;
        std::mem::swap(&mut sc.nodes, &mut sc.nodes_alt);
        sc.alt_box = sc.active;
        Some(acc)
    }

    /// The grid box (clamped, inclusive) of a P2G's reduction; `None` when it wrote nothing.
    fn box_of(&self, acc: &Acc) -> Option<(D::U, D::U)> {
        if !acc.has_box {
            return None;
        }
        let g = self.model.geom;
        let mut lo = D::U::default();
        let mut hi = D::U::default();
        for d in 0..D::N {
            lo.as_mut()[d] = acc.lo[d].max(0) as usize;
            hi.as_mut()[d] = (acc.hi[d] as usize).min(g.n.as_ref()[d] - 1);
        }
        Some((lo, hi))
    }

    /// Zero the spare grid where it was last written (allocated on first use).
    fn zero_alt(&mut self) {
        let sc = &mut self.scratch;
        if sc.nodes_alt.len() != sc.nodes.len() {
            sc.nodes_alt = vec![Node::default(); sc.nodes.len()];
            sc.alt_box = None;
        }
        if let Some(b) = sc.alt_box.take() {
            let geom = self.model.geom;
            gridops::for_box(&geom, &mut sc.nodes_alt, b, &mut sc.plane_sums, |n| {
                *n = Node::default();
                0.0
            });
        }
    }
}

impl<D: Dim, L: Layer<D>> Simulation<D, L> {
    /// Zero the grid where the last step wrote, and the field-1 table.
    fn reset_grid(&mut self) {
        let sc = &mut self.scratch;
        gridops::reset(&self.model.geom, &mut sc.nodes, sc.active);
        for &i in &sc.f1_index {
            sc.slot_of[i as usize] = u32::MAX;
        }
        sc.f1.clear();
        sc.f1_index.clear();
    }

    /// The active box of a P2G's reduction (clamped) and the number of nodes with mass.
    fn set_active(&mut self, acc: &Acc) {
        if !acc.has_box {
            self.scratch.active = None;
            self.scratch.active_nodes = 0;
            return;
        }
        let g = self.model.geom;
        let mut lo = D::U::default();
        let mut hi = D::U::default();
        for d in 0..D::N {
            lo.as_mut()[d] = acc.lo[d].max(0) as usize;
            hi.as_mut()[d] = (acc.hi[d] as usize).min(g.n.as_ref()[d] - 1);
        }
        self.scratch.active = Some((lo, hi));
        let sc = &mut self.scratch;
        sc.active_nodes = gridops::count(&g, &sc.nodes, (lo, hi), self.model.m_tiny) + sc.f1.len();
    }

    /// Nodal velocity (p/m, then q/m) or acceleration (f/m) at `stage`.
    fn nodal(&mut self, stage: Stage) {
        let sc = &mut self.scratch;
        let geom = &self.model.geom;
        let m_tiny = self.model.m_tiny;
        gridops::nodal(geom, &mut sc.nodes, sc.active, &mut sc.f1, stage, m_tiny);
    }

    /// The loads' ramped tractions at `t0`, and moving conditions' nodes.
    fn ramp_loads(&mut self, t0: f64) {
        let geom = self.model.geom;
        for bc in &mut self.model.bcs {
            bc.follow(t0, &geom);
        }
        for (l, out) in self
            .model
            .loads
            .iter()
            .zip(self.scratch.load_now.iter_mut())
        {
            let r = if l.ramp > 0.0 {
                (t0 / l.ramp).min(1.0)
            } else {
                1.0
            };
            for d in 0..D::N {
                out.as_mut()[d] = l.traction.as_ref()[d] * r;
            }
        }
    }

    /// Velocity conditions on the extrapolated (p) or re-extrapolated (q) momenta.
    fn apply_bc_momentum(&mut self, t: f64, reextrapolated: bool) {
        let m_tiny = self.model.m_tiny;
        for bc in &self.model.bcs {
            let v = bc.velocity(t);
            if v[..D::N].iter().all(Option::is_none) {
                continue;
            }
            let sc = &mut self.scratch;
            gridops::hold_momentum::<D>(
                &mut sc.nodes,
                &mut sc.f1,
                &sc.slot_of,
                &bc.nodes,
                &v,
                reextrapolated,
                m_tiny,
            );
        }
    }

    /// Conditions after the force pass: the force that makes p + Δt f meet the prescribed
    /// velocity; the reaction does work at the node's mid-step velocity.
    fn bc_force_fix(&mut self, t1: f64) {
        let dt = self.model.dt;
        let m_tiny = self.model.m_tiny;
        let mut work = 0.0;
        for bc in &self.model.bcs {
            let v = bc.velocity(t1);
            if v[..D::N].iter().all(Option::is_none) {
                continue;
            }
            let sc = &mut self.scratch;
            gridops::hold_force::<D>(
                &mut sc.nodes,
                &mut sc.f1,
                &sc.slot_of,
                &bc.nodes,
                &v,
                m_tiny,
                dt,
                &mut work,
            );
        }
        let l = &mut self.state.ledger;
        l.external_work += work;
        l.work_abs += work.abs();
    }

    /// Damping after the force pass; the work it removes is dissipated.
    fn damp_forces(&mut self) {
        let (m, sc) = (&self.model, &mut self.scratch);
        let d = gridops::damp(
            &m.geom,
            &mut sc.nodes,
            sc.active,
            &mut sc.f1,
            &mut sc.plane_sums,
            &m.damping,
            m.m_tiny,
            m.dt,
        );
        self.state.ledger.dissipated += d;
    }

    /// The grid nodes of the last step (storage layout of [`GridGeom`]).
    pub fn nodes(&self) -> &[Node<D>] {
        &self.scratch.nodes
    }
}

fn kinetic_energy<D: Dim>(p: &Particles<D>) -> f64 {
    p.kin
        .iter()
        .zip(&p.mech)
        .map(|(k, m)| {
            let mut v2 = 0.0;
            for d in 0..D::N {
                v2 += k.v.as_ref()[d] * k.v.as_ref()[d];
            }
            0.5 * m.m * v2
        })
        .sum()
}

/// The pass context of the step: the model, the strips, the ramped loads and the slot map
/// of the field-1 nodes (`displacement`: the P2G also scatters mass-weighted displacement).
fn pass_cx<'a, D: Dim>(
    m: &'a Model<D>,
    bounds: &'a [usize],
    loads: &'a [D::V],
    slot_of: &'a [u32],
    displacement: bool,
) -> PassCx<'a, D> {
    PassCx {
        geom: m.geom,
        shape: m.shape,
        kernel: m.kernel,
        dt: m.dt,
        mats: &m.mats,
        loads,
        bounds,
        slot_of,
        displacement,
        fast: PassCx::<D>::fast_ok(m.shape) && !m.generic_stencil,
    }
}
