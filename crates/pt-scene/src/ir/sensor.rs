//! Sensor (camera, film, sampler) and integrator settings.

use super::SourceLoc;
use glam::Mat4;

/// Which image axis the field of view spans (Mitsuba's `fov_axis`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FovAxis {
    /// Horizontal (the default).
    X,
    /// Vertical.
    Y,
    /// The image diagonal.
    Diagonal,
    /// The smaller of the two image axes.
    Smaller,
    /// The larger of the two image axes.
    Larger,
}

/// Camera projection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Pinhole perspective camera with the full field of view in degrees along `fov_axis`.
    Perspective {
        /// Full field of view in degrees.
        fov_deg: f32,
        /// Which image axis `fov_deg` spans.
        fov_axis: FovAxis,
    },
    /// Thin-lens perspective camera (Mitsuba `thinlens`): a pinhole's field of view, rays from
    /// a disk-shaped aperture focused on the plane `focus_distance` in front of it.
    ThinLens {
        /// Full field of view in degrees.
        fov_deg: f32,
        /// Which image axis `fov_deg` spans.
        fov_axis: FovAxis,
        /// Aperture radius, scene units (0: a pinhole).
        aperture_radius: f32,
        /// Distance of the plane in focus along the view axis, scene units.
        focus_distance: f32,
    },
    /// Orthographic camera (Mitsuba `orthographic`): parallel rays along camera +z from the
    /// rectangle x in [-1, 1], y in [-1/aspect, 1/aspect] of camera space (aspect = width /
    /// height), which `to_world` may scale.
    Orthographic,
    /// Mitsuba's `radiancemeter`: the radiance arriving at the camera's origin along one ray,
    /// camera +z (a 1 x 1 film).
    Radiancemeter,
    /// Mitsuba's `irradiancemeter`, nested in a shape: the irradiance (W m^-2) arriving at the
    /// shape's front side, averaged over its area (a 1 x 1 film). Rays leave points uniform
    /// by area in cosine-distributed directions about the normal, each weighted by pi. The
    /// camera's `to_world` is unused.
    Irradiancemeter {
        /// The shape it measures ([`crate::SceneDesc::shapes`]).
        shape: usize,
    },
    /// Mitsuba's `distant`: the radiance leaving the scene along one direction (camera -z of
    /// `to_world`, rays travel along camera +z), averaged over where its parallel rays aim (a
    /// 1 x 1 film).
    Distant {
        /// Where the rays aim.
        target: DistantTarget,
    },
    /// Mitsuba's `batch`: the sensors of [`crate::SceneDesc::batch`] side by side, each
    /// rendering its equal vertical strip of the film, left to right. The camera's own
    /// `to_world` is unused.
    Batch,
}

/// Where the parallel rays of Mitsuba's `distant` sensor aim: each passes through a point of
/// the target, coming from outside the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DistantTarget {
    /// Points uniform on the disk through the scene's bounding sphere's centre, perpendicular
    /// to the direction, of its radius (Mitsuba's default).
    BoundingDisk,
    /// One point, world space.
    Point(glam::Vec3),
    /// Points uniform by area on the shape [`crate::SceneDesc::sensor_target`] (not
    /// rendered).
    Shape,
}

/// A camera. Camera space follows Mitsuba: it looks along +z, +y is up, +x is *left* in the image
/// (so image x grows towards camera -x). `to_world` maps camera space to world space.
#[derive(Clone, Debug)]
pub struct CameraDesc {
    /// Where it was defined (for errors).
    pub loc: SourceLoc,
    /// Projection and its parameters.
    pub projection: Projection,
    /// Camera-to-world transform (may contain a mirroring `scale x=-1`; any scale for an
    /// orthographic camera, whose film extent it sets).
    pub to_world: Mat4,
    /// Near clip distance along the ray, scene units.
    pub near_clip: f32,
    /// Far clip distance along the ray, scene units.
    pub far_clip: f32,
    /// Mitsuba's `principal_point_offset_x/y` (perspective only; 0 otherwise): where the view
    /// axis meets the film, relative to the film's centre, as fractions of the film's width and
    /// height along camera +x and +y (image left and up). The image content moves by
    /// -offset x (width, height) pixels.
    pub principal_point_offset: [f32; 2],
}

/// Pixel reconstruction filter (Mitsuba's `rfilter`). Radii in pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FilterDesc {
    /// Box of the given radius (Mitsuba default radius 0.5: one pixel).
    Box {
        /// Half-width in pixels.
        radius: f32,
    },
    /// Tent (triangle) of the given radius (Mitsuba default 1.0).
    Tent {
        /// Half-width in pixels.
        radius: f32,
    },
    /// Gaussian with standard deviation `stddev` (Mitsuba default 0.5), truncated at 4 stddev.
    Gaussian {
        /// Standard deviation in pixels.
        stddev: f32,
    },
    /// Mitchell & Netravali 1988's cubic of radius 2 with parameters B and C (Mitsuba's
    /// `mitchell`, B = C = 1/3; `catmullrom` is B = 0, C = 1/2). It has negative lobes.
    Mitchell {
        /// Mitchell-Netravali B.
        b: f32,
        /// Mitchell-Netravali C.
        c: f32,
    },
    /// Windowed sinc, sinc(x) sinc(x / lobes) for |x| < lobes (Mitsuba's `lanczos`, 3 lobes).
    /// It has negative lobes.
    Lanczos {
        /// Number of lobes: the radius in pixels.
        lobes: f32,
    },
}

/// Film: image size, crop window and reconstruction filter.
#[derive(Clone, Debug)]
pub struct FilmDesc {
    /// Width of the image rendered and written, pixels: the crop window's width when there is
    /// one, else the film's.
    pub width: u32,
    /// Height of the image rendered and written, pixels (as `width`).
    pub height: u32,
    /// Mitsuba's crop window (`crop_offset_x/y`, `crop_width/height`), if the image is a part of
    /// a larger film.
    pub crop: Option<CropWindow>,
    /// Reconstruction filter (Mitsuba's default is a Gaussian with stddev 0.5).
    pub filter: FilterDesc,
    /// Mitsuba's `sample_border`: whether samples are also drawn around the image, so that its
    /// edge pixels see their whole filter (otherwise the filter is cut off at the image's edge,
    /// the default).
    pub sample_border: bool,
    /// How samples become pixels (not a Mitsuba parameter: Mitsuba always splats; pt's
    /// `--reconstruction` chooses).
    pub reconstruction: Reconstruction,
    /// The channels written (Mitsuba's `pixel_format`; `rgb` by default, as Mitsuba 3.9.1).
    pub pixel_format: PixelFormat,
}

/// The colour channels an image file holds (Mitsuba's `hdrfilm` `pixel_format`), in the
/// order they are written: linear sRGB (Rec. 709 primaries, D65 white), its luminance Y, or
/// CIE 1931 XYZ, optionally with an alpha channel `A` (the fraction of a pixel's samples
/// whose camera path met the scene, see pt-integrators' render loop).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PixelFormat {
    /// `R`, `G`, `B`.
    #[default]
    Rgb,
    /// `R`, `G`, `B`, `A`.
    Rgba,
    /// `Y`.
    Luminance,
    /// `Y`, `A`.
    LuminanceAlpha,
    /// `X`, `Y`, `Z`.
    Xyz,
    /// `X`, `Y`, `Z`, `A`.
    Xyza,
}

impl PixelFormat {
    /// Every format with its Mitsuba name.
    pub const NAMES: [(&'static str, PixelFormat); 6] = [
        ("rgb", PixelFormat::Rgb),
        ("rgba", PixelFormat::Rgba),
        ("luminance", PixelFormat::Luminance),
        ("luminance_alpha", PixelFormat::LuminanceAlpha),
        ("xyz", PixelFormat::Xyz),
        ("xyza", PixelFormat::Xyza),
    ];

    /// The channel names, in order (Mitsuba's names).
    pub fn channels(self) -> &'static [&'static str] {
        match self {
            PixelFormat::Rgb => &["R", "G", "B"],
            PixelFormat::Rgba => &["R", "G", "B", "A"],
            PixelFormat::Luminance => &["Y"],
            PixelFormat::LuminanceAlpha => &["Y", "A"],
            PixelFormat::Xyz => &["X", "Y", "Z"],
            PixelFormat::Xyza => &["X", "Y", "Z", "A"],
        }
    }

    /// Whether the format has an alpha channel.
    pub fn has_alpha(self) -> bool {
        self.channels().contains(&"A")
    }
}

/// How a film turns samples into pixels. Both have the same expected image for filters
/// without negative lobes (each pixel the filter-weighted mean of the radiance around it, the
/// filter cut off at the image's edge unless `sample_border`); they differ in noise.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Reconstruction {
    /// Mitsuba's: each sample is placed uniformly in its pixel and added, with the filter's
    /// weight, to every pixel whose filter reaches it; a pixel is its weighted sum divided by
    /// its summed weights. Neighbouring pixels share samples (smoother, correlated noise: the
    /// per-pixel variance at equal spp is Mitsuba's).
    #[default]
    Splat,
    /// Filter importance sampling (pbrt-v4's): each sample's offset is drawn from the filter
    /// and it counts for its own pixel only, so pixels are independent (noisier per pixel at
    /// equal spp under wide filters, uncorrelated). Filters with negative lobes carry signed
    /// weights.
    Importance,
}

/// The part of a film that is rendered: the image's pixel (i, j) is the film's pixel
/// (i + `offset[0]`, j + `offset[1]`), and the camera projects onto the whole film.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CropWindow {
    /// The film's pixel at the image's top-left corner.
    pub offset: [u32; 2],
    /// The whole film's width and height, pixels.
    pub film_size: [u32; 2],
}

impl FilmDesc {
    /// A film of `width` x `height` pixels, not cropped.
    pub fn new(width: u32, height: u32, filter: FilterDesc) -> Self {
        FilmDesc {
            width,
            height,
            crop: None,
            filter,
            sample_border: false,
            reconstruction: Reconstruction::Splat,
            pixel_format: PixelFormat::Rgb,
        }
    }

    /// The whole film's width and height, pixels (the camera's projection spans it).
    pub fn film_size(&self) -> [u32; 2] {
        self.crop.map_or([self.width, self.height], |c| c.film_size)
    }

    /// The film's pixel at the image's top-left corner ((0, 0) without a crop window).
    pub fn crop_offset(&self) -> [u32; 2] {
        self.crop.map_or([0, 0], |c| c.offset)
    }
}

/// Sampler settings.
#[derive(Clone, Debug)]
pub struct SamplerDesc {
    /// Samples per pixel (already rounded as the kind requires: [`SamplerKind::round_count`]).
    pub sample_count: u32,
    /// Seed of the random streams (Mitsuba default 0).
    pub seed: u64,
    /// How the samples of a pixel are placed.
    pub kind: SamplerKind,
}

/// How the samples of a pixel are spread over each dimension (Mitsuba's sampler plugins).
/// Every kind gives each sample uniformly distributed numbers (so every estimate stays
/// unbiased); the structured kinds also spread the samples of one pixel evenly over each
/// dimension (and pair of dimensions), which lowers the variance of smooth integrands.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SamplerKind {
    /// Independent uniform numbers (`independent`).
    #[default]
    Independent,
    /// Stratified (`stratified`): n = r^2 samples, each 1D dimension in n strata and each 2D
    /// request in an r x r grid, strata shuffled per dimension; `jitter` places each sample
    /// at random in its stratum (else at its centre).
    Stratified {
        /// Random position within the stratum (Mitsuba default true).
        jitter: bool,
    },
    /// Multi-jittered (`multijitter`, Chiu, Shirley & Wang 1994): n = rx ry samples, 2D
    /// requests stratified in an rx x ry grid and in n columns and n rows at once.
    MultiJitter {
        /// Random position within the fine stratum (Mitsuba default true).
        jitter: bool,
    },
    /// Orthogonal array sampling (`orthogonal`, Jarosz et al. 2019; Bose's strength-2 arrays):
    /// n = p^2 samples (p prime), every pair of dimensions stratified in a p x p grid and
    /// every dimension in n strata.
    Orthogonal {
        /// Random position within the fine stratum (Mitsuba default true).
        jitter: bool,
    },
    /// A scrambled (0, 2)-sequence (`ldsampler`, Kollig & Keller 2002): n = 4^k samples whose
    /// 2D requests form a (0, 2)-net, dimensions decorrelated by shuffling the sample order.
    LowDiscrepancy,
}

impl SamplerKind {
    /// The sample count Mitsuba 3.9.1 uses when `n` is asked for: `stratified` the least square
    /// not below n, `multijitter` rx ry with ry = floor(sqrt n) and rx = ceil(n / ry),
    /// `orthogonal` p^2 for the least prime p with p^2 not below n, `ldsampler` the least power
    /// of 4 not below n (and at least 4).
    pub fn round_count(self, n: u32) -> u32 {
        let n = u64::from(n.max(1));
        let least_root = |n: u64| (1u64..).find(|r| r * r >= n).unwrap_or(1);
        let count = match self {
            SamplerKind::Independent => n,
            SamplerKind::Stratified { .. } => least_root(n).pow(2),
            SamplerKind::MultiJitter { .. } => {
                let ry = (1u64..).take_while(|r| r * r <= n).last().unwrap_or(1);
                n.div_ceil(ry) * ry
            }
            SamplerKind::Orthogonal { .. } => {
                let is_prime =
                    |p: u64| p >= 2 && (2..).take_while(|d| d * d <= p).all(|d| p % d != 0);
                let p = (least_root(n)..).find(|&p| is_prime(p)).unwrap_or(2);
                p * p
            }
            SamplerKind::LowDiscrepancy => {
                let mut c = 4u64;
                while c < n {
                    c *= 4;
                }
                c
            }
        };
        u32::try_from(count).unwrap_or(u32::MAX)
    }

    /// Mitsuba's plugin name.
    pub fn plugin(self) -> &'static str {
        match self {
            SamplerKind::Independent => "independent",
            SamplerKind::Stratified { .. } => "stratified",
            SamplerKind::MultiJitter { .. } => "multijitter",
            SamplerKind::Orthogonal { .. } => "orthogonal",
            SamplerKind::LowDiscrepancy => "ldsampler",
        }
    }
}

/// Which integrator the scene asks for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum IntegratorKind {
    /// Unidirectional path tracing with NEE and MIS (Mitsuba `path`).
    Path,
    /// Path tracing through participating media (Mitsuba `volpath`): free flight, scattering
    /// and light sampling through media and null surfaces; as `Path` where the scene has no
    /// media. (`Path` ignores media, as Mitsuba's does.)
    VolPath,
    /// Direct illumination only (Mitsuba `direct`), with Mitsuba's numbers of emitter and BSDF
    /// samples per hit (`shading_samples` sets both; 1 and 1 by default; one may be 0).
    Direct {
        /// Light samples per hit.
        emitter_samples: u32,
        /// BSDF samples per hit.
        bsdf_samples: u32,
    },
    /// Radiosity (project extension `radiosity`): finite elements for diffuse scenes.
    Radiosity,
    /// Mitsuba's `depth`: each pixel the filter-weighted mean distance from the camera ray's
    /// start (its near clip plane) to the first surface, 0 where it hits nothing.
    Depth,
    /// Light tracing (Mitsuba `ptracer`): paths from the lights, each vertex connected to the
    /// camera. `samples_per_pass` splits the samples into passes of that many per pixel
    /// (Mitsuba requires the sample count to be a multiple of it); it does not change the
    /// image.
    PTracer {
        /// Samples per pixel per pass, if given.
        samples_per_pass: Option<u32>,
    },
    /// Stochastic progressive photon mapping (pt extension `sppm`): one iteration per sample.
    Sppm {
        /// Photons per iteration (`photons_per_iteration`; default: the image's pixel count).
        photons_per_iteration: Option<u32>,
        /// First iteration's radius, scene units (`initial_radius`; default: 1% of the scene's
        /// bounding sphere radius).
        initial_radius: Option<f32>,
        /// Knaus & Zwicker's radius reduction `alpha` in (0, 1) (default 2/3).
        alpha: f32,
    },
    /// Photon mapping as Jensen 1996 describes it (pt extension `photonmapper`): a global and
    /// a caustic map per iteration, k-nearest radiance estimates, final gathering.
    PhotonMapper {
        /// Photons emitted for the global map per iteration (`global_photons`, 100000).
        global_photons: u32,
        /// Photons emitted for the caustic map per iteration (`caustic_photons`, 100000).
        caustic_photons: u32,
        /// Photons per radiance estimate (`lookup_size`, 50).
        lookup_size: u32,
        /// Largest gathering radius, scene units (`lookup_radius`; default: 5% of the scene's
        /// bounding sphere radius).
        lookup_radius: Option<f32>,
        /// Final gathering for indirect light (`final_gather`, true).
        final_gather: bool,
    },
    /// Bidirectional path tracing (pt extension `bdpt`): all connection strategies under the
    /// power heuristic.
    Bdpt,
    /// Vertex connection and merging (pt extension `vcm`): bdpt's strategies and photon
    /// merging under one power heuristic.
    Vcm {
        /// First iteration's merging radius, scene units (`initial_radius`; default: 1% of
        /// the scene's bounding sphere radius).
        initial_radius: Option<f32>,
        /// Radius schedule exponent in (0, 1): r_i = r_0 i^((alpha - 1) / 2) (default 3/4).
        alpha: f32,
    },
}

impl IntegratorKind {
    /// Whether the method traces paths from the camera shading each hit (Mitsuba's `path`,
    /// `volpath` and `direct`): the ones `moment` can wrap and the afterglow renders with.
    pub fn is_camera_path_tracer(self) -> bool {
        match self {
            IntegratorKind::Path | IntegratorKind::VolPath | IntegratorKind::Direct { .. } => true,
            IntegratorKind::Radiosity
            | IntegratorKind::Depth
            | IntegratorKind::PTracer { .. }
            | IntegratorKind::Sppm { .. }
            | IntegratorKind::PhotonMapper { .. }
            | IntegratorKind::Bdpt
            | IntegratorKind::Vcm { .. } => false,
        }
    }
}

/// Which radiosity solver to use (`solver`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum RadiositySolver {
    /// Jacobi iteration (parallel).
    Jacobi,
    /// Gauss-Seidel iteration (sequential, in place), the default.
    #[default]
    GaussSeidel,
    /// Progressive refinement by shooting (Cohen et al. 1988).
    Progressive,
}

/// How a radiosity solution is turned into an image (`display`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum RadiosityDisplay {
    /// Piecewise constant: one value per patch.
    Constant,
    /// Vertex-smoothed, interpolated barycentrically (the default).
    #[default]
    Smoothed,
    /// One diffuse bounce from the visible point, reading the patch radiosities (final gather).
    FinalGather,
}

/// How estimated form factors are made reciprocal (`reciprocity`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Reciprocity {
    /// Keep the raw ray-cast estimates (row sums exact, reciprocity only in expectation).
    None,
    /// Average `A_i F_ij` and `A_j F_ji` (reciprocity exact, row sums off by the estimates' noise).
    Average,
    /// Average, then rescale symmetrically so that row sums equal the measured hit fractions
    /// (the default): reciprocity exact and row sums to 1e-6.
    #[default]
    Balanced,
}

/// Parses the names used in `<integrator type="radiosity">` and on the command line
/// (case-insensitive, `-` and `_` interchangeable); the error lists the accepted names.
macro_rules! named {
    ($ty:ty, $what:literal, $($name:literal => $v:expr),+ $(,)?) => {
        impl std::str::FromStr for $ty {
            type Err = String;
            fn from_str(s: &str) -> Result<Self, Self::Err> {
                match s.to_ascii_lowercase().replace('-', "_").as_str() {
                    $($name => Ok($v),)+
                    _ => Err(format!(
                        concat!("unknown ", $what, " '{}' (expected one of: {})"),
                        s,
                        [$($name),+].join(", ")
                    )),
                }
            }
        }
    };
}

named!(RadiositySolver, "solver",
    "jacobi" => RadiositySolver::Jacobi,
    "gauss_seidel" => RadiositySolver::GaussSeidel,
    "progressive" => RadiositySolver::Progressive);
named!(RadiosityDisplay, "display",
    "constant" => RadiosityDisplay::Constant,
    "smoothed" => RadiosityDisplay::Smoothed,
    "final_gather" => RadiosityDisplay::FinalGather);
named!(Reciprocity, "reciprocity",
    "none" => Reciprocity::None,
    "average" => Reciprocity::Average,
    "balanced" => Reciprocity::Balanced);

/// Options of `<integrator type="radiosity">`, as written (ranges are validated by the
/// radiosity crate, which reports errors at the integrator's location). `None` means the
/// solver's default.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RadiosityOptions {
    /// Longest patch edge, scene units.
    pub patch_size: Option<f32>,
    /// Form-factor rays per patch.
    pub rays_per_patch: Option<u32>,
    /// Relative residual at which the solver stops.
    pub tolerance: Option<f32>,
    /// Iteration cap.
    pub max_iterations: Option<u32>,
    /// The solver.
    pub solver: Option<RadiositySolver>,
    /// How the solution is displayed.
    pub display: Option<RadiosityDisplay>,
    /// How form factors are made reciprocal.
    pub reciprocity: Option<Reciprocity>,
}

/// Mitsuba's `aov` integrator: per sample, quantities of the first surface the camera ray
/// hits (zero where it hits nothing), splatted with the film's filter into extra channels.
#[derive(Clone, Debug, PartialEq)]
pub struct AovDesc {
    /// The nested integrator's name: its image is also written as `name.R`, `name.G`,
    /// `name.B`, `name.A`. `None` when the `aov` integrator has no nested integrator (the
    /// image's own channels are then zero, as in Mitsuba).
    pub image: Option<String>,
    /// The requested outputs, in the order given: (name, quantity).
    pub outputs: Vec<(String, AovKind)>,
}

impl AovDesc {
    /// Every extra channel's name, in the order written: the nested integrator's image, then
    /// each output's channels (`name` + `.` + [`AovKind::suffixes`]).
    pub fn channel_names(&self) -> Vec<String> {
        let image = self
            .image
            .iter()
            .flat_map(|n| ["R", "G", "B", "A"].map(|c| format!("{n}.{c}")));
        let outputs = self
            .outputs
            .iter()
            .flat_map(|(n, k)| k.suffixes().iter().map(move |c| format!("{n}.{c}")));
        image.chain(outputs).collect()
    }

    /// Whether an output needs texture coordinates or their tangents kept on every shape.
    pub fn needs_uv(&self) -> bool {
        self.outputs
            .iter()
            .any(|(_, k)| matches!(k, AovKind::Uv | AovKind::DpDu | AovKind::DpDv))
    }
}

/// A quantity of Mitsuba's `aov` integrator (world space where it is a vector).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AovKind {
    /// `albedo`: the BSDF's diffuse reflectance (Mitsuba's `eval_diffuse_reflectance`), linear
    /// sRGB.
    Albedo,
    /// `depth`: the distance along the camera ray from the near clip plane (where Mitsuba's
    /// camera rays start) to the hit.
    Depth,
    /// `position`: the hit point.
    Position,
    /// `uv`: the texture coordinates.
    Uv,
    /// `geo_normal`: the geometric normal (the primitive's front side).
    GeoNormal,
    /// `sh_normal`: the shading normal (interpolated vertex normal, before normal or bump
    /// maps).
    ShNormal,
    /// `dp_du`: the position's derivative along u.
    DpDu,
    /// `dp_dv`: the position's derivative along v.
    DpDv,
    /// `prim_index`: the triangle's index in its mesh (0 on analytic shapes).
    PrimIndex,
    /// `shape_index`: the shape's number, counted from 1 in file order (0 for no hit).
    /// Mitsuba writes its internal object number, whose order differs between its variants.
    ShapeIndex,
}

impl AovKind {
    /// Mitsuba's names of the quantities pt computes.
    pub const NAMES: [(&'static str, AovKind); 10] = [
        ("albedo", AovKind::Albedo),
        ("depth", AovKind::Depth),
        ("position", AovKind::Position),
        ("uv", AovKind::Uv),
        ("geo_normal", AovKind::GeoNormal),
        ("sh_normal", AovKind::ShNormal),
        ("dp_du", AovKind::DpDu),
        ("dp_dv", AovKind::DpDv),
        ("prim_index", AovKind::PrimIndex),
        ("shape_index", AovKind::ShapeIndex),
    ];

    /// The channel suffixes Mitsuba 3.9.1 writes for the quantity.
    pub fn suffixes(self) -> &'static [&'static str] {
        match self {
            AovKind::Albedo => &["R", "G", "B"],
            AovKind::Depth => &["T"],
            AovKind::Uv => &["U", "V"],
            AovKind::PrimIndex | AovKind::ShapeIndex => &["I"],
            AovKind::Position
            | AovKind::GeoNormal
            | AovKind::ShNormal
            | AovKind::DpDu
            | AovKind::DpDv => &["X", "Y", "Z"],
        }
    }
}

/// Integrator settings with Mitsuba semantics.
#[derive(Clone, Debug)]
pub struct IntegratorDesc {
    /// Which integrator.
    pub kind: IntegratorKind,
    /// Longest path in segments: 1 = emitters seen directly, 2 = direct light, -1 = unlimited.
    pub max_depth: i32,
    /// Depth at which Russian roulette starts (Mitsuba default 5).
    pub rr_depth: u32,
    /// Whether directly visible emitters are hidden (black).
    pub hide_emitters: bool,
    /// Whether paths sample the lights at each vertex (next-event estimation, joined to BSDF
    /// sampling by MIS); false for Mitsuba's `prb_basic`, which finds emitters by BSDF sampling
    /// alone.
    pub light_sampling: bool,
    /// Mitsuba's `moment`: when the scene wrapped the integrator in it, the nested integrator's
    /// name (`_arg_0` when it has none): the image's XYZ is also written as `name.X/Y/Z` and the
    /// per-pixel mean of the samples' squared XYZ as `m2_name.X/Y/Z`.
    pub moment: Option<String>,
    /// Mitsuba's `aov`: the extra channels, when the scene wrapped the integrator in `aov`
    /// (or asked for AOVs alone).
    pub aov: Option<AovDesc>,
    /// Radiosity options (with `IntegratorKind::Radiosity`).
    pub radiosity: RadiosityOptions,
    /// Where the integrator was defined (default location if the scene has none).
    pub loc: SourceLoc,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Radiosity option names parse case-insensitively with `-` or `_`; an unknown name's
    /// error lists the accepted ones.
    #[test]
    fn radiosity_option_names_parse() {
        assert_eq!(
            "gauss-seidel".parse::<RadiositySolver>(),
            Ok(RadiositySolver::GaussSeidel)
        );
        assert_eq!(
            "Final_Gather".parse::<RadiosityDisplay>(),
            Ok(RadiosityDisplay::FinalGather)
        );
        assert_eq!("balanced".parse::<Reciprocity>(), Ok(Reciprocity::Balanced));
        let e = "sor".parse::<RadiositySolver>().unwrap_err();
        assert!(e.contains("jacobi, gauss_seidel, progressive"), "{e}");
    }
}
