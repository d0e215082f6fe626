//! HTTP clients of `fracture submit` and `fracture sweep`: post the request, then (with
//! `--wait`) follow the job's or sweep's events until it ends.

use std::io::{BufRead, BufReader, Write};
use std::time::{Duration, Instant};

use fracture_api::jobs::{ErrorBody, JobInfo, JobStatus, StatusEvent};
use fracture_api::results::{CrackTipRow, Progress};
use fracture_api::sweep::SweepInfo;
use reqwest::StatusCode;
use reqwest::blocking::Client;

use crate::answers;

/// What `fracture submit` does.
#[derive(Debug, Clone)]
pub struct SubmitConfig {
    /// Base URL of the server.
    pub server: String,
    /// API token, if the server needs one.
    pub token: Option<String>,
    /// The scene (or wrapped request) as JSON.
    pub body: serde_json::Value,
    /// Follow the job until it ends.
    pub wait: bool,
    /// With `wait`: how long to keep retrying a server that stopped answering (a restart)
    /// before giving up.
    pub retry_for: Duration,
}

/// Outcome of a submission.
#[derive(Debug, Clone)]
pub enum SubmitOutcome {
    /// Refused (status and error body).
    Rejected(u16, String),
    /// Accepted and not waited for.
    Submitted(String),
    /// Accepted and ended.
    Ended(String, JobStatus, Option<String>),
}

fn show_error(status: u16, body: &str) -> String {
    match serde_json::from_str::<ErrorBody>(body) {
        Ok(b) => {
            let mut s = format!("{status} {}: {}", b.error, b.message);
            for d in b.details {
                s.push_str(&format!("\n  {}: {}", d.path, d.message));
            }
            s
        }
        Err(_) => format!("{status}: {body}"),
    }
}

/// A request error as the user should read it: a refused or failed connection says that no
/// server answers at that address and how to start one; other errors as they are.
pub fn explain_send_error(e: reqwest::Error) -> anyhow::Error {
    if e.is_connect() || e.is_timeout() {
        let at = e.url().map_or_else(
            || "the server address".to_string(),
            |u| {
                format!(
                    "{}://{}",
                    u.scheme(),
                    u.host_str().map_or_else(String::new, |h| match u.port() {
                        Some(p) => format!("{h}:{p}"),
                        None => h.to_string(),
                    })
                )
            },
        );
        let what = if e.is_timeout() {
            "did not answer in time"
        } else {
            "is not running (the connection was refused)"
        };
        return anyhow::anyhow!(
            "no fracture server at {at}: it {what}. Start one with `cargo run --release` \
             (or `fracture serve`) in the project folder, or give the address of a running \
             one with --server URL (FRACTURE_SERVER)"
        );
    }
    anyhow::Error::new(e)
}

/// Send a create request (with the bearer token, if any): the body of a `201 Created` answer,
/// or the status and a readable error for any other answer.
fn post_created(
    req: reqwest::blocking::RequestBuilder,
    token: Option<&str>,
) -> anyhow::Result<Result<String, (u16, String)>> {
    let req = match token {
        Some(t) => req.bearer_auth(t),
        None => req,
    };
    let r = req
        .timeout(Duration::from_secs(60))
        .send()
        .map_err(explain_send_error)?;
    let status = r.status();
    let text = r.text()?;
    if status != StatusCode::CREATED {
        return Ok(Err((status.as_u16(), show_error(status.as_u16(), &text))));
    }
    Ok(Ok(text))
}

/// Submit a scene and, with `wait`, follow its events until it ends (through a restart of
/// the server: see [`wait_for_job`]), then print its result summary
/// ([`crate::answers::job_summary`]) after the id.
pub fn submit(cfg: &SubmitConfig, out: &mut dyn Write) -> anyhow::Result<SubmitOutcome> {
    let base = cfg.server.trim_end_matches('/').to_string();
    let http = http_client()?;
    let req = http.post(format!("{base}/api/v1/jobs")).json(&cfg.body);
    let text = match post_created(req, cfg.token.as_deref())? {
        Ok(text) => text,
        Err((code, msg)) => return Ok(SubmitOutcome::Rejected(code, msg)),
    };
    let job: JobInfo = serde_json::from_str(&text)?;
    writeln!(out, "{}", job.id)?;
    if !cfg.wait {
        return Ok(SubmitOutcome::Submitted(job.id));
    }
    let job = wait_for_job(&http, &base, &job.id, cfg.retry_for)?;
    let tips = match crack_tips(&http, &base, &job.id) {
        Ok(rows) => answers::tip_stats(&rows),
        Err(e) => {
            eprintln!("{}: cannot read the crack tips: {e:#}", job.id);
            Vec::new()
        }
    };
    write!(
        out,
        "{}",
        answers::job_summary(&job, &tips, &answers::dashboard_url(&base, &job.id))
    )?;
    Ok(SubmitOutcome::Ended(job.id, job.status, job.message))
}

/// How a read of the event stream ended.
enum Follow {
    /// A terminal `status` event arrived.
    Ended,
    /// The stream could not be opened, or it ended before the job did.
    Dropped,
}

/// Read the job's event stream, showing progress on stderr, until a terminal `status`.
fn follow_events(http: &Client, base: &str, id: &str, tty: bool) -> Follow {
    let Ok(resp) = http.get(format!("{base}/api/v1/jobs/{id}/events")).send() else {
        return Follow::Dropped;
    };
    if !resp.status().is_success() {
        return Follow::Dropped;
    }
    let mut last_line = Instant::now() - Duration::from_secs(10);
    let mut event = String::new();
    let mut data = String::new();
    for line in BufReader::new(resp).lines() {
        let Ok(line) = line else { break };
        if let Some(e) = line.strip_prefix("event:") {
            event = e.trim().to_string();
        } else if let Some(d) = line.strip_prefix("data:") {
            data.push_str(d.trim_start());
        } else if line.is_empty() {
            match event.as_str() {
                "progress" => {
                    if let Ok(p) = serde_json::from_str::<Progress>(&data) {
                        let msg = format!(
                            "{id}: step {} t = {:.3e} s ({:.0}%)",
                            p.step,
                            p.sim_time,
                            100.0 * p.fraction
                        );
                        if tty {
                            eprint!("\r{msg}   ");
                        } else if last_line.elapsed() > Duration::from_secs(2) {
                            eprintln!("{msg}");
                            last_line = Instant::now();
                        }
                    }
                }
                "status" => {
                    if let Ok(s) = serde_json::from_str::<StatusEvent>(&data) {
                        if tty {
                            eprintln!();
                        }
                        eprintln!("{id}: {}", s.status.as_str());
                        if s.status.is_terminal() {
                            return Follow::Ended;
                        }
                    }
                }
                _ => {}
            }
            event.clear();
            data.clear();
        }
    }
    if tty {
        eprintln!();
    }
    Follow::Dropped
}

/// The job document: `Ok(None)` for a 404, an error when the server does not answer (or
/// answers with something else).
fn get_job(http: &Client, base: &str, id: &str) -> anyhow::Result<Option<JobInfo>> {
    let r = http
        .get(format!("{base}/api/v1/jobs/{id}"))
        .timeout(Duration::from_secs(30))
        .send()
        .map_err(explain_send_error)?;
    if r.status() == StatusCode::NOT_FOUND {
        return Ok(None);
    }
    if !r.status().is_success() {
        anyhow::bail!("GET /api/v1/jobs/{id} answered {}", r.status());
    }
    Ok(Some(r.json::<JobInfo>()?))
}

/// The job's crack-tip rows.
fn crack_tips(http: &Client, base: &str, id: &str) -> anyhow::Result<Vec<CrackTipRow>> {
    let r = http
        .get(format!("{base}/api/v1/jobs/{id}/crack-tips"))
        .timeout(Duration::from_secs(60))
        .send()
        .map_err(explain_send_error)?;
    if !r.status().is_success() {
        anyhow::bail!("GET /api/v1/jobs/{id}/crack-tips answered {}", r.status());
    }
    Ok(r.json::<Vec<CrackTipRow>>()?)
}

/// First pause between retries of an unreachable server; it doubles up to [`MAX_BACKOFF`].
const FIRST_BACKOFF: Duration = Duration::from_millis(500);
/// Longest pause between retries.
const MAX_BACKOFF: Duration = Duration::from_secs(8);

/// Follow a job until it has ended and return its final document. The event stream shows
/// progress; when it drops (a restart of the server, a network fault) the job is polled,
/// and while the server does not answer the connection is retried with exponential backoff
/// (0.5 s doubling to 8 s) for at most `retry_for` from the first failure, each retry said
/// on stderr. Then the stream is opened again.
pub fn wait_for_job(
    http: &Client,
    base: &str,
    id: &str,
    retry_for: Duration,
) -> anyhow::Result<JobInfo> {
    let tty = std::io::IsTerminal::is_terminal(&std::io::stderr());
    let mut outage: Option<(Instant, String)> = None;
    let mut backoff = FIRST_BACKOFF;
    loop {
        let followed = if outage.is_none() {
            follow_events(http, base, id, tty)
        } else {
            Follow::Dropped
        };
        match get_job(http, base, id) {
            Ok(Some(job)) => {
                if let Some((since, _)) = outage.take() {
                    eprintln!(
                        "{id}: reconnected to {base} after {:.1} s; following the job again",
                        since.elapsed().as_secs_f64()
                    );
                }
                backoff = FIRST_BACKOFF;
                if job.status.is_terminal() {
                    return Ok(job);
                }
                if matches!(followed, Follow::Ended) {
                    // The stream said it ended but the document does not yet: look again.
                    std::thread::sleep(Duration::from_millis(200));
                } else {
                    // The stream dropped while the server answers: reopen it after a pause.
                    std::thread::sleep(FIRST_BACKOFF);
                }
            }
            Ok(None) => {
                anyhow::bail!("job {id} is no longer on the server at {base} (deleted?)")
            }
            Err(e) => {
                let (since, _) = outage.get_or_insert_with(|| (Instant::now(), e.to_string()));
                let waited = since.elapsed();
                if waited >= retry_for {
                    anyhow::bail!(
                        "the server at {base} has not answered for {:.0} s (last error: {e:#}); \
                         job {id} may still run there: see {}",
                        waited.as_secs_f64(),
                        answers::dashboard_url(base, id)
                    );
                }
                let pause = backoff.min(retry_for.saturating_sub(waited));
                eprintln!(
                    "{id}: the server at {base} does not answer ({e:#}); retrying in {:.1} s \
                     (giving up {:.0} s after the first failure, {:.0} s so far)",
                    pause.as_secs_f64(),
                    retry_for.as_secs_f64(),
                    waited.as_secs_f64()
                );
                std::thread::sleep(pause);
                backoff = (backoff * 2).min(MAX_BACKOFF);
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// sweep

/// What `fracture sweep` does.
#[derive(Debug, Clone)]
pub struct SweepConfig {
    /// Base URL of the server.
    pub server: String,
    /// API token, if the server needs one.
    pub token: Option<String>,
    /// The request body as JSON text (text, so the parameters keep their order).
    pub body: String,
    /// Follow the jobs until all have ended.
    pub wait: bool,
}

/// Outcome of a sweep submission.
#[derive(Debug, Clone)]
pub enum SweepOutcome {
    /// Refused (status and the error body, shown).
    Rejected(u16, String),
    /// Accepted and not waited for (sweep id).
    Submitted(String),
    /// Accepted and every job ended: sweep id and its final state.
    Ended(String, Box<SweepInfo>),
}

fn http_client() -> reqwest::Result<Client> {
    Client::builder()
        .connect_timeout(Duration::from_secs(5))
        .timeout(None::<Duration>)
        .build()
}

/// One line of a sweep's state: `3 jobs: 1 completed, 1 running, 1 queued (45%)`.
pub fn sweep_line(s: &SweepInfo) -> String {
    let parts: Vec<String> = ["completed", "running", "queued", "failed", "cancelled"]
        .iter()
        .filter_map(|k| {
            let n = s.counts.get(*k).copied().unwrap_or(0);
            (n > 0).then(|| format!("{n} {k}"))
        })
        .collect();
    format!(
        "{}: {} jobs: {} ({:.0}%)",
        s.id,
        s.total,
        parts.join(", "),
        100.0 * s.progress
    )
}

/// Create a sweep (`POST /api/v1/sweeps`), print its id and one line per job (`id label`)
/// and, with `wait`, poll it until every job has ended, showing progress on stderr, then
/// print one table row per combination ([`crate::answers::sweep_table`]).
pub fn sweep(cfg: &SweepConfig, out: &mut dyn Write) -> anyhow::Result<SweepOutcome> {
    use SweepInfo;
    let base = cfg.server.trim_end_matches('/').to_string();
    let http = http_client()?;
    let req = http
        .post(format!("{base}/api/v1/sweeps"))
        .header(reqwest::header::CONTENT_TYPE, "application/json")
        .body(cfg.body.clone());
    let text = match post_created(req, cfg.token.as_deref())? {
        Ok(text) => text,
        Err((code, msg)) => return Ok(SweepOutcome::Rejected(code, msg)),
    };
    let sweep: SweepInfo = serde_json::from_str(&text)?;
    writeln!(out, "{}", sweep.id)?;
    for j in sweep.jobs.iter().flatten() {
        writeln!(out, "{} {}", j.id, j.label)?;
    }
    if !cfg.wait {
        return Ok(SweepOutcome::Submitted(sweep.id));
    }
    let id = sweep.id;
    let tty = std::io::IsTerminal::is_terminal(&std::io::stderr());
    let mut last_line = String::new();
    let mut last_print = Instant::now() - Duration::from_secs(10);
    let mut failures = 0u32;
    loop {
        let r = http
            .get(format!("{base}/api/v1/sweeps/{id}"))
            .timeout(Duration::from_secs(30))
            .send();
        let info = match r {
            Ok(r) if r.status().is_success() => r.json::<SweepInfo>().ok(),
            Ok(r) if r.status() == StatusCode::NOT_FOUND => {
                anyhow::bail!("sweep {id} disappeared from the server (deleted?)")
            }
            _ => None,
        };
        match info {
            Some(s) => {
                failures = 0;
                let line = sweep_line(&s);
                let done = s.total > 0
                    && s.counts.get("queued").copied().unwrap_or(0) == 0
                    && s.counts.get("running").copied().unwrap_or(0) == 0;
                if tty {
                    eprint!("\r{line}   ");
                } else if line != last_line
                    && (done || last_print.elapsed() > Duration::from_secs(2))
                {
                    eprintln!("{line}");
                    last_print = Instant::now();
                }
                last_line = line;
                if done {
                    if tty {
                        eprintln!();
                    }
                    let mut peaks = std::collections::BTreeMap::new();
                    for j in s.jobs.iter().flatten() {
                        if let Some(m) = j.message.as_deref().filter(|m| !m.is_empty()) {
                            eprintln!("  {} {} [{}]: {m}", j.id, j.status.as_str(), j.label);
                        }
                        match crack_tips(&http, &base, &j.id) {
                            Ok(rows) => {
                                peaks.insert(
                                    j.id.clone(),
                                    answers::peak_speed(&answers::tip_stats(&rows)),
                                );
                            }
                            Err(e) => eprintln!("{}: cannot read the crack tips: {e:#}", j.id),
                        }
                    }
                    // A blank line ends the job list; the table follows.
                    write!(out, "\n{}", answers::sweep_table(&s, &peaks))?;
                    writeln!(
                        out,
                        "dashboard: {}",
                        answers::sweep_dashboard_url(&base, &id)
                    )?;
                    return Ok(SweepOutcome::Ended(id, Box::new(s)));
                }
            }
            None => {
                failures += 1;
                if failures == 1 {
                    eprintln!(
                        "{id}: the server at {base} does not answer; retrying every second \
                         (giving up after two minutes)"
                    );
                }
                if failures > 120 {
                    anyhow::bail!("the server has not answered for two minutes");
                }
            }
        }
        std::thread::sleep(Duration::from_secs(1));
    }
}
