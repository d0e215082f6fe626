//! The grid between the particle passes (`algorithm.md` §2), written once for both
//! dimensions and for the crack layer's field-1 nodes: zeroing the active box, counting its
//! nodes with mass, nodal velocities and accelerations (v = p/m, a = f/m, v = q/m) and the
//! damping forces with the work they remove. The active box's x-planes run in parallel; sums
//! are taken per plane in node order and then over the planes in order, then over the
//! field-1 nodes in slot order, so they do not depend on the thread count.

use fracture_api::scene::Damping;
use rayon::prelude::*;

use crate::dim::Dim;
use crate::grid::{GridGeom, Node, PAD};

/// The momentum stage of the step: after the P2G (momenta p), after the force pass (p + Δt f),
/// after the re-extrapolation (momenta q). Nodal values and crack contact act at each.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// After P2G (momentum p).
    Extrapolated,
    /// After the force update (p + Δt f; forces adjusted by ±Δp/Δt).
    Forces,
    /// After re-extrapolation (momentum q).
    Reextrapolated,
}

/// The active box: the lowest and highest node index per direction (inclusive).
pub type ActiveBox<D> = (<D as Dim>::U, <D as Dim>::U);

/// `f` on every node of the box of `nodes`, x-planes in parallel: the sum of its results,
/// per plane in node order (from −0, as `Iterator::sum`), then over the planes in order.
pub fn for_box<D: Dim>(
    geom: &GridGeom<D>,
    nodes: &mut [Node<D>],
    (lo, hi): ActiveBox<D>,
    plane_sums: &mut [f64],
    f: impl Fn(&mut Node<D>) -> f64 + Sync,
) -> f64 {
    let plane = geom.plane();
    let (x0, x1) = (lo.as_ref()[0], hi.as_ref()[0]);
    let planes = &mut nodes[(x0 + PAD) * plane..(x1 + 1 + PAD) * plane];
    let sums = &mut plane_sums[..x1 + 1 - x0];
    let (y0, y1) = (lo.as_ref()[1], hi.as_ref()[1]);
    let nz = if D::N == 3 {
        geom.strides.as_ref()[1]
    } else {
        1
    };
    let (z0, z1) = if D::N == 3 {
        (lo.as_ref()[2], hi.as_ref()[2])
    } else {
        (0, 0)
    };
    planes
        .par_chunks_mut(plane)
        .zip(sums.par_iter_mut())
        .for_each(|(c, s)| {
            *s = if D::N == 2 {
                c[y0..=y1].iter_mut().map(&f).sum()
            } else {
                let mut acc = -0.0;
                for iy in y0..=y1 {
                    for n in &mut c[iy * nz + z0..=iy * nz + z1] {
                        acc += f(n);
                    }
                }
                acc
            };
        });
    sums.iter().sum()
}

/// `f` on every row of the box of `nodes` (a 2D column's nodes y0..=y1, a 3D row's
/// z0..=z1), x-planes in parallel.
pub fn for_rows<D: Dim>(
    geom: &GridGeom<D>,
    nodes: &mut [Node<D>],
    (lo, hi): ActiveBox<D>,
    f: impl Fn(&mut [Node<D>]) + Sync,
) {
    let plane = geom.plane();
    let (x0, x1) = (lo.as_ref()[0], hi.as_ref()[0]);
    let planes = &mut nodes[(x0 + PAD) * plane..(x1 + 1 + PAD) * plane];
    let (y0, y1) = (lo.as_ref()[1], hi.as_ref()[1]);
    if D::N == 2 {
        planes
            .par_chunks_mut(plane)
            .for_each(|c| f(&mut c[y0..=y1]));
    } else {
        let nz = geom.strides.as_ref()[1];
        let (z0, z1) = (lo.as_ref()[2], hi.as_ref()[2]);
        planes.par_chunks_mut(plane).for_each(|c| {
            for iy in y0..=y1 {
                f(&mut c[iy * nz + z0..=iy * nz + z1]);
            }
        });
    }
}

/// Zero the nodes of the box.
pub fn reset<D: Dim>(geom: &GridGeom<D>, nodes: &mut [Node<D>], active: Option<ActiveBox<D>>) {
    if let Some(b) = active {
        for_rows(geom, nodes, b, |r| r.fill(Node::default()));
    }
}

/// Nodes of the box with mass above `m_tiny`.
pub fn count<D: Dim>(
    geom: &GridGeom<D>,
    nodes: &[Node<D>],
    (lo, hi): ActiveBox<D>,
    m_tiny: f64,
) -> usize {
    let plane = geom.plane();
    let (x0, x1) = (lo.as_ref()[0], hi.as_ref()[0]);
    let planes = &nodes[(x0 + PAD) * plane..(x1 + 1 + PAD) * plane];
    let (y0, y1) = (lo.as_ref()[1], hi.as_ref()[1]);
    let heavy = |r: &[Node<D>]| r.iter().filter(|n| n.m > m_tiny).count();
    if D::N == 2 {
        planes.par_chunks(plane).map(|c| heavy(&c[y0..=y1])).sum()
    } else {
        let nz = geom.strides.as_ref()[1];
        let (z0, z1) = (lo.as_ref()[2], hi.as_ref()[2]);
        planes
            .par_chunks(plane)
            .map(|c| {
                (y0..=y1)
                    .map(|iy| heavy(&c[iy * nz + z0..=iy * nz + z1]))
                    .sum::<usize>()
            })
            .sum()
    }
}

/// Nodal values at `stage` on the box and on the field-1 nodes `f1`: v = p/m, a = f/m or
/// v = q/m; zero velocity and acceleration on a node lighter than `m_tiny`.
pub fn nodal<D: Dim>(
    geom: &GridGeom<D>,
    nodes: &mut [Node<D>],
    active: Option<ActiveBox<D>>,
    f1: &mut [Node<D>],
    stage: Stage,
    m_tiny: f64,
) {
    // One loop per stage, so the stage is not tested per node.
    match stage {
        Stage::Extrapolated => nodal_with(geom, nodes, active, f1, m_tiny, |n, inv| {
            for d in 0..D::N {
                n.v.as_mut()[d] = n.p.as_ref()[d] * inv;
            }
        }),
        Stage::Forces => nodal_with(geom, nodes, active, f1, m_tiny, |n, inv| {
            for d in 0..D::N {
                n.a.as_mut()[d] = n.f.as_ref()[d] * inv;
            }
        }),
        Stage::Reextrapolated => nodal_with(geom, nodes, active, f1, m_tiny, |n, inv| {
            for d in 0..D::N {
                n.v.as_mut()[d] = n.q.as_ref()[d] * inv;
            }
        }),
    }
}

#[inline(always)]
fn nodal_with<D: Dim>(
    geom: &GridGeom<D>,
    nodes: &mut [Node<D>],
    active: Option<ActiveBox<D>>,
    f1: &mut [Node<D>],
    m_tiny: f64,
    set: impl Fn(&mut Node<D>, f64) + Sync,
) {
    let one = |n: &mut Node<D>| {
        if n.m > m_tiny {
            set(n, 1.0 / n.m);
        } else {
            n.v = D::V::default();
            n.a = D::V::default();
        }
    };
    if let Some(b) = active {
        for_rows(geom, nodes, b, |r| r.iter_mut().for_each(&one));
    }
    f1.iter_mut().for_each(one);
}

/// The damping force on one node after the force pass, against its motion (kinetic: local
/// non-viscous, |f_d| = c|f| per component; viscous: f_d = c p, mass-proportional), and the
/// work it removes over `dt`.
#[inline]
pub fn damp_node<D: Dim>(n: &mut Node<D>, damping: &Damping, m_tiny: f64, dt: f64) -> f64 {
    if n.m <= m_tiny {
        return 0.0;
    }
    let mut v = D::V::default();
    for d in 0..D::N {
        v.as_mut()[d] = n.p.as_ref()[d] / n.m;
    }
    let v = v.as_ref();
    match *damping {
        Damping::Viscous { coefficient } => {
            let mut out = 0.0;
            for d in 0..D::N {
                let fd = coefficient * n.p.as_ref()[d];
                n.f.as_mut()[d] -= fd;
                // Σ f_d·v, the first term as is (the sum of the 2D solver before the core).
                out = if d == 0 { fd * v[d] } else { out + fd * v[d] };
            }
            out * dt
        }
        Damping::Kinetic { coefficient } => {
            let mut out = 0.0;
            for d in 0..D::N {
                let fd = coefficient * n.f.as_ref()[d].abs() * v[d].signum();
                n.f.as_mut()[d] -= fd;
                out += fd * v[d] * dt;
            }
            out
        }
        Damping::None => 0.0,
    }
}

/// Damping on the box and the field-1 nodes; returns the work removed (J).
#[allow(clippy::too_many_arguments)]
pub fn damp<D: Dim>(
    geom: &GridGeom<D>,
    nodes: &mut [Node<D>],
    active: Option<ActiveBox<D>>,
    f1: &mut [Node<D>],
    plane_sums: &mut [f64],
    damping: &Damping,
    m_tiny: f64,
    dt: f64,
) -> f64 {
    if matches!(damping, Damping::None) {
        return 0.0;
    }
    let mut d = match active {
        Some(b) => for_box(geom, nodes, b, plane_sums, |n| {
            damp_node(n, damping, m_tiny, dt)
        }),
        None => 0.0,
    };
    for n in f1 {
        d += damp_node(n, damping, m_tiny, dt);
    }
    d
}

/// The fields of node `i`: field 0, and field 1 where the slot map `slot_of` gives it a slot.
#[inline]
fn each_field<D: Dim>(
    nodes: &mut [Node<D>],
    f1: &mut [Node<D>],
    slot_of: &[u32],
    i: usize,
    mut f: impl FnMut(&mut Node<D>),
) {
    f(&mut nodes[i]);
    let slot = slot_of.get(i).copied().unwrap_or(u32::MAX);
    if slot != u32::MAX {
        f(&mut f1[slot as usize]);
    }
}

/// A velocity condition on the momenta of every field of the nodes `at` (storage indices):
/// each prescribed component `v[d]` sets p_d = m v_d (after the P2G) or q_d = m v_d (after the
/// re-extrapolation, `reextrapolated`); nodes lighter than `m_tiny` are left alone.
#[allow(clippy::too_many_arguments)]
pub fn hold_momentum<D: Dim>(
    nodes: &mut [Node<D>],
    f1: &mut [Node<D>],
    slot_of: &[u32],
    at: &[u32],
    v: &[Option<f64>],
    reextrapolated: bool,
    m_tiny: f64,
) {
    for &i in at {
        each_field(nodes, f1, slot_of, i as usize, |n| {
            if n.m <= m_tiny {
                return;
            }
            let target = if reextrapolated { &mut n.q } else { &mut n.p };
            for d in 0..D::N {
                if let Some(vk) = v[d] {
                    target.as_mut()[d] = n.m * vk;
                }
            }
        });
    }
}

/// A velocity condition after the force pass: on every field of the nodes `at`, the force
/// that makes p + Δt f meet the prescribed velocity, f_d = (m v_d − p_d)/Δt. The reaction's
/// work at the node's mid-step velocity, Σ (f_new − f)·½(p/m + v)·Δt, is added to `work` in
/// node order.
#[allow(clippy::too_many_arguments)]
pub fn hold_force<D: Dim>(
    nodes: &mut [Node<D>],
    f1: &mut [Node<D>],
    slot_of: &[u32],
    at: &[u32],
    v: &[Option<f64>],
    m_tiny: f64,
    dt: f64,
    work: &mut f64,
) {
    for &i in at {
        each_field(nodes, f1, slot_of, i as usize, |n| {
            if n.m <= m_tiny {
                return;
            }
            for d in 0..D::N {
                if let Some(vk) = v[d] {
                    let p = n.p.as_ref()[d];
                    let f_new = (n.m * vk - p) / dt;
                    let v_mid = 0.5 * (p / n.m + vk);
                    *work += (f_new - n.f.as_ref()[d]) * v_mid * dt;
                    n.f.as_mut()[d] = f_new;
                }
            }
        });
    }
}
