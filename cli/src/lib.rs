//! The commands of the `fracture` binary that are not a crate's own: `run`, `validate` and
//! `schema` ([`local`]), `import-stl` ([`import_stl`]), the remote `worker`, `submit` and
//! `sweep` ([`commands`], over the HTTP [`client`]). `serve` is `fracture_server::service`;
//! `bench` and `study` are `fracture_lab`.

pub mod answers;
pub mod client;
pub mod commands;
pub mod import_stl;
pub mod local;
