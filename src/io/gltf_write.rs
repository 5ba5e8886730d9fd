//! Writes a node tree of coloured triangle meshes as binary glTF 2.0 (.glb).

use std::collections::BTreeMap;

use glam::{Quat, Vec3};
use gltf::json;
use json::validation::Checked::Valid;
use json::validation::USize64;

use crate::geometry::TriMesh;

/// One node: a local pose relative to its parent, an optional mesh, extras and children.
#[derive(Clone, Debug)]
pub struct GltfNode {
    pub name: String,
    pub translation: Vec3,
    pub rotation: Quat,
    /// Geometry in the node's frame with its linear RGB base colour.
    pub mesh: Option<(TriMesh, [f32; 3])>,
    /// Application data, stored as the node's `extras` (joint axes and limits, ids).
    pub extras: Option<serde_json::Value>,
    pub children: Vec<GltfNode>,
}

impl GltfNode {
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            translation: Vec3::ZERO,
            rotation: Quat::IDENTITY,
            mesh: None,
            extras: None,
            children: Vec::new(),
        }
    }
}

/// Hangs each node under its parent (`parent_of(i) < i` for every `i > 0`) and returns node 0
/// with the whole tree below it; `None` for no nodes.
pub fn nest(mut nodes: Vec<GltfNode>, parent_of: impl Fn(usize) -> usize) -> Option<GltfNode> {
    // Children come after their parents: attach from the back so indices stay valid.
    for i in (1..nodes.len()).rev() {
        let node = nodes.remove(i);
        nodes[parent_of(i)].children.insert(0, node);
    }
    nodes.pop()
}

/// Why a node tree could not be written as a .glb.
#[derive(Debug, thiserror::Error)]
pub enum GlbError {
    #[error("no nodes to write")]
    Empty,
    #[error("glTF JSON: {0}")]
    Json(#[from] serde_json::Error),
    #[error("GLB container: {0}")]
    Container(#[from] gltf::Error),
}

/// Serialises `root` as a .glb. glTF is y up: the scene's z-up content is wrapped in a node named
/// `up_axis_node` that turns +z into +y, so any viewer shows it upright.
pub fn glb_bytes(root: &GltfNode, up_axis_node: &str) -> Result<Vec<u8>, GlbError> {
    let mut doc = json::Root::default();
    doc.asset.generator = Some("iscene".into());
    let mut bin: Vec<u8> = Vec::new();
    let buffer = doc.push(json::Buffer {
        byte_length: USize64(0),
        extensions: None,
        extras: Default::default(),
        name: None,
        uri: None,
    });
    let content = push_node(&mut doc, &mut bin, buffer, root)?;
    let wrapper = doc.push(json::Node {
        name: Some(up_axis_node.into()),
        rotation: Some(json::scene::UnitQuaternion(quat_array(
            Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2),
        ))),
        children: Some(vec![content]),
        ..Default::default()
    });
    let scene = doc.push(json::Scene {
        extensions: None,
        extras: Default::default(),
        name: None,
        nodes: vec![wrapper],
    });
    doc.scene = Some(scene);
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    if let Some(b) = doc.buffers.first_mut() {
        b.byte_length = USize64::from(bin.len());
    }
    let json_string = json::serialize::to_string(&doc)?;
    let length = (12 + 8 + json_string.len().next_multiple_of(4) + 8 + bin.len()) as u32;
    let glb = gltf::binary::Glb {
        header: gltf::binary::Header {
            magic: *b"glTF",
            version: 2,
            length,
        },
        json: std::borrow::Cow::Owned(json_string.into_bytes()),
        bin: Some(std::borrow::Cow::Owned(bin)),
    };
    Ok(glb.to_vec()?)
}

fn quat_array(q: Quat) -> [f32; 4] {
    let q = q.normalize();
    [q.x, q.y, q.z, q.w]
}

fn push_node(
    doc: &mut json::Root,
    bin: &mut Vec<u8>,
    buffer: json::Index<json::Buffer>,
    node: &GltfNode,
) -> Result<json::Index<json::Node>, GlbError> {
    let mesh = match &node.mesh {
        Some((m, color)) if !m.is_empty() => {
            Some(push_mesh(doc, bin, buffer, &node.name, m, *color))
        }
        _ => None,
    };
    let children = node
        .children
        .iter()
        .map(|c| push_node(doc, bin, buffer, c))
        .collect::<Result<Vec<_>, _>>()?;
    let extras = match &node.extras {
        Some(v) => Some(serde_json::value::to_raw_value(v)?),
        None => None,
    };
    let rotation = (node.rotation != Quat::IDENTITY)
        .then(|| json::scene::UnitQuaternion(quat_array(node.rotation)));
    let translation = (node.translation != Vec3::ZERO).then(|| node.translation.to_array());
    Ok(doc.push(json::Node {
        name: Some(node.name.clone()),
        mesh,
        rotation,
        translation,
        extras,
        children: (!children.is_empty()).then_some(children),
        ..Default::default()
    }))
}

fn push_view(
    doc: &mut json::Root,
    bin: &mut Vec<u8>,
    buffer: json::Index<json::Buffer>,
    bytes: &[u8],
    target: json::buffer::Target,
) -> json::Index<json::buffer::View> {
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let offset = bin.len();
    bin.extend_from_slice(bytes);
    doc.push(json::buffer::View {
        buffer,
        byte_length: USize64::from(bytes.len()),
        byte_offset: Some(USize64::from(offset)),
        byte_stride: None,
        extensions: None,
        extras: Default::default(),
        name: None,
        target: Some(Valid(target)),
    })
}

fn push_mesh(
    doc: &mut json::Root,
    bin: &mut Vec<u8>,
    buffer: json::Index<json::Buffer>,
    name: &str,
    mesh: &TriMesh,
    color: [f32; 3],
) -> json::Index<json::Mesh> {
    let (lo, hi) = mesh.bounds().unwrap_or((Vec3::ZERO, Vec3::ZERO));
    let positions: Vec<u8> = mesh
        .positions
        .iter()
        .flat_map(|p| p.to_array())
        .flat_map(f32::to_le_bytes)
        .collect();
    let indices: Vec<u8> = mesh
        .triangles
        .iter()
        .flatten()
        .flat_map(|i| i.to_le_bytes())
        .collect();
    let position_view = push_view(
        doc,
        bin,
        buffer,
        &positions,
        json::buffer::Target::ArrayBuffer,
    );
    let index_view = push_view(
        doc,
        bin,
        buffer,
        &indices,
        json::buffer::Target::ElementArrayBuffer,
    );
    let accessor = |view,
                    count: usize,
                    component,
                    type_,
                    min: Option<json::Value>,
                    max: Option<json::Value>| json::Accessor {
        buffer_view: Some(view),
        byte_offset: Some(USize64(0)),
        count: USize64::from(count),
        component_type: Valid(json::accessor::GenericComponentType(component)),
        extensions: None,
        extras: Default::default(),
        type_: Valid(type_),
        min,
        max,
        name: None,
        normalized: false,
        sparse: None,
    };
    let position_accessor = doc.push(accessor(
        position_view,
        mesh.positions.len(),
        json::accessor::ComponentType::F32,
        json::accessor::Type::Vec3,
        Some(json::Value::from(lo.to_array().to_vec())),
        Some(json::Value::from(hi.to_array().to_vec())),
    ));
    let index_accessor = doc.push(accessor(
        index_view,
        mesh.triangles.len() * 3,
        json::accessor::ComponentType::U32,
        json::accessor::Type::Scalar,
        None,
        None,
    ));
    let material = doc.push(json::Material {
        name: Some(format!("{name}_material")),
        pbr_metallic_roughness: json::material::PbrMetallicRoughness {
            base_color_factor: json::material::PbrBaseColorFactor([
                color[0], color[1], color[2], 1.0,
            ]),
            metallic_factor: json::material::StrengthFactor(0.0),
            roughness_factor: json::material::StrengthFactor(0.8),
            ..Default::default()
        },
        ..Default::default()
    });
    let primitive = json::mesh::Primitive {
        attributes: BTreeMap::from([(Valid(json::mesh::Semantic::Positions), position_accessor)]),
        extensions: None,
        extras: Default::default(),
        indices: Some(index_accessor),
        material: Some(material),
        mode: Valid(json::mesh::Mode::Triangles),
        targets: None,
    };
    doc.push(json::Mesh {
        extensions: None,
        extras: Default::default(),
        name: Some(name.into()),
        primitives: vec![primitive],
        weights: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glb_round_trips_through_the_gltf_reader() {
        let mut root = GltfNode::new("table_1");
        root.mesh = Some((TriMesh::cuboid(Vec3::ZERO, Vec3::ONE), [0.5, 0.4, 0.3]));
        let mut child = GltfNode::new("cup_1");
        child.translation = Vec3::new(0.0, 0.0, 1.0);
        child.mesh = Some((
            TriMesh::cylinder(Vec3::ZERO, 0.04, 0.1, 12),
            [1.0, 1.0, 1.0],
        ));
        root.children.push(child);
        let bytes = glb_bytes(&root, "z_up").expect("glb");
        let gltf = gltf::Gltf::from_slice(&bytes).expect("parses");
        let names: Vec<_> = gltf
            .nodes()
            .filter_map(|n| n.name().map(str::to_owned))
            .collect();
        assert_eq!(names.len(), 3);
        for expected in ["z_up", "table_1", "cup_1"] {
            assert!(
                names.iter().any(|n| n == expected),
                "{expected} in {names:?}"
            );
        }
        assert_eq!(bytes.len() % 4, 0);
    }
}
