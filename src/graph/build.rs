//! The contact graph of a set of scene entities (meshes in a gravity-aligned world): a
//! gravity-aligned minimal box and surface planes per entity, support bottom-up, boxes refined so
//! every support holds, then proximal relations.

use std::collections::BTreeMap;

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use crate::classes::{ClassTable, EntityKind};
use crate::geometry::ransac::RansacParams;
use crate::geometry::{GravityBox, Plane, TriMesh};
use crate::graph::entity_shape::{Shape, layout_shape, lies_on, object_shape, room_center};
use crate::graph::floor_units::stands_with_its_foot_hidden;
use crate::graph::proximal::{PROXIMAL_MARGIN, ProximalMargins, proximal_edges};
use crate::graph::sighted_extent::reach_sighted;
use crate::graph::support::{SupportChoice, SupportEntity, SupportParams, infer_supports, rest_on};
use crate::graph::{ContactGraph, GraphEdge, GraphNode};

/// A map's clustering cell is at least this (metres): in a 1 cm map a monitor's neck, a voxel
/// or two thick, parted its stand from its screen on a 2 cm grid, and its box lost the stand.
const MIN_MAP_CLUSTER_CELL_M: f32 = 0.04;

/// One scene entity as the contact graph sees it.
pub struct GraphEntity<'a> {
    pub id: &'a str,
    pub class: &'a str,
    pub kind: EntityKind,
    /// World frame, z up.
    pub mesh: &'a TriMesh,
    /// What precise frames measured of its outline, a list per frame (`panoptic::sighted`),
    /// world frame; empty for most.
    pub sighted: &'a [Vec<Vec3>],
}

#[cfg(test)]
impl<'a> GraphEntity<'a> {
    /// An entity with no outline measured by precise frames (most of them).
    pub(crate) fn unsighted(
        id: &'a str,
        class: &'a str,
        kind: EntityKind,
        mesh: &'a TriMesh,
    ) -> Self {
        Self {
            id,
            class,
            kind,
            mesh,
            sighted: &[],
        }
    }
}

#[derive(Clone, Copy, Debug)]
pub struct ContactGraphParams {
    pub ransac: RansacParams,
    pub support: SupportParams,
    /// Surface points are at most this far apart (metres): mesh vertices, plus samples inside
    /// triangles larger than this (a CAD table top is two triangles).
    pub sample_spacing: f32,
    /// Grid cell (metres) of the clustering that keeps an object's largest connected piece.
    /// A map's: two voxels, at least `MIN_MAP_CLUSTER_CELL_M`.
    pub cluster_cell: f32,
    /// An object's box turns to the room's axes when that makes its footprint at most this
    /// factor larger than the minimal one: a box fitted to a partial, noisy view picks up a
    /// spurious yaw, and furniture mostly stands square with the walls.
    pub square_with_room_area: f32,
    /// Boxes closer than this (metres) are proximal: `PROXIMAL_MARGIN` for exact meshes. A map's
    /// object boxes grow by about a voxel where surfaces bleed past silhouettes, so two objects
    /// need a voxel less (`for_voxel`), unless precise depth carved the bleeding and measured
    /// the outlines (`panoptic::sighted`): then the boxes are as exact as the truth's. Against a
    /// wall (an exact plane, which claims the object points on it, `layout_band`) the margin is
    /// the exact one: what the frames saw as the wall is carved off the object's mesh
    /// (`panoptic::carve`), so its box ends at its last surface vertex, within a voxel of its
    /// true face either way. With 2 cm voxels and noisy depth a 1.8 cm and a 3.7 cm gap still
    /// look alike.
    pub proximal_margins: ProximalMargins,
    /// An object's surface points within this distance (metres) of a wall or the floor, facing
    /// the way that layout surface faces, are the layout's: segmentation bleeds an object's label
    /// onto the wall behind it, and a surface that close cannot be told from the wall anyway.
    pub layout_band: f32,
    /// Likewise an object's points within this distance (metres) of the plane that supports it,
    /// facing up like it, are the parent's (tighter: a book lying on a table is 2 cm thick).
    pub support_band: f32,
    /// Whether and how an object's sparse footprint ends are cut (`sparse_ends`): a map's
    /// labels bleed along surfaces into the neighbour; exact meshes keep their extent.
    pub sparse_ends: Option<SparseEnds>,
    /// What the frames measured of an object's outline within this distance (metres) of a wall
    /// or the floor is the layout's (`sighted_extent`): a quarter voxel, well above the noise of
    /// the depth that measures outlines at all, below the gap of an object standing off a wall.
    pub sighted_layout_band: f32,
    /// A box side may reach this far (metres) past the outline the frames measured before it
    /// is moved in to it (`sighted_extent`): half a voxel, the mesh's own precision.
    pub sighted_slack: f32,
    /// ...by at most this much (metres): a voxel, the mesh's own precision. A mesh reaching
    /// further past every silhouette is surface that no silhouette shows (something lying flat
    /// on its support, seen only against it), not run-on.
    pub sighted_max_shrink: f32,
}

/// Footprint ends counted in bins `bin` metres wide are cut where they hold under `share` of the
/// object's lower-median bin.
#[derive(Clone, Copy, Debug)]
pub struct SparseEnds {
    pub bin: f32,
    pub share: f32,
}

impl ContactGraphParams {
    /// Parameters for entities out of a map with `voxel` metres voxels, from depth that was
    /// `precise` or not (`panoptic::sighted`).
    pub fn for_voxel(voxel: f32, precise: bool) -> Self {
        Self {
            // A map's mesh has a vertex every voxel or so: sampling inside its triangles would
            // multiply the points (and the stage's time) for no new surface.
            sample_spacing: (2.0 * voxel).max(Self::default().sample_spacing),
            cluster_cell: (2.0 * voxel).max(MIN_MAP_CLUSTER_CELL_M),
            proximal_margins: if precise {
                ProximalMargins::EXACT
            } else {
                ProximalMargins {
                    objects: PROXIMAL_MARGIN - voxel,
                    wall: PROXIMAL_MARGIN,
                }
            },
            sparse_ends: Some(SparseEnds {
                bin: voxel,
                share: 0.2,
            }),
            sighted_layout_band: voxel / 4.0,
            sighted_slack: voxel / 2.0,
            sighted_max_shrink: voxel,
            ..Self::default()
        }
    }
}

impl Default for ContactGraphParams {
    fn default() -> Self {
        Self {
            ransac: RansacParams::default(),
            support: SupportParams::default(),
            sample_spacing: 0.02,
            cluster_cell: 0.06,
            square_with_room_area: 1.1,
            proximal_margins: ProximalMargins::EXACT,
            layout_band: 0.02,
            support_band: 0.01,
            sparse_ends: None,
            sighted_layout_band: 0.005,
            sighted_slack: 0.01,
            sighted_max_shrink: 0.02,
        }
    }
}

/// Builds the contact graph of `entities`; entities without a usable surface (fewer than three
/// points) are left out.
pub fn build_contact_graph(entities: &[GraphEntity], params: &ContactGraphParams) -> ContactGraph {
    build_contact_graph_with_surfaces(entities, params).graph
}

/// A contact graph with what it saw of each node.
pub struct BuiltContactGraph {
    pub graph: ContactGraph,
    /// Per node, in node order: the entity's own surface points (its mesh's vertices without
    /// those the layout or, for an object resting on something, its support plane claimed,
    /// and without stray pieces).
    pub surfaces: Vec<Vec<Vec3>>,
}

/// [`build_contact_graph`], keeping each node's surface points for the stages after it.
pub fn build_contact_graph_with_surfaces(
    entities: &[GraphEntity],
    params: &ContactGraphParams,
) -> BuiltContactGraph {
    let room_center = room_center(entities);
    let is_layout = |e: &GraphEntity| e.kind == EntityKind::Layout;
    let mut shaped: Vec<(usize, Shape)> = entities
        .par_iter()
        .enumerate()
        .filter(|(_, e)| is_layout(e))
        .filter_map(|(i, e)| layout_shape(e, room_center, params).map(|s| (i, s)))
        .collect();
    // Walls and floor claim the object points lying on them.
    let claiming: Vec<Plane> = shaped
        .iter()
        .filter(|(i, _)| matches!(entities[*i].class, "wall" | "floor"))
        .filter_map(|(_, s)| s.planes.first().copied())
        .collect();
    // Counters (found from the map's unclaimed surface, graph/counters.rs) are solid from the
    // floor to their top: an object's points inside one are the counter's front or top, bled
    // onto by the object's label (a monitor's mask running down the counter to the floor).
    let is_counter = |e: &GraphEntity| e.class == COUNTER_CLASS;
    let counters: Vec<(usize, Shape)> = entities
        .par_iter()
        .enumerate()
        .filter(|(_, e)| !is_layout(e) && is_counter(e))
        .filter_map(|(i, e)| object_shape(e, &claiming, &[], false, params).map(|s| (i, s)))
        .map(|(i, mut shape)| {
            // Its top is where things stand on it: the median height of its points, not the
            // highest (noise and the rims of what stands on it reach above).
            let mut heights: Vec<f32> = shape.points.iter().map(|p| p.z).collect();
            heights.sort_by(f32::total_cmp);
            let top = heights[heights.len() / 2];
            let bottom = shape.bbox.bottom_z().min(top);
            shape.bbox.center.z = (top + bottom) / 2.0;
            shape.bbox.size.z = top - bottom;
            (i, shape)
        })
        .collect();
    let solids: Vec<GravityBox> = counters
        .iter()
        .map(|(_, s)| counter_solid(&s.bbox))
        .collect();
    shaped.extend(counters);
    shaped.par_extend(
        entities
            .par_iter()
            .enumerate()
            .filter(|(_, e)| !is_layout(e) && !is_counter(e))
            .filter_map(|(i, e)| object_shape(e, &claiming, &solids, true, params).map(|s| (i, s))),
    );
    // Entity order, as given: the graph's nodes and edges come out in it.
    shaped.sort_by_key(|(i, _)| *i);
    let yaw = room_yaw(entities, &shaped);
    for (i, shape) in &mut shaped {
        if entities[*i].kind != EntityKind::Layout {
            shape.bbox = square_with_room(&shape.bbox, &shape.points, yaw, params);
        }
    }
    let table = ClassTable::builtin();
    let support_input: Vec<SupportEntity> = shaped
        .iter()
        .map(|(i, s)| SupportEntity {
            class: entities[*i].class,
            kind: entities[*i].kind,
            movable: table.get(entities[*i].class).is_some_and(|c| c.movable),
            bbox: s.bbox,
            planes: &s.planes,
            vertices: &s.points,
        })
        .collect();
    let mut supports = infer_supports(&support_input, &params.support);
    // A counter stands on the floor, whatever share of the floor around it was seen, and never
    // hangs on the wall behind it (a wall cabinet would have been found above it, not a top at
    // counter height). So does a unit hanging too low for a wall unit over a floor nobody saw
    // (`stands_with_its_foot_hidden`).
    let floor = shaped
        .iter()
        .position(|(i, _)| entities[*i].class == "floor");
    if let Some(floor) = floor
        && let Some(&plane) = shaped[floor].1.planes.first()
    {
        for (k, (i, shape)) in shaped.iter().enumerate() {
            let unsupported = matches!(supports[k], None | Some(SupportChoice::Wall { .. }));
            if unsupported
                && (entities[*i].class == COUNTER_CLASS
                    || stands_with_its_foot_hidden(
                        entities[*i].class,
                        &shape.bbox,
                        &plane,
                        &shaped[floor].1.points,
                    ))
            {
                supports[k] = Some(SupportChoice::Below {
                    parent: floor,
                    plane,
                    score: 0.0,
                    registered: false,
                });
            }
        }
    }

    let mut boxes: Vec<GravityBox> = shaped.iter().map(|(_, s)| s.bbox).collect();
    let mut planes: Vec<Vec<Plane>> = shaped.iter().map(|(_, s)| s.planes.clone()).collect();
    let mut surfaces: Vec<Option<Vec<Vec3>>> = vec![None; shaped.len()];
    let mut support_edges = Vec::new();
    for (child, choice) in supports.iter().enumerate() {
        let Some(choice) = choice else { continue };
        let parent = match *choice {
            SupportChoice::Below {
                parent,
                plane,
                registered,
                ..
            } => {
                if !registered
                    && let Some(kept) = off_support(&shaped[child].1, &plane, params)
                    && let Some(minimal) = GravityBox::minimal(&kept)
                {
                    boxes[child] = square_with_room(&minimal, &kept, yaw, params);
                    surfaces[child] = Some(kept);
                }
                boxes[child] = rest_on(&boxes[child], &plane);
                if registered {
                    planes[parent].push(plane);
                }
                parent
            }
            SupportChoice::Wall { parent } => parent,
        };
        support_edges.push((parent, child));
    }

    for (k, (i, _)) in shaped.iter().enumerate() {
        if entities[*i].kind != EntityKind::Layout {
            boxes[k] = reach_sighted(
                &boxes[k],
                entities[*i].sighted,
                &claiming,
                params.sighted_layout_band,
                params.sighted_slack,
                params.sighted_max_shrink,
            );
        }
    }

    // The floor runs on under everything standing on it: a floor seen only in part would end
    // under a chair's legs, and the simulator's floor slab with it (7-Scenes redkitchen: a chair
    // by the map's edge tipped over the slab's edge).
    if let Some(floor) = floor {
        let under = boxes[floor];
        let mut corners: Vec<Vec3> = under.corners().to_vec();
        for &(parent, child) in &support_edges {
            if parent == floor {
                corners.extend(boxes[child].footprint().map(|q| q.extend(under.center.z)));
            }
        }
        if let Some(mut grown) = GravityBox::enclosing(&corners, under.yaw) {
            grown.center.z = under.center.z;
            grown.size.z = under.size.z;
            boxes[floor] = grown;
        }
    }

    let id = |k: usize| entities[shaped[k].0].id;
    let class = |k: usize| entities[shaped[k].0].class;
    let supports_by_id: Vec<(&str, &str)> =
        support_edges.iter().map(|&(p, c)| (id(p), id(c))).collect();
    let boxed: Vec<(&str, GravityBox, &str)> = (0..shaped.len())
        .map(|k| (id(k), boxes[k], class(k)))
        .collect();
    let mut edges: Vec<GraphEdge> = supports_by_id
        .iter()
        .map(|&(parent, child)| GraphEdge::Support {
            parent: parent.to_string(),
            child: child.to_string(),
        })
        .collect();
    edges.extend(proximal_edges(
        &boxed,
        &supports_by_id,
        params.proximal_margins,
    ));
    let nodes = (0..shaped.len())
        .map(|k| GraphNode {
            id: id(k).to_string(),
            class: class(k).to_string(),
            kind: entities[shaped[k].0].kind,
            bbox: boxes[k].into(),
            planes: planes[k].iter().map(Plane::to_array).collect(),
            cad: None,
            joints: BTreeMap::new(),
            parts: Vec::new(),
        })
        .collect();
    let surfaces = surfaces
        .into_iter()
        .zip(shaped)
        .map(|(kept, (_, shape))| kept.unwrap_or(shape.points))
        .collect();
    BuiltContactGraph {
        graph: ContactGraph { nodes, edges },
        surfaces,
    }
}

/// The room's yaw modulo 90 degrees, from its walls' normals (circular mean of four times the
/// angle, so walls at right angles agree); `None` without walls.
fn room_yaw(entities: &[GraphEntity], shaped: &[(usize, Shape)]) -> Option<f32> {
    let sum: glam::Vec2 = shaped
        .iter()
        .filter(|(i, _)| entities[*i].class == "wall")
        .filter_map(|(_, s)| s.planes.first())
        .map(|p| glam::Vec2::from_angle(4.0 * p.normal.y.atan2(p.normal.x)))
        .sum();
    (sum.length() > 1e-3).then(|| 0.25 * sum.y.atan2(sum.x))
}

/// An object's points without those that lie on the surface holding it and face the way it
/// faces (segmentation bleeds a cup's label onto the counter around its base); `None` when
/// nothing is dropped or too little is left.
fn off_support(shape: &Shape, plane: &Plane, params: &ContactGraphParams) -> Option<Vec<Vec3>> {
    let kept: Vec<Vec3> = shape
        .points
        .iter()
        .zip(&shape.normals)
        .filter(|(p, n)| !lies_on(plane, **p, **n, params.support_band))
        .map(|(p, _)| *p)
        .collect();
    (kept.len() < shape.points.len() && kept.len() * 2 >= shape.points.len()).then_some(kept)
}

/// `bbox`, or the box of `points` square with the room (walls' yaw `room_yaw`, if there are
/// walls) when its footprint is nearly as small.
fn square_with_room(
    bbox: &GravityBox,
    points: &[Vec3],
    room_yaw: Option<f32>,
    params: &ContactGraphParams,
) -> GravityBox {
    match room_yaw.and_then(|yaw| GravityBox::enclosing(points, yaw)) {
        Some(square)
            if square.size.x * square.size.y
                <= params.square_with_room_area * bbox.size.x * bbox.size.y =>
        {
            square
        }
        _ => *bbox,
    }
}

/// The class of the counters found from geometry (graph/counters.rs).
pub const COUNTER_CLASS: &str = "counter";
/// A counter claims the points of other objects within this distance (metres) of its solid:
/// a voxel and a half, the reach of a label bleeding onto its front.
const COUNTER_CLAIM_M: f32 = 0.03;

/// The solid a counter with the box `top` (its top surface) stands for: from the floor to just
/// under its top, grown by `COUNTER_CLAIM_M` at the sides.
fn counter_solid(top: &GravityBox) -> GravityBox {
    let bottom = 0.0;
    let ceiling = top.top_z() - COUNTER_CLAIM_M;
    GravityBox {
        center: top.center.with_z((bottom + ceiling) / 2.0),
        size: (top.size.truncate() + Vec2::splat(2.0 * COUNTER_CLAIM_M))
            .extend((ceiling - bottom).max(0.0)),
        yaw: top.yaw,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::surface_points::surface_points;

    #[test]
    fn a_counter_against_a_wall_stands_on_the_floor_not_on_the_wall() {
        // A floor 4 x 3 m, a wall along its back edge 2 m high, and a counter seen as its top
        // only (a 2 cm slab at 0.9 m, 2 x 0.6 m) against the wall: nothing holds the top from
        // below, and it touches the wall.
        let floor = TriMesh::cuboid(Vec3::new(0.0, 0.0, -0.02), Vec3::new(4.0, 3.0, 0.0));
        let wall = TriMesh::cuboid(Vec3::new(0.0, 3.0, 0.0), Vec3::new(4.0, 3.02, 2.0));
        let top = TriMesh::cuboid(Vec3::new(1.0, 2.4, 0.88), Vec3::new(3.0, 3.0, 0.9));
        let entities = [
            GraphEntity::unsighted("floor", "floor", EntityKind::Layout, &floor),
            GraphEntity::unsighted("wall_0", "wall", EntityKind::Layout, &wall),
            GraphEntity::unsighted("counter_1", COUNTER_CLASS, EntityKind::Rigid, &top),
        ];
        let graph = build_contact_graph(&entities, &ContactGraphParams::default());
        assert_eq!(graph.parent_of("counter_1"), Some("floor"), "{graph:?}");
        // Its box reaches down to the floor it stands on.
        let node = graph.node("counter_1").expect("counter");
        let bottom = node.bbox.center[2] - node.bbox.size[2] / 2.0;
        assert!(bottom.abs() < 0.02, "{:?}", node.bbox);
    }

    #[test]
    fn the_floor_runs_on_under_what_stands_on_it() {
        // A floor seen 2 x 2 m, and a 0.5 m cube standing on it half off its seen edge.
        let floor = TriMesh::cuboid(Vec3::new(0.0, 0.0, -0.02), Vec3::new(2.0, 2.0, 0.0));
        let cube = TriMesh::cuboid(Vec3::new(1.75, 0.5, 0.0), Vec3::new(2.25, 1.0, 0.5));
        let entities = [
            GraphEntity {
                id: "floor",
                class: "floor",
                kind: EntityKind::Layout,
                mesh: &floor,
                sighted: &[],
            },
            GraphEntity {
                id: "box_1",
                class: "box",
                kind: EntityKind::Rigid,
                mesh: &cube,
                sighted: &[],
            },
        ];
        let graph = build_contact_graph(&entities, &ContactGraphParams::default());
        assert_eq!(graph.parent_of("box_1"), Some("floor"), "{graph:?}");
        let b = &graph.node("floor").expect("floor").bbox;
        let (lo, hi) = (b.center[0] - b.size[0] / 2.0, b.center[0] + b.size[0] / 2.0);
        assert!(lo < 0.01 && (hi - 2.25).abs() < 0.01, "{b:?}");
    }

    #[test]
    fn a_cups_label_bled_onto_the_counter_leaves_its_box() {
        // An 8 cm cup standing on a counter at z = 0.9, and a 6 cm ring of counter top around its
        // base that took the cup's label.
        let cup = TriMesh::cylinder(Vec3::new(0.0, 0.0, 0.9), 0.04, 0.1, 24);
        let mut points = surface_points(&cup, 0.01);
        for i in 0..24 {
            let angle = i as f32 / 24.0 * std::f32::consts::TAU;
            for r in [0.05, 0.07, 0.1] {
                points
                    .points
                    .push(Vec3::new(r * angle.cos(), r * angle.sin(), 0.9));
                points.normals.push(Vec3::Z);
            }
        }
        let shape = Shape {
            bbox: GravityBox::minimal(&points.points).expect("points"),
            points: points.points,
            normals: points.normals,
            planes: Vec::new(),
        };
        assert!(shape.bbox.size.x > 0.19, "the ring stretches the box");
        let counter = Plane::from_point_normal(Vec3::new(0.0, 0.0, 0.9), Vec3::Z);
        let params = ContactGraphParams::default();
        let kept = off_support(&shape, &counter, &params).expect("the ring dropped");
        let b = GravityBox::minimal(&kept).expect("a box");
        assert!(
            (b.size.x - 0.08).abs() < 0.005 && (b.size.y - 0.08).abs() < 0.005,
            "{b:?}"
        );
        // Nothing on the counter: nothing to drop.
        let high = Plane::from_point_normal(Vec3::new(0.0, 0.0, 0.5), Vec3::Z);
        assert_eq!(off_support(&shape, &high, &params), None);
    }
}
