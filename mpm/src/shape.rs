//! Shape functions (`algorithm.md` §1), one direction at a time.
//!
//! Uniform GIMP (Bardenhagen & Kober 2004) with the particle half-width l = h/(2·ppc) fixed at
//! its undeformed size, and classic linear MPM. Both are evaluated in cell units
//! (ξ = (x − x_min)/h) as three 1D weights per direction, so a particle touches at most 3^D
//! nodes; the D-dimensional shape function is the tensor product S = Π S_k
//! ([`Dim::weights`](crate::Dim)). The arithmetic is the 2D solver's, to the bit.

use fracture_api::scene::ShapeFunction;

use crate::math::floor_both;

/// 1D weights of one particle: nodes `base`, `base+1`, `base+2`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Weights1 {
    /// Index of the first node.
    pub base: i32,
    /// Shape function values.
    pub s: [f64; 3],
    /// Derivatives dS/dξ (divide by h for dS/dx).
    pub ds: [f64; 3],
}

/// 1D weights at ξ (cell units from the grid origin) for half-width `l` with `q` = 1/(4l)
/// supplied (GIMP; unused by the linear function).
#[inline(always)]
pub fn weights_1d(kind: ShapeFunction, xi: f64, l: f64, q: f64) -> Weights1 {
    let (cell, icell) = floor_both(xi);
    match kind {
        ShapeFunction::Gimp => gimp_1d(cell, icell, xi, l, q),
        ShapeFunction::Linear => {
            let f = xi - cell;
            Weights1 {
                base: icell,
                s: [1.0 - f, f, 0.0],
                ds: [-1.0, 1.0, 0.0],
            }
        }
    }
}

#[inline(always)]
fn gimp_1d(cell: f64, icell: i32, xi: f64, l: f64, q: f64) -> Weights1 {
    let f = xi - cell;
    // A particle reaches node cell−1 only when f < l and node cell+2 only when f > 1 − l
    // (l ≤ ½: never both). The stencil starts at cell−1 in the first case and at cell
    // otherwise, so a particle reaching two nodes has its empty node last. With u the
    // offset from the middle node (|u| < 1) the outer weights are the GIMP branches for that
    // range; the middle one follows from Σ S = 1.
    let (base, u) = if f < l {
        (icell - 1, f)
    } else {
        (icell, f - 1.0)
    };
    let (sl, dl) = if u <= -l {
        (-u, -1.0)
    } else if u < l {
        let r = l - u;
        (q * r * r, -2.0 * q * r)
    } else {
        (0.0, 0.0)
    };
    let (sr, dr) = if u >= l {
        (u, 1.0)
    } else if u > -l {
        let r = l + u;
        (q * r * r, 2.0 * q * r)
    } else {
        (0.0, 0.0)
    };
    Weights1 {
        base,
        s: [sl, 1.0 - sl - sr, sr],
        ds: [dl, -dl - dr, dr],
    }
}

/// One direction of a particle's cached weights: the stencil base and the outer two nodes' S
/// and dS/dξ in f32 (`algorithm.md` §2 allows cached per-step quantities in f32); the middle
/// node follows from Σ S = 1 and Σ S' = 0 in f64, so the partition of unity holds to the
/// last bit of f64.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CachedW1 {
    /// Index of the first node.
    pub base: i32,
    /// S of the first and last node.
    pub s: [f32; 2],
    /// dS/dξ of the first and last node.
    pub ds: [f32; 2],
}

impl CachedW1 {
    /// The cached form of `w`.
    #[inline(always)]
    pub fn pack(w: &Weights1) -> CachedW1 {
        CachedW1 {
            base: w.base,
            s: [w.s[0] as f32, w.s[2] as f32],
            ds: [w.ds[0] as f32, w.ds[2] as f32],
        }
    }
    /// The weights the passes use: the outer ones as stored, the middle from Σ S = 1, Σ S' = 0.
    #[inline(always)]
    pub fn unpack(&self) -> Weights1 {
        let (s0, s2) = (f64::from(self.s[0]), f64::from(self.s[1]));
        let (d0, d2) = (f64::from(self.ds[0]), f64::from(self.ds[1]));
        Weights1 {
            base: self.base,
            s: [s0, 1.0 - s0 - s2, s2],
            ds: [d0, -d0 - d2, d2],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The GIMP weight of a node at signed distance d (cell units), written from the
    /// definition (Bardenhagen & Kober 2004, eq. for uniform GIMP).
    fn gimp_ref(d: f64, l: f64) -> f64 {
        let a = d.abs();
        if a < l {
            1.0 - (a * a + l * l) / (2.0 * l)
        } else if a <= 1.0 - l {
            1.0 - a
        } else if a < 1.0 + l {
            (1.0 + l - a).powi(2) / (4.0 * l)
        } else {
            0.0
        }
    }

    proptest! {
        #[test]
        fn gimp_matches_definition_and_sums_to_one(xi in 1.0f64..50.0, ppc in 1u32..5) {
            let l = 0.5 / f64::from(ppc);
            let w = weights_1d(ShapeFunction::Gimp, xi, l, 0.25 / l);
            let mut sum = 0.0;
            for k in 0..3 {
                let node = f64::from(w.base + k as i32);
                prop_assert!((w.s[k] - gimp_ref(xi - node, l)).abs() < 1e-12);
                sum += w.s[k];
            }
            prop_assert!((sum - 1.0).abs() < 1e-14);
            prop_assert!((w.ds.iter().sum::<f64>()).abs() < 1e-14);
        }

        #[test]
        fn cached_weights_keep_partition_of_unity(xi in 1.0f64..50.0) {
            let w = weights_1d(ShapeFunction::Gimp, xi, 0.25, 1.0);
            let u = CachedW1::pack(&w).unpack();
            prop_assert!((u.s.iter().sum::<f64>() - 1.0).abs() < 1e-15);
            prop_assert!((u.s[1] - w.s[1]).abs() < 1e-7);
        }
    }
}
