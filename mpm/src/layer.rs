//! The crack layer's place in the step: a [`Layer`] adds velocity fields, contact, interface
//! forces, moving surfaces and growth to the continuum step of [`Simulation`](crate::Simulation)
//! through hooks at fixed points of the sequence (`algorithm.md` §2–§7):
//! 1. [`Layer::fields`], after the grid is zeroed and before the P2G: each particle's field
//!    mask and the table of field-1 nodes (§3);
//! 2. [`Layer::stage`], at each momentum stage, after the velocity conditions and before the
//!    nodal values: contact (§4), and at the force stage the process-zone and cohesive forces,
//!    after the re-extrapolation the bonded points' hold;
//! 3. [`Layer::surfaces`], after the last nodal values and before pass 4: the crack surfaces
//!    move with the grid (§5);
//! 4. [`Layer::after_step`], after the step's time is committed: propagation (§7).
//!
//! The layer is part of the [`State`](crate::State) (its second field), so a checkpoint holds
//! it. [`NoLayer`] is the plain continuum: every hook does nothing and serializes to no bytes.

use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::dim::Dim;
use crate::gridops::Stage;
use crate::particles::Particles;
use crate::state::{Ledger, Model, Scratch, WorkCounters};
use crate::step::StepError;

/// What a hook sees: the model, the particles and the grid of the step in progress, and the
/// ledger and counters it books into.
pub struct Hook<'a, D: Dim> {
    /// What the scene gives.
    pub model: &'a Model<D>,
    /// The particles (in the order of the last sort).
    pub parts: &'a mut Particles<D>,
    /// First particle of each strip.
    pub strip_bounds: &'a [usize],
    /// Energies: a hook adds what its forces dissipate.
    pub ledger: &'a mut Ledger,
    /// Counters of the optional phases.
    pub counters: &'a mut WorkCounters,
    /// The grid and the step's working memory (field-0 and field-1 nodes, the slot map).
    pub scratch: &'a mut Scratch<D>,
    /// Time at the start of the step (s); [`Layer::after_step`] sees the end.
    pub time: f64,
    /// Steps taken before this one; [`Layer::after_step`] sees the count with it.
    pub steps: u64,
}

/// A layer on the continuum step (module docs: where each hook runs).
pub trait Layer<D: Dim>: Serialize + DeserializeOwned + Send {
    /// Whether the layer uses a second velocity field per node and the P2G's mass-weighted
    /// displacement (the scratch then carries the slot map; particles carry field masks and
    /// displacement gradients).
    fn multi_field(&self) -> bool;

    /// Field masks of the particles and the field-1 node table (`scratch.f1_index`, in
    /// storage order) before the P2G.
    fn fields(&mut self, cx: Hook<'_, D>) -> Result<(), StepError>;

    /// At a momentum stage, after the velocity conditions, before the nodal values.
    fn stage(&mut self, stage: Stage, cx: Hook<'_, D>);

    /// After the last nodal values and before pass 4.
    fn surfaces(&mut self, cx: Hook<'_, D>);

    /// After the step: whether anything grew.
    fn after_step(&mut self, cx: Hook<'_, D>) -> Result<bool, StepError>;

    /// Take the restored layer of a checkpoint in place of this fresh one (built from the
    /// same scene), or say why it does not fit.
    fn adopt(&mut self, saved: Self) -> Result<(), String>;
}

/// The plain continuum: no layer.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct NoLayer;

impl<D: Dim> Layer<D> for NoLayer {
    fn multi_field(&self) -> bool {
        false
    }
    fn fields(&mut self, _: Hook<'_, D>) -> Result<(), StepError> {
        Ok(())
    }
    fn stage(&mut self, _: Stage, _: Hook<'_, D>) {}
    fn surfaces(&mut self, _: Hook<'_, D>) {}
    fn after_step(&mut self, _: Hook<'_, D>) -> Result<bool, StepError> {
        Ok(false)
    }
    fn adopt(&mut self, _: NoLayer) -> Result<(), String> {
        Ok(())
    }
}
