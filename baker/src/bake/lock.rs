//! One bake per model at a time: an operating-system lock on a file beside the model
//! (`MODEL.lock`), which also holds the baking process's id for the message a second bake
//! prints. The system releases the lock when its process ends however it ends, so a killed
//! bake leaves nothing that stops the next from resuming.

use std::fs::{File, OpenOptions, TryLockError};
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};

use super::BakeError;

/// The lock of one model, held until dropped; dropping it removes the lock file.
pub struct BakeLock {
    path: PathBuf,
    /// Holds the lock: the system releases it when the file is closed.
    _file: File,
}

/// What to do when another bake holds the model.
#[derive(Clone, Copy, Debug)]
pub enum Contended {
    /// Fail with [`BakeError::Locked`], naming the other bake's process.
    Refuse,
    /// Wait until the other bake ends, after calling the function with its process id.
    Wait(fn(Option<u32>)),
}

impl BakeLock {
    /// Takes the lock of `model` (`MODEL.lock`); when another bake holds it, refuses or waits
    /// as `contended` says.
    pub fn acquire(model: &Path, contended: Contended) -> Result<Self, BakeError> {
        let path = model.with_extension("lock");
        let io = |e: std::io::Error| BakeError::Io { path: path.clone(), problem: format!("cannot lock: {e}") };
        loop {
            // Not truncated: the holder's process id stays readable until the lock is ours.
            let mut file =
                OpenOptions::new().read(true).write(true).create(true).truncate(false).open(&path).map_err(io)?;
            match file.try_lock() {
                Ok(()) => {}
                Err(TryLockError::WouldBlock) => {
                    let holder = holder(&mut file);
                    match contended {
                        Contended::Refuse => {
                            return Err(BakeError::Locked { model: model.to_path_buf(), lock: path, pid: holder })
                        }
                        Contended::Wait(waiting) => {
                            waiting(holder);
                            file.lock().map_err(io)?;
                        }
                    }
                }
                Err(TryLockError::Error(e)) => return Err(io(e)),
            }
            // The bake that held the lock before removes the file as it releases it: the lock
            // of a removed file keeps no one out, so start again with the file now there.
            if !is_file_at(&file, &path) {
                continue;
            }
            file.set_len(0).map_err(io)?;
            file.rewind().map_err(io)?;
            write!(file, "{}", std::process::id()).map_err(io)?;
            return Ok(BakeLock { path, _file: file });
        }
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for BakeLock {
    /// Removes the file while the lock is still held (a bake waiting on it then sees that it
    /// was removed, and locks the next one), then closes it, which releases the lock.
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// The process id written in a lock file. The holder writes it just after it takes the lock,
/// so an empty file is read again for up to half a second.
fn holder(file: &mut File) -> Option<u32> {
    for _ in 0..50 {
        let mut text = String::new();
        if file.rewind().is_ok() && file.read_to_string(&mut text).is_ok() {
            if let Ok(pid) = text.trim().parse() {
                return Some(pid);
            }
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    None
}

/// Whether `path` still names the open `file`.
#[cfg(unix)]
fn is_file_at(file: &File, path: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (file.metadata(), std::fs::metadata(path)) {
        (Ok(open), Ok(named)) => (open.dev(), open.ino()) == (named.dev(), named.ino()),
        _ => false,
    }
}

/// Elsewhere an open file cannot be removed, so the path names it while it is open.
#[cfg(not(unix))]
fn is_file_at(_: &File, path: &Path) -> bool {
    path.exists()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_held_lock_is_refused_and_a_released_one_taken() {
        let dir = std::env::temp_dir().join(format!("rrf-lock-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let model = dir.join("model.safetensors");
        let lock = BakeLock::acquire(&model, Contended::Refuse).unwrap();
        let message = BakeLock::acquire(&model, Contended::Refuse).err().expect("second bake refused").to_string();
        assert!(message.contains(&std::process::id().to_string()) && message.contains("model.lock"), "{message}");
        drop(lock);
        assert!(!dir.join("model.lock").exists(), "released on drop");
        // A lock file that no process locks (left by a killed bake) is no obstacle.
        std::fs::write(dir.join("model.lock"), "4194305").unwrap();
        let lock = BakeLock::acquire(&model, Contended::Refuse).expect("an unlocked lock file is taken");
        assert_eq!(std::fs::read_to_string(lock.path()).unwrap(), std::process::id().to_string());
        drop(lock);
        std::fs::remove_dir_all(dir).unwrap();
    }
}
