//! The simulation: build from a scene, step, observe.

use fracture_api::Scene;
use fracture_api::results::{CrackTipRow, EnergyRow, Snapshot};
use fracture_api::scene::FieldKind;

/// How the solver runs (not physics).
#[derive(Debug, Clone, Copy, Default)]
pub struct SolverConfig {
    /// Worker threads; 0 = one per core.
    pub threads: usize,
}

/// Why a simulation could not be built.
#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    /// The scene failed validation.
    #[error("invalid scene:\n{0}")]
    Invalid(#[from] fracture_api::ValidationErrors),
    /// The thread pool could not be created.
    #[error("thread pool: {0}")]
    Threads(String),
}

/// Why a step failed: a numerical failure with its diagnosis.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StepError {
    /// A particle quantity became NaN or infinite.
    #[error("step {step}: {quantity} of particle {particle} at ({x:.6e}, {y:.6e}) m is not finite")]
    NonFinite {
        /// Step number.
        step: u64,
        /// Original particle index.
        particle: usize,
        /// Which quantity.
        quantity: &'static str,
        /// Particle position x (last finite).
        x: f64,
        /// Particle position y.
        y: f64,
    },
    /// Total energy grew far beyond the energy put in.
    #[error("step {step}: energy blow-up: kinetic + strain = {energy:.6e} J against {reference:.6e} J put in")]
    EnergyBlowUp {
        /// Step number.
        step: u64,
        /// Kinetic + strain energy.
        energy: f64,
        /// Initial energy plus external work.
        reference: f64,
    },
    /// A particle reached the grid edge.
    #[error("step {step}: particle {particle} reached the grid edge at ({x:.6e}, {y:.6e}) m; enlarge grid.min/grid.max")]
    LeftGrid {
        /// Step number.
        step: u64,
        /// Original particle index.
        particle: usize,
        /// Position x.
        x: f64,
        /// Position y.
        y: f64,
    },
    /// A grid node needs more velocity fields than supported.
    #[error("step {step}: node at ({x:.6e}, {y:.6e}) m needs {fields} velocity fields; at most {max} are supported (cracks too close together?)")]
    TooManyFields {
        /// Step number.
        step: u64,
        /// Node position x.
        x: f64,
        /// Node position y.
        y: f64,
        /// Fields needed.
        fields: u32,
        /// Fields supported.
        max: u32,
    },
}

/// What happened in one step.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepStats {
    /// Some crack tip advanced in this step.
    pub grew: bool,
    /// Active grid nodes in this step.
    pub active_nodes: usize,
}

/// A running simulation.
pub struct Simulation {
    scene: Scene,
}

impl Simulation {
    /// Build a simulation from a scene (validated here too).
    pub fn new(scene: &Scene, _config: SolverConfig) -> Result<Simulation, BuildError> {
        fracture_api::validate::validate(scene)?;
        Ok(Simulation { scene: scene.clone() })
    }
    /// Advance one time step.
    pub fn step(&mut self) -> Result<StepStats, StepError> {
        Ok(StepStats::default())
    }
    /// The scene.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }
    /// Simulated time (s).
    pub fn time(&self) -> f64 {
        0.0
    }
    /// Steps taken.
    pub fn steps_taken(&self) -> u64 {
        0
    }
    /// Δt (s).
    pub fn time_step(&self) -> f64 {
        0.0
    }
    /// End time (s).
    pub fn end_time(&self) -> f64 {
        self.scene.time.end
    }
    /// Steps to reach the end time.
    pub fn total_steps(&self) -> u64 {
        0
    }
    /// Whether the end time is reached.
    pub fn is_finished(&self) -> bool {
        true
    }
    /// Number of particles.
    pub fn particle_count(&self) -> usize {
        0
    }
    /// Nodes of the grid box.
    pub fn grid_node_count(&self) -> usize {
        0
    }
    /// Nodes touched by particles in the last step.
    pub fn active_node_count(&self) -> usize {
        0
    }
    /// Threads in use.
    pub fn threads(&self) -> usize {
        1
    }
    /// Energies now.
    pub fn energy(&self) -> EnergyRow {
        EnergyRow::default()
    }
    /// One row per crack tip now (computes J and K).
    pub fn crack_tips(&mut self) -> Vec<CrackTipRow> {
        Vec::new()
    }
    /// Node-sampled fields now.
    pub fn snapshot(&self, index: u32, fields: &[FieldKind]) -> Snapshot {
        Snapshot {
            index,
            time: 0.0,
            nx: 0,
            ny: 0,
            origin: [0.0; 2],
            cell_size: 0.0,
            fields: fields.iter().map(|f| f.name().to_string()).collect(),
            components: Vec::new(),
            cracks: Vec::new(),
        }
    }
}
