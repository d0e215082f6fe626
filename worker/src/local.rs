//! The run directory of a local run (`docs/run-output.md`): `summary.json`, `energy.csv`,
//! `crack_tips.csv`, `fields.mcap`, and `path.svg` (the crack-path picture) for scenes with
//! cracks.
//!
//! Every batch is written through to the files as it arrives (CSV flushed, MCAP flushed at
//! each snapshot), so a run that fails or is killed leaves what it had produced.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use fracture_api::Scene;
use fracture_api::results::{
    CRACK_TIPS_CSV_HEADER, CrackTipRow, ENERGY_CSV_HEADER, EnergyRow, Progress, Snapshot, Summary,
    Volume,
};

use crate::{Control, RunSink, SinkError};
use fracture_results::mcapfile::{McapFileError, McapWriter};
use fracture_results::path::PathRecorder;

/// File name of the summary.
pub const SUMMARY_FILE: &str = "summary.json";
/// File name of the energy history.
pub const ENERGY_FILE: &str = "energy.csv";
/// File name of the crack-tip history.
pub const CRACK_TIPS_FILE: &str = "crack_tips.csv";
/// File name of the MCAP file.
pub const FIELDS_FILE: &str = "fields.mcap";
/// File name of the crack-path picture.
pub const PATH_FILE: &str = "path.svg";
/// The files (and folders) a run writes in its directory, what `fracture run --force`
/// replaces: the four of `run-output.md`, the path picture, and the VTK series.
pub const RUN_FILES: &[&str] = &[
    SUMMARY_FILE,
    ENERGY_FILE,
    CRACK_TIPS_FILE,
    FIELDS_FILE,
    PATH_FILE,
    "vtk",
    ".summary.json.tmp",
];

/// Why the run directory could not be written.
#[derive(Debug, thiserror::Error)]
pub enum LocalOutputError {
    /// A file could not be created or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The error.
        source: std::io::Error,
    },
    /// The MCAP file could not be written.
    #[error("{path}: {source}")]
    Mcap {
        /// The file.
        path: PathBuf,
        /// The error.
        source: McapFileError,
    },
}

impl From<LocalOutputError> for SinkError {
    fn from(e: LocalOutputError) -> Self {
        SinkError(e.to_string())
    }
}

/// A [`RunSink`] writing the run directory. Progress reports are accepted and ignored
/// (wrap it to show them); it never cancels.
pub struct LocalOutput {
    dir: PathBuf,
    energy: BufWriter<File>,
    crack_tips: BufWriter<File>,
    mcap: McapWriter,
    finished: bool,
    /// The scene, once [`LocalOutput::write_scene`] gave it: `path.svg` is drawn from it.
    scene: Option<Scene>,
    /// Every tip's path, for `path.svg`.
    paths: PathRecorder,
    /// A 3D run's VTK volumes, when asked for ([`LocalOutput::write_volumes`]).
    volumes: Option<VolumeSeries>,
}

/// Where a 3D run's VTK volumes go and what was written.
struct VolumeSeries {
    dir: PathBuf,
    volumes: Vec<(f64, String)>,
    particles: Vec<(f64, String)>,
}

impl LocalOutput {
    /// Create `dir` (and parents) and the files, with their CSV header rows. Existing files
    /// of a previous run are replaced; a stale `summary.json` is removed at once, so the
    /// directory never shows an old summary beside new histories.
    pub fn create(dir: impl AsRef<Path>) -> Result<Self, LocalOutputError> {
        let dir = dir.as_ref().to_path_buf();
        let io = |path: &Path| {
            let path = path.to_path_buf();
            move |source| LocalOutputError::Io { path, source }
        };
        std::fs::create_dir_all(&dir).map_err(io(&dir))?;
        let summary = dir.join(SUMMARY_FILE);
        match std::fs::remove_file(&summary) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => return Err(io(&summary)(e)),
        }
        let csv = |name: &str, header: &str| -> Result<BufWriter<File>, LocalOutputError> {
            let path = dir.join(name);
            let file = File::create(&path).map_err(io(&path))?;
            let mut w = BufWriter::new(file);
            writeln!(w, "{header}").map_err(io(&path))?;
            w.flush().map_err(io(&path))?;
            Ok(w)
        };
        let energy = csv(ENERGY_FILE, ENERGY_CSV_HEADER)?;
        let crack_tips = csv(CRACK_TIPS_FILE, CRACK_TIPS_CSV_HEADER)?;
        let mcap_path = dir.join(FIELDS_FILE);
        let mcap = McapWriter::create(&mcap_path).map_err(|source| LocalOutputError::Mcap {
            path: mcap_path.clone(),
            source,
        })?;
        Ok(LocalOutput {
            dir,
            energy,
            crack_tips,
            mcap,
            finished: false,
            scene: None,
            paths: PathRecorder::new(),
            volumes: None,
        })
    }

    /// Also record the scene in `fields.mcap` (metadata record `scene`).
    /// It also lets the run's end draw `path.svg` (scenes with cracks or interfaces).
    pub fn write_scene(&mut self, scene: &Scene) -> Result<(), LocalOutputError> {
        self.scene = Some(scene.clone());
        self.mcap
            .write_scene(scene)
            .map_err(|source| self.mcap_error(source))
    }

    /// Record a 3D scene in `fields.mcap` (its metadata record, as [`LocalOutput::write_scene`]).
    pub fn write_scene3(&mut self, scene: &fracture_api::Scene3) -> Result<(), LocalOutputError> {
        self.mcap
            .write_scene_parts(&scene.name, &scene.hash(), &scene.canonical_json())
            .map_err(|source| self.mcap_error(source))
    }

    /// Write a 3D run's fields on its whole grid as VTK files into `dir` (created): one
    /// `volume_NNNNN.vti` per snapshot time, `particles_NNNNN.vtu` when the scene records
    /// particles, and at the end `volumes.pvd` and `particles.pvd` (`three-d.md`, `--vtk`).
    pub fn write_volumes(&mut self, dir: impl AsRef<Path>) -> Result<(), LocalOutputError> {
        let dir = dir.as_ref().to_path_buf();
        std::fs::create_dir_all(&dir).map_err(|source| LocalOutputError::Io {
            path: dir.clone(),
            source,
        })?;
        self.volumes = Some(VolumeSeries {
            dir,
            volumes: Vec::new(),
            particles: Vec::new(),
        });
        Ok(())
    }

    /// The run directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    fn io_error(&self, name: &str, source: std::io::Error) -> LocalOutputError {
        LocalOutputError::Io {
            path: self.dir.join(name),
            source,
        }
    }

    fn mcap_error(&self, source: McapFileError) -> LocalOutputError {
        LocalOutputError::Mcap {
            path: self.dir.join(FIELDS_FILE),
            source,
        }
    }

    /// Write `summary.json` (pretty JSON, newline-terminated) atomically: to a temporary
    /// file, then renamed.
    fn write_summary(&self, summary: &Summary) -> Result<(), LocalOutputError> {
        let path = self.dir.join(SUMMARY_FILE);
        let tmp = self.dir.join(".summary.json.tmp");
        let mut text = serde_json::to_string_pretty(summary)
            .map_err(|e| self.io_error(SUMMARY_FILE, std::io::Error::other(e)))?;
        text.push('\n');
        std::fs::write(&tmp, text).map_err(|e| self.io_error(SUMMARY_FILE, e))?;
        std::fs::rename(&tmp, &path).map_err(|e| self.io_error(SUMMARY_FILE, e))
    }
}

impl RunSink for LocalOutput {
    fn progress(&mut self, _p: &Progress) -> Result<Control, SinkError> {
        Ok(Control::Continue)
    }

    fn energy(&mut self, rows: &[EnergyRow]) -> Result<(), SinkError> {
        for r in rows {
            writeln!(self.energy, "{}", r.to_csv()).map_err(|e| self.io_error(ENERGY_FILE, e))?;
        }
        self.energy
            .flush()
            .map_err(|e| self.io_error(ENERGY_FILE, e))?;
        self.mcap
            .write_energy(rows)
            .map_err(|e| self.mcap_error(e))?;
        Ok(())
    }

    fn crack_tips(&mut self, rows: &[CrackTipRow]) -> Result<(), SinkError> {
        for r in rows {
            writeln!(self.crack_tips, "{}", r.to_csv())
                .map_err(|e| self.io_error(CRACK_TIPS_FILE, e))?;
        }
        self.crack_tips
            .flush()
            .map_err(|e| self.io_error(CRACK_TIPS_FILE, e))?;
        self.paths.extend(rows);
        self.mcap
            .write_crack_tips(rows)
            .map_err(|e| self.mcap_error(e))?;
        Ok(())
    }

    fn snapshot(&mut self, snap: &Snapshot) -> Result<(), SinkError> {
        self.mcap
            .write_snapshot(snap)
            .map_err(|e| self.mcap_error(e))?;
        Ok(())
    }

    fn wants_volumes(&self) -> bool {
        self.volumes.is_some()
    }

    fn volume(&mut self, volume: &Volume) -> Result<(), SinkError> {
        let Some(series) = self.volumes.as_mut() else {
            return Ok(());
        };
        let k = series.volumes.len();
        let files = fracture_results::vtk3::volume_files(volume, k)
            .map_err(|e| SinkError(format!("VTK volume {k}: {e}")))?;
        for (name, bytes) in files {
            let path = series.dir.join(&name);
            std::fs::write(&path, bytes)
                .map_err(|e| SinkError(format!("writing {}: {e}", path.display())))?;
            if name.ends_with(".vti") {
                series.volumes.push((volume.time, name));
            } else {
                series.particles.push((volume.time, name));
            }
        }
        Ok(())
    }

    fn finish(&mut self, summary: &Summary) -> Result<(), SinkError> {
        if self.finished {
            return Ok(());
        }
        self.finished = true;
        let volumes = match &self.volumes {
            Some(series) => {
                let mut r = Ok(());
                for (name, entries) in [
                    ("volumes.pvd", &series.volumes),
                    ("particles.pvd", &series.particles),
                ] {
                    if entries.is_empty() {
                        continue;
                    }
                    let path = series.dir.join(name);
                    if let Err(e) = std::fs::write(&path, fracture_results::vtk::pvd(entries)) {
                        r = Err(SinkError(format!("writing {}: {e}", path.display())));
                    }
                }
                r
            }
            None => Ok(()),
        };
        // Finish every file even if one fails; report the first failure.
        let energy = self
            .energy
            .flush()
            .map_err(|e| self.io_error(ENERGY_FILE, e));
        let tips = self
            .crack_tips
            .flush()
            .map_err(|e| self.io_error(CRACK_TIPS_FILE, e));
        let mcap = self.mcap.finish().map_err(|e| self.mcap_error(e));
        let path = match &self.scene {
            Some(scene) if !(scene.cracks.is_empty() && scene.interfaces.is_empty()) => {
                let svg = fracture_results::path::path_svg(scene, self.paths.paths());
                std::fs::write(self.dir.join(PATH_FILE), svg)
                    .map_err(|e| self.io_error(PATH_FILE, e))
            }
            _ => Ok(()),
        };
        let summary = self.write_summary(summary);
        volumes?;
        path?;
        energy?;
        tips?;
        mcap?;
        summary?;
        Ok(())
    }
}
