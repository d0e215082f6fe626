//! 3D scenes (`"analysis": "3d"`) through the service, `app(state)` driven with
//! `tower::ServiceExt::oneshot` (no socket, no worker process): submission bare and wrapped,
//! validation errors with their field paths, the limits applied before the lattice walk,
//! validation and example routes, reruns, sweeps, and the worker protocol carrying a 3D
//! run's slices and summary. A real run of every 3D example by a worker process is
//! `tests/tests/three_d.rs`.

#![allow(clippy::unwrap_used)]

#[path = "support/app.rs"]
mod app;
use app::call;

use axum::body::Body;
use axum::http::{Request, StatusCode};
use fracture_server::config::{Config, Limits};
use fracture_server::files::JobFiles;
use fracture_server::store::Store;
use fracture_server::{AppState, app};
use serde_json::{Value, json};
use tower::ServiceExt;

async fn state(dir: &std::path::Path, limits: Limits) -> AppState {
    let store = Store::open(&dir.join("t.db")).await.unwrap();
    let cfg = Config {
        worker_token: "wt".into(),
        limits,
        ..Config::default()
    };
    AppState::new(store, cfg, JobFiles::new(dir)).0
}

fn post(uri: &str, body: impl Into<Body>, token: Option<&str>) -> Request<Body> {
    let mut b = Request::post(uri).header("content-type", "application/json");
    if let Some(t) = token {
        b = b.header("authorization", format!("Bearer {t}"));
    }
    b.body(body.into()).unwrap()
}

fn get(uri: &str) -> Request<Body> {
    Request::get(uri).body(Body::empty()).unwrap()
}

/// An aluminium cube of 4 mm at 1 mm cells (512 particles) in a 6 mm grid box, two slices.
fn cube(name: &str) -> Value {
    json!({
        "name": name,
        "analysis": "3d",
        "grid": {"cell_size": 0.001, "min": [0.0, 0.0, 0.0], "max": [0.006, 0.006, 0.006]},
        "materials": {"al": {"model": "linear_elastic", "density": 2700.0,
                              "youngs_modulus": 70e9, "poissons_ratio": 0.33}},
        "bodies": [{"material": "al", "initial_velocity": [1.0, 0.0, 0.0],
                    "region": {"box": {"min": [0.001, 0.001, 0.001], "max": [0.005, 0.005, 0.005]}}}],
        "time": {"end": 1.0e-6},
        "output": {"snapshot_interval": 5.0e-7,
                   "slices": [{"normal": "z", "at": 0.003}, {"normal": "y", "at": 0.002}]}
    })
}

/// A closed tetrahedron with its last triangle turned over: not consistently oriented.
fn bad_mesh_cube() -> Value {
    let mut s = cube("bad-mesh");
    s["bodies"][0]["region"] = json!({"mesh": {
        "vertices": [[0.001, 0.001, 0.001], [0.005, 0.001, 0.001], [0.001, 0.005, 0.001],
                     [0.001, 0.001, 0.005]],
        "triangles": [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 2, 3]]
    }});
    s
}

fn assert_invalid(v: &Value, path: &str) {
    assert_eq!(v["error"], "invalid_scene", "{v}");
    assert!(
        v["details"]
            .as_array()
            .unwrap()
            .iter()
            .any(|d| d["path"] == path),
        "no detail at {path}: {v}"
    );
}

fn example(name: &str) -> Value {
    let path = format!("{}/../scenes/{name}.json", env!("CARGO_MANIFEST_DIR"));
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[tokio::test]
async fn three_d_scenes_are_submitted_bare_or_wrapped_and_stored_canonically() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), Limits::default()).await;
    for name in ["3d-wave-bar", "3d-impact", "3d-sphere-plate"] {
        let sc = example(name);
        let expected = fracture_api::any_scene_from_value(sc.clone()).unwrap();
        let (s, j) = call(&st, post("/api/v1/jobs", sc.to_string(), None)).await;
        assert_eq!(s, StatusCode::CREATED, "{name}: {j}");
        assert_eq!(j["status"], "queued");
        assert_eq!(j["name"], name);
        assert_eq!(j["scene"]["analysis"], "3d", "{j}");
        // The stored scene is the canonical JSON: defaults filled in, same hash.
        let stored: fracture_api::AnyScene = serde_json::from_value(j["scene"].clone()).unwrap();
        assert_eq!(stored, expected);
        let id = j["id"].as_str().unwrap();
        let row = st.store.get(id).await.unwrap().unwrap();
        assert_eq!(row.scene, expected.canonical_json());
        assert_eq!(row.scene_hash.as_deref(), Some(expected.hash().as_str()));
        assert_eq!(row.end_time, expected.end_time());
    }
    // Wrapped, with the wrapper's fields.
    let body = json!({"scene": cube("wrapped"), "priority": 7, "labels": {"dim": "3"},
                      "cache": "force", "max_attempts": 2});
    let (s, j) = call(&st, post("/api/v1/jobs", body.to_string(), None)).await;
    assert_eq!(s, StatusCode::CREATED, "{j}");
    assert_eq!(
        (j["priority"].clone(), j["labels"]["dim"].clone()),
        (json!(7), json!("3"))
    );
    assert_eq!(j["max_attempts"], 2);
    // A rerun admits the stored 3D scene again.
    let id = j["id"].as_str().unwrap();
    let (s, r) = call(&st, post(&format!("/api/v1/jobs/{id}/rerun"), "", None)).await;
    assert_eq!(s, StatusCode::CREATED, "{r}");
    assert_eq!(r["rerun_of"], id);
    assert_eq!(r["scene"], j["scene"]);
    // The list shows them, without scenes.
    let (_, list) = call(&st, get("/api/v1/jobs")).await;
    assert_eq!(list.as_array().unwrap().len(), 5);
}

#[tokio::test]
async fn invalid_3d_scenes_are_422_naming_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), Limits::default()).await;
    let mut thick = cube("thick");
    thick["thickness"] = json!(0.001);
    let mut two_d_grid = cube("flat");
    two_d_grid["grid"]["min"] = json!([0.0, 0.0]);
    let mut nu = cube("nu");
    nu["materials"]["al"]["poissons_ratio"] = json!(0.6);
    let mut slice = cube("slice");
    slice["output"]["slices"][0]["at"] = json!(0.5);
    let mut fringe = cube("fringe");
    fringe["output"]["fields"] = json!(["stress", "fringe"]);
    let cases = [
        (thick, "thickness"),
        (two_d_grid, "grid.min"),
        (nu, "materials.al.poissons_ratio"),
        (slice, "output.slices.0.at"),
        (fringe, "output.fields.1"),
    ];
    for (sc, path) in cases {
        for body in [sc.clone(), json!({"scene": sc.clone(), "priority": 1})] {
            let (s, v) = call(&st, post("/api/v1/jobs", body.to_string(), None)).await;
            assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{path}: {v}");
            assert_invalid(&v, path);
        }
        let (s, v) = call(&st, post("/api/v1/scenes/validate", sc.to_string(), None)).await;
        assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{path}: {v}");
        assert_invalid(&v, path);
    }
    // A mesh whose triangles are not consistently oriented names its first bad triangle.
    let (s, v) = call(&st, post("/api/v1/jobs", bad_mesh_cube().to_string(), None)).await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    let d = &v["details"][0];
    assert!(
        d["path"]
            .as_str()
            .unwrap()
            .starts_with("bodies.0.region.mesh.triangles."),
        "{v}"
    );
    // An unknown field of the wrapper is named at the wrapper; one of the scene in the scene.
    let body = json!({"scene": cube("w"), "priorty": 1});
    let (s, v) = call(&st, post("/api/v1/jobs", body.to_string(), None)).await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    assert!(
        v["details"][0]["message"]
            .as_str()
            .unwrap()
            .contains("priorty"),
        "{v}"
    );
    let mut typo = cube("typo");
    typo["grid"]["cellsize"] = json!(1);
    let (s, v) = call(
        &st,
        post("/api/v1/jobs", json!({ "scene": typo }).to_string(), None),
    )
    .await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    assert_eq!(v["details"][0]["path"], "grid.cellsize", "{v}");
    let (_, list) = call(&st, get("/api/v1/jobs")).await;
    assert!(list.as_array().unwrap().is_empty(), "nothing was queued");
}

#[tokio::test]
async fn three_d_limits_are_422_limit_exceeded_before_and_after_the_walk() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(
        dir.path(),
        Limits {
            max_particles: 300,
            max_steps: 50,
            ..Limits::default()
        },
    )
    .await;
    // 512 particles: the precheck's lower estimate (a box eroded by two cells) is 0 here,
    // so the exact count after validation refuses it.
    let (s, v) = call(&st, post("/api/v1/jobs", cube("c").to_string(), None)).await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    assert_eq!(v["error"], "limit_exceeded", "{v}");
    assert!(
        v["message"].as_str().unwrap().contains("max_particles"),
        "{v}"
    );
    assert_eq!(v["details"][0]["path"], "bodies");
    assert!(
        v["details"][0]["message"]
            .as_str()
            .unwrap()
            .contains("512 particles"),
        "{v}"
    );
    // A large cube is refused by the estimate alone (at least 76³ × 8 particles), before
    // anything walks its lattice (4 million sites would take validation a while).
    let mut big = cube("big");
    big["grid"]["max"] = json!([0.1, 0.1, 0.1]);
    big["bodies"][0]["region"]["box"]["max"] = json!([0.099, 0.099, 0.099]);
    big["output"]["slices"] = json!([]);
    let t0 = std::time::Instant::now();
    let (s, v) = call(&st, post("/api/v1/scenes/validate", big.to_string(), None)).await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    assert_eq!(v["error"], "limit_exceeded", "{v}");
    assert!(
        v["details"][0]["message"]
            .as_str()
            .unwrap()
            .contains("at least"),
        "{v}"
    );
    assert!(t0.elapsed().as_secs_f64() < 1.0, "{:?}", t0.elapsed());
    // Steps: 10 µs at Δt ≈ 80 ns.
    let dir2 = tempfile::tempdir().unwrap();
    let st = state(
        dir2.path(),
        Limits {
            max_steps: 50,
            ..Limits::default()
        },
    )
    .await;
    let mut long = cube("long");
    long["time"]["end"] = json!(1.0e-5);
    long["output"]["snapshot_interval"] = json!(0.0);
    let (s, v) = call(&st, post("/api/v1/jobs", long.to_string(), None)).await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    assert_eq!(v["error"], "limit_exceeded");
    assert!(v["message"].as_str().unwrap().contains("max_steps"), "{v}");
    assert_eq!(v["details"][0]["path"], "time.end");
    // A name over max_name_bytes.
    let (s, v) = call(
        &st,
        post("/api/v1/jobs", cube(&"n".repeat(300)).to_string(), None),
    )
    .await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    assert!(
        v["message"].as_str().unwrap().contains("max_name_bytes"),
        "{v}"
    );
}

#[tokio::test]
async fn validation_examples_and_sweeps_take_3d_scenes() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), Limits::default()).await;
    let (s, v) = call(
        &st,
        post("/api/v1/scenes/validate", cube("v").to_string(), None),
    )
    .await;
    assert_eq!(s, StatusCode::OK, "{v}");
    assert_eq!(v["particles"], 512);
    assert_eq!(v["grid_nodes"], 7 * 7 * 7);
    // The example list sizes the 3D examples as validation does.
    let (_, list) = call(&st, get("/api/v1/scenes")).await;
    let three: Vec<&Value> = list
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["scene"]["analysis"] == "3d")
        .collect();
    assert!(three.len() >= 3, "{list}");
    for e in three {
        let (s, size) = call(
            &st,
            post("/api/v1/scenes/validate", e["scene"].to_string(), None),
        )
        .await;
        assert_eq!(s, StatusCode::OK, "{size}");
        assert_eq!(e["particles"], size["particles"], "{}", e["name"]);
        assert_eq!(e["steps"], size["steps"], "{}", e["name"]);
        assert!(e["particles"].as_u64().unwrap() > 0);
    }
    // A sweep of a 3D scene: one job per value, each a 3D scene.
    let req =
        json!({"scene": cube("sw"), "parameters": {"bodies.0.initial_velocity.0": [1.0, 2.0]}});
    let (s, sw) = call(&st, post("/api/v1/sweeps", req.to_string(), None)).await;
    assert_eq!(s, StatusCode::CREATED, "{sw}");
    let jobs = sw["jobs"].as_array().unwrap();
    assert_eq!(jobs.len(), 2, "{sw}");
    for j in jobs {
        let id = j["id"].as_str().unwrap();
        let (_, job) = call(&st, get(&format!("/api/v1/jobs/{id}"))).await;
        assert_eq!(job["scene"]["analysis"], "3d", "{job}");
    }
    let v = job_velocities(&st, jobs).await;
    assert_eq!(v, vec![1.0, 2.0]);
    // A combination that is not a valid 3D scene refuses the sweep, naming the parameter.
    let req =
        json!({"scene": cube("sw"), "parameters": {"materials.al.poissons_ratio": [0.3, 0.7]}});
    let (s, v) = call(&st, post("/api/v1/sweeps", req.to_string(), None)).await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    assert_eq!(
        v["details"][0]["path"], "materials.al.poissons_ratio",
        "{v}"
    );
}

async fn job_velocities(st: &AppState, jobs: &[Value]) -> Vec<f64> {
    let mut out = Vec::new();
    for j in jobs {
        let id = j["id"].as_str().unwrap();
        let (_, job) = call(st, get(&format!("/api/v1/jobs/{id}"))).await;
        out.push(
            job["scene"]["bodies"][0]["initial_velocity"][0]
                .as_f64()
                .unwrap(),
        );
    }
    out.sort_by(f64::total_cmp);
    out
}

/// A slice snapshot as a 3D worker sends it (`fracture_results::codec`).
fn slice_snapshot(index: u32, time: f64, normal: &str, at: f64) -> Vec<u8> {
    let axes = if normal == "z" {
        ["x", "y"]
    } else {
        ["x", "z"]
    };
    let snap: fracture_api::results::Snapshot = serde_json::from_value(json!({
        "index": index, "time": time, "nx": 7, "ny": 7, "origin": [0.0, 0.0], "cell_size": 0.001,
        "fields": ["stress"],
        "components": [{"name": "sxx", "values": (0..49).map(|k| k as f32).collect::<Vec<_>>()},
                       {"name": "szz", "values": vec![1.0f32; 49]}],
        "cracks": [],
        "slice": {"normal": normal, "at": at, "node_at": at, "axes": axes}
    }))
    .unwrap();
    fracture_results::codec::encode_snapshot(&snap)
}

#[tokio::test]
async fn the_worker_protocol_carries_a_3d_runs_slices_and_summary() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), Limits::default()).await;
    let (_, job) = call(&st, post("/api/v1/jobs", cube("proto").to_string(), None)).await;
    let id = job["id"].as_str().unwrap().to_string();
    let (s, c) = call(
        &st,
        post(
            "/api/v1/worker/claim",
            r#"{"worker_id":"w","wait_seconds":0}"#,
            Some("wt"),
        ),
    )
    .await;
    assert_eq!(s, StatusCode::OK, "{c}");
    assert_eq!(
        c["scene"]["analysis"], "3d",
        "the claim carries the 3D scene"
    );
    let fence = c["fence"].as_i64().unwrap();
    let rows = json!({"fence": fence, "rows": [{"time": 0.0, "kinetic": 1.0, "strain": 0.0,
        "external_work": 0.0, "dissipated": 0.0, "total_error": 0.0}]});
    let (s, _) = call(
        &st,
        post(
            &format!("/api/v1/worker/jobs/{id}/energy"),
            rows.to_string(),
            Some("wt"),
        ),
    )
    .await;
    assert_eq!(s, StatusCode::NO_CONTENT);
    for (k, (normal, at)) in [("z", 0.003), ("y", 0.002)].into_iter().enumerate() {
        let resp = app(st.clone())
            .oneshot(
                Request::post(format!("/api/v1/worker/jobs/{id}/snapshots?fence={fence}"))
                    .header("authorization", "Bearer wt")
                    .header("content-type", "application/octet-stream")
                    .body(Body::from(slice_snapshot(k as u32, 0.0, normal, at)))
                    .unwrap(),
            )
            .await
            .unwrap();
        assert_eq!(resp.status(), StatusCode::NO_CONTENT);
    }
    let (_, snaps) = call(&st, get(&format!("/api/v1/jobs/{id}/snapshots"))).await;
    let snaps = snaps.as_array().unwrap();
    assert_eq!(snaps.len(), 2);
    assert_eq!(snaps[0]["slice"]["normal"], "z");
    assert_eq!(snaps[0]["slice"]["axes"], json!(["x", "y"]));
    assert_eq!(snaps[1]["slice"]["normal"], "y");
    assert_eq!(snaps[1]["slice"]["at"], 0.002);
    assert_eq!(snaps[1]["components"], json!(["sxx", "szz"]));
    // Each slice renders as a picture.
    for f in ["sxx", "szz", "stress"] {
        let resp = app(st.clone())
            .oneshot(get(&format!("/api/v1/jobs/{id}/snapshots/1/{f}.png")))
            .await
            .unwrap();
        assert_eq!(resp.status(), StatusCode::OK, "{f}");
    }
    // A 3D run has no crack path.
    let (s, v) = call(&st, get(&format!("/api/v1/jobs/{id}/path.svg"))).await;
    assert_eq!(s, StatusCode::NOT_FOUND, "{v}");
    assert!(v["message"].as_str().unwrap().contains("3D"), "{v}");
    let summary = json!({"status": "completed", "steps": 13, "time_step": 8e-8, "sim_time": 1e-6,
        "particles": 512, "grid_nodes": 343, "active_nodes_mean": 125.0, "wall_seconds": 0.1,
        "particle_steps_per_second": 66560.0, "threads": 1, "scene_hash": "h",
        "solver_version": "test", "dimension": 3});
    let (s, f) = call(
        &st,
        post(
            &format!("/api/v1/worker/jobs/{id}/finish"),
            json!({"fence": fence, "summary": summary}).to_string(),
            Some("wt"),
        ),
    )
    .await;
    assert_eq!(s, StatusCode::OK, "{f}");
    let (_, j) = call(&st, get(&format!("/api/v1/jobs/{id}"))).await;
    assert_eq!(j["status"], "completed");
    assert_eq!(j["summary"]["dimension"], 3, "{j}");
    assert_eq!(j["scene"]["analysis"], "3d");
    // The MCAP file records the 3D scene and the slices.
    let path = dir.path().join("jobs").join(&id).join("fields.mcap");
    let file = fracture_results::mcapfile::McapContents::read(&path).unwrap();
    assert!(!file.truncated);
    assert_eq!(file.snapshots.len(), 2);
    assert_eq!(
        file.snapshots[1].slice.as_ref().map(|s| s.normal.as_str()),
        Some("y")
    );
    assert_eq!(file.energy.len(), 1);
    let scene = file.scene.expect("the scene metadata");
    assert!(scene["json"].contains(r#""analysis":"3d""#), "{scene:?}");
    assert_eq!(scene["name"], "proto");
}
