//! A request to stop the running job, checkpoint it and hand it back to the queue: set by a
//! batch worker's signal handlers (Slurm's `--signal`, SIGTERM before a time limit), read by
//! the run loop at its progress reports. One flag per process.

use std::sync::atomic::{AtomicBool, Ordering};

static HAND_BACK: AtomicBool = AtomicBool::new(false);

/// Ask this process to checkpoint its job, hand it back and stop claiming.
pub fn request() {
    HAND_BACK.store(true, Ordering::SeqCst);
}

/// Whether a hand back has been requested.
pub fn requested() -> bool {
    HAND_BACK.load(Ordering::SeqCst)
}
