//! Sorting the particles by cell (`algorithm.md` §2, data layout): a stable counting sort of
//! every particle array, column-major by cell, and the strip bounds of the parallel scatter.
//! It runs before the first step and whenever a particle left its strip's column range.

use super::{Simulation, StepError};
use crate::grid::STRIP;

impl Simulation {
    /// Counting sort of the particles by cell (column-major), and the strip bounds.
    pub(super) fn sort_particles(&mut self) -> Result<(), StepError> {
        let geom = self.geom;
        let ncx = geom.nx() - 1;
        let ncy = geom.ny() - 1;
        let ncells = ncx * ncy;
        for (i, k) in self.parts.kin.iter().enumerate() {
            let (cx, cy) = geom.cell_xy(k.x);
            if cx < 1 || cy < 1 || cx as usize + 2 > ncx || cy as usize + 2 > ncy {
                return Err(StepError::LeftGrid {
                    step: self.steps,
                    particle: self.parts.cold[i].id as usize,
                    x: k.x[0],
                    y: k.x[1],
                });
            }
            self.sort_keys[i] = (cx as usize * ncy + cy as usize) as u32;
        }
        self.sort_count.clear();
        self.sort_count.resize(ncells + 1, 0);
        for &k in &self.sort_keys {
            self.sort_count[k as usize + 1] += 1;
        }
        for c in 0..ncells {
            self.sort_count[c + 1] += self.sort_count[c];
        }
        // Strip bounds: first particle with cell column ≥ s·STRIP.
        for s in 0..=geom.strips {
            let col = (s * STRIP).min(ncx);
            self.strip_bounds[s] = self.sort_count[col * ncy] as usize;
        }
        for (i, &k) in self.sort_keys.iter().enumerate() {
            let dst = &mut self.sort_count[k as usize];
            self.sort_perm[i] = *dst;
            *dst += 1;
        }
        let p = &mut self.parts;
        for (i, &d) in self.sort_perm.iter().enumerate() {
            let d = d as usize;
            self.scratch_kin[d] = p.kin[i];
            self.scratch_mech[d] = p.mech[i];
            self.scratch_stress[d] = p.stress[i];
            self.scratch_wden[d] = p.wden[i];
            self.scratch_cold[d] = p.cold[i];
        }
        std::mem::swap(&mut p.kin, &mut self.scratch_kin);
        std::mem::swap(&mut p.mech, &mut self.scratch_mech);
        std::mem::swap(&mut p.stress, &mut self.scratch_stress);
        std::mem::swap(&mut p.wden, &mut self.scratch_wden);
        std::mem::swap(&mut p.cold, &mut self.scratch_cold);
        if !p.grad_u.is_empty() {
            for (i, &d) in self.sort_perm.iter().enumerate() {
                self.scratch_grad[d as usize] = p.grad_u[i];
            }
            std::mem::swap(&mut p.grad_u, &mut self.scratch_grad);
        }
        self.needs_sort = false;
        Ok(())
    }
}
