//! Builds a `SceneWorld` from a validated specification: picks models, sizes them, and stands each
//! object on the floor, on its parent's top, inside its container, or on its wall.

use std::collections::HashMap;
use std::path::Path;

use glam::{Affine3A, Quat, Vec3};

use crate::cad::ParametricLibrary;
use crate::classes::ClassTable;
use crate::error::InputError;
use crate::scene::overlap::{MAX_OVERLAP_M, deepest_overlap};
use crate::scene::spec::{ModelSource, Placement, SceneSpec};
use crate::scene::world::{
    FIRST_OBJECT_INSTANCE, PlacedObject, SceneWorld, Support, wall_frame, wall_length, yaw_facing,
};

/// How far into a container's height the search for its inner floor starts (below the top board).
const INSIDE_PROBE_HEIGHT: f32 = 0.6;

impl SceneWorld {
    /// The world of `spec`. `source` names the specification file in errors.
    pub fn from_spec(spec: &SceneSpec, source: &Path) -> Result<SceneWorld, InputError> {
        let room = Vec3::from_array(spec.room.size);
        let err = |i: usize, problem: String| {
            InputError::invalid(source, format!("objects[{i}].{problem}"))
        };
        let order = support_order(spec);
        let mut placed: Vec<Option<PlacedObject>> = vec![None; spec.objects.len()];
        let index: HashMap<&str, usize> = spec
            .objects
            .iter()
            .enumerate()
            .map(|(i, o)| (o.id.as_str(), i))
            .collect();
        for i in order {
            let o = &spec.objects[i];
            let source = match &o.model {
                Some(m) => spec.model_source(m),
                None => {
                    let variants: Vec<_> = ParametricLibrary::variants(&o.class).collect();
                    variants
                        .get(
                            (crate::base::stable_hash(spec.seed, &o.id)
                                % variants.len().max(1) as u64)
                                as usize,
                        )
                        .map(|e| ModelSource::Parametric(e))
                }
            }
            .ok_or_else(|| err(i, format!("class: no CAD model for class {:?}", o.class)))?;
            let model = source.build(o.size.map(Vec3::from_array));
            for name in o.joints.keys() {
                if !model.movable_parts().any(|p| &p.name == name) {
                    let movable: Vec<_> = model.movable_parts().map(|p| p.name.as_str()).collect();
                    let has = if movable.is_empty() {
                        "it has no joints".to_string()
                    } else {
                        format!("it has: {}", movable.join(", "))
                    };
                    return Err(err(
                        i,
                        format!(
                            "joints.{name}: model {} has no such moving part ({has})",
                            model.id
                        ),
                    ));
                }
            }
            let joint_values: Vec<(String, f32)> =
                o.joints.iter().map(|(k, v)| (k.clone(), *v)).collect();
            let placement = spec.placement(i).map_err(|e| err(i, e.to_string()))?;
            let parent_of = |id: &str| {
                index
                    .get(id)
                    .and_then(|&p| placed[p].as_ref())
                    .map(|p| (index[id], p))
            };
            let (support, yaw, position) = match placement {
                Placement::Floor { x, y } => (
                    Support::Floor,
                    o.yaw_deg.unwrap_or(0.0).to_radians(),
                    Vec3::new(x, y, 0.0),
                ),
                Placement::OnObject { parent, offset } => {
                    let Some((p, parent)) = parent_of(&parent) else {
                        return Err(err(i, format!("on: {parent:?} is not placed")));
                    };
                    let b = parent.closed_box();
                    let top = b.world_from_box().transform_point3(Vec3::new(
                        offset[0],
                        offset[1],
                        0.5 * b.size.z,
                    ));
                    if offset[0].abs() > 0.5 * b.size.x || offset[1].abs() > 0.5 * b.size.y {
                        return Err(err(
                            i,
                            format!(
                                "offset: {offset:?} is off the top of {} ({:.2} x {:.2} m)",
                                parent.id, b.size.x, b.size.y
                            ),
                        ));
                    }
                    // The top of the box is a surface only where the parent has one there (a
                    // chair's box top is its backrest, an open door's is air).
                    let surface = surface_below(&parent.world_mesh(), top + Vec3::Z * ON_TOLERANCE);
                    if surface.is_none_or(|z| (z - top.z).abs() > ON_TOLERANCE) {
                        return Err(err(
                            i,
                            format!(
                                "offset: {} has no top surface under {offset:?} to stand on",
                                parent.id
                            ),
                        ));
                    }
                    (
                        Support::OnObject(p),
                        o.yaw_deg.map_or(parent.yaw, f32::to_radians),
                        top,
                    )
                }
                Placement::InObject { parent, offset } => {
                    let Some((p, parent)) = parent_of(&parent) else {
                        return Err(err(i, format!("in: {parent:?} is not placed")));
                    };
                    let b = parent.gravity_box();
                    let start = parent.world_from_model.transform_point3(Vec3::new(
                        offset[0],
                        offset[1],
                        INSIDE_PROBE_HEIGHT * b.size.z,
                    ));
                    let Some(z) = surface_below(&parent.world_mesh(), start) else {
                        return Err(err(
                            i,
                            format!("in: {} has no inner surface under {offset:?}", parent.id),
                        ));
                    };
                    (
                        Support::InObject(p),
                        o.yaw_deg.map_or(parent.yaw, f32::to_radians),
                        Vec3::new(start.x, start.y, z),
                    )
                }
                Placement::OnWall {
                    wall,
                    along,
                    height,
                } => {
                    let (start, dir, inward) = wall_frame(room, wall);
                    let length = wall_length(room, wall);
                    if along - 0.5 * model.size.x < 0.0 || along + 0.5 * model.size.x > length {
                        return Err(err(
                            i,
                            format!(
                                "offset: {along} m along wall_{wall} puts the object past the wall's ends (0..{length} m)"
                            ),
                        ));
                    }
                    let p = start + dir * along + inward * (0.5 * model.size.y) + Vec3::Z * height;
                    (Support::Wall(wall), yaw_facing(inward), p)
                }
            };
            let world_from_model =
                Affine3A::from_rotation_translation(Quat::from_rotation_z(yaw), position);
            let kind = ClassTable::builtin()
                .get(&o.class)
                .map(|c| c.kind)
                .ok_or_else(|| err(i, format!("class: unknown {:?}", o.class)))?;
            let object = PlacedObject {
                id: o.id.clone(),
                class: o.class.clone(),
                kind,
                instance: FIRST_OBJECT_INSTANCE + i as u16,
                model,
                world_from_model,
                yaw,
                joint_values,
                support,
            };
            let b = object.gravity_box();
            let inside = b.corners().iter().all(|c| {
                c.x >= -0.01
                    && c.y >= -0.01
                    && c.x <= room.x + 0.01
                    && c.y <= room.y + 0.01
                    && c.z <= room.z + 0.01
            });
            if !inside {
                return Err(err(
                    i,
                    format!(
                        "position: {} ({} at {:.2?}, {:.2?} m) does not fit inside the room",
                        o.id, object.model.id, b.center, b.size
                    ),
                ));
            }
            placed[i] = Some(object);
        }
        let objects = placed.into_iter().flatten().collect::<Vec<_>>();
        let world = SceneWorld {
            name: spec.name.clone(),
            seed: spec.seed,
            room_size: room,
            layout: SceneWorld::room_layout(room),
            objects,
        };
        if let Some(o) = deepest_overlap(&world) {
            return Err(InputError::invalid(
                source,
                format!(
                    "objects[{}] {:?} and objects[{}] {:?} overlap by {:.1} mm (at most {:.0} mm is allowed)",
                    o.a,
                    world.objects[o.a].id,
                    o.b,
                    world.objects[o.b].id,
                    1000.0 * o.depth,
                    1000.0 * MAX_OVERLAP_M
                ),
            ));
        }
        Ok(world)
    }
}

/// Object indices with every parent before its children (the spec was checked to be a forest).
fn support_order(spec: &SceneSpec) -> Vec<usize> {
    let depth = |mut i: usize| {
        let mut d = 0;
        while let Some(parent) = spec.objects[i]
            .on
            .as_deref()
            .or(spec.objects[i].inside.as_deref())
        {
            match spec.objects.iter().position(|o| o.id == parent) {
                Some(p) if d < spec.objects.len() => {
                    i = p;
                    d += 1;
                }
                _ => break,
            }
        }
        d
    };
    let mut order: Vec<usize> = (0..spec.objects.len()).collect();
    order.sort_by_key(|&i| (depth(i), i));
    order
}

/// How far the surface under an object's `"on"` point may lie from its parent's box top, metres.
const ON_TOLERANCE: f32 = 0.005;

/// The height of the first upward-facing surface of `mesh` straight below `start`.
fn surface_below(mesh: &crate::geometry::TriMesh, start: Vec3) -> Option<f32> {
    let mut best: Option<f32> = None;
    for i in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.triangle(i);
        if mesh.face_normal(i).z < 0.5 {
            continue;
        }
        // Barycentric test of the start point's footprint in the triangle's projection.
        let (p, a2, b2, c2) = (start.truncate(), a.truncate(), b.truncate(), c.truncate());
        let det = (b2 - a2).perp_dot(c2 - a2);
        if det.abs() < 1e-12 {
            continue;
        }
        let u = (p - a2).perp_dot(c2 - a2) / det;
        let v = (b2 - a2).perp_dot(p - a2) / det;
        if u < 0.0 || v < 0.0 || u + v > 1.0 {
            continue;
        }
        let z = a.z + u * (b.z - a.z) + v * (c.z - a.z);
        if z <= start.z && best.is_none_or(|b| z > b) {
            best = Some(z);
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use crate::scene::{SceneSpec, SceneWorld};

    fn world(objects: &str) -> Result<SceneWorld, String> {
        let json = format!(
            r#"{{"name": "t", "seed": 1, "room": {{"size": [4, 4, 2.6]}}, "objects": [{objects}]}}"#
        );
        let path = Path::new("t.json");
        let spec = SceneSpec::parse(&json, path).map_err(|e| e.to_string())?;
        SceneWorld::from_spec(&spec, path).map_err(|e| e.to_string())
    }

    /// An open door widens the cabinet's box; what stands "on" it is measured in the closed
    /// box, so an offset over the open door is off its top, and one on the top stays put
    /// whether the door is open or not.
    #[test]
    fn on_offsets_are_measured_in_the_closed_parent() {
        let cabinet = |joints: &str| {
            format!(
                r#"{{"id": "cabinet_1", "class": "cabinet", "model": "cabinet_01",
                    "position": [2, 2], "joints": {{{joints}}}}}"#
            )
        };
        let cup = |offset: &str| {
            format!(
                r#"{{"id": "cup_1", "class": "cup", "model": "cup_01", "on": "cabinet_1", "offset": {offset}}}"#
            )
        };
        let over_door = world(&format!(
            "{}, {}",
            cabinet(r#""door_left": 1.5"#),
            cup("[-0.2, -0.45]")
        ));
        let err = over_door.expect_err("over the open door");
        assert!(
            err.contains("objects[1].offset") && err.contains("off the top"),
            "{err}"
        );
        let cup_at = |joints: &str| {
            let w = world(&format!("{}, {}", cabinet(joints), cup("[-0.2, -0.1]"))).expect("valid");
            w.objects[1].world_from_model.translation
        };
        assert_eq!(cup_at(""), cup_at(r#""door_left": 1.5"#));
    }

    /// A chair's box top is its backrest: nothing stands there.
    #[test]
    fn on_needs_a_top_surface_under_the_offset() {
        let err = world(
            r#"{"id": "chair_1", "class": "chair", "model": "chair_01", "position": [2, 2]},
               {"id": "cup_1", "class": "cup", "model": "cup_01", "on": "chair_1"}"#,
        )
        .expect_err("no top under the middle of a chair's box");
        assert!(err.contains("no top surface"), "{err}");
    }
}
