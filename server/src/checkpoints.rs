//! The checkpoint file of a running job, `<data>/jobs/<id>/checkpoint.bin`: the worker's
//! bytes (opaque here: the server runs no physics) behind a header of the server's own that
//! says where the checkpoint stands in the job's history and guards the bytes.
//!
//! Layout: the magic `FRCKPT01`, the header's length (u32, little-endian), the header
//! (JSON: fence, step, the time's bits, snapshots, bytes, SHA-256 of the bytes), the bytes. A file is
//! written to a temporary file, fsynced, renamed over the previous one and the folder
//! fsynced, so a crash or a full disk leaves the previous checkpoint whole. A file whose
//! header or digest does not check out is corrupt: it is removed and the job restarts from
//! step 0.

use std::io::Write;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::store::HistoryCursor;

const MAGIC: &[u8; 8] = b"FRCKPT01";
const FILE: &str = "checkpoint.bin";

/// Serializes the checkpoint writes of running claims with the history rewinds of new
/// claims, so a claim resumes from exactly the checkpoint whose cursor it kept the history
/// to (a stale write is fenced off once the new claim exists).
pub static LOCK: tokio::sync::Mutex<()> = tokio::sync::Mutex::const_new(());

/// The header of a checkpoint file.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Header {
    fence: i64,
    step: u64,
    /// The simulated time's bits (exact, whatever the JSON float parsing).
    time_bits: u64,
    snapshots: u32,
    bytes: u64,
    sha256: String,
}

fn hex(d: &[u8]) -> String {
    d.iter().map(|b| format!("{b:02x}")).collect()
}

/// The checkpoint file in a job's folder.
pub fn path(dir: &Path) -> PathBuf {
    dir.join(FILE)
}

/// Write a checkpoint of claim `fence` at `at` (atomically: temporary file, fsync, rename).
/// On an error the previous checkpoint, if any, is left as it was.
pub fn write(dir: &Path, fence: i64, at: HistoryCursor, body: &[u8]) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    let header = Header {
        fence,
        step: at.step,
        time_bits: at.time.to_bits(),
        snapshots: at.snapshots,
        bytes: body.len() as u64,
        sha256: hex(&Sha256::digest(body)),
    };
    let head = serde_json::to_vec(&header).map_err(std::io::Error::other)?;
    let tmp = dir.join(format!("{FILE}.tmp"));
    let r = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(MAGIC)?;
        f.write_all(&(head.len() as u32).to_le_bytes())?;
        f.write_all(&head)?;
        f.write_all(body)?;
        f.sync_all()?;
        drop(f);
        std::fs::rename(&tmp, path(dir))?;
        std::fs::File::open(dir)?.sync_all()
    })();
    if r.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    r
}

/// What reading a job's checkpoint found.
#[derive(Debug)]
pub enum Found {
    /// No checkpoint.
    None,
    /// A checkpoint and where it stands.
    Some(HistoryCursor, Vec<u8>),
    /// A file that is not a whole checkpoint (the reason).
    Corrupt(String),
}

/// Read and check a job's checkpoint.
pub fn read(dir: &Path) -> std::io::Result<Found> {
    let data = match std::fs::read(path(dir)) {
        Ok(d) => d,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Found::None),
        Err(e) => return Err(e),
    };
    Ok(parse(data))
}

fn parse(mut data: Vec<u8>) -> Found {
    if data.len() < 12 || &data[..8] != MAGIC {
        return Found::Corrupt("no checkpoint header".into());
    }
    let n = u32::from_le_bytes([data[8], data[9], data[10], data[11]]) as usize;
    let Some(head) = data.get(12..12 + n) else {
        return Found::Corrupt("truncated header".into());
    };
    let h: Header = match serde_json::from_slice(head) {
        Ok(h) => h,
        Err(e) => return Found::Corrupt(format!("unreadable header: {e}")),
    };
    let body = data.split_off(12 + n);
    if body.len() as u64 != h.bytes || hex(&Sha256::digest(&body)) != h.sha256 {
        return Found::Corrupt("the bytes do not match the header".into());
    }
    let at = HistoryCursor {
        step: h.step,
        time: f64::from_bits(h.time_bits),
        snapshots: h.snapshots,
    };
    Found::Some(at, body)
}

/// Remove a job's checkpoint (none is fine).
pub fn remove(dir: &Path) -> std::io::Result<()> {
    match std::fs::remove_file(path(dir)) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        r => r,
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn round_trip_and_corruption() {
        let d = tempfile::tempdir().unwrap();
        let at = HistoryCursor {
            step: 12,
            time: 1.0e-6 / 3.0,
            snapshots: 2,
        };
        assert!(matches!(read(d.path()).unwrap(), Found::None));
        write(d.path(), 3, at, b"state").unwrap();
        match read(d.path()).unwrap() {
            Found::Some(a, b) => {
                assert_eq!(a.time.to_bits(), at.time.to_bits());
                assert_eq!((a.step, a.snapshots, b.as_slice()), (12, 2, &b"state"[..]));
            }
            f => panic!("{f:?}"),
        }
        let mut bytes = std::fs::read(path(d.path())).unwrap();
        let last = bytes.len() - 1;
        bytes[last] ^= 1;
        std::fs::write(path(d.path()), &bytes).unwrap();
        assert!(matches!(read(d.path()).unwrap(), Found::Corrupt(_)));
        std::fs::write(path(d.path()), &bytes[..20]).unwrap();
        assert!(matches!(read(d.path()).unwrap(), Found::Corrupt(_)));
        remove(d.path()).unwrap();
        remove(d.path()).unwrap();
        assert!(matches!(read(d.path()).unwrap(), Found::None));
    }
}
