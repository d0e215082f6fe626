//! Sorting the particles by cell (`algorithm.md` §2, data layout): a stable counting sort of
//! every particle array, column-major by cell, and the strip bounds of the parallel scatter.
//! It runs before the first step and whenever a particle left its strip's column range.

use super::{Simulation, StepError};
use fracture_mpm::sort::sort_by_cell;

impl Simulation {
    /// Counting sort of the particles by cell (column-major), and the strip bounds (the
    /// core's `sort_by_cell`).
    pub(super) fn sort_particles(&mut self) -> Result<(), StepError> {
        let sorted = sort_by_cell(
            &self.geom,
            &mut self.parts,
            &mut self.strip_bounds,
            &mut self.sorter,
        );
        if let Err(i) = sorted {
            let k = self.parts.kin[i];
            return Err(StepError::LeftGrid {
                step: self.steps,
                particle: self.parts.cold[i].id as usize,
                x: k.x[0],
                y: k.x[1],
            });
        }
        self.needs_sort = false;
        Ok(())
    }
}
