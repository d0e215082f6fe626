//! `app(state)` driven with `tower::ServiceExt::oneshot`, no socket: error formats, status
//! codes, auth, limits, and the worker protocol's fencing.

#![allow(clippy::unwrap_used)]

#[path = "support/app.rs"]
mod app;
use app::call;

use axum::body::Body;
use axum::http::{Request, StatusCode};
use fracture_api::jobs::JobStatus;
use fracture_server::config::{Config, Limits};
use fracture_server::files::JobFiles;
use fracture_server::store::Store;
use fracture_server::{AppState, app};
use serde_json::{Value, json};
use tower::ServiceExt;

async fn state(dir: &std::path::Path, token: Option<&str>) -> AppState {
    let store = Store::open(&dir.join("t.db")).await.unwrap();
    let cfg = Config {
        api_token: token.map(String::from),
        worker_token: "wt".into(),
        limits: Limits {
            max_particles: 1000,
            max_body_bytes: 32 * 1024,
            ..Limits::default()
        },
        ..Config::default()
    };
    AppState::new(store, cfg, JobFiles::new(dir)).0
}

fn scene() -> Value {
    app::scene("unit", 1.0e-5)
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

fn assert_error_body(v: &Value, kind: &str) {
    assert_eq!(v["error"], kind, "{v}");
    assert!(v["message"].as_str().is_some_and(|m| !m.is_empty()), "{v}");
    assert!(v["details"].is_array(), "{v}");
}

#[tokio::test]
async fn malformed_json_is_400_in_the_error_format() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), None).await;
    let (s, v) = call(&st, post("/api/v1/jobs", "{not json", None)).await;
    assert_eq!(s, StatusCode::BAD_REQUEST);
    assert_error_body(&v, "bad_request");
}

#[tokio::test]
async fn invalid_scene_is_422_with_paths() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), None).await;
    let mut sc = scene();
    sc["materials"]["m"]["poissons_ratio"] = json!(0.7);
    let (s, v) = call(&st, post("/api/v1/jobs", sc.to_string(), None)).await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY);
    assert_error_body(&v, "invalid_scene");
    assert_eq!(v["details"][0]["path"], "materials.m.poissons_ratio");

    let mut sc = scene();
    sc["grid"]["typo"] = json!(1);
    let (s, v) = call(
        &st,
        post("/api/v1/jobs", json!({"scene": sc}).to_string(), None),
    )
    .await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY);
    assert!(
        v["details"][0]["path"]
            .as_str()
            .unwrap()
            .starts_with("grid"),
        "{v}"
    );
    assert!(
        v["details"][0]["message"]
            .as_str()
            .unwrap()
            .contains("typo"),
        "{v}"
    );
    assert_eq!(st.store.count_all().await.unwrap(), 0);
}

#[tokio::test]
async fn oversized_body_is_413_and_limits_are_422() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), None).await;
    let big = format!("{{\"description\": \"{}\"}}", "x".repeat(64 * 1024));
    let (s, v) = call(&st, post("/api/v1/jobs", big, None)).await;
    assert_eq!(s, StatusCode::PAYLOAD_TOO_LARGE);
    assert_error_body(&v, "payload_too_large");

    let mut sc = scene();
    sc["bodies"][0]["particles_per_cell"] = json!(4); // 3200 particles > 1000
    let (s, v) = call(&st, post("/api/v1/scenes/validate", sc.to_string(), None)).await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY);
    assert_error_body(&v, "limit_exceeded");
    assert!(v["message"].as_str().unwrap().contains("max_particles"));
    assert_eq!(st.store.count_all().await.unwrap(), 0);
}

#[tokio::test]
async fn tokens_are_required_where_configured() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), Some("tok")).await;
    let (s, v) = call(&st, post("/api/v1/jobs", scene().to_string(), None)).await;
    assert_eq!(s, StatusCode::UNAUTHORIZED);
    assert_error_body(&v, "unauthorized");
    let (s, _) = call(&st, post("/api/v1/jobs", scene().to_string(), Some("bad"))).await;
    assert_eq!(s, StatusCode::UNAUTHORIZED);
    let (s, v) = call(&st, post("/api/v1/jobs", scene().to_string(), Some("tok"))).await;
    assert_eq!(s, StatusCode::CREATED, "{v}");
    assert_eq!(v["status"], "queued");
    // Reading needs no token.
    let (s, v) = call(&st, get("/api/v1/jobs")).await;
    assert_eq!(s, StatusCode::OK);
    assert_eq!(v.as_array().unwrap().len(), 1);
    // Worker routes need the worker token.
    let (s, _) = call(
        &st,
        post("/api/v1/worker/claim", "{\"worker_id\":\"w\"}", Some("tok")),
    )
    .await;
    assert_eq!(s, StatusCode::UNAUTHORIZED);
}

#[tokio::test]
async fn unknown_ids_are_404() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), None).await;
    for uri in [
        "/api/v1/jobs/nope",
        "/api/v1/jobs/nope/energy",
        "/api/v1/jobs/nope/crack-tips",
        "/api/v1/jobs/nope/snapshots",
        "/api/v1/jobs/nope/snapshots/0/sxx.png",
        "/api/v1/jobs/nope/fields.mcap",
        "/api/v1/jobs/nope/vtk.zip",
        "/api/v1/jobs/nope/snapshots/0/sxx.json",
        "/api/v1/jobs/nope/events",
        "/api/v1/nothing-here",
    ] {
        let (s, v) = call(&st, get(uri)).await;
        assert_eq!(s, StatusCode::NOT_FOUND, "{uri}");
        assert_error_body(&v, "not_found");
    }
    let (s, _) = call(&st, get("/api/v1/jobs?status=sleeping")).await;
    assert_eq!(s, StatusCode::BAD_REQUEST);
}

/// Issue 20 routes without a socket: rerun (token, 404, `rerun_of`), the list's `q` and
/// repeated `label`, and 400s that name the query parameter.
#[tokio::test]
async fn rerun_search_and_parameter_errors() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), Some("tok")).await;
    let body = json!({"scene": scene(), "labels": {"a": "1", "b": "2"}}).to_string();
    let (s, job) = call(&st, post("/api/v1/jobs", body, Some("tok"))).await;
    assert_eq!(s, StatusCode::CREATED, "{job}");
    let id = job["id"].as_str().unwrap().to_string();
    let rerun = format!("/api/v1/jobs/{id}/rerun");
    let (s, v) = call(&st, post(&rerun, "", None)).await;
    assert_eq!(s, StatusCode::UNAUTHORIZED);
    assert_error_body(&v, "unauthorized");
    let (s, v) = call(&st, post("/api/v1/jobs/nope/rerun", "", Some("tok"))).await;
    assert_eq!(s, StatusCode::NOT_FOUND);
    assert_error_body(&v, "not_found");
    let (s, r) = call(&st, post(&rerun, "", Some("tok"))).await;
    assert_eq!(s, StatusCode::CREATED, "{r}");
    assert_eq!(r["rerun_of"], id.as_str());
    assert_eq!(r["labels"], job["labels"]);
    assert_eq!(r["name"], "unit");
    assert_eq!(r["scene"], job["scene"]);
    let (_, again) = call(
        &st,
        get(&format!("/api/v1/jobs/{}", r["id"].as_str().unwrap())),
    )
    .await;
    assert_eq!(again["rerun_of"], id.as_str());
    // Both jobs match `q` (any case) and both labels; a third label value matches none.
    let (s, list) = call(&st, get("/api/v1/jobs?q=UNI&label=a:1&label=b:2")).await;
    assert_eq!(s, StatusCode::OK);
    assert_eq!(list.as_array().map(Vec::len), Some(2), "{list}");
    let (_, list) = call(&st, get("/api/v1/jobs?label=a:1&label=b:3")).await;
    assert_eq!(list.as_array().map(Vec::len), Some(0), "{list}");
    let (_, list) = call(&st, get("/api/v1/jobs?q=zzz")).await;
    assert_eq!(list.as_array().map(Vec::len), Some(0), "{list}");
    for (uri, param) in [
        ("/api/v1/jobs?unknown=1", "unknown"),
        ("/api/v1/jobs?cursor=1&cursor=2", "cursor"),
        ("/api/v1/jobs?limit=x", "limit"),
    ] {
        let (s, v) = call(&st, get(uri)).await;
        assert_eq!(s, StatusCode::BAD_REQUEST, "{uri}");
        assert_error_body(&v, "bad_request");
        assert_eq!(v["details"][0]["path"], param, "{uri}: {v}");
    }
    // Picture options are checked before the job is looked up.
    let (s, v) = call(
        &st,
        get(&format!("/api/v1/jobs/{id}/snapshots/0/sxx.png?width=-3")),
    )
    .await;
    assert_eq!(s, StatusCode::BAD_REQUEST);
    assert_eq!(v["details"][0]["path"], "width", "{v}");
    // A queued job has no snapshots: the zip is a 404 saying so.
    let (s, v) = call(&st, get(&format!("/api/v1/jobs/{id}/vtk.zip"))).await;
    assert_eq!(s, StatusCode::NOT_FOUND);
    assert!(
        v["message"]
            .as_str()
            .unwrap()
            .contains("no field snapshots yet"),
        "{v}"
    );
}

#[tokio::test]
async fn claim_fence_and_finish() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), None).await;
    let (_, job) = call(&st, post("/api/v1/jobs", scene().to_string(), None)).await;
    let id = job["id"].as_str().unwrap().to_string();
    let (s, c) = call(
        &st,
        post(
            "/api/v1/worker/claim",
            "{\"worker_id\":\"w1\",\"wait_seconds\":0}",
            Some("wt"),
        ),
    )
    .await;
    assert_eq!(s, StatusCode::OK);
    assert_eq!(c["job_id"], id.as_str());
    let fence = c["fence"].as_i64().unwrap();
    // Nothing else to claim.
    let resp = app(st.clone())
        .oneshot(post(
            "/api/v1/worker/claim",
            "{\"worker_id\":\"w2\",\"wait_seconds\":0}",
            Some("wt"),
        ))
        .await
        .unwrap();
    assert_eq!(resp.status(), StatusCode::NO_CONTENT);
    // A stale fence is refused.
    let rows = json!({"fence": fence + 7, "rows": [{"time": 0.0, "kinetic": 1.0, "strain": null,
        "external_work": 0.0, "dissipated": 0.0, "total_error": 0.0}]});
    let (s, v) = call(
        &st,
        post(
            &format!("/api/v1/worker/jobs/{id}/energy"),
            rows.to_string(),
            Some("wt"),
        ),
    )
    .await;
    assert_eq!(s, StatusCode::CONFLICT);
    assert_error_body(&v, "conflict");
    let mut rows = rows;
    rows["fence"] = json!(fence);
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
    // Cancel reaches the heartbeat.
    let (s, _) = call(&st, post(&format!("/api/v1/jobs/{id}/cancel"), "", None)).await;
    assert_eq!(s, StatusCode::OK);
    let (s, hb) = call(
        &st,
        post(
            &format!("/api/v1/worker/jobs/{id}/heartbeat"),
            json!({"fence": fence}).to_string(),
            Some("wt"),
        ),
    )
    .await;
    assert_eq!(s, StatusCode::OK);
    assert_eq!(hb["cancel"], true);
    let (_, e) = call(&st, get(&format!("/api/v1/jobs/{id}/energy"))).await;
    assert_eq!(e.as_array().unwrap().len(), 1);
    assert!(e[0]["strain"].is_null(), "NaN travels as null: {e}");
    // Running jobs cannot be deleted.
    let (s, v) = call(
        &st,
        Request::delete(format!("/api/v1/jobs/{id}"))
            .body(Body::empty())
            .unwrap(),
    )
    .await;
    assert_eq!(s, StatusCode::CONFLICT, "{v}");
}

#[tokio::test]
async fn service_pages_are_served() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), None).await;
    let (s, api) = call(&st, get("/api/v1/openapi.json")).await;
    assert_eq!(s, StatusCode::OK);
    assert!(api["paths"]["/api/v1/jobs/{id}/snapshots/{index}/{file}"].is_object());
    assert_eq!(
        api["components"]["securitySchemes"]["bearer"]["scheme"],
        "bearer"
    );
    let resp = app(st.clone()).oneshot(get("/")).await.unwrap();
    assert_eq!(resp.status(), StatusCode::OK);
    let resp = app(st.clone()).oneshot(get("/api/v1/docs/")).await.unwrap();
    assert_eq!(resp.status(), StatusCode::OK);
    let (s, h) = call(&st, get("/api/v1/health")).await;
    assert_eq!(s, StatusCode::OK);
    assert_eq!(h["status"], "ok");
    let (s, v) = call(&st, get("/api/v1/scenes")).await;
    assert_eq!(s, StatusCode::OK);
    assert!(v.is_array());
}

#[tokio::test]
async fn priorities_order_claims_and_lost_leases_hit_the_attempt_limit() {
    use std::time::Duration;
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), None).await;
    let low = json!({"scene": scene(), "priority": 0});
    let high = json!({"scene": scene(), "priority": 5, "labels": {"k": "v"}});
    let (_, a) = call(&st, post("/api/v1/jobs", low.to_string(), None)).await;
    let (_, b) = call(&st, post("/api/v1/jobs", high.to_string(), None)).await;
    let first = st.store.claim("w", Duration::ZERO).await.unwrap().unwrap();
    assert_eq!(
        first.job.id,
        b["id"].as_str().unwrap(),
        "higher priority first"
    );
    // Its worker is lost every time: re-queued until the attempt limit, then failed.
    let max = st.cfg.max_attempts;
    for attempt in 1..=max {
        tokio::time::sleep(Duration::from_millis(5)).await;
        let reaped = st.store.reap(max).await.unwrap();
        assert_eq!(reaped.len(), 1);
        let j = &reaped[0];
        if attempt < max {
            assert_eq!(j.status, JobStatus::Queued);
            let again = st.store.claim("w", Duration::ZERO).await.unwrap().unwrap();
            assert_eq!(again.job.id, j.id);
            assert_eq!(again.job.fence, attempt as i64 + 1);
        } else {
            assert_eq!(j.status, JobStatus::Failed);
            assert!(
                j.message.as_deref().unwrap().contains("lost"),
                "{:?}",
                j.message
            );
        }
    }
    let next = st
        .store
        .claim("w", Duration::from_secs(30))
        .await
        .unwrap()
        .unwrap();
    assert_eq!(next.job.id, a["id"].as_str().unwrap());
}

#[tokio::test]
async fn an_enormous_scene_is_refused_before_its_lattice_is_walked() {
    // 1 µm cells over a 10 mm × 10 mm plate at 8 × 8 particles per cell: 1.0e8 grid nodes
    // (within what validation accepts) and 6.4e9 particles for it to place, minutes of
    // lattice walk; the estimate from the region refuses it at once.
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), None).await;
    let mut sc = scene();
    sc["grid"] = json!({ "cell_size": 1.0e-6, "min": [0.0, 0.0], "max": [0.0102, 0.0102] });
    sc["bodies"][0]["region"] =
        json!({ "rectangle": { "min": [0.0001, 0.0001], "max": [0.0101, 0.0101] } });
    sc["bodies"][0]["particles_per_cell"] = json!(8);
    for uri in ["/api/v1/scenes/validate", "/api/v1/jobs"] {
        let t0 = std::time::Instant::now();
        let (s, v) = call(&st, post(uri, sc.to_string(), None)).await;
        let took = t0.elapsed();
        assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{uri}: {v}");
        assert_error_body(&v, "limit_exceeded");
        assert!(
            v["message"].as_str().unwrap().contains("max_particles"),
            "{v}"
        );
        assert_eq!(v["details"][0]["path"], "bodies", "{v}");
        assert!(
            took < std::time::Duration::from_secs(1),
            "{uri} took {took:?}"
        );
    }
    // The same through a sweep.
    let body = json!({"scene": sc, "parameters": {"time.cfl": [0.2, 0.3]}});
    let t0 = std::time::Instant::now();
    let (s, v) = call(&st, post("/api/v1/sweeps", body.to_string(), None)).await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    assert!(
        v["message"].as_str().unwrap().contains("max_particles"),
        "{v}"
    );
    assert!(t0.elapsed() < std::time::Duration::from_secs(1));
    assert_eq!(st.store.count_all().await.unwrap(), 0);

    // A body whose bounding box is mostly empty (a thin slanted polygon) is refused by the
    // work bound: validation would examine every site of the box.
    let mut sc = scene();
    sc["grid"] = json!({ "cell_size": 1.0e-6, "min": [0.0, 0.0], "max": [0.0102, 0.0102] });
    sc["bodies"][0]["region"] = json!({ "polygon": { "points":
        [[0.0001, 0.0001], [0.0101, 0.0101], [0.0101, 0.010101]] } });
    let t0 = std::time::Instant::now();
    let (s, v) = call(&st, post("/api/v1/scenes/validate", sc.to_string(), None)).await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    assert!(
        v["details"][0]["message"]
            .as_str()
            .unwrap()
            .contains("candidate"),
        "{v}"
    );
    assert!(t0.elapsed() < std::time::Duration::from_secs(1));
}

#[tokio::test]
async fn worker_routes_check_the_token_before_the_body() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), None).await;
    for uri in [
        "/api/v1/worker/claim",
        "/api/v1/worker/jobs/x/heartbeat",
        "/api/v1/worker/jobs/x/energy",
        "/api/v1/worker/jobs/x/finish",
        "/api/v1/worker/jobs/x/died",
        "/api/v1/worker/jobs/x/release",
    ] {
        let (s, v) = call(&st, post(uri, "{not json", None)).await;
        assert_eq!(s, StatusCode::UNAUTHORIZED, "{uri}: {v}");
        assert_error_body(&v, "unauthorized");
        let (s, v) = call(&st, post(uri, "{not json", Some("wt"))).await;
        assert_eq!(s, StatusCode::BAD_REQUEST, "{uri}: {v}");
    }
}

#[tokio::test]
async fn openapi_names_the_api_types() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), None).await;
    let (s, api) = call(&st, get("/api/v1/openapi.json")).await;
    assert_eq!(s, StatusCode::OK);
    let schemas = &api["components"]["schemas"];
    for name in [
        "JobInfo",
        "JobStatus",
        "ErrorBody",
        "ErrorDetail",
        "CrackTipRow",
        "EnergyRow",
        "SnapshotInfo",
        "Summary",
        "Progress",
        "SweepInfo",
        "Claim",
        "Heartbeat",
        "HealthInfo",
        "ValidateResponse",
    ] {
        assert!(schemas[name].is_object(), "no schema {name}");
    }
    let created = &api["paths"]["/api/v1/jobs"]["post"]["responses"]["201"];
    assert_eq!(
        created["content"]["application/json"]["schema"]["$ref"], "#/components/schemas/JobInfo",
        "{created}"
    );
}

#[tokio::test]
async fn a_corrupt_row_is_a_500_not_a_default() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), None).await;
    let (_, job) = call(&st, post("/api/v1/jobs", scene().to_string(), None)).await;
    let id = job["id"].as_str().unwrap().to_string();
    // A raw statement on the store's connection (it holds the file's exclusive lock)
    // damages the row's labels.
    sqlx::query("UPDATE jobs SET labels = 'not json' WHERE id = ?")
        .bind(&id)
        .execute(st.store.sqlite_pool().unwrap())
        .await
        .unwrap();
    let (s, v) = call(&st, get(&format!("/api/v1/jobs/{id}"))).await;
    assert_eq!(s, StatusCode::INTERNAL_SERVER_ERROR, "{v}");
    assert_error_body(&v, "internal");
    assert!(
        !v["message"].as_str().unwrap().contains("labels"),
        "no internals: {v}"
    );
    let err = st.store.get(&id).await.unwrap_err();
    assert!(err.to_string().contains("`labels`"), "{err}");
}

/// The death report of a remote worker's supervisor (`POST /worker/jobs/{id}/died`):
/// fenced like every worker write, it re-queues the job with the cause in its message, a
/// repeated or stale report is 409, and a cause showing the worker ran out of memory
/// fails the job at once (it would again), as for a local worker.
#[tokio::test]
async fn a_reported_worker_death_releases_the_claim_by_the_local_rules() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), None).await;
    let (_, job) = call(&st, post("/api/v1/jobs", scene().to_string(), None)).await;
    let id = job["id"].as_str().unwrap().to_string();
    let claim = |worker: &str| {
        post(
            "/api/v1/worker/claim",
            json!({"worker_id": worker, "wait_seconds": 0}).to_string(),
            Some("wt"),
        )
    };
    let died = |fence: i64, cause: &str| {
        post(
            &format!("/api/v1/worker/jobs/{id}/died"),
            json!({"fence": fence, "cause": cause}).to_string(),
            Some("wt"),
        )
    };
    let (_, c) = call(&st, claim("remote-1")).await;
    let fence = c["fence"].as_i64().unwrap();
    // A wrong fence changes nothing.
    let (s, v) = call(&st, died(fence + 1, "killed by signal 9")).await;
    assert_eq!(s, StatusCode::CONFLICT, "{v}");
    let (_, j) = call(&st, get(&format!("/api/v1/jobs/{id}"))).await;
    assert_eq!(j["status"], "running", "{j}");
    let cause = "killed by signal 9 (SIGKILL: e.g. the out-of-memory killer)";
    let (s, j) = call(&st, died(fence, cause)).await;
    assert_eq!(s, StatusCode::OK, "{j}");
    assert_eq!(j["status"], "queued", "{j}");
    assert!(j["message"].as_str().unwrap().contains(cause), "{j}");
    // Released once: the same report again is stale.
    let (s, _) = call(&st, died(fence, cause)).await;
    assert_eq!(s, StatusCode::CONFLICT);
    // Out of memory: failed at once although attempts are left.
    let (_, c) = call(&st, claim("remote-2")).await;
    assert_eq!(c["attempt"], 2);
    let oom = "aborted (signal 6, SIGABRT: e.g. a failed memory allocation); its last \
               output: memory allocation of 20412450768 bytes failed";
    let (s, j) = call(&st, died(c["fence"].as_i64().unwrap(), oom)).await;
    assert_eq!(s, StatusCode::OK, "{j}");
    assert_eq!(j["status"], "failed", "{j}");
    assert!(
        j["message"]
            .as_str()
            .unwrap()
            .contains("memory allocation of 20412450768 bytes failed"),
        "{j}"
    );
}

/// `POST /api/v1/worker/jobs/{id}/release`: a batch worker told to stop hands its claim
/// back; the job is queued again without counting the attempt (cancelled if that was asked),
/// fenced like every worker write.
#[tokio::test]
async fn a_handed_back_claim_is_queued_again_without_counting_the_attempt() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), None).await;
    let (_, job) = call(&st, post("/api/v1/jobs", scene().to_string(), None)).await;
    let id = job["id"].as_str().unwrap().to_string();
    let claim = |worker: &str| {
        post(
            "/api/v1/worker/claim",
            json!({"worker_id": worker, "wait_seconds": 0}).to_string(),
            Some("wt"),
        )
    };
    let release = |fence: i64| {
        post(
            &format!("/api/v1/worker/jobs/{id}/release"),
            json!({"fence": fence, "reason": "SIGUSR1, at step 40",
                   "worker": "node7-slurm12_3-99-abc, slurm job 15 (array 12 task 3)"})
            .to_string(),
            Some("wt"),
        )
    };
    let (_, c) = call(&st, claim("node7-slurm12_3-99-abc")).await;
    assert_eq!(c["attempt"], 1);
    let fence = c["fence"].as_i64().unwrap();
    let (s, v) = call(&st, release(fence + 1)).await;
    assert_eq!(
        s,
        StatusCode::CONFLICT,
        "a wrong fence changes nothing: {v}"
    );
    let (s, j) = call(&st, release(fence)).await;
    assert_eq!(s, StatusCode::OK, "{j}");
    assert_eq!(j["status"], "queued", "{j}");
    assert_eq!(j["attempts"], 0, "no attempt counted: {j}");
    let m = j["message"].as_str().unwrap();
    assert!(
        m.contains("handed back by its worker node7-slurm12_3-99-abc")
            && m.contains("slurm job 15 (array 12 task 3)")
            && m.contains("SIGUSR1, at step 40"),
        "{m}"
    );
    let (s, _) = call(&st, release(fence)).await;
    assert_eq!(s, StatusCode::CONFLICT, "released once");
    // Another worker claims it as its first attempt; handed back while cancellation was
    // asked, it ends cancelled.
    let (_, c) = call(&st, claim("w2")).await;
    assert_eq!(c["attempt"], 1, "{c}");
    let (s, _) = call(&st, post(&format!("/api/v1/jobs/{id}/cancel"), "", None)).await;
    assert_eq!(s, StatusCode::OK);
    let (s, j) = call(&st, release(c["fence"].as_i64().unwrap())).await;
    assert_eq!(s, StatusCode::OK, "{j}");
    assert_eq!(j["status"], "cancelled", "{j}");
}

/// `GET /api/v1/scenes`: every example carries its run size (validation's) and an estimated
/// wall time, first at the documented nominal throughput, then at the mean measured
/// throughput of the completed runs.
#[tokio::test]
async fn scenes_carry_their_size_and_an_estimated_wall_time() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), None).await;
    let (s, v) = call(&st, get("/api/v1/scenes")).await;
    assert_eq!(s, StatusCode::OK);
    let list = v.as_array().unwrap();
    assert!(!list.is_empty());
    let nominal = fracture_server::http::NOMINAL_PARTICLE_STEPS_PER_SECOND;
    for e in list {
        let name = e["name"].as_str().unwrap();
        let (p, n, ps) = (
            e["particles"].as_u64().unwrap(),
            e["steps"].as_u64().unwrap(),
            e["particle_steps"].as_u64().unwrap(),
        );
        assert!(p > 0 && n > 0, "{name}: {p} particles, {n} steps");
        assert_eq!(ps, p * n, "{name}");
        let est = e["estimated_wall_seconds"].as_f64().unwrap();
        assert!(
            (est - ps as f64 / nominal).abs() <= 1e-9 * est,
            "{name}: {est}"
        );
        assert_eq!(e["estimate_particle_steps_per_second"], json!(nominal));
        assert!(e["estimate_basis"].as_str().unwrap().starts_with("nominal"));
    }
    // The same sizes as validation reports for the scene.
    let first = &list[0];
    let (s, size) = call(
        &st,
        post("/api/v1/scenes/validate", first["scene"].to_string(), None),
    )
    .await;
    if s == StatusCode::OK {
        assert_eq!(size["particles"], first["particles"]);
        assert_eq!(size["steps"], first["steps"]);
    }

    // Two completed runs measured at 2 and 4 M particle-steps/s: the estimate uses 3 M/s.
    for rate in [2.0e6, 4.0e6] {
        let body = json!({"scene": scene(), "cache": "force"});
        let (s, j) = call(&st, post("/api/v1/jobs", body.to_string(), None)).await;
        assert_eq!(s, StatusCode::CREATED, "{j}");
        let c = st
            .store
            .claim("w", std::time::Duration::ZERO)
            .await
            .unwrap()
            .unwrap();
        let summary: fracture_api::results::Summary = serde_json::from_value(json!({
            "status": "completed", "steps": 3, "time_step": 1e-7, "sim_time": 3e-7,
            "particles": 880, "grid_nodes": 299, "active_nodes_mean": 250.0,
            "wall_seconds": 0.25, "particle_steps_per_second": rate, "threads": 1,
            "scene_hash": format!("h{rate}"), "solver_version": "test"}))
        .unwrap();
        st.store
            .finish(&c.job.id, c.job.fence, &summary)
            .await
            .unwrap();
    }
    let (_, v) = call(&st, get("/api/v1/scenes")).await;
    let e = &v[0];
    assert_eq!(e["estimate_particle_steps_per_second"], json!(3.0e6));
    assert!(
        e["estimate_basis"]
            .as_str()
            .unwrap()
            .starts_with("measured")
    );
    let est = e["estimated_wall_seconds"].as_f64().unwrap();
    let ps = e["particle_steps"].as_u64().unwrap() as f64;
    assert!((est - ps / 3.0e6).abs() <= 1e-9 * est, "{est}");
}

/// `GET /docs/{name}.md` serves the repository's guides as Markdown; anything else is a
/// 404 in the API's error format (no path escapes `docs/`).
#[tokio::test]
async fn docs_route_serves_the_guides_as_markdown() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), None).await;
    let names = fracture_server::assets::doc_names();
    assert!(names.contains(&"dashboard"), "{names:?}");
    let (s, h, body) = app::send_raw(&st, get("/docs/dashboard.md")).await;
    assert_eq!(s, StatusCode::OK);
    assert!(
        h["content-type"]
            .to_str()
            .unwrap()
            .starts_with("text/markdown"),
        "{h:?}"
    );
    let text = String::from_utf8(body).unwrap();
    assert!(text.starts_with("# The web dashboard"), "{text:.80}");
    for bad in [
        "/docs/nope.md",
        "/docs/dashboard",
        "/docs/..%2FCargo.toml",
        "/docs/rosakis",
    ] {
        let (s, v) = call(&st, get(bad)).await;
        assert_eq!(s, StatusCode::NOT_FOUND, "{bad}");
        assert_error_body(&v, "not_found");
    }
}
