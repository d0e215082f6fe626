//! The `fracture` binary and 3D scenes (docs/scenes-3d.md): `import-stl` on ASCII and binary
//! STL files written here, `validate` on a 3D scene built from its output, `schema --3d`.
#![allow(clippy::unwrap_used, missing_docs)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::{Value, json};

fn fracture(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_fracture"))
        .args(args)
        .output()
        .unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// The 12 facets of the cube [lo, hi]³ (mm), outward.
fn cube_facets(lo: f32, hi: f32) -> Vec<[[f32; 3]; 3]> {
    let v = |i: usize| [i & 1, (i >> 1) & 1, (i >> 2) & 1].map(|b| if b == 1 { hi } else { lo });
    [
        [0, 2, 1],
        [1, 2, 3],
        [4, 5, 6],
        [5, 7, 6],
        [0, 1, 4],
        [1, 5, 4],
        [2, 6, 3],
        [3, 6, 7],
        [0, 4, 2],
        [2, 4, 6],
        [1, 3, 5],
        [3, 7, 5],
    ]
    .iter()
    .map(|t| t.map(v))
    .collect()
}

fn ascii_stl(facets: &[[[f32; 3]; 3]]) -> String {
    let mut s = String::from("solid cube\n");
    for f in facets {
        s += "  facet normal 0 0 0\n    outer loop\n";
        for p in f {
            s += &format!("      vertex {} {} {}\n", p[0], p[1], p[2]);
        }
        s += "    endloop\n  endfacet\n";
    }
    s + "endsolid cube\n"
}

fn binary_stl(facets: &[[[f32; 3]; 3]]) -> Vec<u8> {
    let mut b = b"solid binary file whose header starts like ASCII".to_vec();
    b.resize(80, b' ');
    b.extend((facets.len() as u32).to_le_bytes());
    for f in facets {
        b.extend([0f32; 3].iter().flat_map(|c| c.to_le_bytes()));
        for p in f {
            b.extend(p.iter().flat_map(|c| c.to_le_bytes()));
        }
        b.extend([0u8; 2]);
    }
    b
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// A 3D scene whose single body is `region`, in a 200 mm grid of 10 mm cells.
fn scene_with(region: Value) -> Value {
    json!({
        "name": "stl-body",
        "analysis": "3d",
        "grid": {"cell_size": 0.01, "min": [0.0, 0.0, 0.0], "max": [0.2, 0.2, 0.2]},
        "materials": {"steel": {"model": "linear_elastic", "density": 7850.0,
                                 "youngs_modulus": 200e9, "poissons_ratio": 0.3}},
        "bodies": [{"material": "steel", "region": region}],
        "time": {"end": 1e-5}
    })
}

#[test]
fn import_stl_reads_ascii_and_binary_and_its_region_validates() {
    let dir = tempfile::tempdir().unwrap();
    // A 100 mm cube from 50 to 150 mm, in millimetres, scaled to metres.
    let facets = cube_facets(50.0, 150.0);
    let files = [
        write(dir.path(), "cube-ascii.stl", ascii_stl(&facets).as_bytes()),
        write(dir.path(), "cube-binary.stl", &binary_stl(&facets)),
    ];
    let mut regions = Vec::new();
    for f in &files {
        let o = fracture(&["import-stl", f.to_str().unwrap(), "--scale", "0.001"]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let region: Value = serde_json::from_str(&stdout(&o)).unwrap();
        let mesh = &region["mesh"];
        assert_eq!(mesh["vertices"].as_array().unwrap().len(), 8, "{region}");
        assert_eq!(mesh["triangles"].as_array().unwrap().len(), 12, "{region}");
        assert!(
            mesh["vertices"]
                .as_array()
                .unwrap()
                .contains(&json!([0.05, 0.05, 0.05]))
        );
        assert!(
            stderr(&o).contains("12 triangles, 8 vertices"),
            "{}",
            stderr(&o)
        );
        regions.push(region);
    }
    assert_eq!(regions[0], regions[1]);

    let scene = write(
        dir.path(),
        "scene.json",
        scene_with(regions[0].clone()).to_string().as_bytes(),
    );
    let o = fracture(&["validate", scene.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(out.starts_with("stl-body: valid (3D)\n"), "{out}");
    // 10 cells a side × 2 particles per cell direction; 21³ grid nodes.
    assert!(out.contains("particles: 8000\n"), "{out}");
    assert!(out.contains("grid nodes: 9261\n"), "{out}");
    assert!(out.contains("memory (estimate): "), "{out}");
}

#[test]
fn import_stl_refuses_missing_unreadable_and_open_files() {
    let dir = tempfile::tempdir().unwrap();
    let o = fracture(&["import-stl", "/nonexistent/part.stl"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("/nonexistent/part.stl"),
        "{}",
        stderr(&o)
    );

    let junk = write(dir.path(), "junk.stl", b"not an stl file");
    let o = fracture(&["import-stl", junk.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("not a readable STL file"),
        "{}",
        stderr(&o)
    );

    let mut facets = cube_facets(0.0, 1.0);
    facets.remove(3);
    let open = write(dir.path(), "open.stl", ascii_stl(&facets).as_bytes());
    let o = fracture(&["import-stl", open.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(e.contains("facet 2 (0-based, in file order)"), "{e}");
    assert!(e.contains("the surface is open"), "{e}");
    assert!(stdout(&o).is_empty());
}

#[test]
fn validate_names_3d_problems_and_schema_3d_prints_the_3d_schema() {
    let dir = tempfile::tempdir().unwrap();
    let mut v = scene_with(json!({"sphere": {"center": [0.1, 0.1, 0.1], "radius": 0.05}}));
    v["thickness"] = json!(0.01);
    let f = write(dir.path(), "thick.json", v.to_string().as_bytes());
    let o = fracture(&["validate", f.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("  thickness: 0.01 does not exist in 3D"),
        "{}",
        stderr(&o)
    );

    let o = fracture(&["schema", "--3d"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let schema: Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(schema, fracture_api::Scene3::json_schema());
    assert!(schema["properties"].get("thickness").is_none());
    let o = fracture(&["schema"]);
    let schema: Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(schema, fracture_api::Scene::json_schema());
}
