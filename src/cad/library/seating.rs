//! Parametric chairs, sofas and beds.

use glam::{Vec2, Vec3};

use crate::cad::library::builder::PartsBuilder;
use crate::cad::model::CadModel;
use crate::geometry::TriMesh;

const WOOD: [f32; 3] = [0.55, 0.36, 0.2];
const DARK_WOOD: [f32; 3] = [0.33, 0.2, 0.12];
const BLACK: [f32; 3] = [0.08, 0.08, 0.09];
const FABRIC_BLUE: [f32; 3] = [0.2, 0.3, 0.55];
const FABRIC_GREY: [f32; 3] = [0.45, 0.45, 0.48];
const LINEN: [f32; 3] = [0.85, 0.83, 0.78];

/// Seat height as a fraction of the overall height of a chair with a back.
const SEAT: f32 = 0.5;

/// Four legs, a seat board and a solid backrest at the rear (+y).
pub fn chair_classic(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(WOOD);
    let seat_z = SEAT * s.z;
    b.legs(s.x, s.y, seat_z - 0.03, 0.01, 0.035)
        .slab(
            Vec3::new(-0.5 * s.x, -0.5 * s.y, seat_z - 0.03),
            Vec3::new(0.5 * s.x, 0.5 * s.y, seat_z),
        )
        .slab(
            Vec3::new(-0.5 * s.x, 0.5 * s.y - 0.035, seat_z),
            Vec3::new(-0.5 * s.x + 0.035, 0.5 * s.y, s.z),
        )
        .slab(
            Vec3::new(0.5 * s.x - 0.035, 0.5 * s.y - 0.035, seat_z),
            Vec3::new(0.5 * s.x, 0.5 * s.y, s.z),
        )
        .slab(
            Vec3::new(-0.5 * s.x, 0.5 * s.y - 0.025, 0.72 * s.z),
            Vec3::new(0.5 * s.x, 0.5 * s.y, s.z),
        );
    b.finish(id, "chair")
}

/// An upholstered armchair: legs, a thick seat, a back and two armrests.
pub fn chair_arm(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(FABRIC_BLUE);
    let seat_z = 0.45 * s.z;
    let arm = 0.08 * s.x;
    b.legs(s.x, s.y, 0.15 * s.z, 0.02, 0.04)
        .slab(
            Vec3::new(-0.5 * s.x, -0.5 * s.y, 0.15 * s.z),
            Vec3::new(0.5 * s.x, 0.5 * s.y, seat_z),
        )
        .slab(
            Vec3::new(-0.5 * s.x, 0.5 * s.y - 0.12 * s.y, seat_z),
            Vec3::new(0.5 * s.x, 0.5 * s.y, s.z),
        )
        .slab(
            Vec3::new(-0.5 * s.x, -0.5 * s.y, seat_z),
            Vec3::new(-0.5 * s.x + arm, 0.5 * s.y, 0.68 * s.z),
        )
        .slab(
            Vec3::new(0.5 * s.x - arm, -0.5 * s.y, seat_z),
            Vec3::new(0.5 * s.x, 0.5 * s.y, 0.68 * s.z),
        );
    b.finish(id, "chair")
}

/// A bar stool: a round seat on four splayed legs with a foot ring, no back.
pub fn chair_stool(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(BLACK);
    let r = 0.5 * s.x.min(s.y);
    let seat_t = 0.04;
    b.add(
        PartsBuilder::BODY,
        TriMesh::cylinder(Vec3::new(0.0, 0.0, s.z - seat_t), r, seat_t, 24),
    );
    for k in 0..4 {
        let a = std::f32::consts::FRAC_PI_4 + k as f32 * std::f32::consts::FRAC_PI_2;
        let dir = Vec3::new(a.cos(), a.sin(), 0.0);
        b.add(
            PartsBuilder::BODY,
            TriMesh::rod(
                dir * (r - 0.02),
                dir * (0.55 * r) + Vec3::Z * (s.z - seat_t),
                0.015,
                8,
            ),
        );
    }
    let ring = TriMesh::lathe(
        Vec3::new(0.0, 0.0, 0.3 * s.z),
        &[
            Vec2::new(0.8 * r, 0.0),
            Vec2::new(0.8 * r, 0.02),
            Vec2::new(0.72 * r, 0.02),
            Vec2::new(0.72 * r, 0.0),
            Vec2::new(0.8 * r, 0.0),
        ],
        24,
    );
    b.add(PartsBuilder::BODY, ring);
    b.finish(id, "chair")
}

/// An office chair: a five-spoke base, a gas column, a seat and a backrest.
pub fn chair_office(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(BLACK);
    let r = 0.5 * s.x.min(s.y);
    let seat_z = 0.5 * s.z;
    for k in 0..5 {
        let a = k as f32 * std::f32::consts::TAU / 5.0 - std::f32::consts::FRAC_PI_2;
        let dir = Vec3::new(a.cos(), a.sin(), 0.0);
        b.add(
            PartsBuilder::BODY,
            TriMesh::rod(Vec3::Z * 0.06, dir * (r - 0.03) + Vec3::Z * 0.06, 0.02, 6),
        );
        b.add(
            PartsBuilder::BODY,
            TriMesh::cylinder(dir * (r - 0.03), 0.025, 0.06, 8),
        );
    }
    b.add(
        PartsBuilder::BODY,
        TriMesh::cylinder(Vec3::Z * 0.06, 0.025, seat_z - 0.13, 12),
    )
    .slab(
        Vec3::new(-0.5 * s.x + 0.02, -0.5 * s.y + 0.02, seat_z - 0.07),
        Vec3::new(0.5 * s.x - 0.02, 0.4 * s.y, seat_z),
    )
    .slab(
        Vec3::new(-0.02, 0.4 * s.y, seat_z - 0.05),
        Vec3::new(0.02, 0.5 * s.y - 0.05, 0.7 * s.z),
    )
    .slab(
        Vec3::new(-0.42 * s.x, 0.5 * s.y - 0.06, 0.6 * s.z),
        Vec3::new(0.42 * s.x, 0.5 * s.y, s.z),
    );
    b.finish(id, "chair")
}

/// A ladder-back chair: the rear legs rise into posts joined by three rails.
pub fn chair_ladder(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(DARK_WOOD);
    let seat_z = SEAT * s.z;
    let leg = 0.03;
    b.legs(s.x, s.y, seat_z - 0.025, 0.0, leg).slab(
        Vec3::new(-0.5 * s.x, -0.5 * s.y, seat_z - 0.025),
        Vec3::new(0.5 * s.x, 0.5 * s.y, seat_z),
    );
    for sx in [-1.0, 1.0] {
        let x = sx * (0.5 * s.x - 0.5 * leg);
        b.slab(
            Vec3::new(x - 0.5 * leg, 0.5 * s.y - leg, seat_z),
            Vec3::new(x + 0.5 * leg, 0.5 * s.y, s.z),
        );
    }
    for k in 0..3 {
        let z = seat_z + (k as f32 + 1.0) * 0.25 * (s.z - seat_z);
        b.slab(
            Vec3::new(-0.5 * s.x + leg, 0.5 * s.y - 0.02, z - 0.03),
            Vec3::new(0.5 * s.x - leg, 0.5 * s.y - 0.005, z + 0.03),
        );
    }
    b.finish(id, "chair")
}

/// A box sofa: a plinth, seat cushions, a back and two arms.
pub fn sofa_box(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(FABRIC_GREY);
    let arm = 0.12f32.min(0.15 * s.x);
    let seat_z = 0.5 * s.z;
    b.slab(
        Vec3::new(-0.5 * s.x, -0.5 * s.y, 0.0),
        Vec3::new(0.5 * s.x, 0.5 * s.y, 0.12),
    )
    .slab(
        Vec3::new(-0.5 * s.x + arm, -0.5 * s.y, 0.12),
        Vec3::new(0.5 * s.x - arm, 0.5 * s.y, seat_z),
    )
    .slab(
        Vec3::new(-0.5 * s.x + arm, 0.5 * s.y - 0.2, seat_z),
        Vec3::new(0.5 * s.x - arm, 0.5 * s.y, s.z),
    )
    .slab(
        Vec3::new(-0.5 * s.x, -0.5 * s.y, 0.12),
        Vec3::new(-0.5 * s.x + arm, 0.5 * s.y, 0.75 * s.z),
    )
    .slab(
        Vec3::new(0.5 * s.x - arm, -0.5 * s.y, 0.12),
        Vec3::new(0.5 * s.x, 0.5 * s.y, 0.75 * s.z),
    );
    b.finish(id, "sofa")
}

/// A sofa on legs with separate seat cushions and a lower back.
pub fn sofa_legs(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(FABRIC_BLUE);
    let leg_h = 0.15;
    let seat_z = 0.52 * s.z;
    let arm = 0.08f32.min(0.1 * s.x);
    b.legs(s.x, s.y, leg_h, 0.05, 0.04).slab(
        Vec3::new(-0.5 * s.x, -0.5 * s.y, leg_h),
        Vec3::new(0.5 * s.x, 0.5 * s.y, leg_h + 0.1),
    );
    let seats = ((s.x - 2.0 * arm) / 0.6).round().max(1.0) as usize;
    let seat_w = (s.x - 2.0 * arm) / seats as f32;
    for k in 0..seats {
        let x0 = -0.5 * s.x + arm + k as f32 * seat_w;
        b.slab(
            Vec3::new(x0 + 0.005, -0.5 * s.y, leg_h + 0.1),
            Vec3::new(x0 + seat_w - 0.005, 0.5 * s.y - 0.18, seat_z),
        );
    }
    b.slab(
        Vec3::new(-0.5 * s.x + arm, 0.5 * s.y - 0.18, leg_h + 0.1),
        Vec3::new(0.5 * s.x - arm, 0.5 * s.y, s.z),
    )
    .slab(
        Vec3::new(-0.5 * s.x, -0.5 * s.y, leg_h + 0.1),
        Vec3::new(-0.5 * s.x + arm, 0.5 * s.y, 0.72 * s.z),
    )
    .slab(
        Vec3::new(0.5 * s.x - arm, -0.5 * s.y, leg_h + 0.1),
        Vec3::new(0.5 * s.x, 0.5 * s.y, 0.72 * s.z),
    );
    b.finish(id, "sofa")
}

/// A bed: a frame, a mattress and a headboard at the rear (+y).
pub fn bed_headboard(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(WOOD);
    let head = 0.05;
    let mattress = b.part(
        "mattress",
        PartsBuilder::BODY,
        glam::Affine3A::IDENTITY,
        crate::base::JointSpec::FIXED,
        LINEN,
    );
    b.slab(
        Vec3::new(-0.5 * s.x, -0.5 * s.y, 0.0),
        Vec3::new(0.5 * s.x, 0.5 * s.y - head, 0.3 * s.z.min(1.0)),
    )
    .slab(
        Vec3::new(-0.5 * s.x, 0.5 * s.y - head, 0.0),
        Vec3::new(0.5 * s.x, 0.5 * s.y, s.z),
    )
    .add(
        mattress,
        TriMesh::cuboid(
            Vec3::new(-0.5 * s.x + 0.02, -0.5 * s.y + 0.02, 0.3 * s.z.min(1.0)),
            Vec3::new(0.5 * s.x - 0.02, 0.5 * s.y - head, 0.55 * s.z.min(1.0)),
        ),
    );
    b.finish(id, "bed")
}

/// A bed on legs with a head- and a footboard.
pub fn bed_legs(id: &str, s: Vec3) -> CadModel {
    let mut b = PartsBuilder::new(DARK_WOOD);
    let board = 0.04;
    let h = s.z.min(1.2);
    let mattress = b.part(
        "mattress",
        PartsBuilder::BODY,
        glam::Affine3A::IDENTITY,
        crate::base::JointSpec::FIXED,
        LINEN,
    );
    b.legs(s.x, s.y, 0.2 * h, 0.0, 0.06)
        .slab(
            Vec3::new(-0.5 * s.x, -0.5 * s.y + board, 0.2 * h),
            Vec3::new(0.5 * s.x, 0.5 * s.y - board, 0.3 * h),
        )
        .slab(
            Vec3::new(-0.5 * s.x, 0.5 * s.y - board, 0.2 * h),
            Vec3::new(0.5 * s.x, 0.5 * s.y, h),
        )
        .slab(
            Vec3::new(-0.5 * s.x, -0.5 * s.y, 0.2 * h),
            Vec3::new(0.5 * s.x, -0.5 * s.y + board, 0.6 * h),
        )
        .add(
            mattress,
            TriMesh::cuboid(
                Vec3::new(-0.5 * s.x + 0.02, -0.5 * s.y + board, 0.3 * h),
                Vec3::new(0.5 * s.x - 0.02, 0.5 * s.y - board, 0.5 * h),
            ),
        );
    b.finish(id, "bed")
}
