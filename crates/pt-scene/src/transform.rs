//! `<transform>` elements: `translate`, `rotate`, `scale`, `matrix` and `lookat`, composed as
//! Mitsuba does: each operation is applied after the ones before it (left-multiplied), so
//! `<scale/><rotate/><translate/>` maps a point p to `T * R * S * p`.
//!
//! Matrices act on column vectors; angles are in degrees; rotations are right-handed (counter-
//! clockwise looking down the axis towards the origin).

use crate::error::{Result, SceneError};
use crate::props::{parse_f32, parse_floats};
use crate::xml::Element;
use glam::{Mat3, Mat4, Vec3, Vec4};

/// Parses a `<transform>` element into the matrix it describes.
pub(crate) fn parse_transform(el: &Element) -> Result<Mat4> {
    let mut m = Mat4::IDENTITY;
    for op in &el.children {
        if let Some(c) = op.children.first() {
            return Err(SceneError::at(
                &c.loc,
                format!("<{}> cannot contain elements", op.tag),
            ));
        }
        m = parse_op(op)? * m;
    }
    Ok(m)
}

fn parse_op(op: &Element) -> Result<Mat4> {
    match op.tag.as_str() {
        "translate" => {
            op.check_attrs(&["value", "x", "y", "z"], &[])?;
            Ok(Mat4::from_translation(xyz(op, 0.0)?))
        }
        "scale" => {
            op.check_attrs(&["value", "x", "y", "z"], &[])?;
            Ok(Mat4::from_scale(xyz(op, 1.0)?))
        }
        "rotate" => rotate(op),
        "matrix" => matrix(op),
        "lookat" => lookat(op),
        "lookAt" => Err(SceneError::at(
            &op.loc,
            "unknown transform operation <lookAt> (write <lookat>; camelCase is only accepted in \
             scenes with version < 2.0.0)",
        )),
        other => Err(SceneError::at(
            &op.loc,
            format!(
                "<{other}> cannot occur inside a <transform> (expected translate, rotate, scale, \
                 matrix or lookat)"
            ),
        )),
    }
}

/// Reads a 3-vector from `value="x, y, z"` (or one number for all three) or from separate
/// `x`, `y`, `z` attributes, where a missing component is `default`.
pub(crate) fn xyz(el: &Element, default: f32) -> Result<Vec3> {
    let err = |m: String| SceneError::at(&el.loc, m);
    let separate = ["x", "y", "z"].map(|k| el.attr(k));
    if let Some(text) = el.attr("value") {
        if separate.iter().any(Option::is_some) {
            return Err(err("cannot mix 'value' with 'x'/'y'/'z' attributes".into()));
        }
        return match parse_floats(text).map_err(err)?[..] {
            [v] => Ok(Vec3::splat(v)),
            [x, y, z] => Ok(Vec3::new(x, y, z)),
            _ => Err(err(format!("expected one or three numbers in '{text}'"))),
        };
    }
    let mut v = [default; 3];
    for (slot, text) in v.iter_mut().zip(separate) {
        if let Some(t) = text {
            *slot = parse_f32(t).map_err(err)?;
        }
    }
    Ok(Vec3::from_array(v))
}

fn rotate(op: &Element) -> Result<Mat4> {
    op.check_attrs(&["value", "x", "y", "z", "angle"], &["angle"])?;
    let axis = xyz(op, 0.0)?;
    let angle =
        parse_f32(op.attr("angle").unwrap_or_default()).map_err(|m| SceneError::at(&op.loc, m))?;
    let unit = axis.try_normalize().ok_or_else(|| {
        SceneError::at(
            &op.loc,
            "rotation axis is zero (give x, y, z or value=\"ax, ay, az\")",
        )
    })?;
    Ok(Mat4::from_axis_angle(unit, angle.to_radians()))
}

/// `value` holds 16 numbers (4x4, row by row) or 9 (the 3x3 linear part).
fn matrix(op: &Element) -> Result<Mat4> {
    op.check_attrs(&["value"], &["value"])?;
    let text = op.attr("value").unwrap_or_default();
    let v = parse_floats(text).map_err(|m| SceneError::at(&op.loc, m))?;
    match v.len() {
        // glam stores columns; the file lists rows, hence the transpose.
        16 => {
            let mut a = [0.0; 16];
            a.copy_from_slice(&v);
            Ok(Mat4::from_cols_array(&a).transpose())
        }
        9 => {
            let mut a = [0.0; 9];
            a.copy_from_slice(&v);
            Ok(Mat4::from_mat3(Mat3::from_cols_array(&a).transpose()))
        }
        n => Err(SceneError::at(
            &op.loc,
            format!("<matrix> needs 16 or 9 numbers, got {n}"),
        )),
    }
}

/// Mitsuba's look-at: the result maps the local frame (left, up, forward) to world space, with
/// forward (+z) towards `target` and the origin at `origin`. Without `up`, any perpendicular
/// direction is used, as in Mitsuba.
fn lookat(op: &Element) -> Result<Mat4> {
    op.check_attrs(&["origin", "target", "up"], &["origin", "target"])?;
    let origin = named_vec3(op, "origin")?;
    let target = named_vec3(op, "target")?;
    let up = match op.attr("up") {
        Some(_) => named_vec3(op, "up")?,
        None => Vec3::ZERO,
    };
    look_at(origin, target, up).map_err(|m| SceneError::at(&op.loc, m))
}

/// The look-at matrix with columns (left, new_up, dir, origin). A zero `up` means "any".
pub(crate) fn look_at(origin: Vec3, target: Vec3, up: Vec3) -> std::result::Result<Mat4, String> {
    let dir = (target - origin)
        .try_normalize()
        .ok_or("'origin' and 'target' are the same point")?;
    let up = if up == Vec3::ZERO {
        dir.any_orthonormal_vector()
    } else {
        up
    };
    let left = up
        .cross(dir)
        .try_normalize()
        .ok_or("'up' is parallel to the viewing direction (target - origin)")?;
    let new_up = dir.cross(left);
    Ok(Mat4::from_cols(
        left.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        origin.extend(1.0),
    ))
}

fn named_vec3(op: &Element, name: &str) -> Result<Vec3> {
    let text = op.attr(name).unwrap_or_default();
    match parse_floats(text).map_err(|m| SceneError::at(&op.loc, format!("'{name}': {m}")))?[..] {
        [x, y, z] => Ok(Vec3::new(x, y, z)),
        _ => Err(SceneError::at(
            &op.loc,
            format!("'{name}' needs three numbers, got '{text}'"),
        )),
    }
}

/// Whether `m` is affine (last row 0, 0, 0, 1): points can then be mapped without a divide.
pub(crate) fn is_affine(m: &Mat4) -> bool {
    m.row(3) == Vec4::W
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn op(tag: &str, attrs: &[(&str, &str)]) -> Element {
        Element {
            tag: tag.into(),
            attrs: attrs
                .iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect(),
            children: vec![],
            loc: Default::default(),
            dir: PathBuf::new(),
        }
    }

    fn transform(ops: Vec<Element>) -> Mat4 {
        let mut t = op("transform", &[("name", "to_world")]);
        t.children = ops;
        parse_transform(&t).unwrap()
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).abs().max_element() < 1e-5
    }

    #[test]
    fn rotate_is_right_handed() {
        let m = transform(vec![op("rotate", &[("z", "1"), ("angle", "90")])]);
        assert!(close(m.transform_point3(Vec3::X), Vec3::Y));
        let m = transform(vec![op("rotate", &[("value", "1, 0, 0"), ("angle", "90")])]);
        assert!(close(m.transform_point3(Vec3::Y), Vec3::Z));
    }

    #[test]
    fn later_operations_apply_after_earlier_ones() {
        // Scale, then rotate about z, then translate.
        let m = transform(vec![
            op("scale", &[("value", "2")]),
            op("rotate", &[("z", "1"), ("angle", "90")]),
            op("translate", &[("x", "10")]),
        ]);
        assert!(close(
            m.transform_point3(Vec3::X),
            Vec3::new(10.0, 2.0, 0.0)
        ));
    }

    #[test]
    fn scale_components_default_to_one() {
        let m = transform(vec![op("scale", &[("y", "3")])]);
        assert!(close(
            m.transform_point3(Vec3::ONE),
            Vec3::new(1.0, 3.0, 1.0)
        ));
    }

    #[test]
    fn matrix_is_row_major() {
        let m = transform(vec![op(
            "matrix",
            &[("value", "1 0 0 5  0 1 0 6  0 0 1 7  0 0 0 1")],
        )]);
        assert!(close(
            m.transform_point3(Vec3::ZERO),
            Vec3::new(5.0, 6.0, 7.0)
        ));
        let m3 = transform(vec![op("matrix", &[("value", "0 -1 0, 1 0 0, 0 0 1")])]);
        assert!(close(m3.transform_point3(Vec3::X), Vec3::Y));
    }

    #[test]
    fn lookat_frame() {
        let m = transform(vec![op(
            "lookat",
            &[
                ("origin", "1, 2, 3"),
                ("target", "1, 2, 4"),
                ("up", "0, 1, 0"),
            ],
        )]);
        assert!(close(
            m.transform_point3(Vec3::ZERO),
            Vec3::new(1.0, 2.0, 3.0)
        ));
        assert!(close(m.transform_vector3(Vec3::Z), Vec3::Z));
        assert!(close(m.transform_vector3(Vec3::Y), Vec3::Y));
        // Camera +x is "left": up x dir = y x z = +x.
        assert!(close(m.transform_vector3(Vec3::X), Vec3::X));
    }

    #[test]
    fn lookat_without_up_is_orthonormal() {
        let m = look_at(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0), Vec3::ZERO).unwrap();
        let l = Mat3::from_mat4(m);
        assert!((l.determinant() - 1.0).abs() < 1e-5);
    }

    #[test]
    fn bad_operations_are_errors() {
        let bad = |e: Element| {
            let mut t = op("transform", &[("name", "to_world")]);
            t.children = vec![e];
            parse_transform(&t).is_err()
        };
        assert!(bad(op(
            "lookat",
            &[("origin", "0,0,0"), ("target", "0,1,0"), ("up", "0,1,0")]
        )));
        assert!(bad(op(
            "lookat",
            &[("origin", "0,0,0"), ("target", "0,0,0")]
        )));
        assert!(bad(op("rotate", &[("angle", "30")])));
        assert!(bad(op("rotate", &[("x", "1")])));
        assert!(bad(op("translate", &[("value", "1 2")])));
        assert!(bad(op("translate", &[("value", "1"), ("x", "2")])));
        assert!(bad(op("translate", &[("x", "nan")])));
        assert!(bad(op("matrix", &[("value", "1 2 3")])));
        assert!(bad(op("shear", &[])));
    }
}
