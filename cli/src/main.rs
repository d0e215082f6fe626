//! `fracture`: the single binary of mpm-fracture (`api.md`, command line). Thin: it parses
//! the arguments and calls the crates (`fracture-server` for `serve`, `fracture-worker` for
//! `worker` and `run`, `fracture-lab` for `bench` and `study`).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use fracture_cli::{commands, import_stl, local};

/// Dynamic fracture with the material point method: service and command-line tools.
#[derive(Parser, Debug)]
#[command(
    name = "fracture",
    version,
    about,
    after_help = "First run: `fracture run scenes/center-crack.json --out out/center-crack`.\n\
Scenes: docs/scenes.md explains every field (units, defaults, examples); \
`fracture schema` prints the JSON Schema."
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run the service: HTTP API, job queue, local workers, dashboard.
    Serve(fracture_server::service::ServeArgs),
    /// Run one worker process that claims jobs from a server.
    Worker(commands::WorkerArgs),
    /// Submit a scene to a server (optionally wait for the outcome).
    Submit(commands::SubmitArgs),
    /// Submit a parameter sweep: one job per combination of `--param` values.
    Sweep(commands::SweepArgs),
    /// Run one scene locally, without a server, writing the run directory.
    #[command(
        after_help = "The scene format: docs/scenes.md (every field with units and \
                            defaults; `fracture schema` prints the JSON Schema). OUT gets \
                            summary.json, crack_tips.csv, energy.csv and fields.mcap \
                            (docs/run-output.md)."
    )]
    Run {
        /// Scene JSON file.
        scene: PathBuf,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
        /// Solver threads (`all` or 0: one per core).
        #[arg(long, default_value = "all")]
        threads: fracture_solver::Parallelism,
        /// Also write the field snapshots as a VTK series for ParaView under `OUT/vtk/`
        /// (open `OUT/vtk/fields.pvd`; docs/vtk.md).
        #[arg(long)]
        vtk: bool,
        /// Replace the files of a previous run in a non-empty OUT (without it, a non-empty
        /// OUT is refused so no run is overwritten or mixed with another's files).
        #[arg(long)]
        force: bool,
    },
    /// Validate a scene (2D, or 3D with "analysis": "3d") and print the size of the run.
    #[command(
        after_help = "The scene format: docs/scenes.md (2D) and docs/scenes-3d.md (3D); \
                            `fracture schema` (`--3d`) prints the JSON Schema."
    )]
    Validate {
        /// Scene JSON file.
        scene: PathBuf,
    },
    /// Print the scene JSON Schema (the 2D scene's; `--3d`: the 3D scene's).
    #[command(
        after_help = "Every field, with units, defaults and worked examples, is \
                            explained in docs/scenes.md (2D) and docs/scenes-3d.md (3D)."
    )]
    Schema {
        /// Print the 3D scene's schema ("analysis": "3d").
        #[arg(long = "3d")]
        three_d: bool,
    },
    /// Print an STL file's surface as a 3D scene's `mesh` region (JSON on stdout).
    #[command(
        after_help = "Reads ASCII or binary STL, merges exactly equal vertices and checks the \
                            surface (closed, consistently oriented, not self-intersecting) \
                            as validation will; exit status 2 names what is wrong. Paste the \
                            output as a body's \"region\" (docs/scenes-3d.md, Meshes)."
    )]
    ImportStl {
        /// STL file (ASCII or binary).
        file: PathBuf,
        /// Multiply every coordinate by this (STL has no units: 0.001 for a file in mm).
        #[arg(long, default_value_t = 1.0)]
        scale: f64,
    },
    /// Benchmarks: throughput (particle-steps per second) and more.
    Bench(fracture_lab::BenchArgs),
    /// Studies: the seed's Rosakis parameter sweeps, with figures and the claims table
    /// (`docs/rosakis.md`).
    Study(fracture_lab::StudyArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        None => fracture_server::service::serve(fracture_server::service::ServeArgs::from_env()),
        Some(Command::Serve(a)) => fracture_server::service::serve(a),
        Some(Command::Worker(a)) => commands::worker(a),
        Some(Command::Submit(a)) => commands::submit(a),
        Some(Command::Sweep(a)) => commands::sweep(a),
        Some(Command::Run {
            scene,
            out,
            threads,
            vtk,
            force,
        }) => local::run(&scene, &out, threads, vtk, force),
        Some(Command::Validate { scene }) => local::validate(&scene),
        Some(Command::Schema { three_d }) => local::schema(three_d),
        Some(Command::ImportStl { file, scale }) => import_stl::import_stl(&file, scale),
        Some(Command::Bench(a)) => fracture_lab::bench(a),
        Some(Command::Study(a)) => fracture_lab::study(a),
    }
}
