//! A model as robot-description formats (MJCF, URDF) describe it, rigid bodies in a tree joined
//! by joints, and how it becomes a [`CadModel`] in the canonical frame.
//!
//! The readers produce a [`BodyTree`] in the file's frame and units. [`canonical_model`] then
//! welds the bodies no joint moves to their parents (a model's parts are what moves), turns the
//! model about z so that its moving parts face -y (the canonical front), scales it uniformly and
//! puts its origin at the bottom centre of its box with every joint at zero. Each part's mesh is
//! the body's convex collision pieces, which is what contact queries, colliders and mass
//! properties downstream take a part's connected pieces to be.

use glam::{Affine3A, Mat3, Vec3};

use crate::base::{InvalidValue, JointKind, JointSpec};
use crate::cad::model::{CadModel, CadPart};
use crate::classes::ClassTable;
use crate::geometry::TriMesh;

/// Colour of a part whose bodies name none (linear RGB).
const DEFAULT_COLOR: [f32; 3] = [0.6, 0.6, 0.6];

/// One rigid body of a model file.
#[derive(Clone, Debug)]
pub struct Body {
    pub name: String,
    /// Index of the parent body; `None` for the root (index 0), whose frame is the model's.
    pub parent: Option<usize>,
    /// The body's frame in its parent's at every joint value zero (a rigid transform).
    pub parent_from_body: Affine3A,
    /// The joint that moves it relative to its parent; `None` when it is welded to it.
    pub joint: Option<BodyJoint>,
    /// Convex collision pieces in the body's frame.
    pub pieces: Vec<TriMesh>,
    /// Convex hulls of its visual-only geometry: the shape where the collision geometry leaves
    /// it out (a table whose file gives only its top a collision box).
    pub visual_pieces: Vec<TriMesh>,
    /// Its visual geometry as the file gives it (not hulls), in the body's frame; empty when
    /// it has none, and then its collision pieces are what it looks like.
    pub visual_meshes: Vec<TriMesh>,
    /// Colours of its visual geometry (linear RGB) with their surface areas.
    pub colors: Vec<([f32; 3], f32)>,
}

/// A revolute or prismatic joint of a body.
#[derive(Clone, Debug, PartialEq)]
pub struct BodyJoint {
    pub name: String,
    /// Revolute or prismatic.
    pub kind: JointKind,
    /// Where the joint's axis passes, in the body's frame.
    pub origin: Vec3,
    /// Unit axis in the body's frame.
    pub axis: Vec3,
    /// Radians or file units.
    pub limits: (f32, f32),
}

/// One model of a file: its name (the file's `model` or `robot` name, else the file's stem) and
/// its bodies, a parent before its children.
#[derive(Clone, Debug, Default)]
pub struct BodyTree {
    pub name: String,
    pub bodies: Vec<Body>,
}

/// The most bodies a model file may have: furniture has a few, a robot arm tens.
pub const MAX_BODIES: usize = 512;
/// The longest chain of bodies from a model's root.
pub const MAX_CHAIN: usize = 64;
/// The deepest nesting of elements in a model file (an MJCF body chain of [`MAX_CHAIN`] sits
/// a few levels down).
pub const MAX_XML_DEPTH: usize = MAX_CHAIN + 16;

impl BodyTree {
    /// Refuses a model past [`MAX_BODIES`] or [`MAX_CHAIN`], before anything walks it.
    pub fn check_size(&self) -> Result<(), ModelFileError> {
        if self.bodies.len() > MAX_BODIES {
            return Err(ModelFileError::Malformed(format!(
                "{} bodies, more than the {MAX_BODIES} a model may have",
                self.bodies.len()
            )));
        }
        let mut depth = vec![0usize; self.bodies.len()];
        for (i, body) in self.bodies.iter().enumerate() {
            if let Some(parent) = body.parent.filter(|&p| p < i) {
                depth[i] = depth[parent] + 1;
                if depth[i] > MAX_CHAIN {
                    return Err(ModelFileError::Malformed(format!(
                        "body {:?} is {} joints from the root, more than {MAX_CHAIN}",
                        body.name, depth[i]
                    )));
                }
            }
        }
        Ok(())
    }
}

/// Refuses XML nested deeper than [`MAX_XML_DEPTH`]: readers that recurse (serde's, ours) would
/// run out of stack on it.
pub fn check_xml_depth(document: &roxmltree::Document) -> Result<(), ModelFileError> {
    let mut depth = vec![0usize; document.descendants().count() + 1];
    for node in document.descendants() {
        let d = node
            .parent()
            .map_or(0, |p| depth[p.id().get() as usize] + 1);
        if d > MAX_XML_DEPTH {
            return Err(ModelFileError::Malformed(format!(
                "elements nested {d} deep at line {}, deeper than {MAX_XML_DEPTH}",
                document.text_pos_at(node.range().start).row
            )));
        }
        depth[node.id().get() as usize] = d;
    }
    Ok(())
}

/// How an imported model is sized.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ImportScale {
    /// Uniformly, to its class's typical size (assets/classes.json): LIBERO's objects are made
    /// for a tabletop (a 25 cm fridge), a room needs them at furniture size.
    Class,
    /// By this factor from the file's units (1: the file is in metres).
    Factor(f32),
}

/// Why a model file could not be read.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ModelFileError {
    /// The file is broken: not XML, a bad number, a missing mesh file.
    #[error("{0}")]
    Malformed(String),
    /// A valid model using what this reader does not read.
    #[error("{0}")]
    Unsupported(String),
}

impl From<String> for ModelFileError {
    fn from(problem: String) -> Self {
        Self::Malformed(problem)
    }
}

impl From<InvalidValue> for ModelFileError {
    fn from(problem: InvalidValue) -> Self {
        Self::Malformed(problem.to_string())
    }
}

impl From<&str> for ModelFileError {
    fn from(problem: &str) -> Self {
        Self::Malformed(problem.to_string())
    }
}

/// Why a file's body tree makes no model; the import skips the file and lists it with this.
#[derive(Debug, thiserror::Error)]
pub enum UnusableModel {
    #[error("the model has no collision geometry")]
    NoCollisionGeometry,
    #[error("the model is flat ({0})")]
    Flat(Vec3),
    #[error("no class {0:?} in assets/classes.json")]
    UnknownClass(String),
    #[error("scale {0} is not a positive number")]
    BadScale(f32),
    #[error("no vertices")]
    NoVertices,
    #[error("body {0:?} comes before its parent")]
    BeforeItsParent(String),
    #[error("joint {name:?} is {kind:?}")]
    UnsupportedJoint { name: String, kind: JointKind },
    #[error("part {0:?} has no geometry")]
    EmptyPart(String),
}

/// A part being assembled: the bodies welded into it and its frame in the file's model frame.
struct PartDraft {
    name: String,
    parent: Option<usize>,
    model_from_part: Affine3A,
    joint: JointSpec,
    mesh: TriMesh,
    visual_pieces: Vec<TriMesh>,
    /// What its bodies look like (their visual meshes, else their collision pieces).
    visual: TriMesh,
    colors: Vec<([f32; 3], f32)>,
}

/// The tree as a model `id` of `class` in the canonical frame.
pub fn canonical_model(
    tree: &BodyTree,
    id: &str,
    class: &str,
    scale: ImportScale,
) -> Result<CadModel, UnusableModel> {
    let drafts = welded_parts(tree)?;
    let closed_mesh = |drafts: &[PartDraft]| {
        let mut mesh = TriMesh::default();
        for d in drafts {
            mesh.append(&d.mesh.transformed(&d.model_from_part));
        }
        mesh
    };
    let (min, max) = closed_mesh(&drafts)
        .bounds()
        .ok_or(UnusableModel::NoCollisionGeometry)?;
    let turn = Mat3::from_rotation_z(front_turn(&drafts, (min + max) / 2.0));
    let turned_extent = (turn * (max - min)).abs();
    if turned_extent.min_element() <= 0.0 {
        return Err(UnusableModel::Flat(turned_extent));
    }
    let factor = match scale {
        ImportScale::Factor(f) => f,
        ImportScale::Class => {
            let typical = ClassTable::builtin()
                .get(class)
                .ok_or_else(|| UnusableModel::UnknownClass(class.to_string()))?
                .size;
            // The geometric mean of the per-axis ratios keeps the model's proportions.
            geometric_mean(typical / turned_extent)
        }
    };
    if !(factor.is_finite() && factor > 0.0) {
        return Err(UnusableModel::BadScale(factor));
    }
    // A rotation about z and a uniform scale commute: frames turn, their offsets and the meshes
    // scale, and every frame stays rigid.
    let mut drafts = drafts;
    for d in &mut drafts {
        let rotation = turn * Mat3::from(d.model_from_part.matrix3);
        let translation = turn * Vec3::from(d.model_from_part.translation) * factor;
        d.model_from_part = Affine3A::from_mat3_translation(rotation, translation);
        d.mesh = d
            .mesh
            .transformed(&Affine3A::from_scale(Vec3::splat(factor)));
        d.visual = d
            .visual
            .transformed(&Affine3A::from_scale(Vec3::splat(factor)));
        if d.joint.kind == JointKind::Prismatic {
            d.joint.limits = d.joint.limits.map(|(lo, hi)| (lo * factor, hi * factor));
        }
    }
    let (min, max) = closed_mesh(&drafts)
        .bounds()
        .ok_or(UnusableModel::NoVertices)?;
    let bottom_centre = Vec3::new((min.x + max.x) / 2.0, (min.y + max.y) / 2.0, min.z);
    for d in &mut drafts {
        d.model_from_part.translation -= glam::Vec3A::from(bottom_centre);
    }
    // The root part's frame is the model's: its mesh takes its frame, its children's offsets
    // are then relative to the model.
    let root_frame = drafts[0].model_from_part;
    drafts[0].mesh = drafts[0].mesh.transformed(&root_frame);
    drafts[0].visual = drafts[0].visual.transformed(&root_frame);
    drafts[0].model_from_part = Affine3A::IDENTITY;
    let parts = drafts
        .iter()
        .map(|d| CadPart {
            name: d.name.clone(),
            parent: d.parent,
            parent_from_part: d
                .parent
                .map_or(Affine3A::IDENTITY, |p| drafts[p].model_from_part.inverse())
                * d.model_from_part,
            joint: d.joint,
            mesh: d.mesh.clone(),
            visual: (d.visual != d.mesh).then(|| d.visual.clone()),
            color: mean_color(&d.colors),
        })
        .collect();
    Ok(CadModel {
        id: id.to_string(),
        class: class.to_string(),
        size: max - min,
        parts,
    })
}

/// The share of the volume of `piece`'s box inside the box `(min, max)`.
fn share_inside(piece: &TriMesh, (min, max): (Vec3, Vec3)) -> f32 {
    let Some((pmin, pmax)) = piece.bounds() else {
        return 1.0;
    };
    let volume = (pmax - pmin).element_product();
    let overlap = (pmax.min(max) - pmin.max(min))
        .max(Vec3::ZERO)
        .element_product();
    if volume > 0.0 { overlap / volume } else { 1.0 }
}

fn geometric_mean(v: Vec3) -> f32 {
    (v.x * v.y * v.z).cbrt()
}

/// Bodies welded into parts: the root and every body with a joint start a part, the others join
/// their parent's. Part frames are at the joint's origin.
fn welded_parts(tree: &BodyTree) -> Result<Vec<PartDraft>, UnusableModel> {
    let mut drafts: Vec<PartDraft> = Vec::new();
    // Per body: its frame in the model, and the part it belongs to.
    let mut model_from_body: Vec<Affine3A> = Vec::with_capacity(tree.bodies.len());
    let mut part_of_body: Vec<usize> = Vec::with_capacity(tree.bodies.len());
    let mut names: Vec<String> = Vec::new();
    for (index, body) in tree.bodies.iter().enumerate() {
        let parent_frame = match body.parent {
            None if index == 0 => Affine3A::IDENTITY,
            Some(p) if p < index => model_from_body[p],
            _ => return Err(UnusableModel::BeforeItsParent(body.name.clone())),
        };
        let frame = parent_frame * body.parent_from_body;
        model_from_body.push(frame);
        let part = match (&body.joint, body.parent) {
            (Some(joint), Some(parent_body)) => {
                let name = unique_name(&mut names, &part_name(&body.name, &joint.name));
                let joint_spec = match joint.kind {
                    JointKind::Revolute => {
                        JointSpec::revolute(joint.axis, joint.limits.0, joint.limits.1)
                    }
                    JointKind::Prismatic => {
                        JointSpec::prismatic(joint.axis, joint.limits.0, joint.limits.1)
                    }
                    kind => {
                        return Err(UnusableModel::UnsupportedJoint {
                            name: joint.name.clone(),
                            kind,
                        });
                    }
                };
                drafts.push(PartDraft {
                    name,
                    parent: Some(part_of_body[parent_body]),
                    model_from_part: frame * Affine3A::from_translation(joint.origin),
                    joint: joint_spec,
                    mesh: TriMesh::default(),
                    visual_pieces: Vec::new(),
                    visual: TriMesh::default(),
                    colors: Vec::new(),
                });
                drafts.len() - 1
            }
            (_, None) => {
                names.push("body".into());
                drafts.push(PartDraft {
                    name: "body".into(),
                    parent: None,
                    model_from_part: Affine3A::IDENTITY,
                    joint: JointSpec::FIXED,
                    mesh: TriMesh::default(),
                    visual_pieces: Vec::new(),
                    visual: TriMesh::default(),
                    colors: Vec::new(),
                });
                0
            }
            (None, Some(parent_body)) => part_of_body[parent_body],
        };
        part_of_body.push(part);
        let part_from_body = drafts[part].model_from_part.inverse() * frame;
        for piece in &body.pieces {
            drafts[part]
                .mesh
                .append(&piece.transformed(&part_from_body));
        }
        for piece in &body.visual_pieces {
            drafts[part]
                .visual_pieces
                .push(piece.transformed(&part_from_body));
        }
        let looks = if body.visual_meshes.is_empty() {
            &body.pieces
        } else {
            &body.visual_meshes
        };
        for mesh in looks {
            drafts[part]
                .visual
                .append(&mesh.transformed(&part_from_body));
        }
        drafts[part].colors.extend_from_slice(&body.colors);
    }
    for d in &mut drafts {
        // Visual geometry inside the collision geometry's box is detail of what the collision
        // pieces already are (a handle, a door's panel); geometry mostly outside it is shape the
        // file left out of its collision geometry (a table's legs).
        let collision_box = d.mesh.bounds();
        for piece in std::mem::take(&mut d.visual_pieces) {
            if collision_box.is_none_or(|b| share_inside(&piece, b) < 0.5) {
                d.mesh.append(&piece);
            }
        }
    }
    if let Some(empty) = drafts.iter().find(|d| d.mesh.is_empty()) {
        return Err(UnusableModel::EmptyPart(empty.name.clone()));
    }
    Ok(drafts)
}

/// A part's name from its body's (or, without one, its joint's) in lowercase letters, digits
/// and underscores.
fn part_name(body: &str, joint: &str) -> String {
    let source = if body.is_empty() { joint } else { body };
    let name: String = source
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '_'
            }
        })
        .collect();
    if name.is_empty() { "part".into() } else { name }
}

/// `name`, or `name_2`, `name_3`... when it is taken; recorded as taken.
fn unique_name(taken: &mut Vec<String>, name: &str) -> String {
    let mut candidate = name.to_string();
    let mut n = 2;
    while taken.contains(&candidate) {
        candidate = format!("{name}_{n}");
        n += 1;
    }
    taken.push(candidate.clone());
    candidate
}

/// The turn about z (a multiple of 90 degrees) that brings the side the moving parts are on to
/// -y: doors and drawers are on a model's front. Zero for a model without moving parts or
/// whose moving parts sit in its middle.
fn front_turn(drafts: &[PartDraft], centre: Vec3) -> f32 {
    let mut side = Vec3::ZERO;
    for d in drafts.iter().filter(|d| d.joint.limits.is_some()) {
        let mesh = d.mesh.transformed(&d.model_from_part);
        if let Some((min, max)) = mesh.bounds() {
            let offset = (min + max) / 2.0 - centre;
            side += Vec3::new(offset.x, offset.y, 0.0);
        }
    }
    if side.length() < 1e-6 {
        return 0.0;
    }
    // The side as an angle from -y, snapped to a quarter turn; turning by minus that angle
    // brings it to -y.
    let angle = side.x.atan2(-side.y);
    let quarters = (angle / std::f32::consts::FRAC_PI_2).round();
    -quarters * std::f32::consts::FRAC_PI_2
}

fn mean_color(colors: &[([f32; 3], f32)]) -> [f32; 3] {
    let weight: f32 = colors.iter().map(|(_, w)| w).sum();
    if weight <= 0.0 {
        return DEFAULT_COLOR;
    }
    let sum = colors
        .iter()
        .fold(Vec3::ZERO, |acc, (c, w)| acc + Vec3::from(*c) * *w);
    (sum / weight).clamp(Vec3::ZERO, Vec3::ONE).to_array()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cabinet drawn facing +x: a 0.4 x 0.6 x 0.8 body and a door hinged on its +x face.
    fn cabinet_facing_x() -> BodyTree {
        let body = Body {
            name: "carcass".into(),
            parent: None,
            parent_from_body: Affine3A::IDENTITY,
            joint: None,
            pieces: vec![TriMesh::cuboid(
                Vec3::new(-0.2, -0.3, 0.1),
                Vec3::new(0.2, 0.3, 0.9),
            )],
            visual_pieces: Vec::new(),
            visual_meshes: Vec::new(),
            colors: vec![([1.0, 0.0, 0.0], 1.0)],
        };
        let door = Body {
            name: "door".into(),
            parent: Some(0),
            parent_from_body: Affine3A::from_translation(Vec3::new(0.2, 0.0, 0.0)),
            joint: Some(BodyJoint {
                name: "hinge".into(),
                kind: JointKind::Revolute,
                origin: Vec3::new(0.0, -0.3, 0.0),
                axis: Vec3::Z,
                // Negative turns swing the door out of the +x face.
                limits: (-1.5, 0.0),
            }),
            pieces: vec![TriMesh::cuboid(
                Vec3::new(0.0, -0.3, 0.1),
                Vec3::new(0.02, 0.3, 0.9),
            )],
            visual_pieces: Vec::new(),
            visual_meshes: Vec::new(),
            colors: Vec::new(),
        };
        BodyTree {
            name: "cabinet".into(),
            bodies: vec![body, door],
        }
    }

    #[test]
    fn the_moving_parts_end_up_in_front_at_the_origin() {
        let model = canonical_model(
            &cabinet_facing_x(),
            "mjcf_cabinet",
            "cabinet",
            ImportScale::Factor(2.0),
        )
        .expect("model");
        // Turned a quarter: the door (at +x) is now at -y; scaled by 2.
        assert!((model.size - Vec3::new(1.2, 0.84, 1.6)).abs().max_element() < 1e-5);
        let mesh = model.merged_mesh(&[]);
        let (min, max) = mesh.bounds().expect("bounds");
        assert!(min.z.abs() < 1e-5 && (min.x + max.x).abs() < 1e-5);
        let door = &model.parts[1];
        assert_eq!(door.name, "door");
        assert_eq!(door.joint.kind, JointKind::Revolute);
        let door_box = door.mesh.transformed(&model.model_from_parts(&[])[1]);
        let (dmin, _) = door_box.bounds().expect("door");
        assert!((dmin.y - min.y).abs() < 1e-5, "the door is the front");
        // The hinge is at the door's edge: opening turns the door about it and moves it forward.
        let open = model.merged_mesh(&[("door".into(), -1.5)]);
        let (omin, _) = open.bounds().expect("open");
        assert!(omin.y < min.y - 0.5, "{omin} vs {min}");
        assert_eq!(model.parts[0].color, [1.0, 0.0, 0.0]);
        assert_eq!(door.color, DEFAULT_COLOR);
    }

    #[test]
    fn class_scale_brings_the_model_to_its_class_size() {
        let model = canonical_model(
            &cabinet_facing_x(),
            "mjcf_cabinet",
            "cabinet",
            ImportScale::Class,
        )
        .expect("model");
        let typical = ClassTable::builtin().get("cabinet").expect("cabinet").size;
        let ratio = typical / model.size;
        assert!((geometric_mean(ratio) - 1.0).abs() < 1e-4, "{ratio}");
        // Uniform: the proportions are the file's.
        assert!((model.size.z / model.size.x - 0.8 / 0.6).abs() < 1e-4);
    }

    #[test]
    fn prismatic_limits_scale_with_the_model() {
        let mut tree = cabinet_facing_x();
        tree.bodies[1].joint = Some(BodyJoint {
            name: "slide".into(),
            kind: JointKind::Prismatic,
            origin: Vec3::ZERO,
            axis: Vec3::X,
            limits: (0.0, 0.3),
        });
        let model = canonical_model(&tree, "m", "cabinet", ImportScale::Factor(3.0)).expect("m");
        let (lo, hi) = model.parts[1].joint.limits.expect("limits");
        assert!(lo == 0.0 && (hi - 0.9).abs() < 1e-5);
        // The axis turned with the model's frame: the drawer pulls out towards -y.
        let pulled = model.model_from_parts(&[("door".into(), 0.9)])[1].translation;
        let closed = model.model_from_parts(&[])[1].translation;
        assert!((pulled - closed).y < -0.89, "{pulled} {closed}");
    }
}
