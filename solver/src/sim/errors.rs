//! Errors: why a simulation could not be built (the core's), and why a step failed, with the
//! particle, the quantity and where, in 2D terms (the core's [`fracture_mpm::StepError`]
//! names positions as 3-vectors; the messages are the same).

/// Why a simulation could not be built (the core's: the thread pool, or an inconsistent
/// specification, which a validated scene never gives).
pub use fracture_mpm::BuildError;

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
        /// Particle position x (start of the step).
        x: f64,
        /// Particle position y.
        y: f64,
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
    #[error(
        "step {step}: particle {particle} reached the grid edge at ({x:.6e}, {y:.6e}) m; enlarge grid.min/grid.max"
    )]
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
    #[error(
        "step {step}: node at ({x:.6e}, {y:.6e}) m needs {fields} velocity fields; at most {max} are supported (two cracks within a cell of each other?)"
    )]
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

impl From<fracture_mpm::StepError> for StepError {
    fn from(e: fracture_mpm::StepError) -> StepError {
        use fracture_mpm::StepError as Core;
        match e {
            Core::NonFinite {
                step,
                particle,
                quantity,
                position,
                ..
            } => StepError::NonFinite {
                step,
                particle,
                quantity,
                x: position[0],
                y: position[1],
            },
            Core::EnergyBlowUp {
                step,
                energy,
                reference,
            } => StepError::EnergyBlowUp {
                step,
                energy,
                reference,
            },
            Core::LeftGrid {
                step,
                particle,
                position,
                ..
            } => StepError::LeftGrid {
                step,
                particle,
                x: position[0],
                y: position[1],
            },
            Core::TooManyFields {
                step,
                position,
                fields,
                max,
                ..
            } => StepError::TooManyFields {
                step,
                x: position[0],
                y: position[1],
                fields,
                max,
            },
        }
    }
}
