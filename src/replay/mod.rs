//! A reconstruction as it happened, for playback (`iscene view OUT --replay`): the camera's
//! trajectory, each panoptic segment's mesh with its triangles in the order the sensor first saw
//! them, and the contact graph's nodes with the frame at which each has been seen enough to
//! stand in the graph. Built from a reconstruction's output folder and the sequence it read
//! (report.json names it); bevy-free, so it is tested without a renderer.

pub mod first_seen;
pub mod vertex_colours;

use std::path::{Path, PathBuf};

use glam::Affine3A;

use crate::error::{InputError, IsceneError};
use crate::geometry::{GravityBox, Pinhole, Plane, TriMesh};
use crate::graph::{ContactGraph, GraphEdge};
use crate::io::Sequence;
use crate::panoptic::panoptic_dir::{aligned_from_world_in, read_index, read_segment_meshes};

pub use first_seen::{first_seen, seen_in_frame};
pub use vertex_colours::vertex_colours;

/// A node appears once this share of its segment's triangles has been seen.
const NODE_SEEN_SHARE: f32 = 0.5;
/// A surface point counts as seen within this many voxels of the measured depth.
const SEEN_TOLERANCE_VOXELS: f32 = 3.0;

/// One panoptic segment, its triangles sorted by the frame that revealed them.
#[derive(Clone, Debug)]
pub struct ReplaySegment {
    pub id: String,
    pub class: String,
    /// The panoptic instance (its colour in the viewer).
    pub instance: u32,
    /// In the contact graph's aligned frame; triangle `i` is revealed at `revealed_at[i]`.
    pub mesh: TriMesh,
    /// Ascending.
    pub revealed_at: Vec<u32>,
}

impl ReplaySegment {
    /// How many of the triangles (a prefix) have been revealed by frame `frame`.
    pub fn revealed_by(&self, frame: u32) -> usize {
        self.revealed_at.partition_point(|&f| f <= frame)
    }
}

/// A contact-graph node and the frame from which the replay shows it.
#[derive(Clone, Debug)]
pub struct ReplayNode {
    pub id: String,
    pub class: String,
    pub gravity_box: GravityBox,
    pub planes: Vec<Plane>,
    /// Index of its support parent in the replay's nodes.
    pub parent: Option<usize>,
    pub appears_at: u32,
}

/// Everything the replay shows, frame by frame.
#[derive(Clone, Debug)]
pub struct Replay {
    /// The reconstruction's folder.
    pub dir: PathBuf,
    pub camera: Pinhole,
    /// Per frame, the camera in the aligned frame (z up, floor at 0).
    pub aligned_from_camera: Vec<Affine3A>,
    pub segments: Vec<ReplaySegment>,
    pub nodes: Vec<ReplayNode>,
    /// Proximal pairs, as node indices.
    pub proximal: Vec<(usize, usize)>,
}

impl Replay {
    pub fn frames(&self) -> u32 {
        self.aligned_from_camera.len() as u32
    }

    /// The support edges shown at `frame`: (parent, child) node indices, both ends appeared.
    pub fn support_edges_at(&self, frame: u32) -> Vec<(usize, usize)> {
        self.nodes
            .iter()
            .enumerate()
            .filter_map(|(child, n)| Some((n.parent?, child)))
            .filter(|&(p, c)| {
                self.nodes[p].appears_at <= frame && self.nodes[c].appears_at <= frame
            })
            .collect()
    }
}

/// What the replay needs from report.json: the sequence read, the frames used and the aligned
/// frame.
pub(crate) struct ReportFacts {
    pub sequence: PathBuf,
    pub frames: Option<(usize, Option<usize>, usize)>,
    pub aligned_from_world: Affine3A,
}

pub(crate) fn read_report(path: &Path) -> Result<ReportFacts, InputError> {
    let text = std::fs::read_to_string(path).map_err(|e| InputError::io(path, &e))?;
    let report: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| InputError::invalid(path, format!("not JSON: {e}")))?;
    let sequence = report["input"]
        .as_str()
        .map(PathBuf::from)
        .ok_or_else(|| InputError::invalid(path, "no \"input\": which sequence was read?"))?;
    let frames = match &report["frame_selection"] {
        serde_json::Value::Null => None,
        value => Some(
            serde_json::from_value(value.clone())
                .map_err(|e| InputError::invalid(path, format!("frame_selection: {e}")))?,
        ),
    };
    let aligned_from_world = aligned_from_world_in(&report, path)?;
    Ok(ReportFacts {
        sequence,
        frames,
        aligned_from_world,
    })
}

/// The sequence the reconstruction in `dir` read, with the frames it used (report.json says
/// which). report.json holds the path as given; a rendered sequence also sits beside the folder.
pub(crate) fn reconstruction_sequence(
    dir: &Path,
    facts: &ReportFacts,
) -> Result<Sequence, IsceneError> {
    let beside = dir
        .parent()
        .zip(facts.sequence.file_name())
        .map(|(parent, name)| parent.join(name));
    let sequence_dir = match beside {
        Some(b) if !facts.sequence.exists() && b.exists() => b,
        _ => facts.sequence.clone(),
    };
    let mut sequence = Sequence::open(&sequence_dir)?;
    if let Some((start, end, step)) = facts.frames {
        sequence.select(start, end, step);
    }
    if sequence.frames.is_empty() {
        return Err(InputError::invalid(&sequence_dir, "no frames to replay").into());
    }
    Ok(sequence)
}

/// The replay of the reconstruction in `dir` (report.json, contact_graph.json, panoptic/),
/// reading the depth frames of the sequence it was made from.
pub fn load_replay(dir: &Path) -> Result<Replay, IsceneError> {
    let facts = read_report(&dir.join("report.json"))?;
    let graph = ContactGraph::load(&dir.join("contact_graph.json"))?;
    let index = read_index(&dir.join("panoptic"))?;
    let sequence = reconstruction_sequence(dir, &facts)?;
    let frames = sequence.frames.len() as u32;

    // Every segment's mesh, in the sequence's world frame, and when each vertex was first seen.
    let meshes = read_segment_meshes(&dir.join("panoptic"), &index)?;
    let vertices: Vec<glam::Vec3> = meshes.iter().flat_map(|m| m.positions.clone()).collect();
    let seen = first_seen(
        &vertices,
        &sequence,
        SEEN_TOLERANCE_VOXELS * index.voxel_size,
    )?;
    let mut offset = 0;
    let mut segments = Vec::with_capacity(meshes.len());
    for (e, mesh) in index.entities.iter().zip(meshes) {
        let vertex_seen = &seen[offset..offset + mesh.positions.len()];
        offset += mesh.positions.len();
        segments.push(reveal_order(
            e.id.clone(),
            e.class.clone(),
            e.instance,
            mesh,
            vertex_seen,
            frames,
            &facts.aligned_from_world,
        ));
    }

    let nodes = replay_nodes(&graph, &segments, frames);
    let at = |id: &str| nodes.iter().position(|n| n.id == id);
    let proximal = graph
        .edges
        .iter()
        .filter_map(|e| match e {
            GraphEdge::Proximal { a, b } => Some((at(a)?, at(b)?)),
            GraphEdge::Support { .. } => None,
        })
        .collect();
    Ok(Replay {
        dir: dir.to_path_buf(),
        camera: sequence.camera,
        aligned_from_camera: sequence
            .frames
            .iter()
            .map(|f| facts.aligned_from_world * f.world_from_camera)
            .collect(),
        segments,
        nodes,
        proximal,
    })
}

/// The segment with its mesh in the aligned frame and its triangles sorted by reveal: a
/// triangle shows once its three corners have been seen; one never seen shows at the last frame.
fn reveal_order(
    id: String,
    class: String,
    instance: u32,
    mesh: TriMesh,
    vertex_seen: &[Option<u32>],
    frames: u32,
    aligned_from_world: &Affine3A,
) -> ReplaySegment {
    let last = frames.saturating_sub(1);
    let mut triangles: Vec<([u32; 3], u32)> = mesh
        .triangles
        .iter()
        .map(|t| {
            let at = t
                .iter()
                .map(|&v| vertex_seen[v as usize].unwrap_or(last))
                .max()
                .unwrap_or(last);
            (*t, at)
        })
        .collect();
    // Stable: triangles revealed together keep the mesh's own order.
    triangles.sort_by_key(|&(_, at)| at);
    let mesh = TriMesh {
        positions: mesh.transformed(aligned_from_world).positions,
        triangles: triangles.iter().map(|(t, _)| *t).collect(),
    };
    ReplaySegment {
        id,
        class,
        instance,
        mesh,
        revealed_at: triangles.iter().map(|(_, at)| *at).collect(),
    }
}

/// The graph's nodes, each appearing once half its segment has been seen (a node without a
/// segment appears with its parent, or at the end).
fn replay_nodes(graph: &ContactGraph, segments: &[ReplaySegment], frames: u32) -> Vec<ReplayNode> {
    let last = frames.saturating_sub(1);
    let own_time = |id: &str| {
        let s = segments.iter().find(|s| s.id == id)?;
        let k = ((s.revealed_at.len() as f32 * NODE_SEEN_SHARE).ceil() as usize).max(1);
        s.revealed_at.get(k - 1).copied()
    };
    let mut nodes: Vec<ReplayNode> = graph
        .nodes
        .iter()
        .map(|n| ReplayNode {
            id: n.id.clone(),
            class: n.class.clone(),
            gravity_box: GravityBox::from(&n.bbox),
            planes: n.planes.iter().map(|p| Plane::from_array(*p)).collect(),
            parent: None,
            appears_at: own_time(&n.id).unwrap_or(last),
        })
        .collect();
    for i in 0..nodes.len() {
        let parent = graph
            .parent_of(&nodes[i].id)
            .and_then(|p| nodes.iter().position(|n| n.id == p));
        nodes[i].parent = parent;
        if own_time(&nodes[i].id).is_none()
            && let Some(p) = parent
        {
            nodes[i].appears_at = nodes[p].appears_at;
        }
    }
    nodes
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    /// Two triangles over the unit square, ordered as `reveal_order` got them for `seen`.
    fn square_revealed(seen: &[Option<u32>], aligned_from_world: &Affine3A) -> ReplaySegment {
        let mesh = TriMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ONE],
            triangles: vec![[0, 1, 2], [1, 3, 2]],
        };
        reveal_order(
            "a".into(),
            "box".into(),
            1,
            mesh,
            seen,
            10,
            aligned_from_world,
        )
    }

    #[test]
    fn triangles_are_revealed_in_the_order_their_corners_were_seen() {
        // Vertex 3 is seen at frame 1, the others at frame 4.
        let up = Affine3A::from_translation(Vec3::Z);
        let s = square_revealed(&[Some(4), Some(4), Some(4), Some(1)], &up);
        assert_eq!(s.revealed_at, [4, 4]);
        assert_eq!(s.mesh.positions[0], Vec3::Z);
        assert_eq!((s.revealed_by(3), s.revealed_by(4)), (0, 2));
        // A never-seen corner waits for the last frame (9 of 10).
        let s = square_revealed(&[Some(6), None, Some(0), Some(2)], &Affine3A::IDENTITY);
        assert_eq!(s.revealed_at, [9, 9]);
        // Each triangle waits for its latest corner, and the mesh is sorted by reveal.
        let s = square_revealed(&[Some(6), Some(0), Some(0), Some(2)], &Affine3A::IDENTITY);
        assert_eq!(s.revealed_at, [2, 6]);
        assert_eq!(s.mesh.triangles, [[1, 3, 2], [0, 1, 2]]);
    }

    #[test]
    fn a_node_appears_when_half_its_segment_is_seen_and_edges_when_both_ends_are() {
        let node = |id: &str, class: &str| crate::graph::GraphNode {
            id: id.into(),
            class: class.into(),
            kind: crate::classes::EntityKind::Rigid,
            bbox: GravityBox {
                center: Vec3::ZERO,
                yaw: 0.0,
                size: Vec3::ONE,
            }
            .into(),
            planes: Vec::new(),
            cad: None,
            joints: Default::default(),
            parts: Vec::new(),
        };
        let graph = ContactGraph {
            nodes: vec![
                node("floor", "floor"),
                node("table_1", "table"),
                node("cup_1", "cup"),
            ],
            edges: vec![
                GraphEdge::Support {
                    parent: "floor".into(),
                    child: "table_1".into(),
                },
                GraphEdge::Support {
                    parent: "table_1".into(),
                    child: "cup_1".into(),
                },
            ],
        };
        let segment = |id: &str, revealed_at: Vec<u32>| ReplaySegment {
            id: id.into(),
            class: String::new(),
            instance: 0,
            mesh: TriMesh::default(),
            revealed_at,
        };
        // The cup has no segment: it comes with its table.
        let segments = [
            segment("floor", vec![0, 1, 2, 3]),
            segment("table_1", vec![2, 5, 7, 8]),
        ];
        let nodes = replay_nodes(&graph, &segments, 12);
        let at: Vec<u32> = nodes.iter().map(|n| n.appears_at).collect();
        assert_eq!(at, [1, 5, 5]);
        assert_eq!(nodes[2].parent, Some(1));
        let replay = Replay {
            dir: PathBuf::new(),
            camera: Pinhole::KINECT,
            aligned_from_camera: vec![Affine3A::IDENTITY; 12],
            segments: Vec::new(),
            nodes,
            proximal: Vec::new(),
        };
        assert_eq!(replay.support_edges_at(4), Vec::<(usize, usize)>::new());
        assert_eq!(replay.support_edges_at(5), [(0, 1), (1, 2)]);
    }
}
