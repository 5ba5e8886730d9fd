//! What an object no model replaced is made of: the part of its segment mesh that is its own,
//! and a support patch under each thing it holds, where the camera could not see. Its link
//! (`LinkGeometry::observed`) collides as the convex pieces along that surface, so what stands in
//! or on it starts where it was seen; before, it was its solid box, and cups in an unmodelled
//! shelf started inside it.

use glam::{Affine3A, Mat4, Vec3};

use crate::cad::db::database::CadDatabase;
use crate::geometry::{GravityBox, TriMesh};
use crate::graph::{ContactGraph, GraphNode};

/// How far (metres) past its box the surface an object no model replaced is made of may reach:
/// half the map's coarsest voxel.
const SEEN_MARGIN_M: f32 = 0.01;

/// The least area (square metres) of a connected piece of an object's segment that it is made
/// of: four voxels of 2 cm. Smaller ones are what bleeding left beside what it holds, and one
/// vertex 15 cm up the side of a bottle made a convex piece that started the bottle 9 cm inside
/// the shelf under it (seed 35).
const MIN_SEEN_AREA_M2: f32 = 0.0016;

/// How far (metres) beside the box of a thing that an object no model replaced holds its
/// surface is cut away: a voxel.
const HELD_MARGIN_M: f32 = 0.02;

/// Thickness (metres) of the surface put under each object that an object no model replaced
/// holds: a voxel.
const SUPPORT_PATCH_M: f32 = 0.02;

/// How far (metres) into a piece of layout (a wall, the floor, the ceiling) a vertex of what an
/// object no model replaced is made of may lie: half the rest test's bar for a start inside
/// another body.
pub const INTO_LAYOUT_SLACK_M: f32 = 0.005;

/// The boxes of the walls, floor and ceiling of `graph`: their room sides are the faces of the
/// blocks the kinematic tree makes of them (`link::node_links`), which a simulator collides with.
pub fn layout_boxes(graph: &ContactGraph) -> Vec<GravityBox> {
    graph
        .nodes
        .iter()
        .filter(|n| matches!(n.class.as_str(), "wall" | "floor" | "ceiling"))
        .map(|n| GravityBox::from(&n.bbox))
        .collect()
}

/// What an object no model replaced is made of: of `seen`, its segment mesh (world frame), the
/// triangles inside its box `own`, outside the boxes `held` of what stands on or in it (where
/// the map saw each and where its model stands) and outside the boxes of `layout` (the walls,
/// floor and ceiling), and under each of `stands` (the placed boxes of what it holds directly) a
/// support patch.
///
/// Nothing the room holds lies behind a wall, under the floor or above the ceiling: a segment's
/// vertices there are the layout's, labelled with the object's class (a 1.9 m "book" of the wall
/// over a cabinet, rejected as no book, reached 3 cm into the wall and 1.2 cm into the ceiling's
/// block, and started its cabinet inside both, seed 1). A vertex more than `INTO_LAYOUT_SLACK_M`
/// inside a layout box takes its triangles out.
///
/// Its box is fitted to the bulk of its points; beyond it, and on what it holds, the segment has
/// label bleeding (a bottle on a cabinet started 2.9 cm inside a "cup" segment of the wall
/// behind it, seed 18 of the benchmark; books on an unmodelled shelf 4-9 cm inside the pieces
/// that the shelf's board made with the books' bled tops, seed 35). Its own box is grown by
/// `SEEN_MARGIN_M`, the held ones by `HELD_MARGIN_M` beside and `SEEN_MARGIN_M` above and
/// below, which takes the board just under each held thing too: the camera never saw it (a
/// cabinet's top came out with a hole under each of its five objects, which fell 77-85 cm
/// through them, seed 31) and where it saw the board around, its noise made a convex piece of
/// the board 1-2 cm higher than the book standing on it. The contact graph says the surface is
/// there, so a patch of it, a box of its own, stands under each one's footprint, its top where
/// the object stands. Pieces smaller than `MIN_SEEN_AREA_M2` left by the cuts are dropped.
pub fn observed_surface(
    seen: &TriMesh,
    own: &GravityBox,
    held: &[GravityBox],
    stands: &[GravityBox],
    layout: &[GravityBox],
) -> SeenShape {
    let m = SEEN_MARGIN_M;
    let held: Vec<(Affine3A, Vec3)> = held
        .iter()
        .map(|b| (b.world_from_box().inverse(), b.size / 2.0))
        .collect();
    let in_held = |p: Vec3| {
        held.iter().any(|(box_from_world, h)| {
            let q = box_from_world.transform_point3(p);
            let beside = HELD_MARGIN_M;
            q.x.abs() <= h.x + beside && q.y.abs() <= h.y + beside && q.z.abs() <= h.z + m
        })
    };
    let behind_layout = |p: Vec3| layout.iter().any(|b| b.contains(p, -INTO_LAYOUT_SLACK_M));
    let kept = seen.filtered(|t| {
        t.iter().all(|&p| own.contains(p, m)) && !t.iter().any(|&p| in_held(p) || behind_layout(p))
    });
    let mut surface = TriMesh::default();
    for component in kept.connected_components() {
        if component.area() >= MIN_SEEN_AREA_M2 {
            surface.append(&component);
        }
    }
    let supports = stands
        .iter()
        .map(|stand| {
            let center = stand
                .center
                .truncate()
                .extend(stand.bottom_z() - SUPPORT_PATCH_M / 2.0);
            TriMesh::cuboid_centered(center, stand.size.truncate().extend(SUPPORT_PATCH_M))
                .transformed(
                    &(Affine3A::from_translation(center)
                        * Affine3A::from_rotation_z(stand.yaw)
                        * Affine3A::from_translation(-center)),
                )
        })
        .collect();
    SeenShape { surface, supports }
}

/// What the object `id` of `graph`, which no model replaced and whose segment mesh is `seen`
/// (world frame), is made of; `db` holds the models of what it holds.
pub fn seen_shape(
    graph: &ContactGraph,
    id: &str,
    seen: &TriMesh,
    db: Option<&CadDatabase>,
) -> Option<SeenShape> {
    let node = graph.node(id).filter(|n| n.cad.is_none())?;
    // Each held thing where it was seen and where its model stands.
    let held: Vec<GravityBox> = held_by(graph, id)
        .iter()
        .filter_map(|h| graph.node(h))
        .flat_map(|h| [GravityBox::from(&h.bbox), placed_box(h, db)])
        .collect();
    let stands: Vec<GravityBox> = graph
        .support_edges()
        .filter(|(parent, _)| *parent == id)
        .filter_map(|(_, child)| graph.node(child))
        .map(|child| placed_box(child, db))
        .collect();
    Some(observed_surface(
        seen,
        &GravityBox::from(&node.bbox),
        &held,
        &stands,
        &layout_boxes(graph),
    ))
}

/// What an object no model replaced is made of ([`observed_surface`]).
#[derive(Clone, Debug, Default)]
pub struct SeenShape {
    /// The part of its segment mesh that is its own.
    pub surface: TriMesh,
    /// A box under each thing it holds, where the camera could not see.
    pub supports: Vec<TriMesh>,
}

impl SeenShape {
    pub fn transformed(&self, to_from_world: &Affine3A) -> Self {
        Self {
            surface: self.surface.transformed(to_from_world),
            supports: self
                .supports
                .iter()
                .map(|p| p.transformed(to_from_world))
                .collect(),
        }
    }
}

/// Where `node` stands: the box of its placed model (in its box's yaw), else its own box.
fn placed_box(node: &GraphNode, db: Option<&CadDatabase>) -> GravityBox {
    let own = GravityBox::from(&node.bbox);
    let placed = node.cad.as_ref().zip(db).and_then(|(cad, db)| {
        let world_from_model = Affine3A::from_mat4(Mat4::from_cols_array(&cad.world_from_model));
        let points: Vec<Vec3> = db
            .get(&cad.model)?
            .mesh
            .positions
            .iter()
            .map(|p| world_from_model.transform_point3(*p))
            .collect();
        GravityBox::enclosing(&points, own.yaw)
    });
    placed.unwrap_or(own)
}

/// The nodes that `id` holds up, directly or through others.
fn held_by<'a>(graph: &'a ContactGraph, id: &str) -> Vec<&'a str> {
    let mut held: Vec<&str> = Vec::new();
    let mut holders = vec![id];
    while let Some(holder) = holders.pop() {
        for (_, child) in graph.support_edges().filter(|(p, _)| *p == holder) {
            if !held.contains(&child) {
                held.push(child);
                holders.push(child);
            }
        }
    }
    held
}
