//! What a finished run's files were: byte size and FNV-1a (64-bit) digest of each,
//! recorded in `summary.json`, so that a reader can tell the files the run finished
//! from files cut short or overwritten since (`collect` reports such a point corrupt).
//! FNV is no defence against tampering, only against accidents, and needs no crate.

use std::collections::BTreeMap;
use std::io::{self, Read};
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::name_error;

/// One file as written.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct FileCheck {
    /// Size in bytes.
    pub bytes: u64,
    /// FNV-1a 64-bit digest of the bytes, 16 hex digits.
    pub fnv1a64: String,
}

impl FileCheck {
    /// Reads `path` through.
    pub fn of(path: &Path) -> io::Result<FileCheck> {
        let mut file = std::fs::File::open(path).map_err(|e| name_error(path, e))?;
        let (mut hash, mut bytes) = (FNV_BASIS, 0_u64);
        let mut buf = vec![0_u8; 1 << 16];
        loop {
            let n = file.read(&mut buf).map_err(|e| name_error(path, e))?;
            if n == 0 {
                break;
            }
            hash = fnv1a64_on(hash, &buf[..n]);
            bytes += n as u64;
        }
        Ok(FileCheck {
            bytes,
            fnv1a64: format!("{hash:016x}"),
        })
    }
}

/// FNV-1a's 64-bit offset basis: the digest of no bytes.
const FNV_BASIS: u64 = 0xcbf2_9ce4_8422_2325;

/// FNV-1a 64 continued from `hash` over `bytes`.
fn fnv1a64_on(mut hash: u64, bytes: &[u8]) -> u64 {
    for &b in bytes {
        hash = (hash ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3);
    }
    hash
}

/// FNV-1a 64 of `bytes`, as 16 hex digits (what [`FileCheck`] records of a file).
pub fn fnv1a64(bytes: &[u8]) -> String {
    format!("{:016x}", fnv1a64_on(FNV_BASIS, bytes))
}

/// The checks of the files `names` present in `dir`, by name.
pub fn check_files(dir: &Path, names: &[&str]) -> io::Result<BTreeMap<String, FileCheck>> {
    let mut out = BTreeMap::new();
    for name in names {
        let path = dir.join(name);
        if path.is_file() {
            out.insert(name.to_string(), FileCheck::of(&path)?);
        }
    }
    Ok(out)
}

/// Why the files of `dir` are not those `recorded`, or None when they are.
pub fn mismatch(dir: &Path, recorded: &BTreeMap<String, FileCheck>) -> Option<String> {
    for (name, want) in recorded {
        let path = dir.join(name);
        let found = match FileCheck::of(&path) {
            Ok(f) => f,
            Err(e) => return Some(format!("{e}")),
        };
        let (what, found, want) = if found.bytes != want.bytes {
            ("bytes", found.bytes.to_string(), want.bytes.to_string())
        } else if found.fnv1a64 != want.fnv1a64 {
            ("digest", found.fnv1a64, want.fnv1a64.clone())
        } else {
            continue;
        };
        return Some(format!(
            "{}: {what} {found} where summary.json records {want}",
            path.display()
        ));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_digest_is_fnv1a_and_a_cut_file_mismatches() {
        let dir = std::env::temp_dir().join(format!("digest-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("a"), b"a").unwrap();
        let checks = check_files(&dir, &["a", "absent"]).unwrap();
        // The published FNV-1a 64 of "a".
        assert_eq!(checks["a"].fnv1a64, "af63dc4c8601ec8c");
        assert_eq!(mismatch(&dir, &checks), None);
        std::fs::write(dir.join("a"), b"").unwrap();
        assert!(
            mismatch(&dir, &checks)
                .unwrap()
                .contains("bytes 0 where summary.json records 1")
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
