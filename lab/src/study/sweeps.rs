//! What the study runs: the sweeps of the seed on each scene under both growth laws, the
//! convergence sweeps of the reduced scene (cell size, J domain radius), their runs
//! (`Variant`) and the scene of one run, its parameters set by JSON path as `fracture sweep`
//! would set them.

use std::path::{Path, PathBuf};

use anyhow::Context;
use fracture_api::Scene;
use fracture_api::sweep::set_path;
use fracture_api::validate::{scene_from_value, validate as validate_scene};
use serde_json::{Value, json};

use super::{StudyArgs, read_json};

/// Impedance-matching factor of a steel projectile on Homalite: the struck edge moves at
/// 0.93·v (`reference-solutions.md`).
pub(super) const EDGE_FACTOR: f64 = 0.93;
/// JSON paths of the swept parameters in the Rosakis scenes.
pub(super) const P_VELOCITY: &str = "boundary_conditions.0.velocity.x";
pub(super) const P_TOUGHNESS: &str = "cracks.0.propagation.toughness";
pub(super) const P_CONTACT: &str = "cracks.0.contact";
pub(super) const P_SPEED: &str = "cracks.0.propagation.speed";
pub(super) const P_J_INTEGRAL: &str = "cracks.0.j_integral";
pub(super) const P_CELL: &str = "grid.cell_size";

/// The cell sizes (m) of the convergence table on the reduced scene.
pub(super) const CELLS: [f64; 4] = [1.0e-3, 0.5e-3, 0.25e-3, 0.125e-3];
/// The J domain radii (m) of the radius tables, held fixed in metres at every cell size (the
/// reduced scene names 6 mm; the process zone is a third of the radius and the equation of
/// motion's filter time R/(2 c_S), so each radius is a different regularisation and each
/// column of the table is one regularisation at two cell sizes). 3 mm spans the 3 cells a
/// growing ring needs at 1 mm cells.
pub(super) const RADII: [f64; 4] = [3.0e-3, 4.5e-3, 6.0e-3, 9.0e-3];
/// The cell sizes (m) of the radius table.
pub(super) const RADIUS_CELLS: [f64; 2] = [1.0e-3, 0.5e-3];
/// The toughnesses (J/m²) of both convergence tables: the two ends of the seed's sweep.
pub(super) const CONV_J: [f64; 2] = [25.0, 250.0];
/// Γ(0) (J/m²) of the free-tip tables, whose toughness rises with speed ([`rising_table`]).
pub(super) const FREE_J: f64 = 250.0;
/// The cell sizes (m) of the free-tip table.
pub(super) const FREE_CELLS: [f64; 3] = [1.0e-3, 0.5e-3, 0.25e-3];
/// The cell size (m) of the free-tip radius table.
pub(super) const FREE_RADIUS_CELL: f64 = 0.5e-3;

/// The free tip's toughness table for Γ(0) = `j` (J/m²): constant to 500 m/s, then rising
/// linearly to 16·Γ(0) at 1100 m/s (0.94 c_R in Homalite) and constant beyond. On the
/// reduced Rosakis scene G* reaches several thousand J/m², so a constant J_Ic of 25 or 250
/// sends the tip to the law's speed limit at 0.999 c_R, where Freund's g(v) → 0 and the tip
/// takes what the grid delivers (the wall that closes Γ(v), `docs/scene-extensions.md`);
/// with this table the tip runs where G_dyn = Γ(v), below the limit.
pub(super) fn rising_table(j: f64) -> [[f64; 2]; 3] {
    [[0.0, j], [500.0, j], [1100.0, 16.0 * j]]
}

/// The crack-growth law of a run (`cracks[].propagation.speed`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(super) enum Law {
    /// The crack-tip equation of motion with a process zone (the product's default).
    Motion,
    /// The seed's rule: a tip jumps c_L·Δt per step while J ≥ J_Ic.
    Wave,
}

impl Law {
    /// The scene's spelling.
    pub(super) fn json(self) -> &'static str {
        match self {
            Law::Motion => "equation_of_motion",
            Law::Wave => "wave",
        }
    }
    /// For tables and titles.
    pub(super) fn label(self) -> &'static str {
        match self {
            Law::Motion => "equation of motion",
            Law::Wave => "seed's wave rule",
        }
    }
}

/// One run of a sweep: its parameters and label.
#[derive(Debug, Clone)]
pub(super) struct Variant {
    /// Impact (projectile) speed v (m/s); the struck edge moves at 0.93·v.
    pub(super) v: f64,
    /// Toughness J_Ic (J/m²).
    pub(super) j_ic: f64,
    /// Crack-face friction coefficient μ.
    pub(super) mu: f64,
    /// The growth law.
    pub(super) law: Law,
    /// Cell size (m), if not the scene's: the bond then moves to mid-cell ([`mid_cell_y`]).
    pub(super) h: Option<f64>,
    /// J domain radius (m), if not the scene's (the reduced scene names 6 mm; the others take
    /// the default, 1/16 of the block's shorter side).
    pub(super) radius: Option<f64>,
    /// Fringe snapshots every 5 µs (off for the convergence runs).
    pub(super) snapshots: bool,
    /// The toughness rises with speed from Γ(0) = `j_ic` ([`rising_table`]), instead of the
    /// constant `j_ic`.
    pub(super) rising: bool,
}

impl Variant {
    pub(super) fn label(&self) -> String {
        let mut s = format!(
            "v = {} m/s, J_Ic = {}, μ = {}, {}",
            self.v,
            self.j_ic,
            self.mu,
            self.law.label()
        );
        if let Some(h) = self.h {
            s.push_str(&format!(", h = {}", mm(h)));
        }
        if let Some(r) = self.radius {
            s.push_str(&format!(", J radius {}", mm(r)));
        }
        if self.rising {
            s.push_str(", Γ(v) rising");
        }
        s
    }
    pub(super) fn key(&self, scene: &str) -> String {
        format!(
            "{scene}|{}|{}|{}|{}|{:?}|{:?}|{}{}",
            self.v,
            self.j_ic,
            self.mu,
            self.law.json(),
            self.h,
            self.radius,
            self.snapshots,
            if self.rising { "|rising" } else { "" }
        )
    }
    /// The scene's `toughness`: J_Ic, or the free tip's table from it.
    pub(super) fn toughness(&self) -> Value {
        if self.rising {
            json!(rising_table(self.j_ic))
        } else {
            json!(self.j_ic)
        }
    }
    /// The JSON-path parameters of this run (as `fracture sweep --param` takes them), but for
    /// the crack points that a cell size moves (see [`variant_scene`]).
    fn params(&self) -> Vec<(&'static str, Value)> {
        let contact = if self.mu > 0.0 {
            json!({"law": "coulomb", "friction": self.mu})
        } else {
            json!({"law": "frictionless"})
        };
        let mut p = vec![
            (P_VELOCITY, json!(EDGE_FACTOR * self.v)),
            (P_TOUGHNESS, self.toughness()),
            (P_CONTACT, contact),
            (P_SPEED, json!(self.law.json())),
        ];
        if let Some(h) = self.h {
            p.push((P_CELL, json!(h)));
        }
        if let Some(r) = self.radius {
            p.push((P_J_INTEGRAL, json!({"method": "domain", "radius": r})));
        }
        p
    }
}

/// "0.25 mm": a length in whole micrometres (so 0.25 mm is not 0.25000000000000006).
pub(super) fn mm(x: f64) -> String {
    format!("{} mm", (x * 1e6).round() / 1e3)
}

/// What a sweep varies, for finding it again in the claims and tables.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Kind {
    Velocity,
    Toughness,
    Friction,
    FrictionSlow,
    /// The toughness sweep on the reduced scene.
    ToughnessMini,
    /// Cell size on the reduced scene at one J_Ic.
    Cells,
    /// J radius on the reduced scene at one J_Ic and cell size.
    Radius,
    /// A free tip on the reduced scene (toughness rising with speed): cell size (default
    /// ring) and J radius runs.
    Free,
}

/// Which scene a sweep of the seed runs on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Scale {
    /// `--scene` (1 mm cells).
    Base,
    /// `--fine`.
    Fine,
    /// `--finest` (J_Ic = 25 and 250 only).
    Finest,
    /// `--mini`, the reduced scene.
    Mini,
}

/// A sweep: a name, what varies, and its runs.
pub(super) struct Sweep {
    pub(super) id: String,
    pub(super) kind: Kind,
    pub(super) scale: Scale,
    pub(super) law: Law,
    pub(super) title: String,
    pub(super) scene: PathBuf,
    /// Simulated time, if not the study's `--end` (the reduced scene keeps its own).
    pub(super) end: Option<f64>,
    pub(super) runs: Vec<Variant>,
    /// Legend of each run.
    pub(super) legend: fn(&Variant) -> String,
}

/// "1 mm cells", "0.25 mm cells": the cell size of a scene file, for titles.
pub(super) fn cells_label(scene: &Path) -> anyhow::Result<String> {
    let doc = read_json(scene)?;
    let h = doc
        .pointer("/grid/cell_size")
        .and_then(Value::as_f64)
        .with_context(|| format!("{}: no grid.cell_size", scene.display()))?;
    Ok(format!("{} cells", mm(h)))
}

/// The y (m) of the middle of the grid row of cell size `h` that holds `y` (a grid starting
/// at `y_min`): the bond at mid-cell, between node rows and between particle rows, for every
/// cell size of the table (27.5 mm at 1 mm cells gives 27.75, 27.625, 27.5625 mm at 0.5,
/// 0.25, 0.125 mm).
pub(super) fn mid_cell_y(y: f64, y_min: f64, h: f64) -> f64 {
    // A hair of slack so that a y on a node row (in decimal) counts as that row's cell.
    let row = ((y - y_min) / h + 1e-9).floor();
    y_min + (row + 0.5) * h
}

/// The scene document of one run: the base scene with the run's parameters, the end time,
/// history every 0.1 µs and, with snapshots, fringe snapshots every 5 µs. A cell size moves
/// both points of the first crack to mid-cell of the new grid.
pub(super) fn variant_doc(base: &Value, v: &Variant, end: f64) -> anyhow::Result<Value> {
    let mut doc = base.clone();
    for (path, value) in v.params() {
        set_path(&mut doc, path, value)?;
    }
    if let Some(h) = v.h {
        let y_min = doc
            .pointer("/grid/min/1")
            .and_then(Value::as_f64)
            .context("the scene has no grid.min")?;
        let n = doc
            .pointer("/cracks/0/points")
            .and_then(Value::as_array)
            .map(Vec::len)
            .context("the scene has no cracks.0.points")?;
        for i in 0..n {
            let y = doc
                .pointer(&format!("/cracks/0/points/{i}/1"))
                .and_then(Value::as_f64)
                .with_context(|| format!("cracks.0.points.{i} has no y"))?;
            set_path(
                &mut doc,
                &format!("cracks.0.points.{i}.1"),
                json!(mid_cell_y(y, y_min, h)),
            )?;
        }
    }
    set_path(&mut doc, "time.end", json!(end))?;
    set_path(&mut doc, "output.history_interval", json!(1.0e-7))?;
    if v.snapshots {
        set_path(&mut doc, "output.snapshot_interval", json!(5.0e-6))?;
        set_path(&mut doc, "output.fields", json!(["fringe", "displacement"]))?;
    } else {
        set_path(&mut doc, "output.snapshot_interval", json!(0.0))?;
    }
    Ok(doc)
}

/// The validated scene of one run (see [`variant_doc`]).
pub(super) fn variant_scene(base: &Value, v: &Variant, end: f64) -> anyhow::Result<Scene> {
    let doc = variant_doc(base, v, end)?;
    let scene = scene_from_value(doc).map_err(|e| anyhow::anyhow!("{e}"))?;
    validate_scene(&scene).map_err(|e| anyhow::anyhow!("{e}"))?;
    Ok(scene)
}

/// A run of the seed's sweeps: impact speed, toughness, friction, under `law`.
fn seed_run(v: f64, j_ic: f64, mu: f64, law: Law) -> Variant {
    Variant {
        v,
        j_ic,
        mu,
        law,
        h: None,
        radius: None,
        snapshots: true,
        rising: false,
    }
}

/// The four sweeps of the seed on one scene under one law.
fn seed_sweeps(scene: &Path, scale: Scale, law: Law, cells: &str) -> Vec<Sweep> {
    let tag = match scale {
        Scale::Fine => "-fine",
        _ => "",
    };
    let wave = if law == Law::Wave { "-wave" } else { "" };
    let r = |v, j, mu| seed_run(v, j, mu, law);
    let at = |t: &str| format!("{t}, {cells}, {}", law.label());
    vec![
        Sweep {
            id: format!("velocity{tag}{wave}"),
            kind: Kind::Velocity,
            scale,
            law,
            title: at("Impact velocity (J_Ic = 25 J/m², frictionless)"),
            scene: scene.to_path_buf(),
            end: None,
            runs: [10.0, 15.0, 20.0, 25.0, 30.0]
                .iter()
                .map(|&v| r(v, 25.0, 0.0))
                .collect(),
            legend: |r| format!("v = {} m/s", r.v),
        },
        Sweep {
            id: format!("toughness{tag}{wave}"),
            kind: Kind::Toughness,
            scale,
            law,
            title: at("Toughness (25 m/s, frictionless)"),
            scene: scene.to_path_buf(),
            end: None,
            runs: [25.0, 100.0, 250.0]
                .iter()
                .map(|&j| r(25.0, j, 0.0))
                .collect(),
            legend: |r| format!("J_Ic = {} J/m²", r.j_ic),
        },
        Sweep {
            id: format!("friction{tag}{wave}"),
            kind: Kind::Friction,
            scale,
            law,
            title: at("Friction (J_Ic = 250 J/m², 25 m/s)"),
            scene: scene.to_path_buf(),
            end: None,
            runs: [0.0, 0.1, 0.3]
                .iter()
                .map(|&mu| r(25.0, 250.0, mu))
                .collect(),
            legend: |r| format!("μ = {}", r.mu),
        },
        Sweep {
            id: format!("friction-slow{tag}{wave}"),
            kind: Kind::FrictionSlow,
            scale,
            law,
            title: at("Friction at a low impact speed (J_Ic = 250 J/m², 15 m/s)"),
            scene: scene.to_path_buf(),
            end: None,
            runs: [0.0, 0.1, 0.3]
                .iter()
                .map(|&mu| r(15.0, 250.0, mu))
                .collect(),
            legend: |r| format!("μ = {}", r.mu),
        },
    ]
}

/// The convergence sweeps on the reduced scene at its own end time: for each law and
/// J_Ic the cell sizes of [`CELLS`] down to `min_cell` (0.125 mm under the equation of motion
/// only: the decisive cases), and for the equation of motion the radii of [`RADII`] at each
/// cell size of [`RADIUS_CELLS`] (the same radii in metres at each).
pub(super) fn convergence_sweeps(mini: &Path, min_cell: f64) -> Vec<Sweep> {
    let run = |j_ic, law, h, radius| Variant {
        v: 25.0,
        j_ic,
        mu: 0.0,
        law,
        h: Some(h),
        radius,
        snapshots: false,
        rising: false,
    };
    let mut out = Vec::new();
    for law in [Law::Motion, Law::Wave] {
        for j in CONV_J {
            let cells: Vec<f64> = CELLS
                .iter()
                .copied()
                .filter(|&h| h >= min_cell * (1.0 - 1e-9))
                .filter(|&h| law == Law::Motion || h > 0.2e-3)
                .collect();
            out.push(Sweep {
                id: format!("cells-{}-j{j}", law.json()),
                kind: Kind::Cells,
                scale: Scale::Mini,
                law,
                title: format!(
                    "Cell size on the reduced scene (J_Ic = {j} J/m², {}, 30 µs)",
                    law.label()
                ),
                scene: mini.to_path_buf(),
                end: Some(3.0e-5),
                runs: cells.iter().map(|&h| run(j, law, h, None)).collect(),
                legend: |r| format!("h = {}", mm(r.h.unwrap_or(0.0))),
            });
        }
    }
    for j in CONV_J {
        for h in RADIUS_CELLS.iter().copied().filter(|&h| h >= min_cell) {
            out.push(Sweep {
                id: format!("radius-j{j}-h{}um", (h * 1e6).round()),
                kind: Kind::Radius,
                scale: Scale::Mini,
                law: Law::Motion,
                title: format!(
                    "J domain radius on the reduced scene (J_Ic = {j} J/m², {} cells, equation of motion, 30 µs)",
                    mm(h)
                ),
                scene: mini.to_path_buf(),
                end: Some(3.0e-5),
                runs: RADII
                    .iter()
                    .map(|&r| run(j, Law::Motion, h, Some(r)))
                    .collect(),
                legend: |r| format!("radius {}", mm(r.radius.unwrap_or(0.0))),
            });
        }
    }
    out
}

/// The free-tip sweeps on the reduced scene (equation of motion, Γ(0) = [`FREE_J`] rising
/// with speed): the cell sizes of [`FREE_CELLS`] down to `min_cell` at the default ring, and
/// the radii of [`RADII`] at [`FREE_RADIUS_CELL`].
pub(super) fn free_tip_sweeps(mini: &Path, min_cell: f64) -> Vec<Sweep> {
    let run = |h, radius| Variant {
        v: 25.0,
        j_ic: FREE_J,
        mu: 0.0,
        law: Law::Motion,
        h: Some(h),
        radius,
        snapshots: false,
        rising: true,
    };
    let [[_, g0], [v1, _], [v2, g2]] = rising_table(FREE_J);
    let what = format!("Γ {g0} → {g2} J/m² over {v1} → {v2} m/s");
    let mut out = vec![Sweep {
        id: "free-cells".into(),
        kind: Kind::Free,
        scale: Scale::Mini,
        law: Law::Motion,
        title: format!("Free tip on the reduced scene: cell size ({what}, equation of motion)"),
        scene: mini.to_path_buf(),
        end: Some(3.0e-5),
        runs: FREE_CELLS
            .iter()
            .copied()
            .filter(|&h| h >= min_cell * (1.0 - 1e-9))
            .map(|h| run(h, None))
            .collect(),
        legend: |r| format!("h = {}", mm(r.h.unwrap_or(0.0))),
    }];
    if FREE_RADIUS_CELL >= min_cell * (1.0 - 1e-9) {
        let h = FREE_RADIUS_CELL;
        out.push(Sweep {
            id: format!("free-radius-h{}um", (h * 1e6).round()),
            kind: Kind::Free,
            scale: Scale::Mini,
            law: Law::Motion,
            title: format!(
                "Free tip on the reduced scene: J radius ({what}, {} cells, equation of motion)",
                mm(h)
            ),
            scene: mini.to_path_buf(),
            end: Some(3.0e-5),
            runs: RADII.iter().map(|&r| run(h, Some(r))).collect(),
            legend: |r| format!("radius {}", mm(r.radius.unwrap_or(0.0))),
        });
    }
    out
}

pub(super) fn sweeps(a: &StudyArgs) -> anyhow::Result<Vec<Sweep>> {
    let cells = cells_label(&a.scene)?;
    let mut out = seed_sweeps(&a.scene, Scale::Base, Law::Motion, &cells);
    if a.wave_all {
        out.extend(seed_sweeps(&a.scene, Scale::Base, Law::Wave, &cells));
    } else {
        out.extend(
            seed_sweeps(&a.scene, Scale::Base, Law::Wave, &cells)
                .into_iter()
                .filter(|s| s.kind == Kind::Toughness),
        );
    }
    // The acceptance test's reduced scene (tests/tests/rosakis_sweep.rs), at its own 30 µs.
    for law in [Law::Motion, Law::Wave] {
        out.push(Sweep {
            id: format!("toughness-mini-{}", law.json()),
            kind: Kind::ToughnessMini,
            scale: Scale::Mini,
            law,
            title: format!(
                "Toughness on the reduced scene (25 m/s, frictionless, 30 µs), {}",
                law.label()
            ),
            scene: a.mini.clone(),
            end: Some(3.0e-5),
            runs: [25.0, 100.0, 250.0]
                .iter()
                .map(|&j| seed_run(25.0, j, 0.0, law))
                .collect(),
            legend: |r| format!("J_Ic = {} J/m²", r.j_ic),
        });
    }
    if a.convergence {
        out.extend(convergence_sweeps(&a.mini, a.min_cell));
        out.extend(free_tip_sweeps(&a.mini, a.min_cell));
    }
    if let Some(fine) = &a.fine {
        let cells = cells_label(fine)?;
        out.extend(seed_sweeps(fine, Scale::Fine, Law::Motion, &cells));
    }
    // The cell-size check on the full block: the two ends of the toughness sweep once more.
    if let Some(finest) = &a.finest {
        let cells = cells_label(finest)?;
        out.push(Sweep {
            id: "toughness-finest".into(),
            kind: Kind::Toughness,
            scale: Scale::Finest,
            law: Law::Motion,
            title: format!("Toughness (25 m/s, frictionless), {cells}, equation of motion"),
            scene: finest.clone(),
            end: None,
            runs: [25.0, 250.0]
                .iter()
                .map(|&j| seed_run(25.0, j, 0.0, Law::Motion))
                .collect(),
            legend: |r| format!("J_Ic = {} J/m²", r.j_ic),
        });
    }
    // A `--min-cell` above a sweep's cell sizes leaves it without runs.
    out.retain(|s| !s.runs.is_empty());
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scenes() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes")
    }

    /// The mid-cell rule: the middle of the row that holds y, for each cell size of the table.
    #[test]
    fn mid_cell_of_each_grid() {
        let want = [27.5e-3, 27.75e-3, 27.625e-3, 27.5625e-3];
        for (h, w) in CELLS.iter().zip(want) {
            let y = mid_cell_y(27.5e-3, 0.0, *h);
            assert!((y - w).abs() < 1e-12, "h {h}: {y}");
        }
        // A grid that does not start at 0.
        assert!((mid_cell_y(0.0105, 0.0002, 0.001) - 0.0107).abs() < 1e-12);
    }

    /// Each convergence variant of the reduced scene has its cell size, both crack points on
    /// the middle of a cell row of that grid, the law and radius asked for, no snapshots, and
    /// everything else as the scene.
    #[test]
    fn variant_builder_keeps_the_bond_mid_cell() {
        let path = scenes().join("rosakis-shear-mini.json");
        let base = read_json(&path).expect("the reduced scene is readable");
        let sweeps = convergence_sweeps(&path, 0.125e-3)
            .into_iter()
            .chain(free_tip_sweeps(&path, 0.125e-3));
        for sw in sweeps {
            for v in &sw.runs {
                let doc = variant_doc(&base, v, 3.0e-5).expect("a variant");
                assert_eq!(doc["cracks"][0]["propagation"]["toughness"], v.toughness());
                assert_eq!(
                    doc["cracks"][0]["propagation"]["toughness"].is_array(),
                    v.rising
                );
                let h = doc["grid"]["cell_size"].as_f64().unwrap_or(0.0);
                assert_eq!(Some(h), v.h);
                let y_min = doc["grid"]["min"][1].as_f64().unwrap_or(f64::NAN);
                for p in doc["cracks"][0]["points"].as_array().into_iter().flatten() {
                    let cells = (p[1].as_f64().unwrap_or(f64::NAN) - y_min) / h;
                    assert!(
                        (cells - cells.floor() - 0.5).abs() < 1e-6,
                        "{}: y at {cells} cells",
                        v.label()
                    );
                }
                assert_eq!(
                    doc["cracks"][0]["propagation"]["speed"].as_str(),
                    Some(v.law.json())
                );
                // A variant without its own radius keeps the scene's (6 mm, fixed in metres).
                let scene_radius = base["cracks"][0]["j_integral"]["radius"].as_f64();
                assert_eq!(
                    doc["cracks"][0]["j_integral"]["radius"].as_f64(),
                    v.radius.or(scene_radius)
                );
                assert_eq!(doc["output"]["snapshot_interval"].as_f64(), Some(0.0));
                assert_eq!(doc["bodies"], base["bodies"]);
                assert_eq!(
                    doc["boundary_conditions"][0]["region"],
                    base["boundary_conditions"][0]["region"]
                );
                assert_eq!(
                    doc["cracks"][0]["points"][1][0],
                    base["cracks"][0]["points"][1][0]
                );
                variant_scene(&base, v, 3.0e-5).expect("the variant validates");
            }
        }
    }

    /// The cell-size sweeps reach 0.125 mm only under the equation of motion, and `min_cell`
    /// drops the finer sizes.
    #[test]
    fn convergence_scope() {
        let path = scenes().join("rosakis-shear-mini.json");
        let all = convergence_sweeps(&path, 0.125e-3);
        let finest: Vec<&Sweep> = all
            .iter()
            .filter(|s| s.runs.iter().any(|v| v.h == Some(0.125e-3)))
            .collect();
        assert_eq!(finest.len(), 2);
        assert!(
            finest
                .iter()
                .all(|s| s.law == Law::Motion && s.kind == Kind::Cells)
        );
        // The free tip: three cell sizes and the four radii at 0.5 mm, down to 0.25 mm.
        let free = free_tip_sweeps(&path, 0.125e-3);
        assert_eq!(free.iter().map(|s| s.runs.len()).sum::<usize>(), 7);
        assert!(
            free.iter()
                .flat_map(|s| &s.runs)
                .all(|v| v.rising && v.law == Law::Motion)
        );
        let quick = convergence_sweeps(&path, 0.5e-3)
            .into_iter()
            .chain(free_tip_sweeps(&path, 0.5e-3))
            .collect::<Vec<_>>();
        assert!(
            quick
                .iter()
                .flat_map(|s| &s.runs)
                .all(|v| v.h.is_some_and(|h| h >= 0.5e-3))
        );
    }
}
