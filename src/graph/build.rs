//! The contact graph of a set of scene entities (meshes in a gravity-aligned world): a
//! gravity-aligned minimal box and surface planes per entity, support bottom-up, boxes refined so
//! every support holds, then proximal relations.

use std::collections::BTreeMap;

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use crate::classes::{ClassTable, EntityKind};
use crate::geometry::clusters::in_largest_cluster;
use crate::geometry::ransac::{RansacParams, ransac_planes};
use crate::geometry::{GravityBox, Plane, TriMesh};
use crate::graph::layout_plane::layout_plane;
use crate::graph::proximal::{PROXIMAL_MARGIN, ProximalMargins, proximal_edges};
use crate::graph::sighted_extent::reach_sighted;
use crate::graph::sparse_ends::keep_dense_extent;
use crate::graph::support::{SupportChoice, SupportEntity, SupportParams, infer_supports, rest_on};
use crate::graph::{ContactGraph, GraphEdge, GraphNode};

/// Layout boxes are slabs this thick behind their surface (as in the ground truth).
pub const LAYOUT_THICKNESS: f32 = 0.1;
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

/// An entity's geometry for the graph: surface points (with their normals for objects), box,
/// planes.
struct Shape {
    points: Vec<Vec3>,
    normals: Vec<Vec3>,
    bbox: GravityBox,
    planes: Vec<Plane>,
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

/// Whether a surface point with normal `n` lies on `surface` (less than `band` in front of it, or
/// behind it) and faces the way it does: then it is that surface, whatever label it took.
fn lies_on(surface: &Plane, p: Vec3, n: Vec3, band: f32) -> bool {
    surface.signed_distance(p) < band && n.dot(surface.normal) > 0.85
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

/// Classes that stand on the floor or hang on a wall as a wall unit.
const FLOOR_OR_WALL_UNITS: [&str; 4] = ["cabinet", "fridge", "oven", "dishwasher"];
/// A wall unit hangs with its bottom at least this high (metres) above the floor: above a
/// counter's top (0.9 m) and the working room over it; the generator hangs them at 1.4-1.6 m.
const LOWEST_WALL_UNIT_M: f32 = 0.9;
/// Floor points under an object's footprint (shrunk by `FOOT_MARGIN_M`) that show the floor was
/// seen beneath it.
const FLOOR_SEEN_BENEATH_POINTS: usize = 10;
const FOOT_MARGIN_M: f32 = 0.05;

/// Whether an object of `class` that nothing holds from below (or that only touches a wall)
/// stands on the floor with its lower part unseen: it is a unit that stands on the floor or
/// hangs on a wall, it hangs lower than a wall unit would, and no floor point lies under its
/// footprint. A nightstand behind a bed, seen over the bed as its top 20 cm with a drawer
/// pulled out, otherwise hung on the wall behind it with a box 20-38 cm high and one drawer
/// instead of three (seeds 3, 21, 38, 43); a unit truly hanging that low leaves the floor under
/// it in view.
fn stands_with_its_foot_hidden(
    class: &str,
    bbox: &GravityBox,
    floor: &Plane,
    floor_points: &[Vec3],
) -> bool {
    if !FLOOR_OR_WALL_UNITS.contains(&class) {
        return false;
    }
    let bottom = bbox.center.with_z(bbox.bottom_z());
    let above_floor = floor.signed_distance(bottom);
    if above_floor >= LOWEST_WALL_UNIT_M {
        return false;
    }
    let foot = GravityBox {
        center: bbox.center.with_z(bottom.z - 0.5 * above_floor),
        yaw: bbox.yaw,
        size: Vec3::new(
            (bbox.size.x - 2.0 * FOOT_MARGIN_M).max(0.0),
            (bbox.size.y - 2.0 * FOOT_MARGIN_M).max(0.0),
            above_floor + 2.0 * FOOT_MARGIN_M,
        ),
    };
    floor_points
        .iter()
        .filter(|p| foot.contains(**p, 0.0))
        .count()
        < FLOOR_SEEN_BENEATH_POINTS
}
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

/// The middle of the room: the centre of the floor if there is one, else of everything.
fn room_center(entities: &[GraphEntity]) -> Vec3 {
    let mean = |meshes: &mut dyn Iterator<Item = &TriMesh>| {
        let (sum, n) = meshes
            .flat_map(|m| m.positions.iter())
            .fold((Vec3::ZERO, 0usize), |(s, n), p| (s + *p, n + 1));
        (n > 0).then(|| sum / n as f32)
    };
    mean(
        &mut entities
            .iter()
            .filter(|e| e.class == "floor")
            .map(|e| e.mesh),
    )
    .or_else(|| mean(&mut entities.iter().map(|e| e.mesh)))
    .unwrap_or(Vec3::ZERO)
}

fn layout_shape(
    entity: &GraphEntity,
    room_center: Vec3,
    params: &ContactGraphParams,
) -> Option<Shape> {
    let points = surface_points(entity.mesh, params.sample_spacing).points;
    if points.len() < 3 {
        return None;
    }
    // The layout piece is its largest plane; voxels a noisy segmentation gave it elsewhere (a
    // cabinet side labelled wall) would make its slab thick.
    let main = ransac_planes(
        &points,
        &RansacParams {
            max_planes: 1,
            ..params.ransac
        },
    );
    let inliers: Vec<Vec3> = match main.first() {
        Some(p) => p.inliers.iter().map(|&i| points[i as usize]).collect(),
        None => points,
    };
    let plane = layout_plane(entity.class, &inliers, room_center)?;
    // The slab's face is the fitted plane itself: the inliers' spread in front of it is noise
    // (up to the RANSAC threshold) and would push the face into the room.
    let behind = -plane.normal * LAYOUT_THICKNESS;
    let slab: Vec<Vec3> = inliers
        .iter()
        .map(|p| *p - plane.normal * plane.signed_distance(*p))
        .flat_map(|p| [p, p + behind])
        .collect();
    let bbox = if entity.class == "wall" {
        GravityBox::enclosing(&slab, plane.normal.y.atan2(plane.normal.x))?
    } else {
        GravityBox::minimal(&slab)?
    };
    Some(Shape {
        points: inliers,
        normals: Vec::new(),
        bbox,
        planes: vec![plane],
    })
}

fn object_shape(
    entity: &GraphEntity,
    claiming: &[Plane],
    solids: &[GravityBox],
    largest_piece: bool,
    params: &ContactGraphParams,
) -> Option<Shape> {
    let surface = surface_points(entity.mesh, params.sample_spacing);
    let on_layout = |p: Vec3, n: Vec3| {
        claiming
            .iter()
            .any(|l| lies_on(l, p, n, params.layout_band))
            || solids.iter().any(|s| s.contains(p, 0.0))
    };
    let (points, normals): (Vec<Vec3>, Vec<Vec3>) = surface
        .points
        .iter()
        .zip(&surface.normals)
        .filter(|(p, n)| !on_layout(**p, **n))
        .unzip();
    // Stray pieces (label bleeding onto a neighbour) would stretch the box. A counter's top is
    // one piece already, seen in strips between what stands on it.
    let keep = if largest_piece {
        in_largest_cluster(&points, params.cluster_cell)
    } else {
        vec![true; points.len()]
    };
    let (points, normals) = kept(points, normals, &keep);
    if points.len() < 3 {
        return None;
    }
    let bbox = GravityBox::minimal(&points)?;
    let (points, normals, bbox) = match params.sparse_ends {
        Some(ends) if largest_piece => {
            let keep = keep_dense_extent(&points, bbox.yaw, ends.bin, ends.share);
            if keep.iter().filter(|k| **k).count() < 3 {
                (points, normals, bbox)
            } else {
                let (points, normals) = kept(points, normals, &keep);
                let bbox = GravityBox::minimal(&points)?;
                (points, normals, bbox)
            }
        }
        _ => (points, normals, bbox),
    };
    let planes = ransac_planes(&points, &params.ransac)
        .into_iter()
        .map(|p| p.plane)
        .collect();
    Some(Shape {
        points,
        normals,
        bbox,
        planes,
    })
}

/// The points and their normals where `keep` is true.
fn kept(points: Vec<Vec3>, normals: Vec<Vec3>, keep: &[bool]) -> (Vec<Vec3>, Vec<Vec3>) {
    points
        .into_iter()
        .zip(normals)
        .zip(keep)
        .filter(|(_, k)| **k)
        .map(|(pn, _)| pn)
        .unzip()
}

/// Points on a mesh's surface with the surface's unit normal at each (zero where undefined).
pub struct SurfacePoints {
    pub points: Vec<Vec3>,
    pub normals: Vec<Vec3>,
}

/// The mesh's vertices, plus points on a barycentric grid inside every triangle with an edge
/// longer than `spacing`, so no two neighbouring surface points are farther apart than that.
pub fn surface_points(mesh: &TriMesh, spacing: f32) -> SurfacePoints {
    let (mut points, mut normals): (Vec<Vec3>, Vec<Vec3>) = mesh
        .positions
        .iter()
        .copied()
        .zip(mesh.vertex_normals())
        .filter(|(p, _)| p.is_finite())
        .unzip();
    for t in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.triangle(t);
        let longest = (b - a).length().max((c - b).length()).max((a - c).length());
        if !longest.is_finite() || longest <= spacing {
            continue;
        }
        let normal = mesh.face_normal(t);
        let k = (longest / spacing).ceil() as usize;
        for i in 0..=k {
            for j in 0..=(k - i) {
                // Corners are vertices already.
                if (i == k) || (j == k) || (i == 0 && j == 0) {
                    continue;
                }
                let (u, v) = (i as f32 / k as f32, j as f32 / k as f32);
                points.push(a + (b - a) * u + (c - a) * v);
                normals.push(normal);
            }
        }
    }
    SurfacePoints { points, normals }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_counter_against_a_wall_stands_on_the_floor_not_on_the_wall() {
        // A floor 4 x 3 m, a wall along its back edge 2 m high, and a counter seen as its top
        // only (a 2 cm slab at 0.9 m, 2 x 0.6 m) against the wall: nothing holds the top from
        // below, and it touches the wall.
        let floor = TriMesh::cuboid(Vec3::new(0.0, 0.0, -0.02), Vec3::new(4.0, 3.0, 0.0));
        let wall = TriMesh::cuboid(Vec3::new(0.0, 3.0, 0.0), Vec3::new(4.0, 3.02, 2.0));
        let top = TriMesh::cuboid(Vec3::new(1.0, 2.4, 0.88), Vec3::new(3.0, 3.0, 0.9));
        let entity = |id, class, kind, mesh| GraphEntity {
            id,
            class,
            kind,
            mesh,
            sighted: &[],
        };
        let entities = [
            entity("floor", "floor", EntityKind::Layout, &floor),
            entity("wall_0", "wall", EntityKind::Layout, &wall),
            entity("counter_1", COUNTER_CLASS, EntityKind::Rigid, &top),
        ];
        let graph = build_contact_graph(&entities, &ContactGraphParams::default());
        assert_eq!(graph.parent_of("counter_1"), Some("floor"), "{graph:?}");
        // Its box reaches down to the floor it stands on.
        let node = graph.node("counter_1").expect("counter");
        let bottom = node.bbox.center[2] - node.bbox.size[2] / 2.0;
        assert!(bottom.abs() < 0.02, "{:?}", node.bbox);
    }

    #[test]
    fn a_cabinet_seen_as_its_top_over_an_unseen_floor_stands_on_it_a_wall_unit_still_hangs() {
        // A floor seen only in front of a wall at y = 3 (y < 2.3); against the wall a cabinet
        // seen as its top 20 cm (0.35-0.55 m: a bed hid the rest), and a wall unit at 1.4-1.9 m.
        let floor = TriMesh::cuboid(Vec3::new(0.0, 0.0, -0.02), Vec3::new(4.0, 2.3, 0.0));
        let wall = TriMesh::cuboid(Vec3::new(0.0, 3.0, 0.0), Vec3::new(4.0, 3.02, 2.5));
        let low = TriMesh::cuboid(Vec3::new(1.0, 2.4, 0.35), Vec3::new(1.45, 3.0, 0.55));
        let high = TriMesh::cuboid(Vec3::new(2.5, 2.65, 1.4), Vec3::new(3.3, 3.0, 1.9));
        let graph_with = |floor: &TriMesh| {
            let entity = |id, class, kind, mesh| GraphEntity {
                id,
                class,
                kind,
                mesh,
                sighted: &[],
            };
            let entities = [
                entity("floor", "floor", EntityKind::Layout, floor),
                entity("wall_0", "wall", EntityKind::Layout, &wall),
                entity("cabinet_1", "cabinet", EntityKind::Articulated, &low),
                entity("cabinet_2", "cabinet", EntityKind::Articulated, &high),
            ];
            build_contact_graph(&entities, &ContactGraphParams::default())
        };
        let graph = graph_with(&floor);
        assert_eq!(graph.parent_of("cabinet_1"), Some("floor"), "{graph:?}");
        let node = graph.node("cabinet_1").expect("cabinet");
        let bottom = node.bbox.center[2] - node.bbox.size[2] / 2.0;
        assert!(
            bottom.abs() < 0.02,
            "its box reaches the floor: {:?}",
            node.bbox
        );
        assert_eq!(graph.parent_of("cabinet_2"), Some("wall_0"), "{graph:?}");
        // With the floor under it seen, the low unit hangs where it was seen.
        let seen = TriMesh::cuboid(Vec3::new(0.0, 0.0, -0.02), Vec3::new(4.0, 3.0, 0.0));
        let graph = graph_with(&seen);
        assert_ne!(graph.parent_of("cabinet_1"), Some("floor"), "{graph:?}");
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
