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

/// All particles (the core's [`fracture_mpm::particles::Particles`] in 2D: stress (xx, yy,
/// xy, zz) in Pa, `grad_u` = (∂ux/∂x, ∂ux/∂y, ∂uy/∂x, ∂uy/∂y), `fmask` bit 3a + b for the
/// pair (a, b) of the 3×3 stencil).
pub type Particles = fracture_mpm::particles::Particles<Dim2>;

/// Mutable views of a contiguous range of particles, splittable for parallel recursion.
pub type PartsMut<'a> = fracture_mpm::particles::PartsMut<'a, Dim2>;
