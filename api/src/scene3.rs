//! The 3D scene document (`"analysis": "3d"`): everything a 3D run needs, in SI units
//! (m, s, kg, Pa).
//!
//! Fields are as in the 2D [`Scene`], with 3-vectors `[x, y, z]` where
//! 2D has 2-vectors, 3D regions ([`Region3`]), and no `thickness` (forces and energies are per
//! the bodies' volume). Materials, contact laws, damping and time control are the 2D types.
//! `docs/scenes-3d.md` explains every field with its units and default, with examples.
//!
//! A document is routed to [`Scene3`] or to the 2D scene by its `analysis`
//! ([`AnyScene`], [`crate::validate3::parse_any_scene`]); validation is
//! [`crate::validate3::validate3`].
//!
//! 3D crack surfaces ([`Crack3`]) and interfaces parse, so documents can be written against
//! the contract, but validation refuses them until the 3D crack solver lands.

use std::collections::BTreeMap;
use std::sync::{Arc, OnceLock};

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::mesh::{self, Crossing, MeshIndex};
use crate::scene::{
    Analysis, ContactLaw, Damping, FieldKind, Material, Scene, ShapeFunction, TimeControl, Vec2,
};

/// A 3D point or vector `[x, y, z]` (m, or m/s, Pa, … as the field says).
pub type Vec3 = [f64; 3];

/// A complete 3D simulation scene (`"analysis": "3d"`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Scene3 {
    /// Short name of the scene (used as the run's name). Default `"untitled"`.
    #[serde(default = "default_name")]
    pub name: String,
    /// Free text describing the scene and its modelling choices.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub description: String,
    /// Always `"3d"`: the field that makes a document a 3D scene (required; a document
    /// without it is a 2D scene).
    #[schemars(schema_with = "analysis_3d_schema")]
    pub analysis: Analysis,
    /// The background grid of cubic cells.
    pub grid: GridSpec3,
    /// Materials by name (the 2D material models).
    pub materials: BTreeMap<String, Material>,
    /// Bodies filled with particles.
    pub bodies: Vec<Body3>,
    /// Crack surfaces. Reserved: validation refuses a non-empty list until the 3D crack
    /// solver lands.
    #[serde(default)]
    pub cracks: Vec<Crack3>,
    /// Cohesive interfaces. Reserved: validation refuses a non-empty list until cohesive
    /// surfaces land in 3D. Omitted when empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub interfaces: Vec<serde_json::Value>,
    /// Prescribed grid velocities.
    #[serde(default)]
    pub boundary_conditions: Vec<BoundaryCondition3>,
    /// Tractions on particles.
    #[serde(default)]
    pub loads: Vec<Load3>,
    /// Damping for quasi-static runs (as 2D).
    #[serde(default)]
    pub damping: Damping,
    /// End time and time step control (as 2D; Δt = cfl·h/c_L).
    pub time: TimeControl,
    /// What is recorded and how often.
    #[serde(default)]
    pub output: Output3,
}

fn default_name() -> String {
    "untitled".to_string()
}

fn two_u32() -> u32 {
    2
}

/// The schema of [`Scene3::analysis`]: the one value `"3d"`.
fn analysis_3d_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
    schemars::json_schema!({
        "description": "Always \"3d\": the field that makes a document a 3D scene.",
        "type": "string",
        "const": "3d"
    })
}

/// The background grid of a 3D scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GridSpec3 {
    /// Edge of the cubic cells (m).
    pub cell_size: f64,
    /// Lowest corner of the grid box `[x, y, z]` (m).
    pub min: Vec3,
    /// Highest corner of the grid box `[x, y, z]` (m).
    pub max: Vec3,
    /// Shape functions (default `"gimp"`).
    #[serde(default)]
    pub shape_function: ShapeFunction,
}

impl GridSpec3 {
    /// Grid nodes along x, y and z (as validation counts them: ⌈span/h⌉ + 1, saturating), or
    /// `None` for a grid validation refuses (non-finite, empty or inverted box, cell ≤ 0).
    pub fn node_counts(&self) -> Option<[u64; 3]> {
        let h = self.cell_size;
        let finite = self
            .min
            .iter()
            .chain(self.max.iter())
            .all(|v| v.is_finite());
        if !(finite && h.is_finite() && h > 0.0) {
            return None;
        }
        let mut n = [0u64; 3];
        for (k, nk) in n.iter_mut().enumerate() {
            if self.max[k] <= self.min[k] {
                return None;
            }
            // A count beyond 10¹⁵ (or an overflowing span) saturates, as 2D's.
            let c = ((self.max[k] - self.min[k]) / h - 1e-9).ceil();
            *nk = if c.is_nan() {
                return None;
            } else if c < 1e15 {
                (c.max(0.0) as u64).saturating_add(1)
            } else {
                u64::MAX
            };
        }
        Some(n)
    }
}

/// A region of space (m): bodies, boundary conditions and loads use them.
///
/// Boundary points count as inside for boxes, spheres, cylinders and prisms. A mesh's surface
/// is a measure-zero set whose points may count either way (a symbolic perturbation decides,
/// consistently; [`crate::mesh`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Region3 {
    /// Axis-aligned box.
    Box {
        /// Lowest corner `[x, y, z]` (m).
        min: Vec3,
        /// Highest corner `[x, y, z]` (m).
        max: Vec3,
    },
    /// Ball.
    Sphere {
        /// Centre `[x, y, z]` (m).
        center: Vec3,
        /// Radius (m).
        radius: f64,
    },
    /// Solid circular cylinder from `base` to `base + axis`.
    Cylinder {
        /// Centre of one end disc `[x, y, z]` (m).
        base: Vec3,
        /// Vector from that centre to the other end disc's centre (m), non-zero.
        axis: Vec3,
        /// Radius (m).
        radius: f64,
    },
    /// A 2D polygon (even-odd rule, as the 2D `polygon` region) extruded along z.
    Prism {
        /// Vertices `[x, y]` of the polygon (m), at least 3, either orientation.
        polygon: Vec<Vec2>,
        /// The extrusion's range `[z0, z1]` (m), z0 < z1.
        z: [f64; 2],
    },
    /// The solid bounded by a closed, consistently oriented triangle surface.
    Mesh(TriMesh),
}

/// A closed triangle surface: the vertices and the triangles that index them
/// (`{"vertices": [[x, y, z], …], "triangles": [[i, j, k], …]}`).
///
/// Validation requires it closed (every edge shared by exactly two triangles), consistently
/// oriented (the two triangles of an edge traverse it in opposite directions), without
/// degenerate triangles and without self-intersections ([`mesh::check_mesh`]). Either
/// orientation is accepted (outward normals are the STL convention).
///
/// The fields are private so that the containment index, built on the first query and kept
/// with the mesh, can never describe another surface: build one with [`TriMesh::new`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TriMesh {
    /// Vertex positions `[x, y, z]` (m).
    vertices: Vec<Vec3>,
    /// Triangles as three indices into `vertices`, each counter-clockwise seen from the same
    /// side (outside, by the STL convention).
    triangles: Vec<[u32; 3]>,
    /// The containment index, built on first use.
    #[serde(skip)]
    #[schemars(skip)]
    index: IndexCache,
}

/// A lazily built [`MeshIndex`], shared by clones. It is derived data: equality ignores it.
#[derive(Clone, Default)]
struct IndexCache(OnceLock<Arc<MeshIndex>>);

impl PartialEq for IndexCache {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl std::fmt::Debug for IndexCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let built = self.0.get().is_some();
        f.debug_struct("IndexCache").field("built", &built).finish()
    }
}

impl TriMesh {
    /// A mesh from its vertices (m) and triangles (vertex indices).
    pub fn new(vertices: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> TriMesh {
        TriMesh {
            vertices,
            triangles,
            index: IndexCache::default(),
        }
    }
    /// Vertex positions (m).
    pub fn vertices(&self) -> &[Vec3] {
        &self.vertices
    }
    /// Triangles (vertex indices).
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }
    /// The vertices and triangles back.
    pub fn into_parts(self) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        (self.vertices, self.triangles)
    }
    /// The containment index (built on the first call, O(triangles); then shared by every
    /// query and every clone of this mesh).
    pub fn index(&self) -> &MeshIndex {
        self.index
            .0
            .get_or_init(|| Arc::new(MeshIndex::new(&self.vertices, &self.triangles)))
    }
    /// Axis-aligned bounding box of the vertices `(min, max)` (m).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for v in &self.vertices {
            for k in 0..3 {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
            }
        }
        (lo, hi)
    }
    /// Enclosed volume (m³) by the divergence theorem: positive for outward-facing triangles,
    /// negative for inward-facing ones. Meaningful for a valid (closed) mesh only.
    pub fn signed_volume(&self) -> f64 {
        let n = self.vertices.len();
        let mut six_v = 0.0;
        for t in &self.triangles {
            if t.iter().any(|&i| i as usize >= n) {
                continue;
            }
            let [a, b, c] = t.map(|i| self.vertices[i as usize]);
            six_v += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]);
        }
        six_v / 6.0
    }
}

/// Even-odd point-in-polygon, the same arithmetic as the 2D `polygon` region, so that a prism
/// and its 2D polygon classify every (x, y) alike.
fn polygon_contains(points: &[Vec2], p: Vec2) -> bool {
    let n = points.len();
    let mut inside = false;
    let mut j = n.wrapping_sub(1);
    for i in 0..n {
        let (a, b) = (points[i], points[j]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
            if p[0] < x {
                inside = !inside;
            }
        }
        j = i;
    }
    inside
}

impl Region3 {
    /// Whether `p` (m) lies inside the region. Boxes, spheres, cylinders and prisms include
    /// their boundary; a mesh is decided by the signed crossings of the line through `p`
    /// parallel to z ([`MeshIndex`], built once per mesh and cached: a query costs the
    /// triangles of one bucket of its index, not all of them).
    pub fn contains(&self, p: Vec3) -> bool {
        match self {
            Region3::Box { min, max } => (0..3).all(|k| p[k] >= min[k] && p[k] <= max[k]),
            Region3::Sphere { center, radius } => {
                let d = [p[0] - center[0], p[1] - center[1], p[2] - center[2]];
                d[0] * d[0] + d[1] * d[1] + d[2] * d[2] <= radius * radius
            }
            Region3::Cylinder { base, axis, radius } => {
                let d = [p[0] - base[0], p[1] - base[1], p[2] - base[2]];
                let aa = axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2];
                let da = d[0] * axis[0] + d[1] * axis[1] + d[2] * axis[2];
                if !(0.0..=aa).contains(&da) {
                    return false;
                }
                // |d|² − (d·a)²/|a|²: the squared distance from the axis.
                let dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                dd - da * da / aa <= radius * radius
            }
            Region3::Prism { polygon, z } => {
                p[2] >= z[0] && p[2] <= z[1] && polygon_contains(polygon, [p[0], p[1]])
            }
            Region3::Mesh(m) => m.index().contains(p),
        }
    }

    /// Axis-aligned bounding box `(min, max)` (m). Exact for every kind (a cylinder's box
    /// holds its two end discs).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        match self {
            Region3::Box { min, max } => (*min, *max),
            Region3::Sphere { center, radius } => (
                center.map(|c| c - radius),
                [center[0] + radius, center[1] + radius, center[2] + radius],
            ),
            Region3::Cylinder { base, axis, radius } => {
                let len2 = axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2];
                let mut lo = [0.0; 3];
                let mut hi = [0.0; 3];
                for k in 0..3 {
                    // A disc of radius r normal to the unit axis n reaches r·sqrt(1 − n_k²)
                    // along axis k.
                    let nk2 = if len2 > 0.0 {
                        axis[k] * axis[k] / len2
                    } else {
                        0.0
                    };
                    let e = radius * (1.0 - nk2).max(0.0).sqrt();
                    let (a, b) = (base[k], base[k] + axis[k]);
                    lo[k] = a.min(b) - e;
                    hi[k] = a.max(b) + e;
                }
                (lo, hi)
            }
            Region3::Prism { polygon, z } => {
                let mut lo = [f64::INFINITY, f64::INFINITY, z[0]];
                let mut hi = [f64::NEG_INFINITY, f64::NEG_INFINITY, z[1]];
                for p in polygon {
                    for k in 0..2 {
                        lo[k] = lo[k].min(p[k]);
                        hi[k] = hi[k].max(p[k]);
                    }
                }
                (lo, hi)
            }
            Region3::Mesh(m) => m.bounds(),
        }
    }

    /// The region along the line parallel to z through `(x, y)`: a [`RegionColumn`] whose
    /// [`RegionColumn::contains`]`(z)` equals `self.contains([x, y, z])` for every z, but
    /// costs O(1) (boxes, spheres, cylinders, prisms after one polygon test) or O(log
    /// crossings) (meshes, whose crossings with the line are found once). The lattice fill
    /// walks particles column by column with it.
    pub fn column(&self, x: f64, y: f64) -> RegionColumn<'_> {
        let kind = match self {
            Region3::Prism { polygon, z } => ColumnKind::Prism {
                inside: polygon_contains(polygon, [x, y]),
                z: *z,
            },
            Region3::Mesh(m) => {
                let mut crossings = Vec::new();
                m.index().crossings(x, y, &mut crossings);
                ColumnKind::Mesh(crossings)
            }
            _ => ColumnKind::Point,
        };
        RegionColumn {
            region: self,
            x,
            y,
            kind,
        }
    }
}

/// A [`Region3`] along one line parallel to z (see [`Region3::column`]).
#[derive(Debug, Clone)]
pub struct RegionColumn<'a> {
    region: &'a Region3,
    x: f64,
    y: f64,
    kind: ColumnKind,
}

#[derive(Debug, Clone)]
enum ColumnKind {
    /// Ask the region point by point (cheap kinds).
    Point,
    /// The polygon test done once for the column.
    Prism { inside: bool, z: [f64; 2] },
    /// The mesh's crossings with the column, sorted by z.
    Mesh(Vec<Crossing>),
}

impl RegionColumn<'_> {
    /// Whether `[x, y, z]` lies inside the region (exactly as [`Region3::contains`]).
    pub fn contains(&self, z: f64) -> bool {
        match &self.kind {
            ColumnKind::Point => self.region.contains([self.x, self.y, z]),
            ColumnKind::Prism { inside, z: range } => z >= range[0] && z <= range[1] && *inside,
            ColumnKind::Mesh(crossings) => mesh::inside_at(crossings, z),
        }
    }
    /// Whether no point of the column is inside (a mesh column that meets no triangle, a
    /// prism column outside the polygon). `false` for the point-wise kinds, which do not
    /// know in advance.
    pub fn is_empty(&self) -> bool {
        match &self.kind {
            ColumnKind::Point => false,
            ColumnKind::Prism { inside, .. } => !inside,
            ColumnKind::Mesh(crossings) => crossings.is_empty(),
        }
    }
}

/// A body: a region filled with particles of one material.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Body3 {
    /// Name of a material in `materials`.
    pub material: String,
    /// The region the particles fill.
    pub region: Region3,
    /// Particles per cell in each direction, 1..=8 (default 2 → 8 particles per cell).
    #[serde(default = "two_u32")]
    pub particles_per_cell: u32,
    /// Uniform initial velocity `[vx, vy, vz]` (m/s), default zero.
    #[serde(default)]
    pub initial_velocity: Vec3,
}

/// A crack surface (reserved: validation refuses 3D cracks until their solver lands).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Crack3 {
    /// The crack's surface.
    pub surface: Surface3,
    /// Contact of the crack faces (as 2D, default frictionless).
    #[serde(default)]
    pub contact: ContactLaw,
    /// How J is evaluated along the front (default: the project's documented domain).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub j_integral: Option<JIntegral3>,
    /// Growth law: only `{"criterion": "none"}` (a stationary crack) until 3D growth lands.
    #[serde(default)]
    pub propagation: Propagation3,
}

/// The surface of a 3D crack (m). The front is the part of its boundary inside a body.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Surface3 {
    /// A planar parallelogram `corner + s·edges[0] + t·edges[1]`, s, t in [0, 1].
    Rectangle {
        /// One corner `[x, y, z]` (m).
        corner: Vec3,
        /// The two edge vectors from the corner (m).
        edges: [Vec3; 2],
    },
    /// A planar ellipse; equal semi-axes give a penny.
    Ellipse {
        /// Centre `[x, y, z]` (m).
        center: Vec3,
        /// The two semi-axis vectors (m), orthogonal.
        axes: [Vec3; 2],
    },
    /// A 2D crack polyline extruded along z (the 3D twin of a 2D crack).
    Extruded {
        /// Polyline vertices `[x, y]` (m), at least two.
        points: Vec<Vec2>,
        /// The extrusion's range `[z0, z1]` (m).
        z: [f64; 2],
    },
    /// An arbitrary triangulated surface.
    Triangles {
        /// Vertex positions `[x, y, z]` (m).
        vertices: Vec<Vec3>,
        /// Triangles as three indices into `vertices`.
        triangles: Vec<[u32; 3]>,
    },
}

/// How J is evaluated along a 3D crack front.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct JIntegral3 {
    /// The method: `"domain"` (default), the only one in 3D.
    #[serde(default)]
    pub method: JMethod3,
    /// Radius (m) of the tube around the front (q smooth along and across it), at least two
    /// cells.
    pub radius: f64,
}

/// Methods of evaluating J in 3D.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum JMethod3 {
    /// Equivalent domain integral over a tube around the front.
    #[default]
    Domain,
}

/// Growth law of a 3D crack: only a stationary crack until 3D growth lands.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "criterion", rename_all = "snake_case", deny_unknown_fields)]
pub enum Propagation3 {
    /// Stationary crack; J and K are still reported.
    #[default]
    None,
}

/// Prescribed velocity on the grid nodes inside a region (as 2D, with a z component).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BoundaryCondition3 {
    /// Nodes inside this region are constrained.
    pub region: Region3,
    /// Prescribed components (m/s); a missing one is free.
    pub velocity: VelocitySpec3,
    /// Velocity rises linearly from 0 over this time (s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ramp_time: Option<f64>,
    /// Condition is active from this time (s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start: Option<f64>,
    /// Condition is active until this time (s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub end: Option<f64>,
    /// The region travels with the prescribed velocity (a rigid impactor's face); false (the
    /// default): fixed in space. As 2D's `moving`.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub moving: bool,
}

/// Prescribed velocity components (m/s), each optional.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct VelocitySpec3 {
    /// x component, if prescribed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub x: Option<f64>,
    /// y component, if prescribed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub y: Option<f64>,
    /// z component, if prescribed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub z: Option<f64>,
}

impl VelocitySpec3 {
    /// The components as `[x, y, z]`.
    pub fn components(&self) -> [Option<f64>; 3] {
        [self.x, self.y, self.z]
    }
}

/// A traction applied to the particles inside a region.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Load3 {
    /// The particles inside this region carry the traction.
    pub region: Region3,
    /// Traction `[tx, ty, tz]` (Pa): force per unit area of the loaded surface, each particle
    /// carrying it times its cross-section (h/ppc)² (2D: its edge length times the
    /// thickness).
    pub traction: Vec3,
    /// Linear rise from 0 over this time (s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ramp_time: Option<f64>,
}

/// A coordinate axis (`"x"`, `"y"` or `"z"`).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize, JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum Axis {
    /// The x axis.
    X,
    /// The y axis.
    Y,
    /// The z axis.
    Z,
}

impl Axis {
    /// The component index: 0, 1, 2.
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }
    /// The name used in scenes: `"x"`, `"y"`, `"z"`.
    pub fn name(self) -> &'static str {
        match self {
            Axis::X => "x",
            Axis::Y => "y",
            Axis::Z => "z",
        }
    }
}

/// A plane of the grid whose fields are written like a 2D snapshot.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Slice {
    /// The axis normal to the plane.
    pub normal: Axis,
    /// The plane's position along that axis (m), inside the grid box.
    pub at: f64,
}

/// What a 3D run records and how often (the 2D output's fields, and slices).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Output3 {
    /// Interval between energy (and, later, crack-front) samples (s). Absent: every step.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub history_interval: Option<f64>,
    /// Interval between field snapshots (s). 0 or absent: none.
    #[serde(default)]
    pub snapshot_interval: f64,
    /// Fields recorded in snapshots (default: stress and velocity). `"fringe"` is refused in
    /// 3D: photoelastic fringes are a 2D thin-plate quantity.
    #[serde(default = "default_fields")]
    pub fields: Vec<FieldKind>,
    /// Refused in 3D (kept so that a 2D output block gets a clear message, not an unknown
    /// field): fringes are a 2D thin-plate quantity.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fringe_constant: Option<f64>,
    /// Width of the moving-box average of crack speeds (s), default 1 µs.
    #[serde(default = "default_speed_window")]
    pub speed_window: f64,
    /// Also record every particle (position and the `fields`' components) in each snapshot.
    /// Off by default.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub particles: bool,
    /// Planes whose field pictures are written like 2D snapshots. Empty (the default): the
    /// mid-plane normal to z ([`Output3::slices_or_default`]). Omitted when empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub slices: Vec<Slice>,
}

fn default_fields() -> Vec<FieldKind> {
    vec![FieldKind::Stress, FieldKind::Velocity]
}
fn default_speed_window() -> f64 {
    1.0e-6
}

impl Default for Output3 {
    fn default() -> Self {
        Output3 {
            history_interval: None,
            snapshot_interval: 0.0,
            fields: default_fields(),
            fringe_constant: None,
            speed_window: default_speed_window(),
            particles: false,
            slices: Vec::new(),
        }
    }
}

impl Output3 {
    /// The slices to write: those given, or the grid's mid-plane normal to z.
    pub fn slices_or_default(&self, grid: &GridSpec3) -> Vec<Slice> {
        if self.slices.is_empty() {
            vec![Slice {
                normal: Axis::Z,
                at: 0.5 * (grid.min[2] + grid.max[2]),
            }]
        } else {
            self.slices.clone()
        }
    }
}

impl Scene3 {
    /// Parse a 3D scene from JSON text. Errors carry serde's message with line and column
    /// ([`crate::validate3::parse_scene3`] names the JSON path instead).
    pub fn from_json(text: &str) -> Result<Scene3, serde_json::Error> {
        serde_json::from_str(text)
    }

    /// The JSON Schema of the 3D scene document (`fracture schema --3d`).
    pub fn json_schema() -> serde_json::Value {
        let schema = schemars::schema_for!(Scene3);
        serde_json::to_value(&schema).unwrap_or(serde_json::Value::Null)
    }

    /// The canonical JSON of the scene (all defaults filled in, keys in a fixed order).
    pub fn canonical_json(&self) -> String {
        // Struct fields serialize in declaration order and maps are BTreeMaps: stable.
        serde_json::to_string(self).unwrap_or_default()
    }

    /// SHA-256 of the canonical JSON, hex encoded (the 2D scheme; the canonical JSON holds
    /// `"analysis":"3d"`, so a 3D scene never shares a 2D scene's hash).
    pub fn hash(&self) -> String {
        use sha2::{Digest, Sha256};
        let digest = Sha256::digest(self.canonical_json().as_bytes());
        digest.iter().map(|b| format!("{b:02x}")).collect()
    }

    /// The scene's length scale L (m): the shortest side of the bounding box of all bodies
    /// (the grid's when there are none), as 2D.
    pub fn length_scale(&self) -> f64 {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for b in &self.bodies {
            let (a, c) = b.region.bounds();
            for k in 0..3 {
                lo[k] = lo[k].min(a[k]);
                hi[k] = hi[k].max(c[k]);
            }
        }
        if !(0..3).all(|k| lo[k] < hi[k]) {
            (lo, hi) = (self.grid.min, self.grid.max);
        }
        (hi[0] - lo[0]).min(hi[1] - lo[1]).min(hi[2] - lo[2])
    }

    /// The time step Δt = cfl·h/c_L with the largest dilatational speed
    /// c_L = sqrt((λ + 2μ)/ρ) over the materials (the bulk P wave, which is the 2D
    /// plane-strain c_L), or `None` when there are no valid materials.
    pub fn time_step(&self) -> Option<f64> {
        let c_max = self
            .materials
            .values()
            .map(|m| m.wave_speeds(Analysis::ThreeD).c_l)
            .filter(|c| c.is_finite() && *c > 0.0)
            .fold(0.0_f64, f64::max);
        (c_max > 0.0).then(|| self.time.cfl * self.grid.cell_size / c_max)
    }
}

/// A scene of either dimension, as a document arrives (routed by its `analysis`:
/// [`crate::validate3::parse_any_scene`]).
#[derive(Debug, Clone, PartialEq)]
pub enum AnyScene {
    /// A 2D scene (`"plane_strain"`, `"plane_stress"` or no `analysis`).
    Two(Scene),
    /// A 3D scene (`"analysis": "3d"`).
    Three(Scene3),
}

impl AnyScene {
    /// The scene's name.
    pub fn name(&self) -> &str {
        match self {
            AnyScene::Two(s) => &s.name,
            AnyScene::Three(s) => &s.name,
        }
    }
    /// The scene's hash (SHA-256 of its canonical JSON, as each type computes it).
    pub fn hash(&self) -> String {
        match self {
            AnyScene::Two(s) => s.hash(),
            AnyScene::Three(s) => s.hash(),
        }
    }
    /// The canonical JSON of the scene.
    pub fn canonical_json(&self) -> String {
        match self {
            AnyScene::Two(s) => s.canonical_json(),
            AnyScene::Three(s) => s.canonical_json(),
        }
    }
    /// 2 or 3.
    pub fn dimension(&self) -> u32 {
        match self {
            AnyScene::Two(_) => 2,
            AnyScene::Three(_) => 3,
        }
    }
}

impl From<Scene> for AnyScene {
    fn from(s: Scene) -> Self {
        AnyScene::Two(s)
    }
}

impl From<Scene3> for AnyScene {
    fn from(s: Scene3) -> Self {
        AnyScene::Three(s)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn cylinder_contains_and_bounds() {
        let c = Region3::Cylinder {
            base: [0.0, 0.0, 0.0],
            axis: [0.0, 0.0, 2.0],
            radius: 1.0,
        };
        assert!(c.contains([0.5, 0.5, 1.0]));
        assert!(c.contains([1.0, 0.0, 2.0])); // rim of the top disc
        assert!(!c.contains([0.0, 0.0, 2.0 + 1e-9]));
        assert!(!c.contains([0.8, 0.8, 1.0]));
        assert_eq!(c.bounds(), ([-1.0, -1.0, 0.0], [1.0, 1.0, 2.0]));
        // A slanted cylinder's box holds its end discs.
        let s = Region3::Cylinder {
            base: [0.0, 0.0, 0.0],
            axis: [1.0, 1.0, 0.0],
            radius: 0.5,
        };
        let (lo, hi) = s.bounds();
        let e = 0.5 * (0.5f64).sqrt();
        assert!((lo[0] + e).abs() < 1e-15 && (hi[0] - 1.0 - e).abs() < 1e-15);
        assert!((lo[2] + 0.5).abs() < 1e-15 && (hi[2] - 0.5).abs() < 1e-15);
    }

    #[test]
    fn columns_agree_with_points() {
        let regions = [
            Region3::Box {
                min: [0.0, 0.0, 0.0],
                max: [1.0, 1.0, 1.0],
            },
            Region3::Prism {
                polygon: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
                z: [0.2, 0.7],
            },
        ];
        for r in &regions {
            for (x, y) in [(0.25, 0.25), (0.9, 0.9), (-0.1, 0.5)] {
                let col = r.column(x, y);
                for k in 0..=20 {
                    let z = -0.1 + 0.06 * f64::from(k);
                    assert_eq!(col.contains(z), r.contains([x, y, z]), "{r:?} {x} {y} {z}");
                }
            }
        }
    }
}
