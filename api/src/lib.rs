//! The public data model of mpm-fracture.
//!
//! * [`scene`]: the scene document (explained field by field in `docs/scenes.md`), with serde
//!   defaults, `deny_unknown_fields` and a JSON Schema.
//! * [`validate`]: validation of a scene, reporting every problem with its JSON path and value.
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
pub mod jobs;
pub mod lattice;
pub mod nan;
pub mod protocol;
pub mod results;
pub mod scene;
pub mod sweep;
pub mod tips;
pub mod validate;

pub use scene::Scene;
pub use validate::{RunSize, ValidScene, ValidationError, ValidationErrors};

/// Version string of the solver and data model, recorded in every run summary.
pub const SOLVER_VERSION: &str = env!("CARGO_PKG_VERSION");
