//! Validation of the sharp edges a newcomer hits: a crack or interface drawn where no body
//! is, and reference values that name nothing.

use fracture_api::validate::{scene_from_value, validate};
use serde_json::{Value, json};

/// A 40 mm plate with a 10 mm centre crack.
fn plate() -> Value {
    json!({
        "grid": {"cell_size": 0.001, "min": [0.0, 0.0], "max": [0.1, 0.05]},
        "materials": {"m": {"model": "linear_elastic", "density": 1000.0,
                             "youngs_modulus": 1e9, "poissons_ratio": 0.3}},
        "bodies": [{"material": "m",
                    "region": {"rectangle": {"min": [0.005, 0.005], "max": [0.045, 0.045]}}}],
        "cracks": [{"points": [[0.02, 0.0255], [0.03, 0.0255]]}],
        "time": {"end": 1e-6}
    })
}

/// The problems of `v` as "path: message" lines (empty when it validates).
fn problems(v: Value) -> Vec<String> {
    let scene = match scene_from_value(v) {
        Ok(s) => s,
        Err(e) => return e.0.iter().map(|e| e.to_string()).collect(),
    };
    match validate(&scene) {
        Ok(_) => Vec::new(),
        Err(e) => e.0.iter().map(|e| e.to_string()).collect(),
    }
}

#[test]
fn a_crack_in_a_body_validates() {
    assert_eq!(problems(plate()), Vec::<String>::new());
    // An edge crack whose mouth lies outside the body still cuts it.
    let mut v = plate();
    v["cracks"][0]["points"] = json!([[0.0, 0.0255], [0.02, 0.0255]]);
    assert_eq!(problems(v), Vec::<String>::new());
}

#[test]
fn a_crack_in_empty_space_is_refused_naming_it() {
    let mut v = plate();
    // Inside the grid box, right of the plate.
    v["cracks"] = json!([{"points": [[0.02, 0.0255], [0.03, 0.0255]]},
                         {"points": [[0.06, 0.0255], [0.09, 0.0255]]}]);
    let p = problems(v);
    assert_eq!(p.len(), 1, "{p:?}");
    assert!(p[0].starts_with("cracks.1.points"), "{p:?}");
    assert!(p[0].contains("outside every body"), "{p:?}");
}

#[test]
fn an_interface_in_empty_space_is_refused_naming_it() {
    let mut v = plate();
    v["interfaces"] = json!([{"points": [[0.06, 0.02], [0.09, 0.02]],
        "cohesive": {"law": "linear",
                     "normal": {"strength": 1e6, "toughness": 10.0},
                     "shear": {"strength": 1e6, "toughness": 10.0}}}]);
    let p = problems(v);
    assert_eq!(p.len(), 1, "{p:?}");
    assert!(p[0].starts_with("interfaces.0.points"), "{p:?}");
}

#[test]
fn references_are_checked() {
    let mut v = plate();
    v["references"] = json!([
        {"quantity": "k1", "value": 1.0e5, "source": "Tada", "tolerance": 0.03},
        {"quantity": "k1", "value": 1.0e5, "crack": 2},
        {"quantity": "growth", "value": 0.01, "tip": 3},
        {"quantity": "j1", "value": 5.0, "tolerance": -1.0}
    ]);
    let p = problems(v);
    assert_eq!(p.len(), 3, "{p:?}");
    assert!(p[0].starts_with("references.1.crack"), "{p:?}");
    assert!(p[1].starts_with("references.2.tip"), "{p:?}");
    assert!(p[2].starts_with("references.3.tolerance"), "{p:?}");
    let mut v = plate();
    v["references"] = json!([{"quantity": "stress", "value": 1.0}]);
    let p = problems(v);
    assert!(p.iter().any(|m| m.contains("references")), "{p:?}");
}

/// A growing crack's ring is part of its tip law (`algorithm.md` pitfall 13): its default is
/// 1/16 of the scene's shortest body side, whatever the cell, and a grid too coarse to put
/// three cells across it is refused naming the field and the fix. The 40 mm plate's default
/// ring is 2.5 mm: three cells at 0.5 mm cells fit, at 1 mm cells they do not.
#[test]
fn a_growing_crack_needs_three_cells_across_its_physical_ring() {
    use fracture_api::scene::JIntegral;
    let growing = |h: f64| {
        let mut v = plate();
        v["grid"]["cell_size"] = json!(h);
        v["cracks"][0]["propagation"] = json!({"criterion": "energy_release", "toughness": 10.0});
        v
    };
    let fine = scene_from_value(growing(0.0005)).expect("parses");
    let coarse = scene_from_value(growing(0.001)).expect("parses");
    let ring = |s: &fracture_api::Scene| match JIntegral::default_in(&s.cracks[0], s) {
        JIntegral::Domain { radius } => radius,
        JIntegral::Contour { .. } => f64::NAN,
    };
    assert!((ring(&fine) - 0.0025).abs() < 1e-12, "{}", ring(&fine));
    assert_eq!(
        ring(&fine),
        ring(&coarse),
        "the default ring follows the cell"
    );
    assert_eq!(problems(growing(0.0005)), Vec::<String>::new());
    let p = problems(growing(0.001));
    assert_eq!(p.len(), 1, "{p:?}");
    assert!(p[0].starts_with("cracks.0.j_integral"), "{p:?}");
    assert!(p[0].contains("cracks.0.j_integral.radius"), "{p:?}");
    // An explicit ring of three cells is accepted; a crack at rest keeps its 6-cell ring.
    let mut v = growing(0.001);
    v["cracks"][0]["j_integral"] = json!({"method": "domain", "radius": 0.003});
    assert_eq!(problems(v), Vec::<String>::new());
    let mut v = growing(0.001);
    v["cracks"][0]["propagation"] = json!({"criterion": "none"});
    let s = scene_from_value(v).expect("parses");
    assert!((ring(&s) - 0.006).abs() < 1e-12);
}

/// Body-to-body contact: the bodies with a contact law share one field, so they take one
/// law, need a body without one to meet, and a negative friction is refused; each error
/// names the body's field.
#[test]
fn body_contact_laws_are_checked_naming_the_body() {
    let mut v = plate();
    v["cracks"] = json!([]);
    let striker = json!({"material": "m",
        "region": {"rectangle": {"min": [0.05, 0.005], "max": [0.06, 0.045]}},
        "contact": {"law": "frictionless"}});
    v["bodies"] = json!([v["bodies"][0].clone(), striker.clone()]);
    assert_eq!(problems(v.clone()), Vec::<String>::new());

    let mut two = v.clone();
    let mut other = striker.clone();
    other["region"] = json!({"rectangle": {"min": [0.07, 0.005], "max": [0.08, 0.045]}});
    other["contact"] = json!({"law": "coulomb", "friction": -0.2});
    two["bodies"] = json!([two["bodies"][0].clone(), two["bodies"][1].clone(), other]);
    let p = problems(two);
    assert!(
        p.iter().any(|e| e.starts_with("bodies.2.contact.friction")),
        "{p:?}"
    );
    assert!(
        p.iter()
            .any(|e| e.starts_with("bodies.2.contact") && e.contains("one law")),
        "{p:?}"
    );

    let mut all = v;
    all["bodies"][0]["contact"] = json!({"law": "frictionless"});
    let p = problems(all);
    assert_eq!(p.len(), 1, "{p:?}");
    assert!(
        p[0].starts_with("bodies.0.contact") && p[0].contains("no body to meet"),
        "{p:?}"
    );
}
