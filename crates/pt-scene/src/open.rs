//! Opening a scene the way every front end does (`pt` and the Python module): a Mitsuba 3 XML
//! file, a glTF 2.0 file (by its extension), or the built-in Cornell box when no file is given.

use crate::{gltf, IntegratorKind, SceneDesc, SceneError};
use std::path::Path;

/// The Cornell box rendered when no scene is given (`scenes/cornell-box.xml`, embedded).
pub const BUILTIN_CORNELL: &str = include_str!("../../../scenes/cornell-box.xml");

/// The name the built-in Cornell box's errors and outputs go by.
pub const BUILTIN_CORNELL_NAME: &str = "<built-in cornell-box.xml>";

/// A scene opened by [`open`].
#[derive(Debug)]
pub struct Opened {
    /// The scene.
    pub desc: SceneDesc,
    /// glTF files: the listing `pt info` prints (meshes, materials, lights, cameras); empty for
    /// XML scenes.
    pub summary: Vec<String>,
    /// Things the user must know (glTF defaults used, features ignored; media the `path`
    /// integrator skips), one line each.
    pub warnings: Vec<String>,
}

/// Opens `path` (a Mitsuba XML scene, or glTF when it ends in `.gltf` / `.glb`), or the
/// built-in Cornell box when `path` is `None`.
///
/// `defines` are Mitsuba's `-D name=value` parameters (XML scenes only); `camera` picks a glTF
/// file's camera (0-based, in node order; glTF only). Either given for the other kind of file
/// is an error rather than silently ignored.
pub fn open(
    path: Option<&Path>,
    defines: &[(String, String)],
    camera: Option<usize>,
) -> Result<Opened, SceneError> {
    if let Some(p) = path.filter(|p| gltf::is_gltf_path(p)) {
        if !defines.is_empty() {
            return Err(SceneError::global(
                "-D applies to Mitsuba XML scenes, not to glTF files",
            ));
        }
        let g = gltf::load(p, &gltf::LoadOptions { camera })
            .map_err(|e| SceneError::global(e.to_string()))?;
        return Ok(Opened {
            desc: g.desc,
            summary: g.summary,
            warnings: g.warnings,
        });
    }
    if camera.is_some() {
        return Err(SceneError::global(
            "--camera applies to glTF files (a Mitsuba XML scene has one sensor)",
        ));
    }
    let desc = match path {
        Some(p) => crate::load_file(p, defines)?,
        // The built-in box names no other file: its folder is never read.
        None => crate::load_str(
            BUILTIN_CORNELL,
            Path::new(BUILTIN_CORNELL_NAME),
            Path::new("."),
            defines,
        )?,
    };
    let mut warnings = Vec::new();
    if desc.integrator.kind == IntegratorKind::Path {
        let medium = desc.camera_medium.as_ref().or_else(|| {
            desc.shapes
                .iter()
                .find_map(|s| s.interior.as_ref().or(s.exterior.as_ref()))
        });
        if let Some(m) = medium {
            warnings.push(format!(
                "{}: the `path` integrator ignores media, as Mitsuba's does; use <integrator type=\"volpath\"> to trace them",
                m.loc
            ));
        }
    }
    Ok(Opened {
        desc,
        summary: Vec::new(),
        warnings,
    })
}
