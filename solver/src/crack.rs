//! Explicit cracks (`algorithm.md` §3–§7; Nairn 2003, Guo & Nairn 2004/2006).
//!
//! * Geometry: each crack is a polyline of crack points, each with its line position and an
//!   "above" (left of the directed polyline) and "below" surface position. Scene segments are
//!   subdivided to at most h/2 so the surfaces and the crack opening are resolved. An end
//!   outside every body is a mouth, not a tip, and is pushed 2h further out so the fields
//!   separate cleanly at the surface.
//! * Fields (§3): for every particle–node pair the segment x_p → x_i is tested against the
//!   crack segments registered in the particle's cell (broad phase: a per-cell list rebuilt
//!   each step). An odd number of crossings puts the pair in field 1. Tie rule: a point exactly
//!   on a crack line counts as above (left), consistently in every orientation test, so a node
//!   on the line is classified without ambiguity.
//! * Contact (§4) at every momentum stage, as ±Δp so momentum is conserved exactly.
//! * Motion (§5): each surface point moves with the mass-weighted velocity of its own side's
//!   fields on the 4 nodes of its cell; the line point takes the mean of its two surfaces.
//! * J (§6): contour of grid lines, a square of half-size `j_contour` cells around the node
//!   nearest the tip, nodal values as mass-weighted particle averages of the node's own field,
//!   trapezoid rule, the edge crossed by the crack split at the crossing with each face using
//!   its own node's values; plus the area term over the particles inside the square.
//! * K (§6): K_I² + K_II² from E'·J1 (with A_I(v), A_II(v) for a moving tip), the mode ratio
//!   K_I/K_II = δ_n/δ_t from the crack opening about 2h behind the tip.
//! * Propagation (§7): G ≥ toughness grows the tip by cfl·h (the seed's C_L·Δt) in the chosen
//!   direction; segments stay at least h/2 long.

use std::collections::VecDeque;

use fracture_api::Scene;
use fracture_api::results::CrackTipRow;
use fracture_api::scene::{ContactLaw, GrowthDirection, Propagation, ShapeFunction};

use rayon::prelude::*;

use crate::grid::{GridGeom, Node, STRIP};
use crate::material::Elastic;
use crate::particles::{Kin, Mech, Particles};
use crate::shape::Weights2;

/// The momentum stage at which contact is applied (`algorithm.md` §4, pitfall 4).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// After P2G (momentum p).
    Extrapolated,
    /// After the force update (p + Δt f; forces adjusted by ±Δp/Δt).
    Forces,
    /// After re-extrapolation (momentum q).
    Reextrapolated,
}

/// A point of a crack: its line position and its two surfaces.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrackPoint {
    /// Position of the crack line.
    pub x: [f64; 2],
    /// Surface on the left of the directed polyline.
    pub above: [f64; 2],
    /// Surface on the right.
    pub below: [f64; 2],
    /// Where the crack line's material point at this crack point sits in the undeformed body
    /// (the scene's coordinates): the point itself for the scene's points, the reference
    /// position the growth chose for grown ones.
    pub x0: [f64; 2],
}

impl CrackPoint {
    fn at(x: [f64; 2]) -> Self {
        CrackPoint::grown(x, x)
    }
    fn grown(x: [f64; 2], x0: [f64; 2]) -> Self {
        CrackPoint {
            x,
            above: x,
            below: x,
            x0,
        }
    }
}

/// State of one end of a crack.
#[derive(Debug, Clone, Default)]
pub struct TipState {
    /// A real tip (false for a mouth, or a tip that has cut through the body).
    pub active: bool,
    /// Total growth of this tip (m).
    pub advance: f64,
    /// Energy released by its growth per unit thickness (J/m): Σ G·Δa over growth steps,
    /// with G the energy release rate that triggered each step.
    pub released: f64,
    /// (time, advance) over the last speed window.
    history: VecDeque<(f64, f64)>,
    /// The tip advanced in the last step.
    pub grew: bool,
    /// J (global x, y) cached at a time.
    cached_j: Option<(f64, [f64; 2])>,
}

/// One crack.
#[derive(Debug, Clone)]
pub struct Crack {
    /// Points from the start (tip 0) to the end (tip 1).
    pub pts: Vec<CrackPoint>,
    /// Tip 0 and tip 1.
    pub tips: [TipState; 2],
    contact: ContactLaw,
    propagation: Propagation,
    contour: usize,
    /// Length added at each end by the mouth extension (not reported).
    ext: [f64; 2],
}

impl Crack {
    /// Current length along the path, without the mouth extensions.
    pub fn length(&self) -> f64 {
        let l: f64 = self.pts.windows(2).map(|w| dist(w[0].x, w[1].x)).sum();
        l - self.ext[0] - self.ext[1]
    }

    /// Tip position and outward unit direction e1 of tip `t`.
    pub fn tip_frame(&self, t: usize) -> ([f64; 2], [f64; 2]) {
        let n = self.pts.len();
        let (tip, prev) = if t == 0 {
            (self.pts[0].x, self.pts[1].x)
        } else {
            (self.pts[n - 1].x, self.pts[n - 2].x)
        };
        let d = sub(tip, prev);
        let l = norm(d).max(1e-300);
        (tip, [d[0] / l, d[1] / l])
    }
}

/// A field-1 pair found by the crossing test: storage index of the node, crack, side of the
/// particle (+1 above, −1 below), normal of the crossed segment.
type FieldEntry = (u32, u32, i32, [f64; 2]);

/// Entries of one chunk of the parallel mask pass and its first error (node, fields needed).
type ChunkEntries = (Vec<FieldEntry>, Option<(usize, u32)>);

/// Field-1 node record: which side field 1 holds, the contact normal, the crack.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SlotInfo {
    /// Field 1 holds the particles above (left of) the crack.
    pub above_is_f1: bool,
    /// Unit normal from above to below.
    pub normal: [f64; 2],
    /// Crack index.
    pub crack: u32,
}

/// All cracks of a scene, with the scratch the crack steps reuse.
pub struct Cracks {
    /// The cracks.
    pub cracks: Vec<Crack>,
    /// Records of the field-1 nodes, parallel to the simulation's field-1 table.
    pub slots: Vec<SlotInfo>,
    h: f64,
    cfl: f64,
    thickness: f64,
    speed_window: f64,
    // Broad phase: segments (crack, segment) registered per cell, CSR.
    cell_start: Vec<u32>,
    cell_segs: Vec<(u32, u32)>,
    entries: Vec<FieldEntry>,
    /// Per-chunk entries and first error of the parallel mask pass.
    chunk_entries: Vec<ChunkEntries>,
    /// Normal contact impulse |Δp_n| of the last force-stage contact at each node (dense over
    /// grid storage): the friction capacity of faces that are in contact but not approaching
    /// at the extrapolation stages.
    normal_impulse: Vec<f64>,
    ncx: usize,
    ncy: usize,
    /// J-integrals evaluated so far (cache misses of `tip_j`): a work counter for benchmarks.
    j_evaluations: u64,
}

#[inline(always)]
fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}
#[inline(always)]
fn norm(a: [f64; 2]) -> f64 {
    a[0].hypot(a[1])
}
#[inline(always)]
fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    norm(sub(a, b))
}
/// Orientation of c relative to the directed line a → b: ≥ 0 counts as left (tie rule).
#[inline(always)]
fn left(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> bool {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) >= 0.0
}

/// Whether segment p → q crosses crack segment a → b (tie rule: on-line counts as left).
#[inline(always)]
pub fn crosses(p: [f64; 2], q: [f64; 2], a: [f64; 2], b: [f64; 2]) -> bool {
    left(a, b, p) != left(a, b, q) && left(p, q, a) != left(p, q, b)
}

/// Parameter t ∈ [0, 1] along p → q where it meets the line a → b.
fn cross_param(p: [f64; 2], q: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let r = sub(q, p);
    let s = sub(b, a);
    let den = r[0] * s[1] - r[1] * s[0];
    if den.abs() < 1e-300 {
        return 0.5;
    }
    let ap = sub(a, p);
    ((ap[0] * s[1] - ap[1] * s[0]) / den).clamp(0.0, 1.0)
}

/// Unit normal of a → b pointing from above (left) to below (right).
fn seg_normal(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    let d = sub(b, a);
    let l = norm(d).max(1e-300);
    [d[1] / l, -d[0] / l]
}

/// A mass-weighted nodal average at x: Σ S q(n) / Σ S m over the 4 nodes of x's cell (bilinear
/// S) that `node` gives and that carry mass. None outside the grid or where no such node has
/// mass.
fn mass_weighted_at<'n>(
    geom: &GridGeom,
    x: [f64; 2],
    node: impl Fn(usize, usize) -> Option<&'n Node>,
    q: impl Fn(&Node) -> [f64; 2],
) -> Option<[f64; 2]> {
    let xi = geom.xi(x);
    let (cx, cy) = (xi[0].floor(), xi[1].floor());
    if cx < 0.0 || cy < 0.0 || cx as usize + 1 >= geom.nx || cy as usize + 1 >= geom.ny {
        return None;
    }
    let (fx, fy) = (xi[0] - cx, xi[1] - cy);
    let (cx, cy) = (cx as usize, cy as usize);
    let (mut m, mut sum) = (0.0, [0.0; 2]);
    for (a, wa) in [(0, 1.0 - fx), (1, fx)] {
        for (b, wb) in [(0, 1.0 - fy), (1, fy)] {
            if let Some(n) = node(cx + a, cy + b)
                && n.m > 0.0
            {
                let (s, qn) = (wa * wb, q(n));
                m += s * n.m;
                sum[0] += s * qn[0];
                sum[1] += s * qn[1];
            }
        }
    }
    (m > 0.0).then(|| [sum[0] / m, sum[1] / m])
}

/// The material displacement at x: the field-0 nodal displacement Σ S m (x_p − X_p) over the
/// mass, mass-weighted over x's cell.
fn displacement_at(v: &View<'_>, x: [f64; 2]) -> Option<[f64; 2]> {
    mass_weighted_at(
        v.geom,
        x,
        |ix, iy| Some(&v.nodes[v.geom.index(ix, iy)]),
        |n| n.u,
    )
}

impl Cracks {
    /// The cracks of `scene`.
    pub fn new(scene: &Scene, geom: &GridGeom, _mats: &[Elastic]) -> Self {
        let h = geom.h;
        let cracks = scene
            .cracks
            .iter()
            .map(|c| {
                // Subdivide each segment to at most h/2.
                let mut pts = vec![CrackPoint::at(c.points[0])];
                for w in c.points.windows(2) {
                    let n = (dist(w[0], w[1]) / (0.5 * h)).ceil().max(1.0) as usize;
                    for k in 1..=n {
                        let t = k as f64 / n as f64;
                        pts.push(CrackPoint::at([
                            w[0][0] + t * (w[1][0] - w[0][0]),
                            w[0][1] + t * (w[1][1] - w[0][1]),
                        ]));
                    }
                }
                let inside = |p: [f64; 2]| scene.bodies.iter().any(|b| b.region.contains(p));
                let mut ext = [0.0; 2];
                let mut tips = [TipState::default(), TipState::default()];
                for end in 0..2 {
                    let n = pts.len();
                    let (i, j) = if end == 0 { (0, 1) } else { (n - 1, n - 2) };
                    if inside(pts[i].x) {
                        tips[end].active = true;
                    } else {
                        // Mouth: extend 2h outward along the end segment.
                        let d = sub(pts[i].x, pts[j].x);
                        let l = norm(d).max(1e-300);
                        let e = 2.0 * h;
                        let x = [pts[i].x[0] + e * d[0] / l, pts[i].x[1] + e * d[1] / l];
                        pts[i] = CrackPoint::at(x);
                        ext[end] = e;
                    }
                }
                Crack {
                    pts,
                    tips,
                    contact: c.contact.clone(),
                    propagation: c.propagation.clone(),
                    contour: c.j_contour.max(1) as usize,
                    ext,
                }
            })
            .collect();
        Cracks {
            cracks,
            slots: Vec::new(),
            h,
            cfl: scene.time.cfl,
            thickness: scene.thickness,
            speed_window: scene.output.speed_window,
            cell_start: Vec::new(),
            cell_segs: Vec::new(),
            entries: Vec::new(),
            chunk_entries: Vec::new(),
            normal_impulse: vec![0.0; geom.storage_len()],
            ncx: geom.nx - 1,
            ncy: geom.ny - 1,
            j_evaluations: 0,
        }
    }

    /// J-integral evaluations so far (one per tip and distinct sample time; a second request
    /// at the same time is served from the cache and not counted).
    pub fn j_evaluations(&self) -> u64 {
        self.j_evaluations
    }

    /// The crack lines (for snapshots), without mouth extensions.
    pub fn lines(&self) -> Vec<Vec<[f64; 2]>> {
        self.cracks
            .iter()
            .map(|c| {
                let mut l: Vec<[f64; 2]> = c.pts.iter().map(|p| p.x).collect();
                let n = l.len();
                for (end, (i, j)) in [(0usize, 1usize), (n - 1, n - 2)].into_iter().enumerate() {
                    if c.ext[end] > 0.0 {
                        let d = sub(l[i], l[j]);
                        let len = norm(d).max(1e-300);
                        let e = c.ext[end].min(len);
                        l[i] = [l[i][0] - e * d[0] / len, l[i][1] - e * d[1] / len];
                    }
                }
                l
            })
            .collect()
    }

    /// Rebuild the per-cell segment lists (segments' boxes grown by 3h).
    fn build_broad_phase(&mut self, geom: &GridGeom) {
        let (ncx, ncy) = (self.ncx, self.ncy);
        self.cell_start.clear();
        self.cell_start.resize(ncx * ncy + 1, 0);
        let margin = 3.0 * self.h;
        let cells_of = |a: [f64; 2], b: [f64; 2]| {
            let lo = geom.xi([a[0].min(b[0]) - margin, a[1].min(b[1]) - margin]);
            let hi = geom.xi([a[0].max(b[0]) + margin, a[1].max(b[1]) + margin]);
            let cx0 = (lo[0].floor().max(0.0) as usize).min(ncx - 1);
            let cx1 = (hi[0].floor().max(0.0) as usize).min(ncx - 1);
            let cy0 = (lo[1].floor().max(0.0) as usize).min(ncy - 1);
            let cy1 = (hi[1].floor().max(0.0) as usize).min(ncy - 1);
            (cx0, cx1, cy0, cy1)
        };
        for c in &self.cracks {
            for w in c.pts.windows(2) {
                let (x0, x1, y0, y1) = cells_of(w[0].x, w[1].x);
                for cx in x0..=x1 {
                    for cy in y0..=y1 {
                        self.cell_start[cx * ncy + cy + 1] += 1;
                    }
                }
            }
        }
        for i in 0..ncx * ncy {
            self.cell_start[i + 1] += self.cell_start[i];
        }
        let total = self.cell_start[ncx * ncy] as usize;
        self.cell_segs.clear();
        self.cell_segs.resize(total, (0, 0));
        let mut fill = self.cell_start.clone();
        for (ci, c) in self.cracks.iter().enumerate() {
            for (si, w) in c.pts.windows(2).enumerate() {
                let (x0, x1, y0, y1) = cells_of(w[0].x, w[1].x);
                for cx in x0..=x1 {
                    for cy in y0..=y1 {
                        let k = &mut fill[cx * ncy + cy];
                        self.cell_segs[*k as usize] = (ci as u32, si as u32);
                        *k += 1;
                    }
                }
            }
        }
    }

    /// Segments registered in the cell containing `x`.
    fn segs_near(&self, geom: &GridGeom, x: [f64; 2]) -> &[(u32, u32)] {
        let (cx, cy) = geom.cell(x);
        if cx < 0 || cy < 0 || cx as usize >= self.ncx || cy as usize >= self.ncy {
            return &[];
        }
        let c = cx as usize * self.ncy + cy as usize;
        &self.cell_segs[self.cell_start[c] as usize..self.cell_start[c + 1] as usize]
    }

    /// Field masks of the particles `kin`/`mech` into `fmask`, and the field-1 entries
    /// (node, crack, side vote, crossed-segment normal) in particle order.
    fn masks(
        &self,
        geom: &GridGeom,
        shape: ShapeFunction,
        kin: &[Kin],
        mech: &[Mech],
        fmask: &mut [u16],
        entries: &mut Vec<FieldEntry>,
    ) -> Result<(), (usize, u32)> {
        for (i, (k, m)) in kin.iter().zip(mech).enumerate() {
            let segs = self.segs_near(geom, k.x);
            if segs.is_empty() {
                fmask[i] = 0;
                continue;
            }
            let w = Weights2::new(shape, geom.xi(k.x), m.lh);
            let mut mask = 0u16;
            for a in 0..3 {
                if w.x.s[a] == 0.0 && w.x.ds[a] == 0.0 {
                    continue;
                }
                for b in 0..3 {
                    if w.y.s[b] == 0.0 && w.y.ds[b] == 0.0 {
                        continue;
                    }
                    let ix = (w.x.base + a as i32) as usize;
                    let iy = (w.y.base + b as i32) as usize;
                    let node = geom.node_pos(ix, iy);
                    // Parity of crossings per crack; side and normal of the last crossing.
                    let mut hit: Option<(u32, u32, bool, [f64; 2])> = None;
                    let mut other_crack = false;
                    for &(ci, si) in segs {
                        let c = &self.cracks[ci as usize];
                        let (pa, pb) = (c.pts[si as usize].x, c.pts[si as usize + 1].x);
                        if crosses(k.x, node, pa, pb) {
                            match &mut hit {
                                None => hit = Some((ci, 1, left(pa, pb, k.x), seg_normal(pa, pb))),
                                Some(h) if h.0 == ci => {
                                    h.1 += 1;
                                    h.2 = left(pa, pb, k.x);
                                    h.3 = seg_normal(pa, pb);
                                }
                                Some(_) => other_crack = true,
                            }
                        }
                    }
                    if let Some((ci, count, above, n)) = hit
                        && count % 2 == 1
                    {
                        if other_crack {
                            return Err((geom.index(ix, iy), 3));
                        }
                        mask |= 1 << (3 * a + b);
                        entries.push((
                            geom.index(ix, iy) as u32,
                            ci,
                            if above { 1 } else { -1 },
                            n,
                        ));
                    }
                }
            }
            fmask[i] = mask;
        }
        Ok(())
    }

    /// Assign the velocity field of every particle–node pair (§3); fills `f1_index` with the
    /// sorted storage indices of nodes needing field 1 and `self.slots` with their records.
    /// Err((node, fields)) when a node would need more than two fields.
    pub fn assign_fields(
        &mut self,
        geom: &GridGeom,
        shape: ShapeFunction,
        kin: &[Kin],
        mech: &[Mech],
        fmask: &mut [u16],
        f1_index: &mut Vec<u32>,
    ) -> Result<(), (usize, u32)> {
        self.build_broad_phase(geom);
        // Masks and field-1 entries per chunk of particles, in parallel; the chunks' entries
        // are concatenated in particle order, so the result is the same for any thread count.
        const CHUNK: usize = 4096;
        let mut chunks = std::mem::take(&mut self.chunk_entries);
        chunks.resize_with(kin.len().div_ceil(CHUNK), Default::default);
        let this = &*self;
        fmask
            .par_chunks_mut(CHUNK)
            .zip(kin.par_chunks(CHUNK))
            .zip(mech.par_chunks(CHUNK))
            .zip(chunks.par_iter_mut())
            .for_each(|(((fm, kn), me), (entries, err))| {
                entries.clear();
                *err = None;
                if let Err(e) = this.masks(geom, shape, kn, me, fm, entries) {
                    *err = Some(e);
                }
            });
        let mut entries = std::mem::take(&mut self.entries);
        entries.clear();
        let mut first_error = None;
        for (chunk, err) in &chunks {
            if let Some(e) = err {
                first_error = Some(*e);
                break;
            }
            entries.extend_from_slice(chunk);
        }
        self.chunk_entries = chunks;
        if let Some(e) = first_error {
            self.entries = entries;
            return Err(e);
        }
        entries.sort_unstable_by_key(|e| (e.0, e.1));
        f1_index.clear();
        self.slots.clear();
        let mut i = 0;
        while i < entries.len() {
            let node = entries[i].0;
            let crack = entries[i].1;
            let mut votes = 0i64;
            let mut n = [0.0; 2];
            while i < entries.len() && entries[i].0 == node {
                if entries[i].1 != crack {
                    return Err((node as usize, 3));
                }
                votes += entries[i].2 as i64;
                n[0] += entries[i].3[0];
                n[1] += entries[i].3[1];
                i += 1;
            }
            let l = norm(n);
            f1_index.push(node);
            self.slots.push(SlotInfo {
                above_is_f1: votes >= 0,
                normal: if l > 0.0 {
                    [n[0] / l, n[1] / l]
                } else {
                    [0.0, -1.0]
                },
                crack,
            });
        }
        self.entries = entries;
        Ok(())
    }

    /// Crack-face contact at every node with two fields (§4). Returns the frictional work.
    pub fn contact(
        &mut self,
        stage: Stage,
        nodes: &mut [Node],
        f1: &mut [Node],
        f1_index: &[u32],
        _m_tiny: f64,
        dt: f64,
    ) -> f64 {
        let mut friction_work = 0.0;
        for (s, info) in self.slots.iter().enumerate() {
            let n0 = &mut nodes[f1_index[s] as usize];
            let n1 = &mut f1[s];
            if n0.m <= 0.0 || n1.m <= 0.0 {
                continue;
            }
            let (a, b) = if info.above_is_f1 { (n1, n0) } else { (n0, n1) };
            let mom = |nd: &Node| match stage {
                Stage::Extrapolated => nd.p,
                Stage::Forces => [nd.p[0] + dt * nd.f[0], nd.p[1] + dt * nd.f[1]],
                Stage::Reextrapolated => nd.q,
            };
            let (pa, pb) = (mom(a), mom(b));
            let big_m = a.m + b.m;
            // Stick change: both fields at the centre-of-mass velocity.
            let d = [
                (a.m * pb[0] - b.m * pa[0]) / big_m,
                (a.m * pb[1] - b.m * pa[1]) / big_m,
            ];
            let n = info.normal;
            let dn = d[0] * n[0] + d[1] * n[1];
            let node_index = f1_index[s] as usize;
            let law = &self.cracks[info.crack as usize].contact;
            let applied = match law {
                ContactLaw::Stick => d,
                _ => {
                    // Separation from the fields' mass-weighted displacements.
                    let ua = [a.u[0] / a.m, a.u[1] / a.m];
                    let ub = [b.u[0] / b.m, b.u[1] / b.m];
                    let sep = (ub[0] - ua[0]) * n[0] + (ub[1] - ua[1]) * n[1];
                    let approaching = dn < 0.0;
                    if stage == Stage::Forces {
                        self.normal_impulse[node_index] =
                            if sep < 0.0 && approaching { -dn } else { 0.0 };
                    }
                    let held = self.normal_impulse[node_index];
                    let friction = match law {
                        ContactLaw::Coulomb { friction } => *friction,
                        _ => 0.0,
                    };
                    // In contact: overlapping and approaching; or, for friction at the
                    // extrapolation stages, overlapping and still pressed by the normal force
                    // of the last force stage (a static contact does not approach).
                    let pressed = stage != Stage::Forces && friction > 0.0 && held > 0.0;
                    if !(sep < 0.0 && (approaching || pressed)) {
                        continue;
                    }
                    let normal = if approaching {
                        [dn * n[0], dn * n[1]]
                    } else {
                        [0.0, 0.0]
                    };
                    if friction > 0.0 {
                        let t = [d[0] - dn * n[0], d[1] - dn * n[1]];
                        let tl = norm(t);
                        let capacity = if stage == Stage::Forces {
                            -dn
                        } else {
                            held.max(-dn)
                        };
                        let limit = friction * capacity.max(0.0);
                        if tl > limit {
                            [normal[0] + limit * t[0] / tl, normal[1] + limit * t[1] / tl]
                        } else {
                            [normal[0] + t[0], normal[1] + t[1]]
                        }
                    } else {
                        normal
                    }
                }
            };
            if stage == Stage::Forces && matches!(law, ContactLaw::Coulomb { .. }) {
                // Frictional work: kinetic energy the tangential impulse removes beyond what
                // the normal impulse alone removes.
                let ke = |da: [f64; 2]| {
                    let qa = [pa[0] + da[0], pa[1] + da[1]];
                    let qb = [pb[0] - da[0], pb[1] - da[1]];
                    0.5 * (qa[0] * qa[0] + qa[1] * qa[1]) / a.m
                        + 0.5 * (qb[0] * qb[0] + qb[1] * qb[1]) / b.m
                };
                let w = ke([dn * n[0], dn * n[1]]) - ke(applied);
                friction_work += w.max(0.0);
            }
            match stage {
                Stage::Extrapolated => {
                    for k in 0..2 {
                        a.p[k] += applied[k];
                        b.p[k] -= applied[k];
                    }
                }
                Stage::Forces => {
                    for k in 0..2 {
                        a.f[k] += applied[k] / dt;
                        b.f[k] -= applied[k] / dt;
                    }
                }
                Stage::Reextrapolated => {
                    for k in 0..2 {
                        a.q[k] += applied[k];
                        b.q[k] -= applied[k];
                    }
                }
            }
        }
        friction_work
    }

    /// The field of node `index` on the same side as `from` (a point just off the crack):
    /// field 0 when the line from → node does not cross a crack, field 1 when it does.
    #[allow(clippy::too_many_arguments)]
    fn side_node<'n>(
        &self,
        geom: &GridGeom,
        from: [f64; 2],
        ix: usize,
        iy: usize,
        nodes: &'n [Node],
        f1: &'n [Node],
        slot_of: &[u32],
    ) -> Option<&'n Node> {
        let node = geom.node_pos(ix, iy);
        let mut count = 0;
        for &(ci, si) in self.segs_near(geom, from) {
            let c = &self.cracks[ci as usize];
            if crosses(from, node, c.pts[si as usize].x, c.pts[si as usize + 1].x) {
                count += 1;
            }
        }
        let idx = geom.index(ix, iy);
        if count % 2 == 0 {
            Some(&nodes[idx])
        } else {
            let s = slot_of[idx];
            (s != u32::MAX).then(|| &f1[s as usize])
        }
    }

    /// Velocity at x of the side reached from `from`, bilinear and mass-weighted over the 4
    /// nodes of x's cell, using the re-extrapolated momenta.
    #[allow(clippy::too_many_arguments)]
    fn side_velocity(
        &self,
        geom: &GridGeom,
        x: [f64; 2],
        from: [f64; 2],
        nodes: &[Node],
        f1: &[Node],
        slot_of: &[u32],
    ) -> Option<[f64; 2]> {
        // Σ S m v = Σ S q.
        mass_weighted_at(
            geom,
            x,
            |ix, iy| self.side_node(geom, from, ix, iy, nodes, f1, slot_of),
            |n| n.q,
        )
    }

    /// Move the crack surfaces and lines with the grid velocities (§5).
    pub fn move_surfaces(
        &mut self,
        geom: &GridGeom,
        nodes: &[Node],
        f1: &[Node],
        slot_of: &[u32],
        _m_tiny: f64,
        dt: f64,
    ) {
        let eps = 1e-3 * self.h;
        for ci in 0..self.cracks.len() {
            let n = self.cracks[ci].pts.len();
            for k in 0..n {
                let c = &self.cracks[ci];
                // Local direction of the crack at point k.
                let (pa, pb) = if k == 0 {
                    (c.pts[0].x, c.pts[1].x)
                } else if k == n - 1 {
                    (c.pts[n - 2].x, c.pts[n - 1].x)
                } else {
                    (c.pts[k - 1].x, c.pts[k + 1].x)
                };
                let nrm = seg_normal(pa, pb); // above → below
                let pt = c.pts[k];
                let from_above = [pt.above[0] - eps * nrm[0], pt.above[1] - eps * nrm[1]];
                let from_below = [pt.below[0] + eps * nrm[0], pt.below[1] + eps * nrm[1]];
                let va = self.side_velocity(geom, pt.above, from_above, nodes, f1, slot_of);
                let vb = self.side_velocity(geom, pt.below, from_below, nodes, f1, slot_of);
                let (va, vb) = match (va, vb) {
                    (Some(a), Some(b)) => (a, b),
                    (Some(a), None) => (a, a),
                    (None, Some(b)) => (b, b),
                    (None, None) => continue,
                };
                let is_tip = (k == 0 && c.tips[0].active) || (k == n - 1 && c.tips[1].active);
                let p = &mut self.cracks[ci].pts[k];
                if is_tip {
                    // The faces meet at a tip: both surfaces move with the mean.
                    let v = [0.5 * (va[0] + vb[0]), 0.5 * (va[1] + vb[1])];
                    p.x = [p.x[0] + dt * v[0], p.x[1] + dt * v[1]];
                    p.above = p.x;
                    p.below = p.x;
                } else {
                    p.above = [p.above[0] + dt * va[0], p.above[1] + dt * va[1]];
                    p.below = [p.below[0] + dt * vb[0], p.below[1] + dt * vb[1]];
                    p.x = [
                        0.5 * (p.above[0] + p.below[0]),
                        0.5 * (p.above[1] + p.below[1]),
                    ];
                }
            }
        }
    }
}

/// Read-only state of the simulation that the J-integral and propagation need (the grid of
/// the last step is still in place between steps).
pub struct View<'a> {
    /// Grid geometry.
    pub geom: &'a GridGeom,
    /// Shape functions.
    pub shape: ShapeFunction,
    /// Particles.
    pub parts: &'a Particles,
    /// Materials.
    pub mats: &'a [Elastic],
    /// Field-0 nodes.
    pub nodes: &'a [Node],
    /// Field-1 nodes.
    pub f1: &'a [Node],
    /// Storage index → field-1 slot.
    pub slot_of: &'a [u32],
    /// Particle range of each strip.
    pub strip_bounds: &'a [usize],
}

impl View<'_> {
    #[inline(always)]
    fn node(&self, ix: usize, iy: usize, field: u8) -> Option<&Node> {
        let idx = self.geom.index(ix, iy);
        if field == 0 {
            Some(&self.nodes[idx])
        } else {
            let s = *self.slot_of.get(idx)?;
            (s != u32::MAX).then(|| &self.f1[s as usize])
        }
    }
}

/// One edge of the J contour: from node, to node, outward normal.
type ContourEdge = ((usize, usize), (usize, usize), [f64; 2]);

/// J of one tip with what K needs.
#[derive(Debug, Clone, Copy, Default)]
struct TipJ {
    j: [f64; 2],
}

/// J of a tip in its own frame: e1 ahead along the crack, e2 to its left.
#[derive(Debug, Clone, Copy)]
struct TipFrameJ {
    tip: [f64; 2],
    e1: [f64; 2],
    e2: [f64; 2],
    j1: f64,
    j2: f64,
}

/// Dynamic correction factors A_I(v), A_II(v) of a moving crack (plane strain,
/// `reference-solutions.md`); 1 at rest, and 1 (static relation) where the sub-Rayleigh
/// formula does not apply.
fn moving_factors(v: f64, m: &Elastic) -> (f64, f64) {
    let c_s = (m.e / (2.0 * (1.0 + m.nu) * m.rho)).sqrt();
    let c_r = fracture_api::scene::rayleigh_speed(m.c_l, c_s);
    if v <= 1e-3 * c_s || v >= 0.95 * c_r {
        return (1.0, 1.0);
    }
    let ad = (1.0 - (v / m.c_l).powi(2)).sqrt();
    let as_ = (1.0 - (v / c_s).powi(2)).sqrt();
    let d = 4.0 * ad * as_ - (1.0 + as_ * as_).powi(2);
    let k = v * v / ((1.0 - m.nu) * c_s * c_s * d);
    (k * ad, k * as_)
}

impl Cracks {
    /// Dynamic J (global components) at tip `t` of crack `ci`: contour plus area term.
    fn compute_j(&self, ci: usize, t: usize, v: &View<'_>) -> TipJ {
        let g = v.geom;
        let h = g.h;
        let c = &self.cracks[ci];
        let (tip, _) = c.tip_frame(t);
        let n = c.contour as i64;
        let xi = g.xi(tip);
        let (c0, r0) = (xi[0].round() as i64, xi[1].round() as i64);
        // Window of nodes around the contour.
        let (wx0, wy0) = (c0 - n - 1, r0 - n - 1);
        let wn = (2 * n + 3) as usize;
        if wx0 < 0 || wy0 < 0 || wx0 as usize + wn > g.nx || wy0 as usize + wn > g.ny {
            return TipJ::default();
        }
        let (wx0, wy0) = (wx0 as usize, wy0 as usize);
        const NV: usize = 9;
        let mut mass = vec![0.0f64; wn * wn];
        let mut vals = vec![0.0f64; wn * wn * NV];
        let mut area = [0.0f64; 2];
        let box_lo = [(c0 - n) as f64, (r0 - n) as f64];
        let box_hi = [(c0 + n) as f64, (r0 + n) as f64];
        let p = v.parts;
        let s_lo = ((wx0 as i64 - 5).max(0) as usize) / STRIP;
        let s_hi = ((wx0 + wn + 5) / STRIP).min(g.strips - 1);
        let range = v.strip_bounds[s_lo]..v.strip_bounds[s_hi + 1];
        let has_mask = !p.fmask.is_empty();
        for i in range {
            let k = p.kin[i];
            let pxi = g.xi(k.x);
            if pxi[0] < wx0 as f64 - 2.0
                || pxi[1] < wy0 as f64 - 2.0
                || pxi[0] > (wx0 + wn) as f64 + 1.0
                || pxi[1] > (wy0 + wn) as f64 + 1.0
            {
                continue;
            }
            let m = p.mech[i];
            let s = p.stress[i];
            let gu = p.grad_u[i];
            let rho = m.m / m.vol;
            let ke = 0.5 * rho * (k.v[0] * k.v[0] + k.v[1] * k.v[1]);
            let pv = [s[0], s[1], s[2], gu[0], gu[1], gu[2], gu[3], m.w, ke];
            let w = Weights2::new(v.shape, pxi, m.lh);
            let mask = if has_mask { p.fmask[i] } else { 0 };
            let inside = pxi[0] > box_lo[0]
                && pxi[0] < box_hi[0]
                && pxi[1] > box_lo[1]
                && pxi[1] < box_hi[1];
            let mut acc = [0.0; 2];
            let mut gv = [[0.0; 2]; 2];
            for a in 0..3 {
                for b in 0..3 {
                    let sh = w.s(a, b);
                    let gr = w.g(a, b);
                    if sh == 0.0 && gr[0] == 0.0 && gr[1] == 0.0 {
                        continue;
                    }
                    let ix = (w.x.base + a as i32) as usize;
                    let iy = (w.y.base + b as i32) as usize;
                    let field = ((mask >> (3 * a + b)) & 1) as u8;
                    if field == 0
                        && ix >= wx0
                        && iy >= wy0
                        && ix < wx0 + wn
                        && iy < wy0 + wn
                        && sh > 0.0
                    {
                        let wk = (ix - wx0) * wn + (iy - wy0);
                        mass[wk] += sh * m.m;
                        for q in 0..NV {
                            vals[wk * NV + q] += sh * m.m * pv[q];
                        }
                    }
                    if inside
                        && let Some(nd) = v.node(ix, iy, field)
                        && nd.m > 0.0
                    {
                        for r in 0..2 {
                            acc[r] += sh * nd.f[r] / nd.m;
                            let vel = nd.q[r] / nd.m;
                            gv[r][0] += vel * gr[0] / h;
                            gv[r][1] += vel * gr[1] / h;
                        }
                    }
                }
            }
            if inside {
                // ∫_A ρ [ü_i ∂u_i/∂x_k − u̇_i ∂u̇_i/∂x_k] dA, per unit thickness.
                let da = m.vol / self.thickness * rho;
                for kk in 0..2 {
                    area[kk] += da
                        * (acc[0] * gu[kk] + acc[1] * gu[2 + kk]
                            - k.v[0] * gv[0][kk]
                            - k.v[1] * gv[1][kk]);
                }
            }
        }
        // Contour integrand at a window node with outward normal nrm.
        let integrand = |ix: usize, iy: usize, nrm: [f64; 2]| -> [f64; 2] {
            let wk = (ix - wx0) * wn + (iy - wy0);
            let m = mass[wk];
            if m <= 0.0 {
                return [0.0; 2];
            }
            let q = |k: usize| vals[wk * NV + k] / m;
            let (sxx, syy, sxy) = (q(0), q(1), q(2));
            let gu = [q(3), q(4), q(5), q(6)];
            let e = q(7) + q(8);
            let tr = [sxx * nrm[0] + sxy * nrm[1], sxy * nrm[0] + syy * nrm[1]];
            [
                e * nrm[0] - (tr[0] * gu[0] + tr[1] * gu[2]),
                e * nrm[1] - (tr[0] * gu[1] + tr[1] * gu[3]),
            ]
        };
        // Walk the square counter-clockwise: bottom, right, top, left edges.
        let (cx0, cx1) = ((c0 - n) as usize, (c0 + n) as usize);
        let (cy0, cy1) = ((r0 - n) as usize, (r0 + n) as usize);
        let mut edges: Vec<ContourEdge> = Vec::new();
        for ix in cx0..cx1 {
            edges.push(((ix, cy0), (ix + 1, cy0), [0.0, -1.0]));
        }
        for iy in cy0..cy1 {
            edges.push(((cx1, iy), (cx1, iy + 1), [1.0, 0.0]));
        }
        for ix in (cx0 + 1..=cx1).rev() {
            edges.push(((ix, cy1), (ix - 1, cy1), [0.0, 1.0]));
        }
        for iy in (cy0 + 1..=cy1).rev() {
            edges.push(((cx0, iy), (cx0, iy - 1), [-1.0, 0.0]));
        }
        let mut j = area;
        for (pn, qn, nrm) in edges {
            let (pp, qp) = (g.node_pos(pn.0, pn.1), g.node_pos(qn.0, qn.1));
            let fp = integrand(pn.0, pn.1, nrm);
            let fq = integrand(qn.0, qn.1, nrm);
            let cut = c
                .pts
                .windows(2)
                .find(|w| crosses(pp, qp, w[0].x, w[1].x))
                .map(|w| cross_param(pp, qp, w[0].x, w[1].x));
            for r in 0..2 {
                j[r] += match cut {
                    // Each face of the crack uses its own side's values up to the crossing.
                    Some(tc) => h * (tc * fp[r] + (1.0 - tc) * fq[r]),
                    None => 0.5 * h * (fp[r] + fq[r]),
                };
            }
        }
        TipJ { j }
    }

    fn tip_j(&mut self, ci: usize, t: usize, v: &View<'_>, time: f64) -> TipJ {
        if let Some((tc, j)) = self.cracks[ci].tips[t].cached_j
            && tc == time
        {
            return TipJ { j };
        }
        let tj = self.compute_j(ci, t, v);
        self.j_evaluations += 1;
        self.cracks[ci].tips[t].cached_j = Some((time, tj.j));
        tj
    }

    /// J at tip `t` of crack `ci` rotated into the tip frame.
    fn tip_frame_j(&mut self, ci: usize, t: usize, v: &View<'_>, time: f64) -> TipFrameJ {
        let tj = self.tip_j(ci, t, v, time);
        let (tip, e1) = self.cracks[ci].tip_frame(t);
        let e2 = [-e1[1], e1[0]];
        TipFrameJ {
            tip,
            e1,
            e2,
            j1: tj.j[0] * e1[0] + tj.j[1] * e1[1],
            j2: tj.j[0] * e2[0] + tj.j[1] * e2[1],
        }
    }

    /// Moving-box tip speed over the speed window.
    fn tip_speed(&self, tip: &TipState, time: f64) -> f64 {
        let Some(&(t0, a0)) = tip
            .history
            .iter()
            .find(|(t, _)| *t >= time - self.speed_window - 1e-15)
        else {
            return 0.0;
        };
        let span = time - t0;
        if span <= 0.0 {
            0.0
        } else {
            (tip.advance - a0) / span
        }
    }

    /// Opening (δ_n, δ_t) in the tip frame, about 2h behind tip `t`: left face − right face.
    fn tip_opening(&self, ci: usize, t: usize) -> [f64; 2] {
        let c = &self.cracks[ci];
        let (_, e1) = c.tip_frame(t);
        let e2 = [-e1[1], e1[0]];
        let n = c.pts.len();
        let order: Box<dyn Iterator<Item = usize>> = if t == 0 {
            Box::new(0..n)
        } else {
            Box::new((0..n).rev())
        };
        let mut prev: Option<[f64; 2]> = None;
        let mut s = 0.0;
        let mut at = if t == 0 { n - 1 } else { 0 };
        for k in order {
            if let Some(p) = prev {
                s += dist(p, c.pts[k].x);
            }
            prev = Some(c.pts[k].x);
            if s >= 2.0 * self.h {
                at = k;
                break;
            }
        }
        let p = c.pts[at];
        let cod = if t == 1 {
            sub(p.above, p.below)
        } else {
            sub(p.below, p.above)
        };
        [
            cod[0] * e2[0] + cod[1] * e2[1],
            cod[0] * e1[0] + cod[1] * e1[1],
        ]
    }

    /// Crack-tip rows now.
    pub fn tip_rows(&mut self, v: &View<'_>, time: f64) -> Vec<CrackTipRow> {
        let mut rows = Vec::new();
        for ci in 0..self.cracks.len() {
            for t in 0..2 {
                if !self.cracks[ci].tips[t].active {
                    continue;
                }
                let TipFrameJ {
                    tip,
                    e1: _,
                    e2: _,
                    j1,
                    j2,
                } = self.tip_frame_j(ci, t, v, time);
                let c = &self.cracks[ci];
                let speed = self.tip_speed(&c.tips[t], time);
                let mat = &v.mats[self.nearest_material(v, tip)];
                let [dn, dt] = self.tip_opening(ci, t);
                let (k1, k2) = if j1 <= 0.0 {
                    (0.0, 0.0)
                } else {
                    let r = dn.hypot(dt);
                    let (cphi, sphi) = if r > 1e-12 * self.h {
                        (dn / r, dt / r)
                    } else {
                        (1.0, 0.0)
                    };
                    let (ai, aii) = moving_factors(speed, mat);
                    let k = (mat.e_prime * j1 / (ai * cphi * cphi + aii * sphi * sphi)).sqrt();
                    (k * cphi, k * sphi)
                };
                rows.push(CrackTipRow {
                    time,
                    crack: ci as u32,
                    tip: t as u32,
                    x: tip[0],
                    y: tip[1],
                    length: c.length(),
                    speed,
                    j1,
                    j2,
                    k1,
                    k2,
                    growing: c.tips[t].grew,
                });
            }
        }
        rows
    }

    fn nearest_material(&self, v: &View<'_>, x: [f64; 2]) -> usize {
        if v.mats.len() == 1 {
            return 0;
        }
        let p = v.parts;
        let mut best = (f64::INFINITY, 0usize);
        for (k, m) in p.kin.iter().zip(&p.mech) {
            let d = dist(k.x, x);
            if d < best.0 {
                best = (d, m.mat as usize);
            }
        }
        best.1
    }

    /// Check every growing tip (§7) and grow it; records the tip history. True if some tip
    /// advanced.
    pub fn propagate(&mut self, v: &View<'_>, time: f64) -> bool {
        let mut any = false;
        let step_len = self.cfl * self.h;
        for ci in 0..self.cracks.len() {
            for t in 0..2 {
                self.cracks[ci].tips[t].grew = false;
                let Propagation::EnergyRelease {
                    toughness,
                    direction,
                    ..
                } = self.cracks[ci].propagation.clone()
                else {
                    continue;
                };
                if !self.cracks[ci].tips[t].active {
                    continue;
                }
                let TipFrameJ {
                    tip,
                    e1,
                    e2,
                    j1,
                    j2,
                } = self.tip_frame_j(ci, t, v, time);
                let (g, dir) = match direction {
                    GrowthDirection::MaxEnergyRelease => {
                        let th = j2.atan2(j1);
                        let (s, co) = th.sin_cos();
                        (
                            j1.hypot(j2),
                            [co * e1[0] + s * e2[0], co * e1[1] + s * e2[1]],
                        )
                    }
                    GrowthDirection::Fixed(d) => {
                        let l = norm(d).max(1e-300);
                        let mut d = [d[0] / l, d[1] / l];
                        // The direction is a line: take the sense that points ahead.
                        if d[0] * e1[0] + d[1] * e1[1] < 0.0 {
                            d = [-d[0], -d[1]];
                        }
                        let co = d[0] * e1[0] + d[1] * e1[1];
                        let s = d[0] * e2[0] + d[1] * e2[1];
                        (j1 * co + j2 * s, d)
                    }
                };
                if g < toughness || !g.is_finite() {
                    continue;
                }
                let (tip_i, prev_i) = {
                    let n = self.cracks[ci].pts.len();
                    if t == 0 { (0, 1) } else { (n - 1, n - 2) }
                };
                let tip0 = self.cracks[ci].pts[tip_i].x0;
                let ahead = [tip[0] + step_len * dir[0], tip[1] + step_len * dir[1]];
                let ahead0 = [tip0[0] + step_len * dir[0], tip0[1] + step_len * dir[1]];
                let new = match direction {
                    // A fixed direction is a line of the undeformed body (a bond, a weak
                    // plane): the new tip is where the material point a step ahead of the
                    // tip's material point along it is now, X + u(X), with u the nodal
                    // displacement field (two fixed-point passes from the straight guess).
                    // Growing straight in the current configuration instead lets the tip
                    // walk off a sheared bond by step × ∂u_n/∂s per growth step.
                    GrowthDirection::Fixed(_) => {
                        let mut x = ahead;
                        for _ in 0..2 {
                            if let Some(u) = displacement_at(v, x) {
                                x = [ahead0[0] + u[0], ahead0[1] + u[1]];
                            }
                        }
                        x
                    }
                    GrowthDirection::MaxEnergyRelease => ahead,
                };
                // Material ahead? If not, the crack has cut through: it becomes a mouth.
                let xi = v.geom.xi(new);
                let (ix, iy) = (xi[0].round(), xi[1].round());
                let has_material = ix >= 1.0
                    && iy >= 1.0
                    && (ix as usize) + 1 < v.geom.nx
                    && (iy as usize) + 1 < v.geom.ny
                    && v.nodes[v.geom.index(ix as usize, iy as usize)].m > 0.0;
                let c = &mut self.cracks[ci];
                if !has_material {
                    let e = 2.0 * self.h;
                    let out = [new[0] + e * dir[0], new[1] + e * dir[1]];
                    if t == 0 {
                        c.pts.insert(0, CrackPoint::at(out));
                    } else {
                        c.pts.push(CrackPoint::at(out));
                    }
                    c.ext[t] = e;
                    c.tips[t].active = false;
                    continue;
                }
                // Keep segments at least h/2: extend a short tip segment instead of adding.
                let short = dist(c.pts[tip_i].x, c.pts[prev_i].x) < 0.5 * self.h * (1.0 - 1e-9);
                let point = CrackPoint::grown(new, ahead0);
                if short {
                    c.pts[tip_i] = point;
                } else if t == 0 {
                    c.pts.insert(0, point);
                } else {
                    c.pts.push(point);
                }
                c.tips[t].advance += step_len;
                c.tips[t].released += g * step_len;
                c.tips[t].grew = true;
                c.tips[t].cached_j = None;
                any = true;
            }
        }
        // Tip histories for the moving-box speed.
        let keep = 2.0 * self.speed_window;
        for c in &mut self.cracks {
            for tip in &mut c.tips {
                tip.history.push_back((time, tip.advance));
                while tip.history.front().is_some_and(|(t0, _)| *t0 < time - keep) {
                    tip.history.pop_front();
                }
            }
        }
        any
    }
}
