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

/// Zero the nodes of the box.
pub fn reset<D: Dim>(
    geom: &GridGeom<D>,
    nodes: &mut [Node<D>],
    active: Option<ActiveBox<D>>,
    plane_sums: &mut [f64],
) {
    if let Some(b) = active {
        for_box(geom, nodes, b, plane_sums, |n| {
            *n = Node::default();
            0.0
        });
    }
}

/// Nodes of the box with mass above `m_tiny`.
pub fn count<D: Dim>(
    geom: &GridGeom<D>,
    nodes: &mut [Node<D>],
    b: ActiveBox<D>,
    plane_sums: &mut [f64],
    m_tiny: f64,
) -> usize {
    for_box(geom, nodes, b, plane_sums, |n| {
        if n.m > m_tiny { 1.0 } else { 0.0 }
    }) as usize
}

/// The nodal value of one node at `stage`: v = p/m, a = f/m or v = q/m; zero velocity and
/// acceleration on a node lighter than `m_tiny`.
#[inline]
pub fn nodal_node<D: Dim>(n: &mut Node<D>, stage: Stage, m_tiny: f64) {
    if n.m > m_tiny {
        let inv = 1.0 / n.m;
        for d in 0..D::N {
            match stage {
                Stage::Extrapolated => n.v.as_mut()[d] = n.p.as_ref()[d] * inv,
                Stage::Forces => n.a.as_mut()[d] = n.f.as_ref()[d] * inv,
                Stage::Reextrapolated => n.v.as_mut()[d] = n.q.as_ref()[d] * inv,
            }
        }
    } else {
        n.v = D::V::default();
        n.a = D::V::default();
    }
}

/// Nodal values at `stage` on the box and on the field-1 nodes `f1`.
pub fn nodal<D: Dim>(
    geom: &GridGeom<D>,
    nodes: &mut [Node<D>],
    active: Option<ActiveBox<D>>,
    f1: &mut [Node<D>],
    plane_sums: &mut [f64],
    stage: Stage,
    m_tiny: f64,
) {
    if let Some(b) = active {
        for_box(geom, nodes, b, plane_sums, |n| {
            nodal_node(n, stage, m_tiny);
            0.0
        });
    }
    for n in f1 {
        nodal_node(n, stage, m_tiny);
    }
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
