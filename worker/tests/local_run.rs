//! `run_scene` with the real solver into `LocalOutput`: the run directory of
//! `run-output.md` (names, headers, columns), cancellation, sink failures.
#![allow(clippy::unwrap_used, missing_docs)]

use std::path::{Path, PathBuf};
use std::time::Duration;

use fracture_api::Scene;
use fracture_api::results::{
    CRACK_TIPS_CSV_HEADER, CrackTipRow, ENERGY_CSV_HEADER, EnergyRow, FieldComponent, Progress,
    RunStatus, Snapshot, Summary,
};
use fracture_results::mcapfile::McapContents;
use fracture_worker::{Control, LocalOutput, RunOptions, RunSink, SinkError, run_scene};

fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes")
        .join(name)
}

fn load(name: &str) -> Scene {
    let text = std::fs::read_to_string(scene_path(name)).unwrap();
    fracture_api::validate::parse_scene(&text).unwrap()
}

fn opts() -> RunOptions {
    RunOptions {
        threads: fracture_solver::Parallelism::threads(1),
        flush_every: Duration::from_millis(50),
    }
}

fn lines(path: &Path) -> Vec<String> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(String::from)
        .collect()
}

#[test]
fn local_output_writes_the_run_output_files() {
    // The sink alone, with rows of every kind: exact headers, column counts, values.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let mut sink = LocalOutput::create(&out).unwrap();
    let e = EnergyRow {
        time: 1.0e-6,
        kinetic: 2.0,
        strain: 3.0,
        external_work: 4.0,
        dissipated: 0.5,
        total_error: -0.25,
        fracture: 0.125,
    };
    let t = CrackTipRow {
        time: 1.0e-6,
        crack: 1,
        tip: 0,
        x: 0.01,
        y: 0.02,
        length: 0.003,
        speed: 500.0,
        j1: 100.0,
        j2: -5.0,
        k1: 1.0e6,
        k2: 2.0e4,
        growing: true,
        j1_half: 101.0,
        j2_half: -4.0,
        j1_double: 99.0,
        j2_double: -6.0,
        k1_cod: 1.1e6,
        k2_cod: 3.0e4,
        zone_x: 0.021,
        zone_y: 0.0275,
        connected_x: 0.019,
        connected_y: 0.0275,
        zone_connected_x: 0.0205,
        zone_connected_y: 0.0275,
    };
    sink.energy(&[e, e]).unwrap();
    sink.crack_tips(&[t]).unwrap();
    sink.snapshot(&Snapshot {
        index: 0,
        time: 1.0e-6,
        nx: 2,
        ny: 2,
        origin: [0.0; 2],
        cell_size: 1.0e-3,
        fields: vec!["fringe".into()],
        components: vec![FieldComponent {
            name: "fringe".into(),
            values: vec![0.0, 1.0, f32::NAN, 3.0],
        }],
        cracks: vec![],
        particles: None,
        slice: None,
    })
    .unwrap();
    // Flushed as it goes: readable before finish.
    assert_eq!(lines(&out.join("energy.csv")).len(), 3);
    assert!(!out.join("summary.json").exists());
    let summary = Summary {
        status: RunStatus::Completed,
        message: None,
        failure: None,
        steps: 10,
        time_step: 1.0e-7,
        sim_time: 1.0e-6,
        particles: 4,
        grid_nodes: 4,
        active_nodes_mean: 4.0,
        wall_seconds: 0.1,
        particle_steps_per_second: 400.0,
        threads: 1,
        scene_hash: "abc".into(),
        solver_version: "0.1.0".into(),
        fracture: None,
        provenance: None,
        tips: Vec::new(),
        references: Vec::new(),
        dimension: None,
    };
    sink.finish(&summary).unwrap();

    let energy = lines(&out.join("energy.csv"));
    assert_eq!(
        energy[0],
        "time,kinetic,strain,external_work,dissipated,total_error,fracture"
    );
    assert_eq!(energy[0], ENERGY_CSV_HEADER);
    assert_eq!(energy.len(), 3);
    let cols: Vec<f64> = energy[1].split(',').map(|c| c.parse().unwrap()).collect();
    assert_eq!(cols, vec![1.0e-6, 2.0, 3.0, 4.0, 0.5, -0.25, 0.125]);

    let tips = lines(&out.join("crack_tips.csv"));
    // run-output.md's columns first; the project's extension columns after them.
    assert!(
        tips[0].starts_with("time,crack,tip,x,y,length,speed,j1,j2,k1,k2,growing,"),
        "{}",
        tips[0]
    );
    assert_eq!(tips[0], CRACK_TIPS_CSV_HEADER);
    assert_eq!(tips.len(), 2);
    let cols: Vec<&str> = tips[1].split(',').collect();
    assert_eq!(cols.len(), 24);
    assert_eq!((cols[1], cols[2], cols[11]), ("1", "0", "1"));
    assert_eq!(cols[6].parse::<f64>().unwrap(), 500.0);
    assert_eq!(cols[18].parse::<f64>().unwrap(), 0.021);
    assert_eq!(cols[20].parse::<f64>().unwrap(), 0.019);

    let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    for key in [
        "status",
        "steps",
        "time_step",
        "sim_time",
        "particles",
        "grid_nodes",
        "active_nodes_mean",
        "wall_seconds",
        "particle_steps_per_second",
        "threads",
        "scene_hash",
        "solver_version",
    ] {
        assert!(v.get(key).is_some(), "summary.json lacks {key}: {text}");
    }
    assert_eq!(v["status"], "completed");
    assert_eq!(serde_json::from_value::<Summary>(v).unwrap(), summary);

    let m = McapContents::read(out.join("fields.mcap")).unwrap();
    assert!(!m.truncated);
    assert_eq!(m.energy, vec![e, e]);
    assert_eq!(m.crack_tips, vec![t]);
    assert_eq!(m.snapshots.len(), 1);
    assert!(m.snapshots[0].components[0].values[2].is_nan());
}

#[test]
fn impact_bar_run_writes_the_run_directory() {
    let scene = load("impact-bar.json");
    let size = fracture_api::validate::validate(&scene).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let mut sink = LocalOutput::create(dir.path()).unwrap();
    sink.write_scene(&scene).unwrap();
    let s = run_scene(
        &fracture_api::ValidScene::new(scene.clone()).unwrap(),
        &opts(),
        &mut sink,
    );
    assert_eq!(s.status, RunStatus::Completed, "{s:?}");
    assert_eq!(s.steps, size.steps);
    assert_eq!(s.particles, size.particles);
    assert_eq!(s.grid_nodes, size.grid_nodes);
    assert!((s.time_step - size.time_step).abs() <= 1e-12 * size.time_step);
    assert!(s.active_nodes_mean > 0.0);
    assert!(s.particle_steps_per_second > 0.0);
    assert_eq!(s.threads, 1);
    assert_eq!(s.scene_hash, scene.hash());

    let on_disk: Summary =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(on_disk, s);

    // History every 0.25 µs over 15 µs: t = 0 and 60 more samples (one more at most if
    // the last step overshoots a sample time by rounding).
    let energy = lines(&dir.path().join("energy.csv"));
    assert_eq!(energy[0], ENERGY_CSV_HEADER);
    let n = energy.len() - 1;
    assert!((61..=62).contains(&n), "{n} energy rows");
    for l in &energy[1..] {
        let cols: Vec<f64> = l.split(',').map(|c| c.parse().unwrap()).collect();
        assert_eq!(cols.len(), 7, "{l}");
        assert!(cols.iter().all(|c| c.is_finite()), "{l}");
    }
    // The bar is being struck: kinetic energy grows from zero.
    let last: Vec<f64> = energy[n].split(',').map(|c| c.parse().unwrap()).collect();
    assert!(last[1] > 0.0, "kinetic energy at the end: {}", energy[n]);
    // No cracks: header only.
    assert_eq!(
        lines(&dir.path().join("crack_tips.csv")),
        vec![CRACK_TIPS_CSV_HEADER.to_string()]
    );

    // Snapshots at 0, 5, 10 (and 15) µs with stress and velocity components.
    let m = McapContents::read(dir.path().join("fields.mcap")).unwrap();
    assert_eq!(m.energy.len(), n);
    assert!(
        (3..=4).contains(&m.snapshots.len()),
        "{}",
        m.snapshots.len()
    );
    for (k, snap) in m.snapshots.iter().enumerate() {
        assert_eq!(snap.index, k as u32);
        // Taken at the first step at or after k · 5 µs.
        let due = 5.0e-6 * k as f64;
        assert!(
            snap.time >= due - 1e-6 * s.time_step && snap.time < due + s.time_step,
            "snapshot {k} at {}",
            snap.time
        );
        for c in ["sxx", "syy", "sxy", "vx", "vy", "speed"] {
            let comp = snap.component(c).unwrap();
            assert_eq!(comp.values.len(), (snap.nx * snap.ny) as usize);
        }
    }
    assert_eq!(m.scene.unwrap()["hash"], scene.hash());
}

/// Wraps a sink: cancels at the first progress report, or fails on the first snapshot.
struct Meddle<S> {
    inner: S,
    cancel: bool,
    fail_snapshot: bool,
    progress_calls: usize,
}

impl<S: RunSink> RunSink for Meddle<S> {
    fn progress(&mut self, p: &Progress) -> Result<Control, SinkError> {
        self.progress_calls += 1;
        self.inner.progress(p)?;
        Ok(if self.cancel {
            Control::Cancel
        } else {
            Control::Continue
        })
    }
    fn energy(&mut self, rows: &[EnergyRow]) -> Result<(), SinkError> {
        self.inner.energy(rows)
    }
    fn crack_tips(&mut self, rows: &[CrackTipRow]) -> Result<(), SinkError> {
        self.inner.crack_tips(rows)
    }
    fn snapshot(&mut self, snap: &Snapshot) -> Result<(), SinkError> {
        if self.fail_snapshot {
            return Err(SinkError("no space left on device".into()));
        }
        self.inner.snapshot(snap)
    }
    fn finish(&mut self, summary: &Summary) -> Result<(), SinkError> {
        self.inner.finish(summary)
    }
}

#[test]
fn cancel_ends_the_run_cancelled_and_keeps_the_files() {
    let scene = load("impact-bar.json");
    let size = fracture_api::validate::validate(&scene).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let mut sink = Meddle {
        inner: LocalOutput::create(dir.path()).unwrap(),
        cancel: true,
        fail_snapshot: false,
        progress_calls: 0,
    };
    let opts = RunOptions {
        threads: fracture_solver::Parallelism::threads(1),
        flush_every: Duration::ZERO,
    };
    let s = run_scene(
        &fracture_api::ValidScene::new(scene.clone()).unwrap(),
        &opts,
        &mut sink,
    );
    assert_eq!(s.status, RunStatus::Cancelled, "{s:?}");
    assert_eq!(s.steps, 1, "cancelled at the first report, after one step");
    assert!(s.steps < size.steps);
    let on_disk: Summary =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(on_disk.status, RunStatus::Cancelled);
    // t = 0 sample and the snapshot at t = 0 are there.
    assert!(lines(&dir.path().join("energy.csv")).len() >= 2);
    let m = McapContents::read(dir.path().join("fields.mcap")).unwrap();
    assert_eq!(m.snapshots.len(), 1);
}

#[test]
fn a_sink_error_ends_the_run_failed() {
    let scene = load("impact-bar.json");
    let dir = tempfile::tempdir().unwrap();
    let mut sink = Meddle {
        inner: LocalOutput::create(dir.path()).unwrap(),
        cancel: false,
        fail_snapshot: true,
        progress_calls: 0,
    };
    let s = run_scene(
        &fracture_api::ValidScene::new(scene.clone()).unwrap(),
        &opts(),
        &mut sink,
    );
    assert_eq!(s.status, RunStatus::Failed);
    let msg = s.message.clone().unwrap();
    assert!(msg.contains("no space left on device"), "{msg}");
    // The snapshot at t = 0 failed: no step was taken, and the summary still got written.
    assert_eq!(s.steps, 0);
    let on_disk: Summary =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(on_disk, s);
    assert_eq!(sink.progress_calls, 0, "no progress to a broken sink");
}

#[test]
fn free_flight_keeps_its_momentum() {
    let scene = load("free-flight.json");
    let dir = tempfile::tempdir().unwrap();
    let mut sink = LocalOutput::create(dir.path()).unwrap();
    let s = run_scene(
        &fracture_api::ValidScene::new(scene.clone()).unwrap(),
        &opts(),
        &mut sink,
    );
    assert_eq!(s.status, RunStatus::Completed, "{s:?}");
    let m = McapContents::read(dir.path().join("fields.mcap")).unwrap();
    // ½ρAt|v|² = 0.5 · 1230 · 1e-4 · 1e-3 · 29 J, constant; no strain energy.
    let ke = 0.5 * 1230.0 * 1.0e-4 * 1.0e-3 * 29.0;
    assert!(m.energy.len() >= 21);
    for e in &m.energy {
        assert!((e.kinetic - ke).abs() < 1e-6 * ke, "{e:?}");
        assert!(e.strain.abs() < 1e-9 * ke, "{e:?}");
    }
    // Snapshots at 0, 10, 20 µs carry the velocity, displacement and material fields.
    assert!((2..=3).contains(&m.snapshots.len()));
    let snap = &m.snapshots[0];
    let vx = snap.component("vx").unwrap();
    assert!(vx.values.iter().any(|v| (v - 5.0).abs() < 1e-4));
    assert!(snap.component("ux").is_some());
    assert!(snap.component("material").is_some());
}

#[test]
fn crack_tips_get_one_row_per_tip_per_sample() {
    // A centre crack in a small plate pulled on two edges; history every 1 µs.
    let scene = fracture_api::validate::parse_scene(
        r#"{"name": "center-crack",
            "grid": {"cell_size": 0.001, "min": [0, 0], "max": [0.04, 0.04]},
            "materials": {"plate": {"model": "linear_elastic", "density": 1230.0,
                                     "youngs_modulus": 5.2e9, "poissons_ratio": 0.34}},
            "bodies": [{"material": "plate",
                        "region": {"rectangle": {"min": [0.004, 0.004], "max": [0.036, 0.036]}}}],
            "cracks": [{"points": [[0.016, 0.0205], [0.024, 0.0205]]}],
            "loads": [
              {"region": {"rectangle": {"min": [0.004, 0.035], "max": [0.036, 0.036]}},
               "traction": [0, 1e6]},
              {"region": {"rectangle": {"min": [0.004, 0.004], "max": [0.036, 0.005]}},
               "traction": [0, -1e6]}],
            "time": {"end": 5e-6},
            "output": {"history_interval": 1e-6}}"#,
    )
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let mut sink = LocalOutput::create(dir.path()).unwrap();
    let s = run_scene(
        &fracture_api::ValidScene::new(scene.clone()).unwrap(),
        &opts(),
        &mut sink,
    );
    assert_eq!(s.status, RunStatus::Completed, "{s:?}");
    let energy = lines(&dir.path().join("energy.csv"));
    let tips = lines(&dir.path().join("crack_tips.csv"));
    assert_eq!(tips[0], CRACK_TIPS_CSV_HEADER);
    // Two tips (both ends lie inside the plate) per history sample.
    assert_eq!(tips.len() - 1, 2 * (energy.len() - 1));
    for (i, l) in tips[1..].iter().enumerate() {
        let cols: Vec<&str> = l.split(',').collect();
        assert_eq!(cols.len(), CRACK_TIPS_CSV_HEADER.split(',').count(), "{l}");
        assert_eq!(cols[1], "0", "{l}");
        assert_eq!(cols[2], (i % 2).to_string(), "{l}");
        assert!(cols[11] == "0" || cols[11] == "1", "{l}");
        // Same time as the energy sample it belongs to.
        let t: f64 = cols[0].parse().unwrap();
        let te: f64 = energy[1 + i / 2]
            .split(',')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        assert_eq!(t, te);
    }
    let m = McapContents::read(dir.path().join("fields.mcap")).unwrap();
    assert_eq!(m.crack_tips.len(), tips.len() - 1);
}
