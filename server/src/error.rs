//! The one error type of the HTTP API and the JSON extractor that reports malformed bodies
//! in the API's error format.

use axum::body::Bytes;
use axum::extract::rejection::BytesRejection;
use axum::extract::{FromRequest, Request};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use fracture_api::ValidationErrors;
use fracture_api::jobs::{ErrorBody, ErrorDetail};
use serde::de::DeserializeOwned;

/// Everything a request can fail with; each variant maps to one status code and error kind.
#[derive(Debug, thiserror::Error)]
pub enum ApiError {
    /// 400: the body is not JSON, or a parameter is malformed.
    #[error("{0}")]
    BadRequest(String),
    /// 422: the scene is not valid.
    #[error("the scene is not valid")]
    InvalidScene(Vec<ErrorDetail>),
    /// 422: the scene is valid but exceeds a limit of this server.
    #[error("{message}")]
    LimitExceeded {
        /// Which limits.
        message: String,
        /// One entry per exceeded limit.
        details: Vec<ErrorDetail>,
    },
    /// 422: a sweep's parameters do not apply to its scene, or a combination is not a
    /// valid scene (each detail names the field path; the message the parameter and value).
    #[error("{message}")]
    InvalidSweep {
        /// The first problem, naming the parameter path and value.
        message: String,
        /// One entry per problem.
        details: Vec<ErrorDetail>,
    },
    /// 401: missing or wrong token.
    #[error("{0}")]
    Unauthorized(String),
    /// 404: no such job, snapshot, field or page.
    #[error("{0}")]
    NotFound(String),
    /// 409: the request conflicts with the job's state (or a stale fencing token).
    #[error("{0}")]
    Conflict(String),
    /// 413: the body is larger than the configured limit.
    #[error("the request body is larger than the limit of {0} bytes")]
    PayloadTooLarge(usize),
    /// 503: the server is shutting down.
    #[error("the server is shutting down")]
    Unavailable,
    /// 500 from the database; the body never shows the cause.
    #[error("database error: {0}")]
    Database(#[from] sqlx::Error),
    /// 500 for anything else; the body never shows the cause.
    #[error("internal error: {0}")]
    Internal(String),
}

impl ApiError {
    /// An internal error from anything displayable (logged, never shown to clients).
    pub fn internal(e: impl std::fmt::Display) -> Self {
        ApiError::Internal(e.to_string())
    }

    /// The status code of this error.
    pub fn status(&self) -> StatusCode {
        match self {
            ApiError::BadRequest(_) => StatusCode::BAD_REQUEST,
            ApiError::InvalidScene(_)
            | ApiError::LimitExceeded { .. }
            | ApiError::InvalidSweep { .. } => StatusCode::UNPROCESSABLE_ENTITY,
            ApiError::Unauthorized(_) => StatusCode::UNAUTHORIZED,
            ApiError::NotFound(_) => StatusCode::NOT_FOUND,
            ApiError::Conflict(_) => StatusCode::CONFLICT,
            ApiError::PayloadTooLarge(_) => StatusCode::PAYLOAD_TOO_LARGE,
            ApiError::Unavailable => StatusCode::SERVICE_UNAVAILABLE,
            ApiError::Database(_) | ApiError::Internal(_) => StatusCode::INTERNAL_SERVER_ERROR,
        }
    }

    /// The JSON body of this error.
    pub fn body(&self) -> ErrorBody {
        let (kind, details) = match self {
            ApiError::BadRequest(_) => ("bad_request", vec![]),
            ApiError::InvalidScene(d) => ("invalid_scene", d.clone()),
            ApiError::LimitExceeded { details, .. } => ("limit_exceeded", details.clone()),
            ApiError::InvalidSweep { details, .. } => ("invalid_sweep", details.clone()),
            ApiError::Unauthorized(_) => ("unauthorized", vec![]),
            ApiError::NotFound(_) => ("not_found", vec![]),
            ApiError::Conflict(_) => ("conflict", vec![]),
            ApiError::PayloadTooLarge(_) => ("payload_too_large", vec![]),
            ApiError::Unavailable => ("unavailable", vec![]),
            ApiError::Database(_) | ApiError::Internal(_) => ("internal", vec![]),
        };
        let message = match self {
            ApiError::Database(_) | ApiError::Internal(_) => {
                "internal server error (see the server log)".to_string()
            }
            ApiError::InvalidScene(d) => format!(
                "the scene is not valid ({} problem{}): {}",
                d.len(),
                if d.len() == 1 { "" } else { "s" },
                d.first()
                    .map(|x| format!("{}: {}", x.path, x.message))
                    .unwrap_or_default()
            ),
            other => other.to_string(),
        };
        ErrorBody {
            error: kind.to_string(),
            message,
            details,
        }
    }
}

impl From<ValidationErrors> for ApiError {
    fn from(e: ValidationErrors) -> Self {
        ApiError::InvalidScene(
            e.0.into_iter()
                .map(|v| ErrorDetail {
                    message: if v.value.is_empty() {
                        v.reason
                    } else {
                        format!("{} {}", v.value, v.reason)
                    },
                    path: v.path,
                })
                .collect(),
        )
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let status = self.status();
        if status.is_server_error() {
            tracing::error!(error = %self, "request failed");
        }
        (status, axum::Json(self.body())).into_response()
    }
}

/// Map a body-buffering rejection: 413 when over the limit, 400 otherwise.
pub fn bytes_rejection(r: BytesRejection, limit: usize) -> ApiError {
    if r.status() == StatusCode::PAYLOAD_TOO_LARGE {
        ApiError::PayloadTooLarge(limit)
    } else {
        ApiError::BadRequest(format!(
            "could not read the request body: {}",
            r.body_text()
        ))
    }
}

/// Limit, in bytes, of the body an extractor may buffer (set by the router for each group).
#[derive(Debug, Clone, Copy)]
pub struct BodyLimit(pub usize);

/// The raw body, with the API's error format for oversized bodies.
pub struct RawBody(pub Bytes);

impl<S: Send + Sync> FromRequest<S> for RawBody {
    type Rejection = ApiError;
    async fn from_request(req: Request, state: &S) -> Result<Self, Self::Rejection> {
        let limit = req
            .extensions()
            .get::<BodyLimit>()
            .map(|l| l.0)
            .unwrap_or(usize::MAX);
        let bytes = Bytes::from_request(req, state)
            .await
            .map_err(|r| bytes_rejection(r, limit))?;
        Ok(RawBody(bytes))
    }
}

/// A JSON body: malformed JSON gets a 400 in the API's error format, an oversized body 413.
pub struct ApiJson<T>(pub T);

impl<T: DeserializeOwned, S: Send + Sync> FromRequest<S> for ApiJson<T> {
    type Rejection = ApiError;
    async fn from_request(req: Request, state: &S) -> Result<Self, Self::Rejection> {
        let RawBody(bytes) = RawBody::from_request(req, state).await?;
        parse_json(&bytes).map(ApiJson)
    }
}

/// Parse JSON text; errors become 400 with serde's message (line and column).
pub fn parse_json<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, ApiError> {
    serde_json::from_slice(bytes)
        .map_err(|e| ApiError::BadRequest(format!("the body is not valid JSON: {e}")))
}
