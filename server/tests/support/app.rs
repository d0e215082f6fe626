//! What the router tests share: a small valid scene and one request through `app(state)`
//! without a socket.

#![allow(dead_code, clippy::unwrap_used)]

use axum::body::Body;
use axum::http::{HeaderMap, Request, StatusCode};
use fracture_server::{AppState, app};
use http_body_util::BodyExt;
use serde_json::{Value, json};
use tower::ServiceExt;

/// A 20 mm × 10 mm block at 1 mm cells named `name`, run to `end` (s).
pub fn scene(name: &str, end: f64) -> Value {
    json!({
        "name": name,
        "grid": { "cell_size": 0.001, "min": [0.0, 0.0], "max": [0.022, 0.012] },
        "materials": { "m": { "model": "linear_elastic", "density": 1230.0,
                              "youngs_modulus": 3.96e9, "poissons_ratio": 0.35 } },
        "bodies": [ { "material": "m",
                      "region": { "rectangle": { "min": [0.001, 0.001], "max": [0.021, 0.011] } },
                      "particles_per_cell": 2 } ],
        "time": { "end": end }
    })
}

/// Send `req` to a fresh router on `st`: status, headers and body bytes.
pub async fn send_raw(st: &AppState, req: Request<Body>) -> (StatusCode, HeaderMap, Vec<u8>) {
    let resp = app(st.clone()).oneshot(req).await.unwrap();
    let status = resp.status();
    let headers = resp.headers().clone();
    let bytes = resp.into_body().collect().await.unwrap().to_bytes();
    (status, headers, bytes.to_vec())
}

/// As [`send_raw`], the body parsed as JSON (`null` when it is not).
pub async fn send(st: &AppState, req: Request<Body>) -> (StatusCode, HeaderMap, Value) {
    let (s, h, b) = send_raw(st, req).await;
    (s, h, serde_json::from_slice(&b).unwrap_or(Value::Null))
}

/// As [`send`], without the headers.
pub async fn call(st: &AppState, req: Request<Body>) -> (StatusCode, Value) {
    let (s, _, v) = send(st, req).await;
    (s, v)
}
