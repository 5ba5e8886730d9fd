//! The occupancy layer: the grid the robot plans on (`sim::actions::nav_grid`, the scene as it
//! stands now), laid on the floor. Occupied cells are dark; free cells are shaded by their
//! clearance, amber where the base's footprint does not fit and green where it does. The grid is
//! rebuilt whenever the scene changes (a door opened from the viewer blocks its swing).

use bevy::asset::RenderAssetUsages;
use bevy::mesh::{Indices, PrimitiveTopology};
use bevy::prelude::*;

use crate::export::occupancy::Cell;
use crate::sim::actions::nav_grid;
use crate::sim::navigation::NavGrid;
use crate::sim::robot::RobotSpec;
use crate::sim::scene_view::SceneView;
use crate::systems::kinematic_tree::read_kinematic_tree;
use crate::systems::simulation::Robot;
use crate::viewer::layers::{ActiveLayers, Layer};
use crate::viewer::motion::Motion;
use crate::viewer::state::{SceneRevision, ViewerStatus};

/// Height of the grid above the floor's top (z = 0), metres: above it, below everything else.
const GRID_Z_M: f32 = 0.004;

/// The grid's mesh entity and the scene revision it shows.
#[derive(Resource, Default)]
struct OccupancyOverlay {
    entity: Option<Entity>,
    revision: Option<u64>,
}

/// The colour of a cell: occupied dark; free by clearance against the base's radius.
fn cell_colour(cell: Cell, clearance: f32, radius: f32) -> [f32; 4] {
    match cell {
        Cell::Unknown => [0.0; 4],
        Cell::Occupied => [0.12, 0.12, 0.14, 1.0],
        Cell::Free if clearance < radius => [0.95, 0.65, 0.1, 1.0],
        Cell::Free => {
            // Lighter the more room there is, up to twice the radius.
            let room = ((clearance - radius) / radius).clamp(0.0, 1.0);
            [0.35 + 0.45 * room, 0.8, 0.35 + 0.45 * room, 1.0]
        }
    }
}

/// One quad per known cell, with the cell's colour on its vertices.
fn grid_mesh(grid: &NavGrid, radius: f32) -> Mesh {
    let g = &grid.grid;
    let mut positions: Vec<[f32; 3]> = Vec::new();
    let mut colours: Vec<[f32; 4]> = Vec::new();
    let mut indices: Vec<u32> = Vec::new();
    for row in 0..g.height {
        for col in 0..g.width {
            let i = row * g.width + col;
            if g.cells[i] == Cell::Unknown {
                continue;
            }
            let lo = g.origin + Vec2::new(col as f32, row as f32) * g.resolution;
            let hi = lo + Vec2::splat(g.resolution);
            let base = positions.len() as u32;
            for (x, y) in [(lo.x, lo.y), (hi.x, lo.y), (hi.x, hi.y), (lo.x, hi.y)] {
                positions.push([x, y, GRID_Z_M]);
                colours.push(cell_colour(g.cells[i], grid.clearance[i], radius));
            }
            indices.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
        }
    }
    let normals = vec![[0.0, 0.0, 1.0]; positions.len()];
    Mesh::new(
        PrimitiveTopology::TriangleList,
        RenderAssetUsages::default(),
    )
    .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, positions)
    .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, normals)
    .with_inserted_attribute(Mesh::ATTRIBUTE_COLOR, colours)
    .with_inserted_indices(Indices::U32(indices))
}

/// Shows or hides the grid, and rebuilds it when the scene changed since it was built.
fn update_occupancy(world: &mut World) {
    let on = world.resource::<ActiveLayers>().is_on(Layer::Occupancy);
    let revision = world.resource::<SceneRevision>().0;
    let overlay = world.resource::<OccupancyOverlay>();
    let (entity, shown) = (overlay.entity, overlay.revision);
    if let Some(entity) = entity
        && let Some(mut visibility) = world.get_mut::<Visibility>(entity)
    {
        let want = if on {
            Visibility::Visible
        } else {
            Visibility::Hidden
        };
        visibility.set_if_neq(want);
    }
    // Transforms in the middle of a motion are no state of the tree: wait for its end.
    if !on || shown == Some(revision) || world.resource::<Motion>().is_running() {
        return;
    }
    let radius = world
        .query::<&Robot>()
        .iter(world)
        .next()
        .map_or(RobotSpec::default().radius, |r| r.spec.radius);
    let grid = read_kinematic_tree(world)
        .map_err(|e| e.to_string())
        .and_then(|tree| nav_grid(&SceneView::new(&tree)).map_err(|e| e.to_string()));
    let grid = match grid {
        Ok(grid) => grid,
        Err(why) => {
            world
                .resource_mut::<ViewerStatus>()
                .0
                .push(format!("occupancy: {why}"));
            world.resource_mut::<OccupancyOverlay>().revision = Some(revision);
            return;
        }
    };
    let mesh = world
        .resource_mut::<Assets<Mesh>>()
        .add(grid_mesh(&grid, radius));
    let material = world
        .resource_mut::<Assets<StandardMaterial>>()
        .add(StandardMaterial {
            base_color: Color::WHITE,
            unlit: true,
            ..default()
        });
    if let Some(old) = entity {
        world.despawn(old);
    }
    let spawned = world
        .spawn((
            Mesh3d(mesh),
            MeshMaterial3d(material),
            Transform::IDENTITY,
            Visibility::Visible,
            Name::new("occupancy grid"),
        ))
        .id();
    let mut overlay = world.resource_mut::<OccupancyOverlay>();
    overlay.entity = Some(spawned);
    overlay.revision = Some(revision);
}

pub struct OccupancyLayerPlugin;

impl Plugin for OccupancyLayerPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<OccupancyOverlay>()
            .add_systems(Update, update_occupancy);
    }
}
