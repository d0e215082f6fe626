//! What a simulation is made of: [`State`] (everything that persists from one step to the
//! next: a checkpoint is the state, nothing copied by hand), [`Model`] (what the scene gives:
//! grid, materials, conditions, time step; rebuilt from the scene on restore) and
//! [`Scratch`] (the step's working memory: grid nodes, sort buffers, timings).

use std::sync::Arc;

use fracture_api::scene::{Damping, ShapeFunction};
use serde::{Deserialize, Serialize};

use crate::dim::{Dim, Elastic};
use crate::grid::{GridGeom, Node};
use crate::layer::NoLayer;
use crate::math::Kernel;
use crate::particles::{Cold, Kin, Mech, Particles};

/// The energy ledger (J; in 2D per the scene's thickness).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Ledger {
    /// Kinetic energy of the particles (end of the last step).
    pub kinetic: f64,
    /// Strain energy Σ V W.
    pub strain: f64,
    /// Work of tractions and of prescribed velocities so far.
    pub external_work: f64,
    /// Energy removed by damping so far.
    pub dissipated: f64,
    /// Kinetic + strain energy at the start.
    pub initial_total: f64,
    /// Σ |work| (the scale of the blow-up check).
    pub work_abs: f64,
}

impl Ledger {
    /// Energy balance error: kinetic + strain + dissipated − external work − initial (summed
    /// in this order: the energy rows of both dimensions report it).
    pub fn balance(&self) -> f64 {
        self.kinetic + self.strain + self.dissipated - self.external_work - self.initial_total
    }
}

/// How often the optional phases of a step ran: cheap counters (incremented once per phase
/// call, outside the particle and node loops) that show what a scene skips.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct WorkCounters {
    /// Steps taken (filled in when read; the stored value stays 0).
    pub steps: u64,
    /// Crack velocity-field assignments (one per step with cracks, §3).
    pub crack_field_passes: u64,
    /// Crack-face contact passes (three per step with cracks, §4).
    pub contact_passes: u64,
    /// Crack-surface moves (one per step with cracks, §5).
    pub surface_moves: u64,
    /// Propagation checks (one per step with cracks, §7).
    pub propagation_checks: u64,
    /// J-integral evaluations (per tip, on a history sample or a growth check, §6; filled in
    /// when read by the layer that counts them; the stored value stays 0).
    pub j_evaluations: u64,
}

/// The state that persists across steps (and is the checkpoint: serialized in this field
/// order).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(bound(
    serialize = "L: Serialize",
    deserialize = "L: serde::de::DeserializeOwned"
))]
pub struct State<D: Dim, L = NoLayer> {
    /// Particles (in the order of the last sort).
    pub parts: Particles<D>,
    /// The crack layer's state ([`NoLayer`]: nothing).
    pub layer: L,
    /// A particle left its strip: sort before the next scatter.
    pub needs_sort: bool,
    /// First particle of each strip (of the last sort).
    pub strip_bounds: Vec<usize>,
    /// Simulated time (s).
    pub time: f64,
    /// Steps taken.
    pub steps: u64,
    /// Energies.
    pub ledger: Ledger,
    /// How often the optional phases ran.
    pub counters: WorkCounters,
}

/// Whether a point lies in a region.
pub type Contains<D> = Arc<dyn Fn(&<D as Dim>::V) -> bool + Send + Sync>;

/// A region of space: containment and a bounding box (the scene's region, resolved by the
/// crate that reads the scene).
#[derive(Clone)]
pub struct Region<D: Dim> {
    /// Whether a point lies in the region.
    pub contains: Contains<D>,
    /// Lower corner of the bounding box.
    pub lo: D::V,
    /// Upper corner of the bounding box.
    pub hi: D::V,
}

impl<D: Dim> std::fmt::Debug for Region<D> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Region {{ lo: {:?}, hi: {:?} }}", self.lo, self.hi)
    }
}

/// A prescribed-velocity condition as the scene gives it.
#[derive(Debug, Clone)]
pub struct BcSpec<D: Dim> {
    /// Nodes inside are constrained.
    pub region: Region<D>,
    /// Prescribed components (the first N are used); None is free.
    pub velocity: [Option<f64>; 3],
    /// Linear rise from 0 over this time (s); 0 for none.
    pub ramp: f64,
    /// Active from this time (s).
    pub start: f64,
    /// Active until this time (s).
    pub end: f64,
    /// The region travels with the prescribed velocity.
    pub moving: bool,
}

/// A traction load as the scene gives it.
#[derive(Debug, Clone, Copy)]
pub struct LoadSpec<D: Dim> {
    /// Traction (Pa; in 2D already multiplied by the thickness: N/m per unit edge).
    pub traction: D::V,
    /// Linear rise from 0 over this time (s); 0 for none.
    pub ramp: f64,
}

/// Everything needed to build a simulation (the reader of a scene fills it).
#[derive(Debug, Clone)]
pub struct Spec<D: Dim> {
    /// Grid box and cell.
    pub min: D::V,
    /// Upper corner of the grid box.
    pub max: D::V,
    /// Cell size (m).
    pub h: f64,
    /// Shape functions.
    pub shape: ShapeFunction,
    /// Materials (particles' `Mech::mat` index it).
    pub materials: Vec<Elastic>,
    /// The particles (in creation order).
    pub particles: Particles<D>,
    /// Velocity conditions.
    pub bcs: Vec<BcSpec<D>>,
    /// Traction loads (particles' `Mech::load` is 1 + index).
    pub loads: Vec<LoadSpec<D>>,
    /// Damping.
    pub damping: Damping,
    /// Time step (s).
    pub dt: f64,
    /// Steps to the end time.
    pub total_steps: u64,
    /// Threads of the parallel loops (results do not depend on it).
    pub threads: usize,
    /// Identity of the scene (checkpoints of other scenes are refused).
    pub scene_hash: String,
}

impl<D: Dim> Spec<D> {
    /// Add a particle of body `body`, material `mat`, `ppc` particles per cell direction and
    /// volume `vol`, at `x` moving with `v` (the id is the creation index).
    #[allow(clippy::too_many_arguments)]
    pub fn add_particle(
        &mut self,
        x: D::V,
        v: D::V,
        vol: f64,
        ppc: u32,
        mat: u32,
        load: u32,
        body: u32,
    ) {
        let id = self.particles.len() as u32;
        let rho = self.materials[mat as usize].rho;
        self.particles.push(
            Kin { x, v },
            Mech {
                m: rho * vol,
                vol,
                lh: 0.5 / f64::from(ppc.max(1)),
                mat,
                load,
            },
            Cold { x0: x, id, body },
        );
    }
}

/// A velocity condition resolved to grid nodes.
#[derive(Debug, Clone)]
pub struct BcNodes<D: Dim> {
    /// Storage indices of the constrained nodes.
    pub nodes: Vec<u32>,
    /// The condition.
    pub spec: BcSpec<D>,
    /// The displacement the nodes of a moving condition were last resolved for.
    pub shift: D::V,
}

/// What the scene gives, fixed for the run.
pub struct Model<D: Dim> {
    /// Grid geometry.
    pub geom: GridGeom<D>,
    /// Shape functions.
    pub shape: ShapeFunction,
    /// Materials.
    pub mats: Vec<Elastic>,
    /// Velocity conditions with their nodes.
    pub bcs: Vec<BcNodes<D>>,
    /// Loads.
    pub loads: Vec<LoadSpec<D>>,
    /// Damping.
    pub damping: Damping,
    /// Time step.
    pub dt: f64,
    /// Steps to the end time.
    pub total_steps: u64,
    /// Nodes lighter than this count as empty (gathers use every node with mass).
    pub m_tiny: f64,
    /// Energy scale of the blow-up check.
    pub energy_scale: f64,
    /// Arithmetic of the particle passes.
    pub kernel: Kernel,
    /// Every particle through the generic stencil path, even where the fast field-0 path
    /// applies (bitwise the same; a switch for the test that proves it).
    pub generic_stencil: bool,
    /// Threads.
    pub threads: usize,
    /// The thread pool.
    pub pool: Arc<rayon::ThreadPool>,
    /// Scene identity for checkpoints.
    pub scene_hash: String,
}

/// Wall time of each pass, summed over the steps so far (s).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct PassTimes {
    /// Sorting particles by cell.
    pub sort: f64,
    /// Pass 1: P2G.
    pub p2g: f64,
    /// Pass 2: stress half-update and forces.
    pub forces: f64,
    /// Pass 3: particle update and re-extrapolation.
    pub update: f64,
    /// Pass 4: second stress half-update.
    pub strain: f64,
    /// Grid work between the passes (zeroing, nodal values, conditions, damping).
    pub grid: f64,
}

impl PassTimes {
    /// Total.
    pub fn total(&self) -> f64 {
        self.sort + self.p2g + self.forces + self.update + self.strain + self.grid
    }
}

/// The step's working memory.
pub struct Scratch<D: Dim> {
    /// Grid nodes (storage layout of `GridGeom`).
    pub nodes: Vec<Node<D>>,
    /// Field-1 nodes of the step (a layer's second velocity field), in storage order.
    pub f1: Vec<Node<D>>,
    /// Storage index of each field-1 node.
    pub f1_index: Vec<u32>,
    /// Storage index → field-1 slot (`u32::MAX`: none); empty without a multi-field layer.
    pub slot_of: Vec<u32>,
    /// Active box of the last P2G per direction, inclusive (lo, hi).
    pub active: Option<(D::U, D::U)>,
    /// Active nodes (mass above `m_tiny`) of the last P2G.
    pub active_nodes: usize,
    /// Loads' ramped tractions of the step in progress.
    pub load_now: Vec<D::V>,
    /// The sort's work arrays.
    pub sorter: crate::sort::SortScratch<D>,
    /// Per-plane partial sums (damping).
    pub plane_sums: Vec<f64>,
    /// Pass wall times.
    pub times: PassTimes,
    /// Spare grid: the next step's P2G, scattered by a fused pass 4 (`passes::strain_p2g`).
    pub nodes_alt: Vec<Node<D>>,
    /// Box of `nodes_alt` that may be non-zero.
    pub alt_box: Option<(D::U, D::U)>,
    /// Reduction of the P2G already in `nodes_alt` for the coming step.
    pub prefetched: Option<crate::passes::Acc>,
    /// Fuse pass 4 with the next P2G where no re-sort falls between (on by default;
    /// bitwise the same either way).
    pub fuse: bool,
}
