use iscene::io::Sequence;
use iscene::panoptic::geometric::{segment_depth, GeometricParams};
use iscene::panoptic::fusion::{fuse_masks, FusionParams};
use iscene::segmentation::oracle::OracleSegmentation;
use iscene::segmentation::SegmentationService;
fn main() {
    let seq = Sequence::open(std::path::Path::new("out/kitchen.sequence")).unwrap();
    let oracle = OracleSegmentation::for_sequence(&seq).unwrap();
    let (mut pure, mut total, mut fpure, mut ftotal) = (0usize, 0usize, 0usize, 0usize);
    for k in (0..300).step_by(10) {
        let f = seq.load_frame(k).unwrap();
        let labels = f.labels.clone().unwrap();
        let g = segment_depth(&f.depth, &f.camera, &GeometricParams::default());
        let masks = oracle.segment(&f).unwrap();
        let fused = fuse_masks(&g, &masks, &FusionParams::default());
        for (segs, n, p, t) in [(&g.segment_of_pixel, g.count as usize, &mut pure, &mut total), (&fused.segment_of_pixel, fused.segments.len(), &mut fpure, &mut ftotal)] {
            let mut counts = vec![std::collections::BTreeMap::<u16, usize>::new(); n + 1];
            for (i, &s) in segs.iter().enumerate() { if s != 0 { *counts[s as usize].entry(labels[i]).or_default() += 1; } }
            for (s, c) in counts.iter().enumerate().skip(1) {
                let sum: usize = c.values().sum(); let best = c.values().max().copied().unwrap_or(0);
                *t += sum; *p += best;
                if sum > 3000 && (best as f64) < 0.9 * sum as f64 { println!("frame {k} seg {s}: {c:?}"); }
            }
        }
    }
    println!("geometric purity {:.4} fused purity {:.4}", pure as f64 / total as f64, fpure as f64 / ftotal as f64);
}
