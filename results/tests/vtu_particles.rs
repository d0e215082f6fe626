//! The VTK export's particle files (`particles_NNNNN.vtu`, `particles.pvd`) read back by an
//! independent reader, meshio (Python; `vtu_readback.py`). Skipped with the reason printed
//! when meshio is missing, unless `FRACTURE_REQUIRE_MESHIO=1` (CI sets it after
//! `pip install meshio`), which makes a missing reader a failure.

use std::path::Path;
use std::process::Command;

use fracture_api::results::{FieldComponent, ParticleSnapshot, Snapshot};
use fracture_results::vtk;
use serde_json::Value;

/// Two snapshots of a 3 × 3 grid with 5 and 6 particles (positions and values known).
fn series() -> Vec<Snapshot> {
    (0..2u32)
        .map(|k| {
            let n = 5 + k as usize;
            let x: Vec<f32> = (0..n).map(|i| 0.001 * i as f32 + 1e-4 * k as f32).collect();
            let y: Vec<f32> = (0..n).map(|i| 0.002 - 0.0003 * i as f32).collect();
            let comp = |name: &str, c: f32| FieldComponent {
                name: name.into(),
                values: (0..n).map(|i| c * (1.0 + i as f32) + k as f32).collect(),
            };
            Snapshot {
                index: k,
                time: 2.5e-6 * k as f64,
                nx: 3,
                ny: 3,
                origin: [0.0, 0.0],
                cell_size: 1e-3,
                fields: vec!["stress".into(), "velocity".into()],
                components: vec![FieldComponent {
                    name: "sxx".into(),
                    values: vec![1.0; 9],
                }],
                cracks: vec![],
                particles: Some(ParticleSnapshot {
                    x,
                    y,
                    components: vec![comp("sxx", 1.0e6), comp("vx", 1.5), comp("vy", -0.5)],
                }),
                slice: None,
            }
        })
        .collect()
}

#[test]
fn particle_files_are_listed_and_sized() {
    let snaps = series();
    let tmp = tempfile::tempdir().expect("tempdir");
    let s = vtk::write_series(tmp.path(), &snaps).expect("exports");
    assert_eq!(s.particles_pvd, Some(tmp.path().join("particles.pvd")));
    // fields.pvd, cracks.pvd, particles.pvd, and three files per snapshot.
    assert_eq!(s.files.len(), 3 + 3 * snaps.len());
    // Without particles there is no particle series.
    let mut bare = series();
    bare.iter_mut().for_each(|s| s.particles = None);
    let files = vtk::series_files(&bare).expect("in memory");
    assert!(files.iter().all(|(n, _)| !n.starts_with("particles")));
    // A particle array of the wrong length is refused, naming it.
    let mut bad = series();
    if let Some(p) = bad[1].particles.as_mut() {
        p.components[1].values.pop();
    }
    let e = vtk::series_files(&bad).expect_err("refused");
    assert!(e.to_string().contains("particles.vx"), "{e}");
}

#[test]
fn particle_files_read_back_with_meshio() {
    let snaps = series();
    let tmp = tempfile::tempdir().expect("tempdir");
    vtk::write_series(tmp.path(), &snaps).expect("exports");
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/vtu_readback.py");
    let require = std::env::var("FRACTURE_REQUIRE_MESHIO").is_ok_and(|v| v == "1");
    let out = match Command::new("python3")
        .arg(&script)
        .arg(tmp.path())
        .output()
    {
        Ok(o) => o,
        Err(e) => {
            assert!(!require, "python3 cannot be started: {e}");
            eprintln!("SKIP meshio read-back: python3 cannot be started ({e})");
            return;
        }
    };
    let stdout = String::from_utf8_lossy(&out.stdout);
    if out.status.code() == Some(77) {
        assert!(!require, "{stdout}");
        eprintln!("SKIP meshio read-back: {}", stdout.trim());
        return;
    }
    assert!(
        out.status.success(),
        "vtu_readback.py failed: {}\n{stdout}",
        String::from_utf8_lossy(&out.stderr)
    );
    let got: Value = serde_json::from_str(&stdout).expect("json from vtu_readback.py");
    eprintln!("meshio {} read the particle files", got["meshio_version"]);
    let pvd = got["pvd"].as_array().expect("pvd");
    assert_eq!(pvd.len(), snaps.len());
    for (k, s) in snaps.iter().enumerate() {
        assert_eq!(pvd[k]["time"].as_f64(), Some(s.time));
        let name = vtk::particle_file_name(k);
        assert_eq!(pvd[k]["file"].as_str(), Some(name.as_str()));
        let f = &got["files"][&name];
        let p = s.particles.as_ref().expect("particles");
        let n = p.x.len();
        assert_eq!(f["cells"]["vertex"].as_u64(), Some(n as u64), "{f}");
        let pts = f["points"].as_array().expect("points");
        assert_eq!(pts.len(), n);
        for (i, q) in pts.iter().enumerate() {
            assert_eq!(q[0].as_f64(), Some(f64::from(p.x[i])));
            assert_eq!(q[1].as_f64(), Some(f64::from(p.y[i])));
            assert_eq!(q[2].as_f64(), Some(0.0));
        }
        for c in &p.components {
            let vals = f["point_data"][&c.name].as_array().expect("array");
            let vals: Vec<f64> = vals.iter().filter_map(Value::as_f64).collect();
            let want: Vec<f64> = c.values.iter().map(|&v| f64::from(v)).collect();
            assert_eq!(vals, want, "{}", c.name);
        }
        // velocity = (vx, vy, 0) per particle.
        let v = f["point_data"]["velocity"].as_array().expect("velocity");
        assert_eq!(v.len(), n);
        assert_eq!(v[2][0].as_f64(), Some(f64::from(p.components[1].values[2])));
        assert_eq!(v[2][1].as_f64(), Some(f64::from(p.components[2].values[2])));
    }
}
