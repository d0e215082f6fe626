//! Crack motion (`algorithm.md` §5): each surface point moves with the mass-weighted velocity
//! of its own side's fields on the 4 nodes of its cell; the line point takes the mean of its
//! two surfaces, and at a tip both surfaces move with the mean.

use crate::grid::{GridGeom, Node};

use super::zone::Field;
use super::{Cracks, mass_weighted_at};

impl Cracks {
    /// The field of node `index` on the same side as `from` (a point just off the crack):
    /// field 0 when the line from → node does not cross a crack, field 1 when it does.
    #[allow(clippy::too_many_arguments)]
    fn side_node<'n>(
        &self,
        geom: &GridGeom,
        from: [f64; 2],
        ix: usize,
        iy: usize,
        nodes: &'n [Node],
        f1: &'n [Node],
        slot_of: &[u32],
    ) -> Option<&'n Node> {
        match self.side_field(geom, from, ix, iy, slot_of)? {
            Field::Zero(i) => Some(&nodes[i]),
            Field::One(s) => Some(&f1[s]),
        }
    }

    /// Velocity at x of the side reached from `from`, bilinear and mass-weighted over the 4
    /// nodes of x's cell, using the re-extrapolated momenta.
    #[allow(clippy::too_many_arguments)]
    fn side_velocity(
        &self,
        geom: &GridGeom,
        x: [f64; 2],
        from: [f64; 2],
        nodes: &[Node],
        f1: &[Node],
        slot_of: &[u32],
    ) -> Option<[f64; 2]> {
        // Σ S m v = Σ S q.
        mass_weighted_at(
            geom,
            x,
            |ix, iy| self.side_node(geom, from, ix, iy, nodes, f1, slot_of),
            |n| n.q,
        )
    }

    /// Move the crack surfaces and lines with the grid velocities (§5).
    pub fn move_surfaces(
        &mut self,
        geom: &GridGeom,
        nodes: &[Node],
        f1: &[Node],
        slot_of: &[u32],
        _m_tiny: f64,
        dt: f64,
    ) {
        let eps = 1e-3 * self.h;
        for ci in 0..self.cracks.len() {
            let n = self.cracks[ci].pts.len();
            for k in 0..n {
                let c = &self.cracks[ci];
                // Local direction of the crack at point k.
                let nrm = c.local_normal(k); // above → below
                let pt = c.pts[k];
                // The side tests start just off the line on each surface's own side. A
                // surface pressed past the line (contact leaves an overlap of a few 1e-3 h)
                // is lifted back over it: from a point on the wrong side both surfaces would
                // take the same field, and the faces would stop sliding (seen at 0.125 mm
                // cells, where a 0.25 µm overlap is 2·eps: the Rosakis bond's slip froze).
                let up = [-nrm[0], -nrm[1]];
                let off = |s: [f64; 2]| (s[0] - pt.x[0]) * up[0] + (s[1] - pt.x[1]) * up[1];
                let lift_a = eps - off(pt.above).min(0.0);
                let lift_b = eps + off(pt.below).max(0.0);
                let from_above = [pt.above[0] + lift_a * up[0], pt.above[1] + lift_a * up[1]];
                let from_below = [pt.below[0] - lift_b * up[0], pt.below[1] - lift_b * up[1]];
                let va = self.side_velocity(geom, pt.above, from_above, nodes, f1, slot_of);
                let vb = self.side_velocity(geom, pt.below, from_below, nodes, f1, slot_of);
                let (va, vb) = match (va, vb) {
                    (Some(a), Some(b)) => (a, b),
                    (Some(a), None) => (a, a),
                    (None, Some(b)) => (b, b),
                    (None, None) => continue,
                };
                let is_tip = (k == 0 && c.tips[0].active) || (k == n - 1 && c.tips[1].active);
                let p = &mut self.cracks[ci].pts[k];
                if is_tip {
                    // The faces meet at a tip: both surfaces move with the mean.
                    let v = [0.5 * (va[0] + vb[0]), 0.5 * (va[1] + vb[1])];
                    p.x = [p.x[0] + dt * v[0], p.x[1] + dt * v[1]];
                    p.above = p.x;
                    p.below = p.x;
                } else {
                    p.above = [p.above[0] + dt * va[0], p.above[1] + dt * va[1]];
                    p.below = [p.below[0] + dt * vb[0], p.below[1] + dt * vb[1]];
                    p.x = [
                        0.5 * (p.above[0] + p.below[0]),
                        0.5 * (p.above[1] + p.below[1]),
                    ];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use crate::grid::Node;

    /// A crack along x at mid-cell; the material above moves at +1 m/s along x and the
    /// material below at −1 m/s (on each node, field 0 holds the node's own side and field 1
    /// the other side). Each surface of a crack point moves with its own side's material,
    /// also when contact has left the faces overlapping by several eps = 10⁻³ h: the surface
    /// above lies below the line then, and a side test started from just off that surface
    /// would take the other side's field (the faces stop sliding; seen on the Rosakis bond at
    /// 0.125 mm cells). The test fails without the lift of `move_surfaces`.
    #[test]
    fn overlapping_surfaces_still_move_with_their_own_sides() {
        let h = 1.0e-3;
        let y = 10.5e-3;
        let dt = 1.0e-8;
        let (geom, mut cracks) = super::super::test_cracks(
            h,
            [0.02, 0.021],
            [[0.002, 0.002], [0.018, 0.019]],
            "cracks",
            serde_json::json!([{"points": [[0.0, y], [0.0105, y]]}]),
        );
        cracks.build_broad_phase(&geom);
        let storage = geom.at(geom.nx() - 1, geom.ny() - 1) + 1;
        let (mut nodes, mut f1) = (
            vec![Node::default(); storage],
            vec![Node::default(); storage],
        );
        let mut slot_of = vec![u32::MAX; storage];
        for ix in 0..geom.nx() {
            for iy in 0..geom.ny() {
                let i = geom.at(ix, iy);
                let own = if geom.pos(ix, iy)[1] > y { 1.0 } else { -1.0 };
                nodes[i] = Node {
                    m: 1.0,
                    q: [own, 0.0],
                    ..Node::default()
                };
                f1[i] = Node {
                    m: 1.0,
                    q: [-own, 0.0],
                    ..Node::default()
                };
                slot_of[i] = i as u32;
            }
        }
        // A face point away from the tip and the mouth, its faces pressed 3 eps past each other.
        let k = cracks.cracks[0].pts.len() / 2;
        let overlap = 3.0e-3 * h;
        let p = &mut cracks.cracks[0].pts[k];
        let x = p.x;
        p.above = [x[0], x[1] - overlap];
        p.below = [x[0], x[1] + overlap];
        cracks.move_surfaces(&geom, &nodes, &f1, &slot_of, 0.0, dt);
        let p = cracks.cracks[0].pts[k];
        assert!(
            (p.above[0] - (x[0] + dt)).abs() < 1e-15,
            "above moved to {:?}",
            p.above
        );
        assert!(
            (p.below[0] - (x[0] - dt)).abs() < 1e-15,
            "below moved to {:?}",
            p.below
        );
    }
}
