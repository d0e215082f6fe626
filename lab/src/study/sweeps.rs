//! What the study runs: the sweeps of the seed on each scene, their runs (`Variant`) and the
//! scene of one run, its parameters set by JSON path as `fracture sweep` would set them.

use std::path::{Path, PathBuf};

use anyhow::Context;
use fracture_api::Scene;
use fracture_api::sweep::set_path;
use fracture_api::validate::{scene_from_value, validate as validate_scene};
use serde_json::{Value, json};

use super::{StudyArgs, read_json};

/// Impedance-matching factor of a steel projectile on Homalite: the struck edge moves at
/// 0.93·v (`reference-solutions.md`).
const EDGE_FACTOR: f64 = 0.93;
/// JSON paths of the swept parameters in the Rosakis scenes.
pub(super) const P_VELOCITY: &str = "boundary_conditions.0.velocity.x";
pub(super) const P_TOUGHNESS: &str = "cracks.0.propagation.toughness";
pub(super) const P_CONTACT: &str = "cracks.0.contact";

/// One run of a sweep: its parameters and label.
#[derive(Debug, Clone)]
pub(super) struct Variant {
    /// Impact (projectile) speed v (m/s); the struck edge moves at 0.93·v.
    pub(super) v: f64,
    /// Toughness J_Ic (J/m²).
    pub(super) j_ic: f64,
    /// Crack-face friction coefficient μ.
    pub(super) mu: f64,
}

impl Variant {
    pub(super) fn label(&self) -> String {
        format!("v = {} m/s, J_Ic = {}, μ = {}", self.v, self.j_ic, self.mu)
    }
    pub(super) fn key(&self, scene: &str) -> String {
        format!("{scene}|{}|{}|{}", self.v, self.j_ic, self.mu)
    }
    /// The JSON-path parameters of this run (as `fracture sweep --param` takes them).
    fn params(&self) -> Vec<(&'static str, Value)> {
        let contact = if self.mu > 0.0 {
            json!({"law": "coulomb", "friction": self.mu})
        } else {
            json!({"law": "frictionless"})
        };
        vec![
            (P_VELOCITY, json!(EDGE_FACTOR * self.v)),
            (P_TOUGHNESS, json!(self.j_ic)),
            (P_CONTACT, contact),
        ]
    }
}

/// A sweep: a name, what varies, and its runs.
pub(super) struct Sweep {
    pub(super) id: &'static str,
    pub(super) title: String,
    pub(super) scene: PathBuf,
    /// Simulated time, if not the study's `--end` (the reduced scene keeps its own).
    pub(super) end: Option<f64>,
    pub(super) runs: Vec<Variant>,
    /// Legend of each run.
    pub(super) legend: fn(&Variant) -> String,
}

/// The id of a sweep's twin on the fine scene.
fn fine_id(id: &str) -> &'static str {
    match id {
        "velocity" => "velocity-fine",
        "toughness" => "toughness-fine",
        "friction" => "friction-fine",
        _ => "friction-slow-fine",
    }
}

/// Which scene a sweep runs on, as the suffix of its id: "" (base), "-fine" or "-finest".
pub(super) fn scale_suffix(id: &str) -> &'static str {
    if id.ends_with("-finest") {
        "-finest"
    } else if id.ends_with("-fine") {
        "-fine"
    } else {
        ""
    }
}

/// "1 mm cells", "0.25 mm cells": the cell size of a scene file, for titles.
pub(super) fn cells_label(scene: &Path) -> anyhow::Result<String> {
    let doc = read_json(scene)?;
    let h = doc
        .pointer("/grid/cell_size")
        .and_then(Value::as_f64)
        .with_context(|| format!("{}: no grid.cell_size", scene.display()))?;
    // Whole micrometres, so 0.25 mm prints as 0.25 and not as 0.25000000000000006.
    Ok(format!("{} mm cells", (h * 1e6).round() / 1e3))
}

/// The scene of one run: the base scene with the run's parameters, the study's end time,
/// history every 0.1 µs and fringe snapshots every 5 µs.
pub(super) fn variant_scene(base: &Value, v: &Variant, end: f64) -> anyhow::Result<Scene> {
    let mut doc = base.clone();
    for (path, value) in v.params() {
        set_path(&mut doc, path, value)?;
    }
    set_path(&mut doc, "time.end", json!(end))?;
    set_path(&mut doc, "output.history_interval", json!(1.0e-7))?;
    set_path(&mut doc, "output.snapshot_interval", json!(5.0e-6))?;
    set_path(&mut doc, "output.fields", json!(["fringe", "displacement"]))?;
    let scene = scene_from_value(doc).map_err(|e| anyhow::anyhow!("{e}"))?;
    validate_scene(&scene).map_err(|e| anyhow::anyhow!("{e}"))?;
    Ok(scene)
}

pub(super) fn sweeps(a: &StudyArgs) -> anyhow::Result<Vec<Sweep>> {
    let base = |v: f64, j_ic: f64, mu: f64| Variant { v, j_ic, mu };
    let mut out = vec![
        Sweep {
            id: "velocity",
            title: "Impact velocity (J_Ic = 25 J/m², frictionless)".into(),
            scene: a.scene.clone(),
            end: None,
            runs: [10.0, 15.0, 20.0, 25.0, 30.0]
                .iter()
                .map(|&v| base(v, 25.0, 0.0))
                .collect(),
            legend: |r| format!("v = {} m/s", r.v),
        },
        Sweep {
            id: "toughness",
            title: "Toughness (25 m/s, frictionless)".into(),
            scene: a.scene.clone(),
            end: None,
            runs: [25.0, 100.0, 250.0]
                .iter()
                .map(|&j| base(25.0, j, 0.0))
                .collect(),
            legend: |r| format!("J_Ic = {} J/m²", r.j_ic),
        },
        Sweep {
            id: "friction",
            title: "Friction (J_Ic = 250 J/m², 25 m/s)".into(),
            scene: a.scene.clone(),
            end: None,
            runs: [0.0, 0.1, 0.3]
                .iter()
                .map(|&mu| base(25.0, 250.0, mu))
                .collect(),
            legend: |r| format!("μ = {}", r.mu),
        },
        Sweep {
            id: "friction-slow",
            title: "Friction at a low impact speed (J_Ic = 250 J/m², 15 m/s)".into(),
            scene: a.scene.clone(),
            end: None,
            runs: [0.0, 0.1, 0.3]
                .iter()
                .map(|&mu| base(15.0, 250.0, mu))
                .collect(),
            legend: |r| format!("μ = {}", r.mu),
        },
    ];
    // The acceptance test's reduced scene (tests/tests/rosakis_sweep.rs), at its own 30 µs.
    out.push(Sweep {
        id: "toughness-mini",
        title:
            "Toughness on the reduced scene of the acceptance test (25 m/s, frictionless, 30 µs)"
                .into(),
        scene: a.mini.clone(),
        end: Some(3.0e-5),
        runs: [25.0, 100.0, 250.0]
            .iter()
            .map(|&j| base(25.0, j, 0.0))
            .collect(),
        legend: |r| format!("J_Ic = {} J/m²", r.j_ic),
    });
    if let Some(fine) = &a.fine {
        let cells = cells_label(fine)?;
        let fine_sweeps: Vec<Sweep> = out
            .iter()
            .filter(|sw| sw.end.is_none())
            .map(|sw| Sweep {
                id: fine_id(sw.id),
                title: format!("{}, {cells}", sw.title),
                scene: fine.clone(),
                end: None,
                runs: sw.runs.clone(),
                legend: sw.legend,
            })
            .collect();
        out.extend(fine_sweeps);
    }
    // The cell-size check: the two ends of the toughness sweep once more at finer cells.
    if let Some(finest) = &a.finest {
        out.push(Sweep {
            id: "toughness-finest",
            title: format!("Toughness (25 m/s, frictionless), {}", cells_label(finest)?),
            scene: finest.clone(),
            end: None,
            runs: [25.0, 250.0].iter().map(|&j| base(25.0, j, 0.0)).collect(),
            legend: |r| format!("J_Ic = {} J/m²", r.j_ic),
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `--finest` adds one toughness sweep on that scene, titled with its cell size, and each
    /// scene's claims see only the sweeps run on that scene.
    #[test]
    fn finest_sweep_is_its_own_scale() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
        let a = StudyArgs {
            kind: super::super::StudyKind::Rosakis,
            scene: dir.join("rosakis-shear-coarse.json"),
            fine: Some(dir.join("rosakis-shear.json")),
            finest: Some(dir.join("rosakis-shear-finest.json")),
            mini: dir.join("rosakis-shear-mini.json"),
            out: "docs".into(),
            end: 8.0e-5,
            window: 4.0e-6,
            threads: fracture_solver::Parallelism::AllCores,
        };
        let all = sweeps(&a).expect("the scenes are readable");
        let finest: Vec<&Sweep> = all
            .iter()
            .filter(|s| scale_suffix(s.id) == "-finest")
            .collect();
        assert_eq!(finest.len(), 1);
        assert_eq!(
            finest[0].title,
            "Toughness (25 m/s, frictionless), 0.25 mm cells"
        );
        let j: Vec<f64> = finest[0].runs.iter().map(|v| v.j_ic).collect();
        assert_eq!(j, [25.0, 250.0]);
        for s in all.iter().filter(|s| s.end.is_none()) {
            let want = match scale_suffix(s.id) {
                "" => &a.scene,
                "-fine" => a.fine.as_ref().expect("fine"),
                _ => a.finest.as_ref().expect("finest"),
            };
            assert_eq!(&s.scene, want, "sweep {}", s.id);
        }
        assert_eq!(
            all.iter()
                .filter(|s| s.title.ends_with(", 0.5 mm cells"))
                .count(),
            4
        );
    }
}
