//! MJCF, MuJoCo's XML model format, read into a [`BodyTree`]: the articulated objects of LIBERO
//! (../shared/data/cad/libero) and of MuJoCo model collections.
//!
//! Read: `<include>` of other files (spliced in as MuJoCo does; a root `<mujocoinclude>` is an
//! include file, passed over by a folder import), `<compiler>` (angle units, Euler sequence, mesh and texture folders), `<default>`
//! classes with their nesting and `childclass`, mesh, material and texture assets, and the body
//! tree with body and geom poses (`pos` with `quat`, `axisangle`, `euler`, `xyaxes` or `zaxis`;
//! `fromto` for capsules and cylinders). Hinge joints become revolute and slide joints prismatic,
//! with their `pos`, `axis` and `range`; the range is taken even where `limited="false"` says
//! the simulator should not enforce it (LIBERO's fridge door), since it is the only statement of
//! how far the part moves. Free joints are the object's own freedom and are dropped.
//!
//! Geometry follows MuJoCo's semantics: a geom collides unless both its `contype` and
//! `conaffinity` are 0, and a colliding mesh geom collides as its convex hull. Mesh vertices are
//! used as the file has them, scaled by the asset's `scale`, then placed by the geom's pose.
//! Primitive geoms become closed meshes. Colours come from the visual geoms: the material's
//! `rgba` times its texture's mean colour, else the geom's `rgba`, weighted by area and opacity.
//!
//! Not read (an error says so where it changes the geometry): `<frame>`, inline
//! mesh vertices, ball joints, more than one joint in a body, height fields.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{Affine3A, EulerRot, Quat, Vec3};
use roxmltree::Node;

use crate::base::JointKind;
use crate::base::srgb::srgb_to_linear;
use crate::cad::import::body_tree::{Body, BodyJoint, BodyTree, ModelFileError, check_xml_depth};
use crate::cad::import::mesh_files::read_mesh_file;
use crate::cad::import::mjcf_include::{MAX_INCLUDED_BYTES, expanded_text};
use crate::cad::import::mjcf_xml::{at, elements, euler_order, numbers, parse_numbers, pose, vec3};
use crate::file_name::inside_folder;
use crate::geometry::TriMesh;

/// Facets around primitives (spheres, capsules, cylinders).
const ROUND_SEGMENTS: u32 = 16;

/// Reads the MJCF file at `path`. Errors name the element's line, not the file: the caller
/// names it.
pub fn read_mjcf(path: &Path) -> Result<BodyTree, ModelFileError> {
    let folder = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let mut budget = MAX_INCLUDED_BYTES;
    let text = expanded_text(path, folder, 0, &mut budget)?;
    let document = roxmltree::Document::parse(&text).map_err(|e| format!("not XML: {e}"))?;
    check_xml_depth(&document)?;
    let root = document.root_element();
    // Masses come from the class's density on import, but a negative one is a broken file.
    for node in root.descendants().filter(|n| n.is_element()) {
        if let Some(mass) = node.attribute("mass")
            && !mass
                .trim()
                .parse::<f64>()
                .is_ok_and(|m| m.is_finite() && m >= 0.0)
        {
            return Err(ModelFileError::Malformed(format!(
                "{}: mass {mass:?} is not a non-negative number",
                at(node)
            )));
        }
    }
    if root.tag_name().name() == "mujocoinclude" {
        return Err(ModelFileError::Unsupported(
            "an include file (<mujocoinclude>): it is read through the model that includes it"
                .into(),
        ));
    }
    if root.tag_name().name() != "mujoco" {
        return Err(ModelFileError::Malformed(format!(
            "the root element is <{}>, not <mujoco>",
            root.tag_name().name()
        )));
    }
    let mut reader = Reader::new(root, folder)?;
    let name = root
        .attribute("model")
        .map(str::to_owned)
        .or_else(|| path.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .unwrap_or_default();
    let worldbody = elements(root, "worldbody").next().ok_or("no <worldbody>")?;
    let mut tree = BodyTree {
        name,
        bodies: Vec::new(),
    };
    tree.bodies.push(Body {
        name: "world".into(),
        parent: None,
        parent_from_body: Affine3A::IDENTITY,
        joint: None,
        pieces: Vec::new(),
        visual_pieces: Vec::new(),
        visual_meshes: Vec::new(),
        colors: Vec::new(),
    });
    reader.read_body_contents(worldbody, 0, "main", &mut tree)?;
    // Models that give their visual geometry no colour (or have none) show their collision
    // geometry's.
    if tree.bodies.iter().all(|b| b.colors.is_empty()) {
        for (body, colors) in tree.bodies.iter_mut().zip(reader.collision_colors) {
            body.colors = colors;
        }
    }
    Ok(tree)
}

/// Attribute values by element kind (`geom`, `joint`, `mesh`, ...) of one default class.
type ClassDefaults = HashMap<String, HashMap<String, String>>;

struct MeshAsset {
    file: PathBuf,
    scale: Vec3,
    /// Read on first use.
    mesh: Option<TriMesh>,
}

struct Material {
    rgba: [f32; 4],
    texture: Option<String>,
}

struct Texture {
    file: Option<PathBuf>,
    /// The colour of a builtin texture without a file.
    rgb1: Vec3,
    /// The mean linear colour, computed on first use.
    mean: Option<Vec3>,
}

struct Reader {
    degrees: bool,
    euler: EulerRot,
    defaults: HashMap<String, ClassDefaults>,
    meshes: HashMap<String, MeshAsset>,
    materials: HashMap<String, Material>,
    textures: HashMap<String, Texture>,
    /// Per body, its collision geoms' colours (used when no visual geom has one).
    collision_colors: Vec<Vec<([f32; 3], f32)>>,
}

impl Reader {
    fn new(root: Node, folder: &Path) -> Result<Self, ModelFileError> {
        let mut degrees = true;
        let mut euler = EulerRot::XYZ;
        // Relative to `folder`; every file named is resolved inside it.
        let mut meshdir = PathBuf::new();
        let mut texturedir = PathBuf::new();
        for compiler in elements(root, "compiler") {
            if let Some(angle) = compiler.attribute("angle") {
                degrees = match angle {
                    "degree" => true,
                    "radian" => false,
                    other => {
                        return Err(ModelFileError::Malformed(format!(
                            "{}: angle {other:?}",
                            at(compiler)
                        )));
                    }
                };
            }
            if let Some(seq) = compiler.attribute("eulerseq") {
                euler = euler_order(seq).ok_or_else(|| {
                    ModelFileError::Unsupported(format!(
                        "{}: eulerseq {seq:?} is not supported",
                        at(compiler)
                    ))
                })?;
            }
            if let Some(dir) = compiler.attribute("assetdir") {
                meshdir = PathBuf::from(dir);
                texturedir = PathBuf::from(dir);
            }
            if let Some(dir) = compiler.attribute("meshdir") {
                meshdir = PathBuf::from(dir);
            }
            if let Some(dir) = compiler.attribute("texturedir") {
                texturedir = PathBuf::from(dir);
            }
        }
        let mut reader = Self {
            degrees,
            euler,
            defaults: HashMap::new(),
            meshes: HashMap::new(),
            materials: HashMap::new(),
            textures: HashMap::new(),
            collision_colors: Vec::new(),
        };
        reader
            .defaults
            .insert("main".into(), ClassDefaults::default());
        for default in elements(root, "default") {
            reader.read_default(default, "main")?;
        }
        for asset in elements(root, "asset") {
            reader.read_assets(asset, folder, &meshdir, &texturedir)?;
        }
        Ok(reader)
    }

    /// A `<default>` element: the top-level one is class `main`; nested ones inherit from their
    /// parent's resolved attributes.
    fn read_default(&mut self, node: Node, parent: &str) -> Result<(), ModelFileError> {
        let class = match node.attribute("class") {
            Some(c) => c.to_string(),
            None if parent == "main" => "main".to_string(),
            None => {
                return Err(ModelFileError::Malformed(format!(
                    "{}: a nested default without a class",
                    at(node)
                )));
            }
        };
        let mut resolved = self.defaults.get(parent).cloned().unwrap_or_default();
        for child in node.children().filter(|c| c.is_element()) {
            let kind = child.tag_name().name();
            if kind == "default" {
                continue;
            }
            let attributes = resolved.entry(kind.to_string()).or_default();
            for a in child.attributes() {
                attributes.insert(a.name().to_string(), a.value().to_string());
            }
        }
        self.defaults.insert(class.clone(), resolved);
        for nested in elements(node, "default") {
            self.read_default(nested, &class)?;
        }
        Ok(())
    }

    fn read_assets(
        &mut self,
        asset: Node,
        folder: &Path,
        meshdir: &Path,
        texturedir: &Path,
    ) -> Result<(), ModelFileError> {
        let inside = |node: Node, dir: &Path, file: &str| {
            inside_folder(folder, &dir.join(file))
                .map_err(|e| ModelFileError::Malformed(format!("{}: {e}", at(node))))
        };
        for node in asset.children().filter(|c| c.is_element()) {
            match node.tag_name().name() {
                "mesh" => {
                    let class = node.attribute("class").unwrap_or("main");
                    let Some(file) = node.attribute("file") else {
                        return Err(ModelFileError::Unsupported(format!(
                            "{}: only meshes from files are supported (no inline vertices)",
                            at(node)
                        )));
                    };
                    let name = node
                        .attribute("name")
                        .map(str::to_owned)
                        .unwrap_or_else(|| file_stem(file));
                    let scale = match self.attribute(node, "mesh", class, "scale") {
                        Some(s) => vec3(node, "scale", &s)?,
                        None => Vec3::ONE,
                    };
                    self.meshes.insert(
                        name,
                        MeshAsset {
                            file: inside(node, meshdir, file)?,
                            scale,
                            mesh: None,
                        },
                    );
                }
                "material" => {
                    let class = node.attribute("class").unwrap_or("main");
                    let name = node
                        .attribute("name")
                        .ok_or_else(|| format!("{}: a material without a name", at(node)))?;
                    let rgba = match self.attribute(node, "material", class, "rgba") {
                        Some(s) => numbers::<4>(node, "rgba", &s)?,
                        None => [1.0; 4],
                    };
                    let texture = self.attribute(node, "material", class, "texture");
                    self.materials
                        .insert(name.to_string(), Material { rgba, texture });
                }
                "texture" => {
                    let file = node.attribute("file");
                    let Some(name) = node
                        .attribute("name")
                        .map(str::to_owned)
                        .or_else(|| file.map(file_stem))
                    else {
                        continue; // the skybox: nothing refers to it by name
                    };
                    let rgb1 = match node.attribute("rgb1") {
                        Some(s) => vec3(node, "rgb1", s)?,
                        None => Vec3::splat(0.8),
                    };
                    self.textures.insert(
                        name,
                        Texture {
                            file: file.map(|f| inside(node, texturedir, f)).transpose()?,
                            rgb1,
                            mean: None,
                        },
                    );
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// The element's own attribute, else its class's default for elements of `kind`.
    fn attribute(&self, node: Node, kind: &str, class: &str, name: &str) -> Option<String> {
        node.attribute(name).map(str::to_owned).or_else(|| {
            self.defaults
                .get(class)
                .and_then(|d| d.get(kind))
                .and_then(|a| a.get(name))
                .cloned()
        })
    }

    /// The geoms of `node` into body `body`, and its child bodies after it.
    fn read_body_contents(
        &mut self,
        node: Node,
        body: usize,
        childclass: &str,
        tree: &mut BodyTree,
    ) -> Result<(), ModelFileError> {
        if let Some(frame) = elements(node, "frame").next() {
            return Err(ModelFileError::Unsupported(format!(
                "{}: <frame> is not supported",
                at(frame)
            )));
        }
        while self.collision_colors.len() <= body {
            self.collision_colors.push(Vec::new());
        }
        for geom in elements(node, "geom") {
            self.read_geom(geom, body, childclass, tree)?;
        }
        for child in elements(node, "body") {
            let class = child.attribute("childclass").unwrap_or(childclass);
            let joint = self.body_joint(child, class)?;
            tree.bodies.push(Body {
                name: child.attribute("name").unwrap_or_default().to_string(),
                parent: Some(body),
                parent_from_body: pose(child, self.degrees, self.euler)?,
                joint,
                pieces: Vec::new(),
                visual_pieces: Vec::new(),
                visual_meshes: Vec::new(),
                colors: Vec::new(),
            });
            let index = tree.bodies.len() - 1;
            self.read_body_contents(child, index, class, tree)?;
        }
        Ok(())
    }

    /// The body's hinge or slide joint, if it has one.
    fn body_joint(
        &self,
        body: Node,
        childclass: &str,
    ) -> Result<Option<BodyJoint>, ModelFileError> {
        let mut joints = Vec::new();
        for node in elements(body, "joint") {
            let class = node.attribute("class").unwrap_or(childclass);
            let get = |name: &str| self.attribute(node, "joint", class, name);
            let kind = match get("type").as_deref().unwrap_or("hinge") {
                "hinge" => JointKind::Revolute,
                "slide" => JointKind::Prismatic,
                "free" => continue,
                other => {
                    return Err(ModelFileError::Unsupported(format!(
                        "{}: {other} joints are not supported",
                        at(node)
                    )));
                }
            };
            let origin = match get("pos") {
                Some(s) => vec3(node, "pos", &s)?,
                None => Vec3::ZERO,
            };
            let axis = match get("axis") {
                Some(s) => vec3(node, "axis", &s)?,
                None => Vec3::Z,
            };
            if axis.length() < 1e-6 {
                return Err(ModelFileError::Malformed(format!(
                    "{}: the axis is zero",
                    at(node)
                )));
            }
            let limits = match (get("range"), kind) {
                (Some(s), _) => {
                    let [lo, hi] = numbers::<2>(node, "range", &s)?;
                    let unit = if kind == JointKind::Revolute && self.degrees {
                        std::f32::consts::PI / 180.0
                    } else {
                        1.0
                    };
                    if lo > hi {
                        return Err(ModelFileError::Malformed(format!(
                            "{}: range {lo} > {hi}",
                            at(node)
                        )));
                    }
                    (lo * unit, hi * unit)
                }
                (None, JointKind::Revolute) => (-std::f32::consts::PI, std::f32::consts::PI),
                (None, _) => {
                    return Err(ModelFileError::Malformed(format!(
                        "{}: a slide joint without a range: how far it moves is unknown",
                        at(node)
                    )));
                }
            };
            joints.push(BodyJoint {
                name: node.attribute("name").unwrap_or_default().to_string(),
                kind,
                origin,
                axis: axis.normalize(),
                limits,
            });
        }
        match joints.len() {
            0 | 1 => Ok(joints.pop()),
            n => Err(ModelFileError::Unsupported(format!(
                "{}: {n} joints in one body; one hinge or slide per body is supported",
                at(body)
            ))),
        }
    }

    fn read_geom(
        &mut self,
        node: Node,
        body: usize,
        childclass: &str,
        tree: &mut BodyTree,
    ) -> Result<(), ModelFileError> {
        let class = node.attribute("class").unwrap_or(childclass).to_string();
        let get = |name: &str| self.attribute(node, "geom", &class, name);
        let kind = get("type").unwrap_or_else(|| "sphere".into());
        let size: Vec<f32> = match get("size") {
            Some(s) => parse_numbers(node, "size", &s)?,
            None => Vec::new(),
        };
        let size_at = |i: usize| {
            size.get(i)
                .copied()
                .filter(|v| *v > 0.0)
                .ok_or_else(|| format!("{}: {kind} needs a positive size {}", at(node), i + 1))
        };
        let fromto = match get("fromto") {
            Some(s) => Some(numbers::<6>(node, "fromto", &s)?),
            None => None,
        };
        let collides =
            get("contype").as_deref() != Some("0") || get("conaffinity").as_deref() != Some("0");
        let rgba = match get("rgba") {
            Some(s) => Some(numbers::<4>(node, "rgba", &s)?),
            None => None,
        };
        let material = get("material");
        // The geom's own frame: `fromto` puts z along the segment, centred on it.
        let (body_from_geom, half_length) = match fromto {
            Some(f) if kind == "capsule" || kind == "cylinder" => {
                let (a, b) = (Vec3::new(f[0], f[1], f[2]), Vec3::new(f[3], f[4], f[5]));
                let axis = b - a;
                if axis.length() < 1e-9 {
                    return Err(ModelFileError::Malformed(format!(
                        "{}: fromto has zero length",
                        at(node)
                    )));
                }
                let rotation = Quat::from_rotation_arc(Vec3::Z, axis.normalize());
                (
                    Affine3A::from_rotation_translation(rotation, (a + b) / 2.0),
                    Some(axis.length() / 2.0),
                )
            }
            _ => (pose(node, self.degrees, self.euler)?, None),
        };
        let local = match kind.as_str() {
            "box" => {
                let h = Vec3::new(size_at(0)?, size_at(1)?, size_at(2)?);
                TriMesh::cuboid(-h, h)
            }
            "sphere" => TriMesh::ellipsoid(Vec3::splat(size_at(0)?), ROUND_SEGMENTS),
            "ellipsoid" => TriMesh::ellipsoid(
                Vec3::new(size_at(0)?, size_at(1)?, size_at(2)?),
                ROUND_SEGMENTS,
            ),
            "capsule" => TriMesh::capsule(
                size_at(0)?,
                half_length.map_or_else(|| size_at(1), Ok)?,
                ROUND_SEGMENTS,
            ),
            "cylinder" => {
                let h = half_length.map_or_else(|| size_at(1), Ok)?;
                TriMesh::cylinder(
                    Vec3::new(0.0, 0.0, -h),
                    size_at(0)?,
                    2.0 * h,
                    ROUND_SEGMENTS,
                )
            }
            "mesh" => {
                let name = get("mesh")
                    .ok_or_else(|| format!("{}: a mesh geom without a mesh", at(node)))?;
                self.mesh(&name)
                    .map_err(|e| format!("{}: mesh {name:?}: {e}", at(node)))?
            }
            // Planes are infinite and height fields terrain: neither is part of an object.
            "plane" | "hfield" => return Ok(()),
            other => {
                return Err(ModelFileError::Unsupported(format!(
                    "{}: geom type {other:?} is not supported",
                    at(node)
                )));
            }
        };
        let mesh = local.transformed(&body_from_geom);
        let color = self
            .geom_color(material.as_deref(), rgba)
            .map_err(|e| format!("{}: {e}", at(node)))?;
        let weight = mesh.area() * color[3];
        let color = ([color[0], color[1], color[2]], weight);
        let target = &mut tree.bodies[body];
        // Mesh geoms collide as their hull; the hull of a primitive is it, cleaned of the
        // degenerate triangles at a sphere's poles.
        let hull = mesh.convex_hull();
        if collides {
            target.pieces.extend(hull);
            self.collision_colors[body].push(color);
        } else {
            target.visual_pieces.extend(hull);
            target.visual_meshes.push(mesh);
            target.colors.push(color);
        }
        Ok(())
    }

    /// The mesh asset `name` (scaled), read on first use.
    fn mesh(&mut self, name: &str) -> Result<TriMesh, AssetError> {
        let asset = self.meshes.get_mut(name).ok_or(AssetError::NoMesh)?;
        if asset.mesh.is_none() {
            let mesh = read_mesh_file(&asset.file).map_err(|source| AssetError::MeshFile {
                file: asset.file.clone(),
                source,
            })?;
            asset.mesh = Some(mesh.transformed(&Affine3A::from_scale(asset.scale)));
        }
        Ok(asset.mesh.clone().unwrap_or_default())
    }

    /// RGBA of a geom: its material's colour times the material's texture's mean colour, else
    /// its own `rgba`, else MuJoCo's default grey.
    fn geom_color(
        &mut self,
        material: Option<&str>,
        rgba: Option<[f32; 4]>,
    ) -> Result<[f32; 4], AssetError> {
        let Some(name) = material else {
            return Ok(rgba.unwrap_or([0.5, 0.5, 0.5, 1.0]));
        };
        let material = self
            .materials
            .get(name)
            .ok_or_else(|| AssetError::NoMaterial(name.to_string()))?;
        let mut color = material.rgba;
        if let Some(texture_name) = material.texture.clone() {
            let texture = self
                .textures
                .get_mut(&texture_name)
                .ok_or_else(|| AssetError::NoTexture(texture_name.clone()))?;
            let mean = match (texture.mean, &texture.file) {
                (Some(mean), _) => mean,
                (None, Some(file)) => {
                    let mean = mean_linear_color(file)?;
                    texture.mean = Some(mean);
                    mean
                }
                (None, None) => texture.rgb1,
            };
            for (c, m) in color.iter_mut().zip(mean.to_array()) {
                *c *= m;
            }
        }
        Ok(color)
    }
}

/// An asset a geom names that is missing or unreadable.
#[derive(Debug, thiserror::Error)]
enum AssetError {
    #[error("no mesh asset of that name")]
    NoMesh,
    #[error("{}: {source}", file.display())]
    MeshFile {
        file: PathBuf,
        source: crate::cad::import::mesh_files::MeshFileError,
    },
    #[error("no material {0:?}")]
    NoMaterial(String),
    #[error("no texture {0:?}")]
    NoTexture(String),
    #[error("texture {}: {source}", file.display())]
    Texture {
        file: PathBuf,
        source: image::ImageError,
    },
}

/// The mean colour of an image file in linear RGB (its pixels are sRGB).
fn mean_linear_color(file: &Path) -> Result<Vec3, AssetError> {
    let image = image::open(file)
        .map_err(|source| AssetError::Texture {
            file: file.to_path_buf(),
            source,
        })?
        .to_rgb8();
    let mut sum = glam::DVec3::ZERO;
    for p in image.pixels() {
        sum += glam::DVec3::new(
            f64::from(srgb_to_linear(p[0])),
            f64::from(srgb_to_linear(p[1])),
            f64::from(srgb_to_linear(p[2])),
        );
    }
    let n = (image.width() as f64 * image.height() as f64).max(1.0);
    Ok((sum / n).as_vec3())
}

fn file_stem(file: &str) -> String {
    Path::new(file)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}
