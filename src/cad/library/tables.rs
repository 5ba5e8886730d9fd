//! Parametric tables and open shelves.

use glam::{Vec2, Vec3};

use crate::cad::library::builder::{BOARD, PartsBuilder};
use crate::cad::model::CadModel;
use crate::geometry::TriMesh;

const OAK: [f32; 3] = [0.7, 0.52, 0.32];
const WALNUT: [f32; 3] = [0.4, 0.26, 0.16];
const WHITE: [f32; 3] = [0.88, 0.88, 0.86];
const STEEL: [f32; 3] = [0.55, 0.56, 0.58];

const TOP: f32 = 0.035;

/// A rectangular top on four legs with an apron.
pub fn table_legs(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(OAK);
    b.legs(s.x, s.y, s.z - TOP, 0.05, 0.05)
        .slab(
            Vec3::new(-0.5 * s.x, -0.5 * s.y, s.z - TOP),
            Vec3::new(0.5 * s.x, 0.5 * s.y, s.z),
        )
        .slab(
            Vec3::new(-0.5 * s.x + 0.05, -0.5 * s.y + 0.07, s.z - TOP - 0.08),
            Vec3::new(0.5 * s.x - 0.05, -0.5 * s.y + 0.09, s.z - TOP),
        )
        .slab(
            Vec3::new(-0.5 * s.x + 0.05, 0.5 * s.y - 0.09, s.z - TOP - 0.08),
            Vec3::new(0.5 * s.x - 0.05, 0.5 * s.y - 0.07, s.z - TOP),
        );
    b.finish(id, "table")
}

/// A round top on a central pedestal and a round foot.
pub fn table_pedestal(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(WHITE);
    let r = 0.5 * s.x.min(s.y);
    b.add(
        PartsBuilder::BODY,
        TriMesh::cylinder(Vec3::new(0.0, 0.0, s.z - TOP), r, TOP, 40),
    )
    .add(
        PartsBuilder::BODY,
        TriMesh::cylinder(Vec3::ZERO, 0.45 * r, 0.03, 32),
    )
    .add(
        PartsBuilder::BODY,
        TriMesh::lathe(
            Vec3::ZERO,
            &[Vec2::new(0.05, 0.03), Vec2::new(0.04, s.z - TOP)],
            16,
        ),
    );
    b.finish(id, "table")
}

/// Two panel legs joined by a stretcher under a rectangular top.
pub fn table_trestle(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(WALNUT);
    let panel = 0.05;
    let inset = 0.12 * s.x;
    for sx in [-1.0, 1.0] {
        let x = sx * (0.5 * s.x - inset);
        b.slab(
            Vec3::new(x - 0.5 * panel, -0.4 * s.y, 0.0),
            Vec3::new(x + 0.5 * panel, 0.4 * s.y, s.z - TOP),
        );
    }
    b.slab(
        Vec3::new(-0.5 * s.x + inset, -0.03, 0.25 * s.z),
        Vec3::new(0.5 * s.x - inset, 0.03, 0.35 * s.z),
    )
    .slab(
        Vec3::new(-0.5 * s.x, -0.5 * s.y, s.z - TOP),
        Vec3::new(0.5 * s.x, 0.5 * s.y, s.z),
    );
    b.finish(id, "table")
}

/// A desk: a top on two side panels with a modesty panel at the rear.
pub fn table_desk(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(WHITE);
    b.slab(
        Vec3::new(-0.5 * s.x, -0.5 * s.y, s.z - TOP),
        Vec3::new(0.5 * s.x, 0.5 * s.y, s.z),
    )
    .slab(
        Vec3::new(-0.5 * s.x, -0.5 * s.y, 0.0),
        Vec3::new(-0.5 * s.x + BOARD, 0.5 * s.y, s.z - TOP),
    )
    .slab(
        Vec3::new(0.5 * s.x - BOARD, -0.5 * s.y, 0.0),
        Vec3::new(0.5 * s.x, 0.5 * s.y, s.z - TOP),
    )
    .slab(
        Vec3::new(-0.5 * s.x + BOARD, 0.5 * s.y - 0.1, 0.35 * s.z),
        Vec3::new(0.5 * s.x - BOARD, 0.5 * s.y - 0.1 + BOARD, s.z - TOP),
    );
    b.finish(id, "table")
}

/// A bookcase: two sides, a back, a top, a plinth and evenly spaced boards.
pub fn shelf_bookcase(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(WALNUT);
    b.carcass(
        Vec3::new(-0.5 * s.x, -0.5 * s.y, 0.0),
        Vec3::new(0.5 * s.x, 0.5 * s.y, s.z),
    );
    let boards = ((s.z / 0.35).floor() as usize).max(2);
    for k in 1..boards {
        let z = k as f32 * s.z / boards as f32;
        b.slab(
            Vec3::new(-0.5 * s.x + BOARD, -0.5 * s.y, z),
            Vec3::new(0.5 * s.x - BOARD, 0.5 * s.y - BOARD, z + BOARD),
        );
    }
    b.finish(id, "shelf")
}

/// An open metal rack: four posts and four boards.
pub fn shelf_rack(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(STEEL);
    b.legs(s.x, s.y, s.z, 0.0, 0.025);
    for k in 0..4 {
        let z = 0.08 + k as f32 * (s.z - 0.1) / 3.0;
        b.slab(
            Vec3::new(-0.5 * s.x, -0.5 * s.y, z - 0.015),
            Vec3::new(0.5 * s.x, 0.5 * s.y, z),
        );
    }
    b.finish(id, "shelf")
}
