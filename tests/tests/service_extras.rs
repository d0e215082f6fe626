//! End-to-end tests of the service's downloads and job routes beyond `api.md` (issue 20):
//! the zipped VTK series, CSV attachments, snapshot picture options and their render
//! report, rerun, name search and combined label filters, the version and the Prometheus
//! metrics. A real server on 127.0.0.1 with one local worker and a temporary data folder.

use std::collections::BTreeSet;
use std::io::Read;
use std::time::Duration;

use fracture_e2e::{Server, tiny_scene};
use serde_json::{Value, json};

const LONG: Duration = Duration::from_secs(120);

fn ids(v: &Value) -> BTreeSet<String> {
    v.as_array()
        .map(|a| {
            a.iter()
                .filter_map(|j| j["id"].as_str().map(String::from))
                .collect()
        })
        .unwrap_or_default()
}

fn header(r: &reqwest::blocking::Response, name: &str) -> String {
    r.headers()
        .get(name)
        .and_then(|v| v.to_str().ok())
        .unwrap_or("")
        .to_string()
}

/// Width and height of a PNG from its IHDR chunk.
fn png_size(bytes: &[u8]) -> (u32, u32) {
    assert!(
        bytes.len() > 24 && bytes.starts_with(b"\x89PNG"),
        "not a PNG"
    );
    let be = |i: usize| u32::from_be_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
    (be(16), be(20))
}

/// A 400 in the error format whose detail names `param`.
fn assert_bad_parameter(s: &Server, path: &str, param: &str) {
    let r = s.http.get(s.at(path)).send().expect("GET");
    assert_eq!(r.status().as_u16(), 400, "{path}");
    let v: Value = r.json().expect("error body");
    assert_eq!(v["error"], "bad_request", "{path}: {v}");
    assert_eq!(v["details"][0]["path"], param, "{path}: {v}");
    assert!(
        v["message"].as_str().is_some_and(|m| m.contains(param)),
        "{path}: {v}"
    );
}

#[test]
fn downloads_pictures_rerun_search_version_and_metrics() {
    let dir = tempfile::tempdir().expect("tmp");
    let s = Server::start(dir.path(), &["--workers", "1"]);
    let a = s.submit(&json!({"scene": tiny_scene("Alpha Plate", 300, 3),
                             "labels": {"team": "x", "kind": "a"}}));
    let b = s.submit(&json!({"scene": tiny_scene("beta-plate", 100, 0),
                             "labels": {"team": "x", "kind": "b"}}));
    for id in [&a, &b] {
        let j = s.wait_done(id, LONG);
        assert_eq!(j["status"], "completed", "{j}");
    }

    // --- The VTK series as a zip: the same files the results crate writes from the MCAP
    // file (the route reads the snapshots from the store: two independent paths).
    let r = s
        .http
        .get(s.at(&format!("/api/v1/jobs/{a}/vtk.zip")))
        .send()
        .expect("GET vtk.zip");
    assert_eq!(r.status().as_u16(), 200);
    assert_eq!(header(&r, "content-type"), "application/zip");
    assert_eq!(
        header(&r, "content-disposition"),
        format!("attachment; filename=\"{a}-vtk.zip\"")
    );
    let bytes = r.bytes().expect("zip bytes").to_vec();
    let mut zip = zip::ZipArchive::new(std::io::Cursor::new(bytes)).expect("a zip archive");
    let mut entries = std::collections::BTreeMap::new();
    for k in 0..zip.len() {
        let mut f = zip.by_index(k).expect("entry");
        let mut data = Vec::new();
        f.read_to_end(&mut data).expect("read entry");
        let name = f.name().expect("entry name").to_string();
        let short = name
            .strip_prefix(&format!("{a}-vtk/"))
            .unwrap_or_else(|| panic!("{name} is not in the folder {a}-vtk/"))
            .to_string();
        entries.insert(short, data);
    }
    let snapshots = s.get_json(&format!("/api/v1/jobs/{a}/snapshots"));
    let n = snapshots.as_array().map(Vec::len).unwrap_or(0);
    assert!(n >= 2, "{snapshots}");
    assert!(entries.contains_key("fields.pvd"), "{:?}", entries.keys());
    assert!(entries.contains_key("cracks.pvd"), "{:?}", entries.keys());
    let grids = entries.keys().filter(|k| k.ends_with(".vti")).count();
    assert_eq!(grids, n, "one grid file per snapshot: {:?}", entries.keys());
    let mcap = s
        .http
        .get(s.at(&format!("/api/v1/jobs/{a}/fields.mcap")))
        .send()
        .expect("GET fields.mcap")
        .bytes()
        .expect("mcap bytes");
    let mcap_file = dir.path().join("fields.mcap");
    std::fs::write(&mcap_file, &mcap).expect("write mcap");
    let snaps = fracture_results::mcapfile::read_snapshots(&mcap_file).expect("read snapshots");
    let expected = fracture_results::vtk::series_files(&snaps).expect("series");
    assert_eq!(
        expected
            .iter()
            .map(|(k, _)| k.clone())
            .collect::<BTreeSet<_>>(),
        entries.keys().cloned().collect::<BTreeSet<_>>()
    );
    for (name, data) in &expected {
        assert!(
            entries.get(name) == Some(data),
            "{name} differs from the MCAP export"
        );
    }
    let pvd = String::from_utf8_lossy(&entries["fields.pvd"]).into_owned();
    for k in entries.keys().filter(|k| k.ends_with(".vti")) {
        assert!(pvd.contains(&format!("file=\"{k}\"")), "{k} not in {pvd}");
    }
    // No snapshots: 404 in the error format; an unknown job: 404.
    for (path, why) in [
        (format!("/api/v1/jobs/{b}/vtk.zip"), "snapshots"),
        ("/api/v1/jobs/nope/vtk.zip".to_string(), "nope"),
    ] {
        let r = s.http.get(s.at(&path)).send().expect("GET");
        assert_eq!(r.status().as_u16(), 404, "{path}");
        let v: Value = r.json().expect("body");
        assert_eq!(v["error"], "not_found");
        assert!(
            v["message"].as_str().is_some_and(|m| m.contains(why)),
            "{v}"
        );
    }

    // --- CSV downloads are attachments named after the job.
    for (route, name) in [("crack-tips", "crack_tips"), ("energy", "energy")] {
        let r = s
            .http
            .get(s.at(&format!("/api/v1/jobs/{a}/{route}")))
            .header("accept", "text/csv")
            .send()
            .expect("GET csv");
        assert_eq!(r.status().as_u16(), 200);
        assert!(header(&r, "content-type").starts_with("text/csv"));
        assert_eq!(
            header(&r, "content-disposition"),
            format!("attachment; filename=\"{a}-{name}.csv\"")
        );
        // JSON stays inline.
        let r = s
            .http
            .get(s.at(&format!("/api/v1/jobs/{a}/{route}")))
            .send()
            .expect("GET json");
        assert_eq!(header(&r, "content-disposition"), "");
    }

    // --- Picture options, the render report and the aliasing header.
    let pic = |q: &str| {
        let r = s
            .http
            .get(s.at(&format!("/api/v1/jobs/{a}/snapshots/1/fringe.png{q}")))
            .send()
            .expect("GET png");
        assert_eq!(r.status().as_u16(), 200, "{q}");
        let aliasing = header(&r, "x-fringe-aliasing");
        let ppc = header(&r, "x-render-px-per-cell");
        (png_size(&r.bytes().expect("png")), aliasing, ppc)
    };
    let (small, aliasing, ppc) = pic("?px_per_cell=2&legend=false");
    assert_eq!(ppc, "2");
    assert!(
        aliasing.starts_with("none; max-per-pixel=") || aliasing.starts_with("aliased; pairs="),
        "{aliasing}"
    );
    let (large, _, ppc) = pic("?px_per_cell=6&legend=false");
    assert_eq!(ppc, "6");
    assert_eq!(large.0, 3 * small.0, "{small:?} {large:?}");
    let (wide, _, _) = pic("?width=400&legend=0&cracks=false");
    assert_eq!(wide.0, 400);
    let report = s.get_json(&format!(
        "/api/v1/jobs/{a}/snapshots/1/fringe.json?px_per_cell=6&legend=false"
    ));
    assert_eq!(report["component"], "fringe");
    assert_eq!(report["width"], large.0);
    assert_eq!(report["height"], large.1);
    assert_eq!(report["px_per_cell"], 6.0);
    assert!(report["aliased"].is_boolean(), "{report}");
    assert!(
        report["aliasing"]
            .as_str()
            .is_some_and(|h| h.starts_with(if report["aliased"] == true {
                "aliased"
            } else {
                "none"
            })),
        "{report}"
    );
    // Not a fringe picture: no aliasing header; a fixed range shows in the report.
    let r = s
        .http
        .get(s.at(&format!(
            "/api/v1/jobs/{a}/snapshots/1/sxx.png?range=-1e6,1e6"
        )))
        .send()
        .expect("GET sxx");
    assert_eq!(r.status().as_u16(), 200);
    assert_eq!(header(&r, "x-fringe-aliasing"), "");
    let report = s.get_json(&format!(
        "/api/v1/jobs/{a}/snapshots/1/sxx.json?range=-1e6,1e6"
    ));
    assert_eq!(report["range"], json!([-1.0e6, 1.0e6]));
    assert!(report["aliasing"].is_null(), "{report}");
    for (q, param) in [
        ("px_per_cell=-1", "px_per_cell"),
        ("px_per_cell=abc", "px_per_cell"),
        ("px_per_cell=1e9", "px_per_cell"),
        ("width=0", "width"),
        ("width=12.5", "width"),
        ("range=5,1", "range"),
        ("range=1", "range"),
        ("fringe_per_pa=0", "fringe_per_pa"),
        ("legend=maybe", "legend"),
        ("cracks=2", "cracks"),
    ] {
        assert_bad_parameter(
            &s,
            &format!("/api/v1/jobs/{a}/snapshots/1/fringe.png?{q}"),
            param,
        );
    }
    let r = s
        .http
        .get(s.at(&format!(
            "/api/v1/jobs/{a}/snapshots/1/fringe.png?colour=red"
        )))
        .send()
        .expect("GET");
    assert_eq!(r.status().as_u16(), 400);

    // --- Rerun: same scene, name, labels; linked by `rerun_of`; cross-site refused.
    let (code, rerun) = s.post_json(&format!("/api/v1/jobs/{a}/rerun"), &json!({}));
    assert_eq!(code, 201, "{rerun}");
    let r_id = rerun["id"].as_str().expect("id").to_string();
    assert_ne!(r_id, a);
    assert_eq!(rerun["rerun_of"], a.as_str());
    assert_eq!(rerun["status"], "queued");
    let orig = s.job(&a);
    assert_eq!(rerun["name"], orig["name"]);
    assert_eq!(rerun["labels"], orig["labels"]);
    assert_eq!(rerun["scene"], orig["scene"]);
    assert!(orig.get("rerun_of").is_none(), "{orig}");
    let (code, v) = s.post_json("/api/v1/jobs/nope/rerun", &json!({}));
    assert_eq!((code, v["error"].as_str()), (404, Some("not_found")), "{v}");
    let r = s
        .http
        .post(s.at(&format!("/api/v1/jobs/{a}/rerun")))
        .header("sec-fetch-site", "cross-site")
        .send()
        .expect("POST");
    assert_eq!(r.status().as_u16(), 403);
    let done = s.wait_done(&r_id, LONG);
    assert_eq!(done["status"], "completed", "{done}");
    assert_eq!(done["rerun_of"], a.as_str());

    // --- Name search and labels combined with AND.
    let list = |q: &str| ids(&s.get_json(&format!("/api/v1/jobs{q}")));
    let set = |v: &[&String]| v.iter().map(|x| x.to_string()).collect::<BTreeSet<_>>();
    assert_eq!(list("?q=ALPHA"), set(&[&a, &r_id]));
    assert_eq!(list("?q=beta-P"), set(&[&b]));
    assert_eq!(list("?q=plate"), set(&[&a, &b, &r_id]));
    assert_eq!(list("?q=gamma"), BTreeSet::new());
    assert_eq!(list("?label=team:x"), set(&[&a, &b, &r_id]));
    assert_eq!(list("?label=team:x&label=kind:b"), set(&[&b]));
    assert_eq!(list("?label=kind:a&label=kind:b"), BTreeSet::new());
    assert_eq!(
        list("?q=alpha&label=kind:a&status=completed"),
        set(&[&a, &r_id])
    );
    assert_eq!(list("?q=alpha&limit=1").len(), 1);
    // Unknown and repeated parameters stay 400s, naming the parameter.
    assert_bad_parameter(&s, "/api/v1/jobs?colour=red", "colour");
    assert_bad_parameter(&s, "/api/v1/jobs?status=queued&status=failed", "status");
    assert_bad_parameter(&s, "/api/v1/jobs?limit=many", "limit");

    // --- Version.
    let v = s.get_json("/api/v1/version");
    assert_eq!(v["service"], "fracture-server");
    assert!(v["version"].as_str().is_some_and(|x| !x.is_empty()), "{v}");
    assert!(
        v["solver_version"].as_str().is_some_and(|x| !x.is_empty()),
        "{v}"
    );
    assert!(
        matches!(v["build_profile"].as_str(), Some("debug" | "release")),
        "{v}"
    );
    assert!(
        v["git_commit"].is_null()
            || v["git_commit"]
                .as_str()
                .is_some_and(|c| c.len() >= 7 && c.chars().all(|x| x.is_ascii_hexdigit())),
        "{v}"
    );

    // --- Metrics, against the job list.
    let r = s.http.get(s.at("/metrics")).send().expect("GET /metrics");
    assert_eq!(r.status().as_u16(), 200);
    assert!(header(&r, "content-type").starts_with("text/plain"));
    let text = r.text().expect("text");
    let sample = |name: &str| -> f64 {
        text.lines()
            .find_map(|l| l.strip_prefix(name)?.strip_prefix(' ')?.trim().parse().ok())
            .unwrap_or_else(|| panic!("no sample {name} in\n{text}"))
    };
    let completed = s
        .get_json("/api/v1/jobs?status=completed")
        .as_array()
        .map(Vec::len)
        .unwrap_or(0);
    assert_eq!(completed, 3);
    assert_eq!(
        sample("fracture_jobs{status=\"completed\"}"),
        completed as f64
    );
    assert_eq!(sample("fracture_jobs{status=\"failed\"}"), 0.0);
    assert_eq!(sample("fracture_queue_depth"), 0.0);
    assert_eq!(sample("fracture_jobs_running"), 0.0);
    assert_eq!(sample("fracture_particle_steps_per_second"), 0.0);
    assert_eq!(sample("fracture_workers"), 1.0);
    // Three jobs ended within the last minute.
    assert_eq!(
        sample("fracture_jobs_finished_per_second{window=\"60s\"}"),
        3.0 / 60.0
    );
    for l in text.lines().filter(|l| l.starts_with("# TYPE ")) {
        assert!(l.ends_with(" gauge") || l.ends_with(" counter"), "{l}");
    }
    // The new routes are in the OpenAPI document.
    let api = s.get_json("/api/v1/openapi.json");
    for p in [
        "/api/v1/jobs/{id}/vtk.zip",
        "/api/v1/jobs/{id}/rerun",
        "/api/v1/version",
        "/metrics",
    ] {
        assert!(
            api["paths"][p].is_object(),
            "{p} missing from the OpenAPI document"
        );
    }
}

/// While a job runs, the metrics count it and its particle-steps per second.
#[test]
fn metrics_see_a_running_job() {
    let dir = tempfile::tempdir().expect("tmp");
    let s = Server::start(dir.path(), &["--workers", "1"]);
    let id = s.submit(&fracture_e2e::scene("long", 40, 20, 200_000, 0));
    s.wait_for(&id, LONG, |j| {
        j["status"] == "running" && j["progress"]["step"].as_u64().unwrap_or(0) > 0
    });
    let text = s
        .http
        .get(s.at("/metrics"))
        .send()
        .expect("GET")
        .text()
        .expect("text");
    let sample = |name: &str| -> f64 {
        text.lines()
            .find_map(|l| l.strip_prefix(name)?.strip_prefix(' ')?.trim().parse().ok())
            .unwrap_or_else(|| panic!("no sample {name} in\n{text}"))
    };
    assert_eq!(sample("fracture_jobs_running"), 1.0);
    let rate = sample("fracture_particle_steps_per_second");
    assert!(rate > 0.0 && rate.is_finite(), "{text}");
    let (code, v) = s.post_json(&format!("/api/v1/jobs/{id}/cancel"), &json!({}));
    assert_eq!(code, 200, "{v}");
    s.wait_done(&id, LONG);
}

/// Runs that are not repeated (docs/service.md, "Cache"): a completed scene submitted again
/// is answered at once by a completed copy whose results (crack-tip rows, CSV, MCAP file,
/// pictures) are the original's; `"cache": "force"` queues a real run. Prints the answer
/// times of the cache hits.
#[test]
fn a_resubmitted_completed_scene_is_answered_from_the_cache_in_milliseconds() {
    let dir = tempfile::tempdir().expect("tmp");
    let s = Server::start(dir.path(), &["--workers", "1"]);
    let scene = tiny_scene("cached plate", 200, 2);
    let t_run = std::time::Instant::now();
    let orig = s.submit(&json!({"scene": scene.clone()}));
    let done = s.wait_done(&orig, LONG);
    let run_s = t_run.elapsed().as_secs_f64();
    assert_eq!(done["status"], "completed", "{done}");
    // Provenance of the run: this binary's commit (as `/api/v1/version` says), a host, times.
    let p = &done["summary"]["provenance"];
    let version = s.get_json("/api/v1/version");
    assert_eq!(p["solver_commit"], version["git_commit"], "{p}");
    assert!(p["host"].as_str().is_some_and(|h| !h.is_empty()), "{p}");
    assert!(p["started_at"].as_str() <= p["finished_at"].as_str(), "{p}");

    let get = |path: String| {
        let r = s.http.get(s.at(&path)).send().expect("GET");
        assert_eq!(r.status().as_u16(), 200, "{path}");
        r.bytes().expect("bytes").to_vec()
    };
    let mut times_ms = Vec::new();
    let mut copies = Vec::new();
    for _ in 0..5 {
        let t0 = std::time::Instant::now();
        let (code, hit) = s.post_json("/api/v1/jobs", &json!({"scene": scene.clone()}));
        times_ms.push(t0.elapsed().as_secs_f64() * 1e3);
        assert_eq!(code, 201, "{hit}");
        assert_eq!(hit["status"], "completed", "answered, not queued: {hit}");
        assert_eq!(hit["cached_from"], orig.as_str(), "{hit}");
        assert_eq!(hit["summary"], done["summary"], "the original's summary");
        copies.push(hit["id"].as_str().expect("id").to_string());
    }
    let copy = &copies[0];
    let tips = get(format!("/api/v1/jobs/{orig}/crack-tips"));
    let rows: Value = serde_json::from_slice(&tips).expect("json");
    assert!(
        rows.as_array().is_some_and(|a| a.len() > 2),
        "the run has crack-tip rows: {rows}"
    );
    assert_eq!(get(format!("/api/v1/jobs/{copy}/crack-tips")), tips);
    assert_eq!(
        get(format!("/api/v1/jobs/{copy}/fields.mcap")),
        get(format!("/api/v1/jobs/{orig}/fields.mcap"))
    );
    assert_eq!(
        get(format!("/api/v1/jobs/{copy}/snapshots/0/sxx.png")),
        get(format!("/api/v1/jobs/{orig}/snapshots/0/sxx.png"))
    );
    // No run was queued for the copies; a forced submission runs again.
    assert_eq!(s.job(copy)["attempts"], 0);
    let t_forced = std::time::Instant::now();
    let forced = s.submit(&json!({"scene": scene, "cache": "force"}));
    let f = s.wait_done(&forced, LONG);
    eprintln!("forced run: {:.2} s", t_forced.elapsed().as_secs_f64());
    assert_eq!(f["status"], "completed", "{f}");
    assert!(f.get("cached_from").is_none(), "{f}");
    assert_eq!(f["attempts"], 1, "it ran: {f}");
    let mut sorted = times_ms.clone();
    sorted.sort_by(f64::total_cmp);
    eprintln!(
        "cache hits: POST /api/v1/jobs answered in {} ms (min {:.2}, median {:.2}, max {:.2}); \
         the original run took {:.2} s from submission to completed ({:.3} s of solver wall time)",
        times_ms
            .iter()
            .map(|t| format!("{t:.2}"))
            .collect::<Vec<_>>()
            .join(", "),
        sorted[0],
        sorted[sorted.len() / 2],
        sorted[sorted.len() - 1],
        run_s,
        done["summary"]["wall_seconds"].as_f64().unwrap_or(f64::NAN)
    );
    assert!(
        sorted[sorted.len() / 2] < 500.0,
        "a cache hit should answer within milliseconds: {times_ms:?}"
    );
}
