//! The precomputed RGB-to-spectrum coefficient table of Jakob and Hanika 2019 (section 4 of the
//! paper; `rgb2spec_opt.cpp` and `rgb2spec.c` of mitsuba-renderer/rgb2spec), for linear sRGB
//! reflectances under D65: upsampling a colour is a lookup with trilinear interpolation instead
//! of a [`RgbSigmoid::fit`] solve.
//!
//! # Layout and lookup (as `rgb2spec`)
//! Three sub-tables of `res^3` cells (`res` = [`RgbToSpectrumTable::RESOLUTION`] = 64, the
//! resolution Mitsuba 3 ships as `srgb.coeff`), three coefficients per cell, at index
//! `((l res + k) res + j) res + i`:
//! - `l` is the largest channel (0 = R, 1 = G, 2 = B; ties go to the later channel);
//! - `i` and `j` index `x = rgb[(l + 1) % 3] / rgb[l]` and `y = rgb[(l + 2) % 3] / rgb[l]` on
//!   the uniform grid `i / (res - 1)`;
//! - `k` indexes the largest channel `z = rgb[l]` on the brightness axis
//!   `scale[k] = smoothstep(smoothstep(k / (res - 1)))`, `smoothstep(v) = v^2 (3 - 2 v)`, which
//!   is dense near black and white where the coefficients change fastest; a lookup finds `z`'s
//!   interval by binary search.
//!
//! The cell at `(l, k, j, i)` holds the fit of the colour with `rgb[l] = scale[k]`,
//! `rgb[(l + 1) % 3] = x scale[k]`, `rgb[(l + 2) % 3] = y scale[k]`. A lookup clamps the colour
//! to [0, 1] and interpolates the three coefficients trilinearly in `(x, y, z)`. Unlike
//! `rgb2spec`, whose coefficients are in nanometres, they are kept in this crate's normalised
//! wavelength `t = (l - 360 nm) / 470 nm` (the optimiser's own variable, better conditioned), so
//! a lookup returns an [`RgbSigmoid`]. Greys (`r == g == b`, black and white included) bypass
//! the table and return [`RgbSigmoid::constant`], exactly as [`RgbSigmoid::fit`] does.
//!
//! # Construction
//! Entries are solved with the crate's own solver (the one behind [`RgbSigmoid::fit`]; linear
//! sRGB residual, converged to 1e-6 per channel with the coefficients rounded to f32). As
//! `rgb2spec_opt` does, each `(l, j, i)` column of the brightness axis is walked from
//! `k = res / 5` up to `res - 1` and then from `res / 5` down to 0, each solve warm-started from
//! its neighbour; here the start is extrapolated linearly from the two previous entries, the
//! solve is undamped Gauss-Newton (falling back to [`RgbSigmoid::fit_from`], then to a cold
//! [`RgbSigmoid::fit`]), and the entry at `k = res / 5` is warm-started from the previous column
//! `i - 1` (a cold fit for `i = 0`). Rows `(l, j)` are solved in parallel (rayon, in a pool of
//! its own so that a caller inside rayon tasks cannot deadlock on the first use), each row
//! serially, so the table does not depend on the thread count. Two kinds of node have no finite
//! fit: `k = 0` is black (the entry copies `k = 1`, whose brightness `scale[1]` is 1.7e-6), and
//! the white corner `(k, j, i) = (res - 1, res - 1, res - 1)`, whose constant 1 has an infinite
//! coefficient (the entry is the mean of its neighbours on the faces `x = 1` and `y = 1`; it is
//! only reached by colours with a channel within 1.7e-6 of 1). About 12 s on two idle cores,
//! once per machine.
//!
//! # Accuracy
//! The colour of a looked-up spectrum (under D65, as [`RgbSigmoid::fit`] inverts it) differs
//! from the colour looked up by the interpolation error: over uniform random colours about
//! 2e-4 per channel on average, 6e-4 at the 99th percentile, 1.6e-3 at worst (the exact fit:
//! below 1e-6). Near white the coefficients grow like `1 / sqrt(1 - v)` and the error does too:
//! up to 1.3e-2 in [0.98, 1]^3 (mean 4e-3). Greys are exact (the constant), as with `fit`.
//!
//! # Disk cache
//! The table is built at first use ([`RgbToSpectrumTable::get`]) and cached in a file, so
//! that later processes load it (tens of milliseconds) instead of rebuilding it:
//! - folder: `$PT_CACHE_DIR` if set and not empty, else `$XDG_CACHE_HOME/pt` (if absolute),
//!   else `$HOME/.cache/pt`; with none of them, no cache;
//! - file: `rgb2spec-srgb-64-v1.bin` (resolution and format version in the name), about 9 MB:
//!   a 40-byte header (magic `PTRGB2SP`, format version u32, resolution u32, cell count u64, a
//!   fingerprint u64 of the colorimetry the solver inverts, FNV-1a 64 checksum of the payload),
//!   then the coefficients as little-endian f32 in table order;
//! - written atomically: a temporary file in the same folder, synced, then renamed over the
//!   final name, so a reader never sees a partial file and concurrent writers are harmless;
//! - a missing, truncated, corrupted or mismatched file (another version, resolution or
//!   colorimetry: CIE tables, D65, matrix or quadrature) is rebuilt and rewritten silently; a
//!   folder that cannot be created or written only means the table lives in memory for this
//!   process. The cache never causes an error or a panic. Deleting the file is always safe.
//!
//! Changing the solver or the walk without changing the colorimetry must bump `FORMAT_VERSION`.
use super::{fit_warm, quadrature, RgbSigmoid};
use rayon::prelude::*;
use std::ffi::OsString;
use std::fmt;
use std::fs;
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;

/// Version of the cache file format and of the construction; bump it when either changes.
const FORMAT_VERSION: u32 = 1;
/// First bytes of a cache file.
const MAGIC: [u8; 8] = *b"PTRGB2SP";
/// Magic, version, resolution, cell count, colorimetry fingerprint, payload checksum.
const HEADER_LEN: usize = 8 + 4 + 4 + 8 + 8 + 8;
/// Initial damping of the table's warm-started solves: Gauss-Newton (the damping only grows if
/// a step fails to reduce the residual), as `rgb2spec_opt`, instead of [`super::FIT_DAMPING`],
/// which costs two to three more evaluations per entry (measured at res 32).
const TABLE_DAMPING: f64 = 1e-12;

/// The Jakob and Hanika 2019 coefficient table for linear sRGB reflectances (3 x 64^3 cells);
/// [`lookup`](Self::lookup) turns a colour into an [`RgbSigmoid`] in well under a microsecond.
///
/// Layout and lookup are those of the paper's `rgb2spec`: the largest channel picks one of
/// three sub-tables, the other two divided by it are `x` and `y` on a uniform 64 x 64 grid, the
/// largest is looked up on the brightness axis `smoothstep(smoothstep(k / 63))`, and the
/// coefficients (in the normalised wavelength of [`RgbSigmoid::from_coefficients`]) are
/// interpolated trilinearly. Greys return the exact constant. The interpolation error is about
/// 2e-4 per channel on average and below 2e-3 over random colours, up to about 1.3e-2 near
/// white (the exact [`RgbSigmoid::fit`] is within 1e-6).
///
/// The shared table ([`get`](Self::get)) is built at first use with the solver of
/// [`RgbSigmoid::fit`] (about 12 s on two cores) and cached on disk, in `$PT_CACHE_DIR`, else
/// `$XDG_CACHE_HOME/pt`, else `$HOME/.cache/pt` (file `rgb2spec-srgb-64-v1.bin`, 9.4 MB,
/// checksummed and written atomically; loading it takes a few tens of milliseconds). A
/// missing, damaged or outdated file is rebuilt silently; an unwritable folder only means the
/// table is kept in memory for the process. Deleting the file is always safe.
pub struct RgbToSpectrumTable {
    /// Cells per axis.
    res: usize,
    /// Brightness axis, `smoothstep(smoothstep(k / (res - 1)))`, strictly increasing.
    scale: Vec<f32>,
    /// `3 res^3` coefficient triples, index `((l res + k) res + j) res + i`.
    coeffs: Vec<[f32; 3]>,
}

impl fmt::Debug for RgbToSpectrumTable {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("RgbToSpectrumTable")
            .field("resolution", &self.res)
            .finish_non_exhaustive()
    }
}

/// The reflectance spectrum of the linear sRGB colour `rgb`, looked up in the shared table
/// ([`RgbToSpectrumTable::get`]; the first call may build it). Components are clamped to
/// [0, 1] (NaN to 0) as [`RgbSigmoid::fit`] does; greys give the exact constant, so black is 0
/// and (1, 1, 1) is 1 at every wavelength. Its colour under D65 is `rgb` to within the table's
/// interpolation error: about 2e-4 per channel on average, below 2e-3 over random colours, up to
/// about 1.3e-2 near white (see [`RgbToSpectrumTable`]; [`RgbSigmoid::fit`] is exact to 1e-6).
pub fn srgb_to_sigmoid(rgb: [f32; 3]) -> RgbSigmoid {
    RgbToSpectrumTable::get().lookup(rgb)
}

impl RgbToSpectrumTable {
    /// Cells per axis of the shared table (Mitsuba 3's `srgb.coeff` uses the same).
    pub const RESOLUTION: usize = 64;

    /// The shared table: loaded from the disk cache, or built (and cached) on the first call in
    /// a process; later calls return it at once. Never fails: without a usable cache the table
    /// is built and kept in memory.
    pub fn get() -> &'static RgbToSpectrumTable {
        static TABLE: OnceLock<RgbToSpectrumTable> = OnceLock::new();
        TABLE.get_or_init(|| Self::load_or_build(cache_dir().as_deref(), Self::RESOLUTION))
    }

    /// The file [`get`](Self::get) reads and writes with this process's environment, or `None`
    /// when no cache folder is defined. The file may not exist yet.
    pub fn cache_path() -> Option<PathBuf> {
        cache_dir().map(|d| d.join(file_name(Self::RESOLUTION)))
    }

    /// Cells per axis.
    pub fn resolution(&self) -> usize {
        self.res
    }

    /// The reflectance whose colour under D65 is (to the interpolation error) the linear sRGB
    /// `rgb`, clamped to [0, 1] (NaN to 0) as [`RgbSigmoid::fit`] does. Greys give the exact
    /// [`RgbSigmoid::constant`]; other colours the trilinear interpolation of the coefficients
    /// of the eight surrounding cells.
    pub fn lookup(&self, rgb: [f32; 3]) -> RgbSigmoid {
        let rgb = rgb.map(|v| if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) });
        if rgb[0] == rgb[1] && rgb[1] == rgb[2] {
            return RgbSigmoid::constant(rgb[0]);
        }
        // Largest channel, ties to the later one (rgb2spec_fetch); z > 0 as rgb is not grey.
        let mut l = 0;
        if rgb[1] >= rgb[l] {
            l = 1;
        }
        if rgb[2] >= rgb[l] {
            l = 2;
        }
        let res = self.res;
        let last = (res - 1) as f32;
        let z = rgb[l];
        let x = (rgb[(l + 1) % 3] * (last / z)).min(last);
        let y = (rgb[(l + 2) % 3] * (last / z)).min(last);
        let xi = (x as usize).min(res - 2);
        let yi = (y as usize).min(res - 2);
        // The last k with scale[k] <= z, within 0..=res - 2.
        let zi = self
            .scale
            .partition_point(|&s| s <= z)
            .saturating_sub(1)
            .min(res - 2);
        let (fx, fy) = (x - xi as f32, y - yi as f32);
        let fz = (z - self.scale[zi]) / (self.scale[zi + 1] - self.scale[zi]);
        // The eight cells around (x, y, z), in the order (k, j, i) = 000, 001, 010, .., 111.
        let base = ((l * res + zi) * res + yi) * res + xi;
        let (dj, dk) = (res, res * res);
        let cell = &self.coeffs[base..=base + dk + dj + 1];
        let lerp = |a: [f32; 3], b: [f32; 3], f: f32| {
            [
                (1.0 - f) * a[0] + f * b[0],
                (1.0 - f) * a[1] + f * b[1],
                (1.0 - f) * a[2] + f * b[2],
            ]
        };
        let c0 = lerp(
            lerp(cell[0], cell[1], fx),
            lerp(cell[dj], cell[dj + 1], fx),
            fy,
        );
        let c1 = lerp(
            lerp(cell[dk], cell[dk + 1], fx),
            lerp(cell[dk + dj], cell[dk + dj + 1], fx),
            fy,
        );
        RgbSigmoid::from_coefficients(lerp(c0, c1, fz))
    }

    /// The entry of sub-table `l` at brightness index `k` and grid indices `(j, i)`.
    #[cfg(test)]
    fn entry(&self, l: usize, k: usize, j: usize, i: usize) -> RgbSigmoid {
        let res = self.res;
        RgbSigmoid::from_coefficients(self.coeffs[((l * res + k) * res + j) * res + i])
    }

    /// The table from the cache file in `dir` if it is valid, else built and (if `dir` is
    /// given and writable) stored there.
    fn load_or_build(dir: Option<&Path>, res: usize) -> Self {
        if let Some(table) = dir.and_then(|d| Self::load(d, res)) {
            return table;
        }
        let table = Self::build_isolated(res);
        if let Some(dir) = dir {
            // An unwritable cache only costs a rebuild in the next process.
            let _ = table.store(dir);
        }
        table
    }

    /// [`build`](Self::build) in a rayon pool of its own, driven from a thread of its own. The
    /// caller may be a rayon worker (a texture loaded in a parallel scene build): waiting for a
    /// job of the global pool would let it pick up another task that asks for the table while
    /// it is being initialised (a deadlock on the `OnceLock`), and the global pool's workers may
    /// all be blocked waiting for the table.
    fn build_isolated(res: usize) -> Self {
        let work = move || match rayon::ThreadPoolBuilder::new()
            .thread_name(|i| format!("pt-rgb2spec-{i}"))
            .build()
        {
            Ok(pool) => pool.install(|| Self::build(res)),
            Err(_) => Self::build_serial(res),
        };
        match std::thread::Builder::new()
            .name("pt-rgb2spec".into())
            .spawn(work)
        {
            Ok(handle) => handle
                .join()
                .unwrap_or_else(|panic| std::panic::resume_unwind(panic)),
            Err(_) => Self::build_serial(res),
        }
    }

    /// Build the table with rows solved in parallel in the current rayon pool.
    fn build(res: usize) -> Self {
        let scale = brightness_axis(res);
        let rows: Vec<Vec<RgbSigmoid>> = (0..3 * res)
            .into_par_iter()
            .map(|row| build_row(&scale, row / res, row % res))
            .collect();
        Self::assemble(scale, rows)
    }

    /// [`build`](Self::build) on the calling thread (if no thread can be started).
    fn build_serial(res: usize) -> Self {
        let scale = brightness_axis(res);
        let rows = (0..3 * res)
            .map(|row| build_row(&scale, row / res, row % res))
            .collect();
        Self::assemble(scale, rows)
    }

    /// Scatter the rows (`(l, j)` in order, each `[i][k]`) into table order.
    fn assemble(scale: Vec<f32>, rows: Vec<Vec<RgbSigmoid>>) -> Self {
        let res = scale.len();
        let mut coeffs = vec![[0.0f32; 3]; 3 * res * res * res];
        for (row, entries) in rows.iter().enumerate() {
            let (l, j) = (row / res, row % res);
            for (n, s) in entries.iter().enumerate() {
                let (i, k) = (n / res, n % res);
                coeffs[((l * res + k) * res + j) * res + i] = s.c;
            }
        }
        // The white corner has no finite fit (the constant 1 has c2 = +inf) and is only used
        // for colours with a channel within 1.7e-6 of 1 that are not grey. The mean of its two
        // neighbours on the faces x = 1 and y = 1 of the last cell (the fits of
        // (1, 1, 1 - 1/63) and (1, 1 - 1/63, 1) in sub-table order) halves the error of
        // colours like (1, 0.99, 0.99) compared with a large constant (about 7e-3 instead of
        // 1.4e-2 at worst in 1 x [0.98, 1]^2).
        let at = |l: usize, k: usize, j: usize, i: usize| ((l * res + k) * res + j) * res + i;
        let n = res - 1;
        for l in 0..3 {
            let (a, b) = (coeffs[at(l, n, n - 1, n)], coeffs[at(l, n, n, n - 1)]);
            coeffs[at(l, n, n, n)] = [0, 1, 2].map(|q| 0.5 * (a[q] + b[q]));
        }
        debug_assert!(coeffs.iter().flatten().all(|v| v.is_finite()));
        RgbToSpectrumTable { res, scale, coeffs }
    }

    /// The cache file's bytes: header, then the coefficients as little-endian f32.
    fn to_bytes(&self) -> Vec<u8> {
        let mut payload = Vec::with_capacity(self.coeffs.len() * 12);
        for v in self.coeffs.iter().flatten() {
            payload.extend_from_slice(&v.to_le_bytes());
        }
        let mut out = Vec::with_capacity(HEADER_LEN + payload.len());
        out.extend_from_slice(&MAGIC);
        out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        out.extend_from_slice(&(self.res as u32).to_le_bytes());
        out.extend_from_slice(&(self.coeffs.len() as u64).to_le_bytes());
        out.extend_from_slice(&colorimetry_fingerprint().to_le_bytes());
        out.extend_from_slice(&fnv1a64(&payload).to_le_bytes());
        out.extend_from_slice(&payload);
        out
    }

    /// Parse a cache file for resolution `res`; `None` unless every header field matches, the
    /// length is exact, the checksum agrees and every coefficient is finite.
    fn from_bytes(bytes: &[u8], res: usize) -> Option<Self> {
        let cells = 3 * res * res * res;
        if res < 2 || bytes.len() != HEADER_LEN + 12 * cells {
            return None;
        }
        let (header, payload) = bytes.split_at(HEADER_LEN);
        let u32_at = |o: usize| u32::from_le_bytes(header[o..o + 4].try_into().unwrap());
        let u64_at = |o: usize| u64::from_le_bytes(header[o..o + 8].try_into().unwrap());
        let valid = header[..8] == MAGIC
            && u32_at(8) == FORMAT_VERSION
            && u32_at(12) as usize == res
            && u64_at(16) == cells as u64
            && u64_at(24) == colorimetry_fingerprint()
            && u64_at(32) == fnv1a64(payload);
        if !valid {
            return None;
        }
        let mut floats = payload
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes(b.try_into().unwrap()));
        let coeffs: Vec<[f32; 3]> = (0..cells)
            .map(|_| [(); 3].map(|_| floats.next().unwrap_or(f32::NAN)))
            .collect();
        if !coeffs.iter().flatten().all(|v| v.is_finite()) {
            return None;
        }
        Some(RgbToSpectrumTable {
            res,
            scale: brightness_axis(res),
            coeffs,
        })
    }

    /// The table cached in `dir`, if there is a valid one.
    fn load(dir: &Path, res: usize) -> Option<Self> {
        let bytes = fs::read(dir.join(file_name(res))).ok()?;
        Self::from_bytes(&bytes, res)
    }

    /// Write the table to `dir` atomically (temporary file in `dir`, synced, renamed).
    fn store(&self, dir: &Path) -> io::Result<()> {
        static COUNTER: AtomicU64 = AtomicU64::new(0);
        fs::create_dir_all(dir)?;
        let name = file_name(self.res);
        let tmp = dir.join(format!(
            ".{name}.{}.{}.tmp",
            std::process::id(),
            COUNTER.fetch_add(1, Ordering::Relaxed)
        ));
        let result = (|| {
            let mut file = fs::File::create_new(&tmp)?;
            file.write_all(&self.to_bytes())?;
            file.sync_all()?;
            fs::rename(&tmp, dir.join(&name))
        })();
        if result.is_err() {
            let _ = fs::remove_file(&tmp);
        }
        result
    }
}

/// `smoothstep(smoothstep(k / (res - 1)))` for k in 0..res (rgb2spec_opt, in double precision).
fn brightness_axis(res: usize) -> Vec<f32> {
    let smoothstep = |v: f64| v * v * (3.0 - 2.0 * v);
    (0..res)
        .map(|k| smoothstep(smoothstep(k as f64 / (res - 1) as f64)) as f32)
        .collect()
}

/// Solve the `res` columns `i = 0..res` of row `(l, j)`; returns the entries as `[i][k]`.
fn build_row(scale: &[f32], l: usize, j: usize) -> Vec<RgbSigmoid> {
    let res = scale.len();
    let start = (res / 5).max(1);
    let y = j as f64 / (res - 1) as f64;
    let mut entries = Vec::with_capacity(res * res);
    let mut previous_start: Option<RgbSigmoid> = None;
    for i in 0..res {
        let x = i as f64 / (res - 1) as f64;
        // The node colour: rgb[l] = b, rgb[l + 1] = x b, rgb[l + 2] = y b.
        let node = |k: usize| {
            let b = scale[k];
            let mut rgb = [0.0f32; 3];
            rgb[l] = b;
            rgb[(l + 1) % 3] = (x * b as f64) as f32;
            rgb[(l + 2) % 3] = (y * b as f64) as f32;
            rgb
        };
        let mut column = vec![RgbSigmoid::constant(0.0); res];
        let first = match &previous_start {
            Some(p) => RgbSigmoid::fit_from(node(start), p),
            None => RgbSigmoid::fit(node(start)),
        };
        previous_start = Some(first);
        column[start] = first;
        for ks in [
            (start + 1..res).collect::<Vec<_>>(),
            (1..start).rev().collect(),
        ] {
            // (entry, brightness) of the two previous nodes of this walk.
            let mut prev = (first, scale[start]);
            let mut prev2: Option<(RgbSigmoid, f32)> = None;
            for k in ks {
                let s = walk_step(node(k), scale[k], prev, prev2);
                column[k] = s;
                prev2 = Some(prev);
                prev = (s, scale[k]);
            }
        }
        // k = 0 is black, which no finite sigmoid reaches: reuse k = 1 (brightness 1.7e-6).
        // The white corner is set by `assemble`.
        column[0] = column[1];
        entries.extend(column);
    }
    entries
}

/// One solve of a column walk: the colour `rgb` at brightness `b`, from the previous entry
/// `prev` and the one before it (`prev2`), each with its brightness.
fn walk_step(
    rgb: [f32; 3],
    b: f32,
    prev: (RgbSigmoid, f32),
    prev2: Option<(RgbSigmoid, f32)>,
) -> RgbSigmoid {
    if rgb[0] == rgb[1] && rgb[1] == rgb[2] {
        return RgbSigmoid::constant(rgb[0]);
    }
    let c1 = prev.0.coefficients_f64();
    // Linear extrapolation along the brightness axis saves about half an iteration per entry.
    let start = match prev2 {
        Some((s2, b2)) => {
            let c2 = s2.coefficients_f64();
            c1 + (c1 - c2) * ((b - prev.1) as f64 / (prev.1 - b2) as f64)
        }
        None => c1,
    };
    if start.is_finite() {
        if let Some(s) = fit_warm(rgb, start, TABLE_DAMPING) {
            return s;
        }
    }
    // Rare (near the gamut boundary): the solver's own warm start, else its cold fit.
    RgbSigmoid::fit_from(rgb, &prev.0)
}

/// The cache folder: `$PT_CACHE_DIR`, else `$XDG_CACHE_HOME/pt`, else `$HOME/.cache/pt`.
fn cache_dir() -> Option<PathBuf> {
    let var = std::env::var_os;
    cache_dir_from(var("PT_CACHE_DIR"), var("XDG_CACHE_HOME"), var("HOME"))
}

/// [`cache_dir`] from the values of the three variables; empty values count as unset.
fn cache_dir_from(
    pt_cache_dir: Option<OsString>,
    xdg_cache_home: Option<OsString>,
    home: Option<OsString>,
) -> Option<PathBuf> {
    let set = |v: Option<OsString>| v.filter(|v| !v.is_empty()).map(PathBuf::from);
    if let Some(d) = set(pt_cache_dir) {
        return Some(d);
    }
    // The XDG base directory specification ignores relative paths.
    if let Some(d) = set(xdg_cache_home).filter(|d| d.is_absolute()) {
        return Some(d.join("pt"));
    }
    set(home).map(|h| h.join(".cache").join("pt"))
}

/// The cache file name for resolution `res`.
fn file_name(res: usize) -> String {
    format!("rgb2spec-srgb-{res}-v{FORMAT_VERSION}.bin")
}

/// FNV-1a, 64 bits.
fn fnv1a64(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// FNV-1a of the solver's quadrature (nodes and RGB weights, f64): changes whenever the CIE
/// tables, D65, the XYZ-to-sRGB matrix or the quadrature change, which invalidates a cached
/// table.
fn colorimetry_fingerprint() -> u64 {
    let q = quadrature();
    let mut bytes = Vec::with_capacity(q.t.len() * 32);
    for (t, w) in q.t.iter().zip(&q.w) {
        for v in [*t, w.x, w.y, w.z] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    fnv1a64(&bytes)
}

#[cfg(test)]
mod tests {
    use super::super::tests::reflectance_rgb;
    use super::*;
    use crate::cie;

    /// Linear sRGB of a reflectance under D65, by the same rule as
    /// [`reflectance_rgb`] (Simpson on 1 nm panels, products in f32, normalised by the
    /// D65-weighted y-bar, then the XYZ-to-sRGB matrix) but with the weights tabulated once, so
    /// that thousands of colours are cheap. Independent of the solver's quadrature code.
    fn observed_rgb(s: &RgbSigmoid) -> [f32; 3] {
        static W: OnceLock<(Vec<f32>, Vec<[f64; 3]>)> = OnceLock::new();
        let (lambda, w) = W.get_or_init(|| {
            let (mut lambda, mut w) = (Vec::new(), Vec::new());
            let norm =
                cie::integrate_visible(|l| (cie::d65(l as f32) * cie::cmf_y(l as f32)) as f64);
            for k in cie::LAMBDA_MIN as i32..cie::LAMBDA_MAX as i32 {
                for (dl, q) in [(0.0, 1.0 / 6.0), (0.5, 4.0 / 6.0), (1.0, 1.0 / 6.0)] {
                    let l = (k as f64 + dl) as f32;
                    let cmf = cie::cmf(l);
                    lambda.push(l);
                    w.push([0, 1, 2].map(|c| (cie::d65(l) * cmf[c]) as f64 * q / norm));
                }
            }
            (lambda, w)
        });
        let mut xyz = [0.0f64; 3];
        for (&l, w) in lambda.iter().zip(w) {
            let r = s.eval(l) as f64;
            for c in 0..3 {
                xyz[c] += w[c] * r;
            }
        }
        crate::color::xyz_to_srgb(xyz.map(|v| v as f32))
    }

    /// Largest per-channel difference.
    fn max_diff(a: [f32; 3], b: [f32; 3]) -> f32 {
        (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, f32::max)
    }

    /// Uniform random colours in [0, 1]^3 from a fixed seed (64-bit LCG, top 24 bits).
    fn random_colours(n: usize, seed: u64) -> Vec<[f32; 3]> {
        let mut state = seed;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        (0..n).map(|_| [next(), next(), next()]).collect()
    }

    /// A fresh, empty folder for one test (removed again by the test).
    fn temp_dir(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("pt-rgb2spec-test-{}-{name}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn observer_matches_reference_quadrature() {
        // The tabulated observer of these tests is the rgb2spec tests' reflectance_rgb.
        for rgb in [[0.8f32, 0.3, 0.1], [0.05, 0.9, 0.4], [1.0, 0.0, 0.0]] {
            let s = RgbSigmoid::fit(rgb);
            let (a, b) = (observed_rgb(&s), reflectance_rgb(|l| s.eval(l)));
            assert!(max_diff(a, b) < 1e-6, "{a:?} vs {b:?}");
        }
    }

    /// Error statistics (mean, 99th percentile, max of the largest per-channel difference).
    fn error_stats(errors: &mut [f32]) -> (f64, f32, f32) {
        errors.sort_by(f32::total_cmp);
        let n = errors.len();
        let mean = errors.iter().map(|&v| v as f64).sum::<f64>() / n as f64;
        (mean, errors[n * 99 / 100], errors[n - 1])
    }

    /// Round-trip error of the table over `colours` and of the exact fit over the first
    /// `fits` of them (a fit costs a fraction of a millisecond, a lookup under a microsecond).
    fn round_trip(
        table: &RgbToSpectrumTable,
        colours: &[[f32; 3]],
        fits: usize,
    ) -> [(f64, f32, f32); 2] {
        let mut t: Vec<f32> = colours
            .par_iter()
            .map(|&c| max_diff(observed_rgb(&table.lookup(c)), c))
            .collect();
        let mut f: Vec<f32> = colours[..fits]
            .par_iter()
            .map(|&c| max_diff(observed_rgb(&RgbSigmoid::fit(c)), c))
            .collect();
        [error_stats(&mut t), error_stats(&mut f)]
    }

    #[test]
    fn round_trip_random_colours() {
        // What the table is for: a looked-up spectrum, seen as a reflectance under D65 (the
        // colorimetry `fit` inverts), has the colour that was looked up. Measured over these
        // 4000 colours: table mean 2.1e-4, p99 5.9e-4, max 1.6e-3 (the interpolation error;
        // largest where a channel nears 1); exact fit (first 1000) mean 1.3e-7, max 7e-7 (its
        // 1e-6 tolerance). The bounds have a margin of about 1.5 over the table's figures and
        // fail on real lookup bugs, each tried by breaking the code: the next sub-table (mean
        // 0.50), a linear brightness axis (mean 0.11), x and y swapped (mean 0.25), a half-cell
        // shift in x (mean 5.9e-3, max 9.0e-3) or in brightness (mean 1.2e-2).
        let table = RgbToSpectrumTable::get();
        let colours = random_colours(4000, 0x5eed_cafe_f00d_0001);
        let fits = 1000;
        let [(mean, p99, max), (fit_mean, fit_p99, fit_max)] = round_trip(table, &colours, fits);
        eprintln!(
            "round trip |rgb error| over {} colours: table mean {mean:.2e} p99 {p99:.2e} max \
             {max:.2e}; exact fit (first {fits}) mean {fit_mean:.2e} p99 {fit_p99:.2e} max \
             {fit_max:.2e}",
            colours.len()
        );
        assert!(
            mean < 3e-4 && p99 < 1e-3 && max < 2.5e-3,
            "{mean} {p99} {max}"
        );
        // The exact fit is three orders of magnitude better: the error above is the table's.
        assert!(fit_max < 1.5e-6, "{fit_max}");
    }

    #[test]
    fn near_white_is_the_weak_spot() {
        // Near white the coefficients grow like 1 / sqrt(1 - v) and trilinear interpolation on
        // the uniform x, y grid is least accurate (the exact fit is still within 1e-6). Measured:
        // [0.98, 1]^3 mean 4.2e-3, max 1.3e-2; the face r = 1 near white, 1 x [0.98, 1]^2, mean
        // 4.3e-3, max 7.4e-3 (1.5e-2 with a large constant in the white corner). The bounds
        // record these figures (margin 1.3) so that a change for the worse is noticed.
        let table = RgbToSpectrumTable::get();
        let cube: Vec<[f32; 3]> = random_colours(1000, 7)
            .iter()
            .map(|c| c.map(|v| 0.98 + 0.02 * v))
            .collect();
        let face: Vec<[f32; 3]> = cube.iter().map(|c| [1.0, c[1], c[2]]).collect();
        let [(cube_mean, _, cube_max), (_, _, cube_fit)] = round_trip(table, &cube, 100);
        let [(face_mean, _, face_max), (_, _, face_fit)] = round_trip(table, &face, 100);
        eprintln!(
            "near white: [0.98, 1]^3 mean {cube_mean:.2e} max {cube_max:.2e} (fit max \
             {cube_fit:.1e}); 1 x [0.98, 1]^2 mean {face_mean:.2e} max {face_max:.2e} (fit max \
             {face_fit:.1e})"
        );
        assert!(
            cube_mean < 5.5e-3 && cube_max < 1.7e-2,
            "{cube_mean} {cube_max}"
        );
        assert!(
            face_mean < 5.5e-3 && face_max < 1e-2,
            "{face_mean} {face_max}"
        );
        assert!(cube_fit < 1.5e-6 && face_fit < 1.5e-6);
    }

    /// The colour of node `(l, k, j, i)` of `table`, as the builder computes it.
    fn node_colour(table: &RgbToSpectrumTable, l: usize, k: usize, j: usize, i: usize) -> [f32; 3] {
        let (b, last) = (table.scale[k], (table.res - 1) as f64);
        let mut rgb = [0.0f32; 3];
        rgb[l] = b;
        rgb[(l + 1) % 3] = (i as f64 / last * b as f64) as f32;
        rgb[(l + 2) % 3] = (j as f64 / last * b as f64) as f32;
        rgb
    }

    #[test]
    fn grid_nodes_are_the_solvers_fits() {
        // Each entry is the solver's fit of its node's colour: it reproduces that colour at
        // least as well as a cold `RgbSigmoid::fit` (both to the solver's 1e-6, plus 1e-7 for
        // the f32 evaluation here; greys to their exact constant, whose colour is off by up to
        // 9.5e-5 because the D65 table's white is not the matrix's), and where the problem is
        // well conditioned it has the fit's coefficients (measured: relative difference below
        // 1e-4 from k = 3 up, bound 1e-3). At k = 1 and 2 (brightness 1.7e-6 and 2.6e-5) the
        // 1e-6 tolerance is most of the colour, so different coefficients are equally good
        // (measured up to 36% apart); only their colours are compared there. A lookup at a node
        // returns the entry (up to the f32 rounding of the interpolation weights).
        let table = RgbToSpectrumTable::get();
        let res = table.res;
        let grid = [0, 1, 18, 31, 45, 62, 63];
        let mut nodes = Vec::new();
        for l in 0..3 {
            for k in [1, 2, 3, 6, 11, 12, 13, 25, 40, 55, 61, 62, 63] {
                for j in grid {
                    for i in grid {
                        if !(k == res - 1 && i == res - 1 && j == res - 1) {
                            nodes.push((l, k, j, i));
                        }
                    }
                }
            }
        }
        nodes.par_iter().for_each(|&(l, k, j, i)| {
            let rgb = node_colour(table, l, k, j, i);
            let entry = table.entry(l, k, j, i);
            let fit = RgbSigmoid::fit(rgb);
            let (e, f) = (
                max_diff(observed_rgb(&entry), rgb),
                max_diff(observed_rgb(&fit), rgb),
            );
            assert!(
                e <= f.max(1e-6) + 1e-7,
                "node {l} {k} {j} {i} {rgb:?}: entry {entry:?} error {e:e}, fit {fit:?} {f:e}"
            );
            let size = fit.c.iter().fold(1.0f32, |a, v| a.max(v.abs()));
            let rel = |a: &RgbSigmoid, b: &RgbSigmoid| {
                (0..3).map(|q| (a.c[q] - b.c[q]).abs()).fold(0.0, f32::max) / size
            };
            if k >= 3 {
                assert!(
                    rel(&entry, &fit) < 1e-3,
                    "node {l} {k} {j} {i}: {entry:?} vs {fit:?}"
                );
            }
            // On the faces x = 1 or y = 1 ties send the lookup to another sub-table.
            if i < res - 1 && j < res - 1 {
                let found = table.lookup(rgb);
                assert!(rel(&found, &entry) < 1e-5, "{found:?} vs {entry:?}");
            }
        });
        // The two kinds of node without a finite fit: black (k = 0) copies k = 1, and the white
        // corner is the mean of its neighbours on the faces x = 1 and y = 1.
        let n = res - 1;
        for l in 0..3 {
            for (j, i) in [(0, 0), (5, 40), (n, n)] {
                assert_eq!(table.entry(l, 0, j, i), table.entry(l, 1, j, i));
            }
            let (a, b) = (table.entry(l, n, n - 1, n).c, table.entry(l, n, n, n - 1).c);
            let corner = table.entry(l, n, n, n).c;
            assert_eq!(corner, [0, 1, 2].map(|q| 0.5 * (a[q] + b[q])));
        }
    }

    #[test]
    fn greys_are_exact_and_inputs_are_clamped() {
        // Greys bypass the table and give exactly what `fit` gives (the constant), so black is
        // 0 and white 1 at every wavelength; out-of-range input is clamped as `fit` clamps it.
        let table = RgbToSpectrumTable::get();
        let mut greys = vec![0.0f32, 1e-7, 1.7e-6, 0.02, 0.25, 0.5, 0.75, 0.999_999, 1.0];
        greys.extend(random_colours(100, 3).iter().map(|c| c[0]));
        for v in greys {
            assert_eq!(table.lookup([v; 3]), RgbSigmoid::constant(v), "{v}");
            assert_eq!(table.lookup([v; 3]), RgbSigmoid::fit([v; 3]), "{v}");
        }
        for l in [360.0f32, 555.0, 830.0] {
            assert_eq!(srgb_to_sigmoid([0.0; 3]).eval(l), 0.0);
            assert_eq!(srgb_to_sigmoid([1.0; 3]).eval(l), 1.0);
        }
        assert_eq!(table.lookup([2.0, 1.5, 7.0]), RgbSigmoid::constant(1.0));
        assert_eq!(
            table.lookup([-1.0, f32::NAN, 0.0]),
            RgbSigmoid::constant(0.0)
        );
        assert_eq!(
            table.lookup([1.5, -0.2, f32::NAN]),
            table.lookup([1.0, 0.0, 0.0])
        );
        assert_eq!(
            srgb_to_sigmoid([0.3, 0.6, 0.1]),
            table.lookup([0.3, 0.6, 0.1])
        );
        // The largest channel picks the sub-table; ties go to the later channel, whose table
        // holds the same colour: both sides of a tie agree.
        let a = table.lookup([0.5, 0.5, 0.2]);
        let b = table.lookup([0.5, 0.5 - 1e-7, 0.2]);
        assert!(
            max_diff(observed_rgb(&a), observed_rgb(&b)) < 1e-5,
            "{a:?} {b:?}"
        );
    }

    #[test]
    fn cache_file_round_trip_and_damage() {
        // The file written for the full table reads back identically; any damage (a flipped
        // payload or header byte, a truncated or extended file, another resolution) is
        // rejected, so the caller rebuilds.
        let table = RgbToSpectrumTable::get();
        let dir = temp_dir("round-trip");
        table.store(&dir).unwrap();
        let path = dir.join(file_name(table.res));
        let bytes = fs::read(&path).unwrap();
        assert_eq!(bytes.len(), HEADER_LEN + 12 * 3 * table.res.pow(3));
        assert_eq!(bytes, table.to_bytes());
        let back = RgbToSpectrumTable::load(&dir, table.res).expect("a valid file");
        assert_eq!(
            (back.res, &back.scale, &back.coeffs),
            (table.res, &table.scale, &table.coeffs)
        );
        // Only the final file is left (the temporary one was renamed).
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 1);

        let res = table.res;
        let flipped = |at: usize| {
            let mut b = bytes.clone();
            b[at] ^= 0x10;
            b
        };
        for (what, damaged) in [
            ("payload byte", flipped(HEADER_LEN + 4_000_001)),
            ("last byte", flipped(bytes.len() - 1)),
            ("magic", flipped(0)),
            ("version", flipped(8)),
            ("resolution", flipped(12)),
            ("cell count", flipped(16)),
            ("fingerprint", flipped(24)),
            ("checksum", flipped(32)),
            ("truncated", bytes[..bytes.len() - 1].to_vec()),
            ("header only", bytes[..HEADER_LEN].to_vec()),
            ("empty", Vec::new()),
            ("extended", [&bytes[..], &[0]].concat()),
        ] {
            assert!(
                RgbToSpectrumTable::from_bytes(&damaged, res).is_none(),
                "{what}"
            );
        }
        assert!(RgbToSpectrumTable::from_bytes(&bytes, 32).is_none());
        // Through the file as well.
        fs::write(&path, flipped(HEADER_LEN + 123)).unwrap();
        assert!(RgbToSpectrumTable::load(&dir, res).is_none());
        fs::remove_dir_all(&dir).unwrap();
        assert!(RgbToSpectrumTable::load(&dir, res).is_none());
    }

    #[test]
    fn damaged_or_missing_cache_is_rebuilt() {
        // A small table (res 5, a few hundredths of a second) stands in for the full one: a
        // missing file is
        // built and written, a valid one is loaded, a damaged or truncated one is rebuilt and
        // rewritten, all silently.
        let res = 5;
        let dir = temp_dir("rebuild");
        let path = dir.join(file_name(res));
        let fresh = RgbToSpectrumTable::load_or_build(Some(&dir), res);
        let bytes = fs::read(&path).expect("written on first use");
        assert_eq!(bytes, fresh.to_bytes());
        // A valid file is what is loaded: mark it (a different but valid table) to tell.
        let mut marked = RgbToSpectrumTable {
            res,
            scale: fresh.scale.clone(),
            coeffs: fresh.coeffs.clone(),
        };
        marked.coeffs[5] = [1.0, 2.0, 3.0];
        marked.store(&dir).unwrap();
        assert_eq!(
            RgbToSpectrumTable::load_or_build(Some(&dir), res).coeffs[5],
            [1.0, 2.0, 3.0]
        );
        for damage in [
            |b: &mut Vec<u8>| b[HEADER_LEN + 100] ^= 1,
            |b: &mut Vec<u8>| b.truncate(b.len() / 2),
        ] {
            let mut b = bytes.clone();
            damage(&mut b);
            fs::write(&path, &b).unwrap();
            let t = RgbToSpectrumTable::load_or_build(Some(&dir), res);
            assert_eq!(t.coeffs, fresh.coeffs);
            assert_eq!(fs::read(&path).unwrap(), bytes, "rewritten");
        }
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn unusable_cache_folder_keeps_the_table_in_memory() {
        // A folder that cannot be created (its parent is a file; permissions do not stop root)
        // or no folder at all: the table is still built, without error or panic.
        let res = 5;
        let dir = temp_dir("unwritable");
        let file = dir.join("not-a-folder");
        fs::write(&file, b"x").unwrap();
        let cache = file.join("pt");
        assert!(RgbToSpectrumTable::load(&cache, res).is_none());
        let a = RgbToSpectrumTable::load_or_build(Some(&cache), res);
        assert!(a.store(&cache).is_err());
        let b = RgbToSpectrumTable::load_or_build(None, res);
        assert_eq!(a.coeffs, b.coeffs);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn build_does_not_depend_on_the_thread_count() {
        // Rows are solved independently and each serially, so one thread, three threads and
        // the serial builder give the same bytes (res 6 keeps this fast).
        let res = 6;
        let build = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| RgbToSpectrumTable::build(res))
                .to_bytes()
        };
        let one = build(1);
        assert_eq!(one, build(3));
        assert_eq!(one, RgbToSpectrumTable::build_serial(res).to_bytes());
        assert_eq!(one, RgbToSpectrumTable::build_isolated(res).to_bytes());
    }

    #[test]
    fn cache_folder_precedence() {
        // $PT_CACHE_DIR, else $XDG_CACHE_HOME/pt (absolute only), else $HOME/.cache/pt; empty
        // variables count as unset. Tested on the pure function: the environment is shared by
        // the test threads.
        let s = |v: &str| Some(std::ffi::OsString::from(v));
        let p = |v: &str| Some(PathBuf::from(v));
        assert_eq!(cache_dir_from(s("/c"), s("/x"), s("/h")), p("/c"));
        assert_eq!(cache_dir_from(s(""), s("/x"), s("/h")), p("/x/pt"));
        assert_eq!(cache_dir_from(None, s("rel"), s("/h")), p("/h/.cache/pt"));
        assert_eq!(cache_dir_from(None, s(""), s("/h")), p("/h/.cache/pt"));
        assert_eq!(cache_dir_from(None, None, None), None);
        assert_eq!(cache_dir_from(None, None, s("")), None);
        assert_eq!(file_name(64), "rgb2spec-srgb-64-v1.bin");
    }
}
