use iscene::io::Sequence;
use iscene::panoptic::*;
use iscene::segmentation::oracle::OracleSegmentation;
fn main() {
    let seq = Sequence::open(std::path::Path::new("out/kitchen.sequence")).unwrap();
    let oracle = OracleSegmentation::for_sequence(&seq).unwrap();
    let params = MapperParams::new(0.02, InstanceFusion::Joint);
    let bar = indicatif::ProgressBar::hidden();
    let mapper = map_sequence(&seq, Some(&oracle), &params, &bar).unwrap();
    let classes = ClassIds::builtin();
    let wall = classes.id("wall").unwrap();
    let scene = extract_entities(&mapper.tsdf, &mapper.instances, &classes, &ExtractionParams::default());
    for e in &scene.entities { if e.class == "wall" || e.class == "ceiling" {
        println!("{} voxels {} labels {}", e.id, e.surface_voxels, e.labels.len());
        for l in e.labels.iter().take(12) { println!("   {l}: {:?}", mapper.instances.votes(*l)); }
    }}
    let _ = wall;
}
