//! Each job's results folder `<data>/jobs/<id>/` and its `fields.mcap`, written only by the
//! server: one open [`McapWriter`] per running job, keyed by the claim's fence. A new claim
//! (a re-run after a lost worker) restarts the file, so nothing is written twice.
//!
//! The database is the record of a run (rows and snapshots are served from it); the MCAP
//! file is its export. A file that cannot be written (a full disk) is therefore given up
//! rather than failing the run: its writer is dropped, the partial file removed, and the
//! reason kept ([`JobFiles::broken`]) for the download route to report. A deletion
//! removes a job's folder only after its row is gone; a folder whose removal failed is an
//! orphan that [`JobFiles::remove_orphans`] removes at the next start.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, MutexGuard};

use fracture_api::results::{CrackTipRow, EnergyRow, Snapshot};
use fracture_results::mcapfile::McapWriter;

/// The results folders and open MCAP writers.
pub struct JobFiles {
    root: PathBuf,
    open: Mutex<HashMap<String, (i64, McapWriter)>>,
    broken: Mutex<HashMap<String, String>>,
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
            broken: Mutex::new(HashMap::new()),
        })
    }

    /// Why the job's MCAP file was given up (it could not be written), if it was.
    pub fn broken(&self, id: &str) -> Option<String> {
        self.broken
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .get(id)
            .cloned()
    }

    /// Give up the job's file after a failed write: drop the writer and the partial file,
    /// remember why.
    fn give_up(&self, id: &str, why: &std::io::Error) {
        let w = self.lock().remove(id);
        drop(w);
        let _ = std::fs::remove_file(self.mcap_path(id));
        tracing::warn!(job = %id, error = %why, "MCAP file given up (its rows stay in the database)");
        self.broken
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .insert(id.to_string(), why.to_string());
    }

    /// Remove the folders of jobs that are not in `known` (a deletion whose file removal
    /// failed, or a crash between the two). Returns how many were removed.
    pub fn remove_orphans(&self, known: &std::collections::HashSet<String>) -> usize {
        let Ok(entries) = std::fs::read_dir(&self.root) else {
            return 0;
        };
        let mut n = 0;
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            if !known.contains(&name) && e.path().is_dir() {
                match std::fs::remove_dir_all(e.path()) {
                    Ok(()) => n += 1,
                    Err(err) => {
                        tracing::warn!(job = %name, error = %err, "cannot remove an orphaned results folder")
                    }
                }
            }
        }
        n
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
    /// A file that cannot be created is given up (the run goes on; see the module docs).
    pub fn start(
        &self,
        id: &str,
        fence: i64,
        scene: Option<&fracture_api::AnyScene>,
    ) -> std::io::Result<()> {
        let old = self.lock().remove(id);
        if let Some((_, mut w)) = old {
            let _ = w.finish();
        }
        self.broken
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .remove(id);
        let r = self.open_file(id, fence, scene);
        if let Err(e) = &r {
            self.give_up(id, e);
        }
        r
    }

    fn open_file(
        &self,
        id: &str,
        fence: i64,
        scene: Option<&fracture_api::AnyScene>,
    ) -> std::io::Result<()> {
        let dir = self.dir(id);
        std::fs::create_dir_all(&dir)?;
        let path = self.mcap_path(id);
        let _ = std::fs::remove_file(&path);
        let mut w = McapWriter::create(&path).map_err(io_error)?;
        if let Some(scene) = scene {
            w.write_scene_parts(scene.name(), &scene.hash(), &scene.canonical_json())
                .map_err(io_error)?;
        }
        self.lock().insert(id.to_string(), (fence, w));
        Ok(())
    }

    /// Write to the job's file if it is open under `fence` (otherwise the write is stale
    /// and was already refused by the store, or the file was closed by a shutdown). A
    /// failed write gives the file up (see the module docs) and is returned.
    pub fn write(&self, id: &str, fence: i64, rec: Record) -> std::io::Result<()> {
        let r = {
            let mut open = self.lock();
            let Some((f, w)) = open.get_mut(id) else {
                return Ok(());
            };
            if *f != fence {
                return Ok(());
            }
            match &rec {
                Record::Energy(rows) => w.write_energy(rows),
                Record::CrackTips(rows) => w.write_crack_tips(rows),
                Record::Snapshot(s) => w.write_snapshot(s),
            }
            .map_err(io_error)
        };
        if let Err(e) = &r {
            self.give_up(id, e);
        }
        r
    }

    /// Finish the job's file (summary and index written: a valid MCAP).
    pub fn finish(&self, id: &str) -> std::io::Result<()> {
        let w = self.lock().remove(id);
        if let Some((_, mut w)) = w
            && let Err(e) = w.finish().map_err(io_error)
        {
            self.give_up(id, &e);
            return Err(e);
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

    /// Remove a job's folder (after its row is gone).
    pub fn delete(&self, id: &str) -> std::io::Result<()> {
        let w = self.lock().remove(id);
        drop(w);
        self.broken
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .remove(id);
        match std::fs::remove_dir_all(self.dir(id)) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
            r => r,
        }
    }
}

/// An MCAP writer's error as an I/O error, keeping the OS error code of the I/O error under
/// it (so a full disk stays recognisable: `crate::error::storage_fault`).
fn io_error(e: fracture_results::mcapfile::McapFileError) -> std::io::Error {
    let mut cur: Option<&(dyn std::error::Error + 'static)> = Some(&e);
    while let Some(err) = cur {
        if let Some(io) = err.downcast_ref::<std::io::Error>() {
            if let Some(code) = io.raw_os_error() {
                return std::io::Error::from_raw_os_error(code);
            }
            return std::io::Error::new(io.kind(), e.to_string());
        }
        cur = err.source();
    }
    std::io::Error::other(e.to_string())
}
