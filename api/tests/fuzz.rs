//! Fuzz test of the scene parser and validation: structured random scenes, mutated real
//! scenes (`scenes/*.json`) and mutated JSON text. Properties: nothing panics; every error
//! names a JSON path; an accepted scene round-trips through its canonical JSON and its
//! cost estimate (`fracture_api::cost`) is computable.
//!
//! CI runs a few hundred cases per property (seconds). The long run (see
//! `docs/service.md`): `PROPTEST_CASES=1000000 cargo test --release -p fracture-api --test
//! fuzz`.

#![allow(clippy::unwrap_used)]

use fracture_api::validate::{parse_scene, scene_from_value, validate};
use fracture_api::{Scene, ValidationErrors, cost};
use proptest::prelude::*;
use serde_json::{Value, json};

fn cases() -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(256)
}

fn config() -> ProptestConfig {
    ProptestConfig {
        cases: cases(),
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

/// The example scenes, as JSON values.
fn examples() -> &'static [Value] {
    static EX: std::sync::OnceLock<Vec<Value>> = std::sync::OnceLock::new();
    EX.get_or_init(|| {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
        let mut names: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|e| e == "json"))
            .collect();
        names.sort();
        names
            .iter()
            .filter_map(|p| serde_json::from_str(&std::fs::read_to_string(p).ok()?).ok())
            // The 2D parser's fuzz: 3D scenes have their own tests (`tests/scene3.rs`).
            .filter(|v: &Value| v["analysis"] != "3d")
            .collect()
    })
}

/// Validation walks the particle lattice: keep the fuzz to scenes whose walk is small
/// (the service refuses larger ones before the walk: `Limits::precheck`).
fn walk_is_small(s: &Scene) -> bool {
    let h = s.grid.cell_size;
    if !(h.is_finite() && h > 0.0) {
        return true; // validation stops at the grid
    }
    // Grids of any size are fine: validation saturates its node count and refuses them
    // before the walk (`huge_grid_is_refused_by_validation`, below).
    let mut sites = 0f64;
    for b in &s.bodies {
        let (lo, hi) = b.region.bounds();
        let lo = [lo[0].max(s.grid.min[0]), lo[1].max(s.grid.min[1])];
        let hi = [hi[0].min(s.grid.max[0]), hi[1].min(s.grid.max[1])];
        let sub = h / f64::from(b.particles_per_cell.clamp(1, 8));
        let n = ((hi[0] - lo[0]) / sub).max(0.0) * ((hi[1] - lo[1]) / sub).max(0.0);
        sites += if n.is_finite() { n } else { f64::INFINITY };
    }
    let segs: usize = s.cracks.iter().map(|c| c.points.len()).sum();
    sites < 2e5 && segs < 10_000
}

fn check_errors(e: &ValidationErrors, what: &str) {
    assert!(!e.0.is_empty(), "{what}: an error without details");
    for v in &e.0 {
        assert!(!v.path.is_empty(), "{what}: an error without a path: {v:?}");
        assert!(
            !v.reason.is_empty(),
            "{what}: an error without a reason: {v:?}"
        );
    }
}

/// Everything the service does with a scene document before it runs, minus IO.
fn exercise(value: Value) {
    match scene_from_value(value) {
        Err(e) => check_errors(&e, "parse"),
        Ok(scene) => {
            let _ = cost::memory_estimate(&scene, u64::MAX);
            let _ = cost::steps_estimate(&scene);
            let _ = scene.time_step();
            let text = scene.canonical_json();
            let again = Scene::from_json(&text)
                .unwrap_or_else(|e| panic!("canonical JSON does not parse: {e}\n{text}"));
            assert_eq!(again.canonical_json(), text, "canonical JSON is not stable");
            if walk_is_small(&scene) {
                match validate(&scene) {
                    Err(e) => check_errors(&e, "validate"),
                    Ok(size) => {
                        let _ = cost::memory_estimate(&scene, size.particles);
                        let _ = cost::particle_steps(size.particles, size.steps);
                    }
                }
            }
        }
    }
}

/// Values that break parsers and checks.
fn nasty() -> impl Strategy<Value = Value> {
    prop_oneof![
        Just(json!(null)),
        Just(json!(0)),
        Just(json!(-0.0)),
        Just(json!(-1)),
        Just(json!(1e-300)),
        Just(json!(1e300)),
        Just(json!(1.7976931348623157e308)),
        Just(json!(-1.7976931348623157e308)),
        Just(json!(5e-324)),
        Just(json!(u64::MAX)),
        Just(json!(i64::MIN)),
        Just(json!(0.5)),
        Just(json!(true)),
        Just(json!("")),
        Just(json!("NaN")),
        Just(json!("<script>alert(1)</script>")),
        Just(json!([])),
        Just(json!({})),
        Just(json!([[0.0, 0.0]])),
        Just(json!([[0.0, 0.0], [0.0, 0.0]])),
        Just(json!([0.0, 0.0])),
        Just(json!([1e300, -1e300])),
        Just(json!({"rectangle": {"min": [0.0, 0.0], "max": [0.0, 0.0]}})),
        Just(json!({"circle": {"center": [0.0, 0.0], "radius": -1.0}})),
        Just(json!({"polygon": {"points": [[0.0, 0.0], [1.0, 0.0]]}})),
        any::<f64>()
            .prop_filter("finite", |x| x.is_finite())
            .prop_map(|x| json!(x)),
        any::<i64>().prop_map(|x| json!(x)),
        "[a-z_]{0,12}".prop_map(|s| json!(s)),
    ]
}

/// A path into `v` chosen by `pick` (a random walk down objects and arrays).
fn walk(v: &mut Value, pick: u32, depth: u32) -> &mut Value {
    let next = pick.rotate_right(5).wrapping_mul(2_654_435_761);
    let len = match &*v {
        Value::Object(m) => m.len(),
        Value::Array(a) => a.len(),
        _ => 0,
    };
    if pick.is_multiple_of(depth + 2) || len == 0 {
        return v;
    }
    let i = pick as usize % len;
    match v {
        Value::Object(m) => {
            let k = m.keys().nth(i).cloned().unwrap();
            walk(m.get_mut(&k).unwrap(), next, depth + 1)
        }
        Value::Array(a) => walk(&mut a[i], next, depth + 1),
        other => other,
    }
}

/// One mutation of a JSON document.
fn mutate(doc: &mut Value, pick: u32, op: u8, with: Value) {
    let target = walk(doc, pick, 0);
    match op % 6 {
        0 | 1 => *target = with,
        2 => {
            // Remove a key or an element.
            match target {
                Value::Object(m) if !m.is_empty() => {
                    let k = m.keys().nth(pick as usize % m.len()).cloned().unwrap();
                    m.remove(&k);
                }
                Value::Array(a) if !a.is_empty() => {
                    a.remove(pick as usize % a.len());
                }
                _ => {}
            }
        }
        3 => {
            // Add an unknown key, or repeat an element many times.
            match target {
                Value::Object(m) => {
                    m.insert(format!("unknown_{}", pick % 7), with);
                }
                Value::Array(a) if !a.is_empty() => {
                    let e = a[0].clone();
                    for _ in 0..(pick % 50) {
                        a.push(e.clone());
                    }
                }
                _ => {}
            }
        }
        4 => {
            // Scale a number.
            if let Some(x) = target.as_f64() {
                let f = [0.0, -1.0, 1e-9, 1e9, 1e200, 0.999_999_999][pick as usize % 6];
                if let Some(n) = serde_json::Number::from_f64(x * f) {
                    *target = Value::Number(n);
                }
            }
        }
        _ => {
            // Nest deeply.
            let mut v = with;
            for _ in 0..(pick % 64) {
                v = json!([v]);
            }
            *target = v;
        }
    }
}

fn num(lo: f64, hi: f64) -> impl Strategy<Value = f64> + Clone {
    prop_oneof![
        4 => lo..hi,
        1 => Just(0.0),
        1 => Just(-1.0),
        1 => Just(1e300),
        1 => Just(1e-300),
    ]
}

/// A structurally valid-looking random scene (many come out invalid: that is the point).
fn structured() -> impl Strategy<Value = Value> {
    let material = (num(1.0, 1e5), num(1e3, 1e12), num(-0.9, 0.6))
        .prop_map(|(rho, e, nu)| json!({"model": "linear_elastic", "density": rho, "youngs_modulus": e, "poissons_ratio": nu}));
    let point = || (num(-0.01, 0.06), num(-0.01, 0.06)).prop_map(|(x, y)| json!([x, y]));
    let region = prop_oneof![
        (point(), point()).prop_map(|(a, b)| json!({"rectangle": {"min": a, "max": b}})),
        (point(), num(0.0, 0.03)).prop_map(|(c, r)| json!({"circle": {"center": c, "radius": r}})),
        prop::collection::vec(point(), 0..6).prop_map(|p| json!({"polygon": {"points": p}})),
    ];
    let body = (region.clone(), 0u32..10)
        .prop_map(|(r, ppc)| json!({"material": "m", "region": r, "particles_per_cell": ppc}));
    let crack = prop::collection::vec(point(), 0..5).prop_map(|p| json!({"points": p}));
    (
        num(0.0005, 0.01),
        point(),
        point(),
        material,
        prop::collection::vec(body, 0..3),
        prop::collection::vec(crack, 0..2),
        num(1e-7, 1e-4),
        num(0.0, 1e-5),
    )
        .prop_map(|(h, lo, hi, m, bodies, cracks, end, snap)| {
            json!({
                "name": "fuzz",
                "grid": {"cell_size": h, "min": lo, "max": hi},
                "materials": {"m": m},
                "bodies": bodies,
                "cracks": cracks,
                "time": {"end": end},
                "output": {"snapshot_interval": snap, "fields": ["stress", "velocity"]}
            })
        })
}

proptest! {
    #![proptest_config(config())]

    /// Random scenes built from the schema's parts.
    #[test]
    fn structured_scenes_never_panic_and_errors_have_paths(doc in structured()) {
        exercise(doc);
    }

    /// Real scenes with a few mutations each.
    #[test]
    fn mutated_example_scenes_never_panic_and_errors_have_paths(
        which in any::<prop::sample::Index>(),
        muts in prop::collection::vec((any::<u32>(), any::<u8>(), nasty()), 1..5),
    ) {
        let ex = examples();
        prop_assume!(!ex.is_empty());
        let mut doc = ex[which.index(ex.len())].clone();
        for (pick, op, with) in muts {
            mutate(&mut doc, pick, op, with);
        }
        exercise(doc);
    }

    /// Real scenes' text with bytes flipped, cut or inserted: the text parser.
    #[test]
    fn mutated_scene_text_never_panics_and_errors_have_paths(
        which in any::<prop::sample::Index>(),
        edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>(), 0u8..3), 1..8),
    ) {
        let ex = examples();
        prop_assume!(!ex.is_empty());
        let mut bytes = ex[which.index(ex.len())].to_string().into_bytes();
        for (at, b, kind) in edits {
            if bytes.is_empty() { break; }
            let i = at.index(bytes.len());
            match kind {
                0 => bytes[i] = b,
                1 => { bytes.truncate(i); }
                _ => bytes.insert(i, b),
            }
        }
        let text = String::from_utf8_lossy(&bytes);
        match parse_scene(&text) {
            Err(e) => check_errors(&e, "parse text"),
            Ok(scene) => exercise(serde_json::to_value(&scene).unwrap()),
        }
    }
}

/// The example scenes themselves pass (the mutations start from valid documents).
#[test]
fn every_example_scene_parses() {
    assert!(examples().len() >= 10);
    for v in examples() {
        scene_from_value(v.clone()).unwrap();
    }
}

/// Found by this fuzz test: a grid of more than 2⁶⁴ nodes a side overflowed the node count
/// of `validate` (`… .ceil() as u64 + 1`: a panic in debug builds, a wrap to a small count
/// in release). It saturates now, and the grid is refused naming `grid.cell_size`.
#[test]
fn huge_grid_is_refused_by_validation() {
    let mut v = examples()[0].clone();
    v["grid"]["cell_size"] = json!(1e-300);
    v["grid"]["max"] = json!([1e300, 1e300]);
    let scene = scene_from_value(v).unwrap();
    let r = std::panic::catch_unwind(|| validate(&scene));
    let ok = matches!(&r, Ok(Err(e)) if e.0.iter().any(|d| d.path == "grid.cell_size"
        && d.reason.contains(&u64::MAX.to_string())));
    assert!(
        ok,
        "validate must refuse the grid at grid.cell_size with a saturated count, got {:?}",
        r.map(|x| x.map(|s| s.grid_nodes))
    );
}

/// Constants that are each valid but whose wave speed overflows (density 1e-300) are
/// refused naming the density and its value, not as a run that "needs NaN steps".
#[test]
fn overflowing_wave_speed_names_the_density() {
    let mut v = examples()[0].clone();
    let name = v["materials"]
        .as_object()
        .unwrap()
        .keys()
        .next()
        .unwrap()
        .clone();
    v["materials"][&name]["density"] = json!(1e-300);
    let e = validate(&scene_from_value(v).unwrap()).unwrap_err();
    let path = format!("materials.{name}.density");
    assert!(
        e.0.iter().any(|d| d.path == path && d.value == "1e-300"),
        "{e}"
    );
    assert!(!e.to_string().contains("NaN"), "{e}");
}
