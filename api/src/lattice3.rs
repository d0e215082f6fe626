//! Particle placement in 3D: the 2D rule ([`crate::lattice`]) with a third direction. Each
//! body is filled on the grid-aligned lattice of `particles_per_cell` sub-cells per cell
//! direction, one particle at the centre of each sub-cell whose centre lies inside the
//! region; a later body skips every candidate inside an earlier body's region, so bodies
//! never overlap.
//!
//! The walk goes column by column (lines parallel to z): each region answers for a whole
//! column at once ([`crate::scene3::Region3::column`]), so a mesh region costs one ray
//! query per column, not one per particle. The result is exactly what asking
//! [`crate::scene3::Region3::contains`] at every sub-cell centre gives.

use crate::scene3::{RegionColumn, Scene3, Vec3};

/// A particle as placed by the lattice fill.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Seed3 {
    /// Position `[x, y, z]` (m).
    pub x: Vec3,
    /// Index of the body in `scene.bodies`.
    pub body: u32,
    /// Particles per cell direction of that body (its particle's edge is `cell_size / ppc`).
    pub ppc: u32,
}

/// The sub-cell index range `[i0, i1)` along axis `k` that covers `lo..hi` on the lattice of
/// spacing `sub`, clipped to the grid box (the 2D rule, with the upper end clipped too so an
/// unvalidated scene cannot walk outside the grid).
fn span(scene: &Scene3, sub: f64, lo: f64, hi: f64, k: usize) -> (i64, i64) {
    let g = &scene.grid;
    let i0 = ((lo - g.min[k]) / sub).floor().max(0.0) as i64;
    let i1 = ((hi - g.min[k]) / sub).ceil() as i64;
    let top = ((g.max[k] - g.min[k]) / sub).ceil() as i64;
    (i0, i1.min(top))
}

/// Visit every particle of every body in order: body, then x, then y, then z (z fastest).
pub fn for_each_seed3(scene: &Scene3, mut f: impl FnMut(Seed3)) {
    let g = &scene.grid;
    let h = g.cell_size;
    let mut earlier: Vec<RegionColumn<'_>> = Vec::with_capacity(scene.bodies.len());
    for (bi, body) in scene.bodies.iter().enumerate() {
        let ppc = body.particles_per_cell.max(1);
        let sub = h / f64::from(ppc);
        let (lo, hi) = body.region.bounds();
        let (i0, i1) = span(scene, sub, lo[0], hi[0], 0);
        let (j0, j1) = span(scene, sub, lo[1], hi[1], 1);
        let (k0, k1) = span(scene, sub, lo[2], hi[2], 2);
        for i in i0..i1 {
            let x = g.min[0] + (i as f64 + 0.5) * sub;
            for j in j0..j1 {
                let y = g.min[1] + (j as f64 + 0.5) * sub;
                let column = body.region.column(x, y);
                if column.is_empty() {
                    continue;
                }
                earlier.clear();
                earlier.extend(
                    scene.bodies[..bi]
                        .iter()
                        .map(|b| b.region.column(x, y))
                        .filter(|c| !c.is_empty()),
                );
                for k in k0..k1 {
                    let z = g.min[2] + (k as f64 + 0.5) * sub;
                    if !column.contains(z) || earlier.iter().any(|c| c.contains(z)) {
                        continue;
                    }
                    f(Seed3 {
                        x: [x, y, z],
                        body: bi as u32,
                        ppc,
                    });
                }
            }
        }
    }
}

/// Number of particles each body gets.
pub fn count_per_body3(scene: &Scene3) -> Vec<usize> {
    let mut counts = vec![0usize; scene.bodies.len()];
    for_each_seed3(scene, |s| counts[s.body as usize] += 1);
    counts
}

/// The candidate sites the walk of [`for_each_seed3`] visits: every body's bounding box,
/// clipped to the grid box, in sub-cells (saturating). An upper bound of the particle count
/// and of the walk's work, in O(bodies); validation refuses a scene above
/// [`crate::validate3::MAX_LATTICE_SITES`] before walking.
pub fn candidate_sites3(scene: &Scene3) -> u64 {
    let g = &scene.grid;
    let h = g.cell_size;
    let finite = |v: &Vec3| v.iter().all(|c| c.is_finite());
    if !(h.is_finite() && h > 0.0 && finite(&g.min) && finite(&g.max)) {
        return 0;
    }
    let mut sites = 0u64;
    for body in &scene.bodies {
        let ppc = body.particles_per_cell.max(1);
        let sub = h / f64::from(ppc);
        let (lo, hi) = body.region.bounds();
        if !(finite(&lo) && finite(&hi)) {
            continue;
        }
        let mut n = 1.0f64;
        for k in 0..3 {
            let a = ((lo[k].max(g.min[k]) - g.min[k]) / sub).floor().max(0.0);
            let b = ((hi[k].min(g.max[k]) - g.min[k]) / sub).ceil();
            n *= (b - a).max(0.0);
        }
        let n = if n < u64::MAX as f64 {
            n as u64
        } else {
            u64::MAX
        };
        sites = sites.saturating_add(n);
    }
    sites
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use serde_json::json;

    fn scene(bodies: serde_json::Value) -> Scene3 {
        serde_json::from_value(json!({
            "analysis": "3d",
            "grid": {"cell_size": 0.1, "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 1.0]},
            "materials": {"m": {"model": "linear_elastic", "density": 1000.0,
                                 "youngs_modulus": 1e9, "poissons_ratio": 0.3}},
            "bodies": bodies,
            "time": {"end": 1e-6}
        }))
        .unwrap()
    }

    #[test]
    fn a_box_fills_z_fastest_and_later_bodies_skip() {
        let s = scene(json!([
            {"material": "m", "region": {"box": {"min": [0.1, 0.1, 0.1], "max": [0.3, 0.3, 0.3]}}},
            {"material": "m", "particles_per_cell": 1,
             "region": {"box": {"min": [0.2, 0.1, 0.1], "max": [0.5, 0.2, 0.2]}}}
        ]));
        let mut seeds = Vec::new();
        for_each_seed3(&s, |p| seeds.push(p));
        // Body 0: 2 cells a side × 2 per cell = 4³ particles.
        assert_eq!(seeds.iter().filter(|p| p.body == 0).count(), 64);
        assert_eq!(seeds[0].x, [0.125, 0.125, 0.125]);
        assert_eq!(seeds[1].x, [0.125, 0.125, 0.17500000000000002]);
        // Body 1: centres 0.25, 0.35, 0.45 in x at y = z = 0.15; 0.25 lies in body 0.
        let b1: Vec<Vec3> = seeds.iter().filter(|p| p.body == 1).map(|p| p.x).collect();
        assert_eq!(b1.len(), 2, "{b1:?}");
        assert!(b1.iter().all(|x| x[0] > 0.3));
        assert_eq!(count_per_body3(&s), vec![64, 2]);
        assert_eq!(candidate_sites3(&s), 64 + 3);
    }
}
