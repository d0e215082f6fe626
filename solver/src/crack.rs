//! Explicit cracks (`algorithm.md` §3–§7). Placeholder while the continuum solver lands.

use fracture_api::Scene;
use fracture_api::results::CrackTipRow;
use fracture_api::scene::ShapeFunction;

use crate::grid::{GridGeom, Node};
use crate::material::Elastic;
use crate::particles::{Kin, Mech, Particles};
use crate::sim::Stage;

/// All cracks of a scene.
pub struct Cracks {}

impl Cracks {
    /// Cracks of `scene`.
    pub fn new(_scene: &Scene, _geom: &GridGeom, _mats: &[Elastic]) -> Self {
        Cracks {}
    }
    /// Assign fields; fills `f1_index` with the sorted storage indices of field-1 nodes.
    pub fn assign_fields(
        &mut self,
        _geom: &GridGeom,
        _shape: ShapeFunction,
        _kin: &[Kin],
        _mech: &[Mech],
        _fmask: &mut [u16],
        _f1_index: &mut Vec<u32>,
    ) -> Result<(), (usize, u32)> {
        Ok(())
    }
    /// Contact at multi-field nodes; returns frictional work dissipated.
    pub fn contact(
        &mut self,
        _stage: Stage,
        _nodes: &mut [Node],
        _f1: &mut [Node],
        _f1_index: &[u32],
        _m_tiny: f64,
        _dt: f64,
    ) -> f64 {
        0.0
    }
    /// Move crack surfaces.
    pub fn move_surfaces(
        &mut self,
        _geom: &GridGeom,
        _nodes: &[Node],
        _f1: &[Node],
        _slot_of: &[u32],
        _m_tiny: f64,
        _dt: f64,
    ) {
    }
    /// Propagation check; true when some tip grew.
    #[allow(clippy::too_many_arguments)]
    pub fn propagate(
        &mut self,
        _geom: &GridGeom,
        _shape: ShapeFunction,
        _parts: &Particles,
        _nodes: &[Node],
        _mats: &[Elastic],
        _time: f64,
        _dt: f64,
    ) -> bool {
        false
    }
    /// Rows for the tips.
    pub fn tip_rows(
        &mut self,
        _geom: &GridGeom,
        _shape: ShapeFunction,
        _parts: &Particles,
        _mats: &[Elastic],
        _time: f64,
        _dt: f64,
    ) -> Vec<CrackTipRow> {
        Vec::new()
    }
    /// Crack lines.
    pub fn lines(&self) -> Vec<Vec<[f64; 2]>> {
        Vec::new()
    }
}
