//! Maps a whole sequence: frames are read, segmented and fused with their masks a few at a
//! time in parallel, while the frames before them are associated and integrated in order.

use rayon::prelude::*;

use crate::error::IsceneError;
use crate::io::Sequence;
use crate::io::sequence::Frame;
use crate::panoptic::entities::ClassIds;
use crate::panoptic::mapper::{
    MapperFrame, MapperParams, PanopticMapper, SegmentedFrame, segment_frame,
};
use crate::segmentation::SegmentationService;
use crate::segmentation::geometric::segment_depth;

pub fn map_sequence(
    sequence: &Sequence,
    service: Option<&dyn SegmentationService>,
    params: &MapperParams,
    progress: &indicatif::ProgressBar,
) -> Result<PanopticMapper, IsceneError> {
    let classes = ClassIds::builtin();
    let mut mapper = PanopticMapper::new(params.clone());
    let n = sequence.frames.len();
    // Enough frames in flight to keep every core busy with the per-frame work.
    let batch = 2 * rayon::current_num_threads().max(1);
    let prepare = |i: usize| {
        let networks = service.is_some() && i.is_multiple_of(params.segment_every.max(1));
        prepare_frame(sequence, i, service, params, &classes, networks)
    };
    // Frames are decoded and segmented (independently, in parallel) on one thread while this one
    // associates and integrates them in order: the two overlap, and both draw on the same rayon
    // pool. The channel holds two batches, which bounds the frames in memory.
    let (sender, receiver) = std::sync::mpsc::sync_channel(2 * batch);
    std::thread::scope(|scope| {
        scope.spawn(move || {
            for start in (0..n).step_by(batch) {
                let prepared: Vec<_> = (start..(start + batch).min(n))
                    .into_par_iter()
                    .map(prepare)
                    .collect();
                for item in prepared {
                    let failed = item.is_err();
                    // A closed channel means the integrating side stopped on an error.
                    if sender.send(item).is_err() || failed {
                        return;
                    }
                }
            }
        });
        for item in receiver {
            let (frame, segmented) = item?;
            mapper.integrate(&mapper_frame(&frame), &segmented);
            progress.inc(1);
        }
        Ok::<(), IsceneError>(())
    })?;
    mapper.regularise();
    Ok(mapper)
}

/// Reads frame `i` and segments it: geometric segments, the service's masks (its networks only
/// where `networks`, the cheap part otherwise) and their fusion. Frames are independent here.
pub fn prepare_frame(
    sequence: &Sequence,
    i: usize,
    service: Option<&dyn SegmentationService>,
    params: &MapperParams,
    classes: &ClassIds,
    networks: bool,
) -> Result<(Frame, SegmentedFrame), IsceneError> {
    let class_id = |name: &str| classes.id(name);
    let exact_classes = service.map_or(&[][..], |s| s.exact_classes());
    let frame = sequence.load_frame(i)?;
    let geometry = segment_depth(&frame.depth, &frame.camera, &params.geometric);
    let masks = match service {
        Some(s) if networks => Some(s.segment(&frame, &geometry)?),
        Some(s) => s.segment_without_networks(&frame, &geometry),
        None => None,
    };
    let segmented = segment_frame(
        &mapper_frame(&frame),
        &geometry,
        masks.as_ref(),
        &class_id,
        exact_classes,
        params,
    );
    Ok((frame, segmented))
}

pub(crate) fn mapper_frame(frame: &Frame) -> MapperFrame<'_> {
    MapperFrame {
        depth: &frame.depth,
        color: &frame.color,
        camera: &frame.camera,
        world_from_camera: &frame.world_from_camera,
    }
}
