//! The grid between the particle passes (`algorithm.md` §2): zeroing what the last step
//! wrote, the crack velocity-field table (§3), the active box, nodal velocities and
//! accelerations (v = p/m, a = f/m, v = q/m), and damping forces.

use fracture_mpm::Dim2;
use fracture_mpm::gridops::{self, ActiveBox};
use rayon::prelude::*;

use super::transfer::Acc;
use super::{Simulation, StepError};
use crate::crack::Stage;
use crate::grid::{Node, PAD};

impl Simulation {
    /// Zero the grid where the last step wrote.
    pub(super) fn reset_grid(&mut self) {
        let active = self.active();
        gridops::reset(&self.geom, &mut self.nodes, active);
        for &i in &self.f1_index {
            self.slot_of[i as usize] = u32::MAX;
        }
        self.f1.clear();
        self.f1_index.clear();
    }

    /// Crack velocity fields of every particle–node pair and the field-1 node table.
    pub(super) fn setup_fields(&mut self) -> Result<(), StepError> {
        let Some(cr) = self.cracks.as_mut() else {
            return Ok(());
        };
        self.counters.crack_field_passes += 1;
        cr.assign_fields(
            &self.geom,
            self.shape,
            &self.parts.kin,
            &self.parts.mech,
            &self.parts.cold,
            &mut self.parts.fmask,
            &mut self.f1_index,
        )
        .map_err(|(idx, fields)| {
            let (ix, iy) = self.geom.node_xy(idx);
            let p = self.geom.pos(ix, iy);
            StepError::TooManyFields {
                step: self.steps + 1,
                x: p[0],
                y: p[1],
                fields,
                max: 2,
            }
        })?;
        self.f1.resize(self.f1_index.len(), Node::default());
        for (slot, &i) in self.f1_index.iter().enumerate() {
            self.slot_of[i as usize] = slot as u32;
        }
        Ok(())
    }

    /// The grid box (clamped, inclusive) of a P2G's reduction; `None` when it wrote nothing.
    pub(super) fn box_of(&self, acc: &Acc) -> Option<[usize; 4]> {
        if !acc.has_box {
            return None;
        }
        let g = self.geom;
        Some([
            acc.bx[0].max(0) as usize,
            (acc.bx[1] as usize).min(g.nx() - 1),
            acc.bx[2].max(0) as usize,
            (acc.bx[3] as usize).min(g.ny() - 1),
        ])
    }

    /// Zero the spare grid where it was last written (allocated on first use): the fused
    /// pass 4 scatters the next step's P2G into it (`transfer.rs`).
    pub(super) fn zero_alt(&mut self) {
        if self.nodes_alt.len() != self.nodes.len() {
            self.nodes_alt = vec![Node::default(); self.nodes.len()];
            self.alt_box = None;
        }
        if let Some([x0, x1, y0, y1]) = self.alt_box.take() {
            let ny = self.geom.ny();
            self.nodes_alt[(x0 + PAD) * ny..(x1 + 1 + PAD) * ny]
                .par_chunks_mut(ny)
                .for_each(|col| col[y0..=y1].fill(Node::default()));
        }
    }

    /// At the start of a step: when the last step's fused pass 4 did this step's P2G, swap
    /// its grid in (the old one becomes the spare, dirty in its active box) and return the
    /// P2G's reduction.
    pub(super) fn take_prefetched_p2g(&mut self) -> Option<Acc> {
        let acc = self.prefetched.take()?;
        std::mem::swap(&mut self.nodes, &mut self.nodes_alt);
        self.alt_box = (self.active_nodes > 0).then_some(self.active_box);
        Some(acc)
    }

    pub(super) fn set_active_box(&mut self, acc: &Acc) {
        if !acc.has_box {
            self.active_nodes = 0;
            return;
        }
        let g = self.geom;
        let b = [
            acc.bx[0].max(0) as usize,
            (acc.bx[1] as usize).min(g.nx() - 1),
            acc.bx[2].max(0) as usize,
            (acc.bx[3] as usize).min(g.ny() - 1),
        ];
        self.active_box = b;
        self.active_nodes =
            gridops::count(&g, &self.nodes, ([b[0], b[2]], [b[1], b[3]]), self.m_tiny)
                + self.f1.len();
    }

    /// Nodal velocity (p/m after extrapolation, q/m after re-extrapolation) or acceleration
    /// (f/m after the force stage) on every active node and field.
    pub(super) fn nodal(&mut self, stage: Stage) {
        let active = self.active();
        gridops::nodal(
            &self.geom,
            &mut self.nodes,
            active,
            &mut self.f1,
            stage,
            self.m_tiny,
        );
    }

    /// The active box as the core's grid operations take it (None: nothing active).
    fn active(&self) -> Option<ActiveBox<Dim2>> {
        let [x0, x1, y0, y1] = self.active_box;
        (x1 >= x0 && self.active_nodes > 0).then_some(([x0, y0], [x1, y1]))
    }

    /// Damping after the force pass: a grid force against the motion (kinetic: local
    /// non-viscous; viscous: mass-proportional); the work it removes is recorded as
    /// dissipated.
    pub(super) fn damp_forces(&mut self) {
        let active = self.active();
        self.ledger.dissipated += gridops::damp(
            &self.geom,
            &mut self.nodes,
            active,
            &mut self.f1,
            &mut self.col_sums,
            &self.damping,
            self.m_tiny,
            self.dt,
        );
    }
}
