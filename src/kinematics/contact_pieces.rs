//! Convex collision pieces as rapier can touch them.
//!
//! Rapier finds where two convex polyhedra touch from the faces they turn to each other, and
//! parry keeps only the first four corners of such a face (`ConvexPolyhedron::
//! local_support_feature`, "TODO: if there are more than 4 vertices"). A round table top is a
//! 40-gon: a book lying on it got contacts only in the sliver of those four corners at the rim,
//! sank through the top and fell 72 cm in the rest test, while MuJoCo, loading the same
//! exported files, kept it still. So every face with more than four corners also gets pieces of
//! its own: the face cut into triangles from its centre, each the base of a tetrahedron whose
//! apex is the piece's centre. The tetrahedra lie inside the piece, so they change
//! no shape and no mass (the bodies' masses are given, not derived from the colliders); they
//! only give the wide face contact points where it is really touched.

use glam::Vec3;
use parry3d::shape::ConvexPolyhedron;

/// Corners of a face parry uses whole.
const MAX_FEATURE_CORNERS: usize = 4;

/// The point sets of the convex pieces that stand for the convex hull of `points`: the hull
/// itself, and a tetrahedron over every triangle (from the face's centre) of a face with more
/// than four corners.
pub fn contact_pieces(points: &[Vec3]) -> Vec<Vec<Vec3>> {
    let mut pieces = vec![points.to_vec()];
    let Some(hull) = ConvexPolyhedron::from_convex_hull(points) else {
        return pieces;
    };
    let corners = hull.points();
    let centre = corners.iter().copied().sum::<Vec3>() / corners.len().max(1) as f32;
    let adjacent = hull.vertices_adj_to_face();
    for face in hull.faces() {
        let first = face.first_vertex_or_edge as usize;
        let count = face.num_vertices_or_edges as usize;
        if count <= MAX_FEATURE_CORNERS {
            continue;
        }
        let ring: Vec<Vec3> = adjacent[first..first + count]
            .iter()
            .map(|&v| corners[v as usize])
            .collect();
        // Triangles from the face's centre: a fan from one corner gives slivers, which parry
        // merges into faces of five corners again.
        let middle = ring.iter().copied().sum::<Vec3>() / count as f32;
        for k in 0..count {
            pieces.push(vec![middle, ring[k], ring[(k + 1) % count], centre]);
        }
    }
    pieces
}

#[cfg(test)]
mod tests {
    use super::*;

    fn disk(radius: f32, bottom: f32, top: f32, sides: usize) -> Vec<Vec3> {
        (0..sides)
            .flat_map(|k| {
                let t = k as f32 / sides as f32 * std::f32::consts::TAU;
                let p = Vec3::new(radius * t.cos(), radius * t.sin(), 0.0);
                [p.with_z(bottom), p.with_z(top)]
            })
            .collect()
    }

    #[test]
    fn a_box_stays_one_piece() {
        let corners: Vec<Vec3> = (0..8)
            .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, (i >> 2) as f32))
            .collect();
        assert_eq!(contact_pieces(&corners).len(), 1);
    }

    #[test]
    fn a_round_top_gets_tetrahedra_that_tile_its_caps_with_faces_of_at_most_four_corners() {
        let points = disk(0.45, 0.705, 0.74, 40);
        let pieces = contact_pieces(&points);
        // A tetrahedron over each of the 40 triangles of each cap.
        assert_eq!(pieces.len(), 1 + 2 * 40);
        let hull = ConvexPolyhedron::from_convex_hull(&points).expect("hull");
        let mut top_area = 0.0;
        for piece in &pieces[1..] {
            let p = ConvexPolyhedron::from_convex_hull(piece).expect("a tetrahedron");
            assert!(
                p.faces()
                    .iter()
                    .all(|f| f.num_vertices_or_edges as usize <= MAX_FEATURE_CORNERS)
            );
            // Inside the hull.
            for c in p.points() {
                assert!(c.z >= 0.705 - 1e-5 && c.z <= 0.74 + 1e-5);
                assert!(c.truncate().length() <= 0.45 + 1e-5);
            }
            let base: Vec<Vec3> = piece[..piece.len() - 1].to_vec();
            if base.iter().all(|c| (c.z - 0.74).abs() < 1e-5) {
                for k in 1..base.len() - 1 {
                    top_area += 0.5 * (base[k] - base[0]).cross(base[k + 1] - base[0]).length();
                }
            }
        }
        let polygon = 0.5 * 40.0 * 0.45f32 * 0.45 * (std::f32::consts::TAU / 40.0).sin();
        assert!((top_area - polygon).abs() < 1e-4, "{top_area} {polygon}");
        assert_eq!(hull.faces().len(), 42);
    }
}
