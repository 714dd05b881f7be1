//! Mitsuba's `serialized` meshes: one or more zlib-compressed triangle meshes in one file, as
//! Mitsuba 3.9.1 reads them (its `serialized` plugin; the format of Mitsuba 0.6's
//! `TriMesh::serialize`).
//!
//! Layout (every number little-endian):
//! - each mesh: `u16` format identifier `0x041C`, `u16` version (3 or 4; the first mesh's
//!   applies to the whole file, the copies before later meshes are not checked), then a zlib
//!   stream (RFC 1950: deflate with the zlib header) holding
//!   - `u32` flags: `0x1` vertex normals, `0x2` texture coordinates, `0x8` vertex colours,
//!     `0x2000` double precision (every real is an `f64`, else an `f32`); `0x4` (tangents) and
//!     `0x10` (face normals) carry no data and are ignored, as in Mitsuba 3;
//!   - version 4 only: the mesh name, bytes up to a NUL;
//!   - `u64` vertex count, `u64` triangle count;
//!   - positions (3 reals per vertex), then normals, uvs (2 reals), colours (3 reals) where
//!     the flags say so, then 3 `u32` vertex indices per triangle (always 32-bit, whatever
//!     the vertex count: no reader ever wrote or read 64-bit indices);
//! - after the last mesh, a table of each mesh's byte offset (`u64` in version 4, `u32` in
//!   version 3) and the `u32` number of meshes, which ends the file. Mesh 0 starts at byte 0
//!   and is read without the table (files of one mesh may lack it).
//!
//! The reader decompresses only the bytes it needs, straight into the mesh, and stops: it
//! neither needs the stream's end nor checks its Adler-32 trailer (as Mitsuba). Unlike Mitsuba
//! 3.9.1 it refuses triangles that name a vertex past the end, `shape_index` equal to the
//! number of meshes (Mitsuba's range check lets it through and then reads garbage), and counts
//! above 2^32 - 1 (Mitsuba narrows them to 32 bits). Vertex colours, which Mitsuba 3.9.1 reads
//! and drops, become the mesh attribute `vertex_color` (as from a PLY file), so a
//! `mesh_attribute` texture can use them; uvs are kept as stored (no `1 - v`).

use crate::error::io_message;
use crate::ir::{AttributeKind, MeshAttribute};
use crate::shapes::LocalMesh;
use flate2::read::ZlibDecoder;
use glam::{Vec2, Vec3};
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;

/// The format identifier that starts every mesh (bytes `1C 04`).
const FORMAT_ID: u16 = 0x041C;
/// Flag bits of a mesh.
const HAS_NORMALS: u32 = 0x0001;
const HAS_UVS: u32 = 0x0002;
const HAS_COLORS: u32 = 0x0008;
const DOUBLE_PRECISION: u32 = 0x2000;

/// Loads mesh `shape_index` of a serialized file into an object-space mesh. Errors name the
/// file as the scene names it (`shown_name`).
pub(crate) fn load_serialized(
    path: &Path,
    shown_name: &str,
    shape_index: u32,
) -> std::result::Result<LocalMesh, String> {
    let file = std::fs::File::open(path)
        .map_err(|e| format!("cannot open mesh '{shown_name}': {}", io_message(&e)))?;
    read_serialized(BufReader::new(file), shape_index)
        .map_err(|e| format!("serialized mesh '{shown_name}': {e}"))
}

/// Reads mesh `shape_index` from a serialized file's bytes.
pub(crate) fn read_serialized<R: Read + Seek>(
    mut r: R,
    shape_index: u32,
) -> std::result::Result<LocalMesh, String> {
    let io = |e: std::io::Error| match e.kind() {
        std::io::ErrorKind::UnexpectedEof => "the file ends early (truncated?)".to_string(),
        _ => io_message(&e),
    };
    let (id, version) = (read_u16(&mut r).map_err(io)?, read_u16(&mut r).map_err(io)?);
    if id != FORMAT_ID {
        return Err(format!(
            "not a serialized mesh file (format identifier {id:#06x}, expected 0x041c)"
        ));
    }
    if version != 3 && version != 4 {
        return Err(format!(
            "unsupported version {version} (Mitsuba 3 reads versions 3 and 4)"
        ));
    }
    if shape_index > 0 {
        let offset = mesh_offset(&mut r, version, shape_index)?;
        // Past the mesh's own identifier and version, which Mitsuba does not check.
        r.seek(SeekFrom::Start(offset + 4)).map_err(io)?;
    }
    read_mesh(ZlibDecoder::new(r), version).map_err(|e| format!("mesh {shape_index}: {e}"))
}

/// Byte offset of mesh `index` (> 0) from the table at the end of the file.
fn mesh_offset<R: Read + Seek>(
    r: &mut R,
    version: u16,
    index: u32,
) -> std::result::Result<u64, String> {
    let io = |e: std::io::Error| io_message(&e);
    let size = r.seek(SeekFrom::End(0)).map_err(io)?;
    if size < 8 {
        return Err("the file is too short for a table of meshes".into());
    }
    r.seek(SeekFrom::End(-4)).map_err(io)?;
    let count = read_u32(r).map_err(io)?;
    if index >= count {
        return Err(format!(
            "shape_index {index} is out of range: the file holds {count} mesh(es), 0..{}",
            count.saturating_sub(1)
        ));
    }
    let width: u64 = if version == 4 { 8 } else { 4 };
    let from_end = 4 + width * u64::from(count - index);
    if from_end > size {
        return Err(format!(
            "the table of {count} meshes does not fit in the file ({size} bytes)"
        ));
    }
    r.seek(SeekFrom::Start(size - from_end)).map_err(io)?;
    let offset = if version == 4 {
        read_u64(r).map_err(io)?
    } else {
        u64::from(read_u32(r).map_err(io)?)
    };
    if offset.saturating_add(4) >= size - from_end {
        return Err(format!(
            "mesh {index}'s offset {offset} points past the meshes ({} bytes)",
            size - from_end
        ));
    }
    Ok(offset)
}

/// Reads one mesh from its decompressed stream.
fn read_mesh(mut z: impl Read, version: u16) -> std::result::Result<LocalMesh, String> {
    let io = |e: std::io::Error| match e.kind() {
        std::io::ErrorKind::UnexpectedEof => "the compressed data ends early".to_string(),
        _ => format!("cannot decompress: {}", io_message(&e)),
    };
    let flags = read_u32(&mut z).map_err(io)?;
    if version == 4 {
        // The name: bytes up to a NUL (only for messages in Mitsuba; unused here).
        let mut byte = [0u8; 1];
        loop {
            z.read_exact(&mut byte).map_err(io)?;
            if byte[0] == 0 {
                break;
            }
        }
    }
    let count = |z: &mut dyn Read, what: &str| -> std::result::Result<usize, String> {
        let n = read_u64(z).map_err(io)?;
        u32::try_from(n)
            .map(|n| n as usize)
            .map_err(|_| format!("{n} {what} (at most 2^32 - 1, as in Mitsuba)"))
    };
    let vertices = count(&mut z, "vertices")?;
    let triangles = count(&mut z, "triangles")?;
    let double = flags & DOUBLE_PRECISION != 0;
    let mut reals = Reals::new(double);
    let positions = reals
        .read(&mut z, vertices, |v| Vec3::new(v[0], v[1], v[2]), 3)
        .map_err(io)?;
    let normals = if flags & HAS_NORMALS != 0 {
        Some(
            reals
                .read(&mut z, vertices, |v| Vec3::new(v[0], v[1], v[2]), 3)
                .map_err(io)?,
        )
    } else {
        None
    };
    let uvs = if flags & HAS_UVS != 0 {
        Some(
            reals
                .read(&mut z, vertices, |v| Vec2::new(v[0], v[1]), 2)
                .map_err(io)?,
        )
    } else {
        None
    };
    let mut attributes = Vec::new();
    if flags & HAS_COLORS != 0 {
        let colors = reals
            .read(&mut z, vertices, |v| [v[0], v[1], v[2]], 3)
            .map_err(io)?;
        attributes.push(MeshAttribute {
            name: "vertex_color".into(),
            kind: AttributeKind::Vertex,
            dims: 3,
            values: colors.into_iter().flatten().collect(),
        });
    }
    // Read through a buffer of many triangles rather than 12 bytes at a time from the
    // decompressor (5M triangles: the whole load 0.49 -> 0.45 s).
    let mut indices = Vec::with_capacity(triangles.min(PREALLOCATE));
    let mut buf = vec![0u8; 12 << 11];
    let mut left = triangles;
    while left > 0 {
        let k = left.min(buf.len() / 12);
        let chunk = &mut buf[..12 * k];
        z.read_exact(chunk).map_err(io)?;
        for b in chunk.chunks_exact(12) {
            let tri = [0, 1, 2]
                .map(|k| u32::from_le_bytes([b[4 * k], b[4 * k + 1], b[4 * k + 2], b[4 * k + 3]]));
            if let Some(&bad) = tri.iter().find(|&&i| i as usize >= vertices) {
                return Err(format!(
                    "triangle {} names vertex {bad}, but the mesh has {vertices} vertices",
                    indices.len()
                ));
            }
            indices.push(tri);
        }
        left -= k;
    }
    Ok(LocalMesh {
        positions,
        normals,
        uvs,
        indices,
        attributes,
    })
}

/// Elements reserved before reading: counts come from the file, so a corrupt count must not
/// allocate gigabytes up front; the vectors grow past this as the data really arrives.
const PREALLOCATE: usize = 1 << 20;

/// Reads arrays of `f32` or `f64` reals through a fixed buffer.
struct Reals {
    double: bool,
    bytes: Vec<u8>,
}

impl Reals {
    fn new(double: bool) -> Self {
        Reals {
            double,
            bytes: vec![0; 1 << 15],
        }
    }

    /// `n` elements of `dims` reals each, made into `T` by `make` (f64 narrowed to f32).
    fn read<T>(
        &mut self,
        z: &mut impl Read,
        n: usize,
        make: impl Fn(&[f32]) -> T,
        dims: usize,
    ) -> std::io::Result<Vec<T>> {
        let size = if self.double { 8 } else { 4 };
        let per_chunk = self.bytes.len() / (size * dims);
        let mut out = Vec::with_capacity(n.min(PREALLOCATE));
        let mut values = [0f32; 3];
        let mut left = n;
        while left > 0 {
            let k = left.min(per_chunk);
            let chunk = &mut self.bytes[..k * size * dims];
            z.read_exact(chunk)?;
            for element in chunk.chunks_exact(size * dims) {
                for (v, b) in values.iter_mut().zip(element.chunks_exact(size)) {
                    *v = if self.double {
                        f64::from_le_bytes(b.try_into().expect("8 bytes")) as f32
                    } else {
                        f32::from_le_bytes(b.try_into().expect("4 bytes"))
                    };
                }
                out.push(make(&values[..dims]));
            }
            left -= k;
        }
        Ok(out)
    }
}

fn read_u16(r: &mut impl Read) -> std::io::Result<u16> {
    let mut b = [0; 2];
    r.read_exact(&mut b)?;
    Ok(u16::from_le_bytes(b))
}

fn read_u32(r: &mut (impl Read + ?Sized)) -> std::io::Result<u32> {
    let mut b = [0; 4];
    r.read_exact(&mut b)?;
    Ok(u32::from_le_bytes(b))
}

fn read_u64(r: &mut (impl Read + ?Sized)) -> std::io::Result<u64> {
    let mut b = [0; 8];
    r.read_exact(&mut b)?;
    Ok(u64::from_le_bytes(b))
}

/// A writer of the format, for tests (the reader's differential partner and the fuzzer's
/// source of valid files) and for the scripts that make test scenes.
#[cfg(test)]
pub(crate) mod write {
    use flate2::write::ZlibEncoder;
    use flate2::Compression;
    use std::io::Write;

    /// One mesh to write: positions, optional normals, uvs and colours, triangles.
    #[derive(Clone, Debug, Default)]
    pub struct MeshData {
        pub name: String,
        pub positions: Vec<[f32; 3]>,
        pub normals: Option<Vec<[f32; 3]>>,
        pub uvs: Option<Vec<[f32; 2]>>,
        pub colors: Option<Vec<[f32; 3]>>,
        pub indices: Vec<[u32; 3]>,
    }

    /// The file of `meshes` in `version` (3 or 4), reals as f64 when `double`.
    pub fn file(meshes: &[MeshData], version: u16, double: bool) -> Vec<u8> {
        let mut out = Vec::new();
        let mut offsets = Vec::new();
        for m in meshes {
            offsets.push(out.len() as u64);
            out.extend(0x041Cu16.to_le_bytes());
            out.extend(version.to_le_bytes());
            let mut z = ZlibEncoder::new(Vec::new(), Compression::fast());
            let mut flags = if double { 0x2000 } else { 0x1000 };
            flags |= u32::from(m.normals.is_some())
                | u32::from(m.uvs.is_some()) << 1
                | u32::from(m.colors.is_some()) << 3;
            let mut payload: Vec<u8> = flags.to_le_bytes().to_vec();
            if version == 4 {
                payload.extend(m.name.as_bytes());
                payload.push(0);
            }
            payload.extend((m.positions.len() as u64).to_le_bytes());
            payload.extend((m.indices.len() as u64).to_le_bytes());
            let mut reals = |vals: &[f32]| {
                for &v in vals {
                    if double {
                        payload.extend(f64::from(v).to_le_bytes());
                    } else {
                        payload.extend(v.to_le_bytes());
                    }
                }
            };
            m.positions.iter().for_each(|p| reals(p));
            m.normals.iter().flatten().for_each(|n| reals(n));
            m.uvs.iter().flatten().for_each(|uv| reals(uv));
            m.colors.iter().flatten().for_each(|c| reals(c));
            for t in &m.indices {
                for i in t {
                    payload.extend(i.to_le_bytes());
                }
            }
            z.write_all(&payload).expect("in memory");
            out.extend(z.finish().expect("in memory"));
        }
        for o in &offsets {
            if version == 4 {
                out.extend(o.to_le_bytes());
            } else {
                out.extend((*o as u32).to_le_bytes());
            }
        }
        out.extend((meshes.len() as u32).to_le_bytes());
        out
    }
}

#[cfg(test)]
mod tests {
    use super::write::{file, MeshData};
    use super::*;
    use proptest::prelude::*;
    use std::io::Cursor;

    fn quad() -> MeshData {
        MeshData {
            name: "quad".into(),
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            normals: Some(vec![[0.0, 0.0, 1.0]; 4]),
            uvs: Some(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]),
            colors: Some(vec![
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
                [1.0, 1.0, 1.0],
            ]),
            indices: vec![[0, 1, 2], [0, 2, 3]],
        }
    }

    fn tri() -> MeshData {
        MeshData {
            name: String::new(),
            positions: vec![[0.0, 0.0, 1.0], [2.0, 0.0, 1.0], [0.0, 3.0, 1.0]],
            indices: vec![[0, 1, 2]],
            ..Default::default()
        }
    }

    fn read(bytes: &[u8], index: u32) -> std::result::Result<LocalMesh, String> {
        read_serialized(Cursor::new(bytes), index)
    }

    /// A file written by another zlib (Python's) and read by Mitsuba 3.9.1 itself, which gave
    /// exactly these meshes: version 4, mesh 0 "quad" (f32, normals and uvs), mesh 1 "tri_dp"
    /// (f64, positions only) at offset 49 of the table.
    #[test]
    fn reads_a_file_mitsuba_reads() {
        const ORACLE: [u8; 112] = [
            0x1c, 0x04, 0x04, 0x00, 0x78, 0x9c, 0x63, 0x16, 0x60, 0x60, 0x28, 0x2c, 0x4d, 0x4c,
            0x61, 0x60, 0x61, 0x80, 0x00, 0x26, 0x06, 0x6c, 0xa0, 0xc1, 0x1e, 0x95, 0x8d, 0xce,
            0xc7, 0xa7, 0x96, 0x58, 0x36, 0xb2, 0xb9, 0x10, 0x9a, 0x11, 0xc9, 0x3d, 0x20, 0x9a,
            0x19, 0x88, 0x01, 0xed, 0xa9, 0x0a, 0xc1, 0x1c, 0x04, 0x04, 0x00, 0x78, 0x9c, 0x63,
            0x50, 0x60, 0x60, 0x28, 0x29, 0xca, 0x8c, 0x4f, 0x29, 0x60, 0x60, 0x66, 0x80, 0x00,
            0x46, 0x06, 0x7c, 0xe0, 0x83, 0x3d, 0x2a, 0x8d, 0x2e, 0x8e, 0x5d, 0x1d, 0xc8, 0x4c,
            0x26, 0x20, 0x06, 0x00, 0xf5, 0xb2, 0x08, 0x95, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
            0x00, 0x00, 0x31, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00,
        ];
        let q = read(&ORACLE, 0).unwrap();
        let v = |x, y, z| Vec3::new(x, y, z);
        assert_eq!(
            q.positions,
            vec![v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)]
        );
        assert_eq!(q.normals, Some(vec![Vec3::Z; 4]));
        assert_eq!(q.uvs.as_ref().unwrap()[1], Vec2::new(1.0, 0.0));
        assert_eq!(q.indices, vec![[0, 1, 2], [0, 2, 3]]);
        let t = read(&ORACLE, 1).unwrap();
        assert_eq!(
            t.positions,
            vec![v(0., 0., 1.), v(1., 0., 1.), v(0., 1., 1.)]
        );
        assert!(t.normals.is_none() && t.uvs.is_none());
        assert_eq!(t.indices, vec![[0, 1, 2]]);
    }

    /// Every version, precision and optional array through the test writer (flate2's zlib).
    #[test]
    fn reads_every_version_precision_and_index() {
        for version in [3, 4] {
            for double in [false, true] {
                let bytes = file(&[quad(), tri()], version, double);
                let a = read(&bytes, 0).unwrap();
                assert_eq!(a.positions.len(), 4);
                assert_eq!(a.indices, vec![[0, 1, 2], [0, 2, 3]]);
                assert_eq!(a.uvs.as_ref().unwrap()[2], Vec2::new(1.0, 1.0));
                assert_eq!(a.normals.as_ref().unwrap()[3], Vec3::Z);
                assert_eq!(a.attributes[0].name, "vertex_color");
                assert_eq!(&a.attributes[0].values[3..6], &[0.0, 1.0, 0.0]);
                let b = read(&bytes, 1).unwrap();
                assert_eq!(
                    b.positions,
                    vec![
                        Vec3::new(0.0, 0.0, 1.0),
                        Vec3::new(2.0, 0.0, 1.0),
                        Vec3::new(0.0, 3.0, 1.0)
                    ]
                );
                assert!(b.normals.is_none() && b.uvs.is_none() && b.attributes.is_empty());
                let e = read(&bytes, 2).unwrap_err();
                assert!(e.contains("out of range") && e.contains("2 mesh"), "{e}");
            }
        }
    }

    #[test]
    fn bad_files_are_refused_with_a_reason() {
        let good = file(&[quad(), tri()], 4, false);
        let mut wrong_id = good.clone();
        wrong_id[0] = 0x04;
        wrong_id[1] = 0x1C;
        assert!(read(&wrong_id, 0)
            .unwrap_err()
            .contains("format identifier"));
        let mut v5 = good.clone();
        v5[2] = 5;
        assert!(read(&v5, 0).unwrap_err().contains("version 5"));
        let truncated = &good[..good.len() / 3];
        assert!(read(truncated, 0).unwrap_err().contains("ends early"));
        let mut bad_index = quad();
        bad_index.indices[1][2] = 4;
        let e = read(&file(&[bad_index], 4, false), 0).unwrap_err();
        assert!(e.contains("triangle 1 names vertex 4"), "{e}");
        assert!(read(&[0x1C, 0x04], 0).is_err());
    }

    proptest! {
        /// Round trip on random meshes: what the writer puts in, the reader gives back (f32
        /// exactly; f64 narrowed from the f32 values, so exactly too), for any mesh of any
        /// file, and no random damage to a file makes the reader panic.
        #[test]
        fn round_trip_and_damage(
            meshes in prop::collection::vec((1usize..20, 0usize..30, any::<(bool, bool, bool)>(), -1e3f32..1e3), 1..4),
            version in 3u16..5,
            double in any::<bool>(),
            damage in prop::collection::vec((any::<usize>(), any::<u8>()), 0..4),
        ) {
            let data: Vec<MeshData> = meshes.iter().map(|&(nv, nt, (n, uv, c), x)| {
                let f = |k: usize, j: usize| x * (k * 3 + j) as f32 * 0.37;
                MeshData {
                    name: "m".repeat(nt % 3),
                    positions: (0..nv).map(|k| [f(k, 0), f(k, 1), f(k, 2)]).collect(),
                    normals: n.then(|| (0..nv).map(|k| [f(k, 2), 1.0, 0.0]).collect()),
                    uvs: uv.then(|| (0..nv).map(|k| [f(k, 1), 0.5]).collect()),
                    colors: c.then(|| (0..nv).map(|k| [0.1, f(k, 0), 0.3]).collect()),
                    indices: (0..nt).map(|t| [(t % nv) as u32, ((t * 7) % nv) as u32, ((t * 13 + 1) % nv) as u32]).collect(),
                }
            }).collect();
            let bytes = file(&data, version, double);
            for (i, m) in data.iter().enumerate() {
                let got = read(&bytes, i as u32).unwrap();
                let v3 = |a: &[f32; 3]| Vec3::from_array(*a);
                prop_assert_eq!(&got.positions, &m.positions.iter().map(v3).collect::<Vec<_>>());
                prop_assert_eq!(&got.normals, &m.normals.as_ref().map(|ns| ns.iter().map(v3).collect::<Vec<_>>()));
                prop_assert_eq!(&got.uvs, &m.uvs.as_ref().map(|u| u.iter().map(|a| Vec2::from_array(*a)).collect::<Vec<_>>()));
                prop_assert_eq!(got.attributes.len(), usize::from(m.colors.is_some()));
                prop_assert_eq!(&got.indices, &m.indices);
            }
            let mut damaged = bytes.clone();
            for (at, byte) in damage {
                let n = damaged.len();
                damaged[at % n] = byte;
            }
            for i in 0..data.len() as u32 + 1 {
                let _ = read(&damaged, i);
            }
        }
    }
}
