//! Where the particle passes run. [`Backend`] is the step's four particle passes over the
//! particle arrays and the grid, each with its read and write sets stated — the list a GPU
//! backend binds as buffers (`gpu.md`). [`Cpu`] runs them on the host with the
//! strip-coloured deterministic scatter (`passes.rs`).

use crate::dim::Dim;
use crate::passes::{self, Acc};
use crate::state::{Model, Scratch, State};

/// The particle passes of one step.
pub trait Backend<D: Dim>: Send {
    /// Name for logs and benchmarks ("cpu", "gpu").
    fn name(&self) -> &'static str;
    /// Pass 1. Reads particle kin, mech; writes the particles' cached weights and the nodes'
    /// mass and momentum.
    fn p2g(&mut self, model: &Model<D>, state: &mut State<D>, scratch: &mut Scratch<D>) -> Acc;
    /// Pass 2. Reads weights, mech, nodal velocities, loads; writes stress, strain energy
    /// density and nodal forces.
    fn forces(&mut self, model: &Model<D>, state: &mut State<D>, scratch: &mut Scratch<D>) -> Acc;
    /// Pass 3. Reads weights, mech, nodal velocities and accelerations; writes particle
    /// velocities and positions and the nodes' re-extrapolated momenta.
    fn update(&mut self, model: &Model<D>, state: &mut State<D>, scratch: &mut Scratch<D>) -> Acc;
    /// Pass 4. Reads weights, mech, nodal velocities; writes stress and strain energy density.
    fn strain(&mut self, model: &Model<D>, state: &mut State<D>, scratch: &mut Scratch<D>) -> Acc;
    /// Pass 4 fused with the next step's pass 1 into the spare grid (`Scratch::nodes_alt`):
    /// pass 4's reads and writes plus pass 1's. Returns both reductions.
    fn strain_p2g(
        &mut self,
        model: &Model<D>,
        state: &mut State<D>,
        scratch: &mut Scratch<D>,
    ) -> (Acc, Acc);
}

/// The host backend: rayon over strips, bitwise independent of the thread count.
#[derive(Debug, Clone, Copy, Default)]
pub struct Cpu;

impl<D: Dim> Backend<D> for Cpu {
    fn name(&self) -> &'static str {
        "cpu"
    }
    fn p2g(&mut self, model: &Model<D>, state: &mut State<D>, scratch: &mut Scratch<D>) -> Acc {
        passes::p2g(model, state, scratch)
    }
    fn forces(&mut self, model: &Model<D>, state: &mut State<D>, scratch: &mut Scratch<D>) -> Acc {
        passes::forces(model, state, scratch)
    }
    fn update(&mut self, model: &Model<D>, state: &mut State<D>, scratch: &mut Scratch<D>) -> Acc {
        passes::update(model, state, scratch)
    }
    fn strain(&mut self, model: &Model<D>, state: &mut State<D>, scratch: &mut Scratch<D>) -> Acc {
        passes::strain(model, state, scratch)
    }
    fn strain_p2g(
        &mut self,
        model: &Model<D>,
        state: &mut State<D>,
        scratch: &mut Scratch<D>,
    ) -> (Acc, Acc) {
        passes::strain_p2g(model, state, scratch)
    }
}
