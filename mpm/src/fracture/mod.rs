//! The dimension-free fracture laws (`three-d.md`, shape of the code): the stick change of
//! two velocity fields and the contact law, the cohesive bond and process-zone laws, the
//! growth law (Freund's equation of motion), the tip mechanics (A(v), Williams fields, kink
//! criteria) and the J domain weights. The crack layers apply them: the 2D solver's
//! (`fracture-solver`) today, the 3D fronts' next.

pub mod cohesive;
pub mod contact;
pub mod domain;
pub mod growth;
pub mod tip_mechanics;
pub mod zone;
