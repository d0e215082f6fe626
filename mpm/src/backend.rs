//! Where the particle passes run. [`Backend`] is the step's four particle passes over the
//! particle arrays and the grid, each with its read and write sets stated — the list a GPU
//! backend binds as buffers (`gpu.md`). [`Cpu`] runs them on the host with the
//! strip-coloured deterministic scatter (`passes.rs`).

use crate::dim::Dim;
use crate::grid::Node;
use crate::particles::Particles;
use crate::passes::{self, Acc, Grid, PassCx};

/// The particle passes of one step. Every pass reads the pass context (`PassCx`: geometry,
/// shape functions, kernel, Δt, materials, loads, strip bounds, the field-1 slot map) and the
/// cached weights and field masks of the particles.
pub trait Backend<D: Dim>: Send {
    /// Name for logs and benchmarks ("cpu", "gpu").
    fn name(&self) -> &'static str;
    /// Pass 1. Reads particle kin, mech (and cold with cracks); writes the particles' cached
    /// weights and the nodes' mass, momentum (and mass-weighted displacement).
    fn p2g(&mut self, cx: &PassCx<'_, D>, parts: &mut Particles<D>, grid: &mut Grid<'_, D>) -> Acc;
    /// Pass 2. Reads weights, mech, nodal velocities, loads; writes stress, strain energy
    /// density (and ∇u with cracks) and nodal forces.
    fn forces(
        &mut self,
        cx: &PassCx<'_, D>,
        parts: &mut Particles<D>,
        grid: &mut Grid<'_, D>,
    ) -> Acc;
    /// Pass 3. Reads weights, mech, nodal velocities and accelerations; writes particle
    /// velocities and positions and the nodes' re-extrapolated momenta.
    fn update(
        &mut self,
        cx: &PassCx<'_, D>,
        parts: &mut Particles<D>,
        grid: &mut Grid<'_, D>,
    ) -> Acc;
    /// Pass 4. Reads weights, mech, nodal velocities; writes stress and strain energy density
    /// (and ∇u with cracks).
    fn strain(
        &mut self,
        cx: &PassCx<'_, D>,
        parts: &mut Particles<D>,
        grid: &mut Grid<'_, D>,
    ) -> Acc;
    /// Pass 4 fused with the next step's pass 1 into the spare grid `next` (no cracks): pass
    /// 4's reads and writes plus pass 1's. Returns both reductions.
    fn strain_p2g(
        &mut self,
        cx: &PassCx<'_, D>,
        parts: &mut Particles<D>,
        cur: &mut Grid<'_, D>,
        next: &mut [Node<D>],
    ) -> (Acc, Acc);
}

/// The host backend: rayon over strips, bitwise independent of the thread count.
#[derive(Debug, Clone, Copy, Default)]
pub struct Cpu;

impl<D: Dim> Backend<D> for Cpu {
    fn name(&self) -> &'static str {
        "cpu"
    }
    fn p2g(&mut self, cx: &PassCx<'_, D>, parts: &mut Particles<D>, grid: &mut Grid<'_, D>) -> Acc {
        passes::p2g(cx, parts, grid)
    }
    fn forces(
        &mut self,
        cx: &PassCx<'_, D>,
        parts: &mut Particles<D>,
        grid: &mut Grid<'_, D>,
    ) -> Acc {
        passes::forces(cx, parts, grid)
    }
    fn update(
        &mut self,
        cx: &PassCx<'_, D>,
        parts: &mut Particles<D>,
        grid: &mut Grid<'_, D>,
    ) -> Acc {
        passes::update(cx, parts, grid)
    }
    fn strain(
        &mut self,
        cx: &PassCx<'_, D>,
        parts: &mut Particles<D>,
        grid: &mut Grid<'_, D>,
    ) -> Acc {
        passes::strain(cx, parts, grid)
    }
    fn strain_p2g(
        &mut self,
        cx: &PassCx<'_, D>,
        parts: &mut Particles<D>,
        cur: &mut Grid<'_, D>,
        next: &mut [Node<D>],
    ) -> (Acc, Acc) {
        passes::strain_p2g(cx, parts, cur, next)
    }
}
