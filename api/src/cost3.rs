//! What a 3D run's size is before its lattice is walked: the particle estimate the service's
//! admission needs before it may spend O(particles) on validation ([`crate::cost`] holds the
//! 3D memory and step estimates).
//!
//! Everything here is O(bodies): it can run on an async thread.

use crate::lattice3;
use crate::scene3::{Region3, Scene3, Slice, Vec3};

/// What [`estimate_particles3`] can tell without walking a lattice.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ParticleEstimate3 {
    /// A lower estimate of the particle count: the largest box, sphere or cylinder eroded by
    /// two cells (every point of the eroded solid lies in a lattice sub-cell wholly inside
    /// the region: the sub-cell's half diagonal √3/2·h/ppc is under one cell), at the
    /// sparsest lattice among its body and the bodies before it (those win an overlap).
    /// Prisms and meshes count 0: their volume is unsafe to guess (even-odd polygons,
    /// arbitrary surfaces).
    pub at_least: u64,
    /// Candidate sites the lattice walk visits ([`lattice3::candidate_sites3`]): an upper
    /// bound of the particle count and of the walk's work.
    pub sites: u64,
}

/// The solid's volume once eroded by `d` (m³; 0 when nothing is left), clipped to the grid box
/// for boxes; `None` for regions whose volume is not estimated.
fn eroded_volume(region: &Region3, d: f64, grid_min: Vec3, grid_max: Vec3) -> Option<f64> {
    match region {
        Region3::Box { min, max } => {
            let mut v = 1.0;
            for k in 0..3 {
                let lo = min[k].max(grid_min[k]);
                let hi = max[k].min(grid_max[k]);
                v *= (hi - lo - 2.0 * d).max(0.0);
            }
            Some(v)
        }
        Region3::Sphere { radius, .. } => {
            let r = (radius - d).max(0.0);
            Some(4.0 / 3.0 * std::f64::consts::PI * r * r * r)
        }
        Region3::Cylinder { axis, radius, .. } => {
            let len = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
            let r = (radius - d).max(0.0);
            Some(std::f64::consts::PI * r * r * (len - 2.0 * d).max(0.0))
        }
        Region3::Prism { .. } | Region3::Mesh(_) => None,
    }
}

/// Estimate a 3D scene's particles from its grid and its bodies' regions in O(bodies) (the
/// exact count walks every candidate site). Bodies validation refuses before its walk
/// (`particles_per_cell` outside 1..=8, a region reaching outside the grid box) and an
/// invalid grid are left out of the lower estimate.
pub fn estimate_particles3(scene: &Scene3) -> ParticleEstimate3 {
    let g = &scene.grid;
    let h = g.cell_size;
    let finite = |v: &Vec3| v.iter().all(|c| c.is_finite());
    if !(h.is_finite() && h > 0.0 && finite(&g.min) && finite(&g.max)) {
        return ParticleEstimate3::default();
    }
    let mut at_least = 0f64;
    let mut sparsest = f64::INFINITY; // particles per m³ of the sparsest body so far
    for body in &scene.bodies {
        let ppc = body.particles_per_cell;
        if !(1..=8).contains(&ppc) {
            continue;
        }
        let sub = h / f64::from(ppc);
        sparsest = sparsest.min(1.0 / (sub * sub * sub));
        let (lo, hi) = body.region.bounds();
        let inside =
            finite(&lo) && finite(&hi) && (0..3).all(|k| lo[k] >= g.min[k] && hi[k] <= g.max[k]);
        if !inside {
            continue;
        }
        if let Some(v) = eroded_volume(&body.region, 2.0 * h, g.min, g.max)
            && v.is_finite()
        {
            at_least = at_least.max(v * sparsest);
        }
    }
    ParticleEstimate3 {
        at_least: if at_least >= u64::MAX as f64 {
            u64::MAX
        } else {
            at_least as u64
        },
        sites: lattice3::candidate_sites3(scene),
    }
}

/// How many snapshot times a 3D run has (each writes one snapshot per slice): as 2D, one at
/// t = 0 and one every `output.snapshot_interval` up to the end time; 0 without snapshots.
pub fn snapshot_times3(scene: &Scene3) -> u64 {
    let dt = scene.output.snapshot_interval;
    if dt > 0.0 && dt.is_finite() && scene.time.end.is_finite() {
        let n = (scene.time.end / dt).floor();
        if (0.0..1e15).contains(&n) {
            n as u64 + 1
        } else {
            u64::MAX
        }
    } else {
        0
    }
}

/// Grid nodes of one snapshot time: the nodes of every slice plane (`output.slices`, or the
/// default mid-plane), saturating; 0 for a grid validation refuses.
pub fn slice_nodes3(scene: &Scene3) -> u64 {
    let Some([nx, ny, nz]) = scene.grid.node_counts() else {
        return 0;
    };
    scene
        .output
        .slices_or_default(&scene.grid)
        .iter()
        .map(|s: &Slice| match s.normal {
            crate::scene3::Axis::X => ny.saturating_mul(nz),
            crate::scene3::Axis::Y => nx.saturating_mul(nz),
            crate::scene3::Axis::Z => nx.saturating_mul(ny),
        })
        .fold(0u64, u64::saturating_add)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use serde_json::json;

    fn scene(bodies: serde_json::Value) -> Scene3 {
        serde_json::from_value(json!({
            "analysis": "3d",
            "grid": {"cell_size": 0.001, "min": [0.0, 0.0, 0.0], "max": [0.03, 0.02, 0.02]},
            "materials": {"m": {"model": "linear_elastic", "density": 1000.0,
                                 "youngs_modulus": 1e9, "poissons_ratio": 0.3}},
            "bodies": bodies,
            "time": {"end": 1e-5},
            "output": {"snapshot_interval": 2.5e-6,
                       "slices": [{"normal": "z", "at": 0.01}, {"normal": "x", "at": 0.015}]}
        }))
        .unwrap()
    }

    /// The estimate brackets the exact count of the lattice walk: at_least ≤ particles ≤ sites.
    #[test]
    fn the_estimate_brackets_the_exact_count() {
        let cases = [
            json!([{"material": "m", "region": {"box": {"min": [0.001, 0.001, 0.001], "max": [0.029, 0.019, 0.019]}}}]),
            json!([{"material": "m", "particles_per_cell": 3,
                    "region": {"sphere": {"center": [0.015, 0.01, 0.01], "radius": 0.008}}}]),
            json!([{"material": "m", "particles_per_cell": 1,
                    "region": {"cylinder": {"base": [0.003, 0.01, 0.01], "axis": [0.024, 0.0, 0.0], "radius": 0.006}}}]),
            // Overlap: a sparse body first takes the part a dense one shares with it.
            json!([
                {"material": "m", "particles_per_cell": 1, "region": {"box": {"min": [0.001, 0.001, 0.001], "max": [0.015, 0.019, 0.019]}}},
                {"material": "m", "particles_per_cell": 4, "region": {"box": {"min": [0.008, 0.001, 0.001], "max": [0.029, 0.019, 0.019]}}}
            ]),
            json!([{"material": "m", "region": {"prism": {"polygon": [[0.002, 0.002], [0.028, 0.004], [0.01, 0.018]], "z": [0.002, 0.018]}}}]),
        ];
        for bodies in cases {
            let s = scene(bodies.clone());
            let exact = crate::validate3::validate3(&s).unwrap().particles;
            let est = estimate_particles3(&s);
            assert!(
                est.at_least <= exact && exact <= est.sites,
                "{bodies}: {est:?}, exact {exact}"
            );
            assert!(
                est.at_least > 0 || bodies.to_string().contains("prism"),
                "{est:?}"
            );
        }
    }

    #[test]
    fn snapshot_times_and_slice_nodes() {
        let s = scene(json!([{"material": "m",
            "region": {"box": {"min": [0.001, 0.001, 0.001], "max": [0.029, 0.019, 0.019]}}}]));
        assert_eq!(snapshot_times3(&s), 5);
        // 31 × 21 nodes normal to z, 21 × 21 normal to x.
        assert_eq!(slice_nodes3(&s), 31 * 21 + 21 * 21);
    }
}
