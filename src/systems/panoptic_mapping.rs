//! The panoptic mapping stages: choose the segmentation service (Segment), fuse every frame
//! into the panoptic map (Integrate), and spawn one scene entity per object and layout piece
//! with its panoptic identity and segment mesh, objects' meshes carved with the frames'
//! free-space evidence and their outlines as precise frames measured them (Extract).

use bevy::prelude::*;

use crate::components::{Panoptic, SceneEntity, SegmentMesh, SightedOutline};
use crate::error::{InputError, IsceneError};
use crate::map::free_space::FreeSpaceParams;
use crate::panoptic::sighted::{SightedParams, precise_depth, sighted_outlines};
use crate::panoptic::{
    ClassIds, ExtractionParams, MapperParams, PanopticEntity, PanopticMapper, carve_objects,
    extract_entities, map_sequence,
};
use crate::segmentation::onnx::{OnnxDevice, OnnxModels, OnnxParams, OnnxSegmentation};
use crate::segmentation::oracle::OracleSegmentation;
use crate::segmentation::{SegmentationChoice, SegmentationService};
use crate::systems::ingest::InputSequence;
use crate::systems::stages::record_failure;

/// How this reconstruction maps.
#[derive(Resource, Clone, Debug)]
pub struct MappingConfig {
    pub params: MapperParams,
    pub segmentation: SegmentationChoice,
    /// The onnx backend's model folder; `None` for the shared data's.
    pub models: Option<std::path::PathBuf>,
    /// Where the onnx backend's networks run.
    pub onnx_device: OnnxDevice,
    pub progress: bool,
}

impl Default for MappingConfig {
    /// Joint fusion at 2 cm with the oracle segmentation, quiet.
    fn default() -> Self {
        Self {
            params: MapperParams::new(0.02, crate::panoptic::InstanceFusion::Joint),
            segmentation: SegmentationChoice::Oracle,
            models: None,
            onnx_device: OnnxDevice::Cpu,
            progress: false,
        }
    }
}

/// The segmentation service the Segment stage chose; `None` maps geometry only.
#[derive(Resource)]
pub struct Segmenter(pub Option<Box<dyn SegmentationService>>);

/// The panoptic map after integration.
#[derive(Resource)]
pub struct PanopticMap(pub PanopticMapper);

/// What the Extract stage found, for export and evaluation: the entities in spawn order and
/// every surface voxel with its entity index plus one.
#[derive(Resource, Default)]
pub struct PanopticSurface {
    pub entities: Vec<PanopticEntity>,
    pub voxels: Vec<(Vec3, u32)>,
    /// The depth's noise as a multiple of the Kinect curve when it is precise enough to measure
    /// the objects' outlines (`panoptic::sighted`), `None` otherwise.
    pub precise_depth: Option<f32>,
}

/// The segmentation service `config` asks for, set up for `sequence`; `None` maps geometry only.
pub fn segmentation_service(
    config: &MappingConfig,
    sequence: &crate::io::Sequence,
) -> Result<Option<Box<dyn SegmentationService>>, InputError> {
    match config.segmentation {
        SegmentationChoice::Oracle => OracleSegmentation::for_sequence(sequence)
            .map(|o| Some(Box::new(o) as Box<dyn SegmentationService>)),
        SegmentationChoice::None => Ok(None),
        SegmentationChoice::Onnx => {
            let dir = config
                .models
                .clone()
                .unwrap_or_else(|| OnnxModels::DEFAULT_DIR.into());
            OnnxSegmentation::for_sequence(
                sequence,
                &OnnxModels::in_dir(&dir),
                OnnxParams {
                    device: config.onnx_device,
                    ..OnnxParams::default()
                },
            )
            .map(|o| Some(Box::new(o) as Box<dyn SegmentationService>))
        }
    }
}

/// Marks the short-lived world a live session refreshes once a second from the map so far: the
/// Extract stage skips what reads every frame again (carving, outlines), which the final pass
/// does.
#[derive(Resource)]
pub struct LivePreview;

fn choose_segmenter(
    mut commands: Commands,
    config: Res<MappingConfig>,
    sequence: Res<InputSequence>,
) -> Result<(), IsceneError> {
    commands.insert_resource(Segmenter(segmentation_service(&config, &sequence.0)?));
    Ok(())
}

fn integrate_frames(
    mut commands: Commands,
    config: Res<MappingConfig>,
    sequence: Res<InputSequence>,
    segmenter: Res<Segmenter>,
) -> Result<(), IsceneError> {
    let bar = crate::progress::bar(sequence.0.frames.len() as u64, "mapping", config.progress);
    let mapped = map_sequence(&sequence.0, segmenter.0.as_deref(), &config.params, &bar);
    bar.finish_and_clear();
    commands.insert_resource(PanopticMap(mapped?));
    Ok(())
}

fn spawn_entities(
    mut commands: Commands,
    map: Res<PanopticMap>,
    segmenter: Option<Res<Segmenter>>,
    sequence: Res<InputSequence>,
    preview: Option<Res<LivePreview>>,
) -> Result<(), IsceneError> {
    let mut scene = extract_entities(
        &map.0.tsdf,
        &map.0.instances,
        &ClassIds::builtin(),
        &ExtractionParams::default(),
    );
    if let Some(service) = segmenter.as_ref().and_then(|s| s.0.as_deref()) {
        for e in &mut scene.entities {
            if let Some(part) = service.layout_part(&e.class, &e.mesh) {
                e.mesh = part;
            }
        }
    }
    if preview.is_some() {
        spawn_scene_entities(&mut commands, &scene.entities, None);
        commands.insert_resource(PanopticSurface {
            entities: scene.entities,
            voxels: scene.surface_voxels,
            precise_depth: None,
        });
        return Ok(());
    }
    let sighted = SightedParams::for_voxel(map.0.tsdf.voxel_size);
    let precise = precise_depth(&sequence.0, &sighted)?;
    // Depth far more precise than a Kinect's is carved by its own noise, not the Kinect curve's.
    let params = FreeSpaceParams {
        noise_scale: precise.unwrap_or(1.0),
        ..FreeSpaceParams::for_voxel(map.0.tsdf.voxel_size)
    };
    carve_objects(&mut scene.entities, &sequence.0, &map.0, &params)?;
    let outlines = sighted_outlines(&scene.entities, &sequence.0, &map.0, precise, &sighted)?;
    spawn_scene_entities(&mut commands, &scene.entities, Some(outlines));
    commands.insert_resource(PanopticSurface {
        entities: scene.entities,
        voxels: scene.surface_voxels,
        precise_depth: precise,
    });
    Ok(())
}

fn spawn_scene_entities(
    commands: &mut Commands,
    entities: &[PanopticEntity],
    outlines: Option<Vec<Vec<Vec<Vec3>>>>,
) {
    let mut outlines = outlines.map(Vec::into_iter);
    for e in entities {
        let outline = outlines
            .as_mut()
            .and_then(Iterator::next)
            .unwrap_or_default();
        commands.spawn((
            SceneEntity(e.id.clone()),
            Panoptic {
                instance: e.instance,
                class: crate::base::ClassId::new(&e.class),
                kind: e.kind,
            },
            SegmentMesh(e.mesh.clone()),
            SightedOutline(outline),
        ));
    }
}

/// Adds the Segment, Integrate and Extract systems.
pub struct PanopticMappingPlugin;

impl Plugin for PanopticMappingPlugin {
    fn build(&self, app: &mut App) {
        use crate::systems::ReconstructionStage as Stage;
        app.init_resource::<MappingConfig>().add_systems(
            crate::systems::Reconstruct,
            (
                // A map made outside the schedule (a live session) is not made again.
                choose_segmenter
                    .pipe(record_failure)
                    .run_if(not(resource_exists::<PanopticMap>))
                    .in_set(Stage::Segment),
                integrate_frames
                    .pipe(record_failure)
                    .run_if(not(resource_exists::<PanopticMap>))
                    .in_set(Stage::Integrate),
                spawn_entities.pipe(record_failure).in_set(Stage::Extract),
            ),
        );
    }
}
