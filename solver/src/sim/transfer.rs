//! The four particle passes of a step (`algorithm.md` §2, USAVG): the core's
//! (`fracture_mpm::passes`, written once over the dimension and the particle's stencil, the
//! fast field-0 path or the generic path through the crack fields), run by the simulation's
//! `Backend<Dim2>` with the crack layer's data (field masks, the field-1 slot map, the
//! mass-weighted displacement of the P2G, ∇u of the stress updates):
//! 1. [`pass_p2g`](Simulation::pass_p2g): weights, mass, momentum and (with cracks)
//!    mass-weighted displacement to the grid.
//! 2. [`pass_forces`](Simulation::pass_forces): velocity gradient from p/m, first stress
//!    half-update, internal and external forces to the grid.
//! 3. [`pass_update`](Simulation::pass_update): FLIP velocity, position from the mid-step grid
//!    velocity, re-extrapolation of momentum with the same weights and fields (pitfall 2).
//! 4. [`pass_strain_last`](Simulation::pass_strain_last): velocity gradient from q/m, second
//!    stress half-update, positions committed.

use fracture_api::scene::ShapeFunction;
use fracture_mpm::passes::{Grid, PassCx};

use super::Simulation;
use crate::grid::Reduce;

/// Reduction of a particle pass: partial sums and the first offending particle.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Acc {
    /// Kinetic energy (pass 3) or strain energy (pass 4).
    pub(super) e: f64,
    /// External work of tractions (pass 3).
    pub(super) w: f64,
    /// A particle drifted too far from its strip: re-sort before the next scatter.
    pub(super) resort: bool,
    /// First failure: (sorted index, kind).
    pub(super) fail: Option<(usize, u8)>,
    /// Active box in node columns/rows.
    pub(super) bx: [i64; 4],
    /// Whether `bx` is set.
    pub(super) has_box: bool,
}

impl Reduce for Acc {
    fn merge(self, r: Self) -> Self {
        let bx = match (self.has_box, r.has_box) {
            (true, true) => [
                self.bx[0].min(r.bx[0]),
                self.bx[1].max(r.bx[1]),
                self.bx[2].min(r.bx[2]),
                self.bx[3].max(r.bx[3]),
            ],
            (true, false) => self.bx,
            _ => r.bx,
        };
        Acc {
            e: self.e + r.e,
            w: self.w + r.w,
            resort: self.resort || r.resort,
            fail: match (self.fail, r.fail) {
                (Some(a), Some(b)) => Some(if a.0 <= b.0 { a } else { b }),
                (a, b) => a.or(b),
            },
            bx,
            has_box: self.has_box || r.has_box,
        }
    }
}

impl Acc {
    /// The 2D reduction of a core pass's (active box as [ix0, ix1, iy0, iy1]).
    fn of(a: fracture_mpm::passes::Acc) -> Acc {
        Acc {
            e: a.e,
            w: a.w,
            resort: a.resort,
            fail: a.fail,
            bx: [a.lo[0], a.hi[0], a.lo[1], a.hi[1]],
            has_box: a.has_box,
        }
    }
}

/// The pass context of the simulation `$s` (its fields borrowed one by one, so that the
/// particles and the grid can be borrowed mutably beside it).
macro_rules! pass_cx {
    ($s:ident) => {
        PassCx {
            geom: $s.geom,
            shape: $s.shape,
            kernel: $s.kernel,
            dt: $s.dt,
            mats: &$s.mats,
            loads: &$s.load_now,
            bounds: &$s.strip_bounds,
            slot_of: &$s.slot_of,
            displacement: $s.cracks.is_some(),
            fast: $s.shape == ShapeFunction::Gimp && !$s.generic_stencil,
        }
    };
}

/// The grid of the simulation `$s`: field-0 and field-1 nodes.
macro_rules! grid {
    ($s:ident) => {
        Grid {
            nodes: &mut $s.nodes,
            f1: &mut $s.f1,
            f1_index: &$s.f1_index,
        }
    };
}

impl Simulation {
    /// Pass 1: P2G of mass, momentum and (with cracks) mass-weighted displacement.
    pub(super) fn pass_p2g(&mut self) -> Acc {
        let cx = pass_cx!(self);
        Acc::of(self.backend.p2g(&cx, &mut self.parts, &mut grid!(self)))
    }

    /// Pass 2: velocity gradient from p/m, first stress half-update, forces to the grid.
    pub(super) fn pass_forces(&mut self) -> Acc {
        let cx = pass_cx!(self);
        Acc::of(self.backend.forces(&cx, &mut self.parts, &mut grid!(self)))
    }

    /// Pass 3: FLIP particle update and re-extrapolation of the new momenta with the same
    /// weights and fields.
    pub(super) fn pass_update(&mut self) -> Acc {
        let cx = pass_cx!(self);
        Acc::of(self.backend.update(&cx, &mut self.parts, &mut grid!(self)))
    }

    /// Pass 4: velocity gradient from the re-extrapolated momenta, second stress half-update,
    /// strain energy summed. Fused with the next step's P2G
    /// ([`pass_strain_last_p2g`](Simulation::pass_strain_last_p2g)) when nothing can fall
    /// between the two.
    pub(super) fn pass_strain_last(&mut self) -> Acc {
        if self.can_fuse() {
            let (acc, next) = self.pass_strain_last_p2g();
            self.prefetched = Some(next);
            return acc;
        }
        let cx = pass_cx!(self);
        Acc::of(self.backend.strain(&cx, &mut self.parts, &mut grid!(self)))
    }

    /// Whether pass 4 may run fused with the next step's P2G: no crack (the next step's
    /// velocity fields depend on the committed positions and the crack's motion), no re-sort
    /// due (it reorders the particles before the next P2G), fusion not switched off.
    /// Observers between the steps see the same particles and the same grid (`nodes`): the
    /// next step's P2G goes to the spare grid `nodes_alt`, swapped in when that step starts.
    fn can_fuse(&self) -> bool {
        self.fuse && self.cracks.is_none() && !self.needs_sort
    }

    /// Pass 4 fused with pass 1 of the next step into the spare grid (bitwise an unfused P2G:
    /// `tests/fused_step.rs`). Returns the reduction of pass 4 and that of the next P2G.
    pub(super) fn pass_strain_last_p2g(&mut self) -> (Acc, Acc) {
        debug_assert!(self.cracks.is_none());
        self.zero_alt();
        let mut next = std::mem::take(&mut self.nodes_alt);
        let cx = pass_cx!(self);
        let (a, b) = self
            .backend
            .strain_p2g(&cx, &mut self.parts, &mut grid!(self), &mut next);
        self.nodes_alt = next;
        let (a, b) = (Acc::of(a), Acc::of(b));
        self.alt_box = self.box_of(&b);
        (a, b)
    }
}
