//! Files written whole or not at all: models, bake-cache files, and (through the `rrf` crate)
//! images and sidecars.

use std::io;
use std::path::Path;

/// Runs `write` on a temporary file beside `path` (`NAME.partial-PID.EXT`: the same extension,
/// so that encoders that go by it still work, and this process's own, so that two processes
/// writing the same file, as a cluster's retried job may, never write into one temporary),
/// then renames it to `path`. On any failure (a full disk, a kill before the rename) the
/// temporary file is removed and whatever was at `path` is left as it was.
pub fn write_atomically<E: From<io::Error>>(path: &Path, write: impl FnOnce(&Path) -> Result<(), E>) -> Result<(), E> {
    let extension = path.extension().and_then(|e| e.to_str()).unwrap_or("tmp");
    let tmp = path.with_extension(format!("partial-{}.{extension}", std::process::id()));
    let written = write(&tmp).and_then(|()| {
        std::fs::rename(&tmp, path)
            .map_err(|e| E::from(io::Error::new(e.kind(), format!("cannot write {}: {e}", path.display()))))
    });
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_write_leaves_the_old_file_and_no_temporary() {
        let dir = std::env::temp_dir().join(format!("rrf-atomic-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("model.safetensors");
        std::fs::write(&path, "old").unwrap();
        let failed = write_atomically(&path, |tmp| {
            std::fs::write(tmp, "half")?;
            Err(io::Error::other("disk full"))
        });
        assert!(failed.is_err());
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old");
        write_atomically(&path, |tmp| std::fs::write(tmp, "new")).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "new");
        let names: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names, ["model.safetensors"]);
        std::fs::remove_dir_all(dir).unwrap();
    }
}
