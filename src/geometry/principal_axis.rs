//! The principal axis of points in a plane: the direction of largest spread (the major axis of
//! their 2x2 covariance), through their mean.

use glam::Vec2;

/// The mean of `points` and their principal direction (unit, sign arbitrary); `None` without
/// points.
pub fn principal_axis(points: &[Vec2]) -> Option<(Vec2, Vec2)> {
    if points.is_empty() {
        return None;
    }
    let mean = points.iter().copied().sum::<Vec2>() / points.len() as f32;
    let (mut xx, mut xy, mut yy) = (0.0, 0.0, 0.0);
    for q in points {
        let d = *q - mean;
        xx += d.x * d.x;
        xy += d.x * d.y;
        yy += d.y * d.y;
    }
    Some((mean, Vec2::from_angle(0.5 * (2.0 * xy).atan2(xx - yy))))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_along_a_line_give_its_direction_and_middle() {
        let points: Vec<Vec2> = (0..=10)
            .map(|i| Vec2::new(1.0, 2.0) + Vec2::new(3.0, 4.0) * (0.1 * i as f32))
            .collect();
        let (mean, axis) = principal_axis(&points).expect("axis");
        assert!((mean - Vec2::new(2.5, 4.0)).length() < 1e-5, "{mean}");
        assert!(axis.dot(Vec2::new(0.6, 0.8)).abs() > 0.9999, "{axis}");
        assert!(principal_axis(&[]).is_none());
    }
}
