//! Emitters: area emitters attached to shapes, and lights on their own (point, spot,
//! directional, sun, constant, environment map).

use super::{SourceLoc, SpectrumDesc, TextureDesc};
use glam::{Mat3, Mat4, Vec3};
use std::path::PathBuf;

/// An area emitter attached to a shape: emits `radiance` from the shape's front side only
/// (the side its normal points to), as Mitsuba's `area` emitter does.
#[derive(Clone, Debug)]
pub struct AreaEmitterDesc {
    /// Where it was defined.
    pub loc: SourceLoc,
    /// Emitted radiance, W sr^-1 m^-2: a constant or a texture over the shape's texture
    /// coordinates (a screen, a monitor; glTF `emissiveFactor` times `emissiveTexture`).
    /// RGB values are emission colours: in spectral mode they are upsampled and multiplied by
    /// D65 (Mitsuba's `d65` texture, which may also be written around the bitmap).
    pub radiance: TextureDesc,
    /// pt extension: spectra of the display's red, green and blue primaries, which the
    /// radiance bitmap's linear RGB drive in spectral mode (see the loader's `area_emitter`).
    pub primaries: Option<Box<[SpectrumDesc; 3]>>,
}

/// An emitter that is not attached to a shape, with where it was defined.
#[derive(Clone, Debug)]
pub struct LightDesc {
    /// Where it was defined.
    pub loc: SourceLoc,
    /// Its type and parameters.
    pub kind: LightKind,
}

/// Emitters not attached to shapes. Directions are unit vectors in world space.
#[derive(Clone, Debug)]
pub enum LightKind {
    /// Point light (Mitsuba `point`): `intensity` in W/sr, inverse-square falloff; isotropic,
    /// or shaped by an intensity profile (pt's `ies` parameter and `goniometric` plugin).
    Point {
        /// Position, world space.
        position: Vec3,
        /// Radiant intensity, W/sr (with an IES profile: its colour only, see
        /// [`IntensityProfile`]).
        intensity: SpectrumDesc,
        /// How the intensity varies over directions, if it does.
        profile: Option<Box<IntensityProfile>>,
    },
    /// Spot light (Mitsuba `spot`): intensity `intensity` (W/sr) on its axis (local +z of
    /// `to_world`), full until `beam_width_deg` off axis, falling linearly in angle to 0 at
    /// `cutoff_deg`.
    Spot {
        /// Light-to-world transform; the light sits at its origin and points along its +z.
        to_world: Mat4,
        /// Radiant intensity on the axis, W/sr.
        intensity: SpectrumDesc,
        /// Angle from the axis beyond which no light leaves, degrees.
        cutoff_deg: f32,
        /// Angle from the axis within which the intensity is full, degrees.
        beam_width_deg: f32,
        /// An image projected through the cone (Mitsuba's `texture`): the intensity is
        /// multiplied by its value at uv = (1/2 + x/(2 z tan(cutoff)), 1/2 + y/(2 z
        /// tan(cutoff))) for the direction (x, y, z) in the light's frame, so the cone's
        /// cross-section is the circle inscribed in the unit uv square.
        texture: Option<TextureDesc>,
        /// An IES profile multiplying the cone's falloff (pt's `ies` parameter), its nadir
        /// along the spot's axis.
        profile: Option<Box<IntensityProfile>>,
    },
    /// A projector (Mitsuba `projector`): a pinhole at the origin of `to_world` casting an
    /// image along its +z axis through a perspective frustum. `irradiance` is the
    /// irradiance (W/m^2, divided by pi) that arrives on the plane z = 1 in the light's frame,
    /// which is covered by the image; Mitsuba's value at a point is
    /// `pi scale E(uv) / (d^2 cos^3 theta)` (theta from the axis).
    Projector {
        /// Light-to-world transform; the projector sits at its origin and points along its +z.
        to_world: Mat4,
        /// The projected image (or a constant).
        irradiance: TextureDesc,
        /// Factor on `irradiance`.
        scale: f32,
        /// Field of view of the frustum, as a camera's (`fov`, `fov_axis`, or `focal_length`).
        projection: super::Projection,
    },
    /// A distant light from one direction (Mitsuba `directional`).
    Directional {
        /// Direction the light travels in (from the light towards the scene), unit, world.
        direction: Vec3,
        /// Irradiance on a surface facing the light, W/m^2.
        irradiance: SpectrumDesc,
    },
    /// A sun: a distant light of finite angular diameter, uniform radiance over its disk, so that
    /// shadows get a penumbra (project extension `sun`).
    Sun {
        /// Direction the light travels in (from the sun towards the scene), unit, world.
        direction: Vec3,
        /// Irradiance on a surface facing the sun, W/m^2.
        irradiance: SpectrumDesc,
        /// Full angular diameter of the disk, degrees (the Sun's mean is 0.5338).
        angular_diameter_deg: f32,
    },
    /// The Hosek-Wilkie sun and sky (Mitsuba `sunsky`): sky radiance over the upper hemisphere
    /// of its frame and the sun's disc in it (crate pt-sky).
    SunSky(Box<SunSkyDesc>),
    /// Uniform radiance from every direction (Mitsuba `constant`).
    Constant {
        /// Radiance, W sr^-1 m^-2.
        radiance: SpectrumDesc,
    },
    /// Environment map (Mitsuba `envmap`): a latitude-longitude image of incident radiance.
    EnvMap {
        /// The image file (EXR), resolved.
        filename: PathBuf,
        /// Map-to-world transform (rotation).
        to_world: Mat4,
        /// Factor applied to the image's values.
        scale: f32,
    },
}

/// A radiant intensity that varies over directions: an IES file's candelas
/// (`crate::ies`) or an image's values (pbrt-v4's `goniometric` light), in the frame of the
/// light that carries it.
#[derive(Clone, Debug)]
pub struct IntensityProfile {
    /// Where the values come from.
    pub source: ProfileSource,
    /// Rotation from the light's local frame to world space (the linear part of its
    /// `to_world`, checked to be a rotation times a uniform scale, then normalised).
    pub to_world: Mat3,
    /// Factor on the values (`scale`).
    pub scale: f32,
}

/// The data of an [`IntensityProfile`].
#[derive(Clone, Debug)]
pub enum ProfileSource {
    /// An IES file's table, in W/sr per unit of luminance of the light's colour (the light's
    /// `intensity` then sets only the colour: the renderer divides it by its luminance).
    Ies(IntensityTable),
    /// An equirectangular image (EXR), laid out as Mitsuba's `envmap` in the light's frame: its
    /// luminance at a direction multiplies the light's `intensity` (W/sr).
    Image(PathBuf),
}

/// Values over a grid of directions: rows at polar angles `theta` from the table's pole, columns
/// at azimuths `phi` around it, bilinear in (theta, phi) between nodes, zero beyond the first
/// and last row, periodic in phi.
#[derive(Clone, Debug, PartialEq)]
pub struct IntensityTable {
    /// Polar angles of the rows, radians, increasing, within [0, pi].
    pub theta: Vec<f32>,
    /// Azimuths of the columns, radians, increasing, within [0, 2 pi); one column means the
    /// values do not depend on the azimuth.
    pub phi: Vec<f32>,
    /// `values[row * phi.len() + column]`, not negative.
    pub values: Vec<f32>,
    /// Linear map from the light's local frame to the table's axes (x', y', z'), where
    /// theta = acos z' and phi = atan2(y', x'): orthogonal (identity for IES files).
    pub axes: Mat3,
}

/// Mitsuba's `sunsky`, resolved: the sun's direction is computed from the date and place when
/// those were given.
#[derive(Clone, Debug)]
pub struct SunSkyDesc {
    /// Unit direction towards the sun's centre in the sky's frame (z the zenith; with a date
    /// and place, x points south and y west).
    pub sun_local: Vec3,
    /// Sky-to-world rotation (Mitsuba's `to_world`).
    pub to_world: glam::Mat3,
    /// Atmospheric turbidity, 1 to 10.
    pub turbidity: f32,
    /// Ground albedo, each channel or wavelength in [0, 1].
    pub albedo: SpectrumDesc,
    /// Factor on the sun's radiance.
    pub sun_scale: f32,
    /// Factor on the sky's radiance.
    pub sky_scale: f32,
    /// Full angular diameter of the sun's disc, degrees (Mitsuba's default 0.5358).
    pub sun_aperture_deg: f32,
    /// The 2013 solar radiance function with limb darkening instead of a uniform disc.
    pub complex_sun: bool,
}
