//! One voxel of the TSDF: signed distance, weight, colour and the segment-label vote, 16 bytes.

/// A global segment label; 0 = none.
pub type SegmentLabel = u32;

/// Weights are stored in fixed point, this many steps per unit of weight: a voxel stays 16 bytes,
/// four to a cache line (integration streams every voxel of a touched block through the cache),
/// and 1/64 is far finer than the weight drop-off needs.
pub(super) const WEIGHT_STEPS: f32 = 64.0;

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Voxel {
    /// Signed distance in metres (positive in front of the surface: see `tsdf`).
    pub sdf: f32,
    /// Accumulated integration weight in steps of 1/`WEIGHT_STEPS`; 0 = never observed.
    pub(super) weight: u16,
    /// How far `label` leads the vote (Voxblox++'s label confidence), in weight steps.
    pub(super) label_weight: u16,
    /// The segment label that won the vote so far; 0 = none.
    pub label: SegmentLabel,
    pub color: [u8; 3],
}

const _: () = assert!(std::mem::size_of::<Voxel>() == 16);

impl Voxel {
    /// A voxel observed with `weight`, its label leading the vote by the same weight.
    pub fn observed(sdf: f32, weight: f32, color: [u8; 3], label: SegmentLabel) -> Self {
        let steps = weight_steps(weight);
        Self {
            sdf,
            weight: steps,
            label_weight: steps,
            label,
            color,
        }
    }

    /// Accumulated integration weight; 0 = never observed.
    pub fn weight(&self) -> f32 {
        f32::from(self.weight) / WEIGHT_STEPS
    }

    /// Observed free space: the distance at `sdf` (the truncation), no colour, no label.
    pub(super) fn free(sdf: f32, weight_steps: u16) -> Self {
        Self {
            sdf,
            weight: weight_steps,
            ..Self::default()
        }
    }

    pub fn is_observed(&self) -> bool {
        self.weight > 0
    }

    /// How far `label` leads the vote.
    pub fn label_weight(&self) -> f32 {
        f32::from(self.label_weight) / WEIGHT_STEPS
    }
}

/// `weight` in fixed-point steps, at least one step (a measurement that fuses counts) and at
/// most what a `u16` holds.
pub(super) fn weight_steps(weight: f32) -> u16 {
    (weight * WEIGHT_STEPS + 0.5).clamp(1.0, f32::from(u16::MAX)) as u16
}
