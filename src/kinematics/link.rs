//! The links a contact-graph node becomes: what each is made of (visual mesh, convex collision
//! pieces, mass properties, friction) and, for the parts of an articulated CAD model, where each
//! sits on its parent and how it moves.
//!
//! A CAD model is placed with a per-axis scale, but links are rigid frames. The object's link is
//! the rigid part of the placement and carries the scale in its mesh; each moving part gets a
//! rigid frame at its scaled origin, its mesh scaled in that frame and its joint axis turned
//! with the scale (a drawer of a widened cabinet slides as far as the cabinet is deep).

use glam::{Affine3A, Mat3, Vec2, Vec3};

use crate::cad::model::CadModel;
use crate::classes::{ClassTable, EntityKind};
use crate::geometry::{GravityBox, Plane, TriMesh};
use crate::graph::GraphNode;
use crate::kinematics::JointSpec;
use crate::kinematics::inertial::Inertial;
use crate::kinematics::observed::SeenShape;

/// Thickness given to the floor and ceiling slabs and the least given to a wall.
pub const LAYOUT_THICKNESS_M: f32 = 0.05;

/// How far the floor slab reaches beyond the floor's observed footprint.
const FLOOR_MARGIN_M: f32 = 0.5;

/// What a link is made of, in the link's frame.
#[derive(Clone, Debug)]
pub struct LinkGeometry {
    /// What it looks like (the URDF's and the .glb's visual mesh).
    pub visual: TriMesh,
    /// Its exact collision surface: static bodies collide as this triangle mesh, and the
    /// simulator's navigation and placement read it. The visual mesh but for imported models
    /// with visual geometry of their own.
    pub surface: TriMesh,
    /// Linear RGB in 0..1.
    pub color: [f32; 3],
    /// Convex pieces covering the surface (`TriMesh::collision_pieces`: the hull of each
    /// connected component, a hollow one decomposed, open where it is open): what the arm
    /// plans around, the joint sweeps check and the URDF and MJCF exports collide with.
    pub collision: Vec<TriMesh>,
    /// The hull of each connected component: what rapier simulates. Resting and being knocked
    /// depend on the outside only, and a decomposed cup's pieces made the rest test of the
    /// kitchen 8 times slower (600 ms a step instead of 70, test build, 2026-11-28).
    pub hulls: Vec<TriMesh>,
    pub inertial: Inertial,
    pub friction: f32,
}

impl LinkGeometry {
    /// Collision pieces, mass and friction of `visual`, which is also its surface, for a link of
    /// `class`.
    pub fn new(visual: TriMesh, color: [f32; 3], class: &str) -> Self {
        let (hulls, collision) = visual.hulls_and_collision_pieces();
        Self::of_pieces(visual, color, class, hulls, collision)
    }

    /// What `look` shows of a body whose convex `pieces` are known (an arm's link: its visual
    /// meshes and collision pieces from its URDF), for a link of `class`.
    pub fn of_look(look: TriMesh, pieces: Vec<TriMesh>, color: [f32; 3], class: &str) -> Self {
        Self::of_pieces(look, color, class, pieces.clone(), pieces)
    }

    /// `visual`, also its surface, colliding as `collision` in the planners and exports and as
    /// `hulls` in rapier, with the mass and friction of `class`.
    fn of_pieces(
        visual: TriMesh,
        color: [f32; 3],
        class: &str,
        hulls: Vec<TriMesh>,
        collision: Vec<TriMesh>,
    ) -> Self {
        let info = ClassTable::builtin().get(class);
        let density = info.map_or(500.0, |c| c.density);
        let friction = info.map_or(0.5, |c| c.friction);
        let inertial = Inertial::of_mesh(&visual, density);
        Self {
            surface: visual.clone(),
            visual,
            color,
            collision,
            hulls,
            inertial,
            friction,
        }
    }

    /// What the map saw of an object no model replaced (`seen`, in the link's frame), for a link
    /// of `class`: it collides and rests as the convex pieces along its surface and its support
    /// patches, so what stands in or on it starts where it was seen, not inside the hull of its
    /// parent. `None` when the surface spans no volume (a counter found from a few points of its
    /// top, one plane): its patches alone are no object.
    pub fn observed(seen: &SeenShape, color: [f32; 3], class: &str) -> Option<Self> {
        let mut pieces = seen.surface.surface_pieces();
        if pieces.is_empty() {
            return None;
        }
        pieces.extend(seen.supports.iter().cloned());
        let mut visual = seen.surface.clone();
        for patch in &seen.supports {
            visual.append(patch);
        }
        // It stays fixed in every check and every export; its mass is its hull's, as for any
        // open surface.
        Some(Self::of_pieces(
            visual,
            color,
            class,
            pieces.clone(),
            pieces,
        ))
    }
}

/// One link of a node: the node's own link (first) or a moving part of its CAD model.
#[derive(Clone, Debug)]
pub struct NodeLink {
    /// The part's name in the model (`door`, `drawer_1`); `None` for the node's own link.
    pub part: Option<String>,
    /// Index of the parent among the node's links (`None` for the node's own link).
    pub parent: Option<usize>,
    /// The link's frame in its parent's at joint value zero (identity for the node's own link,
    /// whose place is the support tree's).
    pub parent_from_link: Affine3A,
    pub joint: JointSpec,
    /// The joint value the contact graph records (0 when none).
    pub value: f32,
    pub geometry: LinkGeometry,
}

/// The links of `node`, whose own frame is `world_from_link` (the rigid part of its CAD
/// placement, else its box). `model` is its CAD model when it was replaced; `seen` is what an
/// object no model replaced is made of (`observed::seen_shape`, world frame; its box when none is
/// given or its surface spans no volume); `floor` is the floor node, which tells walls which side
/// is the room's.
pub fn node_links(
    node: &GraphNode,
    model: Option<&CadModel>,
    seen: Option<&SeenShape>,
    world_from_link: Affine3A,
    floor: Option<&GraphNode>,
) -> Vec<NodeLink> {
    let link_from_world = world_from_link.inverse();
    if let (Some(model), Some(cad)) = (model, node.cad.as_ref()) {
        let world_from_model =
            Affine3A::from_mat4(glam::Mat4::from_cols_array(&cad.world_from_model));
        let link_from_model = link_from_world * world_from_model;
        return cad_links(node, model, link_from_model);
    }
    let color = match node.kind {
        EntityKind::Layout => [0.75, 0.73, 0.70],
        _ => [0.55, 0.55, 0.6],
    };
    let observed = seen
        .filter(|_| node.kind != EntityKind::Layout)
        .and_then(|seen| {
            LinkGeometry::observed(&seen.transformed(&link_from_world), color, &node.class)
        });
    if let Some(geometry) = observed {
        return vec![NodeLink::own(geometry)];
    }
    let gbox = GravityBox::from(&node.bbox);
    let world_mesh = match (node.kind, node.class.as_str()) {
        (EntityKind::Layout, "floor") => floor_slab(node, &gbox),
        (EntityKind::Layout, "ceiling") => {
            let bottom = gbox.bottom_z();
            slab(&gbox, Vec2::ZERO, bottom, bottom + LAYOUT_THICKNESS_M)
        }
        (EntityKind::Layout, _) => {
            wall_block(&gbox, floor.map(|f| Vec3::from_array(f.bbox.center)))
        }
        _ => TriMesh::cuboid_centered(gbox.center, gbox.size.max(Vec3::splat(0.01)))
            .transformed(&Affine3A::from_rotation_z(gbox.yaw).with_fixed_point(gbox.center)),
    };
    vec![NodeLink::own(LinkGeometry::new(
        world_mesh.transformed(&link_from_world),
        color,
        &node.class,
    ))]
}

impl NodeLink {
    /// The node's own link made of `geometry`, its only one.
    fn own(geometry: LinkGeometry) -> Self {
        Self {
            part: None,
            parent: None,
            parent_from_link: Affine3A::IDENTITY,
            joint: JointSpec::FIXED,
            value: 0.0,
            geometry,
        }
    }
}

/// Rotation about a fixed point, for boxes turned about their centre.
trait WithFixedPoint {
    fn with_fixed_point(self, point: Vec3) -> Affine3A;
}

impl WithFixedPoint for Affine3A {
    fn with_fixed_point(self, point: Vec3) -> Affine3A {
        Affine3A::from_translation(point) * self * Affine3A::from_translation(-point)
    }
}

/// A model's parts as links: part 0 is the node's own link (`link_from_model` places the model
/// in it, scale included); every other part gets a rigid frame at its scaled origin.
fn cad_links(node: &GraphNode, model: &CadModel, link_from_model: Affine3A) -> Vec<NodeLink> {
    let (scale, rotation, translation) = link_from_model.to_scale_rotation_translation();
    let link_rotation = Affine3A::from_rotation_translation(rotation, translation);
    let scale_matrix = Mat3::from_diagonal(scale);
    let model_from_parts = model.model_from_parts(&[]);
    // Each part's rigid frame in the node's link frame.
    let frames: Vec<Affine3A> = model_from_parts
        .iter()
        .map(|model_from_part| {
            let (_, r, t) = model_from_part.to_scale_rotation_translation();
            link_rotation * Affine3A::from_rotation_translation(r, scale * t)
        })
        .collect();
    model
        .parts
        .iter()
        .enumerate()
        .map(|(k, part)| {
            let (_, r, _) = model_from_parts[k].to_scale_rotation_translation();
            let part_rotation = Mat3::from_quat(r);
            // The scale as seen in the part's frame: R^-1 S R.
            let scale_in_part = part_rotation.transpose() * scale_matrix * part_rotation;
            let in_link = Affine3A::from_mat3(scale_in_part);
            let mut geometry =
                LinkGeometry::new(part.mesh.transformed(&in_link), part.color, &node.class);
            if let Some(visual) = &part.visual {
                geometry.visual = visual.transformed(&in_link);
            }
            let (parent, parent_from_link, joint) = match (k, part.parent) {
                (0, _) | (_, None) => (None, Affine3A::IDENTITY, JointSpec::FIXED),
                (_, Some(p)) => (
                    Some(p),
                    frames[p].inverse() * frames[k],
                    scaled_joint(&part.joint, scale_in_part),
                ),
            };
            let value = node.joints.get(&part.name).copied().unwrap_or(0.0);
            NodeLink {
                part: (k > 0).then(|| part.name.clone()),
                parent,
                parent_from_link,
                joint,
                value: joint.clamp(value),
                geometry,
            }
        })
        .collect()
}

/// The joint of a part whose frame sees the scale `scale_in_part`: the axis turns with it, and a
/// prismatic joint's travel stretches with the axis.
fn scaled_joint(joint: &JointSpec, scale_in_part: Mat3) -> JointSpec {
    let stretched = scale_in_part * joint.axis;
    let Some(axis) = stretched.try_normalize() else {
        return *joint;
    };
    let stretch = stretched.length();
    let limits = match joint.kind {
        crate::kinematics::JointKind::Prismatic => {
            joint.limits.map(|(lo, hi)| (lo * stretch, hi * stretch))
        }
        _ => joint.limits,
    };
    JointSpec {
        kind: joint.kind,
        axis,
        limits,
    }
}

/// A slab over the box's footprint grown by `margin` (x, y in the box frame), from `bottom` to
/// `top`, in world coordinates.
fn slab(gbox: &GravityBox, margin: Vec2, bottom: f32, top: f32) -> TriMesh {
    let half = gbox.size.truncate() / 2.0 + margin;
    let center = gbox.center.truncate().extend((bottom + top) / 2.0);
    TriMesh::cuboid_centered(center, (2.0 * half).extend(top - bottom))
        .transformed(&Affine3A::from_rotation_z(gbox.yaw).with_fixed_point(center))
}

/// The floor: a slab whose top face lies in the floor's plane (so objects snapped onto that
/// plane rest on it exactly, even where it tilts a little), reaching past the observed floor.
fn floor_slab(node: &GraphNode, gbox: &GravityBox) -> TriMesh {
    let plane = node
        .planes
        .iter()
        .map(|p| Plane::from_array(*p))
        .find(|p| p.normal.z > 0.9)
        .unwrap_or(Plane {
            normal: Vec3::Z,
            offset: -gbox.top_z(),
        });
    let half = gbox.size.truncate() / 2.0 + Vec2::splat(FLOOR_MARGIN_M);
    let world_from_box = gbox.world_from_box();
    let height_at =
        |xy: Vec2| -(plane.normal.x * xy.x + plane.normal.y * xy.y + plane.offset) / plane.normal.z;
    let mut corners = Vec::with_capacity(8);
    for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
        let xy = world_from_box
            .transform_point3(Vec3::new(sx * half.x, sy * half.y, 0.0))
            .truncate();
        let top = height_at(xy);
        corners.push(xy.extend(top));
        corners.push(xy.extend(top - LAYOUT_THICKNESS_M));
    }
    TriMesh {
        positions: corners,
        triangles: Vec::new(),
    }
    .convex_hull()
    .unwrap_or_else(|| slab(gbox, Vec2::ZERO, -LAYOUT_THICKNESS_M, 0.0))
}

/// A wall: its box thickened to at least `LAYOUT_THICKNESS_M`, growing away from the room's
/// middle so the room keeps its size.
fn wall_block(gbox: &GravityBox, room_middle: Option<Vec3>) -> TriMesh {
    let thin_is_x = gbox.size.x < gbox.size.y;
    let thin_axis = if thin_is_x { Vec3::X } else { Vec3::Y };
    let thin_world = glam::Quat::from_rotation_z(gbox.yaw) * thin_axis;
    let thickness = if thin_is_x { gbox.size.x } else { gbox.size.y };
    let grow = (LAYOUT_THICKNESS_M - thickness).max(0.0);
    let outward = match room_middle {
        Some(m) if (gbox.center - m).truncate().dot(thin_world.truncate()) < 0.0 => -thin_world,
        _ => thin_world,
    };
    let mut grown = *gbox;
    grown.center += outward * grow / 2.0;
    if thin_is_x {
        grown.size.x += grow;
    } else {
        grown.size.y += grow;
    }
    slab(&grown, Vec2::ZERO, grown.bottom_z(), grown.top_z())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cad::ParametricLibrary;
    use crate::graph::{BoxJson, CadPlacement};
    use crate::kinematics::JointKind;
    use crate::kinematics::observed::{INTO_LAYOUT_SLACK_M, observed_surface};

    fn node(id: &str, class: &str, kind: EntityKind, gbox: GravityBox) -> GraphNode {
        GraphNode {
            id: id.into(),
            class: class.into(),
            kind,
            bbox: BoxJson::from(gbox),
            planes: Vec::new(),
            cad: None,
            joints: Default::default(),
            parts: Vec::new(),
        }
    }

    #[test]
    fn a_wall_thickens_away_from_the_room() {
        let floor = node(
            "floor",
            "floor",
            EntityKind::Layout,
            GravityBox {
                center: Vec3::new(2.0, 2.0, 0.0),
                yaw: 0.0,
                size: Vec3::new(4.0, 4.0, 0.0),
            },
        );
        let wall_box = GravityBox {
            center: Vec3::new(4.0, 2.0, 1.3),
            yaw: 0.0,
            size: Vec3::new(0.01, 4.0, 2.6),
        };
        let wall = node("wall_0", "wall", EntityKind::Layout, wall_box);
        let links = node_links(&wall, None, None, wall_box.world_from_box(), Some(&floor));
        let (lo, hi) = links[0].geometry.visual.bounds().expect("mesh");
        let lo = lo + wall_box.center;
        let hi = hi + wall_box.center;
        assert!((lo.x - 3.995).abs() < 1e-4, "inner face stays: {lo}");
        assert!((hi.x - (3.995 + LAYOUT_THICKNESS_M)).abs() < 1e-4, "{hi}");
    }

    #[test]
    fn the_floor_slab_lies_under_its_plane() {
        let gbox = GravityBox {
            center: Vec3::new(2.0, 2.0, 0.0),
            yaw: 0.0,
            size: Vec3::new(4.0, 4.0, 0.0),
        };
        let mut floor = node("floor", "floor", EntityKind::Layout, gbox);
        floor.planes = vec![[0.0, 0.0, 1.0, -0.01]];
        let links = node_links(&floor, None, None, gbox.world_from_box(), None);
        let (lo, hi) = links[0].geometry.visual.bounds().expect("mesh");
        assert!((hi.z - 0.01).abs() < 1e-5 && (lo.z - (0.01 - LAYOUT_THICKNESS_M)).abs() < 1e-5);
        assert!((hi.x - lo.x - (4.0 + 2.0 * FLOOR_MARGIN_M)).abs() < 1e-4);
        assert_eq!(links[0].geometry.collision.len(), 1);
    }

    /// The surface of the box from `lo` to `hi` in triangles of about `step`, as a map's mesh is.
    fn fine_cuboid(lo: Vec3, hi: Vec3, step: f32) -> TriMesh {
        let mut mesh = TriMesh::default();
        for axis in 0..3 {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let (nu, nv) = (
                ((hi[u] - lo[u]) / step).ceil().max(1.0) as u32,
                ((hi[v] - lo[v]) / step).ceil().max(1.0) as u32,
            );
            for side in [lo[axis], hi[axis]] {
                let base = mesh.positions.len() as u32;
                for i in 0..=nu {
                    for j in 0..=nv {
                        let mut p = Vec3::ZERO;
                        p[axis] = side;
                        p[u] = lo[u] + (hi[u] - lo[u]) * i as f32 / nu as f32;
                        p[v] = lo[v] + (hi[v] - lo[v]) * j as f32 / nv as f32;
                        mesh.positions.push(p);
                    }
                }
                let at = |i: u32, j: u32| base + i * (nv + 1) + j;
                let outwards = side == hi[axis];
                for i in 0..nu {
                    for j in 0..nv {
                        let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                        if outwards {
                            mesh.triangles.extend([[a, b, c], [a, c, d]]);
                        } else {
                            mesh.triangles.extend([[a, c, b], [a, d, c]]);
                        }
                    }
                }
            }
        }
        mesh
    }

    #[test]
    fn an_object_no_model_replaced_is_made_of_what_was_seen_with_room_between_its_boards() {
        // A shelf as the map saw it (triangles of a voxel's size): two sides and three boards,
        // 2 cm thick; its box (what it was made of before) is solid where the bottles stand.
        let mut seen = TriMesh::default();
        for (lo, hi) in [
            (Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.02, 0.3, 1.0)),
            (Vec3::new(0.78, 0.0, 0.0), Vec3::new(0.8, 0.3, 1.0)),
            (Vec3::new(0.02, 0.0, 0.0), Vec3::new(0.78, 0.3, 0.02)),
            (Vec3::new(0.02, 0.0, 0.49), Vec3::new(0.78, 0.3, 0.51)),
            (Vec3::new(0.02, 0.0, 0.98), Vec3::new(0.78, 0.3, 1.0)),
        ] {
            seen.append(&fine_cuboid(lo, hi, 0.02));
        }
        let gbox = GravityBox {
            center: Vec3::new(0.4, 0.15, 0.5),
            yaw: 0.0,
            size: Vec3::new(0.8, 0.3, 1.0),
        };
        let shelf = node("shelf_1", "shelf", EntityKind::Rigid, gbox);
        let world_from_link = gbox.world_from_box();
        let seen = SeenShape {
            surface: seen,
            supports: Vec::new(),
        };
        let links = node_links(&shelf, None, Some(&seen), world_from_link, None);
        assert_eq!(links.len(), 1);
        let g = &links[0].geometry;
        assert_eq!(g.hulls, g.collision, "rapier collides as the exports do");
        let inside = |world: Vec3| {
            let p = world_from_link.inverse().transform_point3(world);
            g.hulls.iter().any(|piece| {
                (0..piece.triangles.len()).all(|i| {
                    let [a, _, _] = piece.triangle(i);
                    piece.face_normal(i).dot(p - a) <= 0.0
                })
            })
        };
        for level in [0.25, 0.75] {
            for x in [0.1, 0.33, 0.6] {
                assert!(
                    !inside(Vec3::new(x, 0.1, level)),
                    "level at {level} is open"
                );
            }
        }
        // What rests on a board rests on a piece: points just under each board's top are in
        // the pieces but on seams between them, up to a triangle wide (a triangle belongs to one
        // piece only; here a row of 15 of the 75 points).
        for top in [0.02, 0.51, 1.0] {
            let grid: Vec<Vec3> = (1..16)
                .flat_map(|i| {
                    (1..6).map(move |j| Vec3::new(0.05 * i as f32, 0.05 * j as f32, top - 0.003))
                })
                .collect();
            let held = grid.iter().filter(|p| inside(**p)).count();
            assert!(
                held * 4 >= grid.len() * 3,
                "board at {top}: {held} of {}",
                grid.len()
            );
        }
        // A surface that spans no volume (a counter's top points) keeps the box.
        let flat = TriMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            triangles: Vec::new(),
        };
        let flat = SeenShape {
            surface: flat,
            supports: Vec::new(),
        };
        let links = node_links(&shelf, None, Some(&flat), world_from_link, None);
        assert_eq!(links[0].geometry.hulls.len(), 1);
        let (lo, hi) = links[0].geometry.visual.bounds().expect("the box");
        assert!(((hi - lo) - gbox.size).abs().max_element() < 1e-5);
    }

    #[test]
    fn an_unmodelled_table_keeps_its_own_surface_and_holds_what_stands_on_it() {
        // A table top seen with a hole where a cup hides it, the cup's side bled into the
        // table's segment, and a strip of the wall behind past the table's box.
        let top = Vec3::new(1.0, 1.0, 0.75);
        let cup = GravityBox {
            center: Vec3::new(1.2, 1.0, 0.8),
            yaw: 0.0,
            size: Vec3::new(0.08, 0.08, 0.1),
        };
        let mut seen = fine_cuboid(top - Vec3::new(0.6, 0.4, 0.03), top, 0.02)
            .filtered(|t| t.iter().any(|p| !cup.contains(*p, 0.0) || p.z < 0.74));
        seen.append(&fine_cuboid(
            Vec3::new(1.16, 0.96, 0.76),
            Vec3::new(1.17, 1.04, 0.84),
            0.02,
        ));
        let wall_strip = fine_cuboid(Vec3::new(0.3, 1.45, 0.2), Vec3::new(1.6, 1.47, 1.0), 0.05);
        seen.append(&wall_strip);
        let table = GravityBox {
            center: top - Vec3::new(0.0, 0.0, 0.375),
            yaw: 0.0,
            size: Vec3::new(1.2, 0.8, 0.75),
        };
        let shape = observed_surface(&seen, &table, &[cup], &[cup], &[]);
        let (lo, hi) = shape.surface.bounds().expect("the top");
        assert!(
            hi.y < 1.41 && lo.y > 0.59,
            "the wall's strip is not the table's"
        );
        assert!(
            shape
                .surface
                .positions
                .iter()
                .all(|p| !cup.contains(*p, 0.0)),
            "nor is the cup's side"
        );
        assert_eq!(shape.supports.len(), 1);
        let (plo, phi) = shape.supports[0].bounds().expect("a patch");
        assert!(
            (phi.z - cup.bottom_z()).abs() < 1e-5,
            "the cup stands on its patch"
        );
        assert!(plo.x <= cup.center.x - 0.04 + 1e-5 && phi.x >= cup.center.x + 0.04 - 1e-5);
        // As the table's link: the patch is a piece of its own under the cup.
        let node = node("table_1", "table", EntityKind::Rigid, table);
        let links = node_links(&node, None, Some(&shape), table.world_from_box(), None);
        let g = &links[0].geometry;
        let under_cup = table
            .world_from_box()
            .inverse()
            .transform_point3(cup.center.truncate().extend(cup.bottom_z() - 0.005));
        let holding = g.hulls.iter().filter(|piece| {
            (0..piece.triangles.len()).all(|i| {
                let [a, _, _] = piece.triangle(i);
                piece.face_normal(i).dot(under_cup - a) <= 0.0
            })
        });
        assert!(holding.count() >= 1);
    }

    #[test]
    fn what_an_unmodelled_object_is_made_of_stops_at_the_layout() {
        // A tall "book" segment of the wall over a cabinet (seed 1): a sheet of the map from
        // 4 cm behind the wall's face at x = 0 to 3 cm in front of it.
        let slab = GravityBox {
            center: Vec3::new(-0.005, 2.6, 1.85),
            yaw: 0.0,
            size: Vec3::new(0.07, 0.23, 1.87),
        };
        let seen = fine_cuboid(
            Vec3::new(-0.04, 2.49, 0.92),
            Vec3::new(0.03, 2.71, 2.78),
            0.02,
        );
        let wall = GravityBox {
            center: Vec3::new(-0.05, 2.5, 1.4),
            yaw: 0.0,
            size: Vec3::new(0.1, 5.0, 2.8),
        };
        let unclipped = observed_surface(&seen, &slab, &[], &[], &[]);
        let (lo, _) = unclipped.surface.bounds().expect("a surface");
        assert!(lo.x < -0.03, "the sheet reaches behind the wall: {lo}");
        let clipped = observed_surface(&seen, &slab, &[], &[], &[wall]);
        let (lo, hi) = clipped.surface.bounds().expect("its front");
        assert!(
            lo.x >= -INTO_LAYOUT_SLACK_M,
            "nothing behind the face: {lo}"
        );
        assert!(hi.x > 0.025, "what stands before the wall stays: {hi}");
        // A wall elsewhere (past the sheet's end along it) cuts nothing.
        let elsewhere = GravityBox {
            center: Vec3::new(-0.05, 6.0, 1.4),
            ..wall
        };
        let kept = observed_surface(&seen, &slab, &[], &[], &[elsewhere]);
        assert_eq!(
            kept.surface.triangles.len(),
            unclipped.surface.triangles.len()
        );
    }

    #[test]
    fn a_scaled_cabinet_keeps_rigid_part_frames_and_stretches_drawer_travel() {
        let model = ParametricLibrary::entries()
            .iter()
            .map(|e| e.model())
            .find(|m| m.parts.iter().any(|p| p.joint.kind == JointKind::Prismatic))
            .expect("a model with a drawer");
        let scale = Vec3::new(1.5, 2.0, 1.0);
        let world_from_model = Affine3A::from_scale_rotation_translation(
            scale,
            glam::Quat::from_rotation_z(0.3),
            Vec3::new(1.0, 2.0, 0.0),
        );
        let mut n = node(
            "cabinet_1",
            &model.class,
            EntityKind::Articulated,
            GravityBox {
                center: Vec3::ZERO,
                yaw: 0.0,
                size: Vec3::ONE,
            },
        );
        n.cad = Some(CadPlacement {
            model: model.id.clone(),
            world_from_model: glam::Mat4::from(world_from_model).to_cols_array(),
            scale: 1.0,
            alignment_error: 0.0,
        });
        let rigid = Affine3A::from_rotation_translation(
            glam::Quat::from_rotation_z(0.3),
            Vec3::new(1.0, 2.0, 0.0),
        );
        let links = node_links(&n, Some(&model), None, rigid, None);
        assert_eq!(links.len(), model.parts.len());
        // The links, posed along the tree at joint zero, cover what the scaled model covers.
        let mut world_from_links: Vec<Affine3A> = Vec::new();
        let mut merged = TriMesh::default();
        for link in &links {
            let pose = match link.parent {
                Some(p) => world_from_links[p] * link.parent_from_link,
                None => rigid,
            };
            let (s, _, _) = pose.to_scale_rotation_translation();
            assert!((s - Vec3::ONE).abs().max_element() < 1e-4, "rigid frames");
            merged.append(&link.geometry.visual.transformed(&pose));
            world_from_links.push(pose);
        }
        let expected = model.merged_mesh(&[]).transformed(&world_from_model);
        let (a, b) = (merged.bounds().expect("m"), expected.bounds().expect("e"));
        assert!(a.0.distance(b.0) < 1e-4 && a.1.distance(b.1) < 1e-4);
        let (k, part) = model
            .parts
            .iter()
            .enumerate()
            .find(|(_, p)| p.joint.kind == JointKind::Prismatic)
            .expect("drawer");
        let travel = |j: &JointSpec| j.limits.map_or(0.0, |(lo, hi)| hi - lo);
        let stretch = (Mat3::from_diagonal(scale) * part.joint.axis).length();
        assert!((travel(&links[k].joint) - travel(&part.joint) * stretch).abs() < 1e-5);
    }
}
