//! The `fracture` binary's local commands (`api.md`, command line; `run-output.md`):
//! invalid scenes exit 2 naming the JSON path, `run` writes the four files with the exact
//! headers, `validate` prints the size, `schema` prints JSON, `bench` runs CI-sized.
#![allow(clippy::unwrap_used, missing_docs)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::{Value, json};

fn fracture(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_fracture"))
        .args(args)
        .output()
        .unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes")
}

/// A tiny valid scene: 8 mm × 8 mm plate, 1 mm cells, a few steps.
fn tiny() -> Value {
    json!({
        "name": "tiny",
        "grid": {"cell_size": 0.001, "min": [0.0, 0.0], "max": [0.01, 0.01]},
        "materials": {"plate": {"model": "linear_elastic", "density": 1230.0,
                                "youngs_modulus": 5.2e9, "poissons_ratio": 0.34}},
        "bodies": [{"material": "plate",
                    "region": {"rectangle": {"min": [0.002, 0.002], "max": [0.008, 0.008]}},
                    "initial_velocity": [1.0, 0.0]}],
        "time": {"end": 2.0e-6},
        "output": {"snapshot_interval": 1.0e-6}
    })
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Run `validate` and `run` on a broken scene: both exit 2 and name `path` (and `value`).
fn assert_invalid(text: &str, path: &str, value: &str) {
    let dir = tempfile::tempdir().unwrap();
    let file = write(dir.path(), "scene.json", text);
    let f = file.to_str().unwrap();
    for args in [
        vec!["validate", f],
        vec!["run", f, "--out", dir.path().join("out").to_str().unwrap()],
    ] {
        let o = fracture(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains(path),
            "{args:?}: stderr does not name {path}: {err}"
        );
        assert!(
            err.contains(value),
            "{args:?}: stderr does not show {value}: {err}"
        );
    }
}

fn with(f: impl FnOnce(&mut Value)) -> String {
    let mut s = tiny();
    f(&mut s);
    s.to_string()
}

#[test]
fn poissons_ratio_out_of_range_is_named() {
    let text = with(|s| s["materials"]["plate"]["poissons_ratio"] = json!(0.7));
    assert_invalid(
        &text,
        "materials.plate.poissons_ratio: 0.7 is outside (-1, 0.5)",
        "0.7",
    );
}

#[test]
fn bad_constants_are_named() {
    let text = with(|s| {
        s["materials"]["plate"]["youngs_modulus"] = json!(-1.0);
        s["materials"]["plate"]["density"] = json!(0.0);
    });
    assert_invalid(&text, "materials.plate.youngs_modulus", "-1");
    assert_invalid(&text, "materials.plate.density", "0");
}

#[test]
fn body_outside_the_grid_is_named() {
    let text = with(|s| s["bodies"][0]["region"]["rectangle"]["max"] = json!([0.02, 0.008]));
    assert_invalid(&text, "bodies.0.region", "0.02");
}

#[test]
fn empty_body_is_named() {
    // A disc smaller than a sub-cell, between particle centres: no particle.
    let text = with(|s| {
        s["bodies"][0]["region"] = json!({"circle": {"center": [0.005, 0.005], "radius": 1.0e-5}})
    });
    assert_invalid(&text, "bodies.0.region", "no particle");
}

#[test]
fn cfl_out_of_range_is_named() {
    let text = with(|s| s["time"]["cfl"] = json!(1.5));
    assert_invalid(&text, "time.cfl", "1.5");
}

#[test]
fn negative_time_is_named() {
    let text = with(|s| s["time"]["end"] = json!(-1.0e-6));
    assert_invalid(&text, "time.end", "-1e-6");
}

#[test]
fn unknown_material_is_named() {
    let text = with(|s| s["bodies"][0]["material"] = json!("steel"));
    assert_invalid(&text, "bodies.0.material", "steel");
}

#[test]
fn unknown_field_is_named() {
    let text = with(|s| s["grid"]["cellsize"] = json!(0.001));
    assert_invalid(&text, "grid", "cellsize");
    let text = with(|s| s["output"]["fields"] = json!(["stress", "temperature"]));
    assert_invalid(&text, "output.fields", "temperature");
}

#[test]
fn malformed_json_is_reported() {
    let text = tiny().to_string();
    let cut = &text[..text.len() - 10];
    assert_invalid(cut, "scene.json", "EOF");
    assert_invalid("{\"name\": \"x\",, }", "scene.json", "line 1");
}

#[test]
fn missing_file_exits_2() {
    let o = fracture(&["validate", "/nonexistent/scene.json"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("/nonexistent/scene.json"));
}

#[test]
fn validate_prints_the_size() {
    let dir = tempfile::tempdir().unwrap();
    let file = write(dir.path(), "scene.json", &tiny().to_string());
    let o = fracture(&["validate", file.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let out = stdout(&o);
    // 6 mm × 6 mm at 1 mm cells, 2 × 2 per cell; 11 × 11 nodes.
    assert!(out.contains("particles: 144"), "{out}");
    assert!(out.contains("grid nodes: 121"), "{out}");
    let size = fracture_api::validate::validate(
        &fracture_api::validate::parse_scene(&tiny().to_string()).unwrap(),
    )
    .unwrap();
    assert!(out.contains(&format!("steps: {}", size.steps)), "{out}");
    assert!(
        out.contains(&format!("time step: {:e} s", size.time_step)),
        "{out}"
    );
}

#[test]
fn example_scenes_are_valid() {
    let mut n = 0;
    for entry in std::fs::read_dir(scenes()).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("json") {
            continue;
        }
        let o = fracture(&["validate", path.to_str().unwrap()]);
        assert_eq!(
            o.status.code(),
            Some(0),
            "{}: {}",
            path.display(),
            stderr(&o)
        );
        n += 1;
    }
    assert!(n >= 2, "scenes/ holds {n} scenes");
}

#[test]
fn schema_prints_the_scene_schema() {
    let o = fracture(&["schema"]);
    assert_eq!(o.status.code(), Some(0));
    let v: Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(v, fracture_api::Scene::json_schema());
    for key in ["grid", "materials", "bodies", "time", "output"] {
        assert!(v["properties"].get(key).is_some(), "schema lacks {key}");
    }
}

#[test]
fn run_writes_the_four_files() {
    let dir = tempfile::tempdir().unwrap();
    let file = write(dir.path(), "scene.json", &tiny().to_string());
    let out = dir.path().join("out");
    let o = fracture(&[
        "run",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--threads",
        "1",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    // Not a terminal: no progress bar drawn.
    assert!(!stderr(&o).contains("steps,"), "{}", stderr(&o));
    for f in [
        "summary.json",
        "energy.csv",
        "crack_tips.csv",
        "fields.mcap",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let energy = std::fs::read_to_string(out.join("energy.csv")).unwrap();
    let mut lines = energy.lines();
    assert_eq!(
        lines.next(),
        Some("time,kinetic,strain,external_work,dissipated,total_error,fracture")
    );
    let rows: Vec<&str> = lines.collect();
    assert!(!rows.is_empty());
    assert!(rows.iter().all(|l| l.split(',').count() == 7));
    let tips = std::fs::read_to_string(out.join("crack_tips.csv")).unwrap();
    assert_eq!(
        tips,
        format!("{}\n", fracture_api::results::CRACK_TIPS_CSV_HEADER)
    );
    assert!(tips.starts_with("time,crack,tip,x,y,length,speed,j1,j2,k1,k2,growing,"));
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "completed");
    assert_eq!(summary["particles"], 144);
    assert_eq!(summary["threads"], 1);
    let scene = fracture_api::validate::parse_scene(&tiny().to_string()).unwrap();
    assert_eq!(summary["scene_hash"], scene.hash());
    let size = fracture_api::validate::validate(&scene).unwrap();
    assert_eq!(summary["steps"], size.steps);
    // One row per step (no history_interval) and t = 0.
    assert_eq!(rows.len() as u64, size.steps + 1);
    let snaps = fracture_results::mcapfile::read_snapshots(out.join("fields.mcap")).unwrap();
    assert_eq!(snaps.len(), 3, "t = 0, 1 µs, 2 µs");
}

#[test]
fn run_with_vtk_writes_a_paraview_series() {
    let dir = tempfile::tempdir().unwrap();
    let file = write(dir.path(), "scene.json", &tiny().to_string());
    let out = dir.path().join("out");
    let o = fracture(&[
        "run",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--threads",
        "1",
        "--vtk",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stdout(&o).contains("fields.pvd"), "{}", stdout(&o));
    let snaps = fracture_results::mcapfile::read_snapshots(out.join("fields.mcap")).unwrap();
    assert!(!snaps.is_empty());
    let vtk = out.join("vtk");
    let pvd = std::fs::read_to_string(vtk.join("fields.pvd")).unwrap();
    assert!(vtk.join("cracks.pvd").is_file());
    // One grid file per snapshot, each named in the collection with its time.
    let mut grids: Vec<String> = std::fs::read_dir(&vtk)
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".vti"))
        .collect();
    grids.sort();
    assert_eq!(grids.len(), snaps.len(), "{grids:?}");
    for (g, s) in grids.iter().zip(&snaps) {
        assert!(pvd.contains(&format!("file=\"{g}\"")), "{g} not in {pvd}");
        let text = std::fs::read_to_string(vtk.join(g)).unwrap();
        assert!(text.contains("<ImageData"), "{g}");
        let stamp = format!("timestep=\"{:e}\"", s.time);
        assert!(pvd.contains(&stamp), "{stamp} not in {pvd}");
    }
    // Without --vtk there is no vtk folder.
    let out2 = dir.path().join("out2");
    let o = fracture(&[
        "run",
        file.to_str().unwrap(),
        "--out",
        out2.to_str().unwrap(),
        "--threads",
        "1",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(!out2.join("vtk").exists());
}

#[test]
fn impact_bar_runs() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let scene = scenes().join("impact-bar.json");
    let o = fracture(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stdout(&o).contains("completed"));
}

#[test]
fn numerical_failure_exits_3_and_keeps_partial_results() {
    // A body flying at 100 km/s leaves the grid within a few steps; the solver stops it
    // with a diagnosis naming the step and where.
    let text = with(|s| {
        s["bodies"][0]["initial_velocity"] = json!([1.0e5, 0.0]);
        s["time"]["end"] = json!(1.0e-4);
    });
    let dir = tempfile::tempdir().unwrap();
    let file = write(dir.path(), "scene.json", &text);
    let out = dir.path().join("out");
    let o = fracture(&[
        "run",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(err.contains("step"), "{err}");
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "failed");
    assert!(summary["message"].as_str().unwrap().contains("step"));
    let energy = std::fs::read_to_string(out.join("energy.csv")).unwrap();
    assert!(energy.lines().count() >= 2, "partial rows kept: {energy}");
}

#[test]
fn bench_runs_ci_sized() {
    let o = fracture(&[
        "bench",
        "--cell-size",
        "0.005",
        "--steps",
        "3",
        "--warmup",
        "1",
        "--threads",
        "1",
        "--json",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v: Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(v["benchmark"], "throughput");
    assert_eq!(v["steps"], 3);
    assert_eq!(v["threads"], 1);
    // 125 mm × 250 mm at 5 mm cells, 2 × 2 per cell: 25 × 50 × 4.
    assert_eq!(v["particles"], 5000);
    assert!(v["particle_steps_per_second"].as_f64().unwrap() > 0.0);
    let o = fracture(&[
        "bench",
        "throughput",
        "--cell-size",
        "0.005",
        "--steps",
        "2",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stdout(&o).contains("particle-steps/s"));
}

#[cfg(unix)]
#[test]
fn ctrl_c_cancels_the_run_and_writes_the_summary() {
    use std::time::{Duration, Instant};
    // Millions of steps of a body at rest: runs until interrupted (a moving body would
    // reach the grid edge first now that runs are fast).
    let text = with(|s| {
        s["time"]["end"] = json!(1.0);
        s["bodies"][0]["initial_velocity"] = json!([0.0, 0.0]);
    });
    let dir = tempfile::tempdir().unwrap();
    let file = write(dir.path(), "scene.json", &text);
    let out = dir.path().join("out");
    let child = Command::new(env!("CARGO_BIN_EXE_fracture"))
        .args([
            "run",
            file.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Wait until rows are flushed (the run is stepping and the handler installed).
    let start = Instant::now();
    loop {
        let rows = std::fs::read_to_string(out.join("energy.csv"))
            .map(|t| t.lines().count())
            .unwrap_or(0);
        if rows > 2 {
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "the run never started"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "cancelled");
    assert!(summary["steps"].as_u64().unwrap() > 0);
    // The MCAP file was finished properly.
    let m = fracture_results::mcapfile::McapContents::read(out.join("fields.mcap")).unwrap();
    assert!(!m.truncated);
}

/// `bench accuracy` on the tiny ladder writes its four files with one finite error per run
/// (a test of the command, not of the errors' size or the timings).
#[test]
fn bench_accuracy_tiny_ladder_writes_its_files() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("acc");
    let o = fracture(&[
        "bench",
        "accuracy",
        "--ladder",
        "tiny",
        "--threads",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    for f in [
        "accuracy.csv",
        "accuracy.md",
        "accuracy.svg",
        "accuracy.json",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let csv = std::fs::read_to_string(out.join("accuracy.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (err, wall) = (col("error"), col("wall_seconds"));
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    // Every problem has a row, every row a finite error and a positive wall time.
    assert!(rows.len() >= 6, "{csv}");
    for r in &rows {
        let e: f64 = r[err].parse().unwrap();
        let w: f64 = r[wall].parse().unwrap();
        assert!(e.is_finite() && w > 0.0, "row {r:?}");
    }
    let svg = std::fs::read_to_string(out.join("accuracy.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    assert!(stdout(&o).contains("order p"));
}

/// Arguments of a CI-sized benchmark: the seed block at 5 mm cells, 2 steps after 1, 1 thread.
const SMALL_BENCH: [&str; 8] = [
    "--cell-size",
    "0.005",
    "--steps",
    "2",
    "--warmup",
    "1",
    "--threads",
    "1",
];

/// Run `fracture <args> --out <dir>/<name> SMALL_BENCH`, expect success and read the JSON
/// report `<name>.json` it wrote.
fn small_bench(args: &[&str], dir: &std::path::Path, name: &str) -> Value {
    let out = dir.join(name);
    let mut all = args.to_vec();
    all.extend(["--out", out.to_str().unwrap()]);
    all.extend(SMALL_BENCH);
    let o = fracture(&all);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    serde_json::from_str(&std::fs::read_to_string(out.join(format!("{name}.json"))).unwrap())
        .unwrap()
}

/// `bench skip` and the throughput matrix (with instruction counts) run CI-sized and write
/// their files.
#[test]
fn bench_skip_and_throughput_matrix_run_ci_sized() {
    let dir = tempfile::tempdir().unwrap();
    let v = small_bench(&["bench", "skip"], dir.path(), "skip");
    let figs = v["figures"].as_array().unwrap();
    // Without a crack no crack phase runs and no J is evaluated.
    assert_eq!(figs[0]["counters"], json!([0, 0, 0, 0, 0]));
    let args = [
        "bench",
        "throughput",
        "--instructions",
        "--thread-counts",
        "1",
    ];
    let v = small_bench(&args, dir.path(), "throughput");
    let out = dir.path().join("throughput");
    assert_eq!(v["runs"].as_array().unwrap().len(), 3);
    assert!(out.join("throughput.csv").is_file());
    // Instructions per particle-step where valgrind is installed (the step is ~1,000 per
    // particle), a note where not.
    let has_valgrind = std::process::Command::new("valgrind")
        .arg("--version")
        .output()
        .is_ok();
    for r in v["runs"].as_array().unwrap() {
        let n = r["instructions_per_particle_step"].as_f64();
        if has_valgrind {
            let n = n.unwrap();
            assert!(
                (200.0..20_000.0).contains(&n),
                "{n} instructions per particle-step"
            );
        } else {
            assert!(n.is_none());
        }
    }
    if !has_valgrind {
        let md = std::fs::read_to_string(out.join("throughput.md")).unwrap();
        assert!(md.contains("valgrind is not installed"), "{md}");
    }
}

/// `bench ab` runs interleaved pairs against a baseline binary (here this one) and reports
/// both medians; without `--baseline` it names the missing option.
#[test]
fn bench_ab_runs_ci_sized() {
    let dir = tempfile::tempdir().unwrap();
    let me = env!("CARGO_BIN_EXE_fracture");
    let v = small_bench(
        &["bench", "ab", "--baseline", me, "--pairs", "2"],
        dir.path(),
        "ab",
    );
    assert_eq!(v["samples"].as_array().unwrap().len(), 4);
    let sides: Vec<&str> = v["samples"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["side"].as_str().unwrap())
        .collect();
    assert_eq!(
        sides,
        ["baseline", "this", "this", "baseline"],
        "interleaved"
    );
    assert!(v["ratio_of_medians"].as_f64().unwrap() > 0.0);
    let o = fracture(&["bench", "ab", "--pairs", "1"]);
    assert_ne!(o.status.code(), Some(0));
    assert!(stderr(&o).contains("--baseline"), "{}", stderr(&o));
}

#[test]
fn overflowing_wave_speed_names_the_density() {
    // Each constant is positive, but E/ρ overflows: no time step (it was "needs NaN steps").
    let text = with(|s| s["materials"]["plate"]["density"] = json!(1e-300));
    assert_invalid(&text, "materials.plate.density: 1e-300", "overflows");
    let dir = tempfile::tempdir().unwrap();
    let file = write(dir.path(), "scene.json", &text);
    let err = stderr(&fracture(&["validate", file.to_str().unwrap()]));
    assert!(!err.contains("NaN"), "{err}");
}

#[test]
fn grid_beyond_two_to_the_64_nodes_a_side_is_named() {
    let text = with(|s| {
        s["grid"]["cell_size"] = json!(1e-300);
        s["grid"]["max"] = json!([1e300, 1e300]);
    });
    assert_invalid(&text, "grid.cell_size", &u64::MAX.to_string());
}
