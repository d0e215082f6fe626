//! A 3D scene through the run loop into a run folder, as `fracture run --vtk` does: the
//! summary says `dimension` 3, energy rows are written, and the VTK volumes arrive through
//! the sink (also through the `&mut` forwarding impl the CLI's sink uses).

use fracture_api::{AnyScene, ValidScene3, parse_any_scene};
use fracture_worker::{LocalOutput, RunOptions, run_scene3};

#[test]
fn a_3d_run_writes_its_folder_and_volumes() {
    let path = format!("{}/../scenes/3d-impact.json", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(path).expect("scene");
    let AnyScene::Three(mut scene) = parse_any_scene(&text).expect("parses") else {
        panic!("not 3D");
    };
    scene.time.end = 2.0e-6;
    scene.output.snapshot_interval = 1.0e-6;
    let valid = ValidScene3::new(scene).expect("valid");
    let dir = std::env::temp_dir().join(format!("three-d-local-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let mut out = LocalOutput::create(&dir).expect("out");
    out.write_scene3(valid.scene()).expect("scene");
    out.write_volumes(dir.join("vtk")).expect("vtk");
    let opts = RunOptions {
        threads: fracture_solver::Parallelism::threads(2),
        ..RunOptions::default()
    };
    let mut sink = &mut out;
    let summary = run_scene3(&valid, &opts, &mut sink);
    assert_eq!(
        summary.status,
        fracture_api::results::RunStatus::Completed,
        "{summary:?}"
    );
    assert_eq!(summary.dimension, Some(3));
    let energy = std::fs::read_to_string(dir.join("energy.csv")).expect("energy");
    assert!(energy.lines().count() > 10);
    let pvd = std::fs::read_to_string(dir.join("vtk/volumes.pvd")).expect("volumes.pvd");
    assert_eq!(pvd.matches("<DataSet").count(), 3, "{pvd}");
    assert!(dir.join("vtk/volume_00002.vti").exists());
    let _ = std::fs::remove_dir_all(&dir);
}
