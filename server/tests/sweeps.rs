//! The sweep routes driven through `app(state)` with `oneshot`, no socket: the cartesian
//! product of jobs with labels, validation of every combination before anything is stored,
//! the combination limit, listing with cursors, cancellation and deletion.

#![allow(clippy::unwrap_used)]

#[path = "support/app.rs"]
mod app;

use axum::body::Body;
use axum::http::{Request, StatusCode};
use fracture_server::AppState;
use fracture_server::config::{Config, Limits};
use fracture_server::files::JobFiles;
use fracture_server::store::Store;
use serde_json::{Value, json};

async fn state(dir: &std::path::Path, token: Option<&str>) -> AppState {
    let store = Store::open(&dir.join("t.db")).await.unwrap();
    let cfg = Config {
        api_token: token.map(String::from),
        worker_token: "wt".into(),
        limits: Limits {
            max_particles: 1000,
            max_sweep_jobs: 6,
            ..Limits::default()
        },
        ..Config::default()
    };
    AppState::new(store, cfg, JobFiles::new(dir)).0
}

fn scene() -> Value {
    let mut s = app::scene("unit", 1.0e-5);
    s["boundary_conditions"] = json!([ { "region": { "rectangle": { "min": [0.0, 0.0], "max": [0.001, 0.012] } },
                                         "velocity": { "x": 1.0 } } ]);
    s
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

#[tokio::test]
async fn a_sweep_creates_one_labelled_job_per_combination() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), None).await;
    // Written as text: `json!` would sort the parameters, and their order matters.
    let body = format!(
        r#"{{"scene": {}, "parameters": {{"time.cfl": [0.25, 0.5],
            "boundary_conditions.0.velocity.x": [1.0, 2.5, 4]}},
            "priority": 3, "labels": {{"study": "unit"}}}}"#,
        scene()
    );
    let req = Request::post("/api/v1/sweeps")
        .header("content-type", "application/json")
        .body(Body::from(body))
        .unwrap();
    let (s, h, v) = app::send(&st, req).await;
    assert_eq!(s, StatusCode::CREATED, "{v}");
    let id = v["id"].as_str().unwrap().to_string();
    assert_eq!(
        h.get("location").unwrap().to_str().unwrap(),
        format!("/api/v1/sweeps/{id}")
    );
    assert_eq!(v["name"], "unit");
    assert_eq!(v["total"], 6);
    assert_eq!(v["status"], "queued");
    assert_eq!(v["counts"]["queued"], 6);
    assert_eq!(v["parameters"][0]["path"], "time.cfl");
    assert_eq!(v["parameters"][1]["values"], json!([1.0, 2.5, 4]));
    let jobs = v["jobs"].as_array().unwrap();
    assert_eq!(jobs.len(), 6);
    // Cartesian product, last parameter fastest; labels use short names.
    assert_eq!(jobs[0]["label"], "cfl=0.25, velocity.x=1.0");
    assert_eq!(jobs[5]["label"], "cfl=0.5, velocity.x=4");
    assert_eq!(jobs[4]["values"]["boundary_conditions.0.velocity.x"], 2.5);
    assert_eq!(jobs[4]["index"], 4);
    assert_eq!(jobs[4]["name"], "unit (cfl=0.5, velocity.x=2.5)");
    // Each job is a real job with the values set in its scene, the sweep's labels and its
    // link to the sweep.
    let jid = jobs[4]["id"].as_str().unwrap();
    let (s, _, j) = app::send(&st, get(&format!("/api/v1/jobs/{jid}"))).await;
    assert_eq!(s, StatusCode::OK);
    assert_eq!(j["sweep_id"], id.as_str());
    assert_eq!(j["priority"], 3);
    assert_eq!(j["scene"]["time"]["cfl"], 0.5);
    assert_eq!(j["scene"]["boundary_conditions"][0]["velocity"]["x"], 2.5);
    assert_eq!(j["labels"]["sweep"], id.as_str());
    assert_eq!(j["labels"]["cfl"], "0.5");
    assert_eq!(j["labels"]["velocity.x"], "2.5");
    assert_eq!(j["labels"]["study"], "unit");
    // The jobs list carries the link too; a lone job has none.
    let (_, _, lone) = app::send(&st, post("/api/v1/jobs", &scene(), None)).await;
    assert!(lone.get("sweep_id").is_none(), "{lone}");
    let (_, _, list) = app::send(&st, get("/api/v1/jobs?limit=10")).await;
    let linked = list
        .as_array()
        .unwrap()
        .iter()
        .filter(|j| j["sweep_id"] == id.as_str())
        .count();
    assert_eq!(linked, 6);
    // GET returns the same sweep with its base scene.
    let (s, _, g) = app::send(&st, get(&format!("/api/v1/sweeps/{id}"))).await;
    assert_eq!(s, StatusCode::OK);
    assert_eq!(g["scene"]["name"], "unit");
    assert_eq!(g["jobs"].as_array().unwrap().len(), 6);
    assert_eq!(g["progress"], 0.0);
}

#[tokio::test]
async fn bad_paths_values_and_sizes_are_refused_before_any_job_is_queued() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), None).await;
    let count = || async {
        let (_, _, v) = app::send(&st, get("/api/v1/jobs")).await;
        v.as_array().map(Vec::len).unwrap_or(usize::MAX)
    };
    // A path that does not exist in the scene.
    let body = json!({"scene": scene(), "parameters": {"cracks.0.propagation.toughness": [1, 2]}});
    let (s, _, v) = app::send(&st, post("/api/v1/sweeps", &body, None)).await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    assert_eq!(v["error"], "invalid_sweep");
    assert_eq!(
        v["details"][0]["path"],
        "parameters.cracks.0.propagation.toughness"
    );
    assert!(
        v["message"]
            .as_str()
            .unwrap()
            .contains("the scene has no field `cracks`"),
        "{v}"
    );
    // An index past the end.
    let body = json!({"scene": scene(), "parameters": {"bodies.3.particles_per_cell": [1]}});
    let (s, _, v) = app::send(&st, post("/api/v1/sweeps", &body, None)).await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    assert!(v["message"].as_str().unwrap().contains("index 3"), "{v}");
    // One bad value among good ones: the error names the parameter, the value and the
    // validator's field path; nothing is stored.
    let body = json!({"scene": scene(), "parameters": {
        "time.cfl": [0.5, 0.25],
        "materials.m.poissons_ratio": [0.3, 0.7],
    }});
    let (s, _, v) = app::send(&st, post("/api/v1/sweeps", &body, None)).await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    assert_eq!(v["error"], "invalid_sweep");
    let details = v["details"].as_array().unwrap();
    assert_eq!(details.len(), 2, "{v}");
    assert_eq!(details[0]["path"], "materials.m.poissons_ratio");
    let m = details[0]["message"].as_str().unwrap();
    assert!(
        m.contains("parameter `materials.m.poissons_ratio` = 0.7") && m.contains("cfl=0.5"),
        "{m}"
    );
    let m = v["message"].as_str().unwrap();
    assert!(
        m.contains("materials.m.poissons_ratio") && m.contains("0.7"),
        "{m}"
    );
    // Values of the wrong type are caught the same way.
    let body = json!({"scene": scene(), "parameters": {"time.end": ["soon"]}});
    let (s, _, v) = app::send(&st, post("/api/v1/sweeps", &body, None)).await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    assert!(
        v["details"][0]["message"]
            .as_str()
            .unwrap()
            .contains("parameter `time.end` = \"soon\""),
        "{v}"
    );
    // A misspelt last segment adds a key; the validator refuses it at its parent, and the
    // error still names the parameter.
    let body = json!({"scene": scene(), "parameters": {"time.cfll": [0.5]}});
    let (s, _, v) = app::send(&st, post("/api/v1/sweeps", &body, None)).await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    let m = v["details"][0]["message"].as_str().unwrap();
    assert!(
        m.contains("parameter `time.cfll` = 0.5") && m.contains("unknown field `cfll`"),
        "{v}"
    );
    // Too many combinations (limit 6 here).
    let body = json!({"scene": scene(), "parameters": {
        "time.cfl": [0.1, 0.2, 0.3],
        "boundary_conditions.0.velocity.x": [1, 2, 3],
    }});
    let (s, _, v) = app::send(&st, post("/api/v1/sweeps", &body, None)).await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    assert_eq!(v["error"], "limit_exceeded");
    assert!(
        v["message"]
            .as_str()
            .unwrap()
            .contains("9 combinations (3 × 3)")
            && v["message"]
                .as_str()
                .unwrap()
                .contains("max_sweep_jobs = 6"),
        "{v}"
    );
    // No parameters, empty values, unknown fields, malformed JSON.
    for body in [
        json!({"scene": scene(), "parameters": {}}),
        json!({"scene": scene(), "parameters": {"time.cfl": []}}),
        json!({"scene": scene(), "parameters": {"time.cfl": [0.5]}, "colour": 1}),
        json!({"parameters": {"time.cfl": [0.5]}}),
    ] {
        let (s, _, v) = app::send(&st, post("/api/v1/sweeps", &body, None)).await;
        assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{body} → {v}");
        assert_eq!(v["error"], "invalid_sweep", "{v}");
    }
    let req = Request::post("/api/v1/sweeps")
        .header("content-type", "application/json")
        .body(Body::from("{nope"))
        .unwrap();
    let (s, _, _) = app::send(&st, req).await;
    assert_eq!(s, StatusCode::BAD_REQUEST);
    assert_eq!(count().await, 0);
    let (_, _, v) = app::send(&st, get("/api/v1/sweeps")).await;
    assert_eq!(v, json!([]));
}

#[tokio::test]
async fn sweeps_list_with_cursors_cancel_and_delete() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), Some("tok")).await;
    let body = json!({"scene": scene(), "parameters": {"time.cfl": [0.25, 0.5]}, "name": "s"});
    let (s, _, _) = app::send(&st, post("/api/v1/sweeps", &body, None)).await;
    assert_eq!(s, StatusCode::UNAUTHORIZED);
    let mut ids = Vec::new();
    for _ in 0..3 {
        let (s, _, v) = app::send(&st, post("/api/v1/sweeps", &body, Some("tok"))).await;
        assert_eq!(s, StatusCode::CREATED, "{v}");
        ids.push(v["id"].as_str().unwrap().to_string());
    }
    let (s, h, v) = app::send(&st, get("/api/v1/sweeps?limit=2")).await;
    assert_eq!(s, StatusCode::OK);
    let page = v.as_array().unwrap();
    assert_eq!(page.len(), 2);
    assert_eq!(page[0]["id"], ids[2].as_str());
    assert_eq!(page[0]["name"], "s");
    assert_eq!(page[0]["total"], 2);
    assert!(page[0].get("jobs").is_none() && page[0].get("scene").is_none());
    let cursor = h
        .get("x-next-cursor")
        .unwrap()
        .to_str()
        .unwrap()
        .to_string();
    let (_, h, v) = app::send(&st, get(&format!("/api/v1/sweeps?limit=2&cursor={cursor}"))).await;
    assert_eq!(v.as_array().unwrap().len(), 1);
    assert_eq!(v[0]["id"], ids[0].as_str());
    assert!(h.get("x-next-cursor").is_none());
    let (s, _, _) = app::send(&st, get("/api/v1/sweeps?limit=0")).await;
    assert_eq!(s, StatusCode::BAD_REQUEST);

    // A sweep with unfinished jobs cannot be deleted; cancel it, then delete it.
    let del = |id: &str| {
        Request::delete(format!("/api/v1/sweeps/{id}"))
            .header("authorization", "Bearer tok")
            .body(Body::empty())
            .unwrap()
    };
    let (s, _, v) = app::send(&st, del(&ids[0])).await;
    assert_eq!(s, StatusCode::CONFLICT, "{v}");
    let (s, _, v) = app::send(
        &st,
        post(
            &format!("/api/v1/sweeps/{}/cancel", ids[0]),
            &json!({}),
            Some("tok"),
        ),
    )
    .await;
    assert_eq!(s, StatusCode::OK, "{v}");
    assert_eq!(v["status"], "cancelled");
    assert_eq!(v["counts"]["cancelled"], 2);
    assert_eq!(v["progress"], 1.0);
    let (s, _, _) = app::send(&st, del(&ids[0])).await;
    assert_eq!(s, StatusCode::NO_CONTENT);
    let (s, _, v) = app::send(&st, get(&format!("/api/v1/sweeps/{}", ids[0]))).await;
    assert_eq!(s, StatusCode::NOT_FOUND);
    assert_eq!(v["error"], "not_found");
    let (_, _, jobs) = app::send(&st, get("/api/v1/jobs")).await;
    assert_eq!(jobs.as_array().unwrap().len(), 4);
    // Unknown ids.
    let (s, _, _) = app::send(
        &st,
        post("/api/v1/sweeps/nope/cancel", &json!({}), Some("tok")),
    )
    .await;
    assert_eq!(s, StatusCode::NOT_FOUND);
    // The routes are in the OpenAPI document.
    let (_, _, api) = app::send(&st, get("/api/v1/openapi.json")).await;
    for p in [
        "/api/v1/sweeps",
        "/api/v1/sweeps/{id}",
        "/api/v1/sweeps/{id}/cancel",
    ] {
        assert!(api["paths"][p].is_object(), "{p} missing");
    }
    assert!(api["components"]["schemas"]["SweepInfo"].is_object());
}

/// Claim the next job as worker `w`: its id, or `None` when nothing may be claimed.
async fn claim(st: &AppState, w: &str) -> Option<(String, i64)> {
    let (s, _, c) = app::send(
        st,
        post(
            "/api/v1/worker/claim",
            &json!({"worker_id": w, "wait_seconds": 0}),
            Some("wt"),
        ),
    )
    .await;
    if s == StatusCode::NO_CONTENT {
        return None;
    }
    assert_eq!(s, StatusCode::OK, "{c}");
    Some((
        c["job_id"].as_str().unwrap().to_string(),
        c["fence"].as_i64().unwrap(),
    ))
}

#[tokio::test]
async fn max_concurrent_limits_the_running_jobs_of_a_sweep() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), None).await;
    // 0 is refused, naming the field.
    let body = |m: Value| {
        json!({"scene": scene(), "max_concurrent": m,
               "parameters": {"time.end": [1.0e-5, 2.0e-5, 3.0e-5]}})
    };
    for bad in [json!(0), json!(-1), json!(1.5)] {
        let (s, _, v) = app::send(&st, post("/api/v1/sweeps", &body(bad.clone()), None)).await;
        assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{bad}: {v}");
        assert_eq!(v["details"][0]["path"], "max_concurrent", "{bad}: {v}");
    }
    let (s, _, sw) = app::send(&st, post("/api/v1/sweeps", &body(json!(2)), None)).await;
    assert_eq!(s, StatusCode::CREATED, "{sw}");
    assert_eq!(sw["max_concurrent"], 2);
    let jobs: Vec<String> = sw["jobs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| j["id"].as_str().unwrap().to_string())
        .collect();
    // A lone job queued after the sweep.
    let (s, _, lone) = app::send(&st, post("/api/v1/jobs", &scene(), None)).await;
    assert_eq!(s, StatusCode::CREATED, "{lone}");
    // Two of the sweep's jobs run; the third waits, the lone job is claimed past it.
    let a = claim(&st, "w1").await.unwrap();
    let b = claim(&st, "w2").await.unwrap();
    assert_eq!([&a.0, &b.0], [&jobs[0], &jobs[1]]);
    let c = claim(&st, "w3").await.unwrap();
    assert_eq!(
        c.0,
        lone["id"].as_str().unwrap(),
        "the lone job, not the third"
    );
    assert!(claim(&st, "w4").await.is_none(), "the third waits");
    // One of the two ends: the third may run.
    let (s, _, v) = app::send(
        &st,
        post(&format!("/api/v1/jobs/{}/cancel", a.0), &json!(null), None),
    )
    .await;
    assert_eq!(s, StatusCode::OK, "{v}");
    let (s, _, v) = app::send(
        &st,
        post(
            &format!("/api/v1/worker/jobs/{}/heartbeat", a.0),
            &json!({"fence": a.1}),
            Some("wt"),
        ),
    )
    .await;
    assert_eq!(s, StatusCode::OK, "{v}");
    assert!(claim(&st, "w4").await.is_none(), "still two running");
    let fin = json!({"fence": a.1, "summary": {"status": "cancelled", "message": "cancelled on request",
        "steps": 0, "time_step": 1e-7, "sim_time": 0.0, "particles": 1, "grid_nodes": 1,
        "active_nodes_mean": 0.0, "wall_seconds": 0.0, "particle_steps_per_second": 0.0,
        "threads": 1, "scene_hash": "h", "solver_version": "v"}});
    let (s, _, v) = app::send(
        &st,
        post(
            &format!("/api/v1/worker/jobs/{}/finish", a.0),
            &fin,
            Some("wt"),
        ),
    )
    .await;
    assert_eq!(s, StatusCode::OK, "{v}");
    let d = claim(&st, "w4").await.unwrap();
    assert_eq!(d.0, jobs[2]);
    // Without a limit every job is claimable at once (and the field is absent).
    let (_, _, free) = app::send(
        &st,
        post(
            "/api/v1/sweeps",
            &json!({"scene": scene(), "parameters": {"time.end": [1.0e-5, 2.0e-5, 3.0e-5]},
                    "cache": "force"}),
            None,
        ),
    )
    .await;
    assert!(free.get("max_concurrent").is_none(), "{free}");
    for w in ["x1", "x2", "x3"] {
        assert!(claim(&st, w).await.is_some(), "{w}");
    }
}

#[tokio::test]
async fn a_jobs_own_retry_budget_decides_when_a_lost_worker_fails_it() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path(), None).await;
    let died = |id: &str, fence: i64| {
        post(
            &format!("/api/v1/worker/jobs/{id}/died"),
            &json!({"fence": fence, "cause": "killed by signal 15"}),
            Some("wt"),
        )
    };
    // 0 is refused naming the field, for a job and for a sweep.
    let (s, _, v) = app::send(
        &st,
        post(
            "/api/v1/jobs",
            &json!({"scene": scene(), "max_attempts": 0}),
            None,
        ),
    )
    .await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    assert_eq!(v["details"][0]["path"], "max_attempts", "{v}");
    let sweep = |n: Value| {
        json!({"scene": scene(), "max_attempts": n, "cache": "force",
               "parameters": {"time.end": [1.0e-5, 2.0e-5]}})
    };
    let (s, _, v) = app::send(&st, post("/api/v1/sweeps", &sweep(json!(0)), None)).await;
    assert_eq!(s, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    assert_eq!(v["details"][0]["path"], "max_attempts", "{v}");
    // Budget 1: the first lost worker fails it (the server's default, 3, would re-queue).
    let (_, _, j) = app::send(
        &st,
        post(
            "/api/v1/jobs",
            &json!({"scene": scene(), "max_attempts": 1}),
            None,
        ),
    )
    .await;
    assert_eq!(j["max_attempts"], 1, "{j}");
    let (id, fence) = claim(&st, "w1").await.unwrap();
    let (s, _, j) = app::send(&st, died(&id, fence)).await;
    assert_eq!(s, StatusCode::OK, "{j}");
    assert_eq!(j["status"], "failed", "{j}");
    assert!(
        j["message"].as_str().unwrap().contains("attempt 1 of 1"),
        "{j}"
    );
    // Without one: re-queued after the same death.
    let (_, _, j) = app::send(
        &st,
        post(
            "/api/v1/jobs",
            &json!({"scene": scene(), "cache": "force"}),
            None,
        ),
    )
    .await;
    assert!(j.get("max_attempts").is_none(), "{j}");
    let (id, fence) = claim(&st, "w2").await.unwrap();
    let (_, _, j) = app::send(&st, died(&id, fence)).await;
    assert_eq!(j["status"], "queued", "{j}");
    // A sweep's budget goes to every job; a budget of 2 re-queues once, then fails.
    let (s, _, sw) = app::send(&st, post("/api/v1/sweeps", &sweep(json!(2)), None)).await;
    assert_eq!(s, StatusCode::CREATED, "{sw}");
    let first = sw["jobs"][0]["id"].as_str().unwrap().to_string();
    let (_, _, j) = app::send(&st, get(&format!("/api/v1/jobs/{first}"))).await;
    assert_eq!(j["max_attempts"], 2, "{j}");
    // (the lone job re-queued above is older: claim it out of the way first)
    let (lone, _) = claim(&st, "w3").await.unwrap();
    assert_eq!(lone, id);
    for (k, want) in [(1, "queued"), (2, "failed")] {
        let (cid, fence) = claim(&st, "w4").await.unwrap();
        assert_eq!(cid, first, "attempt {k}");
        let (_, _, j) = app::send(&st, died(&cid, fence)).await;
        assert_eq!(j["status"], want, "attempt {k}: {j}");
    }
}
