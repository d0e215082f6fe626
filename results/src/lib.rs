//! The files of a run (`docs/run-output.md`), one copy of each format:
//!
//! * [`mcapfile`]: the `fields.mcap` file (writer and readers; channels in `docs/mcap.md`).
//! * [`codec`]: the binary snapshot encoding of worker uploads and the store.
//! * [`render`]: field snapshots as PNG images (colour maps, isochromatic fringes resolved
//!   between the nodes, legends with units).
//! * [`path`]: the crack-path picture (`path.svg`): every tip's x–y path over the bodies.
//! * [`vtk`]: snapshots as VTK files (ImageData grids, PolyData cracks, `.pvd` time series)
//!   for ParaView.
//!
//! This crate runs no physics: it reads and writes what the solver produced.

pub mod codec;
pub mod mcapfile;
pub mod path;
pub mod render;
pub mod vtk;
pub mod vtk3;
