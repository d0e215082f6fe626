//! A job's Server-Sent Events: the current state first, then every change, ending after a
//! terminal `status` (or at shutdown).

use std::convert::Infallible;
use std::time::Duration;

use axum::extract::{Path, State};
use axum::response::sse::{Event, KeepAlive, Sse};
use fracture_api::jobs::ErrorBody;
use futures::{Stream, StreamExt};
use tokio::sync::broadcast::error::RecvError;

use super::job_or_404;
use crate::error::ApiError;
use crate::events::JobEvent;
use crate::server::AppState;

fn sse(ev: &JobEvent) -> Event {
    Event::default().event(ev.name()).data(ev.data())
}

/// Server-Sent Events of a job: `progress`, `energy`, `crack_tip`, `snapshot`, `status`.
/// A subscriber first gets the current `status` (and `progress`); the stream ends after a
/// terminal `status`.
#[utoipa::path(get, path = "/api/v1/jobs/{id}/events", tag = "jobs",
    params(("id" = String, Path, description = "Job id")),
    responses((status = 200, description = "text/event-stream", content_type = "text/event-stream"),
        (status = 404, description = "Unknown id", body = ErrorBody)))]
pub(super) async fn job_events(
    State(st): State<AppState>,
    Path(id): Path<String>,
) -> Result<Sse<impl Stream<Item = Result<Event, Infallible>>>, ApiError> {
    job_or_404(&st, &id).await?;
    // Subscribe before reading the state so no change falls between the two.
    let rx = st.hub.subscribe(&id);
    let job = job_or_404(&st, &id).await?;
    // Current state first: progress, then status (so a terminal status stays the last event).
    let mut first = Vec::new();
    if let Some(p) = job.progress {
        first.push(sse(&JobEvent::Progress(p)));
    }
    first.push(sse(&JobEvent::Status(Box::new(job.status_event()))));
    let done = job.status.is_terminal();
    let shutdown = st.shutdown.clone();
    let live = futures::stream::unfold((rx, shutdown, done), |(mut rx, mut sd, done)| async move {
        if done {
            return None;
        }
        loop {
            let next = tokio::select! {
                r = rx.recv() => Some(r),
                _ = crate::server::until_shutdown(&mut sd) => None,
            };
            match next {
                None | Some(Err(RecvError::Closed)) => return None,
                Some(Err(RecvError::Lagged(_))) => continue,
                Some(Ok(ev)) => {
                    let term = matches!(&ev, JobEvent::Status(s) if s.status.is_terminal());
                    return Some((Ok(sse(&ev)), (rx, sd, term)));
                }
            }
        }
    });
    let stream = futures::stream::iter(first.into_iter().map(Ok)).chain(live);
    Ok(Sse::new(stream).keep_alive(KeepAlive::new().interval(Duration::from_secs(10))))
}
