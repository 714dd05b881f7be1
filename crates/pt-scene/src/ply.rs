//! Stanford PLY meshes (Turk 1994, "The PLY polygon file format"), read as a stream, as
//! Mitsuba 3.9.1's `ply` plugin interprets them.
//!
//! The header (`ply`, `format ascii | binary_little_endian | binary_big_endian 1.0`, `comment`
//! lines, `element NAME COUNT`, `property TYPE NAME`, `property list COUNT_TYPE ITEM_TYPE
//! NAME`, `end_header`) declares the elements in file order; the data follows, element by
//! element, each record as whitespace-separated numbers (ascii) or packed values (binary).
//! Types: `char uchar short ushort int uint float double` and their sized names `int8 uint8
//! int16 uint16 int32 uint32 float32 float64`.
//!
//! What the mesh takes from the `vertex` element: `x y z` (required); `nx ny nz`; texture
//! coordinates `u v` (or `texture_u texture_v`, or `s t`, in that order of preference), used as
//! stored; colours `red green blue` or `r g b` as the attribute `vertex_color`; and, by
//! Mitsuba's rule, properties named `PREFIX_c` in runs of postfixes `x y z`, `r g b`, `0 1 2`
//! or `1 2 3` (or one alone) as the attribute `vertex_PREFIX` of 1 or 3 values
//! (`vertex_PREFIX_color` for `r g b`). From the `face` element: the list `vertex_indices` (or
//! `vertex_index`), and attributes named as for vertices with the prefix `face_`. Other
//! elements (`edge`, `material`, ...) and other properties are read past and dropped.
//!
//! Where pt reads more than Mitsuba 3.9.1 (which refuses these files): polygons of n > 3
//! corners become the fan (0, i, i + 1); `obj_info` header lines are skipped; data after the
//! last element is ignored. Where it reads differently: integer colours are fractions of the
//! type's range, sRGB-encoded, for every integer type (Mitsuba decodes them so except `uchar`,
//! which it keeps as 0..255 with a warning that colours should be in [0, 1]); other integer
//! properties (positions, uvs, attributes) are their values (Mitsuba 3.9.1 also divides them
//! by the type's maximum and sRGB-decodes them, which turns integer positions into fractions).
//! Alpha channels are dropped (attributes have 1 or 3 values). Triangles that name a vertex
//! past the end are refused (Mitsuba reads past its buffer).
//!
//! The reader holds the vertex arrays and the triangles, nothing per record: an element's
//! records are decoded one at a time into a fixed buffer.

use crate::error::io_message;
use crate::ir::{AttributeKind, MeshAttribute};
use crate::shapes::LocalMesh;
use glam::{Vec2, Vec3};
use std::io::BufRead;
use std::path::Path;

/// Loads a PLY file into an object-space mesh. Errors name the file as the scene names it
/// (`shown_name`), and the header line or the element record at fault.
pub(crate) fn load_ply(path: &Path, shown_name: &str) -> std::result::Result<LocalMesh, String> {
    let file = std::fs::File::open(path)
        .map_err(|e| format!("cannot open mesh '{shown_name}': {}", io_message(&e)))?;
    read_ply(std::io::BufReader::with_capacity(1 << 16, file))
        .map_err(|e| format!("PLY mesh '{shown_name}': {e}"))
}

/// How the data after the header is encoded.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Format {
    Ascii,
    BinaryLittle,
    BinaryBig,
}

/// A scalar type of the format.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    /// The factor that maps the type's range onto [0, 1] for colours (1 for floats).
    fn colour_scale(self) -> f64 {
        match self {
            Scalar::U8 | Scalar::I8 => 1.0 / 255.0,
            Scalar::U16 | Scalar::I16 => 1.0 / 65535.0,
            _ => 1.0,
        }
    }
}

/// A property of an element: a scalar, or a list with its count type.
#[derive(Clone, Debug)]
struct Property {
    name: String,
    kind: Scalar,
    /// The count type of a list property.
    list: Option<Scalar>,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
}

/// Reads a PLY file's bytes.
pub(crate) fn read_ply(mut r: impl BufRead) -> std::result::Result<LocalMesh, String> {
    let (format, elements) = read_header(&mut r)?;
    let mut data = Data::new(r, format);
    let mut mesh = LocalMesh::default();
    let mut have_vertices = false;
    for el in &elements {
        match el.name.as_str() {
            "vertex" => {
                read_vertices(&mut data, el, &mut mesh)?;
                have_vertices = true;
            }
            "face" => {
                if !have_vertices {
                    return Err("the face element comes before the vertex element".into());
                }
                read_faces(&mut data, el, &mut mesh)?;
            }
            _ => skip_element(&mut data, el)?,
        }
    }
    if !have_vertices {
        return Err("no vertex element".into());
    }
    Ok(mesh)
}

fn read_header<R: BufRead>(r: &mut R) -> std::result::Result<(Format, Vec<Element>), String> {
    let mut line = String::new();
    let mut n = 0;
    let mut next_line = |line: &mut String| -> std::result::Result<bool, String> {
        line.clear();
        n += 1;
        // The header is ASCII text; a line longer than this is not one.
        let read = <&mut R as std::io::Read>::take(&mut *r, 4096)
            .read_line(line)
            .map_err(|e| format!("header line {n}: {}", io_message(&e)))?;
        Ok(read > 0)
    };
    if !next_line(&mut line)? || line.trim_end() != "ply" {
        return Err("not a PLY file (the first line is not 'ply')".into());
    }
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut line_no = 1;
    loop {
        line_no += 1;
        if !next_line(&mut line)? {
            return Err("the header has no 'end_header' line".into());
        }
        let err = |msg: String| format!("header line {line_no}: {msg}");
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            [] | ["comment", ..] | ["obj_info", ..] => {}
            ["format", f, version] => {
                if *version != "1.0" {
                    return Err(err(format!("unsupported version {version}")));
                }
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::BinaryLittle,
                    "binary_big_endian" => Format::BinaryBig,
                    other => return Err(err(format!("unknown format '{other}'"))),
                });
            }
            ["element", name, count] => {
                let count = count
                    .parse()
                    .map_err(|_| err(format!("bad element count '{count}'")))?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    properties: Vec::new(),
                });
            }
            ["property", "list", count, item, name] => {
                let el = elements
                    .last_mut()
                    .ok_or_else(|| err("a property before any element".into()))?;
                let scalar =
                    |t: &str| Scalar::parse(t).ok_or_else(|| err(format!("unknown type '{t}'")));
                let (count, kind) = (scalar(count)?, scalar(item)?);
                if matches!(count, Scalar::F32 | Scalar::F64) {
                    return Err(err(format!("a list count of type '{}'", words[2])));
                }
                el.properties.push(Property {
                    name: name.to_string(),
                    kind,
                    list: Some(count),
                });
            }
            ["property", t, name] => {
                let el = elements
                    .last_mut()
                    .ok_or_else(|| err("a property before any element".into()))?;
                let kind = Scalar::parse(t).ok_or_else(|| err(format!("unknown type '{t}'")))?;
                el.properties.push(Property {
                    name: name.to_string(),
                    kind,
                    list: None,
                });
            }
            ["end_header"] => break,
            _ => return Err(err(format!("cannot read '{}'", line.trim_end()))),
        }
    }
    let format = format.ok_or("the header has no 'format' line")?;
    Ok((format, elements))
}

/// The data section: values by type, in ascii or binary.
struct Data<R> {
    r: R,
    format: Format,
    /// The current ascii token.
    token: Vec<u8>,
}

impl<R: BufRead> Data<R> {
    fn new(r: R, format: Format) -> Self {
        Data {
            r,
            format,
            token: Vec::new(),
        }
    }

    /// The next value, as f64 (exact for every type of the format but 64-bit integers,
    /// which it does not have).
    fn value(&mut self, t: Scalar) -> std::result::Result<f64, String> {
        match self.format {
            Format::Ascii => self.ascii(),
            Format::BinaryLittle | Format::BinaryBig => {
                let mut b = [0u8; 8];
                let n = t.size();
                self.r.read_exact(&mut b[..n]).map_err(|e| match e.kind() {
                    std::io::ErrorKind::UnexpectedEof => "the file ends early".to_string(),
                    _ => io_message(&e),
                })?;
                if self.format == Format::BinaryBig {
                    b[..n].reverse();
                }
                Ok(match t {
                    Scalar::I8 => f64::from(b[0] as i8),
                    Scalar::U8 => f64::from(b[0]),
                    Scalar::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
                    Scalar::U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
                    Scalar::I32 => f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
                    Scalar::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
                    Scalar::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
                    Scalar::F64 => f64::from_le_bytes(b),
                })
            }
        }
    }

    /// The next whitespace-separated ascii number.
    fn ascii(&mut self) -> std::result::Result<f64, String> {
        self.token.clear();
        loop {
            let buf = self.r.fill_buf().map_err(|e| io_message(&e))?;
            if buf.is_empty() {
                break;
            }
            let mut used = 0;
            let mut done = false;
            for &c in buf {
                if c.is_ascii_whitespace() {
                    used += 1;
                    if !self.token.is_empty() {
                        done = true;
                        break;
                    }
                } else {
                    if self.token.len() > 64 {
                        return Err("a number longer than 64 characters".into());
                    }
                    self.token.push(c);
                    used += 1;
                }
            }
            self.r.consume(used);
            if done {
                break;
            }
        }
        if self.token.is_empty() {
            return Err("the file ends early".into());
        }
        std::str::from_utf8(&self.token)
            .ok()
            .and_then(|s| s.parse::<f64>().ok())
            .ok_or_else(|| format!("'{}' is not a number", String::from_utf8_lossy(&self.token)))
    }

    /// A list's length.
    fn count(&mut self, t: Scalar) -> std::result::Result<usize, String> {
        let n = self.value(t)?;
        if n < 0.0 || n.fract() != 0.0 {
            return Err(format!("list length {n}"));
        }
        Ok(n as usize)
    }
}

/// Reads past an element the mesh does not use.
fn skip_element(d: &mut Data<impl BufRead>, el: &Element) -> std::result::Result<(), String> {
    // Records without properties occupy no bytes, however many the header declares.
    if el.properties.is_empty() {
        return Ok(());
    }
    for i in 0..el.count {
        for p in &el.properties {
            let n = match p.list {
                Some(c) => d.count(c),
                None => Ok(1),
            }
            .map_err(|e| format!("{} {i}: {e}", el.name))?;
            for _ in 0..n {
                d.value(p.kind)
                    .map_err(|e| format!("{} {i}: {e}", el.name))?;
            }
        }
    }
    Ok(())
}

/// Elements reserved before reading: counts come from the header, so a corrupt count must not
/// allocate gigabytes up front; the vectors grow past this as the data really arrives.
const PREALLOCATE: usize = 1 << 20;

/// What a property of the vertex or face element becomes.
#[derive(Clone, Copy, PartialEq)]
enum Role {
    Position(usize),
    Normal(usize),
    Uv(usize),
    Colour(usize),
    /// Component `.1` of attribute `.0`.
    Attribute(usize, usize),
    /// The face's vertex list.
    Indices,
    /// Read and dropped.
    Skip,
}

/// The texture-coordinate names Mitsuba 3.9.1 accepts, as (u, v) pairs, first match wins.
const UV_NAMES: [(&str, &str); 3] = [("u", "v"), ("texture_u", "texture_v"), ("s", "t")];

/// The postfix sequences that group properties `PREFIX_c` into one attribute (Mitsuba's
/// rule): runs of consecutive properties with one prefix and these postfixes in order.
const SEQUENCES: [&str; 4] = ["xyzw", "rgba", "0123", "1234"];

/// The roles of an element's properties and the attributes they fill (`kind` prefixes the
/// attribute names: `vertex_` or `face_`). Reserved names (positions, normals, uvs, colours,
/// the index list) take their roles; every other scalar named `PREFIX_c` joins a run of
/// postfixes `x y z`, `r g b`, `0 1 2` or `1 2 3` that becomes the attribute
/// `KIND_PREFIX` (`KIND_PREFIX_color` for `r g b`) of 1 or 3 values; other names are
/// dropped, as Mitsuba drops them (with a warning there).
fn layout(el: &Element, kind: AttributeKind) -> (Vec<Role>, Vec<MeshAttribute>) {
    let names: Vec<&str> = el.properties.iter().map(|p| p.name.as_str()).collect();
    let has = |n: &str| names.contains(&n);
    let vertex = kind == AttributeKind::Vertex;
    let uv_pair = UV_NAMES.iter().find(|(u, v)| vertex && has(u) && has(v));
    let colours = if has("red") && has("green") && has("blue") {
        Some(["red", "green", "blue", "alpha"])
    } else if has("r") && has("g") && has("b") {
        Some(["r", "g", "b", "a"])
    } else {
        None
    };
    let normals = vertex && ["nx", "ny", "nz"].iter().all(|n| has(n));
    let mut attributes = Vec::new();
    if colours.is_some() {
        attributes.push(attribute(kind, "color", 3));
    }
    let prefix_name = if vertex { "vertex" } else { "face" };
    // The open run: prefix, sequence, components so far, their property indices.
    let mut run: Option<(&str, &str, Vec<usize>)> = None;
    let mut roles = vec![Role::Skip; el.properties.len()];
    let close = |run: &mut Option<(&str, &str, Vec<usize>)>,
                 roles: &mut Vec<Role>,
                 attributes: &mut Vec<MeshAttribute>| {
        if let Some((prefix, seq, members)) = run.take() {
            let suffix = if seq == "rgba" && members.len() == 3 {
                "_color"
            } else {
                ""
            };
            let name = format!("{prefix_name}_{prefix}{suffix}");
            if (members.len() == 1 || members.len() == 3)
                && !attributes.iter().any(|a: &MeshAttribute| a.name == name)
            {
                attributes.push(MeshAttribute {
                    name,
                    kind,
                    dims: members.len() as u32,
                    values: Vec::new(),
                });
                for (c, &m) in members.iter().enumerate() {
                    roles[m] = Role::Attribute(attributes.len() - 1, c);
                }
            }
        }
    };
    for (i, p) in el.properties.iter().enumerate() {
        let n = p.name.as_str();
        let reserved =
            if !vertex && p.list.is_some() && (n == "vertex_indices" || n == "vertex_index") {
                Some(Role::Indices)
            } else if p.list.is_some() {
                Some(Role::Skip)
            } else if let Some(k) = ["x", "y", "z"].iter().position(|&c| vertex && c == n) {
                Some(Role::Position(k))
            } else if let Some(k) = ["nx", "ny", "nz"].iter().position(|&c| normals && c == n) {
                Some(Role::Normal(k))
            } else if let Some(k) = uv_pair.and_then(|(u, v)| [*u, *v].iter().position(|&c| c == n))
            {
                Some(Role::Uv(k))
            } else if let Some(k) = colours.and_then(|c| c.iter().position(|&c| c == n)) {
                // Alpha is read and dropped: attributes have 1 or 3 values.
                Some(if k < 3 {
                    Role::Attribute(0, k)
                } else {
                    Role::Skip
                })
            } else if ["x", "y", "z", "nx", "ny", "nz"].contains(&n) {
                Some(Role::Skip)
            } else {
                None
            };
        if let Some(role) = reserved {
            close(&mut run, &mut roles, &mut attributes);
            roles[i] = match role {
                Role::Attribute(0, k) => Role::Colour(k),
                r => r,
            };
            continue;
        }
        let Some((prefix, postfix)) = n
            .rsplit_once('_')
            .filter(|(a, b)| !a.is_empty() && b.len() == 1)
        else {
            close(&mut run, &mut roles, &mut attributes);
            continue;
        };
        let c = postfix.as_bytes()[0];
        let continues = match &run {
            Some((pre, seq, members)) => {
                *pre == prefix && seq.as_bytes().get(members.len()) == Some(&c)
            }
            None => false,
        };
        if continues {
            if let Some((_, _, members)) = &mut run {
                members.push(i);
            }
            continue;
        }
        close(&mut run, &mut roles, &mut attributes);
        if let Some(seq) = SEQUENCES.iter().find(|s| s.as_bytes()[0] == c) {
            run = Some((prefix, seq, vec![i]));
        }
    }
    close(&mut run, &mut roles, &mut attributes);
    (roles, attributes)
}

/// A mesh attribute without values yet.
fn attribute(kind: AttributeKind, name: &str, dims: u32) -> MeshAttribute {
    let prefix = if kind == AttributeKind::Vertex {
        "vertex"
    } else {
        "face"
    };
    MeshAttribute {
        name: format!("{prefix}_{name}"),
        kind,
        dims,
        values: Vec::new(),
    }
}

/// sRGB to linear (IEC 61966-2-1), for integer colours.
fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Reads one record's scalar values into `values` (one per property; lists are read past,
/// except the face's index list, which goes into `corners`).
fn read_record(
    d: &mut Data<impl BufRead>,
    el: &Element,
    roles: &[Role],
    values: &mut [f64],
    corners: &mut Vec<u32>,
    vertices: usize,
    i: usize,
) -> std::result::Result<(), String> {
    for (k, (prop, role)) in el.properties.iter().zip(roles).enumerate() {
        let err = |e: String| format!("{} {i}, property '{}': {e}", el.name, prop.name);
        if let Some(count_type) = prop.list {
            let len = d.count(count_type).map_err(err)?;
            if *role != Role::Indices {
                for _ in 0..len {
                    d.value(prop.kind).map_err(err)?;
                }
                continue;
            }
            if len < 3 {
                return Err(err(format!("a face of {len} corners")));
            }
            corners.clear();
            for _ in 0..len {
                let x = d.value(prop.kind).map_err(err)?;
                if !(x >= 0.0 && x.fract() == 0.0 && (x as usize) < vertices) {
                    return Err(err(format!(
                        "vertex index {x} is out of range (the mesh has {vertices} vertices)"
                    )));
                }
                corners.push(x as u32);
            }
            continue;
        }
        let x = d.value(prop.kind).map_err(err)?;
        values[k] = match role {
            // Integer colours are sRGB-encoded fractions of the type's range.
            Role::Colour(_) if prop.kind.colour_scale() != 1.0 => {
                srgb_to_linear(x * prop.kind.colour_scale())
            }
            _ => x,
        };
    }
    Ok(())
}

fn read_vertices(
    d: &mut Data<impl BufRead>,
    el: &Element,
    mesh: &mut LocalMesh,
) -> std::result::Result<(), String> {
    let (roles, mut attributes) = layout(el, AttributeKind::Vertex);
    for axis in 0..3 {
        if !roles.contains(&Role::Position(axis)) {
            return Err(format!(
                "the vertex element has no property '{}'",
                ["x", "y", "z"][axis]
            ));
        }
    }
    let normals = roles.contains(&Role::Normal(0));
    let uvs = roles.contains(&Role::Uv(0));
    let cap = el.count.min(PREALLOCATE);
    mesh.positions = Vec::with_capacity(cap);
    let mut ns = Vec::with_capacity(if normals { cap } else { 0 });
    let mut uv = Vec::with_capacity(if uvs { cap } else { 0 });
    let mut values = vec![0f64; el.properties.len()];
    let mut corners = Vec::new();
    for i in 0..el.count {
        read_record(d, el, &roles, &mut values, &mut corners, 0, i)?;
        let (mut p, mut n, mut t) = ([0f32; 3], [0f32; 3], [0f32; 2]);
        for (role, &x) in roles.iter().zip(&values) {
            match *role {
                Role::Position(k) => p[k] = x as f32,
                Role::Normal(k) => n[k] = x as f32,
                Role::Uv(k) => t[k] = x as f32,
                _ => {}
            }
        }
        mesh.positions.push(Vec3::from_array(p));
        if normals {
            ns.push(Vec3::from_array(n));
        }
        if uvs {
            uv.push(Vec2::from_array(t));
        }
        push_attributes(&roles, &values, &mut attributes, 1);
    }
    mesh.normals = normals.then_some(ns);
    mesh.uvs = uvs.then_some(uv);
    mesh.attributes.extend(attributes);
    Ok(())
}

/// Appends one record's attribute values, `repeat` times (a polygon's values go to each of its
/// triangles).
fn push_attributes(
    roles: &[Role],
    values: &[f64],
    attributes: &mut [MeshAttribute],
    repeat: usize,
) {
    for (a, attr) in attributes.iter_mut().enumerate() {
        let mut v = [0f32; 3];
        for (role, &x) in roles.iter().zip(values) {
            match *role {
                Role::Attribute(j, c) if j == a => v[c] = x as f32,
                Role::Colour(c) if a == 0 && attr.name.ends_with("_color") => v[c] = x as f32,
                _ => {}
            }
        }
        for _ in 0..repeat {
            attr.values.extend_from_slice(&v[..attr.dims as usize]);
        }
    }
}

fn read_faces(
    d: &mut Data<impl BufRead>,
    el: &Element,
    mesh: &mut LocalMesh,
) -> std::result::Result<(), String> {
    let (roles, mut attributes) = layout(el, AttributeKind::Face);
    if !roles.contains(&Role::Indices) {
        return Err("the face element has no list 'vertex_indices' (or 'vertex_index')".into());
    }
    let vertices = mesh.positions.len();
    let mut indices = Vec::with_capacity(el.count.min(PREALLOCATE));
    let mut values = vec![0f64; el.properties.len()];
    let mut corners: Vec<u32> = Vec::with_capacity(8);
    for i in 0..el.count {
        read_record(d, el, &roles, &mut values, &mut corners, vertices, i)?;
        // Polygons as fans (0, j, j + 1), as the OBJ reader does (Mitsuba reads triangles only).
        for j in 1..corners.len() - 1 {
            indices.push([corners[0], corners[j], corners[j + 1]]);
        }
        push_attributes(&roles, &values, &mut attributes, corners.len() - 2);
    }
    mesh.indices = indices;
    mesh.attributes.extend(attributes);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn read(bytes: &[u8]) -> std::result::Result<LocalMesh, String> {
        read_ply(bytes)
    }

    fn attr<'a>(m: &'a LocalMesh, name: &str) -> &'a MeshAttribute {
        m.attributes
            .iter()
            .find(|a| a.name == name)
            .unwrap_or_else(|| panic!("no attribute {name} in {:?}", m.attributes))
    }

    /// A file written by Mitsuba 3.9.1's own `write_ply` (binary little endian, uvs as `s t`,
    /// a 3-value attribute `color_0..2`, a face attribute `id_0`), which Mitsuba reads back
    /// as these arrays and the attributes `vertex_color` and `face_id`.
    #[test]
    fn reads_a_file_mitsuba_wrote() {
        let m = read(include_bytes!("tests/data/mitsuba_written.ply")).unwrap();
        let v = |x, y, z| Vec3::new(x, y, z);
        assert_eq!(
            m.positions,
            vec![v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)]
        );
        assert_eq!(m.normals, Some(vec![Vec3::Z; 4]));
        let uv: Vec<Vec2> = [(0., 0.), (1., 0.), (1., 1.), (0., 1.)]
            .map(Vec2::from)
            .to_vec();
        assert_eq!(m.uvs, Some(uv));
        assert_eq!(m.indices, vec![[0, 1, 2], [0, 2, 3]]);
        let c = attr(&m, "vertex_color");
        assert_eq!((c.dims, &c.values[9..]), (3, &[0.5, 0.25, 0.125][..]));
        assert_eq!(attr(&m, "face_id").values, vec![7.0, 9.0]);
    }

    const ASCII: &str = "ply\nformat ascii 1.0\ncomment made by hand\nobj_info x\nelement vertex 5\n\
        property float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\n\
        property uchar blue\nproperty float quality\nproperty float w_x\nproperty float w_y\nproperty float w_z\n\
        element edge 1\nproperty int vertex1\nproperty int vertex2\n\
        element face 2\nproperty list uchar uint vertex_indices\nproperty ushort mat_0\nend_header\n\
        0 0 0 255 0 0 0.5 1 2 3\n1 0 0 0 255 0 0.5 4 5 6\n1 1 0 0 0 255 0.5 7 8 9\n0 1 0 128 128 128 0.5 0 0 0\n\
        0.5 1.5 0 0 0 0 0.5 0 0 0\n0 1\n4 0 1 2 3 3\n3 3 2 4 5\n";

    /// The layout rules: colours (uchar, sRGB-decoded), a `PREFIX_x y z` run, names without
    /// a postfix dropped, a skipped element, a quad as a fan with its face attribute on both
    /// triangles.
    #[test]
    fn ascii_attributes_polygons_and_skipped_elements() {
        let m = read(ASCII.as_bytes()).unwrap();
        assert_eq!(m.positions.len(), 5);
        assert!(m.normals.is_none() && m.uvs.is_none());
        assert_eq!(m.indices, vec![[0, 1, 2], [0, 2, 3], [3, 2, 4]]);
        let c = attr(&m, "vertex_color");
        assert_eq!(&c.values[..3], &[1.0, 0.0, 0.0]);
        // 128 / 255 = 0.50196 encoded: 0.21586 linear.
        assert!((c.values[9] - 0.21586).abs() < 1e-4, "{}", c.values[9]);
        assert_eq!(&attr(&m, "vertex_w").values[3..6], &[4.0, 5.0, 6.0]);
        assert_eq!(attr(&m, "face_mat").values, vec![3.0, 3.0, 5.0]);
        assert!(m.attributes.iter().all(|a| !a.name.contains("quality")));
    }

    /// The same mesh as ascii, binary little endian and binary big endian.
    #[test]
    fn binary_orders_read_like_ascii() {
        let mesh = MeshData::sample();
        let ascii = read(&mesh.file(Format::Ascii)).unwrap();
        for f in [Format::BinaryLittle, Format::BinaryBig] {
            let b = read(&mesh.file(f)).unwrap();
            assert_eq!(b.positions, ascii.positions);
            assert_eq!(b.normals, ascii.normals);
            assert_eq!(b.uvs, ascii.uvs);
            assert_eq!(b.indices, ascii.indices);
        }
        assert_eq!(ascii.indices, mesh.indices);
    }

    #[test]
    fn bad_files_are_refused_with_a_reason() {
        let e = |text: &str| read(text.as_bytes()).unwrap_err();
        assert!(e("plx\n").contains("not a PLY file"));
        assert!(e("ply\nformat ascii 1.0\n").contains("no 'end_header'"));
        assert!(e("ply\nformat ascii 1.1\nend_header\n").contains("line 2: unsupported version"));
        assert!(
            e("ply\nformat ascii 1.0\nelement vertex 1\nproperty real x\nend_header\n")
                .contains("line 4: unknown type 'real'")
        );
        assert!(
            e("ply\nformat ascii 1.0\nelement vertex 1\nproperty float y\nend_header\n0\n")
                .contains("no property 'x'")
        );
        let head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 1 0 0 0 1 0\n";
        assert!(e(&format!("{head}3 0 1 3\n"))
            .contains("face 0, property 'vertex_indices': vertex index 3 is out of range"));
        assert!(e(&format!("{head}2 0 1\n")).contains("a face of 2 corners"));
        assert!(e(&format!("{head}3 0 1\n")).contains("ends early"));
        assert!(e(&format!("{head}3 0 1 x\n")).contains("'x' is not a number"));
        let mut bin = MeshData::sample().file(Format::BinaryLittle);
        bin.truncate(bin.len() - 5);
        assert!(read(&bin).unwrap_err().contains("ends early"));
    }

    /// A mesh to write in each encoding (the tests' writer).
    #[derive(Clone, Debug)]
    struct MeshData {
        positions: Vec<[f32; 3]>,
        normals: bool,
        uvs: bool,
        indices: Vec<[u32; 3]>,
    }

    impl MeshData {
        fn sample() -> Self {
            MeshData {
                positions: vec![
                    [0.0, 0.0, 0.0],
                    [1.5, -2.0, 0.25],
                    [0.0, 1.0, 3.0],
                    [7.0, 8.0, 9.0],
                ],
                normals: true,
                uvs: true,
                indices: vec![[0, 1, 2], [1, 3, 2]],
            }
        }

        /// Vertex k's values: position, then normal (a function of it), then uv.
        fn vertex(&self, k: usize) -> Vec<f32> {
            let p = self.positions[k];
            let mut v = p.to_vec();
            if self.normals {
                v.extend([p[1], -p[0], 1.0]);
            }
            if self.uvs {
                v.extend([p[2] * 0.5, 0.25]);
            }
            v
        }

        fn file(&self, f: Format) -> Vec<u8> {
            let name = match f {
                Format::Ascii => "ascii",
                Format::BinaryLittle => "binary_little_endian",
                Format::BinaryBig => "binary_big_endian",
            };
            let mut h = format!("ply\nformat {name} 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n", self.positions.len());
            if self.normals {
                h += "property float nx\nproperty float ny\nproperty float nz\n";
            }
            if self.uvs {
                h += "property double u\nproperty double v\n";
            }
            h += &format!(
                "element face {}\nproperty list uchar int vertex_indices\nend_header\n",
                self.indices.len()
            );
            let mut out = h.into_bytes();
            let uv_from = 3 + if self.normals { 3 } else { 0 };
            for k in 0..self.positions.len() {
                for (j, x) in self.vertex(k).into_iter().enumerate() {
                    let double = self.uvs && j >= uv_from;
                    match (f, double) {
                        (Format::Ascii, _) => out.extend(format!("{x} ").into_bytes()),
                        (Format::BinaryLittle, false) => out.extend(x.to_le_bytes()),
                        (Format::BinaryBig, false) => out.extend(x.to_be_bytes()),
                        (Format::BinaryLittle, true) => out.extend(f64::from(x).to_le_bytes()),
                        (Format::BinaryBig, true) => out.extend(f64::from(x).to_be_bytes()),
                    }
                }
                if f == Format::Ascii {
                    out.push(b'\n');
                }
            }
            for t in &self.indices {
                match f {
                    Format::Ascii => {
                        out.extend(format!("3 {} {} {}\n", t[0], t[1], t[2]).into_bytes())
                    }
                    _ => {
                        out.push(3);
                        for &i in t {
                            let i = i as i32;
                            out.extend(if f == Format::BinaryBig {
                                i.to_be_bytes()
                            } else {
                                i.to_le_bytes()
                            });
                        }
                    }
                }
            }
            out
        }
    }

    proptest! {
        /// Round trip on random meshes in every encoding (f32 values print and parse back
        /// exactly), and random damage never makes the reader panic.
        #[test]
        fn round_trip_and_damage(
            nv in 1usize..12,
            tris in prop::collection::vec(any::<(u32, u32, u32)>(), 0..20),
            (normals, uvs) in any::<(bool, bool)>(),
            scale in -1e3f32..1e3,
            format in 0u8..3,
            damage in prop::collection::vec((any::<usize>(), any::<u8>()), 0..4),
        ) {
            let m = MeshData {
                positions: (0..nv).map(|k| [scale * k as f32, 0.1 * k as f32, -scale]).collect(),
                normals,
                uvs,
                indices: tris.iter().map(|&(a, b, c)| [a % nv as u32, b % nv as u32, c % nv as u32]).collect(),
            };
            let f = [Format::Ascii, Format::BinaryLittle, Format::BinaryBig][format as usize];
            let bytes = m.file(f);
            let got = read(&bytes).unwrap();
            prop_assert_eq!(&got.indices, &m.indices);
            prop_assert_eq!(got.positions.iter().map(|p| p.to_array()).collect::<Vec<_>>(), m.positions.clone());
            for k in 0..nv {
                let v = m.vertex(k);
                if normals {
                    prop_assert_eq!(got.normals.as_ref().unwrap()[k].to_array().to_vec(), v[3..6].to_vec());
                }
                if uvs {
                    let uv = got.uvs.as_ref().unwrap()[k];
                    prop_assert_eq!(vec![uv.x, uv.y], v[v.len() - 2..].to_vec());
                }
            }
            let mut damaged = bytes.clone();
            for (at, byte) in damage {
                let n = damaged.len();
                damaged[at % n] = byte;
            }
            let _ = read(&damaged);
        }
    }
}
