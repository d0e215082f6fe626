//! The one error type of the HTTP API, the extractors that report malformed bodies and
//! query strings in the API's error format ([`JsonBody`], [`ApiJson`], [`ApiQuery`]), and the
//! classification of storage failures (a full disk or an I/O error is 507
//! `insufficient_storage`, a busy store 503, never a bare 500).

use axum::body::Bytes;
use axum::extract::rejection::BytesRejection;
use axum::extract::{FromRequest, Request};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use fracture_api::ValidationErrors;
use fracture_api::jobs::{ErrorBody, ErrorDetail};
use serde::de::DeserializeOwned;

use crate::store::StoreError;

/// Everything a request can fail with; each variant maps to one status code and error kind.
#[derive(Debug, thiserror::Error)]
pub enum ApiError {
    /// 400: the body is not JSON, or a parameter is malformed.
    #[error("{0}")]
    BadRequest(String),
    /// 400: a query parameter has a bad value; each detail names the parameter (`path`) and
    /// what is wrong with its value.
    #[error("{message}")]
    BadParameter {
        /// The first problem, naming the parameter and its value.
        message: String,
        /// One entry per bad parameter.
        details: Vec<ErrorDetail>,
    },
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
    /// 403: a cross-site request to a state-changing route, or a `Host` this server does
    /// not answer to (DNS rebinding).
    #[error("{0}")]
    Forbidden(String),
    /// 405: the route exists but not with this method.
    #[error("{0}")]
    MethodNotAllowed(String),
    /// 415: the body is not sent as `application/json`.
    #[error("{0}")]
    UnsupportedMediaType(String),
    /// 503: the server is shutting down.
    #[error("the server is shutting down")]
    Unavailable,
    /// 503: the store is busy (locked by another writer past the busy timeout); retry.
    #[error("{0}")]
    Busy(String),
    /// 507: the data folder is full or failed (I/O error, read-only): nothing was stored.
    #[error("{0}")]
    Storage(String),
    /// 500 from the database; the body never shows the cause.
    #[error("database error: {0}")]
    Database(sqlx::Error),
    /// 500 for anything else; the body never shows the cause.
    #[error("internal error: {0}")]
    Internal(String),
}

impl ApiError {
    /// An internal error from anything displayable (logged, never shown to clients).
    pub fn internal(e: impl std::fmt::Display) -> Self {
        ApiError::Internal(e.to_string())
    }

    /// A file-system error: a full disk, a quota, a read-only or failing file system is
    /// [`ApiError::Storage`] (507); anything else internal.
    pub fn io(e: &(dyn std::error::Error + 'static)) -> Self {
        match storage_fault(e) {
            Some(what) => ApiError::Storage(storage_message(what)),
            None => ApiError::internal(e),
        }
    }

    /// 400 for the query parameter `name`: `message` says what is wrong with its value.
    pub fn bad_parameter(name: &str, message: impl Into<String>) -> Self {
        let message = message.into();
        ApiError::BadParameter {
            message: format!("query parameter `{name}`: {message}"),
            details: vec![ErrorDetail {
                path: name.to_string(),
                message,
            }],
        }
    }

    /// The status code of this error.
    pub fn status(&self) -> StatusCode {
        match self {
            ApiError::BadRequest(_) | ApiError::BadParameter { .. } => StatusCode::BAD_REQUEST,
            ApiError::InvalidScene(_)
            | ApiError::LimitExceeded { .. }
            | ApiError::InvalidSweep { .. } => StatusCode::UNPROCESSABLE_ENTITY,
            ApiError::Unauthorized(_) => StatusCode::UNAUTHORIZED,
            ApiError::NotFound(_) => StatusCode::NOT_FOUND,
            ApiError::Conflict(_) => StatusCode::CONFLICT,
            ApiError::PayloadTooLarge(_) => StatusCode::PAYLOAD_TOO_LARGE,
            ApiError::Forbidden(_) => StatusCode::FORBIDDEN,
            ApiError::MethodNotAllowed(_) => StatusCode::METHOD_NOT_ALLOWED,
            ApiError::UnsupportedMediaType(_) => StatusCode::UNSUPPORTED_MEDIA_TYPE,
            ApiError::Unavailable | ApiError::Busy(_) => StatusCode::SERVICE_UNAVAILABLE,
            ApiError::Storage(_) => StatusCode::INSUFFICIENT_STORAGE,
            ApiError::Database(_) | ApiError::Internal(_) => StatusCode::INTERNAL_SERVER_ERROR,
        }
    }

    /// The JSON body of this error.
    pub fn body(&self) -> ErrorBody {
        let (kind, details) = match self {
            ApiError::BadRequest(_) => ("bad_request", vec![]),
            ApiError::BadParameter { details, .. } => ("bad_request", details.clone()),
            ApiError::InvalidScene(d) => ("invalid_scene", d.clone()),
            ApiError::LimitExceeded { details, .. } => ("limit_exceeded", details.clone()),
            ApiError::InvalidSweep { details, .. } => ("invalid_sweep", details.clone()),
            ApiError::Unauthorized(_) => ("unauthorized", vec![]),
            ApiError::NotFound(_) => ("not_found", vec![]),
            ApiError::Conflict(_) => ("conflict", vec![]),
            ApiError::PayloadTooLarge(_) => ("payload_too_large", vec![]),
            ApiError::Forbidden(_) => ("forbidden", vec![]),
            ApiError::MethodNotAllowed(_) => ("method_not_allowed", vec![]),
            ApiError::UnsupportedMediaType(_) => ("unsupported_media_type", vec![]),
            ApiError::Unavailable | ApiError::Busy(_) => ("unavailable", vec![]),
            ApiError::Storage(_) => ("insufficient_storage", vec![]),
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

impl From<StoreError> for ApiError {
    fn from(e: StoreError) -> Self {
        match e {
            StoreError::Fenced => ApiError::Conflict(e.to_string()),
            StoreError::Db(d) => d.into(),
            other => ApiError::internal(other),
        }
    }
}

impl From<sqlx::Error> for ApiError {
    fn from(e: sqlx::Error) -> Self {
        match classify_db(&e) {
            Some(DbFault::Storage(what)) => {
                tracing::error!(error = %e, "store write failed: {what}");
                ApiError::Storage(storage_message(what))
            }
            Some(DbFault::Busy) => {
                tracing::warn!(error = %e, "store busy");
                ApiError::Busy("the store is busy; retry in a moment".into())
            }
            None => ApiError::Database(e),
        }
    }
}

/// What a database error says about the store.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DbFault {
    /// The disk is full, or the file system failed or is read-only (the `&str` says which).
    Storage(&'static str),
    /// Another writer held the lock past the busy timeout, or no connection was free.
    Busy,
}

/// Classify a database error: SQLite's primary result code (`SQLITE_FULL` 13,
/// `SQLITE_IOERR` 10, `SQLITE_READONLY` 8, `SQLITE_CANTOPEN` 14, `SQLITE_BUSY` 5,
/// `SQLITE_LOCKED` 6), PostgreSQL's SQLSTATE ([`classify_postgres`]), or the I/O error under
/// it; a connection to the database that is refused or drops is [`DbFault::Busy`].
pub fn classify_db(e: &sqlx::Error) -> Option<DbFault> {
    match e {
        sqlx::Error::Database(d) => {
            if let Some(pg) = d.try_downcast_ref::<sqlx::postgres::PgDatabaseError>() {
                return classify_postgres(pg.code());
            }
            let code = d.code()?.parse::<i64>().ok()? & 0xff;
            match code {
                13 => Some(DbFault::Storage("the disk is full")),
                10 => Some(DbFault::Storage("an I/O error")),
                8 => Some(DbFault::Storage("the data folder is read-only")),
                14 => Some(DbFault::Storage("a database file cannot be opened")),
                5 | 6 => Some(DbFault::Busy),
                _ => None,
            }
        }
        sqlx::Error::Io(io) => storage_fault(io).map(DbFault::Storage).or_else(|| {
            use std::io::ErrorKind::*;
            matches!(
                io.kind(),
                ConnectionRefused
                    | ConnectionReset
                    | ConnectionAborted
                    | BrokenPipe
                    | UnexpectedEof
            )
            .then_some(DbFault::Busy)
        }),
        sqlx::Error::PoolTimedOut => Some(DbFault::Busy),
        _ => None,
    }
}

/// Classify a PostgreSQL error by its SQLSTATE: `53100` (disk full) and `58030` (I/O error)
/// are storage faults of the database server, `25006` (a read-only transaction: a standby)
/// too; the other insufficient resources (`53…`), serialization failures and deadlocks
/// (`40001`, `40P01`), a lock not available (`55P03`), a server shutting down or starting
/// (`57P01`–`57P03`) and connection exceptions (`08…`) are [`DbFault::Busy`].
pub fn classify_postgres(sqlstate: &str) -> Option<DbFault> {
    match sqlstate {
        "53100" => Some(DbFault::Storage("the database server's disk is full")),
        "58030" => Some(DbFault::Storage("an I/O error on the database server")),
        "25006" => Some(DbFault::Storage("the database is read-only")),
        "40001" | "40P01" | "55P03" | "57P01" | "57P02" | "57P03" => Some(DbFault::Busy),
        s if s.starts_with("53") || s.starts_with("08") => Some(DbFault::Busy),
        _ => None,
    }
}

/// Whether an error (or one under it) is an I/O error of a full, failing or read-only file
/// system (`ENOSPC`, `EDQUOT`, `EIO`, `EROFS`), and which.
pub fn storage_fault(e: &(dyn std::error::Error + 'static)) -> Option<&'static str> {
    let mut cur: Option<&(dyn std::error::Error + 'static)> = Some(e);
    while let Some(err) = cur {
        if let Some(io) = err.downcast_ref::<std::io::Error>() {
            match io.raw_os_error() {
                Some(28) | Some(122) => return Some("the disk is full"),
                Some(5) => return Some("an I/O error"),
                Some(30) => return Some("the data folder is read-only"),
                _ => {}
            }
            if io.kind() == std::io::ErrorKind::StorageFull {
                return Some("the disk is full");
            }
        }
        cur = err.source();
    }
    None
}

/// The message of a 507.
fn storage_message(what: &str) -> String {
    let place = if what.contains("database server") || what.contains("the database is") {
        ""
    } else {
        " in its data folder"
    };
    format!(
        "the server could not store this request: {what}{place}. Nothing was stored; retry \
         once space is freed (no restart needed)"
    )
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

/// Whether the request says its body is JSON (`application/json`, with or without
/// parameters such as `charset`, or any `application/*+json`).
pub fn is_json(headers: &axum::http::HeaderMap) -> bool {
    let Some(ct) = headers
        .get(axum::http::header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
    else {
        return false;
    };
    let mime = ct
        .split(';')
        .next()
        .unwrap_or("")
        .trim()
        .to_ascii_lowercase();
    mime == "application/json" || (mime.starts_with("application/") && mime.ends_with("+json"))
}

/// The raw bytes of a body sent as `application/json` (415 otherwise: a browser sends a
/// cross-site "simple" request only as `text/plain`, form data or multipart, so refusing
/// them keeps other pages from submitting work), with the limits of [`RawBody`].
pub struct JsonBody(pub Bytes);

impl<S: Send + Sync> FromRequest<S> for JsonBody {
    type Rejection = ApiError;
    async fn from_request(req: Request, state: &S) -> Result<Self, Self::Rejection> {
        if !is_json(req.headers()) {
            let given = req
                .headers()
                .get(axum::http::header::CONTENT_TYPE)
                .and_then(|v| v.to_str().ok())
                .map(|v| format!("`{v}`"))
                .unwrap_or_else(|| "none".into());
            return Err(ApiError::UnsupportedMediaType(format!(
                "the body must be sent with `Content-Type: application/json` (given: {given})"
            )));
        }
        let RawBody(bytes) = RawBody::from_request(req, state).await?;
        Ok(JsonBody(bytes))
    }
}

/// A JSON body: a body not sent as `application/json` gets 415, malformed JSON a 400 in the
/// API's error format, an oversized body 413.
pub struct ApiJson<T>(pub T);

impl<T: DeserializeOwned, S: Send + Sync> FromRequest<S> for ApiJson<T> {
    type Rejection = ApiError;
    async fn from_request(req: Request, state: &S) -> Result<Self, Self::Rejection> {
        let JsonBody(bytes) = JsonBody::from_request(req, state).await?;
        parse_json(&bytes).map(ApiJson)
    }
}

/// A query string: a malformed value or an unknown parameter (the query types deny unknown
/// fields) is a 400 in the API's error format instead of axum's plain-text rejection.
pub struct ApiQuery<T>(pub T);

impl<T: DeserializeOwned, S: Send + Sync> axum::extract::FromRequestParts<S> for ApiQuery<T> {
    type Rejection = ApiError;
    async fn from_request_parts(
        parts: &mut axum::http::request::Parts,
        _: &S,
    ) -> Result<Self, Self::Rejection> {
        let q = parts.uri.query().unwrap_or("");
        query_from_str(q)
            .map(ApiQuery)
            .map_err(|e| ApiError::BadRequest(format!("bad query string: {e}")))
    }
}

/// Decode a query string the way axum's `Query` does.
fn query_from_str<T: DeserializeOwned>(q: &str) -> Result<T, String> {
    let uri: axum::http::Uri = format!("/?{q}")
        .parse()
        .map_err(|e: axum::http::uri::InvalidUri| e.to_string())?;
    axum::extract::Query::<T>::try_from_uri(&uri)
        .map(|axum::extract::Query(v)| v)
        .map_err(|e| e.body_text())
}

/// Parse JSON text; errors become 400 with serde's message (line and column).
pub fn parse_json<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, ApiError> {
    serde_json::from_slice(bytes)
        .map_err(|e| ApiError::BadRequest(format!("the body is not valid JSON: {e}")))
}
