//! Articulated models built from what the camera saw (issue 36, section 2): when no model of
//! the database agrees with the doors and drawers perceived on an object's front, the object
//! gets a carcass of its box with a door, drawer or flap per perceived part, each with its
//! handle where it was seen and its joint on the perceived side. The model is exported, sized
//! and simulated like any other; its parts are listed with `source: "perceived"`.

use glam::{Affine3A, Mat3, Vec3};

use crate::cad::library::builder::{BOARD, DRAWER_CLEARANCE, HingeSide, PartsBuilder};
use crate::cad::model::CadModel;
use crate::geometry::{GravityBox, TriMesh};
use crate::perception::fronts::PerceivedFront;
use crate::perception::handles::{Handle, HandleKind};
use crate::perception::parts::{PartKind, Side};

/// A synthesised model's id is this prefix and the object's id: it stands for that object only.
pub const PERCEIVED_MODEL_PREFIX: &str = "perceived_";

/// Whether model `id` was built from an object's perceived parts.
pub fn is_perceived_model(id: &str) -> bool {
    id.starts_with(PERCEIVED_MODEL_PREFIX)
}

const CARCASS: [f32; 3] = [0.75, 0.74, 0.7];
const FRONT: [f32; 3] = [0.85, 0.84, 0.8];
const HANDLE: [f32; 3] = [0.6, 0.6, 0.62];

/// Gap between neighbouring fronts, metres (as the library's units).
const GAP: f32 = 0.004;
/// Parts starting this high above the floor (metres) or more stand on a plinth set back under
/// them.
const MIN_PLINTH_M: f32 = 0.03;
/// How far the plinth is set back from the fronts, metres.
const PLINTH_SETBACK_M: f32 = 0.05;
/// A handle's bar is this thick, metres, and stands out at least and at most this far.
const BAR_THICKNESS_M: f32 = 0.016;
const HANDLE_OUT_M: (f32, f32) = (0.015, 0.06);
/// Parts narrower or lower than this (metres) are not built: a handle seen at the very edge.
const MIN_PART_M: f32 = 0.08;
/// A box shallower than this (metres) holds no carcass with doors and drawers: a segment of
/// a front alone.
const MIN_DEPTH_M: f32 = 0.15;

/// The model of `class` for object `object_id`, whose closed box is `bbox` (world frame), built
/// from the parts perceived on its front `seen`, and the placement of its frame in the world
/// (`None` without parts, or for a front too small to hold them). Its frame is the canonical
/// one: front towards -y along the perceived front, +x to the right seen from the room, the
/// origin at the bottom centre of its box.
pub fn perceived_model(
    object_id: &str,
    class: &str,
    bbox: &GravityBox,
    seen: &PerceivedFront,
) -> Option<(CadModel, Affine3A)> {
    let front = &seen.front;
    let box_axes = Mat3::from_rotation_z(bbox.yaw);
    let extent_along = |dir: Vec3| {
        (box_axes.x_axis.dot(dir).abs() * bbox.size.x)
            + (box_axes.y_axis.dot(dir).abs() * bbox.size.y)
    };
    let (width, depth, height) = (
        extent_along(front.right),
        extent_along(front.normal),
        bbox.size.z,
    );
    if depth < MIN_DEPTH_M {
        return None;
    }
    let bottom = bbox.bottom_z();
    // The builder's frame: x along the front's right, y into the object, z up from the floor,
    // the origin under the box's centre.
    let builder_to_world = Affine3A::from_mat3_translation(
        Mat3::from_cols(front.right, -front.normal, Vec3::Z),
        bbox.center.with_z(bottom),
    );
    let builder_from_world = builder_to_world.inverse();
    let to_builder = |p: Vec3| builder_from_world.transform_point3(p);
    // The fronts' outer faces, at most a board behind the box's face.
    let face_y = to_builder(front.origin)
        .y
        .clamp(-0.5 * depth, 0.5 * depth - 4.0 * BOARD);
    let parts: Vec<_> = seen
        .parts
        .iter()
        .filter(|p| p.right[1] - p.right[0] >= MIN_PART_M && p.z[1] - p.z[0] >= MIN_PART_M)
        .collect();
    if parts.is_empty() || width < MIN_PART_M || height < MIN_PART_M {
        return None;
    }
    let mut b = PartsBuilder::new(CARCASS);
    let lowest = parts
        .iter()
        .map(|p| p.z[0] - bottom)
        .fold(f32::MAX, f32::min)
        .max(0.0);
    let plinth = if lowest >= MIN_PLINTH_M { lowest } else { 0.0 };
    let carcass_front = face_y + BOARD;
    b.carcass(
        Vec3::new(-0.5 * width, carcass_front, plinth),
        Vec3::new(0.5 * width, 0.5 * depth, height),
    );
    if plinth > 0.0 {
        b.slab(
            Vec3::new(-0.5 * width + BOARD, carcass_front + PLINTH_SETBACK_M, 0.0),
            Vec3::new(0.5 * width - BOARD, 0.5 * depth, plinth),
        );
    }
    let inside_depth = 0.5 * depth - BOARD - carcass_front - 0.01;
    for (k, part) in parts.iter().enumerate() {
        let x = (
            (part.right[0] + GAP).max(-0.5 * width),
            (part.right[1] - GAP).min(0.5 * width),
        );
        let z = (
            (part.z[0] - bottom + GAP).max(plinth),
            (part.z[1] - bottom - GAP).min(height),
        );
        if x.1 - x.0 < MIN_PART_M || z.1 - z.0 < MIN_PART_M {
            continue;
        }
        let index = match part.kind {
            PartKind::Door { hinge } => b.hinged_door(
                &format!("door_{k}"),
                PartsBuilder::BODY,
                x,
                z,
                carcass_front,
                match hinge {
                    Side::Left => HingeSide::Left,
                    Side::Right => HingeSide::Right,
                },
                FRONT,
                HANDLE,
            ),
            PartKind::Drawer => b.drawer(
                &format!("drawer_{k}"),
                PartsBuilder::BODY,
                x,
                z,
                carcass_front,
                (
                    0.5 * (x.1 - x.0) - BOARD - DRAWER_CLEARANCE,
                    inside_depth.max(0.1),
                ),
                FRONT,
                HANDLE,
            ),
            PartKind::Flap => b.drop_door(
                &format!("flap_{k}"),
                PartsBuilder::BODY,
                x,
                z,
                carcass_front,
                FRONT,
                HANDLE,
            ),
        };
        let handle = handle_mesh(&part.handle, &to_builder, face_y, x, z);
        b.reshape_handle(index, &handle);
    }
    let model = b.finish(&format!("{PERCEIVED_MODEL_PREFIX}{object_id}"), class);
    // `finish` centres the model on its box: the carcass's back stays the back, so the frame
    // moved by as much along y as the handles stand out of the face.
    let shift_y = 0.5 * model.size.y - 0.5 * depth;
    let world_from_model =
        builder_to_world * Affine3A::from_translation(Vec3::new(0.0, -shift_y, 0.0));
    Some((model, world_from_model))
}

/// The handle `seen` (world frame) as a box in the builder's frame on the front face `face_y`,
/// kept on its part's rectangle `x` by `z`.
fn handle_mesh(
    seen: &Handle,
    to_builder: &impl Fn(Vec3) -> Vec3,
    face_y: f32,
    x: (f32, f32),
    z: (f32, f32),
) -> TriMesh {
    let c = to_builder(seen.center);
    let out = seen.depth.clamp(HANDLE_OUT_M.0, HANDLE_OUT_M.1);
    let (across, up) = match seen.kind {
        HandleKind::Bar if seen.axis.z.abs() >= std::f32::consts::FRAC_1_SQRT_2 => {
            (BAR_THICKNESS_M, seen.length.min(z.1 - z.0 - 0.02))
        }
        HandleKind::Bar => (seen.length.min(x.1 - x.0 - 0.02), BAR_THICKNESS_M),
        HandleKind::Knob => (seen.length, seen.length),
    };
    let cx = c.x.clamp(x.0 + 0.5 * across, x.1 - 0.5 * across);
    let cz = c.z.clamp(z.0 + 0.5 * up, z.1 - 0.5 * up);
    TriMesh::cuboid(
        Vec3::new(cx - 0.5 * across, face_y - out, cz - 0.5 * up),
        Vec3::new(cx + 0.5 * across, face_y, cz + 0.5 * up),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::JointKind;
    use crate::perception::handles::Front;
    use crate::perception::parts::{FrontExtent, PerceivedPart};

    /// A cabinet 0.8 x 0.5 x 0.9 m turned 90 degrees (its front faces +x at x = 1.25), with a
    /// drawer over a door hinged on the right (seen from the room).
    fn seen() -> (GravityBox, PerceivedFront) {
        let bbox = GravityBox {
            center: Vec3::new(1.0, 2.0, 0.45),
            yaw: std::f32::consts::FRAC_PI_2,
            size: Vec3::new(0.8, 0.5, 0.9),
        };
        let front = Front::new(Vec3::new(1.225, 2.0, 0.45), Vec3::X).expect("front");
        let bar = |c: Vec3, axis: Vec3| Handle {
            kind: HandleKind::Bar,
            center: c,
            axis,
            length: 0.2,
            depth: 0.025,
        };
        // Seen from +x, the right is +y.
        let drawer = bar(Vec3::new(1.24, 2.0, 0.8), Vec3::Y);
        let door = bar(Vec3::new(1.24, 1.66, 0.4), Vec3::Z);
        let extent = FrontExtent {
            right: [-0.4, 0.4],
            z: [0.08, 0.9],
        };
        let parts = vec![
            PerceivedPart {
                kind: PartKind::Door { hinge: Side::Right },
                right: [-0.4, 0.4],
                z: [0.08, 0.7],
                handle: door,
            },
            PerceivedPart {
                kind: PartKind::Drawer,
                right: [-0.4, 0.4],
                z: [0.7, 0.9],
                handle: drawer,
            },
        ];
        (
            bbox,
            PerceivedFront {
                front,
                handles: vec![drawer, door],
                open_drawers: Vec::new(),
                open_doors: Vec::new(),
                extent,
                parts,
                clear: true,
            },
        )
    }

    #[test]
    fn a_perceived_drawer_over_a_door_builds_a_model_that_opens_where_they_were_seen() {
        let (bbox, front) = seen();
        let (model, world_from_model) =
            perceived_model("cabinet_3", "cabinet", &bbox, &front).expect("model");
        assert_eq!(model.id, "perceived_cabinet_3");
        assert!(is_perceived_model(&model.id));
        // The model's box is the object's (the handles stand 2.5 cm out of a face 2.5 cm in).
        assert!(
            (model.size - Vec3::new(0.8, 0.5, 0.9)).abs().max_element() < 0.01,
            "{}",
            model.size
        );
        let moving: Vec<_> = model
            .parts
            .iter()
            .filter(|p| p.joint.limits.is_some())
            .collect();
        assert_eq!(moving.len(), 2);
        let poses = model.model_from_parts(&[]);
        let world_of = |name: &str| {
            let k = model
                .parts
                .iter()
                .position(|p| p.name == name)
                .expect("part");
            world_from_model * poses[k]
        };
        // The door's hinge runs up its right edge seen from +x: the +y side of the box.
        let door = model
            .parts
            .iter()
            .find(|p| p.name == "door_0")
            .expect("door");
        assert_eq!(door.joint.kind, JointKind::Revolute);
        let hinge = world_of("door_0").translation;
        assert!(
            (hinge.y - 2.4).abs() < 0.01 && (hinge.x - 1.225).abs() < 0.03,
            "{hinge}"
        );
        // The drawer slides out along +x.
        let drawer = model
            .parts
            .iter()
            .find(|p| p.name == "drawer_1")
            .expect("drawer");
        assert_eq!(drawer.joint.kind, JointKind::Prismatic);
        let slide = world_of("drawer_1").transform_vector3(drawer.joint.axis);
        assert!(slide.dot(Vec3::X) > 0.99, "{slide}");
        // The door's handle is where it was seen.
        let k = model
            .parts
            .iter()
            .position(|p| p.name == "door_0_handle")
            .expect("handle");
        let (lo, hi) = model.parts[k]
            .mesh
            .transformed(&(world_from_model * poses[k]))
            .bounds()
            .expect("bounds");
        let centre = 0.5 * (lo + hi);
        assert!(
            centre.distance(Vec3::new(1.2375, 1.66, 0.4)) < 0.01,
            "{centre}"
        );
    }

    #[test]
    fn a_front_without_parts_or_a_box_too_shallow_for_a_carcass_builds_nothing() {
        let (bbox, mut front) = seen();
        let shallow = GravityBox {
            size: Vec3::new(0.8, 0.047, 0.9),
            ..bbox
        };
        assert!(perceived_model("cabinet_3", "cabinet", &shallow, &front).is_none());
        front.parts.clear();
        assert!(perceived_model("cabinet_3", "cabinet", &bbox, &front).is_none());
    }
}
