//! The client commands: `worker` (a remote worker: a supervisor and its worker process),
//! `submit` and `sweep`.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use fracture_api::jobs::JobStatus;
use fracture_server::server::random_hex;
use fracture_server::service::init_tracing;
use fracture_worker::remote::{self, WorkerConfig};
use fracture_worker::supervise::Supervisor;

use crate::client::{self, SubmitConfig, SubmitOutcome};

/// Arguments of `fracture worker`.
#[derive(clap::Args, Debug)]
pub struct WorkerArgs {
    /// URL of the server.
    #[arg(long, env = "FRACTURE_SERVER", default_value = "http://127.0.0.1:8080")]
    pub server: String,
    /// Worker token of the server.
    #[arg(long, env = "FRACTURE_WORKER_TOKEN", hide_env_values = true)]
    pub token: String,
    /// Solver threads (`all` or 0: one per core).
    #[arg(long, env = "FRACTURE_THREADS", default_value = "all")]
    pub threads: fracture_solver::Parallelism,
    /// How often the run reports progress and sends its rows (ms).
    #[arg(long, default_value_t = 500)]
    pub flush_ms: u64,
    /// Exit after the server has been unreachable this long (s).
    #[arg(long, default_value_t = 120)]
    pub give_up_seconds: u64,
    /// Exit when this process is no longer the parent (set for a server's local workers).
    #[arg(long, hide = true)]
    pub parent_pid: Option<u32>,
    /// First part of this worker's id, `PREFIX-PID-RANDOM` (default: the host name; a
    /// server names its local workers `local<slot>` so it can tell which jobs a dead one
    /// held).
    #[arg(long, hide = true)]
    pub worker_name: Option<String>,
    /// Fail jobs whose memory estimate exceeds this many bytes before building them.
    #[arg(long, env = "FRACTURE_WORKER_MAX_MEMORY_BYTES")]
    pub max_memory_bytes: Option<u64>,
    /// Run the worker loop in this process, reporting its claims on stdout: the child of
    /// the supervisor that `fracture worker` is otherwise (`fracture_worker::supervise`).
    #[arg(long, hide = true)]
    pub supervised_child: bool,
    /// Checkpoint the running job every this many steps, at the next history sample
    /// (0: not by steps). A re-claimed job resumes from its last checkpoint.
    #[arg(long, env = "FRACTURE_CHECKPOINT_STEPS", default_value_t = 0)]
    pub checkpoint_steps: u64,
    /// Checkpoint the running job every this many minutes of wall time, at the next history
    /// sample (0: not by time).
    #[arg(long, env = "FRACTURE_CHECKPOINT_MINUTES", default_value_t = 5.0)]
    pub checkpoint_minutes: f64,
    /// Exit (status 0) after this many seconds without a job, e.g. once the queue is
    /// drained (for workers started by a batch scheduler).
    #[arg(long, env = "FRACTURE_IDLE_EXIT", value_parser = parse_seconds, allow_negative_numbers = true)]
    pub idle_exit: Option<f64>,
    /// Exit (status 0) after claiming this many jobs.
    #[arg(long, env = "FRACTURE_MAX_JOBS", value_parser = clap::value_parser!(u64).range(1..), allow_negative_numbers = true)]
    pub max_jobs: Option<u64>,
    /// Claims made by earlier worker processes of the same supervisor (set by it).
    #[arg(long, hide = true, default_value_t = 0)]
    pub jobs_before: u64,
}

/// A number of seconds: finite, > 0, at most a year.
fn parse_seconds(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v <= 3.2e7 => Ok(v),
        _ => Err(format!(
            "`{s}` is not a number of seconds > 0 (at most a year)"
        )),
    }
}

/// Arguments of `fracture submit`.
#[derive(clap::Args, Debug)]
pub struct SubmitArgs {
    /// Scene JSON file (a scene, or `{"scene": …, "priority": …, "labels": …}`).
    pub scene: PathBuf,
    /// URL of the server.
    #[arg(long, env = "FRACTURE_SERVER", default_value = "http://127.0.0.1:8080")]
    pub server: String,
    /// API token.
    #[arg(long, env = "FRACTURE_TOKEN", hide_env_values = true)]
    pub token: Option<String>,
    /// Priority (higher runs first).
    #[arg(long)]
    pub priority: Option<i64>,
    /// Label `key=value` (repeatable).
    #[arg(long = "label")]
    pub labels: Vec<String>,
    /// Show progress and exit with the job's outcome (0 completed, 3 failed, 4 cancelled),
    /// after a result summary on stdout.
    #[arg(long)]
    pub wait: bool,
    /// With `--wait`: how long to keep retrying a server that stopped answering (e.g. while
    /// it restarts), in seconds, before giving up (exit 1).
    #[arg(long, default_value_t = 120)]
    pub retry_seconds: u64,
    /// Run the scene even if the server has a completed run of it (`"cache": "force"`;
    /// otherwise such a submission is answered from that run at once).
    #[arg(long)]
    pub no_cache: bool,
}

/// Arguments of `fracture sweep`.
#[derive(clap::Args, Debug)]
pub struct SweepArgs {
    /// Base scene JSON file (a scene, or `{"scene": …}`).
    pub scene: PathBuf,
    /// A swept parameter, `json.path=v1,v2,…` (repeatable; one job per combination).
    /// Numeric path segments index arrays; each value is read as JSON (a number, `true`,
    /// `"text"`), or as a string if it is not JSON; `path=[…]` gives the values as a JSON
    /// array (for values with commas).
    #[arg(long = "param", required = true)]
    pub params: Vec<String>,
    /// URL of the server.
    #[arg(long, env = "FRACTURE_SERVER", default_value = "http://127.0.0.1:8080")]
    pub server: String,
    /// API token.
    #[arg(long, env = "FRACTURE_TOKEN", hide_env_values = true)]
    pub token: Option<String>,
    /// Name of the sweep (default: the scene's name).
    #[arg(long)]
    pub name: Option<String>,
    /// Priority of its jobs (higher runs first).
    #[arg(long)]
    pub priority: Option<i64>,
    /// Label `key=value` for every job (repeatable).
    #[arg(long = "label")]
    pub labels: Vec<String>,
    /// Show the progress of all jobs and exit with the outcome (0 all completed, 3 some
    /// failed, 4 some cancelled and none failed).
    #[arg(long)]
    pub wait: bool,
    /// Most of the sweep's jobs running at once (default: no limit).
    #[arg(long)]
    pub max_concurrent: Option<u32>,
    /// Run every combination even if the server has a completed run of its scene
    /// (`"cache": "force"`).
    #[arg(long)]
    pub no_cache: bool,
}

/// Parse one `--param path=v1,v2` into the path and its values.
pub fn parse_param(arg: &str) -> Result<(String, Vec<serde_json::Value>), String> {
    let (path, values) = arg
        .split_once('=')
        .ok_or_else(|| format!("--param must be path=v1,v2,…, got `{arg}`"))?;
    let path = path.trim();
    if path.is_empty() {
        return Err(format!("--param `{arg}`: the path is empty"));
    }
    let values = values.trim();
    let list: Vec<serde_json::Value> = if values.starts_with('[') {
        serde_json::from_str(values)
            .map_err(|e| format!("--param {path}: `{values}` is not a JSON array: {e}"))?
    } else {
        values
            .split(',')
            .map(str::trim)
            .filter(|v| !v.is_empty())
            .map(|v| {
                serde_json::from_str(v).unwrap_or_else(|_| serde_json::Value::String(v.into()))
            })
            .collect()
    };
    if list.is_empty() {
        return Err(format!("--param {path}: no values"));
    }
    Ok((path.to_string(), list))
}

/// The body of `POST /api/v1/sweeps` as text: the parameters in the order given (a
/// `serde_json::Value` would sort them).
pub fn sweep_body(
    scene: &serde_json::Value,
    params: &[(String, Vec<serde_json::Value>)],
    name: Option<&str>,
    priority: i64,
    labels: &serde_json::Map<String, serde_json::Value>,
    extra: &serde_json::Map<String, serde_json::Value>,
) -> String {
    let params: Vec<String> = params
        .iter()
        .map(|(p, v)| {
            format!(
                "{}: {}",
                serde_json::Value::String(p.clone()),
                serde_json::Value::Array(v.clone())
            )
        })
        .collect();
    let mut body = format!(
        "{{\"scene\": {scene}, \"parameters\": {{{}}}, \"priority\": {priority}, \"labels\": {}",
        params.join(", "),
        serde_json::Value::Object(labels.clone())
    );
    if let Some(n) = name {
        body.push_str(&format!(
            ", \"name\": {}",
            serde_json::Value::String(n.into())
        ));
    }
    for (k, v) in extra {
        body.push_str(&format!(", {}: {v}", serde_json::Value::String(k.clone())));
    }
    body.push('}');
    body
}

/// A JSON file the command line names; an unreadable or invalid file is reported on stderr
/// and gives exit code 2.
fn read_json_file(path: &std::path::Path) -> Result<serde_json::Value, ExitCode> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        eprintln!("cannot read {}: {e}", path.display());
        ExitCode::from(2)
    })?;
    serde_json::from_str(&text).map_err(|e| {
        eprintln!("{} is not valid JSON: {e}", path.display());
        ExitCode::from(2)
    })
}

/// `--label key=value` arguments as a JSON object; a malformed one is reported on stderr and
/// gives exit code 2.
fn parse_labels(args: &[String]) -> Result<serde_json::Map<String, serde_json::Value>, ExitCode> {
    let mut labels = serde_json::Map::new();
    for l in args {
        let Some((k, v)) = l.split_once('=') else {
            eprintln!("--label must be key=value, got `{l}`");
            return Err(ExitCode::from(2));
        };
        labels.insert(k.to_string(), serde_json::Value::String(v.to_string()));
    }
    Ok(labels)
}

/// `fracture sweep`.
pub fn sweep(a: SweepArgs) -> ExitCode {
    let doc = match read_json_file(&a.scene) {
        Ok(v) => v,
        Err(code) => return code,
    };
    let scene = match doc.get("scene") {
        Some(s) if doc.get("grid").is_none() => s.clone(),
        _ => doc,
    };
    let mut params = Vec::new();
    for p in &a.params {
        match parse_param(p) {
            Ok(p) => params.push(p),
            Err(e) => {
                eprintln!("{e}");
                return ExitCode::from(2);
            }
        }
    }
    let labels = match parse_labels(&a.labels) {
        Ok(l) => l,
        Err(code) => return code,
    };
    let mut extra = serde_json::Map::new();
    if let Some(n) = a.max_concurrent {
        extra.insert("max_concurrent".into(), n.into());
    }
    if a.no_cache {
        extra.insert("cache".into(), "force".into());
    }
    let cfg = client::SweepConfig {
        server: a.server,
        token: a.token,
        body: sweep_body(
            &scene,
            &params,
            a.name.as_deref(),
            a.priority.unwrap_or(0),
            &labels,
            &extra,
        ),
        wait: a.wait,
    };
    let mut out = std::io::stdout();
    match client::sweep(&cfg, &mut out) {
        Ok(client::SweepOutcome::Rejected(_, msg)) => {
            eprintln!("{msg}");
            ExitCode::from(2)
        }
        Ok(client::SweepOutcome::Submitted(_)) => ExitCode::SUCCESS,
        Ok(client::SweepOutcome::Ended(_, s)) => match s.status.as_str() {
            "completed" => ExitCode::SUCCESS,
            "cancelled" => ExitCode::from(4),
            _ => ExitCode::from(3),
        },
        Err(e) => {
            eprintln!("sweep failed: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// `fracture worker`: a supervisor that runs the worker loop in a child process and
/// reports the child's death for the job it held; the loop itself in a server's local
/// workers (`--parent-pid`) and in the supervised child.
pub fn worker(a: WorkerArgs) -> ExitCode {
    init_tracing();
    if a.parent_pid.is_none() && !a.supervised_child {
        match std::env::current_exe() {
            Ok(exe) => {
                let mut args: Vec<std::ffi::OsString> = std::env::args_os().skip(1).collect();
                args.push("--supervised-child".into());
                let code = fracture_worker::supervise::supervise(&Supervisor {
                    exe,
                    args,
                    server: a.server,
                    token: a.token,
                });
                return ExitCode::from(u8::try_from(code).unwrap_or(1));
            }
            Err(e) => tracing::warn!(
                error = %e,
                "cannot find this executable: running unsupervised (a death is seen by the lease)"
            ),
        }
    }
    // Stop signals hand the job back (batch workers, `fracture_worker::batch`); a server's
    // local workers are stopped by their server instead.
    #[cfg(unix)]
    if (a.supervised_child || a.parent_pid.is_none())
        && let Err(e) = fracture_worker::batch::hand_back_on_signals()
    {
        tracing::warn!(error = %e, "cannot handle stop signals");
    }
    let mut host = fracture_worker::provenance::host()
        .or_else(|| {
            std::fs::read_to_string("/etc/hostname")
                .ok()
                .map(|h| h.trim().to_string())
        })
        .unwrap_or_else(|| "host".into());
    if let Some(tag) = fracture_worker::provenance::scheduler_tag() {
        host = format!("{host}-{tag}");
    }
    let cfg = WorkerConfig {
        server: a.server,
        token: a.token,
        threads: a.threads,
        flush_every: Duration::from_millis(a.flush_ms.max(10)),
        give_up: Duration::from_secs(a.give_up_seconds),
        parent_pid: a.parent_pid,
        worker_id: format!(
            "{}-{}-{}",
            a.worker_name.unwrap_or(host),
            std::process::id(),
            random_hex(3)
        ),
        max_memory: a.max_memory_bytes,
        announce_claims: a.supervised_child,
        checkpoints: fracture_worker::CheckpointPolicy {
            steps: (a.checkpoint_steps > 0).then_some(a.checkpoint_steps),
            every: (a.checkpoint_minutes.is_finite() && a.checkpoint_minutes > 0.0)
                .then(|| Duration::from_secs_f64(a.checkpoint_minutes * 60.0)),
        },
        idle_exit: a.idle_exit.map(Duration::from_secs_f64),
        max_jobs: a.max_jobs,
        jobs_before: a.jobs_before,
    };
    match remote::run_worker(cfg) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            tracing::error!(error = format!("{e:#}"), "worker stopped");
            ExitCode::FAILURE
        }
    }
}

/// `fracture submit`.
pub fn submit(a: SubmitArgs) -> ExitCode {
    let mut body = match read_json_file(&a.scene) {
        Ok(v) => v,
        Err(code) => return code,
    };
    if a.priority.is_some() || !a.labels.is_empty() {
        let labels = match parse_labels(&a.labels) {
            Ok(l) => l,
            Err(code) => return code,
        };
        let scene = match body.get("scene") {
            Some(s) if body.get("grid").is_none() => s.clone(),
            _ => body,
        };
        body = serde_json::json!({
            "scene": scene,
            "priority": a.priority.unwrap_or(0),
            "labels": labels,
        });
    }
    if a.no_cache {
        if body.get("scene").is_some() && body.get("grid").is_none() {
            body["cache"] = "force".into();
        } else {
            body = serde_json::json!({"scene": body, "cache": "force"});
        }
    }
    let cfg = SubmitConfig {
        server: a.server,
        token: a.token,
        body,
        wait: a.wait,
        retry_for: Duration::from_secs(a.retry_seconds),
    };
    let mut out = std::io::stdout();
    match client::submit(&cfg, &mut out) {
        Ok(SubmitOutcome::Rejected(_, msg)) => {
            eprintln!("{msg}");
            ExitCode::from(2)
        }
        Ok(SubmitOutcome::Submitted(_)) => ExitCode::SUCCESS,
        Ok(SubmitOutcome::Ended(_, status, message)) => {
            if let Some(m) = message {
                eprintln!("{m}");
            }
            match status {
                JobStatus::Completed => ExitCode::SUCCESS,
                JobStatus::Cancelled => ExitCode::from(4),
                _ => ExitCode::from(3),
            }
        }
        Err(e) => {
            eprintln!("submit failed: {e:#}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn params_parse_numbers_strings_and_arrays() {
        let (p, v) =
            parse_param("cracks.0.propagation.toughness=25, 100,2.5e2").unwrap_or_default();
        assert_eq!(p, "cracks.0.propagation.toughness");
        assert_eq!(
            v,
            [
                serde_json::json!(25),
                serde_json::json!(100),
                serde_json::json!(250.0)
            ]
        );
        let (_, v) = parse_param("analysis=plane_strain,\"plane_stress\"").unwrap_or_default();
        assert_eq!(
            v,
            [
                serde_json::json!("plane_strain"),
                serde_json::json!("plane_stress")
            ]
        );
        let (_, v) = parse_param("cracks.0.points.1=[[0.1,0.2],[0.3,0.4]]").unwrap_or_default();
        assert_eq!(v.len(), 2);
        assert!(parse_param("toughness").is_err_and(|e| e.contains("path=v1,v2")));
        assert!(parse_param("=1").is_err());
        assert!(parse_param("a=").is_err_and(|e| e.contains("no values")));
        assert!(parse_param("a=[1,").is_err_and(|e| e.contains("not a JSON array")));
    }

    #[test]
    fn sweep_body_keeps_the_parameter_order() {
        let params = vec![
            ("z.b".to_string(), vec![serde_json::json!(1)]),
            ("a.c".to_string(), vec![serde_json::json!("x")]),
        ];
        let body = sweep_body(
            &serde_json::json!({"name": "s"}),
            &params,
            Some("n"),
            2,
            &serde_json::Map::new(),
            &serde_json::json!({"max_concurrent": 3, "cache": "force"})
                .as_object()
                .cloned()
                .unwrap_or_default(),
        );
        let z = body.find("z.b").unwrap_or(usize::MAX);
        let a = body.find("a.c").unwrap_or(0);
        assert!(z < a, "{body}");
        let v: serde_json::Value = serde_json::from_str(&body).unwrap_or_default();
        assert_eq!(v["name"], "n");
        assert_eq!(v["priority"], 2);
        assert_eq!(v["parameters"]["a.c"][0], "x");
        assert_eq!(v["max_concurrent"], 3);
        assert_eq!(v["cache"], "force");
    }
}
