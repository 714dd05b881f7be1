//! IES photometric files (ANSI/IES LM-63: the 1986, 1991, 1995, 2002 and 2019 editions),
//! read into an [`IntensityTable`]: the luminaire's radiant intensity over directions.
//!
//! A file is a first line naming the edition (`IESNA:LM-63-2002`; none for 1986), keyword lines
//! (`[MANUFAC] ...`), a `TILT=` line, then numbers separated by white space or commas over any
//! number of lines:
//!
//! | numbers | meaning |
//! |---|---|
//! | 10 | lamps, lumens per lamp, candela multiplier, vertical angle count `nv`, horizontal angle count `nh`, photometric type (1 = C, 2 = B, 3 = A), units (1 feet, 2 metres), width, length, height of the luminous opening |
//! | 3 | ballast factor, ballast-lamp photometric factor (1991, 1995; "future use" in 2002, the file generation type in 2019), input watts |
//! | `nv` | vertical angles, degrees, increasing |
//! | `nh` | horizontal angles, degrees, increasing |
//! | `nv` x `nh` | candelas: for each horizontal angle, one value per vertical angle |
//!
//! `TILT=INCLUDE` puts the lamp-tilt table (geometry, count `n`, `n` angles, `n` factors)
//! before the first line of the table above; it, and a tilt table in another file, is read past and
//! not applied: pt assumes the lamp burns in the position it was measured in.
//!
//! **Conversion.** Each candela value is multiplied by the candela multiplier and the ballast
//! factor (and by the ballast-lamp photometric factor in the editions where the field is one)
//! and used as it is: 1 cd becomes an intensity whose luminance Y is 1 per sr, the convention
//! of pt's glTF lights (the `gltf` module: the scene is then in photometric units and a pixel
//! holds luminance in cd/m^2). Dividing by 683 lm/W would give watts only for 555 nm light and
//! is not done. The light's colour (its luminance divided out) and `scale` apply on top
//! (scenes/README.md, "Photometric lights").
//!
//! **Angles (type C, the photometry of architectural luminaires).** The vertical angle gamma is
//! measured from the luminaire's nadir, which is the light's local +z (the axis a `spot`
//! shines along), the horizontal angle C from local +x towards local +y, so the direction is
//! (sin gamma cos C, sin gamma sin C, cos gamma). Between tabulated angles the intensity is
//! linear in gamma and in C (bilinear over the table's cells); beyond the first or last vertical
//! angle it is zero. The horizontal angles say the luminaire's symmetry (LM-63-2002, 5.13):
//! a single angle 0 is symmetric about the nadir axis, 0..90 about the planes C = 0-180 and
//! C = 90-270, 0..180 about the plane C = 0-180, 90..270 about the plane C = 90-270, 0..360
//! has none. Types A and B (floodlights, vehicle lamps) are refused.

use crate::ir::IntensityTable;
use glam::Mat3;

/// Why an IES file was refused: the 1-based line, and what is wrong there.
#[derive(Debug, Clone, PartialEq)]
pub struct IesError {
    /// 1-based line of the file the problem is on (the last line for a file that ends early).
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

/// The edition of LM-63 a file follows, from its first line.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Edition {
    Lm63_1986,
    Lm63_1991,
    Lm63_1995,
    Lm63_2002,
    Lm63_2019,
}

/// The numbers of a file after its `TILT=` line, each with its line.
struct Numbers {
    values: Vec<(f64, usize)>,
    next: usize,
    last_line: usize,
}

impl Numbers {
    fn take(&mut self, what: &str) -> Result<(f64, usize), IesError> {
        let v = self
            .values
            .get(self.next)
            .copied()
            .ok_or_else(|| IesError {
                line: self.last_line,
                message: format!("the file ends before {what}"),
            })?;
        self.next += 1;
        Ok(v)
    }

    fn count(&mut self, what: &str) -> Result<usize, IesError> {
        let (v, line) = self.take(what)?;
        if v.fract() != 0.0 || !(1.0..=100_000.0).contains(&v) {
            return Err(IesError {
                line,
                message: format!("{what} must be a whole number from 1 to 100000, not {v}"),
            });
        }
        Ok(v as usize)
    }
}

/// Parses an IES file's text (as read from disk; Latin-1 bytes outside ASCII are fine in
/// keyword lines) into its intensity table, `scale` not yet applied.
pub fn parse_ies(text: &str) -> Result<IntensityTable, IesError> {
    let (edition, tilt, mut nums) = split_file(text)?;
    if tilt == "INCLUDE" {
        nums.take("the lamp-to-luminaire geometry of the tilt table")?;
        let n = nums.count("the number of tilt angles")?;
        for _ in 0..2 * n {
            nums.take("the end of the tilt table")?;
        }
    }
    let (nv, nh, factor) = read_header(&mut nums, edition)?;
    let vertical = increasing_angles(&mut nums, nv, "vertical")?;
    let horizontal = increasing_angles(&mut nums, nh, "horizontal")?;
    let (v0, v0_line) = vertical[0];
    let (v1, v1_line) = vertical[nv - 1];
    if v0 < 0.0 || v1 > 180.0 {
        let line = if v0 < 0.0 { v0_line } else { v1_line };
        return Err(IesError {
            line,
            message: format!(
                "type C vertical angles lie in [0, 180] degrees, these run from {v0} to {v1}"
            ),
        });
    }
    let symmetry = Symmetry::of(&horizontal)?;
    let candela = read_candela(&mut nums, nv, nh)?;
    Ok(full_circle(
        &vertical,
        &horizontal,
        symmetry,
        &candela,
        factor,
    ))
}

/// The edition a file's first line names (none: 1986).
fn edition(first: &str) -> Edition {
    let head = first.trim().to_ascii_uppercase();
    if head.starts_with("IESNA:LM-63-2002") {
        Edition::Lm63_2002
    } else if head.starts_with("IESNA:LM-63-1995") {
        Edition::Lm63_1995
    } else if head.starts_with("IESNA91") {
        Edition::Lm63_1991
    } else if head.starts_with("IES:LM-63-2019") || head.starts_with("IESNA:LM-63-2019") {
        Edition::Lm63_2019
    } else {
        Edition::Lm63_1986
    }
}

/// A file's edition, its `TILT=` value (upper case) and the numbers after that line.
fn split_file(text: &str) -> Result<(Edition, String, Numbers), IesError> {
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l));
    let (first_no, first) = lines.next().ok_or_else(|| IesError {
        line: 1,
        message: "the file is empty".into(),
    })?;
    let edition = edition(first);
    // Keyword lines up to TILT= (the 1986 edition's first line is already a free-form one).
    let mut tilt = None;
    let header = std::iter::once((first_no, first)).filter(|_| edition == Edition::Lm63_1986);
    let mut last_line = first_no;
    for (no, line) in header.chain(&mut lines) {
        last_line = no;
        let t = line.trim_start();
        if let Some(rest) = t.strip_prefix("TILT=").or_else(|| t.strip_prefix("TILT =")) {
            tilt = Some(rest.trim().to_ascii_uppercase());
            break;
        }
    }
    let tilt = tilt.ok_or_else(|| IesError {
        line: last_line,
        message: "no TILT= line (every LM-63 file has one before its photometric data)".into(),
    })?;
    let mut values = Vec::new();
    for (no, line) in lines {
        last_line = no;
        for token in line
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|s| !s.is_empty())
        {
            let v: f64 = token.parse().map_err(|_| IesError {
                line: no,
                message: format!("'{token}' is not a number"),
            })?;
            if !v.is_finite() {
                return Err(IesError {
                    line: no,
                    message: format!("'{token}' is not a finite number"),
                });
            }
            values.push((v, no));
        }
    }
    let nums = Numbers {
        values,
        next: 0,
        last_line,
    };
    Ok((edition, tilt, nums))
}

/// The 13 numbers before the angles: the vertical and horizontal angle counts and the factor
/// every candela value is multiplied by (module doc, "Conversion"); refuses photometric
/// types other than C and negative factors.
fn read_header(nums: &mut Numbers, edition: Edition) -> Result<(usize, usize, f64), IesError> {
    let _lamps = nums.take("the number of lamps")?;
    let _lumens = nums.take("the lumens per lamp")?;
    let (multiplier, m_line) = nums.take("the candela multiplier")?;
    let nv = nums.count("the number of vertical angles")?;
    let nh = nums.count("the number of horizontal angles")?;
    let (kind, kind_line) = nums.take("the photometric type")?;
    match kind as i64 {
        1 if kind == 1.0 => {}
        2 | 3 if kind.fract() == 0.0 => {
            return Err(IesError {
                line: kind_line,
                message: format!(
                    "photometric type {} ({}) is not supported: pt reads type C (1), the photometry of architectural luminaires",
                    kind,
                    if kind == 2.0 { "B" } else { "A" }
                ),
            })
        }
        _ => {
            return Err(IesError {
                line: kind_line,
                message: format!("the photometric type must be 1 (C), 2 (B) or 3 (A), not {kind}"),
            })
        }
    }
    for what in [
        "the units type",
        "the luminous opening's width",
        "its length",
        "its height",
    ] {
        nums.take(what)?;
    }
    let (ballast, b_line) = nums.take("the ballast factor")?;
    let (lamp_factor, l_line) = nums.take("the ballast-lamp photometric factor")?;
    let _watts = nums.take("the input watts")?;
    for (v, line, name) in [
        (multiplier, m_line, "candela multiplier"),
        (ballast, b_line, "ballast factor"),
    ] {
        if v < 0.0 {
            return Err(IesError {
                line,
                message: format!("the {name} must not be negative, not {v}"),
            });
        }
    }
    // The second field multiplies only where it is the ballast-lamp photometric factor.
    let lamp_factor = match edition {
        Edition::Lm63_1986 | Edition::Lm63_1991 | Edition::Lm63_1995 => {
            if lamp_factor < 0.0 {
                return Err(IesError {
                    line: l_line,
                    message: format!(
                        "the ballast-lamp photometric factor must not be negative, not {lamp_factor}"
                    ),
                });
            }
            lamp_factor
        }
        Edition::Lm63_2002 | Edition::Lm63_2019 => 1.0,
    };
    Ok((nv, nh, multiplier * ballast * lamp_factor))
}

/// The next `n` numbers as strictly increasing `what` ("vertical", "horizontal") angles in
/// degrees, each with its line.
fn increasing_angles(
    nums: &mut Numbers,
    n: usize,
    what: &str,
) -> Result<Vec<(f64, usize)>, IesError> {
    let mut a: Vec<(f64, usize)> = Vec::with_capacity(n);
    for _ in 0..n {
        let (v, line) = nums.take(&format!("the {n} {what} angles"))?;
        if let Some(&(prev, _)) = a.last() {
            if !(v > prev) {
                return Err(IesError {
                    line,
                    message: format!("{what} angles must increase ({prev} then {v})"),
                });
            }
        }
        a.push((v, line));
    }
    Ok(a)
}

/// The `nv` x `nh` candela values (column by column: one per vertical angle for each
/// horizontal angle), which must be the file's last numbers.
fn read_candela(nums: &mut Numbers, nv: usize, nh: usize) -> Result<Vec<f64>, IesError> {
    let mut candela = Vec::with_capacity(nv * nh);
    for _ in 0..nv * nh {
        let (v, line) = nums.take(&format!("the {} candela values", nv * nh))?;
        if v < 0.0 {
            return Err(IesError {
                line,
                message: format!("candela values must not be negative, not {v}"),
            });
        }
        candela.push(v);
    }
    if let Some(&(v, line)) = nums.values.get(nums.next) {
        return Err(IesError {
            line,
            message: format!(
                "{v} follows the {} candela values the header announces ({nv} vertical x {nh} horizontal angles)",
                nv * nh
            ),
        });
    }
    Ok(candela)
}

/// The intensity table over the full circle of azimuths from the measured `vertical` and
/// `horizontal` angles (degrees) and `candela` columns, each value times `factor`.
fn full_circle(
    vertical: &[(f64, usize)],
    horizontal: &[(f64, usize)],
    symmetry: Symmetry,
    candela: &[f64],
    factor: f64,
) -> IntensityTable {
    let nv = vertical.len();
    // The full circle of azimuths: every image of a measured angle under the symmetry, each
    // taking the measured column it is an image of (so linear interpolation between the new
    // nodes is linear interpolation between measured angles, mirrored).
    let mut columns: Vec<(f64, usize)> = Vec::new();
    for (j, &(h, _)) in horizontal.iter().enumerate() {
        for image in symmetry.images(h) {
            let c = image.rem_euclid(360.0);
            if !columns.iter().any(|&(x, _)| (x - c).abs() < 1e-6) {
                columns.push((c, j));
            }
        }
    }
    columns.sort_by(|a, b| a.0.total_cmp(&b.0));
    let theta: Vec<f32> = vertical
        .iter()
        .map(|&(v, _)| v.to_radians() as f32)
        .collect();
    let phi: Vec<f32> = columns
        .iter()
        .map(|&(c, _)| c.to_radians() as f32)
        .collect();
    let mut values = Vec::with_capacity(nv * columns.len());
    for i in 0..nv {
        for &(_, j) in &columns {
            values.push((candela[j * nv + i] * factor) as f32);
        }
    }
    IntensityTable {
        theta,
        phi,
        values,
        axes: Mat3::IDENTITY,
    }
}

/// The symmetries LM-63 type C files declare through their horizontal angles.
#[derive(Clone, Copy, Debug)]
enum Symmetry {
    /// One angle: the same in every vertical plane.
    Axial,
    /// 0..90: mirror planes C = 0-180 and C = 90-270.
    Quadrant,
    /// 0..180: mirror plane C = 0-180.
    Bilateral0,
    /// 90..270: mirror plane C = 90-270.
    Bilateral90,
    /// 0..360: none (the 360 column repeats the 0 one).
    None,
}

impl Symmetry {
    /// The symmetry the first and last of the (increasing) `horizontal` angles declare, or
    /// the error naming the first angle's line.
    fn of(horizontal: &[(f64, usize)]) -> Result<Symmetry, IesError> {
        let (h0, h0_line) = horizontal[0];
        let (h1, _) = horizontal[horizontal.len() - 1];
        Ok(match (h0, h1) {
            (a, b) if a == 0.0 && b == 0.0 => Symmetry::Axial,
            (a, b) if a == 0.0 && b == 90.0 => Symmetry::Quadrant,
            (a, b) if a == 0.0 && b == 180.0 => Symmetry::Bilateral0,
            (a, b) if a == 90.0 && b == 270.0 => Symmetry::Bilateral90,
            (a, b) if a == 0.0 && b == 360.0 => Symmetry::None,
            _ => {
                return Err(IesError {
                    line: h0_line,
                    message: format!(
                        "type C horizontal angles must run 0 (one angle), 0-90, 0-180, 90-270 or 0-360 degrees, not {h0}-{h1}"
                    ),
                })
            }
        })
    }

    /// The azimuths (degrees, any turn) that carry the same intensity as the measured `c`.
    fn images(self, c: f64) -> Vec<f64> {
        match self {
            Symmetry::Axial => vec![0.0],
            Symmetry::Quadrant => vec![c, -c, 180.0 - c, 180.0 + c],
            Symmetry::Bilateral0 => vec![c, -c],
            Symmetry::Bilateral90 => vec![c, 180.0 - c],
            Symmetry::None => vec![c],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An LM-63-2002 file of a luminaire with `h` horizontal angles over vertical 0, 45, 90.
    fn file(h: &[f64], candela: &[f64]) -> String {
        let hs: Vec<String> = h.iter().map(|x| x.to_string()).collect();
        let cs: Vec<String> = candela.iter().map(|x| x.to_string()).collect();
        format!(
            "IESNA:LM-63-2002\n[TEST] unit test\n[MANUFAC] pt\nTILT=NONE\n1 1000 2 3 {} 1 2 0.1 0.1 0\n0.5 1 50\n0 45 90\n{}\n{}\n",
            h.len(),
            hs.join(" "),
            cs.join(" ")
        )
    }

    #[test]
    fn reads_an_axial_file_and_converts_candela() {
        let t = parse_ies(&file(&[0.0], &[300.0, 150.0, 0.0])).unwrap();
        assert_eq!(t.phi, vec![0.0]);
        assert_eq!(t.theta.len(), 3);
        // 300 cd x multiplier 2 x ballast 0.5 = 300 per sr.
        assert!((t.values[0] - 300.0).abs() < 1e-4, "{:?}", t.values);
        assert!((t.values[1] - 150.0).abs() < 1e-4);
    }

    #[test]
    fn symmetries_fill_the_circle_with_mirrored_columns() {
        // Quadrant: columns at 0, 45, 90 become 0, 45, 90, 135, 180, 225, 270, 315.
        let c: Vec<f64> = (0..9).map(|k| k as f64).collect();
        let t = parse_ies(&file(&[0.0, 45.0, 90.0], &c)).unwrap();
        let deg: Vec<f32> = t.phi.iter().map(|p| p.to_degrees().round()).collect();
        assert_eq!(deg, vec![0., 45., 90., 135., 180., 225., 270., 315.]);
        // At vertical index 1 the measured columns hold 1, 4, 7; 135 mirrors 45, 180 mirrors 0.
        let row: Vec<f32> = t.values[8..16].to_vec();
        assert_eq!(row, vec![1., 4., 7., 4., 1., 4., 7., 4.]);
        // Bilateral about 90-270: measured 90, 180, 270.
        let t = parse_ies(&file(&[90.0, 180.0, 270.0], &c)).unwrap();
        let deg: Vec<f32> = t.phi.iter().map(|p| p.to_degrees().round()).collect();
        assert_eq!(deg, vec![0., 90., 180., 270.]);
        let row: Vec<f32> = t.values[4..8].to_vec();
        // 0 mirrors 180 (4), 90 is 1, 180 is 4, 270 is 7.
        assert_eq!(row, vec![4., 1., 4., 7.]);
        // Full circle: the 360 column is the 0 one.
        let c: Vec<f64> = (0..12).map(|k| k as f64).collect();
        let t = parse_ies(&file(&[0.0, 120.0, 240.0, 360.0], &c)).unwrap();
        assert_eq!(t.phi.len(), 3);
    }

    #[test]
    fn older_editions_apply_the_ballast_lamp_factor_and_tilt_tables_are_skipped() {
        let text = "IESNA:LM-63-1995\nTILT=INCLUDE\n1\n2\n0 90\n1 1\n1 -1 1 2 1 1 2 0 0 0\n1 0.5 10\n0 90\n0\n100 100\n";
        let t = parse_ies(text).unwrap();
        assert!((t.values[0] - 50.0).abs() < 1e-4, "{:?}", t.values);
    }

    #[test]
    fn malformed_files_name_the_line() {
        let ok = file(&[0.0], &[1.0, 2.0, 3.0]);
        let cases = [
            (ok.replace("TILT=NONE", "TILT NONE"), 9, "TILT"),
            (ok.replace("0 45 90", "0 45 x"), 7, "'x'"),
            (ok.replace("0 45 90", "0 90 45"), 7, "increase"),
            (ok.replace("1 2 0.1", "2 2 0.1"), 5, "(B)"),
            (ok.replace("\n1 2 3\n", "\n1 2\n"), 9, "ends before"),
            (ok.replace("\n1 2 3\n", "\n1 2 3 4\n"), 9, "follows"),
            (ok.replace("\n1 2 3\n", "\n1 -2 3\n"), 9, "negative"),
            (
                file(&[0.0, 45.0], &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]),
                8,
                "0-45",
            ),
        ];
        for (text, line, words) in cases {
            let e = parse_ies(&text).unwrap_err();
            assert_eq!(e.line, line, "{e:?}");
            assert!(e.message.contains(words), "{e:?}");
        }
    }
}
