//! Shape functions (`algorithm.md` §1).
//!
//! Uniform GIMP (Bardenhagen & Kober 2004) with the particle half-width l = h/(2·ppc) fixed at
//! its undeformed size, and classic bilinear MPM. Both are evaluated in cell units
//! (ξ = (x − x_min)/h) as three 1D weights per direction, so a particle touches at most 3×3
//! nodes; the 2D shape function is the tensor product S = S_x S_y.

use fracture_api::scene::ShapeFunction;

pub use fracture_mpm::shape::{CachedW1, Weights1};

/// Uniform GIMP weight and its derivative for the signed distance `d` (cell units) between
/// particle and node, with particle half-width `l` (cell units, 0 < l ≤ ½).
#[inline(always)]
pub fn gimp(d: f64, l: f64) -> (f64, f64) {
    gimp_inv(d, l, 1.0 / l)
}

/// [`gimp`] with the reciprocal `il` = 1/l supplied (no division in the hot loops).
#[inline(always)]
pub fn gimp_inv(d: f64, l: f64, il: f64) -> (f64, f64) {
    let a = d.abs();
    let sign = if d < 0.0 { -1.0 } else { 1.0 };
    if a < l {
        (1.0 - 0.5 * (a * a + l * l) * il, -d * il)
    } else if a <= 1.0 - l {
        (1.0 - a, -sign)
    } else if a < 1.0 + l {
        let r = 1.0 + l - a;
        (0.25 * r * r * il, -0.5 * sign * r * il)
    } else {
        (0.0, 0.0)
    }
}

/// Bilinear (tent) weight and derivative for the signed distance `d` (cell units).
#[inline(always)]
pub fn linear(d: f64) -> (f64, f64) {
    let a = d.abs();
    if a < 1.0 {
        (1.0 - a, if d < 0.0 { 1.0 } else { -1.0 })
    } else {
        (0.0, 0.0)
    }
}

/// floor(x) for |x| < 2⁵¹ in plain float arithmetic: adding and subtracting 1.5·2⁵² rounds
/// to the nearest integer, then one correction. `f64::floor` is an out-of-line libm call on
/// baseline x86-64 and a saturating `as i64` cast costs a dozen instructions; this is four.
#[inline(always)]
pub fn fast_floor(x: f64) -> f64 {
    const MAGIC: f64 = 6_755_399_441_055_744.0;
    let r = (x + MAGIC) - MAGIC;
    if r > x { r - 1.0 } else { r }
}

/// 1D weights at ξ (cell units from the grid origin): the core's
/// [`fracture_mpm::shape::weights_1d`] with q = 1/(4l).
#[inline(always)]
pub fn weights_1d(kind: ShapeFunction, xi: f64, l: f64) -> Weights1 {
    fracture_mpm::shape::weights_1d(kind, xi, l, 0.25 / l)
}

/// GIMP 1D weights at ξ with half-width `l` and `q` = 1/(4l) supplied (the hot loops keep it
/// across particles of equal size instead of dividing per particle). A particle reaching only
/// two nodes has its empty node last (the core's stencil base rule), which `Field0` in
/// `sim/stencil.rs` relies on.
#[inline(always)]
pub fn gimp_weights_1d(xi: f64, l: f64, q: f64) -> Weights1 {
    fracture_mpm::shape::weights_1d(ShapeFunction::Gimp, xi, l, q)
}

/// 2D weights of one particle: 3×3 nodes starting at `(bx, by)`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Weights2 {
    /// x weights.
    pub x: Weights1,
    /// y weights.
    pub y: Weights1,
}

impl Weights2 {
    /// Weights at position ξ = (x − x_min)/h in cell units.
    #[inline(always)]
    pub fn new(kind: ShapeFunction, xi: [f64; 2], l: f64) -> Self {
        Weights2 {
            x: weights_1d(kind, xi[0], l),
            y: weights_1d(kind, xi[1], l),
        }
    }
    /// S for node (a, b) of the 3×3 stencil.
    #[inline(always)]
    pub fn s(&self, a: usize, b: usize) -> f64 {
        self.x.s[a] * self.y.s[b]
    }
    /// ∇S in cell units (multiply by 1/h) for node (a, b).
    #[inline(always)]
    pub fn g(&self, a: usize, b: usize) -> [f64; 2] {
        [self.x.ds[a] * self.y.s[b], self.x.s[a] * self.y.ds[b]]
    }
}

/// The shape-function weights a particle's P2G caches for the step's later passes
/// (`algorithm.md` §2 allows cached per-step quantities in f32): per direction (x, y) the
/// core's [`CachedW1`], the base and the outer nodes' S and S' rounded to f32; the middle node
/// follows from Σ S = 1 and Σ S' = 0 in f64, so the unpacked weights keep the partition of
/// unity to the last bit of f64. 40 bytes instead of `Weights2`'s 112.
pub type CachedW2 = [CachedW1; 2];

/// Packing and unpacking of [`CachedW2`] from and to the 2D [`Weights2`].
pub trait Cached2 {
    /// The cached form of `w`.
    fn pack(w: &Weights2) -> Self;
    /// The weights the passes use: the outer ones as stored, the middle from Σ S = 1, Σ S' = 0.
    fn unpack(&self) -> Weights2;
}

impl Cached2 for CachedW2 {
    #[inline(always)]
    fn pack(w: &Weights2) -> CachedW2 {
        [CachedW1::pack(&w.x), CachedW1::pack(&w.y)]
    }
    #[inline(always)]
    fn unpack(&self) -> Weights2 {
        Weights2 {
            x: self[0].unpack(),
            y: self[1].unpack(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn sums(kind: ShapeFunction, xi: [f64; 2], l: f64) -> (f64, [f64; 2]) {
        let w = Weights2::new(kind, xi, l);
        let mut s = 0.0;
        let mut g = [0.0; 2];
        for a in 0..3 {
            for b in 0..3 {
                s += w.s(a, b);
                let gg = w.g(a, b);
                g[0] += gg[0];
                g[1] += gg[1];
            }
        }
        (s, g)
    }

    proptest! {
        // algorithm.md §1: Σ S = 1 and Σ ∇S = 0 at every point inside the grid, for every
        // particle size of 1..4 particles per cell.
        #[test]
        fn partition_of_unity_gimp(x in 2.0f64..50.0, y in 2.0f64..50.0, ppc in 1u32..5) {
            let l = 0.5 / ppc as f64;
            let (s, g) = sums(ShapeFunction::Gimp, [x, y], l);
            prop_assert!((s - 1.0).abs() < 1e-12, "sum S = {s}");
            prop_assert!(g[0].abs() < 1e-12 && g[1].abs() < 1e-12, "sum G = {g:?}");
        }

        #[test]
        fn partition_of_unity_linear(x in 2.0f64..50.0, y in 2.0f64..50.0) {
            let (s, g) = sums(ShapeFunction::Linear, [x, y], 0.25);
            prop_assert!((s - 1.0).abs() < 1e-12);
            prop_assert!(g[0].abs() < 1e-12 && g[1].abs() < 1e-12);
        }

        // The cached (f32) weights: every S and S' within f32 rounding of the f64 ones
        // (|Δ| ≤ 2⁻²³ for the outer nodes, two of those for the middle one), the partition of
        // unity kept to f64 rounding, the empty last node still exactly empty (the passes skip
        // it on S = 0), for both shape functions.
        #[test]
        fn cached_weights_keep_the_partition_of_unity(
            x in 2.0f64..50.0, y in 2.0f64..50.0, ppc in 1u32..5, gimp in proptest::bool::ANY,
        ) {
            let kind = if gimp { ShapeFunction::Gimp } else { ShapeFunction::Linear };
            let w = Weights2::new(kind, [x, y], 0.5 / ppc as f64);
            let c = CachedW2::pack(&w).unpack();
            let (mut s, mut g) = (0.0, [0.0; 2]);
            for a in 0..3 {
                for b in 0..3 {
                    s += c.s(a, b);
                    g[0] += c.g(a, b)[0];
                    g[1] += c.g(a, b)[1];
                }
            }
            prop_assert!((s - 1.0).abs() < 1e-12, "sum S = {s}");
            prop_assert!(g[0].abs() < 1e-12 && g[1].abs() < 1e-12, "sum G = {g:?}");
            for (e, f) in [(&w.x, &c.x), (&w.y, &c.y)] {
                prop_assert_eq!(e.base, f.base);
                for k in 0..3 {
                    let tol = if k == 1 { 4.0 } else { 2.0 } * f64::from(f32::EPSILON);
                    prop_assert!((e.s[k] - f.s[k]).abs() <= tol, "S {k}: {} vs {}", e.s[k], f.s[k]);
                    prop_assert!((e.ds[k] - f.ds[k]).abs() <= 2.0 * tol, "S' {k}");
                }
                for k in [0, 2] {
                    prop_assert_eq!(e.s[k] == 0.0, f.s[k] == 0.0);
                }
            }
        }

        // The derivative is the derivative: central differences agree to O(ε²).
        #[test]
        fn gimp_derivative_matches_difference(d in -1.6f64..1.6, ppc in 1u32..5) {
            let l = 0.5 / ppc as f64;
            let eps = 1e-6;
            // Skip the kink points of S' (|d| = l, 1−l, 1+l) where the difference straddles.
            let a = d.abs();
            prop_assume!([l, 1.0 - l, 1.0 + l].iter().all(|k| (a - k).abs() > 1e-4));
            let num = (gimp(d + eps, l).0 - gimp(d - eps, l).0) / (2.0 * eps);
            prop_assert!((num - gimp(d, l).1).abs() < 1e-6, "d={d} l={l}: {num} vs {}", gimp(d, l).1);
        }
    }

    proptest! {
        #[test]
        fn fast_floor_is_floor(x in -1.0e6f64..1.0e6) {
            prop_assert_eq!(fast_floor(x), x.floor());
            prop_assert_eq!(fast_floor(x.floor()), x.floor());
        }

        // The fast 1D weights equal the branch-by-branch GIMP formula at every node.
        #[test]
        fn fast_weights_match_reference(xi in 1.0f64..60.0, ppc in 1u32..5) {
            let l = 0.5 / ppc as f64;
            let w = weights_1d(ShapeFunction::Gimp, xi, l);
            for k in 0..3 {
                let (s, ds) = gimp(xi - (w.base + k as i32) as f64, l);
                prop_assert!((w.s[k] - s).abs() < 1e-12, "S node {k}: {} vs {s}", w.s[k]);
                prop_assert!((w.ds[k] - ds).abs() < 1e-12, "S' node {k}: {} vs {ds}", w.ds[k]);
            }
        }

        // The stencil holds every node the particle reaches, its first node always carries
        // weight, and only its last node can be empty (the hot loops skip an empty last
        // column and row, so a two-node particle must have its empty node last).
        #[test]
        fn stencil_holds_every_reached_node_empty_last(xi in 1.0f64..60.0, ppc in 1u32..5) {
            let l = 0.5 / ppc as f64;
            let w = weights_1d(ShapeFunction::Gimp, xi, l);
            for outside in [w.base - 1, w.base + 3] {
                let (s, ds) = gimp(xi - outside as f64, l);
                prop_assert!(s == 0.0 && ds == 0.0, "node {outside} outside the stencil has S = {s}");
            }
            prop_assert!(w.s[0] > 0.0, "first node empty at xi = {xi}, l = {l}");
            prop_assert!(w.s[1] > 0.0, "middle node empty at xi = {xi}, l = {l}");
            let f = xi - xi.floor();
            let reached = if f < l || f > 1.0 - l { 3 } else { 2 };
            prop_assert_eq!(w.s.iter().filter(|&&s| s > 0.0).count(), reached, "xi = {}, l = {}", xi, l);
        }
    }

    #[test]
    fn gimp_is_continuous_across_piecewise_boundaries() {
        // S and dS/dd are continuous at |d| = l, 1 − l and 1 + l (GIMP is C¹ in S).
        for ppc in 1..=4 {
            let l = 0.5 / ppc as f64;
            for k in [l, 1.0 - l, 1.0 + l] {
                for sign in [-1.0, 1.0] {
                    let at = sign * k;
                    let lo = gimp(at - 1e-12, l);
                    let hi = gimp(at + 1e-12, l);
                    assert!((lo.0 - hi.0).abs() < 1e-9, "S jumps at {at} (l={l})");
                    assert!((lo.1 - hi.1).abs() < 1e-9, "S' jumps at {at} (l={l})");
                }
            }
        }
    }

    #[test]
    fn weights_continuous_when_particle_crosses_cell_half() {
        // Moving the particle across the stencil switch (f = ½) must not change any node's
        // weight: the node set changes only where the dropped node's weight is zero.
        let l = 0.25;
        let a = weights_1d(ShapeFunction::Gimp, 10.5 - 1e-12, l);
        let b = weights_1d(ShapeFunction::Gimp, 10.5 + 1e-12, l);
        let node_w = |w: &Weights1, node: i32| {
            (0..3)
                .find(|&k| w.base + k as i32 == node)
                .map_or(0.0, |k| w.s[k])
        };
        for node in 8..14 {
            assert!(
                (node_w(&a, node) - node_w(&b, node)).abs() < 1e-9,
                "node {node}"
            );
        }
    }
}
