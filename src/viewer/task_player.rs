//! Runs a task script in the viewer (`iscene view DIR --task FILE`): N does the next action,
//! P plays them one after another. Each action goes through the simulation's ECS messages as in
//! `iscene simulate`, so the kinematic tree (and with it the meshes) follows: the robot drives,
//! doors turn, a picked object rides in the gripper. The panel shows the step and its outcome,
//! and the change is shown happening (motion.rs); the next action waits for it.

use bevy::prelude::*;

use crate::sim::actions::Action;
use crate::systems::simulation::{ActionRequest, SimulationTrace, StepPhysics};
use crate::viewer::motion::{Motion, animate, show_motion};
use crate::viewer::state::{SceneRevision, ViewerStatus};

/// The task's actions and how far the viewer has run them.
#[derive(Resource, Clone, Debug, Default)]
pub struct TaskPlayer {
    pub actions: Vec<Action>,
    /// The next action to ask for.
    pub next: usize,
    pub playing: bool,
    /// Seconds until the next action while playing.
    wait_s: f32,
    /// Trace length when the last action was asked for: its record is the one after.
    asked_at: Option<usize>,
}

impl TaskPlayer {
    pub fn new(actions: Vec<Action>) -> Self {
        Self {
            actions,
            ..default()
        }
    }
}

/// While playing, one action per this many seconds: time to see each one.
const PLAY_STEP_S: f32 = 1.0;

/// N asks for the next action, P plays or pauses; a refused action stops the play.
fn step_task(
    keys: Res<ButtonInput<KeyCode>>,
    time: Res<Time>,
    trace: Res<SimulationTrace>,
    motion: Res<Motion>,
    mut player: ResMut<TaskPlayer>,
    mut requests: MessageWriter<ActionRequest>,
) {
    if player.actions.is_empty() {
        return;
    }
    if keys.just_pressed(KeyCode::KeyP) {
        player.playing = !player.playing;
        player.wait_s = 0.0;
    }
    // The last action is still being shown, or its record is still to come.
    if motion.is_running() || player.asked_at.is_some() {
        return;
    }
    let failed = trace.0.last().is_some_and(|r| !r.success);
    if failed {
        player.playing = false;
    }
    let mut go = keys.just_pressed(KeyCode::KeyN);
    if player.playing {
        player.wait_s -= time.delta_secs();
        if player.wait_s <= 0.0 {
            player.wait_s = PLAY_STEP_S;
            go = true;
        }
    }
    if !go || player.next >= player.actions.len() {
        if player.next >= player.actions.len() {
            player.playing = false;
        }
        return;
    }
    let action = player.actions[player.next].clone();
    player.next += 1;
    if player.next == player.actions.len() {
        // The last one: the play is over.
        player.playing = false;
    }
    player.asked_at = Some(trace.0.len());
    let then = player.actions[player.next..].to_vec();
    requests.write(ActionRequest(action, then));
}

/// Once the asked action has its record: the panel says how it went, and the layers that
/// depend on the scene as it stands rebuild.
fn report_step(
    mut commands: Commands,
    trace: Res<SimulationTrace>,
    mut player: ResMut<TaskPlayer>,
    mut status: ResMut<ViewerStatus>,
    mut revision: ResMut<SceneRevision>,
) {
    let Some(asked_at) = player.asked_at else {
        return;
    };
    let Some(record) = trace.0.get(asked_at) else {
        return;
    };
    player.asked_at = None;
    let outcome = match (&record.failed_precondition, &record.physics) {
        (Some(why), _) => format!("refused: {why}"),
        (None, Some(physics)) => format!("done; {}", physics_words(physics)),
        (None, None) => "done".into(),
    };
    status.0 = vec![format!(
        "task step {} of {}: {} - {outcome}",
        player.next,
        player.actions.len(),
        record.action.in_words()
    )];
    if record.success {
        revision.0 += 1;
        let changes = record.changes.clone();
        commands.queue(move |world: &mut World| show_motion(world, &changes));
    }
}

fn physics_words(physics: &StepPhysics) -> String {
    if physics.not_stable.is_empty() {
        return format!("all {} objects stable", physics.checked.len());
    }
    let names: Vec<String> = physics
        .not_stable
        .iter()
        .map(|o| format!("{} ({})", o.object, o.reason.as_deref().unwrap_or("?")))
        .collect();
    format!("not stable: {}", names.join(", "))
}

pub struct TaskPlayerPlugin;

impl Plugin for TaskPlayerPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<TaskPlayer>()
            // The request is read by the simulation's Update system, this frame or the next;
            // the report waits for its record.
            .add_systems(Update, step_task)
            // The motion starts at its beginning on the frame the action is reported.
            .add_systems(PostUpdate, report_step.before(animate));
    }
}
