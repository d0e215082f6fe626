//! Velocity fields per node (`algorithm.md` §3, CRAMP): each particle's field mask (which of
//! its nodes it reaches across a crack), and the sorted field-1 node table with a
//! [`SlotInfo`] per node (side, contact normal, crack).

use fracture_api::scene::ShapeFunction;

use rayon::prelude::*;

use crate::grid::GridGeom;
use crate::particles::{Cold, Kin, Mech};
use crate::shape::Weights2;

use super::Cracks;
use super::geometry::{left, left_d, norm, sub};

/// A field-1 pair found by the crossing test: storage index of the node, crack, side of the
/// particle (+1 above, −1 below), normal of the crossed segment.
pub(super) type FieldEntry = (u32, u32, i32, [f64; 2]);

/// The `crack` of a field-1 slot that holds a body with a contact law (body-to-body contact,
/// `Body::contact`) rather than one side of a crack.
pub const BODY_CONTACT: u32 = u32::MAX;

/// Entries of one chunk of the parallel mask pass and its first error (node, fields needed).
pub(super) type ChunkEntries = (Vec<FieldEntry>, Option<(usize, u32)>);

/// Field-1 node record: which side field 1 holds, the contact normal, the crack.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SlotInfo {
    /// Field 1 holds the particles above (left of) the crack.
    pub above_is_f1: bool,
    /// Unit normal from above to below.
    pub normal: [f64; 2],
    /// Crack index, or [`BODY_CONTACT`] where field 1 holds the contact bodies.
    pub crack: u32,
}

/// A crack segment near a particle (`Cracks::masks`): crack and segment index, the crack's
/// group, the end points a and b, d = b − a, and whether the particle lies left of a → b.
struct NearSeg {
    ci: u32,
    si: u32,
    group: u32,
    a: [f64; 2],
    b: [f64; 2],
    d: [f64; 2],
    p_left: bool,
}

impl Cracks {
    /// Field masks of the particles `kin`/`mech` into `fmask`, and the field-1 entries
    /// (node, crack, side vote, crossed-segment normal) in particle order. `seg_box`: the box
    /// of the cells holding a segment (`build_broad_phase`).
    #[allow(clippy::too_many_arguments)]
    fn masks(
        &self,
        geom: &GridGeom,
        shape: ShapeFunction,
        seg_box: Option<[f64; 4]>,
        kin: &[Kin],
        mech: &[Mech],
        cold: &[Cold],
        fmask: &mut [u16],
        entries: &mut Vec<FieldEntry>,
    ) -> Result<(), (usize, u32)> {
        let cell = self.h;
        let mut near: Vec<NearSeg> = Vec::new();
        // Scenes without contact bodies never read the particles' body index.
        let any_contact = self.contact_bodies.contains(&true);
        for (i, ((k, m), c)) in kin.iter().zip(mech).zip(cold).enumerate() {
            if any_contact && self.contact_bodies.get(c.body as usize) == Some(&true) {
                // A contact body's particle reaches all its nodes in field 1. The slots'
                // normals come from the nodal masses (`Cracks::body_normals`).
                let w = Weights2::new(shape, geom.xi(&k.x), m.lh);
                let mut mask = 0u16;
                for a in 0..3 {
                    for b in 0..3 {
                        if w.x.s[a] * w.y.s[b] == 0.0 {
                            continue;
                        }
                        let ix = (w.x.base + a as i32) as usize;
                        let iy = (w.y.base + b as i32) as usize;
                        mask |= 1 << (3 * a + b);
                        entries.push((geom.at(ix, iy) as u32, BODY_CONTACT, -1, [0.0, 0.0]));
                    }
                }
                fmask[i] = mask;
                continue;
            }
            // Most particles lie outside the box of cells holding a segment, where
            // `segs_near` finds none (a NaN ξ is not outside and takes the full look-up).
            let xi = geom.xi(&k.x);
            let outside = seg_box
                .is_none_or(|b| xi[0] < b[0] || xi[0] >= b[1] || xi[1] < b[2] || xi[1] >= b[3]);
            if outside {
                debug_assert!(self.segs_near(geom, k.x).is_empty());
                fmask[i] = 0;
                continue;
            }
            let segs = self.segs_near(geom, k.x);
            if segs.is_empty() {
                fmask[i] = 0;
                continue;
            }
            // The particle's side of each nearby segment, once for its nine nodes.
            near.clear();
            near.extend(segs.iter().map(|&(ci, si)| {
                let c = &self.cracks[ci as usize];
                let (a, b) = (c.pts[si as usize].x, c.pts[si as usize + 1].x);
                let d = sub(b, a);
                NearSeg {
                    ci,
                    si,
                    group: c.group,
                    a,
                    b,
                    d,
                    p_left: left_d(a, d, k.x),
                }
            }));
            let w = Weights2::new(shape, geom.xi(&k.x), m.lh);
            let mut mask = 0u16;
            for a in 0..3 {
                if w.x.s[a] == 0.0 && w.x.ds[a] == 0.0 {
                    continue;
                }
                for b in 0..3 {
                    if w.y.s[b] == 0.0 && w.y.ds[b] == 0.0 {
                        continue;
                    }
                    let ix = (w.x.base + a as i32) as usize;
                    let iy = (w.y.base + b as i32) as usize;
                    let node = geom.pos(ix, iy);
                    // Parity of crossings per crack; side and normal of the last crossing.
                    let mut hit: Option<(u32, u32, bool, [f64; 2])> = None;
                    let mut other_crack = false;
                    for s in &near {
                        // A crack and the interface that continues it are one line with one
                        // pair of fields: crossings count per group. The crossing test of
                        // `geometry::crosses(k.x, node, s.a, s.b)`, its first orientation
                        // taken from `near`.
                        let g = s.group;
                        if s.p_left != left_d(s.a, s.d, node)
                            && left(k.x, node, s.a) != left(k.x, node, s.b)
                        {
                            let c = &self.cracks[s.ci as usize];
                            match &mut hit {
                                None => hit = Some((g, 1, s.p_left, c.contact_normal(s.si, cell))),
                                Some(h) if h.0 == g => {
                                    h.1 += 1;
                                    h.2 = s.p_left;
                                    h.3 = c.contact_normal(s.si, cell);
                                }
                                Some(_) => other_crack = true,
                            }
                        }
                    }
                    if let Some((ci, count, above, n)) = hit
                        && count % 2 == 1
                    {
                        if other_crack {
                            return Err((geom.at(ix, iy), 3));
                        }
                        mask |= 1 << (3 * a + b);
                        entries.push((geom.at(ix, iy) as u32, ci, if above { 1 } else { -1 }, n));
                    }
                }
            }
            fmask[i] = mask;
        }
        Ok(())
    }

    /// Assign the velocity field of every particle–node pair (§3); fills `f1_index` with the
    /// sorted storage indices of nodes needing field 1 and `self.slots` with their records.
    /// Err((node, fields)) when a node would need more than two fields.
    #[allow(clippy::too_many_arguments)]
    pub fn assign_fields(
        &mut self,
        geom: &GridGeom,
        shape: ShapeFunction,
        kin: &[Kin],
        mech: &[Mech],
        cold: &[Cold],
        fmask: &mut [u16],
        f1_index: &mut Vec<u32>,
    ) -> Result<(), (usize, u32)> {
        let seg_box = self.build_broad_phase(geom);
        // Masks and field-1 entries per chunk of particles, in parallel; the chunks' entries
        // are concatenated in particle order, so the result is the same for any thread count.
        const CHUNK: usize = 4096;
        let mut chunks = std::mem::take(&mut self.chunk_entries);
        chunks.resize_with(kin.len().div_ceil(CHUNK), Default::default);
        let this = &*self;
        fmask
            .par_chunks_mut(CHUNK)
            .zip(kin.par_chunks(CHUNK))
            .zip(mech.par_chunks(CHUNK))
            .zip(cold.par_chunks(CHUNK))
            .zip(chunks.par_iter_mut())
            .for_each(|((((fm, kn), me), co), (entries, err))| {
                entries.clear();
                *err = None;
                if let Err(e) = this.masks(geom, shape, seg_box, kn, me, co, fm, entries) {
                    *err = Some(e);
                }
            });
        let mut entries = std::mem::take(&mut self.entries);
        entries.clear();
        let mut first_error = None;
        for (chunk, err) in &chunks {
            if let Some(e) = err {
                first_error = Some(*e);
                break;
            }
            entries.extend_from_slice(chunk);
        }
        self.chunk_entries = chunks;
        if let Some(e) = first_error {
            self.entries = entries;
            return Err(e);
        }
        entries.sort_unstable_by_key(|e| (e.0, e.1));
        f1_index.clear();
        self.slots.clear();
        let mut i = 0;
        while i < entries.len() {
            let node = entries[i].0;
            let crack = entries[i].1;
            let mut votes = 0i64;
            let mut n = [0.0; 2];
            while i < entries.len() && entries[i].0 == node {
                if entries[i].1 != crack {
                    return Err((node as usize, 3));
                }
                votes += entries[i].2 as i64;
                n[0] += entries[i].3[0];
                n[1] += entries[i].3[1];
                i += 1;
            }
            let l = norm(n);
            f1_index.push(node);
            self.slots.push(SlotInfo {
                above_is_f1: votes >= 0,
                normal: if l > 0.0 {
                    [n[0] / l, n[1] / l]
                } else {
                    [0.0, -1.0]
                },
                crack,
            });
        }
        self.entries = entries;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    /// An interface along x whose points wiggle by ±0.3 µm (the means of two overlapping
    /// surfaces do) at 0.125 mm cells: one h/2 segment's normal tilts by about 0.01 rad, the
    /// contact normal (the chord over the node's support) by less than a tenth of that.
    #[test]
    fn an_interfaces_contact_normal_ignores_a_sub_cell_wiggle() {
        let h = 1.25e-4;
        let y = 5.0625e-3;
        let (_, mut cracks) = super::super::test_cracks(
            h,
            [0.01, 0.01],
            [[0.001, 0.001], [0.009, 0.009]],
            "interfaces",
            serde_json::json!([{"points": [[0.002, y], [0.008, y]],
                                "cohesive": {"law": "linear",
                                             "normal": {"strength": 1.0e6, "toughness": 10.0},
                                             "shear": {"strength": 1.0e6, "toughness": 10.0}}}]),
        );
        let c = cracks.cracks.iter_mut().find(|c| c.interface).unwrap();
        for (k, p) in c.pts.iter_mut().enumerate() {
            p.x[1] += if k % 2 == 0 { 0.3e-6 } else { -0.3e-6 };
        }
        let si = c.pts.len() / 2;
        let seg = crate::crack::geometry::seg_normal(c.pts[si].x, c.pts[si + 1].x);
        let chord = c.contact_normal(si as u32, h);
        assert!(seg[0].abs() > 5e-3, "the wiggle tilts a segment: {seg:?}");
        assert!(
            chord[0].abs() < 0.1 * seg[0].abs(),
            "chord {chord:?}, segment {seg:?}"
        );
        assert!((chord[1].abs() - 1.0).abs() < 1e-9);
    }
}
