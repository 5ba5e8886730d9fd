use super::*;

fn slab(center: Vec3, size: Vec3) -> GravityBox {
    GravityBox {
        center,
        yaw: 0.0,
        size,
    }
}

/// Vertices on the top face of a box, 1 cm apart.
fn top_vertices(b: &GravityBox) -> Vec<Vec3> {
    let mut v = Vec::new();
    let n = (b.size.truncate() / 0.01).as_uvec2();
    for i in 0..=n.x {
        for j in 0..=n.y {
            v.push(Vec3::new(
                b.center.x - 0.5 * b.size.x + i as f32 * 0.01,
                b.center.y - 0.5 * b.size.y + j as f32 * 0.01,
                b.top_z(),
            ));
        }
    }
    v
}

/// The floor (layout), a fixed parent and a movable child, in that order.
fn floor_parent_child<'a>(
    classes: &[&'a str; 3],
    boxes: &[GravityBox; 3],
    planes: &'a [Vec<Plane>; 3],
    vertices: &'a [Vec<Vec3>; 3],
) -> Vec<SupportEntity<'a>> {
    (0..3)
        .map(|i| SupportEntity {
            class: classes[i],
            kind: if i == 0 {
                EntityKind::Layout
            } else {
                EntityKind::Rigid
            },
            movable: i == 2,
            bbox: boxes[i],
            planes: &planes[i],
            vertices: &vertices[i],
        })
        .collect()
}

#[test]
fn a_cup_rests_on_the_table_a_wall_cabinet_hangs_and_an_occluded_top_is_registered() {
    let floor = slab(Vec3::new(2.0, 2.0, -0.05), Vec3::new(4.0, 4.0, 0.1));
    let wall = slab(Vec3::new(2.0, 4.05, 1.3), Vec3::new(4.0, 0.1, 2.6));
    let table = slab(Vec3::new(1.0, 1.0, 0.375), Vec3::new(1.2, 0.8, 0.75));
    let cup = slab(Vec3::new(1.1, 0.9, 0.8), Vec3::new(0.08, 0.08, 0.1));
    let base = slab(Vec3::new(2.5, 3.7, 0.45), Vec3::new(0.6, 0.6, 0.9));
    let hanging = slab(Vec3::new(2.5, 3.8, 1.8), Vec3::new(0.6, 0.4, 0.7));
    // A microwave whose cabinet's top was never seen (no vertices, no plane).
    let cabinet = slab(Vec3::new(3.5, 1.0, 0.45), Vec3::new(0.6, 0.6, 0.9));
    let microwave = slab(Vec3::new(3.5, 1.0, 1.05), Vec3::new(0.5, 0.4, 0.3));
    let up = |b: &GravityBox| Plane::from_point_normal(Vec3::new(0.0, 0.0, b.top_z()), Vec3::Z);
    let planes = [
        vec![up(&floor)],
        vec![Plane::from_point_normal(Vec3::new(0.0, 4.0, 0.0), -Vec3::Y)],
        vec![up(&table)],
        vec![up(&cup)],
        vec![up(&base)],
        vec![],
        vec![],
        vec![up(&microwave)],
    ];
    let vertices = [
        vec![],
        vec![],
        top_vertices(&table),
        top_vertices(&cup),
        top_vertices(&base),
        vec![],
        vec![],
        top_vertices(&microwave),
    ];
    let kinds = [EntityKind::Layout, EntityKind::Layout];
    let boxes = [floor, wall, table, cup, base, hanging, cabinet, microwave];
    let classes = [
        "floor",
        "wall",
        "table",
        "cup",
        "cabinet",
        "cabinet",
        "cabinet",
        "microwave",
    ];
    let entities: Vec<SupportEntity> = (0..boxes.len())
        .map(|i| SupportEntity {
            class: classes[i],
            kind: kinds.get(i).copied().unwrap_or(EntityKind::Rigid),
            movable: classes[i] == "cup",
            bbox: boxes[i],
            planes: &planes[i],
            vertices: &vertices[i],
        })
        .collect();
    let supports = infer_supports(&entities, &SupportParams::default());
    let parent = |i: usize| match supports[i] {
        Some(SupportChoice::Below { parent, .. }) | Some(SupportChoice::Wall { parent }) => {
            Some(parent)
        }
        None => None,
    };
    assert_eq!(parent(0), None);
    assert_eq!(parent(1), None);
    assert_eq!(parent(2), Some(0), "table on the floor");
    assert_eq!(parent(3), Some(2), "cup on the table");
    assert_eq!(parent(4), Some(0), "base cabinet on the floor");
    assert_eq!(
        supports[5],
        Some(SupportChoice::Wall { parent: 1 }),
        "wall cabinet on the wall"
    );
    assert_eq!(parent(6), Some(0));
    assert!(
        matches!(
            supports[7],
            Some(SupportChoice::Below {
                parent: 6,
                registered: true,
                ..
            })
        ),
        "{:?}",
        supports[7]
    );
}

#[test]
fn a_monitor_whose_stand_was_not_seen_stands_on_the_counter_under_it() {
    let floor = slab(Vec3::new(2.0, 2.0, -0.05), Vec3::new(4.0, 4.0, 0.1));
    let counter = slab(Vec3::new(1.0, 3.5, 0.45), Vec3::new(2.0, 0.6, 0.9));
    // The screen alone, 30 cm above the counter top.
    let monitor = slab(Vec3::new(1.0, 3.5, 1.4), Vec3::new(0.6, 0.15, 0.4));
    let up = |b: &GravityBox| Plane::from_point_normal(Vec3::new(0.0, 0.0, b.top_z()), Vec3::Z);
    let planes = [vec![up(&floor)], vec![up(&counter)], vec![]];
    let vertices = [vec![], top_vertices(&counter), vec![]];
    let boxes = [floor, counter, monitor];
    let classes = ["floor", "counter", "monitor"];
    let entities = floor_parent_child(&classes, &boxes, &planes, &vertices);
    let supports = infer_supports(&entities, &SupportParams::default());
    match supports[2] {
        Some(SupportChoice::Below { parent, plane, .. }) => {
            assert_eq!(parent, 1, "on the counter, not the floor");
            assert!((plane_height(&plane, Vec2::ZERO) - 0.9).abs() < 1e-4);
        }
        other => panic!("{other:?}"),
    }
    // Not movable (a wall cabinet with no wall near): the floor, as before.
    let fixed: Vec<SupportEntity> = entities
        .into_iter()
        .map(|e| SupportEntity {
            movable: false,
            ..e
        })
        .collect();
    let supports = infer_supports(&fixed, &SupportParams::default());
    assert!(
        matches!(supports[2], Some(SupportChoice::Below { parent: 0, .. })),
        "{:?}",
        supports[2]
    );
}

#[test]
fn a_bottle_on_a_shelf_board_hidden_under_it_stands_in_the_shelf_not_on_the_floor() {
    let floor = slab(Vec3::new(2.0, 2.0, -0.05), Vec3::new(4.0, 4.0, 0.1));
    // A shelf 1.6 m tall whose board at 0.82 m is seen only as its front edge, a row of
    // vertices beside the bottle; its other surfaces are the sides and top.
    let shelf = slab(Vec3::new(1.0, 1.0, 0.8), Vec3::new(0.9, 0.4, 1.6));
    let mut shelf_vertices = top_vertices(&shelf);
    shelf_vertices.extend((0..30).map(|i| Vec3::new(0.7 + 0.01 * i as f32, 0.82, 0.82)));
    let bottle = slab(Vec3::new(0.85, 0.9, 0.93), Vec3::new(0.07, 0.07, 0.22));
    let up = |b: &GravityBox| Plane::from_point_normal(Vec3::new(0.0, 0.0, b.top_z()), Vec3::Z);
    let planes = [vec![up(&floor)], vec![up(&shelf)], vec![]];
    let vertices = [vec![], shelf_vertices, vec![]];
    let boxes = [floor, shelf, bottle];
    let classes = ["floor", "shelf", "bottle"];
    let entities = floor_parent_child(&classes, &boxes, &planes, &vertices);
    match infer_supports(&entities, &SupportParams::default())[2] {
        Some(SupportChoice::Below {
            parent,
            plane,
            registered,
            ..
        }) => {
            assert_eq!(parent, 1, "in the shelf, not on the floor");
            assert!((plane_height(&plane, Vec2::ZERO) - 0.82).abs() < 1e-4);
            assert!(registered);
        }
        other => panic!("{other:?}"),
    }
    // A box under a table, its bottom unseen, two of the table's legs beside it: a cell each
    // at every height make no board, and the floor holds it.
    let table = slab(Vec3::new(1.0, 1.0, 0.375), Vec3::new(1.2, 0.8, 0.75));
    let mut table_vertices = top_vertices(&table);
    table_vertices.extend((0..75).map(|i| Vec3::new(0.42, 0.62, 0.01 * i as f32)));
    table_vertices.extend((0..75).map(|i| Vec3::new(0.58, 0.62, 0.01 * i as f32)));
    let low_box = slab(Vec3::new(0.5, 0.7, 0.3), Vec3::new(0.12, 0.12, 0.2));
    let planes = [vec![up(&floor)], vec![up(&table)], vec![]];
    let vertices = [vec![], table_vertices, vec![]];
    let boxes = [floor, table, low_box];
    let classes = ["floor", "table", "box"];
    let entities = floor_parent_child(&classes, &boxes, &planes, &vertices);
    assert!(
        matches!(
            infer_supports(&entities, &SupportParams::default())[2],
            Some(SupportChoice::Below { parent: 0, .. })
        ),
        "on the floor"
    );
}

#[test]
fn a_book_hiding_the_table_top_rests_on_the_table_plane() {
    let floor = slab(Vec3::new(2.0, 2.0, -0.05), Vec3::new(4.0, 4.0, 0.1));
    let table = slab(Vec3::new(1.0, 1.0, 0.375), Vec3::new(1.2, 0.8, 0.75));
    // Only the book's top was seen, 4 cm above the table (beyond the plane's band).
    let book = slab(Vec3::new(1.1, 0.9, 0.79), Vec3::new(0.2, 0.15, 0.0));
    let up = |b: &GravityBox| Plane::from_point_normal(Vec3::new(0.0, 0.0, b.top_z()), Vec3::Z);
    // The table top is seen around the book, not under it; a strip of the book's top took
    // the table's label (bleeding), so "the table's surface under the book" is up there.
    let footprint = Footprint::of(&book);
    let mut table_vertices: Vec<Vec3> = top_vertices(&table)
        .into_iter()
        .filter(|v| !footprint.contains(v.truncate()))
        .collect();
    table_vertices.extend(
        top_vertices(&book)
            .into_iter()
            .map(|v| v.with_z(book.top_z())),
    );
    let planes = [vec![up(&floor)], vec![up(&table)], vec![up(&book)]];
    let vertices = [vec![], table_vertices, top_vertices(&book)];
    let boxes = [floor, table, book];
    let classes = ["floor", "table", "book"];
    let entities = floor_parent_child(&classes, &boxes, &planes, &vertices);
    let supports = infer_supports(&entities, &SupportParams::default());
    let Some(SupportChoice::Below {
        parent,
        plane,
        registered,
        ..
    }) = supports[2]
    else {
        panic!("the book is not held from below: {:?}", supports[2]);
    };
    assert_eq!((parent, registered), (1, false), "on the table's own plane");
    let rested = rest_on(&book, &plane);
    assert!((rested.bottom_z() - 0.75).abs() < 1e-5, "{rested:?}");
}

#[test]
fn a_floating_box_is_stretched_down_to_its_plane() {
    let b = slab(Vec3::new(0.0, 0.0, 0.6), Vec3::new(0.5, 0.5, 0.4));
    let r = rest_on(&b, &Plane::from_point_normal(Vec3::ZERO, Vec3::Z));
    assert!((r.bottom_z()).abs() < 1e-6 && (r.top_z() - 0.8).abs() < 1e-6);
    let sunk = slab(Vec3::new(0.0, 0.0, 0.74), Vec3::new(0.1, 0.1, 0.1));
    let lifted = rest_on(
        &sunk,
        &Plane::from_point_normal(Vec3::new(0.0, 0.0, 0.75), Vec3::Z),
    );
    assert!((lifted.bottom_z() - 0.75).abs() < 1e-6 && (lifted.top_z() - 0.79).abs() < 1e-6);
}

#[test]
fn a_microwave_on_a_unit_seen_only_as_its_front_stands_on_that_unit_not_on_the_floor() {
    let floor = slab(Vec3::new(2.0, 2.0, -0.05), Vec3::new(4.0, 4.0, 0.1));
    // A dishwasher between neighbours with a microwave on it: only its front was seen, a slab
    // 5 cm deep whose top meets the microwave's bottom, 3 cm in front of the microwave's box.
    let front = slab(Vec3::new(2.0, 1.025, 0.42), Vec3::new(0.6, 0.05, 0.84));
    let microwave = slab(Vec3::new(2.0, 1.28, 0.99), Vec3::new(0.5, 0.4, 0.3));
    // A bottle 30 cm above the unit's top is not on it: it falls to the floor as before.
    let bottle = slab(Vec3::new(2.9, 1.1, 1.25), Vec3::new(0.07, 0.07, 0.2));
    // A table seen as its top alone (legs never seen), a chair beside it as high as its top's
    // underside: no unit, so the table stands on the floor, its legs unseen.
    let table = slab(Vec3::new(2.0, 3.0, 0.735), Vec3::new(0.9, 0.9, 0.03));
    let chair = slab(Vec3::new(2.0, 3.7, 0.375), Vec3::new(0.45, 0.45, 0.75));
    let up = |b: &GravityBox| Plane::from_point_normal(Vec3::new(0.0, 0.0, b.top_z()), Vec3::Z);
    let planes = [
        vec![up(&floor)],
        vec![],
        vec![up(&microwave)],
        vec![],
        vec![],
        vec![],
    ];
    let vertices = [
        vec![],
        vec![],
        top_vertices(&microwave),
        vec![],
        vec![],
        vec![],
    ];
    let boxes = [floor, front, microwave, bottle, table, chair];
    let classes = [
        "floor",
        "dishwasher",
        "microwave",
        "bottle",
        "table",
        "chair",
    ];
    let entities: Vec<SupportEntity> = (0..boxes.len())
        .map(|i| SupportEntity {
            class: classes[i],
            kind: match i {
                0 => EntityKind::Layout,
                1 | 2 => EntityKind::Articulated,
                _ => EntityKind::Rigid,
            },
            movable: matches!(classes[i], "bottle" | "chair"),
            bbox: boxes[i],
            planes: &planes[i],
            vertices: &vertices[i],
        })
        .collect();
    let supports = infer_supports(&entities, &SupportParams::default());
    assert!(
        matches!(
            supports[2],
            Some(SupportChoice::Below {
                parent: 1,
                registered: true,
                ..
            })
        ),
        "{:?}",
        supports[2]
    );
    let Some(SupportChoice::Below { plane, .. }) = supports[2] else {
        unreachable!()
    };
    assert!((plane_height(&plane, Vec2::new(2.0, 1.28)) - 0.84).abs() < 1e-4);
    for k in [3, 4] {
        assert!(
            matches!(supports[k], Some(SupportChoice::Below { parent: 0, .. })),
            "{k}: {:?}",
            supports[k]
        );
    }
}
