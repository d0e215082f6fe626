//! The public data model of mpm-fracture.
//!
//! * [`scene`]: the scene document (explained field by field in `docs/scenes.md`), with serde
//!   defaults, `deny_unknown_fields` and a JSON Schema.
//! * [`validate`]: validation of a scene, reporting every problem with its JSON path and value.
//! * [`scene3`], [`mod@validate3`], [`lattice3`], [`mesh`]: the 3D scene (`"analysis": "3d"`,
//!   `docs/scenes-3d.md`), its validation, its particle lattice and its triangle-mesh
//!   regions; [`AnyScene`] and [`parse_any_scene`] take a document of either dimension.
//! * [`scene_any`]: documents of either dimension as JSON values (what the service receives
//!   and stores, [`any_scene_from_value`]); [`cost3`]: a 3D scene's particle estimate before
//!   its lattice walk.
//! * [`results`]: the rows and files a run produces (`run-output.md`): energy and crack-tip
//!   history rows, field snapshots, the run summary.
//! * [`jobs`]: job states and the request/response types of the HTTP API (`api.md`).
//! * [`sweep`]: parameter sweeps (request, combinations, labels).
//! * [`protocol`]: the worker protocol (`/api/v1/worker/…`).
//! * [`nan`]: NaN as JSON `null` in history rows.
//!
//! This crate does no IO and knows nothing of HTTP or SQL.

pub mod clock;
pub mod cost;
pub mod cost3;
pub mod jobs;
pub mod lattice;
pub mod lattice3;
pub mod mesh;
pub mod nan;
pub mod protocol;
pub mod results;
pub mod scene;
pub mod scene3;
pub mod scene_any;
pub mod sweep;
pub mod tips;
pub mod validate;
pub mod validate3;

pub use scene::Scene;
pub use scene_any::any_scene_from_value;
pub use scene3::{AnyScene, Scene3};
pub use validate::{RunSize, ValidScene, ValidationError, ValidationErrors};
pub use validate3::{ValidScene3, parse_any_scene, validate_any, validate3};

/// Version string of the solver and data model, recorded in every run summary.
pub const SOLVER_VERSION: &str = env!("CARGO_PKG_VERSION");
