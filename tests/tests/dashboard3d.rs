//! The dashboard with a 3D run, in a real headless browser (as `dashboard.rs`, which walks
//! the 2D views): the real `fracture` binary with one local worker, Debian's chromium
//! through chromedriver. A short 3D run (the `3d-wave-bar` example cut to one snapshot
//! interval: two slices at two times) completes first; its page must show the energy
//! plot, the slice picture labelled with its plane (`slice z = 2.0 mm …`), a selector of the
//! two planes that switches the picture and its label, and no crack-tip panels; the scene
//! editor validates the 3D example through the API. Any browser console error fails the
//! test. Screenshot `run-3d.png` in `tests/screenshots/` (git-ignored).
//!
//! Skips (with a message) when chromium or chromedriver is not installed.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use fantoccini::{Client, ClientBuilder};
use fracture_e2e::Server;
use serde_json::{Value, json};

const WAIT: Duration = Duration::from_secs(60);

/// Kills the child process when dropped (also when the test panics).
struct Proc(Child);
impl Drop for Proc {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// The first of `names` found on `PATH` or in the usual Debian folders.
fn find(names: &[&str]) -> Option<PathBuf> {
    let mut dirs: Vec<PathBuf> =
        std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default()).collect();
    dirs.extend(["/usr/bin", "/usr/lib/chromium"].map(PathBuf::from));
    names
        .iter()
        .flat_map(|n| dirs.iter().map(move |d| d.join(n)))
        .find(|p| p.is_file())
}

/// chromedriver on a free port; returns it and its URL once it answers.
fn chromedriver(driver: &Path) -> (Proc, String) {
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .expect("a free port");
    let child = Command::new(driver)
        .arg(format!("--port={port}"))
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("start chromedriver");
    let url = format!("http://127.0.0.1:{port}");
    let t0 = Instant::now();
    while std::net::TcpStream::connect(("127.0.0.1", port)).is_err() {
        assert!(
            t0.elapsed() < Duration::from_secs(30),
            "chromedriver did not start"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    (Proc(child), url)
}

/// Poll a script (a function body) until it returns something truthy; panic with the page's
/// recorded errors after `WAIT`.
async fn wait_js(c: &Client, what: &str, script: &str) -> Value {
    let t0 = Instant::now();
    loop {
        let v = c.execute(script, vec![]).await.unwrap_or(Value::Null);
        let truthy = match &v {
            Value::Null => false,
            Value::Bool(b) => *b,
            Value::String(s) => !s.is_empty(),
            Value::Number(n) => n.as_f64() != Some(0.0),
            _ => true,
        };
        if truthy {
            return v;
        }
        if t0.elapsed() > WAIT {
            let errors = c
                .execute("return window.__dashboardErrors || [];", vec![])
                .await
                .unwrap_or(Value::Null);
            panic!("timed out waiting for {what} (last value {v}); page errors: {errors}");
        }
        tokio::time::sleep(Duration::from_millis(250)).await;
    }
}

async fn no_page_errors(c: &Client, stage: &str) {
    let errors = c
        .execute(
            "return window.__dashboardErrors || ['errors.js not loaded'];",
            vec![],
        )
        .await
        .expect("the page's error list");
    assert_eq!(errors, json!([]), "browser errors at {stage}");
}

/// The steps in the browser, once the 3D job `id` has completed.
async fn steps(c: &Client, base: &str, id: &str) {
    c.goto(&format!("{base}/#/runs/{id}"))
        .await
        .expect("open the run page");
    wait_js(
        c,
        "the completed badge",
        "return document.querySelector('.badge-host .badge')?.textContent === 'completed';",
    )
    .await;
    // The energy balance is plotted; the crack-tip panels are not there.
    wait_js(
        c,
        "the energy plot's curves",
        "return document.querySelectorAll('#plot-energy .series path').length >= 4;",
    )
    .await;
    let hidden = c
        .execute(
            "return ['plot-speed', 'plot-position', 'plot-j', 'plot-k'].map(i => document.getElementById(i).hidden);",
            vec![],
        )
        .await
        .expect("tip plots");
    assert_eq!(
        hidden,
        json!([true, true, true, true]),
        "tip plots of a 3D run"
    );
    // The slice picture, labelled with its plane.
    let label = wait_js(
        c,
        "the slice picture and its label",
        "const i = document.getElementById('snap-image'); const l = document.getElementById('snap-slice-label'); \
         return i && !i.hidden && i.complete && i.naturalWidth > 0 && !l.hidden && l.textContent;",
    )
    .await;
    let label = label.as_str().unwrap_or_default().to_string();
    assert!(label.starts_with("slice z = 2.0 mm"), "{label}");
    assert!(label.contains("x–y plane"), "{label}");
    let planes = c
        .execute(
            "return [...document.querySelectorAll('#snap-slice option')].map(o => o.textContent);",
            vec![],
        )
        .await
        .expect("slice options");
    assert_eq!(planes.as_array().map(Vec::len), Some(2), "{planes}");
    let title = c
        .execute(
            "return document.getElementById('snap-h').textContent;",
            vec![],
        )
        .await
        .expect("title");
    assert_eq!(title, json!("Field slices"));
    let dim = c
        .execute(
            "return document.getElementById('summary-dimension')?.textContent;",
            vec![],
        )
        .await
        .expect("dimension");
    assert_eq!(dim, json!("3D"));
    // The other plane: its picture (another snapshot index) and its label.
    let first_src = c
        .execute("return document.getElementById('snap-image').src;", vec![])
        .await
        .expect("src");
    c.execute(
        "const s = document.getElementById('snap-slice'); s.value = s.options[1].value; \
         s.dispatchEvent(new Event('change'));",
        vec![],
    )
    .await
    .expect("choose the second slice");
    let label = wait_js(
        c,
        "the second plane's picture",
        "const i = document.getElementById('snap-image'); \
         const l = document.getElementById('snap-slice-label').textContent; \
         return l.startsWith('slice y') && i.complete && i.naturalWidth > 0 && l;",
    )
    .await;
    let label = label.as_str().unwrap_or_default();
    assert!(label.starts_with("slice y = 2.0 mm"), "{label}");
    assert!(label.contains("x–z plane"), "{label}");
    let src = c
        .execute("return document.getElementById('snap-image').src;", vec![])
        .await
        .expect("src");
    assert_ne!(src, first_src, "the picture follows the plane");
    // The time slider runs over the chosen plane's two times.
    let max = c
        .execute("return document.getElementById('snap-slider').max;", vec![])
        .await
        .expect("slider");
    assert_eq!(max, json!("1"));
    c.execute("window.scrollTo(0, 0);", vec![])
        .await
        .expect("scroll");
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("screenshots");
    if std::fs::create_dir_all(&dir).is_ok()
        && let Ok(png) = c.screenshot().await
    {
        let _ = std::fs::write(dir.join("run-3d.png"), png);
    }
    no_page_errors(c, "the 3D run page").await;

    // The scene editor takes the 3D example and the server validates it.
    c.goto(&format!("{base}/#/submit?example=3d-wave-bar"))
        .await
        .expect("open the editor");
    let size = wait_js(
        c,
        "the 3D example validated",
        "const r = document.getElementById('run-size'); return r && r.textContent;",
    )
    .await;
    // 10 240 particles, shown with an SI prefix.
    let size = size.as_str().unwrap_or_default();
    assert!(
        size.starts_with("Valid.") && size.contains("10.2 k"),
        "run size of 3d-wave-bar: {size}"
    );
    no_page_errors(c, "the scene editor").await;
}

#[test]
fn a_3d_runs_page_shows_its_slices_and_energies() {
    let (Some(chromium), Some(driver)) = (
        find(&["chromium", "chromium-browser", "google-chrome"]),
        find(&["chromedriver"]),
    ) else {
        eprintln!(
            "SKIPPED a_3d_runs_page_shows_its_slices_and_energies: chromium and chromedriver \
             are not installed (apt-get install -y chromium chromium-driver)"
        );
        return;
    };
    let dir = tempfile::tempdir().expect("tmp");
    let s = Server::start(dir.path(), &["--workers", "1"]);
    let mut scene: Value = serde_json::from_str(
        &std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../scenes/3d-wave-bar.json"
        ))
        .expect("scenes/3d-wave-bar.json"),
    )
    .expect("scene JSON");
    scene["time"]["end"] = scene["output"]["snapshot_interval"].clone();
    let id = s.submit(&json!({ "scene": scene }));
    let j = s.wait_done(&id, Duration::from_secs(240));
    assert_eq!(j["status"], "completed", "{j}");

    let browser_dir = tempfile::tempdir().expect("tmp");
    let profile = browser_dir.path().join("chromium-profile");
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .expect("runtime");
    let (_driver, driver_url) = chromedriver(&driver);
    let base = s.url.clone();
    rt.block_on(async move {
        let mut caps = serde_json::Map::new();
        caps.insert("browserName".into(), json!("chrome"));
        caps.insert(
            "goog:chromeOptions".into(),
            json!({
                "binary": chromium,
                "args": ["--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                         "--no-first-run", format!("--user-data-dir={}", profile.display()),
                         "--window-size=1280,1400", "--hide-scrollbars"]
            }),
        );
        let c = ClientBuilder::new(hyper_util::client::legacy::connect::HttpConnector::new())
            .capabilities(caps)
            .connect(&driver_url)
            .await
            .expect("connect to chromedriver");
        let (c2, id2) = (c.clone(), id.clone());
        let outcome = tokio::spawn(async move { steps(&c2, &base, &id2).await }).await;
        let _ = c.close().await;
        if let Err(e) = outcome {
            if e.is_panic() {
                std::panic::resume_unwind(e.into_panic());
            }
            panic!("the browser steps failed: {e}");
        }
    });
}
