//! Gives every link body a Bevy mesh (flat-shaded, from its visual triangles) and two materials:
//! its own colour and its object's instance colour (the panoptic segments layer). Every entity of
//! the scene hierarchy gets a visibility so that hiding a parent hides what it carries.

use bevy::asset::RenderAssetUsages;
use bevy::mesh::{Indices, PrimitiveTopology};
use bevy::prelude::*;

use crate::base::ClassId;
use crate::components::{LinkBody, ModelPart, Panoptic, SceneEntity};
use crate::geometry::TriMesh;
use crate::viewer::layers::{ActiveLayers, Layer};
use crate::viewer::map_layer::MapSegments;

/// A link's two looks, and the class of its object (`None` for the robot's links).
#[derive(Component, Clone, Debug)]
pub struct LinkMaterials {
    pub colour: Handle<StandardMaterial>,
    pub segment: Handle<StandardMaterial>,
    pub class: Option<ClassId>,
}

impl LinkMaterials {
    /// Hidden classes never show, and the scene's models hide while the map stands in for
    /// them; the robot always shows.
    pub fn visibility(&self, map_shown: bool) -> Visibility {
        let robot = self.class.is_none();
        let hidden = self
            .class
            .is_some_and(|c| HIDDEN_CLASSES.contains(&c.as_str()));
        if hidden || (map_shown && !robot) {
            Visibility::Hidden
        } else {
            Visibility::Inherited
        }
    }
}

/// Classes never drawn: the viewer looks into the room from above.
pub const HIDDEN_CLASSES: [&str; 1] = ["ceiling"];

/// A Bevy mesh of `mesh`, one normal per face (the CAD models are boxy).
pub fn bevy_mesh(mesh: &TriMesh) -> Mesh {
    coloured_bevy_mesh(mesh, None)
}

/// A Bevy mesh of `mesh`, one normal per face, with a linear RGBA colour per vertex when given.
pub fn coloured_bevy_mesh(mesh: &TriMesh, colours: Option<Vec<[f32; 4]>>) -> Mesh {
    let positions: Vec<[f32; 3]> = mesh.positions.iter().map(|p| p.to_array()).collect();
    let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
    let mut out = Mesh::new(
        PrimitiveTopology::TriangleList,
        RenderAssetUsages::default(),
    )
    .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, positions)
    .with_inserted_indices(Indices::U32(indices));
    if let Some(colours) = colours {
        out.insert_attribute(Mesh::ATTRIBUTE_COLOR, colours);
    }
    out.duplicate_vertices();
    out.compute_flat_normals();
    out
}

/// The colour of instance `instance`: hues a golden angle apart, so neighbours differ.
pub fn instance_colour(instance: u32) -> Color {
    let hue = (instance as f32 * 137.507_77) % 360.0;
    Color::hsl(hue, 0.65, 0.55)
}

pub fn material(colour: Color) -> StandardMaterial {
    StandardMaterial {
        base_color: colour,
        perceptual_roughness: 0.8,
        ..default()
    }
}

/// The object a link belongs to: its own entity, or the object its part belongs to.
fn object_instance(
    entity: Entity,
    part: Option<&ModelPart>,
    panoptic: &Query<(&SceneEntity, &Panoptic)>,
) -> (u32, Option<ClassId>) {
    if let Ok((_, p)) = panoptic.get(entity) {
        return (p.instance, Some(p.class));
    }
    let Some(part) = part else {
        return (0, None);
    };
    panoptic
        .get(part.object)
        .map_or((0, None), |(_, p)| (p.instance, Some(p.class)))
}

fn attach_link_meshes(
    mut commands: Commands,
    links: Query<(Entity, &LinkBody, Option<&ModelPart>), Without<Mesh3d>>,
    panoptic: Query<(&SceneEntity, &Panoptic)>,
    layers: Res<ActiveLayers>,
    map: Res<MapSegments>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    for (entity, body, part) in &links {
        let geometry = &body.0;
        let [r, g, b] = geometry.color;
        let (instance, class) = object_instance(entity, part, &panoptic);
        let looks = LinkMaterials {
            colour: materials.add(material(Color::linear_rgb(r, g, b))),
            segment: materials.add(material(instance_colour(instance))),
            class,
        };
        let shown = if layers.is_on(Layer::Segments) {
            looks.segment.clone()
        } else {
            looks.colour.clone()
        };
        // The map layer hides the models once it has a map to show instead (map_layer.rs).
        let visibility = looks.visibility(layers.is_on(Layer::Map) && !map.segments.is_empty());
        commands.entity(entity).insert((
            Mesh3d(meshes.add(bevy_mesh(&geometry.visual))),
            MeshMaterial3d(shown),
            looks,
            visibility,
        ));
    }
}

/// Entities of the hierarchy without a visibility get one (the scene root, bodiless nodes).
fn give_hierarchy_visibility(
    mut commands: Commands,
    entities: Query<Entity, (With<Transform>, Without<Visibility>)>,
) {
    for entity in &entities {
        commands.entity(entity).insert(Visibility::Inherited);
    }
}

/// Switches every link between its colour and its segment material when the layers change.
fn show_segment_colours(
    layers: Res<ActiveLayers>,
    mut links: Query<(&LinkMaterials, &mut MeshMaterial3d<StandardMaterial>)>,
) {
    if !layers.is_changed() {
        return;
    }
    let segments = layers.is_on(Layer::Segments);
    for (looks, mut shown) in &mut links {
        let want = if segments {
            &looks.segment
        } else {
            &looks.colour
        };
        if shown.0 != *want {
            shown.0 = want.clone();
        }
    }
}

/// A sun from above and a little to the side, with shadows off (software rendering).
pub fn sun() -> impl Bundle {
    (
        DirectionalLight {
            illuminance: 3000.0,
            shadow_maps_enabled: false,
            ..default()
        },
        Transform::from_xyz(1.0, -2.0, 6.0).looking_at(Vec3::ZERO, Vec3::Z),
    )
}

fn spawn_light(mut commands: Commands) {
    commands.spawn(sun());
}

pub struct LinkMeshesPlugin;

impl Plugin for LinkMeshesPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(Startup, spawn_light).add_systems(
            Update,
            (
                give_hierarchy_visibility,
                attach_link_meshes,
                show_segment_colours,
            )
                .chain(),
        );
    }
}
