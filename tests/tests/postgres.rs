//! `fracture serve --database postgres://…` end to end: the real binary with local worker
//! processes on a real PostgreSQL server (the throwaway cluster of
//! `server/tests/support/postgres.rs`, or `FRACTURE_TEST_POSTGRES`; skipped with the reason
//! when there is none, unless `FRACTURE_REQUIRE_POSTGRES=1`), and the flag's errors.

#![allow(clippy::unwrap_used)]

#[path = "../../server/tests/support/postgres.rs"]
mod pg;

use std::process::Command;
use std::time::Duration;

use fracture_e2e::{Server, fracture_bin, tiny_scene};
use serde_json::json;

fn fresh_database() -> Option<String> {
    tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap()
        .block_on(pg::fresh_database())
}

/// Jobs run to completion with the store on PostgreSQL (no `fracture.db` in the data
/// folder, results files there), and a restart of the server keeps them.
#[test]
fn serve_on_postgres_runs_jobs_and_keeps_them_across_a_restart() {
    let Some(url) = fresh_database() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let mut s = Server::start(dir.path(), &["--workers", "2", "--database", &url]);
    let ids: Vec<String> = (0..3)
        .map(|i| s.submit(&json!({"scene": tiny_scene(&format!("pg{i}"), 60, 2)})))
        .collect();
    for id in &ids {
        let j = s.wait_done(id, Duration::from_secs(90));
        assert_eq!(j["status"], "completed", "{j}");
        assert_eq!(j["attempts"], 1, "{j}");
        let energy = s.get_json(&format!("/api/v1/jobs/{id}/energy"));
        assert!(!energy.as_array().unwrap().is_empty(), "{energy}");
        let snaps = s.get_json(&format!("/api/v1/jobs/{id}/snapshots"));
        assert!(snaps.as_array().unwrap().len() >= 2, "{snaps}");
        assert!(
            dir.path()
                .join("jobs")
                .join(id)
                .join("fields.mcap")
                .exists()
        );
    }
    assert!(
        !dir.path().join("fracture.db").exists(),
        "the store is on PostgreSQL, not in the data folder"
    );
    // The cache answers from PostgreSQL's rows too.
    let again = s.submit(&json!({"scene": tiny_scene("pg0", 60, 2)}));
    let j = s.job(&again);
    assert_eq!(
        (j["status"].as_str(), j["cached_from"].as_str()),
        (Some("completed"), Some(ids[0].as_str())),
        "{j}"
    );

    s.restart();
    let list = s.get_json("/api/v1/jobs");
    let listed = list["jobs"].as_array().or(list.as_array()).unwrap().len();
    assert_eq!(listed, 4, "{list}");
    let j = s.job(&ids[2]);
    assert_eq!(j["status"], "completed", "{j}");
    let log = std::fs::read_to_string(dir.path().join("server.log")).unwrap();
    assert!(log.contains("store on PostgreSQL"), "{log}");
}

/// `--database` errors at start (status 1), naming the flag, password hidden: a URL of
/// another kind, an unreachable server.
#[test]
fn bad_or_unreachable_database_is_a_clear_startup_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(fracture_bin())
        .args([
            "serve",
            "--bind",
            "127.0.0.1:0",
            "--workers",
            "0",
            "--database",
        ])
        .arg("mysql://u:pw@localhost/db")
        .arg("--data")
        .arg(dir.path())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("--database") && err.contains("not a PostgreSQL URL"),
        "{err}"
    );
    assert!(!err.contains("pw@"), "{err}");

    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let out = Command::new(fracture_bin())
        .args(["serve", "--bind", "127.0.0.1:0", "--workers", "0"])
        .env(
            "FRACTURE_DATABASE",
            format!("postgres://u:secret@127.0.0.1:{port}/db"),
        )
        .arg("--data")
        .arg(dir.path())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&format!("--database postgres://u:***@127.0.0.1:{port}/db")),
        "{err}"
    );
    assert!(err.to_lowercase().contains("refused"), "{err}");
    assert!(!err.contains("secret"), "{err}");
}
