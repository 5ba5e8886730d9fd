//! URDF model files read into a [`BodyTree`] (with urdf-rs): links are bodies, joints place them.
//!
//! A child link's frame is its joint's `origin` in the parent link's frame (`rpy` turns about
//! the fixed x, then y, then z axes); revolute and continuous joints become revolute (continuous
//! ones a full turn either way), prismatic ones prismatic, fixed ones weld. Collision geometry
//! is each link's shape, a mesh as its convex hull (as Bullet collides with it); visual geometry
//! gives the colours, from the visual's material or the robot's material of that name. Mesh
//! files are STL, OBJ or MuJoCo `.msh`: relative to the URDF file, `file://` paths, or
//! `package://NAME/...` found in a folder NAME that holds the file or sits beside one that does
//! (no ROS package path is searched).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{Affine3A, EulerRot, Quat, Vec3};

use crate::base::JointKind;
use crate::cad::import::body_tree::{
    Body, BodyJoint, BodyTree, MAX_BODIES, ModelFileError, check_xml_depth,
};
use crate::cad::import::mesh_files::{MeshFileError, read_mesh_file};
use crate::file_name::inside_folder;
use crate::geometry::TriMesh;

/// Facets around cylinders, capsules and spheres.
const ROUND_SEGMENTS: u32 = 16;

/// Reads the URDF file at `path`. Errors name the link or joint, not the file: the caller
/// names it.
pub fn read_urdf(path: &Path) -> Result<BodyTree, ModelFileError> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read: {e}"))?;
    let document = roxmltree::Document::parse(&text).map_err(|e| format!("not XML: {e}"))?;
    check_xml_depth(&document)?;
    drop(document);
    let robot = urdf_rs::read_from_string(&text).map_err(|e| format!("not a URDF model: {e}"))?;
    if robot.links.len() > MAX_BODIES {
        return Err(format!(
            "{} links, more than the {MAX_BODIES} a model may have",
            robot.links.len()
        )
        .into());
    }
    // Masses come from the class's density on import, but a negative one is a broken file.
    if let Some(link) = robot
        .links
        .iter()
        .find(|l| !(l.inertial.mass.value.is_finite() && l.inertial.mass.value >= 0.0))
    {
        return Err(format!(
            "link {:?}: mass {} is not a non-negative number",
            link.name, link.inertial.mass.value
        )
        .into());
    }
    let folder = path.parent().unwrap_or(Path::new("."));
    let children: Vec<&str> = robot.joints.iter().map(|j| j.child.link.as_str()).collect();
    let roots: Vec<&urdf_rs::Link> = robot
        .links
        .iter()
        .filter(|l| !children.contains(&l.name.as_str()))
        .collect();
    let [root] = roots[..] else {
        return Err(format!(
            "{} links are no joint's child; a model has one root link",
            roots.len()
        )
        .into());
    };
    let materials: HashMap<&str, [f32; 4]> = robot
        .materials
        .iter()
        .filter_map(|m| m.color.as_ref().map(|c| (m.name.as_str(), rgba(&c.rgba.0))))
        .collect();
    let links: HashMap<&str, &urdf_rs::Link> =
        robot.links.iter().map(|l| (l.name.as_str(), l)).collect();
    let mut tree = BodyTree {
        name: robot.name.clone(),
        bodies: Vec::new(),
    };
    // Breadth first from the root: a parent before its children.
    let mut queue: Vec<(&urdf_rs::Link, Option<usize>, Option<&urdf_rs::Joint>)> =
        vec![(root, None, None)];
    let mut next = 0;
    while let Some(&(link, parent, joint)) = queue.get(next) {
        next += 1;
        if tree.bodies.len() > robot.links.len() {
            return Err("the joints form a loop".to_string().into());
        }
        let mut body = Body {
            name: link.name.clone(),
            parent,
            parent_from_body: joint.map_or(Affine3A::IDENTITY, |j| pose(&j.origin)),
            joint: match joint {
                Some(j) => body_joint(j)?,
                None => None,
            },
            pieces: Vec::new(),
            visual_pieces: Vec::new(),
            visual_meshes: Vec::new(),
            colors: Vec::new(),
        };
        for collision in &link.collision {
            let mesh = geometry_mesh(&collision.geometry, folder)
                .map_err(|e| with_context(e, &format!("link {:?}: collision", link.name)))?;
            body.pieces
                .extend(mesh.transformed(&pose(&collision.origin)).convex_hull());
        }
        for visual in &link.visual {
            let mesh = geometry_mesh(&visual.geometry, folder)
                .map_err(|e| with_context(e, &format!("link {:?}: visual", link.name)))?
                .transformed(&pose(&visual.origin));
            let color = visual
                .material
                .as_ref()
                .and_then(|m| {
                    m.color
                        .as_ref()
                        .map(|c| rgba(&c.rgba.0))
                        .or_else(|| materials.get(m.name.as_str()).copied())
                })
                .unwrap_or([0.6, 0.6, 0.6, 1.0]);
            body.colors
                .push(([color[0], color[1], color[2]], mesh.area() * color[3]));
            body.visual_pieces.extend(mesh.convex_hull());
            body.visual_meshes.push(mesh);
        }
        tree.bodies.push(body);
        let index = tree.bodies.len() - 1;
        for j in robot.joints.iter().filter(|j| j.parent.link == link.name) {
            let child = links
                .get(j.child.link.as_str())
                .ok_or_else(|| format!("joint {:?}: no link {:?}", j.name, j.child.link))?;
            queue.push((child, Some(index), Some(j)));
        }
    }
    if tree.bodies.len() < robot.links.len() {
        return Err(format!(
            "{} of {} links hang from no joint chain of the root link {:?}",
            robot.links.len() - tree.bodies.len(),
            robot.links.len(),
            root.name
        )
        .into());
    }
    Ok(tree)
}

fn with_context(error: ModelFileError, context: &str) -> ModelFileError {
    match error {
        ModelFileError::Malformed(e) => ModelFileError::Malformed(format!("{context}: {e}")),
        ModelFileError::Unsupported(e) => ModelFileError::Unsupported(format!("{context}: {e}")),
    }
}

fn rgba(v: &[f64; 4]) -> [f32; 4] {
    v.map(|c| c as f32)
}

fn vec3(v: &urdf_rs::Vec3) -> Vec3 {
    Vec3::new(v.0[0] as f32, v.0[1] as f32, v.0[2] as f32)
}

/// An `<origin xyz rpy>`: roll about x, then pitch about y, then yaw about z, all fixed axes.
fn pose(origin: &urdf_rs::Pose) -> Affine3A {
    let rpy = vec3(&origin.rpy);
    let rotation = Quat::from_euler(EulerRot::ZYX, rpy.z, rpy.y, rpy.x);
    Affine3A::from_rotation_translation(rotation, vec3(&origin.xyz))
}

/// The joint that moves a child link, `None` for a fixed joint.
fn body_joint(joint: &urdf_rs::Joint) -> Result<Option<BodyJoint>, ModelFileError> {
    use urdf_rs::JointType;
    let kind = match joint.joint_type {
        JointType::Fixed => return Ok(None),
        JointType::Revolute | JointType::Continuous => JointKind::Revolute,
        JointType::Prismatic => JointKind::Prismatic,
        ref other => {
            return Err(ModelFileError::Unsupported(format!(
                "joint {:?}: {other:?} joints are not supported",
                joint.name
            )));
        }
    };
    let axis = vec3(&joint.axis.xyz);
    if !axis.is_finite() || axis.length() < 1e-6 {
        return Err(format!("joint {:?}: the axis is zero", joint.name).into());
    }
    let limits = if joint.joint_type == JointType::Continuous {
        (-std::f32::consts::PI, std::f32::consts::PI)
    } else {
        let (lo, hi) = (joint.limit.lower as f32, joint.limit.upper as f32);
        if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
            return Err(
                format!("joint {:?}: limits {lo}..{hi} are not a range", joint.name).into(),
            );
        }
        (lo, hi)
    };
    Ok(Some(BodyJoint {
        name: joint.name.clone(),
        kind,
        origin: Vec3::ZERO,
        axis: axis.normalize(),
        limits,
    }))
}

/// A geometry element as a closed mesh in its own frame.
fn geometry_mesh(geometry: &urdf_rs::Geometry, folder: &Path) -> Result<TriMesh, ModelFileError> {
    use urdf_rs::Geometry;
    let positive = |v: f64, what: &str| {
        (v.is_finite() && v > 0.0)
            .then_some(v as f32)
            .ok_or_else(|| format!("{what} {v} is not a positive length"))
    };
    Ok(match geometry {
        Geometry::Box { size } => {
            let half = Vec3::new(
                positive(size.0[0], "box size")?,
                positive(size.0[1], "box size")?,
                positive(size.0[2], "box size")?,
            ) / 2.0;
            TriMesh::cuboid(-half, half)
        }
        Geometry::Cylinder { radius, length } => {
            let h = positive(*length, "cylinder length")?;
            TriMesh::cylinder(
                Vec3::new(0.0, 0.0, -h / 2.0),
                positive(*radius, "cylinder radius")?,
                h,
                ROUND_SEGMENTS,
            )
        }
        Geometry::Capsule { radius, length } => {
            let r = positive(*radius, "capsule radius")?;
            let h = positive(*length, "capsule length")? / 2.0;
            TriMesh::capsule(r, h, ROUND_SEGMENTS)
        }
        Geometry::Sphere { radius } => TriMesh::ellipsoid(
            Vec3::splat(positive(*radius, "sphere radius")?),
            ROUND_SEGMENTS,
        ),
        Geometry::Mesh { filename, scale } => {
            let file = mesh_path(filename, folder)?;
            let mesh = read_mesh_file(&file).map_err(|e| {
                let problem = format!("{}: {e}", file.display());
                match e {
                    MeshFileError::UnsupportedFormat => ModelFileError::Unsupported(problem),
                    _ => ModelFileError::Malformed(problem),
                }
            })?;
            let scale = scale.as_ref().map_or(Vec3::ONE, vec3);
            mesh.transformed(&Affine3A::from_scale(scale))
        }
    })
}

/// A mesh file name of a URDF file that names no file this reader may read.
#[derive(Debug, thiserror::Error)]
enum MeshNameError {
    #[error(transparent)]
    OutsideFolder(#[from] crate::file_name::FileNameError),
    #[error("{0:?} names no file in the package")]
    NoFileInPackage(String),
    #[error(
        "{filename:?}: no folder {package:?} holding it around the URDF file (no ROS package \
         path is searched)"
    )]
    NoPackage { filename: String, package: String },
}

impl From<MeshNameError> for ModelFileError {
    fn from(e: MeshNameError) -> Self {
        Self::Malformed(e.to_string())
    }
}

/// Where a mesh `filename` of a URDF file in `folder` is.
fn mesh_path(filename: &str, folder: &Path) -> Result<PathBuf, MeshNameError> {
    // A package:// name is looked up in the folders around the file, as ROS would; any other
    // name must lie inside the file's own folder.
    if let Some(path) = filename.strip_prefix("file://") {
        return Ok(inside_folder(folder, Path::new(path))?);
    }
    let Some(rest) = filename.strip_prefix("package://") else {
        return Ok(inside_folder(folder, Path::new(filename))?);
    };
    let (package, relative) = rest
        .split_once('/')
        .ok_or_else(|| MeshNameError::NoFileInPackage(filename.to_string()))?;
    for dir in folder.ancestors() {
        for candidate in [dir.to_path_buf(), dir.join(package)] {
            if candidate.file_name().is_some_and(|n| n == package)
                && candidate.join(relative).is_file()
            {
                return Ok(candidate.join(relative));
            }
        }
    }
    Err(MeshNameError::NoPackage {
        filename: filename.to_string(),
        package: package.to_string(),
    })
}
