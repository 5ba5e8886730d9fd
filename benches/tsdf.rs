//! TSDF integration speed on 7-Scenes redkitchen (640x480, with colour), frames per second at
//! 2 cm and 1 cm voxels. Needs ../shared/data.

use std::path::Path;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use iscene::io::Sequence;
use iscene::map::{TsdfFrame, TsdfMap};

fn integrate(c: &mut Criterion) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/rgbd/7scenes-redkitchen");
    let mut seq =
        Sequence::open(&root).expect("this benchmark needs ../shared/data/rgbd/7scenes-redkitchen");
    seq.select(0, Some(60), 1);
    let frames: Vec<_> = (0..seq.frames.len())
        .map(|i| seq.load_frame(i).expect("frame"))
        .collect();
    let mut group = c.benchmark_group("tsdf_integrate_7scenes");
    group.sample_size(10);
    group.throughput(Throughput::Elements(frames.len() as u64));
    for voxel in [0.02f32, 0.01] {
        group.bench_function(format!("{}cm_60_frames", (voxel * 100.0).round()), |b| {
            b.iter(|| {
                let mut map = TsdfMap::new(voxel);
                for f in &frames {
                    map.integrate(&TsdfFrame {
                        depth: &f.depth,
                        color: &f.color,
                        labels: None,
                        label_gains: None,
                        camera: &f.camera,
                        world_from_camera: &f.world_from_camera,
                    });
                }
                map.blocks.len()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, integrate);
criterion_main!(benches);
