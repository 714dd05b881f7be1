//! OpenEXR input and output.
//!
//! Written files are single-part scan-line EXRs with float32 channels (`R`, `G`, `B` for
//! [`write_exr`]; any named channels for [`write_exr_channels`]), ZIP compressed (lossless, so values round-trip bit-exactly), readable by OpenEXR, Mitsuba 3 and
//! `exrheader`. Metadata goes into header attributes:
//!
//! | [`ExrMeta`] field | attribute | EXR type |
//! |---|---|---|
//! | `spp` | `spp` | `int` (`double` above `i32::MAX`) |
//! | `mode` | `mode` | `string` |
//! | `render_time_s` | `renderTimeSeconds` | `double` |
//! | `extra` | each key as given | `string` |
//!
//! The reader accepts what pt and Mitsuba 3 write: `R`, `G`, `B` with or without `A`, half, float
//! or uint samples, or a single `Y` (or `L`) luminance channel, which becomes grey.

use std::fs::File;
use std::io::{BufReader, BufWriter, Write};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

use exr::prelude::{
    self as x, AttributeValue, Encoding, FlatSamples, LayerAttributes, ReadChannels as _,
    ReadLayers as _, Text, WritableImage as _,
};

use crate::atomic::write_atomically;
use crate::{Image, ImageError};

/// Attribute name of [`ExrMeta::spp`].
const SPP: &str = "spp";
/// Attribute name of [`ExrMeta::mode`].
const MODE: &str = "mode";
/// Attribute name of [`ExrMeta::render_time_s`].
const RENDER_TIME: &str = "renderTimeSeconds";

/// Names that `extra` may not use: ours, and the OpenEXR attributes that describe the file's
/// structure (overriding them would produce a broken file).
const RESERVED: &[&str] = &[
    SPP,
    MODE,
    RENDER_TIME,
    "channels",
    "compression",
    "dataWindow",
    "displayWindow",
    "lineOrder",
    "pixelAspectRatio",
    "screenWindowCenter",
    "screenWindowWidth",
    "tiles",
    "type",
    "name",
    "version",
    "chunkCount",
    "maxSamplesPerPixel",
    "view",
    "multiView",
    "preview",
];

/// Metadata written as EXR header attributes (text/float/int attributes), and read back where
/// present. See the module table for attribute names and types.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ExrMeta {
    /// Samples per pixel of the render.
    pub spp: Option<u32>,
    /// Colour mode, e.g. "rgb" or "spectral".
    pub mode: Option<String>,
    /// Wall-clock render time in seconds.
    pub render_time_s: Option<f64>,
    /// Further `(name, value)` text attributes. Names and values must be Latin-1 (EXR text is
    /// bytes). On reading this holds every other text attribute of the layer (including the
    /// standard `owner`, `comments`, `capDate` and `software`), sorted by name.
    pub extra: Vec<(String, String)>,
}

fn to_text(path: &Path, s: &str, what: &str) -> Result<Text, ImageError> {
    Text::new_or_none(s).ok_or_else(|| ImageError::InvalidMeta {
        path: path.to_path_buf(),
        reason: format!("{what} {s:?} is not Latin-1 text, which EXR attributes require"),
    })
}

/// Latin-1 bytes to a Rust string (every byte is the code point of the same value).
fn from_text(t: &Text) -> String {
    t.bytes().iter().map(|&b| char::from(b)).collect()
}

fn meta_attributes(path: &Path, meta: &ExrMeta) -> Result<LayerAttributes, ImageError> {
    let mut attrs = LayerAttributes::default();
    let other = &mut attrs.other;
    if let Some(spp) = meta.spp {
        let v = match i32::try_from(spp) {
            Ok(i) => AttributeValue::I32(i),
            Err(_) => AttributeValue::F64(f64::from(spp)),
        };
        other.insert(Text::from(SPP), v);
    }
    if let Some(mode) = &meta.mode {
        other.insert(
            Text::from(MODE),
            AttributeValue::Text(to_text(path, mode, "mode")?),
        );
    }
    if let Some(t) = meta.render_time_s {
        other.insert(Text::from(RENDER_TIME), AttributeValue::F64(t));
    }
    for (i, (k, v)) in meta.extra.iter().enumerate() {
        let invalid = |reason: String| ImageError::InvalidMeta {
            path: path.to_path_buf(),
            reason,
        };
        if k.is_empty() || k.contains('\0') {
            return Err(invalid(format!(
                "extra attribute name {k:?} is empty or contains NUL"
            )));
        }
        if RESERVED.contains(&k.as_str()) {
            return Err(invalid(format!("extra attribute name {k:?} is reserved")));
        }
        if meta.extra[..i].iter().any(|(k2, _)| k2 == k) {
            return Err(invalid(format!("extra attribute name {k:?} appears twice")));
        }
        let key = to_text(path, k, "extra attribute name")?;
        let value = to_text(path, v, "extra attribute value")?;
        other.insert(key, AttributeValue::Text(value));
    }
    Ok(attrs)
}

/// Write a float32 RGB EXR atomically: write to a temporary file in the same directory (name
/// starting with '.' and ending in ".tmp"), fsync, then rename over the target; on any error
/// remove the temporary file and leave no output file (an existing target stays untouched).
///
/// Fails on an empty image, on an image whose `data` length does not match its size, and on
/// metadata that EXR cannot hold (see [`ExrMeta::extra`]).
pub fn write_exr(path: &Path, img: &Image, meta: &ExrMeta) -> Result<(), ImageError> {
    img.check_len().map_err(|reason| ImageError::InvalidImage {
        what: path.display().to_string(),
        reason,
    })?;
    let plane = |c: usize| img.data.iter().map(|p| p[c]).collect::<Vec<f32>>();
    let channels = [("R", plane(0)), ("G", plane(1)), ("B", plane(2))];
    let named: Vec<(&str, &[f32])> = channels.iter().map(|(n, v)| (*n, &v[..])).collect();
    write_exr_channels(path, img.width, img.height, &named, meta)
}

/// Write float32 channels of a `width` x `height` image atomically (as [`write_exr`]): each
/// `(name, plane)` is one channel, its samples row-major from the top. Names are written as
/// given (`R`, `A`, `nn.X`: OpenEXR's layer.channel convention), and readers list them
/// alphabetically, as OpenEXR stores them.
///
/// Fails on an empty image, on no channels, on a plane whose length is not `width * height`,
/// on an empty or repeated channel name, and on metadata that EXR cannot hold.
pub fn write_exr_channels(
    path: &Path,
    width: u32,
    height: u32,
    channels: &[(&str, &[f32])],
    meta: &ExrMeta,
) -> Result<(), ImageError> {
    let invalid = |reason: String| ImageError::InvalidImage {
        what: path.display().to_string(),
        reason,
    };
    if width == 0 || height == 0 {
        return Err(invalid(format!(
            "cannot write an empty {width}x{height} image"
        )));
    }
    if channels.is_empty() {
        return Err(invalid("cannot write an image without channels".into()));
    }
    let n = width as usize * height as usize;
    for (i, (name, plane)) in channels.iter().enumerate() {
        if plane.len() != n {
            return Err(invalid(format!(
                "channel {name:?} has {} samples, a {width}x{height} image needs {n}",
                plane.len()
            )));
        }
        if name.is_empty() || channels[..i].iter().any(|(other, _)| other == name) {
            return Err(invalid(format!(
                "channel name {name:?} is empty or repeated"
            )));
        }
    }
    let attrs = meta_attributes(path, meta)?;
    let mut list = x::SmallVec::new();
    for (name, plane) in channels {
        let text = to_text(path, name, "channel name")?;
        list.push(x::AnyChannel::new(text, FlatSamples::F32(plane.to_vec())));
    }
    let layer = x::Layer::new(
        (width as usize, height as usize),
        attrs,
        Encoding::SMALL_LOSSLESS,
        x::AnyChannels::sort(list),
    );
    let exr_image = x::Image::from_layer(layer);

    write_atomically(path, |file| {
        let mut buffered = BufWriter::new(file);
        exr_image
            .write()
            .to_buffered(&mut buffered)
            .map_err(|source| ImageError::ExrWrite {
                path: path.to_path_buf(),
                source,
            })?;
        buffered
            .flush()
            .map_err(|e| ImageError::io(path, "write temporary file", e))
    })
}

type AnyLayer = x::Layer<x::AnyChannels<FlatSamples>>;

/// Channel names of a layer, prefixed by the layer name where there is one (for error messages).
fn channel_names(layer: &AnyLayer) -> impl Iterator<Item = String> + '_ {
    let prefix = layer.attributes.layer_name.as_ref().map(from_text);
    layer.channel_data.list.iter().map(move |c| match &prefix {
        Some(p) => format!("{p}.{}", from_text(&c.name)),
        None => from_text(&c.name),
    })
}

fn find_channel<'a>(layer: &'a AnyLayer, name: &str) -> Option<&'a FlatSamples> {
    layer
        .channel_data
        .list
        .iter()
        .find(|c| c.name.bytes() == name.as_bytes())
        .map(|c| &c.sample_data)
}

/// The colour channels of a layer: `[R, G, B]`, or `[Y]` for a luminance image.
fn colour_channels(layer: &AnyLayer) -> Option<Vec<&FlatSamples>> {
    let rgb: Option<Vec<_>> = ["R", "G", "B"]
        .iter()
        .map(|n| find_channel(layer, n))
        .collect();
    rgb.or_else(|| {
        // Luminance-chroma files (Y with RY, BY) would need a colour conversion: not grey.
        if find_channel(layer, "RY").is_some() || find_channel(layer, "BY").is_some() {
            return None;
        }
        ["Y", "L"]
            .iter()
            .find_map(|n| find_channel(layer, n))
            .map(|c| vec![c])
    })
}

fn read_meta(layer: &AnyLayer) -> ExrMeta {
    let mut meta = ExrMeta::default();
    let a = &layer.attributes;
    let standard_text = [
        ("owner", &a.owner),
        ("comments", &a.comments),
        ("capDate", &a.capture_date),
        ("software", &a.software_name),
    ];
    for (name, value) in standard_text {
        if let Some(t) = value {
            meta.extra.push((name.to_string(), from_text(t)));
        }
    }
    for (name, value) in &a.other {
        let name = from_text(name);
        match (name.as_str(), value) {
            (SPP, AttributeValue::I32(v)) => meta.spp = u32::try_from(*v).ok(),
            (SPP, AttributeValue::F64(v))
                if v.fract() == 0.0 && (0.0..=f64::from(u32::MAX)).contains(v) =>
            {
                meta.spp = Some(*v as u32);
            }
            (SPP, AttributeValue::F32(v)) if v.fract() == 0.0 && *v >= 0.0 && *v < 4.2e9 => {
                meta.spp = Some(*v as u32);
            }
            (SPP, AttributeValue::Text(t)) => meta.spp = from_text(t).trim().parse().ok(),
            (MODE, AttributeValue::Text(t)) => meta.mode = Some(from_text(t)),
            (RENDER_TIME, AttributeValue::F64(v)) => meta.render_time_s = Some(*v),
            (RENDER_TIME, AttributeValue::F32(v)) => meta.render_time_s = Some(f64::from(*v)),
            (RENDER_TIME, AttributeValue::I32(v)) => meta.render_time_s = Some(f64::from(*v)),
            (_, AttributeValue::Text(t)) => meta.extra.push((name, from_text(t))),
            _ => {}
        }
    }
    meta.extra.sort();
    meta
}

fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "non-string panic payload".to_string()
    }
}

/// The whole file, every layer and channel, decoded (panics inside the `exr` crate caught).
fn decode(path: &Path) -> Result<x::Image<x::Layers<x::AnyChannels<FlatSamples>>>, ImageError> {
    let file = File::open(path).map_err(|e| ImageError::io(path, "open file", e))?;
    let reader = BufReader::new(file);
    let result = catch_unwind(AssertUnwindSafe(|| {
        x::read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .all_layers()
            .all_attributes()
            .non_parallel()
            .from_buffered(reader)
    }));
    match result {
        Ok(Ok(image)) => Ok(image),
        Ok(Err(source)) => Err(ImageError::ExrRead {
            path: path.to_path_buf(),
            source,
        }),
        Err(payload) => Err(ImageError::DecoderPanic {
            path: path.to_path_buf(),
            message: panic_message(payload.as_ref()),
        }),
    }
}

/// Named float32 planes of an image: (channel name, row-major samples).
pub type NamedChannels = Vec<(String, Vec<f32>)>;

/// Every channel of an EXR's first part as float32 planes (row-major from the top), named as
/// stored (`R`, `A`, `nn.X`; a part's layer name, where it has one, prefixed with a dot), in
/// the file's (alphabetical) order; and the image's width and height. For the channels that
/// [`read_exr`] does not return: alpha, AOVs, moments.
pub fn read_exr_channels(path: &Path) -> Result<(u32, u32, NamedChannels), ImageError> {
    let exr_image = decode(path)?;
    let Some(layer) = exr_image.layer_data.first() else {
        return Err(ImageError::MissingChannels {
            path: path.to_path_buf(),
            channels: Vec::new(),
        });
    };
    let (w, h) = (layer.size.x(), layer.size.y());
    let (Ok(width), Ok(height)) = (u32::try_from(w), u32::try_from(h)) else {
        return Err(ImageError::Unsupported {
            path: path.to_path_buf(),
            reason: format!("image size {w}x{h} is too large"),
        });
    };
    let channels = channel_names(layer)
        .zip(&layer.channel_data.list)
        .map(|(name, c)| (name, c.sample_data.values_as_f32().collect()))
        .collect();
    Ok((width, height, channels))
}

/// Read an EXR written by pt or by Mitsuba 3: channels R, G, B (with or without A, half or
/// float32 or u32; a single Y or L luminance channel becomes grey). Also return metadata where
/// present (see [`ExrMeta`]).
///
/// In a multi-part file the first part with colour channels is used; the data window's offset is
/// ignored (pixel (0, 0) is the first pixel of the data window). Missing, truncated or corrupt
/// files and files without colour channels give an error naming the file, never a panic (a panic
/// inside the `exr` crate is caught and reported as [`ImageError::DecoderPanic`]).
pub fn read_exr(path: &Path) -> Result<(Image, ExrMeta), ImageError> {
    let exr_image = decode(path)?;

    let found = exr_image
        .layer_data
        .iter()
        .find_map(|layer| colour_channels(layer).map(|channels| (layer, channels)));
    let Some((layer, channels)) = found else {
        return Err(ImageError::MissingChannels {
            path: path.to_path_buf(),
            channels: exr_image
                .layer_data
                .iter()
                .flat_map(channel_names)
                .collect(),
        });
    };

    let (w, h) = (layer.size.x(), layer.size.y());
    let unsupported = |reason: String| ImageError::Unsupported {
        path: path.to_path_buf(),
        reason,
    };
    let (width, height) = match (u32::try_from(w), u32::try_from(h)) {
        (Ok(width), Ok(height)) => (width, height),
        _ => return Err(unsupported(format!("image size {w}x{h} is too large"))),
    };
    let n = w * h;
    if let Some(c) = channels.iter().find(|c| c.len() != n) {
        return Err(unsupported(format!(
            "a colour channel holds {} samples for {w}x{h} pixels (subsampled channels are not supported)",
            c.len()
        )));
    }

    let mut data = vec![[0.0f32; 3]; n];
    if let [grey] = channels[..] {
        for (p, v) in data.iter_mut().zip(grey.values_as_f32()) {
            *p = [v; 3];
        }
    } else {
        for (c, samples) in channels.iter().enumerate() {
            for (p, v) in data.iter_mut().zip(samples.values_as_f32()) {
                p[c] = v;
            }
        }
    }
    Ok((
        Image {
            width,
            height,
            data,
        },
        read_meta(layer),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::scratch_dir;
    use exr::prelude::f16;

    fn test_image() -> Image {
        // 3x2, non-square, every value distinct, including values that need all 32 bits.
        let mut img = Image::new(3, 2);
        for y in 0..2 {
            for x in 0..3 {
                let base = (y * 3 + x) as f32;
                img.set(
                    x,
                    y,
                    [
                        base + 0.1,
                        -base * 1e-7 - 1.0 / 3.0,
                        base * 1e30 + f32::MIN_POSITIVE,
                    ],
                );
            }
        }
        img
    }

    #[test]
    fn round_trip_is_bit_exact_with_metadata() {
        let dir = scratch_dir("exr-roundtrip");
        let path = dir.join("a.exr");
        let img = test_image();
        let meta = ExrMeta {
            spp: Some(1024),
            mode: Some("spectral".into()),
            render_time_s: Some(12.345678901234),
            extra: vec![
                ("scene".into(), "cornell-box.xml".into()),
                ("integrator".into(), "path".into()),
            ],
        };
        write_exr(&path, &img, &meta).unwrap();
        let (back, meta_back) = read_exr(&path).unwrap();
        assert_eq!((back.width, back.height), (3, 2));
        for (a, b) in img.data.iter().zip(&back.data) {
            for c in 0..3 {
                assert_eq!(a[c].to_bits(), b[c].to_bits());
            }
        }
        assert_eq!(back.get(2, 0), img.get(2, 0), "transposed?");
        assert_eq!(meta_back.spp, meta.spp);
        assert_eq!(meta_back.mode, meta.mode);
        assert_eq!(meta_back.render_time_s, meta.render_time_s);
        let mut extra = meta.extra.clone();
        extra.sort();
        assert_eq!(meta_back.extra, extra);
        // Only the target is left in the directory.
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn round_trip_without_metadata_and_special_values() {
        let dir = scratch_dir("exr-special");
        let path = dir.join("b.exr");
        let mut img = Image::new(2, 1);
        img.set(0, 0, [f32::NAN, f32::INFINITY, -0.0]);
        img.set(1, 0, [f32::MAX, -f32::INFINITY, 1e-45]);
        write_exr(&path, &img, &ExrMeta::default()).unwrap();
        let (back, meta) = read_exr(&path).unwrap();
        assert_eq!(meta, ExrMeta::default());
        for (a, b) in img.data.iter().zip(&back.data) {
            for c in 0..3 {
                assert_eq!(a[c].to_bits(), b[c].to_bits());
            }
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn write_into_missing_directory_is_an_error_and_leaves_nothing() {
        let dir = scratch_dir("exr-nodir");
        let path = dir.join("does-not-exist").join("a.exr");
        let err = write_exr(&path, &test_image(), &ExrMeta::default()).unwrap_err();
        assert!(err.to_string().contains("does-not-exist"), "{err}");
        assert!(!path.exists());
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn failed_write_removes_temporary_file() {
        // Non-Latin-1 metadata is rejected before any file is created; a malformed image too.
        let dir = scratch_dir("exr-badmeta");
        let path = dir.join("a.exr");
        let meta = ExrMeta {
            mode: Some("spectral \u{1F308}".into()),
            ..Default::default()
        };
        assert!(matches!(
            write_exr(&path, &test_image(), &meta),
            Err(ImageError::InvalidMeta { .. })
        ));
        let reserved = ExrMeta {
            extra: vec![("channels".into(), "x".into())],
            ..Default::default()
        };
        assert!(write_exr(&path, &test_image(), &reserved).is_err());
        let mut bad = test_image();
        bad.data.pop();
        assert!(matches!(
            write_exr(&path, &bad, &ExrMeta::default()),
            Err(ImageError::InvalidImage { .. })
        ));
        assert!(write_exr(&path, &Image::new(0, 5), &ExrMeta::default()).is_err());
        // An attribute name with NUL makes the encoder fail after the temporary file exists.
        let nul = ExrMeta {
            extra: vec![("a\0b".into(), "x".into())],
            ..Default::default()
        };
        assert!(write_exr(&path, &test_image(), &nul).is_err());
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn missing_file_is_an_error_naming_it() {
        let err = read_exr(Path::new("/nonexistent/dir/missing.exr")).unwrap_err();
        assert!(matches!(err, ImageError::Io { .. }));
        assert!(err.to_string().contains("missing.exr"), "{err}");
    }

    #[test]
    fn truncated_and_garbage_files_are_errors() {
        let dir = scratch_dir("exr-truncated");
        let good = dir.join("good.exr");
        // Large enough for several scan-line blocks, noisy so that compression cannot shrink it.
        let mut img = Image::new(64, 48);
        let mut s = 1u32;
        for p in &mut img.data {
            for v in p.iter_mut() {
                s ^= s << 13;
                s ^= s >> 17;
                s ^= s << 5;
                *v = s as f32 / u32::MAX as f32;
            }
        }
        write_exr(&good, &img, &ExrMeta::default()).unwrap();
        let bytes = std::fs::read(&good).unwrap();
        for (name, len) in [
            ("half.exr", bytes.len() / 2),
            ("header.exr", 20),
            ("empty.exr", 0),
        ] {
            let p = dir.join(name);
            std::fs::write(&p, &bytes[..len]).unwrap();
            let err = read_exr(&p).unwrap_err();
            assert!(err.to_string().contains(name), "{err}");
        }
        let garbage = dir.join("garbage.exr");
        std::fs::write(&garbage, b"this is not an EXR file at all, just text").unwrap();
        assert!(read_exr(&garbage).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn half_float_rgba_file_reads_correctly() {
        let dir = scratch_dir("exr-half");
        let path = dir.join("half.exr");
        let (w, h) = (5usize, 3usize);
        // Values exactly representable in f16, distinct per pixel and channel.
        let value = |x: usize, y: usize, c: usize| (y * w + x) as f32 * 0.25 + c as f32 * 8.0;
        exr::prelude::write_rgba_file(&path, w, h, |x, y| {
            (
                f16::from_f32(value(x, y, 0)),
                f16::from_f32(value(x, y, 1)),
                f16::from_f32(value(x, y, 2)),
                f16::from_f32(0.5),
            )
        })
        .unwrap();
        let (img, meta) = read_exr(&path).unwrap();
        assert_eq!((img.width, img.height), (5, 3));
        for y in 0..h {
            for x in 0..w {
                let expect = [value(x, y, 0), value(x, y, 1), value(x, y, 2)];
                assert_eq!(img.get(x as u32, y as u32), expect, "pixel ({x}, {y})");
            }
        }
        assert_eq!(meta.spp, None);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    fn write_channels(path: &Path, w: usize, h: usize, channels: Vec<(&str, FlatSamples)>) {
        let list = channels
            .into_iter()
            .map(|(n, s)| x::AnyChannel::new(n, s))
            .collect();
        let layer = x::Layer::new(
            (w, h),
            LayerAttributes::default(),
            Encoding::UNCOMPRESSED,
            x::AnyChannels::sort(list),
        );
        x::Image::from_layer(layer).write().to_file(path).unwrap();
    }

    #[test]
    fn luminance_and_u32_channels() {
        let dir = scratch_dir("exr-y");
        let y_path = dir.join("y.exr");
        write_channels(
            &y_path,
            2,
            2,
            vec![("Y", FlatSamples::F32(vec![1.0, 2.0, 3.0, 4.0]))],
        );
        let (img, _) = read_exr(&y_path).unwrap();
        assert_eq!(img.get(1, 1), [4.0; 3]);
        assert_eq!(img.get(1, 0), [2.0; 3]);

        let u_path = dir.join("u.exr");
        write_channels(
            &u_path,
            1,
            2,
            vec![
                ("R", FlatSamples::U32(vec![1, 2])),
                ("G", FlatSamples::U32(vec![3, 4])),
                ("B", FlatSamples::U32(vec![5, 6])),
            ],
        );
        let (img, _) = read_exr(&u_path).unwrap();
        assert_eq!(img.data, vec![[1.0, 3.0, 5.0], [2.0, 4.0, 6.0]]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn missing_colour_channels_is_an_error_listing_channels() {
        let dir = scratch_dir("exr-nocolour");
        let path = dir.join("depth.exr");
        write_channels(
            &path,
            1,
            1,
            vec![
                ("R", FlatSamples::F32(vec![1.0])),
                ("Z", FlatSamples::F32(vec![1.0])),
            ],
        );
        let err = read_exr(&path).unwrap_err();
        assert!(matches!(err, ImageError::MissingChannels { .. }));
        let msg = err.to_string();
        assert!(msg.contains("depth.exr") && msg.contains('Z'), "{msg}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Named channels round-trip bit for bit, layer-style names included; the reader returns
    /// them in the file's alphabetical order; a wrong plane length or a repeated name is an
    /// error that writes nothing.
    #[test]
    fn named_channels_round_trip() {
        let dir = scratch_dir("named_channels");
        let path = dir.join("c.exr");
        let a: Vec<f32> = (0..6).map(|i| i as f32 * 0.25 - 1e-30).collect();
        let b: Vec<f32> = (0..6).map(|i| -(i as f32) / 3.0).collect();
        write_exr_channels(
            &path,
            3,
            2,
            &[("R", &a), ("nn.X", &b), ("A", &a)],
            &ExrMeta::default(),
        )
        .expect("write");
        let (w, h, channels) = read_exr_channels(&path).expect("read");
        assert_eq!((w, h), (3, 2));
        let names: Vec<&str> = channels.iter().map(|c| c.0.as_str()).collect();
        assert_eq!(names, ["A", "R", "nn.X"]);
        assert_eq!(channels[1].1, a);
        assert_eq!(channels[2].1, b);
        let bad = dir.join("bad.exr");
        assert!(write_exr_channels(&bad, 3, 2, &[("R", &a[..5])], &ExrMeta::default()).is_err());
        assert!(
            write_exr_channels(&bad, 3, 2, &[("R", &a), ("R", &b)], &ExrMeta::default()).is_err()
        );
        assert!(!bad.exists());
    }
}
