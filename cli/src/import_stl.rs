//! `fracture import-stl FILE.stl`: an STL surface as a 3D scene's `mesh` region
//! (`docs/scenes-3d.md`, "From an STL file").
//!
//! Reads ASCII or binary STL with `stl_io`, merges vertices whose coordinates are exactly
//! equal, checks the surface as validation will ([`fracture_api::mesh::check_mesh`]: closed,
//! consistently oriented, no degenerate or self-intersecting triangles) and prints
//! `{"mesh": {"vertices": […], "triangles": […]}}` on stdout, ready to paste as a body's
//! `region`. Its size, bounding box and volume go to stderr.
//!
//! STL stores single-precision coordinates written, in ASCII files, as decimals: each is
//! printed as the shortest decimal that reads back to the same `f32` (the file's `0.1` prints
//! as `0.1`, not as `f64::from(0.1f32)` = 0.10000000149011612), then multiplied by `--scale`.
//!
//! Exit status: 0 success; 1 the output could not be written; 2 a missing, unreadable or
//! malformed file, or a surface that is not a valid region.

use std::collections::HashMap;
use std::fmt;
use std::io::Write;
use std::path::Path;
use std::process::ExitCode;

use fracture_api::mesh::{MeshDefect, check_mesh};
use fracture_api::scene3::{TriMesh, Vec3};

/// Exit status of an output error.
const EXIT_ERROR: u8 = 1;
/// Exit status of an unreadable file or an invalid surface.
const EXIT_INVALID: u8 = 2;

/// Why an STL file gives no region.
#[derive(Debug)]
pub enum ImportError {
    /// The file could not be read.
    Read(std::io::Error),
    /// The file is not STL, or is truncated or malformed.
    Parse(String),
    /// The file holds no facet.
    Empty,
    /// A facet with a NaN or infinite coordinate (0-based, in file order).
    NonFinite {
        /// The facet.
        facet: usize,
    },
    /// `--scale` is not a finite positive number.
    Scale(f64),
    /// The surface fails the region checks; triangle numbers are facets in file order.
    Surface(MeshDefect),
}

impl fmt::Display for ImportError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ImportError::Read(e) => write!(f, "cannot read it: {e}"),
            ImportError::Parse(m) => write!(f, "not a readable STL file: {m}"),
            ImportError::Empty => write!(f, "holds no triangles"),
            ImportError::NonFinite { facet } => {
                write!(
                    f,
                    "facet {facet} has a coordinate that is not a finite number"
                )
            }
            ImportError::Scale(s) => write!(f, "--scale {s} must be a finite number > 0"),
            ImportError::Surface(d) => match d.triangle() {
                Some(t) => write!(
                    f,
                    "its surface is not a valid region: facet {t} (0-based, in file order) {d}"
                ),
                None => write!(f, "its surface is not a valid region: it {d}"),
            },
        }
    }
}

impl std::error::Error for ImportError {}

/// How the bytes are to be read.
enum Format {
    Ascii,
    Binary,
}

/// Binary when the facet count in bytes 80..84 accounts for the file's length exactly (a
/// binary header may begin with "solid", as some exporters write), else ASCII when the text
/// begins with `solid`, else binary.
fn format_of(bytes: &[u8]) -> Format {
    if bytes.len() >= 84 {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]);
        if 84 + 50 * u64::from(n) == bytes.len() as u64 {
            return Format::Binary;
        }
    }
    let start = bytes.iter().position(|b| !b.is_ascii_whitespace());
    let text = start.map_or(&bytes[..0], |s| &bytes[s..]);
    if text.len() >= 5 && text[..5].eq_ignore_ascii_case(b"solid") {
        Format::Ascii
    } else {
        Format::Binary
    }
}

/// The bytes as `stl_io` reads them: a binary header that begins with "solid" is blanked
/// (its reader would take the file for ASCII); an ASCII file is lower-cased, its leading
/// blank lines dropped and its first line made `solid NAME` (the reader wants the space).
fn normalise(bytes: &[u8]) -> Vec<u8> {
    match format_of(bytes) {
        Format::Binary => {
            let mut out = bytes.to_vec();
            let header = out.len().min(80);
            out[..header].fill(b' ');
            out
        }
        Format::Ascii => {
            let text = String::from_utf8_lossy(bytes).to_ascii_lowercase();
            let text = text.trim_start();
            let (first, rest) = text.split_once('\n').unwrap_or((text, ""));
            let name = first.trim_end().strip_prefix("solid").unwrap_or("").trim();
            let name = if name.is_empty() { "stl" } else { name };
            format!("solid {name}\n{rest}").into_bytes()
        }
    }
}

/// Read an STL file's surface from its bytes: vertices merged where exactly equal (−0 and
/// +0 alike), coordinates as the shortest decimals of the file's `f32` values times `scale`,
/// triangles in file order. Checked as a region mesh.
pub fn read_stl(bytes: &[u8], scale: f64) -> Result<TriMesh, ImportError> {
    if !(scale.is_finite() && scale > 0.0) {
        return Err(ImportError::Scale(scale));
    }
    let mut cursor = std::io::Cursor::new(normalise(bytes));
    let reader =
        stl_io::create_stl_reader(&mut cursor).map_err(|e| ImportError::Parse(e.to_string()))?;
    let mut index: HashMap<[u32; 3], u32> = HashMap::new();
    let mut vertices: Vec<Vec3> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    for (facet, t) in reader.enumerate() {
        let t = t.map_err(|e| ImportError::Parse(format!("facet {facet}: {e}")))?;
        let mut tri = [0u32; 3];
        for (corner, v) in t.vertices.iter().enumerate() {
            if !v.0.iter().all(|c| c.is_finite()) {
                return Err(ImportError::NonFinite { facet });
            }
            // −0.0 + 0.0 = +0.0: one vertex, as "exactly equal" means.
            let v = v.0.map(|c| c + 0.0);
            let key = v.map(f32::to_bits);
            let next = u32::try_from(vertices.len())
                .map_err(|_| ImportError::Parse("more than 2³² vertices".into()))?;
            tri[corner] = *index.entry(key).or_insert_with(|| {
                vertices.push(v.map(|c| shortest_f64(c) * scale));
                next
            });
        }
        triangles.push(tri);
    }
    if triangles.is_empty() {
        return Err(ImportError::Empty);
    }
    check_mesh(&vertices, &triangles).map_err(ImportError::Surface)?;
    Ok(TriMesh::new(vertices, triangles))
}

/// The `f64` of the shortest decimal that reads back to `x` (`0.1f32` → `0.1`). Distinct
/// `f32` values give distinct results (their shortest decimals differ and have at most nine
/// digits, which `f64` tells apart).
fn shortest_f64(x: f32) -> f64 {
    x.to_string().parse().unwrap_or(f64::from(x))
}

/// The region JSON of a mesh, one vertex and one triangle per line.
pub fn region_json(mesh: &TriMesh) -> String {
    let list = |items: Vec<String>| {
        if items.is_empty() {
            "[]".to_string()
        } else {
            format!("[\n    {}\n  ]", items.join(",\n    "))
        }
    };
    let vertices = mesh
        .vertices()
        .iter()
        .map(|v| serde_json::to_string(v).unwrap_or_default())
        .collect();
    let triangles = mesh
        .triangles()
        .iter()
        .map(|t| serde_json::to_string(t).unwrap_or_default())
        .collect();
    format!(
        "{{\"mesh\": {{\n  \"vertices\": {},\n  \"triangles\": {}\n}}}}\n",
        list(vertices),
        list(triangles)
    )
}

/// `fracture import-stl FILE --scale S`.
pub fn import_stl(path: &Path, scale: f64) -> ExitCode {
    let mesh = std::fs::read(path)
        .map_err(ImportError::Read)
        .and_then(|bytes| read_stl(&bytes, scale));
    let mesh = match mesh {
        Ok(m) => m,
        Err(e) => {
            eprintln!("error: {}: {e}", path.display());
            return ExitCode::from(EXIT_INVALID);
        }
    };
    let (lo, hi) = mesh.bounds();
    let volume = mesh.signed_volume();
    eprintln!(
        "{}: {} triangles, {} vertices, bounding box {lo:?} – {hi:?}, volume {:e} ({} \
         triangles)",
        path.display(),
        mesh.triangles().len(),
        mesh.vertices().len(),
        volume.abs(),
        if volume >= 0.0 { "outward" } else { "inward" }
    );
    let text = region_json(&mesh);
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: cannot write the output: {e}");
            ExitCode::from(EXIT_ERROR)
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    /// A tetrahedron's four facets as (vertices) in outward order.
    fn tetra() -> Vec<[[f32; 3]; 3]> {
        let p = [
            [0.0, 0.0, 0.0],
            [0.1, 0.0, 0.0],
            [0.0, 0.1, 0.0],
            [0.0, 0.0, 0.1],
        ];
        [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
            .iter()
            .map(|t| t.map(|i| p[i]))
            .collect()
    }

    fn binary(facets: &[[[f32; 3]; 3]], header: &[u8]) -> Vec<u8> {
        let mut b = vec![0u8; 80];
        b[..header.len()].copy_from_slice(header);
        b.extend((facets.len() as u32).to_le_bytes());
        for f in facets {
            b.extend([0f32; 3].iter().flat_map(|c| c.to_le_bytes()));
            for v in f {
                b.extend(v.iter().flat_map(|c| c.to_le_bytes()));
            }
            b.extend([0u8; 2]);
        }
        b
    }

    #[test]
    fn a_binary_header_that_says_solid_is_still_binary() {
        let m = read_stl(&binary(&tetra(), b"solid exported by a CAD tool"), 1.0).unwrap();
        assert_eq!(m.vertices().len(), 4);
        // In order of first use: facet [0, 2, 1] gives p0, p2, p1.
        assert_eq!(m.vertices()[2], [0.1, 0.0, 0.0]);
        assert!((m.signed_volume() - 0.1f64.powi(3) / 6.0).abs() < 1e-12);
    }

    #[test]
    fn ascii_with_a_bare_solid_line_and_capitals_reads() {
        let mut s = String::from("SOLID\n");
        for f in tetra() {
            s += "  FACET NORMAL 0 0 0\n    OUTER LOOP\n";
            for v in f {
                s += &format!("      VERTEX {:E} {} {}\n", v[0], v[1], v[2]);
            }
            s += "    ENDLOOP\n  ENDFACET\n";
        }
        s += "ENDSOLID\n";
        let m = read_stl(s.as_bytes(), 0.001).unwrap();
        assert_eq!(m.vertices().len(), 4);
        assert_eq!(m.vertices()[3], [0.0, 0.0, 0.1 * 0.001]);
    }

    #[test]
    fn negative_zero_merges_and_bad_input_is_refused() {
        let mut f = tetra();
        f[3][0][1] = -0.0; // vertex 1 written as (0.1, −0, 0)
        let m = read_stl(&binary(&f, b""), 1.0).unwrap();
        assert_eq!(m.vertices().len(), 4);
        assert!(matches!(
            read_stl(&binary(&f[..3], b""), 1.0),
            Err(ImportError::Surface(MeshDefect::TooFewTriangles {
                count: 3
            }))
        ));
        f[2][1][0] = f32::NAN;
        assert!(matches!(
            read_stl(&binary(&f, b""), 1.0),
            Err(ImportError::NonFinite { facet: 2 })
        ));
        assert!(matches!(
            read_stl(&binary(&[], b""), 1.0),
            Err(ImportError::Empty)
        ));
        assert!(matches!(
            read_stl(b"hello", 1.0),
            Err(ImportError::Parse(_))
        ));
        assert!(matches!(
            read_stl(&binary(&tetra(), b""), 0.0),
            Err(ImportError::Scale(_))
        ));
    }

    #[test]
    fn the_json_is_a_region() {
        let m = read_stl(&binary(&tetra(), b""), 1.0).unwrap();
        let v: serde_json::Value = serde_json::from_str(&region_json(&m)).unwrap();
        let r: fracture_api::scene3::Region3 = serde_json::from_value(v).unwrap();
        assert!(r.contains([0.01, 0.01, 0.01]));
        assert!(!r.contains([0.05, 0.05, 0.05]));
    }
}
