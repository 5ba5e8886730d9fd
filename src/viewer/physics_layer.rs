//! The physics layer: the rest test (`rest_physics`, rapier, 2 s) on the scene as it stands,
//! each object's box coloured by its verdict (stable green, unstable orange, penetrating red) and
//! the exceptions with their reasons in the panel. It reruns whenever the scene changes.

use bevy::prelude::*;

use crate::components::{OrientedBox, SceneEntity};
use crate::kinematics::rest_test::Verdict;
use crate::systems::physics_validation::{PhysicsReport, scene_rest_physics};
use crate::viewer::layers::{ActiveLayers, Layer};
use crate::viewer::motion::Motion;
use crate::viewer::state::SceneRevision;

/// The last rest test and the scene revision it ran on.
#[derive(Resource, Clone, Debug, Default)]
pub struct RestVerdicts {
    pub revision: Option<u64>,
    pub report: Option<PhysicsReport>,
}

impl RestVerdicts {
    /// The panel's lines: the stable share, then each exception with its reason.
    pub fn summary(&self) -> Vec<String> {
        let Some(report) = &self.report else {
            return Vec::new();
        };
        let mut lines = vec![format!(
            "rest test: {:.0} % of {} objects stable",
            100.0 * report.stable_fraction,
            report.objects.len()
        )];
        lines.extend(
            report
                .objects
                .iter()
                .filter(|o| o.verdict != Verdict::Stable)
                .map(|o| format!("  {}: {}", o.object, o.reason.as_deref().unwrap_or("?"))),
        );
        lines
    }
}

/// Runs the rest test on the scene as it stands and keeps it for `revision`.
pub fn run_rest_test(world: &mut World, revision: u64) {
    let report = scene_rest_physics(world)
        .inspect_err(|e| tracing::warn!("no rest test: {e}"))
        .ok();
    *world.resource_mut::<RestVerdicts>() = RestVerdicts {
        revision: Some(revision),
        report,
    };
}

/// Reruns the rest test when the layer is on and the scene changed since the last one.
fn refresh_verdicts(world: &mut World) {
    let revision = world.resource::<SceneRevision>().0;
    // Transforms in the middle of a motion are no state of the tree: wait for its end.
    if world.resource::<ActiveLayers>().is_on(Layer::Physics)
        && world.resource::<RestVerdicts>().revision != Some(revision)
        && !world.resource::<Motion>().is_running()
    {
        run_rest_test(world, revision);
    }
}

fn verdict_colour(verdict: Verdict) -> Color {
    match verdict {
        Verdict::Stable => Color::srgb(0.0, 0.75, 0.2),
        Verdict::Unstable => Color::srgb(1.0, 0.55, 0.0),
        Verdict::Penetrating => Color::srgb(0.9, 0.0, 0.0),
    }
}

/// Grown boxes, so that a verdict shows beside the boxes layer's own.
const VERDICT_BOX_MARGIN_M: f32 = 0.015;

fn draw_verdicts(
    layers: Res<ActiveLayers>,
    verdicts: Res<RestVerdicts>,
    nodes: Query<(&SceneEntity, &OrientedBox)>,
    mut gizmos: Gizmos,
) {
    if !layers.is_on(Layer::Physics) {
        return;
    }
    let Some(report) = &verdicts.report else {
        return;
    };
    for object in &report.objects {
        let Some((_, b)) = nodes.iter().find(|(id, _)| id.0 == object.object) else {
            continue;
        };
        let colour = verdict_colour(object.verdict);
        let transform = Transform::from_translation(b.0.center)
            .with_rotation(Quat::from_rotation_z(b.0.yaw))
            .with_scale(b.0.size + Vec3::splat(2.0 * VERDICT_BOX_MARGIN_M));
        gizmos.cube(transform, colour);
        if object.verdict != Verdict::Stable {
            // A mark above the object, visible from afar.
            let top = b.0.center + Vec3::Z * (b.0.size.z / 2.0 + 0.1);
            gizmos.sphere(Isometry3d::from_translation(top), 0.05, colour);
        }
    }
}

pub struct PhysicsLayerPlugin;

impl Plugin for PhysicsLayerPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<RestVerdicts>()
            .add_systems(Update, (refresh_verdicts, draw_verdicts).chain());
    }
}
