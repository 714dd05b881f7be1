//! Scene description for the path tracer: the IR the renderer consumes ([`SceneDesc`] and
//! friends, in world space), a loader for the subset of Mitsuba 3's XML scene format that
//! the renderer supports, so that one scene file drives both renderers, and a glTF 2.0 reader
//! ([`gltf`]).
//!
//! ```
//! use pt_scene::{load_str, Geometry, IntegratorKind};
//! use std::path::Path;
//!
//! let xml = r#"
//!     <scene version="3.0.0">
//!         <default name="spp" value="16"/>
//!         <integrator type="path"><integer name="max_depth" value="4"/></integrator>
//!         <sensor type="perspective">
//!             <float name="fov" value="40"/>
//!             <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
//!             <film type="hdrfilm"><integer name="width" value="64"/></film>
//!         </sensor>
//!         <shape type="sphere"><float name="radius" value="2"/></shape>
//!     </scene>"#;
//! // Like `mitsuba -D spp=4 scene.xml`: command-line values override <default>s.
//! let defaults = [("spp".to_string(), "4".to_string())];
//! let scene = load_str(xml, Path::new("<built-in>"), Path::new("."), &defaults)?;
//! assert_eq!(scene.sampler.sample_count, 4);
//! assert_eq!(scene.integrator.kind, IntegratorKind::Path);
//! assert_eq!((scene.film.width, scene.film.height), (64, 576));
//! assert!(matches!(scene.shapes[0].geometry, Geometry::Sphere { radius: 2.0, .. }));
//! # Ok::<(), pt_scene::SceneError>(())
//! ```
//!
//! # Supported XML
//!
//! Every plugin and parameter this loader reads, Mitsuba's and the extensions, is listed with a
//! snippet in `scenes/README.md` (a test loads each snippet, and checks that every plugin the
//! loader accepts is documented there).
//!
//! Everything else is an error naming the file, line, column and element: unknown elements and
//! plugins, Mitsuba plugins not implemented yet ("not yet implemented"), properties a plugin
//! does not read (Mitsuba 3 rejects those too), values of the wrong type, malformed or
//! non-finite numbers. The loader never panics on bad input.

#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod build;
mod curves;
mod error;
pub mod gltf;
pub mod ies;
pub mod ir;
pub mod named;
mod obj;
mod open;
mod ply;
mod props;
mod serialized;
mod shapes;
mod transform;
pub mod volgrid;
mod xml;

#[cfg(test)]
mod tests;

pub use error::SceneError;
pub use ir::*;
pub use named::{conductor_names, ior_names, named_conductor, named_ior, NamedConductor};
pub use open::{open, Opened, BUILTIN_CORNELL, BUILTIN_CORNELL_NAME};
pub use props::PropValue;
pub use shapes::cylinder_bounds;

use std::path::Path;

/// Loads a Mitsuba 3 XML scene file.
///
/// `defaults` are (name, value) pairs that override the file's `<default>` elements, like
/// Mitsuba's `-D name=value` command-line option. Relative filenames in the scene (meshes,
/// includes) are resolved from the scene file's folder.
pub fn load_file(path: &Path, defaults: &[(String, String)]) -> Result<SceneDesc, SceneError> {
    let xml = std::fs::read_to_string(path).map_err(|e| {
        SceneError::global(format!(
            "{}: cannot open scene file: {}",
            path.display(),
            error::io_message(&e)
        ))
    })?;
    let base_dir = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    load_str(&xml, path, base_dir, defaults)
}

/// Loads a scene from a string (for built-in scenes).
///
/// `source_name` names the scene in messages and in [`SourceLoc`]s; `base_dir` is where
/// relative filenames are resolved from. `defaults` act as in [`load_file`].
pub fn load_str(
    xml: &str,
    source_name: &Path,
    base_dir: &Path,
    defaults: &[(String, String)],
) -> Result<SceneDesc, SceneError> {
    let doc = xml::read_document(xml, source_name, base_dir, defaults)?;
    build::build(&doc, source_name, base_dir)
}

/// Reads a BSDF model plugin (`diffuse`, `orennayar`, `roughconductor`, ...; not the wrappers
/// `twosided`, `mask`, `blendbsdf`, `normalmap`) from properties given in code, exactly as the
/// XML loader reads `<bsdf type="plugin">` with these properties: the same names, defaults,
/// named materials, validation and messages (Mitsuba 3's). Errors are located at
/// `<properties>:0:0` and name the plugin; an unknown plugin or a property the plugin does not
/// have is an error, as in a file.
///
/// ```
/// use pt_scene::{bsdf_from_properties, BsdfKind, OrenNayarVariant, PropValue};
///
/// let props = [("sigma".to_string(), PropValue::Float(0.3))];
/// let desc = bsdf_from_properties("orennayar", &props)?;
/// assert!(matches!(desc.kind, BsdfKind::OrenNayar { variant: OrenNayarVariant::Qualitative, .. }));
/// let typo = [("sigmaa".to_string(), PropValue::Float(0.3))];
/// assert!(bsdf_from_properties("orennayar", &typo).unwrap_err().message.contains("unused property 'sigmaa'"));
/// # Ok::<(), pt_scene::SceneError>(())
/// ```
pub fn bsdf_from_properties(
    plugin: &str,
    props: &[(String, PropValue)],
) -> Result<BsdfDesc, SceneError> {
    build::bsdf_from_properties(plugin, props)
}
