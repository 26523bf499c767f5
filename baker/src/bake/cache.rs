//! The bake cache: files that a bake writes as it goes so that a bake started again after a
//! kill reuses them. Each file is `magic (8 bytes) | key (u64) | FNV-1a 64 of the payload |
//! payload`, written through [`write_atomically`], so a file on disk is whole or absent. A file with
//! another key (other settings or scene) is ignored; one whose payload does not match its
//! checksum, or cannot be decoded, is counted as corrupt and recomputed.

use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

use super::BakeError;
use crate::atomic_file::write_atomically;
use crate::hash::Fnv64;

const HEADER: usize = 24;

/// The payload of the file at `path`, decoded: `None` when there is no such file or it was
/// made with another key, and also when its payload fails its checksum or `decode`, which
/// `corrupt` counts. On `None` the caller computes the payload again.
pub fn read<T>(
    path: &Path,
    magic: &[u8; 8],
    key: u64,
    corrupt: &AtomicUsize,
    decode: impl FnOnce(&[u8]) -> Option<T>,
) -> Option<T> {
    let bytes = std::fs::read(path).ok()?;
    if bytes.len() < HEADER || &bytes[..8] != magic || bytes[8..16] != key.to_le_bytes() {
        return None;
    }
    let payload = &bytes[HEADER..];
    let found = (bytes[16..24] == Fnv64::of(payload).to_le_bytes()).then(|| decode(payload)).flatten();
    if found.is_none() {
        corrupt.fetch_add(1, Ordering::SeqCst);
    }
    found
}

pub fn write(path: &Path, magic: &[u8; 8], key: u64, payload: &[u8]) -> Result<(), BakeError> {
    let mut bytes = Vec::with_capacity(HEADER + payload.len());
    bytes.extend(magic);
    bytes.extend(key.to_le_bytes());
    bytes.extend(Fnv64::of(payload).to_le_bytes());
    bytes.extend(payload);
    write_atomically(path, |tmp| std::fs::write(tmp, bytes)).map_err(|e| BakeError::Io {
        path: path.to_path_buf(),
        problem: format!("cannot write to the bake cache: {e}"),
    })
}
