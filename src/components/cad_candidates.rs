//! What the CAD stages found for an object before one model is chosen: the database's models
//! ranked for it (CadMatch), or why the shape filters kept it from replacement, and the ranked
//! models aligned to its observed surface (CadAlign). The PhysicalCheck stage chooses among the
//! alignments and gives the entity its `CadModel`.

use bevy::prelude::*;

use crate::cad::replace::alignment::Alignment;
use crate::cad::replace::matching::Candidate;
use crate::cad::replace::shape_filter::Rejection;

/// The database's models ranked for the object, best first.
#[derive(Component, Clone, Debug, Default)]
pub struct CadCandidates(pub Vec<Candidate>);

/// The shape filters found the segment to be label bleeding or several objects: it keeps its
/// segment mesh.
#[derive(Component, Clone, Debug)]
pub struct ShapeRejection(pub Rejection);

/// The candidates aligned to the object's observed surface, best first (empty where none could
/// be, or the object was rejected).
#[derive(Component, Clone, Debug, Default)]
pub struct CadAlignments(pub Vec<Alignment>);
