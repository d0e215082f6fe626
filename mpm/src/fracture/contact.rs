//! The algebra of two velocity fields at one node (Bardenhagen et al. 2000, 2001; the seed's
//! multi-velocity contact): the stick change, and the frictional contact law built on it.
//! Written once for every momentum stage and both dimensions; the crack-face contact, the
//! body contact and the process-zone and cohesive impulses of the crack layers use it.

use crate::dim::Dim;

/// The stick change Δp_a of field a's momentum that brings fields a and b to their common
/// centre-of-mass velocity: Δp_a = (m_a p_b − m_b p_a)/(m_a + m_b); field b takes −Δp_a, so
/// momentum is conserved exactly.
#[inline]
pub fn stick_change<D: Dim>(ma: f64, pa: &D::V, mb: f64, pb: &D::V) -> D::V {
    let big_m = ma + mb;
    let mut d = D::V::default();
    let (pa, pb) = (pa.as_ref(), pb.as_ref());
    for (k, dk) in d.as_mut().iter_mut().enumerate() {
        *dk = (ma * pb[k] - mb * pa[k]) / big_m;
    }
    d
}

/// The contact change of field a's momentum from the stick change `d` and the unit normal `n`
/// (from a towards b): the normal part of `d` while the fields approach (d·n < 0), plus the
/// tangential part of `d` capped by Coulomb's law at `friction × capacity` (capacity: the
/// normal impulse that presses the faces, ≥ 0).
#[inline]
pub fn coulomb_change<D: Dim>(
    d: &D::V,
    n: &D::V,
    approaching: bool,
    friction: f64,
    capacity: f64,
) -> D::V {
    let (dv, nv) = (d.as_ref(), n.as_ref());
    let mut dn = dv[0] * nv[0];
    for k in 1..D::N {
        dn += dv[k] * nv[k];
    }
    let mut out = D::V::default();
    if approaching {
        for (k, o) in out.as_mut().iter_mut().enumerate() {
            *o = dn * nv[k];
        }
    }
    if friction > 0.0 {
        let mut t = D::V::default();
        for (k, tk) in t.as_mut().iter_mut().enumerate() {
            *tk = dv[k] - dn * nv[k];
        }
        // |t| by hypot (no overflow or underflow of the squares).
        let tv = t.as_ref();
        let mut tl = tv[0].abs();
        for tk in &tv[1..] {
            tl = tl.hypot(*tk);
        }
        let limit = friction * capacity.max(0.0);
        let o = out.as_mut();
        for (k, tk) in t.as_ref().iter().enumerate() {
            o[k] += if tl > limit { limit * tk / tl } else { *tk };
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Dim2, Dim3};

    /// After the stick change both fields move with the centre-of-mass velocity and the total
    /// momentum is unchanged.
    #[test]
    fn stick_change_gives_the_common_velocity() {
        let (ma, mb) = (2.0, 3.0);
        let (pa, pb) = ([4.0, -2.0, 1.0], [-3.0, 6.0, 0.5]);
        let d = stick_change::<Dim3>(ma, &pa, mb, &pb);
        for k in 0..3 {
            let (va, vb) = ((pa[k] + d[k]) / ma, (pb[k] - d[k]) / mb);
            let vcm = (pa[k] + pb[k]) / (ma + mb);
            assert!((va - vcm).abs() < 1e-15 && (vb - vcm).abs() < 1e-15);
        }
    }

    /// Frictionless contact keeps only the normal part while approaching; with friction the
    /// tangential part is capped at μ × the normal impulse (the kinetic energy removed is
    /// never negative: the change opposes the relative tangential motion).
    #[test]
    fn coulomb_caps_the_tangential_change() {
        let n = [0.0, 1.0];
        let d = [3.0, -1.0]; // approaching (d·n < 0), sliding along x
        assert_eq!(coulomb_change::<Dim2>(&d, &n, true, 0.0, 1.0), [0.0, -1.0]);
        assert_eq!(coulomb_change::<Dim2>(&d, &n, true, 0.5, 1.0), [0.5, -1.0]);
        assert_eq!(coulomb_change::<Dim2>(&d, &n, true, 10.0, 1.0), [3.0, -1.0]);
        assert_eq!(coulomb_change::<Dim2>(&d, &n, false, 0.0, 1.0), [0.0, 0.0]);
    }
}
