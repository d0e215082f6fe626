//! Sorting the particles by cell (`algorithm.md` §2, data layout), written once for both
//! dimensions: a stable counting sort of every particle array, x-plane major (2D: column
//! major), and the strip bounds of the parallel scatter. It runs before the first step and
//! whenever a particle left its strip's planes. The crack layer's field masks are not moved:
//! they are recomputed before every P2G.

use crate::dim::Dim;
use crate::grid::{GridGeom, STRIP};
use crate::particles::Particles;

/// The sort's work arrays (kept between sorts: no allocation after the first).
#[derive(Debug, Clone, Default)]
pub struct SortScratch<D: Dim> {
    keys: Vec<u32>,
    count: Vec<u32>,
    perm: Vec<u32>,
    spare: Particles<D>,
}

/// Move every element of `a` to its place `perm[i]`, through `spare`.
fn permute<T: Copy + Default>(a: &mut Vec<T>, spare: &mut Vec<T>, perm: &[u32]) {
    spare.resize(a.len(), T::default());
    for (i, &d) in perm.iter().enumerate() {
        spare[d as usize] = a[i];
    }
    std::mem::swap(a, spare);
}

/// Sort `parts` by cell and set the strip bounds `bounds` (`geom.strips + 1` entries: the
/// first particle of each strip, then the count). A particle within one cell of the grid's
/// edge (where its stencil would leave the grid) is refused: `Err(i)`, its index.
pub fn sort_by_cell<D: Dim>(
    geom: &GridGeom<D>,
    parts: &mut Particles<D>,
    bounds: &mut [usize],
    sc: &mut SortScratch<D>,
) -> Result<(), usize> {
    let mut nc = [1usize; 3];
    for d in 0..D::N {
        nc[d] = geom.n.as_ref()[d] - 1;
    }
    let ncells: usize = nc.iter().product();
    let plane_cells = ncells / nc[0];
    let n = parts.len();
    sc.keys.resize(n, 0);
    sc.perm.resize(n, 0);
    for (i, k) in parts.kin.iter().enumerate() {
        let c = geom.cell(&k.x);
        let mut key = 0usize;
        for d in 0..D::N {
            if c[d] < 1 || c[d] as usize + 2 > nc[d] {
                return Err(i);
            }
            key = key * nc[d] + c[d] as usize;
        }
        sc.keys[i] = key as u32;
    }
    sc.count.clear();
    sc.count.resize(ncells + 1, 0);
    for &k in &sc.keys {
        sc.count[k as usize + 1] += 1;
    }
    for c in 0..ncells {
        sc.count[c + 1] += sc.count[c];
    }
    // Strip bounds: the first particle with cell plane ≥ s·STRIP.
    for (s, b) in bounds.iter_mut().enumerate().take(geom.strips + 1) {
        let col = (s * STRIP).min(nc[0]);
        *b = sc.count[col * plane_cells] as usize;
    }
    for (i, &k) in sc.keys.iter().enumerate() {
        let dst = &mut sc.count[k as usize];
        sc.perm[i] = *dst;
        *dst += 1;
    }
    let (s, perm) = (&mut sc.spare, &sc.perm);
    permute(&mut parts.kin, &mut s.kin, perm);
    permute(&mut parts.mech, &mut s.mech, perm);
    permute(&mut parts.stress, &mut s.stress, perm);
    permute(&mut parts.wden, &mut s.wden, perm);
    permute(&mut parts.cold, &mut s.cold, perm);
    if !parts.grad_u.is_empty() {
        permute(&mut parts.grad_u, &mut s.grad_u, perm);
    }
    Ok(())
}
