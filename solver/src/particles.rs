//! Particles as structure-of-arrays, grouped by access: hot kinematics, mechanics, stress,
//! and cold metadata. Kept sorted by cell (column-major) so that the scatter to the grid is
//! a strip-coloured parallel loop (see `sim`).

use fracture_mpm::Dim2;

/// Position and velocity (the core's [`fracture_mpm::particles::Kin`] in 2D).
pub type Kin = fracture_mpm::particles::Kin<Dim2>;

/// Per-particle mechanical data (the core's).
pub use fracture_mpm::particles::Mech;

/// Cold metadata, read for output and diagnostics only (the core's
/// [`fracture_mpm::particles::Cold`] in 2D).
pub type Cold = fracture_mpm::particles::Cold<Dim2>;

/// All particles.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct Particles {
    /// Position and velocity.
    pub kin: Vec<Kin>,
    /// Mechanical data.
    pub mech: Vec<Mech>,
    /// Stress (xx, yy, xy, zz) in Pa.
    pub stress: Vec<[f64; 4]>,
    /// Metadata.
    pub cold: Vec<Cold>,
    /// Strain energy density W (J/m³), apart from `mech` so that the two stress passes,
    /// which update it, leave `mech` read-only (issue 21: arrays grouped by the pass).
    pub wden: Vec<f64>,
    /// Shape-function weights of the step in progress, computed once in the P2G pass and
    /// reused by the later passes (which must use the same weights, `algorithm.md` pitfall 2).
    /// Scratch of the step: not in checkpoints.
    #[serde(skip)]
    pub wts: Vec<crate::shape::CachedW2>,
    /// Displacement gradient (∂ux/∂x, ∂ux/∂y, ∂uy/∂x, ∂uy/∂y), accumulated as Σ L·Δt; only
    /// the J-integral needs it, so it is empty (never computed) when the scene has no cracks.
    pub grad_u: Vec<[f64; 4]>,
    /// Crack field of each particle–node pair: bit (3a + b) set means the pair (a, b) of the
    /// 3×3 stencil uses velocity field 1. Empty when the scene has no cracks.
    pub fmask: Vec<u16>,
}

impl Particles {
    /// Number of particles.
    pub fn len(&self) -> usize {
        self.kin.len()
    }
    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.kin.is_empty()
    }
}

/// Mutable views of a contiguous range of particles, splittable for parallel recursion.
pub struct PartsMut<'a> {
    /// Kinematics.
    pub kin: &'a mut [Kin],
    /// Mechanical data.
    pub mech: &'a mut [Mech],
    /// Stress.
    pub stress: &'a mut [[f64; 4]],
    /// Metadata.
    pub cold: &'a mut [Cold],
    /// Strain energy densities.
    pub wden: &'a mut [f64],
    /// Field masks (empty without cracks).
    pub fmask: &'a mut [u16],
    /// Displacement gradients (empty without cracks).
    pub grad_u: &'a mut [[f64; 4]],
    /// Weights of the step.
    pub wts: &'a mut [crate::shape::CachedW2],
}

impl<'a> PartsMut<'a> {
    /// Views of all particles.
    pub fn new(p: &'a mut Particles) -> Self {
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
    /// may be empty). Called before a particle loop, it lets the compiler drop the range
    /// checks of `slice[i]` for `i < len()`.
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
    pub fn split_at(self, i: usize) -> (PartsMut<'a>, PartsMut<'a>) {
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
