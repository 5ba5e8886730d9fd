//! Camera poses as a tracker reports them: a slow random-walk drift plus per-frame jitter, so
//! that mapping is measured with the pose errors of a real tracker rather than exact poses. The
//! frames are rendered from the true poses; the sequence's `pose.txt` files hold the noisy ones.
//! The preset is in the range of RGB-D odometry on TUM RGB-D and 7-Scenes (a centimetre or two
//! of drift over a 300-frame loop, a few millimetres of jitter).

use glam::{Affine3A, Quat, Vec3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use crate::base::{InvalidValue, stable_hash};

/// Parameters of the pose noise. Lengths in metres, angles in degrees, per frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PoseNoise {
    /// Standard deviation of each frame's step of the translation drift (a random walk).
    pub drift_m: f32,
    /// Standard deviation of each frame's step of the rotation drift.
    pub drift_deg: f32,
    /// Standard deviation of the translation jitter of each frame, on top of the drift.
    pub jitter_m: f32,
    pub jitter_deg: f32,
}

impl PoseNoise {
    /// About 1.2 cm and 0.26 degrees of drift after 300 frames (one standard deviation per axis),
    /// 1.5 mm and 0.1 degrees of jitter.
    pub const TRACKER: PoseNoise = PoseNoise {
        drift_m: 0.0007,
        drift_deg: 0.015,
        jitter_m: 0.0015,
        jitter_deg: 0.1,
    };

    /// Checks the parameters: finite, not negative, at most 5 cm or 2 degrees per frame.
    pub fn check(&self) -> Result<(), InvalidValue> {
        let lengths = [self.drift_m, self.jitter_m];
        let angles = [self.drift_deg, self.jitter_deg];
        if lengths.iter().any(|v| !(0.0..=0.05).contains(v))
            || angles.iter().any(|v| !(0.0..=2.0).contains(v))
        {
            return Err(InvalidValue::at(
                "noise.pose",
                format!(
                    "{self:?}: lengths must lie in 0..0.05 m and angles in 0..2 degrees per frame"
                ),
            ));
        }
        Ok(())
    }

    /// The poses a tracker would report for the true `poses`, the same for the same seed.
    pub fn apply(&self, poses: &[Affine3A], seed: u64) -> Vec<Affine3A> {
        let mut rng = ChaCha8Rng::seed_from_u64(stable_hash(seed, "pose-noise"));
        let mut gauss3 = |sigma: f32| {
            let mut v = || -> f32 { StandardNormal.sample(&mut rng) };
            Vec3::new(v(), v(), v()) * sigma
        };
        let mut drift_t = Vec3::ZERO;
        let mut drift_r = Vec3::ZERO;
        poses
            .iter()
            .enumerate()
            .map(|(k, pose)| {
                if k > 0 {
                    drift_t += gauss3(self.drift_m);
                    drift_r += gauss3(self.drift_deg.to_radians());
                }
                let t = drift_t + gauss3(self.jitter_m);
                let r = drift_r + gauss3(self.jitter_deg.to_radians());
                // The first frame defines the map's frame, as a tracker's does, and the map
                // turns about where that camera stood (not about the room's corner, which would
                // turn a degree into ten centimetres across a room).
                if k == 0 {
                    return *pose;
                }
                let centre = Vec3::from(poses[0].translation);
                let error = Affine3A::from_translation(centre + t)
                    * Affine3A::from_quat(Quat::from_scaled_axis(r))
                    * Affine3A::from_translation(-centre);
                error * *pose
            })
            .collect()
    }
}

/// A pose noise setting: a preset name or explicit parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum PoseNoiseSetting {
    Preset(PosePreset),
    Custom(PoseNoise),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PosePreset {
    Tracker,
    None,
}

impl PoseNoiseSetting {
    pub fn model(&self) -> Option<PoseNoise> {
        match self {
            Self::Preset(PosePreset::Tracker) => Some(PoseNoise::TRACKER),
            Self::Preset(PosePreset::None) => None,
            Self::Custom(p) => Some(*p),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tracker_noise_drifts_by_centimetres_and_is_deterministic() {
        let poses: Vec<Affine3A> = (0..300)
            .map(|k| Affine3A::from_translation(Vec3::new(4.0 + 0.01 * k as f32, 3.0, 1.4)))
            .collect();
        let noisy = PoseNoise::TRACKER.apply(&poses, 3);
        assert_eq!(noisy, PoseNoise::TRACKER.apply(&poses, 3));
        assert_ne!(noisy, PoseNoise::TRACKER.apply(&poses, 4));
        assert_eq!(noisy[0], poses[0]);
        let errors: Vec<f32> = noisy
            .iter()
            .zip(&poses)
            .map(|(n, p)| (n.translation - p.translation).length())
            .collect();
        let mean = errors.iter().sum::<f32>() / errors.len() as f32;
        // Centimetres, wherever the room's corner is.
        assert!((0.002..0.04).contains(&mean), "mean error {mean}");
        for n in &noisy {
            let det = glam::Mat3::from(n.matrix3).determinant();
            assert!((det - 1.0).abs() < 1e-4, "rotation stays a rotation: {det}");
        }
    }

    #[test]
    fn parameters_out_of_range_are_refused() {
        let mut p = PoseNoise::TRACKER;
        p.jitter_m = f32::NAN;
        assert!(p.check().is_err());
        p.jitter_m = 0.2;
        assert!(p.check().is_err());
        assert!(PoseNoise::TRACKER.check().is_ok());
    }
}
