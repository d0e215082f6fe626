//! The scene document: everything a run needs, in SI units (m, s, kg, Pa, J/m²).
//!
//! Field names and defaults are the public contract of `scene-format.md`. Extensions made by
//! this project are marked "(extension)" and documented in `docs/scene-extensions.md`; every
//! extension has a default, so a scene written against the shared contract means the same.

use std::collections::BTreeMap;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A 2D point or vector `[x, y]`.
pub type Vec2 = [f64; 2];

/// A complete simulation scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Short name of the scene (used as the run's name).
    #[serde(default = "default_name")]
    pub name: String,
    /// Free text describing the scene and its modelling choices.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub description: String,
    /// 2D stress state.
    #[serde(default)]
    pub analysis: Analysis,
    /// Out-of-plane thickness (m). Forces, energies and tractions are per this thickness;
    /// J and K are per unit thickness regardless.
    #[serde(default = "one")]
    pub thickness: f64,
    /// The background grid.
    pub grid: GridSpec,
    /// Materials by name.
    pub materials: BTreeMap<String, Material>,
    /// Bodies filled with particles.
    pub bodies: Vec<Body>,
    /// Explicit cracks.
    #[serde(default)]
    pub cracks: Vec<Crack>,
    /// Weak planes held by a cohesive law until they fail (`scene-format.md`,
    /// `algorithm.md` §8). Omitted when empty, so scenes without them keep their hash.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub interfaces: Vec<Interface>,
    /// Prescribed grid velocities.
    #[serde(default)]
    pub boundary_conditions: Vec<BoundaryCondition>,
    /// Tractions on particles.
    #[serde(default)]
    pub loads: Vec<Load>,
    /// Damping for quasi-static runs.
    #[serde(default)]
    pub damping: Damping,
    /// End time and time step control.
    pub time: TimeControl,
    /// What is recorded and how often.
    #[serde(default)]
    pub output: Output,
    /// (extension) Reference values the run's summary compares with (`summary.references`):
    /// an analytic K, a measured speed, a published growth length. Omitted when empty, so
    /// scenes without them keep their hash.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub references: Vec<Reference>,
}

/// (extension) A reference value of one crack tip's result, e.g. Tada's K_I of a centre
/// crack; the run's summary reports the measured value and the relative error.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Reference {
    /// The quantity compared.
    pub quantity: ReferenceQuantity,
    /// The reference value in SI units: J/m² (`j1`), Pa·√m (`k1`, `k2`), m (`growth`),
    /// m/s (`mean_speed`, `peak_speed`), s (`initiation_time`).
    pub value: f64,
    /// Index of the crack (scene cracks first, then interfaces, as `crack_tips.csv`);
    /// default 0.
    #[serde(default)]
    pub crack: u32,
    /// The tip (0: start of the polyline, 1: its end); absent: the crack's first tip that has
    /// samples.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tip: Option<u32>,
    /// Which value of J or K is compared: `final` (the last sample, default), `peak` (the
    /// largest magnitude) or `late_mean` (the mean over the last 20 % of `time.end`). Ignored
    /// by the other quantities.
    #[serde(default)]
    pub at: ReferenceAt,
    /// Where the value comes from (free text, e.g. "Tada, Paris & Irwin 2000, eq. 2.1").
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub source: String,
    /// Relative tolerance (e.g. 0.03 for 3 %): the summary says whether the run is within
    /// it. Absent: the error is reported, not judged.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<f64>,
}

/// (extension) The quantity of a [`Reference`].
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema, utoipa::ToSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum ReferenceQuantity {
    /// J along the crack (J/m²).
    J1,
    /// Mode I stress intensity factor (Pa·√m).
    K1,
    /// Mode II stress intensity factor (Pa·√m).
    K2,
    /// Crack growth at the tip (m).
    Growth,
    /// Mean speed while running (m/s).
    MeanSpeed,
    /// Peak speed over the summary's speed window (m/s).
    PeakSpeed,
    /// Time of initiation (s).
    InitiationTime,
}

/// (extension) Which sample of J or K a [`Reference`] compares.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema, utoipa::ToSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum ReferenceAt {
    /// The last sample where the value is defined.
    #[default]
    Final,
    /// The value of largest magnitude.
    Peak,
    /// The mean over the last 20 % of the scene's end time.
    LateMean,
}

fn default_name() -> String {
    "untitled".to_string()
}
fn one() -> f64 {
    1.0
}

/// The 2D stress state.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Analysis {
    /// Plane strain (ε_zz = 0, σ_zz = ν(σ_xx + σ_yy)).
    #[default]
    PlaneStrain,
    /// Plane stress (σ_zz = 0).
    PlaneStress,
    /// A 3D scene: such a document is a `Scene3` (`scene3.rs`, `docs/scenes-3d.md`); a 2D
    /// `Scene` naming it is refused by validation.
    #[serde(rename = "3d")]
    ThreeD,
}

/// The background grid.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GridSpec {
    /// Edge of the square cells (m).
    pub cell_size: f64,
    /// Lower-left corner of the grid box.
    pub min: Vec2,
    /// Upper-right corner of the grid box.
    pub max: Vec2,
    /// Shape functions.
    #[serde(default)]
    pub shape_function: ShapeFunction,
}

/// Particle–grid shape functions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ShapeFunction {
    /// Uniform GIMP (Bardenhagen & Kober 2004), particle domain fixed at its undeformed size.
    #[default]
    Gimp,
    /// Classic MPM bilinear shape functions.
    Linear,
}

/// A material model with its constants.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "model", rename_all = "snake_case", deny_unknown_fields)]
pub enum Material {
    /// Small-strain isotropic linear elasticity (hypoelastic rate form).
    LinearElastic {
        /// Mass density ρ (kg/m³).
        density: f64,
        /// Young's modulus E (Pa).
        youngs_modulus: f64,
        /// Poisson's ratio ν, in (-1, 0.5).
        poissons_ratio: f64,
    },
}

impl Material {
    /// Mass density (kg/m³).
    pub fn density(&self) -> f64 {
        match self {
            Material::LinearElastic { density, .. } => *density,
        }
    }
    /// Young's modulus (Pa).
    pub fn youngs_modulus(&self) -> f64 {
        match self {
            Material::LinearElastic { youngs_modulus, .. } => *youngs_modulus,
        }
    }
    /// Poisson's ratio.
    pub fn poissons_ratio(&self) -> f64 {
        match self {
            Material::LinearElastic { poissons_ratio, .. } => *poissons_ratio,
        }
    }
    /// Elastic wave speeds of this material in the given 2D state.
    pub fn wave_speeds(&self, analysis: Analysis) -> WaveSpeeds {
        WaveSpeeds::new(
            self.youngs_modulus(),
            self.poissons_ratio(),
            self.density(),
            analysis,
        )
    }
}

/// Dilatational, shear and Rayleigh wave speeds (m/s) of an isotropic elastic material.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct WaveSpeeds {
    /// Dilatational speed c_L of the 2D state (plane strain: the bulk P-wave speed; plane
    /// stress: the thin-plate speed sqrt(E/(ρ(1−ν²)))).
    pub c_l: f64,
    /// Shear speed c_S.
    pub c_s: f64,
    /// Rayleigh speed c_R, the exact root of the Rayleigh equation.
    pub c_r: f64,
}

impl WaveSpeeds {
    /// Wave speeds for E, ν, ρ in the given 2D state.
    pub fn new(e: f64, nu: f64, rho: f64, analysis: Analysis) -> Self {
        let c_s = (e / (2.0 * (1.0 + nu) * rho)).sqrt();
        let c_l = match analysis {
            Analysis::PlaneStress => (e / (rho * (1.0 - nu * nu))).sqrt(),
            _ => (e * (1.0 - nu) / (rho * (1.0 + nu) * (1.0 - 2.0 * nu))).sqrt(),
        };
        let c_r = rayleigh_speed(c_l, c_s);
        WaveSpeeds { c_l, c_s, c_r }
    }
}

/// The Rayleigh wave speed: x = (c_R/c_S)² is the root in (0, 1) of
/// (2 − x)² = 4·sqrt(1 − x)·sqrt(1 − κx), κ = (c_S/c_L)² (`reference-solutions.md`).
/// Solved by bisection to machine precision (no fitted approximation).
pub fn rayleigh_speed(c_l: f64, c_s: f64) -> f64 {
    let kappa = (c_s / c_l).powi(2);
    let f = |x: f64| (2.0 - x).powi(2) - 4.0 * (1.0 - x).sqrt() * (1.0 - kappa * x).sqrt();
    // f(0) = 0 is the trivial root; f is negative just above 0 and f(1) = 1 > 0.
    let (lo, hi) = bisect(1e-6, 1.0, 200, |x| {
        let fx = f(x);
        fx.is_nan() || fx <= 0.0
    });
    c_s * (0.5 * (lo + hi)).sqrt()
}

/// Bisection: halves [lo, hi] `iterations` times, keeping the upper half where
/// `root_above(mid)` holds and the lower half otherwise; returns the final bracket.
pub fn bisect(
    mut lo: f64,
    mut hi: f64,
    iterations: u32,
    root_above: impl Fn(f64) -> bool,
) -> (f64, f64) {
    for _ in 0..iterations {
        let mid = 0.5 * (lo + hi);
        if root_above(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (lo, hi)
}

/// A region of the plane.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Region {
    /// Axis-aligned rectangle.
    Rectangle {
        /// Lower-left corner.
        min: Vec2,
        /// Upper-right corner.
        max: Vec2,
    },
    /// Disc.
    Circle {
        /// Centre.
        center: Vec2,
        /// Radius (m).
        radius: f64,
    },
    /// Closed polygon, either orientation.
    Polygon {
        /// Vertices.
        points: Vec<Vec2>,
    },
}

impl Region {
    /// Whether `p` lies inside the region (boundary points count as inside for rectangles
    /// and circles; polygons use the even-odd rule).
    pub fn contains(&self, p: Vec2) -> bool {
        match self {
            Region::Rectangle { min, max } => {
                p[0] >= min[0] && p[0] <= max[0] && p[1] >= min[1] && p[1] <= max[1]
            }
            Region::Circle { center, radius } => {
                let dx = p[0] - center[0];
                let dy = p[1] - center[1];
                dx * dx + dy * dy <= radius * radius
            }
            Region::Polygon { points } => {
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
        }
    }

    /// Axis-aligned bounding box `(min, max)`.
    pub fn bounds(&self) -> (Vec2, Vec2) {
        match self {
            Region::Rectangle { min, max } => (*min, *max),
            Region::Circle { center, radius } => (
                [center[0] - radius, center[1] - radius],
                [center[0] + radius, center[1] + radius],
            ),
            Region::Polygon { points } => {
                let mut lo = [f64::INFINITY; 2];
                let mut hi = [f64::NEG_INFINITY; 2];
                for p in points {
                    for k in 0..2 {
                        lo[k] = lo[k].min(p[k]);
                        hi[k] = hi[k].max(p[k]);
                    }
                }
                (lo, hi)
            }
        }
    }
}

/// A body: a region filled with particles of one material.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Body {
    /// Name of a material in `materials`.
    pub material: String,
    /// The region the particles fill.
    pub region: Region,
    /// Particles per cell in each direction (2 → 4 particles per cell).
    #[serde(default = "two_u32")]
    pub particles_per_cell: u32,
    /// Uniform initial velocity (m/s).
    #[serde(default)]
    pub initial_velocity: Vec2,
    /// (extension, `docs/scene-extensions.md`) Body-to-body contact: the body carries its own
    /// velocity field at the nodes it shares with the other bodies, and meets them through
    /// this law (frictionless, stick or Coulomb; `algorithm.md` §4's algebra with the struck
    /// body's surface normal). Absent: the body shares one field with every other
    /// body it touches (bonded, as before). Bodies with `contact` share that second field
    /// with each other.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact: Option<ContactLaw>,
}

fn two_u32() -> u32 {
    2
}

/// An explicit crack.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Crack {
    /// Polyline of at least two points. Its ends are crack tips, except an end outside every
    /// body (an edge crack's mouth).
    pub points: Vec<Vec2>,
    /// Crack-face contact law.
    #[serde(default)]
    pub contact: ContactLaw,
    /// Propagation criterion.
    #[serde(default)]
    pub propagation: Propagation,
    /// (extension, the old spelling of `{"j_integral": {"method": "contour", "cells": n}}`)
    /// Half-size of the square J-integral contour, in cells. Used only when `j_integral` is
    /// absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub j_contour: Option<u32>,
    /// How J is evaluated at this crack's tips (`scene-format.md`); default
    /// [`JIntegral::default_in`]: the domain integral over a ring of radius 6 cells, or for
    /// a crack growing by the equation of motion, of L/16 (L the scene's length scale).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub j_integral: Option<JIntegral>,
}

/// A cohesive interface: a polyline whose two sides carry separate velocity fields from the
/// start and are held together by a traction–separation law until it fails; failed parts
/// behave as a crack with `contact`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Interface {
    /// Polyline of at least two points.
    pub points: Vec<Vec2>,
    /// The traction–separation law and its mode I and mode II constants.
    pub cohesive: Cohesive,
    /// Contact of the failed faces (and of closed faces: compression is always contact).
    #[serde(default)]
    pub contact: ContactLaw,
}

/// A traction–separation law with its normal (mode I) and shear (mode II) constants.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Cohesive {
    /// The shape of the law.
    pub law: CohesiveLaw,
    /// Opening: peak traction σ_c (Pa) and toughness G_Ic (J/m²).
    pub normal: CohesiveMode,
    /// Sliding: peak traction τ_c (Pa) and toughness G_IIc (J/m²).
    pub shear: CohesiveMode,
}

/// One mode's constants of a cohesive law.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CohesiveMode {
    /// Peak traction (Pa).
    pub strength: f64,
    /// Work per unit area to separate fully in this mode (J/m²).
    pub toughness: f64,
}

/// Shapes of the traction–separation law, written on the effective separation
/// λ = sqrt((δ_n/δ_nc)² + (δ_t/δ_tc)²) as T(λ) times the mode's strength
/// (`docs/scene-extensions.md`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum CohesiveLaw {
    /// Linear softening from the peak (rigid until the peak): T = 1 − λ on [0, 1],
    /// δ_c = 2G/σ_c.
    Linear,
    /// Xu–Needleman's exponential shape: T = e·λ·e^(−λ), peak at λ = 1, δ_c = G/(e·σ_c).
    Exponential,
    /// Needleman's cubic: T = (27/4)·λ(1 − λ)², peak at λ = 1/3, δ_c = 16G/(9σ_c).
    Cubic,
}

impl CohesiveLaw {
    /// T(λ), the traction over the strength on the loading envelope.
    pub fn shape(self, l: f64) -> f64 {
        let l = l.max(0.0);
        match self {
            CohesiveLaw::Linear => (1.0 - l).max(0.0),
            CohesiveLaw::Exponential => std::f64::consts::E * l * (-l).exp(),
            CohesiveLaw::Cubic => {
                if l >= 1.0 {
                    0.0
                } else {
                    6.75 * l * (1.0 - l) * (1.0 - l)
                }
            }
        }
    }
    /// ∫₀^∞ T(λ) dλ: the toughness is strength × δ_c × this.
    pub fn area(self) -> f64 {
        match self {
            CohesiveLaw::Linear => 0.5,
            CohesiveLaw::Exponential => std::f64::consts::E,
            CohesiveLaw::Cubic => 9.0 / 16.0,
        }
    }
    /// λ at the peak traction (the elastic branch ends there; unloading past it follows the
    /// secant to the origin).
    pub fn peak(self) -> f64 {
        match self {
            CohesiveLaw::Linear => 0.0,
            CohesiveLaw::Exponential => 1.0,
            CohesiveLaw::Cubic => 1.0 / 3.0,
        }
    }
    /// λ at which a point counts as failed: the law's end (linear, cubic), or where the
    /// exponential's remaining work is below 10⁻³ of G (λ = 11: (1 + λ)e^(−λ) < 10⁻⁴).
    pub fn end(self) -> f64 {
        match self {
            CohesiveLaw::Linear | CohesiveLaw::Cubic => 1.0,
            CohesiveLaw::Exponential => 11.0,
        }
    }
}

impl CohesiveMode {
    /// The characteristic separation δ_c = G/(σ_c·∫T) of this mode under `law` (m).
    pub fn critical_separation(&self, law: CohesiveLaw) -> f64 {
        self.toughness / (self.strength * law.area())
    }
}

/// How the J-integral of a tip is evaluated (`algorithm.md` §6).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "method", rename_all = "snake_case", deny_unknown_fields)]
pub enum JIntegral {
    /// Equivalent domain integral over a ring around the tip: weight q = 1 inside r/2,
    /// falling linearly to 0 at r = `radius` (m), every particle with its own field's
    /// values, the inertial terms and the crack-face traction term.
    Domain {
        /// Outer radius of the ring (m), at least two cells.
        radius: f64,
    },
    /// The seed's square grid-line contour of half-size `cells`, plus the area term.
    Contour {
        /// Half-size in cells (1..=16).
        cells: u32,
    },
}

impl JIntegral {
    /// Cells of the default domain radius of a crack that does not grow by the equation of
    /// motion. J of a crack at rest is domain independent, so this ring is a quadrature
    /// choice that converges with h (`docs/verification.md`), not part of a model.
    pub const DEFAULT_RADIUS_CELLS: f64 = 6.0;

    /// The default domain radius of a crack that grows by the equation of motion, as a
    /// fraction of the scene's length scale ([`Scene::length_scale`]). The ring sets the
    /// zone behind the tip ([`Propagation::DEFAULT_ZONE_FRACTION`]) and the filter time
    /// ([`Propagation::DEFAULT_FILTER_TRANSITS`]), so it is part of the tip law: it must not
    /// follow the cell (`algorithm.md` pitfall 13). 1/16 of the shortest side of the bodies'
    /// bounding box: 6.25 mm for Kalthoff–Winkler (100 mm), 7.8 mm for the Rosakis block
    /// (125 mm), 4.4 mm for the growing Freund strip (70 mm); `docs/growth.md` measures
    /// the dependence on it.
    pub const GROWTH_RADIUS_FRACTION: f64 = 1.0 / 16.0;

    /// The fewest cells across the ring of a crack that grows by the equation of motion
    /// (validation): the zone behind the tip, a third of the ring, then spans one cell.
    pub const MIN_GROWTH_RADIUS_CELLS: f64 = 3.0;

    /// The method of a crack: its `j_integral`, else its `j_contour` (old spelling), else
    /// the domain integral with radius [`Self::DEFAULT_RADIUS_CELLS`]·`cell_size`.
    pub fn default_for(crack: &Crack, cell_size: f64) -> JIntegral {
        match (crack.j_integral, crack.j_contour) {
            (Some(j), _) => j,
            (None, Some(cells)) => JIntegral::Contour { cells },
            (None, None) => JIntegral::Domain {
                radius: Self::DEFAULT_RADIUS_CELLS * cell_size,
            },
        }
    }

    /// The method of a crack in `scene`: as [`Self::default_for`], except that a crack
    /// growing by the equation of motion without its own method gets the physical ring
    /// [`Self::GROWTH_RADIUS_FRACTION`]·L (L the scene's length scale), whatever the cell.
    pub fn default_in(crack: &Crack, scene: &Scene) -> JIntegral {
        let eom = matches!(
            crack.propagation,
            Propagation::EnergyRelease {
                speed: GrowthSpeed::EquationOfMotion,
                ..
            }
        );
        match (crack.j_integral, crack.j_contour) {
            (None, None) if eom => JIntegral::Domain {
                radius: Self::GROWTH_RADIUS_FRACTION * scene.length_scale(),
            },
            _ => Self::default_for(crack, scene.grid.cell_size),
        }
    }
}

/// Crack-face contact law.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "law", rename_all = "snake_case", deny_unknown_fields)]
pub enum ContactLaw {
    /// Faces cannot interpenetrate; no tangential force.
    #[default]
    Frictionless,
    /// Faces move together (bonded) wherever both fields are present.
    Stick,
    /// Coulomb friction: sliding when |τ| > μ|σ_n|.
    Coulomb {
        /// Friction coefficient μ ≥ 0.
        friction: f64,
    },
}

/// Crack propagation.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "criterion", rename_all = "snake_case", deny_unknown_fields)]
pub enum Propagation {
    /// Stationary crack; J and K are still reported.
    #[default]
    None,
    /// Grow while the energy release rate G reaches the toughness.
    EnergyRelease {
        /// Critical energy release rate Γ (J/m²): a number, or a table of (crack speed m/s,
        /// Γ J/m²) rows, ascending in speed from 0, linear between rows, constant past the
        /// last.
        toughness: Toughness,
        /// Growth direction.
        #[serde(default)]
        direction: GrowthDirection,
        /// Growth speed law.
        #[serde(default)]
        speed: GrowthSpeed,
        /// Time constant (s) of the filter on J that the equation of motion decides on, and
        /// of the speed's relaxation towards the balance (`equation_of_motion` only).
        /// Default: the time a shear wave takes to cross half the J ring, R/(2c_S)
        /// ([`Propagation::DEFAULT_FILTER_TRANSITS`]): the ring's own delay.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        filter_time: Option<f64>,
        /// Length (m) of the process zone behind a tip that moves by the equation of motion:
        /// the new faces are held by a traction that falls linearly to zero over an opening
        /// δ_c = 2Γ/σ_c, σ_c = sqrt(π E' Γ / (8 l)), so each unit of new area dissipates Γ.
        /// Default: a third of the J domain radius (the zone lies where the domain's weight
        /// is 1). 0 switches the zone off (the new faces are released at once and the
        /// fracture energy stays in the body, as with the seed's rule).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        process_zone: Option<f64>,
    },
}

impl Propagation {
    /// The default filter time is this many shear-wave transits of the J ring's radius R,
    /// τ = n·R/c_S: a time of the model (R is physical), never of the cell
    /// (`algorithm.md` pitfall 13). The ring's J answers a change at the tip after the
    /// waves have crossed it, so filtering over less than about R/(2c_S) removes noise the
    /// ring has not averaged, and over much more delays the tip (`docs/growth.md`).
    pub const DEFAULT_FILTER_TRANSITS: f64 = 0.5;
    /// The default process zone is this fraction of the J domain radius.
    pub const DEFAULT_ZONE_FRACTION: f64 = 1.0 / 3.0;
}

/// Toughness Γ(v) (J/m²): a constant or a table against crack speed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum Toughness {
    /// The same at every speed.
    Constant(f64),
    /// Rows (v m/s, Γ J/m²), ascending in v from 0; linear between rows, constant past the
    /// last.
    Table(Vec<Vec2>),
}

impl From<f64> for Toughness {
    fn from(g: f64) -> Self {
        Toughness::Constant(g)
    }
}

impl Toughness {
    /// Γ at crack speed v (m/s).
    pub fn at(&self, v: f64) -> f64 {
        match self {
            Toughness::Constant(g) => *g,
            Toughness::Table(rows) => {
                let Some(first) = rows.first() else {
                    return f64::NAN;
                };
                if v <= first[0] {
                    return first[1];
                }
                for w in rows.windows(2) {
                    let ([v0, g0], [v1, g1]) = (w[0], w[1]);
                    if v <= v1 {
                        let t = if v1 > v0 { (v - v0) / (v1 - v0) } else { 1.0 };
                        return g0 + t * (g1 - g0);
                    }
                }
                rows[rows.len() - 1][1]
            }
        }
    }

    /// Γ(0), the initiation toughness.
    pub fn at_rest(&self) -> f64 {
        self.at(0.0)
    }
}

/// Direction in which a tip grows (`algorithm.md` §7).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum GrowthDirection {
    /// The kink angle of largest energy release of a kinked extension, from K_I and K_II
    /// (the kinked-crack solution of Hussain, Pu & Underwood 1974: ∓75.2° for pure mode II);
    /// G is the energy release rate of that kink.
    #[default]
    MaxEnergyRelease,
    /// Erdogan–Sih: the angle of largest hoop stress, θ = 2 atan[(K_I − √(K_I² + 8K_II²))/
    /// (4K_II)] (∓70.5° for pure mode II); G is the energy release rate of that kink.
    MaxHoopStress,
    /// Growth constrained to a material line of the undeformed body (a bond, a weak plane)
    /// along this direction; G = J1 of the tip frame (the tip segment lies along it).
    Fixed(Vec2),
}

/// How fast a tip advances while it grows (`algorithm.md` §7).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum GrowthSpeed {
    /// The seed's rule: the tip moves at C_L during a time step in which G ≥ toughness
    /// (its speed is set by the J contour and the grid; kept to reproduce the seed).
    Wave,
    /// The default: the tip moves continuously at the speed v where the dynamic energy
    /// release rate g(v)·G* (Freund, g ≈ 1 − v/c_R) equals Γ(v), deciding on J filtered over
    /// `filter_time`.
    #[default]
    EquationOfMotion,
}

/// Prescribed velocity on the grid nodes inside a region.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BoundaryCondition {
    /// Nodes inside this region are constrained.
    pub region: Region,
    /// Prescribed components; a missing one is free.
    pub velocity: VelocitySpec,
    /// Velocity rises linearly from 0 over this time (s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ramp_time: Option<f64>,
    /// Condition is active from this time (s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start: Option<f64>,
    /// Condition is active until this time (s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub end: Option<f64>,
    /// The region travels with the prescribed velocity (the displacement of the prescribed
    /// components so far): a rigid impactor's face, whose nodes at each step are those it
    /// covers then. False (the default): the region is fixed in space, and material that
    /// moves out of it is no longer driven (after a travel of about a cell, so how long a
    /// fixed region drives depends on the cell size). An extension (`docs/scene-extensions.md`).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub moving: bool,
}

/// Prescribed velocity components (m/s).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct VelocitySpec {
    /// x component, if prescribed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub x: Option<f64>,
    /// y component, if prescribed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub y: Option<f64>,
}

/// A traction applied to the particles inside a region.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Load {
    /// The particles inside this region carry the traction.
    pub region: Region,
    /// Traction `[tx, ty]` (Pa), applied as traction × particle edge length × thickness.
    pub traction: Vec2,
    /// Linear rise from 0 over this time (s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ramp_time: Option<f64>,
}

/// Damping for quasi-static runs.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Damping {
    /// No damping (default).
    #[default]
    None,
    /// Local non-viscous ("kinetic") damping: each grid force component is reduced by
    /// `coefficient`·|f| against the node's velocity, coefficient in [0, 1).
    Kinetic {
        /// Fraction of the unbalanced force removed, in [0, 1).
        coefficient: f64,
    },
    /// Viscous (mass-proportional) damping: a grid force −`coefficient`·m·v.
    Viscous {
        /// Damping rate α (1/s).
        coefficient: f64,
    },
}

/// End time and time step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TimeControl {
    /// Simulated end time (s).
    pub end: f64,
    /// Courant number: Δt = cfl·cell_size/C_L, in (0, 1].
    #[serde(default = "default_cfl")]
    pub cfl: f64,
}

fn default_cfl() -> f64 {
    0.5
}

/// A field that can be recorded in snapshots.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize, JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum FieldKind {
    /// σ_xx, σ_yy, σ_xy (Pa).
    Stress,
    /// ε_xx, ε_yy, ε_xy.
    Strain,
    /// v_x, v_y and |v| (m/s).
    Velocity,
    /// u_x, u_y (m).
    Displacement,
    /// Isochromatic fringe order N = h(σ₁ − σ₂)/f_σ.
    Fringe,
    /// Material index.
    Material,
}

impl FieldKind {
    /// Every field kind.
    pub const ALL: [FieldKind; 6] = [
        FieldKind::Stress,
        FieldKind::Strain,
        FieldKind::Velocity,
        FieldKind::Displacement,
        FieldKind::Fringe,
        FieldKind::Material,
    ];
    /// The name used in scenes, URLs and files.
    pub fn name(self) -> &'static str {
        match self {
            FieldKind::Stress => "stress",
            FieldKind::Strain => "strain",
            FieldKind::Velocity => "velocity",
            FieldKind::Displacement => "displacement",
            FieldKind::Fringe => "fringe",
            FieldKind::Material => "material",
        }
    }
    /// Parse a field name.
    pub fn from_name(name: &str) -> Option<FieldKind> {
        FieldKind::ALL.into_iter().find(|k| k.name() == name)
    }
}

/// What is recorded and how often.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Output {
    /// Interval between crack-tip and energy samples (s). Absent: every step.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub history_interval: Option<f64>,
    /// Interval between field snapshots (s). 0 or absent: none.
    #[serde(default)]
    pub snapshot_interval: f64,
    /// Fields recorded in snapshots (default: stress and velocity).
    #[serde(default = "default_fields")]
    pub fields: Vec<FieldKind>,
    /// Stress-optic (fringe) constant f_σ (N/m), required for the `fringe` field.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fringe_constant: Option<f64>,
    /// Width of the moving-box average of the crack-tip speed (s).
    #[serde(default = "default_speed_window")]
    pub speed_window: f64,
    /// (extension) Also record every particle (position and the `fields`' components) in
    /// each snapshot, for the VTK export's `.vtu` particle files. Off by default: a
    /// particle snapshot is about 8 bytes per particle and component.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub particles: bool,
}

fn default_fields() -> Vec<FieldKind> {
    vec![FieldKind::Stress, FieldKind::Velocity]
}
fn default_speed_window() -> f64 {
    1.0e-6
}

impl Default for Output {
    fn default() -> Self {
        Output {
            history_interval: None,
            snapshot_interval: 0.0,
            fields: default_fields(),
            fringe_constant: None,
            speed_window: default_speed_window(),
            particles: false,
        }
    }
}

impl Scene {
    /// Parse a scene from JSON text. Errors carry serde's message with line and column.
    pub fn from_json(text: &str) -> Result<Scene, serde_json::Error> {
        serde_json::from_str(text)
    }

    /// The JSON Schema of the scene document.
    pub fn json_schema() -> serde_json::Value {
        let schema = schemars::schema_for!(Scene);
        serde_json::to_value(&schema).unwrap_or(serde_json::Value::Null)
    }

    /// The canonical JSON of the scene (all defaults filled in, keys in a fixed order).
    pub fn canonical_json(&self) -> String {
        // Struct fields serialize in declaration order and maps are BTreeMaps: stable.
        serde_json::to_string(self).unwrap_or_default()
    }

    /// SHA-256 of the canonical JSON, hex encoded (the `scene_hash` of a run summary).
    pub fn hash(&self) -> String {
        use sha2::{Digest, Sha256};
        let digest = Sha256::digest(self.canonical_json().as_bytes());
        digest.iter().map(|b| format!("{b:02x}")).collect()
    }

    /// The scene's length scale L (m): the shorter side of the bounding box of all bodies
    /// (the grid's when there are none). Physical defaults of the growth law are fractions
    /// of it ([`JIntegral::GROWTH_RADIUS_FRACTION`]), so they do not change with the cell.
    pub fn length_scale(&self) -> f64 {
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for b in &self.bodies {
            let (a, c) = b.region.bounds();
            for k in 0..2 {
                lo[k] = lo[k].min(a[k]);
                hi[k] = hi[k].max(c[k]);
            }
        }
        if !(lo[0] < hi[0] && lo[1] < hi[1]) {
            (lo, hi) = (self.grid.min, self.grid.max);
        }
        (hi[0] - lo[0]).min(hi[1] - lo[1])
    }

    /// The time step Δt = cfl·h/C_L with the largest C_L over the materials, or `None`
    /// when there are no valid materials.
    pub fn time_step(&self) -> Option<f64> {
        let c_max = self
            .materials
            .values()
            .map(|m| m.wave_speeds(self.analysis).c_l)
            .filter(|c| c.is_finite() && *c > 0.0)
            .fold(0.0_f64, f64::max);
        (c_max > 0.0).then(|| self.time.cfl * self.grid.cell_size / c_max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn homalite_wave_speeds_match_reference() {
        // reference-solutions.md: dynamic Homalite, c_S = 1256, c_L = 2551 (pe) / 2186 (ps),
        // c_R = 1172 (pe) / 1156 (ps), all to the quoted digits (±1 m/s).
        let pe = WaveSpeeds::new(5.2e9, 0.34, 1230.0, Analysis::PlaneStrain);
        let ps = WaveSpeeds::new(5.2e9, 0.34, 1230.0, Analysis::PlaneStress);
        assert!((pe.c_s - 1256.0).abs() < 1.0, "{pe:?}");
        assert!((pe.c_l - 2551.0).abs() < 1.0, "{pe:?}");
        assert!((ps.c_l - 2186.0).abs() < 1.0, "{ps:?}");
        assert!((pe.c_r - 1172.0).abs() < 1.0, "{pe:?}");
        assert!((ps.c_r - 1156.0).abs() < 1.0, "{ps:?}");
    }

    #[test]
    fn polygon_contains_even_odd() {
        let r = Region::Polygon {
            points: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
        };
        assert!(r.contains([0.5, 0.5]));
        assert!(!r.contains([1.5, 0.5]));
    }
}
