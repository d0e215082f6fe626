//! What a hostile tester found, each as a test against `app(state)` (no socket): storage
//! faults (a full store answers 507 and keeps what it acknowledged, no connection is left
//! inside a transaction), cost limits (memory estimate, particle-steps), browser and
//! network safety (JSON only, `Host` allow-list, same-origin state changes, headers), and
//! the contract gaps (query errors, 405 bodies, unknown parameters, name and label sizes,
//! a missing MCAP file, the worker token before the body).

#![allow(clippy::unwrap_used)]

#[path = "support/app.rs"]
mod app;

use std::time::{Duration, Instant};

use axum::body::Body;
use axum::http::{Request, StatusCode};
use fracture_api::results::{RunStatus, Summary};
use fracture_server::config::{Config, Limits};
use fracture_server::files::JobFiles;
use fracture_server::store::Store;
use fracture_server::{AppState, app};
use serde_json::{Value, json};
use tower::ServiceExt;

async fn state_with(dir: &std::path::Path, limits: Limits) -> AppState {
    let store = Store::open(&dir.join("t.db")).await.unwrap();
    let cfg = Config {
        worker_token: "wt".into(),
        limits,
        ..Config::default()
    };
    AppState::new(store, cfg, JobFiles::new(dir)).0
}

async fn state(dir: &std::path::Path) -> AppState {
    state_with(dir, Limits::default()).await
}

fn scene() -> Value {
    app::scene("unit", 1.0e-5)
}

use app::call;

fn post_json(uri: &str, body: impl Into<Body>) -> Request<Body> {
    Request::post(uri)
        .header("content-type", "application/json")
        .body(body.into())
        .unwrap()
}

fn worker_post(uri: &str, body: impl Into<Body>) -> Request<Body> {
    Request::post(uri)
        .header("content-type", "application/json")
        .header("authorization", "Bearer wt")
        .body(body.into())
        .unwrap()
}

fn get(uri: &str) -> Request<Body> {
    Request::get(uri).body(Body::empty()).unwrap()
}

fn assert_error(v: &Value, kind: &str) {
    assert_eq!(v["error"], kind, "{v}");
    assert!(v["message"].as_str().is_some_and(|m| !m.is_empty()), "{v}");
    assert!(v["details"].is_array(), "{v}");
}

async fn submit(st: &AppState, body: &Value) -> (StatusCode, Value) {
    call(st, post_json("/api/v1/jobs", body.to_string())).await
}

// ---------------------------------------------------------------------------------------
// Storage faults

/// Cap every pooled connection at `pages` database pages (`PRAGMA max_page_count`): past
/// it SQLite answers `SQLITE_FULL`, as on a full disk. 0 lifts the cap.
async fn cap_pages(store: &Store, pages: u64) {
    let pool = store.sqlite_pool().unwrap();
    let mut held = Vec::new();
    for _ in 0..pool.options().get_max_connections() {
        held.push(pool.acquire().await.unwrap());
    }
    for c in &mut held {
        let n = if pages == 0 { 1 << 30 } else { pages };
        sqlx::raw_sql(sqlx::AssertSqlSafe(format!("PRAGMA max_page_count = {n}")))
            .execute(&mut **c)
            .await
            .unwrap();
    }
}

async fn page_count(store: &Store) -> u64 {
    let n: i64 = sqlx::query_scalar("PRAGMA page_count")
        .fetch_one(store.sqlite_pool().unwrap())
        .await
        .unwrap();
    n as u64
}

/// A full store: writes answer 507 `insufficient_storage` at once, every 201 is kept (also
/// after reopening), a 204 delete stays deleted, reads agree, and writes work again as soon
/// as there is room — without a restart.
#[tokio::test]
async fn a_full_store_answers_507_keeps_what_it_acknowledged_and_recovers() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path()).await;
    // A finished job to delete while the store is full.
    let (s, j) = submit(&st, &scene()).await;
    assert_eq!(s, StatusCode::CREATED);
    let doomed = j["id"].as_str().unwrap().to_string();
    let (s, _) = call(&st, post_json(&format!("/api/v1/jobs/{doomed}/cancel"), "")).await;
    assert_eq!(s, StatusCode::OK);

    cap_pages(&st.store, page_count(&st.store).await + 6).await;
    let mut kept = Vec::new();
    let mut refused = 0;
    for i in 0..400 {
        // Big labels fill pages quickly.
        let labels: serde_json::Map<String, Value> = (0..8)
            .map(|k| {
                (
                    format!("k{k}"),
                    Value::String(format!("{i}-{}", "x".repeat(250))),
                )
            })
            .collect();
        let t0 = Instant::now();
        let (s, v) = submit(&st, &json!({"scene": scene(), "labels": labels})).await;
        match s {
            StatusCode::CREATED => kept.push(v["id"].as_str().unwrap().to_string()),
            StatusCode::INSUFFICIENT_STORAGE => {
                assert_error(&v, "insufficient_storage");
                assert!(
                    v["message"].as_str().unwrap().contains("full"),
                    "the message says why: {v}"
                );
                assert!(t0.elapsed() < Duration::from_secs(1), "507 at once");
                refused += 1;
                if refused == 5 {
                    break;
                }
            }
            other => panic!("unexpected {other}: {v}"),
        }
    }
    assert!(refused == 5, "the store never filled up");
    assert!(!kept.is_empty());
    // Reads agree with each other and with the answers.
    for id in &kept {
        let (s, v) = call(&st, get(&format!("/api/v1/jobs/{id}"))).await;
        assert_eq!(s, StatusCode::OK, "{id}: {v}");
        assert_eq!(v["attempts"], 0);
    }
    let (_, list) = call(&st, get("/api/v1/jobs?status=queued&limit=500")).await;
    assert_eq!(list.as_array().unwrap().len(), kept.len());
    // A delete still works on a full store (it frees pages) and is final.
    let resp = app(st.clone())
        .oneshot(
            Request::delete(format!("/api/v1/jobs/{doomed}"))
                .body(Body::empty())
                .unwrap(),
        )
        .await
        .unwrap();
    let deleted = resp.status() == StatusCode::NO_CONTENT;
    assert!(
        deleted || resp.status() == StatusCode::INSUFFICIENT_STORAGE,
        "{}",
        resp.status()
    );
    // Room again: the next write succeeds without a restart.
    cap_pages(&st.store, 0).await;
    let (s, v) = submit(&st, &scene()).await;
    assert_eq!(s, StatusCode::CREATED, "{v}");
    kept.push(v["id"].as_str().unwrap().to_string());

    // Reopen: everything acknowledged is there, the deleted job is not.
    st.store.close().await;
    let again = Store::open(&dir.path().join("t.db")).await.unwrap();
    for id in &kept {
        assert!(again.get(id).await.unwrap().is_some(), "201 job {id} lost");
    }
    assert_eq!(
        again.get(&doomed).await.unwrap().is_none(),
        deleted,
        "a 204 delete is final, a refused one changed nothing"
    );
    assert_eq!(
        again.count_all().await.unwrap() as usize,
        kept.len() + usize::from(!deleted)
    );
}

/// The store maps no file into the process: the WAL index is in heap memory (EXCLUSIVE
/// locking mode), so a data folder whose files become unwritable under the server
/// (`chattr +i`, a failing file system) gives I/O errors (507), not SIGBUS at the next
/// write to a mapped page. Before, `t.db-shm` was created and mapped by every connection.
#[tokio::test]
async fn the_store_maps_no_shared_memory_file() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path()).await;
    for _ in 0..3 {
        let (s, v) = submit(&st, &scene()).await;
        assert_eq!(s, StatusCode::CREATED, "{v}");
    }
    let (s, _) = call(&st, get("/api/v1/jobs")).await;
    assert_eq!(s, StatusCode::OK);
    assert!(dir.path().join("t.db-wal").exists(), "not in WAL mode");
    assert!(
        !dir.path().join("t.db-shm").exists(),
        "a -shm file was created"
    );
    #[cfg(target_os = "linux")]
    {
        let maps = std::fs::read_to_string("/proc/self/maps").unwrap();
        let db = dir.path().display().to_string();
        assert!(
            !maps.lines().any(|l| l.contains(&db)),
            "a data folder file is mapped:\n{maps}"
        );
    }
}

/// A connection that comes back to the pool inside a transaction (what a failed `COMMIT`
/// on a full disk can leave) is rolled back and closed: it neither holds the write lock
/// ("database is locked" for every other writer) nor swallows later writes.
#[tokio::test]
async fn no_connection_returns_to_the_pool_inside_a_transaction() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path()).await;
    {
        let mut c = st.store.sqlite_pool().unwrap().acquire().await.unwrap();
        sqlx::raw_sql(
            "BEGIN IMMEDIATE; INSERT INTO jobs (id, name, status, priority, labels, scene, \
             end_time, created_at) VALUES ('ghost', 'g', 'queued', 0, '{}', '{}', 1.0, 'now')",
        )
        .execute(&mut *c)
        .await
        .unwrap();
    } // back to the pool with the transaction open
    let t0 = Instant::now();
    for _ in 0..10 {
        let (s, v) = submit(&st, &scene()).await;
        assert_eq!(s, StatusCode::CREATED, "{v}");
    }
    assert!(
        t0.elapsed() < Duration::from_secs(5),
        "writers were blocked"
    );
    assert!(st.store.get("ghost").await.unwrap().is_none());
    st.store.close().await;
    let again = Store::open(&dir.path().join("t.db")).await.unwrap();
    assert_eq!(again.count_all().await.unwrap(), 10, "every 201 committed");
}

// ---------------------------------------------------------------------------------------
// Cost limits

/// The reported scene: 1,600 particles on a 196 M-node grid (20 GB) is refused at once.
#[tokio::test]
async fn a_196_m_node_grid_is_refused_by_its_memory_estimate() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path()).await;
    let mut sc = scene();
    sc["grid"] = json!({ "cell_size": 1e-5, "min": [0.0, 0.0], "max": [0.14, 0.14] });
    sc["bodies"][0]["region"] =
        json!({ "rectangle": { "min": [0.0, 0.0], "max": [0.0004, 0.0004] } });
    for route in ["/api/v1/jobs", "/api/v1/scenes/validate"] {
        let t0 = Instant::now();
        let (s, v) = call(&st, post_json(route, sc.to_string())).await;
        assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{route}: {v}");
        assert_error(&v, "limit_exceeded");
        let m = v["details"][0]["message"].as_str().unwrap();
        assert!(
            v["message"].as_str().unwrap().contains("max_memory_bytes"),
            "{v}"
        );
        assert!(m.contains("196"), "names the grid nodes: {m}");
        assert!(
            m.contains("GB") && m.contains("max_memory_bytes = "),
            "value and limit: {m}"
        );
        assert_eq!(v["details"][0]["path"], "grid.cell_size");
        assert!(t0.elapsed() < Duration::from_secs(2));
    }
    let (_, list) = call(&st, get("/api/v1/jobs")).await;
    assert_eq!(list, json!([]));
}

/// 4 M particles × 500 k steps = 2·10¹² particle-steps: refused before any lattice walk.
#[tokio::test]
async fn two_trillion_particle_steps_are_refused_before_the_walk() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path()).await;
    let mut sc = scene();
    let h = 0.001;
    // 2000 × 2000 cells, one particle per cell: 4 M particles.
    sc["grid"] = json!({ "cell_size": h, "min": [0.0, 0.0], "max": [2.002, 2.002] });
    sc["bodies"][0]["region"] =
        json!({ "rectangle": { "min": [0.001, 0.001], "max": [2.001, 2.001] } });
    sc["bodies"][0]["particles_per_cell"] = json!(1);
    let dt = 0.5 * h / 2551.0; // cfl 0.5, c_L of the material in plane strain
    sc["time"] = json!({ "end": dt * 500_000.0, "cfl": 0.5 });
    let t0 = Instant::now();
    let (s, v) = submit(&st, &sc).await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    assert_error(&v, "limit_exceeded");
    assert!(
        v["message"]
            .as_str()
            .unwrap()
            .contains("max_particle_steps"),
        "{v}"
    );
    let d = v["details"]
        .as_array()
        .unwrap()
        .iter()
        .find(|d| d["path"] == "time.end")
        .unwrap();
    assert!(
        d["message"].as_str().unwrap().contains("particle-steps"),
        "{d}"
    );
    assert!(
        t0.elapsed() < Duration::from_secs(1),
        "refused by the cheap counts"
    );
    // The same scene with fewer steps passes the work limit.
    let mut ok = sc.clone();
    ok["time"]["end"] = json!(dt * 1000.0);
    let limits = Limits {
        max_particle_steps: 5_000_000_000,
        ..Limits::default()
    };
    assert!(
        limits
            .precheck(&serde_json::from_value(ok).unwrap())
            .is_ok()
    );
}

/// Density 1e-300 overflows the wave speed: a clear 422 naming the field, not "NaN steps".
#[tokio::test]
async fn an_overflowing_wave_speed_names_the_density() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path()).await;
    let mut sc = scene();
    sc["materials"]["m"]["density"] = json!(1e-300);
    let (s, v) = submit(&st, &sc).await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    assert_error(&v, "invalid_scene");
    assert_eq!(v["details"][0]["path"], "materials.m.density");
    assert!(!v.to_string().contains("NaN"), "{v}");
}

// ---------------------------------------------------------------------------------------
// Browser and network safety

#[tokio::test]
async fn bodies_that_are_not_json_are_415_and_store_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path()).await;
    for route in ["/api/v1/jobs", "/api/v1/scenes/validate", "/api/v1/sweeps"] {
        for ct in [
            Some("text/plain"),
            Some("application/x-www-form-urlencoded"),
            Some("multipart/form-data; boundary=x"),
            None,
        ] {
            let mut b = Request::post(route);
            if let Some(ct) = ct {
                b = b.header("content-type", ct);
            }
            let (s, v) = call(&st, b.body(Body::from(scene().to_string())).unwrap()).await;
            assert_eq!(s, StatusCode::UNSUPPORTED_MEDIA_TYPE, "{route} {ct:?}: {v}");
            assert_error(&v, "unsupported_media_type");
        }
    }
    // `application/json; charset=utf-8` is JSON.
    let (s, _) = call(
        &st,
        Request::post("/api/v1/jobs")
            .header("content-type", "application/json; charset=utf-8")
            .body(Body::from(scene().to_string()))
            .unwrap(),
    )
    .await;
    assert_eq!(s, StatusCode::CREATED);
    assert_eq!(st.store.count_all().await.unwrap(), 1);
}

#[tokio::test]
async fn a_foreign_host_is_refused_and_local_names_are_not() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path()).await;
    for (host, ok) in [
        ("evil.example:8080", false),
        ("attacker.test", false),
        ("localhost:8080", true),
        ("127.0.0.1:8080", true),
        ("[::1]:8080", true),
        ("192.168.1.20:8080", true),
    ] {
        let (s, v) = call(
            &st,
            Request::get("/api/v1/health")
                .header("host", host)
                .body(Body::empty())
                .unwrap(),
        )
        .await;
        if ok {
            assert_eq!(s, StatusCode::OK, "{host}: {v}");
        } else {
            assert_eq!(s, StatusCode::FORBIDDEN, "{host}: {v}");
            assert_error(&v, "forbidden");
            assert!(
                v["message"].as_str().unwrap().contains("--allowed-host"),
                "{v}"
            );
        }
    }
    // `--allowed-host` adds a name.
    let dir2 = tempfile::tempdir().unwrap();
    let mut st2 = state(dir2.path()).await;
    let mut cfg = (*st2.cfg).clone();
    cfg.allowed_hosts = vec!["lab.example".into()];
    st2.cfg = std::sync::Arc::new(cfg);
    let (s, _) = call(
        &st2,
        Request::get("/api/v1/health")
            .header("host", "lab.example:8080")
            .body(Body::empty())
            .unwrap(),
    )
    .await;
    assert_eq!(s, StatusCode::OK);
}

/// A page on another origin cannot cancel or delete (body-less requests) nor submit.
#[tokio::test]
async fn cross_site_state_changes_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path()).await;
    let (_, j) = submit(&st, &scene()).await;
    let id = j["id"].as_str().unwrap().to_string();
    let cancel = format!("/api/v1/jobs/{id}/cancel");
    let attempts = [
        vec![
            ("host", "127.0.0.1:8080"),
            ("origin", "http://evil.example"),
        ],
        vec![("host", "127.0.0.1:8080"), ("origin", "null")],
        vec![("host", "127.0.0.1:8080"), ("sec-fetch-site", "cross-site")],
        vec![("host", "127.0.0.1:8080"), ("sec-fetch-site", "same-site")],
        vec![
            ("host", "127.0.0.1:8080"),
            ("origin", "http://127.0.0.1:9999"),
        ],
    ];
    for headers in &attempts {
        for method in ["POST", "DELETE"] {
            let uri = if method == "POST" {
                cancel.clone()
            } else {
                format!("/api/v1/jobs/{id}")
            };
            let mut b = Request::builder().method(method).uri(&uri);
            for (k, v) in headers {
                b = b.header(*k, *v);
            }
            let (s, v) = call(&st, b.body(Body::empty()).unwrap()).await;
            assert_eq!(s, StatusCode::FORBIDDEN, "{method} {headers:?}: {v}");
            assert_error(&v, "forbidden");
        }
    }
    assert_eq!(
        st.store.get(&id).await.unwrap().unwrap().status.as_str(),
        "queued",
        "nothing changed"
    );
    // The dashboard's own requests (same origin) and tools without Origin pass.
    let (s, v) = call(
        &st,
        Request::post(&cancel)
            .header("host", "127.0.0.1:8080")
            .header("origin", "http://127.0.0.1:8080")
            .header("sec-fetch-site", "same-origin")
            .body(Body::empty())
            .unwrap(),
    )
    .await;
    assert_eq!(s, StatusCode::OK, "{v}");
    // Reads stay open cross-site (the browser's same-origin policy guards the answers).
    let (s, _) = call(
        &st,
        Request::get("/api/v1/health")
            .header("origin", "http://evil.example")
            .header("sec-fetch-site", "cross-site")
            .body(Body::empty())
            .unwrap(),
    )
    .await;
    assert_eq!(s, StatusCode::OK);
}

#[tokio::test]
async fn security_headers_are_on_every_response_and_the_dashboard_has_a_csp() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path()).await;
    for uri in [
        "/api/v1/health",
        "/api/v1/jobs/nope",
        "/",
        "/app.js",
        "/api/v1/openapi.json",
    ] {
        let (_, h, _) = app::send(&st, get(uri)).await;
        assert_eq!(h["x-content-type-options"], "nosniff", "{uri}");
        assert_eq!(h["x-frame-options"], "DENY", "{uri}");
        let csp = h["content-security-policy"].to_str().unwrap();
        assert!(csp.contains("frame-ancestors 'none'"), "{uri}: {csp}");
    }
    let (_, h, _) = app::send(&st, get("/")).await;
    let csp = h["content-security-policy"].to_str().unwrap();
    assert!(
        csp.contains("script-src 'self'") && !csp.contains("script-src 'self' 'unsafe"),
        "{csp}"
    );
    // The policy fits the pages: no inline script or inline event handler in web/*.html.
    for f in fracture_server::assets::Web::iter() {
        if !f.ends_with(".html") {
            continue;
        }
        let page = fracture_server::assets::Web::get(&f).unwrap();
        let text = String::from_utf8_lossy(&page.data).to_lowercase();
        for (i, _) in text.match_indices("<script") {
            let tag = &text[i..i + text[i..].find('>').unwrap()];
            assert!(
                tag.contains("src="),
                "{f}: inline script `{tag}` breaks the CSP"
            );
        }
        assert!(
            !text.contains(" onclick=") && !text.contains(" onload="),
            "{f}"
        );
    }
}

#[tokio::test]
async fn worker_routes_check_the_token_before_the_body() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path()).await;
    for auth in [None, Some("Bearer wrong")] {
        for (uri, body) in [
            ("/api/v1/worker/claim", "{not json"),
            ("/api/v1/worker/jobs/x/heartbeat", "[[[["),
            ("/api/v1/worker/jobs/x/snapshots?fence=1", "garbage"),
        ] {
            let mut b = Request::post(uri).header("content-type", "application/json");
            if let Some(a) = auth {
                b = b.header("authorization", a);
            }
            let (s, v) = call(&st, b.body(Body::from(body)).unwrap()).await;
            assert_eq!(s, StatusCode::UNAUTHORIZED, "{uri} {auth:?}: {v}");
            assert_error(&v, "unauthorized");
        }
    }
    let (s, v) = call(&st, worker_post("/api/v1/worker/claim", "{not json")).await;
    assert_eq!(s, StatusCode::BAD_REQUEST, "{v}");
}

// ---------------------------------------------------------------------------------------
// Contract gaps

#[tokio::test]
async fn query_errors_and_unknown_parameters_are_400_in_the_error_format() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path()).await;
    let (_, j) = submit(&st, &scene()).await;
    let id = j["id"].as_str().unwrap();
    for uri in [
        "/api/v1/jobs?limit=abc".to_string(),
        "/api/v1/jobs?statuss=queued".to_string(),
        "/api/v1/sweeps?limit=-".to_string(),
        format!("/api/v1/jobs/{id}/energy?since=abc"),
        format!("/api/v1/jobs/{id}/crack-tips?sinse=0"),
    ] {
        let (s, v) = call(&st, get(&uri)).await;
        assert_eq!(s, StatusCode::BAD_REQUEST, "{uri}: {v}");
        assert_error(&v, "bad_request");
    }
    let (s, v) = call(&st, get("/api/v1/jobs?status=queued&limit=5")).await;
    assert_eq!(s, StatusCode::OK, "{v}");
}

#[tokio::test]
async fn a_wrong_method_is_405_with_the_error_body() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path()).await;
    for (method, uri) in [
        ("PUT", "/api/v1/jobs"),
        ("PATCH", "/api/v1/health"),
        ("DELETE", "/api/v1/scenes"),
    ] {
        let (s, v) = call(
            &st,
            Request::builder()
                .method(method)
                .uri(uri)
                .body(Body::empty())
                .unwrap(),
        )
        .await;
        assert_eq!(s, StatusCode::METHOD_NOT_ALLOWED, "{method} {uri}");
        assert_error(&v, "method_not_allowed");
    }
}

#[tokio::test]
async fn names_and_labels_are_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path()).await;
    let long = "n".repeat(Limits::default().max_name_bytes + 1);
    let mut sc = scene();
    sc["name"] = json!(long);
    let cases = [
        (json!(sc.clone()), "name", "max_name_bytes"),
        (
            json!({"scene": scene(), "labels": (0..33).map(|i| (format!("k{i}"), json!("v"))).collect::<serde_json::Map<_, _>>()}),
            "labels",
            "max_labels",
        ),
        (
            json!({"scene": scene(), "labels": {"k": "v".repeat(257)}}),
            "labels.k",
            "max_label_value_bytes",
        ),
        (
            json!({"scene": scene(), "labels": {"k".repeat(65): "v"}}),
            "labels.",
            "max_label_key_bytes",
        ),
    ];
    for (body, path, limit) in cases {
        let (s, v) = submit(&st, &body).await;
        assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{limit}: {v}");
        assert_error(&v, "limit_exceeded");
        assert!(v["message"].as_str().unwrap().contains(limit), "{v}");
        assert!(
            v["details"][0]["path"].as_str().unwrap().starts_with(path),
            "{v}"
        );
    }
    // A sweep's name and labels too.
    let (s, v) = call(
        &st,
        post_json(
            "/api/v1/sweeps",
            json!({"scene": scene(), "parameters": {"time.end": [1e-5]}, "name": long}).to_string(),
        ),
    )
    .await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    assert!(
        v["message"].as_str().unwrap().contains("max_name_bytes"),
        "{v}"
    );
    assert_eq!(st.store.count_all().await.unwrap(), 0);
}

fn summary() -> Summary {
    Summary {
        status: RunStatus::Completed,
        message: None,
        failure: None,
        steps: 1,
        time_step: 1e-7,
        sim_time: 1e-7,
        particles: 1,
        grid_nodes: 1,
        active_nodes_mean: 1.0,
        wall_seconds: 0.1,
        particle_steps_per_second: 10.0,
        threads: 1,
        scene_hash: String::new(),
        solver_version: String::new(),
        fracture: None,
        provenance: None,
        tips: Vec::new(),
        references: Vec::new(),
        dimension: None,
    }
}

/// A completed job whose MCAP file was removed says so (not "no MCAP file yet").
#[tokio::test]
async fn a_missing_mcap_file_of_a_finished_job_is_reported_as_missing() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path()).await;
    let (_, j) = submit(&st, &scene()).await;
    let id = j["id"].as_str().unwrap().to_string();
    let (s, v) = call(&st, get(&format!("/api/v1/jobs/{id}/fields.mcap"))).await;
    assert_eq!(s, StatusCode::NOT_FOUND);
    assert!(
        v["message"].as_str().unwrap().contains("not started"),
        "{v}"
    );
    let (_, c) = call(
        &st,
        worker_post(
            "/api/v1/worker/claim",
            r#"{"worker_id":"w","wait_seconds":0}"#,
        ),
    )
    .await;
    let fence = c["fence"].as_i64().unwrap();
    let (s, v) = call(
        &st,
        worker_post(
            &format!("/api/v1/worker/jobs/{id}/finish"),
            json!({"fence": fence, "summary": summary()}).to_string(),
        ),
    )
    .await;
    assert_eq!(s, StatusCode::OK, "{v}");
    let resp = app(st.clone())
        .oneshot(get(&format!("/api/v1/jobs/{id}/fields.mcap")))
        .await
        .unwrap();
    assert_eq!(resp.status(), StatusCode::OK);
    std::fs::remove_file(st.files.mcap_path(&id)).unwrap();
    let (s, v) = call(&st, get(&format!("/api/v1/jobs/{id}/fields.mcap"))).await;
    assert_eq!(s, StatusCode::NOT_FOUND);
    assert_error(&v, "not_found");
    let m = v["message"].as_str().unwrap();
    assert!(m.contains("completed") && m.contains("missing"), "{m}");
}

/// A job's results folder whose removal failed (or a crash between the row and the folder)
/// is removed at the next start; folders of stored jobs are kept.
#[tokio::test]
async fn orphaned_results_folders_are_removed() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path()).await;
    let (_, j) = submit(&st, &scene()).await;
    let id = j["id"].as_str().unwrap().to_string();
    std::fs::create_dir_all(st.files.dir(&id)).unwrap();
    std::fs::create_dir_all(st.files.dir("deleted-long-ago")).unwrap();
    let known = st.store.job_ids().await.unwrap();
    assert_eq!(st.files.remove_orphans(&known), 1);
    assert!(st.files.dir(&id).exists());
    assert!(!st.files.dir("deleted-long-ago").exists());
}
