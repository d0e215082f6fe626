//! `fracture-mpm`: the continuum core of mpm-fracture, written once for two and three
//! dimensions (`three-d.md`, shape of the code).
//!
//! [`Dim`] (implemented by [`Dim2`] and [`Dim3`]) carries the dimension's arrays and the
//! little arithmetic that depends on it; the grid ([`grid`]), GIMP and linear shape
//! functions ([`shape`]), particles ([`particles`]), the four particle passes ([`passes`])
//! on a [`Backend`] (today [`Cpu`]), the step sequence with boundary conditions, damping and
//! the energy ledger ([`step`]), and checkpoints ([`checkpoint`]) are generic over it.
//! A [`Simulation`] is `{ state, model, scratch }`: the checkpoint is the [`State`].
//!
//! The passes keep the 2D solver's arithmetic (`madd`, the order of every sum, f32-cached
//! weights): `tests/twin.rs` checks a `Dim2` run against the 2D solver bit for bit.
//! The core does no IO and never logs. Results are bitwise identical for any thread count.

#![allow(clippy::needless_range_loop)]

pub mod backend;
pub mod bc;
pub mod checkpoint;
pub mod dim;
pub mod fracture;
pub mod grid;
pub mod gridops;
pub mod layer;
pub mod math;
pub mod particles;
pub mod passes;
pub mod scenes;
pub mod shape;
pub mod sort;
pub mod state;
pub mod stencil;
pub mod step;

pub use backend::{Backend, Cpu};
pub use checkpoint::CheckpointError;
pub use dim::{Dim, Dim2, Dim3, Elastic};
pub use layer::{Hook, Layer, NoLayer};
pub use math::Kernel;
pub use state::{BcSpec, Ledger, LoadSpec, PassTimes, Region, Spec, State, WorkCounters};
pub use step::{BuildError, Simulation, StepError, StepStats};
