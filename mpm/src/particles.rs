//! Particles as structure-of-arrays, grouped by the pass that reads them: kinematics,
//! mechanics, stress, strain energy density, cold metadata, and the step's cached weights.
//! Kept sorted by cell (x-plane major) so the scatter to the grid is a strip-coloured
//! parallel loop (`grid.rs`).

use serde::{Deserialize, Serialize};

use crate::dim::Dim;
use crate::grid::SplitParts;

/// Position and velocity.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(bound = "")]
pub struct Kin<D: Dim> {
    /// Position (m).
    pub x: D::V,
    /// Velocity (m/s).
    pub v: D::V,
}

/// Per-particle mechanical data.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Mech {
    /// Mass (kg; in 2D per the scene's thickness).
    pub m: f64,
    /// Undeformed volume (m³; in 2D per the scene's thickness).
    pub vol: f64,
    /// Half-width l in cell units (1/(2·ppc)).
    pub lh: f64,
    /// Material index.
    pub mat: u32,
    /// 1 + index of the load acting on the particle, 0 for none.
    pub load: u32,
}

/// Cold metadata, read for output and diagnostics only.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(bound = "")]
pub struct Cold<D: Dim> {
    /// Initial position (m), for displacements.
    pub x0: D::V,
    /// Index of the particle in creation order (stable across re-sorting).
    pub id: u32,
    /// Body index.
    pub body: u32,
}

/// All particles.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(bound = "")]
pub struct Particles<D: Dim> {
    /// Position and velocity.
    pub kin: Vec<Kin<D>>,
    /// Mechanical data.
    pub mech: Vec<Mech>,
    /// Stress (Pa): 2D (xx, yy, xy, zz), 3D (xx, yy, zz, yz, xz, xy).
    pub stress: Vec<D::S>,
    /// Metadata.
    pub cold: Vec<Cold<D>>,
    /// Strain energy density W (J/m³).
    pub wden: Vec<f64>,
    /// Shape-function weights of the step in progress, computed by the P2G and reused by the
    /// later passes (which must use the same weights, `algorithm.md` pitfall 2). Scratch of
    /// the step: not in checkpoints.
    #[serde(skip)]
    pub wts: Vec<D::C>,
    /// Displacement gradient ∂u_r/∂x_c (row-major, as `Dim::L`), accumulated as Σ L·Δt; only
    /// the J-integral needs it, so it is empty (never computed) when the scene has no cracks.
    pub grad_u: Vec<D::L>,
    /// Crack field of each particle–node pair (bit k of the stencil's pair k, x outer: set
    /// means the pair uses velocity field 1). Empty when the scene has no cracks.
    pub fmask: Vec<D::Mask>,
}

impl<D: Dim> Particles<D> {
    /// Number of particles.
    pub fn len(&self) -> usize {
        self.kin.len()
    }
    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.kin.is_empty()
    }
    /// Add one particle at rest in stress.
    pub fn push(&mut self, kin: Kin<D>, mech: Mech, cold: Cold<D>) {
        self.kin.push(kin);
        self.mech.push(mech);
        self.stress.push(D::S::default());
        self.cold.push(cold);
        self.wden.push(0.0);
        self.wts.push(D::C::default());
    }
}

/// Mutable views of a contiguous range of particles, splittable for parallel recursion.
pub struct PartsMut<'a, D: Dim> {
    /// Kinematics.
    pub kin: &'a mut [Kin<D>],
    /// Mechanical data.
    pub mech: &'a mut [Mech],
    /// Stress.
    pub stress: &'a mut [D::S],
    /// Metadata.
    pub cold: &'a mut [Cold<D>],
    /// Strain energy densities.
    pub wden: &'a mut [f64],
    /// Field masks (empty without cracks).
    pub fmask: &'a mut [D::Mask],
    /// Displacement gradients (empty without cracks).
    pub grad_u: &'a mut [D::L],
    /// Weights of the step.
    pub wts: &'a mut [D::C],
}

impl<'a, D: Dim> PartsMut<'a, D> {
    /// Views of all particles.
    pub fn new(p: &'a mut Particles<D>) -> Self {
        PartsMut {
            kin: &mut p.kin,
            mech: &mut p.mech,
            stress: &mut p.stress,
            cold: &mut p.cold,
            wden: &mut p.wden,
            fmask: &mut p.fmask,
            grad_u: &mut p.grad_u,
            wts: &mut p.wts,
        }
    }
    /// Number of particles in the view.
    pub fn len(&self) -> usize {
        self.kin.len()
    }
    /// Whether the view is empty.
    pub fn is_empty(&self) -> bool {
        self.kin.is_empty()
    }
    /// Assert that every per-particle slice has the length of the view (the optional ones
    /// may be empty), so the compiler drops the range checks of `slice[i]` for `i < len()`.
    #[inline(always)]
    pub fn assert_lengths(&self) {
        let n = self.kin.len();
        assert!(
            self.mech.len() == n
                && self.stress.len() == n
                && self.cold.len() == n
                && self.wden.len() == n
                && self.wts.len() == n
                && (self.fmask.is_empty() || self.fmask.len() == n)
                && (self.grad_u.is_empty() || self.grad_u.len() == n),
            "particle arrays of unequal length"
        );
    }
    /// Split at particle `i` (relative to the view).
    pub fn split_at(self, i: usize) -> (PartsMut<'a, D>, PartsMut<'a, D>) {
        let (k0, k1) = self.kin.split_at_mut(i);
        let (m0, m1) = self.mech.split_at_mut(i);
        let (s0, s1) = self.stress.split_at_mut(i);
        let (c0, c1) = self.cold.split_at_mut(i);
        let (x0, x1) = self.wden.split_at_mut(i);
        let (f0, f1) = if self.fmask.is_empty() {
            (&mut [][..], &mut [][..])
        } else {
            self.fmask.split_at_mut(i)
        };
        let (w0, w1) = self.wts.split_at_mut(i);
        let (g0, g1) = if self.grad_u.is_empty() {
            (&mut [][..], &mut [][..])
        } else {
            self.grad_u.split_at_mut(i)
        };
        (
            PartsMut {
                kin: k0,
                mech: m0,
                stress: s0,
                cold: c0,
                wden: x0,
                fmask: f0,
                grad_u: g0,
                wts: w0,
            },
            PartsMut {
                kin: k1,
                mech: m1,
                stress: s1,
                cold: c1,
                wden: x1,
                fmask: f1,
                grad_u: g1,
                wts: w1,
            },
        )
    }
}

impl<D: Dim> SplitParts for PartsMut<'_, D> {
    #[inline]
    fn split_at(self, i: usize) -> (Self, Self) {
        PartsMut::split_at(self, i)
    }
}
