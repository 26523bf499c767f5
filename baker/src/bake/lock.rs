//! One bake per model at a time: a lock file beside the model that holds the baking process's
//! id. A lock left by a bake that was killed (its process is gone) is taken over, so a killed
//! bake can always be resumed.

use std::io::Write;
use std::path::{Path, PathBuf};

use super::BakeError;

pub struct BakeLock {
    path: PathBuf,
}

impl BakeLock {
    /// Takes the lock of `model` (`MODEL.lock`), or says which process holds it.
    pub fn acquire(model: &Path) -> Result<Self, BakeError> {
        let path = model.with_extension("lock");
        let io = |e: std::io::Error| BakeError::Io { path: path.clone(), problem: format!("cannot create: {e}") };
        loop {
            match std::fs::OpenOptions::new().write(true).create_new(true).open(&path) {
                Ok(mut file) => {
                    write!(file, "{}", std::process::id()).map_err(io)?;
                    return Ok(BakeLock { path });
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    let holder = std::fs::read_to_string(&path).ok().and_then(|s| s.trim().parse::<u32>().ok());
                    match holder {
                        Some(pid) if process_exists(pid) => {
                            return Err(BakeError::Locked { model: model.to_path_buf(), lock: path, pid })
                        }
                        // Left by a bake that was killed, or half-written: stale.
                        _ => std::fs::remove_file(&path).map_err(io)?,
                    }
                }
                Err(e) => return Err(io(e)),
            }
        }
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for BakeLock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Whether a process with this id runs (Linux: it has a /proc entry; elsewhere a lock is
/// only ever taken over after its file is removed by hand).
fn process_exists(pid: u32) -> bool {
    if cfg!(target_os = "linux") {
        Path::new("/proc").join(pid.to_string()).exists()
    } else {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_held_lock_is_refused_and_a_stale_one_taken_over() {
        let dir = std::env::temp_dir().join(format!("rrf-lock-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let model = dir.join("model.safetensors");
        let lock = BakeLock::acquire(&model).unwrap();
        let message = BakeLock::acquire(&model).err().expect("second bake refused").to_string();
        assert!(message.contains(&std::process::id().to_string()) && message.contains("model.lock"), "{message}");
        drop(lock);
        assert!(!dir.join("model.lock").exists(), "released on drop");
        // A lock whose process is gone (pid beyond Linux's pid_max) is stale.
        std::fs::write(dir.join("model.lock"), "4194305").unwrap();
        let lock = BakeLock::acquire(&model).expect("a stale lock is taken over");
        assert_eq!(std::fs::read_to_string(lock.path()).unwrap(), std::process::id().to_string());
        drop(lock);
        std::fs::remove_dir_all(dir).unwrap();
    }
}
