//! The world a scene specification describes: the room's layout and every object's CAD model,
//! pose, joint values and support. Everything the renderer and the ground truth need.

use glam::{Affine3A, Vec2, Vec3};

use crate::cad::CadModel;
use crate::classes::EntityKind;
use crate::geometry::{GravityBox, Plane, TriMesh};
use crate::render::render_scene::{RenderScene, Surface};

/// What holds an object up.
#[derive(Clone, Debug, PartialEq)]
pub enum Support {
    Floor,
    /// Standing on top of another object (index into `SceneWorld::objects`).
    OnObject(usize),
    /// Standing on an inner surface of a container.
    InObject(usize),
    /// Hung on wall `k`.
    Wall(usize),
}

/// Floor, ceiling or a wall: a flat rectangle facing into the room.
#[derive(Clone, Debug)]
pub struct LayoutEntity {
    pub id: String,
    pub class: &'static str,
    pub instance: u16,
    /// The room-facing surface, world frame.
    pub mesh: TriMesh,
    /// The surface's plane, normal into the room.
    pub plane: Plane,
    pub color: [f32; 3],
}

#[derive(Clone, Debug)]
pub struct PlacedObject {
    pub id: String,
    pub class: String,
    pub kind: EntityKind,
    pub instance: u16,
    pub model: CadModel,
    pub world_from_model: Affine3A,
    pub yaw: f32,
    pub joint_values: Vec<(String, f32)>,
    pub support: Support,
}

impl PlacedObject {
    /// Each part's world pose at the object's joint values.
    pub fn world_from_parts(&self) -> Vec<Affine3A> {
        self.model
            .model_from_parts(&self.joint_values)
            .into_iter()
            .map(|m| self.world_from_model * m)
            .collect()
    }

    /// The whole object as one mesh in the world frame.
    pub fn world_mesh(&self) -> TriMesh {
        self.model
            .merged_mesh(&self.joint_values)
            .transformed(&self.world_from_model)
    }

    /// What the camera sees of the object (imported models' visual meshes), world frame.
    pub fn world_visual_mesh(&self) -> TriMesh {
        self.model
            .merged_visual_mesh(&self.joint_values)
            .transformed(&self.world_from_model)
    }

    /// The gravity-aligned box around the object's mesh, turned by the object's yaw.
    pub fn gravity_box(&self) -> GravityBox {
        self.box_around(&self.world_mesh())
    }

    /// The box of the object with every joint closed: the frame of `"on"` offsets, which an
    /// open door or drawer does not move.
    pub fn closed_box(&self) -> GravityBox {
        self.box_around(
            &self
                .model
                .merged_mesh(&[])
                .transformed(&self.world_from_model),
        )
    }

    fn box_around(&self, mesh: &TriMesh) -> GravityBox {
        GravityBox::enclosing(&mesh.positions, self.yaw).unwrap_or(GravityBox {
            center: self.world_from_model.translation.into(),
            yaw: self.yaw,
            size: Vec3::ZERO,
        })
    }
}

/// A synthetic room with its objects.
#[derive(Clone, Debug)]
pub struct SceneWorld {
    pub name: String,
    pub seed: u64,
    /// x, y extent and height.
    pub room_size: Vec3,
    pub layout: Vec<LayoutEntity>,
    pub objects: Vec<PlacedObject>,
}

/// First instance id given to objects; 1..=6 are the floor, the ceiling and four walls.
pub const FIRST_OBJECT_INSTANCE: u16 = 7;

impl SceneWorld {
    /// Floor, ceiling and walls of a room `size.x` by `size.y`, `size.z` high.
    pub fn room_layout(size: Vec3) -> Vec<LayoutEntity> {
        let quad = |a: Vec3, b: Vec3, c: Vec3, d: Vec3| TriMesh {
            positions: vec![a, b, c, d],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        };
        let (x, y, h) = (size.x, size.y, size.z);
        let mut layout = vec![
            LayoutEntity {
                id: "floor".into(),
                class: "floor",
                instance: 1,
                mesh: quad(
                    Vec3::ZERO,
                    Vec3::new(x, 0.0, 0.0),
                    Vec3::new(x, y, 0.0),
                    Vec3::new(0.0, y, 0.0),
                ),
                plane: Plane::from_point_normal(Vec3::ZERO, Vec3::Z),
                color: [0.62, 0.58, 0.52],
            },
            LayoutEntity {
                id: "ceiling".into(),
                class: "ceiling",
                instance: 2,
                mesh: quad(
                    Vec3::new(0.0, 0.0, h),
                    Vec3::new(0.0, y, h),
                    Vec3::new(x, y, h),
                    Vec3::new(x, 0.0, h),
                ),
                plane: Plane::from_point_normal(Vec3::new(0.0, 0.0, h), -Vec3::Z),
                color: [0.93, 0.93, 0.92],
            },
        ];
        for k in 0..4 {
            let (start, along, _) = wall_frame(size, k);
            let end = start + along * wall_length(size, k);
            let up = Vec3::new(0.0, 0.0, h);
            layout.push(LayoutEntity {
                id: format!("wall_{k}"),
                class: "wall",
                instance: 3 + k as u16,
                mesh: quad(start, start + up, end + up, end),
                plane: Plane::from_point_normal(start, wall_frame(size, k).2),
                color: [
                    [0.86, 0.84, 0.78],
                    [0.8, 0.83, 0.86],
                    [0.86, 0.84, 0.78],
                    [0.8, 0.83, 0.86],
                ][k],
            });
        }
        layout
    }

    pub fn object(&self, id: &str) -> Option<&PlacedObject> {
        self.objects.iter().find(|o| o.id == id)
    }

    /// Every entity's id and class by instance id, layout first.
    pub fn instances(&self) -> Vec<(u16, String, String)> {
        let layout = self
            .layout
            .iter()
            .map(|l| (l.instance, l.class.to_string(), l.id.clone()));
        let objects = self
            .objects
            .iter()
            .map(|o| (o.instance, o.class.clone(), o.id.clone()));
        layout.chain(objects).collect()
    }
}

/// Wall `k`'s first corner, unit direction along it, and unit normal into the room. The walls go
/// counter-clockwise seen from above: wall_0 at y = 0, wall_1 at x = max, wall_2 at y = max,
/// wall_3 at x = 0.
pub fn wall_frame(room: Vec3, k: usize) -> (Vec3, Vec3, Vec3) {
    match k % 4 {
        0 => (Vec3::ZERO, Vec3::X, Vec3::Y),
        1 => (Vec3::new(room.x, 0.0, 0.0), Vec3::Y, -Vec3::X),
        2 => (Vec3::new(room.x, room.y, 0.0), -Vec3::X, -Vec3::Y),
        _ => (Vec3::new(0.0, room.y, 0.0), -Vec3::Y, Vec3::X),
    }
}

pub fn wall_length(room: Vec3, k: usize) -> f32 {
    if k.is_multiple_of(2) { room.x } else { room.y }
}

/// The yaw that turns a model's front (-y) to face along `inward`.
pub fn yaw_facing(inward: Vec3) -> f32 {
    // Rz(yaw) * (0, -1) = (sin yaw, -cos yaw) = inward.xy
    let d = Vec2::new(inward.x, inward.y);
    d.x.atan2(-d.y)
}

impl SceneWorld {
    /// The world flattened into triangles for the rasteriser.
    pub fn render_scene(&self) -> RenderScene {
        let mut scene = RenderScene::default();
        for l in &self.layout {
            let surface = if l.class == "floor" {
                Surface::FloorTiles
            } else {
                Surface::Plain
            };
            scene.push_mesh(&l.mesh, l.instance, l.color, surface);
        }
        for o in &self.objects {
            for (part, world_from_part) in o.model.parts.iter().zip(o.world_from_parts()) {
                scene.push_mesh(
                    &part.visual_mesh().transformed(&world_from_part),
                    o.instance,
                    part.color,
                    Surface::Plain,
                );
            }
        }
        scene
    }
}
