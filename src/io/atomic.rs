//! Atomic file replacement: a file is written whole or not at all.
//!
//! The data is first written to a uniquely named temporary file in the same
//! directory as the target, flushed to disk, and then renamed over the target.
//! Because the rename happens within one directory (hence one file system), a
//! reader (e.g. ParaView polling a running simulation) sees either the old
//! complete file or the new complete file, never a truncated one.

use std::fs::{self, File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Per-process counter making temporary names unique across threads.
static TMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Writes `bytes` to `path` atomically.
///
/// A temporary file `.<name>.<pid>.<n>.tmp` is created next to `path`
/// (never clobbering an existing file), filled, synced to disk and renamed
/// over `path`, replacing any existing file. On failure the temporary file is
/// removed and `path` is left untouched. The parent directory must exist.
///
/// # Errors
/// Returns the underlying I/O error if the temporary file cannot be created,
/// written or synced, or if the rename fails (e.g. `path` is a directory).
/// Returns [`io::ErrorKind::InvalidInput`] if `path` has no file name.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let file_name = path.file_name().ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("cannot write '{}': path has no file name", path.display()),
        )
    })?;
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };

    let (tmp_path, mut file) = create_temp(&dir, file_name)?;
    let result = (|| {
        file.write_all(bytes)?;
        file.sync_all()?;
        drop(file);
        fs::rename(&tmp_path, path)
    })();
    if let Err(e) = result {
        // Best effort clean-up; the original error is what matters.
        let _ = fs::remove_file(&tmp_path);
        return Err(io::Error::new(
            e.kind(),
            format!("writing '{}' failed: {e}", path.display()),
        ));
    }
    sync_dir(&dir);
    Ok(())
}

/// Creates a fresh temporary file in `dir`, retrying on name collisions.
fn create_temp(dir: &Path, file_name: &std::ffi::OsStr) -> io::Result<(PathBuf, File)> {
    let pid = std::process::id();
    let mut last_err = None;
    for _ in 0..100 {
        let n = TMP_COUNTER.fetch_add(1, Ordering::Relaxed);
        let mut name = std::ffi::OsString::from(".");
        name.push(file_name);
        name.push(format!(".{pid}.{n}.tmp"));
        let tmp_path = dir.join(name);
        match OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp_path)
        {
            Ok(f) => return Ok((tmp_path, f)),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => last_err = Some(e),
            Err(e) => {
                return Err(io::Error::new(
                    e.kind(),
                    format!("cannot create temporary file '{}': {e}", tmp_path.display()),
                ));
            }
        }
    }
    Err(last_err.unwrap_or_else(|| io::Error::other("could not create a temporary file")))
}

/// Flushes the directory entry (the rename) to disk where supported.
fn sync_dir(dir: &Path) {
    #[cfg(unix)]
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
    #[cfg(not(unix))]
    let _ = dir;
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch_dir(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("plyshell_atomic_{tag}_{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).expect("create scratch dir");
        d
    }

    fn leftovers(dir: &Path) -> Vec<String> {
        fs::read_dir(dir)
            .expect("read dir")
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".tmp"))
            .collect()
    }

    #[test]
    fn writes_and_replaces() {
        let d = scratch_dir("replace");
        let p = d.join("out.txt");
        write_atomic(&p, b"first version, long").expect("write 1");
        assert_eq!(fs::read(&p).expect("read"), b"first version, long");
        write_atomic(&p, b"second").expect("write 2");
        assert_eq!(fs::read(&p).expect("read"), b"second");
        write_atomic(&p, b"").expect("write empty");
        assert_eq!(fs::read(&p).expect("read"), b"");
        assert!(leftovers(&d).is_empty());
        let _ = fs::remove_dir_all(&d);
    }

    #[test]
    fn failure_leaves_target_and_no_temp() {
        let d = scratch_dir("fail");
        // Target is an existing non-empty directory: rename must fail.
        let target = d.join("adir");
        fs::create_dir_all(target.join("inner")).expect("mkdir");
        assert!(write_atomic(&target, b"x").is_err());
        assert!(target.is_dir());
        assert!(leftovers(&d).is_empty());
        // Missing parent directory.
        assert!(write_atomic(&d.join("missing/out.txt"), b"x").is_err());
        // No file name.
        assert!(write_atomic(Path::new("/"), b"x").is_err());
        let _ = fs::remove_dir_all(&d);
    }

    #[test]
    fn concurrent_writers_produce_whole_files() {
        let d = scratch_dir("threads");
        let p = d.join("shared.bin");
        std::thread::scope(|s| {
            for t in 0..4u8 {
                let p = &p;
                s.spawn(move || {
                    for _ in 0..20 {
                        write_atomic(p, &vec![t; 10_000]).expect("write");
                    }
                });
            }
        });
        let content = fs::read(&p).expect("read");
        assert_eq!(content.len(), 10_000);
        assert!(content.iter().all(|&b| b == content[0]));
        assert!(leftovers(&d).is_empty());
        let _ = fs::remove_dir_all(&d);
    }
}
