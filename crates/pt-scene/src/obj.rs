//! Wavefront OBJ meshes, read as a stream: each line is parsed and turned into mesh data at
//! once, so that memory holds the file's vertex lists, the mesh being built and nothing per
//! face but its final triangles.
//!
//! Why not the tobj crate, which this loader used before: tobj keeps every face as a 104-byte
//! record (three `usize` per corner, room for a quad) until the end of the file, and then builds
//! the mesh through a hash map of vertices. On the 1M-triangle scene of the README's memory
//! comparison that was 147 MB on top of the program (peak 156 MB, Mitsuba `scalar_rgb` 155.8
//! MB); this reader needs 12 bytes per triangle and about 36 per vertex (the file's position,
//! the mesh's copy and the lookup of corners; peak of the load 40 MB). It also names the line
//! of an error, which tobj cannot. tobj stays a dev-dependency: the tests below check that both
//! read the same mesh from random files.
//!
//! What is read (the format as published by Wavefront, "Object Files (.obj)", Appendix B1 of the
//! Advanced Visualizer manual):
//! - `v x y z`: a position; further numbers (a weight `w`, vertex colours) are ignored, as
//!   Mitsuba does (`w` weighs control points of rational curves, not polygon vertices).
//! - `vt u [v]`: a texture coordinate (`v` = 0 when absent); `vn x y z`: a normal.
//! - `f a b c ...` with corners `v`, `v/vt`, `v//vn` or `v/vt/vn`; indices count from 1, or
//!   from the end of the list read so far when negative (-1 is the last one), and must refer
//!   to lines before the face (the file is read in one pass). A face of n >= 3 corners becomes
//!   the fan (1, i, i + 1), i = 2 .. n - 1; fewer corners are an error.
//! - Everything else (`o`, `g`, `s`, `usemtl`, `mtllib`, `l`, `p`, curves, comments) is
//!   ignored: all objects and groups form one mesh, and a vertex shared by two groups stays
//!   shared (as in Mitsuba's reader; tobj duplicated it, which left a seam in smooth normals).
//!
//! The mesh has one index per vertex: each distinct corner (v, vt, vn) becomes one vertex, in
//! the order of first use, so unused positions are dropped. Texture coordinates and normals
//! are kept only if every vertex has them.

use crate::error::io_message;
use crate::shapes::LocalMesh;
use glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::io::BufRead;
use std::path::Path;

/// Options of the `obj` shape.
pub(crate) struct ObjOptions {
    /// Drop vertex normals and shade flat.
    pub face_normals: bool,
    /// Use v' = 1 - v (Mitsuba's default: most OBJ files put v = 0 at the bottom).
    pub flip_tex_coords: bool,
}

/// Loads an OBJ file into an object-space mesh (see the module documentation for the subset).
/// Errors name the file as the scene names it (`shown_name`) and the line.
///
/// Without normals in the file (and without `face_normals`), vertex normals are computed after
/// `to_world`, as Mitsuba does, so that meshes render smooth in both renderers.
pub(crate) fn load_obj(
    path: &Path,
    shown_name: &str,
    opts: &ObjOptions,
) -> std::result::Result<LocalMesh, String> {
    let file = std::fs::File::open(path)
        .map_err(|e| format!("cannot open mesh '{shown_name}': {}", io_message(&e)))?;
    read_obj(std::io::BufReader::new(file), opts).map_err(|e| match e {
        ObjError::Io(e) => format!("cannot read mesh '{shown_name}': {}", io_message(&e)),
        ObjError::Line(line, msg) => format!("mesh '{shown_name}', line {line}: {msg}"),
    })
}

/// Why a file could not be read: the system's error, or a line (1-based) that is not valid.
#[derive(Debug)]
enum ObjError {
    Io(std::io::Error),
    Line(usize, String),
}

/// Marks an absent `vt` or `vn` in a corner, and an unassigned entry of [`Builder::first`].
const NONE: u32 = u32::MAX;

/// The mesh under construction, and the file's vertex lists it is built from.
#[derive(Default)]
struct Builder {
    /// The file's `v`, `vt` and `vn` lines so far, in file order.
    positions: Vec<Vec3>,
    uvs: Vec<Vec2>,
    normals: Vec<Vec3>,
    /// For each file position: the mesh vertex of the first corner seen with it, or [`NONE`].
    first: Vec<u32>,
    /// The (vt, vn) of each mesh vertex, to tell whether a corner repeats [`Self::first`]'s.
    vt_vn: Vec<[u32; 2]>,
    /// Corners (v, vt, vn) whose position already has another mesh vertex (uv seams, split
    /// normals): rare, so a map is cheap.
    others: HashMap<[u32; 3], u32>,
    /// The mesh; its `uvs`/`normals` become `None` at the first vertex without them.
    mesh: LocalMesh,
}

fn read_obj(
    mut reader: impl BufRead,
    opts: &ObjOptions,
) -> std::result::Result<LocalMesh, ObjError> {
    let mut b = Builder {
        mesh: LocalMesh {
            uvs: Some(Vec::new()),
            normals: (!opts.face_normals).then(Vec::new),
            ..Default::default()
        },
        ..Default::default()
    };
    let mut line = Vec::new();
    // Mesh vertices of the current face's corners (reused: no allocation per face).
    let mut corners = Vec::new();
    for line_number in 1.. {
        line.clear();
        if reader.read_until(b'\n', &mut line).map_err(ObjError::Io)? == 0 {
            break;
        }
        let fail = |msg: String| ObjError::Line(line_number, msg);
        let mut words = line
            .split(|c| c.is_ascii_whitespace())
            .filter(|w| !w.is_empty());
        match words.next() {
            Some(b"v") => {
                let [x, y, z] = numbers(&mut words, "v", "position").map_err(fail)?;
                b.positions.push(Vec3::new(x, y, z));
            }
            Some(b"vt") => {
                let u = number(words.next(), "vt", "texture coordinate u").map_err(fail)?;
                let v = match words.next() {
                    Some(w) => number(Some(w), "vt", "texture coordinate v").map_err(fail)?,
                    None => 0.0,
                };
                let v = if opts.flip_tex_coords { 1.0 - v } else { v };
                b.uvs.push(Vec2::new(u, v));
            }
            Some(b"vn") => {
                let [x, y, z] = numbers(&mut words, "vn", "normal").map_err(fail)?;
                b.normals.push(Vec3::new(x, y, z));
            }
            Some(b"f") => {
                corners.clear();
                for word in words {
                    let key = b.corner(word).map_err(fail)?;
                    corners.push(b.vertex(key).map_err(fail)?);
                }
                if corners.len() < 3 {
                    return Err(fail(format!(
                        "a face needs at least three corners, this one has {}",
                        corners.len()
                    )));
                }
                // Fan from the first corner (Wavefront's faces are convex and planar).
                for pair in corners[1..].windows(2) {
                    b.mesh.indices.push([corners[0], pair[0], pair[1]]);
                }
            }
            _ => {}
        }
    }
    let mut mesh = b.mesh;
    if mesh.positions.is_empty() {
        (mesh.uvs, mesh.normals) = (None, None);
    }
    Ok(mesh)
}

impl Builder {
    /// The file indices (v, vt, vn) of a face corner `v`, `v/vt`, `v//vn` or `v/vt/vn`, checked
    /// against the lists read so far.
    fn corner(&self, word: &[u8]) -> std::result::Result<[u32; 3], String> {
        let mut parts = word.split(|&c| c == b'/');
        let mut key = [NONE; 3];
        let lists = [
            (["vertex", "vertices"], self.positions.len()),
            (
                ["texture coordinate", "texture coordinates"],
                self.uvs.len(),
            ),
            (["normal", "normals"], self.normals.len()),
        ];
        for (n, (slot, (what, count))) in key.iter_mut().zip(lists).enumerate() {
            match parts.next() {
                // `v//vn` leaves vt empty, `v/` is read as `v`; the position is never optional.
                Some([]) if n > 0 => {}
                Some(text) => *slot = index(text, count, what, word)?,
                None => break,
            }
        }
        if parts.next().is_some() {
            return Err(format!(
                "face corner '{}' has more than three indices",
                String::from_utf8_lossy(word)
            ));
        }
        Ok(key)
    }

    /// The mesh vertex of a corner: the one made at its first use, or a new one.
    fn vertex(&mut self, key: [u32; 3]) -> std::result::Result<u32, String> {
        let [v, vt, vn] = key;
        if self.first.len() < self.positions.len() {
            self.first.resize(self.positions.len(), NONE);
        }
        let slot = self.first[v as usize];
        if slot != NONE {
            if self.vt_vn[slot as usize] == [vt, vn] {
                return Ok(slot);
            }
            if let Some(&id) = self.others.get(&key) {
                return Ok(id);
            }
        }
        let id = u32::try_from(self.mesh.positions.len())
            .ok()
            .filter(|&id| id != NONE)
            .ok_or("more than 4294967294 vertices")?;
        if slot == NONE {
            self.first[v as usize] = id;
        } else {
            self.others.insert(key, id);
        }
        self.vt_vn.push([vt, vn]);
        self.mesh.positions.push(self.positions[v as usize]);
        keep_while_present(
            &mut self.mesh.uvs,
            (vt != NONE).then(|| self.uvs[vt as usize]),
        );
        keep_while_present(
            &mut self.mesh.normals,
            (vn != NONE).then(|| self.normals[vn as usize]),
        );
        Ok(id)
    }
}

/// Appends `value` to a vertex attribute list while every vertex so far has had one; at the
/// first vertex without, the list is freed and stays `None`.
fn keep_while_present<T>(list: &mut Option<Vec<T>>, value: Option<T>) {
    match (value, list.as_mut()) {
        (Some(value), Some(list)) => list.push(value),
        _ => *list = None,
    }
}

/// A face index as a 0-based position in a list of `count` entries: 1-based from the start, or
/// negative from the end (-1 is the last entry read so far).
/// `what` names the list, singular and plural; `corner` is the whole corner, for messages.
fn index(
    text: &[u8],
    count: usize,
    what: [&str; 2],
    corner: &[u8],
) -> std::result::Result<u32, String> {
    let corner = || String::from_utf8_lossy(corner);
    let parsed = std::str::from_utf8(text)
        .ok()
        .and_then(|t| t.parse::<i64>().ok());
    let Some(i) = parsed else {
        return Err(format!(
            "face corner '{}': '{}' is not an index",
            corner(),
            String::from_utf8_lossy(text)
        ));
    };
    let count = count as i64;
    let resolved = if i > 0 { i - 1 } else { count + i };
    if i == 0 || !(0..count).contains(&resolved) {
        return Err(format!(
            "face corner '{}' refers to {} {i}, but {count} {} are defined before it",
            corner(),
            what[0],
            what[1]
        ));
    }
    // `count` came from a Vec of at most as many entries as mesh vertices allow.
    u32::try_from(resolved)
        .map_err(|_| format!("face corner '{}': {} index too large", corner(), what[0]))
}

/// A finite number, or an error naming the statement and the quantity.
fn number(word: Option<&[u8]>, statement: &str, what: &str) -> std::result::Result<f32, String> {
    let Some(word) = word else {
        return Err(format!(
            "'{statement}' has too few numbers (a {what} is missing)"
        ));
    };
    let value = std::str::from_utf8(word)
        .ok()
        .and_then(|t| t.parse::<f32>().ok());
    match value {
        Some(x) if x.is_finite() => Ok(x),
        Some(_) => Err(format!(
            "{what} '{}' is not finite",
            String::from_utf8_lossy(word)
        )),
        None => Err(format!(
            "{what} '{}' is not a number",
            String::from_utf8_lossy(word)
        )),
    }
}

/// The first three numbers of a `v` or `vn` line (further ones ignored).
fn numbers<'a>(
    words: &mut impl Iterator<Item = &'a [u8]>,
    statement: &str,
    what: &str,
) -> std::result::Result<[f32; 3], String> {
    let mut xyz = [0.0; 3];
    for x in &mut xyz {
        *x = number(words.next(), statement, what)?;
    }
    Ok(xyz)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const SMOOTH: ObjOptions = ObjOptions {
        face_normals: false,
        flip_tex_coords: true,
    };

    fn read(text: &str, opts: &ObjOptions) -> std::result::Result<LocalMesh, ObjError> {
        read_obj(text.as_bytes(), opts)
    }

    /// The error's line and message, for files that must be refused.
    fn refused(text: &str) -> (usize, String) {
        match read(text, &SMOOTH) {
            Err(ObjError::Line(line, msg)) => (line, msg),
            other => panic!("{text:?} read as {:?}", other.map(|m| m.indices)),
        }
    }

    /// The same file through tobj (single-index mode, fans, one object) and merged the way this
    /// loader used to merge tobj's output: the mesh the old loader produced.
    fn read_with_tobj(text: &str, opts: &ObjOptions) -> Option<LocalMesh> {
        let options = tobj::LoadOptions {
            single_index: true,
            triangulate: true,
            ignore_points: true,
            ignore_lines: true,
        };
        let (models, _) = tobj::load_obj_buf(&mut text.as_bytes(), &options, |_| {
            Ok((Vec::new(), Default::default()))
        })
        .ok()?;
        let mut out = LocalMesh::default();
        let (mut uvs, mut normals) = (Vec::new(), Vec::new());
        for m in &models {
            let base = out.positions.len() as u32;
            out.positions.extend(
                m.mesh
                    .positions
                    .chunks(3)
                    .map(|p| Vec3::new(p[0], p[1], p[2])),
            );
            uvs.extend(m.mesh.texcoords.chunks(2).map(|t| {
                Vec2::new(
                    t[0],
                    if opts.flip_tex_coords {
                        1.0 - t[1]
                    } else {
                        t[1]
                    },
                )
            }));
            normals.extend(
                m.mesh
                    .normals
                    .chunks(3)
                    .map(|n| Vec3::new(n[0], n[1], n[2])),
            );
            out.indices.extend(
                m.mesh
                    .indices
                    .chunks(3)
                    .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
            );
        }
        let n = out.positions.len();
        out.uvs = (n > 0 && uvs.len() == n).then_some(uvs);
        out.normals = (n > 0 && normals.len() == n && !opts.face_normals).then_some(normals);
        Some(out)
    }

    fn same(a: &LocalMesh, b: &LocalMesh) -> bool {
        a.positions == b.positions
            && a.indices == b.indices
            && a.uvs == b.uvs
            && a.normals == b.normals
    }

    #[test]
    fn corners_become_vertices_in_order_of_first_use() {
        // Positions used out of file order, an unused position, a quad as a fan, a corner
        // repeated with another uv (a seam: a second vertex), negative indices.
        let m = read(
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 5 5 5\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
                      f 3/3 1/1 2/2\nf -5/-4 -2/-2 -1/-1\n",
            &SMOOTH,
        )
        .unwrap();
        assert_eq!(
            m.positions,
            [
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::ZERO,
                Vec3::X,
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(5.0, 5.0, 5.0)
            ]
        );
        assert_eq!(m.indices, [[0, 1, 2], [1, 3, 4]]);
        // flip_tex_coords: v' = 1 - v.
        assert_eq!(
            m.uvs.unwrap(),
            [
                Vec2::new(1.0, 0.0),
                Vec2::new(0.0, 1.0),
                Vec2::new(1.0, 1.0),
                Vec2::new(1.0, 0.0),
                Vec2::new(0.0, 0.0)
            ]
        );
        assert_eq!(m.normals, None);
        let quad = read(
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 2 0\nf 1 2 3 4 5\n",
            &SMOOTH,
        )
        .unwrap();
        assert_eq!(quad.indices, [[0, 1, 2], [0, 2, 3], [0, 3, 4]]);
    }

    #[test]
    fn objects_and_groups_share_vertices() {
        // Two groups sharing an edge: one mesh of four vertices (tobj gave six, with a seam).
        let m = read(
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\no a\nf 1 2 3\ng b\nusemtl x\ns 1\nf 1 3 4\n",
            &SMOOTH,
        )
        .unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.indices, [[0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn attributes_are_kept_only_if_every_vertex_has_them() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvt 0 0\nf 1//1 2//1 3//1\n";
        assert_eq!(read(text, &SMOOTH).unwrap().normals.unwrap(), [Vec3::Z; 3]);
        assert_eq!(read(text, &SMOOTH).unwrap().uvs, None);
        assert_eq!(
            read(
                text,
                &ObjOptions {
                    face_normals: true,
                    ..SMOOTH
                }
            )
            .unwrap()
            .normals,
            None
        );
        let partial = read(
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3\n",
            &SMOOTH,
        )
        .unwrap();
        assert_eq!((partial.normals, partial.positions.len()), (None, 3));
        let empty = read("# nothing\n\n", &SMOOTH).unwrap();
        assert!(empty.positions.is_empty() && empty.uvs.is_none() && empty.normals.is_none());
        // `vt u` alone: v = 0, flipped to 1; `v` with a weight and colours: the weight ignored.
        let m = read(
            "v 0 0 0 2\nv 1 0 0 0.5 0.5 0.5\nv 0 1 0\nvt 0.25\nf 1/1 2/1 3/1\n",
            &SMOOTH,
        )
        .unwrap();
        assert_eq!(m.uvs.unwrap()[0], Vec2::new(0.25, 1.0));
        assert_eq!(m.positions[1], Vec3::X);
    }

    #[test]
    fn bad_lines_are_refused_with_their_number() {
        let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        assert_eq!(refused(&format!("{tri}f 1 2 4\n")).0, 4);
        assert!(refused(&format!("{tri}f 1 2 4\n"))
            .1
            .contains("vertex 4, but 3 vertices"));
        assert_eq!(refused(&format!("{tri}f 1 2 -4\n")).0, 4);
        assert_eq!(refused(&format!("{tri}f 0 1 2\n")).0, 4);
        assert_eq!(refused(&format!("{tri}f 1/1 2 3\n")).0, 4); // no vt defined
        assert_eq!(refused(&format!("{tri}f 1//1 2 3\n")).0, 4); // no vn defined
        assert_eq!(refused(&format!("{tri}f 1/1/1/1 2 3\n")).0, 4);
        assert_eq!(refused(&format!("{tri}f 1 2\n")).0, 4);
        assert_eq!(refused(&format!("{tri}f 1 x 3\n")).0, 4);
        assert_eq!(refused(&format!("{tri}f /1 2 3\n")).0, 4);
        assert_eq!(refused("v 0 0\n").0, 1);
        assert!(refused("v 0 nan 0\n").1.contains("not finite"));
        assert!(refused("v 0 0 1e39\n").1.contains("not finite"));
        assert_eq!(refused("v 0 0 0\r\nvn 0 x 1\r\n").0, 2);
        assert_eq!(refused("v 0 0 0\nvt\n").0, 2);
        // A vertex may not be used before its line (the file is read in one pass).
        assert_eq!(refused("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n").0, 1);
        // Invalid UTF-8 outside numbers (a comment, a group name) is harmless.
        assert!(read_obj(
            &b"# caf\xe9\ng \xff\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"[..],
            &SMOOTH
        )
        .is_ok());
    }

    #[test]
    fn the_scenes_mesh_reads_as_tobj_read_it() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/meshes/ico.obj");
        let text = std::fs::read_to_string(path).unwrap();
        let ours = read(&text, &SMOOTH).unwrap();
        assert_eq!(ours.indices.len(), 128);
        assert!(same(&ours, &read_with_tobj(&text, &SMOOTH).unwrap()));
    }

    /// A corner referring to earlier entries: 1-based or negative, in any of the four forms.
    fn corner(
        counts: (usize, usize, usize),
        pick: (usize, usize, usize),
        form: u8,
        negative: bool,
    ) -> String {
        let at = |count: usize, k: usize| {
            if negative {
                format!("-{}", k % count + 1)
            } else {
                format!("{}", k % count + 1)
            }
        };
        let v = at(counts.0, pick.0);
        match form {
            1 if counts.1 > 0 => format!("{v}/{}", at(counts.1, pick.1)),
            2 if counts.2 > 0 => format!("{v}//{}", at(counts.2, pick.2)),
            3 if counts.1 > 0 && counts.2 > 0 => {
                format!("{v}/{}/{}", at(counts.1, pick.1), at(counts.2, pick.2))
            }
            _ => v,
        }
    }

    proptest! {
        /// Differential test: on random valid files (the four corner forms, negative indices,
        /// polygons, repeated corners, attributes on some corners only, CRLF, comments), this
        /// reader gives exactly the mesh tobj gave (same vertices in the same order, same
        /// triangles, same bits). Files without `o`/`g`: there the two differ on purpose.
        #[test]
        fn reads_the_same_mesh_as_tobj(
            steps in prop::collection::vec((0u8..6, any::<(usize, usize, usize)>(), prop::collection::vec((any::<(usize, usize, usize)>(), 0u8..4, any::<bool>()), 3..7), -4.0f32..4.0), 1..40),
            crlf in any::<bool>(),
            flip in any::<bool>(),
            always in 0u8..4,
        ) {
            // Every list starts non-empty, and `always` (bit 1: vt, bit 2: vn) is given to every
            // corner, so that a quarter of the files keep uvs and normals on every vertex.
            let eol = if crlf { "\r\n" } else { "\n" };
            let mut text = format!("v 0 0 0{eol}v 1 0 0{eol}v 0 1 0{eol}vt 0.5 0.25{eol}vn 0 0 1{eol}");
            let mut counts = (3, 1, 1);
            for (kind, (a, b, c), corners, x) in steps {
                let (a, b, c) = (a % 7, b % 5, c % 3);
                match kind {
                    0 | 1 => { text += &format!("v {x} {a} {}{eol}", c as f32 * 0.1); counts.0 += 1 }
                    2 => { text += &format!("vt {x} 0.{b}{eol}"); counts.1 += 1 }
                    3 => { text += &format!("vn {a} {x} 1{eol}"); counts.2 += 1 }
                    4 => text += &format!("# comment {a}{eol}"),
                    _ => {
                        let words: Vec<String> = corners.into_iter().map(|(p, f, n)| corner(counts, p, f | always, n)).collect();
                        text += &format!("f {}{eol}", words.join(" "));
                    }
                }
            }
            let opts = ObjOptions { face_normals: false, flip_tex_coords: flip };
            let ours = read(&text, &opts).unwrap();
            if always == 3 {
                prop_assert!(ours.positions.is_empty() || (ours.uvs.is_some() && ours.normals.is_some()));
            }
            let theirs = read_with_tobj(&text, &opts).unwrap();
            prop_assert!(same(&ours, &theirs), "{}", text);
        }
    }
}
