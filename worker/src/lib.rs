//! Runs scenes: drives the solver, samples histories, renders snapshots, writes the run
//! directory (local runs) or streams to the server (jobs).
//!
//! * [`run_scene`] is the run loop: it builds a [`Simulation`](fracture_solver::Simulation),
//!   steps it to the end time, samples energies and crack tips every
//!   `output.history_interval`, takes field snapshots every `output.snapshot_interval`,
//!   and hands everything to a [`RunSink`] in batches. It never panics: a panic inside the
//!   solver becomes a failed [`Summary`].
//! * [`LocalOutput`] is the sink of `fracture run`: the files of `run-output.md`.
//! * [`remote`] is the remote worker: claims jobs from a server over HTTP, heartbeats,
//!   obeys cancellation and streams the results ([`remote::run_worker`]).
//! * [`checkpoint`]: a remote job writes checkpoints every N steps or M minutes and when
//!   it stops to hand its job back ([`Control::HandBack`]); a re-claimed job resumes from
//!   the last one ([`run_job`]).
//! * [`supervise`] runs the remote worker loop in a child process and reports the child's
//!   death (signal, exit status, last lines of stderr) for the job it held.
//! * [`batch`]: workers of a batch scheduler (Slurm, Kubernetes): stop signals that hand the
//!   running job back ([`handback`]), idle and job-count limits.
//!
//! The `fields.mcap` format itself lives in [`fracture_results::mcapfile`].

pub mod batch;
pub mod checkpoint;
pub mod handback;
pub mod local;
pub mod provenance;
pub mod remote;
mod run;
mod run3;
pub mod supervise;

pub use checkpoint::{CheckpointAt, CheckpointPolicy};
pub use local::{LocalOutput, LocalOutputError};
pub use run::{run_job, run_scene};
pub use run3::{run_job3, run_scene3};

use std::time::Duration;

use fracture_api::results::{CrackTipRow, EnergyRow, Progress, Snapshot, Summary, Volume};

/// What the sink wants the run to do next.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Control {
    /// Keep running.
    Continue,
    /// Stop now; the run ends with status `cancelled`.
    Cancel,
    /// Stop now to hand the job back to the queue (a batch worker told to stop,
    /// [`handback`]): the rows sampled so far are flushed, but there is no final sample, no
    /// last progress report and no [`RunSink::finish`]; the returned summary says
    /// `cancelled` with the message `handed back at step N` and is not a result. The caller
    /// hands the job back after [`run_scene`] returns (so a checkpoint written as the loop
    /// stops comes first).
    HandBack,
}

/// A sink could not take the results (IO error, server gone, lease lost, …). The run ends
/// `failed` with this message.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct SinkError(pub String);

impl From<std::io::Error> for SinkError {
    fn from(e: std::io::Error) -> Self {
        SinkError(e.to_string())
    }
}

/// Where a run's results go. Calls come in this order: rows and snapshots as they are
/// produced (rows in batches), `progress` about every [`RunOptions::flush_every`] of wall
/// time (rows sampled so far are flushed just before it), a last `progress`, then `finish`.
pub trait RunSink {
    /// Progress report; return [`Control::Cancel`] to stop the run ([`Control::HandBack`]:
    /// stop it unfinished). Called about every
    /// [`RunOptions::flush_every`] of wall time and once at the end (where the answer is
    /// ignored).
    fn progress(&mut self, p: &Progress) -> Result<Control, SinkError>;
    /// A batch of energy samples, in time order.
    fn energy(&mut self, rows: &[EnergyRow]) -> Result<(), SinkError>;
    /// A batch of crack-tip samples, in time order (one row per tip per sample).
    fn crack_tips(&mut self, rows: &[CrackTipRow]) -> Result<(), SinkError>;
    /// One field snapshot.
    fn snapshot(&mut self, snap: &Snapshot) -> Result<(), SinkError>;
    /// The run is over; called exactly once, also after failures and cancellation (not
    /// after [`Control::HandBack`]: the run is not over).
    fn finish(&mut self, summary: &Summary) -> Result<(), SinkError>;
    /// A checkpoint of the run ([`checkpoint`]), taken after every row sampled at or before
    /// `at.time` was given to the sink. A sink that keeps none ignores it. An error is
    /// logged and the run goes on (the previous checkpoint stays the one to resume from).
    fn checkpoint(&mut self, bytes: &[u8], at: &CheckpointAt) -> Result<(), SinkError> {
        let _ = (bytes, at);
        Ok(())
    }
    /// Whether the sink takes whole-grid volumes of 3D runs ([`RunSink::volume`]): they
    /// cost a pass over the particles and a grid of values, so the loop only makes them
    /// when asked (`fracture run --vtk` of a 3D scene).
    fn wants_volumes(&self) -> bool {
        false
    }
    /// A 3D run's fields on its whole grid at a snapshot time (after that time's slices).
    fn volume(&mut self, volume: &Volume) -> Result<(), SinkError> {
        let _ = volume;
        Ok(())
    }
}

/// How a run is driven (not physics).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RunOptions {
    /// Solver threads.
    pub threads: fracture_solver::Parallelism,
    /// Wall-clock interval between progress reports (and row flushes).
    pub flush_every: Duration,
}

impl Default for RunOptions {
    fn default() -> Self {
        RunOptions {
            threads: fracture_solver::Parallelism::AllCores,
            flush_every: Duration::from_millis(500),
        }
    }
}

/// Forwarding impl, so a `&mut S` or a boxed sink can be passed where a sink is owned.
impl<S: RunSink + ?Sized> RunSink for &mut S {
    fn progress(&mut self, p: &Progress) -> Result<Control, SinkError> {
        (**self).progress(p)
    }
    fn energy(&mut self, rows: &[EnergyRow]) -> Result<(), SinkError> {
        (**self).energy(rows)
    }
    fn crack_tips(&mut self, rows: &[CrackTipRow]) -> Result<(), SinkError> {
        (**self).crack_tips(rows)
    }
    fn snapshot(&mut self, snap: &Snapshot) -> Result<(), SinkError> {
        (**self).snapshot(snap)
    }
    fn finish(&mut self, summary: &Summary) -> Result<(), SinkError> {
        (**self).finish(summary)
    }
    fn checkpoint(&mut self, bytes: &[u8], at: &CheckpointAt) -> Result<(), SinkError> {
        (**self).checkpoint(bytes, at)
    }
    fn wants_volumes(&self) -> bool {
        (**self).wants_volumes()
    }
    fn volume(&mut self, volume: &Volume) -> Result<(), SinkError> {
        (**self).volume(volume)
    }
}
