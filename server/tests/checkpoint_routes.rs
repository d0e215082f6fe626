//! The checkpoint routes of the worker protocol (`PUT/GET/DELETE
//! /api/v1/worker/jobs/{id}/checkpoint`) driven through `app(state)` without a socket: they
//! are fenced, a re-claim keeps exactly the history the checkpoint covers (rows at times ≤
//! its time) and says so in the job's message, and a refusal drops the checkpoint and the
//! history.

#![allow(clippy::unwrap_used)]

#[path = "support/app.rs"]
mod app;

use axum::body::Body;
use axum::http::{Request, StatusCode};
use fracture_server::AppState;
use fracture_server::config::Config;
use fracture_server::files::JobFiles;
use fracture_server::store::Store;
use serde_json::{Value, json};

async fn state(dir: &std::path::Path) -> AppState {
    let store = Store::open(&dir.join("t.db")).await.unwrap();
    let cfg = Config {
        worker_token: "wt".into(),
        ..Config::default()
    };
    AppState::new(store, cfg, JobFiles::new(dir)).0
}

fn scene() -> Value {
    app::scene("unit", 1.0e-5)
}

async fn call(st: &AppState, req: Request<Body>) -> (StatusCode, Vec<u8>) {
    let (s, _, b) = app::send_raw(st, req).await;
    (s, b)
}

async fn json_call(st: &AppState, req: Request<Body>) -> (StatusCode, Value) {
    let (s, b) = call(st, req).await;
    (s, serde_json::from_slice(&b).unwrap_or(Value::Null))
}

fn req(method: &str, uri: &str, body: impl Into<Body>, worker: bool) -> Request<Body> {
    let mut b = Request::builder()
        .method(method)
        .uri(uri)
        .header("content-type", "application/json");
    if worker {
        b = b.header("authorization", "Bearer wt");
    }
    b.body(body.into()).unwrap()
}

fn energy_row(t: f64) -> Value {
    json!({"time": t, "kinetic": 1.0, "strain": 2.0, "external_work": 3.0,
           "dissipated": 0.0, "total_error": 0.0, "fracture": 0.0})
}

#[tokio::test]
async fn checkpoints_are_fenced_and_a_reclaim_keeps_the_history_they_cover() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path()).await;
    let (_, job) = json_call(&st, req("POST", "/api/v1/jobs", scene().to_string(), false)).await;
    let id = job["id"].as_str().unwrap().to_string();
    let claim = || {
        req(
            "POST",
            "/api/v1/worker/claim",
            json!({"worker_id": "w", "wait_seconds": 0}).to_string(),
            true,
        )
    };
    let (_, c) = json_call(&st, claim()).await;
    let f1 = c["fence"].as_i64().unwrap();
    let rows: Vec<Value> = [0.0, 1e-6, 2e-6, 3e-6].map(energy_row).to_vec();
    let (s, _) = call(
        &st,
        req(
            "POST",
            &format!("/api/v1/worker/jobs/{id}/energy"),
            json!({"fence": f1, "rows": rows}).to_string(),
            true,
        ),
    )
    .await;
    assert_eq!(s, StatusCode::NO_CONTENT);
    let ck = |fence: i64| format!("/api/v1/worker/jobs/{id}/checkpoint?fence={fence}");
    let put = |fence: i64, body: &'static [u8]| {
        req(
            "PUT",
            &format!("{}&step=20&time={}&snapshots=0", ck(fence), 2e-6),
            body,
            true,
        )
    };
    // None yet; a stale fence or no token is refused.
    assert_eq!(
        call(&st, req("GET", &ck(f1), "", true)).await.0,
        StatusCode::NOT_FOUND
    );
    assert_eq!(
        call(&st, put(f1 + 1, b"state")).await.0,
        StatusCode::CONFLICT
    );
    assert_eq!(
        call(
            &st,
            req(
                "PUT",
                &format!("{}&step=20&time=0&snapshots=0", ck(f1)),
                "x",
                false
            )
        )
        .await
        .0,
        StatusCode::UNAUTHORIZED
    );
    assert_eq!(call(&st, put(f1, b"state")).await.0, StatusCode::NO_CONTENT);
    let (s, b) = call(&st, req("GET", &ck(f1), "", true)).await;
    assert_eq!((s, b.as_slice()), (StatusCode::OK, &b"state"[..]));

    // The worker dies; the re-claim keeps the rows at times ≤ 2 µs.
    let (s, _) = call(
        &st,
        req(
            "POST",
            &format!("/api/v1/worker/jobs/{id}/died"),
            json!({"fence": f1, "cause": "killed"}).to_string(),
            true,
        ),
    )
    .await;
    assert_eq!(s, StatusCode::OK);
    let (_, c) = json_call(&st, claim()).await;
    let f2 = c["fence"].as_i64().unwrap();
    let energy = || req("GET", &format!("/api/v1/jobs/{id}/energy"), "", false);
    let (_, e) = json_call(&st, energy()).await;
    let times: Vec<f64> = e
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["time"].as_f64().unwrap())
        .collect();
    assert_eq!(times, vec![0.0, 1e-6, 2e-6]);
    let (_, j) = json_call(&st, req("GET", &format!("/api/v1/jobs/{id}"), "", false)).await;
    assert!(
        j["message"]
            .as_str()
            .unwrap_or("")
            .contains("checkpoint at step 20"),
        "{j}"
    );
    assert_eq!(
        call(&st, req("GET", &ck(f1), "", true)).await.0,
        StatusCode::CONFLICT
    );
    let (s, b) = call(&st, req("GET", &ck(f2), "", true)).await;
    assert_eq!((s, b.as_slice()), (StatusCode::OK, &b"state"[..]));

    // Refused by the worker: checkpoint and history gone.
    assert_eq!(
        call(&st, req("DELETE", &ck(f2), "", true)).await.0,
        StatusCode::NO_CONTENT
    );
    assert_eq!(
        call(&st, req("GET", &ck(f2), "", true)).await.0,
        StatusCode::NOT_FOUND
    );
    let (_, e) = json_call(&st, energy()).await;
    assert_eq!(e.as_array().unwrap().len(), 0, "{e}");

    // A corrupt file is not served as a checkpoint: a new claim removes it and drops the
    // history.
    assert_eq!(call(&st, put(f2, b"state")).await.0, StatusCode::NO_CONTENT);
    let path = dir.path().join("jobs").join(&id).join("checkpoint.bin");
    let mut bytes = std::fs::read(&path).unwrap();
    let last = bytes.len() - 1;
    bytes[last] ^= 1;
    std::fs::write(&path, &bytes).unwrap();
    let (s, _) = call(
        &st,
        req(
            "POST",
            &format!("/api/v1/worker/jobs/{id}/died"),
            json!({"fence": f2, "cause": "killed"}).to_string(),
            true,
        ),
    )
    .await;
    assert_eq!(s, StatusCode::OK);
    let (_, c) = json_call(&st, claim()).await;
    let f3 = c["fence"].as_i64().unwrap();
    assert!(!path.exists(), "the corrupt checkpoint was not removed");
    assert_eq!(
        call(&st, req("GET", &ck(f3), "", true)).await.0,
        StatusCode::NOT_FOUND
    );
}
