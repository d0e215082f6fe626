//! Binary encoding of a [`Snapshot`]: how workers upload snapshots and how the store keeps
//! them. JSON cannot carry the NaN that marks empty nodes, so the values travel as raw
//! little-endian `f32` after a small JSON header.
//!
//! Layout: `b"FSN1"`, header length (u32 LE), header JSON, then each component's values.

use fracture_api::results::{FieldComponent, Snapshot};
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
    };
    let h = serde_json::to_vec(&header).unwrap_or_default();
    let n: usize = s.components.iter().map(|c| c.values.len()).sum();
    let mut out = Vec::with_capacity(8 + h.len() + 4 * n);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&(h.len() as u32).to_le_bytes());
    out.extend_from_slice(&h);
    for c in &s.components {
        for v in &c.values {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
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
        if rest.len() < 4 * len {
            return Err(bad("truncated values"));
        }
        let (vals, tail) = rest.split_at(4 * len);
        rest = tail;
        let values = vals
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        components.push(FieldComponent { name, values });
    }
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
        };
        let d = decode_snapshot(&encode_snapshot(&s)).expect("decodes");
        assert_eq!(d.index, 3);
        assert!(d.components[0].values[1].is_nan());
        assert_eq!(d.components[0].values[2], -2.0);
        assert_eq!(d.cracks, s.cracks);
        assert!(decode_snapshot(b"nope").is_err());
    }
}
