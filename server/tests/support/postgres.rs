//! A real PostgreSQL server for tests: `FRACTURE_TEST_POSTGRES` (a URL whose user may
//! create databases), or else a throwaway cluster this test process starts itself with
//! Debian's `postgresql` binaries (`initdb`, `pg_ctl`; as the `postgres` user when run as
//! root, never as root), on 127.0.0.1 and a socket in its own temporary folder, fsync off.
//! A watcher process stops the cluster (`pg_ctl stop -m immediate`) and removes its folder
//! once this test process has exited, whatever the way.
//!
//! Without PostgreSQL the tests print why and skip, unless `FRACTURE_REQUIRE_POSTGRES=1`
//! (set by `.ci/run`): then they fail with the reason.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::OnceLock;
use std::sync::atomic::{AtomicU32, Ordering};

/// The administrative URL of the test server (its `postgres` database), or why there is none.
fn admin_url() -> &'static Result<String, String> {
    static URL: OnceLock<Result<String, String>> = OnceLock::new();
    URL.get_or_init(|| match std::env::var("FRACTURE_TEST_POSTGRES") {
        Ok(u) if !u.trim().is_empty() => Ok(u.trim().to_string()),
        _ => start_cluster(),
    })
}

/// A fresh, empty database on the test server: its URL. `None` (after printing why) when
/// PostgreSQL is not available and not required; a panic when it is required.
pub async fn fresh_database() -> Option<String> {
    use sqlx::Connection;
    static N: AtomicU32 = AtomicU32::new(0);
    let admin = match admin_url() {
        Ok(u) => u.clone(),
        Err(why) => {
            let required = std::env::var("FRACTURE_REQUIRE_POSTGRES").is_ok_and(|v| v == "1");
            assert!(
                !required,
                "FRACTURE_REQUIRE_POSTGRES=1 but PostgreSQL is not usable: {why}"
            );
            eprintln!("skipped: no PostgreSQL for this test ({why})");
            return None;
        }
    };
    let name = format!(
        "fracture_t{}_{}_{}",
        std::process::id(),
        N.fetch_add(1, Ordering::SeqCst),
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.subsec_nanos())
            .unwrap_or(0)
    );
    let mut c = sqlx::PgConnection::connect(&admin)
        .await
        .unwrap_or_else(|e| panic!("cannot connect to the test PostgreSQL at {admin}: {e}"));
    sqlx::raw_sql(sqlx::AssertSqlSafe(format!("CREATE DATABASE {name}")))
        .execute(&mut c)
        .await
        .unwrap_or_else(|e| panic!("cannot create a test database: {e}"));
    let _ = c.close().await;
    Some(with_database(&admin, &name))
}

/// `url` with its database replaced by `name`.
fn with_database(url: &str, name: &str) -> String {
    let (base, query) = match url.split_once('?') {
        Some((b, q)) => (b, format!("?{q}")),
        None => (url, String::new()),
    };
    let scheme_end = base.find("://").map(|i| i + 3).unwrap_or(0);
    let base = match base[scheme_end..].find('/') {
        Some(i) => &base[..scheme_end + i],
        None => base,
    };
    format!("{base}/{name}{query}")
}

/// The folder of Debian's PostgreSQL binaries (the newest version), or one on `PATH`.
fn bin_dir() -> Option<PathBuf> {
    let mut versions: Vec<(u32, PathBuf)> = std::fs::read_dir("/usr/lib/postgresql")
        .ok()?
        .filter_map(|e| {
            let e = e.ok()?;
            let v: u32 = e.file_name().to_str()?.parse().ok()?;
            let bin = e.path().join("bin");
            bin.join("initdb").exists().then_some((v, bin))
        })
        .collect();
    versions.sort();
    versions.pop().map(|(_, b)| b).or_else(|| {
        let out = Command::new("pg_config").arg("--bindir").output().ok()?;
        let p = PathBuf::from(String::from_utf8_lossy(&out.stdout).trim());
        p.join("initdb").exists().then_some(p)
    })
}

fn is_root() -> bool {
    Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
}

/// A command run as the `postgres` user when this process is root.
fn as_owner(root: bool, program: &Path) -> Command {
    if root {
        let mut c = Command::new("runuser");
        c.args(["-u", "postgres", "--"]).arg(program);
        c
    } else {
        Command::new(program)
    }
}

fn free_port() -> Option<u16> {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .ok()
}

/// Start the throwaway cluster; its admin URL.
fn start_cluster() -> Result<String, String> {
    let bin = bin_dir().ok_or(
        "no PostgreSQL binaries (install Debian's `postgresql`; /usr/lib/postgresql/*/bin/initdb)",
    )?;
    let root = is_root();
    let dir = std::env::temp_dir().join(format!(
        "fracture-pg-{}-{}",
        std::process::id(),
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_nanos())
            .unwrap_or(0)
    ));
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    // The watcher first: whatever happens next, the folder (and a started server) goes
    // away after this process.
    let pg_ctl = bin.join("pg_ctl");
    let stop = format!(
        "{} '{}' -D '{}/data' -m immediate stop >/dev/null 2>&1",
        if root { "runuser -u postgres --" } else { "" },
        pg_ctl.display(),
        dir.display()
    );
    let script = format!(
        "while kill -0 {pid} 2>/dev/null; do sleep 0.5; done; {stop}; rm -rf '{dir}'",
        pid = std::process::id(),
        dir = dir.display()
    );
    Command::new("sh")
        .args(["-c", &script])
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .map_err(|e| format!("cannot start the cluster's watcher: {e}"))?;
    if root {
        let ok = Command::new("chown")
            .args(["postgres:postgres"])
            .arg(&dir)
            .status()
            .is_ok_and(|s| s.success());
        if !ok {
            return Err(
                "cannot give the cluster's folder to the `postgres` user (no such user?)".into(),
            );
        }
    }
    let data = dir.join("data");
    let out = as_owner(root, &bin.join("initdb"))
        .arg("-D")
        .arg(&data)
        .args([
            "-A",
            "trust",
            "-U",
            "postgres",
            "-E",
            "UTF8",
            "--locale=C",
            "--no-sync",
        ])
        .output()
        .map_err(|e| format!("cannot run initdb: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "initdb failed: {}",
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    let mut last = String::new();
    for _ in 0..3 {
        let port = free_port().ok_or("no free port on 127.0.0.1")?;
        let opts = format!(
            "-c listen_addresses=127.0.0.1 -p {port} -k {} -c fsync=off -c synchronous_commit=off \
             -c full_page_writes=off -c max_connections=200",
            dir.display()
        );
        let out = as_owner(root, &pg_ctl)
            .arg("-D")
            .arg(&data)
            .args(["-o", &opts, "-l"])
            .arg(dir.join("server.log"))
            .args(["-w", "-t", "60", "start"])
            .stdin(Stdio::null())
            .output()
            .map_err(|e| format!("cannot run pg_ctl: {e}"))?;
        if out.status.success() {
            return Ok(format!("postgres://postgres@127.0.0.1:{port}/postgres"));
        }
        last = format!(
            "{} {}",
            String::from_utf8_lossy(&out.stderr).trim(),
            std::fs::read_to_string(dir.join("server.log")).unwrap_or_default()
        );
    }
    Err(format!("the cluster did not start: {last}"))
}
