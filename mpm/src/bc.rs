//! Velocity conditions resolved to grid nodes (`algorithm.md` §2): the nodes inside a
//! condition's region, the prescribed components at a time (with the ramp and the active
//! interval), and a moving condition's nodes re-resolved as its region moves. Applying them
//! to the momenta and forces is `gridops::hold_momentum` and `gridops::hold_force`.

use crate::dim::Dim;
use crate::grid::GridGeom;
use crate::state::{BcNodes, BcSpec, Region};

/// The nodes of `region` translated by `shift`.
pub fn nodes_in<D: Dim>(region: &Region<D>, shift: &D::V, geom: &GridGeom<D>) -> Vec<u32> {
    let mut lo = [0usize; 3];
    let mut hi = [0usize; 3];
    for d in 0..D::N {
        let a = (region.lo.as_ref()[d] + shift.as_ref()[d] - geom.origin.as_ref()[d]) * geom.inv_h;
        let b = (region.hi.as_ref()[d] + shift.as_ref()[d] - geom.origin.as_ref()[d]) * geom.inv_h;
        let n = geom.n.as_ref()[d];
        // One node of margin each side: `contains` decides, not the rounding of ξ.
        let first = (a.ceil() - 1.0).max(0.0);
        let last = (b.floor() + 1.0).min(n as f64 - 1.0);
        if !(first.is_finite() && last.is_finite()) || last < first {
            return Vec::new();
        }
        lo[d] = first as usize;
        hi[d] = last as usize;
    }
    let mut out = Vec::new();
    let mut i = D::U::default();
    let (nz0, nz1) = if D::N == 3 { (lo[2], hi[2]) } else { (0, 0) };
    for ix in lo[0]..=hi[0] {
        for iy in lo[1]..=hi[1] {
            for iz in nz0..=nz1 {
                i.as_mut()[0] = ix;
                i.as_mut()[1] = iy;
                if D::N == 3 {
                    i.as_mut()[2] = iz;
                }
                let p = geom.node_pos(&i);
                let mut q = p;
                for d in 0..D::N {
                    q.as_mut()[d] -= shift.as_ref()[d];
                }
                if (region.contains)(&q) {
                    out.push(geom.index(&i) as u32);
                }
            }
        }
    }
    out
}

impl<D: Dim> BcNodes<D> {
    /// The condition `spec` with the nodes inside its region.
    pub fn new(spec: BcSpec<D>, geom: &GridGeom<D>) -> Self {
        BcNodes {
            nodes: nodes_in(&spec.region, &D::V::default(), geom),
            spec,
            shift: D::V::default(),
        }
    }

    /// The displacement of the prescribed components from 0 to `t` (closed form of the ramp).
    pub fn displacement(&self, t: f64) -> D::V {
        let s = &self.spec;
        let mut out = D::V::default();
        let (a, b) = (s.start, t.min(s.end));
        if b <= a {
            return out;
        }
        let r = s.ramp;
        let big_f = |tau: f64| {
            if r <= 0.0 {
                tau
            } else if tau <= r {
                tau * tau / (2.0 * r)
            } else {
                0.5 * r + (tau - r)
            }
        };
        let dist = big_f(b) - big_f(a);
        for d in 0..D::N {
            out.as_mut()[d] = s.velocity[d].unwrap_or(0.0) * dist;
        }
        out
    }

    /// Prescribed components at time t (None where free or inactive).
    pub fn velocity(&self, t: f64) -> [Option<f64>; 3] {
        let s = &self.spec;
        if t < s.start || t > s.end {
            return [None; 3];
        }
        let r = if s.ramp > 0.0 {
            (t / s.ramp).min(1.0)
        } else {
            1.0
        };
        [
            s.velocity[0].map(|v| v * r),
            s.velocity[1].map(|v| v * r),
            s.velocity[2].map(|v| v * r),
        ]
    }

    /// A moving condition: its nodes for the displacement at `t` (the nearest face, as 2D).
    pub fn follow(&mut self, t: f64, geom: &GridGeom<D>) {
        if !self.spec.moving {
            return;
        }
        let d = self.displacement(t);
        // |d| by hypot (the 2D solver's, before the core).
        let dv = d.as_ref();
        let mut len = dv[0].abs();
        for v in &dv[1..D::N] {
            len = len.hypot(*v);
        }
        let mut shift = d;
        if len > 0.0 {
            let k = 1.0 + 0.5 * geom.h / len;
            for v in shift.as_mut() {
                *v *= k;
            }
        }
        if shift != self.shift {
            self.nodes = nodes_in(&self.spec.region, &shift, geom);
            self.shift = shift;
        }
    }
}
