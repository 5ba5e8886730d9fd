//! A frame's label image, kept as runs along its rows: segment labels are constant over long
//! stretches of a row, so a frame takes a few kilobytes instead of 1.2 MB and the mapper can keep
//! every frame's for checks against what each frame saw after mapping (panoptic/carve.rs).

use crate::map::SegmentLabel;

#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FrameLabels {
    width: u32,
    height: u32,
    /// Where each row's runs begin in `run_start` / `run_label`; one more entry than rows.
    row_runs: Vec<u32>,
    /// Each run's first column and its label.
    run_start: Vec<u16>,
    run_label: Vec<SegmentLabel>,
}

impl FrameLabels {
    /// Encodes a row-major `width` x `height` image (at most 65,536 columns).
    pub fn encode(labels: &[SegmentLabel], width: u32, height: u32) -> Self {
        assert_eq!(labels.len(), (width * height) as usize, "label image size");
        assert!(width <= 1 << 16, "rows up to 65,536 pixels");
        let mut encoded = Self {
            width,
            height,
            row_runs: Vec::with_capacity(height as usize + 1),
            run_start: Vec::new(),
            run_label: Vec::new(),
        };
        for row in labels.chunks_exact(width.max(1) as usize) {
            encoded.row_runs.push(encoded.run_start.len() as u32);
            let mut previous = None;
            for (u, &label) in row.iter().enumerate() {
                if previous != Some(label) {
                    encoded.run_start.push(u as u16);
                    encoded.run_label.push(label);
                    previous = Some(label);
                }
            }
        }
        encoded.row_runs.push(encoded.run_start.len() as u32);
        encoded.run_start.shrink_to_fit();
        encoded.run_label.shrink_to_fit();
        encoded
    }

    /// The label at column `u`, row `v` (0 outside the image).
    pub fn at(&self, u: u32, v: u32) -> SegmentLabel {
        if u >= self.width || v >= self.height {
            return 0;
        }
        let runs = self.row_runs[v as usize] as usize..self.row_runs[v as usize + 1] as usize;
        let starts = &self.run_start[runs.clone()];
        // The last run starting at or before u.
        let k = starts.partition_point(|&s| u32::from(s) <= u);
        self.run_label[runs.start + k - 1]
    }

    /// A frame whose labels are not kept: every pixel reads 0 (none).
    pub fn dropped() -> Self {
        Self::default()
    }

    /// Whether the labels were dropped (`dropped`).
    pub fn is_dropped(&self) -> bool {
        self.width == 0
    }

    /// Bytes the runs take.
    pub fn heap_bytes(&self) -> usize {
        self.row_runs.capacity() * 4 + self.run_start.capacity() * 2 + self.run_label.capacity() * 4
    }
}

/// The frames' label images within a budget of bytes: every frame's while they fit; past it,
/// every other kept frame's is dropped and the stride of the frames kept doubles, so the kept
/// ones stay evenly spread along the sequence (frames 0, 2, 4, ..., then 0, 4, 8, ...) and
/// memory stays bounded on a sequence of any length. Which frames are kept depends on the
/// sequence alone (deterministic).
#[derive(Clone, Debug)]
pub struct FrameLabelStore {
    frames: Vec<FrameLabels>,
    budget: usize,
    /// Frames whose index is a multiple of this are kept.
    stride: usize,
    bytes: usize,
}

impl FrameLabelStore {
    pub fn new(budget_bytes: usize) -> Self {
        Self {
            frames: Vec::new(),
            budget: budget_bytes,
            stride: 1,
            bytes: 0,
        }
    }

    /// Every frame's labels so far, in order (a dropped frame's read 0 everywhere).
    pub fn frames(&self) -> &[FrameLabels] {
        &self.frames
    }

    /// Frames whose labels are kept.
    pub fn kept(&self) -> usize {
        self.frames.iter().filter(|f| !f.is_dropped()).count()
    }

    /// Bytes the kept labels take.
    pub fn bytes(&self) -> usize {
        self.bytes
    }

    /// The next frame's labels (`encode`d only when kept).
    pub fn push(&mut self, encode: impl FnOnce() -> FrameLabels) {
        let index = self.frames.len();
        let labels = if index.is_multiple_of(self.stride) {
            encode()
        } else {
            FrameLabels::dropped()
        };
        self.bytes += labels.heap_bytes();
        self.frames.push(labels);
        while self.bytes > self.budget && self.kept() > 1 {
            self.stride *= 2;
            for (i, f) in self.frames.iter_mut().enumerate() {
                if !i.is_multiple_of(self.stride) && !f.is_dropped() {
                    self.bytes -= f.heap_bytes();
                    *f = FrameLabels::dropped();
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Every pixel reads back, and outside the image is 0.
        #[test]
        fn every_pixel_reads_back(
            width in 1u32..40,
            height in 1u32..12,
            seed in any::<u64>(),
        ) {
            let mut state = seed | 1;
            let labels: Vec<SegmentLabel> = (0..width * height)
                .map(|_| {
                    state ^= state << 13;
                    state ^= state >> 7;
                    state ^= state << 17;
                    // Mostly continuing the previous label's run.
                    (state % 3) as SegmentLabel
                })
                .collect();
            let encoded = FrameLabels::encode(&labels, width, height);
            for v in 0..height {
                for u in 0..width {
                    prop_assert_eq!(encoded.at(u, v), labels[(v * width + u) as usize]);
                }
            }
            prop_assert_eq!(encoded.at(width, 0), 0);
            prop_assert_eq!(encoded.at(0, height), 0);
        }
    }

    /// Within the budget every frame's labels are kept; past it the kept ones thin out evenly
    /// (every second, then every fourth frame), the bytes stay within the budget, and a dropped
    /// frame reads 0.
    #[test]
    fn the_store_thins_evenly_past_its_budget() {
        let frame = |k: u32| FrameLabels::encode(&[k + 1, k + 2, k + 2, 7], 2, 2);
        let one = frame(0).heap_bytes();
        let mut store = FrameLabelStore::new(4 * one);
        for k in 0..4 {
            store.push(|| frame(k));
        }
        assert_eq!(store.kept(), 4);
        store.push(|| frame(4));
        assert_eq!(store.bytes(), 3 * one);
        let kept: Vec<usize> = (0..5)
            .filter(|&i| !store.frames()[i].is_dropped())
            .collect();
        assert_eq!(kept, [0, 2, 4]);
        for k in 5..17 {
            store.push(|| frame(k));
            assert!(store.bytes() <= 4 * one, "{} bytes", store.bytes());
        }
        let kept: Vec<usize> = (0..17)
            .filter(|&i| !store.frames()[i].is_dropped())
            .collect();
        assert_eq!(kept, [0, 8, 16]);
        assert_eq!(store.frames()[16].at(0, 0), 17);
        assert_eq!(store.frames()[3].at(0, 0), 0);
    }

    #[test]
    fn a_frame_of_a_few_segments_takes_a_few_kilobytes() {
        let (w, h) = (640u32, 480u32);
        // A wall, a table across the lower half and a cup on it.
        let labels: Vec<SegmentLabel> = (0..w * h)
            .map(|i| {
                let (u, v) = (i % w, i / w);
                match (u, v) {
                    (300..340, 200..260) => 7,
                    (_, 240..) => 3,
                    _ => 1,
                }
            })
            .collect();
        let encoded = FrameLabels::encode(&labels, w, h);
        assert_eq!(encoded.at(320, 230), 7);
        assert_eq!(encoded.at(10, 300), 3);
        assert_eq!(encoded.at(639, 0), 1);
        assert!(
            encoded.heap_bytes() < 12_000,
            "{} bytes",
            encoded.heap_bytes()
        );
    }
}
