//! Atomic file replacement: write a temporary file in the target's directory, fsync it, rename it
//! over the target. A reader never sees a half-written image, and a failed or interrupted write
//! leaves the previous file (if any) untouched and no temporary file behind.

use std::fs::{self, File, OpenOptions};
use std::io;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::ImageError;

/// Distinguishes temporary files of concurrent writes from one process.
static COUNTER: AtomicU64 = AtomicU64::new(0);

/// Removes the temporary file when dropped, unless disarmed after the rename. Runs on error
/// returns and on panics alike.
struct TempGuard {
    path: Option<PathBuf>,
}

impl Drop for TempGuard {
    fn drop(&mut self) {
        if let Some(p) = self.path.take() {
            let _ = fs::remove_file(p);
        }
    }
}

/// The temporary file name for `target`: `.<name>.<pid>-<n>.tmp` in the same directory, so that
/// the final rename stays within one file system and the file is hidden from casual listings.
fn temp_path(dir: &Path, file_name: &std::ffi::OsStr) -> PathBuf {
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let name = format!(
        ".{}.{}-{}.tmp",
        file_name.to_string_lossy(),
        std::process::id(),
        n
    );
    dir.join(name)
}

/// Write `path` atomically. `write` receives the open temporary file and must write the whole
/// content (flushing any buffer it wraps around the file); this function then fsyncs the file,
/// renames it over `path` and (on Unix) fsyncs the directory.
pub(crate) fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut File) -> Result<(), ImageError>,
) -> Result<(), ImageError> {
    let Some(file_name) = path.file_name() else {
        return Err(ImageError::io(
            path,
            "write file",
            io::Error::new(io::ErrorKind::InvalidInput, "path does not name a file"),
        ));
    };
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };

    // create_new: never clobber someone else's file; retry on the (unlikely) name collision.
    let mut attempt = 0;
    let (tmp, mut file) = loop {
        let tmp = temp_path(&dir, file_name);
        match OpenOptions::new().write(true).create_new(true).open(&tmp) {
            Ok(f) => break (tmp, f),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists && attempt < 16 => attempt += 1,
            Err(e) => return Err(ImageError::io(tmp, "create temporary file", e)),
        }
    };
    let mut guard = TempGuard {
        path: Some(tmp.clone()),
    };

    write(&mut file)?;
    file.sync_all()
        .map_err(|e| ImageError::io(&tmp, "fsync temporary file", e))?;
    drop(file);
    fs::rename(&tmp, path)
        .map_err(|e| ImageError::io(path, "rename temporary file over target", e))?;
    guard.path = None;

    // Make the rename itself durable. Best effort: not every platform can open a directory.
    #[cfg(unix)]
    if let Ok(d) = File::open(&dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::scratch_dir;

    fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn failed_write_leaves_nothing_and_keeps_old_file() {
        let dir = scratch_dir("atomic-fail");
        let target = dir.join("out.bin");
        fs::write(&target, b"old").unwrap();
        let r = write_atomically(&target, |f| {
            use std::io::Write;
            f.write_all(b"partial").unwrap();
            Err(ImageError::InvalidArgument("simulated failure".into()))
        });
        assert!(r.is_err());
        assert_eq!(entries(&dir), vec!["out.bin".to_string()]);
        assert_eq!(fs::read(&target).unwrap(), b"old");
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn successful_write_replaces_target() {
        let dir = scratch_dir("atomic-ok");
        let target = dir.join("out.bin");
        fs::write(&target, b"old").unwrap();
        write_atomically(&target, |f| {
            use std::io::Write;
            f.write_all(b"new")
                .map_err(|e| ImageError::io(&target, "write", e))
        })
        .unwrap();
        assert_eq!(entries(&dir), vec!["out.bin".to_string()]);
        assert_eq!(fs::read(&target).unwrap(), b"new");
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn temp_name_is_hidden_and_ends_in_tmp() {
        let p = temp_path(Path::new("/x"), std::ffi::OsStr::new("a.exr"));
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        assert!(
            name.starts_with(".a.exr.") && name.ends_with(".tmp"),
            "{name}"
        );
        assert_eq!(p.parent(), Some(Path::new("/x")));
    }
}
