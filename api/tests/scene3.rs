//! The 3D scene (`"analysis": "3d"`, docs/scenes-3d.md): parsing of every region and crack
//! surface, containment of every region kind, the mesh checks (each defect named by its
//! triangle), the 3D-only refusals (thickness, cracks, fringes), and 2D documents read
//! through `parse_any_scene` exactly as before.
#![allow(clippy::unwrap_used, missing_docs)]

use std::collections::BTreeSet;
use std::path::Path;

use fracture_api::lattice3::{count_per_body3, for_each_seed3};
use fracture_api::scene3::{Axis, Region3, Scene3, Slice, TriMesh, Vec3};
use fracture_api::validate::parse_scene;
use fracture_api::{AnyScene, parse_any_scene, validate_any, validate3};
use serde_json::{Value, json};

/// A 10 cm steel cube in a 20 cm grid of 1 cm cells.
fn steel_box() -> Value {
    json!({
        "name": "steel-box",
        "analysis": "3d",
        "grid": {"cell_size": 0.01, "min": [0.0, 0.0, 0.0], "max": [0.2, 0.2, 0.2]},
        "materials": {"steel": {"model": "linear_elastic", "density": 7850.0,
                                 "youngs_modulus": 200e9, "poissons_ratio": 0.3}},
        "bodies": [{"material": "steel",
                    "region": {"box": {"min": [0.05, 0.05, 0.05], "max": [0.15, 0.15, 0.15]}}}],
        "time": {"end": 1e-5}
    })
}

fn parse3(v: &Value) -> Scene3 {
    match parse_any_scene(&v.to_string()).unwrap() {
        AnyScene::Three(s) => s,
        AnyScene::Two(_) => panic!("read as 2D: {v}"),
    }
}

/// The problems of `v` as "path: message" lines (empty when it validates).
fn problems(v: &Value) -> Vec<String> {
    let scene = match parse_any_scene(&v.to_string()) {
        Ok(s) => s,
        Err(e) => return e.0.iter().map(|e| e.to_string()).collect(),
    };
    match validate_any(&scene) {
        Ok(_) => Vec::new(),
        Err(e) => e.0.iter().map(|e| e.to_string()).collect(),
    }
}

/// The unit cube scaled to [lo, hi]³ as 12 outward triangles.
fn cube_mesh(lo: f64, hi: f64) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let v: Vec<Vec3> = (0..8u32)
        .map(|i| [i & 1, (i >> 1) & 1, (i >> 2) & 1].map(|b| if b == 1 { hi } else { lo }))
        .collect();
    let t = vec![
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
    ];
    (v, t)
}

/// An icosphere: the icosahedron subdivided `levels` times, outward triangles.
fn icosphere(center: Vec3, radius: f64, levels: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let p = (1.0 + 5f64.sqrt()) / 2.0;
    let mut v: Vec<Vec3> = vec![
        [-1.0, p, 0.0],
        [1.0, p, 0.0],
        [-1.0, -p, 0.0],
        [1.0, -p, 0.0],
        [0.0, -1.0, p],
        [0.0, 1.0, p],
        [0.0, -1.0, -p],
        [0.0, 1.0, -p],
        [p, 0.0, -1.0],
        [p, 0.0, 1.0],
        [-p, 0.0, -1.0],
        [-p, 0.0, 1.0],
    ];
    let mut t: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    let unit = |a: Vec3| {
        let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        a.map(|c| c / n)
    };
    v = v.into_iter().map(unit).collect();
    for _ in 0..levels {
        let mut mid = std::collections::HashMap::new();
        let mut next = Vec::new();
        for tri in &t {
            let mut m = [0u32; 3];
            for e in 0..3 {
                let (a, b) = (tri[e], tri[(e + 1) % 3]);
                let key = (a.min(b), a.max(b));
                m[e] = *mid.entry(key).or_insert_with(|| {
                    let (pa, pb) = (v[a as usize], v[b as usize]);
                    v.push(unit([pa[0] + pb[0], pa[1] + pb[1], pa[2] + pb[2]]));
                    (v.len() - 1) as u32
                });
            }
            next.push([tri[0], m[0], m[2]]);
            next.push([tri[1], m[1], m[0]]);
            next.push([tri[2], m[2], m[1]]);
            next.push(m);
        }
        t = next;
    }
    let v = v
        .into_iter()
        .map(|a| [0, 1, 2].map(|k| center[k] + radius * a[k]))
        .collect();
    (v, t)
}

fn mesh_json(v: &[Vec3], t: &[[u32; 3]]) -> Value {
    json!({"mesh": {"vertices": v, "triangles": t}})
}

/// Every sub-cell centre of the grid box, filtered by `Region3::contains` and the earlier
/// bodies: the lattice rule by brute force.
fn brute_force(scene: &Scene3) -> Vec<(u32, Vec3)> {
    let g = &scene.grid;
    let mut out = Vec::new();
    for (bi, b) in scene.bodies.iter().enumerate() {
        let sub = g.cell_size / f64::from(b.particles_per_cell);
        let n = |k: usize| ((g.max[k] - g.min[k]) / sub).round() as i64;
        for i in 0..n(0) {
            for j in 0..n(1) {
                for k in 0..n(2) {
                    let p = [i, j, k].map(|c| c as f64 + 0.5);
                    let x = [0, 1, 2].map(|d| g.min[d] + p[d] * sub);
                    if b.region.contains(x)
                        && !scene.bodies[..bi].iter().any(|e| e.region.contains(x))
                    {
                        out.push((bi as u32, x));
                    }
                }
            }
        }
    }
    out
}

fn seeds(scene: &Scene3) -> Vec<(u32, Vec3)> {
    let mut out = Vec::new();
    for_each_seed3(scene, |s| out.push((s.body, s.x)));
    out
}

#[test]
fn every_region_kind_parses_and_fills() {
    let (cv, ct) = cube_mesh(0.06, 0.14);
    let regions = [
        json!({"box": {"min": [0.05, 0.05, 0.05], "max": [0.15, 0.15, 0.15]}}),
        json!({"sphere": {"center": [0.1, 0.1, 0.1], "radius": 0.05}}),
        json!({"cylinder": {"base": [0.1, 0.1, 0.03], "axis": [0.0, 0.0, 0.12], "radius": 0.04}}),
        json!({"cylinder": {"base": [0.05, 0.05, 0.05], "axis": [0.1, 0.1, 0.1], "radius": 0.02}}),
        json!({"prism": {"polygon": [[0.05, 0.05], [0.15, 0.05], [0.1, 0.15]], "z": [0.05, 0.12]}}),
        mesh_json(&cv, &ct),
    ];
    for r in regions {
        let mut v = steel_box();
        v["bodies"][0]["region"] = r.clone();
        let scene = parse3(&v);
        let size = validate3(&scene).unwrap_or_else(|e| panic!("{r}: {e}"));
        assert!(size.particles > 100, "{r}: {size:?}");
        assert_eq!(size.grid_nodes, 21 * 21 * 21);
        // The column walk places exactly the sub-cell centres `contains` accepts.
        assert_eq!(seeds(&scene), brute_force(&scene), "{r}");
    }
}

#[test]
fn overlapping_bodies_give_the_first_one_the_overlap() {
    let (sv, st) = icosphere([0.12, 0.1, 0.1], 0.04, 2);
    let mut v = steel_box();
    v["bodies"] = json!([
        {"material": "steel", "region": {"box": {"min": [0.05, 0.05, 0.05], "max": [0.12, 0.15, 0.15]}}},
        {"material": "steel", "particles_per_cell": 3, "region": mesh_json(&sv, &st)},
        {"material": "steel", "particles_per_cell": 1,
         "region": {"prism": {"polygon": [[0.05, 0.05], [0.18, 0.05], [0.18, 0.09]], "z": [0.02, 0.18]}}}
    ]);
    let scene = parse3(&v);
    validate3(&scene).unwrap();
    let s = seeds(&scene);
    assert_eq!(s, brute_force(&scene));
    let counts = count_per_body3(&scene);
    assert!(counts.iter().all(|&n| n > 0), "{counts:?}");
    // Visiting order: body, then x, y, z with z fastest.
    let order = |a: &(u32, Vec3)| (a.0, a.1.map(|c| (c * 1e9).round() as i64));
    assert!(s.windows(2).all(|w| order(&w[0]) < order(&w[1])));
}

#[test]
fn every_crack_surface_parses_but_cracks_are_refused() {
    let surfaces = [
        json!({"rectangle": {"corner": [0.08, 0.05, 0.1], "edges": [[0.04, 0.0, 0.0], [0.0, 0.1, 0.0]]}}),
        json!({"ellipse": {"center": [0.1, 0.1, 0.1], "axes": [[0.02, 0.0, 0.0], [0.0, 0.01, 0.0]]}}),
        json!({"extruded": {"points": [[0.05, 0.1], [0.08, 0.1]], "z": [0.05, 0.15]}}),
        json!({"triangles": {"vertices": [[0.08, 0.08, 0.1], [0.12, 0.08, 0.1], [0.1, 0.12, 0.1]],
                             "triangles": [[0, 1, 2]]}}),
    ];
    for s in surfaces {
        let mut v = steel_box();
        v["cracks"] = json!([{"surface": s, "contact": {"law": "coulomb", "friction": 0.2},
                              "j_integral": {"method": "domain", "radius": 0.03},
                              "propagation": {"criterion": "none"}}]);
        let scene = parse3(&v);
        assert_eq!(scene.cracks.len(), 1);
        let p = problems(&v);
        assert_eq!(p.len(), 1, "{p:?}");
        assert!(
            p[0].starts_with("cracks: 1 3D crack surfaces are not supported yet"),
            "{p:?}"
        );
    }
    // Growth laws other than "none" do not exist in 3D yet.
    let mut v = steel_box();
    v["cracks"] = json!([{"surface": {"extruded": {"points": [[0.05, 0.1], [0.08, 0.1]], "z": [0.0, 0.1]}},
                          "propagation": {"criterion": "energy_release", "toughness": 10.0}}]);
    let p = problems(&v);
    assert!(
        p[0].starts_with("cracks[0].propagation.criterion: unknown variant `energy_release`"),
        "{p:?}"
    );
    let mut v = steel_box();
    v["interfaces"] = json!([{"points": [[0.0, 0.1], [0.2, 0.1]]}]);
    let p = problems(&v);
    assert!(p[0].starts_with("interfaces: 1 cohesive interfaces are not supported in 3D"));
}

#[test]
fn a_sphere_cylinder_and_prism_hold_their_volume() {
    // 20 cells per radius, one particle per cell: within 2 % of the exact volume.
    let r: f64 = 0.1;
    let h = r / 20.0;
    let cases = [
        (
            json!({"sphere": {"center": [0.15, 0.15, 0.15], "radius": r}}),
            4.0 / 3.0 * std::f64::consts::PI * r.powi(3),
        ),
        (
            json!({"cylinder": {"base": [0.06, 0.07, 0.08], "axis": [0.12, 0.1, 0.14], "radius": r / 2.0}}),
            std::f64::consts::PI
                * (r / 2.0).powi(2)
                * (0.12f64.powi(2) + 0.01 + 0.14f64.powi(2)).sqrt(),
        ),
        (
            json!({"prism": {"polygon": [[0.05, 0.05], [0.25, 0.05], [0.05, 0.25]], "z": [0.1, 0.2]}}),
            0.5 * 0.2 * 0.2 * 0.1,
        ),
    ];
    for (region, exact) in cases {
        let mut v = steel_box();
        v["grid"] = json!({"cell_size": h, "min": [0.0, 0.0, 0.0], "max": [0.3, 0.3, 0.3]});
        v["bodies"] = json!([{"material": "steel", "particles_per_cell": 1, "region": region}]);
        let scene = parse3(&v);
        let n = validate3(&scene).unwrap().particles as f64;
        let err = n * h.powi(3) / exact - 1.0;
        assert!(err.abs() < 0.02, "{region}: {:.2} %", 100.0 * err);
    }
}

#[test]
fn a_cube_mesh_contains_exactly_the_box_lattice_points() {
    // Lattice centres at 2.5 mm + k·5 mm: lines with x = y run through the faces' diagonals
    // and lines through the cube's edges and corners are counted once.
    let (v, t) = cube_mesh(0.05, 0.15);
    let mesh = Region3::Mesh(TriMesh::new(v.clone(), t.clone()));
    let boxed = Region3::Box {
        min: [0.05; 3],
        max: [0.15; 3],
    };
    let mut a = steel_box();
    a["bodies"][0]["region"] = mesh_json(&v, &t);
    let (sa, sb) = (parse3(&a), parse3(&steel_box()));
    assert_eq!(seeds(&sa), seeds(&sb));
    assert_eq!(seeds(&sa).len(), 20 * 20 * 20);
    // Point queries off the lattice too, including the faces' diagonal planes.
    let mut x = 12345u64;
    let mut next = || {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (x >> 11) as f64 / (1u64 << 53) as f64 * 0.2
    };
    for _ in 0..20_000 {
        let p = [next(), next(), next()];
        assert_eq!(mesh.contains(p), boxed.contains(p), "{p:?}");
        let d = next();
        let q = [d, d, next()];
        assert_eq!(mesh.contains(q), boxed.contains(q), "{q:?}");
    }
}

#[test]
fn a_mesh_sphere_holds_its_volume() {
    let (v, t) = icosphere([0.1, 0.1, 0.1], 0.05, 3);
    let m = TriMesh::new(v.clone(), t.clone());
    let volume = m.signed_volume();
    assert!(volume > 0.0, "the icosphere faces outward");
    let mut s = steel_box();
    s["grid"]["cell_size"] = json!(0.0025); // 20 cells per radius
    s["bodies"][0]["particles_per_cell"] = json!(1);
    s["bodies"][0]["region"] = mesh_json(&v, &t);
    let scene = parse3(&s);
    let n = validate3(&scene).unwrap().particles as f64;
    let err = n * 0.0025f64.powi(3) / volume - 1.0;
    assert!(err.abs() < 0.02, "{:.2} %", 100.0 * err);
    let region = Region3::Mesh(m);
    assert!(region.contains([0.1, 0.1, 0.1]));
    assert!(region.contains([0.1, 0.1, 0.1495]));
    assert!(!region.contains([0.1, 0.1, 0.1505]));
    assert!(!region.contains([0.14, 0.14, 0.1]));
    // Reversed triangles (inward) bound the same solid.
    let inward: Vec<[u32; 3]> = t.iter().map(|&[a, b, c]| [a, c, b]).collect();
    s["bodies"][0]["region"] = mesh_json(&v, &inward);
    assert_eq!(validate3(&parse3(&s)).unwrap().particles as f64, n);
}

#[test]
fn the_fill_is_fast() {
    // A million-particle box, and a 20 480-triangle sphere mesh with a million candidate
    // sites: measured at about 5 and 15 ms (test profile); the bounds leave room for slow
    // machines and still catch a fill that asks the mesh once per particle.
    let mut v = steel_box();
    v["grid"] = json!({"cell_size": 0.01, "min": [0.0, 0.0, 0.0], "max": [0.52, 0.52, 0.52]});
    v["bodies"][0]["region"] =
        json!({"box": {"min": [0.01, 0.01, 0.01], "max": [0.51, 0.51, 0.51]}});
    let scene = parse3(&v);
    let t = std::time::Instant::now();
    assert_eq!(count_per_body3(&scene), vec![1_000_000]);
    let box_s = t.elapsed().as_secs_f64();
    assert!(box_s < 1.0, "{box_s} s");

    let (mv, mt) = icosphere([0.1, 0.1, 0.1], 0.08, 5);
    assert_eq!(mt.len(), 20_480);
    let mut v = steel_box();
    v["grid"] = json!({"cell_size": 0.0016, "min": [0.0, 0.0, 0.0], "max": [0.2, 0.2, 0.2]});
    v["bodies"][0]["particles_per_cell"] = json!(1);
    v["bodies"][0]["region"] = mesh_json(&mv, &mt);
    let scene = parse3(&v);
    assert!(fracture_api::lattice3::candidate_sites3(&scene) > 1_000_000);
    let t = std::time::Instant::now();
    let size = validate3(&scene).unwrap(); // the mesh checks and the fill
    let mesh_s = t.elapsed().as_secs_f64();
    assert!(mesh_s < 3.0, "{mesh_s} s");
    let exact = 4.0 / 3.0 * std::f64::consts::PI * 0.08f64.powi(3);
    assert!((size.particles as f64 * 0.0016f64.powi(3) / exact - 1.0).abs() < 0.02);
}

/// The single problem of a scene whose body is the given mesh.
fn mesh_problem(v: &[Vec3], t: &[[u32; 3]]) -> String {
    let mut s = steel_box();
    s["bodies"][0]["region"] = mesh_json(v, t);
    let p = problems(&s);
    assert_eq!(p.len(), 1, "{p:?}");
    p[0].clone()
}

#[test]
fn an_open_mesh_is_refused_naming_the_triangle() {
    let (v, mut t) = cube_mesh(0.05, 0.15);
    t.remove(3); // [5, 7, 6]: triangle 2 ([4, 5, 6]) loses its neighbour across 5–6
    let p = mesh_problem(&v, &t);
    assert!(
        p.starts_with("bodies.0.region.mesh.triangles.2: [4,5,6] has the edge 5–6"),
        "{p}"
    );
    assert!(p.contains("the surface is open"), "{p}");
}

#[test]
fn a_flipped_triangle_is_refused_naming_it() {
    let (v, mut t) = icosphere([0.1, 0.1, 0.1], 0.04, 2);
    t[37].swap(0, 1);
    let p = mesh_problem(&v, &t);
    assert!(p.starts_with("bodies.0.region.mesh.triangles.37: "), "{p}");
    assert!(p.contains("oriented against its neighbours"), "{p}");
}

#[test]
fn a_self_intersecting_mesh_is_refused_naming_the_triangle() {
    // Two closed cubes that overlap: no open edge, consistently oriented, but crossing. The
    // first cube's bottom (triangles 0 and 1) lies below the second; its top crosses it.
    let (mut v, mut t) = cube_mesh(0.05, 0.11);
    let (v2, t2) = cube_mesh(0.08, 0.14);
    t.extend(t2.iter().map(|tri| tri.map(|i| i + 8)));
    v.extend(v2);
    let p = mesh_problem(&v, &t);
    assert!(p.starts_with("bodies.0.region.mesh.triangles.2: "), "{p}");
    assert!(p.contains("intersects triangle 1"), "{p}");
}

#[test]
fn a_folded_or_degenerate_mesh_is_refused() {
    let (v, t) = cube_mesh(0.05, 0.15);
    // An index past the last vertex.
    let mut bad = t.clone();
    bad[5] = [1, 5, 8];
    let p = mesh_problem(&v, &bad);
    assert!(
        p.starts_with("bodies.0.region.mesh.triangles.5: [1,5,8] names vertex 8"),
        "{p}"
    );
    // A repeated vertex.
    let mut bad = t.clone();
    bad[4] = [0, 0, 4];
    assert!(mesh_problem(&v, &bad).starts_with("bodies.0.region.mesh.triangles.4: "));
    // Too few triangles.
    let p = mesh_problem(&v, &t[..3]);
    assert!(
        p.starts_with("bodies.0.region.mesh.triangles: 3 has 3 triangles"),
        "{p}"
    );
}

#[test]
fn thickness_in_3d_is_refused_naming_it() {
    let mut v = steel_box();
    v["thickness"] = json!(0.01);
    let p = problems(&v);
    assert_eq!(p.len(), 1, "{p:?}");
    assert!(
        p[0].starts_with("thickness: 0.01 does not exist in 3D"),
        "{p:?}"
    );
    assert!(p[0].contains("per the bodies' volume"), "{p:?}");
    // Any other unknown field gets serde's message with its path.
    let mut v = steel_box();
    v["bodies"][0]["contact"] = json!({"law": "stick"});
    let p = problems(&v);
    assert!(
        p[0].starts_with("bodies[0].contact: unknown field `contact`"),
        "{p:?}"
    );
}

#[test]
fn a_body_outside_the_grid_is_refused_naming_it() {
    let mut v = steel_box();
    v["bodies"] = json!([
        {"material": "steel", "region": {"box": {"min": [0.05, 0.05, 0.05], "max": [0.1, 0.1, 0.1]}}},
        {"material": "steel", "region": {"sphere": {"center": [0.15, 0.15, 0.18], "radius": 0.03}}}
    ]);
    let p = problems(&v);
    assert_eq!(p.len(), 1, "{p:?}");
    assert!(p[0].starts_with("bodies.1.region: "), "{p:?}");
    assert!(
        p[0].contains("body 1's bounding box) reaches outside the grid box"),
        "{p:?}"
    );
    // Inside the box, but in the empty cell layer GIMP needs.
    v["bodies"][1]["region"]["sphere"]["center"] = json!([0.15, 0.15, 0.165]);
    let p = problems(&v);
    assert!(p[0].starts_with("bodies.1.region: ") && p[0].contains("closer than one cell"));
    // A body with no particles (covered by the first).
    v["bodies"][1]["region"] =
        json!({"box": {"min": [0.06, 0.06, 0.06], "max": [0.09, 0.09, 0.09]}});
    let p = problems(&v);
    assert!(
        p[0].starts_with("bodies.1.region: ") && p[0].contains("no particle"),
        "{p:?}"
    );
}

#[test]
fn malformed_regions_name_their_field() {
    let cases = [
        (
            json!({"box": {"min": [0.1, 0.05, 0.05], "max": [0.15, 0.15, 0.05]}}),
            "bodies.0.region.box.max",
        ),
        (
            json!({"sphere": {"center": [0.1, 0.1, 0.1], "radius": 0.0}}),
            "bodies.0.region.sphere.radius",
        ),
        (
            json!({"cylinder": {"base": [0.1, 0.1, 0.1], "axis": [0.0, 0.0, 0.0], "radius": 0.01}}),
            "bodies.0.region.cylinder.axis",
        ),
        (
            json!({"prism": {"polygon": [[0.05, 0.05], [0.1, 0.1]], "z": [0.05, 0.1]}}),
            "bodies.0.region.prism.polygon",
        ),
        (
            json!({"prism": {"polygon": [[0.05, 0.05], [0.1, 0.1], [0.05, 0.1]], "z": [0.1, 0.05]}}),
            "bodies.0.region.prism.z",
        ),
    ];
    for (r, path) in cases {
        let mut v = steel_box();
        v["bodies"][0]["region"] = r;
        let p = problems(&v);
        assert!(
            p.iter().any(|e| e.starts_with(&format!("{path}: "))),
            "{path}: {p:?}"
        );
    }
}

#[test]
fn boundary_conditions_and_loads_are_checked() {
    let (cv, ct) = cube_mesh(0.04, 0.16);
    let mut v = steel_box();
    v["boundary_conditions"] = json!([
        {"region": {"box": {"min": [0.0, 0.0, 0.0], "max": [0.2, 0.2, 0.06]}}, "velocity": {"z": 0.0}},
        {"region": mesh_json(&cv, &ct), "velocity": {"x": 1.0, "y": 0.0, "z": -1.0},
         "ramp_time": 1e-6, "start": 0.0, "end": 5e-6, "moving": true}
    ]);
    v["loads"] = json!([{"region": {"box": {"min": [0.0, 0.0, 0.14], "max": [0.2, 0.2, 0.2]}},
                         "traction": [0.0, 0.0, 1e6], "ramp_time": 1e-6}]);
    assert_eq!(problems(&v), Vec::<String>::new());
    let scene = parse3(&v);
    assert_eq!(
        scene.boundary_conditions[1].velocity.components(),
        [Some(1.0), Some(0.0), Some(-1.0)]
    );

    v["boundary_conditions"][0]["velocity"] = json!({});
    v["boundary_conditions"][1]["end"] = json!(0.0);
    let p = problems(&v);
    assert!(
        p.iter()
            .any(|e| e.starts_with("boundary_conditions.0.velocity: {} prescribes no component")),
        "{p:?}"
    );
    assert!(
        p.iter()
            .any(|e| e.starts_with("boundary_conditions.1.end: 0.0 must be after start")),
        "{p:?}"
    );

    let mut scene = parse3(&steel_box());
    scene.loads.push(fracture_api::scene3::Load3 {
        region: Region3::Sphere {
            center: [0.1; 3],
            radius: 0.01,
        },
        traction: [0.0, 0.0, f64::NAN],
        ramp_time: None,
    });
    let e = validate3(&scene).unwrap_err();
    assert_eq!(e.0[0].path, "loads.0.traction.2");
}

#[test]
fn output_rules_of_3d() {
    let mut v = steel_box();
    v["output"] = json!({"fields": ["stress", "fringe"], "fringe_constant": 1e4,
                         "slices": [{"normal": "x", "at": 0.1}, {"normal": "z", "at": 0.25}]});
    let p = problems(&v);
    assert!(
        p.iter()
            .any(|e| e.starts_with("output.fields.1: \"fringe\" is not available in 3D")),
        "{p:?}"
    );
    assert!(
        p.iter().any(|e| e.starts_with("output.fringe_constant: ")),
        "{p:?}"
    );
    assert!(
        p.iter()
            .any(|e| e.starts_with("output.slices.1.at: 0.25 lies outside the grid box along z")),
        "{p:?}"
    );
    assert_eq!(p.len(), 3, "{p:?}");

    v["output"] = json!({"fields": ["stress", "strain", "velocity", "displacement", "material"],
                         "snapshot_interval": 1e-6, "particles": true,
                         "slices": [{"normal": "y", "at": 0.1}]});
    let scene = parse3(&v);
    assert_eq!(problems(&v), Vec::<String>::new());
    assert_eq!(
        scene.output.slices_or_default(&scene.grid),
        vec![Slice {
            normal: Axis::Y,
            at: 0.1
        }]
    );
    let plain = parse3(&steel_box());
    assert_eq!(
        plain.output.slices_or_default(&plain.grid),
        vec![Slice {
            normal: Axis::Z,
            at: 0.1
        }]
    );
    // No slices: none in the canonical JSON either.
    assert!(!plain.canonical_json().contains("slices"));
}

#[test]
fn the_time_step_uses_the_bulk_wave_speed() {
    let scene = parse3(&steel_box());
    let (e, nu, rho): (f64, f64, f64) = (200e9, 0.3, 7850.0);
    let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let mu = e / (2.0 * (1.0 + nu));
    let c_l = ((lambda + 2.0 * mu) / rho).sqrt();
    let dt = scene.time_step().unwrap();
    assert!((dt / (0.5 * 0.01 / c_l) - 1.0).abs() < 1e-12, "{dt}");
    let size = validate3(&scene).unwrap();
    assert_eq!(size.particles, 20 * 20 * 20);
    assert_eq!(size.steps, (1e-5 / dt * (1.0 - 1e-12)).ceil() as u64);
    assert!((scene.length_scale() - 0.1).abs() < 1e-15);
}

#[test]
fn canonical_json_round_trips_and_the_hash_is_stable() {
    let (v, t) = icosphere([0.1, 0.1, 0.1], 0.04, 1);
    let mut doc = steel_box();
    doc["bodies"][0]["region"] = mesh_json(&v, &t);
    doc["bodies"][0]["initial_velocity"] = json!([0.0, 0.0, -10.0]);
    let scene = parse3(&doc);
    let canon = scene.canonical_json();
    assert!(canon.contains("\"analysis\":\"3d\""), "{canon}");
    let again = parse3(&serde_json::from_str(&canon).unwrap());
    assert_eq!(again, scene);
    assert_eq!(again.hash(), scene.hash());
    assert_eq!(again.canonical_json(), canon);
    let any = AnyScene::Three(scene.clone());
    assert_eq!(any.hash(), scene.hash());
    assert_eq!(any.name(), "steel-box");
    assert_eq!(any.dimension(), 3);
    // A region query (which builds the mesh index) changes neither equality nor the hash.
    assert!(scene.bodies[0].region.contains([0.1, 0.1, 0.1]));
    assert_eq!(again, scene);
    assert_eq!(scene.hash(), again.hash());
}

#[test]
fn two_d_documents_read_exactly_as_before() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("json") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        let doc: Value = serde_json::from_str(&text).unwrap();
        if doc["analysis"] == json!("3d") {
            // The 3D example scenes read as 3D and validate.
            let scene = parse_any_scene(&text).unwrap();
            assert_eq!(scene.dimension(), 3, "{}", path.display());
            validate_any(&scene).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            continue;
        }
        let two = parse_scene(&text).unwrap();
        match parse_any_scene(&text).unwrap() {
            AnyScene::Two(s) => {
                assert_eq!(s, two, "{}", path.display());
                assert_eq!(AnyScene::Two(s).hash(), two.hash());
            }
            AnyScene::Three(_) => panic!("{} read as 3D", path.display()),
        }
        n += 1;
    }
    assert!(n >= 10, "{n} scenes");
    // Broken 2D documents get the 2D parser's errors, unchanged.
    for text in [
        "{\"name\": \"x\",, }",
        "[1, 2]",
        "{\"grid\": 3}",
        "{\"analysis\": \"plane_strain\", \"thickness\": \"thin\"}",
        "{\"analysis\": \"3D\"}",
        "",
    ] {
        assert_eq!(
            parse_any_scene(text).unwrap_err(),
            parse_scene(text).unwrap_err(),
            "{text}"
        );
    }
    // A 2D scene still refuses "3d", pointing at the 3D format.
    let mut v: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("center-crack.json")).unwrap())
            .unwrap();
    v["analysis"] = json!("3d");
    let scene: fracture_api::Scene = serde_json::from_value(v).unwrap();
    let e = fracture_api::validate::validate(&scene).unwrap_err();
    assert!(e.0[0].reason.contains("docs/scenes-3d.md"), "{e}");
}

#[test]
fn the_run_size_is_bounded_before_the_walk() {
    // 1 µm cells in a 20 cm box: 8·10¹⁵ nodes.
    let mut v = steel_box();
    v["grid"]["cell_size"] = json!(1e-6);
    let p = problems(&v);
    assert!(p[0].starts_with("grid.cell_size: 1e-6 gives"), "{p:?}");
    // 64 M nodes is within the grid limit, but 8 particles per cell direction in a 26 cm
    // cube of 0.5 mm cells is 6.6·10¹⁰ candidate sites: refused from the bounding box, at
    // once (no walk).
    let mut v = steel_box();
    v["grid"] = json!({"cell_size": 5e-4, "min": [0.0, 0.0, 0.0], "max": [0.2, 0.2, 0.2]});
    v["bodies"][0]["particles_per_cell"] = json!(8);
    v["bodies"][0]["region"] =
        json!({"box": {"min": [0.001, 0.001, 0.001], "max": [0.199, 0.199, 0.199]}});
    let t = std::time::Instant::now();
    let p = problems(&v);
    assert!(t.elapsed().as_secs_f64() < 1.0);
    assert_eq!(p.len(), 1, "{p:?}");
    assert!(p[0].starts_with("bodies: "), "{p:?}");
    assert!(p[0].contains("candidate particle sites"), "{p:?}");
    let scene = parse3(&v);
    let est = fracture_api::cost::memory_estimate3(&scene, 1000);
    assert_eq!(
        est.particles,
        1000 * fracture_api::cost::BYTES_PER_PARTICLE_3D
    );
    assert_eq!(
        est.grid,
        401 * 401 * 401 * fracture_api::cost::BYTES_PER_NODE_3D
    );
}

/// Walks a schema: the keys of every `properties` object go to `props`, every string of an
/// `enum` and every `const` to `names`.
fn walk(v: &Value, props: &mut BTreeSet<String>, names: &mut BTreeSet<String>) {
    match v {
        Value::Object(map) => {
            if let Some(Value::Object(p)) = map.get("properties") {
                props.extend(p.keys().cloned());
            }
            if let Some(Value::Array(e)) = map.get("enum") {
                names.extend(e.iter().filter_map(|s| s.as_str().map(str::to_string)));
            }
            if let Some(Value::String(c)) = map.get("const") {
                names.insert(c.clone());
            }
            for child in map.values() {
                walk(child, props, names);
            }
        }
        Value::Array(items) => {
            for child in items {
                walk(child, props, names);
            }
        }
        _ => {}
    }
}

#[test]
fn every_3d_schema_name_is_documented() {
    let schema = Scene3::json_schema();
    let (mut props, mut names) = (BTreeSet::new(), BTreeSet::new());
    walk(&schema, &mut props, &mut names);
    for known in [
        "slices",
        "normal",
        "vertices",
        "triangles",
        "axis",
        "polygon",
        "corner",
    ] {
        assert!(props.contains(known), "the schema walk missed `{known}`");
    }
    assert!(names.contains("3d") && names.contains("gimp") && names.contains("z"));
    assert!(
        schema["properties"].get("thickness").is_none(),
        "3D has no thickness"
    );
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/scenes-3d.md");
    let doc = std::fs::read_to_string(&path).unwrap();
    let documented = |name: &str| {
        doc.contains(&format!("`{name}`"))
            || doc.contains(&format!(".{name}`"))
            || doc.contains(&format!("`\"{name}\"`"))
    };
    let missing: Vec<String> = props
        .iter()
        .filter(|p| !documented(p))
        .map(|p| format!("property `{p}`"))
        .chain(
            names
                .iter()
                .filter(|n| !documented(n))
                .map(|n| format!("value \"{n}\"")),
        )
        .collect();
    assert!(
        missing.is_empty(),
        "docs/scenes-3d.md does not document:\n  {}",
        missing.join("\n  ")
    );
}

#[test]
fn the_worked_examples_of_the_guide_validate() {
    // Every ```json block of docs/scenes-3d.md that is a whole 3D scene validates.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/scenes-3d.md");
    let doc = std::fs::read_to_string(&path).unwrap();
    let mut n = 0;
    for block in doc.split("```json\n").skip(1) {
        let Some((body, _)) = block.split_once("```") else {
            continue;
        };
        let Ok(v) = serde_json::from_str::<Value>(body) else {
            continue;
        };
        if v.get("analysis") != Some(&json!("3d")) || v.get("bodies").is_none() {
            continue;
        }
        assert_eq!(problems(&v), Vec::<String>::new(), "{body}");
        n += 1;
    }
    assert!(n >= 2, "{n} worked examples");
}

mod fuzz {
    //! Mutated 3D scenes and random triangle soups: nothing panics, every error names a
    //! path, an accepted scene round-trips through its canonical JSON. CI-sized (256 cases a
    //! property); `PROPTEST_CASES=100000 cargo test --release -p fracture-api --test scene3
    //! fuzz` for a long run.
    use super::*;
    use fracture_api::mesh::{MeshIndex, check_mesh};
    use proptest::prelude::*;

    fn config() -> ProptestConfig {
        let cases = std::env::var("PROPTEST_CASES")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(256);
        ProptestConfig {
            cases,
            failure_persistence: None,
            ..ProptestConfig::default()
        }
    }

    /// Paths to every leaf (and every array and object) of `v`.
    fn nodes(v: &Value, path: &mut Vec<String>, out: &mut Vec<Vec<String>>) {
        out.push(path.clone());
        match v {
            Value::Object(m) => {
                for (k, c) in m {
                    path.push(k.clone());
                    nodes(c, path, out);
                    path.pop();
                }
            }
            Value::Array(a) => {
                for (i, c) in a.iter().enumerate() {
                    path.push(i.to_string());
                    nodes(c, path, out);
                    path.pop();
                }
            }
            _ => {}
        }
    }

    fn at<'a>(v: &'a mut Value, path: &[String]) -> &'a mut Value {
        path.iter().fold(v, |v, k| match v {
            Value::Array(a) => &mut a[k.parse::<usize>().unwrap()],
            _ => &mut v[k.as_str()],
        })
    }

    fn replacement(i: usize) -> Value {
        let all = [
            json!(0),
            json!(-1.0),
            json!(1e300),
            json!(-1e-300),
            json!(0.5),
            json!(3),
            json!(1e-9),
            json!(40000000000u64),
            json!("x"),
            json!("3d"),
            json!(null),
            json!([]),
            json!({}),
            json!([0.1, 0.2]),
            json!([0.1, 0.1, 0.1]),
            json!([[0, 1, 2]]),
            json!({"box": {"min": [0.0, 0.0, 0.0], "max": [0.3, 0.3, 0.3]}}),
        ];
        all[i % all.len()].clone()
    }

    fn bases() -> Vec<Value> {
        let (cv, ct) = cube_mesh(0.06, 0.14);
        let mut mesh = steel_box();
        mesh["bodies"][0]["region"] = mesh_json(&cv, &ct);
        mesh["boundary_conditions"] = json!([{"region": {"cylinder": {"base": [0.0, 0.1, 0.1],
            "axis": [0.2, 0.0, 0.0], "radius": 0.02}}, "velocity": {"x": 1.0}}]);
        mesh["loads"] = json!([{"region": {"prism": {"polygon": [[0.0, 0.0], [0.2, 0.0], [0.1, 0.2]],
            "z": [0.14, 0.2]}}, "traction": [0.0, 0.0, 1e6]}]);
        mesh["output"] = json!({"slices": [{"normal": "x", "at": 0.1}], "snapshot_interval": 1e-6});
        vec![steel_box(), mesh]
    }

    proptest! {
        #![proptest_config(config())]

        #[test]
        fn mutated_3d_scenes_never_panic(base in 0usize..2, edits in prop::collection::vec((any::<usize>(), any::<usize>()), 1..4)) {
            let mut v = bases()[base].clone();
            for (node, value) in edits {
                let mut all = Vec::new();
                nodes(&v, &mut Vec::new(), &mut all);
                let path = all[node % all.len()].clone();
                *at(&mut v, &path) = replacement(value);
            }
            let text = v.to_string();
            let scene = match parse_any_scene(&text) {
                Ok(s) => s,
                Err(e) => {
                    prop_assert!(e.0.iter().all(|e| !e.path.is_empty() && !e.reason.is_empty()));
                    return Ok(());
                }
            };
            if let AnyScene::Three(s) = &scene
                && fracture_api::lattice3::candidate_sites3(s) > 200_000
            {
                return Ok(()); // validation walks it; keep the fuzz fast
            }
            if let AnyScene::Two(_) = &scene {
                return Ok(()); // the 2D fuzz (tests/fuzz.rs) covers 2D scenes
            }
            match validate_any(&scene) {
                Ok(_) => {
                    let canon = scene.canonical_json();
                    let again = parse_any_scene(&canon).unwrap();
                    prop_assert_eq!(again.canonical_json(), canon);
                }
                Err(e) => {
                    prop_assert!(e.0.iter().all(|e| !e.path.is_empty() && !e.reason.is_empty()));
                }
            }
        }

        #[test]
        fn a_rotated_cube_mesh_holds_the_rotated_box(
            angles in (0.0f64..6.3, 0.0f64..6.3, 0.0f64..6.3),
            points in prop::collection::vec((-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0), 64),
        ) {
            // Rotation R = Rz·Ry·Rx; the cube [-0.5, 0.5]³ rotated about the origin and moved
            // to c. A point is in the mesh iff R^T(p − c) is in the box (points within 1e-9
            // of a face are skipped: either answer is right there).
            let (a, b, g) = angles;
            let rx = [[1.0, 0.0, 0.0], [0.0, a.cos(), -a.sin()], [0.0, a.sin(), a.cos()]];
            let ry = [[b.cos(), 0.0, b.sin()], [0.0, 1.0, 0.0], [-b.sin(), 0.0, b.cos()]];
            let rz = [[g.cos(), -g.sin(), 0.0], [g.sin(), g.cos(), 0.0], [0.0, 0.0, 1.0]];
            let mul = |m: [[f64; 3]; 3], n: [[f64; 3]; 3]| {
                let mut r = [[0.0; 3]; 3];
                for i in 0..3 {
                    for j in 0..3 {
                        r[i][j] = (0..3).map(|k| m[i][k] * n[k][j]).sum();
                    }
                }
                r
            };
            let r = mul(rz, mul(ry, rx));
            let c = [0.3, -0.2, 0.1];
            let (v, t) = cube_mesh(-0.5, 0.5);
            let v: Vec<Vec3> = v
                .iter()
                .map(|p| [0, 1, 2].map(|i| c[i] + (0..3).map(|k| r[i][k] * p[k]).sum::<f64>()))
                .collect();
            prop_assert!(fracture_api::mesh::check_mesh(&v, &t).is_ok());
            let mesh = Region3::Mesh(TriMesh::new(v, t));
            for (x, y, z) in points {
                let p = [c[0] + x, c[1] + y, c[2] + z];
                let d = [x, y, z];
                let q = [0, 1, 2].map(|j| (0..3).map(|k| r[k][j] * d[k]).sum::<f64>());
                let margin = q.iter().map(|e| (e.abs() - 0.5).abs()).fold(f64::INFINITY, f64::min);
                if margin < 1e-9 {
                    continue;
                }
                let inside = q.iter().all(|e| e.abs() <= 0.5);
                prop_assert_eq!(mesh.contains(p), inside, "{:?} {:?}", p, q);
            }
        }

        #[test]
        fn triangle_soups_never_panic(
            verts in prop::collection::vec((0u8..3, 0u8..3, 0u8..3), 4..9),
            tris in prop::collection::vec((0u32..10, 0u32..10, 0u32..10), 4..14),
        ) {
            // Coordinates on a 3³ lattice: coplanar, collinear and touching cases abound.
            let v: Vec<Vec3> = verts.iter().map(|&(x, y, z)| [f64::from(x), f64::from(y), f64::from(z)]).collect();
            let t: Vec<[u32; 3]> = tris.iter().map(|&(a, b, c)| [a, b, c]).collect();
            let verdict = check_mesh(&v, &t);
            let index = MeshIndex::new(&v, &t);
            for p in [[0.5, 0.5, 0.5], [1.0, 1.0, 1.0], [1.5, 0.25, 2.0], [2.0, 2.0, 0.0]] {
                let inside = index.contains(p);
                if verdict.is_ok() {
                    // A valid surface's winding is 0 or ±1: the column test agrees with
                    // the point test.
                    let r = Region3::Mesh(TriMesh::new(v.clone(), t.clone()));
                    prop_assert_eq!(r.column(p[0], p[1]).contains(p[2]), inside);
                }
            }
        }
    }
}
