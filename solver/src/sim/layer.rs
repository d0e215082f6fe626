//! The crack layer on the core's step (`fracture_mpm::layer`): the 2D cracks' velocity
//! fields before the P2G (§3), contact at each momentum stage (§4) with the process-zone and
//! cohesive forces at the force stage and the bonded points' hold after re-extrapolation,
//! the surfaces' motion before pass 4 (§5), and growth after the step (§7).

use fracture_api::scene::Damping;
use fracture_mpm::layer::{Hook, Layer};
use fracture_mpm::state::{Model, Scratch};
use fracture_mpm::{Dim2, StepError};
use serde::{Deserialize, Serialize};

use crate::crack::{Cracks, Stage, View};
use crate::particles::Particles;

/// The 2D crack layer: the scene's cracks, interfaces and contact bodies (None: a plain
/// continuum scene, whose step then does nothing more than the core's). Serialized as the
/// `Option` itself, so 2D checkpoints keep their bytes.
#[derive(Serialize, Deserialize)]
#[serde(transparent)]
pub struct CrackLayer(pub Option<Box<Cracks>>);

/// The read-only view of the crack code over the core's model, particles and grid.
pub(crate) fn view<'a>(
    model: &'a Model<Dim2>,
    parts: &'a Particles,
    strip_bounds: &'a [usize],
    scratch: &'a Scratch<Dim2>,
) -> View<'a> {
    View {
        geom: &model.geom,
        shape: model.shape,
        parts,
        mats: &model.mats,
        nodes: &scratch.nodes,
        f1: &scratch.f1,
        slot_of: &scratch.slot_of,
        strip_bounds,
        viscous_damping: match model.damping {
            Damping::Viscous { coefficient } => coefficient,
            _ => 0.0,
        },
        m_tiny: model.m_tiny,
    }
}

impl Layer<Dim2> for CrackLayer {
    fn multi_field(&self) -> bool {
        self.0.is_some()
    }

    fn fields(&mut self, cx: Hook<'_, Dim2>) -> Result<(), StepError> {
        let Some(cr) = self.0.as_mut() else {
            return Ok(());
        };
        cx.counters.crack_field_passes += 1;
        let (m, p) = (cx.model, &mut *cx.parts);
        cr.assign_fields(
            &m.geom,
            m.shape,
            &p.kin,
            &p.mech,
            &p.cold,
            &mut p.fmask,
            &mut cx.scratch.f1_index,
        )
        .map_err(|(idx, fields)| {
            let (ix, iy) = m.geom.node_xy(idx);
            let x = m.geom.pos(ix, iy);
            StepError::TooManyFields {
                step: cx.steps + 1,
                position: [x[0], x[1], 0.0],
                dims: 2,
                fields,
                max: 2,
            }
        })
    }

    fn stage(&mut self, stage: Stage, cx: Hook<'_, Dim2>) {
        let Some(cr) = self.0.as_mut() else {
            return;
        };
        let (m, sc) = (cx.model, &mut *cx.scratch);
        match stage {
            // Process-zone and cohesive tractions behind tips (`crack/zone.rs`), before the
            // force-stage contact; their work is dissipated (fracture energy).
            Stage::Forces => {
                cx.ledger.dissipated +=
                    cr.zone_forces(&m.geom, &mut sc.nodes, &mut sc.f1, &sc.slot_of, m.dt);
            }
            // Rigid bonded interface points hold their re-extrapolated momenta together.
            Stage::Reextrapolated => {
                cr.bond_hold(&m.geom, &mut sc.nodes, &mut sc.f1, &sc.slot_of);
            }
            Stage::Extrapolated => {}
        }
        cx.counters.contact_passes += 1;
        cx.ledger.dissipated += cr.contact(
            stage,
            &mut sc.nodes,
            &mut sc.f1,
            &sc.f1_index,
            m.m_tiny,
            m.dt,
        );
    }

    fn surfaces(&mut self, cx: Hook<'_, Dim2>) {
        let Some(cr) = self.0.as_mut() else {
            return;
        };
        cx.counters.surface_moves += 1;
        let (m, sc) = (cx.model, &*cx.scratch);
        cr.move_surfaces(&m.geom, &sc.nodes, &sc.f1, &sc.slot_of, m.m_tiny, m.dt);
    }

    fn after_step(&mut self, cx: Hook<'_, Dim2>) -> Result<bool, StepError> {
        let Some(cr) = self.0.as_mut() else {
            return Ok(false);
        };
        cx.counters.propagation_checks += 1;
        let v = view(cx.model, cx.parts, cx.strip_bounds, cx.scratch);
        Ok(cr.propagate(&v, cx.time))
    }

    fn adopt(&mut self, saved: CrackLayer) -> Result<(), String> {
        match (saved.0, self.0.as_deref()) {
            (Some(mut c), Some(fresh)) => {
                c.adopt_scene(fresh)?;
                self.0 = Some(c);
                Ok(())
            }
            (None, None) => Ok(()),
            _ => Err("cracks in one of the checkpoint and the scene only".into()),
        }
    }
}
