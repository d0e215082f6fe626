//! 3D runs as VTK files for ParaView (`three-d.md`, run output with `--vtk`): one
//! `volume_NNNNN.vti` per snapshot time (the whole nodal grid as XML ImageData, every
//! component a Float32 point array, `velocity` and `displacement` as 3-vectors, `occupied`
//! to threshold on), one `particles_NNNNN.vtu` where the scene records particles (vertices
//! with their components), and the `.pvd` collections `volumes.pvd` and `particles.pvd`.
//! Written by [`vtkio`] like the 2D export (`vtk.rs`); the collections by [`crate::vtk::pvd`].

use fracture_api::results::{FieldComponent, Volume};
use vtkio::model::{
    Attribute, Attributes, ByteOrder, CellType, Cells, DataArray, DataSet, Extent, ImageDataPiece,
    Piece, UnstructuredGridPiece, Version, VertexNumbers, Vtk,
};

use crate::vtk::VtkError;

/// Name of the grid file of the `k`-th snapshot time of a 3D series.
pub fn volume_file_name(k: usize) -> String {
    format!("volume_{k:05}.vti")
}

/// Name of the particle file of the `k`-th snapshot time of a 3D series.
pub fn particle_file_name(k: usize) -> String {
    format!("particles_{k:05}.vtu")
}

/// `velocity` = (vx, vy, vz) and `displacement` = (ux, uy, uz) as 3-component arrays, for
/// those whose three components are among `components`.
fn vectors3(components: &[FieldComponent]) -> Vec<Attribute> {
    let find = |name: &str| components.iter().find(|c| c.name == name);
    [
        ("velocity", "vx", "vy", "vz"),
        ("displacement", "ux", "uy", "uz"),
    ]
    .into_iter()
    .filter_map(|(name, a, b, c)| {
        let (a, b, c) = (find(a)?, find(b)?, find(c)?);
        let v: Vec<f32> = (0..a.values.len())
            .flat_map(|i| [a.values[i], b.values[i], c.values[i]])
            .collect();
        Some(Attribute::DataArray(DataArray::vectors(name).with_data(v)))
    })
    .collect()
}

/// The nodal grid of a volume as a VTK ImageData data set.
pub fn volume_image_data(v: &Volume) -> Result<Vtk, VtkError> {
    let [nx, ny, nz] = v.n.map(|k| k as usize);
    let nodes = nx * ny * nz;
    for c in &v.components {
        if c.values.len() != nodes {
            return Err(VtkError::BadSnapshot {
                index: v.index,
                component: c.name.clone(),
                len: c.values.len(),
                nodes,
            });
        }
    }
    let mut point: Vec<Attribute> = v
        .components
        .iter()
        .map(|c| {
            Attribute::DataArray(DataArray::scalars(c.name.clone(), 1).with_data(c.values.clone()))
        })
        .collect();
    point.extend(vectors3(&v.components));
    let occupied: Vec<u8> = (0..nodes)
        .map(|n| {
            u8::from(
                v.components
                    .iter()
                    .any(|c| c.values[n].is_finite() && c.name != "material"),
            )
        })
        .collect();
    point.push(Attribute::DataArray(
        DataArray::scalars("occupied", 1).with_data(occupied),
    ));
    let last = |n: usize| (n as i32 - 1).max(0);
    let extent = Extent::Ranges([0..=last(nx), 0..=last(ny), 0..=last(nz)]);
    let h = v.cell_size as f32;
    Ok(Vtk {
        version: Version::new_xml(1, 0),
        title: format!("volume {} t = {} s", v.index, v.time),
        byte_order: ByteOrder::LittleEndian,
        file_path: None,
        data: DataSet::ImageData {
            extent: extent.clone(),
            origin: v.origin.map(|o| o as f32),
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

/// The particles of a volume as a VTK UnstructuredGrid of vertices; `None` without them.
pub fn particle_data(v: &Volume) -> Result<Option<Vtk>, VtkError> {
    let Some(p) = &v.particles else {
        return Ok(None);
    };
    let n = p.x.len();
    let lens = [("y", p.y.len()), ("z", p.z.len())].into_iter().chain(
        p.components
            .iter()
            .map(|c| (c.name.as_str(), c.values.len())),
    );
    for (name, len) in lens {
        if len != n {
            return Err(VtkError::BadSnapshot {
                index: v.index,
                component: format!("particles.{name}"),
                len,
                nodes: n,
            });
        }
    }
    let points: Vec<f32> = (0..n).flat_map(|i| [p.x[i], p.y[i], p.z[i]]).collect();
    let mut point: Vec<Attribute> = p
        .components
        .iter()
        .map(|c| {
            Attribute::DataArray(DataArray::scalars(c.name.clone(), 1).with_data(c.values.clone()))
        })
        .collect();
    point.extend(vectors3(&p.components));
    Ok(Some(Vtk {
        version: Version::new_xml(1, 0),
        title: format!("particles of volume {} t = {} s", v.index, v.time),
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

/// The files of one snapshot time as (name, bytes): its `.vti` and, with particles, `.vtu`.
pub fn volume_files(v: &Volume, k: usize) -> Result<Vec<(String, Vec<u8>)>, VtkError> {
    let mut out = Vec::new();
    let name = volume_file_name(k);
    out.push((name.clone(), xml(volume_image_data(v)?, &name)?));
    if let Some(vtu) = particle_data(v)? {
        let name = particle_file_name(k);
        out.push((name.clone(), xml(vtu, &name)?));
    }
    Ok(out)
}

fn xml(vtk: Vtk, name: &str) -> Result<Vec<u8>, VtkError> {
    let mut out = Vec::new();
    vtk.write_xml(&mut out).map_err(|e| VtkError::Encode {
        name: name.to_string(),
        message: e.to_string(),
    })?;
    Ok(out)
}
