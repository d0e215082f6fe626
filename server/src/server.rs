//! The shared state of the HTTP handlers and the background tasks of the service
//! (the lease reaper).

use std::sync::Arc;
use std::time::Duration;

use fracture_api::jobs::JobStatus;
use tokio::sync::{Notify, watch};

use crate::config::Config;
use crate::events::{Hub, JobEvent};
use crate::files::JobFiles;
use crate::store::{JobRow, Store};

/// What every handler can reach.
#[derive(Debug, Clone)]
pub struct AppState {
    /// The database.
    pub store: Store,
    /// Configuration.
    pub cfg: Arc<Config>,
    /// SSE fan-out.
    pub hub: Arc<Hub>,
    /// Results files.
    pub files: Arc<JobFiles>,
    /// Wakes long-polling claims when a job becomes claimable.
    pub queue_changed: Arc<Notify>,
    /// `true` once the server is shutting down (ends SSE streams and long polls).
    pub shutdown: watch::Receiver<bool>,
    /// Particle counts of running jobs, for `GET /metrics`.
    pub particles: Arc<crate::http::metrics::ParticleCache>,
}

impl AppState {
    /// A state over an open store; returns the sender that starts the shutdown.
    pub fn new(store: Store, cfg: Config, files: Arc<JobFiles>) -> (AppState, watch::Sender<bool>) {
        let (tx, rx) = watch::channel(false);
        (
            AppState {
                store,
                cfg: Arc::new(cfg),
                hub: Arc::new(Hub::default()),
                files,
                queue_changed: Arc::new(Notify::new()),
                shutdown: rx,
                particles: Arc::default(),
            },
            tx,
        )
    }

    /// Whether shutdown has begun.
    pub fn shutting_down(&self) -> bool {
        *self.shutdown.borrow()
    }

    /// Announce a job's new state on its stream (and wake claimers if it is queued).
    pub fn announce(&self, job: &JobRow) {
        self.hub
            .send(&job.id, JobEvent::Status(Box::new(job.status_event())));
        if job.status == JobStatus::Queued {
            self.queue_changed.notify_waiters();
        }
    }

    /// Re-queue or fail the jobs whose lease expired; every `period` until shutdown.
    pub async fn run_reaper(self, period: Duration) {
        let mut shutdown = self.shutdown.clone();
        loop {
            tokio::select! {
                _ = tokio::time::sleep(period) => {}
                _ = crate::server::until_shutdown(&mut shutdown) => return,
            }
            match self.store.reap(self.cfg.max_attempts).await {
                Ok(rows) => {
                    for j in rows {
                        tracing::warn!(job = %j.id, status = j.status.as_str(), "lease expired");
                        if j.status != JobStatus::Queued {
                            let files = self.files.clone();
                            let id = j.id.clone();
                            let _ = tokio::task::spawn_blocking(move || files.finish(&id)).await;
                        }
                        self.announce(&j);
                    }
                }
                Err(e) => tracing::error!(error = %e, "reaper failed"),
            }
        }
    }
}

/// `n` random bytes as hex, from the operating system's generator (falls back to the clock
/// and process id where `/dev/urandom` cannot be read).
pub fn random_hex(n: usize) -> String {
    use std::io::Read;
    let mut buf = vec![0u8; n];
    let ok = std::fs::File::open("/dev/urandom")
        .and_then(|mut f| f.read_exact(&mut buf))
        .is_ok();
    if !ok {
        use std::hash::{BuildHasher, Hasher};
        for (i, b) in buf.iter_mut().enumerate() {
            let mut h = std::collections::hash_map::RandomState::new().build_hasher();
            h.write_u128(
                std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .map(|d| d.as_nanos())
                    .unwrap_or(0),
            );
            h.write_usize(i);
            h.write_u32(std::process::id());
            *b = h.finish() as u8;
        }
    }
    buf.iter().map(|b| format!("{b:02x}")).collect()
}

/// A new job id: time-ordered prefix plus randomness.
pub fn new_job_id() -> String {
    format!("{:011x}{}", crate::store::now_ms(), random_hex(4))
}

/// Resolves once shutdown has begun (or the sender is gone).
pub async fn until_shutdown(rx: &mut watch::Receiver<bool>) {
    let _ = rx.wait_for(|s| *s).await;
}
