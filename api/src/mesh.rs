//! Triangle meshes as regions: the containment index and the checks a region mesh must pass.
//!
//! **Containment** ([`MeshIndex`]): a point is inside when the signed crossings of the line
//! through it parallel to z, above it, do not sum to zero (the winding number of the surface
//! around the point; for a valid mesh it is ±1 inside and 0 outside, whichever way the
//! triangles face). A crossing is a triangle whose projection on the xy-plane contains the
//! line's foot; its sign is the projection's orientation. The projection test uses exact
//! orientation predicates (`robust`, Shewchuk's adaptive arithmetic) and a symbolic
//! perturbation of the foot by (ε, ε²) for feet exactly on a projected edge or vertex, so a
//! line through a shared edge or vertex is counted once, never twice or not at all, and
//! triangles seen edge-on (vertical) never count. A point exactly on the surface counts as
//! inside when its z equals a crossing's; otherwise the perturbation decides (consistently).
//! Triangles are bucketed on a uniform xy grid, so a line costs the triangles of one bucket;
//! the lattice fill asks once per line of particles ([`crate::scene3::Region3::column`]).
//!
//! **Checks** ([`check_mesh`]): at least four triangles, finite vertices, indices in range,
//! no degenerate triangle (exactly collinear vertices), closed (every edge shared by exactly
//! two triangles), consistently oriented (the two triangles of an edge traverse it in
//! opposite directions) and not self-intersecting (no two triangles meet except along their
//! shared edge or at their shared vertex; exact predicates, a uniform 3D grid for the
//! candidate pairs). The first failure is reported with the first bad triangle.

use std::collections::HashMap;

use robust::{Coord, Coord3D};

use crate::scene3::Vec3;

fn orient2(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    robust::orient2d(
        Coord { x: a[0], y: a[1] },
        Coord { x: b[0], y: b[1] },
        Coord { x: c[0], y: c[1] },
    )
}

fn orient3(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> f64 {
    let p = |v: Vec3| Coord3D {
        x: v[0],
        y: v[1],
        z: v[2],
    };
    robust::orient3d(p(a), p(b), p(c), p(d))
}

fn xy(v: Vec3) -> [f64; 2] {
    [v[0], v[1]]
}

/// The sign of an exact orientation value: 1, -1 or 0.
fn sign(v: f64) -> i8 {
    if v > 0.0 {
        1
    } else if v < 0.0 {
        -1
    } else {
        0
    }
}

/// One crossing of a line parallel to z with a mesh triangle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    /// Height of the crossing (m).
    pub z: f64,
    /// +1 where the triangle's projection on the xy-plane is counter-clockwise (its normal
    /// points up), -1 where clockwise.
    pub sign: i8,
}

/// Whether height `z` of a line is inside the mesh, given the line's crossings sorted by z
/// ([`MeshIndex::crossings`]): a crossing at exactly `z` counts as inside, otherwise the
/// crossings above `z` must not sum to zero.
pub fn inside_at(crossings: &[Crossing], z: f64) -> bool {
    let i = crossings.partition_point(|c| c.z < z);
    if crossings.get(i).is_some_and(|c| c.z == z) {
        return true;
    }
    let winding: i32 = crossings[i..].iter().map(|c| i32::from(c.sign)).sum();
    winding != 0
}

/// A triangle as the index keeps it: only those whose xy projection has non-zero area (an
/// edge-on triangle is parallel to every line and never crossed).
#[derive(Debug, Clone, Copy)]
struct Tri {
    v: [Vec3; 3],
    /// Orientation of the projection: +1 counter-clockwise, -1 clockwise.
    sign: i8,
    lo: [f64; 2],
    hi: [f64; 2],
    z: [f64; 2],
}

/// The sign of orient2(u, v, q') for the foot q' = q + (ε, ε²) when q lies exactly on the
/// line uv: orient2(u, v, q') = orient2(u, v, q) + (v_x − u_x)ε² − (v_y − u_y)ε. Reversing
/// the edge reverses the sign, so the two triangles of a shared edge always disagree about
/// which side the perturbed foot is on: exactly one of them contains it.
fn perturbed_side(u: [f64; 2], v: [f64; 2]) -> i8 {
    if v[1] != u[1] {
        if u[1] > v[1] { 1 } else { -1 }
    } else if v[0] > u[0] {
        1
    } else if v[0] < u[0] {
        -1
    } else {
        0
    }
}

impl Tri {
    /// Height at which the line through `q` crosses the triangle, if its (perturbed) foot is
    /// inside the projection.
    fn crossing(&self, q: [f64; 2]) -> Option<f64> {
        let [a, b, c] = self.v;
        let (pa, pb, pc) = (xy(a), xy(b), xy(c));
        let wa = orient2(pb, pc, q);
        let wb = orient2(pc, pa, q);
        let wc = orient2(pa, pb, q);
        for (w, u, v) in [(wc, pa, pb), (wa, pb, pc), (wb, pc, pa)] {
            let s = match sign(w) {
                0 => perturbed_side(u, v),
                s => s,
            };
            if s != self.sign {
                return None;
            }
        }
        let sum = wa + wb + wc;
        let z = if sum != 0.0 && sum.is_finite() {
            (wa * a[2] + wb * b[2] + wc * c[2]) / sum
        } else {
            (a[2] + b[2] + c[2]) / 3.0
        };
        // Exact for flat triangles (z[0] == z[1]), never outside the triangle's heights.
        Some(z.clamp(self.z[0], self.z[1]))
    }
}

/// A point-in-mesh index: the triangles bucketed by their xy bounding boxes on a uniform
/// grid. Built once per mesh (O(triangles)); a query costs the triangles of one bucket.
#[derive(Debug, Clone)]
pub struct MeshIndex {
    tris: Vec<Tri>,
    lo: [f64; 2],
    hi: [f64; 2],
    cell: [f64; 2],
    n: [usize; 2],
    /// Bucket b holds `items[starts[b]..starts[b + 1]]`, buckets row by row (x fastest).
    starts: Vec<usize>,
    items: Vec<u32>,
}

impl MeshIndex {
    /// Index the triangles of a mesh. Triangles with an index out of range or a non-finite
    /// vertex are left out (validation refuses such meshes).
    pub fn new(vertices: &[Vec3], triangles: &[[u32; 3]]) -> MeshIndex {
        let mut tris = Vec::with_capacity(triangles.len());
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for t in triangles {
            let Some(v) = triangle_vertices(vertices, t) else {
                continue;
            };
            if !v.iter().flatten().all(|c| c.is_finite()) {
                continue;
            }
            let s = sign(orient2(xy(v[0]), xy(v[1]), xy(v[2])));
            if s == 0 {
                continue;
            }
            let mut tlo = [f64::INFINITY; 2];
            let mut thi = [f64::NEG_INFINITY; 2];
            for p in &v {
                for k in 0..2 {
                    tlo[k] = tlo[k].min(p[k]);
                    thi[k] = thi[k].max(p[k]);
                }
            }
            for k in 0..2 {
                lo[k] = lo[k].min(tlo[k]);
                hi[k] = hi[k].max(thi[k]);
            }
            let zs = [v[0][2], v[1][2], v[2][2]];
            tris.push(Tri {
                v,
                sign: s,
                lo: tlo,
                hi: thi,
                z: [zs[0].min(zs[1]).min(zs[2]), zs[0].max(zs[1]).max(zs[2])],
            });
        }
        let mut index = MeshIndex {
            tris,
            lo,
            hi,
            cell: [1.0; 2],
            n: [1; 2],
            starts: Vec::new(),
            items: Vec::new(),
        };
        index.bucket();
        index
    }

    /// Bucket the triangles: about one bucket per triangle, square-ish cells; coarser while
    /// the entries would exceed 32 per triangle (long thin triangles across the mesh).
    fn bucket(&mut self) {
        let count = self.tris.len();
        if count == 0 {
            self.starts = vec![0, 0];
            return;
        }
        let w = [self.hi[0] - self.lo[0], self.hi[1] - self.lo[1]];
        let area = (w[0] * w[1]).max(f64::MIN_POSITIVE);
        let mut side = (area / count as f64).sqrt();
        if !(side.is_finite() && side > 0.0) {
            side = w[0].max(w[1]).max(1.0);
        }
        loop {
            for (k, &wk) in w.iter().enumerate() {
                let n = (wk / side).ceil();
                self.n[k] = if n.is_finite() {
                    (n as usize).clamp(1, 4096)
                } else {
                    1
                };
                self.cell[k] = if wk > 0.0 { wk / self.n[k] as f64 } else { 1.0 };
            }
            let entries: usize = self
                .tris
                .iter()
                .map(|t| {
                    let (i0, i1) = (self.slot(0, t.lo[0]), self.slot(0, t.hi[0]));
                    let (j0, j1) = (self.slot(1, t.lo[1]), self.slot(1, t.hi[1]));
                    (i1 - i0 + 1) * (j1 - j0 + 1)
                })
                .sum();
            if entries <= 32 * count + 4096 || self.n[0] * self.n[1] == 1 {
                break;
            }
            side *= 2.0;
        }
        let buckets = self.n[0] * self.n[1];
        let mut starts = vec![0usize; buckets + 1];
        for t in &self.tris {
            for j in self.slot(1, t.lo[1])..=self.slot(1, t.hi[1]) {
                for i in self.slot(0, t.lo[0])..=self.slot(0, t.hi[0]) {
                    starts[j * self.n[0] + i + 1] += 1;
                }
            }
        }
        for b in 0..buckets {
            starts[b + 1] += starts[b];
        }
        let mut fill = starts.clone();
        let mut items = vec![0u32; starts[buckets]];
        for (ti, t) in self.tris.iter().enumerate() {
            for j in self.slot(1, t.lo[1])..=self.slot(1, t.hi[1]) {
                for i in self.slot(0, t.lo[0])..=self.slot(0, t.hi[0]) {
                    let b = j * self.n[0] + i;
                    items[fill[b]] = ti as u32;
                    fill[b] += 1;
                }
            }
        }
        self.starts = starts;
        self.items = items;
    }

    /// The bucket column (k = 0) or row (k = 1) of coordinate `v`. Monotone in `v`, so a
    /// triangle whose box holds `v` is in `v`'s bucket.
    fn slot(&self, k: usize, v: f64) -> usize {
        // Negative and NaN saturate to 0.
        ((((v - self.lo[k]) / self.cell[k]).floor()) as usize).min(self.n[k] - 1)
    }

    /// Number of triangles that can be crossed (those not seen edge-on from z).
    pub fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    /// The crossings of the line through `(x, y)` parallel to z, sorted by z, into `out`
    /// (cleared first).
    pub fn crossings(&self, x: f64, y: f64, out: &mut Vec<Crossing>) {
        out.clear();
        if !(x >= self.lo[0] && x <= self.hi[0] && y >= self.lo[1] && y <= self.hi[1]) {
            return;
        }
        let b = self.slot(1, y) * self.n[0] + self.slot(0, x);
        for &ti in &self.items[self.starts[b]..self.starts[b + 1]] {
            let t = &self.tris[ti as usize];
            if x < t.lo[0] || x > t.hi[0] || y < t.lo[1] || y > t.hi[1] {
                continue;
            }
            if let Some(z) = t.crossing([x, y]) {
                out.push(Crossing { z, sign: t.sign });
            }
        }
        out.sort_by(|a, b| a.z.total_cmp(&b.z).then(a.sign.cmp(&b.sign)));
    }

    /// Whether `p` is inside the mesh (see the module documentation).
    pub fn contains(&self, p: Vec3) -> bool {
        let mut crossings = Vec::new();
        self.crossings(p[0], p[1], &mut crossings);
        inside_at(&crossings, p[2])
    }
}

fn triangle_vertices(vertices: &[Vec3], t: &[u32; 3]) -> Option<[Vec3; 3]> {
    Some([
        *vertices.get(t[0] as usize)?,
        *vertices.get(t[1] as usize)?,
        *vertices.get(t[2] as usize)?,
    ])
}

/// Why a mesh is not a valid region surface. Triangle and vertex numbers are indices into the
/// mesh's `triangles` and `vertices`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum MeshDefect {
    /// Fewer than four triangles (no closed surface has fewer).
    #[error("has {count} triangles: a closed surface needs at least 4")]
    TooFewTriangles {
        /// The number of triangles.
        count: usize,
    },
    /// A vertex with a NaN or infinite coordinate.
    #[error("is not a finite point")]
    NonFiniteVertex {
        /// The vertex.
        vertex: usize,
    },
    /// A triangle names a vertex that does not exist.
    #[error("names vertex {index}, but the mesh has {vertices} vertices")]
    IndexOutOfRange {
        /// The triangle.
        triangle: usize,
        /// The index it names.
        index: u32,
        /// The number of vertices.
        vertices: usize,
    },
    /// A triangle names one vertex twice.
    #[error("names one vertex twice (a degenerate triangle)")]
    RepeatedIndex {
        /// The triangle.
        triangle: usize,
    },
    /// A triangle whose three vertices are exactly collinear.
    #[error("has zero area (its three vertices are collinear)")]
    ZeroArea {
        /// The triangle.
        triangle: usize,
    },
    /// An edge no other triangle shares: the surface has a hole.
    #[error(
        "has the edge {}–{} that no other triangle shares: the surface is open (a region mesh \
         must be closed)",
        edge[0], edge[1]
    )]
    OpenEdge {
        /// The first triangle with such an edge.
        triangle: usize,
        /// The edge's vertices, in the triangle's order.
        edge: [u32; 2],
    },
    /// An edge shared by more than two triangles.
    #[error(
        "shares its edge {}–{} with {} other triangles: every edge of a closed surface belongs \
         to exactly two",
        edge[0], edge[1], count - 1
    )]
    NonManifoldEdge {
        /// The first triangle with such an edge.
        triangle: usize,
        /// The edge's vertices, in the triangle's order.
        edge: [u32; 2],
        /// How many triangles share it.
        count: usize,
    },
    /// Triangles whose vertex order disagrees with their neighbours': reported is the first
    /// of the smaller group of a connected surface.
    #[error(
        "is oriented against its neighbours (its edges run the same way as theirs; {count} \
         triangle(s) of this surface are): reverse its vertex order"
    )]
    Flipped {
        /// The first flipped triangle.
        triangle: usize,
        /// How many triangles of its surface are flipped.
        count: usize,
    },
    /// A one-sided surface (no consistent orientation exists).
    #[error("cannot be oriented consistently with its neighbours (a one-sided surface)")]
    NonOrientable {
        /// A triangle where the conflict shows.
        triangle: usize,
    },
    /// Two triangles that meet other than along their shared edge or at their shared vertex.
    #[error("intersects triangle {other}: the surface must not cross or touch itself")]
    SelfIntersecting {
        /// The lower-numbered triangle of the first intersecting pair.
        triangle: usize,
        /// The other triangle.
        other: usize,
    },
}

impl MeshDefect {
    /// The bad triangle, if the defect is one triangle's.
    pub fn triangle(&self) -> Option<usize> {
        match *self {
            MeshDefect::TooFewTriangles { .. } | MeshDefect::NonFiniteVertex { .. } => None,
            MeshDefect::IndexOutOfRange { triangle, .. }
            | MeshDefect::RepeatedIndex { triangle }
            | MeshDefect::ZeroArea { triangle }
            | MeshDefect::OpenEdge { triangle, .. }
            | MeshDefect::NonManifoldEdge { triangle, .. }
            | MeshDefect::Flipped { triangle, .. }
            | MeshDefect::NonOrientable { triangle }
            | MeshDefect::SelfIntersecting { triangle, .. } => Some(triangle),
        }
    }
}

/// The uses of one undirected edge.
#[derive(Debug, Clone, Copy)]
struct EdgeUse {
    count: usize,
    /// The first two triangles that use it, and whether each runs it from the lower vertex
    /// index to the higher.
    tris: [usize; 2],
    forward: [bool; 2],
}

fn edges(t: &[u32; 3]) -> [[u32; 2]; 3] {
    [[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]]
}

fn key(e: [u32; 2]) -> ((u32, u32), bool) {
    if e[0] < e[1] {
        ((e[0], e[1]), true)
    } else {
        ((e[1], e[0]), false)
    }
}

/// Check that `vertices` and `triangles` bound a solid: see the module documentation. The
/// first problem found is returned, in the order listed there, naming the first bad triangle.
pub fn check_mesh(vertices: &[Vec3], triangles: &[[u32; 3]]) -> Result<(), MeshDefect> {
    if triangles.len() < 4 {
        return Err(MeshDefect::TooFewTriangles {
            count: triangles.len(),
        });
    }
    if let Some(vertex) = vertices
        .iter()
        .position(|v| !v.iter().all(|c| c.is_finite()))
    {
        return Err(MeshDefect::NonFiniteVertex { vertex });
    }
    for (ti, t) in triangles.iter().enumerate() {
        if let Some(&index) = t.iter().find(|&&i| i as usize >= vertices.len()) {
            return Err(MeshDefect::IndexOutOfRange {
                triangle: ti,
                index,
                vertices: vertices.len(),
            });
        }
        if t[0] == t[1] || t[1] == t[2] || t[2] == t[0] {
            return Err(MeshDefect::RepeatedIndex { triangle: ti });
        }
        let [a, b, c] = t.map(|i| vertices[i as usize]);
        if collinear(a, b, c) {
            return Err(MeshDefect::ZeroArea { triangle: ti });
        }
    }

    let mut uses: HashMap<(u32, u32), EdgeUse> = HashMap::with_capacity(triangles.len() * 2);
    for (ti, t) in triangles.iter().enumerate() {
        for e in edges(t) {
            let (k, fwd) = key(e);
            let u = uses.entry(k).or_insert(EdgeUse {
                count: 0,
                tris: [usize::MAX; 2],
                forward: [false; 2],
            });
            if u.count < 2 {
                u.tris[u.count] = ti;
                u.forward[u.count] = fwd;
            }
            u.count += 1;
        }
    }
    for (ti, t) in triangles.iter().enumerate() {
        for e in edges(t) {
            let count = uses.get(&key(e).0).map_or(0, |u| u.count);
            if count == 1 {
                return Err(MeshDefect::OpenEdge {
                    triangle: ti,
                    edge: e,
                });
            }
            if count > 2 {
                return Err(MeshDefect::NonManifoldEdge {
                    triangle: ti,
                    edge: e,
                    count,
                });
            }
        }
    }

    check_orientation(triangles, &uses)?;
    check_self_intersection(vertices, triangles)
}

/// Exactly collinear points: every coordinate-plane projection has zero area.
fn collinear(a: Vec3, b: Vec3, c: Vec3) -> bool {
    let proj = |v: Vec3, i: usize, j: usize| [v[i], v[j]];
    [(0, 1), (1, 2), (2, 0)]
        .iter()
        .all(|&(i, j)| orient2(proj(a, i, j), proj(b, i, j), proj(c, i, j)) == 0.0)
}

/// Walk each connected surface from its lowest triangle, marking each triangle as agreeing
/// with it or flipped; the smaller group of each surface is the flipped one.
fn check_orientation(
    triangles: &[[u32; 3]],
    uses: &HashMap<(u32, u32), EdgeUse>,
) -> Result<(), MeshDefect> {
    let mut flipped: Vec<Option<bool>> = vec![None; triangles.len()];
    let mut first_bad: Option<(usize, usize)> = None;
    let mut queue = Vec::new();
    for seed in 0..triangles.len() {
        if flipped[seed].is_some() {
            continue;
        }
        flipped[seed] = Some(false);
        queue.clear();
        queue.push(seed);
        let mut members = Vec::new();
        while let Some(t) = queue.pop() {
            members.push(t);
            let ft = flipped[t].unwrap_or(false);
            for e in edges(&triangles[t]) {
                let Some(u) = uses.get(&key(e).0) else {
                    continue;
                };
                let (other, same_way) = if u.tris[0] == t {
                    (u.tris[1], u.forward[0] == u.forward[1])
                } else {
                    (u.tris[0], u.forward[0] == u.forward[1])
                };
                if other == usize::MAX {
                    continue;
                }
                // Two triangles running their shared edge the same way disagree.
                let expected = ft ^ same_way;
                match flipped[other] {
                    None => {
                        flipped[other] = Some(expected);
                        queue.push(other);
                    }
                    Some(f) if f != expected => {
                        return Err(MeshDefect::NonOrientable {
                            triangle: t.min(other),
                        });
                    }
                    Some(_) => {}
                }
            }
        }
        // The minority is flipped: the triangles marked against the seed, unless they are
        // the majority (a tie blames the side without the seed).
        let n_against = members
            .iter()
            .filter(|&&t| flipped[t] == Some(true))
            .count();
        let bad_mark = 2 * n_against <= members.len();
        let bad: Vec<usize> = members
            .iter()
            .copied()
            .filter(|&t| flipped[t] == Some(bad_mark))
            .collect();
        if let Some(&t) = bad.iter().min() {
            let candidate = (t, bad.len());
            if first_bad.is_none_or(|(b, _)| t < b) {
                first_bad = Some(candidate);
            }
        }
    }
    match first_bad {
        Some((triangle, count)) => Err(MeshDefect::Flipped { triangle, count }),
        None => Ok(()),
    }
}

/// Find the first pair of triangles (lowest first index) that meet other than along their
/// shared edge or at their shared vertex. Candidate pairs come from a uniform 3D grid of
/// buckets over the triangles' bounding boxes.
fn check_self_intersection(vertices: &[Vec3], triangles: &[[u32; 3]]) -> Result<(), MeshDefect> {
    let tri = |t: usize| triangles[t].map(|i| vertices[i as usize]);
    let boxes: Vec<(Vec3, Vec3)> = (0..triangles.len())
        .map(|t| {
            let v = tri(t);
            let mut lo = v[0];
            let mut hi = v[0];
            for p in &v[1..] {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
            (lo, hi)
        })
        .collect();
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for (a, b) in &boxes {
        for k in 0..3 {
            lo[k] = lo[k].min(a[k]);
            hi[k] = hi[k].max(b[k]);
        }
    }
    let count = triangles.len();
    let w = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
    let wmax = w[0].max(w[1]).max(w[2]);
    let floor = wmax * 1e-3;
    let vol = w.iter().map(|x| x.max(floor)).product::<f64>();
    let mut side = (vol / (2.0 * count as f64)).cbrt().max(wmax / 1024.0);
    if !(side.is_finite() && side > 0.0) {
        side = 1.0;
    }
    let (n, cell) = loop {
        let mut n = [1usize; 3];
        let mut cell = [1.0f64; 3];
        for k in 0..3 {
            n[k] = ((w[k] / side).ceil() as usize).clamp(1, 1024);
            cell[k] = if w[k] > 0.0 { w[k] / n[k] as f64 } else { 1.0 };
        }
        let slot = |k: usize, v: f64| ((((v - lo[k]) / cell[k]).floor()) as usize).min(n[k] - 1);
        let entries: usize = boxes
            .iter()
            .map(|(a, b)| {
                (0..3)
                    .map(|k| slot(k, b[k]) - slot(k, a[k]) + 1)
                    .product::<usize>()
            })
            .sum();
        if entries <= 64 * count + 4096 || n == [1, 1, 1] {
            break (n, cell);
        }
        side *= 2.0;
    };
    let slot = |k: usize, v: f64| ((((v - lo[k]) / cell[k]).floor()) as usize).min(n[k] - 1);
    let range = |b: &(Vec3, Vec3)| {
        let r = |k: usize| slot(k, b.0[k])..=slot(k, b.1[k]);
        (r(0), r(1), r(2))
    };
    let cells = n[0] * n[1] * n[2];
    let mut starts = vec![0usize; cells + 1];
    for b in &boxes {
        let (ri, rj, rk) = range(b);
        for k in rk {
            for j in rj.clone() {
                for i in ri.clone() {
                    starts[(k * n[1] + j) * n[0] + i + 1] += 1;
                }
            }
        }
    }
    for c in 0..cells {
        starts[c + 1] += starts[c];
    }
    let mut fill = starts.clone();
    let mut items = vec![0usize; starts[cells]];
    for (t, b) in boxes.iter().enumerate() {
        let (ri, rj, rk) = range(b);
        for k in rk {
            for j in rj.clone() {
                for i in ri.clone() {
                    let c = (k * n[1] + j) * n[0] + i;
                    items[fill[c]] = t;
                    fill[c] += 1;
                }
            }
        }
    }
    let mut seen = vec![usize::MAX; count];
    for t in 0..count {
        let (ri, rj, rk) = range(&boxes[t]);
        for k in rk {
            for j in rj.clone() {
                for i in ri.clone() {
                    let c = (k * n[1] + j) * n[0] + i;
                    for &u in &items[starts[c]..starts[c + 1]] {
                        if u <= t || seen[u] == t {
                            continue;
                        }
                        seen[u] = t;
                        let (a, b) = (&boxes[t], &boxes[u]);
                        if (0..3).any(|k| a.1[k] < b.0[k] || b.1[k] < a.0[k]) {
                            continue;
                        }
                        if pair_intersects(vertices, &triangles[t], &triangles[u]) {
                            return Err(MeshDefect::SelfIntersecting {
                                triangle: t,
                                other: u,
                            });
                        }
                    }
                }
            }
        }
    }
    Ok(())
}

/// Whether two triangles of a mesh meet other than along their shared edge or at their
/// shared vertex (closed triangles, exact predicates).
fn pair_intersects(vertices: &[Vec3], t: &[u32; 3], u: &[u32; 3]) -> bool {
    let shared: Vec<u32> = t.iter().copied().filter(|i| u.contains(i)).collect();
    let p = |i: u32| vertices[i as usize];
    let tv = t.map(p);
    let uv = u.map(p);
    match shared.len() {
        3 => true, // the same triangle twice
        2 => {
            // Along the shared edge only, unless the two lie in one plane on the same side of
            // it (folded onto each other).
            let (s0, s1) = (shared[0], shared[1]);
            let c = t.iter().copied().find(|i| !shared.contains(i)).map(p);
            let d = u.iter().copied().find(|i| !shared.contains(i)).map(p);
            let (Some(c), Some(d)) = (c, d) else {
                return true;
            };
            let (a, b) = (p(s0), p(s1));
            if orient3(a, b, c, d) != 0.0 {
                return false;
            }
            let drop = dominant_axis(a, b, c);
            let (a2, b2, c2, d2) = (
                project(a, drop),
                project(b, drop),
                project(c, drop),
                project(d, drop),
            );
            let (sc, sd) = (sign(orient2(a2, b2, c2)), sign(orient2(a2, b2, d2)));
            sc != 0 && sc == sd
        }
        1 => {
            // Two triangles with one common vertex meet elsewhere only if the edge opposite
            // that vertex in one of them meets the other.
            let s = shared[0];
            let opposite = |tri: &[u32; 3]| {
                let o: Vec<Vec3> = tri.iter().copied().filter(|&i| i != s).map(p).collect();
                [o[0], o[1]]
            };
            let (ot, ou) = (opposite(t), opposite(u));
            segment_meets_triangle(ot[0], ot[1], uv) || segment_meets_triangle(ou[0], ou[1], tv)
        }
        _ => {
            // Disjoint index sets: two closed triangles meet iff an edge of one meets the
            // other (a point of the intersection's boundary lies on an edge).
            (0..3).any(|k| segment_meets_triangle(tv[k], tv[(k + 1) % 3], uv))
                || (0..3).any(|k| segment_meets_triangle(uv[k], uv[(k + 1) % 3], tv))
        }
    }
}

/// The coordinate to drop when projecting a plane through a, b, c onto a coordinate plane:
/// the largest component of its normal (any non-zero one gives a faithful projection).
fn dominant_axis(a: Vec3, b: Vec3, c: Vec3) -> usize {
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    let nrm = [
        (u[1] * v[2] - u[2] * v[1]).abs(),
        (u[2] * v[0] - u[0] * v[2]).abs(),
        (u[0] * v[1] - u[1] * v[0]).abs(),
    ];
    if nrm[0] >= nrm[1] && nrm[0] >= nrm[2] {
        0
    } else if nrm[1] >= nrm[2] {
        1
    } else {
        2
    }
}

fn project(v: Vec3, drop: usize) -> [f64; 2] {
    match drop {
        0 => [v[1], v[2]],
        1 => [v[2], v[0]],
        _ => [v[0], v[1]],
    }
}

/// Whether the closed segment pq meets the closed triangle abc.
fn segment_meets_triangle(p: Vec3, q: Vec3, [a, b, c]: [Vec3; 3]) -> bool {
    let sp = sign(orient3(a, b, c, p));
    let sq = sign(orient3(a, b, c, q));
    if sp != 0 && sp == sq {
        return false;
    }
    if sp == 0 && sq == 0 {
        let drop = dominant_axis(a, b, c);
        let [p2, q2, a2, b2, c2] = [p, q, a, b, c].map(|v| project(v, drop));
        return segment_meets_triangle_2d(p2, q2, [a2, b2, c2]);
    }
    // The line pq meets the plane once, within the segment: it is inside the triangle when
    // it passes on the same side of (or through) all three edges.
    let s = [
        sign(orient3(p, q, a, b)),
        sign(orient3(p, q, b, c)),
        sign(orient3(p, q, c, a)),
    ];
    s.iter().all(|&x| x >= 0) || s.iter().all(|&x| x <= 0)
}

fn point_in_triangle_2d(p: [f64; 2], [a, b, c]: [[f64; 2]; 3]) -> bool {
    let s = [
        sign(orient2(a, b, p)),
        sign(orient2(b, c, p)),
        sign(orient2(c, a, p)),
    ];
    s.iter().all(|&x| x >= 0) || s.iter().all(|&x| x <= 0)
}

fn on_segment_2d(p: [f64; 2], q: [f64; 2], r: [f64; 2]) -> bool {
    (0..2).all(|k| r[k] >= p[k].min(q[k]) && r[k] <= p[k].max(q[k]))
}

fn segments_meet_2d(p: [f64; 2], q: [f64; 2], a: [f64; 2], b: [f64; 2]) -> bool {
    let d1 = sign(orient2(p, q, a));
    let d2 = sign(orient2(p, q, b));
    let d3 = sign(orient2(a, b, p));
    let d4 = sign(orient2(a, b, q));
    if d1 * d2 < 0 && d3 * d4 < 0 {
        return true;
    }
    (d1 == 0 && on_segment_2d(p, q, a))
        || (d2 == 0 && on_segment_2d(p, q, b))
        || (d3 == 0 && on_segment_2d(a, b, p))
        || (d4 == 0 && on_segment_2d(a, b, q))
}

fn segment_meets_triangle_2d(p: [f64; 2], q: [f64; 2], t: [[f64; 2]; 3]) -> bool {
    point_in_triangle_2d(p, t)
        || point_in_triangle_2d(q, t)
        || (0..3).any(|k| segments_meet_2d(p, q, t[k], t[(k + 1) % 3]))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    /// The unit cube [0, 1]³, outward.
    fn cube() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let v: Vec<Vec3> = (0..8)
            .map(|i| {
                [
                    f64::from(i & 1),
                    f64::from((i >> 1) & 1),
                    f64::from((i >> 2) & 1),
                ]
            })
            .collect();
        let t = vec![
            [0, 2, 1],
            [1, 2, 3], // z = 0, normal −z
            [4, 5, 6],
            [5, 7, 6], // z = 1
            [0, 1, 4],
            [1, 5, 4], // y = 0
            [2, 6, 3],
            [3, 6, 7], // y = 1
            [0, 4, 2],
            [2, 4, 6], // x = 0
            [1, 3, 5],
            [3, 7, 5], // x = 1
        ];
        (v, t)
    }

    #[test]
    fn the_cube_is_valid_and_contains_its_inside() {
        let (v, t) = cube();
        check_mesh(&v, &t).unwrap();
        let idx = MeshIndex::new(&v, &t);
        assert!(idx.contains([0.5, 0.5, 0.5]));
        // On the diagonal of the top and bottom faces: counted once each.
        assert!(idx.contains([0.25, 0.25, 0.5]));
        assert!(idx.contains([0.75, 0.75, 0.9]));
        assert!(!idx.contains([0.5, 0.5, 1.5]));
        assert!(!idx.contains([0.5, 0.5, -0.5]));
        assert!(!idx.contains([1.5, 0.5, 0.5]));
        // Through the vertex column (0, 0) and (1, 1): consistent, no double count.
        let mut c = Vec::new();
        idx.crossings(0.0, 0.0, &mut c);
        assert_eq!(c.iter().map(|c| i32::from(c.sign)).sum::<i32>(), 0, "{c:?}");
        idx.crossings(0.5, 0.5, &mut c);
        assert_eq!(c.len(), 2, "{c:?}");
    }

    #[test]
    fn defects_name_their_triangle() {
        let (v, t) = cube();
        let mut open = t.clone();
        open.remove(3);
        assert!(matches!(
            check_mesh(&v, &open),
            Err(MeshDefect::OpenEdge { .. })
        ));
        let mut flipped = t.clone();
        flipped[7].swap(1, 2);
        assert_eq!(
            check_mesh(&v, &flipped),
            Err(MeshDefect::Flipped {
                triangle: 7,
                count: 1
            })
        );
        let mut bad = t.clone();
        bad[2] = [4, 5, 9];
        assert!(matches!(
            check_mesh(&v, &bad),
            Err(MeshDefect::IndexOutOfRange { triangle: 2, .. })
        ));
    }
}
