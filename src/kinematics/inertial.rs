//! Mass, centre of mass and inertia tensor of a link from its mesh and its class's density.
//!
//! Each connected component counts once: by its own volume when it is closed (a board, a leg, a
//! cup with its inner wall), by its convex hull otherwise (an open scan or an open shell).

use glam::{Mat3, Vec3};
use parry3d::mass_properties::MassProperties;
use serde::Serialize;

use crate::geometry::TriMesh;

/// Lighter links than this are given this mass, so no simulator sees a zero-mass moving body
/// (a paper-thin part that happens to have no volume).
pub const MIN_MASS_KG: f32 = 0.01;

/// Mass properties in the link's frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Inertial {
    pub mass: f32,
    pub center_of_mass: Vec3,
    /// The inertia tensor about the centre of mass, in the link's axes (kg m^2).
    pub inertia: Mat3,
}

impl Inertial {
    /// The mass properties of `mesh` filled with `density` (kg/m^3).
    pub fn of_mesh(mesh: &TriMesh, density: f32) -> Inertial {
        let mut total: Option<MassProperties> = None;
        for component in mesh.connected_components() {
            let solid = if component.is_closed() && component.signed_volume() > 0.0 {
                Some(component)
            } else {
                component.convex_hull()
            };
            if let Some(solid) = solid {
                let part =
                    MassProperties::from_trimesh(density, &solid.positions, &solid.triangles);
                total = Some(total.map_or(part, |t| t + part));
            }
        }
        let Some(total) = total else {
            return Self::small_box(mesh);
        };
        let mass = total.mass();
        if !(mass.is_finite() && mass >= MIN_MASS_KG) {
            return Self::small_box(mesh);
        }
        Inertial {
            mass,
            center_of_mass: total.local_com,
            inertia: total.reconstruct_inertia_matrix(),
        }
    }

    /// `MIN_MASS_KG` spread over the mesh's bounding box (or a 1 cm cube at the origin).
    fn small_box(mesh: &TriMesh) -> Inertial {
        let (lo, hi) = mesh
            .bounds()
            .unwrap_or((Vec3::splat(-0.005), Vec3::splat(0.005)));
        let s = (hi - lo).max(Vec3::splat(0.01));
        let m = MIN_MASS_KG;
        Inertial {
            mass: m,
            center_of_mass: (lo + hi) / 2.0,
            inertia: Mat3::from_diagonal(Vec3::new(
                m * (s.y * s.y + s.z * s.z) / 12.0,
                m * (s.x * s.x + s.z * s.z) / 12.0,
                m * (s.x * s.x + s.y * s.y) / 12.0,
            )),
        }
    }

    /// Whether the tensor is a physical one: symmetric, positive principal moments that satisfy
    /// the triangle inequality (what MuJoCo checks before it loads a body).
    pub fn is_physical(&self) -> bool {
        let i = self.inertia;
        let symmetric = (i.x_axis.y - i.y_axis.x).abs() < 1e-6
            && (i.x_axis.z - i.z_axis.x).abs() < 1e-6
            && (i.y_axis.z - i.z_axis.y).abs() < 1e-6;
        let d = Vec3::new(i.x_axis.x, i.y_axis.y, i.z_axis.z);
        let tolerance = 1e-6 * (d.x + d.y + d.z);
        self.mass > 0.0
            && symmetric
            && d.min_element() > 0.0
            && d.x + d.y + tolerance >= d.z
            && d.y + d.z + tolerance >= d.x
            && d.x + d.z + tolerance >= d.y
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_solid_box_has_the_textbook_mass_and_inertia() {
        let size = Vec3::new(0.4, 0.2, 0.1);
        let mesh = TriMesh::cuboid_centered(Vec3::new(1.0, 0.0, 0.05), size);
        let inertial = Inertial::of_mesh(&mesh, 500.0);
        let m = 500.0 * size.x * size.y * size.z;
        assert!((inertial.mass - m).abs() < 1e-4 * m);
        assert!(inertial.center_of_mass.distance(Vec3::new(1.0, 0.0, 0.05)) < 1e-5);
        let expected = Vec3::new(
            m * (size.y * size.y + size.z * size.z) / 12.0,
            m * (size.x * size.x + size.z * size.z) / 12.0,
            m * (size.x * size.x + size.y * size.y) / 12.0,
        );
        let diagonal = Vec3::new(
            inertial.inertia.x_axis.x,
            inertial.inertia.y_axis.y,
            inertial.inertia.z_axis.z,
        );
        assert!((diagonal - expected).abs().max_element() < 1e-4 * expected.max_element());
        assert!(inertial.inertia.x_axis.y.abs() < 1e-7);
        assert!(inertial.is_physical());
    }

    #[test]
    fn two_boards_weigh_their_own_volume_not_their_hull() {
        let mut mesh = TriMesh::cuboid(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.02));
        mesh.append(&TriMesh::cuboid(
            Vec3::new(0.0, 0.0, 0.98),
            Vec3::new(1.0, 1.0, 1.0),
        ));
        let inertial = Inertial::of_mesh(&mesh, 1000.0);
        assert!((inertial.mass - 40.0).abs() < 0.01, "{}", inertial.mass);
        assert!((inertial.center_of_mass.z - 0.5).abs() < 1e-4);
    }

    #[test]
    fn an_open_shell_counts_as_its_hull_and_nothing_gets_zero_mass() {
        let mut open = TriMesh::cuboid(Vec3::ZERO, Vec3::ONE * 0.1);
        open.triangles.truncate(10);
        let inertial = Inertial::of_mesh(&open, 1000.0);
        assert!((inertial.mass - 1.0).abs() < 1e-3);
        let flat = TriMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            triangles: vec![[0, 1, 2]],
        };
        let tiny = Inertial::of_mesh(&flat, 1000.0);
        assert_eq!(tiny.mass, MIN_MASS_KG);
        assert!(tiny.is_physical());
    }
}
