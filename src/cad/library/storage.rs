//! Parametric cabinets: carcasses with hinged doors, drawers, or both.

use glam::Vec3;

use crate::cad::library::builder::{BOARD, DRAWER_CLEARANCE, HingeSide, PartsBuilder};
use crate::cad::model::CadModel;

const RED: [f32; 3] = [0.62, 0.12, 0.1];
const WHITE: [f32; 3] = [0.9, 0.9, 0.88];
const BIRCH: [f32; 3] = [0.8, 0.68, 0.5];
const CARCASS: [f32; 3] = [0.75, 0.74, 0.7];
const STEEL: [f32; 3] = [0.6, 0.6, 0.62];

/// Gap between neighbouring fronts, metres.
const GAP: f32 = 0.004;

fn carcass(b: &mut PartsBuilder, s: Vec3, plinth: f32) {
    b.carcass(
        Vec3::new(-0.5 * s.x, -0.5 * s.y + BOARD, plinth),
        Vec3::new(0.5 * s.x, 0.5 * s.y, s.z),
    );
    if plinth > 0.0 {
        b.slab(
            Vec3::new(-0.5 * s.x + 0.02, -0.5 * s.y + BOARD + 0.05, 0.0),
            Vec3::new(0.5 * s.x - 0.02, 0.5 * s.y, plinth),
        );
    }
    // An inner shelf halfway up gives the inside a support surface.
    let mid = plinth + 0.5 * (s.z - plinth);
    b.slab(
        Vec3::new(-0.5 * s.x + BOARD, -0.5 * s.y + BOARD + 0.02, mid),
        Vec3::new(0.5 * s.x - BOARD, 0.5 * s.y - BOARD, mid + BOARD),
    );
}

/// Two doors hinged at the outer sides, meeting in the middle.
pub fn cabinet_two_doors(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(CARCASS);
    let plinth = 0.08;
    carcass(&mut b, s, plinth);
    let front = -0.5 * s.y + BOARD;
    let z = (plinth + GAP, s.z - GAP);
    b.hinged_door(
        "door_left",
        PartsBuilder::BODY,
        (-0.5 * s.x + GAP, -GAP),
        z,
        front,
        HingeSide::Left,
        RED,
        STEEL,
    );
    b.hinged_door(
        "door_right",
        PartsBuilder::BODY,
        (GAP, 0.5 * s.x - GAP),
        z,
        front,
        HingeSide::Right,
        RED,
        STEEL,
    );
    b.finish(id, "cabinet")
}

/// A chest of three drawers.
pub fn cabinet_drawers(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(CARCASS);
    let plinth = 0.08;
    b.carcass(
        Vec3::new(-0.5 * s.x, -0.5 * s.y + BOARD, plinth),
        Vec3::new(0.5 * s.x, 0.5 * s.y, s.z),
    )
    .slab(
        Vec3::new(-0.5 * s.x + 0.02, -0.5 * s.y + BOARD + 0.05, 0.0),
        Vec3::new(0.5 * s.x - 0.02, 0.5 * s.y, plinth),
    );
    let front = -0.5 * s.y + BOARD;
    let h = (s.z - plinth) / 3.0;
    for k in 0..3 {
        let z0 = plinth + k as f32 * h;
        b.drawer(
            &format!("drawer_{}", 3 - k),
            PartsBuilder::BODY,
            (-0.5 * s.x + GAP, 0.5 * s.x - GAP),
            (z0 + GAP, z0 + h - GAP),
            front,
            (
                0.5 * s.x - BOARD - DRAWER_CLEARANCE,
                s.y - 2.0 * BOARD - 0.03,
            ),
            WHITE,
            STEEL,
        );
    }
    b.finish(id, "cabinet")
}

/// A base unit: one drawer on top of a single door hinged on the left.
pub fn cabinet_drawer_door(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(CARCASS);
    let plinth = 0.08;
    carcass(&mut b, s, plinth);
    let front = -0.5 * s.y + BOARD;
    let drawer_h = 0.18f32.min(0.3 * s.z);
    let x = (-0.5 * s.x + GAP, 0.5 * s.x - GAP);
    b.drawer(
        "drawer_1",
        PartsBuilder::BODY,
        x,
        (s.z - drawer_h + GAP, s.z - GAP),
        front,
        (
            0.5 * s.x - BOARD - DRAWER_CLEARANCE,
            s.y - 2.0 * BOARD - 0.03,
        ),
        BIRCH,
        STEEL,
    );
    b.hinged_door(
        "door",
        PartsBuilder::BODY,
        x,
        (plinth + GAP, s.z - drawer_h - GAP),
        front,
        HingeSide::Left,
        BIRCH,
        STEEL,
    );
    b.finish(id, "cabinet")
}

/// A wall unit without plinth: one door hinged on the right, for hanging on a wall.
pub fn cabinet_wall(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(CARCASS);
    carcass(&mut b, s, 0.0);
    let front = -0.5 * s.y + BOARD;
    b.hinged_door(
        "door",
        PartsBuilder::BODY,
        (-0.5 * s.x + GAP, 0.5 * s.x - GAP),
        (GAP, s.z - GAP),
        front,
        HingeSide::Right,
        WHITE,
        STEEL,
    );
    b.finish(id, "cabinet")
}
