//! Part files: one share of a render split over processes (`pt render --part K/N`), written
//! by the part's process and read by `pt merge`.
//!
//! Layout (little-endian), version 1:
//!
//! | bytes | what |
//! |---|---|
//! | 8 | magic `PTPART01` |
//! | 4 + 4 | the share's index K - 1 (from 0) and the number of shares N |
//! | 4 + 4 + 4 | samples per pixel of the whole render, of this share, and of this share taken so far |
//! | 8 | the render's key: a hash of the scene file and every option that changes the samples |
//! | 8 | the seed |
//! | 4 + 4 | image width and height |
//! | 4 + n | the working folder of the render command (UTF-8) |
//! | 4 + (4 + n) ... | the render command's arguments, without `--part` and the output |
//! | 8 + n | the renderer's saved state (its exact sums; opaque here) |
//! | 8 | FNV-1a 64 of every byte before it: a truncated or damaged file is refused |
//!
//! A part file is written atomically (a temporary file renamed), when the part ends and at its
//! checkpoints, so a reader sees either the previous complete file or the new one.

use std::path::{Path, PathBuf};

/// First bytes of a part file (and its format version).
const MAGIC: &[u8; 8] = b"PTPART01";

/// What is wrong with a part file or a set of them.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum PartError {
    /// The file is not a part file, or is truncated or damaged.
    #[error("{0}: {1}")]
    Malformed(PathBuf, String),
    /// The parts do not form one whole render.
    #[error("{0}")]
    Set(String),
}

/// One share of a render and its sums so far.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PartFile {
    /// Which share, from 0 (`--part K/N` is K - 1).
    pub index: u32,
    /// Number of shares N.
    pub count: u32,
    /// Samples per pixel of the whole render.
    pub spp: u32,
    /// Samples per pixel of this share in all (the renderer's count of the sample indices equal
    /// to `index` modulo `count`).
    pub share_spp: u32,
    /// Samples per pixel of this share taken so far.
    pub done: u32,
    /// Identifies the scene file and the options that change the samples.
    pub key: u64,
    /// Seed of the random streams.
    pub seed: u64,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Working folder of the render command (relative paths in `args` are relative to it).
    pub cwd: String,
    /// The `pt render` arguments (after `render`), without `--part` and the output path.
    pub args: Vec<String>,
    /// The renderer's state: its sums (`RenderState::to_bytes` of pt-integrators).
    pub state: Vec<u8>,
}

impl PartFile {
    /// Whether the share has all its samples.
    pub fn complete(&self) -> bool {
        self.done == self.share_spp
    }

    /// `K/N` as the command line writes it.
    pub fn label(&self) -> String {
        format!("{}/{}", self.index + 1, self.count)
    }

    /// The file's bytes (see the module documentation).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut b = Vec::with_capacity(128 + self.state.len());
        b.extend_from_slice(MAGIC);
        for v in [self.index, self.count, self.spp, self.share_spp, self.done] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&self.key.to_le_bytes());
        b.extend_from_slice(&self.seed.to_le_bytes());
        b.extend_from_slice(&self.width.to_le_bytes());
        b.extend_from_slice(&self.height.to_le_bytes());
        let put_str = |b: &mut Vec<u8>, s: &str| {
            b.extend_from_slice(&(s.len() as u32).to_le_bytes());
            b.extend_from_slice(s.as_bytes());
        };
        put_str(&mut b, &self.cwd);
        b.extend_from_slice(&(self.args.len() as u32).to_le_bytes());
        for a in &self.args {
            put_str(&mut b, a);
        }
        b.extend_from_slice(&(self.state.len() as u64).to_le_bytes());
        b.extend_from_slice(&self.state);
        let sum = fnv1a(&b);
        b.extend_from_slice(&sum.to_le_bytes());
        b
    }

    /// Reads a part file's bytes; `path` names it in errors.
    pub fn from_bytes(bytes: &[u8], path: &Path) -> Result<PartFile, PartError> {
        let bad = |m: &str| PartError::Malformed(path.to_path_buf(), m.to_string());
        if bytes.len() < 8 || &bytes[..8] != MAGIC {
            return Err(bad("not a pt part file (wrong magic number)"));
        }
        if bytes.len() < 16 {
            return Err(bad("truncated part file"));
        }
        let (body, tail) = bytes.split_at(bytes.len() - 8);
        let stored = u64::from_le_bytes(tail.try_into().expect("8 bytes"));
        let mut r = Reader { b: body, at: 8 };
        let truncated = || bad("truncated or damaged part file (its checksum does not match)");
        // Parse first (a field that runs past the end is reported as truncation), then check
        // the sum over everything that was read.
        let parsed = (|| {
            let index = r.u32()?;
            let count = r.u32()?;
            let spp = r.u32()?;
            let share_spp = r.u32()?;
            let done = r.u32()?;
            let key = r.u64()?;
            let seed = r.u64()?;
            let width = r.u32()?;
            let height = r.u32()?;
            let cwd = r.string()?;
            let argc = r.u32()?;
            let mut args = Vec::new();
            for _ in 0..argc {
                args.push(r.string()?);
            }
            let len = usize::try_from(r.u64()?).ok()?;
            let state = r.take(len)?.to_vec();
            (r.at == body.len()).then_some(PartFile {
                index,
                count,
                spp,
                share_spp,
                done,
                key,
                seed,
                width,
                height,
                cwd,
                args,
                state,
            })
        })();
        let part = match parsed {
            Some(p) if fnv1a(body) == stored => p,
            _ => return Err(truncated()),
        };
        if part.count == 0 || part.index >= part.count {
            return Err(bad(&format!(
                "part index {} of {} is out of range",
                part.index + 1,
                part.count
            )));
        }
        if part.done > part.share_spp || part.share_spp > part.spp {
            return Err(bad("the part has more samples than its share"));
        }
        Ok(part)
    }

    /// Reads the part file at `path`.
    pub fn read(path: &Path) -> Result<PartFile, PartError> {
        let bytes = std::fs::read(path).map_err(|e| {
            PartError::Malformed(
                path.to_path_buf(),
                format!("cannot read the part file: {e}"),
            )
        })?;
        PartFile::from_bytes(&bytes, path)
    }
}

/// Checks that `parts` (each with the path it was read from) are the N complete shares of one
/// render, each exactly once; returns them in share order (the order `pt merge` adds them in,
/// although the sums are exact and any order gives the same bits). Refused: parts of other
/// renders (another scene file, option set, seed, size, sample count or number of shares), a
/// missing or duplicated share, an incomplete share.
pub fn check_set(parts: Vec<(PathBuf, PartFile)>) -> Result<Vec<(PathBuf, PartFile)>, PartError> {
    let set = |m: String| Err(PartError::Set(m));
    let Some((first_path, first)) = parts.first().cloned() else {
        return set("no part files given".into());
    };
    for (path, p) in &parts[1..] {
        let differs = if p.key != first.key {
            Some("another scene file or another set of render options")
        } else if p.seed != first.seed {
            Some("another seed")
        } else if (p.width, p.height) != (first.width, first.height) {
            Some("another image size")
        } else if p.spp != first.spp {
            Some("another sample count")
        } else if p.count != first.count {
            Some("another number of parts")
        } else {
            None
        };
        if let Some(what) = differs {
            return set(format!(
                "{} (part {}) and {} (part {}) belong to different renders: {what} (seed {} vs {}, {}x{} vs {}x{}, {} vs {} spp, {} vs {} parts)",
                first_path.display(),
                first.label(),
                path.display(),
                p.label(),
                first.seed,
                p.seed,
                first.width,
                first.height,
                p.width,
                p.height,
                first.spp,
                p.spp,
                first.count,
                p.count
            ));
        }
    }
    let n = first.count as usize;
    let mut slots: Vec<Option<(PathBuf, PartFile)>> = vec![None; n];
    for (path, p) in parts {
        let i = p.index as usize;
        if let Some((other, _)) = &slots[i] {
            return set(format!(
                "part {} is given twice: {} and {}",
                p.label(),
                other.display(),
                path.display()
            ));
        }
        slots[i] = Some((path, p));
    }
    let missing: Vec<String> = (0..n)
        .filter(|&i| slots[i].is_none())
        .map(|i| format!("{}/{n}", i + 1))
        .collect();
    if !missing.is_empty() {
        return set(format!("missing part(s): {}", missing.join(", ")));
    }
    let out: Vec<(PathBuf, PartFile)> = slots.into_iter().flatten().collect();
    for (path, p) in &out {
        if !p.complete() {
            return set(format!(
                "{} (part {}) has {} of its {} samples per pixel: it is still running or was stopped (run it again to resume it)",
                path.display(),
                p.label(),
                p.done,
                p.share_spp
            ));
        }
    }
    Ok(out)
}

/// Sequential reads from a byte slice; `None` past its end.
struct Reader<'a> {
    b: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let end = self.at.checked_add(n)?;
        let s = self.b.get(self.at..end)?;
        self.at = end;
        Some(s)
    }
    fn u32(&mut self) -> Option<u32> {
        Some(u32::from_le_bytes(self.take(4)?.try_into().ok()?))
    }
    fn u64(&mut self) -> Option<u64> {
        Some(u64::from_le_bytes(self.take(8)?.try_into().ok()?))
    }
    fn string(&mut self) -> Option<String> {
        let n = self.u32()? as usize;
        String::from_utf8(self.take(n)?.to_vec()).ok()
    }
}

/// FNV-1a, 64 bits: the part files' checksum, and the hash of a render's scene file and
/// options (`pt render`'s state key).
pub fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    fn part(index: u32, count: u32, spp: u32) -> PartFile {
        let share = (0..spp).filter(|s| s % count == index).count() as u32;
        PartFile {
            index,
            count,
            spp,
            share_spp: share,
            done: share,
            key: 42,
            seed: 7,
            width: 8,
            height: 4,
            cwd: "/tmp".into(),
            args: vec!["scene.xml".into(), "--spp".into(), spp.to_string()],
            state: vec![1, 2, 3, 4, 5],
        }
    }

    /// A file reads back as written; any truncation or changed byte is refused.
    #[test]
    fn round_trip_and_damage() {
        let p = part(2, 4, 64);
        let path = Path::new("x.ptpart");
        let b = p.to_bytes();
        assert_eq!(PartFile::from_bytes(&b, path).unwrap(), p);
        for cut in [0, 5, 8, 20, b.len() / 2, b.len() - 1] {
            assert!(
                PartFile::from_bytes(&b[..cut], path).is_err(),
                "cut at {cut}"
            );
        }
        for i in [9, 30, b.len() - 10, b.len() - 3] {
            let mut d = b.clone();
            d[i] ^= 0x10;
            assert!(PartFile::from_bytes(&d, path).is_err(), "byte {i} changed");
        }
    }

    /// The set checks name what is wrong: another render, a duplicate, a missing or an
    /// incomplete share.
    #[test]
    fn sets_are_checked() {
        let named = |ps: Vec<PartFile>| {
            ps.into_iter()
                .enumerate()
                .map(|(i, p)| (PathBuf::from(format!("p{i}.ptpart")), p))
                .collect::<Vec<_>>()
        };
        let ok = named(vec![part(2, 3, 10), part(0, 3, 10), part(1, 3, 10)]);
        let sorted = check_set(ok).unwrap();
        assert_eq!(
            sorted.iter().map(|(_, p)| p.index).collect::<Vec<_>>(),
            [0, 1, 2]
        );
        let err = |ps| match check_set(named(ps)) {
            Err(PartError::Set(m)) => m,
            other => panic!("{other:?}"),
        };
        let mut other_key = part(1, 3, 10);
        other_key.key = 43;
        assert!(err(vec![part(0, 3, 10), other_key]).contains("another scene file"));
        let mut other_seed = part(1, 3, 10);
        other_seed.seed = 8;
        assert!(err(vec![part(0, 3, 10), other_seed]).contains("another seed"));
        assert!(err(vec![part(0, 3, 10), part(1, 3, 12)]).contains("sample count"));
        assert!(err(vec![part(0, 3, 10), part(0, 3, 10)]).contains("given twice"));
        assert!(err(vec![part(0, 3, 10), part(2, 3, 10)]).contains("missing part(s): 2/3"));
        let mut running = part(1, 3, 10);
        running.done = 1;
        assert!(err(vec![part(0, 3, 10), running, part(2, 3, 10)]).contains("1 of its 3"));
    }
}
