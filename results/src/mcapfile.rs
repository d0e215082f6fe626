//! The run's MCAP file (`fields.mcap`): field snapshots and the histories again, openable
//! in Foxglove. Channels and schemas are documented in `docs/mcap.md`. (One format, writer
//! and readers together, so a change to a channel changes both: about 710 lines.)
//!
//! | topic | schema (JSON Schema) | one message per |
//! | --- | --- | --- |
//! | `/energy` | `fracture.EnergyRow` | energy sample |
//! | `/crack_tips` | `fracture.CrackTipRow` | crack tip per history sample |
//! | `/snapshot` | `fracture.Snapshot` | snapshot (everything, for exact round trips) |
//! | `/fields/<component>` | `foxglove.Grid` | snapshot, per scalar component (`sxx`, `vx`, …) |
//!
//! All channels are JSON-encoded. Log and publish time = simulated time in nanoseconds.
//! The writer is chunked and zstd-compressed; [`McapWriter::write_snapshot`] ends the
//! chunk and flushes the file, so a crash keeps every snapshot written so far (and the rows
//! written before it). The readers accept such an unfinished file.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Seek, Write};
use std::path::Path;

use base64::Engine as _;
use fracture_api::Scene;
use fracture_api::results::{CrackTipRow, EnergyRow, FieldComponent, ParticleSnapshot, Snapshot};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Topic of the energy history.
pub const ENERGY_TOPIC: &str = "/energy";
/// Topic of the crack-tip history.
pub const CRACK_TIPS_TOPIC: &str = "/crack_tips";
/// Topic of the full snapshots.
pub const SNAPSHOT_TOPIC: &str = "/snapshot";
/// Prefix of the per-component `foxglove.Grid` topics (`/fields/sxx`, …).
pub const FIELDS_TOPIC_PREFIX: &str = "/fields/";
/// Foxglove frame id of the grids (the simulation's x–y plane, metres).
pub const FRAME_ID: &str = "sim";
/// Name of the metadata record that holds the scene.
pub const SCENE_METADATA: &str = "scene";

/// Schema name of the energy messages.
pub const ENERGY_SCHEMA: &str = "fracture.EnergyRow";
/// Schema name of the crack-tip messages.
pub const CRACK_TIPS_SCHEMA: &str = "fracture.CrackTipRow";
/// Schema name of the snapshot messages.
pub const SNAPSHOT_SCHEMA: &str = "fracture.Snapshot";
/// Schema name of the field grids (Foxglove's well-known schema).
pub const GRID_SCHEMA: &str = "foxglove.Grid";

/// Why the MCAP file could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum McapFileError {
    /// File system error.
    #[error("{0}")]
    Io(#[from] std::io::Error),
    /// The MCAP library reported an error (bad or truncated file, too many channels, …).
    #[error("mcap: {0}")]
    Mcap(#[from] mcap::McapError),
    /// A message could not be encoded or decoded.
    #[error("message JSON on {topic}: {source}")]
    Json {
        /// Topic of the message.
        topic: String,
        /// The serde error.
        source: serde_json::Error,
    },
    /// The writer was already finished.
    #[error("the MCAP file is already finished")]
    Finished,
}

/// A snapshot as carried on `/snapshot`: the [`Snapshot`] with each value `null` where it
/// is NaN (no material), since JSON has no NaN.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[schemars(title = "fracture.Snapshot")]
pub struct SnapshotMessage {
    /// Index of the snapshot in its run (0, 1, …).
    pub index: u32,
    /// Simulated time (s).
    pub time: f64,
    /// Nodes in x.
    pub nx: u32,
    /// Nodes in y.
    pub ny: u32,
    /// Position of node (0, 0) (m).
    pub origin: [f64; 2],
    /// Node spacing (m).
    pub cell_size: f64,
    /// Field kinds recorded (names as in the scene's `output.fields`).
    pub fields: Vec<String>,
    /// The components of those fields.
    pub components: Vec<ComponentMessage>,
    /// Each crack's line as a polyline (m).
    pub cracks: Vec<Vec<[f64; 2]>>,
    /// (extension) The particles, when the scene records them (`output.particles`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub particles: Option<ParticlesMessage>,
    /// (extension) The plane of a 3D run this snapshot samples.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slice: Option<fracture_api::results::SnapshotSlice>,
}

/// The particles of a `/snapshot` message: positions (m) and each component per particle
/// (`null` where not finite).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ParticlesMessage {
    /// Positions x (m).
    pub x: Vec<f32>,
    /// Positions y (m).
    pub y: Vec<f32>,
    /// The components, one value per particle.
    pub components: Vec<ComponentMessage>,
}

impl From<&FieldComponent> for ComponentMessage {
    /// The values as the message carries them: `None` for a non-finite value.
    fn from(c: &FieldComponent) -> Self {
        ComponentMessage {
            name: c.name.clone(),
            values: c
                .values
                .iter()
                .map(|v| v.is_finite().then_some(*v))
                .collect(),
        }
    }
}

impl From<ComponentMessage> for FieldComponent {
    /// `null` values read back as NaN.
    fn from(c: ComponentMessage) -> Self {
        FieldComponent {
            name: c.name,
            values: c
                .values
                .into_iter()
                .map(|v| v.unwrap_or(f32::NAN))
                .collect(),
        }
    }
}

/// One field component on `/snapshot`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ComponentMessage {
    /// Component name, e.g. `sxx`, `vx`, `speed`, `fringe`.
    pub name: String,
    /// Values at the nodes, row-major from the lower-left node (index = iy·nx + ix);
    /// `null` where no material touches the node (or the value is not finite).
    pub values: Vec<Option<f32>>,
}

impl From<&Snapshot> for SnapshotMessage {
    fn from(s: &Snapshot) -> Self {
        SnapshotMessage {
            index: s.index,
            time: s.time,
            nx: s.nx,
            ny: s.ny,
            origin: s.origin,
            cell_size: s.cell_size,
            fields: s.fields.clone(),
            components: s.components.iter().map(ComponentMessage::from).collect(),
            cracks: s.cracks.clone(),
            particles: s.particles.as_ref().map(|p| ParticlesMessage {
                x: p.x.clone(),
                y: p.y.clone(),
                components: p.components.iter().map(ComponentMessage::from).collect(),
            }),
            slice: s.slice.clone(),
        }
    }
}

impl From<SnapshotMessage> for Snapshot {
    fn from(m: SnapshotMessage) -> Self {
        Snapshot {
            index: m.index,
            time: m.time,
            nx: m.nx,
            ny: m.ny,
            origin: m.origin,
            cell_size: m.cell_size,
            fields: m.fields,
            components: m.components.into_iter().map(FieldComponent::from).collect(),
            cracks: m.cracks,
            particles: m.particles.map(|p| ParticleSnapshot {
                x: p.x,
                y: p.y,
                components: p.components.into_iter().map(FieldComponent::from).collect(),
            }),
            slice: m.slice,
        }
    }
}

/// Foxglove's `foxglove.Grid` message (JSON encoding of the published schema).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GridMessage {
    /// Time of the snapshot.
    pub timestamp: FoxgloveTime,
    /// Frame of reference ([`FRAME_ID`]).
    pub frame_id: String,
    /// Corner of cell (0, 0): half a cell below and left of node (0, 0), so that each
    /// cell is centred on its node.
    pub pose: Pose,
    /// Cells per row (nodes in x).
    pub column_count: u32,
    /// Cell size (the node spacing) in x and y.
    pub cell_size: Vector2,
    /// Bytes per row (4 · column_count).
    pub row_stride: u32,
    /// Bytes per cell (4: one little-endian f32).
    pub cell_stride: u32,
    /// One field, `FLOAT32` at offset 0, named after the component.
    pub fields: Vec<PackedElementField>,
    /// Cell values, base64 of little-endian f32, rows from the lowest y up; NaN where no
    /// material touches the node.
    pub data: String,
}

/// Foxglove time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct FoxgloveTime {
    /// Seconds.
    pub sec: u32,
    /// Nanoseconds, 0..1e9.
    pub nsec: u32,
}

/// Foxglove pose.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// Position.
    pub position: Vector3,
    /// Orientation.
    pub orientation: Quaternion,
}

/// Foxglove 2-vector.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Vector2 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
}

/// Foxglove 3-vector.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Vector3 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

/// Foxglove quaternion.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

/// Foxglove packed element field.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PackedElementField {
    /// Field name.
    pub name: String,
    /// Byte offset within a cell.
    pub offset: u32,
    /// `foxglove.NumericType` (7 = FLOAT32).
    #[serde(rename = "type")]
    pub kind: u8,
}

/// `foxglove.NumericType` FLOAT32.
pub const NUMERIC_TYPE_FLOAT32: u8 = 7;

impl GridMessage {
    /// The grid of one component of a snapshot.
    pub fn from_component(s: &Snapshot, c: &FieldComponent) -> Self {
        let mut bytes = Vec::with_capacity(c.values.len() * 4);
        for v in &c.values {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        let h = s.cell_size;
        GridMessage {
            timestamp: foxglove_time(s.time),
            frame_id: FRAME_ID.to_string(),
            pose: Pose {
                position: Vector3 {
                    x: s.origin[0] - 0.5 * h,
                    y: s.origin[1] - 0.5 * h,
                    z: 0.0,
                },
                orientation: Quaternion {
                    x: 0.0,
                    y: 0.0,
                    z: 0.0,
                    w: 1.0,
                },
            },
            column_count: s.nx,
            cell_size: Vector2 { x: h, y: h },
            row_stride: 4 * s.nx,
            cell_stride: 4,
            fields: vec![PackedElementField {
                name: c.name.clone(),
                offset: 0,
                kind: NUMERIC_TYPE_FLOAT32,
            }],
            data: base64::engine::general_purpose::STANDARD.encode(bytes),
        }
    }

    /// The cell values decoded from `data` (for FLOAT32 grids at offset 0 with cell
    /// stride 4), or `None` when the data is not that.
    pub fn values(&self) -> Option<Vec<f32>> {
        let bytes = base64::engine::general_purpose::STANDARD
            .decode(&self.data)
            .ok()?;
        if self.cell_stride != 4 || bytes.len() % 4 != 0 {
            return None;
        }
        Some(
            bytes
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect(),
        )
    }
}

/// Simulated time (s) as MCAP log time (ns). Negative or non-finite times map to 0.
pub fn log_time(t: f64) -> u64 {
    let ns = (t * 1e9).round();
    if ns.is_finite() && ns > 0.0 {
        ns as u64
    } else {
        0
    }
}

fn foxglove_time(t: f64) -> FoxgloveTime {
    let ns = log_time(t);
    FoxgloveTime {
        sec: u32::try_from(ns / 1_000_000_000).unwrap_or(u32::MAX),
        nsec: (ns % 1_000_000_000) as u32,
    }
}

/// The published JSON Schema of `foxglove.Grid` (JSON encoding).
pub fn grid_json_schema() -> serde_json::Value {
    let num = |d: &str| serde_json::json!({"type": "number", "description": d});
    let numeric_types = [
        "UNKNOWN", "UINT8", "INT8", "UINT16", "INT16", "UINT32", "INT32", "FLOAT32", "FLOAT64",
    ];
    let one_of: Vec<serde_json::Value> = numeric_types
        .iter()
        .enumerate()
        .map(|(i, t)| serde_json::json!({"title": t, "const": i}))
        .collect();
    serde_json::json!({
        "title": "foxglove.Grid",
        "description": "A 2D grid of data",
        "type": "object",
        "properties": {
            "timestamp": {
                "type": "object",
                "title": "time",
                "properties": {
                    "sec": {"type": "integer", "minimum": 0},
                    "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999}
                },
                "description": "Timestamp of grid"
            },
            "frame_id": {"type": "string", "description": "Frame of reference"},
            "pose": {
                "title": "foxglove.Pose",
                "description": "Origin of grid's corner relative to frame of reference; grid is positioned in the x-y plane relative to this origin",
                "type": "object",
                "properties": {
                    "position": {
                        "title": "foxglove.Vector3",
                        "description": "Point denoting position in 3D space",
                        "type": "object",
                        "properties": {
                            "x": num("x coordinate length"),
                            "y": num("y coordinate length"),
                            "z": num("z coordinate length")
                        }
                    },
                    "orientation": {
                        "title": "foxglove.Quaternion",
                        "description": "Quaternion denoting orientation in 3D space",
                        "type": "object",
                        "properties": {
                            "x": num("x value"),
                            "y": num("y value"),
                            "z": num("z value"),
                            "w": num("w value")
                        }
                    }
                }
            },
            "column_count": {"type": "integer", "minimum": 0, "description": "Number of grid columns"},
            "cell_size": {
                "title": "foxglove.Vector2",
                "description": "Size of single grid cell along x and y axes, relative to `pose`",
                "type": "object",
                "properties": {"x": num("x coordinate length"), "y": num("y coordinate length")}
            },
            "row_stride": {"type": "integer", "minimum": 0, "description": "Number of bytes between rows in `data`"},
            "cell_stride": {"type": "integer", "minimum": 0, "description": "Number of bytes between cells within a row in `data`"},
            "fields": {
                "type": "array",
                "items": {
                    "title": "foxglove.PackedElementField",
                    "description": "List of fields included for every cell",
                    "type": "object",
                    "properties": {
                        "name": {"type": "string", "description": "Name of the field"},
                        "offset": {"type": "integer", "minimum": 0, "description": "Byte offset from start of data buffer"},
                        "type": {
                            "title": "foxglove.NumericType",
                            "description": "Type of data in the field. Integers are stored using little-endian byte order.",
                            "oneOf": one_of
                        }
                    }
                },
                "description": "Fields in `data`. `red`, `green`, `blue`, and `alpha` are optional for customizing the grid's color."
            },
            "data": {
                "type": "string",
                "contentEncoding": "base64",
                "description": "Grid cell data, interpreted using `fields`, in row-major (y-major) order"
            }
        }
    })
}

fn schema_bytes<T: JsonSchema>() -> Vec<u8> {
    let schema = schemars::schema_for!(T);
    serde_json::to_vec(&schema).unwrap_or_default()
}

/// Writes a run's MCAP file.
///
/// Rows and grids are written as they come; [`write_snapshot`](Self::write_snapshot)
/// flushes. [`finish`](Self::finish) writes the summary section (indexes); dropping the
/// writer without it also tries to finish the file.
pub struct McapWriter<W: Write + Seek = BufWriter<File>> {
    out: Option<mcap::Writer<W>>,
    energy: u16,
    crack_tips: u16,
    snapshot: u16,
    grid_schema: u16,
    grids: BTreeMap<String, u16>,
    sequence: u32,
}

impl McapWriter<BufWriter<File>> {
    /// Create (or truncate) the file at `path`.
    pub fn create(path: impl AsRef<Path>) -> Result<Self, McapFileError> {
        let file = File::create(path)?;
        Self::new(BufWriter::new(file))
    }
}

impl<W: Write + Seek> McapWriter<W> {
    /// Write to any seekable sink (e.g. a `Cursor<Vec<u8>>`).
    pub fn new(w: W) -> Result<Self, McapFileError> {
        let mut out = mcap::WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            // The solver owns the cores; compress on the calling thread.
            .compression_threads(0)
            .profile("")
            .create(w)?;
        let none = BTreeMap::new();
        let es = out.add_schema(ENERGY_SCHEMA, "jsonschema", &schema_bytes::<EnergyRow>())?;
        let cs = out.add_schema(
            CRACK_TIPS_SCHEMA,
            "jsonschema",
            &schema_bytes::<CrackTipRow>(),
        )?;
        let ss = out.add_schema(
            SNAPSHOT_SCHEMA,
            "jsonschema",
            &schema_bytes::<SnapshotMessage>(),
        )?;
        let grid_bytes = serde_json::to_vec(&grid_json_schema()).unwrap_or_default();
        let gs = out.add_schema(GRID_SCHEMA, "jsonschema", &grid_bytes)?;
        let energy = out.add_channel(es, ENERGY_TOPIC, "json", &none)?;
        let crack_tips = out.add_channel(cs, CRACK_TIPS_TOPIC, "json", &none)?;
        let snapshot = out.add_channel(ss, SNAPSHOT_TOPIC, "json", &none)?;
        Ok(McapWriter {
            out: Some(out),
            energy,
            crack_tips,
            snapshot,
            grid_schema: gs,
            grids: BTreeMap::new(),
            sequence: 0,
        })
    }

    fn writer(&mut self) -> Result<&mut mcap::Writer<W>, McapFileError> {
        self.out.as_mut().ok_or(McapFileError::Finished)
    }

    fn put<T: Serialize>(
        &mut self,
        channel: u16,
        topic: &str,
        time: f64,
        msg: &T,
    ) -> Result<(), McapFileError> {
        let data = serde_json::to_vec(msg).map_err(|source| McapFileError::Json {
            topic: topic.to_string(),
            source,
        })?;
        self.sequence = self.sequence.wrapping_add(1);
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: self.sequence,
            log_time: log_time(time),
            publish_time: log_time(time),
        };
        self.writer()?.write_to_known_channel(&header, &data)?;
        Ok(())
    }

    /// Record the scene (canonical JSON and hash) as the metadata record `scene`.
    pub fn write_scene(&mut self, scene: &Scene) -> Result<(), McapFileError> {
        self.write_scene_parts(&scene.name, &scene.hash(), &scene.canonical_json())
    }

    /// The scene metadata of a scene of either dimension: its name, hash and canonical JSON.
    pub fn write_scene_parts(
        &mut self,
        name: &str,
        hash: &str,
        json: &str,
    ) -> Result<(), McapFileError> {
        let mut metadata = BTreeMap::new();
        metadata.insert("name".to_string(), name.to_string());
        metadata.insert("hash".to_string(), hash.to_string());
        metadata.insert("json".to_string(), json.to_string());
        metadata.insert(
            "solver_version".to_string(),
            fracture_api::SOLVER_VERSION.to_string(),
        );
        self.writer()?.write_metadata(&mcap::records::Metadata {
            name: SCENE_METADATA.to_string(),
            metadata,
        })?;
        Ok(())
    }

    /// Append energy rows (one message each on `/energy`).
    pub fn write_energy(&mut self, rows: &[EnergyRow]) -> Result<(), McapFileError> {
        let ch = self.energy;
        for r in rows {
            self.put(ch, ENERGY_TOPIC, r.time, r)?;
        }
        Ok(())
    }

    /// Append crack-tip rows (one message each on `/crack_tips`).
    pub fn write_crack_tips(&mut self, rows: &[CrackTipRow]) -> Result<(), McapFileError> {
        let ch = self.crack_tips;
        for r in rows {
            self.put(ch, CRACK_TIPS_TOPIC, r.time, r)?;
        }
        Ok(())
    }

    /// Append a snapshot: the whole snapshot on `/snapshot` and one `foxglove.Grid` per
    /// component on `/fields/<component>`; then end the chunk and flush the file.
    pub fn write_snapshot(&mut self, snap: &Snapshot) -> Result<(), McapFileError> {
        let ch = self.snapshot;
        self.put(ch, SNAPSHOT_TOPIC, snap.time, &SnapshotMessage::from(snap))?;
        for c in &snap.components {
            let expected = snap.nx as usize * snap.ny as usize;
            if c.values.len() != expected || expected == 0 {
                // Not a grid of this snapshot's size: it stays on /snapshot only.
                continue;
            }
            let ch = self.grid_channel(&c.name)?;
            let topic = format!("{FIELDS_TOPIC_PREFIX}{}", c.name);
            self.put(ch, &topic, snap.time, &GridMessage::from_component(snap, c))?;
        }
        self.flush()
    }

    fn grid_channel(&mut self, name: &str) -> Result<u16, McapFileError> {
        if let Some(id) = self.grids.get(name) {
            return Ok(*id);
        }
        let schema = self.grid_schema;
        let topic = format!("{FIELDS_TOPIC_PREFIX}{name}");
        let id = self
            .writer()?
            .add_channel(schema, &topic, "json", &BTreeMap::new())?;
        self.grids.insert(name.to_string(), id);
        Ok(id)
    }

    /// End the current chunk and flush it to the file.
    pub fn flush(&mut self) -> Result<(), McapFileError> {
        self.writer()?.flush()?;
        Ok(())
    }

    /// Write the summary section and footer, and flush. Later writes fail with
    /// [`McapFileError::Finished`].
    pub fn finish(&mut self) -> Result<(), McapFileError> {
        let mut out = self.out.take().ok_or(McapFileError::Finished)?;
        out.finish()?;
        let mut inner = out.into_inner();
        inner.flush()?;
        Ok(())
    }
}

/// Everything a run's MCAP file holds, read back.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct McapContents {
    /// `/energy` rows in file order.
    pub energy: Vec<EnergyRow>,
    /// `/crack_tips` rows in file order.
    pub crack_tips: Vec<CrackTipRow>,
    /// `/snapshot` snapshots in file order (NaN restored where the JSON has `null`).
    pub snapshots: Vec<Snapshot>,
    /// The `foxglove.Grid` messages as (component, snapshot time in s, grid), file order.
    pub grids: Vec<(String, f64, GridMessage)>,
    /// The `scene` metadata record, if present (name → value).
    pub scene: Option<BTreeMap<String, String>>,
    /// Whether the file ended early (no footer: the writer did not finish); what was
    /// flushed before is still returned.
    pub truncated: bool,
}

impl McapContents {
    /// Read a whole MCAP file, finished or not.
    pub fn read(path: impl AsRef<Path>) -> Result<Self, McapFileError> {
        let bytes = std::fs::read(path)?;
        Self::from_bytes(&bytes)
    }

    /// Read MCAP bytes, finished or not. A file whose writer did not finish yields what was
    /// flushed; a damaged finished file is an error.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, McapFileError> {
        let finished = bytes.len() >= 2 * mcap::MAGIC.len() && bytes.ends_with(mcap::MAGIC);
        let mut out = McapContents {
            truncated: !finished,
            ..Default::default()
        };
        let mut options = enumset::EnumSet::new();
        if !finished {
            options.insert(mcap::read::Options::IgnoreEndMagic);
        }
        let stream = mcap::MessageStream::new_with_options(bytes, options)?;
        for msg in stream {
            let msg = match msg {
                Ok(m) => m,
                // An unfinished file may end inside a record: keep what came before.
                Err(_) if !finished => break,
                Err(e) => return Err(e.into()),
            };
            let topic = msg.channel.topic.as_str();
            let json = |e: serde_json::Error| McapFileError::Json {
                topic: topic.to_string(),
                source: e,
            };
            match topic {
                ENERGY_TOPIC => out
                    .energy
                    .push(serde_json::from_slice(&msg.data).map_err(json)?),
                CRACK_TIPS_TOPIC => out
                    .crack_tips
                    .push(serde_json::from_slice(&msg.data).map_err(json)?),
                SNAPSHOT_TOPIC => {
                    let m: SnapshotMessage = serde_json::from_slice(&msg.data).map_err(json)?;
                    out.snapshots.push(m.into());
                }
                t => {
                    if let Some(name) = t.strip_prefix(FIELDS_TOPIC_PREFIX) {
                        let g: GridMessage = serde_json::from_slice(&msg.data).map_err(json)?;
                        out.grids
                            .push((name.to_string(), msg.log_time as f64 * 1e-9, g));
                    }
                }
            }
        }
        if finished {
            out.scene = read_scene_metadata(bytes)?;
        } else {
            out.scene = scan_scene_metadata(bytes);
        }
        Ok(out)
    }
}

fn read_scene_metadata(bytes: &[u8]) -> Result<Option<BTreeMap<String, String>>, McapFileError> {
    let Some(summary) = mcap::Summary::read(bytes)? else {
        return Ok(scan_scene_metadata(bytes));
    };
    for index in &summary.metadata_indexes {
        if index.name == SCENE_METADATA {
            return Ok(Some(mcap::read::metadata(bytes, index)?.metadata));
        }
    }
    Ok(None)
}

/// Find the scene metadata record by scanning records (unfinished files have no index).
fn scan_scene_metadata(bytes: &[u8]) -> Option<BTreeMap<String, String>> {
    let reader = mcap::read::LinearReader::new_with_options(
        bytes,
        enumset::EnumSet::only(mcap::read::Options::IgnoreEndMagic),
    )
    .ok()?;
    for record in reader {
        match record {
            Ok(mcap::records::Record::Metadata(m)) if m.name == SCENE_METADATA => {
                return Some(m.metadata);
            }
            Ok(_) => {}
            Err(_) => break,
        }
    }
    None
}

/// The snapshots of an MCAP file (finished or not), in order.
pub fn read_snapshots(path: impl AsRef<Path>) -> Result<Vec<Snapshot>, McapFileError> {
    Ok(McapContents::read(path)?.snapshots)
}

/// The energy rows of an MCAP file (finished or not), in order.
pub fn read_energy(path: impl AsRef<Path>) -> Result<Vec<EnergyRow>, McapFileError> {
    Ok(McapContents::read(path)?.energy)
}

/// The crack-tip rows of an MCAP file (finished or not), in order.
pub fn read_crack_tips(path: impl AsRef<Path>) -> Result<Vec<CrackTipRow>, McapFileError> {
    Ok(McapContents::read(path)?.crack_tips)
}
