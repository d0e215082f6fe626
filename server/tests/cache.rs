//! Runs that are not repeated (docs/service.md, "Cache"), with `oneshot`: a resubmitted
//! scene with a completed run is answered by a completed copy whose results are the
//! original's; `"cache": "force"`, another scene, another solver version and a failed run
//! all queue a new run; sweeps reuse finished combinations.

#![allow(clippy::unwrap_used)]

#[path = "support/app.rs"]
mod app;
use app::call;

use axum::body::Body;
use axum::http::{Request, StatusCode};
use fracture_server::config::Config;
use fracture_server::files::JobFiles;
use fracture_server::store::Store;
use fracture_server::{AppState, app};
use http_body_util::BodyExt;
use serde_json::{Value, json};
use tower::ServiceExt;

async fn state(dir: &std::path::Path) -> AppState {
    let store = Store::open(&dir.join("t.db")).await.unwrap();
    let cfg = Config {
        worker_token: "wt".into(),
        ..Config::default()
    };
    AppState::new(store, cfg, JobFiles::new(dir)).0
}

fn scene(end: f64) -> Value {
    app::scene("cache", end)
}

fn post(uri: &str, body: &Value, token: Option<&str>) -> Request<Body> {
    let mut b = Request::post(uri).header("content-type", "application/json");
    if let Some(t) = token {
        b = b.header("authorization", format!("Bearer {t}"));
    }
    b.body(Body::from(body.to_string())).unwrap()
}

fn get(uri: &str) -> Request<Body> {
    Request::get(uri).body(Body::empty()).unwrap()
}

async fn submit(st: &AppState, body: &Value) -> Value {
    let (s, j) = call(st, post("/api/v1/jobs", body, None)).await;
    assert_eq!(s, StatusCode::CREATED, "{j}");
    j
}

fn summary(status: &str, solver_version: &str) -> Value {
    let mut s = json!({"status": status, "steps": 3, "time_step": 1e-7, "sim_time": 3e-7,
        "particles": 880, "grid_nodes": 299, "active_nodes_mean": 250.0, "wall_seconds": 0.25,
        "particle_steps_per_second": 10560.0, "threads": 1, "scene_hash": "h",
        "solver_version": solver_version});
    if status == "failed" {
        s["message"] = json!("energy blew up");
        s["failure"] = json!("numerical");
    }
    s
}

/// Claim the next job as a worker, record one energy row with `kinetic` as its marker, and
/// finish it with `status`; returns the job id.
async fn run_next(st: &AppState, kinetic: f64, status: &str, solver_version: &str) -> String {
    let (s, c) = call(
        st,
        post(
            "/api/v1/worker/claim",
            &json!({"worker_id": "w", "wait_seconds": 0}),
            Some("wt"),
        ),
    )
    .await;
    assert_eq!(s, StatusCode::OK, "{c}");
    let id = c["job_id"].as_str().unwrap().to_string();
    let fence = c["fence"].as_i64().unwrap();
    let rows = json!({"fence": fence, "rows": [{"time": 0.0, "kinetic": kinetic, "strain": 0.0,
        "external_work": 0.0, "dissipated": 0.0, "total_error": 0.0}]});
    let (s, v) = call(
        st,
        post(
            &format!("/api/v1/worker/jobs/{id}/energy"),
            &rows,
            Some("wt"),
        ),
    )
    .await;
    assert_eq!(s, StatusCode::NO_CONTENT, "{v}");
    let fin = json!({"fence": fence, "summary": summary(status, solver_version)});
    let (s, v) = call(
        st,
        post(
            &format!("/api/v1/worker/jobs/{id}/finish"),
            &fin,
            Some("wt"),
        ),
    )
    .await;
    assert_eq!(s, StatusCode::OK, "{v}");
    id
}

async fn queued(st: &AppState) -> usize {
    let (_, l) = call(st, get("/api/v1/jobs?status=queued")).await;
    l.as_array().unwrap().len()
}

#[tokio::test]
async fn a_completed_scene_is_answered_from_the_cache_unless_forced() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path()).await;
    let first = submit(&st, &scene(1e-5)).await;
    assert!(first.get("cached_from").is_none(), "{first}");
    // Queued and running identical jobs are not reused: a second submission queues too.
    let twin = submit(&st, &scene(1e-5)).await;
    assert_eq!(twin["status"], "queued", "{twin}");
    let orig = run_next(&st, 42.0, "completed", fracture_api::SOLVER_VERSION).await;
    assert_eq!(orig, first["id"].as_str().unwrap());

    // Same scene (wrapped, with its own labels and priority): a completed copy.
    let body = json!({"scene": scene(1e-5), "labels": {"who": "b"}, "priority": 3});
    let hit = submit(&st, &body).await;
    let hid = hit["id"].as_str().unwrap();
    assert_ne!(hid, orig);
    assert_eq!(hit["cached_from"], orig.as_str(), "{hit}");
    assert_eq!(hit["status"], "completed");
    assert_eq!(hit["attempts"], 0);
    assert_eq!(hit["labels"]["who"], "b");
    assert_eq!(hit["priority"], 3);
    assert_eq!(hit["summary"]["particles"], 880, "the original's summary");
    // Nothing was queued for it (the twin is still the only queued job).
    assert_eq!(queued(&st).await, 1);
    // Its results are the original's, its listing says where they come from.
    let (s, e) = call(&st, get(&format!("/api/v1/jobs/{hid}/energy"))).await;
    assert_eq!(s, StatusCode::OK);
    assert_eq!(e[0]["kinetic"], 42.0, "{e}");
    let resp = app(st.clone())
        .oneshot(
            Request::get(format!("/api/v1/jobs/{hid}/energy"))
                .header("accept", "text/csv")
                .body(Body::empty())
                .unwrap(),
        )
        .await
        .unwrap();
    let csv = resp.into_body().collect().await.unwrap().to_bytes();
    assert!(
        String::from_utf8_lossy(&csv).contains("42"),
        "csv of the copy"
    );
    let (_, list) = call(&st, get("/api/v1/jobs?label=who:b")).await;
    assert_eq!(list[0]["cached_from"], orig.as_str(), "{list}");

    // `"cache": "force"` runs it again; a rerun always runs.
    let forced = submit(&st, &json!({"scene": scene(1e-5), "cache": "force"})).await;
    assert_eq!(forced["status"], "queued", "{forced}");
    assert!(forced.get("cached_from").is_none());
    let (s, v) = call(
        &st,
        post(&format!("/api/v1/jobs/{orig}/rerun"), &json!(null), None),
    )
    .await;
    assert_eq!(s, StatusCode::CREATED, "{v}");
    assert_eq!(v["status"], "queued");
    assert_eq!(queued(&st).await, 3);
    // A bad cache mode names the field.
    let (s, v) = call(
        &st,
        post(
            "/api/v1/jobs",
            &json!({"scene": scene(1e-5), "cache": "sometimes"}),
            None,
        ),
    )
    .await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    assert!(v.to_string().contains("cache"), "{v}");

    // Another scene is not a hit.
    let other = submit(&st, &scene(2e-5)).await;
    assert_eq!(other["status"], "queued");

    // Deleting the original: the copy stays, its results say why they are gone.
    let (s, _) = call(
        &st,
        Request::delete(format!("/api/v1/jobs/{orig}"))
            .body(Body::empty())
            .unwrap(),
    )
    .await;
    assert_eq!(s, StatusCode::NO_CONTENT);
    let (s, v) = call(&st, get(&format!("/api/v1/jobs/{hid}/energy"))).await;
    assert_eq!(s, StatusCode::NOT_FOUND, "{v}");
    assert!(v["message"].as_str().unwrap().contains(&orig), "{v}");
}

#[tokio::test]
async fn failed_runs_and_other_solver_versions_are_not_reused() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path()).await;
    submit(&st, &scene(1e-5)).await;
    run_next(&st, 1.0, "failed", fracture_api::SOLVER_VERSION).await;
    let again = submit(&st, &scene(1e-5)).await;
    assert_eq!(
        again["status"], "queued",
        "a failed run is never reused: {again}"
    );
    // Completed, but by another solver version.
    run_next(&st, 2.0, "completed", "0.0.0-other").await;
    let third = submit(&st, &scene(1e-5)).await;
    assert_eq!(third["status"], "queued", "{third}");
    let tid = run_next(&st, 3.0, "completed", fracture_api::SOLVER_VERSION).await;
    let hit = submit(&st, &scene(1e-5)).await;
    assert_eq!(hit["cached_from"], tid.as_str(), "{hit}");
    // A copy is never the source of another copy.
    let hit2 = submit(&st, &scene(1e-5)).await;
    assert_eq!(hit2["cached_from"], tid.as_str(), "{hit2}");
}

#[tokio::test]
async fn sweeps_reuse_finished_combinations() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path()).await;
    let sweep = |cache: Option<&str>| {
        let mut b = json!({"scene": scene(1e-5),
            "parameters": {"bodies.0.particles_per_cell": [1, 2]}});
        if let Some(c) = cache {
            b["cache"] = json!(c);
        }
        b
    };
    let (s, a) = call(&st, post("/api/v1/sweeps", &sweep(None), None)).await;
    assert_eq!(s, StatusCode::CREATED, "{a}");
    let ids: Vec<String> = a["jobs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| j["id"].as_str().unwrap().to_string())
        .collect();
    // Finish only the first combination (claims go oldest first).
    let done = run_next(&st, 7.0, "completed", fracture_api::SOLVER_VERSION).await;
    assert_eq!(done, ids[0]);
    let (s, b) = call(&st, post("/api/v1/sweeps", &sweep(None), None)).await;
    assert_eq!(s, StatusCode::CREATED, "{b}");
    let jobs = b["jobs"].as_array().unwrap();
    assert_eq!(jobs[0]["cached_from"], done.as_str(), "{b}");
    assert_eq!(jobs[0]["status"], "completed");
    assert!(jobs[1].get("cached_from").is_none(), "unfinished: {b}");
    assert_eq!(jobs[1]["status"], "queued");
    assert_eq!(b["counts"]["completed"], 1);
    let cid = jobs[0]["id"].as_str().unwrap();
    let (_, e) = call(&st, get(&format!("/api/v1/jobs/{cid}/energy"))).await;
    assert_eq!(e[0]["kinetic"], 7.0, "{e}");
    // A lone job with a combination's scene is a hit too (the same canonical scene).
    let mut lone = scene(1e-5);
    lone["bodies"][0]["particles_per_cell"] = json!(1);
    let hit = submit(&st, &lone).await;
    assert_eq!(hit["cached_from"], done.as_str(), "{hit}");
    // Forced: every combination queued.
    let (_, f) = call(&st, post("/api/v1/sweeps", &sweep(Some("force")), None)).await;
    assert!(
        f["jobs"]
            .as_array()
            .unwrap()
            .iter()
            .all(|j| j["status"] == "queued" && j.get("cached_from").is_none()),
        "{f}"
    );
}
