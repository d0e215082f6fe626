//! Workers started by a batch scheduler (Slurm job arrays, Kubernetes Jobs): the signals
//! that ask a worker to stop before its time limit, and its lifecycle limits.
//!
//! * SIGUSR1 (Slurm's `--signal=B:USR1@SECONDS`) and SIGTERM (`scancel`, the time limit,
//!   a Kubernetes pod's termination) ask the worker process to hand its job back
//!   ([`crate::handback::request`]): the run stops at its next progress report, the job
//!   goes back to the queue (`POST /api/v1/worker/jobs/{id}/release`, no attempt counted)
//!   and the process exits 0. The supervisor of `fracture worker` forwards the signal to
//!   its worker process and does not start another.
//! * `--idle-exit` and `--max-jobs` ([`crate::remote::WorkerConfig`]) end a worker that has
//!   had no job for a while or has run its share, so an array of workers drains a queue and
//!   gives its nodes back.

use std::sync::atomic::{AtomicI32, Ordering};

/// The last stop signal received (0: none).
static SIGNAL: AtomicI32 = AtomicI32::new(0);

/// The signals that stop a batch worker.
#[cfg(unix)]
pub const STOP_SIGNALS: [i32; 2] = [signal_hook::consts::SIGTERM, signal_hook::consts::SIGUSR1];

/// Why the worker was asked to stop, for the handed-back job's message (`None`: it was
/// not).
pub fn stop_reason() -> Option<String> {
    match SIGNAL.load(Ordering::SeqCst) {
        0 => None,
        s => Some(signal_text(s)),
    }
}

/// A stop signal in words.
pub fn signal_text(sig: i32) -> String {
    #[cfg(unix)]
    {
        use signal_hook::consts::{SIGTERM, SIGUSR1};
        if sig == SIGUSR1 {
            return "SIGUSR1: the scheduler's warning before the time limit".into();
        }
        if sig == SIGTERM {
            return "SIGTERM: the job was stopped (scancel, time limit, pod termination)".into();
        }
    }
    format!("signal {sig}")
}

/// Handle the stop signals on a thread of this process: each one records itself and calls
/// `on_signal` with its number. The default actions (SIGTERM and SIGUSR1 end a process)
/// no longer apply once this returns.
#[cfg(unix)]
pub fn on_stop_signals(on_signal: impl Fn(i32) + Send + 'static) -> std::io::Result<()> {
    let mut signals = signal_hook::iterator::Signals::new(STOP_SIGNALS)?;
    std::thread::Builder::new()
        .name("stop-signals".into())
        .spawn(move || {
            for sig in signals.forever() {
                SIGNAL.store(sig, Ordering::SeqCst);
                on_signal(sig);
            }
        })?;
    Ok(())
}

/// Make the stop signals hand the running job back (the worker process; see the module
/// documentation).
#[cfg(unix)]
pub fn hand_back_on_signals() -> std::io::Result<()> {
    on_stop_signals(|sig| {
        tracing::warn!(
            signal = %signal_text(sig),
            "asked to stop: the running job is handed back at its next progress report"
        );
        crate::handback::request();
    })
}
