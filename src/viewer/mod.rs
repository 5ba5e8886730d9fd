//! `iscene view DIR` (cargo feature `viewer`): a Bevy window on a scene folder's live world (the
//! contact graph's entities with their CAD links, as `iscene simulate` builds it), with layers
//! switched from the keyboard, an orbit camera, and doors and drawers worked by clicking them;
//! or, with `--screenshot`, the same world rendered off screen into a PNG.
//! `iscene view OUT --replay` plays a reconstruction back frame by frame instead: the map
//! growing as the sensor saw it, the camera moving, the contact graph's nodes appearing.
//!
//! The kinematic tree is the transform hierarchy, so a joint that moves moves its meshes.

mod camera;
mod collision;
mod drag_drop;
mod graph_labels;
mod graph_overlays;
mod interaction;
mod layers;
mod link_meshes;
mod live_scene;
mod map_layer;
mod motion;
mod occupancy;
mod physics_layer;
mod replay_scene;
mod screenshot;
mod state;
mod task_player;
mod timeline;

use std::path::{Path, PathBuf};

use bevy::prelude::*;
use bevy::render::RenderPlugin;
use bevy::render::pipelined_rendering::PipelinedRenderingPlugin;
use bevy::window::ExitCondition;
use bevy::winit::WinitPlugin;

use crate::cad::db::database::CadDatabase;
use crate::error::{InputError, IsceneError};
use crate::graph::ContactGraph;
use crate::replay::{Replay, load_replay};
use crate::sim::scene_view::{SceneView, open_value};
use crate::sim::task::Task;
use crate::simulation::{SceneShapes, read_arm, simulation_app, task_world};
use crate::systems::kinematic_tree::read_kinematic_tree;
use crate::systems::simulation::apply_change;

pub use camera::OrbitCamera;
pub use drag_drop::{DragPreview, DropGhost, drop_object};
pub use graph_labels::{NodeLabel, ReplayLabel};
pub use interaction::work_joint_at;
pub use layers::{ActiveLayers, Layer};
pub use map_layer::{MapSegments, read_map};
pub use motion::Motion;
pub use physics_layer::RestVerdicts;
pub use replay_scene::ReplayData;
pub use screenshot::{RenderTiming, render_offscreen};
pub use state::{PointerPosition, SceneRevision, ViewerStatus};
pub use task_player::TaskPlayer;
pub use timeline::ReplayClock;

/// What `iscene view` shows and does.
#[derive(Clone, Debug)]
pub struct ViewOptions {
    /// A folder with contact_graph.json.
    pub dir: PathBuf,
    /// Render off screen into this PNG and exit.
    pub screenshot: Option<PathBuf>,
    /// The layers shown (default: colour).
    pub layers: Vec<Layer>,
    /// Frames rendered before the screenshot is taken.
    pub frames: u32,
    /// Off-screen image size in pixels.
    pub size: (u32, u32),
    /// Objects whose main door or drawer is opened before the first frame.
    pub open: Vec<String>,
    /// Play back the reconstruction in `dir` instead of showing its world.
    pub replay: bool,
    /// A task script to run step by step (N) or play (P) in the window.
    pub task: Option<PathBuf>,
    /// The URDF of an arm on the robot's base.
    pub robot: Option<PathBuf>,
    /// Screenshots of a replay, evenly spaced from its first frame to its last.
    pub shots: u32,
    /// Follow a running `reconstruct --live --out DIR` session: the world is rebuilt each time
    /// the session refreshes it.
    pub live: bool,
}

/// How long `view --live` waits for the session's first graph.
const LIVE_WAIT: std::time::Duration = std::time::Duration::from_secs(120);

/// The clear colour: a light grey-blue that no model uses.
const BACKGROUND: Color = Color::srgb(0.93, 0.94, 0.96);

/// Adds what the viewer draws and how it reacts, on top of a scene world and Bevy's renderer.
pub struct ViewerPlugin {
    pub layers: Vec<Layer>,
}

impl Plugin for ViewerPlugin {
    fn build(&self, app: &mut App) {
        app.insert_resource(ActiveLayers::new(&self.layers))
            .insert_resource(GlobalAmbientLight {
                brightness: 300.0,
                ..default()
            })
            .insert_resource(ClearColor(BACKGROUND))
            .add_plugins((
                link_meshes::LinkMeshesPlugin,
                layers::LayersPlugin,
                graph_overlays::GraphOverlaysPlugin,
                graph_labels::GraphLabelsPlugin,
                map_layer::MapLayerPlugin,
                collision::CollisionLayerPlugin,
                occupancy::OccupancyLayerPlugin,
                physics_layer::PhysicsLayerPlugin,
                task_player::TaskPlayerPlugin,
                motion::MotionPlugin,
                drag_drop::DragDropPlugin,
                camera::OrbitCameraPlugin,
                interaction::InteractionPlugin,
            ));
    }
}

/// The scene world of `options.dir` with the robot, doors opened as asked, and the viewer's
/// plugins; `offscreen` renders into an image of that size instead of a window.
pub fn viewer_app(options: &ViewOptions, offscreen: bool) -> Result<App, IsceneError> {
    let arm = options.robot.as_deref().map(read_arm).transpose()?;
    let (actions, mut app) = match &options.task {
        Some(task) => task_world(&options.dir, task, arm.as_ref())?,
        None => {
            let graph = if options.live {
                live_scene::first_graph(&options.dir, LIVE_WAIT)?.1
            } else {
                ContactGraph::load(&options.dir.join("contact_graph.json"))?
            };
            let shapes = SceneShapes::read(&options.dir, &graph)?;
            let app = simulation_app(&graph, &Task::default(), &shapes, arm.as_ref())?;
            (Vec::new(), app)
        }
    };
    open_doors(app.world_mut(), &options.open, &options.dir)?;
    let map = read_map(&options.dir)?;
    add_render_plugins(&mut app, &options.dir, offscreen);
    app.add_plugins(ViewerPlugin {
        layers: options.layers.clone(),
    })
    .insert_resource(TaskPlayer::new(actions))
    .insert_resource(map);
    if options.live {
        app.insert_resource(live_scene::LiveSource {
            out: options.dir.clone(),
            // The first poll compares with what the world was built from.
            shown: live_scene::current_graph(&options.dir)
                .map(|p| (p.clone(), live_scene::modified(&p))),
            models: CadDatabase::for_scene(&options.dir)?,
            since_poll: std::time::Duration::ZERO,
        })
        .add_plugins(live_scene::LiveScenePlugin);
    }
    Ok(app)
}

/// Bevy's renderer, UI and input: into a window titled after `dir`, or off screen (no window,
/// one frame rendered per update, so the screenshot frame is the frame asked for).
fn add_render_plugins(app: &mut App, dir: &std::path::Path, offscreen: bool) {
    let render = RenderPlugin {
        // Every pipeline ready on the frame that first needs it: a screenshot after N frames
        // shows the whole scene, not whatever had compiled by then.
        synchronous_pipeline_compilation: true,
        ..default()
    };
    if offscreen {
        app.add_plugins(
            DefaultPlugins
                .set(WindowPlugin {
                    primary_window: None,
                    exit_condition: ExitCondition::DontExit,
                    close_when_requested: false,
                    ..default()
                })
                .set(render)
                // The command line's subscriber (RUST_LOG) shows the renderer's warnings.
                .disable::<bevy::log::LogPlugin>()
                .disable::<WinitPlugin>()
                .disable::<PipelinedRenderingPlugin>(),
        );
    } else {
        app.add_plugins(
            DefaultPlugins
                .set(WindowPlugin {
                    primary_window: Some(Window {
                        title: format!("iscene: {}", dir.display()),
                        ..default()
                    }),
                    ..default()
                })
                .set(render)
                .disable::<bevy::log::LogPlugin>(),
        );
    }
}

/// The replay of the reconstruction in `replay.dir`, on Bevy's renderer.
pub fn replay_app(replay: Replay, offscreen: bool) -> App {
    let mut app = App::new();
    add_render_plugins(&mut app, &replay.dir.clone(), offscreen);
    let clock = ReplayClock::new(replay.frames());
    app.insert_resource(ReplayData(replay))
        .insert_resource(ReplayClock {
            // A window starts playing; screenshots set the clock themselves.
            playing: !offscreen,
            ..clock
        })
        .insert_resource(ActiveLayers::new(&[Layer::Boxes, Layer::Graph]))
        .insert_resource(GlobalAmbientLight {
            brightness: 300.0,
            ..default()
        })
        .insert_resource(ClearColor(BACKGROUND))
        .add_plugins((
            timeline::TimelinePlugin,
            replay_scene::ReplayScenePlugin,
            graph_labels::ReplayLabelsPlugin,
            camera::OrbitCameraPlugin,
        ));
    app
}

/// Runs every action of the task at `task` (a refused one is an error in the task): a
/// screenshot then shows where the task ends.
fn run_whole_task(app: &mut App, task: &std::path::Path) -> Result<(), IsceneError> {
    let actions = app.world().resource::<TaskPlayer>().actions.clone();
    for (k, action) in actions.iter().enumerate() {
        let record =
            crate::systems::simulation::perform(app.world_mut(), action, &actions[k + 1..]);
        if let Some(refused) = record.failed_precondition {
            return Err(InputError::invalid(
                task,
                format!("the task stopped at {}: {refused}", action.in_words()),
            )
            .into());
        }
    }
    let mut player = app.world_mut().resource_mut::<TaskPlayer>();
    player.next = player.actions.len();
    Ok(())
}

/// Opens the main door or drawer of each object in `objects` (`--open`, for the scene in `dir`).
fn open_doors(world: &mut World, objects: &[String], dir: &Path) -> Result<(), IsceneError> {
    for object in objects {
        let tree = read_kinematic_tree(world)?;
        let view = SceneView::new(&tree);
        let part = view.main_part(object).ok_or_else(|| {
            InputError::invalid(
                dir,
                format!("--open {object}: no such object with a door or drawer"),
            )
        })?;
        let link = &tree.links[part];
        apply_change(
            world,
            &crate::sim::actions::Change::SetJoint {
                link: link.name.clone(),
                from: link.value,
                to: open_value(&tree, part),
            },
        );
    }
    Ok(())
}

/// Runs the viewer: a window until it is closed (`None`), or one off-screen screenshot (how fast
/// its frames rendered).
pub fn view(options: &ViewOptions) -> Result<Option<RenderTiming>, IsceneError> {
    if options.replay {
        let replay = load_replay(&options.dir)?;
        let Some(path) = &options.screenshot else {
            replay_app(replay, false).run();
            return Ok(None);
        };
        let frames = replay.frames();
        let mut app = replay_app(replay, true);
        return screenshot::take_replay(&mut app, path, options.shots, frames, options.size)
            .map(Some);
    }
    let Some(path) = &options.screenshot else {
        let mut app = viewer_app(options, false)?;
        app.run();
        return Ok(None);
    };
    let mut app = viewer_app(options, true)?;
    if let Some(task) = &options.task {
        run_whole_task(&mut app, task)?;
    }
    screenshot::take(&mut app, path, options.frames, options.size).map(Some)
}
