//! The sun's position in the sky at a date, time and place: the PSA algorithm of Blanco-Muriel,
//! Alarcon-Padilla, Lopez-Moratalla and Lara-Coira, "Computing the solar vector", Solar Energy
//! 70(5), 2001 (stated accuracy 0.5 arc minutes over 1999-2015), as Mitsuba's `sunsky` uses it
//! (with its parallax correction, Earth radius over the astronomical unit).
//!
//! Evaluated in double precision. Mitsuba 3.9.1 evaluates it in single precision, where the
//! Julian date (about 2.46e6) is rounded to quarter days; the hour angle uses the exact hour,
//! so its sun differs from this one by a few hundredths of a degree (up to 0.032 degrees in the
//! cases tested), a tenth of the sun's radius.

use glam::Vec3;
use std::f64::consts::{PI, TAU};

/// A place on Earth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Location {
    /// Latitude, degrees north.
    pub latitude: f64,
    /// Longitude, degrees east.
    pub longitude: f64,
    /// Offset of local time from UTC, hours.
    pub timezone: f64,
}

/// A local date and time (Gregorian calendar).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DateTime {
    /// Year.
    pub year: i32,
    /// Month, 1-12.
    pub month: i32,
    /// Day of the month, 1-31.
    pub day: i32,
    /// Hour, local time (fractions allowed).
    pub hour: f64,
    /// Minute.
    pub minute: f64,
    /// Second.
    pub second: f64,
}

/// Mean radius of the Earth, km.
const EARTH_MEAN_RADIUS: f64 = 6371.01;
/// Astronomical unit, km.
const ASTRONOMICAL_UNIT: f64 = 149_597_890.0;

/// Unit direction towards the sun in the frame of Mitsuba's `sunsky` (z up, x towards the
/// south, y towards the west), and whether it is above the horizon.
pub fn sun_direction(t: &DateTime, at: &Location) -> Vec3 {
    // Universal time of day, decimal hours.
    let hours = t.hour - at.timezone + (t.minute + t.second / 60.0) / 60.0;
    // Julian day number (integer arithmetic truncating, as in the paper).
    let aux1 = (t.month - 14) / 12;
    let aux2 = (1461 * (t.year + 4800 + aux1)) / 4 + (367 * (t.month - 2 - 12 * aux1)) / 12
        - (3 * ((t.year + 4900 + aux1) / 100)) / 4
        + t.day
        - 32075;
    let julian_date = aux2 as f64 - 0.5 + hours / 24.0;
    // Days since noon UT, 1 January 2000.
    let n = julian_date - 2_451_545.0;

    // Ecliptic coordinates, radians.
    let omega = 2.1429 - 0.001_039_459_4 * n;
    let mean_longitude = 4.895_063 + 0.017_202_791_698 * n;
    let mean_anomaly = 6.240_06 + 0.017_201_969_9 * n;
    let ecliptic_longitude = mean_longitude
        + 0.033_416_07 * mean_anomaly.sin()
        + 0.000_348_94 * (2.0 * mean_anomaly).sin()
        - 0.000_113_4
        - 0.000_020_3 * omega.sin();
    let obliquity = 0.409_092_8 - 6.214e-9 * n + 0.000_039_6 * omega.cos();

    // Celestial coordinates.
    let sin_lon = ecliptic_longitude.sin();
    let mut right_ascension = (obliquity.cos() * sin_lon).atan2(ecliptic_longitude.cos());
    if right_ascension < 0.0 {
        right_ascension += TAU;
    }
    let declination = (obliquity.sin() * sin_lon).asin();

    // Local coordinates: zenith angle and azimuth (from north, through east).
    let gmst = 6.697_424_324_2 + 0.065_709_828_3 * n + hours;
    let lmst = (gmst * 15.0 + at.longitude).to_radians();
    let lat = at.latitude.to_radians();
    let hour_angle = lmst - right_ascension;
    let mut zenith = (lat.cos() * hour_angle.cos() * declination.cos()
        + declination.sin() * lat.sin())
    .clamp(-1.0, 1.0)
    .acos();
    let mut azimuth =
        (-hour_angle.sin()).atan2(declination.tan() * lat.cos() - lat.sin() * hour_angle.cos());
    if azimuth < 0.0 {
        azimuth += TAU;
    }
    // Parallax.
    zenith += EARTH_MEAN_RADIUS / ASTRONOMICAL_UNIT * zenith.sin();

    // Mitsuba's frame: spherical angles (zenith, azimuth - pi) about +z.
    let phi = azimuth - PI;
    Vec3::new(
        (zenith.sin() * phi.cos()) as f32,
        (zenith.sin() * phi.sin()) as f32,
        zenith.cos() as f32,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noon_sun_is_due_south_at_the_solstice_elevation() {
        // Greenwich, June solstice 2026, solar noon is near 12:02 UT: the sun is close to the
        // meridian (azimuth within ~1 degree of south) at 90 - 51.48 + 23.44 = 61.96 degrees
        // elevation (within the equation of time's few tenths of a degree).
        let d = sun_direction(
            &DateTime {
                year: 2026,
                month: 6,
                day: 21,
                hour: 12.0,
                minute: 2.0,
                second: 0.0,
            },
            &Location {
                latitude: 51.48,
                longitude: 0.0,
                timezone: 0.0,
            },
        );
        let elevation = d.z.asin().to_degrees();
        assert!((elevation - 61.96).abs() < 0.1, "elevation {elevation}");
        // South is +x in this frame.
        assert!(d.x > 0.0 && d.y.abs() / d.x < 0.02, "{d:?}");
    }
}
