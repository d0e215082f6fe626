//! The physics of mpm-fracture: a 2D GIMP material point method with explicit cracks.
//!
//! A [`Simulation`] is built from a validated [`Scene`](fracture_api::Scene), advanced by
//! [`Simulation::step`], and observed through read-only views ([`Simulation::energy`],
//! [`Simulation::crack_tips`], [`Simulation::snapshot`], [`Simulation::particles`]).
//! The method is described in `docs/solver.md` (overview: `docs/architecture.md`); modules:
//! [`shape`] (shape functions), [`grid`] and [`particles`] (data), [`sim`] (the simulation: the
//! core's step with the crack layer on its hooks),
//! [`material`], [`crack`] (crack fields, contact, motion, J, growth), [`tip_mechanics`] (A(v),
//! Williams fields, kink criteria).
//!
//! The solver does no IO and never logs. Parallel loops use rayon with a deterministic
//! strip-coloured scatter, so results are bitwise identical for any thread count.

// Index loops over vector/tensor components (k in 0..2) read like the equations they implement.
#![allow(clippy::needless_range_loop)]

pub mod crack;
pub mod grid;
pub mod kernel;
pub mod material;
pub mod particles;
pub mod shape;
pub mod sim;
/// Tip mechanics (A(v), Williams fields, kink criteria): the core's dimension-free laws.
pub use fracture_mpm::fracture::tip_mechanics;

pub use sim::{
    BuildError, CheckpointError, Parallelism, Simulation, SolverConfig, StepError, StepStats,
    WorkCounters,
};
