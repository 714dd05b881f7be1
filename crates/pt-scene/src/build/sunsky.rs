//! Mitsuba's `sunsky` emitter (Hosek-Wilkie sun and sky), with Mitsuba 3.9.1's parameters and
//! defaults: `turbidity` 3 (in [1, 10]), `albedo` 0.3 (each value in [0, 1]), the sun from
//! `sun_direction` (world) or from `latitude` 35.6894, `longitude` 139.6917, `timezone` 9,
//! `year` 2010, `month` 7, `day` 10, `hour` 15, `minute` 0, `second` 0 (Tokyo, a summer
//! afternoon), never both; `sun_scale` and `sky_scale` 1 (not negative), `sun_aperture` 0.5358
//! degrees (in (0, 180)), `complex_sun` false, `to_world` (a rotation).

use super::emitter::rotation_of;
use super::*;
use pt_sky::solar::{sun_direction, DateTime, Location};

/// The date and place properties, any of which selects the date-and-place form.
const TIME_AND_PLACE: [&str; 9] = [
    "latitude",
    "longitude",
    "timezone",
    "year",
    "month",
    "day",
    "hour",
    "minute",
    "second",
];

/// Reads a `sunsky` emitter's properties; `to_world` is its `to_world` property.
pub(super) fn sunsky(v: &ObjectView<'_>, to_world: Option<Mat4>) -> Result<SunSkyDesc> {
    let rotation = match to_world {
        Some(m) => rotation_of(v, &m, "the sky's to_world")?,
        None => Mat3::IDENTITY,
    };
    let non_negative = |name: &str| -> Result<f32> {
        let x = v.float(name)?.unwrap_or(1.0);
        if !(x >= 0.0) {
            return Err(v.prop_error(name, format!("{name} must not be negative")));
        }
        Ok(x)
    };
    let turbidity = v.float("turbidity")?.unwrap_or(3.0);
    if !(1.0..=10.0).contains(&turbidity) {
        return Err(v.prop_error("turbidity", "turbidity must be in [1, 10]"));
    }
    let albedo = v.spectrum("albedo")?.unwrap_or(SpectrumDesc::Constant(0.3));
    if albedo.values().iter().any(|a| !(0.0..=1.0).contains(a)) {
        return Err(v.prop_error("albedo", "the ground albedo must be in [0, 1]"));
    }
    let sun_aperture_deg = v.float("sun_aperture")?.unwrap_or(0.5358);
    if !(sun_aperture_deg > 0.0 && sun_aperture_deg < 180.0) {
        return Err(v.prop_error("sun_aperture", "sun_aperture must be in (0, 180) degrees"));
    }
    let sun_local = match v.vec3("sun_direction")? {
        Some(d) => {
            if let Some(name) = TIME_AND_PLACE.iter().find(|n| v.has(n)) {
                return Err(v.prop_error(
                    name,
                    "give either sun_direction or a date and place, not both (as Mitsuba)",
                ));
            }
            let d = d
                .try_normalize()
                .ok_or_else(|| v.prop_error("sun_direction", "sun_direction must not be zero"))?;
            // World to the sky's frame.
            rotation.transpose() * d
        }
        None => {
            let f = |name: &str, default: f32| -> Result<f64> {
                Ok(v.float(name)?.unwrap_or(default) as f64)
            };
            let int =
                |name: &str, default: i64, range: std::ops::RangeInclusive<i64>| -> Result<i32> {
                    let x = v.integer(name)?.unwrap_or(default);
                    if !range.contains(&x) {
                        return Err(v.prop_error(
                            name,
                            format!("{name} must be in [{}, {}]", range.start(), range.end()),
                        ));
                    }
                    Ok(x as i32)
                };
            let latitude = f("latitude", 35.6894)?;
            if !(-90.0..=90.0).contains(&latitude) {
                return Err(v.prop_error("latitude", "latitude must be in [-90, 90] degrees"));
            }
            let place = Location {
                latitude,
                longitude: f("longitude", 139.6917)?,
                timezone: f("timezone", 9.0)?,
            };
            let date = DateTime {
                year: int("year", 2010, -4000..=100_000)?,
                month: int("month", 7, 1..=12)?,
                day: int("day", 10, 1..=31)?,
                hour: f("hour", 15.0)?,
                minute: f("minute", 0.0)?,
                second: f("second", 0.0)?,
            };
            sun_direction(&date, &place)
        }
    };
    Ok(SunSkyDesc {
        sun_local,
        to_world: rotation,
        turbidity,
        albedo,
        sun_scale: non_negative("sun_scale")?,
        sky_scale: non_negative("sky_scale")?,
        sun_aperture_deg,
        complex_sun: v.boolean("complex_sun")?.unwrap_or(false),
    })
}
