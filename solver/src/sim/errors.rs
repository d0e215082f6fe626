//! Errors: why a simulation could not be built, why a step failed (with the particle, the
//! quantity and where), and how a particle pass reports its first failure (`Acc::fail`,
//! merged in strip order so that the reported particle does not depend on the thread count).

use super::Simulation;
use super::transfer::Acc;

/// Why a simulation could not be built.
#[derive(Debug, thiserror::Error)]
pub enum BuildError {
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

// The failure kinds of the core's particle passes.
use fracture_mpm::passes::{FAIL_GRID, FAIL_POSITION, FAIL_VELOCITY};

impl Simulation {
    /// The step error of a pass's first failure, if any.
    pub(super) fn check(&self, acc: &Acc) -> Result<(), StepError> {
        let Some((i, kind)) = acc.fail else {
            return Ok(());
        };
        let k = self.parts.kin[i];
        let particle = self.parts.cold[i].id as usize;
        let step = self.steps + 1;
        Err(match kind {
            FAIL_GRID => StepError::LeftGrid {
                step,
                particle,
                x: k.x[0],
                y: k.x[1],
            },
            _ => StepError::NonFinite {
                step,
                particle,
                quantity: match kind {
                    FAIL_VELOCITY => "velocity",
                    FAIL_POSITION => "position",
                    _ => "stress",
                },
                x: k.x[0],
                y: k.x[1],
            },
        })
    }
}
