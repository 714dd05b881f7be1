//! Mitsuba's curve files (`linearcurve`, `bsplinecurve`): text, one control point per line as
//! four numbers `x y z radius`; a blank line ends a curve. A linear curve needs at least two
//! control points, a B-spline at least four (Mitsuba 3.9.1's rules). Positions go through
//! `to_world`; radii do not (Mitsuba documents them as invariant to it).

use crate::ir::{CurveBasis, Curves};
use glam::{Mat4, Vec3, Vec4};
use std::io::BufRead;

/// Reads the curve file at `path` (named `shown_name` in errors, which give the line).
pub(crate) fn load_curves(
    path: &std::path::Path,
    shown_name: &str,
    basis: CurveBasis,
    to_world: &Mat4,
) -> Result<Curves, String> {
    let file = std::fs::File::open(path).map_err(|e| {
        format!(
            "cannot open curve file '{shown_name}': {}",
            crate::error::io_message(&e)
        )
    })?;
    read_curves(std::io::BufReader::new(file), basis, to_world).map_err(|e| match e {
        CurveError::Io(e) => format!(
            "cannot read curve file '{shown_name}': {}",
            crate::error::io_message(&e)
        ),
        CurveError::Line(line, msg) => format!("curve file '{shown_name}', line {line}: {msg}"),
        CurveError::File(msg) => format!("curve file '{shown_name}': {msg}"),
    })
}

/// Why a curve file was refused.
#[derive(Debug)]
pub(crate) enum CurveError {
    /// The system could not read it.
    Io(std::io::Error),
    /// A line (1-based) that is not valid.
    Line(usize, String),
    /// The file as a whole (no control points).
    File(String),
}

/// Reads curves from `reader` (see the module documentation).
pub(crate) fn read_curves(
    mut reader: impl BufRead,
    basis: CurveBasis,
    to_world: &Mat4,
) -> Result<Curves, CurveError> {
    let need = basis.points_per_segment();
    let mut points: Vec<Vec4> = Vec::new();
    let mut segments = Vec::new();
    // The first control point of the curve being read, and the line it is on.
    let mut curve: Option<(usize, usize)> = None;
    let mut finish = |curve: &mut Option<(usize, usize)>, n_points: usize| {
        if let Some((first, line)) = curve.take() {
            let count = n_points - first;
            if count < need {
                let kind = match basis {
                    CurveBasis::Linear => "a linear curve needs at least 2",
                    CurveBasis::BSpline => "a B-spline curve needs at least 4",
                };
                return Err(CurveError::Line(
                    line,
                    format!("the curve starting here has {count} control point(s); {kind}"),
                ));
            }
            segments.extend((first..=n_points - need).map(|i| i as u32));
        }
        Ok(())
    };
    let mut line = String::new();
    for line_number in 1.. {
        line.clear();
        if reader.read_line(&mut line).map_err(CurveError::Io)? == 0 {
            break;
        }
        let text = line.trim();
        if text.is_empty() {
            finish(&mut curve, points.len())?;
            continue;
        }
        let fail = |msg: String| CurveError::Line(line_number, msg);
        let numbers = text
            .split_whitespace()
            .map(|w| {
                w.parse::<f32>()
                    .map_err(|_| fail(format!("'{w}' is not a number")))
            })
            .collect::<Result<Vec<f32>, _>>()?;
        let [x, y, z, r] = numbers[..] else {
            return Err(fail(format!(
                "expected four numbers (x y z radius), found {}",
                numbers.len()
            )));
        };
        let p = to_world.transform_point3(Vec3::new(x, y, z));
        if !p.is_finite() {
            return Err(fail(format!("the control point {p} is not finite")));
        }
        if !(r.is_finite() && r >= 0.0) {
            return Err(fail(format!("the radius {r} is not a finite number >= 0")));
        }
        if points.len() >= u32::MAX as usize {
            return Err(fail("more than 2^32 control points".into()));
        }
        curve.get_or_insert((points.len(), line_number));
        points.push(p.extend(r));
    }
    finish(&mut curve, points.len())?;
    if points.is_empty() {
        return Err(CurveError::File("no control points".into()));
    }
    Ok(Curves {
        basis,
        points,
        segments,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str, basis: CurveBasis) -> Result<Curves, String> {
        read_curves(text.as_bytes(), basis, &Mat4::IDENTITY).map_err(|e| match e {
            CurveError::Line(l, m) => format!("line {l}: {m}"),
            CurveError::File(m) => m,
            CurveError::Io(e) => e.to_string(),
        })
    }

    /// Mitsuba's documentation example: two linear curves (2 and 4 control points) give 1 + 3
    /// segments; blank lines (with spaces, several in a row, at the end) separate curves.
    #[test]
    fn reads_mitsubas_example() {
        let text = "-1.0 0.1 0.1 0.5\n 1.0 1.4 1.2 0.5\n\n  \n-1.0 5.0 2.2 1\n-2.3 4.0 2.3 2\n\t4.0 1.0 2.2 5\n 4.0 0.0 2.3 6\n\n";
        let c = read(text, CurveBasis::Linear).unwrap();
        assert_eq!(c.points.len(), 6);
        assert_eq!(c.segments, vec![0, 2, 3, 4]);
        assert_eq!(c.points[5], Vec4::new(4.0, 0.0, 2.3, 6.0));
        assert_eq!(c.segment(1), &c.points[2..4]);
        // As B-splines, the second curve has one segment and the first is too short.
        let e = read(text, CurveBasis::BSpline).unwrap_err();
        assert!(e.contains("line 1") && e.contains("at least 4"), "{e}");
        let c = read(&text[text.find("-1.0 5.0").unwrap()..], CurveBasis::BSpline).unwrap();
        assert_eq!(c.segments, vec![0]);
        assert_eq!(c.segment(0).len(), 4);
    }

    /// `to_world` moves the positions and leaves the radii alone.
    #[test]
    fn to_world_moves_points_not_radii() {
        let m = Mat4::from_scale_rotation_translation(
            Vec3::splat(2.0),
            glam::Quat::from_rotation_z(std::f32::consts::FRAC_PI_2),
            Vec3::new(1.0, 0.0, 0.0),
        );
        let c = read_curves("1 0 0 0.25\n2 0 0 0.5\n".as_bytes(), CurveBasis::Linear, &m).unwrap();
        assert!((c.points[0] - Vec4::new(1.0, 2.0, 0.0, 0.25)).length() < 1e-6);
        assert!((c.points[1] - Vec4::new(1.0, 4.0, 0.0, 0.5)).length() < 1e-6);
    }

    /// Bad lines are refused with their line number and what is wrong.
    #[test]
    fn refuses_bad_lines() {
        for (text, want) in [
            ("0 0 0 1\n0 0 1\n", "line 2: expected four numbers"),
            ("0 0 0 1\n0 0 1 1 1\n", "line 2: expected four numbers"),
            ("0 0 0 1\n0 zero 1 1\n", "line 2: 'zero' is not a number"),
            ("0 0 0 1\n0 0 1 -1\n", "line 2: the radius -1"),
            ("0 0 0 1\n0 0 1 nan\n", "line 2: the radius NaN"),
            ("0 0 0 1\n0 inf 1 1\n", "line 2: the control point"),
            (
                "0 0 0 1\n0 0 1 1\n\n0 0 0 1\n\n",
                "line 4: the curve starting here has 1",
            ),
            ("\n\n", "no control points"),
            ("", "no control points"),
        ] {
            let e = read(text, CurveBasis::Linear).unwrap_err();
            assert!(e.contains(want), "{text:?}: {e}");
        }
    }
}
