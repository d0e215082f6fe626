//! Crossing test and velocity-field assignment on hand-made configurations (`algorithm.md`
//! §3): straight and kinked cracks, a node exactly on the crack, an edge-crack mouth, lines
//! passing beyond the tip. Cell size 1, grid 16 × 16 cells.
#![allow(clippy::unwrap_used)]

mod common;
use common::*;
use fracture_solver::crack::{Cracks, crosses};
use fracture_solver::grid::GridGeom;
use fracture_solver::particles::{Kin, Mech};
use serde_json::json;

fn cracks(points: serde_json::Value) -> (Cracks, GridGeom) {
    let s = scene(json!({
        "grid": {"cell_size": 1.0, "min": [0.0, 0.0], "max": [16.0, 16.0]},
        "materials": {"m": {"model": "linear_elastic", "density": 1.0, "youngs_modulus": 1.0, "poissons_ratio": 0.3}},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": [1.0, 1.0], "max": [15.0, 15.0]}}}],
        "cracks": [{"points": points}],
        "time": {"end": 1.0}
    }));
    let geom = GridGeom::new([0.0, 0.0], [16.0, 16.0], 1.0);
    (Cracks::new(&s, &geom, &[], 1e-7), geom)
}

/// Field of the pair (particle at x, node (ix, iy)) and the node's slot record.
fn field_of(
    c: &mut Cracks,
    geom: &GridGeom,
    x: [f64; 2],
    node: (usize, usize),
) -> (u8, Option<fracture_solver::crack::SlotInfo>) {
    let kin = [Kin { x, v: [0.0; 2] }];
    let mech = [Mech {
        m: 1.0,
        vol: 1.0,
        lh: 0.25,
        mat: 0,
        load: 0,
    }];
    let mut fmask = [0u16];
    let mut f1 = Vec::new();
    c.assign_fields(
        geom,
        fracture_api::scene::ShapeFunction::Gimp,
        &kin,
        &mech,
        &[fracture_solver::particles::Cold::default()],
        &mut fmask,
        &mut f1,
    )
    .unwrap();
    let w = fracture_solver::shape::Weights2::new(
        fracture_api::scene::ShapeFunction::Gimp,
        geom.xi(&x),
        0.25,
    );
    let a = node.0 as i32 - w.x.base;
    let b = node.1 as i32 - w.y.base;
    assert!(
        (0..3).contains(&a) && (0..3).contains(&b),
        "node not in the particle's stencil"
    );
    let bit = ((fmask[0] >> (3 * a + b) as u32) & 1) as u8;
    let idx = geom.at(node.0, node.1) as u32;
    let slot = f1.iter().position(|&i| i == idx).map(|s| c.slots[s]);
    (bit, slot)
}

#[test]
fn segment_crossing_primitive() {
    assert!(crosses([0.0, 0.0], [0.0, 2.0], [-1.0, 1.0], [1.0, 1.0]));
    assert!(!crosses([0.0, 0.0], [0.0, 0.9], [-1.0, 1.0], [1.0, 1.0]));
    // Beyond the end of the crack segment: no crossing.
    assert!(!crosses([2.0, 0.0], [2.0, 2.0], [-1.0, 1.0], [1.0, 1.0]));
}

#[test]
fn straight_crack_separates_the_two_sides() {
    let (mut c, g) = cracks(json!([[2.0, 5.5], [9.0, 5.5]]));
    // Particle below the crack, node above: field 1, which holds the below side.
    let (f, slot) = field_of(&mut c, &g, [4.25, 5.25], (4, 6));
    assert_eq!(f, 1);
    let s = slot.unwrap();
    assert!(!s.above_is_f1);
    assert!(
        (s.normal[0]).abs() < 1e-12 && (s.normal[1] + 1.0).abs() < 1e-12,
        "normal above→below {:?}",
        s.normal
    );
    // Same particle, node on its own side: field 0.
    assert_eq!(field_of(&mut c, &g, [4.25, 5.25], (4, 5)).0, 0);
    // Particle above, node below: field 1 holding the above side.
    let (f, slot) = field_of(&mut c, &g, [4.75, 5.75], (5, 5));
    assert_eq!(f, 1);
    assert!(slot.unwrap().above_is_f1);
}

#[test]
fn kinked_crack_uses_the_crossed_segment() {
    // Horizontal then rising at 45°.
    let (mut c, g) = cracks(json!([[2.0, 5.5], [6.0, 5.5], [10.0, 9.5]]));
    // Across the inclined part: particle at (8.25, 7.25) is below/right of the line y = x − 0.5,
    // node (8, 8) is above/left.
    let (f, slot) = field_of(&mut c, &g, [8.25, 7.25], (8, 8));
    assert_eq!(f, 1);
    let n = slot.unwrap().normal;
    let r = std::f64::consts::FRAC_1_SQRT_2;
    assert!(
        (n[0] - r).abs() < 1e-9 && (n[1] + r).abs() < 1e-9,
        "normal of the inclined segment {n:?}"
    );
    // Not across: node (9, 7) on the same side.
    assert_eq!(field_of(&mut c, &g, [8.25, 7.25], (9, 7)).0, 0);
}

#[test]
fn node_exactly_on_the_crack_counts_as_above() {
    // Crack along the node row y = 5 (tie rule: on the line counts as above/left).
    let (mut c, g) = cracks(json!([[2.0, 5.0], [9.0, 5.0]]));
    assert_eq!(
        field_of(&mut c, &g, [4.25, 4.75], (4, 5)).0,
        1,
        "below particle to on-line node crosses"
    );
    assert_eq!(
        field_of(&mut c, &g, [4.25, 5.25], (4, 5)).0,
        0,
        "above particle to on-line node does not"
    );
}

#[test]
fn lines_beyond_the_tip_cross_nothing() {
    let (mut c, g) = cracks(json!([[2.0, 5.5], [6.0, 5.5]]));
    // Particle below and ahead of the tip (x = 6.75 > 6), node above ahead.
    assert_eq!(field_of(&mut c, &g, [6.75, 5.25], (7, 6)).0, 0);
    // Just behind the tip the same pair is separated.
    assert_eq!(field_of(&mut c, &g, [5.25, 5.25], (5, 6)).0, 1);
    assert!(c.cracks[0].tips[0].active && c.cracks[0].tips[1].active);
}

#[test]
fn edge_crack_mouth_is_not_a_tip_and_separates_at_the_surface() {
    // The body starts at x = 1; the crack starts just outside it (mouth) at x = 0.95.
    let (mut c, g) = cracks(json!([[0.95, 5.5], [6.0, 5.5]]));
    assert!(!c.cracks[0].tips[0].active, "mouth");
    assert!(c.cracks[0].tips[1].active, "tip");
    // The surface particle column: particle below at x = 1.25, nodes above on the body's edge
    // (x = 1) and inside (x = 2): both separated right up to the surface.
    assert_eq!(field_of(&mut c, &g, [1.25, 5.25], (1, 6)).0, 1);
    assert_eq!(field_of(&mut c, &g, [1.25, 5.25], (2, 6)).0, 1);
    // A surface particle at the very edge to the outside node row below/above is separated too.
    assert_eq!(field_of(&mut c, &g, [1.25, 5.75], (1, 5)).0, 1);
    // Reported length excludes the 2h extension of the mouth.
    assert!(
        (c.cracks[0].length() - 5.05).abs() < 1e-12,
        "length {}",
        c.cracks[0].length()
    );
}
