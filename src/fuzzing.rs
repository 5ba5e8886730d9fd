//! Every reader of outside data, run on arbitrary bytes: the entry points of the `cargo fuzz`
//! targets in `fuzz/` and of the test that replays their corpora. Each call writes the bytes
//! where the reader expects its file, in a scratch folder of its own thread, and runs the
//! reader. A reader may refuse anything; it must not panic, hang or grow without bound.

use std::cell::RefCell;
use std::path::{Path, PathBuf};

use crate::geometry::Pinhole;

/// The readers that are fuzzed; each name is a `fuzz/` target and a corpus folder.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reader {
    /// A 16-bit PNG depth image (`frame-*.depth.png`).
    Depth,
    /// A colour image (`frame-*.color.png`, JPEG too).
    Color,
    /// A 4x4 pose (`frame-*.pose.txt`, Open3D log entries).
    Pose,
    /// `camera-intrinsics.txt`.
    Intrinsics,
    /// Open3D's intrinsics JSON.
    Open3dIntrinsics,
    /// `gravity-direction.txt`.
    Gravity,
    /// A TUM RGB-D folder: `rgb.txt`, `depth.txt` and `groundtruth.txt`, split at NUL bytes.
    Tum,
    /// An Open3D `trajectory.log`.
    Open3dLog,
    /// A scene specification.
    Spec,
    /// A task file.
    Task,
    /// `contact_graph.json`.
    ContactGraph,
    /// A CAD database's `index.json` (and the models it lists).
    CadIndex,
    /// An MJCF model file.
    Mjcf,
    /// A URDF model file.
    Urdf,
    /// A Sweet Home 3D catalogue (a zip).
    Sh3d,
}

impl Reader {
    pub const ALL: [Reader; 15] = [
        Reader::Depth,
        Reader::Color,
        Reader::Pose,
        Reader::Intrinsics,
        Reader::Open3dIntrinsics,
        Reader::Gravity,
        Reader::Tum,
        Reader::Open3dLog,
        Reader::Spec,
        Reader::Task,
        Reader::ContactGraph,
        Reader::CadIndex,
        Reader::Mjcf,
        Reader::Urdf,
        Reader::Sh3d,
    ];

    /// The target's and the corpus folder's name.
    pub fn name(self) -> &'static str {
        match self {
            Reader::Depth => "depth",
            Reader::Color => "color",
            Reader::Pose => "pose",
            Reader::Intrinsics => "intrinsics",
            Reader::Open3dIntrinsics => "open3d_intrinsics",
            Reader::Gravity => "gravity",
            Reader::Tum => "tum",
            Reader::Open3dLog => "open3d_log",
            Reader::Spec => "spec",
            Reader::Task => "task",
            Reader::ContactGraph => "contact_graph",
            Reader::CadIndex => "cad_index",
            Reader::Mjcf => "mjcf",
            Reader::Urdf => "urdf",
            Reader::Sh3d => "sh3d",
        }
    }
}

/// A thread's scratch folder, removed with the thread (a test run leaves nothing in the
/// temporary folder).
struct Scratch(PathBuf);

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

thread_local! {
    static SCRATCH: RefCell<Option<Scratch>> = const { RefCell::new(None) };
}

/// This thread's scratch folder, made empty.
fn scratch() -> PathBuf {
    SCRATCH.with(|cell| {
        let mut cell = cell.borrow_mut();
        let dir = cell
            .get_or_insert_with(|| {
                let thread = format!("{:?}", std::thread::current().id());
                let tag: String = thread.chars().filter(char::is_ascii_digit).collect();
                Scratch(
                    std::env::temp_dir().join(format!("iscene-fuzz-{}-{tag}", std::process::id())),
                )
            })
            .0
            .clone();
        let _ = std::fs::remove_dir_all(&dir);
        let _ = std::fs::create_dir_all(&dir);
        dir
    })
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    if let Some(parent) = path.parent() {
        let _ = std::fs::create_dir_all(parent);
    }
    let _ = std::fs::write(&path, bytes);
    path
}

/// Runs `reader` on `bytes`; whether it accepted them.
pub fn read(reader: Reader, bytes: &[u8]) -> bool {
    let dir = scratch();
    let camera = Pinhole::KINECT;
    match reader {
        Reader::Depth => {
            let path = write(&dir, "frame-000000.depth.png", bytes);
            crate::io::images::read_depth(&path, &camera, 1000.0).is_ok()
        }
        Reader::Color => {
            let path = write(&dir, "frame-000000.color.png", bytes);
            crate::io::images::read_color(&path, &camera).is_ok()
        }
        Reader::Pose => {
            let path = write(&dir, "frame-000000.pose.txt", bytes);
            crate::io::pose::read_pose_file(&path).is_ok()
        }
        Reader::Intrinsics => {
            let path = write(&dir, "camera-intrinsics.txt", bytes);
            crate::io::intrinsics::read_matrix_file(&path, camera.width, camera.height).is_ok()
        }
        Reader::Open3dIntrinsics => {
            let path = write(&dir, "intrinsic.json", bytes);
            crate::io::intrinsics::read_open3d_json(&path).is_ok()
        }
        Reader::Gravity => {
            let path = write(&dir, "gravity-direction.txt", bytes);
            crate::io::native::read_gravity(&path).is_ok()
        }
        Reader::Tum => {
            let mut parts = bytes.split(|&b| b == 0);
            for name in ["rgb.txt", "depth.txt", "groundtruth.txt"] {
                write(&dir, name, parts.next().unwrap_or_default());
            }
            crate::io::tum::open(&dir).is_ok()
        }
        Reader::Open3dLog => {
            write(&dir, "trajectory.log", bytes);
            for k in 0..2 {
                let _ = write(&dir, &format!("depth/{k:06}.png"), b"");
                let _ = write(&dir, &format!("color/{k:06}.jpg"), b"");
            }
            crate::io::open3d_log::open(&dir).is_ok()
        }
        Reader::Spec => {
            let text = String::from_utf8_lossy(bytes);
            crate::scene::SceneSpec::parse(&text, &dir.join("spec.json")).is_ok()
        }
        Reader::Task => {
            let path = write(&dir, "task.json", bytes);
            crate::sim::task::Task::load(&path).is_ok()
        }
        Reader::ContactGraph => {
            let path = write(&dir, "contact_graph.json", bytes);
            crate::graph::ContactGraph::load(&path).is_ok()
        }
        Reader::CadIndex => {
            write(&dir, "index.json", bytes);
            crate::cad::db::load::read_database(&dir).is_ok()
        }
        Reader::Mjcf => {
            let path = write(&dir, "model.xml", bytes);
            crate::cad::import::mjcf::read_mjcf(&path).is_ok_and(|t| t.check_size().is_ok())
        }
        Reader::Urdf => {
            let path = write(&dir, "model.urdf", bytes);
            crate::cad::import::urdf::read_urdf(&path).is_ok_and(|t| t.check_size().is_ok())
        }
        Reader::Sh3d => {
            let path = write(&dir, "catalogue.sh3f", bytes);
            crate::cad::import::sh3d::import_catalogue(&path).is_ok()
        }
    }
}
