//! Reading and validating 3D scenes, and the one entry for documents of either dimension.
//!
//! [`parse_any_scene`] routes a document by its `analysis`: `"3d"` parses as a
//! [`Scene3`], anything else exactly as [`crate::validate::parse_scene`] parses a 2D scene
//! (same result, same errors). [`validate3`] checks a 3D scene as [`crate::validate::validate`]
//! checks a 2D one, every problem with its JSON path and value, and returns the run size.
//!
//! The walk that counts particles is bounded before it starts, from the bodies' bounding
//! boxes alone: at most [`MAX_GRID_NODES`] grid nodes (the 2D limit) and
//! [`MAX_LATTICE_SITES`] candidate particle sites.

use std::fmt;

use serde::Deserialize;
use serde::de::{IgnoredAny, MapAccess, Visitor};

use crate::cost;
use crate::lattice3;
use crate::mesh::{self, MeshDefect};
use crate::scene::{Analysis, FieldKind};
use crate::scene3::{AnyScene, Region3, Scene3, Vec3};
use crate::validate::{
    Checker, RunSize, ValidationError, ValidationErrors, check_damping, check_materials,
    check_time, parse_scene, parse_with_path,
};

/// Most grid nodes a 3D scene may have: the 2D limit (200 million), checked before anything
/// else is sized.
pub const MAX_GRID_NODES: u64 = 200_000_000;

/// Most candidate particle sites (sub-cells of the bodies' bounding boxes, [`lattice3::
/// candidate_sites3`]) validation examines. Past it a scene is refused before the walk: 10⁹
/// particles would need about 1.3 TB at [`cost::BYTES_PER_PARTICLE_3D`], beyond one machine,
/// and the walk alone would take minutes.
pub const MAX_LATTICE_SITES: u64 = 1_000_000_000;

/// The top-level keys that decide how a document is read: its `analysis`, and a
/// `thickness` (which a 3D scene must not have).
#[derive(Default)]
struct Probe {
    analysis: Option<serde_json::Value>,
    thickness: Option<serde_json::Value>,
}

impl<'de> Deserialize<'de> for Probe {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Probe, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Probe;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a scene object")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Probe, A::Error> {
                let mut probe = Probe::default();
                while let Some(key) = map.next_key::<String>()? {
                    match key.as_str() {
                        "analysis" => probe.analysis = Some(map.next_value()?),
                        "thickness" => probe.thickness = Some(map.next_value()?),
                        _ => {
                            map.next_value::<IgnoredAny>()?;
                        }
                    }
                }
                Ok(probe)
            }
        }
        d.deserialize_map(V)
    }
}

impl Probe {
    /// The probe of `text`, or `None` where it is not a JSON object (the 2D parser reports
    /// that as it always has).
    fn of(text: &str) -> Option<Probe> {
        serde_json::from_str(text).ok()
    }
    fn is_3d(&self) -> bool {
        self.analysis.as_ref().and_then(|a| a.as_str()) == Some("3d")
    }
    /// The error of a 3D document that carries `thickness`.
    fn thickness_error(&self) -> Option<ValidationErrors> {
        let t = self.thickness.as_ref()?;
        Some(ValidationErrors(vec![ValidationError {
            path: "thickness".into(),
            value: t.to_string(),
            reason: "does not exist in 3D (forces and energies are per the bodies' volume): \
                     remove it"
                .into(),
        }]))
    }
}

/// Parse a 3D scene from JSON text; syntax, type and unknown-field errors name their path,
/// and a `thickness` gets its own message.
pub fn parse_scene3(text: &str) -> Result<Scene3, ValidationErrors> {
    if let Some(e) = Probe::of(text).and_then(|p| p.thickness_error()) {
        return Err(e);
    }
    parse_with_path(text)
}

/// Parse a scene of either dimension: a document whose `analysis` is `"3d"` is a
/// [`Scene3`] ([`parse_scene3`]); any other is a 2D scene, read exactly as
/// [`parse_scene`] reads it (the same scene, hash and errors).
pub fn parse_any_scene(text: &str) -> Result<AnyScene, ValidationErrors> {
    match Probe::of(text) {
        Some(p) if p.is_3d() => parse_scene3(text).map(AnyScene::Three),
        _ => parse_scene(text).map(AnyScene::Two),
    }
}

/// Validate a scene of either dimension ([`crate::validate::validate`] or [`validate3`]).
pub fn validate_any(scene: &AnyScene) -> Result<RunSize, ValidationErrors> {
    match scene {
        AnyScene::Two(s) => crate::validate::validate(s),
        AnyScene::Three(s) => validate3(s),
    }
}

/// A 3D scene that passed [`validate3`], with its run size: what a 3D simulation is built
/// from, so a scene is validated once, where it enters.
#[derive(Debug, Clone)]
pub struct ValidScene3 {
    scene: Scene3,
    size: RunSize,
}

impl ValidScene3 {
    /// Validate `scene`; every problem found, with its JSON path, on error.
    pub fn new(scene: Scene3) -> Result<ValidScene3, ValidationErrors> {
        let size = validate3(&scene)?;
        Ok(ValidScene3 { scene, size })
    }
    /// The scene.
    pub fn scene(&self) -> &Scene3 {
        &self.scene
    }
    /// Its run size (particles, grid nodes, time step, steps).
    pub fn size(&self) -> &RunSize {
        &self.size
    }
    /// The scene back.
    pub fn into_scene(self) -> Scene3 {
        self.scene
    }
}

impl std::ops::Deref for ValidScene3 {
    type Target = Scene3;
    fn deref(&self) -> &Scene3 {
        &self.scene
    }
}

impl Checker {
    /// A finite 3-vector (each bad component named).
    fn point3(&mut self, path: &str, p: Vec3) -> bool {
        let mut ok = true;
        for (k, v) in p.iter().enumerate() {
            ok &= self.finite(&format!("{path}.{k}"), *v);
        }
        ok
    }

    /// A well-formed region: finite numbers, positive sizes, a closed valid mesh.
    fn region3(&mut self, path: &str, r: &Region3) -> bool {
        match r {
            Region3::Box { min, max } => {
                let ok = self.point3(&format!("{path}.box.min"), *min)
                    & self.point3(&format!("{path}.box.max"), *max);
                if ok && (0..3).any(|k| max[k] <= min[k]) {
                    self.err(
                        format!("{path}.box.max"),
                        max,
                        format!("must exceed min {min:?} in every component"),
                    );
                    return false;
                }
                ok
            }
            Region3::Sphere { center, radius } => {
                let ok = self.point3(&format!("{path}.sphere.center"), *center);
                self.radius(&format!("{path}.sphere.radius"), *radius) && ok
            }
            Region3::Cylinder { base, axis, radius } => {
                let mut ok = self.point3(&format!("{path}.cylinder.base"), *base);
                let ap = format!("{path}.cylinder.axis");
                if self.point3(&ap, *axis) && axis.iter().all(|&a| a == 0.0) {
                    self.err(
                        ap,
                        axis,
                        "must be a non-zero vector (from base to the other end)",
                    );
                    ok = false;
                }
                self.radius(&format!("{path}.cylinder.radius"), *radius) && ok
            }
            Region3::Prism { polygon, z } => {
                let mut ok = true;
                if polygon.len() < 3 {
                    self.err(
                        format!("{path}.prism.polygon"),
                        polygon,
                        "needs at least 3 points",
                    );
                    ok = false;
                }
                for (i, p) in polygon.iter().enumerate() {
                    let pp = format!("{path}.prism.polygon.{i}");
                    ok &= self.finite(&format!("{pp}.0"), p[0])
                        & self.finite(&format!("{pp}.1"), p[1]);
                }
                let zp = format!("{path}.prism.z");
                if self.finite(&format!("{zp}.0"), z[0]) & self.finite(&format!("{zp}.1"), z[1]) {
                    if z[1] <= z[0] {
                        self.err(zp, z, "must be [z0, z1] with z0 < z1");
                        ok = false;
                    }
                } else {
                    ok = false;
                }
                ok
            }
            Region3::Mesh(m) => match mesh::check_mesh(m.vertices(), m.triangles()) {
                Ok(()) => true,
                Err(defect) => {
                    let mp = format!("{path}.mesh");
                    match &defect {
                        MeshDefect::TooFewTriangles { count } => {
                            self.err(format!("{mp}.triangles"), count, defect.to_string());
                        }
                        MeshDefect::NonFiniteVertex { vertex } => {
                            let v = m.vertices()[*vertex];
                            self.errors.push(ValidationError {
                                path: format!("{mp}.vertices.{vertex}"),
                                value: format!("{v:?}"),
                                reason: defect.to_string(),
                            });
                        }
                        _ => {
                            let t = defect.triangle().unwrap_or(0);
                            let tri = m.triangles().get(t).copied();
                            self.err(format!("{mp}.triangles.{t}"), tri, defect.to_string());
                        }
                    }
                    false
                }
            },
        }
    }

    fn radius(&mut self, path: &str, r: f64) -> bool {
        if !self.finite(path, r) {
            return false;
        }
        if r <= 0.0 {
            self.err(path, r, "must be > 0");
            return false;
        }
        true
    }
}

/// Validate a 3D scene. Returns the run size, or every problem found.
///
/// Checks what 2D's validation checks where it applies (grid, materials, bodies and their
/// regions inside the grid with GIMP's empty cell layer, boundary conditions, loads,
/// damping, output, time), plus the 3D regions (a mesh must be closed, consistently
/// oriented, without degenerate triangles and without self-intersections: the first bad
/// triangle is named) and the slices. Refuses `cracks` and `interfaces` (not solved in 3D
/// yet) and the `fringe` field (a 2D thin-plate quantity).
pub fn validate3(scene: &Scene3) -> Result<RunSize, ValidationErrors> {
    let mut c = Checker { errors: Vec::new() };

    if scene.analysis != Analysis::ThreeD {
        c.err(
            "analysis",
            scene.analysis,
            "must be \"3d\" in a 3D scene (a document with another analysis is a 2D scene)",
        );
    }

    // Grid.
    let g = &scene.grid;
    let h = g.cell_size;
    c.positive("grid.cell_size", h);
    let mut grid_ok =
        c.point3("grid.min", g.min) & c.point3("grid.max", g.max) && h.is_finite() && h > 0.0;
    let mut grid_nodes = 0u64;
    if grid_ok {
        if (0..3).any(|k| g.max[k] <= g.min[k]) {
            c.err(
                "grid.max",
                g.max,
                format!("must exceed grid.min {:?} in every component", g.min),
            );
            grid_ok = false;
        } else if let Some([nx, ny, nz]) = g.node_counts() {
            grid_nodes = nx.saturating_mul(ny).saturating_mul(nz);
            if grid_nodes > MAX_GRID_NODES {
                c.err(
                    "grid.cell_size",
                    h,
                    format!(
                        "gives {nx} × {ny} × {nz} = {grid_nodes} grid nodes; at most \
                         {MAX_GRID_NODES} are supported"
                    ),
                );
                grid_ok = false;
            }
        }
    }

    check_materials(&mut c, &scene.materials, Analysis::ThreeD);
    check_time(&mut c, &scene.time);

    // Bodies: known material, well-formed region inside the grid with GIMP's empty layer.
    if scene.bodies.is_empty() {
        c.err(
            "bodies",
            serde_json::json!([]),
            "must contain at least one body",
        );
    }
    let mut regions_ok = true;
    for (i, b) in scene.bodies.iter().enumerate() {
        let p = format!("bodies.{i}");
        if !scene.materials.contains_key(&b.material) {
            let known: Vec<&String> = scene.materials.keys().collect();
            c.err(
                format!("{p}.material"),
                &b.material,
                format!("is not a defined material (known: {known:?})"),
            );
        }
        if b.particles_per_cell == 0 || b.particles_per_cell > 8 {
            c.err(
                format!("{p}.particles_per_cell"),
                b.particles_per_cell,
                "is outside 1..=8",
            );
            regions_ok = false;
        }
        c.point3(&format!("{p}.initial_velocity"), b.initial_velocity);
        let rok = c.region3(&format!("{p}.region"), &b.region);
        regions_ok &= rok;
        if rok && grid_ok {
            let (lo, hi) = b.region.bounds();
            let inner_lo = g.min.map(|m| m + h);
            let inner_hi = g.max.map(|m| m - h);
            let tol = 1e-12 * h;
            if (0..3).any(|k| lo[k] < g.min[k] || hi[k] > g.max[k]) {
                c.err(
                    format!("{p}.region"),
                    [lo, hi],
                    format!(
                        "(body {i}'s bounding box) reaches outside the grid box [{:?}, {:?}]",
                        g.min, g.max
                    ),
                );
                regions_ok = false;
            } else if (0..3).any(|k| lo[k] < inner_lo[k] - tol || hi[k] > inner_hi[k] + tol) {
                c.err(
                    format!("{p}.region"),
                    [lo, hi],
                    format!(
                        "(body {i}'s bounding box) comes closer than one cell to the grid \
                         edge: GIMP needs one empty cell layer, keep bodies within \
                         [{inner_lo:?}, {inner_hi:?}]"
                    ),
                );
                regions_ok = false;
            }
        }
    }

    // The size of the walk, from the bounding boxes alone, before walking.
    let walk_ok = regions_ok && grid_ok && c.errors.is_empty();
    if walk_ok {
        let sites = lattice3::candidate_sites3(scene);
        if sites > MAX_LATTICE_SITES {
            let mem = cost::memory_estimate3(scene, sites);
            c.err(
                "bodies",
                sites,
                format!(
                    "candidate particle sites in the bodies' bounding boxes: more than the \
                     {MAX_LATTICE_SITES} validation examines (up to {sites} particles would \
                     need about {}: {mem}); coarsen grid.cell_size or lower \
                     particles_per_cell",
                    cost::bytes(mem.total)
                ),
            );
        }
    }

    // Count particles (also detects empty bodies).
    let mut particles = 0u64;
    if walk_ok && c.errors.is_empty() {
        let counts = lattice3::count_per_body3(scene);
        for (i, n) in counts.iter().enumerate() {
            if *n == 0 {
                c.err(
                    format!("bodies.{i}.region"),
                    scene.bodies[i].region.bounds(),
                    "contains no particle centre (empty body, or entirely covered by earlier bodies)",
                );
            }
            particles += *n as u64;
        }
    }

    // Reserved parts of the format.
    if !scene.cracks.is_empty() {
        c.err(
            "cracks",
            scene.cracks.len(),
            "3D crack surfaces are not supported yet: the 3D solver runs the continuum only \
             (crack surfaces come with a later issue); remove `cracks`, or run the scene's 2D \
             twin",
        );
    }
    if !scene.interfaces.is_empty() {
        c.err(
            "interfaces",
            scene.interfaces.len(),
            "cohesive interfaces are not supported in 3D yet: remove `interfaces`",
        );
    }

    // Boundary conditions.
    for (i, bc) in scene.boundary_conditions.iter().enumerate() {
        let p = format!("boundary_conditions.{i}");
        c.region3(&format!("{p}.region"), &bc.region);
        let comps = bc.velocity.components();
        if comps.iter().all(Option::is_none) {
            c.err(
                format!("{p}.velocity"),
                serde_json::json!({}),
                "prescribes no component (give x, y, z or several)",
            );
        }
        for (k, v) in ["x", "y", "z"].iter().zip(comps) {
            if let Some(v) = v {
                c.finite(&format!("{p}.velocity.{k}"), v);
            }
        }
        if let Some(t) = bc.ramp_time {
            c.non_negative(&format!("{p}.ramp_time"), t);
        }
        if let Some(t) = bc.start {
            c.non_negative(&format!("{p}.start"), t);
        }
        if let Some(t) = bc.end {
            c.non_negative(&format!("{p}.end"), t);
            if let Some(s) = bc.start
                && t <= s
            {
                c.err(format!("{p}.end"), t, format!("must be after start ({s})"));
            }
        }
    }

    // Loads.
    for (i, l) in scene.loads.iter().enumerate() {
        let p = format!("loads.{i}");
        c.region3(&format!("{p}.region"), &l.region);
        c.point3(&format!("{p}.traction"), l.traction);
        if let Some(t) = l.ramp_time {
            c.non_negative(&format!("{p}.ramp_time"), t);
        }
    }

    check_damping(&mut c, &scene.damping);

    // Output.
    let o = &scene.output;
    if let Some(hi) = o.history_interval {
        c.positive("output.history_interval", hi);
    }
    c.non_negative("output.snapshot_interval", o.snapshot_interval);
    c.positive("output.speed_window", o.speed_window);
    for (k, f) in o.fields.iter().enumerate() {
        if *f == FieldKind::Fringe {
            c.err(
                format!("output.fields.{k}"),
                f,
                "is not available in 3D: photoelastic fringes are a 2D thin-plate quantity \
                 (take \"stress\")",
            );
        }
    }
    if let Some(f) = o.fringe_constant {
        c.err(
            "output.fringe_constant",
            f,
            "does not apply in 3D: photoelastic fringes are a 2D thin-plate quantity (remove it)",
        );
    }
    for (i, s) in o.slices.iter().enumerate() {
        let p = format!("output.slices.{i}.at");
        let k = s.normal.index();
        if c.finite(&p, s.at) && grid_ok && !(s.at >= g.min[k] && s.at <= g.max[k]) {
            c.err(
                p,
                s.at,
                format!(
                    "lies outside the grid box along {} [{}, {}]",
                    s.normal.name(),
                    g.min[k],
                    g.max[k]
                ),
            );
        }
    }

    // Time step and steps.
    let time_step = scene.time_step().unwrap_or(f64::NAN);
    let mut steps = 0;
    if c.errors.is_empty() {
        let s = (scene.time.end / time_step * (1.0 - 1e-12)).ceil();
        if !(time_step.is_finite() && time_step > 0.0) {
            c.err(
                "grid.cell_size",
                h,
                format!(
                    "gives a time step Δt = cfl·h/c_L = {time_step:e} s that is not a finite \
                     positive number"
                ),
            );
        } else if !(s.is_finite() && s < 1e12) {
            c.err(
                "time.end",
                scene.time.end,
                format!("needs {s} steps of {time_step:e} s"),
            );
        } else {
            steps = s as u64;
        }
    }

    if c.errors.is_empty() {
        Ok(RunSize {
            particles,
            grid_nodes,
            time_step,
            steps,
        })
    } else {
        Err(ValidationErrors(c.errors))
    }
}
