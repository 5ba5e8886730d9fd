//! Kinect-like depth noise, and the noise settings of a scene specification.
//!
//! The depth model follows Nguyen, Izadi and Lovell (3DIMPVT 2012) for axial noise,
//! sigma(z) = 0.0012 + 0.0019 (z - 0.4)^2 metres, and the structured-light disparity
//! quantisation of Smisek et al. (2011): depth is measured as a disparity in 1/8 pixel steps over
//! a 7.5 cm baseline, so the depth step grows with z^2. Pixels drop out beyond the range limits,
//! at grazing angles, next to depth edges, and at random.

use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use crate::render::pose_noise::{PoseNoise, PoseNoiseSetting, PosePreset};
use crate::segmentation::noise::{SegmentationNoise, SegmentationNoiseSetting, SegmentationPreset};

/// Parameters of the depth noise model. Angles in degrees, lengths in metres.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DepthNoise {
    pub min_range: f32,
    pub max_range: f32,
    /// sigma(z) = axial_base + axial_quadratic * (z - axial_offset)^2.
    pub axial_base: f32,
    pub axial_quadratic: f32,
    pub axial_offset: f32,
    /// Projector-camera baseline of the disparity quantisation; 0 turns quantisation off.
    pub baseline: f32,
    /// Disparity step in pixels (1/8 for the Kinect).
    pub disparity_step: f32,
    /// Incidence angle (between the view ray and the surface normal) where dropouts begin...
    pub grazing_start_deg: f32,
    /// ...and where every pixel drops out; the probability rises linearly in between.
    pub grazing_end_deg: f32,
    /// A neighbour this much nearer or farther (relative to depth) makes a pixel a depth edge.
    pub edge_jump_ratio: f32,
    pub edge_dropout: f32,
    pub random_dropout: f32,
}

impl Default for DepthNoise {
    fn default() -> Self {
        Self::KINECT
    }
}

impl DepthNoise {
    pub const KINECT: DepthNoise = DepthNoise {
        min_range: 0.5,
        max_range: 4.5,
        axial_base: 0.0012,
        axial_quadratic: 0.0019,
        axial_offset: 0.4,
        baseline: 0.075,
        disparity_step: 0.125,
        grazing_start_deg: 70.0,
        grazing_end_deg: 85.0,
        edge_jump_ratio: 0.05,
        edge_dropout: 0.6,
        random_dropout: 0.002,
    };

    /// Standard deviation of the axial noise at depth `z`.
    pub fn axial_sigma(&self, z: f32) -> f32 {
        self.axial_base + self.axial_quadratic * (z - self.axial_offset).powi(2)
    }

    /// Depth quantisation step at depth `z` for focal length `fx` (0 when quantisation is off).
    pub fn quantisation_step(&self, z: f32, fx: f32) -> f32 {
        if self.baseline <= 0.0 || self.disparity_step <= 0.0 {
            return 0.0;
        }
        z * z * self.disparity_step / (fx * self.baseline)
    }

    /// Probability that a pixel seeing a surface at incidence angle `angle_deg` drops out.
    pub fn grazing_dropout(&self, angle_deg: f32) -> f32 {
        let span = (self.grazing_end_deg - self.grazing_start_deg).max(1e-3);
        ((angle_deg - self.grazing_start_deg) / span).clamp(0.0, 1.0)
    }

    /// Applies the model to a clean depth image in place. `cos_incidence[i]` is |cos| of the angle
    /// between pixel i's view ray and the surface normal; `fx` is the focal length in pixels.
    pub fn apply(
        &self,
        depth: &mut [f32],
        cos_incidence: &[f32],
        width: usize,
        fx: f32,
        rng: &mut impl Rng,
    ) {
        let height = depth.len() / width.max(1);
        let clean = depth.to_vec();
        let cos_start = self.grazing_start_deg.to_radians().cos();
        let is_edge = |i: usize| {
            let z = clean[i];
            let (x, y) = (i % width, i / width);
            let mut neighbours = [None; 4];
            if x > 0 {
                neighbours[0] = Some(i - 1);
            }
            if x + 1 < width {
                neighbours[1] = Some(i + 1);
            }
            if y > 0 {
                neighbours[2] = Some(i - width);
            }
            if y + 1 < height {
                neighbours[3] = Some(i + width);
            }
            neighbours.into_iter().flatten().any(|j| {
                let n = clean[j];
                n == 0.0 || (n - z).abs() > self.edge_jump_ratio * z
            })
        };
        for i in 0..depth.len() {
            let z = clean[i];
            // Draw every random number for every pixel, so that one parameter's change does not
            // reshuffle the others' outcomes.
            let u_grazing: f32 = rng.random();
            let u_edge: f32 = rng.random();
            let u_random: f32 = rng.random();
            let normal: f32 = StandardNormal.sample(rng);
            if z == 0.0 || z < self.min_range || z > self.max_range {
                depth[i] = 0.0;
                continue;
            }
            // Most pixels face the camera well within the dropout band: skip the arc cosine.
            let cos = cos_incidence[i].clamp(0.0, 1.0);
            let grazing = if cos >= cos_start {
                0.0
            } else {
                self.grazing_dropout(cos.acos().to_degrees())
            };
            if u_grazing < grazing
                || u_random < self.random_dropout
                || (u_edge < self.edge_dropout && is_edge(i))
            {
                depth[i] = 0.0;
                continue;
            }
            let noisy = z + self.axial_sigma(z) * normal;
            let step = self.quantisation_step(noisy, fx);
            // Quantise in disparity, which is linear in 1/z; the axial noise before it dithers the
            // steps, so the error stays close to zero-mean.
            let measured = if step > 0.0 {
                let disparity_unit = fx * self.baseline / self.disparity_step;
                let d = (disparity_unit / noisy).round();
                if d > 0.0 { disparity_unit / d } else { 0.0 }
            } else {
                noisy
            };
            // The sensor reports nothing outside its range, whatever the noise did.
            depth[i] = if (self.min_range..=self.max_range).contains(&measured) {
                measured
            } else {
                0.0
            };
        }
    }
}

/// The noise of a generated room (`generate`, `benchmark --noise`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum NoiseChoice {
    /// Kinect depth, realistic segmentation and a tracker's poses.
    #[default]
    Realistic,
    /// Exact depth, labels and poses.
    Clean,
}

impl NoiseChoice {
    pub fn settings(self) -> NoiseSettings {
        match self {
            Self::Realistic => NoiseSettings::realistic(),
            Self::Clean => NoiseSettings::off(),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::Realistic => "realistic",
            Self::Clean => "clean",
        }
    }

    /// The `noise` object of a specification.
    pub fn to_json(self) -> serde_json::Value {
        serde_json::to_value(self.settings()).unwrap_or_default()
    }
}

/// A depth noise setting: a preset name or explicit parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum DepthNoiseSetting {
    Preset(DepthPreset),
    Custom(DepthNoise),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DepthPreset {
    Kinect,
    None,
}

/// The `noise` object of a scene specification.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NoiseSettings {
    #[serde(default = "NoiseSettings::default_depth")]
    pub depth: DepthNoiseSetting,
    #[serde(default = "NoiseSettings::default_segmentation")]
    pub segmentation: SegmentationNoiseSetting,
    /// Camera pose noise of a tracker; off unless asked for (`"pose": "tracker"`).
    #[serde(default = "NoiseSettings::default_pose")]
    pub pose: PoseNoiseSetting,
}

impl Default for NoiseSettings {
    fn default() -> Self {
        Self {
            depth: Self::default_depth(),
            segmentation: Self::default_segmentation(),
            pose: Self::default_pose(),
        }
    }
}

impl NoiseSettings {
    fn default_depth() -> DepthNoiseSetting {
        DepthNoiseSetting::Preset(DepthPreset::Kinect)
    }

    fn default_segmentation() -> SegmentationNoiseSetting {
        SegmentationNoiseSetting::Preset(SegmentationPreset::Realistic)
    }

    fn default_pose() -> PoseNoiseSetting {
        PoseNoiseSetting::Preset(PosePreset::None)
    }

    /// No noise at all (the `--no-noise` switch).
    pub fn off() -> Self {
        Self {
            depth: DepthNoiseSetting::Preset(DepthPreset::None),
            segmentation: SegmentationNoiseSetting::Preset(SegmentationPreset::None),
            pose: Self::default_pose(),
        }
    }

    /// Kinect depth, realistic segmentation and a tracker's poses.
    pub fn realistic() -> Self {
        Self {
            depth: DepthNoiseSetting::Preset(DepthPreset::Kinect),
            segmentation: SegmentationNoiseSetting::Preset(SegmentationPreset::Realistic),
            pose: PoseNoiseSetting::Preset(PosePreset::Tracker),
        }
    }

    pub fn pose_model(&self) -> Option<PoseNoise> {
        self.pose.model()
    }

    /// The depth model to apply, or `None` for clean depth.
    pub fn depth_model(&self) -> Option<DepthNoise> {
        match &self.depth {
            DepthNoiseSetting::Preset(DepthPreset::Kinect) => Some(DepthNoise::KINECT),
            DepthNoiseSetting::Preset(DepthPreset::None) => None,
            DepthNoiseSetting::Custom(params) => Some(*params),
        }
    }

    pub fn segmentation_model(&self) -> Option<SegmentationNoise> {
        self.segmentation.model()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn dropped_fraction(model: &DepthNoise, depth: f32, angle_deg: f32) -> f32 {
        let n = 200 * 200;
        let mut d = vec![depth; n];
        let cos = vec![angle_deg.to_radians().cos(); n];
        model.apply(&mut d, &cos, 200, 525.0, &mut ChaCha8Rng::seed_from_u64(5));
        d.iter().filter(|&&v| v == 0.0).count() as f32 / n as f32
    }

    #[test]
    fn dropouts_follow_incidence_angle_and_range() {
        let model = DepthNoise {
            edge_dropout: 0.0,
            random_dropout: 0.0,
            ..DepthNoise::KINECT
        };
        assert_eq!(dropped_fraction(&model, 2.0, 30.0), 0.0);
        let half = dropped_fraction(&model, 2.0, 77.5);
        assert!(
            (half - 0.5).abs() < 0.02,
            "half-way through the grazing band: {half}"
        );
        assert_eq!(dropped_fraction(&model, 2.0, 88.0), 1.0);
        assert_eq!(
            dropped_fraction(&model, 0.3, 0.0),
            1.0,
            "closer than the minimum range"
        );
        assert_eq!(
            dropped_fraction(&model, 6.0, 0.0),
            1.0,
            "beyond the maximum range"
        );
    }

    #[test]
    fn depth_edges_drop_out_at_their_rate() {
        let model = DepthNoise {
            random_dropout: 0.0,
            ..DepthNoise::KINECT
        };
        let (w, h) = (100, 100);
        // Left half at 1 m, right half at 2 m: columns 49 and 50 are edge pixels.
        let mut d: Vec<f32> = (0..w * h)
            .map(|i| if i % w < 50 { 1.0 } else { 2.0 })
            .collect();
        let cos = vec![1.0; w * h];
        model.apply(&mut d, &cos, w, 525.0, &mut ChaCha8Rng::seed_from_u64(8));
        let dropped =
            |col: usize| (0..h).filter(|r| d[r * w + col] == 0.0).count() as f32 / h as f32;
        assert!(
            (dropped(49) - model.edge_dropout).abs() < 0.15,
            "edge column dropped {}",
            dropped(49)
        );
        assert_eq!(dropped(20), 0.0, "no dropout away from edges");
    }
}
