//! Parameter sweeps: one base scene, a grid of values for fields named by JSON path, one
//! job per combination (the cartesian product).
//!
//! This module is the pure part (request type, paths, combinations, labels); the routes
//! (`POST /api/v1/sweeps`, …) validate every combination with the scene validator before
//! any job is stored.

use std::collections::BTreeMap;
use std::fmt;

use crate::jobs::JobStatus;
use crate::results::{Progress, Summary};
use serde::de::{MapAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize};

/// One swept parameter: a JSON path into the scene and the values it takes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct SweepParameter {
    /// Dot-separated path into the scene; numeric segments index arrays,
    /// e.g. `cracks.0.propagation.toughness`.
    pub path: String,
    /// Values in the order given.
    #[schema(value_type = Vec<Object>)]
    pub values: Vec<serde_json::Value>,
}

/// The parameters of a request, in the order the client wrote them (a JSON object
/// `{"path": [values…]}`; a repeated path is an error).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct OrderedParameters(pub Vec<SweepParameter>);

impl<'de> Deserialize<'de> for OrderedParameters {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = OrderedParameters;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("an object {\"json.path\": [value, …], …}")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut m: A) -> Result<Self::Value, A::Error> {
                let mut out: Vec<SweepParameter> = Vec::new();
                while let Some((path, values)) = m.next_entry::<String, Vec<serde_json::Value>>()? {
                    if out.iter().any(|p| p.path == path) {
                        return Err(serde::de::Error::custom(format!(
                            "parameter `{path}` is given twice"
                        )));
                    }
                    out.push(SweepParameter { path, values });
                }
                Ok(OrderedParameters(out))
            }
        }
        d.deserialize_map(V)
    }
}

/// Body of `POST /api/v1/sweeps`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepRequest {
    /// The base scene (each job is a copy with the parameters set).
    pub scene: serde_json::Value,
    /// `{"json.path": [values…]}`, in order.
    pub parameters: OrderedParameters,
    /// Name of the sweep (default: the scene's name).
    #[serde(default)]
    pub name: Option<String>,
    /// Priority of every job.
    #[serde(default)]
    pub priority: i64,
    /// Labels added to every job (besides `sweep` and the parameter values).
    #[serde(default)]
    pub labels: BTreeMap<String, String>,
    /// Whether combinations with a completed run of the same scene reuse it (as in
    /// `POST /api/v1/jobs`).
    #[serde(default)]
    pub cache: crate::jobs::CacheMode,
    /// Most of the sweep's jobs running at once (≥ 1; absent: no limit).
    #[serde(default)]
    pub max_concurrent: Option<u32>,
    /// Every job's retry budget (as in `POST /api/v1/jobs`).
    #[serde(default)]
    pub max_attempts: Option<u32>,
}

/// One job of a sweep, as `GET /api/v1/sweeps/{id}` shows it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct SweepJob {
    /// Job id.
    pub id: String,
    /// Place in the sweep (order of the combinations).
    pub index: u32,
    /// Label of the combination, e.g. `toughness=100, velocity.x=25`.
    pub label: String,
    /// The parameter values, `{"path": value}`.
    #[schema(value_type = Object)]
    pub values: serde_json::Map<String, serde_json::Value>,
    /// Job name (the scene's name and the label).
    pub name: String,
    /// Current state.
    pub status: JobStatus,
    /// Progress of the run.
    pub progress: Option<Progress>,
    /// RFC 3339 UTC.
    pub started_at: Option<String>,
    /// RFC 3339 UTC.
    pub finished_at: Option<String>,
    /// Why the job failed or was cancelled.
    pub message: Option<String>,
    /// The run summary once finished.
    pub summary: Option<Summary>,
    /// The completed job whose results this combination serves (a cache hit; absent for
    /// jobs that ran).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cached_from: Option<String>,
}

/// A sweep (`GET /api/v1/sweeps/{id}`; lists leave out `scene` and `jobs`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct SweepInfo {
    /// Sweep id.
    pub id: String,
    /// Name.
    pub name: String,
    /// RFC 3339 UTC.
    pub created_at: String,
    /// Priority of its jobs.
    pub priority: i64,
    /// Labels given with the request (each job also has `sweep` and one label per
    /// parameter).
    pub labels: BTreeMap<String, String>,
    /// The swept parameters, in order.
    pub parameters: Vec<SweepParameter>,
    /// Overall state: `queued` (no job started), `running` (some job queued or running),
    /// then `completed` (all completed), `failed` (some failed) or `cancelled`.
    pub status: String,
    /// Number of jobs.
    pub total: u64,
    /// Jobs per state (every state named, zeros included).
    pub counts: BTreeMap<String, u64>,
    /// Mean progress of the jobs, 0–1 (a finished job counts 1).
    pub progress: f64,
    /// The base scene (omitted in lists).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<Object>)]
    pub scene: Option<serde_json::Value>,
    /// The jobs, in the order of the combinations (omitted in lists).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub jobs: Option<Vec<SweepJob>>,
    /// Most of its jobs running at once (absent: no limit).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_concurrent: Option<u32>,
}

/// Overall state of a sweep from its jobs' states (see [`SweepInfo::status`]).
pub fn overall_status(statuses: &[JobStatus]) -> &'static str {
    let has = |s: JobStatus| statuses.contains(&s);
    if statuses.iter().any(|s| !s.is_terminal()) {
        if statuses.iter().all(|s| *s == JobStatus::Queued) {
            "queued"
        } else {
            "running"
        }
    } else if has(JobStatus::Failed) {
        "failed"
    } else if has(JobStatus::Cancelled) {
        "cancelled"
    } else {
        "completed"
    }
}

/// A path that does not lead into the scene.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("parameter `{path}`: {reason}")]
pub struct PathError {
    /// The parameter path.
    pub path: String,
    /// What is wrong.
    pub reason: String,
}

/// Set `value` at the dot-separated `path` of `doc`. Every segment but the last must exist;
/// the last may name a new key of an object (the scene validator then judges it).
pub fn set_path(
    doc: &mut serde_json::Value,
    path: &str,
    value: serde_json::Value,
) -> Result<(), PathError> {
    let err = |reason: String| PathError {
        path: path.to_string(),
        reason,
    };
    if path.is_empty() {
        return Err(err("the path is empty".into()));
    }
    let segs: Vec<&str> = path.split('.').collect();
    if let Some(i) = segs.iter().position(|s| s.is_empty()) {
        return Err(err(format!("segment {} is empty", i + 1)));
    }
    let mut cur = doc;
    for (i, seg) in segs.iter().enumerate() {
        let last = i + 1 == segs.len();
        let here = if i == 0 {
            "the scene".to_string()
        } else {
            format!("`{}`", segs[..i].join("."))
        };
        cur = match cur {
            serde_json::Value::Object(o) => {
                if last {
                    o.insert((*seg).to_string(), value);
                    return Ok(());
                }
                match o.get_mut(*seg) {
                    Some(v) => v,
                    None => return Err(err(format!("{here} has no field `{seg}`"))),
                }
            }
            serde_json::Value::Array(a) => {
                let len = a.len();
                let idx: usize = seg.parse().map_err(|_| {
                    err(format!(
                        "{here} is an array: segment `{seg}` must be an index"
                    ))
                })?;
                match a.get_mut(idx) {
                    Some(slot) if last => {
                        *slot = value;
                        return Ok(());
                    }
                    Some(v) => v,
                    None => {
                        return Err(err(format!(
                            "index {idx} is past the end of {here} ({len} entr{})",
                            if len == 1 { "y" } else { "ies" }
                        )));
                    }
                }
            }
            other => {
                let kind = match other {
                    serde_json::Value::Null => "null",
                    serde_json::Value::Bool(_) => "a boolean",
                    serde_json::Value::Number(_) => "a number",
                    serde_json::Value::String(_) => "a string",
                    _ => "a value",
                };
                return Err(err(format!("{here} is {kind}, not an object or array")));
            }
        };
    }
    Ok(())
}

/// Number of combinations (saturating).
pub fn combination_count(params: &[SweepParameter]) -> u64 {
    params
        .iter()
        .fold(1u64, |n, p| n.saturating_mul(p.values.len() as u64))
}

/// Every combination as one value index per parameter, the last parameter varying
/// fastest (so the jobs of the first parameter's first value come first).
pub fn combinations(params: &[SweepParameter]) -> Vec<Vec<usize>> {
    let mut out: Vec<Vec<usize>> = vec![Vec::new()];
    for p in params {
        let mut next = Vec::with_capacity(out.len() * p.values.len());
        for prefix in &out {
            for i in 0..p.values.len() {
                let mut c = prefix.clone();
                c.push(i);
                next.push(c);
            }
        }
        out = next;
    }
    if params.is_empty() { Vec::new() } else { out }
}

/// Short names of the parameters for labels: the last path segment, extended to the left
/// while it is an index or a single character, or while two parameters would share it
/// (`cracks.0.propagation.toughness` → `toughness`, `boundary_conditions.0.velocity.x` →
/// `velocity.x`).
pub fn short_names(params: &[SweepParameter]) -> Vec<String> {
    let segs: Vec<Vec<&str>> = params.iter().map(|p| p.path.split('.').collect()).collect();
    let mut take: Vec<usize> = segs
        .iter()
        .map(|s| {
            let mut n = 1;
            while n < s.len() {
                let first = s[s.len() - n];
                if first.chars().count() <= 1 || first.bytes().all(|b| b.is_ascii_digit()) {
                    n += 1;
                } else {
                    break;
                }
            }
            n
        })
        .collect();
    let name = |s: &Vec<&str>, n: usize| s[s.len() - n.min(s.len())..].join(".");
    // Lengthen names that collide until they differ (or are whole paths).
    loop {
        let names: Vec<String> = segs.iter().zip(&take).map(|(s, &n)| name(s, n)).collect();
        let mut changed = false;
        for i in 0..names.len() {
            let clash = names
                .iter()
                .enumerate()
                .any(|(j, o)| j != i && *o == names[i]);
            if clash && take[i] < segs[i].len() {
                take[i] += 1;
                changed = true;
            }
        }
        if !changed {
            return names;
        }
    }
}

/// A value as a label shows it: strings bare, everything else as JSON.
pub fn value_text(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// The label of one combination, e.g. `toughness=100, velocity.x=25`.
pub fn label(names: &[String], params: &[SweepParameter], combo: &[usize]) -> String {
    names
        .iter()
        .zip(params)
        .zip(combo)
        .map(|((n, p), &i)| {
            let v = p.values.get(i).map(value_text).unwrap_or_default();
            format!("{n}={v}")
        })
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// Parsed from text: `json!` would sort the keys.
    fn params(text: &str) -> Vec<SweepParameter> {
        serde_json::from_str::<OrderedParameters>(text)
            .map(|p| p.0)
            .unwrap_or_default()
    }

    #[test]
    fn parameters_keep_their_order_and_refuse_repeats() {
        let p: OrderedParameters =
            serde_json::from_str(r#"{"b.x": [1], "a.y": [2, 3]}"#).unwrap_or_default();
        let paths: Vec<&str> = p.0.iter().map(|p| p.path.as_str()).collect();
        assert_eq!(paths, ["b.x", "a.y"]);
        let e = serde_json::from_str::<OrderedParameters>(r#"{"a": [1], "a": [2]}"#);
        assert!(e.is_err_and(|e| e.to_string().contains("`a` is given twice")));
    }

    #[test]
    fn set_path_walks_objects_and_arrays() {
        let mut d = json!({"cracks": [{"propagation": {"toughness": 25.0}}], "time": {}});
        assert!(set_path(&mut d, "cracks.0.propagation.toughness", json!(100)).is_ok());
        assert_eq!(d["cracks"][0]["propagation"]["toughness"], json!(100));
        // A new key at the end is allowed (the validator judges it).
        assert!(set_path(&mut d, "time.cfl", json!(0.4)).is_ok());
        assert_eq!(d["time"]["cfl"], json!(0.4));
        let e = set_path(&mut d, "cracks.1.propagation.toughness", json!(1));
        assert!(e.is_err_and(|e| e.reason.contains("index 1 is past the end of `cracks`")));
        let e = set_path(&mut d, "cracks.x.toughness", json!(1));
        assert!(e.is_err_and(|e| e.reason.contains("must be an index")));
        let e = set_path(&mut d, "grid.cell_size", json!(1));
        assert!(e.is_err_and(|e| e.reason.contains("the scene has no field `grid`")));
        let e = set_path(&mut d, "time.cfl.x", json!(1));
        assert!(e.is_err_and(|e| e.reason.contains("`time.cfl` is a number")));
        assert!(set_path(&mut d, "a..b", json!(1)).is_err());
        assert!(set_path(&mut d, "", json!(1)).is_err());
    }

    #[test]
    fn combinations_are_the_cartesian_product_last_fastest() {
        let p = params(r#"{"a": [1, 2], "b": [10, 20, 30]}"#);
        assert_eq!(combination_count(&p), 6);
        let c = combinations(&p);
        assert_eq!(c.len(), 6);
        assert_eq!(c[0], [0, 0]);
        assert_eq!(c[1], [0, 1]);
        assert_eq!(c[5], [1, 2]);
        assert!(combinations(&[]).is_empty());
        let empty = params(r#"{"a": [1, 2], "b": []}"#);
        assert_eq!(combination_count(&empty), 0);
        assert!(combinations(&empty).is_empty());
    }

    #[test]
    fn short_names_and_labels() {
        let p = params(
            r#"{"cracks.0.propagation.toughness": [25, 100],
                "boundary_conditions.0.velocity.x": [12.5]}"#,
        );
        let n = short_names(&p);
        assert_eq!(n, ["toughness", "velocity.x"]);
        assert_eq!(label(&n, &p, &[1, 0]), "toughness=100, velocity.x=12.5");
        // Collisions lengthen the names until they differ.
        let p = params(r#"{"materials.a.density": [1], "materials.b.density": [2]}"#);
        assert_eq!(short_names(&p), ["a.density", "b.density"]);
        let p = params(r#"{"cracks.0": ["s"]}"#);
        assert_eq!(short_names(&p), ["cracks.0"]);
        assert_eq!(value_text(&json!("plane_stress")), "plane_stress");
    }

    #[test]
    fn overall_status_of_a_sweep() {
        use JobStatus::*;
        assert_eq!(overall_status(&[Queued, Queued]), "queued");
        assert_eq!(overall_status(&[Completed, Queued]), "running");
        assert_eq!(overall_status(&[Running, Failed]), "running");
        assert_eq!(overall_status(&[Completed, Failed, Cancelled]), "failed");
        assert_eq!(overall_status(&[Completed, Cancelled]), "cancelled");
        assert_eq!(overall_status(&[Completed, Completed]), "completed");
    }
}
