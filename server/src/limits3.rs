//! The service's limits ([`Limits`]) applied to 3D scenes, and the admission of a scene of
//! either dimension ([`Limits::admit_any`]), in the two stages of 2D (`config.rs`): a cheap
//! precheck from the bodies' regions in O(bodies) ([`fracture_api::cost3`]), so that an
//! enormous 3D scene is refused before anything walks its lattice, then validation
//! ([`fracture_api::validate3()`]) and the exact limits, which callers run off the async
//! threads.
//!
//! What differs from 2D: the grid has `nx × ny × nz` nodes, the memory estimate is
//! [`fracture_api::cost::memory_estimate3`], and a snapshot time records its slices (one
//! plane each), so `max_snapshot_volume` bounds snapshot times × slice nodes.

use fracture_api::jobs::ErrorDetail;
use fracture_api::{AnyScene, RunSize, Scene3, cost, cost3, validate3};

use crate::config::{Exceeded, Limits, exceeded};
use crate::error::ApiError;

impl Limits {
    /// The cheap check of a 3D scene, before any lattice walk: `max_particles` by the
    /// particle estimate and the candidate sites ([`cost3::estimate_particles3`]), then the
    /// cost limits (memory, particle-steps) with the lower particle estimate. O(bodies).
    pub fn precheck3(&self, scene: &Scene3) -> Result<(), ApiError> {
        let est = cost3::estimate_particles3(scene);
        if let Some(e) = self.particle_precheck(est.at_least, est.sites) {
            return Err(e);
        }
        let steps = cost::steps_estimate3(scene).unwrap_or(0);
        exceeded(self.cost3(scene, est.at_least, steps, "at least "))
    }

    /// The cost limits of a 3D run of `particles` particles and `steps` steps.
    fn cost3(&self, scene: &Scene3, particles: u64, steps: u64, qualifier: &str) -> Vec<Exceeded> {
        let mem = cost::memory_estimate3(scene, particles);
        let (nx, ny, nz) = cost::grid_dims3(scene).unwrap_or((0, 0, 0));
        let grid = format!(
            "{nx} × {ny} × {nz} = {}",
            nx.saturating_mul(ny).saturating_mul(nz)
        );
        self.cost_of(&mem, &grid, particles, steps, qualifier)
    }

    /// Check a valid 3D scene's size against the limits: 422 naming each exceeded limit.
    pub fn check3(&self, scene: &Scene3, size: &RunSize) -> Result<(), ApiError> {
        let mut found = self.size_limits(&scene.name, size);
        let times = cost3::snapshot_times3(scene);
        let nodes = cost3::slice_nodes3(scene);
        let volume = times.saturating_mul(nodes);
        if volume > self.max_snapshot_volume {
            found.push((
                "max_snapshot_volume",
                ErrorDetail {
                    path: "output.snapshot_interval".into(),
                    message: format!(
                        "{times} snapshot times × {nodes} slice nodes = {volume}, more than this \
                         server's limit max_snapshot_volume = {}",
                        self.max_snapshot_volume
                    ),
                },
            ));
        }
        found.extend(self.cost3(scene, size.particles, size.steps, ""));
        exceeded(found)
    }

    /// Admit a 3D scene: [`Limits::precheck3`], validation ([`validate3()`], every problem
    /// with its path) and [`Limits::check3`]. CPU-bound: call it off the async threads.
    pub fn admit3(&self, scene: &Scene3) -> Result<RunSize, ApiError> {
        self.precheck3(scene)?;
        let size = validate3(scene)?;
        self.check3(scene, &size)?;
        Ok(size)
    }

    /// [`Limits::precheck`] or [`Limits::precheck3`], by the scene's dimension.
    pub fn precheck_any(&self, scene: &AnyScene) -> Result<(), ApiError> {
        match scene {
            AnyScene::Two(s) => self.precheck(s),
            AnyScene::Three(s) => self.precheck3(s),
        }
    }

    /// [`Limits::admit`] or [`Limits::admit3`], by the scene's dimension. CPU-bound.
    pub fn admit_any(&self, scene: &AnyScene) -> Result<RunSize, ApiError> {
        match scene {
            AnyScene::Two(s) => self.admit(s),
            AnyScene::Three(s) => self.admit3(s),
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use serde_json::json;

    fn cube(h: f64, end: f64) -> Scene3 {
        serde_json::from_value(json!({
            "name": "cube",
            "analysis": "3d",
            "grid": {"cell_size": h, "min": [0.0, 0.0, 0.0], "max": [0.1, 0.1, 0.1]},
            "materials": {"m": {"model": "linear_elastic", "density": 1000.0,
                                 "youngs_modulus": 1e9, "poissons_ratio": 0.3}},
            "bodies": [{"material": "m",
                        "region": {"box": {"min": [0.01, 0.01, 0.01], "max": [0.09, 0.09, 0.09]}}}],
            "time": {"end": end},
            "output": {"snapshot_interval": end / 4.0}
        }))
        .unwrap()
    }

    fn limit_of(e: ApiError) -> (String, Vec<ErrorDetail>) {
        match e {
            ApiError::LimitExceeded { message, details } => (message, details),
            other => panic!("not a limit: {other:?}"),
        }
    }

    #[test]
    fn a_large_3d_scene_is_refused_before_its_lattice_walk() {
        // 80³ cells × 8 per cell = 4.1 M particles; the precheck's lower estimate of 76³ × 8
        // is above 1 M.
        let s = cube(0.001, 1e-6);
        let limits = Limits {
            max_particles: 1_000_000,
            ..Limits::default()
        };
        let (m, d) = limit_of(limits.precheck3(&s).unwrap_err());
        assert!(m.contains("max_particles"), "{m}");
        assert_eq!(d[0].path, "bodies");
        assert!(d[0].message.contains("at least"), "{d:?}");
    }

    #[test]
    fn exact_limits_name_what_is_exceeded() {
        let s = cube(0.01, 1e-4);
        let size = validate3(&s).unwrap();
        assert!(Limits::default().admit3(&s).is_ok());
        let limits = Limits {
            max_steps: size.steps - 1,
            max_snapshot_volume: 10,
            max_memory_bytes: 1 << 20,
            ..Limits::default()
        };
        let (m, d) = limit_of(limits.check3(&s, &size).unwrap_err());
        for name in ["max_steps", "max_snapshot_volume", "max_memory_bytes"] {
            assert!(m.contains(name), "{m}");
        }
        let mem = d.iter().find(|x| x.message.contains("memory")).unwrap();
        assert!(
            mem.message.contains("11 × 11 × 11 = 1331 grid nodes"),
            "{mem:?}"
        );
        let (m, _) = limit_of(
            Limits {
                max_particle_steps: 10,
                ..Limits::default()
            }
            .admit_any(&AnyScene::Three(s))
            .unwrap_err(),
        );
        assert!(m.contains("max_particle_steps"), "{m}");
    }
}
