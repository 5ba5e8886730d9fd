//! How deep two convex pieces interpenetrate, by the separating axis theorem.
//!
//! parry's contact query (GJK, then EPA for the depth) reports two interpenetrating hulls whose
//! faces lie in one plane as touching with depth 0: a cup standing on the table exactly where a
//! book lies, bottoms coplanar, came out 0 deep and a generated room with the cup 2 cm inside
//! the book passed the overlap check. For convex polyhedra the least separating translation lies
//! along a face normal of one of them or along the cross product of an edge of each, so testing
//! those axes gives the exact depth whatever the degeneracy.

use glam::{Affine3A, Vec3};
use parry3d::math::Pose;
use parry3d::shape::ConvexPolyhedron;

/// A depth parry's EPA reports beyond this (metres) is taken as it is; at or under it the pieces
/// may be touching or degenerate, and the separating axes decide.
const TRUSTED_EPA_DEPTH: f32 = 1e-4;
/// The most edge-pair axes tested.
const MAX_EDGE_AXES: usize = 4096;
/// Axes closer than this to zero length (cross products of parallel edges) are skipped.
const MIN_AXIS_LENGTH: f32 = 1e-6;

/// The depth (metres, > 0) and direction (unit, out of `a` towards `b`) of the least translation
/// of `b` that separates it from `a`, both placed by their poses; `None` when they do not
/// interpenetrate.
pub fn convex_penetration(
    a: &ConvexPolyhedron,
    pose_a: &Affine3A,
    b: &ConvexPolyhedron,
    pose_b: &Affine3A,
) -> Option<(f32, Vec3)> {
    let (pa, pb) = (rigid_pose(pose_a), rigid_pose(pose_b));
    match parry3d::query::contact(&pa, a, &pb, b, 0.0) {
        Ok(Some(c)) if c.dist < -TRUSTED_EPA_DEPTH => return Some((-c.dist, c.normal1)),
        Ok(None) => return None,
        // Touching, or interpenetrating in a way EPA cannot tell from touching.
        _ => {}
    }
    if !parry3d::query::intersection_test(&pa, a, &pb, b).unwrap_or(false) {
        return None;
    }
    separating_axis_depth(a, pose_a, b, pose_b)
}

/// The separating-axis depth: face normals of both, and the cross products of their edge
/// directions unless there are more than `MAX_EDGE_AXES` (then the face normals alone, which
/// bound the depth from above).
fn separating_axis_depth(
    a: &ConvexPolyhedron,
    pose_a: &Affine3A,
    b: &ConvexPolyhedron,
    pose_b: &Affine3A,
) -> Option<(f32, Vec3)> {
    let points_a: Vec<Vec3> = a
        .points()
        .iter()
        .map(|p| pose_a.transform_point3(*p))
        .collect();
    let points_b: Vec<Vec3> = b
        .points()
        .iter()
        .map(|p| pose_b.transform_point3(*p))
        .collect();
    let normals = |shape: &ConvexPolyhedron, pose: &Affine3A| -> Vec<Vec3> {
        shape
            .faces()
            .iter()
            .map(|f| pose.transform_vector3(f.normal))
            .collect()
    };
    let edges = |shape: &ConvexPolyhedron, pose: &Affine3A| -> Vec<Vec3> {
        let mut dirs: Vec<Vec3> = Vec::new();
        for e in shape.edges() {
            let d = pose.transform_vector3(e.dir).normalize_or_zero();
            // Parallel edges (a cylinder's sides) give the same axes.
            if d != Vec3::ZERO && dirs.iter().all(|o| o.cross(d).length() > 1e-4) {
                dirs.push(d);
            }
        }
        dirs
    };
    let mut axes = normals(a, pose_a);
    axes.extend(normals(b, pose_b));
    let (edges_a, edges_b) = (edges(a, pose_a), edges(b, pose_b));
    let pairs = if edges_a.len() * edges_b.len() <= MAX_EDGE_AXES {
        edges_a.len()
    } else {
        0
    };
    for ea in &edges_a[..pairs] {
        for eb in &edges_b {
            let axis = ea.cross(*eb);
            if axis.length() > MIN_AXIS_LENGTH {
                axes.push(axis.normalize());
            }
        }
    }
    let extent = |points: &[Vec3], axis: Vec3| {
        points
            .iter()
            .map(|p| p.dot(axis))
            .fold((f32::MAX, f32::MIN), |(lo, hi), t| (lo.min(t), hi.max(t)))
    };
    let mut least: Option<(f32, Vec3)> = None;
    for axis in axes {
        let (alo, ahi) = extent(&points_a, axis);
        let (blo, bhi) = extent(&points_b, axis);
        // Moving b along +axis clears it by ahi - blo, along -axis by bhi - alo.
        let (depth, direction) = if ahi - blo <= bhi - alo {
            (ahi - blo, axis)
        } else {
            (bhi - alo, -axis)
        };
        if depth <= 0.0 {
            return None;
        }
        if least.is_none_or(|(d, _)| depth < d) {
            least = Some((depth, direction));
        }
    }
    least
}

/// A parry pose of the rigid part of `a`.
/// parry's pose of a rigid affine transform (any scale dropped).
pub fn rigid_pose(a: &Affine3A) -> Pose {
    let (_, rotation, translation) = a.to_scale_rotation_translation();
    Pose::from_parts(translation, rotation.normalize())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cuboid(lo: Vec3, hi: Vec3) -> ConvexPolyhedron {
        let corners: Vec<Vec3> = (0..8)
            .map(|i| {
                Vec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                )
            })
            .collect();
        ConvexPolyhedron::from_convex_hull(&corners).expect("a box")
    }

    fn cylinder(center: Vec3, radius: f32, lo: f32, hi: f32) -> ConvexPolyhedron {
        let points: Vec<Vec3> = (0..32)
            .flat_map(|k| {
                let t = k as f32 / 32.0 * std::f32::consts::TAU;
                let p = center + Vec3::new(radius * t.cos(), radius * t.sin(), 0.0);
                [p.with_z(lo), p.with_z(hi)]
            })
            .collect();
        ConvexPolyhedron::from_convex_hull(&points).expect("a cylinder")
    }

    #[test]
    fn coplanar_bottoms_give_the_full_depth() {
        // A book 2 cm thick and a cup standing where it lies, both on z = 0.47.
        let book = cuboid(Vec3::new(-0.1, -0.12, 0.47), Vec3::new(0.1, 0.12, 0.49));
        let cup = cylinder(Vec3::new(0.02, 0.01, 0.0), 0.04, 0.47, 0.57);
        let id = Affine3A::IDENTITY;
        let (depth, direction) = convex_penetration(&book, &id, &cup, &id).expect("overlap");
        assert!((depth - 0.02).abs() < 1e-5, "{depth}");
        assert!(direction.z > 0.999, "{direction}");
    }

    #[test]
    fn touching_and_apart_are_not_penetrating_and_poses_apply() {
        let a = cuboid(Vec3::ZERO, Vec3::ONE);
        let b = cuboid(Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 1.0, 2.0));
        let id = Affine3A::IDENTITY;
        assert!(convex_penetration(&a, &id, &b, &id).is_none());
        let lowered = Affine3A::from_translation(Vec3::new(0.3, 0.2, -0.1));
        let (depth, direction) = convex_penetration(&a, &id, &b, &lowered).expect("overlap");
        assert!(
            (depth - 0.1).abs() < 1e-5 && direction.z > 0.999,
            "{depth} {direction}"
        );
        let turned = Affine3A::from_rotation_translation(
            glam::Quat::from_rotation_z(0.5),
            Vec3::new(3.0, 0.0, 0.0),
        );
        assert!(convex_penetration(&a, &id, &b, &turned).is_none());
    }
}
