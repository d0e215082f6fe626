//! Material models. Linear elasticity in hypoelastic small-strain form (`algorithm.md` §2):
//! Δσ = C:Δε with the 2D stiffness of plane strain or plane stress, σ_zz = ν(σ_xx + σ_yy) in
//! plane strain; the strain energy density grows by the midpoint rule ΔW = ½(σ_old + σ_new):Δε.

use fracture_api::scene::{Analysis, Material};

use crate::kernel::{Arith, madd};

/// 2D stiffness of one material, ready for the stress update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Elastic {
    /// C11 = C22.
    pub c11: f64,
    /// C12.
    pub c12: f64,
    /// C66 = shear modulus μ.
    pub c66: f64,
    /// dσ_zz = cz·(dε_xx + dε_yy): λ in plane strain, 0 in plane stress.
    pub cz: f64,
    /// Young's modulus.
    pub e: f64,
    /// Poisson's ratio.
    pub nu: f64,
    /// Density.
    pub rho: f64,
    /// Dilatational wave speed of the 2D state.
    pub c_l: f64,
    /// E' = E/(1−ν²) (plane strain) or E (plane stress), for K from J.
    pub e_prime: f64,
}

impl Elastic {
    /// Constants of `m` in the 2D state `analysis`.
    pub fn new(m: &Material, analysis: Analysis) -> Self {
        let (e, nu, rho) = (m.youngs_modulus(), m.poissons_ratio(), m.density());
        let mu = e / (2.0 * (1.0 + nu));
        let (c11, c12, cz, e_prime) = match analysis {
            Analysis::PlaneStress => {
                let q = e / (1.0 - nu * nu);
                (q, nu * q, 0.0, e)
            }
            _ => {
                let lam = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
                (lam + 2.0 * mu, lam, lam, e / (1.0 - nu * nu))
            }
        };
        Elastic {
            c11,
            c12,
            c66: mu,
            cz,
            e,
            nu,
            rho,
            c_l: m.wave_speeds(analysis).c_l,
            e_prime,
        }
    }

    /// Update stress `s` = (xx, yy, xy, zz) for the velocity gradient `l` = [[Lxx, Lxy],
    /// [Lyx, Lyy]] over `dt`; returns the strain energy density increment.
    #[inline(always)]
    pub fn update(&self, s: &mut [f64; 4], l: [[f64; 2]; 2], dt: f64) -> f64 {
        self.update_k::<crate::kernel::Portable>(s, l, dt)
    }

    /// [`Elastic::update`] in the arithmetic `A` of a pass (`kernel.rs`): the same sums, each
    /// product-and-sum fused in the FMA build.
    #[inline(always)]
    pub(crate) fn update_k<A: Arith>(&self, s: &mut [f64; 4], l: [[f64; 2]; 2], dt: f64) -> f64 {
        let exx = l[0][0] * dt;
        let eyy = l[1][1] * dt;
        let gxy = (l[0][1] + l[1][0]) * dt;
        let old = *s;
        // Δσ = C:Δε (plane strain: σ_zz = λ(Δε_xx + Δε_yy)).
        s[0] += madd::<A>(self.c11, exx, self.c12 * eyy);
        s[1] += madd::<A>(self.c12, exx, self.c11 * eyy);
        s[2] = madd::<A>(self.c66, gxy, s[2]);
        s[3] = madd::<A>(self.cz, exx + eyy, s[3]);
        // ΔW = ½(σ_old + σ_new):Δε.
        let e = madd::<A>(old[0] + s[0], exx, (old[1] + s[1]) * eyy);
        0.5 * madd::<A>(old[2] + s[2], gxy, e)
    }
}
