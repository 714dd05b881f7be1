//! Mitsuba's binary grid volume files (`.vol`, the format of Mitsuba's `gridvolume` and
//! `sdfgrid` plugins), as Mitsuba 3.9.1 reads them.
//!
//! Layout (every number little-endian):
//! - the bytes `VOL` and the version byte 3;
//! - `i32` encoding: 1 (dense `f32` values; the only one Mitsuba 3 reads);
//! - `i32` resolutions along x, y and z, then `i32` channels per sample;
//! - six `f32`: the grid's bounding box (min x, y, z, max x, y, z), which `sdfgrid` ignores
//!   (its grid spans the unit cube of its object space);
//! - the samples, x fastest, then y, then z, each with its channels in order.

use crate::error::io_message;
use std::io::Read;
use std::path::Path;

/// A grid volume as stored: `channels` values per sample, samples x fastest, then y, then z.
#[derive(Clone, Debug, PartialEq)]
pub struct VolumeGrid {
    /// Samples along x, y and z (each at least 1).
    pub resolution: [u32; 3],
    /// Values per sample.
    pub channels: u32,
    /// The file's bounding box, min and max corners.
    pub bbox: [[f32; 3]; 2],
    /// The values: `resolution[0] * resolution[1] * resolution[2] * channels` of them.
    pub values: Vec<f32>,
}

/// Reads a `.vol` file. Errors name the file as the scene names it (`shown_name`).
pub(crate) fn load_vol(path: &Path, shown_name: &str) -> Result<VolumeGrid, String> {
    let file = std::fs::File::open(path)
        .map_err(|e| format!("cannot open grid '{shown_name}': {}", io_message(&e)))?;
    read_vol(std::io::BufReader::new(file)).map_err(|e| format!("grid '{shown_name}': {e}"))
}

/// Reads a `.vol` file's bytes.
pub(crate) fn read_vol(mut r: impl Read) -> Result<VolumeGrid, String> {
    let short = |e: std::io::Error| match e.kind() {
        std::io::ErrorKind::UnexpectedEof => "the file ends early".to_string(),
        _ => io_message(&e),
    };
    let mut magic = [0u8; 4];
    r.read_exact(&mut magic).map_err(short)?;
    if &magic[..3] != b"VOL" {
        return Err("not a Mitsuba grid volume (it does not start with 'VOL')".into());
    }
    if magic[3] != 3 {
        return Err(format!(
            "version {} of the grid volume format (Mitsuba reads version 3)",
            magic[3]
        ));
    }
    let mut int = || -> Result<i32, String> {
        let mut b = [0u8; 4];
        r.read_exact(&mut b).map_err(short)?;
        Ok(i32::from_le_bytes(b))
    };
    let encoding = int()?;
    if encoding != 1 {
        return Err(format!(
            "encoding {encoding} (Mitsuba 3 reads encoding 1, dense 32-bit floats, only)"
        ));
    }
    let mut dims = [0u32; 4];
    for (d, name) in dims.iter_mut().zip([
        "x resolution",
        "y resolution",
        "z resolution",
        "channel count",
    ]) {
        let v = int()?;
        *d = u32::try_from(v)
            .ok()
            .filter(|&v| v > 0)
            .ok_or_else(|| format!("{name} {v} (must be positive)"))?;
    }
    let [nx, ny, nz, channels] = dims;
    let count = [nx, ny, nz, channels]
        .iter()
        .try_fold(1u64, |acc, &d| acc.checked_mul(u64::from(d)))
        .filter(|&c| c <= 1 << 32)
        .ok_or_else(|| format!("{nx} x {ny} x {nz} samples of {channels} channels is too large"))?;
    // Read as far as the file goes, not allocated up front: a damaged header's counts must
    // not reserve gigabytes.
    let mut floats = |n: usize| -> Result<Vec<f32>, String> {
        let mut bytes = Vec::new();
        (&mut r)
            .take(n as u64 * 4)
            .read_to_end(&mut bytes)
            .map_err(short)?;
        if bytes.len() < n * 4 {
            return Err("the file ends early".into());
        }
        Ok(bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect())
    };
    let b = floats(6)?;
    let values = floats(count as usize)?;
    Ok(VolumeGrid {
        resolution: [nx, ny, nz],
        channels,
        bbox: [[b[0], b[1], b[2]], [b[3], b[4], b[5]]],
        values,
    })
}

/// The bytes of a `.vol` file holding `grid` (for tests and tools that write grids).
pub fn write_vol(grid: &VolumeGrid) -> Vec<u8> {
    let mut out = b"VOL\x03".to_vec();
    let ints = [
        1u32,
        grid.resolution[0],
        grid.resolution[1],
        grid.resolution[2],
        grid.channels,
    ];
    for v in ints {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for v in grid.bbox.iter().flatten().chain(&grid.values) {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> VolumeGrid {
        VolumeGrid {
            resolution: [2, 3, 2],
            channels: 1,
            bbox: [[0.0; 3], [1.0; 3]],
            values: (0..12).map(|i| i as f32 - 5.5).collect(),
        }
    }

    #[test]
    fn a_written_grid_reads_back() {
        let g = grid();
        assert_eq!(read_vol(&write_vol(&g)[..]).unwrap(), g);
    }

    #[test]
    fn damaged_files_are_refused_with_the_reason() {
        let bytes = write_vol(&grid());
        let cases: Vec<(Vec<u8>, &str)> = vec![
            (bytes[..bytes.len() - 1].to_vec(), "ends early"),
            (b"VOX\x03".to_vec(), "does not start with 'VOL'"),
            ([&b"VOL\x02"[..], &bytes[4..]].concat(), "version 2"),
            (
                [&bytes[..4], &2u32.to_le_bytes()[..], &bytes[8..]].concat(),
                "encoding 2",
            ),
            (
                [&bytes[..8], &0u32.to_le_bytes()[..], &bytes[12..]].concat(),
                "x resolution 0",
            ),
            (
                [&bytes[..8], &[0xff; 12][..], &bytes[20..]].concat(),
                "x resolution -1",
            ),
            (Vec::new(), "ends early"),
        ];
        for (b, want) in cases {
            let e = read_vol(&b[..]).unwrap_err();
            assert!(e.contains(want), "{want}: {e}");
        }
    }

    #[test]
    fn arbitrary_bytes_never_panic() {
        // Fuzz: every prefix and single-byte corruption of a valid file.
        let bytes = write_vol(&grid());
        for n in 0..bytes.len() {
            let _ = read_vol(&bytes[..n]);
            for v in [0u8, 0x7f, 0xff] {
                let mut b = bytes.clone();
                b[n] = v;
                let _ = read_vol(&b[..]);
            }
        }
    }
}
