//! MJCF's XML values: child elements by tag, element positions for errors, number lists,
//! Euler sequences and the pose attributes bodies and geoms share.

use glam::{Affine3A, EulerRot, Mat3, Quat, Vec3};
use roxmltree::Node;

use crate::base::InvalidValue;

/// Child elements of `node` named `tag`.
pub fn elements<'a, 'input>(
    node: Node<'a, 'input>,
    tag: &'static str,
) -> impl Iterator<Item = Node<'a, 'input>> {
    node.children()
        .filter(move |c| c.is_element() && c.tag_name().name() == tag)
}

/// `<tag>` at line N, for errors.
pub fn at(node: Node) -> String {
    let pos = node.document().text_pos_at(node.range().start);
    format!("<{}> at line {}", node.tag_name().name(), pos.row)
}

/// The rotation order of a `eulerseq`: lowercase letters turn about the rotating axes
/// (intrinsic, glam's plain orders), uppercase about the fixed ones (glam's `Ex` orders).
pub fn euler_order(seq: &str) -> Option<EulerRot> {
    use EulerRot::*;
    Some(match seq {
        "xyz" => XYZ,
        "XYZ" => XYZEx,
        "zyx" => ZYX,
        "ZYX" => ZYXEx,
        "zxy" => ZXY,
        "ZXY" => ZXYEx,
        "xzy" => XZY,
        "XZY" => XZYEx,
        "yxz" => YXZ,
        "YXZ" => YXZEx,
        "yzx" => YZX,
        "YZX" => YZXEx,
        _ => return None,
    })
}

/// An element's pose in its parent's frame: `pos` and one of the orientation attributes.
pub fn pose(node: Node, degrees: bool, euler: EulerRot) -> Result<Affine3A, InvalidValue> {
    let translation = match node.attribute("pos") {
        Some(s) => vec3(node, "pos", s)?,
        None => Vec3::ZERO,
    };
    let unit = if degrees {
        std::f32::consts::PI / 180.0
    } else {
        1.0
    };
    let rotation = if let Some(s) = node.attribute("quat") {
        let [w, x, y, z] = numbers::<4>(node, "quat", s)?;
        let q = Quat::from_xyzw(x, y, z, w);
        if q.length() < 1e-9 {
            return Err(InvalidValue::at(at(node), "quat is zero"));
        }
        q.normalize()
    } else if let Some(s) = node.attribute("axisangle") {
        let [x, y, z, a] = numbers::<4>(node, "axisangle", s)?;
        let axis = Vec3::new(x, y, z);
        if axis.length() < 1e-9 {
            return Err(InvalidValue::at(at(node), "axisangle has a zero axis"));
        }
        Quat::from_axis_angle(axis.normalize(), a * unit)
    } else if let Some(s) = node.attribute("euler") {
        let [a, b, c] = numbers::<3>(node, "euler", s)?;
        Quat::from_euler(euler, a * unit, b * unit, c * unit)
    } else if let Some(s) = node.attribute("xyaxes") {
        let v = numbers::<6>(node, "xyaxes", s)?;
        let x = Vec3::new(v[0], v[1], v[2]).normalize_or_zero();
        let y = Vec3::new(v[3], v[4], v[5]);
        let y = (y - x * x.dot(y)).normalize_or_zero();
        if x == Vec3::ZERO || y == Vec3::ZERO {
            return Err(InvalidValue::at(
                at(node),
                "xyaxes are not two independent axes",
            ));
        }
        Quat::from_mat3(&Mat3::from_cols(x, y, x.cross(y)))
    } else if let Some(s) = node.attribute("zaxis") {
        let z = vec3(node, "zaxis", s)?;
        if z.length() < 1e-9 {
            return Err(InvalidValue::at(at(node), "zaxis is zero"));
        }
        Quat::from_rotation_arc(Vec3::Z, z.normalize())
    } else {
        Quat::IDENTITY
    };
    Ok(Affine3A::from_rotation_translation(rotation, translation))
}

/// The numbers of attribute `name` (its `text`) of `node`.
pub fn parse_numbers(node: Node, name: &str, text: &str) -> Result<Vec<f32>, InvalidValue> {
    text.split_whitespace()
        .map(|t| {
            t.parse::<f32>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| InvalidValue::at(at(node), format!("{name}: {t:?} is not a number")))
        })
        .collect()
}

/// Exactly `N` numbers of attribute `name` (its `text`) of `node`.
pub fn numbers<const N: usize>(
    node: Node,
    name: &str,
    text: &str,
) -> Result<[f32; N], InvalidValue> {
    let values = parse_numbers(node, name, text)?;
    <[f32; N]>::try_from(values.as_slice()).map_err(|_| {
        InvalidValue::at(
            at(node),
            format!("{name} has {} numbers, not {N}", values.len()),
        )
    })
}

/// Three numbers of attribute `name` (its `text`) of `node`.
pub fn vec3(node: Node, name: &str, text: &str) -> Result<Vec3, InvalidValue> {
    numbers::<3>(node, name, text).map(Vec3::from)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose_of(attributes: &str, degrees: bool) -> Result<Affine3A, InvalidValue> {
        let text = format!("<geom {attributes}/>");
        let doc = roxmltree::Document::parse(&text).expect("XML");
        pose(doc.root_element(), degrees, EulerRot::XYZ)
    }

    #[test]
    fn orientations_are_read_as_mujoco_reads_them() {
        // quat is w first: a quarter turn about z takes x to y.
        let q = pose_of(r#"pos="1 2 3" quat="0.7071068 0 0 0.7071068""#, false).expect("quat");
        assert!((q.transform_vector3(Vec3::X) - Vec3::Y).length() < 1e-5);
        assert_eq!(Vec3::from(q.translation), Vec3::new(1.0, 2.0, 3.0));
        // Degrees by default; axisangle and euler agree on a quarter turn about z.
        for attributes in [
            r#"axisangle="0 0 1 90""#,
            r#"euler="0 0 90""#,
            r#"zaxis="0 0 1""#,
        ] {
            let p = pose_of(attributes, true).expect(attributes);
            let expected = if attributes.starts_with("zaxis") {
                Vec3::X
            } else {
                Vec3::Y
            };
            assert!(
                (p.transform_vector3(Vec3::X) - expected).length() < 1e-5,
                "{attributes}"
            );
        }
        // Intrinsic x then y (MuJoCo's default "xyz"), R = Rx Ry: x goes to -z under Ry, then
        // to y under Rx. Turning about the fixed axes instead would leave it at -z.
        let e = pose_of(r#"euler="1.5707964 1.5707964 0""#, false).expect("euler");
        assert!((e.transform_vector3(Vec3::X) - Vec3::Y).length() < 1e-5);
        // xyaxes: the frame's x and y axes; z follows.
        let xy = pose_of(r#"xyaxes="0 1 0 -1 0 0""#, false).expect("xyaxes");
        assert!((xy.transform_vector3(Vec3::Z) - Vec3::Z).length() < 1e-5);
        assert!((xy.transform_vector3(Vec3::X) - Vec3::Y).length() < 1e-5);
        let bad = pose_of(r#"pos="0 zero 0""#, false).expect_err("bad");
        assert_eq!(bad.key, "<geom> at line 1");
        assert_eq!(
            bad.to_string(),
            r#"<geom> at line 1: pos: "zero" is not a number"#
        );
    }
}
