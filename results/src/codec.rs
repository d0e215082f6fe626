//! Binary encoding of a [`Snapshot`]: how workers upload snapshots and how the store keeps
//! them. JSON cannot carry the NaN that marks empty nodes, so the values travel as raw
//! little-endian `f32` after a small JSON header.
//!
//! Layout: `b"FSN1"`, header length (u32 LE), header JSON, then each component's values;
//! with particles (`Snapshot::particles`, an extension), then their x, y and each particle
//! component's values (the header's `particles`: the count and the component names).

use fracture_api::results::{FieldComponent, ParticleSnapshot, Snapshot, SnapshotSlice};
use serde::{Deserialize, Serialize};

const MAGIC: &[u8; 4] = b"FSN1";

#[derive(Serialize, Deserialize)]
struct Header {
    index: u32,
    time: f64,
    nx: u32,
    ny: u32,
    origin: [f64; 2],
    cell_size: f64,
    fields: Vec<String>,
    components: Vec<(String, u32)>,
    cracks: Vec<Vec<[f64; 2]>>,
    /// Particle count and component names (absent: no particles).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    particles: Option<(u64, Vec<String>)>,
    /// The plane of a 3D run's slice (absent: a 2D snapshot).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    slice: Option<SnapshotSlice>,
}

/// A snapshot that could not be decoded.
#[derive(Debug, thiserror::Error)]
#[error("malformed snapshot: {0}")]
pub struct CodecError(pub String);

/// Encode a snapshot.
pub fn encode_snapshot(s: &Snapshot) -> Vec<u8> {
    let header = Header {
        index: s.index,
        time: s.time,
        nx: s.nx,
        ny: s.ny,
        origin: s.origin,
        cell_size: s.cell_size,
        fields: s.fields.clone(),
        components: s
            .components
            .iter()
            .map(|c| (c.name.clone(), c.values.len() as u32))
            .collect(),
        cracks: s.cracks.clone(),
        particles: s.particles.as_ref().map(|p| {
            (
                p.x.len() as u64,
                p.components.iter().map(|c| c.name.clone()).collect(),
            )
        }),
        slice: s.slice.clone(),
    };
    let h = serde_json::to_vec(&header).unwrap_or_default();
    let n: usize = s.components.iter().map(|c| c.values.len()).sum::<usize>()
        + s.particles.as_ref().map_or(0, |p| {
            p.x.len() + p.y.len() + p.components.iter().map(|c| c.values.len()).sum::<usize>()
        });
    let mut out = Vec::with_capacity(8 + h.len() + 4 * n);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&(h.len() as u32).to_le_bytes());
    out.extend_from_slice(&h);
    for c in &s.components {
        for v in &c.values {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    if let Some(p) = &s.particles {
        for vals in [&p.x, &p.y]
            .into_iter()
            .chain(p.components.iter().map(|c| &c.values))
        {
            for v in vals {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    out
}

/// Take `len` f32 values off the front of `rest`.
fn take_f32(rest: &mut &[u8], len: usize) -> Result<Vec<f32>, CodecError> {
    let bytes = len
        .checked_mul(4)
        .filter(|&b| b <= rest.len())
        .ok_or_else(|| CodecError("truncated values".into()))?;
    let (vals, tail) = rest.split_at(bytes);
    *rest = tail;
    Ok(vals
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect())
}

/// Decode a snapshot, checking every length.
pub fn decode_snapshot(b: &[u8]) -> Result<Snapshot, CodecError> {
    let bad = |m: &str| CodecError(m.to_string());
    if b.len() < 8 || &b[..4] != MAGIC {
        return Err(bad("missing FSN1 header"));
    }
    let hl = u32::from_le_bytes([b[4], b[5], b[6], b[7]]) as usize;
    let h = b.get(8..8 + hl).ok_or_else(|| bad("truncated header"))?;
    let header: Header = serde_json::from_slice(h).map_err(|e| CodecError(e.to_string()))?;
    let nodes = header.nx as usize * header.ny as usize;
    let mut rest = &b[8 + hl..];
    let mut components = Vec::with_capacity(header.components.len());
    for (name, len) in header.components {
        let len = len as usize;
        if len != nodes {
            return Err(CodecError(format!(
                "component {name} has {len} values for {nodes} nodes"
            )));
        }
        let values = take_f32(&mut rest, len)?;
        components.push(FieldComponent { name, values });
    }
    let particles = match header.particles {
        None => None,
        Some((n, names)) => {
            let n = usize::try_from(n).map_err(|_| bad("particle count"))?;
            let x = take_f32(&mut rest, n)?;
            let y = take_f32(&mut rest, n)?;
            let mut components = Vec::with_capacity(names.len());
            for name in names {
                let values = take_f32(&mut rest, n)?;
                components.push(FieldComponent { name, values });
            }
            Some(ParticleSnapshot { x, y, components })
        }
    };
    if !rest.is_empty() {
        return Err(bad("trailing bytes"));
    }
    Ok(Snapshot {
        index: header.index,
        time: header.time,
        nx: header.nx,
        ny: header.ny,
        origin: header.origin,
        cell_size: header.cell_size,
        fields: header.fields,
        components,
        cracks: header.cracks,
        particles,
        slice: header.slice,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn snapshot_round_trips_with_nan() {
        let s = Snapshot {
            index: 3,
            time: 1e-6,
            nx: 2,
            ny: 2,
            origin: [0.0, 1.0],
            cell_size: 0.5,
            fields: vec!["velocity".into()],
            components: vec![FieldComponent {
                name: "vx".into(),
                values: vec![1.0, f32::NAN, -2.0, 0.0],
            }],
            cracks: vec![vec![[0.0, 0.0], [1.0, 0.5]]],
            particles: None,
            slice: Some(SnapshotSlice {
                normal: "z".into(),
                at: 0.01,
                node_at: 0.0105,
                axes: ["x".into(), "y".into()],
            }),
        };
        let d = decode_snapshot(&encode_snapshot(&s)).expect("decodes");
        assert_eq!(d.index, 3);
        assert!(d.components[0].values[1].is_nan());
        assert_eq!(d.components[0].values[2], -2.0);
        assert_eq!(d.cracks, s.cracks);
        assert_eq!(d.slice, s.slice);
        assert!(decode_snapshot(b"nope").is_err());
    }

    #[test]
    fn particles_round_trip_and_truncation_is_refused() {
        let s = Snapshot {
            index: 0,
            time: 0.0,
            nx: 1,
            ny: 1,
            origin: [0.0, 0.0],
            cell_size: 1.0,
            fields: vec!["stress".into()],
            components: vec![FieldComponent {
                name: "sxx".into(),
                values: vec![5.0],
            }],
            cracks: vec![],
            particles: Some(ParticleSnapshot {
                x: vec![0.25, 0.75],
                y: vec![0.5, 0.5],
                components: vec![FieldComponent {
                    name: "sxx".into(),
                    values: vec![4.0, 6.0],
                }],
            }),
            slice: None,
        };
        let b = encode_snapshot(&s);
        assert_eq!(decode_snapshot(&b).expect("decodes"), s);
        assert!(decode_snapshot(&b[..b.len() - 4]).is_err());
    }
}
