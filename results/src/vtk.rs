//! A run's field snapshots as VTK files for ParaView (`docs/vtk.md`):
//!
//! * one `fields_NNNNN.vti` per snapshot: the nodal grid as XML ImageData (origin, spacing =
//!   the cell size), every component as a Float32 point array (NaN where no material touches
//!   the node), `velocity` = (vx, vy, 0) and `displacement` = (ux, uy, 0) as vectors where
//!   both components are recorded, and `occupied` (UInt8, 1 where the node has material) to
//!   threshold on;
//! * one `cracks_NNNNN.vtp` per snapshot: the crack lines as XML PolyData polylines (z = 0),
//!   with the crack's index as cell data `crack`; an empty PolyData when there are none;
//! * `fields.pvd` and `cracks.pvd`: the time series (ParaView's collection format), each
//!   entry the snapshot's simulated time in seconds.
//!
//! * one `particles_NNNNN.vtu` per snapshot that carries particles (the scene's
//!   `output.particles`): the particles as XML UnstructuredGrid vertices (z = 0) with every
//!   component per particle and the `velocity`/`displacement` vectors, and `particles.pvd`.
//!
//! The `.vti`/`.vtp` files are written by [`vtkio`] (inline base64 binary, XML format 1.0,
//! uncompressed); the `.pvd` collection, which vtkio does not model, is a few lines of XML
//! written here. ImageData stores origin and spacing as Float32 (vtkio's model), a relative
//! error of about 1e-7.

use std::fs;
use std::path::{Path, PathBuf};

use fracture_api::results::{FieldComponent, Snapshot};
use vtkio::model::{
    Attribute, Attributes, ByteOrder, CellType, Cells, DataArray, DataSet, Extent, ImageDataPiece,
    Piece, PolyDataPiece, UnstructuredGridPiece, Version, VertexNumbers, Vtk,
};

use crate::mcapfile::{self, McapFileError};

/// Why an export failed.
#[derive(Debug, thiserror::Error)]
pub enum VtkError {
    /// A file could not be written.
    #[error("writing {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        source: std::io::Error,
    },
    /// vtkio could not encode a data set.
    #[error("encoding {name}: {message}")]
    Encode {
        /// The file name.
        name: String,
        /// vtkio's message.
        message: String,
    },
    /// A snapshot is inconsistent (component length ≠ nx·ny).
    #[error("snapshot {index}: component `{component}` has {len} values for {nodes} nodes")]
    BadSnapshot {
        /// Snapshot index.
        index: u32,
        /// Component name.
        component: String,
        /// Its length.
        len: usize,
        /// nx·ny.
        nodes: usize,
    },
    /// The MCAP file could not be read.
    #[error(transparent)]
    Mcap(#[from] McapFileError),
}

/// The files of an exported series.
#[derive(Debug, Clone, PartialEq)]
pub struct VtkSeries {
    /// The grid time series: open this in ParaView (for a 3D run's slices: every plane, one
    /// part each).
    pub fields_pvd: PathBuf,
    /// The crack time series (2D runs; a 3D slice series has none).
    pub cracks_pvd: Option<PathBuf>,
    /// The particle time series, when the snapshots carry particles.
    pub particles_pvd: Option<PathBuf>,
    /// Every file written, the two `.pvd` first.
    pub files: Vec<PathBuf>,
}

/// Name of the grid file of the `k`-th snapshot of a series.
pub fn grid_file_name(k: usize) -> String {
    format!("fields_{k:05}.vti")
}

/// Name of the crack file of the `k`-th snapshot of a series.
pub fn crack_file_name(k: usize) -> String {
    format!("cracks_{k:05}.vtp")
}

/// `velocity` = (vx, vy, vz) and `displacement` = (ux, uy, uz) as 3-component point arrays
/// (the z component 0 where the snapshot has none: 2D), for those whose x and y components
/// are among `components`.
fn vectors(components: &[FieldComponent]) -> Vec<Attribute> {
    let find = |name: &str| components.iter().find(|c| c.name == name);
    [
        ("velocity", "vx", "vy", "vz"),
        ("displacement", "ux", "uy", "uz"),
    ]
    .into_iter()
    .filter_map(|(name, a, b, c)| {
        let (a, b) = (find(a)?, find(b)?);
        let c = find(c);
        let v: Vec<f32> = a
            .values
            .iter()
            .zip(&b.values)
            .enumerate()
            .flat_map(|(i, (&x, &y))| [x, y, c.map_or(0.0, |c| c.values[i])])
            .collect();
        Some(Attribute::DataArray(DataArray::vectors(name).with_data(v)))
    })
    .collect()
}

/// Where a snapshot's image lies in space: its extent and origin. A 2D snapshot is the plane
/// z = 0; a 3D slice (`Snapshot::slice`) is its node plane at `node_at` along its normal, its
/// two axes the snapshot's x and y, so a slice series opens in place in ParaView.
fn placement(snap: &Snapshot) -> (Extent, [f32; 3]) {
    let (nx, ny) = ((snap.nx as i32 - 1).max(0), (snap.ny as i32 - 1).max(0));
    let (o0, o1) = (snap.origin[0] as f32, snap.origin[1] as f32);
    match &snap.slice {
        Some(sl) if sl.normal == "x" => (
            Extent::Ranges([0..=0, 0..=nx, 0..=ny]),
            [sl.node_at as f32, o0, o1],
        ),
        Some(sl) if sl.normal == "y" => (
            Extent::Ranges([0..=nx, 0..=0, 0..=ny]),
            [o0, sl.node_at as f32, o1],
        ),
        Some(sl) => (
            Extent::Ranges([0..=nx, 0..=ny, 0..=0]),
            [o0, o1, sl.node_at as f32],
        ),
        None => (Extent::Ranges([0..=nx, 0..=ny, 0..=0]), [o0, o1, 0.0]),
    }
}

/// Name of the particle file of the `k`-th snapshot of a series.
pub fn particle_file_name(k: usize) -> String {
    format!("particles_{k:05}.vtu")
}

/// The particles of a snapshot as a VTK UnstructuredGrid of vertices (z = 0), with every
/// component as a Float32 point array and `velocity`/`displacement` as 3-vectors where both
/// components are there. `None` when the snapshot carries no particles.
pub fn particle_data(snap: &Snapshot) -> Result<Option<Vtk>, VtkError> {
    let Some(p) = &snap.particles else {
        return Ok(None);
    };
    let n = p.x.len();
    for (name, len) in std::iter::once(("y", p.y.len())).chain(
        p.components
            .iter()
            .map(|c| (c.name.as_str(), c.values.len())),
    ) {
        if len != n {
            return Err(VtkError::BadSnapshot {
                index: snap.index,
                component: format!("particles.{name}"),
                len,
                nodes: n,
            });
        }
    }
    let points: Vec<f32> =
        p.x.iter()
            .zip(&p.y)
            .flat_map(|(&x, &y)| [x, y, 0.0])
            .collect();
    let mut point = Vec::new();
    for c in &p.components {
        point.push(Attribute::DataArray(
            DataArray::scalars(c.name.clone(), 1).with_data(c.values.clone()),
        ));
    }
    point.extend(vectors(&p.components));
    Ok(Some(Vtk {
        version: Version::new_xml(1, 0),
        title: format!("particles of snapshot {} t = {} s", snap.index, snap.time),
        byte_order: ByteOrder::LittleEndian,
        file_path: None,
        data: DataSet::inline(UnstructuredGridPiece {
            points: points.into(),
            cells: Cells {
                cell_verts: VertexNumbers::XML {
                    connectivity: (0..n as u64).collect(),
                    offsets: (1..=n as u64).collect(),
                },
                types: vec![CellType::Vertex; n],
            },
            data: Attributes {
                point,
                cell: vec![],
            },
        }),
    }))
}

/// The nodal grid of a snapshot as a VTK ImageData data set.
pub fn image_data(snap: &Snapshot) -> Result<Vtk, VtkError> {
    let nx = snap.nx as usize;
    let ny = snap.ny as usize;
    let nodes = nx * ny;
    for c in &snap.components {
        if c.values.len() != nodes {
            return Err(VtkError::BadSnapshot {
                index: snap.index,
                component: c.name.clone(),
                len: c.values.len(),
                nodes,
            });
        }
    }
    let mut point = Vec::new();
    for c in &snap.components {
        point.push(Attribute::DataArray(
            DataArray::scalars(c.name.clone(), 1).with_data(c.values.clone()),
        ));
    }
    point.extend(vectors(&snap.components));
    let occupied: Vec<u8> = (0..nodes)
        .map(|n| {
            u8::from(
                snap.components
                    .iter()
                    .any(|c| c.values[n].is_finite() && c.name != "material"),
            )
        })
        .collect();
    point.push(Attribute::DataArray(
        DataArray::scalars("occupied", 1).with_data(occupied),
    ));
    let (extent, origin) = placement(snap);
    let h = snap.cell_size as f32;
    Ok(Vtk {
        version: Version::new_xml(1, 0),
        title: format!("snapshot {} t = {} s", snap.index, snap.time),
        byte_order: ByteOrder::LittleEndian,
        file_path: None,
        data: DataSet::ImageData {
            extent: extent.clone(),
            origin,
            spacing: [h, h, h],
            meta: None,
            pieces: vec![Piece::Inline(Box::new(ImageDataPiece {
                extent,
                data: Attributes {
                    point,
                    cell: vec![],
                },
            }))],
        },
    })
}

/// The cracks of a snapshot as a VTK PolyData data set: one polyline per crack.
pub fn crack_poly_data(snap: &Snapshot) -> Vtk {
    let mut points: Vec<f64> = Vec::new();
    let mut vertices: Vec<u32> = Vec::new();
    let mut ids: Vec<i32> = Vec::new();
    let mut n = 0u32;
    for (k, crack) in snap.cracks.iter().enumerate() {
        if crack.is_empty() {
            continue;
        }
        vertices.push(crack.len() as u32);
        for p in crack {
            points.extend([p[0], p[1], 0.0]);
            vertices.push(n);
            n += 1;
        }
        ids.push(k as i32);
    }
    let lines = (!ids.is_empty()).then_some(VertexNumbers::Legacy {
        num_cells: ids.len() as u32,
        vertices,
    });
    Vtk {
        version: Version::new_xml(1, 0),
        title: format!("cracks of snapshot {} t = {} s", snap.index, snap.time),
        byte_order: ByteOrder::LittleEndian,
        file_path: None,
        data: DataSet::inline(PolyDataPiece {
            points: points.into(),
            lines,
            data: Attributes {
                point: vec![],
                cell: vec![Attribute::DataArray(
                    DataArray::scalars("crack", 1).with_data(ids),
                )],
            },
            ..Default::default()
        }),
    }
}

/// A `.pvd` collection: (time in s, file name relative to the `.pvd`) per entry.
pub fn pvd(entries: &[(f64, String)]) -> String {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"1.0\" \
         byte_order=\"LittleEndian\">\n  <Collection>\n",
    );
    for (t, file) in entries {
        // `{:e}` of an f64 is the shortest string that reads back as the same number.
        s.push_str(&format!(
            "    <DataSet timestep=\"{t:e}\" group=\"\" part=\"0\" file=\"{}\"/>\n",
            xml_escape(file)
        ));
    }
    s.push_str("  </Collection>\n</VTKFile>\n");
    s
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('"', "&quot;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

fn xml_bytes(vtk: Vtk, name: &str) -> Result<Vec<u8>, VtkError> {
    let mut out = Vec::new();
    vtk.write_xml(&mut out).map_err(|e| VtkError::Encode {
        name: name.to_string(),
        message: e.to_string(),
    })?;
    Ok(out)
}

/// The files of a series in memory, as (name, bytes): `fields.pvd`, `cracks.pvd` (and
/// `particles.pvd` when the snapshots carry particles), then per snapshot its `.vti`, `.vtp`
/// (and `.vtu`); for a 3D run's slices, one series per plane and `fields.pvd` with a part per
/// plane (each image at its node plane). For a server packing them into an archive.
pub fn series_files(snaps: &[Snapshot]) -> Result<Vec<(String, Vec<u8>)>, VtkError> {
    if snaps.iter().any(|s| s.slice.is_some()) {
        return slice_series_files(snaps);
    }
    let mut files = Vec::with_capacity(2 + 2 * snaps.len());
    let mut grids = Vec::new();
    let mut cracks = Vec::new();
    let mut particles = Vec::new();
    let mut data = Vec::new();
    for (k, s) in snaps.iter().enumerate() {
        let (g, c) = (grid_file_name(k), crack_file_name(k));
        data.push((g.clone(), xml_bytes(image_data(s)?, &g)?));
        data.push((c.clone(), xml_bytes(crack_poly_data(s), &c)?));
        grids.push((s.time, g));
        cracks.push((s.time, c));
        if let Some(vtu) = particle_data(s)? {
            let name = particle_file_name(k);
            data.push((name.clone(), xml_bytes(vtu, &name)?));
            particles.push((s.time, name));
        }
    }
    files.push(("fields.pvd".to_string(), pvd(&grids).into_bytes()));
    files.push(("cracks.pvd".to_string(), pvd(&cracks).into_bytes()));
    if !particles.is_empty() {
        files.push(("particles.pvd".to_string(), pvd(&particles).into_bytes()));
    }
    files.extend(data);
    Ok(files)
}

/// The series of a 3D run's slices: per plane `slice_<normal>_<at>mm.pvd` and its
/// `slice_<normal>_<at>mm_NNNNN.vti` (each image placed at its node plane), and `fields.pvd`
/// with every plane of every time as one part per plane, so that one file opens all the
/// planes in place. A slice snapshot has no cracks or particles in this series.
fn slice_series_files(snaps: &[Snapshot]) -> Result<Vec<(String, Vec<u8>)>, VtkError> {
    let mut planes: Vec<String> = Vec::new();
    let mut per_plane: Vec<Vec<(f64, String)>> = Vec::new();
    let mut all: Vec<(f64, usize, String)> = Vec::new();
    let mut data = Vec::new();
    for s in snaps {
        let plane = match &s.slice {
            Some(sl) => format!("slice_{}_{:.3}mm", sl.normal, sl.node_at * 1e3),
            None => "fields".to_string(),
        };
        let part = match planes.iter().position(|p| *p == plane) {
            Some(k) => k,
            None => {
                planes.push(plane.clone());
                per_plane.push(Vec::new());
                planes.len() - 1
            }
        };
        let name = format!("{plane}_{:05}.vti", per_plane[part].len());
        data.push((name.clone(), xml_bytes(image_data(s)?, &name)?));
        per_plane[part].push((s.time, name.clone()));
        all.push((s.time, part, name));
    }
    let mut files = Vec::with_capacity(1 + planes.len() + data.len());
    let mut fields = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"1.0\" \
         byte_order=\"LittleEndian\">\n  <Collection>\n",
    );
    for (t, part, file) in &all {
        fields.push_str(&format!(
            "    <DataSet timestep=\"{t:e}\" group=\"\" part=\"{part}\" file=\"{}\"/>\n",
            xml_escape(file)
        ));
    }
    fields.push_str("  </Collection>\n</VTKFile>\n");
    files.push(("fields.pvd".to_string(), fields.into_bytes()));
    for (plane, entries) in planes.iter().zip(&per_plane) {
        files.push((format!("{plane}.pvd"), pvd(entries).into_bytes()));
    }
    files.extend(data);
    Ok(files)
}

/// Write a series into `dir` (created if missing): `fields.pvd`, `cracks.pvd` and the
/// per-snapshot files. Files of an earlier export with more snapshots are not removed.
pub fn write_series(dir: &Path, snaps: &[Snapshot]) -> Result<VtkSeries, VtkError> {
    fs::create_dir_all(dir).map_err(|source| VtkError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    let mut written = Vec::new();
    let mut particles_pvd = None;
    let mut cracks_pvd = None;
    for (name, bytes) in series_files(snaps)? {
        if name == "cracks.pvd" {
            cracks_pvd = Some(dir.join(&name));
        }
        if name == "particles.pvd" {
            particles_pvd = Some(dir.join(&name));
        }
        let path = dir.join(name);
        fs::write(&path, bytes).map_err(|source| VtkError::Io {
            path: path.clone(),
            source,
        })?;
        written.push(path);
    }
    Ok(VtkSeries {
        fields_pvd: dir.join("fields.pvd"),
        cracks_pvd,
        particles_pvd,
        files: written,
    })
}

/// Export the snapshots of a run's `fields.mcap` into `dir`.
pub fn export_mcap(mcap: &Path, dir: &Path) -> Result<VtkSeries, VtkError> {
    let snaps = mcapfile::read_snapshots(mcap)?;
    write_series(dir, &snaps)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pvd_lists_times_and_files() {
        let s = pvd(&[(0.0, "a.vti".into()), (1.25e-5, "b&c.vti".into())]);
        assert!(s.contains("timestep=\"0e0\""));
        assert!(s.contains("timestep=\"1.25e-5\" group=\"\" part=\"0\" file=\"b&amp;c.vti\""));
        assert_eq!("1.25e-5".parse::<f64>().ok(), Some(1.25e-5));
    }

    #[test]
    fn inconsistent_snapshots_are_refused() {
        let s = Snapshot {
            index: 7,
            time: 0.0,
            nx: 3,
            ny: 2,
            origin: [0.0, 0.0],
            cell_size: 1.0,
            fields: vec![],
            components: vec![fracture_api::results::FieldComponent {
                name: "sxx".into(),
                values: vec![0.0; 5],
            }],
            cracks: vec![],
            particles: None,
            slice: None,
        };
        assert!(matches!(
            image_data(&s),
            Err(VtkError::BadSnapshot {
                index: 7,
                len: 5,
                nodes: 6,
                ..
            })
        ));
    }

    /// A 3D run's slices: one series per plane and `fields.pvd` with a part per plane; each
    /// image lies at its node plane (a plane normal to x spans y and z at x = node_at), with
    /// velocity a 3-vector.
    #[test]
    fn slice_series_place_each_plane_in_space() {
        let slice = |t: f64, normal: &str, node_at: f64, axes: [&str; 2]| Snapshot {
            index: 0,
            time: t,
            nx: 4,
            ny: 3,
            origin: [0.01, 0.02],
            cell_size: 0.001,
            fields: vec![],
            components: ["vx", "vy", "vz"]
                .iter()
                .enumerate()
                .map(|(k, n)| fracture_api::results::FieldComponent {
                    name: (*n).into(),
                    values: vec![k as f32 + 1.0; 12],
                })
                .collect(),
            cracks: vec![],
            particles: None,
            slice: Some(fracture_api::results::SnapshotSlice {
                normal: normal.into(),
                at: node_at,
                node_at,
                axes: axes.map(String::from),
            }),
        };
        let snaps = [
            slice(0.0, "z", 0.002, ["x", "y"]),
            slice(0.0, "x", 0.005, ["y", "z"]),
            slice(1e-6, "z", 0.002, ["x", "y"]),
            slice(1e-6, "x", 0.005, ["y", "z"]),
        ];
        let files = series_files(&snaps).expect("series");
        let names: Vec<&str> = files.iter().map(|f| f.0.as_str()).collect();
        assert_eq!(
            names[..3],
            ["fields.pvd", "slice_z_2.000mm.pvd", "slice_x_5.000mm.pvd"]
        );
        assert!(names.contains(&"slice_x_5.000mm_00001.vti"));
        assert!(!names.contains(&"cracks.pvd"));
        let text = |n: &str| {
            String::from_utf8(files.iter().find(|f| f.0 == n).expect(n).1.clone()).expect("utf8")
        };
        let fields = text("fields.pvd");
        assert!(
            fields.contains("part=\"1\" file=\"slice_x_5.000mm_00000.vti\""),
            "{fields}"
        );
        assert!(
            fields.contains("timestep=\"1e-6\" group=\"\" part=\"0\""),
            "{fields}"
        );
        let x = text("slice_x_5.000mm_00000.vti");
        assert!(x.contains("WholeExtent=\"0 0 0 3 0 2\""), "{x}");
        assert!(x.contains("Origin=\"0.005 0.01 0.02\""), "{x}");
        let z = text("slice_z_2.000mm_00001.vti");
        assert!(z.contains("WholeExtent=\"0 3 0 2 0 0\""), "{z}");
        assert!(z.contains("Origin=\"0.01 0.02 0.002\""), "{z}");
        assert!(
            z.contains("Name=\"velocity\" NumberOfComponents=\"3\""),
            "{z}"
        );
    }
}
