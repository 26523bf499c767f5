//! The bake cache: files that a bake writes as it goes so that a bake started again after a
//! kill reuses them. Each file is `magic (8 bytes) | key (u64) | FNV-1a 64 of the payload |
//! payload`, written beside and renamed, so a file on disk is whole or absent. A file with
//! another key (other settings or scene) is ignored; one whose payload does not match its
//! checksum is reported as corrupt and recomputed.

use std::path::Path;

use super::BakeError;
use crate::hash::Fnv64;

pub enum Cached {
    /// No file, or one made with other settings.
    Missing,
    /// A file with the right key whose payload does not match its checksum or cannot be read.
    Corrupt,
    Found(Vec<u8>),
}

const HEADER: usize = 24;

pub fn read(path: &Path, magic: &[u8; 8], key: u64) -> Cached {
    let Ok(bytes) = std::fs::read(path) else { return Cached::Missing };
    if bytes.len() < HEADER || &bytes[..8] != magic || bytes[8..16] != key.to_le_bytes() {
        return Cached::Missing;
    }
    let payload = &bytes[HEADER..];
    if bytes[16..24] != Fnv64::of(payload).to_le_bytes() {
        return Cached::Corrupt;
    }
    Cached::Found(payload.to_vec())
}

pub fn write(path: &Path, magic: &[u8; 8], key: u64, payload: &[u8]) -> Result<(), BakeError> {
    let mut bytes = Vec::with_capacity(HEADER + payload.len());
    bytes.extend(magic);
    bytes.extend(key.to_le_bytes());
    bytes.extend(Fnv64::of(payload).to_le_bytes());
    bytes.extend(payload);
    let partial = path.with_extension("partial");
    std::fs::write(&partial, bytes).and_then(|()| std::fs::rename(&partial, path)).map_err(|e| BakeError::Io {
        path: path.to_path_buf(),
        problem: format!("cannot write to the bake cache: {e}"),
    })
}
