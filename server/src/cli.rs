//! Service commands: `serve`, `worker`, `submit`.

use std::process::ExitCode;

/// Arguments of `fracture serve`.
#[derive(clap::Args, Debug, Default)]
pub struct ServeArgs {}

impl ServeArgs {
    /// Defaults and `FRACTURE_*` variables (what `cargo run --release` with no arguments uses).
    pub fn from_env() -> Self {
        ServeArgs {}
    }
}

/// Arguments of `fracture worker`.
#[derive(clap::Args, Debug)]
pub struct WorkerArgs {}

/// Arguments of `fracture submit`.
#[derive(clap::Args, Debug)]
pub struct SubmitArgs {}

/// `fracture serve`.
pub fn serve(_a: ServeArgs) -> ExitCode {
    ExitCode::FAILURE
}
/// `fracture worker`.
pub fn worker(_a: WorkerArgs) -> ExitCode {
    ExitCode::FAILURE
}
/// `fracture submit`.
pub fn submit(_a: SubmitArgs) -> ExitCode {
    ExitCode::FAILURE
}
