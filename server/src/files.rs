//! Each job's results folder `<data>/jobs/<id>/` and its `fields.mcap`, written only by the
//! server: one open [`McapWriter`] per running job, keyed by the claim's fence. A new claim
//! (a re-run after a lost worker) restarts the file, so nothing is written twice.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, MutexGuard};

use fracture_api::results::{CrackTipRow, EnergyRow, Snapshot};
use fracture_results::mcapfile::McapWriter;

/// The results folders and open MCAP writers.
pub struct JobFiles {
    root: PathBuf,
    open: Mutex<HashMap<String, (i64, McapWriter)>>,
}

impl std::fmt::Debug for JobFiles {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("JobFiles")
            .field("root", &self.root)
            .finish()
    }
}

/// What to write into a job's MCAP file.
pub enum Record {
    /// Energy rows.
    Energy(Vec<EnergyRow>),
    /// Crack-tip rows.
    CrackTips(Vec<CrackTipRow>),
    /// A snapshot (flushed after writing).
    Snapshot(Box<Snapshot>),
}

impl JobFiles {
    /// Results under `<data>/jobs`.
    pub fn new(data: &Path) -> Arc<JobFiles> {
        Arc::new(JobFiles {
            root: data.join("jobs"),
            open: Mutex::new(HashMap::new()),
        })
    }

    fn lock(&self) -> MutexGuard<'_, HashMap<String, (i64, McapWriter)>> {
        self.open.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The folder of a job.
    pub fn dir(&self, id: &str) -> PathBuf {
        self.root.join(id)
    }

    /// The MCAP file of a job.
    pub fn mcap_path(&self, id: &str) -> PathBuf {
        self.dir(id).join("fields.mcap")
    }

    /// A claim under `fence` starts: drop any earlier writer and file, open a fresh file.
    pub fn start(
        &self,
        id: &str,
        fence: i64,
        scene: Option<&fracture_api::Scene>,
    ) -> std::io::Result<()> {
        let old = self.lock().remove(id);
        if let Some((_, mut w)) = old {
            let _ = w.finish();
        }
        let dir = self.dir(id);
        std::fs::create_dir_all(&dir)?;
        let path = self.mcap_path(id);
        let _ = std::fs::remove_file(&path);
        let mut w = McapWriter::create(&path).map_err(|e| std::io::Error::other(e.to_string()))?;
        if let Some(scene) = scene {
            w.write_scene(scene)
                .map_err(|e| std::io::Error::other(e.to_string()))?;
        }
        self.lock().insert(id.to_string(), (fence, w));
        Ok(())
    }

    /// Write to the job's file if it is open under `fence` (otherwise the write is stale
    /// and was already refused by the store, or the file was closed by a shutdown).
    pub fn write(&self, id: &str, fence: i64, rec: Record) -> std::io::Result<()> {
        let mut open = self.lock();
        let Some((f, w)) = open.get_mut(id) else {
            return Ok(());
        };
        if *f != fence {
            return Ok(());
        }
        let r = match &rec {
            Record::Energy(rows) => w.write_energy(rows),
            Record::CrackTips(rows) => w.write_crack_tips(rows),
            Record::Snapshot(s) => w.write_snapshot(s),
        };
        r.map_err(|e| std::io::Error::other(e.to_string()))
    }

    /// Finish the job's file (summary and index written: a valid MCAP).
    pub fn finish(&self, id: &str) -> std::io::Result<()> {
        let w = self.lock().remove(id);
        if let Some((_, mut w)) = w {
            w.finish()
                .map_err(|e| std::io::Error::other(e.to_string()))?;
        }
        Ok(())
    }

    /// Finish every open file (shutdown).
    pub fn finish_all(&self) {
        let all: Vec<(String, (i64, McapWriter))> = self.lock().drain().collect();
        for (id, (_, mut w)) in all {
            if let Err(e) = w.finish() {
                tracing::warn!(job = %id, error = %e, "could not finish MCAP file");
            }
        }
    }

    /// Remove a job's folder.
    pub fn delete(&self, id: &str) -> std::io::Result<()> {
        let w = self.lock().remove(id);
        drop(w);
        match std::fs::remove_dir_all(self.dir(id)) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
            r => r,
        }
    }
}
