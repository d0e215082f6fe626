//! Scene validation: every problem is reported with its JSON path and the offending value.
//!
//! [`parse_scene`] turns JSON text into a scene (syntax and type errors carry their path
//! too, via `serde_path_to_error`); [`validate`] checks the physics and geometry and returns
//! the size of the run.

use std::collections::BTreeMap;
use std::fmt;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::lattice;
use crate::scene::{
    Analysis, CohesiveLaw, ContactLaw, Damping, FieldKind, GrowthDirection, GrowthSpeed, JIntegral,
    Material, Propagation, Region, Scene, TimeControl, Toughness, Vec2,
};

/// The largest `time.cfl` a scene with an exponential or cubic interface may use: their stiff
/// initial branch makes larger steps unstable (measured on a cohesive double-cantilever beam,
/// `docs/scene-extensions.md`).
pub const MAX_CFL_ELASTIC_LAW: f64 = 0.15;

/// One validation problem.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ValidationError {
    /// JSON path of the offending field, e.g. `materials.plate.poissons_ratio`.
    pub path: String,
    /// The offending value as JSON text (empty when the field is missing).
    pub value: String,
    /// What is wrong, e.g. `is outside (-1, 0.5)`.
    pub reason: String,
}

impl fmt::Display for ValidationError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.value.is_empty() {
            write!(f, "{}: {}", self.path, self.reason)
        } else {
            write!(f, "{}: {} {}", self.path, self.value, self.reason)
        }
    }
}

/// All problems found in a scene.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct ValidationErrors(pub Vec<ValidationError>);

impl fmt::Display for ValidationErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, e) in self.0.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            write!(f, "{e}")?;
        }
        Ok(())
    }
}

/// The size of a valid run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct RunSize {
    /// Number of particles.
    pub particles: u64,
    /// Number of nodes of the grid box.
    pub grid_nodes: u64,
    /// Time step Δt (s).
    pub time_step: f64,
    /// Number of time steps to reach `time.end`.
    pub steps: u64,
}

/// Parse a scene from JSON text; syntax, type and unknown-field errors name their path.
pub fn parse_scene(text: &str) -> Result<Scene, ValidationErrors> {
    parse_with_path(text)
}

/// Deserialize `T` from JSON text; the error names its JSON path (`(document)` for the
/// whole document). Shared by the 2D and 3D scene parsers.
pub(crate) fn parse_with_path<T: serde::de::DeserializeOwned>(
    text: &str,
) -> Result<T, ValidationErrors> {
    let de = &mut serde_json::Deserializer::from_str(text);
    serde_path_to_error::deserialize(de).map_err(|e| {
        let path = e.path().to_string();
        let path = if path == "." { String::new() } else { path };
        ValidationErrors(vec![ValidationError {
            path: if path.is_empty() {
                "(document)".into()
            } else {
                path
            },
            value: String::new(),
            reason: e.into_inner().to_string(),
        }])
    })
}

/// Parse a scene from an already-parsed JSON value; errors name their path.
pub fn scene_from_value(value: serde_json::Value) -> Result<Scene, ValidationErrors> {
    serde_path_to_error::deserialize(value).map_err(|e| {
        let path = e.path().to_string();
        ValidationErrors(vec![ValidationError {
            path: if path == "." || path.is_empty() {
                "(document)".into()
            } else {
                path
            },
            value: String::new(),
            reason: e.into_inner().to_string(),
        }])
    })
}

/// Collects validation problems (shared by the 2D and 3D validators).
pub(crate) struct Checker {
    pub(crate) errors: Vec<ValidationError>,
}

impl Checker {
    pub(crate) fn err(
        &mut self,
        path: impl Into<String>,
        value: impl Serialize,
        reason: impl Into<String>,
    ) {
        self.errors.push(ValidationError {
            path: path.into(),
            value: serde_json::to_string(&value).unwrap_or_default(),
            reason: reason.into(),
        });
    }
    pub(crate) fn finite(&mut self, path: &str, v: f64) -> bool {
        if v.is_finite() {
            true
        } else {
            self.errors.push(ValidationError {
                path: path.into(),
                value: format!("{v}"),
                reason: "is not a finite number".into(),
            });
            false
        }
    }
    pub(crate) fn positive(&mut self, path: &str, v: f64) {
        if self.finite(path, v) && v <= 0.0 {
            self.err(path, v, "must be > 0");
        }
    }
    pub(crate) fn non_negative(&mut self, path: &str, v: f64) {
        if self.finite(path, v) && v < 0.0 {
            self.err(path, v, "must be ≥ 0");
        }
    }
    fn point(&mut self, path: &str, p: Vec2) -> bool {
        let a = self.finite(&format!("{path}.0"), p[0]);
        let b = self.finite(&format!("{path}.1"), p[1]);
        a && b
    }
    fn region(&mut self, path: &str, r: &Region) -> bool {
        match r {
            Region::Rectangle { min, max } => {
                let ok = self.point(&format!("{path}.rectangle.min"), *min)
                    & self.point(&format!("{path}.rectangle.max"), *max);
                if ok && (max[0] <= min[0] || max[1] <= min[1]) {
                    self.err(
                        format!("{path}.rectangle.max"),
                        max,
                        format!("must be above and to the right of min {min:?}"),
                    );
                    return false;
                }
                ok
            }
            Region::Circle { center, radius } => {
                let ok = self.point(&format!("{path}.circle.center"), *center);
                let rp = format!("{path}.circle.radius");
                if self.finite(&rp, *radius) && *radius <= 0.0 {
                    self.err(rp, radius, "must be > 0");
                    return false;
                }
                ok && radius.is_finite()
            }
            Region::Polygon { points } => {
                if points.len() < 3 {
                    self.err(
                        format!("{path}.polygon.points"),
                        points.len(),
                        "points: a polygon needs at least 3",
                    );
                    return false;
                }
                let mut ok = true;
                for (i, p) in points.iter().enumerate() {
                    ok &= self.point(&format!("{path}.polygon.points.{i}"), *p);
                }
                ok
            }
        }
    }
}

/// A scene that passed [`validate`]: the only way to build a simulation
/// (`fracture_solver::Simulation::new` takes one), so a scene is validated once, where it
/// enters, and never again.
#[derive(Debug, Clone)]
pub struct ValidScene {
    scene: Scene,
    size: RunSize,
}

impl ValidScene {
    /// Validate `scene`; every problem found, with its JSON path, on error.
    pub fn new(scene: Scene) -> Result<ValidScene, ValidationErrors> {
        let size = validate(&scene)?;
        Ok(ValidScene { scene, size })
    }
    /// The scene.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }
    /// Its run size (particles, grid nodes, time step, steps).
    pub fn size(&self) -> &RunSize {
        &self.size
    }
    /// The scene back.
    pub fn into_scene(self) -> Scene {
        self.scene
    }
}

impl std::ops::Deref for ValidScene {
    type Target = Scene;
    fn deref(&self) -> &Scene {
        &self.scene
    }
}

/// Constants that are each valid can still give a dilatational wave speed that is not a
/// finite positive number (E/ρ overflows or underflows: density 1e-300), and so no time
/// step: name the more extreme of the two constants, with its value.
pub(crate) fn wave_speed(c: &mut Checker, p: &str, rho: f64, e: f64, nu: f64, analysis: Analysis) {
    let ok = |x: f64| x.is_finite() && x > 0.0;
    if !(ok(rho) && ok(e) && nu > -1.0 && nu < 0.5) {
        return; // already reported
    }
    let c_l = crate::scene::WaveSpeeds::new(e, nu, rho, analysis).c_l;
    if ok(c_l) {
        return;
    }
    let (field, value) = if rho.log10().abs() >= e.log10().abs() {
        ("density", rho)
    } else {
        ("youngs_modulus", e)
    };
    let what = if c_l.is_finite() {
        "underflows to 0"
    } else {
        "overflows"
    };
    c.err(
        format!("{p}.{field}"),
        value,
        format!(
            "makes the dilatational wave speed c_L = √(E(1−ν)/((1+ν)(1−2ν)ρ)) not a finite \
             positive number (E/ρ = {e:e} / {rho:e} {what}), so there is no time step: \
             give the constants in SI units (kg/m³, Pa)"
        ),
    );
}

/// The materials: at least one; ρ > 0, E > 0, ν in (-1, 0.5), and a finite c_L.
pub(crate) fn check_materials(
    c: &mut Checker,
    materials: &BTreeMap<String, Material>,
    analysis: Analysis,
) {
    if materials.is_empty() {
        c.err(
            "materials",
            serde_json::json!({}),
            "must define at least one material",
        );
    }
    for (name, m) in materials {
        let p = format!("materials.{name}");
        c.positive(&format!("{p}.density"), m.density());
        c.positive(&format!("{p}.youngs_modulus"), m.youngs_modulus());
        let nu = m.poissons_ratio();
        let np = format!("{p}.poissons_ratio");
        if c.finite(&np, nu) && !(nu > -1.0 && nu < 0.5) {
            c.err(np, nu, "is outside (-1, 0.5)");
        } else {
            wave_speed(c, &p, m.density(), m.youngs_modulus(), nu, analysis);
        }
    }
}

/// `time.end` > 0 and `time.cfl` in (0, 1].
pub(crate) fn check_time(c: &mut Checker, time: &TimeControl) {
    c.positive("time.end", time.end);
    let cfl = time.cfl;
    if c.finite("time.cfl", cfl) && !(cfl > 0.0 && cfl <= 1.0) {
        c.err("time.cfl", cfl, "is outside (0, 1]");
    }
}

/// The damping coefficient: kinetic in [0, 1), viscous ≥ 0.
pub(crate) fn check_damping(c: &mut Checker, damping: &Damping) {
    match *damping {
        Damping::None => {}
        Damping::Kinetic { coefficient } => {
            if c.finite("damping.coefficient", coefficient) && !(0.0..1.0).contains(&coefficient) {
                c.err("damping.coefficient", coefficient, "is outside [0, 1)");
            }
        }
        Damping::Viscous { coefficient } => c.non_negative("damping.coefficient", coefficient),
    }
}

/// Validate a scene. Returns the run size, or every problem found.
pub fn validate(scene: &Scene) -> Result<RunSize, ValidationErrors> {
    let mut c = Checker { errors: Vec::new() };

    if scene.analysis == Analysis::ThreeD {
        c.err(
            "analysis",
            "3d",
            "is a 3D scene: read it with fracture_api::parse_any_scene (or as a Scene3), \
             whose format is docs/scenes-3d.md; a 2D scene takes plane_strain or plane_stress",
        );
    }
    c.positive("thickness", scene.thickness);

    // Grid.
    let g = &scene.grid;
    let h = g.cell_size;
    c.positive("grid.cell_size", h);
    let grid_ok =
        c.point("grid.min", g.min) & c.point("grid.max", g.max) && h.is_finite() && h > 0.0;
    let mut grid_nodes = 0u64;
    if grid_ok {
        if g.max[0] <= g.min[0] || g.max[1] <= g.min[1] {
            c.err(
                "grid.max",
                g.max,
                format!("must be above and to the right of grid.min {:?}", g.min),
            );
        } else {
            // `as u64` saturates on huge spans; the + 1 must too (grids beyond 2⁶⁴ nodes a
            // side are refused below, not wrapped to a small count).
            let nx = (((g.max[0] - g.min[0]) / h - 1e-9).ceil() as u64).saturating_add(1);
            let ny = (((g.max[1] - g.min[1]) / h - 1e-9).ceil() as u64).saturating_add(1);
            grid_nodes = nx.saturating_mul(ny);
            if grid_nodes > 200_000_000 {
                c.err(
                    "grid.cell_size",
                    h,
                    format!("gives {grid_nodes} grid nodes; at most 200000000 are supported"),
                );
            }
        }
    }

    // Materials.
    check_materials(&mut c, &scene.materials, scene.analysis);

    // Time.
    check_time(&mut c, &scene.time);

    // Bodies: region inside the grid (with the empty cell layer GIMP needs), known material.
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
        c.point(&format!("{p}.initial_velocity"), b.initial_velocity);
        let rok = c.region(&format!("{p}.region"), &b.region);
        regions_ok &= rok;
        if rok && grid_ok {
            let (lo, hi) = b.region.bounds();
            let inner_lo = [g.min[0] + h, g.min[1] + h];
            let inner_hi = [g.max[0] - h, g.max[1] - h];
            if lo[0] < g.min[0] || lo[1] < g.min[1] || hi[0] > g.max[0] || hi[1] > g.max[1] {
                c.err(
                    format!("{p}.region"),
                    [lo, hi],
                    format!("reaches outside the grid box [{:?}, {:?}]", g.min, g.max),
                );
                regions_ok = false;
            } else if lo[0] < inner_lo[0] - 1e-12 * h
                || lo[1] < inner_lo[1] - 1e-12 * h
                || hi[0] > inner_hi[0] + 1e-12 * h
                || hi[1] > inner_hi[1] + 1e-12 * h
            {
                c.err(
                    format!("{p}.region"),
                    [lo, hi],
                    format!(
                        "comes closer than one cell to the grid edge: GIMP needs one empty \
                         cell layer, keep bodies within [{inner_lo:?}, {inner_hi:?}]"
                    ),
                );
                regions_ok = false;
            }
        }
    }

    // Body-to-body contact: the bodies with `contact` share the second velocity field, so
    // they take one law, and they need a body without it to meet.
    let contact_bodies: Vec<(usize, &ContactLaw)> = scene
        .bodies
        .iter()
        .enumerate()
        .filter_map(|(i, b)| b.contact.as_ref().map(|law| (i, law)))
        .collect();
    if let Some(&(first, law)) = contact_bodies.first() {
        for &(i, other) in &contact_bodies {
            if let ContactLaw::Coulomb { friction } = other {
                c.non_negative(&format!("bodies.{i}.contact.friction"), *friction);
            }
            if other != law {
                c.err(
                    format!("bodies.{i}.contact"),
                    other,
                    format!(
                        "differs from bodies.{first}.contact: the bodies with a contact law share \
                         one velocity field, so they take one law"
                    ),
                );
            }
        }
        if contact_bodies.len() == scene.bodies.len() {
            c.err(
                format!("bodies.{first}.contact"),
                law,
                "has no body to meet: every body names a contact law, so all share one \
                 velocity field; leave it off the body they strike",
            );
        }
    }

    // Count particles (also detects empty bodies).
    let mut particles = 0u64;
    if regions_ok && grid_ok && c.errors.is_empty() {
        let counts = lattice::count_per_body(scene);
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

    // Cracks.
    for (i, cr) in scene.cracks.iter().enumerate() {
        let p = format!("cracks.{i}");
        if cr.points.len() < 2 {
            c.err(
                format!("{p}.points"),
                &cr.points,
                "needs at least two points",
            );
        }
        let mut pts_ok = true;
        for (k, q) in cr.points.iter().enumerate() {
            pts_ok &= c.point(&format!("{p}.points.{k}"), *q);
            if grid_ok
                && pts_ok
                && (q[0] < g.min[0] || q[0] > g.max[0] || q[1] < g.min[1] || q[1] > g.max[1])
            {
                c.err(format!("{p}.points.{k}"), q, "lies outside the grid box");
            }
        }
        if pts_ok {
            for k in 1..cr.points.len() {
                let (a, b) = (cr.points[k - 1], cr.points[k]);
                if (a[0] - b[0]).hypot(a[1] - b[1]) <= 1e-12 * h.abs().max(1e-300) {
                    c.err(
                        format!("{p}.points.{k}"),
                        b,
                        "repeats the previous point (zero-length segment)",
                    );
                }
            }
        }
        if let Some(n) = cr.j_contour
            && (n == 0 || n > 16)
        {
            c.err(format!("{p}.j_contour"), n, "is outside 1..=16 cells");
        }
        match cr.j_integral {
            Some(JIntegral::Contour { cells }) if cells == 0 || cells > 16 => {
                c.err(
                    format!("{p}.j_integral.cells"),
                    cells,
                    "is outside 1..=16 cells",
                );
            }
            Some(JIntegral::Domain { radius }) => {
                let rp = format!("{p}.j_integral.radius");
                c.positive(&rp, radius);
                if radius.is_finite()
                    && radius > 0.0
                    && h.is_finite()
                    && h > 0.0
                    && radius < 2.0 * h
                {
                    c.err(
                        rp,
                        radius,
                        format!(
                            "is under two cells ({:e} m): the ring would not hold enough particles",
                            2.0 * h
                        ),
                    );
                }
            }
            _ => {}
        }
        // A crack growing by the equation of motion: its ring (and with it the zone behind
        // the tip and the filter time) is part of the tip law and must span enough cells.
        if let (
            Propagation::EnergyRelease {
                speed: GrowthSpeed::EquationOfMotion,
                ..
            },
            JIntegral::Domain { radius },
        ) = (&cr.propagation, JIntegral::default_in(cr, scene))
            && radius.is_finite()
            && h.is_finite()
            && h > 0.0
            && (cr.j_integral.is_none() || radius >= 2.0 * h)
            && radius < JIntegral::MIN_GROWTH_RADIUS_CELLS * h
        {
            let (field, what) = if cr.j_integral.is_some() {
                (format!("{p}.j_integral.radius"), "the ring")
            } else {
                (
                    format!("{p}.j_integral"),
                    "the default ring (1/16 of the scene's shortest body side)",
                )
            };
            c.err(
                field,
                radius,
                format!(
                    "{what} of a crack growing by the equation of motion spans under {} cells ({:e} m): the zone behind the tip (a third of it) would not span a cell; refine the grid or set cracks.{i}.j_integral.radius",
                    JIntegral::MIN_GROWTH_RADIUS_CELLS,
                    JIntegral::MIN_GROWTH_RADIUS_CELLS * h
                ),
            );
        }
        if let ContactLaw::Coulomb { friction } = cr.contact {
            c.non_negative(&format!("{p}.contact.friction"), friction);
        }
        if let Propagation::EnergyRelease {
            toughness,
            direction,
            filter_time,
            process_zone,
            ..
        } = &cr.propagation
        {
            let tp = format!("{p}.propagation.toughness");
            match toughness {
                Toughness::Constant(g) => c.positive(&tp, *g),
                Toughness::Table(rows) => {
                    if rows.is_empty() {
                        c.err(
                            tp.clone(),
                            serde_json::json!([]),
                            "is an empty table (give [[v, Γ], …] rows)",
                        );
                    }
                    for (k, r) in rows.iter().enumerate() {
                        c.non_negative(&format!("{tp}.{k}.0"), r[0]);
                        c.positive(&format!("{tp}.{k}.1"), r[1]);
                        if k == 0 && r[0] != 0.0 {
                            c.err(
                                format!("{tp}.0.0"),
                                r[0],
                                "must be 0 (the table starts at rest)",
                            );
                        }
                        if k > 0 && r[0] <= rows[k - 1][0] {
                            c.err(
                                format!("{tp}.{k}.0"),
                                r[0],
                                "must be above the previous row's speed (ascending)",
                            );
                        }
                    }
                }
            }
            if let Some(t) = filter_time {
                c.positive(&format!("{p}.propagation.filter_time"), *t);
            }
            if let Some(l) = process_zone {
                c.non_negative(&format!("{p}.propagation.process_zone"), *l);
            }
            if let GrowthDirection::Fixed(d) = direction {
                let dp = format!("{p}.propagation.direction.fixed");
                if c.point(&dp, *d) && d[0] == 0.0 && d[1] == 0.0 {
                    c.err(dp, d, "must be a non-zero vector");
                }
            }
        }
    }

    // Interfaces.
    for (i, it) in scene.interfaces.iter().enumerate() {
        let p = format!("interfaces.{i}");
        if it.points.len() < 2 {
            c.err(
                format!("{p}.points"),
                &it.points,
                "needs at least two points",
            );
        }
        for (k, q) in it.points.iter().enumerate() {
            if c.point(&format!("{p}.points.{k}"), *q)
                && grid_ok
                && (q[0] < g.min[0] || q[0] > g.max[0] || q[1] < g.min[1] || q[1] > g.max[1])
            {
                c.err(format!("{p}.points.{k}"), q, "lies outside the grid box");
            }
        }
        for k in 1..it.points.len() {
            let (a, b) = (it.points[k - 1], it.points[k]);
            if (a[0] - b[0]).hypot(a[1] - b[1]) <= 1e-12 * h.abs().max(1e-300) {
                c.err(
                    format!("{p}.points.{k}"),
                    b,
                    "repeats the previous point (zero-length segment)",
                );
            }
        }
        for (mode, m) in [("normal", it.cohesive.normal), ("shear", it.cohesive.shear)] {
            c.positive(&format!("{p}.cohesive.{mode}.strength"), m.strength);
            c.positive(&format!("{p}.cohesive.{mode}.toughness"), m.toughness);
        }
        if let ContactLaw::Coulomb { friction } = it.contact {
            c.non_negative(&format!("{p}.contact.friction"), friction);
        }
        // The elastic laws' stiff initial branch (slope e²σ_c²/G exponential, 3.8σ_c²/G cubic)
        // bounds the explicit step (docs/scene-extensions.md, "Stability"): measured on a
        // double-cantilever beam at 1 and 0.5 mm cells, cfl 0.15 is stable, 0.2 is not.
        if matches!(
            it.cohesive.law,
            CohesiveLaw::Exponential | CohesiveLaw::Cubic
        ) && scene.time.cfl > MAX_CFL_ELASTIC_LAW
        {
            c.err(
                "time.cfl",
                scene.time.cfl,
                format!(
                    "is above {MAX_CFL_ELASTIC_LAW}, the largest stable with the {} law of \
                     {p}.cohesive.law (its stiff initial branch); lower time.cfl or use the \
                     linear law, which has no such limit",
                    match it.cohesive.law {
                        CohesiveLaw::Exponential => "exponential",
                        _ => "cubic",
                    }
                ),
            );
        }
    }

    // A crack or interface drawn where no body is cuts nothing: the run would complete with
    // no tip rows. Sampled every half cell along the polyline (at most 4096 points a segment).
    let lines = (scene.cracks.iter().enumerate()).map(|(i, cr)| ("cracks", i, &cr.points));
    let lines = lines
        .chain((scene.interfaces.iter().enumerate()).map(|(i, it)| ("interfaces", i, &it.points)));
    for (kind, i, pts) in lines {
        if scene.bodies.is_empty() || pts.len() < 2 || !h.is_finite() || h <= 0.0 {
            continue;
        }
        if !polyline_meets_a_body(pts, &scene.bodies, h) {
            c.err(
                format!("{kind}.{i}.points"),
                pts,
                "lies outside every body: it cuts no material (move it into a body)",
            );
        }
    }

    // Reference values.
    let lines_count = scene.cracks.len() + scene.interfaces.len();
    for (i, r) in scene.references.iter().enumerate() {
        let p = format!("references.{i}");
        c.finite(&format!("{p}.value"), r.value);
        if r.crack as usize >= lines_count {
            c.err(
                format!("{p}.crack"),
                r.crack,
                format!(
                    "names no crack: the scene has {} cracks and {} interfaces (indices 0..{})",
                    scene.cracks.len(),
                    scene.interfaces.len(),
                    lines_count
                ),
            );
        }
        if let Some(t) = r.tip
            && t > 1
        {
            c.err(
                format!("{p}.tip"),
                t,
                "must be 0 (polyline start) or 1 (end)",
            );
        }
        if let Some(t) = r.tolerance {
            c.positive(&format!("{p}.tolerance"), t);
        }
    }

    // Boundary conditions.
    for (i, bc) in scene.boundary_conditions.iter().enumerate() {
        let p = format!("boundary_conditions.{i}");
        c.region(&format!("{p}.region"), &bc.region);
        if bc.velocity.x.is_none() && bc.velocity.y.is_none() {
            c.err(
                format!("{p}.velocity"),
                serde_json::json!({}),
                "prescribes no component (give x, y or both)",
            );
        }
        if let Some(v) = bc.velocity.x {
            c.finite(&format!("{p}.velocity.x"), v);
        }
        if let Some(v) = bc.velocity.y {
            c.finite(&format!("{p}.velocity.y"), v);
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
        c.region(&format!("{p}.region"), &l.region);
        c.point(&format!("{p}.traction"), l.traction);
        if let Some(t) = l.ramp_time {
            c.non_negative(&format!("{p}.ramp_time"), t);
        }
    }

    // Damping.
    check_damping(&mut c, &scene.damping);

    // Output.
    let o = &scene.output;
    if let Some(hi) = o.history_interval {
        c.positive("output.history_interval", hi);
    }
    c.non_negative("output.snapshot_interval", o.snapshot_interval);
    c.positive("output.speed_window", o.speed_window);
    if o.fields.contains(&FieldKind::Fringe) {
        match o.fringe_constant {
            None => c.err(
                "output.fringe_constant",
                serde_json::Value::Null,
                "is required when output.fields contains \"fringe\" (f_σ in N/m)",
            ),
            Some(f) => c.positive("output.fringe_constant", f),
        }
    }

    let time_step = scene.time_step().unwrap_or(f64::NAN);
    let mut steps = 0;
    if c.errors.is_empty() {
        let s = (scene.time.end / time_step * (1.0 - 1e-12)).ceil();
        if !(time_step.is_finite() && time_step > 0.0) {
            // A density or modulus so extreme that c_L (and so Δt) is not a number: name the
            // material constants rather than "NaN steps".
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

/// Whether some point of the polyline `pts`, sampled at least every `h / 2`, lies inside one
/// of `bodies`' regions.
fn polyline_meets_a_body(pts: &[Vec2], bodies: &[crate::scene::Body], h: f64) -> bool {
    pts.windows(2).any(|w| {
        let (a, b) = (w[0], w[1]);
        let len = (b[0] - a[0]).hypot(b[1] - a[1]);
        let n = ((2.0 * len / h).ceil() as usize).clamp(1, 4096);
        (0..=n).any(|k| {
            let s = k as f64 / n as f64;
            let q = [a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])];
            bodies.iter().any(|body| body.region.contains(q))
        })
    })
}
