//! Maps a whole sequence: frames are read, segmented and fused with their masks a few at a
//! time in parallel, then associated and integrated in order.

use rayon::prelude::*;

use crate::error::IsceneError;
use crate::io::Sequence;
use crate::panoptic::entities::ClassIds;
use crate::panoptic::mapper::{MapperFrame, MapperParams, PanopticMapper, segment_frame};
use crate::segmentation::SegmentationService;
use crate::segmentation::geometric::segment_depth;

pub fn map_sequence(
    sequence: &Sequence,
    service: Option<&dyn SegmentationService>,
    params: &MapperParams,
    progress: &indicatif::ProgressBar,
) -> Result<PanopticMapper, IsceneError> {
    let classes = ClassIds::builtin();
    let class_id = |name: &str| classes.id(name);
    let mut mapper = PanopticMapper::new(params.clone());
    let exact_classes = service.map_or(&[][..], |s| s.exact_classes());
    let n = sequence.frames.len();
    // Enough frames in flight to keep every core busy with the per-frame work.
    let batch = 2 * rayon::current_num_threads().max(1);
    for start in (0..n).step_by(batch) {
        let prepared: Vec<_> = (start..(start + batch).min(n))
            .into_par_iter()
            .map(|i| -> Result<_, IsceneError> {
                let frame = sequence.load_frame(i)?;
                let geometry = segment_depth(&frame.depth, &frame.camera, &params.geometric);
                let masks = match service {
                    Some(s) if i % params.segment_every.max(1) == 0 => {
                        Some(s.segment(&frame, &geometry)?)
                    }
                    Some(s) => s.segment_without_networks(&frame, &geometry),
                    None => None,
                };
                let segmented = segment_frame(
                    &MapperFrame {
                        depth: &frame.depth,
                        color: &frame.color,
                        camera: &frame.camera,
                        world_from_camera: &frame.world_from_camera,
                    },
                    &geometry,
                    masks.as_ref(),
                    &class_id,
                    exact_classes,
                    params,
                );
                Ok((frame, segmented))
            })
            .collect();
        for item in prepared {
            let (frame, segmented) = item?;
            mapper.integrate(
                &MapperFrame {
                    depth: &frame.depth,
                    color: &frame.color,
                    camera: &frame.camera,
                    world_from_camera: &frame.world_from_camera,
                },
                &segmented,
            );
            progress.inc(1);
        }
    }
    mapper.regularise();
    Ok(mapper)
}
