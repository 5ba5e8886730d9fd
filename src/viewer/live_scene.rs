//! `iscene view OUT --live`: the world of a running `reconstruct --live` session, rebuilt each
//! time the session refreshes its preview, so the window shows the twin growing.
//!
//! A live session writes `live/contact_graph.json` in its output's staging folder
//! (`.NAME.partial-PID/` beside `OUT`) and, when it finishes, puts the whole output at `OUT`.
//! The viewer follows the newest of these graphs: the staging folder's while the session runs,
//! then `OUT/contact_graph.json`.

use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime};

use bevy::prelude::*;

use crate::cad::db::database::CadDatabase;
use crate::components::SceneEntity;
use crate::error::{InputError, IsceneError};
use crate::graph::ContactGraph;
use crate::systems::kinematic_tree::spawn_node_links;
use crate::systems::scene_graph::spawn_contact_graph;
use crate::viewer::graph_labels::NodeLabel;

/// How often the viewer looks for a newer graph.
const POLL: Duration = Duration::from_millis(500);

/// The graph a live view shows now: the staging folder's preview of a running session, else the
/// finished output's graph; `None` while neither exists.
pub fn current_graph(out: &Path) -> Option<PathBuf> {
    let name = out.file_name()?.to_string_lossy().into_owned();
    let parent = out
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let staged = std::fs::read_dir(parent)
        .ok()?
        .filter_map(Result::ok)
        .filter(|e| {
            e.file_name()
                .to_string_lossy()
                .starts_with(&format!(".{name}.partial-"))
        })
        .map(|e| e.path().join("live").join("contact_graph.json"))
        .filter(|p| p.is_file())
        .max_by_key(|p| modified(p));
    staged.or_else(|| Some(out.join("contact_graph.json")).filter(|p| p.is_file()))
}

/// When the file at `path` last changed.
pub fn modified(path: &Path) -> Option<SystemTime> {
    std::fs::metadata(path).and_then(|m| m.modified()).ok()
}

/// Waits up to `wait` for the session's first graph.
pub fn first_graph(out: &Path, wait: Duration) -> Result<(PathBuf, ContactGraph), IsceneError> {
    let start = std::time::Instant::now();
    loop {
        if let Some(path) = current_graph(out)
            && let Ok(graph) = ContactGraph::load(&path)
        {
            return Ok((path, graph));
        }
        if start.elapsed() > wait {
            return Err(InputError::missing(
                out,
                format!(
                    "no live session's graph appeared within {} s (start `iscene reconstruct ... --live --out {}` first)",
                    wait.as_secs(),
                    out.display()
                ),
            )
            .into());
        }
        std::thread::sleep(Duration::from_millis(100));
    }
}

/// What the live view follows.
#[derive(Resource)]
pub struct LiveSource {
    pub out: PathBuf,
    pub shown: Option<(PathBuf, Option<SystemTime>)>,
    pub models: CadDatabase,
    pub since_poll: Duration,
}

/// Rebuilds the scene's nodes and links from a newer graph: the old nodes (with their links,
/// children of theirs) and their labels go, the new ones are spawned under the same root, and the
/// viewer's systems give them meshes and labels as for any new node. The robot stays.
fn follow_live_graph(world: &mut World) {
    let delta = world.resource::<Time>().delta();
    let mut source = world.resource_mut::<LiveSource>();
    source.since_poll += delta;
    if source.since_poll < POLL {
        return;
    }
    source.since_poll = Duration::ZERO;
    let Some(path) = current_graph(&source.out) else {
        return;
    };
    let stamp = (path.clone(), modified(&path));
    if source.shown.as_ref() == Some(&stamp) {
        return;
    }
    // A graph caught while being replaced is read again at the next poll.
    let Ok(graph) = ContactGraph::load(&path) else {
        return;
    };
    world.resource_mut::<LiveSource>().shown = Some(stamp);
    let mut old: Vec<Entity> = world
        .query_filtered::<Entity, With<SceneEntity>>()
        .iter(world)
        .collect();
    old.extend(
        world
            .query_filtered::<Entity, With<NodeLabel>>()
            .iter(world),
    );
    for entity in old {
        if let Ok(e) = world.get_entity_mut(entity) {
            e.despawn();
        }
    }
    if spawn_contact_graph(world, &graph).is_ok() {
        // A preview's models built to an object's size are written with the output only.
        let mut source = world.resource_mut::<LiveSource>();
        source.models = source.models.with_sized_models_of(&graph);
        world.resource_scope(|world, source: Mut<LiveSource>| {
            spawn_node_links(world, &graph, Some(&source.models));
        });
    }
}

pub struct LiveScenePlugin;

impl Plugin for LiveScenePlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(First, follow_live_graph);
    }
}
