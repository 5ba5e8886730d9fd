//! Assembly helpers for the parametric models: panels, legs, handles, hinged doors and drawers.

use glam::{Affine3A, Vec3};

use crate::base::JointSpec;
use crate::cad::model::{CadModel, CadPart};
use crate::geometry::TriMesh;

/// Panel thickness of furniture boards, metres.
pub const BOARD: f32 = 0.018;
/// How far a handle stands out of a front, metres.
pub const HANDLE_DEPTH: f32 = 0.025;
/// Play (metres) between a drawer's tray and the sides of the opening it slides in.
pub const DRAWER_CLEARANCE: f32 = 0.005;
/// Opening range of side-hinged doors, radians (a little over 100 degrees).
pub const DOOR_OPEN: f32 = 1.8;

/// Which side of a front its hinge is on, seen from the front.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HingeSide {
    Left,
    Right,
}

/// Collects parts; part 0 is the body, to which the rest attach.
pub struct PartsBuilder {
    parts: Vec<CadPart>,
}

impl PartsBuilder {
    pub fn new(body_color: [f32; 3]) -> Self {
        Self {
            parts: vec![CadPart {
                name: "body".into(),
                parent: None,
                parent_from_part: Affine3A::IDENTITY,
                joint: JointSpec::FIXED,
                mesh: TriMesh::default(),
                visual: None,
                color: body_color,
            }],
        }
    }

    pub const BODY: usize = 0;

    /// Adds geometry, given in the part's frame, to part `part`.
    pub fn add(&mut self, part: usize, mesh: TriMesh) -> &mut Self {
        if let Some(p) = self.parts.get_mut(part) {
            p.mesh.append(&mesh);
        }
        self
    }

    /// Adds a box spanning `min..max` to the body.
    pub fn slab(&mut self, min: Vec3, max: Vec3) -> &mut Self {
        self.add(Self::BODY, TriMesh::cuboid(min, max))
    }

    pub fn part(
        &mut self,
        name: &str,
        parent: usize,
        parent_from_part: Affine3A,
        joint: JointSpec,
        color: [f32; 3],
    ) -> usize {
        self.parts.push(CadPart {
            name: name.into(),
            parent: Some(parent),
            parent_from_part,
            joint,
            mesh: TriMesh::default(),
            visual: None,
            color,
        });
        self.parts.len() - 1
    }

    /// Four square legs of side `thickness` under a `width` x `depth` footprint, `inset` from its edges.
    pub fn legs(
        &mut self,
        width: f32,
        depth: f32,
        height: f32,
        inset: f32,
        thickness: f32,
    ) -> &mut Self {
        for sx in [-1.0, 1.0] {
            for sy in [-1.0, 1.0] {
                let c = Vec3::new(
                    sx * (0.5 * width - inset - 0.5 * thickness),
                    sy * (0.5 * depth - inset - 0.5 * thickness),
                    0.0,
                );
                let half = Vec3::new(0.5 * thickness, 0.5 * thickness, 0.0);
                self.slab(c - half, c + half + Vec3::Z * height);
            }
        }
        self
    }

    /// A box with five boards (bottom, top, sides, back), open towards -y; `min..max` is its outside.
    pub fn carcass(&mut self, min: Vec3, max: Vec3) -> &mut Self {
        let t = BOARD;
        self.slab(min, Vec3::new(max.x, max.y, min.z + t))
            .slab(Vec3::new(min.x, min.y, max.z - t), max)
            .slab(
                Vec3::new(min.x, min.y, min.z + t),
                Vec3::new(min.x + t, max.y, max.z - t),
            )
            .slab(
                Vec3::new(max.x - t, min.y, min.z + t),
                Vec3::new(max.x, max.y, max.z - t),
            )
            .slab(
                Vec3::new(min.x + t, max.y - t, min.z + t),
                Vec3::new(max.x - t, max.y, max.z - t),
            )
    }

    /// A side-hinged door covering `x0..x1` by `z0..z1` on the front plane `front_y`, with a
    /// vertical handle near its free edge. Opening swings the free edge out (towards -y).
    #[expect(
        clippy::too_many_arguments,
        reason = "a door is described by its rectangle, hinge and colours"
    )]
    pub fn hinged_door(
        &mut self,
        name: &str,
        parent: usize,
        (x0, x1): (f32, f32),
        (z0, z1): (f32, f32),
        front_y: f32,
        hinge: HingeSide,
        color: [f32; 3],
        handle_color: [f32; 3],
    ) -> usize {
        let width = x1 - x0;
        let height = z1 - z0;
        let (hinge_x, axis, sign) = match hinge {
            HingeSide::Left => (x0, -Vec3::Z, 1.0),
            HingeSide::Right => (x1, Vec3::Z, -1.0),
        };
        // The hinge runs along the door's outer edge, so the open door never swings back into
        // the side of its own body.
        let door = self.part(
            name,
            parent,
            Affine3A::from_translation(Vec3::new(hinge_x, front_y - BOARD, z0)),
            JointSpec::revolute(axis, 0.0, DOOR_OPEN),
            color,
        );
        let (lo, hi) = if sign > 0.0 {
            (0.0, width)
        } else {
            (-width, 0.0)
        };
        self.add(
            door,
            TriMesh::cuboid(Vec3::new(lo, 0.0, 0.0), Vec3::new(hi, BOARD, height)),
        );
        let handle_x = sign * (width - 0.06f32.min(0.25 * width));
        let handle_len = (0.3 * height).clamp(0.05, 0.35);
        let handle_z = if height > 1.0 {
            0.35 * height
        } else {
            0.5 * height
        };
        let handle = self.part(
            &format!("{name}_handle"),
            door,
            Affine3A::IDENTITY,
            JointSpec::FIXED,
            handle_color,
        );
        self.add(
            handle,
            TriMesh::cuboid(
                Vec3::new(handle_x - 0.008, -HANDLE_DEPTH, handle_z - 0.5 * handle_len),
                Vec3::new(handle_x + 0.008, 0.0, handle_z + 0.5 * handle_len),
            ),
        );
        door
    }

    /// A door hinged along its bottom edge (oven, dishwasher) with a horizontal handle near its top.
    #[expect(
        clippy::too_many_arguments,
        reason = "a door is described by its rectangle and colours"
    )]
    pub fn drop_door(
        &mut self,
        name: &str,
        parent: usize,
        (x0, x1): (f32, f32),
        (z0, z1): (f32, f32),
        front_y: f32,
        color: [f32; 3],
        handle_color: [f32; 3],
    ) -> usize {
        // The hinge runs along the door's outer bottom edge: turning about it, the door folds
        // out and down in front of the body, never below the hinge line into the body's floor.
        let door = self.part(
            name,
            parent,
            Affine3A::from_translation(Vec3::new(0.5 * (x0 + x1), front_y - BOARD, z0)),
            JointSpec::revolute(Vec3::X, 0.0, std::f32::consts::FRAC_PI_2),
            color,
        );
        let w = x1 - x0;
        let h = z1 - z0;
        self.add(
            door,
            TriMesh::cuboid(Vec3::new(-0.5 * w, 0.0, 0.0), Vec3::new(0.5 * w, BOARD, h)),
        );
        let handle = self.part(
            &format!("{name}_handle"),
            door,
            Affine3A::IDENTITY,
            JointSpec::FIXED,
            handle_color,
        );
        self.add(
            handle,
            TriMesh::cuboid(
                Vec3::new(-0.35 * w, -HANDLE_DEPTH, h - 0.07),
                Vec3::new(0.35 * w, 0.0, h - 0.05),
            ),
        );
        door
    }

    /// A drawer whose front covers `x0..x1` by `z0..z1` on `front_y`, with a tray `depth` deep and
    /// `2 tray_half_width` wide behind it (narrower than the opening, so it never rubs the sides);
    /// it slides out along -y by up to three quarters of its depth.
    #[expect(
        clippy::too_many_arguments,
        reason = "a drawer is described by its rectangle, depth and colours"
    )]
    pub fn drawer(
        &mut self,
        name: &str,
        parent: usize,
        (x0, x1): (f32, f32),
        (z0, z1): (f32, f32),
        front_y: f32,
        (tray_half_width, depth): (f32, f32),
        color: [f32; 3],
        handle_color: [f32; 3],
    ) -> usize {
        let drawer = self.part(
            name,
            parent,
            Affine3A::from_translation(Vec3::new(0.5 * (x0 + x1), front_y, z0)),
            JointSpec::prismatic(-Vec3::Y, 0.0, 0.75 * depth),
            color,
        );
        let w = x1 - x0;
        let h = z1 - z0;
        let t = BOARD;
        let inner = tray_half_width;
        // The tray stands a board and some play above the front's bottom edge, clear of the
        // board under the opening.
        const TRAY_BOTTOM: f32 = BOARD + DRAWER_CLEARANCE;
        let tray_h = (0.8 * h).max(TRAY_BOTTOM + 0.03);
        self.add(
            drawer,
            TriMesh::cuboid(Vec3::new(-0.5 * w, -t, 0.0), Vec3::new(0.5 * w, 0.0, h)),
        )
        .add(
            drawer,
            TriMesh::cuboid(
                Vec3::new(-inner, 0.0, TRAY_BOTTOM),
                Vec3::new(inner, depth, TRAY_BOTTOM + t),
            ),
        )
        .add(
            drawer,
            TriMesh::cuboid(
                Vec3::new(-inner, 0.0, TRAY_BOTTOM),
                Vec3::new(-inner + t, depth, tray_h),
            ),
        )
        .add(
            drawer,
            TriMesh::cuboid(
                Vec3::new(inner - t, 0.0, TRAY_BOTTOM),
                Vec3::new(inner, depth, tray_h),
            ),
        )
        .add(
            drawer,
            TriMesh::cuboid(
                Vec3::new(-inner, depth - t, TRAY_BOTTOM),
                Vec3::new(inner, depth, tray_h),
            ),
        );
        let handle = self.part(
            &format!("{name}_handle"),
            drawer,
            Affine3A::IDENTITY,
            JointSpec::FIXED,
            handle_color,
        );
        let hz = 0.5 * h;
        self.add(
            handle,
            TriMesh::cuboid(
                Vec3::new(-0.25 * w, -t - HANDLE_DEPTH, hz - 0.01),
                Vec3::new(0.25 * w, -t, hz + 0.01),
            ),
        );
        drawer
    }

    /// Gives the handle of `part` (the `<name>_handle` part a door or drawer helper added) the
    /// geometry `mesh`, given in the body's frame: a handle where it was seen instead of where
    /// the helper puts one.
    pub fn reshape_handle(&mut self, part: usize, mesh: &TriMesh) -> &mut Self {
        let Some(name) = self.parts.get(part).map(|p| format!("{}_handle", p.name)) else {
            return self;
        };
        let mut body_from_part = Affine3A::IDENTITY;
        let mut at = Some(part);
        while let Some(k) = at.filter(|&k| k != Self::BODY) {
            body_from_part = self.parts[k].parent_from_part * body_from_part;
            at = self.parts[k].parent;
        }
        let part_from_body = body_from_part.inverse();
        if let Some(handle) = self
            .parts
            .iter_mut()
            .find(|p| p.parent == Some(part) && p.name == name)
        {
            handle.mesh = mesh.transformed(&part_from_body);
        }
        self
    }

    /// The finished model, moved so that the bottom centre of its closed bounding box is the origin.
    pub fn finish(mut self, id: &str, class: &str) -> CadModel {
        let provisional = CadModel {
            id: id.into(),
            class: class.into(),
            size: Vec3::ZERO,
            parts: self.parts.clone(),
        };
        let (lo, hi) = provisional
            .merged_mesh(&[])
            .bounds()
            .unwrap_or((Vec3::ZERO, Vec3::ZERO));
        let shift = -Vec3::new(0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), lo.z);
        for part in &mut self.parts {
            match part.parent {
                None => part.mesh = part.mesh.transformed(&Affine3A::from_translation(shift)),
                Some(0) => {
                    part.parent_from_part =
                        Affine3A::from_translation(shift) * part.parent_from_part
                }
                Some(_) => {}
            }
        }
        CadModel {
            id: id.into(),
            class: class.into(),
            size: hi - lo,
            parts: self.parts,
        }
    }
}
