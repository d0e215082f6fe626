//! Local commands: `run`, `validate`, `schema`, `bench`.

use std::path::Path;
use std::process::ExitCode;

/// Arguments of `fracture bench`.
#[derive(clap::Args, Debug)]
pub struct BenchArgs {}

/// `fracture run`.
pub fn run(_scene: &Path, _out: &Path, _threads: usize) -> ExitCode {
    ExitCode::FAILURE
}
/// `fracture validate`.
pub fn validate(_scene: &Path) -> ExitCode {
    ExitCode::FAILURE
}
/// `fracture schema`.
pub fn schema() -> ExitCode {
    ExitCode::FAILURE
}
/// `fracture bench`.
pub fn bench(_a: BenchArgs) -> ExitCode {
    ExitCode::FAILURE
}
