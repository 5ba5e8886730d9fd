//! Units the contact graph stands on the floor although nothing was seen holding them from
//! below: cabinets and appliances whose lower part the camera never saw. (Counters, seen as
//! their tops only, are the other such case: `build::COUNTER_CLASS`.)

use glam::Vec3;

use crate::geometry::{GravityBox, Plane};

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
pub fn stands_with_its_foot_hidden(
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
    // Enough floor seen beneath ends the count.
    floor_points
        .iter()
        .filter(|p| foot.contains(**p, 0.0))
        .take(FLOOR_SEEN_BENEATH_POINTS)
        .count()
        < FLOOR_SEEN_BENEATH_POINTS
}

#[cfg(test)]
mod tests {
    use crate::classes::EntityKind;
    use crate::geometry::TriMesh;
    use crate::graph::build::{ContactGraphParams, GraphEntity, build_contact_graph};
    use glam::Vec3;

    #[test]
    fn a_cabinet_seen_as_its_top_over_an_unseen_floor_stands_on_it_a_wall_unit_still_hangs() {
        // A floor seen only in front of a wall at y = 3 (y < 2.3); against the wall a cabinet
        // seen as its top 20 cm (0.35-0.55 m: a bed hid the rest), and a wall unit at 1.4-1.9 m.
        let floor = TriMesh::cuboid(Vec3::new(0.0, 0.0, -0.02), Vec3::new(4.0, 2.3, 0.0));
        let wall = TriMesh::cuboid(Vec3::new(0.0, 3.0, 0.0), Vec3::new(4.0, 3.02, 2.5));
        let low = TriMesh::cuboid(Vec3::new(1.0, 2.4, 0.35), Vec3::new(1.45, 3.0, 0.55));
        let high = TriMesh::cuboid(Vec3::new(2.5, 2.65, 1.4), Vec3::new(3.3, 3.0, 1.9));
        let graph_with = |floor: &TriMesh| {
            let entities = [
                GraphEntity::unsighted("floor", "floor", EntityKind::Layout, floor),
                GraphEntity::unsighted("wall_0", "wall", EntityKind::Layout, &wall),
                GraphEntity::unsighted("cabinet_1", "cabinet", EntityKind::Articulated, &low),
                GraphEntity::unsighted("cabinet_2", "cabinet", EntityKind::Articulated, &high),
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
}
