//! The mpm-fracture service: HTTP API, SQLite store, durable job queue, SSE streams,
//! results files and the dashboard.
//!
//! * [`app`] ([`http`]) builds the axum [`Router`](axum::Router) from an [`AppState`]; it is what the
//!   binary serves and what the unit tests drive with `tower::ServiceExt::oneshot`.
//! * [`store`] owns the SQLite database (jobs, the queue with leases and fencing tokens,
//!   history rows and snapshots); [`files`] owns each job's MCAP file. The server is the
//!   one writer of both; workers talk HTTP only (`fracture_api::protocol`).
//! * [`config`] holds the limits of a request; [`limits3`] applies them to 3D scenes
//!   (`"analysis": "3d"`), which every route that takes a scene accepts.
//! * [`service`] is `fracture serve`: the process around the router (store, reaper, local
//!   worker processes, graceful shutdown).
//!
//! The crate runs no physics and does not depend on the solver or the worker: local workers
//! are child processes of the `fracture` binary.

pub mod assets;
pub mod checkpoints;
pub mod config;
pub mod error;
pub mod events;
pub mod files;
pub mod http;
pub mod limits3;
pub mod server;
pub mod service;
pub mod store;

pub use config::Config;
pub use error::ApiError;
/// The router's old path (`fracture_server::routes::app`), kept for callers.
pub use http as routes;
pub use http::app;
pub use server::AppState;
