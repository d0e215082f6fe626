//! Explicit cracks (`algorithm.md` §3–§7; Nairn 2003, Guo & Nairn 2004/2006).
//!
//! This file holds the data (crack points, tips, cracks, the [`Cracks`] set with its scratch,
//! the [`View`] of the simulation that J and propagation read) and the construction; each
//! stage of the crack step lives in its own file, in step order:
//!
//! * Geometry (built here; side and crossing tests and the broad phase in `geometry.rs`):
//!   each crack is a polyline of crack points, each with its line position and an "above"
//!   (left of the directed polyline) and "below" surface position. Scene segments are
//!   subdivided to at most h/2 so the surfaces and the crack opening are resolved. An end
//!   outside every body is a mouth, not a tip, and is pushed 2h further out so the fields
//!   separate cleanly at the surface.
//! * Fields (§3, `fields.rs`): for every particle–node pair the segment x_p → x_i is tested
//!   against the crack segments registered in the particle's cell (broad phase: a per-cell
//!   list rebuilt each step). An odd number of crossings puts the pair in field 1. Tie rule: a
//!   point exactly on a crack line counts as above (left), consistently in every orientation
//!   test, so a node on the line is classified without ambiguity.
//! * Contact (§4, `contact.rs`) at every momentum stage, as ±Δp so momentum is conserved
//!   exactly.
//! * Motion (§5, `motion.rs`): each surface point moves with the mass-weighted velocity of its
//!   own side's fields on the 4 nodes of its cell; the line point takes the mean of its two
//!   surfaces.
//! * J (§6, `j_integral.rs`): contour of grid lines, a square of half-size `j_contour` cells
//!   around the node nearest the tip, nodal values as mass-weighted particle averages of the
//!   node's own field, trapezoid rule, the edge crossed by the crack split at the crossing with
//!   each face using its own node's values; plus the area term over the particles inside the
//!   square.
//! * K (§6, `j_integral.rs`): K_I² + K_II² from E'·J1 (with A_I(v), A_II(v) for a moving
//!   tip), the mode ratio K_I/K_II = δ_n/δ_t from the crack opening about 2h behind the tip.
//! * Propagation (§7, `propagation.rs`): G ≥ toughness grows the tip by cfl·h (the seed's
//!   C_L·Δt) in the chosen direction; segments stay at least h/2 long.

mod cohesive;
mod contact;
mod domain;
mod fields;
mod geometry;
mod j_integral;
mod motion;
mod propagation;
mod zone;

pub use cohesive::Bond;
pub use contact::Stage;
pub use fields::{BODY_CONTACT, SlotInfo};
pub use geometry::crosses;
pub use zone::Zone;

use std::collections::VecDeque;

use fracture_api::Scene;
use fracture_api::scene::{Analysis, ContactLaw, JIntegral, Propagation, ShapeFunction};

use crate::grid::{GridGeom, Node};
use crate::material::Elastic;
use crate::particles::Particles;
use crate::shape::Weights2;
use crate::tip_mechanics::TipMedium;

use fields::{ChunkEntries, FieldEntry};
use geometry::{dist, norm, sub};

/// A point of a crack: its line position and its two surfaces.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
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
    /// The process-zone traction state of a point that growth by the equation of motion
    /// created (`zone.rs`); None for the scene's points and the seed's rule.
    pub zone: Option<Zone>,
    /// The cohesive state of an interface point (`cohesive.rs`); None for crack points.
    pub bond: Option<Bond>,
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
            zone: None,
            bond: None,
        }
    }
}

/// State of one end of a crack.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
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
    /// Energy the new surface takes per unit thickness (J/m): Σ Γ(v)·Δa over advances (at the
    /// speed wall, the energy that reached the tip: `propagation::WALL_FRACTION`).
    pub required: f64,
    /// The part of `required` above Γ(v), taken at the speed limit (J/m).
    #[serde(default)]
    pub above_toughness: f64,
    /// The driving force G filtered over the filter time (equation of motion); NaN until the
    /// first finite sample.
    pub g_filtered: f64,
    /// The speed the equation of motion gave in the last step (m/s).
    pub eom_speed: f64,
    /// J and K cached at a time.
    cached_j: Option<(f64, j_integral::TipEval)>,
    /// The tip lies on an interface, which grows instead of it (`algorithm.md` §8).
    pub on_interface: bool,
    /// The tip's advance when it last kinked (its direction turned by more than
    /// `propagation::KINK_DEG`), while the kinked branch is shorter than the J ring: its
    /// driving force then comes from the parent crack (`j_integral.rs`, pitfall 15).
    #[serde(default)]
    pub kink_at: Option<f64>,
}

/// One crack.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Crack {
    /// Points from the start (tip 0) to the end (tip 1).
    pub pts: Vec<CrackPoint>,
    /// Tip 0 and tip 1.
    pub tips: [TipState; 2],
    // The scene's laws: not in checkpoints (internally tagged, and the scene gives them).
    #[serde(skip)]
    contact: ContactLaw,
    #[serde(skip)]
    propagation: Propagation,
    /// Verification only: a prescribed (speed m/s, toughness J/m²) that replaces the
    /// equation of motion's speed and the toughness its process zone takes
    /// (`Simulation::set_prescribed_motion`); not in checkpoints.
    #[serde(skip)]
    pub(crate) prescribed: Option<[f64; 2]>,
    /// How J is evaluated (domain or contour).
    #[serde(skip, default = "default_j_method")]
    j_method: JIntegral,
    /// Length added at each end by the mouth extension (not reported).
    ext: [f64; 2],
    /// A cohesive interface (`scene.interfaces`), not a crack of `scene.cracks`.
    pub interface: bool,
    /// An interface's fronts (`cohesive.rs`).
    pub fronts: Fronts,
    /// The crack whose velocity fields this one shares (its own index, or for an interface
    /// that continues a crack's tip, that crack's group): one line, one pair of fields.
    pub group: u32,
}

/// The fronts of a cohesive interface, as distances along it from its first point (m) and
/// the index of the crack point there.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Fronts {
    /// Farthest fully failed point, connected to a crack or not.
    pub failure: Option<(f64, usize)>,
    /// Farthest point past its peak traction (the process zone's front).
    pub zone: Option<(f64, usize)>,
    /// Last point of the unbroken run of failed points from the interface's first point.
    pub connected_failure: Option<(f64, usize)>,
    /// Last point of the unbroken run of softening (or failed) points from the first point.
    pub connected_zone: Option<(f64, usize)>,
    /// Failed length (m): Σ of the failed points' shares.
    pub failed_length: f64,
}

impl Crack {
    /// The lengths of the segments before and after point k (0 at an end), measured on
    /// `at` (the current line `|p| p.x` or the reference `|p| p.x0`).
    pub(super) fn neighbour_lengths(
        &self,
        k: usize,
        at: impl Fn(&CrackPoint) -> [f64; 2],
    ) -> [f64; 2] {
        let n = self.pts.len();
        let back = if k > 0 {
            dist(at(&self.pts[k - 1]), at(&self.pts[k]))
        } else {
            0.0
        };
        let fore = if k + 1 < n {
            dist(at(&self.pts[k]), at(&self.pts[k + 1]))
        } else {
            0.0
        };
        [back, fore]
    }

    /// Current length along the path, without the mouth extensions.
    pub fn length(&self) -> f64 {
        let l: f64 = self.pts.windows(2).map(|w| dist(w[0].x, w[1].x)).sum();
        l - self.ext[0] - self.ext[1]
    }

    /// Unit normal from above to below at point `k`: of the chord through its neighbours
    /// (of the end segment at an end).
    pub(crate) fn local_normal(&self, k: usize) -> [f64; 2] {
        let n = self.pts.len();
        let (pa, pb) = if k == 0 {
            (self.pts[0].x, self.pts[1].x)
        } else if k == n - 1 {
            (self.pts[n - 2].x, self.pts[n - 1].x)
        } else {
            (self.pts[k - 1].x, self.pts[k + 1].x)
        };
        geometry::seg_normal(pa, pb)
    }

    /// The contact normal of segment `si` (`fields.rs`): for an interface, the normal of the
    /// chord from the farthest points within `h` behind its start and ahead of its end, the
    /// line's direction over a node's support. One h/2 segment's normal tilts by the line's sub-micrometre
    /// wiggle (the points are the means of two surfaces that contact leaves overlapping) over
    /// h/2, a tilt that doubles with each halving of h; through the frictionless normal
    /// impulse it acted as a friction that grew as the cells shrank (the Rosakis bond at
    /// 0.125 mm, `docs/scene-extensions.md`).
    ///
    /// Used for interfaces; a scene crack keeps its segment's normal until the studies whose
    /// numbers its contact enters (`docs/rosakis.md`) are regenerated with the chord.
    pub(crate) fn contact_normal(&self, si: u32, h: f64) -> [f64; 2] {
        let si = si as usize;
        if !self.interface {
            return geometry::seg_normal(self.pts[si].x, self.pts[si + 1].x);
        }
        self.chord_normal(si, h)
    }

    /// The normal of the chord around segment `si` (see `contact_normal`).
    fn chord_normal(&self, si: usize, h: f64) -> [f64; 2] {
        let n = self.pts.len();
        let (mut lo, mut hi) = (si, (si + 1).min(n - 1));
        while lo > 0 && geometry::dist(self.pts[lo - 1].x, self.pts[si].x) <= h {
            lo -= 1;
        }
        while hi + 1 < n && geometry::dist(self.pts[hi + 1].x, self.pts[si + 1].x) <= h {
            hi += 1;
        }
        geometry::seg_normal(self.pts[lo].x, self.pts[hi].x)
    }

    /// Tip position and outward unit direction e1 of tip `t`: along the chord from the first
    /// point at least h/2 behind the tip (the other end if none is). A growing tip's last
    /// segment starts at zero length and its end point is placed by the interpolated
    /// displacement (`propagation.rs`), so its own direction is noise until it is h/2 long;
    /// a direction from it once turned a tip backwards (J1 = −G at a DCB's first step).
    pub fn tip_frame(&self, t: usize, h: f64) -> ([f64; 2], [f64; 2]) {
        let n = self.pts.len();
        let at = |i: usize| {
            if t == 0 {
                self.pts[i].x
            } else {
                self.pts[n - 1 - i].x
            }
        };
        let tip = at(0);
        let prev = (1..n)
            .map(at)
            .find(|&p| geometry::dist(p, tip) >= 0.5 * h)
            .unwrap_or_else(|| at(n - 1));
        let d = sub(tip, prev);
        let l = norm(d).max(1e-300);
        (tip, [d[0] / l, d[1] / l])
    }
}

/// All cracks of a scene, with the scratch the crack steps reuse. Serialized for checkpoints
/// (`sim/checkpoint.rs`) without the scratch (`#[serde(skip)]`, taken from a fresh build).
#[derive(serde::Serialize, serde::Deserialize)]
pub struct Cracks {
    /// The cracks.
    pub cracks: Vec<Crack>,
    /// Records of the field-1 nodes, parallel to the simulation's field-1 table.
    pub slots: Vec<SlotInfo>,
    /// Per body: whether it carries the contact field (`Body::contact`); from the scene.
    #[serde(skip)]
    contact_bodies: Vec<bool>,
    /// The contact bodies' law (`Body::contact`), the same for all of them; from the scene.
    #[serde(skip)]
    body_contact: ContactLaw,
    h: f64,
    cfl: f64,
    thickness: f64,
    speed_window: f64,
    // Broad phase: segments (crack, segment) registered per cell, CSR.
    #[serde(skip)]
    cell_start: Vec<u32>,
    #[serde(skip)]
    cell_segs: Vec<(u32, u32)>,
    #[serde(skip)]
    entries: Vec<FieldEntry>,
    /// Per-chunk entries and first error of the parallel mask pass.
    #[serde(skip)]
    chunk_entries: Vec<ChunkEntries>,
    /// Normal contact impulse |Δp_n| of the last force-stage contact at each node (dense over
    /// grid storage): the friction capacity of faces that are in contact but not approaching
    /// at the extrapolation stages.
    normal_impulse: Vec<f64>,
    ncx: usize,
    ncy: usize,
    /// J-integrals evaluated so far (cache misses of `tip_j`): a work counter for benchmarks.
    j_evaluations: u64,
    /// The tip constants of each material in the scene's 2D state.
    media: Vec<TipMedium>,
    /// Force-stage contact force on the above side's material at each field-1 slot (the
    /// crack-face traction of the J face term); empty until the first force-stage contact.
    face_force: Vec<[f64; 2]>,
    /// Energy removed by the process-zone tractions so far (J, the scene's thickness).
    zone_work: f64,
    /// Time step (s).
    dt: f64,
}

/// Placeholder of a checkpoint's skipped J method (the scene's is put back on restore).
fn default_j_method() -> JIntegral {
    JIntegral::Domain { radius: 0.0 }
}

/// Distance from x to a polyline (m).
fn polyline_distance(points: &[[f64; 2]], x: [f64; 2]) -> f64 {
    points
        .windows(2)
        .map(|w| {
            let d = sub(w[1], w[0]);
            let l2 = d[0] * d[0] + d[1] * d[1];
            let t = if l2 > 0.0 {
                (((x[0] - w[0][0]) * d[0] + (x[1] - w[0][1]) * d[1]) / l2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            dist(x, [w[0][0] + t * d[0], w[0][1] + t * d[1]])
        })
        .fold(f64::INFINITY, f64::min)
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
    let (cx, cy, fx, fy) = geom.cell_with_fractions(x)?;
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

impl Cracks {
    /// The cracks of `scene`.
    pub fn new(scene: &Scene, geom: &GridGeom, mats: &[Elastic], scene_dt: f64) -> Self {
        let h = geom.h;
        let inside = |p: [f64; 2]| scene.bodies.iter().any(|b| b.region.contains(p));
        // A polyline subdivided to at most h/2, its ends inside a body tips, the others
        // mouths pushed 2h outward along their end segment.
        let polyline = |points: &[[f64; 2]]| {
            let mut pts = vec![CrackPoint::at(points[0])];
            for w in points.windows(2) {
                let n = (dist(w[0], w[1]) / (0.5 * h)).ceil().max(1.0) as usize;
                for k in 1..=n {
                    let t = k as f64 / n as f64;
                    pts.push(CrackPoint::at([
                        w[0][0] + t * (w[1][0] - w[0][0]),
                        w[0][1] + t * (w[1][1] - w[0][1]),
                    ]));
                }
            }
            let mut ext = [0.0; 2];
            let mut tips = [TipState::default(), TipState::default()];
            for t in &mut tips {
                t.g_filtered = f64::NAN;
            }
            for end in 0..2 {
                let n = pts.len();
                let (i, j) = if end == 0 { (0, 1) } else { (n - 1, n - 2) };
                if inside(pts[i].x) {
                    tips[end].active = true;
                } else {
                    let d = sub(pts[i].x, pts[j].x);
                    let l = norm(d).max(1e-300);
                    let e = 2.0 * h;
                    let x = [pts[i].x[0] + e * d[0] / l, pts[i].x[1] + e * d[1] / l];
                    pts[i] = CrackPoint::at(x);
                    ext[end] = e;
                }
            }
            (pts, tips, ext)
        };
        // (crack, interface) pairs where a crack tip lies on an interface (within h/4): the
        // tip hands its growth to the interface (§8), and the two share one pair of fields.
        let mut joins: Vec<(usize, usize)> = Vec::new();
        let mut cracks: Vec<Crack> = scene
            .cracks
            .iter()
            .enumerate()
            .map(|(ci, c)| {
                let (pts, mut tips, ext) = polyline(&c.points);
                for (end, tip) in tips.iter_mut().enumerate() {
                    let x = if end == 0 {
                        pts[0].x
                    } else {
                        pts[pts.len() - 1].x
                    };
                    for (ii, it) in scene.interfaces.iter().enumerate() {
                        if polyline_distance(&it.points, x) <= 0.25 * h {
                            tip.on_interface = true;
                            joins.push((ci, ii));
                        }
                    }
                }
                Crack {
                    pts,
                    tips,
                    contact: c.contact.clone(),
                    propagation: c.propagation.clone(),
                    prescribed: None,
                    j_method: JIntegral::default_in(c, scene),
                    ext,
                    interface: false,
                    fronts: Fronts::default(),
                    group: ci as u32,
                }
            })
            .collect();
        // Interfaces: cracks from the start whose every point is bonded; their ends are not
        // tips (no J, no growth: the bond's failure is the growth).
        let n_cracks = scene.cracks.len();
        for (ii, it) in scene.interfaces.iter().enumerate() {
            let (mut pts, mut tips, ext) = polyline(&it.points);
            for t in &mut tips {
                t.active = false;
            }
            for p in &mut pts {
                p.bond = Some(Bond::new(&it.cohesive));
            }
            cracks.push(Crack {
                pts,
                tips,
                contact: it.contact.clone(),
                propagation: Propagation::None,
                prescribed: None,
                j_method: JIntegral::Domain {
                    radius: JIntegral::DEFAULT_RADIUS_CELLS * h,
                },
                ext,
                interface: true,
                fronts: Fronts::default(),
                group: (n_cracks + ii) as u32,
            });
        }
        // An interface that a crack tip lies on continues that crack: it joins its group.
        for (ci, ii) in joins {
            cracks[n_cracks + ii].group = cracks[ci].group;
        }
        Cracks {
            cracks,
            slots: Vec::new(),
            contact_bodies: scene.bodies.iter().map(|b| b.contact.is_some()).collect(),
            body_contact: scene
                .bodies
                .iter()
                .find_map(|b| b.contact.clone())
                .unwrap_or_default(),
            h,
            cfl: scene.time.cfl,
            thickness: scene.thickness,
            speed_window: scene.output.speed_window,
            cell_start: Vec::new(),
            cell_segs: Vec::new(),
            entries: Vec::new(),
            chunk_entries: Vec::new(),
            normal_impulse: vec![0.0; geom.storage_len()],
            ncx: geom.nx() - 1,
            ncy: geom.ny() - 1,
            j_evaluations: 0,
            media: mats
                .iter()
                .map(|m| TipMedium::new(m.e, m.nu, m.rho, scene.analysis == Analysis::PlaneStress))
                .collect(),
            face_force: Vec::new(),
            zone_work: 0.0,
            dt: scene_dt,
        }
    }

    /// Put back into cracks restored from a checkpoint what checkpoints leave out (each
    /// crack's laws from the scene, via a fresh build), and check that the state fits this
    /// scene's grid and materials. Returns what does not fit.
    pub(crate) fn adopt_scene(&mut self, fresh: &Cracks) -> Result<(), String> {
        if self.cracks.len() != fresh.cracks.len() {
            return Err(format!(
                "{} cracks and interfaces, the scene has {}",
                self.cracks.len(),
                fresh.cracks.len()
            ));
        }
        if self.normal_impulse.len() != fresh.normal_impulse.len()
            || self.media.len() != fresh.media.len()
            || (self.ncx, self.ncy) != (fresh.ncx, fresh.ncy)
        {
            return Err("crack tables of another grid or material set".into());
        }
        self.contact_bodies = fresh.contact_bodies.clone();
        self.body_contact = fresh.body_contact.clone();
        for (c, f) in self.cracks.iter_mut().zip(&fresh.cracks) {
            if c.pts.len() < 2 || c.interface != f.interface {
                return Err("a crack of another kind or with fewer than 2 points".into());
            }
            c.contact = f.contact.clone();
            c.propagation = f.propagation.clone();
            c.j_method = f.j_method;
        }
        Ok(())
    }

    /// Energy the process-zone tractions have removed so far (J, the scene's thickness).
    pub fn zone_work(&self) -> f64 {
        self.zone_work
    }

    /// Σ Γ·Δa·thickness over every advance of every tip (J): the energy the new surface
    /// takes; the part of it above Γ(v), taken at the speed limit (J); and the new crack
    /// area (m²).
    pub fn fracture_required(&self) -> (f64, f64, f64) {
        let (mut e, mut above, mut a) = (0.0, 0.0, 0.0);
        for c in &self.cracks {
            for t in &c.tips {
                e += t.required * self.thickness;
                above += t.above_toughness * self.thickness;
                a += t.advance * self.thickness;
            }
        }
        (e, above, a)
    }

    /// Whether some tip can grow.
    pub fn can_grow(&self) -> bool {
        self.cracks
            .iter()
            .any(|c| !matches!(c.propagation, Propagation::None))
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
    /// The scene's viscous damping coefficient c (1/s; 0 without viscous damping): the force
    /// stage took c·p off every node heavier than `m_tiny`, and J's area term adds it back.
    pub viscous_damping: f64,
    /// The nodal mass below which a node is not damped (kg).
    pub m_tiny: f64,
}

impl View<'_> {
    /// A particle's own-field nodal acceleration ü = Σ S f/m and velocity gradient
    /// ∂u̇_i/∂x_k = Σ (q_i/m) ∂S/∂x_k, each node taken in the field `mask` gives the pair
    /// (the area terms of J, `algorithm.md` §6).
    pub(super) fn own_field_rates(&self, w: &Weights2, mask: u16) -> ([f64; 2], [[f64; 2]; 2]) {
        let h = self.geom.h;
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
                if let Some(nd) = self.node(ix, iy, field)
                    && nd.m > 0.0
                {
                    // ∇·σ (+ external, contact and zone forces) per mass: the viscous damping
                    // −c·p is a body force of the scheme, not of the elastic field whose J this
                    // is (with it in ü the area term misses ∫ρc u̇·∂u/∂x_k q dA).
                    let damp = if nd.m > self.m_tiny {
                        self.viscous_damping
                    } else {
                        0.0
                    };
                    for q in 0..2 {
                        acc[q] += sh * (nd.f[q] + damp * nd.p[q]) / nd.m;
                        let vel = nd.q[q] / nd.m;
                        gv[q][0] += vel * gr[0] / h;
                        gv[q][1] += vel * gr[1] / h;
                    }
                }
            }
        }
        (acc, gv)
    }

    #[inline(always)]
    fn node(&self, ix: usize, iy: usize, field: u8) -> Option<&Node> {
        let idx = self.geom.at(ix, iy);
        if field == 0 {
            Some(&self.nodes[idx])
        } else {
            let s = *self.slot_of.get(idx)?;
            (s != u32::MAX).then(|| &self.f1[s as usize])
        }
    }
}

/// For unit tests: the grid and the cracks of a scene given as JSON whose body is one
/// material "m" (ρ 1000, E 1 GPa, ν 0.3) filling `body`, with `lines` its `cracks` or
/// `interfaces` entries (`key`).
#[cfg(test)]
pub(crate) fn test_cracks(
    h: f64,
    max: [f64; 2],
    body: [[f64; 2]; 2],
    key: &str,
    lines: serde_json::Value,
) -> (GridGeom, Cracks) {
    let mut doc = serde_json::json!({
        "grid": {"cell_size": h, "min": [0.0, 0.0], "max": max},
        "materials": {"m": {"model": "linear_elastic", "density": 1000.0,
                            "youngs_modulus": 1.0e9, "poissons_ratio": 0.3}},
        "bodies": [{"material": "m", "region": {"rectangle": {"min": body[0], "max": body[1]}}}],
        "time": {"end": 1.0e-6}
    });
    doc[key] = lines;
    let scene = Scene::from_json(&doc.to_string()).expect("a valid test scene");
    let geom = GridGeom::new(scene.grid.min, scene.grid.max, h);
    let mats: Vec<Elastic> = scene
        .materials
        .values()
        .map(|m| Elastic::new(m, scene.analysis))
        .collect();
    let cracks = Cracks::new(&scene, &geom, &mats, 1.0e-8);
    (geom, cracks)
}
