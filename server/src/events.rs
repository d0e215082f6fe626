//! Per-job event fan-out for the SSE streams.

use std::collections::HashMap;
use std::sync::Mutex;

use fracture_api::jobs::{SnapshotInfo, StatusEvent};
use fracture_api::results::{CrackTipRow, EnergyRow, Progress};
use tokio::sync::broadcast;

/// One event of a job's stream.
#[derive(Debug, Clone)]
pub enum JobEvent {
    /// `progress`.
    Progress(Progress),
    /// `energy`: a batch of rows.
    Energy(Vec<EnergyRow>),
    /// `crack_tip`: a batch of rows.
    CrackTips(Vec<CrackTipRow>),
    /// `snapshot`: a new snapshot is readable.
    Snapshot(SnapshotInfo),
    /// `status`: the job changed state.
    Status(Box<StatusEvent>),
    /// `restart` (extension): a new attempt resumes the job from its checkpoint (or from
    /// the start): `{attempt, progress, message}`.
    Restart(crate::store::Restart),
}

impl JobEvent {
    /// SSE event name.
    pub fn name(&self) -> &'static str {
        match self {
            JobEvent::Progress(_) => "progress",
            JobEvent::Energy(_) => "energy",
            JobEvent::CrackTips(_) => "crack_tip",
            JobEvent::Snapshot(_) => "snapshot",
            JobEvent::Status(_) => "status",
            JobEvent::Restart(_) => "restart",
        }
    }
    /// SSE data (JSON).
    pub fn data(&self) -> String {
        let r = match self {
            JobEvent::Progress(p) => serde_json::to_string(p),
            JobEvent::Energy(r) => serde_json::to_string(r),
            JobEvent::CrackTips(r) => serde_json::to_string(r),
            JobEvent::Snapshot(s) => serde_json::to_string(s),
            JobEvent::Status(s) => serde_json::to_string(s),
            JobEvent::Restart(r) => serde_json::to_string(r),
        };
        r.unwrap_or_else(|_| "null".into())
    }
}

/// Broadcast channels by job id, created when first used.
#[derive(Debug, Default)]
pub struct Hub {
    chans: Mutex<HashMap<String, broadcast::Sender<JobEvent>>>,
}

impl Hub {
    /// Subscribe to a job's events.
    pub fn subscribe(&self, id: &str) -> broadcast::Receiver<JobEvent> {
        let mut m = self.chans.lock().unwrap_or_else(|p| p.into_inner());
        m.entry(id.to_string())
            .or_insert_with(|| broadcast::channel(1024).0)
            .subscribe()
    }

    /// Send an event to a job's subscribers (none: dropped). A terminal status also forgets
    /// the channel once sent.
    pub fn send(&self, id: &str, ev: JobEvent) {
        let mut m = self.chans.lock().unwrap_or_else(|p| p.into_inner());
        let terminal = matches!(&ev, JobEvent::Status(s) if s.status.is_terminal());
        if let Some(tx) = m.get(id) {
            let _ = tx.send(ev);
            if terminal || tx.receiver_count() == 0 {
                m.remove(id);
            }
        }
    }
}
