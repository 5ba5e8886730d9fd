//! Parametric kitchen appliances: fridges, microwaves, ovens, dishwashers.

use glam::Vec3;

use crate::cad::library::builder::{BOARD, DRAWER_CLEARANCE, HingeSide, PartsBuilder};
use crate::cad::model::CadModel;
use crate::geometry::TriMesh;

const WHITE: [f32; 3] = [0.92, 0.92, 0.92];
const STEEL: [f32; 3] = [0.62, 0.63, 0.65];
const BLACK: [f32; 3] = [0.07, 0.07, 0.08];
const GLASS: [f32; 3] = [0.15, 0.17, 0.2];
const INSIDE: [f32; 3] = [0.8, 0.82, 0.85];

/// Wall thickness of appliance shells, metres.
const SHELL: f32 = 0.03;

/// An appliance body open at the front, `front_y` being the plane its doors close on.
fn shell(b: &mut PartsBuilder, s: Vec3, door: f32) -> f32 {
    let front = -0.5 * s.y + door;
    let lo = Vec3::new(-0.5 * s.x, front, 0.0);
    let hi = Vec3::new(0.5 * s.x, 0.5 * s.y, s.z);
    b.slab(lo, Vec3::new(hi.x, hi.y, SHELL))
        .slab(Vec3::new(lo.x, lo.y, hi.z - SHELL), hi)
        .slab(
            Vec3::new(lo.x, lo.y, SHELL),
            Vec3::new(lo.x + SHELL, hi.y, hi.z - SHELL),
        )
        .slab(
            Vec3::new(hi.x - SHELL, lo.y, SHELL),
            Vec3::new(hi.x, hi.y, hi.z - SHELL),
        )
        .slab(
            Vec3::new(lo.x + SHELL, hi.y - SHELL, SHELL),
            Vec3::new(hi.x - SHELL, hi.y, hi.z - SHELL),
        );
    front
}

/// A single-door fridge hinged on the right with two inner shelves.
pub fn fridge_single(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(WHITE);
    let door = 0.05;
    let front = shell(&mut b, s, door);
    // The shelves stand clear of the door's liner (it reaches `door - BOARD` into the body).
    for k in 1..3 {
        let z = k as f32 * s.z / 3.0;
        b.slab(
            Vec3::new(-0.5 * s.x + SHELL, front + door - BOARD + 0.01, z),
            Vec3::new(0.5 * s.x - SHELL, 0.5 * s.y - SHELL, z + 0.01),
        );
    }
    let d = b.hinged_door(
        "door",
        PartsBuilder::BODY,
        (-0.5 * s.x, 0.5 * s.x),
        (0.0, s.z),
        front,
        HingeSide::Right,
        WHITE,
        STEEL,
    );
    // A thicker door: a liner behind the front board, inside the body's opening (+y in the
    // door's frame; in front of the board it buried the handle, and no camera saw one).
    b.add(
        d,
        TriMesh::cuboid(
            Vec3::new(-s.x + 0.04, BOARD, 0.04),
            Vec3::new(-0.04, door, s.z - 0.04),
        ),
    );
    b.finish(id, "fridge")
}

/// A fridge over a freezer drawer: a door hinged on the left above a pull-out drawer.
pub fn fridge_freezer(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(STEEL);
    let door = 0.05;
    let front = shell(&mut b, s, door);
    let split = 0.35 * s.z;
    b.slab(
        Vec3::new(-0.5 * s.x + SHELL, front, split - 0.01),
        Vec3::new(0.5 * s.x - SHELL, 0.5 * s.y - SHELL, split + 0.01),
    )
    .slab(
        Vec3::new(-0.5 * s.x + SHELL, front + 0.02, 0.7 * s.z),
        Vec3::new(0.5 * s.x - SHELL, 0.5 * s.y - SHELL, 0.7 * s.z + 0.01),
    );
    b.hinged_door(
        "door",
        PartsBuilder::BODY,
        (-0.5 * s.x, 0.5 * s.x),
        (split + 0.003, s.z),
        front,
        HingeSide::Left,
        STEEL,
        BLACK,
    );
    b.drawer(
        "freezer",
        PartsBuilder::BODY,
        (-0.5 * s.x, 0.5 * s.x),
        // The front starts where the tray, a board above its bottom edge, clears the shell.
        (SHELL - BOARD, split - 0.003),
        front,
        (
            0.5 * s.x - SHELL - DRAWER_CLEARANCE,
            s.y - door - 2.0 * SHELL,
        ),
        STEEL,
        BLACK,
    );
    b.finish(id, "fridge")
}

/// A microwave whose glass door, hinged on the left, covers the whole front.
pub fn microwave_full_door(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(BLACK);
    let front = shell(&mut b, s, BOARD);
    let inside = b.part(
        "cavity",
        PartsBuilder::BODY,
        glam::Affine3A::IDENTITY,
        crate::base::JointSpec::FIXED,
        INSIDE,
    );
    b.add(
        inside,
        TriMesh::cuboid(
            Vec3::new(-0.5 * s.x + SHELL, 0.5 * s.y - SHELL - 0.005, SHELL),
            Vec3::new(0.5 * s.x - SHELL, 0.5 * s.y - SHELL, s.z - SHELL),
        ),
    );
    b.hinged_door(
        "door",
        PartsBuilder::BODY,
        (-0.5 * s.x, 0.5 * s.x),
        (0.0, s.z),
        front,
        HingeSide::Left,
        GLASS,
        STEEL,
    );
    b.finish(id, "microwave")
}

/// A microwave with a control panel on the right and a door over the left three quarters.
pub fn microwave_panel(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(WHITE);
    let front = shell(&mut b, s, BOARD);
    let panel_x = 0.5 * s.x - 0.25 * s.x;
    b.slab(
        Vec3::new(panel_x, front - BOARD, 0.0),
        Vec3::new(0.5 * s.x, front, s.z),
    )
    .slab(
        Vec3::new(panel_x, front, SHELL),
        Vec3::new(panel_x + SHELL, 0.5 * s.y - SHELL, s.z - SHELL),
    );
    b.hinged_door(
        "door",
        PartsBuilder::BODY,
        (-0.5 * s.x, panel_x - 0.003),
        (0.0, s.z),
        front,
        HingeSide::Left,
        GLASS,
        BLACK,
    );
    b.finish(id, "microwave")
}

/// A built-in oven: a drop-down door below a control strip.
pub fn oven_builtin(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(STEEL);
    let front = shell(&mut b, s, BOARD);
    let strip = 0.12f32.min(0.2 * s.z);
    b.slab(
        Vec3::new(-0.5 * s.x, front - BOARD, s.z - strip),
        Vec3::new(0.5 * s.x, front, s.z),
    )
    .slab(
        Vec3::new(-0.5 * s.x + SHELL, front, s.z - strip - SHELL),
        Vec3::new(0.5 * s.x - SHELL, 0.5 * s.y - SHELL, s.z - strip),
    );
    b.drop_door(
        "door",
        PartsBuilder::BODY,
        (-0.5 * s.x, 0.5 * s.x),
        (0.05, s.z - strip - 0.003),
        front,
        GLASS,
        STEEL,
    );
    b.slab(
        Vec3::new(-0.5 * s.x, front - BOARD, 0.0),
        Vec3::new(0.5 * s.x, front, 0.05),
    );
    b.finish(id, "oven")
}

/// A free-standing cooker: a drop-down oven door and four burners on top.
pub fn oven_range(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(WHITE);
    let front = shell(&mut b, s, BOARD);
    let burners = b.part(
        "hob",
        PartsBuilder::BODY,
        glam::Affine3A::IDENTITY,
        crate::base::JointSpec::FIXED,
        BLACK,
    );
    for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
        b.add(
            burners,
            TriMesh::cylinder(
                Vec3::new(sx * 0.22 * s.x, sy * 0.2 * s.y, s.z),
                0.09f32.min(0.18 * s.x),
                0.012,
                20,
            ),
        );
    }
    b.drop_door(
        "door",
        PartsBuilder::BODY,
        (-0.5 * s.x, 0.5 * s.x),
        (0.1, s.z - 0.1),
        front,
        GLASS,
        STEEL,
    );
    b.slab(
        Vec3::new(-0.5 * s.x, front - BOARD, 0.0),
        Vec3::new(0.5 * s.x, front, 0.1),
    )
    .slab(
        Vec3::new(-0.5 * s.x, front - BOARD, s.z - 0.1 + 0.003),
        Vec3::new(0.5 * s.x, front, s.z),
    );
    b.finish(id, "oven")
}

/// A dishwasher: a full-height drop-down door and a rack that slides out.
pub fn dishwasher_rack(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(STEEL);
    let front = shell(&mut b, s, BOARD);
    b.drop_door(
        "door",
        PartsBuilder::BODY,
        (-0.5 * s.x, 0.5 * s.x),
        (0.1, s.z),
        front,
        STEEL,
        BLACK,
    );
    b.slab(
        Vec3::new(-0.5 * s.x, front - BOARD, 0.0),
        Vec3::new(0.5 * s.x, front, 0.1 - 0.003),
    );
    let rack = b.part(
        "rack",
        PartsBuilder::BODY,
        glam::Affine3A::from_translation(Vec3::new(0.0, front + 0.02, 0.25 * s.z)),
        crate::base::JointSpec::prismatic(-Vec3::Y, 0.0, 0.6 * s.y),
        INSIDE,
    );
    let w = 0.5 * s.x - SHELL - 0.01;
    b.add(
        rack,
        TriMesh::cuboid(
            Vec3::new(-w, 0.0, 0.0),
            Vec3::new(w, s.y - BOARD - 2.0 * SHELL - 0.03, 0.015),
        ),
    );
    b.finish(id, "dishwasher")
}

/// A dishwasher panelled like the cabinets around it, with a control strip above the door.
pub fn dishwasher_panel(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(WHITE);
    let front = shell(&mut b, s, BOARD);
    b.slab(
        Vec3::new(-0.5 * s.x, front - BOARD, s.z - 0.08),
        Vec3::new(0.5 * s.x, front, s.z),
    );
    b.drop_door(
        "door",
        PartsBuilder::BODY,
        (-0.5 * s.x, 0.5 * s.x),
        (0.08, s.z - 0.083),
        front,
        WHITE,
        STEEL,
    );
    b.slab(
        Vec3::new(-0.5 * s.x, front - BOARD, 0.0),
        Vec3::new(0.5 * s.x, front, 0.08 - 0.003),
    );
    b.finish(id, "dishwasher")
}
