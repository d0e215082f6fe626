//! Acceptance test of issue 6 (sweeps): the reduced Rosakis shear-crack scene
//! (`scenes/rosakis-shear-mini.json`) as a three-run toughness sweep through the real
//! service — `fracture sweep --wait` against `fracture serve` on 127.0.0.1:0 with local
//! worker processes — and the physics the sweep must show.
//!
//! The scene: two Homalite-100 halves (E = 5.2 GPa, ν = 0.34, ρ = 1230 kg/m³, plane
//! strain) bonded along y = 27.5 mm (mid-cell), a 15 mm notch along the bond, the impact as a
//! prescribed x velocity of 23.25 m/s on the struck patch below the notch, growth fixed
//! along the bond ([1, 0]), 1 mm cells, 30 µs (154 steps). The sweep runs it under the
//! product's law, the crack-tip equation of motion, which is also the scene file's default
//! since it stopped naming the seed's `wave` rule (the test still writes the scene with
//! `"speed": "equation_of_motion"` and sweeps that file, so it does not depend on the file).
//! Under the seed's rule the speed is c_L times the share of steps whose raw J1 reaches
//! J_Ic, so its order in J_Ic hangs on J's transients: once J's kinetic pair was summed by
//! parts, the stationary notch's J1 at 5.1 µs (the impact wave crossing the ring) read 29.9
//! instead of 17.8 J/m², the J_Ic = 25 crack started 3 µs earlier and ran 45 mm at
//! 1795 m/s, slower than J_Ic = 100's 1887 m/s (pitfall 12: the rule, not the material).
//!
//! Checks, for J_Ic = 25, 100 and 250 J/m² (tolerances stated where they are used):
//! * the crack grows along the bond: the tip's y stays within h/2 = 0.5 mm of the bond
//!   line (the tip moves with the material; at 1 mm cells we see up to 0.23 mm);
//! * a tougher bond starts later: initiation strictly later, by more than a time step
//!   (≈ 0.2 µs), from one toughness to the next (G* at the notch rises with the impact
//!   wave, so Γ is reached later: 5.10, 8.43, 8.82 µs at af46b79, the J_Ic = 25 tip starting
//!   on its unfiltered J as the wave reaches the notch);
//! * and has grown less by 30 µs: the extension strictly decreases (22.11, 21.71,
//!   20.43 mm at af46b79).
//!
//! Not checked, since issue 34: an ordering of speeds. Under constant toughness these tips
//! run at the law's cap near c_R (the study flags them, `docs/rosakis.md`: most of their
//! fracture energy taken above Γ at the speed wall), where the speed is the limit's, not
//! the material's; the mean from initiation to the end also mixes in how early each
//! started (881, 998, 956 m/s at af46b79: the J_Ic = 25 tip starts 3.3 µs earlier, on a
//! weaker drive). The extension differences come from the initiation delays (0.33 µs at
//! ~1170 m/s ≈ 0.4 mm between 100 and 250 J/m² … ). Nor "speed ≤ c_L": a law capped at
//! 0.999 c_R meets it by itself. (Before issue 34, with the ring and filter in cells and a
//! filtered start: 22.0, 21.1, 19.9 mm, initiation 9.0, 9.4, 10.0 µs; the seed's rule with
//! the bond on a node row carried the crack 16 mm further, `algorithm.md` pitfall 9.)

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use fracture_e2e::{Server, fracture_bin};
use serde_json::Value;

/// Bond line of the scene (m).
const BOND_Y: f64 = 0.0275;
/// Cell size of the scene (m).
const H: f64 = 0.001;
/// About one time step of the scene (s): 30 µs in 154 steps.
const STEP: f64 = 0.2e-6;

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

/// Plane-strain longitudinal wave speed √(E(1−ν)/((1+ν)(1−2ν)ρ)).
fn c_l(e: f64, nu: f64, rho: f64) -> f64 {
    (e * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu) * rho)).sqrt()
}

/// What one run's crack-tip history says.
#[derive(Debug)]
struct Growth {
    toughness: f64,
    initiation: f64,
    extension: f64,
    mean_speed: f64,
    max_speed: f64,
    max_dy: f64,
}

fn growth(toughness: f64, rows: &[Value]) -> Growth {
    // The notch has one tip (its mouth is outside the body): crack 0, tip 1.
    let tip: Vec<&Value> = rows
        .iter()
        .filter(|r| r["crack"] == 0 && r["tip"] == 1)
        .collect();
    assert!(tip.len() > 100, "too few crack-tip rows: {}", tip.len());
    let x0 = f(&tip[0]["x"]);
    let last = tip[tip.len() - 1];
    let initiation = tip
        .iter()
        .find(|r| r["growing"] == true || r["growing"] == 1)
        .map(|r| f(&r["time"]))
        .unwrap_or(f64::NAN);
    let extension = f(&last["x"]) - x0;
    Growth {
        toughness,
        initiation,
        extension,
        mean_speed: extension / (f(&last["time"]) - initiation),
        max_speed: tip.iter().map(|r| f(&r["speed"])).fold(0.0, f64::max),
        max_dy: tip
            .iter()
            .map(|r| (f(&r["y"]) - BOND_Y).abs())
            .fold(0.0, f64::max),
    }
}

#[test]
fn rosakis_mini_toughness_sweep_through_the_service() {
    let t0 = Instant::now();
    let scene_path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/rosakis-shear-mini.json");
    let scene: Value = serde_json::from_str(
        &std::fs::read_to_string(&scene_path).expect("read rosakis-shear-mini.json"),
    )
    .expect("scene JSON");
    assert_eq!(scene["cracks"][0]["points"][1][1], BOND_Y);
    assert_eq!(scene["grid"]["cell_size"], H);
    let m = &scene["materials"]["homalite"];
    let cl = c_l(
        f(&m["youngs_modulus"]),
        f(&m["poissons_ratio"]),
        f(&m["density"]),
    );
    assert!((cl - 2551.0).abs() < 1.0, "c_L = {cl}");

    let dir = tempfile::tempdir().expect("tmp");
    // The product's growth law, not the seed's rule the scene file names (module doc).
    let mut eom = scene.clone();
    eom["cracks"][0]["propagation"]["speed"] = Value::from("equation_of_motion");
    let scene_path = dir.path().join("rosakis-shear-mini-eom.json");
    std::fs::write(&scene_path, eom.to_string()).expect("write the scene");
    let s = Server::start(dir.path(), &["--workers", "2", "--worker-threads", "1"]);
    let toughness = [25.0, 100.0, 250.0];
    let mut child = Command::new(fracture_bin())
        .args([
            "sweep",
            scene_path.to_str().expect("path"),
            "--param",
            "cracks.0.propagation.toughness=25,100,250",
            "--name",
            "rosakis-mini-toughness",
            "--server",
            &s.url,
            "--wait",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start fracture sweep");
    let deadline = Instant::now() + Duration::from_secs(180);
    let code = loop {
        if let Ok(Some(st)) = child.try_wait() {
            break st.code();
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("fracture sweep --wait did not finish in 180 s");
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    let out = child.wait_with_output().expect("sweep output");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(code, Some(0), "fracture sweep --wait:\n{stdout}\n{stderr}");
    // stdout: the sweep id, then `job-id label` per job, a blank line, the result table
    // (header and one row per combination).
    let mut lines = stdout.lines();
    let sweep_id = lines.next().expect("sweep id").trim().to_string();
    let listed: Vec<&str> = lines.by_ref().take_while(|l| !l.is_empty()).collect();
    assert_eq!(listed.len(), 3, "{stdout}");
    let table: Vec<&str> = lines.collect();
    assert!(
        table
            .first()
            .is_some_and(|h| h.starts_with("cracks.0.propagation.toughness")),
        "{stdout}"
    );

    let sw = s.get_json(&format!("/api/v1/sweeps/{sweep_id}"));
    assert_eq!(sw["status"], "completed", "{sw}");
    assert_eq!(sw["name"], "rosakis-mini-toughness");
    assert_eq!(sw["counts"]["completed"], 3);
    assert_eq!(f(&sw["progress"]), 1.0);
    let jobs = sw["jobs"].as_array().expect("jobs");
    assert_eq!(jobs.len(), 3);
    let mut results = Vec::new();
    for (j, &g) in jobs.iter().zip(&toughness) {
        assert_eq!(j["label"], format!("toughness={}", g as i64));
        assert_eq!(f(&j["values"]["cracks.0.propagation.toughness"]), g, "{j}");
        let id = j["id"].as_str().expect("job id");
        assert!(listed.iter().any(|l| l.starts_with(id)), "{stdout}");
        let row = table
            .iter()
            .find(|l| l.contains(id))
            .unwrap_or_else(|| panic!("no table row for {id}: {stdout}"));
        let cells: Vec<&str> = row.split_whitespace().collect();
        assert_eq!(
            cells.first().copied(),
            Some(format!("{g}").as_str()),
            "{row}"
        );
        assert!(cells.contains(&"completed"), "{row}");
        let job = s.job(id);
        assert_eq!(job["sweep_id"], sweep_id.as_str());
        assert_eq!(f(&job["scene"]["cracks"][0]["propagation"]["toughness"]), g);
        let rows = s.get_json(&format!("/api/v1/jobs/{id}/crack-tips"));
        results.push(growth(g, rows.as_array().expect("rows")));
    }

    eprintln!(
        "c_L = {cl:.0} m/s; J_Ic, initiation, extension at 30 µs, mean speed, max speed, max |y − bond|:"
    );
    for r in &results {
        eprintln!(
            "  {:>5} J/m²  {:5.2} µs  {:5.1} mm  {:5.0} m/s  {:5.0} m/s  {:.3} mm",
            r.toughness,
            r.initiation * 1e6,
            r.extension * 1e3,
            r.mean_speed,
            r.max_speed,
            r.max_dy * 1e3
        );
    }
    for r in &results {
        // It grows, along the bond, never faster than c_L.
        assert!(
            r.initiation.is_finite() && r.extension > 10.0 * H,
            "J_Ic = {}: the crack did not grow: {r:?}",
            r.toughness
        );
        assert!(
            r.max_dy <= 0.5 * H,
            "J_Ic = {}: the tip left the bond line by {} m (tolerance h/2)",
            r.toughness,
            r.max_dy
        );
    }
    for w in results.windows(2) {
        assert!(
            w[1].initiation > w[0].initiation + STEP,
            "a tougher bond must start later by more than a step as J_Ic rises {} → {}: {:.2} → {:.2} µs",
            w[0].toughness,
            w[1].toughness,
            w[0].initiation * 1e6,
            w[1].initiation * 1e6
        );
        assert!(
            w[1].extension < w[0].extension,
            "extension must fall as J_Ic rises {} → {}: {:.2} mm → {:.2} mm",
            w[0].toughness,
            w[1].toughness,
            w[0].extension * 1e3,
            w[1].extension * 1e3
        );
    }
    eprintln!("sweep test took {:.1} s", t0.elapsed().as_secs_f64());
}

/// The sweep command refuses a bad value with exit 2 naming the parameter, the value and
/// the field path, and stores nothing; cancelling a sweep cancels its unfinished jobs
/// (the third job is still queued behind the two workers when the cancel arrives).
#[test]
fn sweep_command_errors_and_sweep_cancel_through_the_service() {
    let scene_path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/rosakis-shear-mini.json");
    let dir = tempfile::tempdir().expect("tmp");
    let s = Server::start(dir.path(), &["--workers", "2", "--worker-threads", "1"]);
    let refused = |param: &str| {
        let out = Command::new(fracture_bin())
            .args([
                "sweep",
                scene_path.to_str().expect("path"),
                "--param",
                param,
                "--server",
                &s.url,
            ])
            .output()
            .expect("run fracture sweep");
        assert_eq!(out.status.code(), Some(2), "{out:?}");
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let err = refused("cracks.0.propagation.toughness=25,-1");
    assert!(
        err.contains("invalid_sweep")
            && err.contains("parameter `cracks.0.propagation.toughness` = -1")
            && err.contains("\n  cracks.0.propagation.toughness: "),
        "{err}"
    );
    let err = refused("cracks.0.propagation.tougness=25");
    // The last segment may add a key (optional fields), so the validator catches the typo
    // and the error still names the parameter.
    assert!(
        err.contains("parameter `cracks.0.propagation.tougness` = 25")
            && err.contains("unknown field `tougness`"),
        "{err}"
    );
    assert_eq!(s.get_json("/api/v1/jobs"), serde_json::json!([]));

    // Cancel a fresh three-job sweep at once.
    let scene: Value = serde_json::from_str(
        &std::fs::read_to_string(&scene_path).expect("read rosakis-shear-mini.json"),
    )
    .expect("scene JSON");
    let (code, sw) = s.post_json(
        "/api/v1/sweeps",
        &serde_json::json!({"scene": scene,
            "parameters": {"cracks.0.propagation.toughness": [25, 100, 250]}}),
    );
    assert_eq!(code, 201, "{sw}");
    let id = sw["id"].as_str().expect("sweep id").to_string();
    let (code, after) = s.post_json(
        &format!("/api/v1/sweeps/{id}/cancel"),
        &serde_json::json!({}),
    );
    assert_eq!(code, 200, "{after}");
    let t0 = Instant::now();
    let done = loop {
        let v = s.get_json(&format!("/api/v1/sweeps/{id}"));
        if v["counts"]["queued"] == 0 && v["counts"]["running"] == 0 {
            break v;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "sweep did not end: {v}"
        );
        std::thread::sleep(Duration::from_millis(100));
    };
    assert_eq!(done["status"], "cancelled", "{done}");
    assert_eq!(done["counts"]["failed"], 0, "{done}");
    assert!(done["counts"]["cancelled"].as_u64() >= Some(1), "{done}");
    assert_eq!(f(&done["progress"]), 1.0);
}
