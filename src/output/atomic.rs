//! Atomic file writes: every output file is written under a temporary name beside its final
//! one and renamed into place once complete, so that a reader (ParaView, a resumed run, a
//! script) never sees half a file, even after `kill -9`. A write that fails (a full disk, a
//! file-size limit) removes its temporary file and leaves the previous version, if any.

use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// The temporary name of `path`: hidden, in the same directory (so the rename stays on one
/// file system), with the same extension (writers that choose a format by it still do):
/// `dir/name.ext` → `dir/.name.tmp.ext`.
pub fn temp_path(path: &Path) -> PathBuf {
    let stem = path
        .file_stem()
        .map_or_else(Default::default, |s| s.to_os_string());
    let mut name = std::ffi::OsString::from(".");
    name.push(stem);
    name.push(".tmp");
    if let Some(ext) = path.extension() {
        name.push(".");
        name.push(ext);
    }
    path.with_file_name(name)
}

/// Whether `name` is one of [`temp_path`]'s temporary names.
pub fn is_temp_name(name: &str) -> bool {
    name.starts_with('.') && (name.contains(".tmp.") || name.ends_with(".tmp"))
}

/// Write `path` by calling `write` on its temporary name, then renaming it into place.
pub fn write_with(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let tmp = temp_path(path);
    let done =
        write(&tmp).and_then(|()| std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e)));
    if done.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    done
}

/// Write `bytes` to `path` atomically.
pub fn write(path: &Path, bytes: &[u8]) -> Result<()> {
    write_with(path, |tmp| {
        std::fs::write(tmp, bytes).map_err(|e| Error::io(path, e))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temporary_names_keep_the_extension_and_are_recognised() {
        let t = temp_path(Path::new("out/run_000010.vtp"));
        assert_eq!(t, Path::new("out/.run_000010.tmp.vtp"));
        assert!(is_temp_name(".run_000010.tmp.vtp"));
        assert_eq!(
            temp_path(Path::new("checkpoint")),
            Path::new(".checkpoint.tmp")
        );
        assert!(!is_temp_name("run_000010.vtp"));
    }

    /// A write that fails leaves neither a temporary file nor a changed target.
    #[test]
    fn failed_write_leaves_the_old_file_and_no_temporary() {
        let dir = std::env::temp_dir().join(format!("strike_atomic_{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.txt");
        write(&path, b"old").unwrap();
        let err = write_with(&path, |tmp| {
            std::fs::write(tmp, b"half").unwrap();
            Err(Error::Invalid("disk full".into()))
        });
        assert!(err.is_err());
        assert_eq!(std::fs::read(&path).unwrap(), b"old");
        let names: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("a.txt")]);
        write(&path, b"new").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"new");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
