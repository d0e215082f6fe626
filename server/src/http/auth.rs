//! Bearer-token extractors. A handler names [`ApiToken`] or [`WorkerToken`] before its body
//! extractor, so the token is checked before the body is read or parsed (axum runs the
//! `FromRequestParts` extractors first, in order, then the one body extractor).

use axum::extract::FromRequestParts;
use axum::http::header;
use axum::http::request::Parts;

use crate::error::ApiError;
use crate::server::AppState;

/// The `Authorization: Bearer …` token of a request.
fn bearer(parts: &Parts) -> Option<&str> {
    parts
        .headers
        .get(header::AUTHORIZATION)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| {
            v.strip_prefix("Bearer ")
                .or_else(|| v.strip_prefix("bearer "))
        })
        .map(str::trim)
}

/// Compare tokens without an early exit: the length leaks, the content does not.
fn same(a: &str, b: &str) -> bool {
    a.len() == b.len()
        && a.bytes()
            .zip(b.bytes())
            .fold(0u8, |acc, (x, y)| acc | (x ^ y))
            == 0
}

/// The request carries the API token (submit, cancel, delete), or the server has none.
#[derive(Debug, Clone, Copy)]
pub struct ApiToken;

impl FromRequestParts<AppState> for ApiToken {
    type Rejection = ApiError;

    async fn from_request_parts(parts: &mut Parts, st: &AppState) -> Result<Self, ApiError> {
        match &st.cfg.api_token {
            None => Ok(ApiToken),
            Some(t) => match bearer(parts) {
                Some(given) if same(given, t) => Ok(ApiToken),
                Some(_) => Err(ApiError::Unauthorized("wrong API token".into())),
                None => Err(ApiError::Unauthorized(
                    "this server requires an API token: send `Authorization: Bearer <token>`"
                        .into(),
                )),
            },
        }
    }
}

/// The request carries the worker token (every `/api/v1/worker/…` route).
#[derive(Debug, Clone, Copy)]
pub struct WorkerToken;

impl FromRequestParts<AppState> for WorkerToken {
    type Rejection = ApiError;

    async fn from_request_parts(parts: &mut Parts, st: &AppState) -> Result<Self, ApiError> {
        match bearer(parts) {
            Some(given) if same(given, &st.cfg.worker_token) => Ok(WorkerToken),
            Some(_) => Err(ApiError::Unauthorized("wrong worker token".into())),
            None => Err(ApiError::Unauthorized(
                "worker routes need `Authorization: Bearer <worker token>`".into(),
            )),
        }
    }
}
