//! The shape filters of Sivananda et al.: an object segment that is flat and lies on the floor
//! or a wall is label bleeding, not an object (a "table" label smeared over the floor under
//! it); one far larger than any object of its class is too. Such a segment is not replaced by
//! a model: it keeps its segment mesh, and report.json says why.

use glam::Vec3;
use serde::Serialize;

use crate::cad::replace::matching::ObservedObject;
use crate::classes::ClassTable;
use crate::geometry::Plane;
use crate::geometry::plane::fit_plane;
use crate::graph::ContactGraph;

/// A segment whose points lie within this RMS distance (metres) of their plane is flat: a
/// board's thickness seen from one side, or depth noise on a wall.
const FLAT_RMS_M: f32 = 0.01;
/// ... parallel to a layout plane (|cos| of the normals) ...
const PARALLEL_COS: f32 = 0.95;
/// ... and on it: mean distance to the layout plane, metres. A book lying on the floor is at
/// least its thickness above it, and its sides are not flat with its top.
const ON_LAYOUT_M: f32 = 0.02;
/// A box whose sides, sorted, exceed the class's largest sizes (sorted) by this factor in any
/// place holds more than one object of the class could.
const OVERSIZE_FACTOR: f32 = 2.0;

/// Why an object segment is not replaced.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "reason", rename_all = "snake_case")]
pub enum Rejection {
    /// Flat and lying on a layout surface (`layout` is its node id).
    FlatOnLayout { layout: String, rms_m: f32 },
    /// Larger than the class allows: the box's sides against the class's largest, both sorted.
    Oversized {
        box_m: [f32; 3],
        class_max_m: [f32; 3],
    },
}

/// The layout planes of `graph` (floor and walls) with their node ids.
pub fn layout_planes(graph: &ContactGraph) -> Vec<(String, Plane)> {
    graph
        .nodes
        .iter()
        .filter(|n| n.class == "floor" || n.class == "wall")
        .filter_map(|n| Some((n.id.clone(), Plane::from_array(*n.planes.first()?))))
        .collect()
}

/// Why `object` is not an object, or `None` when it passes both filters.
pub fn rejection(object: &ObservedObject, layout: &[(String, Plane)]) -> Option<Rejection> {
    flat_on_layout(&object.points, layout).or_else(|| oversized(object))
}

fn flat_on_layout(points: &[Vec3], layout: &[(String, Plane)]) -> Option<Rejection> {
    let plane = fit_plane(points)?;
    let rms = |plane: &Plane| {
        (points
            .iter()
            .map(|p| plane.signed_distance(*p).powi(2))
            .sum::<f32>()
            / points.len() as f32)
            .sqrt()
    };
    let own_rms = rms(&plane);
    if own_rms > FLAT_RMS_M {
        return None;
    }
    layout
        .iter()
        .filter(|(_, l)| l.normal.dot(plane.normal).abs() >= PARALLEL_COS)
        .map(|(id, l)| {
            let mean = points
                .iter()
                .map(|p| l.signed_distance(*p).abs())
                .sum::<f32>()
                / points.len() as f32;
            (id, mean)
        })
        .filter(|(_, mean)| *mean <= ON_LAYOUT_M)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(id, _)| Rejection::FlatOnLayout {
            layout: id.clone(),
            rms_m: own_rms,
        })
}

fn oversized(object: &ObservedObject) -> Option<Rejection> {
    let class = ClassTable::builtin().get(object.class)?.clone();
    let sorted = |v: Vec3| {
        let mut a = v.to_array();
        a.sort_by(f32::total_cmp);
        a
    };
    let box_m = sorted(object.bbox.size);
    let class_max_m = sorted(class.size_max);
    box_m
        .iter()
        .zip(&class_max_m)
        .any(|(b, c)| *b > OVERSIZE_FACTOR * c)
        .then_some(Rejection::Oversized { box_m, class_max_m })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::GravityBox;

    fn object<'a>(class: &'a str, points: &'a [Vec3]) -> ObservedObject<'a> {
        let bbox = GravityBox::minimal(points).expect("a box");
        ObservedObject {
            id: "x_1",
            class,
            top_z: bbox.top_z(),
            bbox,
            planes: Vec::new(),
            points: points.into(),
            facing: None,
            front: None,
        }
    }

    fn grid(f: impl Fn(f32, f32) -> Vec3) -> Vec<Vec3> {
        (0..30)
            .flat_map(|i| (0..30).map(move |j| (i as f32 / 29.0, j as f32 / 29.0)))
            .map(|(u, v)| f(u, v))
            .collect()
    }

    fn layout() -> Vec<(String, Plane)> {
        vec![
            ("floor".into(), Plane::from_array([0.0, 0.0, 1.0, 0.0])),
            // The wall x = 3 facing -x (into the room).
            ("wall_0".into(), Plane::from_array([-1.0, 0.0, 0.0, 3.0])),
        ]
    }

    #[test]
    fn bleeding_on_the_floor_and_a_wall_is_rejected_with_the_layout_named() {
        // A "table" label smeared over 60 x 60 cm of floor, with 4 mm of depth noise.
        let floor_patch = grid(|u, v| Vec3::new(u * 0.6, v * 0.6, 0.004 * ((u * 40.0).sin())));
        match rejection(&object("table", &floor_patch), &layout()) {
            Some(Rejection::FlatOnLayout { layout, rms_m }) => {
                assert_eq!(layout, "floor");
                assert!(rms_m < 0.005);
            }
            other => panic!("{other:?}"),
        }
        let wall_patch = grid(|u, v| Vec3::new(2.995, 1.0 + u * 0.4, 0.5 + v * 0.5));
        assert!(matches!(
            rejection(&object("cabinet", &wall_patch), &layout()),
            Some(Rejection::FlatOnLayout { layout, .. }) if layout == "wall_0"
        ));
    }

    #[test]
    fn real_objects_pass_even_when_flat() {
        // A table top seen from above: flat, but 75 cm over the floor.
        let top = grid(|u, v| Vec3::new(u * 1.2, v * 0.8, 0.75));
        assert_eq!(rejection(&object("table", &top), &layout()), None);
        // A book lying on the floor: its top 3 cm up, with its sides.
        let mut book = grid(|u, v| Vec3::new(u * 0.2, v * 0.15, 0.03));
        book.extend(grid(|u, v| Vec3::new(u * 0.2, 0.0, v * 0.03)));
        assert_eq!(rejection(&object("book", &book), &layout()), None);
        // A cabinet standing against the wall: its front is flat but 50 cm from the wall.
        let front = grid(|u, v| Vec3::new(2.5, 1.0 + u * 0.6, v * 0.9));
        assert_eq!(rejection(&object("cabinet", &front), &layout()), None);
    }

    #[test]
    fn a_cup_label_over_a_whole_counter_is_oversized() {
        let counter = grid(|u, v| Vec3::new(u * 1.5, v * 0.6, 0.9 + 0.05 * u * v));
        let counter_top: Vec<Vec3> = counter
            .iter()
            .chain(grid(|u, v| Vec3::new(u * 1.5, 0.0, 0.9 - v * 0.1)).iter())
            .copied()
            .collect();
        assert!(matches!(
            rejection(&object("cup", &counter_top), &layout()),
            Some(Rejection::Oversized { .. })
        ));
        assert_eq!(rejection(&object("table", &counter_top), &layout()), None);
    }
}
