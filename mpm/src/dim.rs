//! The dimension as a type: [`Dim2`] and [`Dim3`] implement [`Dim`], whose associated types
//! are the vectors, velocity gradients, stresses and shape-function weights of that
//! dimension, and whose methods are the few pieces of arithmetic that differ between them
//! (the stress update, σ·∇S, the stencil's node visits). Everything else in the core is
//! written once over `D: Dim` (`three-d.md`, shape of the code).

use std::fmt::Debug;

use fracture_api::scene::{Analysis, Material, ShapeFunction};
use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::grid::{GridGeom, GridMut};
use crate::math::{Arith, madd};
use crate::shape::{CachedW1, Weights1, weights_1d};
use crate::stencil::{Field0, Rows, Stencil};

/// A fixed-size array of `T` (`[T; N]` for the dimension's N), read and written as a slice.
pub trait Array<T>:
    Copy + Default + Debug + PartialEq + Send + Sync + AsRef<[T]> + AsMut<[T]> + 'static
{
}
impl<T, A> Array<T> for A where
    A: Copy + Default + Debug + PartialEq + Send + Sync + AsRef<[T]> + AsMut<[T]> + 'static
{
}

/// An array that is also stored in checkpoints.
pub trait Stored<T>: Array<T> + Serialize + DeserializeOwned {}
impl<T, A> Stored<T> for A where A: Array<T> + Serialize + DeserializeOwned {}

/// Isotropic linear elasticity of one material, in the constants both dimensions use.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Elastic {
    /// Lamé's λ (3D).
    pub lambda: f64,
    /// Shear modulus μ.
    pub mu: f64,
    /// 2D: C11 = C22 of the plane state.
    pub c11: f64,
    /// 2D: C12 of the plane state.
    pub c12: f64,
    /// 2D: dσ_zz = cz·(dε_xx + dε_yy): λ in plane strain, 0 in plane stress.
    pub cz: f64,
    /// Young's modulus.
    pub e: f64,
    /// Poisson's ratio.
    pub nu: f64,
    /// Density.
    pub rho: f64,
    /// Dilatational wave speed of the state (plane strain and 3D: √((λ+2μ)/ρ)).
    pub c_l: f64,
}

impl Elastic {
    /// The constants of `m`; `analysis` chooses the 2D plane state (3D uses λ and μ).
    pub fn new(m: &Material, analysis: Analysis) -> Self {
        let (e, nu, rho) = (m.youngs_modulus(), m.poissons_ratio(), m.density());
        let mu = e / (2.0 * (1.0 + nu));
        let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let (c11, c12, cz) = match analysis {
            Analysis::PlaneStress => {
                let q = e / (1.0 - nu * nu);
                (q, nu * q, 0.0)
            }
            _ => (lambda + 2.0 * mu, lambda, lambda),
        };
        let state = if analysis == Analysis::PlaneStress {
            Analysis::PlaneStress
        } else {
            Analysis::PlaneStrain
        };
        Elastic {
            lambda,
            mu,
            c11,
            c12,
            cz,
            e,
            nu,
            rho,
            c_l: m.wave_speeds(state).c_l,
        }
    }
}

/// A spatial dimension: its arrays and the arithmetic that depends on it.
pub trait Dim: Copy + Clone + Debug + Default + PartialEq + Send + Sync + 'static {
    /// Number of spatial dimensions.
    const N: usize;
    /// Nodes of a particle's stencil (3^N).
    const STENCIL: usize;
    /// Name ("2d", "3d").
    const NAME: &'static str;
    /// A vector (position, velocity, momentum, force): `[f64; N]`.
    type V: Stored<f64>;
    /// Node counts or node indices: `[usize; N]`.
    type U: Stored<usize>;
    /// A velocity gradient L (row-major N×N: L[r·N + c] = ∂v_r/∂x_c).
    type L: Stored<f64>;
    /// A stress: 2D (xx, yy, xy, zz); 3D (xx, yy, zz, yz, xz, xy).
    type S: Stored<f64>;
    /// Shape-function weights, one [`Weights1`] per direction.
    type W: Array<Weights1>;
    /// The weights a particle caches for the step, one [`CachedW1`] per direction.
    type C: Array<CachedW1>;
    /// A particle's crack-field mask: one bit per stencil pair (set: the pair uses velocity
    /// field 1). u16 in 2D (9 pairs), u32 in 3D (27).
    type Mask: Copy
        + Default
        + Debug
        + PartialEq
        + Send
        + Sync
        + Serialize
        + DeserializeOwned
        + Into<u32>
        + 'static;
    /// The fast-path stencil of a particle whose pairs are all in field 0
    /// ([`crate::stencil`]).
    type Fast<'a>: Stencil<Self>
    where
        Self: 'a;

    /// The fast-path stencil of the cached weights `c` in the strip's grid `g`.
    fn fast<'a>(g: &'a mut GridMut<'_, Self>, geom: &GridGeom<Self>, c: &Self::C)
    -> Self::Fast<'a>;

    /// Stress half-update Δσ = C:Δε for L (in 1/s) over `dt`, returning ΔW = ½(σ_old +
    /// σ_new):Δε (the midpoint rule; `algorithm.md` §2).
    fn stress_update<A: Arith>(m: &Elastic, s: &mut Self::S, l: &Self::L, dt: f64) -> f64;

    /// σ·g for a gradient g (the nodal force is −V σ·∇S).
    fn stress_dot<A: Arith>(s: &Self::S, g: &[f64]) -> Self::V;

    /// Visit the stencil of weights `w` whose first node is `nodes[0]` (`strides`: storage
    /// strides of the directions, the last 1): `f(S, ∇S, node)`, ∇S in cell units. Order: x
    /// outer, then y, then z (the 2D solver's order). A direction's last node is skipped
    /// where it is empty (S = S' = 0: GIMP and linear weights put an empty node last); with
    /// `weighted`, every pair with S = 0 too. Visiting a pair of zero weights would only add
    /// signed zeros to sums that start at +0, so the skips change no bits.
    fn visit<N>(
        w: &Self::W,
        strides: &Self::U,
        weighted: bool,
        nodes: &mut [N],
        f: impl FnMut(f64, Self::V, &mut N),
    );

    /// The strain energy density-free check that a stress is finite.
    fn stress_finite(s: &Self::S) -> bool {
        s.as_ref().iter().all(|v| v.is_finite())
    }
}

/// The weights of a particle at ξ (cell units) with half-width `lh` and q = 1/(4·lh).
#[inline(always)]
pub fn weights<D: Dim>(kind: ShapeFunction, xi: &D::V, lh: f64, q: f64) -> D::W {
    let mut w = D::W::default();
    for (k, wk) in w.as_mut().iter_mut().enumerate() {
        *wk = weights_1d(kind, xi.as_ref()[k], lh, q);
    }
    w
}

/// The cached form of `w`.
#[inline(always)]
pub fn pack<D: Dim>(w: &D::W) -> D::C {
    let mut c = D::C::default();
    for (ck, wk) in c.as_mut().iter_mut().zip(w.as_ref()) {
        *ck = CachedW1::pack(wk);
    }
    c
}

/// The weights of a cached form.
#[inline(always)]
pub fn unpack<D: Dim>(c: &D::C) -> D::W {
    let mut w = D::W::default();
    for (wk, ck) in w.as_mut().iter_mut().zip(c.as_ref()) {
        *wk = ck.unpack();
    }
    w
}

/// Nodes of one direction to visit: 2 when the last is empty (S = S' = 0), else 3.
#[inline(always)]
fn extent(w: &Weights1) -> usize {
    if w.s[2] == 0.0 && w.ds[2] == 0.0 {
        2
    } else {
        3
    }
}

/// The three nodes of a stencil row starting at `at` (one range check for the row).
#[inline(always)]
fn row3<N>(nodes: &mut [N], at: usize) -> &mut [N; 3] {
    nodes[at..]
        .first_chunk_mut::<3>()
        .expect("stencil row inside the strip's grid")
}

/// Two dimensions (the plane states of `Analysis`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Dim2;

/// Three dimensions.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Dim3;

impl Dim for Dim2 {
    const N: usize = 2;
    const STENCIL: usize = 9;
    const NAME: &'static str = "2d";
    type V = [f64; 2];
    type U = [usize; 2];
    type L = [f64; 4];
    type S = [f64; 4];
    type W = [Weights1; 2];
    type C = [CachedW1; 2];
    type Mask = u16;
    type Fast<'a> = Field0<'a>;

    #[inline(always)]
    fn fast<'a>(
        g: &'a mut GridMut<'_, Dim2>,
        geom: &GridGeom<Dim2>,
        c: &[CachedW1; 2],
    ) -> Field0<'a> {
        Field0::new(g, geom, c)
    }

    #[inline(always)]
    fn stress_update<A: Arith>(m: &Elastic, s: &mut [f64; 4], l: &[f64; 4], dt: f64) -> f64 {
        let exx = l[0] * dt;
        let eyy = l[3] * dt;
        let gxy = (l[1] + l[2]) * dt;
        let old = *s;
        // Δσ = C:Δε (plane strain: σ_zz = λ(Δε_xx + Δε_yy)).
        s[0] += madd::<A>(m.c11, exx, m.c12 * eyy);
        s[1] += madd::<A>(m.c12, exx, m.c11 * eyy);
        s[2] = madd::<A>(m.mu, gxy, s[2]);
        s[3] = madd::<A>(m.cz, exx + eyy, s[3]);
        // ΔW = ½(σ_old + σ_new):Δε.
        let e = madd::<A>(old[0] + s[0], exx, (old[1] + s[1]) * eyy);
        0.5 * madd::<A>(old[2] + s[2], gxy, e)
    }

    #[inline(always)]
    fn stress_dot<A: Arith>(s: &[f64; 4], g: &[f64]) -> [f64; 2] {
        [
            madd::<A>(s[0], g[0], s[2] * g[1]),
            madd::<A>(s[2], g[0], s[1] * g[1]),
        ]
    }

    #[inline(always)]
    fn visit<N>(
        w: &[Weights1; 2],
        strides: &[usize; 2],
        weighted: bool,
        nodes: &mut [N],
        mut f: impl FnMut(f64, [f64; 2], &mut N),
    ) {
        let [x, y] = w;
        let (xl, yl) = (extent(x) == 3, extent(y) == 3);
        for a in 0..3 {
            if a == 2 && !xl {
                break;
            }
            let col = row3(nodes, a * strides[0]);
            for b in 0..3 {
                if b == 2 && !yl {
                    break;
                }
                let s = x.s[a] * y.s[b];
                if weighted && s == 0.0 {
                    continue;
                }
                f(s, [x.ds[a] * y.s[b], x.s[a] * y.ds[b]], &mut col[b]);
            }
        }
    }
}

impl Dim for Dim3 {
    const N: usize = 3;
    const STENCIL: usize = 27;
    const NAME: &'static str = "3d";
    type V = [f64; 3];
    type U = [usize; 3];
    type L = [f64; 9];
    type S = [f64; 6];
    type W = [Weights1; 3];
    type C = [CachedW1; 3];
    type Mask = u32;
    type Fast<'a> = Rows<'a, Dim3>;

    #[inline(always)]
    fn fast<'a>(
        g: &'a mut GridMut<'_, Dim3>,
        geom: &GridGeom<Dim3>,
        c: &[CachedW1; 3],
    ) -> Rows<'a, Dim3> {
        Rows::new(g, geom, c)
    }

    #[inline(always)]
    fn stress_update<A: Arith>(m: &Elastic, s: &mut [f64; 6], l: &[f64; 9], dt: f64) -> f64 {
        let exx = l[0] * dt;
        let eyy = l[4] * dt;
        let ezz = l[8] * dt;
        let gyz = (l[5] + l[7]) * dt;
        let gxz = (l[2] + l[6]) * dt;
        let gxy = (l[1] + l[3]) * dt;
        let old = *s;
        // Δσ = λ tr(Δε) I + 2μ Δε (engineering shear strains γ = 2ε).
        let lt = m.lambda * (exx + eyy + ezz);
        let mu2 = 2.0 * m.mu;
        s[0] += madd::<A>(mu2, exx, lt);
        s[1] += madd::<A>(mu2, eyy, lt);
        s[2] += madd::<A>(mu2, ezz, lt);
        s[3] = madd::<A>(m.mu, gyz, s[3]);
        s[4] = madd::<A>(m.mu, gxz, s[4]);
        s[5] = madd::<A>(m.mu, gxy, s[5]);
        // ΔW = ½(σ_old + σ_new):Δε.
        let mut e = (old[0] + s[0]) * exx;
        e = madd::<A>(old[1] + s[1], eyy, e);
        e = madd::<A>(old[2] + s[2], ezz, e);
        e = madd::<A>(old[3] + s[3], gyz, e);
        e = madd::<A>(old[4] + s[4], gxz, e);
        0.5 * madd::<A>(old[5] + s[5], gxy, e)
    }

    #[inline(always)]
    fn stress_dot<A: Arith>(s: &[f64; 6], g: &[f64]) -> [f64; 3] {
        [
            madd::<A>(s[0], g[0], madd::<A>(s[5], g[1], s[4] * g[2])),
            madd::<A>(s[5], g[0], madd::<A>(s[1], g[1], s[3] * g[2])),
            madd::<A>(s[4], g[0], madd::<A>(s[3], g[1], s[2] * g[2])),
        ]
    }

    #[inline(always)]
    fn visit<N>(
        w: &[Weights1; 3],
        strides: &[usize; 3],
        weighted: bool,
        nodes: &mut [N],
        mut f: impl FnMut(f64, [f64; 3], &mut N),
    ) {
        let [x, y, z] = w;
        let (na, nb, nc) = (extent(x), extent(y), extent(z));
        for a in 0..na {
            for b in 0..nb {
                let row = row3(nodes, a * strides[0] + b * strides[1]);
                let sxy = x.s[a] * y.s[b];
                let (gx, gy) = (x.ds[a] * y.s[b], x.s[a] * y.ds[b]);
                for c in 0..nc {
                    let s = sxy * z.s[c];
                    if weighted && s == 0.0 {
                        continue;
                    }
                    f(s, [gx * z.s[c], gy * z.s[c], sxy * z.ds[c]], &mut row[c]);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Portable;

    fn steel() -> Elastic {
        let m: Material =
            serde_json::from_str(r#"{"model": "linear_elastic", "density": 7800, "youngs_modulus": 200e9, "poissons_ratio": 0.3}"#)
                .expect("material");
        Elastic::new(&m, Analysis::PlaneStrain)
    }

    /// A uniaxial strain increment in 3D gives σ_xx = (λ+2μ)ε, σ_yy = σ_zz = λε and the
    /// energy ½(λ+2μ)ε² — the plane-strain 2D update's numbers.
    #[test]
    fn uniaxial_strain_matches_plane_strain() {
        let m = steel();
        let eps = 1e-4;
        let mut s3 = [0.0; 6];
        let l3 = [eps, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let w3 = Dim3::stress_update::<Portable>(&m, &mut s3, &l3, 1.0);
        let mut s2 = [0.0; 4];
        let w2 = Dim2::stress_update::<Portable>(&m, &mut s2, &[eps, 0.0, 0.0, 0.0], 1.0);
        let rel = |a: f64, b: f64| ((a - b) / b).abs();
        assert!(rel(s3[0], s2[0]) < 1e-14 && rel(s3[1], s2[1]) < 1e-14);
        assert!(rel(s3[2], s2[3]) < 1e-14);
        assert!(rel(w3, w2) < 1e-14);
        assert!(rel(w3, 0.5 * (m.lambda + 2.0 * m.mu) * eps * eps) < 1e-12);
    }

    /// Simple shear γ: τ = μγ on the right component, W = ½μγ².
    #[test]
    fn shear_components_land_in_voigt_order() {
        let m = steel();
        let g = 2e-4;
        for (r, c, k) in [(1, 2, 3), (0, 2, 4), (0, 1, 5)] {
            let mut l = [0.0; 9];
            l[r * 3 + c] = g;
            let mut s = [0.0; 6];
            let w = Dim3::stress_update::<Portable>(&m, &mut s, &l, 1.0);
            assert!((s[k] - m.mu * g).abs() < 1e-6 * m.mu * g, "{s:?}");
            assert!((w - 0.5 * m.mu * g * g).abs() < 1e-12 * m.mu);
        }
    }

    /// The 3D stencil's S sums to 1 and ∇S to 0 (partition of unity in the tensor product).
    #[test]
    fn stencil_partition_of_unity() {
        let w: [Weights1; 3] = [
            weights_1d(ShapeFunction::Gimp, 4.3, 0.25, 1.0),
            weights_1d(ShapeFunction::Gimp, 7.81, 0.25, 1.0),
            weights_1d(ShapeFunction::Gimp, 2.5, 0.25, 1.0),
        ];
        let (mut s, mut g) = (0.0, [0.0; 3]);
        let mut n = 0;
        let mut nodes = vec![0u8; 300];
        Dim3::visit(&w, &[100, 10, 1], false, &mut nodes, |sk, gk, _| {
            s += sk;
            for c in 0..3 {
                g[c] += gk[c];
            }
            n += 1;
        });
        assert!(
            (s - 1.0).abs() < 1e-14 && g.iter().all(|v| v.abs() < 1e-14),
            "{s} {g:?}"
        );
        assert!(n <= 27);
    }
}
