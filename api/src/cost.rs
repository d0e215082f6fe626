//! What a run costs before it runs: the memory the solver will allocate and the work
//! (particle-steps), from the scene and its size, without building anything.
//!
//! The memory model follows the solver's allocations (`solver/src/sim/build.rs`,
//! `solver/src/grid.rs`): a dense grid of packed nodes (13 `f64` = 104 B per node,
//! including ghost columns and the padding of the parallel strips), the particles'
//! structure-of-arrays with their sort scratch (≈ 470 B; counted as
//! [`BYTES_PER_PARTICLE`] with the validated seeds), the crack side tables (a slot index
//! and a contact impulse per node, a second velocity field near the cracks), and one field
//! snapshot in flight (accumulators, the encoded `f32` components, the upload copy). It is
//! an estimate meant to be on the safe side by a few tens of percent; the service refuses
//! a scene whose estimate exceeds its `max_memory_bytes` and caps its workers' memory at
//! the estimate plus a margin.
//!
//! The 3D estimates ([`memory_estimate3`], [`BYTES_PER_NODE_3D`], [`BYTES_PER_PARTICLE_3D`])
//! are made before the 3D solver's storage is fixed: estimates by analogy with 2D, to be
//! replaced by the solver's own accounting.
//!
//! Everything here is O(1) in the number of particles: it can run on an async thread, and
//! before the lattice walk of validation (with a particle estimate) as well as after it
//! (with the exact count).

use crate::scene::{FieldKind, Scene};
use crate::scene3::{Axis, Scene3};

/// Bytes per grid node of the dense grid (one `Node`: mass, five 2-vectors).
pub const BYTES_PER_NODE: u64 = 104;
/// Extra bytes per grid node when the scene has cracks (slot index, contact impulse, and
/// the second velocity field where it is needed, bounded by a quarter of the nodes).
pub const CRACK_BYTES_PER_NODE: u64 = 4 + 8 + BYTES_PER_NODE / 4;
/// Bytes per particle: state, shape-function weights, sort scratch, the validated seed.
pub const BYTES_PER_PARTICLE: u64 = 640;
/// Fixed cost of a worker process running a job (code, thread stacks, allocator arenas).
pub const BASE_BYTES: u64 = 64 << 20;
/// Ghost and strip-padding columns of the grid storage (`grid::PAD` on both sides and up
/// to one colour chunk of `2·STRIP` columns).
const PAD_COLUMNS: u64 = 2 * 3 + 2 * 8;

/// The memory a run needs, by part (bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MemoryEstimate {
    /// The dense grid.
    pub grid: u64,
    /// The particles.
    pub particles: u64,
    /// Crack side tables.
    pub cracks: u64,
    /// One snapshot in flight.
    pub snapshot: u64,
    /// Fixed cost of the process.
    pub base: u64,
    /// The sum.
    pub total: u64,
}

impl std::fmt::Display for MemoryEstimate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} (grid {}, particles {}, cracks {}, snapshot {}, base {})",
            bytes(self.total),
            bytes(self.grid),
            bytes(self.particles),
            bytes(self.cracks),
            bytes(self.snapshot),
            bytes(self.base)
        )
    }
}

/// A byte count for people: `20.4 GB`, `512.0 MB`, `900 B`.
pub fn bytes(n: u64) -> String {
    let x = n as f64;
    if x >= 1e9 {
        format!("{:.1} GB", x / 1e9)
    } else if x >= 1e6 {
        format!("{:.1} MB", x / 1e6)
    } else if x >= 1e3 {
        format!("{:.1} kB", x / 1e3)
    } else {
        format!("{n} B")
    }
}

/// Grid nodes in x and y of the scene's grid box (as validation counts them; saturated at
/// `u64::MAX` for astronomically large grids), or `None` for a grid validation refuses
/// (non-finite, empty or inverted box, cell size ≤ 0).
pub fn grid_dims(scene: &Scene) -> Option<(u64, u64)> {
    let g = &scene.grid;
    let h = g.cell_size;
    let finite = g.min.iter().chain(g.max.iter()).all(|v| v.is_finite());
    if !(finite && h.is_finite() && h > 0.0 && g.max[0] > g.min[0] && g.max[1] > g.min[1]) {
        return None;
    }
    // A count beyond 10¹⁵ (or an overflowing span) saturates: such a grid is refused by
    // every memory limit instead of wrapping around to a small number.
    let n = |k: usize| {
        let c = ((g.max[k] - g.min[k]) / h - 1e-9).ceil();
        if c.is_nan() {
            None
        } else if c < 1e15 {
            Some(c.max(0.0) as u64 + 1)
        } else {
            Some(u64::MAX)
        }
    };
    Some((n(0)?, n(1)?))
}

/// Components a snapshot records per node (an upper bound: the solver's component lists).
fn snapshot_components(scene: &Scene) -> u64 {
    scene
        .output
        .fields
        .iter()
        .map(|f| match f {
            FieldKind::Stress => 4,
            FieldKind::Strain => 3,
            FieldKind::Velocity => 3,
            FieldKind::Displacement => 2,
            FieldKind::Fringe => 1,
            FieldKind::Material => 1,
        })
        .sum()
}

/// The memory estimate of a run of `scene` with `particles` particles (the exact count, or
/// an estimate before the lattice walk). Saturates instead of overflowing.
pub fn memory_estimate(scene: &Scene, particles: u64) -> MemoryEstimate {
    let (nx, ny) = grid_dims(scene).unwrap_or((0, 0));
    let nodes = nx.saturating_mul(ny);
    let storage = nx.saturating_add(PAD_COLUMNS).saturating_mul(ny);
    let grid = storage.saturating_mul(BYTES_PER_NODE);
    let cracks = if scene.cracks.is_empty() {
        0
    } else {
        storage.saturating_mul(CRACK_BYTES_PER_NODE)
    };
    let snapshot = if scene.output.snapshot_interval > 0.0 {
        // mass (f64) + accumulators (f64) per component, then the f32 values three times
        // (the snapshot, its encoding, the upload's copy).
        let nc = snapshot_components(scene);
        nodes.saturating_mul(8 + nc.saturating_mul(8 + 3 * 4))
    } else {
        0
    };
    let particles = particles.saturating_mul(BYTES_PER_PARTICLE);
    let total = grid
        .saturating_add(particles)
        .saturating_add(cracks)
        .saturating_add(snapshot)
        .saturating_add(BASE_BYTES);
    MemoryEstimate {
        grid,
        particles,
        cracks,
        snapshot,
        base: BASE_BYTES,
        total,
    }
}

/// Time steps of a run, from the scene alone (as validation computes them), or `None`
/// when the time step is not a positive finite number.
pub fn steps_estimate(scene: &Scene) -> Option<u64> {
    steps_of(scene.time_step()?, scene.time.end)
}

/// ⌈end/Δt⌉ (less a rounding allowance, as validation counts), saturating; `None` when Δt
/// is not a positive finite number or `end` is not finite.
fn steps_of(dt: f64, end: f64) -> Option<u64> {
    if !(dt.is_finite() && dt > 0.0 && end.is_finite()) {
        return None;
    }
    let s = (end / dt * (1.0 - 1e-12)).ceil();
    if s.is_finite() && s >= 0.0 {
        Some(if s >= u64::MAX as f64 {
            u64::MAX
        } else {
            s as u64
        })
    } else {
        None
    }
}

/// The work of a run: particles × steps, saturating.
pub fn particle_steps(particles: u64, steps: u64) -> u64 {
    particles.saturating_mul(steps)
}

/// Bytes per grid node of a 3D run (an estimate made before the 3D solver's storage is
/// fixed): mass, momentum, force, re-extrapolated momentum, velocity and acceleration, 16
/// `f64`.
pub const BYTES_PER_NODE_3D: u64 = 16 * 8;
/// Bytes per particle of a 3D run (an estimate): twice the 2D particle's
/// ([`BYTES_PER_PARTICLE`]), for 3-vectors, 3×3 gradients, six stress and strain components
/// and 27-node weights.
pub const BYTES_PER_PARTICLE_3D: u64 = 2 * BYTES_PER_PARTICLE;

/// Grid nodes in x, y and z of a 3D scene's grid box (as validation counts them, saturated),
/// or `None` for a grid validation refuses.
pub fn grid_dims3(scene: &Scene3) -> Option<(u64, u64, u64)> {
    scene.grid.node_counts().map(|[x, y, z]| (x, y, z))
}

/// Components a 3D snapshot records per node (an upper bound).
fn snapshot_components3(scene: &Scene3) -> u64 {
    scene
        .output
        .fields
        .iter()
        .map(|f| match f {
            FieldKind::Stress => 7, // six components and the von Mises stress
            FieldKind::Strain => 6,
            FieldKind::Velocity => 4,
            FieldKind::Displacement => 3,
            FieldKind::Fringe => 0, // refused in 3D
            FieldKind::Material => 1,
        })
        .sum()
}

/// The memory estimate of a 3D run of `scene` with `particles` particles (the exact count, or
/// an estimate before the lattice walk): the dense grid at [`BYTES_PER_NODE_3D`], the
/// particles at [`BYTES_PER_PARTICLE_3D`], no crack tables (3D cracks are refused), and one
/// snapshot in flight (accumulators over the whole grid, then the slices' `f32` values three
/// times, as 2D). An estimate meant to be on the safe side; saturates instead of
/// overflowing.
pub fn memory_estimate3(scene: &Scene3, particles: u64) -> MemoryEstimate {
    let (nx, ny, nz) = grid_dims3(scene).unwrap_or((0, 0, 0));
    let nodes = nx.saturating_mul(ny).saturating_mul(nz);
    let grid = nodes.saturating_mul(BYTES_PER_NODE_3D);
    let snapshot = if scene.output.snapshot_interval > 0.0 {
        let nc = snapshot_components3(scene);
        let plane = |normal: Axis| match normal {
            Axis::X => ny.saturating_mul(nz),
            Axis::Y => nx.saturating_mul(nz),
            Axis::Z => nx.saturating_mul(ny),
        };
        let slice_nodes = scene
            .output
            .slices_or_default(&scene.grid)
            .iter()
            .fold(0u64, |n, s| n.saturating_add(plane(s.normal)));
        nodes
            .saturating_mul(8 + nc.saturating_mul(8))
            .saturating_add(slice_nodes.saturating_mul(nc.saturating_mul(3 * 4)))
    } else {
        0
    };
    let particles = particles.saturating_mul(BYTES_PER_PARTICLE_3D);
    let total = grid
        .saturating_add(particles)
        .saturating_add(snapshot)
        .saturating_add(BASE_BYTES);
    MemoryEstimate {
        grid,
        particles,
        cracks: 0,
        snapshot,
        base: BASE_BYTES,
        total,
    }
}

/// Time steps of a 3D run, from the scene alone (as validation computes them), or `None`
/// when the time step is not a positive finite number.
pub fn steps_estimate3(scene: &Scene3) -> Option<u64> {
    steps_of(scene.time_step()?, scene.time.end)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use serde_json::json;

    fn scene(h: f64, w: f64, cracks: bool, snapshots: bool) -> Scene {
        let mut v = json!({
            "name": "cost",
            "grid": { "cell_size": h, "min": [0.0, 0.0], "max": [w, w] },
            "materials": { "m": { "model": "linear_elastic", "density": 1230.0,
                                  "youngs_modulus": 3.96e9, "poissons_ratio": 0.35 } },
            "bodies": [ { "material": "m",
                "region": { "rectangle": { "min": [0.0, 0.0], "max": [0.01, 0.01] } } } ],
            "time": { "end": 1.0e-5 }
        });
        if cracks {
            v["cracks"] = json!([{ "points": [[0.0, 0.005], [0.004, 0.005]] }]);
        }
        if snapshots {
            v["output"] = json!({ "snapshot_interval": 1e-6, "fields": ["stress", "velocity"] });
        }
        serde_json::from_value(v).unwrap()
    }

    /// The reported case: a 14 000² grid (196 M nodes) is ≈ 20.4 GB of grid alone.
    #[test]
    fn a_196_m_node_grid_is_about_20_gb() {
        let s = scene(1e-5, 0.14, false, false);
        let (nx, ny) = grid_dims(&s).unwrap();
        assert_eq!(nx * ny, 14_001 * 14_001);
        let m = memory_estimate(&s, 1600);
        assert!((20.0e9..21.0e9).contains(&(m.total as f64)), "{m}");
    }

    #[test]
    fn parts_add_up_and_cracks_and_snapshots_cost_more() {
        let plain = memory_estimate(&scene(1e-3, 0.1, false, false), 10_000);
        let cracked = memory_estimate(&scene(1e-3, 0.1, true, false), 10_000);
        let snaps = memory_estimate(&scene(1e-3, 0.1, false, true), 10_000);
        assert_eq!(
            plain.total,
            plain.grid + plain.particles + plain.cracks + plain.snapshot + plain.base
        );
        assert!(cracked.total > plain.total && cracked.cracks > 0);
        assert!(snaps.total > plain.total && snaps.snapshot > 0);
        assert_eq!(plain.particles, 10_000 * BYTES_PER_PARTICLE);
    }

    #[test]
    fn steps_match_the_time_step_and_saturate() {
        let s = scene(1e-3, 0.1, false, false);
        let dt = s.time_step().unwrap();
        assert_eq!(
            steps_estimate(&s),
            Some((1e-5 / dt * (1.0 - 1e-12)).ceil() as u64)
        );
        assert_eq!(particle_steps(u64::MAX, 2), u64::MAX);
        let mut huge = s.clone();
        huge.grid.cell_size = 1e-300;
        huge.grid.max = [1e300, 1e300];
        assert_eq!(grid_dims(&huge), Some((u64::MAX, u64::MAX)));
        assert_eq!(memory_estimate(&huge, 0).total, u64::MAX);
        let mut bad = s.clone();
        bad.grid.cell_size = f64::NAN;
        assert_eq!(grid_dims(&bad), None);
        assert_eq!(memory_estimate(&bad, 0).grid, 0);
    }
}
