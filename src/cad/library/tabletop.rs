//! Parametric small objects: monitors, cups, bottles, books, boxes, bowls.

use glam::{Vec2, Vec3};

use crate::cad::library::builder::PartsBuilder;
use crate::cad::model::CadModel;
use crate::geometry::TriMesh;

const BLACK: [f32; 3] = [0.06, 0.06, 0.07];
const SCREEN: [f32; 3] = [0.1, 0.12, 0.16];
const CERAMIC: [f32; 3] = [0.92, 0.9, 0.85];
const BLUE: [f32; 3] = [0.15, 0.35, 0.7];
const GREEN_GLASS: [f32; 3] = [0.15, 0.4, 0.2];
const CLEAR_BLUE: [f32; 3] = [0.55, 0.7, 0.85];
const RED_COVER: [f32; 3] = [0.7, 0.15, 0.15];
const PAPER: [f32; 3] = [0.95, 0.93, 0.88];
const CARDBOARD: [f32; 3] = [0.65, 0.5, 0.32];
const YELLOW: [f32; 3] = [0.85, 0.7, 0.2];

const SEGMENTS: u32 = 24;

/// A flat screen on a neck and a rectangular foot.
pub fn monitor_stand(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(BLACK);
    let screen_h = 0.75 * s.z;
    let screen = b.part(
        "screen",
        PartsBuilder::BODY,
        glam::Affine3A::IDENTITY,
        crate::base::JointSpec::FIXED,
        SCREEN,
    );
    b.slab(
        Vec3::new(-0.2 * s.x, -0.5 * s.y, 0.0),
        Vec3::new(0.2 * s.x, 0.5 * s.y, 0.015),
    )
    .slab(
        Vec3::new(-0.03, 0.1 * s.y, 0.015),
        Vec3::new(0.03, 0.1 * s.y + 0.02, s.z - screen_h + 0.05),
    )
    .slab(
        Vec3::new(-0.5 * s.x, -0.03, s.z - screen_h),
        Vec3::new(0.5 * s.x, 0.0, s.z),
    )
    .add(
        screen,
        TriMesh::cuboid(
            Vec3::new(-0.48 * s.x, -0.032, s.z - 0.97 * screen_h),
            Vec3::new(0.48 * s.x, -0.03, s.z - 0.02 * screen_h),
        ),
    );
    b.finish(id, "monitor")
}

/// A thin screen on a round foot.
pub fn monitor_round_foot(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(BLACK);
    let screen_h = 0.8 * s.z;
    b.add(
        PartsBuilder::BODY,
        TriMesh::cylinder(Vec3::ZERO, 0.5 * s.y.min(0.4 * s.x), 0.012, SEGMENTS),
    )
    .add(
        PartsBuilder::BODY,
        TriMesh::cylinder(Vec3::Z * 0.012, 0.015, s.z - screen_h + 0.03, 12),
    )
    .slab(
        Vec3::new(-0.5 * s.x, -0.015, s.z - screen_h),
        Vec3::new(0.5 * s.x, 0.01, s.z),
    );
    b.finish(id, "monitor")
}

/// A mug: a hollow cylinder with a handle on its side.
pub fn cup_mug(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(CERAMIC);
    let r = 0.5 * s.y;
    let wall = 0.005;
    let body = TriMesh::lathe(
        Vec3::ZERO,
        &[
            Vec2::new(r, 0.0),
            Vec2::new(r, s.z),
            Vec2::new(r - wall, s.z),
            Vec2::new(r - wall, 0.008),
        ],
        SEGMENTS,
    );
    let handle_w = (s.x - s.y).max(0.015);
    b.add(PartsBuilder::BODY, body)
        .slab(
            Vec3::new(r - 0.002, -0.006, 0.25 * s.z),
            Vec3::new(r + handle_w, 0.006, 0.33 * s.z),
        )
        .slab(
            Vec3::new(r - 0.002, -0.006, 0.72 * s.z),
            Vec3::new(r + handle_w, 0.006, 0.8 * s.z),
        )
        .slab(
            Vec3::new(r + handle_w - 0.008, -0.006, 0.25 * s.z),
            Vec3::new(r + handle_w, 0.006, 0.8 * s.z),
        );
    b.finish(id, "cup")
}

/// A tapered tumbler without a handle.
pub fn cup_tumbler(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(BLUE);
    let r = 0.5 * s.x.min(s.y);
    let wall = 0.004;
    b.add(
        PartsBuilder::BODY,
        TriMesh::lathe(
            Vec3::ZERO,
            &[
                Vec2::new(0.75 * r, 0.0),
                Vec2::new(r, s.z),
                Vec2::new(r - wall, s.z),
                Vec2::new(0.75 * r - wall, 0.01),
            ],
            SEGMENTS,
        ),
    );
    b.finish(id, "cup")
}

/// A wine bottle: a cylinder, a shoulder and a long neck.
pub fn bottle_wine(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(GREEN_GLASS);
    let r = 0.5 * s.x.min(s.y);
    let profile = [
        Vec2::new(r, 0.0),
        Vec2::new(r, 0.62 * s.z),
        Vec2::new(0.6 * r, 0.75 * s.z),
        Vec2::new(0.32 * r, 0.82 * s.z),
        Vec2::new(0.32 * r, s.z),
    ];
    b.add(
        PartsBuilder::BODY,
        TriMesh::lathe(Vec3::ZERO, &profile, SEGMENTS),
    );
    b.finish(id, "bottle")
}

/// A water bottle with a waist and a cap.
pub fn bottle_water(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(CLEAR_BLUE);
    let r = 0.5 * s.x.min(s.y);
    let cap = b.part(
        "cap",
        PartsBuilder::BODY,
        glam::Affine3A::IDENTITY,
        crate::base::JointSpec::FIXED,
        BLUE,
    );
    let profile = [
        Vec2::new(0.9 * r, 0.0),
        Vec2::new(r, 0.05 * s.z),
        Vec2::new(r, 0.4 * s.z),
        Vec2::new(0.85 * r, 0.5 * s.z),
        Vec2::new(r, 0.6 * s.z),
        Vec2::new(r, 0.75 * s.z),
        Vec2::new(0.4 * r, 0.9 * s.z),
    ];
    b.add(
        PartsBuilder::BODY,
        TriMesh::lathe(Vec3::ZERO, &profile, SEGMENTS),
    )
    .add(
        cap,
        TriMesh::cylinder(Vec3::Z * 0.9 * s.z, 0.42 * r, 0.1 * s.z, 16),
    );
    b.finish(id, "bottle")
}

/// A closed hardback book lying flat: covers and a page block.
pub fn book_hardback(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(RED_COVER);
    let cover = 0.003f32.min(0.2 * s.z);
    let pages = b.part(
        "pages",
        PartsBuilder::BODY,
        glam::Affine3A::IDENTITY,
        crate::base::JointSpec::FIXED,
        PAPER,
    );
    b.slab(
        Vec3::new(-0.5 * s.x, -0.5 * s.y, 0.0),
        Vec3::new(0.5 * s.x, 0.5 * s.y, cover),
    )
    .slab(
        Vec3::new(-0.5 * s.x, -0.5 * s.y, s.z - cover),
        Vec3::new(0.5 * s.x, 0.5 * s.y, s.z),
    )
    .slab(
        Vec3::new(-0.5 * s.x, -0.5 * s.y, cover),
        Vec3::new(-0.5 * s.x + cover, 0.5 * s.y, s.z - cover),
    )
    .add(
        pages,
        TriMesh::cuboid(
            Vec3::new(-0.5 * s.x + cover, -0.5 * s.y + 0.003, cover),
            Vec3::new(0.5 * s.x - 0.003, 0.5 * s.y - 0.003, s.z - cover),
        ),
    );
    b.finish(id, "book")
}

/// A paperback: one block with a coloured cover.
pub fn book_paperback(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(YELLOW);
    b.slab(
        Vec3::new(-0.5 * s.x, -0.5 * s.y, 0.0),
        Vec3::new(0.5 * s.x, 0.5 * s.y, s.z),
    );
    b.finish(id, "book")
}

/// A closed carton.
pub fn box_carton(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(CARDBOARD);
    b.slab(
        Vec3::new(-0.5 * s.x, -0.5 * s.y, 0.0),
        Vec3::new(0.5 * s.x, 0.5 * s.y, s.z),
    );
    b.finish(id, "box")
}

/// A storage box with an overhanging lid.
pub fn box_lidded(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(BLUE);
    let lid = b.part(
        "lid",
        PartsBuilder::BODY,
        glam::Affine3A::IDENTITY,
        crate::base::JointSpec::FIXED,
        CERAMIC,
    );
    b.slab(
        Vec3::new(-0.5 * s.x + 0.01, -0.5 * s.y + 0.01, 0.0),
        Vec3::new(0.5 * s.x - 0.01, 0.5 * s.y - 0.01, 0.85 * s.z),
    )
    .add(
        lid,
        TriMesh::cuboid(
            Vec3::new(-0.5 * s.x, -0.5 * s.y, 0.85 * s.z),
            Vec3::new(0.5 * s.x, 0.5 * s.y, s.z),
        ),
    );
    b.finish(id, "box")
}

/// A deep round bowl with a foot ring.
pub fn bowl_deep(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(CERAMIC);
    let r = 0.5 * s.x.min(s.y);
    let wall = 0.005;
    let profile = [
        Vec2::new(0.4 * r, 0.0),
        Vec2::new(0.45 * r, 0.1 * s.z),
        Vec2::new(0.8 * r, 0.45 * s.z),
        Vec2::new(r, s.z),
        Vec2::new(r - wall, s.z),
        Vec2::new(0.8 * r - wall, 0.45 * s.z + wall),
        Vec2::new(0.45 * r - wall, 0.1 * s.z + wall),
    ];
    b.add(
        PartsBuilder::BODY,
        TriMesh::lathe(Vec3::ZERO, &profile, SEGMENTS),
    );
    b.finish(id, "bowl")
}

/// A wide, shallow serving bowl.
pub fn bowl_shallow(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(YELLOW);
    let r = 0.5 * s.x.min(s.y);
    let wall = 0.005;
    let profile = [
        Vec2::new(0.55 * r, 0.0),
        Vec2::new(0.9 * r, 0.6 * s.z),
        Vec2::new(r, s.z),
        Vec2::new(r - wall, s.z),
        Vec2::new(0.9 * r - wall, 0.6 * s.z + wall),
        Vec2::new(0.55 * r - wall, wall),
    ];
    b.add(
        PartsBuilder::BODY,
        TriMesh::lathe(Vec3::ZERO, &profile, SEGMENTS),
    );
    b.finish(id, "bowl")
}
