//! Material models. Linear elasticity in hypoelastic small-strain form (`algorithm.md` §2):
//! Δσ = C:Δε with the 2D stiffness of plane strain or plane stress, σ_zz = ν(σ_xx + σ_yy) in
//! plane strain; the strain energy density grows by the midpoint rule ΔW = ½(σ_old + σ_new):Δε.

/// 2D stiffness of one material (the core's: `c11`, `c12`, `mu` = C66, `cz`, and the stress
/// update `Dim2::stress_update` of the passes).
pub use fracture_mpm::Elastic;
