//! The mpm-fracture service: HTTP API, SQLite store, durable job queue, SSE streams,
//! results files and the dashboard.

pub mod cli;
