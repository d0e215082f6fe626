//! Scene documents of either dimension as the service receives, stores and serves them: JSON
//! values routed by their `analysis` (`"3d"`: a [`Scene3`], anything else: a 2D [`Scene`]),
//! as [`crate::validate3::parse_any_scene`] routes JSON text.
//!
//! * [`any_scene_from_value`]: a parsed JSON document to an [`AnyScene`], errors naming their
//!   JSON path. A 2D document is read exactly as [`scene_from_value`] reads it (the same
//!   scene, the same errors).
//! * [`AnyScene`] serializes as the scene it holds and deserializes by the same routing, so
//!   a job's `scene` ([`crate::jobs::JobInfo`]) may be of either dimension.

use std::borrow::Cow;

use schemars::JsonSchema;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::scene::Scene;
use crate::scene3::{AnyScene, Scene3};
use crate::validate::{ValidationError, ValidationErrors, scene_from_value};

/// Whether a JSON document is a 3D scene: an object whose `analysis` is `"3d"`.
pub fn is_3d(value: &serde_json::Value) -> bool {
    value.get("analysis").and_then(serde_json::Value::as_str) == Some("3d")
}

/// Read a scene of either dimension from a parsed JSON document; errors name their JSON path
/// (`(document)` for the whole document). A 3D document with a `thickness` gets the message
/// of [`crate::validate3::parse_scene3`].
pub fn any_scene_from_value(value: serde_json::Value) -> Result<AnyScene, ValidationErrors> {
    if !is_3d(&value) {
        return scene_from_value(value).map(AnyScene::Two);
    }
    if value.get("thickness").is_some() {
        // The text parser's probe owns the message; a document this small re-serializes
        // cheaply, and only on this error path.
        return crate::validate3::parse_scene3(&value.to_string()).map(AnyScene::Three);
    }
    serde_path_to_error::deserialize::<_, Scene3>(value)
        .map(AnyScene::Three)
        .map_err(|e| {
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

impl AnyScene {
    /// The scene's end time `time.end` (s).
    pub fn end_time(&self) -> f64 {
        match self {
            AnyScene::Two(s) => s.time.end,
            AnyScene::Three(s) => s.time.end,
        }
    }

    /// The 2D scene, if this is one.
    pub fn as_2d(&self) -> Option<&Scene> {
        match self {
            AnyScene::Two(s) => Some(s),
            AnyScene::Three(_) => None,
        }
    }

    /// The 3D scene, if this is one.
    pub fn as_3d(&self) -> Option<&Scene3> {
        match self {
            AnyScene::Two(_) => None,
            AnyScene::Three(s) => Some(s),
        }
    }

    /// Number of entries in the scene's `cracks`.
    pub fn crack_count(&self) -> usize {
        match self {
            AnyScene::Two(s) => s.cracks.len(),
            AnyScene::Three(s) => s.cracks.len(),
        }
    }
}

impl Serialize for AnyScene {
    fn serialize<S: Serializer>(&self, ser: S) -> Result<S::Ok, S::Error> {
        match self {
            AnyScene::Two(s) => s.serialize(ser),
            AnyScene::Three(s) => s.serialize(ser),
        }
    }
}

impl<'de> Deserialize<'de> for AnyScene {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<AnyScene, D::Error> {
        let value = serde_json::Value::deserialize(d)?;
        let scene = if is_3d(&value) {
            Scene3::deserialize(value).map(AnyScene::Three)
        } else {
            Scene::deserialize(value).map(AnyScene::Two)
        };
        scene.map_err(serde::de::Error::custom)
    }
}

impl JsonSchema for AnyScene {
    fn schema_name() -> Cow<'static, str> {
        "AnyScene".into()
    }

    fn json_schema(generator: &mut schemars::SchemaGenerator) -> schemars::Schema {
        let two = generator.subschema_for::<Scene>();
        let three = generator.subschema_for::<Scene3>();
        schemars::json_schema!({
            "description": "A scene of either dimension: a 3D scene when `analysis` is \"3d\", \
                            else a 2D scene.",
            "anyOf": [two, three]
        })
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use serde_json::json;

    fn cube() -> serde_json::Value {
        json!({
            "name": "cube",
            "analysis": "3d",
            "grid": {"cell_size": 0.001, "min": [0.0, 0.0, 0.0], "max": [0.006, 0.006, 0.006]},
            "materials": {"m": {"model": "linear_elastic", "density": 1000.0,
                                 "youngs_modulus": 1e9, "poissons_ratio": 0.3}},
            "bodies": [{"material": "m",
                        "region": {"box": {"min": [0.001, 0.001, 0.001], "max": [0.005, 0.005, 0.005]}}}],
            "time": {"end": 1e-6}
        })
    }

    #[test]
    fn documents_route_by_analysis_and_round_trip() {
        let three = any_scene_from_value(cube()).unwrap();
        assert_eq!(three.dimension(), 3);
        let text = serde_json::to_string(&three).unwrap();
        let back: AnyScene = serde_json::from_str(&text).unwrap();
        assert_eq!(back, three);
        assert_eq!(back.end_time(), 1e-6);
        assert_eq!(back.crack_count(), 0);
        assert!(back.as_3d().is_some() && back.as_2d().is_none());

        let mut two = cube();
        two["analysis"] = json!("plane_strain");
        // A 2D document gets the 2D parser's error, path and all.
        let e = any_scene_from_value(two.clone()).unwrap_err();
        assert_eq!(e, scene_from_value(two).unwrap_err());
    }

    #[test]
    fn errors_name_their_path() {
        let mut v = cube();
        v["grid"]["min"] = json!([0.0, 0.0]);
        let e = any_scene_from_value(v).unwrap_err();
        assert_eq!(e.0[0].path, "grid.min", "{e}");
        let mut v = cube();
        v["thickness"] = json!(0.01);
        let e = any_scene_from_value(v).unwrap_err();
        assert_eq!(e.0[0].path, "thickness", "{e}");
        assert!(e.0[0].reason.contains("does not exist in 3D"), "{e}");
        let mut v = cube();
        v["bodies"][0]["color"] = json!("red");
        let e = any_scene_from_value(v).unwrap_err();
        assert_eq!(e.0[0].path, "bodies[0].color", "{e}");
    }
}
