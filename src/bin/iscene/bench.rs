//! `iscene bench`: benchmarks that print their figures as one JSON object.

use iscene::error::IsceneError;

use crate::args::BenchCommand;
use crate::print_json;

pub(crate) fn bench(command: BenchCommand) -> Result<(), IsceneError> {
    match command {
        BenchCommand::Tsdf {
            sequence,
            frames,
            voxel,
            holdout,
            labels,
            mesh,
            runs,
            max_memory,
            pack_after,
        } => {
            let report = iscene::bench::bench_tsdf(&iscene::bench::TsdfBenchOptions {
                sequence,
                frames,
                voxel,
                holdout_every: holdout,
                labels,
                mesh,
                runs: runs as usize,
                max_memory_gb: max_memory,
                pack_after_frames: pack_after,
            })?;
            print_json(&report)
        }
        BenchCommand::Segmentation {
            sequence,
            frames,
            models,
            onnx_device,
        } => {
            let report = iscene::segmentation::onnx::bench::bench_segmentation(
                &iscene::segmentation::onnx::bench::SegmentationBenchOptions {
                    sequence,
                    frames,
                    models,
                    device: onnx_device,
                },
            )?;
            print_json(&report)
        }
        BenchCommand::Simulation {
            dir,
            task,
            robot,
            runs,
        } => {
            let report =
                iscene::simulation::bench_simulation(&dir, &task, robot.as_deref(), runs as usize)?;
            print_json(&report)
        }
    }
}
