//! Closest point on a triangle (Ericson, Real-Time Collision Detection, 5.1.5).

use glam::Vec3;

/// The point of triangle `[a, b, c]` closest to `p`.
pub fn closest_point_on_triangle(p: Vec3, [a, b, c]: [Vec3; 3]) -> Vec3 {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn closest_point_is_no_farther_than_any_vertex_or_sample(
            px in -2.0f32..2.0, py in -2.0f32..2.0, pz in -2.0f32..2.0,
            u in 0.0f32..1.0, v in 0.0f32..1.0,
        ) {
            let tri = [Vec3::ZERO, Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
            let p = Vec3::new(px, py, pz);
            let q = closest_point_on_triangle(p, tri);
            let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
            let sample = tri[0] + (tri[1] - tri[0]) * u + (tri[2] - tri[0]) * v;
            prop_assert!(p.distance(q) <= p.distance(sample) + 1e-5);
            prop_assert!(q.z.abs() < 1e-6 && q.x >= -1e-6 && q.y >= -1e-6 && q.x + q.y <= 1.0 + 1e-5);
        }
    }
}
