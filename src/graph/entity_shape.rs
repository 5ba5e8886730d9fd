//! Each entity's geometry for the contact graph: a layout piece's plane and slab, an object's
//! surface points without what lies on the layout, its largest piece, its box and its planes.

use glam::Vec3;

use crate::geometry::clusters::in_largest_cluster;
use crate::geometry::ransac::{RansacParams, ransac_planes};
use crate::geometry::surface_points::surface_points;
use crate::geometry::{GravityBox, Plane, TriMesh};
use crate::graph::build::{ContactGraphParams, GraphEntity};
use crate::graph::layout_plane::layout_plane;
use crate::graph::sparse_ends::keep_dense_extent;

/// Layout boxes are slabs this thick behind their surface (as in the ground truth).
pub const LAYOUT_THICKNESS: f32 = 0.1;

/// An entity's geometry for the graph: surface points (with their normals for objects), box,
/// planes.
pub(super) struct Shape {
    pub(super) points: Vec<Vec3>,
    pub(super) normals: Vec<Vec3>,
    pub(super) bbox: GravityBox,
    pub(super) planes: Vec<Plane>,
}

/// Whether a surface point with normal `n` lies on `surface` (less than `band` in front of it, or
/// behind it) and faces the way it does: then it is that surface, whatever label it took.
pub(super) fn lies_on(surface: &Plane, p: Vec3, n: Vec3, band: f32) -> bool {
    surface.signed_distance(p) < band && n.dot(surface.normal) > 0.85
}

/// The middle of the room: the centre of the floor if there is one, else of everything.
pub(super) fn room_center(entities: &[GraphEntity]) -> Vec3 {
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

pub(super) fn layout_shape(
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

pub(super) fn object_shape(
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
