//! Particle placement (`scene-format.md`, bodies): each body is filled on a regular lattice
//! of `particles_per_cell` sub-cells per grid cell direction, one particle at the centre of
//! each sub-cell whose centre lies inside the region.
//!
//! Overlap rule (ours, documented): a later body skips every candidate particle whose
//! centre lies inside the region of an earlier body, so bodies never overlap.

use crate::scene::{Scene, Vec2};

/// A particle as placed by the lattice fill.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Seed {
    /// Position (m).
    pub x: Vec2,
    /// Index of the body in `scene.bodies`.
    pub body: u32,
    /// Particles per cell direction of that body.
    pub ppc: u32,
}

/// Visit every particle of every body in order (body, then x column, then y row).
pub fn for_each_seed(scene: &Scene, mut f: impl FnMut(Seed)) {
    let g = &scene.grid;
    let h = g.cell_size;
    for (bi, body) in scene.bodies.iter().enumerate() {
        let ppc = body.particles_per_cell.max(1);
        let sub = h / ppc as f64;
        let (lo, hi) = body.region.bounds();
        // Sub-cell index range covering the bounding box, on the grid-aligned lattice.
        let i0 = ((lo[0] - g.min[0]) / sub).floor().max(0.0) as i64;
        let i1 = ((hi[0] - g.min[0]) / sub).ceil() as i64;
        let j0 = ((lo[1] - g.min[1]) / sub).floor().max(0.0) as i64;
        let j1 = ((hi[1] - g.min[1]) / sub).ceil() as i64;
        for i in i0..i1 {
            let x = g.min[0] + (i as f64 + 0.5) * sub;
            for j in j0..j1 {
                let y = g.min[1] + (j as f64 + 0.5) * sub;
                let p = [x, y];
                if !body.region.contains(p) {
                    continue;
                }
                if scene.bodies[..bi].iter().any(|b| b.region.contains(p)) {
                    continue;
                }
                f(Seed {
                    x: p,
                    body: bi as u32,
                    ppc,
                });
            }
        }
    }
}

/// Number of particles each body gets.
pub fn count_per_body(scene: &Scene) -> Vec<usize> {
    let mut counts = vec![0usize; scene.bodies.len()];
    for_each_seed(scene, |s| counts[s.body as usize] += 1);
    counts
}
